//! The contact stage's driver: the load path of a run over one [`Session`].
//!
//! Place in the flow: `bem::prepare` (the bodies' operators) → **`driver`** → post-processing.
//! [`solve`] runs every load step from the state the previous one left (docs/formulation.md
//! §6, §10): the main solver gives the answer and the history, the cross-check solvers solve the
//! same step from the same state and their statuses are compared pair by pair. A
//! "no equilibrium" of the evolutive path or the QP is first put to the rigid-block statics
//! (`statics`): where that LP is infeasible no equilibrium exists and the run reports the
//! mechanism at once; otherwise the sparse solver tries the step from the same state. With
//! Coulomb pairs the LP's verdict then confirms the "no equilibrium", or leaves it
//! undecided. A step that does not converge for a reason other than a
//! mechanism (confirmed or undecided) is solved again in substeps; with
//! `[solve] time` and loads that depend on t, every step is assembled at its pseudo-time (the
//! operators are those of the bodies; the columns of the opening stiffness are kept). With
//! `[solve] collapse` the largest load multiplier with an equilibrium is searched first
//! (`collapse`), then the run is made at that multiplier.

use std::collections::HashSet;
use std::time::Instant;

use crate::bem::quadrature::QuadratureSettings;
use crate::bem::{prepare, Operators};
use crate::contact::cuts::{at_joints, guess, recut, MAX_RECUTS};
use crate::contact::problem::{Component, Cuts};
use crate::contact::statics::Verdict;
use crate::contact::{status_differences, ContactResult, Iterate, Session, Solver, StepState};
use crate::error::{Error, Result};
use crate::input::model::{fmt_num, Model};
use crate::input::scene::{HistoryLevel, Method, Scene};
use crate::output::progress::{ContactTick, Progress, Stage};
use crate::plan::{ContactProblem, Plan};
use crate::solution::{
    BodyField, BodyMotion, CollapseSummary, ContactSolveSummary, ContactSummary, CrossCheck,
    History, ImpliedComponent, ImpliedSlipping, InterfaceResult, Junctions, LinearSummary,
    PairStatus, RunStatus, SlippingPair, SolverInfo,
};
use crate::timings::Timings;

/// What the contact stage works on.
#[derive(Clone, Copy)]
pub struct Case<'a> {
    pub scene: &'a Scene,
    pub model: &'a Model,
    pub plan: &'a Plan,
    pub settings: &'a QuadratureSettings,
}

/// Everything the contact stage computed, for post-processing and the writers.
pub struct ContactRun {
    pub status: RunStatus,
    pub load_factor: f64,
    /// Pseudo-time of the final state (1 without `[solve] time`).
    pub time: f64,
    /// Body force of each body at the final state (before the load factor).
    pub body_force: Vec<Option<[f64; 2]>>,
    pub fields: Vec<BodyField>,
    pub interfaces: Vec<InterfaceResult>,
    /// Nodal normal contact force of each interface pair (on the second body, compression
    /// positive): the force the complementarity conditions hold.
    pub nodal_force: Vec<Vec<f64>>,
    pub history: History,
    pub states: Vec<Iterate>,
    /// The summary's `contact` block.
    pub contact: ContactSummary,
    /// The QP's solution at the last load step, where it ran.
    pub qp: Option<QpCheck>,
    pub notes: Vec<String>,
    pub failure: Option<Error>,
    /// Where the run failed at a mechanism whose motion was found: the moving bodies' rigid
    /// motions (fastest boundary node at 1).
    pub mechanism: Option<Vec<BodyMotion>>,
    /// The motion of the collapse search's mechanism at `collapses_at`, where it found one.
    pub collapse_mechanism: Option<Vec<BodyMotion>>,
    /// The bodies' operators at the final pseudo-time where they were assembled again
    /// there (loads that depend on t); otherwise those the stage was given hold.
    pub operators: Option<Operators>,
}

/// The QP's solution at the last load step (as the main solver or a cross-check).
#[derive(Clone)]
pub struct QpCheck {
    pub interfaces: Vec<InterfaceResult>,
    pub converged: bool,
    /// Pairs whose status differs from the main solver's, as a cross-check.
    pub differing_pairs: Option<usize>,
    /// The solver's figures (iterations, status).
    pub info: SolverInfo,
}

/// Solves the contact problem of `case` (or, without unilateral interfaces, the one linear
/// system) along the scene's load path, on the bodies' operators `ops`.
pub fn solve(
    case: Case,
    ops: &Operators,
    timings: &mut Timings,
    progress: &Progress,
) -> Result<ContactRun> {
    let Case {
        scene, model, plan, ..
    } = case;
    let t = Instant::now();
    // The sparse solver's problem cuts junction cycles at whole joints (`Cuts::Joints`),
    // which a wall's T-junctions need to be exact, up to `JOINT_CUTS_MAX_PAIRS`; the others
    // keep the tangential cut (`Cuts::Tangential`) of the paper's scenes.
    let joints = at_joints(scene, model);
    let cuts = if joints {
        Cuts::Joints
    } else {
        Cuts::Tangential
    };
    let mut session = Session::with_cuts(model, ops, cuts).map_err(|e| plan.explain(e))?;
    timings.add("interface_system", t.elapsed().as_secs_f64());
    if plan.problem == ContactProblem::None {
        return solve_linear(case, &session, ops, timings);
    }
    let maxit = scene
        .solve
        .max_iterations
        .unwrap_or_else(|| (4 * session.problem.n_open_rows).max(1000));
    let (main, checks) = solvers(scene.solve.method, session.problem.n_open_rows);
    let steps = scene.solve.steps();
    let stage = progress.contact(steps.len());
    session.stage = Some(stage.clone());
    let stepper = Stepper {
        case,
        timed: timed(scene),
    };
    let mut reassembled = None;
    let ctx = |checks, steps: &[(f64, f64)]| StepContext {
        scene,
        model,
        main,
        checks,
        last: steps.len() - 1,
        steps: steps.len(),
        tol: scene.solve.tolerance,
        maxit,
        stage: &stage,
    };
    // The collapse search: the largest multiplier t with an equilibrium, then the run
    // itself at that t.
    let (steps, collapse) = match scene.solve.collapse {
        None => (steps, None),
        Some(c) => {
            let trial = ctx(&[], &[(1.0, 0.0)]);
            let found = super::collapse::search(
                &c,
                &stepper,
                &trial,
                &mut session,
                timings,
                &mut reassembled,
            )?;
            // The run follows the load path of the trial that stood at the multiplier: in
            // the steps of t that trial was solved in (two where one left it undecided).
            let m = found.multiplier;
            let parts = found
                .info
                .trials
                .iter()
                .rev()
                .find(|x| x.stands && x.t == m)
                .map_or(1, |x| x.steps.max(1));
            stage.count_steps(parts as u64);
            let path = (1..=parts)
                .map(|k| (1.0, m * k as f64 / parts as f64))
                .collect();
            (path, Some(found))
        }
    };
    let mut acc = load_path(
        &stepper,
        &mut session,
        &ctx(&checks, &steps),
        &steps,
        timings,
        &mut reassembled,
    )?;
    let session = if joints {
        move_cuts(
            (&stepper, &ctx(&checks, &steps), &steps),
            session,
            &mut acc,
            timings,
            &mut reassembled,
        )?
    } else {
        session
    };
    stage.finish();
    let (info, motion) = collapse.map_or((None, None), |f| (Some(f.info), f.motion));
    let mut run = finish(&session, main, steps.len(), acc, info)?;
    run.collapse_mechanism = motion;
    run.operators = reassembled;
    Ok(run)
}

/// `[solve] junctions = "joints"` after the load path: while implied components of the
/// state in `acc` break their law, the cuts of their cycles move ([`recut`]) and the path
/// is solved again on the new cut, from the statuses of the last (up to [`MAX_RECUTS`]
/// times). A path that does not converge on the new cut leaves the last state, on the
/// last cut. Returns the session of the state in `acc`.
fn move_cuts<'a>(
    (stepper, ctx, steps): (&Stepper, &StepContext, &[(f64, f64)]),
    session: Session<'a>,
    acc: &mut StepAcc,
    timings: &mut Timings,
    reassembled: &mut Option<Operators>,
) -> Result<Session<'a>> {
    let (model, ops, plan) = (session.model, session.prepared, stepper.case.plan);
    let stage = session.stage.clone();
    // One session at a time: two problems at once would add to the peak.
    let fresh = |cuts: &HashSet<Component>, timings: &mut Timings| -> Result<Session<'a>> {
        let t = Instant::now();
        let mut s = Session::with_cuts(model, ops, Cuts::At(cuts)).map_err(|e| plan.explain(e))?;
        s.stage = stage.clone();
        timings.add("interface_system", t.elapsed().as_secs_f64());
        Ok(s)
    };
    let mut cuts = session.problem.cuts.clone();
    let mut held = session;
    for round in 0..=MAX_RECUTS {
        if acc.failure.is_some() {
            break;
        }
        let Some(sol) = &acc.final_sol else { break };
        let (broken, moved) = recut(model, &held.problem, &sol.interfaces, &mut cuts);
        if broken > 0 && (moved == 0 || round == MAX_RECUTS) {
            acc.notes.push(format!(
                "junctions: {broken} implied components break their law (slipping ones are \
                 listed in contact.junctions.implied_slipping), and every other component of \
                 their cycles carries force there: such a cycle needs every pair's own row \
                 (method = \"exact\")"
            ));
        }
        if broken == 0 || moved == 0 || round == MAX_RECUTS {
            break;
        }
        let interfaces = sol.interfaces.clone();
        let last = held.problem.cuts.clone();
        drop(held);
        release_freed_memory();
        let mut next = fresh(&cuts, timings)?;
        next.guess = Some(guess(model, &next.problem, &interfaces, steps.len() - 1));
        let again = load_path(stepper, &mut next, ctx, steps, timings, reassembled)?;
        if again.failure.is_some() {
            drop(next);
            acc.notes.push(format!(
                "junctions: {broken} implied components break their law (see \
                 contact.junctions.implied_slipping); the load path with their cycles cut at \
                 {moved} other components did not converge, so this solution is kept"
            ));
            return fresh(&last, timings);
        }
        let mut notes = std::mem::take(&mut acc.notes);
        *acc = again;
        held = next;
        notes.push(format!(
            "junctions: {broken} implied components broke their law (a pair sliding at a \
             junction node without a friction force of its own, or pressing into its \
             neighbour); their cycles were cut at {moved} other components that carry no \
             force there, and the load path was solved again"
        ));
        notes.append(&mut acc.notes);
        acc.notes = notes;
    }
    Ok(held)
}

/// Hands the heap's freed pages back to the system: the problem of the last cut was built on
/// rayon's threads, whose allocator arenas keep its pages after it is dropped, so the next
/// one's would add to the peak (a 204-brick wall: 554–638 MB in runs alike without this).
fn release_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only releases free memory of the heap; it takes no pointer.
    unsafe {
        libc::malloc_trim(0);
    }
}

/// Whether every step is evaluated and assembled at its own pseudo-time: with `[solve]
/// time` (or a collapse search) and values that depend on t.
fn timed(scene: &Scene) -> bool {
    (scene.solve.time.is_some() || scene.solve.collapse.is_some()) && crate::plan::uses_time(scene)
}

/// The main solver and the cross-checks of a scene's `method`.
fn solvers(method: Method, open_rows: usize) -> (Solver, Vec<Solver>) {
    let main = match method {
        Method::Qp => Solver::Qp,
        Method::Sparse => Solver::Sparse,
        Method::Exact => return (Solver::Exact, Vec::new()),
        _ => Solver::Evolutive,
    };
    if method == Method::Sparse {
        // The paper's path cross-checks the sparse solver while its columns are affordable.
        let checks = if open_rows <= 2000 {
            vec![Solver::Evolutive]
        } else {
            Vec::new()
        };
        return (main, checks);
    }
    let mut checks = vec![Solver::ActiveSet];
    if method == Method::Both {
        checks.push(Solver::Qp);
        if open_rows <= 2000 {
            checks.push(Solver::Lemke);
        }
    }
    (main, checks)
}

/// Without unilateral interfaces: one linear solve at the last load step.
fn solve_linear(
    case: Case,
    session: &Session,
    ops: &Operators,
    timings: &mut Timings,
) -> Result<ContactRun> {
    let Case {
        scene,
        model,
        plan,
        settings,
    } = case;
    let t = Instant::now();
    let steps = scene.solve.steps();
    let (f, time) = steps[steps.len() - 1];
    let at = if timed(scene) && time != model.time {
        let m = model.at_time(scene, time)?;
        let p = prepare(&m, scene.plane, settings, 1.0, &scene.path, &|_| {})
            .map_err(|e| plan.explain(e))?;
        Some((m, p))
    } else {
        None
    };
    let (m, p) = match &at {
        Some((m, p)) => (m, p),
        None => (model, ops),
    };
    // The session's factorised system serves unless the loads are those of another t.
    let other = match &at {
        Some(_) => Some(crate::contact::problem::Problem::new(m, p).map_err(|e| plan.explain(e))?),
        None => None,
    };
    let problem = other.as_ref().unwrap_or(&session.problem);
    let n = problem.n_open_rows;
    let start = session.initial();
    let (fields, interfaces, nodal_force) = problem.state(m, p, f, &vec![0.0; n], &start.open);
    timings.add("solve", t.elapsed().as_secs_f64());
    let junctions = m.junctions();
    let contact = ContactSummary::Linear(LinearSummary {
        junctions: (!junctions.is_empty())
            .then(|| junctions_summary(m, &junctions, &problem.implied, false)),
        solver: "linear (no unilateral interface)",
    });
    let body_force = m.bodies.iter().map(|b| b.body_force).collect();
    drop(other);
    Ok(ContactRun {
        status: RunStatus::Solved,
        load_factor: f,
        time,
        body_force,
        fields,
        interfaces,
        nodal_force,
        history: History::default(),
        states: Vec::new(),
        contact,
        qp: None,
        notes: Vec::new(),
        failure: None,
        mechanism: None,
        collapse_mechanism: None,
        operators: at.map(|(_, p)| p),
    })
}

/// Every load step in turn, each from the state the previous one left; stops at a failure.
fn load_path(
    stepper: &Stepper,
    session: &mut Session,
    ctx: &StepContext,
    steps: &[(f64, f64)],
    timings: &mut Timings,
    reassembled: &mut Option<Operators>,
) -> Result<StepAcc> {
    let mut state = session.initial();
    let mut acc = StepAcc::default();
    for (step, &to) in steps.iter().enumerate() {
        // Where the step starts, for substeps: the previous step, or (timed paths aside)
        // the unloaded state.
        let from = match step {
            0 if stepper.timed => None,
            0 => Some((0.0, to.1)),
            _ => Some(steps[step - 1]),
        };
        load_step(
            stepper,
            session,
            ctx,
            (step, from, to, 0),
            &mut state,
            &mut acc,
            timings,
            reassembled,
        )?;
        if acc.failure.is_some() {
            break;
        }
    }
    Ok(acc)
}

/// The run's result from what the load steps accumulated (and the collapse search that
/// chose the load multiplier, where there was one).
fn finish(
    session: &Session,
    main: Solver,
    steps: usize,
    acc: StepAcc,
    collapse: Option<CollapseSummary>,
) -> Result<ContactRun> {
    let StepAcc {
        iterations,
        residual,
        final_sol,
        cross,
        qp_block,
        notes,
        history,
        states,
        failure,
        mechanism,
        motion,
        ..
    } = acc;
    let converged = failure.is_none();
    let Some(sol) = final_sol else {
        return Err(Error::numerical("the contact stage produced no state"));
    };
    let junctions = session.model.junctions();
    // The full-row solver gives every pair component its own row: none is implied.
    let none = Vec::new();
    let implied = if main == Solver::Exact {
        &none
    } else {
        &session.problem.implied
    };
    let junctions = (!junctions.is_empty()).then(|| Junctions {
        implied_slipping: Some(implied_slipping(
            session.model,
            &session.problem,
            implied,
            &sol.interfaces,
        )),
        ..junctions_summary(
            session.model,
            &junctions,
            implied,
            !session.problem.cuts.is_empty(),
        )
    });
    let contact = ContactSummary::Contact(Box::new(ContactSolveSummary {
        collapse,
        complementarity_residual: residual,
        converged,
        cross_checks: cross,
        interface_system_size: session.problem.base_size(),
        iterations,
        junctions,
        load_steps: steps,
        opening_stiffness_columns: session.cols.computed(),
        problem: if main == Solver::Exact {
            "every pair component its own row (junctions exact): the bodies' energy on the \
             symmetric Steklov-Poincare stiffness, minimised under every pair's law (one convex \
             programme per set of slip bounds; Coulomb's fixed point for friction), or one \
             linear solve of the law where the statuses are known (from the sparse solver on a \
             first step, from the programmes after)"
        } else {
            "nodal contact forces against nodal gaps on the symmetric Steklov-Poincare \
             stiffness (one LCP; Tresca fixed point for friction)"
        },
        solver: main.name(),
    }));
    Ok(ContactRun {
        status: if converged {
            RunStatus::Converged
        } else {
            RunStatus::NotConverged
        },
        load_factor: sol.load_factor,
        time: sol.time,
        body_force: sol.body_force,
        fields: sol.fields,
        interfaces: sol.interfaces,
        nodal_force: sol.nodal_force,
        history,
        states,
        contact,
        qp: qp_block,
        notes,
        failure,
        // An undecided step has no mechanism to show.
        mechanism: if mechanism { motion } else { None },
        collapse_mechanism: None,
        operators: None,
    })
}

/// What every load step of a contact run shares.
pub(super) struct StepContext<'a> {
    scene: &'a Scene,
    model: &'a Model,
    main: Solver,
    checks: &'a [Solver],
    last: usize,
    steps: usize,
    tol: f64,
    maxit: usize,
    pub(super) stage: &'a Stage,
}

/// The `contact.junctions` block: how many points join three or more bodies, and the pair
/// components there that the kept rows imply (no row of their own; see
/// `contact::problem::Problem::new`), by interface.
fn junctions_summary(
    model: &Model,
    junctions: &[([f64; 2], Vec<usize>)],
    implied: &[crate::contact::problem::Implied],
    at_joints: bool,
) -> Junctions {
    let mut by_iface: std::collections::BTreeMap<String, Vec<ImpliedComponent>> =
        std::collections::BTreeMap::new();
    for i in implied {
        let it = &model.interfaces[i.iface];
        by_iface
            .entry(it.spec.name.clone())
            .or_default()
            .push(ImpliedComponent {
                component: if i.comp == 1 { "normal" } else { "tangential" },
                x: it.pairs[i.pair].x,
            });
    }
    let most = junctions.iter().map(|j| j.1.len()).max().unwrap_or(0);
    Junctions {
        implied: by_iface,
        implied_components: implied.len(),
        implied_slipping: None,
        most_bodies_at_a_point: most,
        points: junctions.len(),
        rule: if at_joints {
            "at a point where bodies meet in a cycle of pairs, the cycle is cut at a whole \
             pair where it joins a normal component to tangential ones (at a T-junction the \
             head joint: each bed joint keeps its friction there), and moved to another \
             component where an implied one broke its law (solve.junctions); the implied \
             components carry no force of their own"
        } else {
            "at a point where bodies meet in a cycle of pairs, rows are kept bonded first \
             (normal components first), then unilateral normal, then tangential, while \
             independent; the others are implied by the kept rows while these are closed, \
             and carry no force of their own"
        },
    }
}

/// The implied tangential components of closed pairs with friction (`friction` or `stick`)
/// whose tangential jump is not zero (above 1e-9 of the model's size) in the final state,
/// where that breaks the pair's law (`cuts::slip_breaks_law`: a stick pair, or a friction
/// pair whose normal component has a row): there the pair slides at its junction node
/// without a friction force of its own, since an implied component has no row (it slides by
/// the opening of a joint of its cycle, e.g. a bed joint beside a head joint that opens). A
/// one-node approximation of each such joint, counted and located so that it is seen. A
/// friction pair whose normal component is implied too carries no force at that node, and
/// its slip there obeys Coulomb's law: not listed.
fn implied_slipping(
    model: &Model,
    problem: &crate::contact::problem::Problem,
    implied: &[crate::contact::problem::Implied],
    interfaces: &[InterfaceResult],
) -> ImpliedSlipping {
    let tol = 1e-9 * model.scale;
    let mut at = Vec::new();
    let mut largest = 0.0f64;
    for i in implied.iter().filter(|i| i.comp == 0) {
        let it = &model.interfaces[i.iface];
        if !crate::contact::cuts::slip_breaks_law(model, problem, i) {
            continue;
        }
        let Some(p) = interfaces.get(i.iface).and_then(|r| r.pairs.get(i.pair)) else {
            continue;
        };
        let slip = p.jump[0].abs();
        if p.status == PairStatus::Closed && slip > tol {
            largest = largest.max(slip);
            at.push(SlippingPair {
                interface: it.spec.name.clone(),
                slip: p.jump[0],
                x: it.pairs[i.pair].x,
            });
        }
    }
    ImpliedSlipping {
        count: at.len(),
        at,
        largest_slip: largest,
        meaning: "closed pairs whose tangential component is implied at a junction and slips \
                  there while the pair presses there (its normal component has a row) or \
                  sticks: at that node the pair slides without a friction force of its own",
    }
}

/// The final boundary solution of a step.
#[derive(Clone)]
struct FinalState {
    load_factor: f64,
    time: f64,
    body_force: Vec<Option<[f64; 2]>>,
    fields: Vec<BodyField>,
    interfaces: Vec<InterfaceResult>,
    nodal_force: Vec<Vec<f64>>,
}

/// What a load step needs to evaluate the model at another pseudo-time.
pub(super) struct Stepper<'a> {
    pub(super) case: Case<'a>,
    /// Every step is assembled at its own pseudo-time ([`timed`]).
    pub(super) timed: bool,
}

/// A (sub)step: the load step, where it starts (load factor, time; none for the first step
/// of a load path), where it ends, and the subdivision level.
type StepSpan = (usize, Option<(f64, f64)>, (f64, f64), usize);

/// Substep levels of a load step that does not converge (up to 2³ substeps).
const MAX_SUBDIVISION: usize = 3;

/// One load step from the state `state`, to the load factor and pseudo-time `to`; a step
/// that does not converge for a reason other than a mechanism is solved again in two halves
/// from `from` (recursively, up to [`MAX_SUBDIVISION`] levels). `at` = (step, from, to,
/// level).
#[allow(clippy::too_many_arguments)]
fn load_step(
    stp: &Stepper,
    session: &mut Session,
    ctx: &StepContext,
    at: StepSpan,
    state: &mut StepState,
    acc: &mut StepAcc,
    timings: &mut Timings,
    reassembled: &mut Option<Operators>,
) -> Result<()> {
    let (step, from, to, level) = at;
    if level == 0 {
        acc.substeps = 0;
    }
    let saved = (state.clone(), acc.mark());
    step_at(
        stp,
        session,
        ctx,
        step,
        to,
        state,
        acc,
        timings,
        reassembled,
    )?;
    let Some(from) = from else { return Ok(()) };
    // No substeps for a mechanism, nor where the rigid-block statics left the solver's "no
    // equilibrium" undecided (the solver's finding is a mechanism's all the same).
    let found_mechanism = acc.mechanism || acc.statics.is_some();
    if acc.failure.is_none() || found_mechanism || level >= MAX_SUBDIVISION {
        acc.substeps += 1;
        return Ok(());
    }
    let why = acc
        .failure
        .as_ref()
        .map(|e| e.message().to_string())
        .unwrap_or_default();
    acc.restore(saved.1);
    *state = saved.0;
    let mid = (0.5 * (from.0 + to.0), 0.5 * (from.1 + to.1));
    load_step(
        stp,
        session,
        ctx,
        (step, Some(from), mid, level + 1),
        state,
        acc,
        timings,
        reassembled,
    )?;
    if acc.failure.is_none() {
        load_step(
            stp,
            session,
            ctx,
            (step, Some(mid), to, level + 1),
            state,
            acc,
            timings,
            reassembled,
        )?;
    }
    if level == 0 {
        acc.notes.push(format!(
            "load step {} (load factor {}, t = {}) did not converge in one step ({why}); it \
             was solved again in {} substeps from load factor {}, t = {}{}",
            step + 1,
            fmt_num(to.0),
            fmt_num(to.1),
            acc.substeps,
            fmt_num(from.0),
            fmt_num(from.1),
            if acc.failure.is_none() {
                ", which converged"
            } else {
                ", the last of which did not converge either"
            }
        ));
        acc.substeps = 0;
    }
    Ok(())
}

/// Solves one (sub)step at `(f, time)`: on the run's session, or, where the loads depend on
/// t and the pseudo-time differs from the model's, on the model evaluated and assembled at
/// `time` (the columns of the opening stiffness move between the sessions).
#[allow(clippy::too_many_arguments)]
pub(super) fn step_at(
    stp: &Stepper,
    session: &mut Session,
    ctx: &StepContext,
    step: usize,
    (f, time): (f64, f64),
    state: &mut StepState,
    acc: &mut StepAcc,
    timings: &mut Timings,
    reassembled: &mut Option<Operators>,
) -> Result<()> {
    if !stp.timed || time == stp.case.model.time {
        contact_step(session, ctx, step, f, state, acc, timings);
        return Ok(());
    }
    let Case {
        scene,
        model,
        plan,
        settings,
    } = stp.case;
    let model_t = model.at_time(scene, time)?;
    let prepared_t = prepare(&model_t, scene.plane, settings, 1.0, &scene.path, &|_| {})
        .map_err(|e| plan.explain(e))?;
    timings.add("assemble", prepared_t.assemble_seconds);
    timings.add("condense", prepared_t.condense_seconds);
    let t1 = Instant::now();
    {
        // The same cut of the junction cycles as the run's own session (`Cuts::At` of its
        // cut components reproduces `Cuts::Joints`, and of none `Cuts::Tangential`).
        let cuts = Cuts::At(&session.problem.cuts);
        let mut s = Session::with_cuts(&model_t, &prepared_t, cuts).map_err(|e| plan.explain(e))?;
        s.cols = std::mem::take(&mut session.cols);
        s.coupled_after = session.coupled_after;
        s.last_from_rest = session.last_from_rest.take();
        timings.add("interface_system", t1.elapsed().as_secs_f64());
        // Cohesion follows its expression where the pair has never opened.
        for (k, it) in model_t.interfaces.iter().enumerate() {
            for (j, p) in it.pairs.iter().enumerate() {
                if !state.broken[k][j] {
                    state.cohesion[k][j] = p.cohesion;
                }
            }
        }
        contact_step(&mut s, ctx, step, f, state, acc, timings);
        session.cols = std::mem::take(&mut s.cols);
        session.last_from_rest = s.last_from_rest.take();
    }
    *reassembled = Some(prepared_t);
    Ok(())
}

/// Lengths and values of a [`StepAcc`] to go back to.
struct AccMark {
    iterations: usize,
    residual: f64,
    final_sol: Option<FinalState>,
    cross: usize,
    qp_block: Option<QpCheck>,
    notes: usize,
    rows: usize,
    states: usize,
    recorded: usize,
}

impl StepAcc {
    fn mark(&self) -> AccMark {
        AccMark {
            iterations: self.iterations,
            residual: self.residual,
            final_sol: self.final_sol.clone(),
            cross: self.cross.len(),
            qp_block: self.qp_block.clone(),
            notes: self.notes.len(),
            rows: self.history.rows.len(),
            states: self.states.len(),
            recorded: self.recorded,
        }
    }

    /// Forgets what was accumulated since `m` (a failed step solved again in substeps).
    fn restore(&mut self, m: AccMark) {
        self.iterations = m.iterations;
        self.residual = m.residual;
        self.final_sol = m.final_sol;
        self.cross.truncate(m.cross);
        self.qp_block = m.qp_block;
        self.notes.truncate(m.notes);
        self.history.rows.truncate(m.rows);
        self.states.truncate(m.states);
        self.recorded = m.recorded;
        self.failure = None;
        self.mechanism = false;
        self.undecided = false;
        self.motion = None;
        self.statics = None;
    }
}

/// What the load steps of a contact run accumulate.
#[derive(Default)]
pub(super) struct StepAcc {
    iterations: usize,
    residual: f64,
    final_sol: Option<FinalState>,
    cross: Vec<CrossCheck>,
    qp_block: Option<QpCheck>,
    notes: Vec<String>,
    history: History,
    states: Vec<Iterate>,
    /// The states of a full history so far (those kept and those `output.every` or
    /// "steps" left out): the number of the next one.
    recorded: usize,
    pub(super) failure: Option<Error>,
    /// The failure is a mechanism (no equilibrium): no substeps help.
    pub(super) mechanism: bool,
    /// The motion the solver found at its "no equilibrium", where found (also where the
    /// rigid-block check left it undecided: the run then reports none).
    pub(super) motion: Option<Vec<BodyMotion>>,
    /// The rigid-block check's verdict on that "no equilibrium", where it ran.
    pub(super) statics: Option<Verdict>,
    /// The failure leaves the step undecided (a fixed point that did not settle, a solver
    /// without progress): neither an equilibrium nor its absence is shown.
    pub(super) undecided: bool,
    /// Substeps solved since the last load step that was subdivided.
    substeps: usize,
}

/// One load step of a contact run: the main solver, the cross-checks, the history.
fn contact_step(
    session: &mut Session,
    ctx: &StepContext,
    step: usize,
    f: f64,
    state: &mut StepState,
    acc: &mut StepAcc,
    timings: &mut Timings,
) {
    let (scene, main) = (ctx.scene, ctx.main);
    let t = Instant::now();
    // "steps" records the iterations too (a status and an opening per row each), and keeps
    // the last of the step.
    let full = scene.output.history != HistoryLevel::Final;
    let mut r = session.solve_step(state, main, ctx.tol, ctx.maxit, step, f, full);
    timings.add(main.timing_key(), t.elapsed().as_secs_f64());
    let rescuable = matches!(main, Solver::Evolutive | Solver::Qp);
    // A "no equilibrium" that the rigid-block statics proves (an infeasible LP, a fraction
    // of a second) needs no rescue: no solver can find an equilibrium there.
    let known = (rescuable && r.mechanism).then(|| {
        let t = Instant::now();
        let v = super::statics::certify(session.model, f);
        timings.add("contact_statics", t.elapsed().as_secs_f64());
        v
    });
    if (r.mechanism || r.undecided) && rescuable && known != Some(Verdict::Infeasible) {
        // The pivoting path, or the QP's statuses checked exactly, can stop at a row that
        // cannot open without leaving a body free although an equilibrium exists, and the
        // QP may find no statuses that keep the stick law at closure (it poses each row
        // tied or free before it solves): the sparse solver decides it from the same state.
        let who = if main == Solver::Qp {
            "the QP"
        } else {
            "the evolutive path"
        };
        let t = Instant::now();
        let x = session.solve_step(state, Solver::Sparse, ctx.tol, ctx.maxit, step, f, full);
        timings.add(Solver::Sparse.timing_key(), t.elapsed().as_secs_f64());
        if x.converged && x.failure.is_none() {
            let why = r.failure.as_ref().map(|e| e.message().to_string());
            let what = if r.mechanism {
                "found no equilibrium"
            } else {
                "could not decide the step"
            };
            r = x;
            r.notes.push(format!(
                "load step {}: {who} {what} ({}); the sparse solver found an equilibrium \
                 from the same state, which is the step's result",
                step + 1,
                why.unwrap_or_default()
            ));
        }
    }
    // A "no equilibrium" with Coulomb pairs is checked by the rigid-block statics (the
    // verdict above holds where the rescue found none either: the same model and load).
    let t = Instant::now();
    let verdict = super::statics::judge_step(session.model, f, &mut r, known);
    if verdict.is_some() {
        timings.add("contact_statics", t.elapsed().as_secs_f64());
    }
    let t = Instant::now();
    keep_recorded(session, &mut r, scene, &mut acc.recorded);
    timings.add("contact_record", t.elapsed().as_secs_f64());
    for &c in ctx.checks {
        cross_check(session, ctx, c, step, f, state, &r.interfaces, acc, timings);
    }
    acc.iterations += r.iterations;
    acc.residual = acc.residual.max(r.residual);
    acc.notes.extend(r.notes.iter().cloned());
    acc.history.rows.extend(r.rows);
    if let Some(row) = acc.history.rows.last() {
        let status = row.status.iter().flatten();
        ctx.stage.contact_tick(&ContactTick {
            load_step: step,
            load_steps: ctx.steps,
            iteration: row.iteration,
            max_iterations: ctx.maxit,
            open_pairs: status.clone().filter(|s| **s == PairStatus::Open).count(),
            pairs: status.count(),
            detached_length: row.detached_length.iter().sum(),
            step_done: true,
        });
    }
    acc.states.extend(r.states);
    // The QP's own zones, unless the sparse solver gave the step's result.
    if main == Solver::Qp && r.solver == Solver::Qp.name() && step == ctx.last {
        acc.qp_block = Some(QpCheck {
            interfaces: r.interfaces.clone(),
            converged: r.converged,
            differing_pairs: None,
            info: r.info,
        });
    }
    *state = r.state;
    acc.final_sol = Some(FinalState {
        load_factor: f,
        time: session.model.time,
        body_force: session.body_forces(),
        fields: r.fields,
        interfaces: r.interfaces,
        nodal_force: r.nodal_force,
    });
    if let Some(e) = r.failure {
        acc.failure = Some(e);
        acc.mechanism = r.mechanism;
        acc.undecided = r.undecided;
        acc.motion = r.motion;
        acc.statics = verdict;
    }
}

/// Expands the recorded iterations of a load step that the history keeps: with "full" every
/// `output.every`-th (from the first) and the last, with "steps" the last; numbers the
/// states kept by their place in the full history, from `*recorded` on (which it advances).
fn keep_recorded(session: &Session, r: &mut ContactResult, scene: &Scene, recorded: &mut usize) {
    let m = r.recorded.len();
    let keep = |k: usize| match scene.output.history {
        HistoryLevel::Full => k.is_multiple_of(scene.output.every) || k + 1 == m,
        _ => k + 1 == m,
    };
    let kept: Vec<usize> = (0..m).filter(|&k| keep(k)).collect();
    let mut k = 0;
    r.recorded.retain(|_| {
        k += 1;
        keep(k - 1)
    });
    session.expand(r);
    for (s, &k) in r
        .states
        .iter_mut()
        .zip(kept.iter().chain(std::iter::repeat(&0)))
    {
        s.index = *recorded + k;
    }
    *recorded += m.max(r.states.len());
}

/// One cross-check of a load step: solver `c` from the same state, its statuses compared
/// with the main solver's (`main`) pair by pair.
#[allow(clippy::too_many_arguments)]
fn cross_check(
    session: &mut Session,
    ctx: &StepContext,
    c: Solver,
    step: usize,
    f: f64,
    state: &StepState,
    main: &[InterfaceResult],
    acc: &mut StepAcc,
    timings: &mut Timings,
) {
    let t = Instant::now();
    let x = session.solve_step(state, c, ctx.tol, ctx.maxit, step, f, false);
    timings.add(c.timing_key(), t.elapsed().as_secs_f64());
    let (all, degenerate) = status_differences(&x.interfaces, main, ctx.model.scale);
    let differing = all - degenerate;
    acc.cross.push(CrossCheck {
        converged: x.converged,
        degenerate_pairs: degenerate,
        differing_pairs: differing,
        failure: x.failure.as_ref().map(|e| e.message().to_string()),
        info: x.info.clone(),
        iterations: x.iterations,
        load_step: step,
        outer_iterations: x.outer_iterations,
        solver: c.name(),
    });
    if c == Solver::Qp && step == ctx.last {
        acc.qp_block = Some(QpCheck {
            interfaces: x.interfaces,
            converged: x.converged,
            differing_pairs: Some(differing),
            info: x.info,
        });
    }
}
