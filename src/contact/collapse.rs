//! The collapse search: the largest load multiplier t with an equilibrium
//! (docs/formulation.md §11).
//!
//! Place in the flow: called by the `driver` before the run itself, which is then made at
//! the multiplier found. Each trial is a single step from the unloaded state at t; a trial
//! stands when the contact problem has a solution and fails when the solver reports a
//! mechanism (no equilibrium exists). The multiplier is bracketed by bisection between 0
//! (which must stand) and `max`, down to `tolerance`.

use std::time::Instant;

use super::driver::{step_at, StepAcc, StepContext, Stepper};
use crate::bem::Operators;
use crate::contact::Session;
use crate::error::{Error, Result};
use crate::input::model::fmt_num;
use crate::input::scene::Collapse;
use crate::solution::{BodyMotion, CollapseSummary, CollapseTrial};
use crate::timings::Timings;

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
}

impl Search<'_, '_> {
    /// One trial at `t`: `Some((mechanism, motion))` when no equilibrium exists, an error
    /// when the solver fails otherwise.
    fn trial(
        &mut self,
        t: f64,
        session: &mut Session,
        timings: &mut Timings,
        reassembled: &mut Option<Operators>,
    ) -> Result<Option<Collapsed>> {
        let mut st = session.initial();
        let mut a = StepAcc::default();
        let t0 = Instant::now();
        // The trial's stages are timed within the search, so that the total counts them once.
        let mut inner = Timings::default();
        step_at(
            self.stepper,
            session,
            self.ctx,
            0,
            (1.0, t),
            &mut st,
            &mut a,
            &mut inner,
            reassembled,
        )?;
        timings.add_within("collapse_search", t0.elapsed().as_secs_f64(), inner);
        let outcome = match a.failure {
            None => None,
            Some(e) if a.mechanism => Some((e, a.motion)),
            Some(e) => {
                return Err(Error::numerical(format!(
                    "the collapse search failed at t = {}: {}",
                    fmt_num(t),
                    e.message()
                )))
            }
        };
        self.trials.push(CollapseTrial {
            stands: outcome.is_none(),
            t,
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
    };
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
        },
        motion,
    })
}
