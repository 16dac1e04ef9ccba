//! The collapse search: the largest load multiplier t with an equilibrium
//! (docs/formulation.md §11).
//!
//! Place in the flow: called by the `driver` before the run itself, which is then made at
//! the multiplier found. Each trial is a single step from the unloaded state at t; a trial
//! stands when the contact problem has a solution and fails when the solver reports a
//! mechanism (no equilibrium exists), or one that the rigid-block statics leaves undecided
//! (`statics`). The multiplier is bracketed by bisection between 0 (which must stand) and
//! `max`, down to `tolerance`; the statics' largest feasible t bounds it from above.

use std::time::Instant;

use super::driver::{step_at, StepAcc, StepContext, Stepper};
use super::statics::{self, Bound, Verdict};
use crate::bem::Operators;
use crate::contact::Session;
use crate::error::{Error, Result};
use crate::input::model::fmt_num;
use crate::input::scene::Collapse;
use crate::solution::{BodyMotion, CollapseSummary, CollapseTrial};
use crate::timings::Timings;

/// Trials above this multiple of the rigid-block bound are not solved (failing by proof).
const STATICS_MARGIN: f64 = 1.1;

/// The equal steps a trial that one step leaves undecided is solved in again.
const TRIAL_PARTS: usize = 2;

/// What the search found: the multiplier, the summary's `contact.collapse` block and the
/// motion of the mechanism at `collapses_at`, where it was found.
pub(super) struct Found {
    pub(super) multiplier: f64,
    pub(super) info: CollapseSummary,
    pub(super) motion: Option<Vec<BodyMotion>>,
}

/// A trial without an equilibrium: why, and the motion of its mechanism where found.
type Collapsed = (Error, Option<Vec<BodyMotion>>);

/// The trials of one search.
struct Search<'a, 'b> {
    stepper: &'a Stepper<'b>,
    ctx: &'a StepContext<'b>,
    trials: Vec<CollapseTrial>,
    /// The rigid-block statics' largest t (`statics::collapse_bound`).
    bound: Bound,
}

impl Search<'_, '_> {
    /// What the search knows so far, for a failure's message: the largest t that stood and
    /// the rigid-block upper bound.
    fn bracket(&self) -> String {
        let stood = self
            .trials
            .iter()
            .filter(|t| t.stands)
            .map(|t| t.t)
            .reduce(f64::max);
        let stood = match stood {
            Some(t) => format!("the largest t that stands so far is {}", fmt_num(t)),
            None => "no t stands so far".to_string(),
        };
        let (bound, meaning) = bound_figures(&self.bound);
        match bound {
            Some(b) => format!(
                "{stood}; no equilibrium exists above t = {} (rigid-block statics)",
                fmt_num(b)
            ),
            None => format!("{stood}; rigid-block upper bound: {meaning}"),
        }
    }

    /// One trial at `t`: `Some((mechanism, motion))` when no equilibrium exists, an error
    /// when the solver fails otherwise.
    fn trial(
        &mut self,
        t: f64,
        session: &mut Session,
        timings: &mut Timings,
        reassembled: &mut Option<Operators>,
    ) -> Result<Option<Collapsed>> {
        self.ctx.stage.begin_trial(self.trials.len() as u64 + 1, t);
        // Well above the rigid-block bound no equilibrium exists by proof: not solved (a
        // solver there only finds its mechanism or, with Coulomb joints, often nothing in
        // minutes). Within 10 % above it the trial is solved, so that the bisection's
        // `collapses_at` next to a tight bound has the solver's mechanism and motion.
        if let Bound::Value(b) = self.bound {
            if t > STATICS_MARGIN * b {
                self.trials.push(CollapseTrial {
                    undecided: false,
                    by_statics: true,
                    stands: false,
                    t,
                    steps: 0,
                });
                let e = Error::numerical(format!(
                    "no equilibrium exists at t = {}: it is above the rigid-block statics' bound \
                     t = {} (no interface forces within the pairs' laws balance every body); \
                     not solved",
                    fmt_num(t),
                    fmt_num(b)
                ));
                return Ok(Some((e, None)));
            }
        }
        let mut st = session.initial();
        let mut a = StepAcc::default();
        let t0 = Instant::now();
        // The trial's stages are timed within the search, so that the total counts them once.
        let mut inner = Timings::default();
        // A trial the solver could not decide in one step from the unloaded state (no
        // mechanism found: a friction fixed point that did not settle) is solved again along
        // its load path, in 2 equal steps of t: near collapse the lagged slip bounds
        // of a large friction coefficient settle from a state nearer the load (the 4 x 5
        // wall with μ = 1 000 at t = 0.6875: undecided in one step, stands in two).
        let mut parts = 1;
        loop {
            for k in 1..=parts {
                let tk = t * k as f64 / parts as f64;
                let at = (1.0, tk);
                step_at(
                    self.stepper,
                    session,
                    self.ctx,
                    k - 1,
                    at,
                    &mut st,
                    &mut a,
                    &mut inner,
                    reassembled,
                )?;
                if a.failure.is_some() {
                    break;
                }
            }
            let unsettled = a.failure.is_some() && !a.mechanism && a.undecided;
            if !unsettled || parts >= TRIAL_PARTS || t == 0.0 || !self.stepper.timed {
                break;
            }
            parts *= 2;
            st = session.initial();
            a = StepAcc::default();
        }
        timings.add_within("collapse_search", t0.elapsed().as_secs_f64(), inner);
        // A "no equilibrium" that the rigid-block check leaves undecided fails the trial
        // too (its message says so; the bracket stays [multiplier, upper_bound]).
        let undecided = a.statics == Some(Verdict::Feasible);
        // A solver that could not decide the step (no verdict either way) fails the trial
        // too, said so in the trial's record.
        let unsettled = a.failure.is_some() && !a.mechanism && a.undecided;
        let outcome = match a.failure {
            None => None,
            Some(e) if a.mechanism || undecided || unsettled => Some((e, a.motion)),
            Some(e) => {
                return Err(Error::numerical(format!(
                    "the collapse search failed at t = {} ({}): {}",
                    fmt_num(t),
                    self.bracket(),
                    e.message()
                )))
            }
        };
        self.trials.push(CollapseTrial {
            by_statics: false,
            undecided: undecided || unsettled,
            stands: outcome.is_none(),
            t,
            steps: parts,
        });
        Ok(outcome)
    }
}

/// Bisects the load multiplier of `c` on `session`.
pub(super) fn search(
    c: &Collapse,
    stepper: &Stepper,
    ctx: &StepContext,
    session: &mut Session,
    timings: &mut Timings,
    reassembled: &mut Option<Operators>,
) -> Result<Found> {
    let mut s = Search {
        stepper,
        ctx,
        trials: Vec::new(),
        bound: statics::collapse_bound(stepper.case.scene, stepper.case.model, c.max),
    };
    ctx.stage.count_trials(trials_needed(c));
    if let Some((e, _)) = s.trial(0.0, session, timings, reassembled)? {
        return Err(Error::numerical(format!(
            "the collapse search found no equilibrium at t = 0 (before any load \
             multiplier): {}",
            e.message()
        )));
    }
    let (mut lo, mut hi) = (0.0, c.max);
    let mut mechanism = s.trial(c.max, session, timings, reassembled)?;
    if mechanism.is_none() {
        lo = c.max;
    } else {
        while hi - lo > c.tolerance {
            let mid = 0.5 * (lo + hi);
            match s.trial(mid, session, timings, reassembled)? {
                None => lo = mid,
                Some(e) => {
                    hi = mid;
                    mechanism = Some(e);
                }
            }
        }
    }
    let collapses = mechanism.is_some();
    let (upper_bound, upper_bound_meaning) = bound_figures(&s.bound);
    let (message, motion) = mechanism.map_or((None, None), |(e, m)| (Some(e), m));
    Ok(Found {
        multiplier: lo,
        info: CollapseSummary {
            collapses_at: collapses.then_some(hi),
            max: c.max,
            mechanism: message.map(|e| e.message().to_string()),
            motion: motion
                .as_ref()
                .map(|m| super::mechanism::mechanism_bodies(session.model, m)),
            multiplier: lo,
            state: "the results are those of the largest multiplier with an equilibrium",
            tolerance: c.tolerance,
            trials: s.trials,
            upper_bound,
            upper_bound_meaning,
        },
        motion,
    })
}

/// The trials of a search that bisects down to its tolerance: t = 0, `max`, and one per
/// halving of [0, max] until the bracket is within the tolerance (fewer where `max`
/// stands). The brackets are exact: their ends are multiples of max / 2^k. (The scene
/// refuses a tolerance finer than floating point resolves; the bound only guards the loop.)
fn trials_needed(c: &Collapse) -> u64 {
    let mut width = c.max;
    let mut trials = 2;
    while width > c.tolerance && trials < 2100 {
        width *= 0.5;
        trials += 1;
    }
    trials
}

/// The summary's `upper_bound` and what it is (or why there is none).
fn bound_figures(b: &Bound) -> (Option<f64>, String) {
    match b {
        Bound::Value(t) => (
            Some(*t),
            "the largest t at which interface forces within the pairs' laws (Coulomb's cone, \
             no tension) balance every body that no displacement condition holds (rigid-block \
             statics, docs/formulation.md §6.9): no equilibrium exists above it"
                .to_string(),
        ),
        Bound::Unbounded => (
            None,
            "none: such forces exist at every t (the rigid-block statics is unbounded)".into(),
        ),
        Bound::Infeasible => (
            None,
            "none: such forces exist at no t (the rigid-block statics is infeasible)".into(),
        ),
        Bound::None(why) => (None, format!("none: {why}")),
    }
}
