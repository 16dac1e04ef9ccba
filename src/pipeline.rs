//! The stage order of a run; the only module that knows it.
//!
//! Place in the flow: the top. `load` reads the scene and the mesh, builds the model and
//! decides the plan; `check` is `load` plus the report.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::input::mesh::{self, Mesh};
use crate::input::model::{self, Model};
use crate::input::scene::{self, Scene};
use crate::plan::{self, Plan};

/// A scene read and validated against its mesh.
#[derive(Debug, Clone)]
pub struct Loaded {
    pub scene: Scene,
    pub mesh: Mesh,
    pub model: Model,
    pub plan: Plan,
}

/// Reads the scene and its mesh (`mesh_override` replaces the scene's `mesh`), builds the
/// model and the plan.
pub fn load(scene_path: &Path, mesh_override: Option<&Path>) -> Result<Loaded> {
    load_with(
        scene_path,
        &LoadOptions {
            mesh: mesh_override.map(Path::to_path_buf),
            ..LoadOptions::default()
        },
    )
}

/// What `load_with` applies to the scene file.
#[derive(Debug, Clone, Default)]
pub struct LoadOptions {
    /// Replaces the scene's `mesh`.
    pub mesh: Option<PathBuf>,
    /// `--set KEY=VALUE` overrides, applied to the TOML document before validation.
    pub sets: Vec<String>,
    /// Where a `.geo` mesh is meshed; by default the `mesh` folder of the scene's output
    /// directory.
    pub mesh_dir: Option<PathBuf>,
}

/// [`load`] with `--set` overrides; a `.geo` mesh is meshed with gmsh first.
pub fn load_with(scene_path: &Path, opts: &LoadOptions) -> Result<Loaded> {
    if !scene_path.is_file() {
        return Err(Error::input(
            scene_path,
            "no such scene file: give the path of a .toml scene",
        ));
    }
    let scene = scene::read_scene_with(scene_path, &opts.sets)?;
    let mut mesh_path: PathBuf = match (&opts.mesh, &scene.mesh) {
        (Some(m), _) => m.clone(),
        (None, Some(m)) => m.clone(),
        (None, None) => {
            return Err(Error::input(
                scene_path,
                "no mesh: add mesh = \"FILE.msh\" to the scene or pass --mesh FILE.msh",
            ))
        }
    };
    if crate::input::gmsh::is_geo(&mesh_path) {
        let dir = opts
            .mesh_dir
            .clone()
            .unwrap_or_else(|| scene.output.directory.join("mesh"));
        mesh_path = crate::input::gmsh::mesh_geo(&mesh_path, &scene.mesh_parameters, &dir)?;
    }
    if !mesh_path.is_file() {
        return Err(Error::input(
            &mesh_path,
            "no such mesh file: mesh the .geo first (make mesh, or gmsh -2 -format msh41 FILE.geo)",
        ));
    }
    let mesh = mesh::read_msh(&mesh_path)?;
    let model = model::build(&scene, &mesh, &mesh_path)?;
    let plan = plan::plan(&scene, &model)?;
    Ok(Loaded {
        scene,
        mesh,
        model,
        plan,
    })
}

/// Command-line overrides of a run.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    pub mesh: Option<PathBuf>,
    pub out: Option<PathBuf>,
    pub method: Option<crate::input::scene::Method>,
    pub quiet: bool,
    /// `--set KEY=VALUE` overrides of the scene.
    pub sets: Vec<String>,
}

/// What a run produced, for the caller to report.
#[derive(Debug, Clone)]
pub struct RunReport {
    pub out_dir: PathBuf,
    pub summary: serde_json::Value,
    pub notes: Vec<String>,
}

/// Seconds per stage, in stage order.
#[derive(Debug, Clone, Default)]
pub struct Timings(pub Vec<(&'static str, f64)>);

impl Timings {
    fn add(&mut self, stage: &'static str, seconds: f64) {
        match self.0.iter_mut().find(|(s, _)| *s == stage) {
            Some((_, t)) => *t += seconds,
            None => self.0.push((stage, seconds)),
        }
    }
    fn json(&self) -> serde_json::Value {
        let mut m = serde_json::Map::new();
        let mut total = 0.0;
        for (s, t) in &self.0 {
            m.insert((*s).to_string(), serde_json::json!(t));
            total += t;
        }
        m.insert("total".into(), serde_json::json!(total));
        serde_json::Value::Object(m)
    }
}

/// Everything a run computed, for the writers.
pub struct RunResult {
    pub status: String,
    pub load_factor: f64,
    /// Pseudo-time of the final state (1 without `[solve] time`).
    pub time: f64,
    /// Body force of each body at the final state (before the load factor).
    pub body_force: Vec<Option<[f64; 2]>>,
    pub fields: Vec<crate::solution::BodyField>,
    pub interfaces: Vec<crate::solution::InterfaceResult>,
    /// Nodal normal contact force of each interface pair (on the second body, compression
    /// positive): the force the complementarity conditions hold.
    pub nodal_force: Vec<Vec<f64>>,
    pub history: crate::solution::History,
    pub states: Vec<crate::contact::RecordedState>,
    pub contact: serde_json::Value,
    pub qp: Option<serde_json::Value>,
    pub notes: Vec<String>,
    pub failure: Option<Error>,
}

/// The solve stages: assembly and condensation once, then the contact problem (or one
/// linear solve) for each load step, each step starting from the previous state.
pub fn solve_loaded(
    loaded: &Loaded,
    settings: &crate::bem::quadrature::QuadratureSettings,
    timings: &mut Timings,
) -> Result<(crate::contact::solve::Prepared, RunResult)> {
    solve_loaded_with(
        loaded,
        settings,
        timings,
        &crate::output::progress::Progress::hidden(),
    )
}

/// [`solve_loaded`] showing progress on a terminal.
pub fn solve_loaded_with(
    loaded: &Loaded,
    settings: &crate::bem::quadrature::QuadratureSettings,
    timings: &mut Timings,
    progress: &crate::output::progress::Progress,
) -> Result<(crate::contact::solve::Prepared, RunResult)> {
    solve_loaded_then(loaded, settings, timings, progress, &mut |_| {})
}

/// [`solve_loaded_with`] calling `after_prepare` with the body operators as soon as they are
/// assembled and condensed, before the contact stage (the run starts writing the archive).
fn solve_loaded_then(
    loaded: &Loaded,
    settings: &crate::bem::quadrature::QuadratureSettings,
    timings: &mut Timings,
    progress: &crate::output::progress::Progress,
    after_prepare: &mut dyn FnMut(&crate::contact::solve::Prepared),
) -> Result<(crate::contact::solve::Prepared, RunResult)> {
    use crate::contact::solve::prepare;
    use crate::contact::{Method as Solver, Session};
    use crate::input::scene::Method;
    use crate::plan::ContactProblem;
    use std::time::Instant;

    let Loaded {
        scene, model, plan, ..
    } = loaded;
    // Two steps per body (assembly, condensation); each message starts the next.
    let stage = progress.bar("assemble", 2 * model.bodies.len() as u64);
    let started = std::cell::Cell::new(0u64);
    // A numerical failure of the operators names the stiffness contrast when it is the
    // likely cause.
    let cause = |e: Error| -> Error {
        let (c, iface) = &plan.contrast;
        if e.exit_code() == 3 && *c >= 1e6 {
            Error::numerical(format!(
                "{}; likely cause: the stiffness contrast across interface \"{iface}\" is \
                 {c:.1e}, which costs about {:.0} of the 16 digits of the boundary systems: \
                 model the much stiffer body as a rigid support (displacement conditions) or \
                 keep the contrast below about 1e6",
                e.message(),
                c.log10()
            ))
        } else {
            e
        }
    };
    let prepared = prepare(model, scene.plane, settings, 1.0, &scene.path, &|m| {
        stage.set_position(started.get());
        started.set(started.get() + 1);
        stage.set_message(m.to_string())
    })
    .map_err(cause)?;
    stage.finish();
    timings.add("assemble", prepared.assemble_seconds);
    timings.add("condense", prepared.condense_seconds);
    after_prepare(&prepared);
    let steps = scene.solve.steps();
    let last = steps.len() - 1;
    // With `[solve] time` and values that depend on t, every step has its own loads: the
    // model is evaluated and the bodies assembled again at the step's pseudo-time (the
    // operators are the same; the columns of the opening stiffness are kept).
    let timed = (scene.solve.time.is_some() || scene.solve.collapse.is_some())
        && crate::plan::uses_time(scene);
    let method = scene.solve.method;
    let tol = scene.solve.tolerance;

    let t = Instant::now();
    let mut session = Session::new(model, &prepared).map_err(cause)?;
    let maxit = scene
        .solve
        .max_iterations
        .unwrap_or_else(|| (4 * session.problem.n_open_rows).max(1000));
    timings.add("interface_system", t.elapsed().as_secs_f64());
    if plan.problem == ContactProblem::None {
        let t = Instant::now();
        let (f, time) = steps[last];
        let at = if timed && time != model.time {
            let m = model.at_time(scene, time)?;
            let p = prepare(&m, scene.plane, settings, 1.0, &scene.path, &|_| {}).map_err(cause)?;
            Some((m, p))
        } else {
            None
        };
        let (m, p) = match &at {
            Some((m, p)) => (m, p),
            None => (model, &prepared),
        };
        // The session's factorised system serves unless the loads are those of another t.
        let other = match &at {
            Some(_) => Some(crate::contact::problem::Problem::new(m, p).map_err(cause)?),
            None => None,
        };
        let problem = other.as_ref().unwrap_or(&session.problem);
        let n = problem.n_open_rows;
        let start = session.initial();
        let (fields, interfaces, nodal_force) = problem.state(m, p, f, &vec![0.0; n], &start.open);
        timings.add("solve", t.elapsed().as_secs_f64());
        let mut contact = serde_json::json!({"solver": "linear (no unilateral interface)"});
        let junctions = m.junctions();
        if !junctions.is_empty() {
            contact["junctions"] = junctions_json(m, &junctions, &problem.implied);
        }
        let result = RunResult {
            status: "solved".into(),
            load_factor: f,
            time,
            body_force: m.bodies.iter().map(|b| b.body_force).collect(),
            fields,
            interfaces,
            nodal_force,
            history: crate::solution::History::default(),
            states: Vec::new(),
            contact,
            qp: None,
            notes: Vec::new(),
            failure: None,
        };
        drop(other);
        drop(session);
        return Ok((at.map_or(prepared, |(_, p)| p), result));
    }

    // The main solver gives the answer and the history; the others cross-check it on the
    // same problem (statuses compared pair by pair).
    let main = match method {
        Method::Qp => Solver::Qp,
        _ => Solver::Evolutive,
    };
    let mut checks = vec![Solver::ActiveSet];
    if method == Method::Both {
        checks.push(Solver::Qp);
        if session.problem.n_open_rows <= 2000 {
            checks.push(Solver::Lemke);
        }
    }
    let stage = progress.contact(steps.len());
    let mut last_prepared = None;
    let stepper = Stepper {
        scene,
        model,
        settings,
        timed,
        cause: &cause,
    };
    // The collapse search: the largest multiplier t with an equilibrium, then the run
    // itself at that t.
    let mut collapse_info = None;
    let (steps, last) = match scene.solve.collapse {
        None => (steps, last),
        Some(c) => {
            let trial_ctx = StepContext {
                scene,
                model,
                main,
                checks: &[],
                last: 0,
                steps: 1,
                tol,
                maxit,
                stage: &stage,
            };
            let mut trials: Vec<serde_json::Value> = Vec::new();
            // One trial: a single step from the unloaded state at t; Some(mechanism) when
            // no equilibrium exists, an error when the solver fails otherwise.
            let mut trial = |t: f64,
                             session: &mut crate::contact::Session,
                             timings: &mut Timings,
                             last_prepared: &mut Option<crate::contact::solve::Prepared>|
             -> Result<Option<Error>> {
                let mut st = session.initial();
                let mut a = StepAcc::default();
                let t0 = Instant::now();
                step_at(
                    &stepper,
                    session,
                    &trial_ctx,
                    0,
                    (1.0, t),
                    &mut st,
                    &mut a,
                    timings,
                    last_prepared,
                )?;
                timings.add("collapse_search", t0.elapsed().as_secs_f64());
                let outcome = match a.failure {
                    None => None,
                    Some(e) if a.mechanism => Some(e),
                    Some(e) => {
                        return Err(Error::numerical(format!(
                            "the collapse search failed at t = {}: {}",
                            crate::input::model::fmt_num(t),
                            e.message()
                        )))
                    }
                };
                trials.push(serde_json::json!({
                    "t": t, "stands": outcome.is_none(),
                }));
                Ok(outcome)
            };
            if let Some(e) = trial(0.0, &mut session, timings, &mut last_prepared)? {
                return Err(Error::numerical(format!(
                    "the collapse search found no equilibrium at t = 0 (before any load \
                     multiplier): {}",
                    e.message()
                )));
            }
            let (mut lo, mut hi) = (0.0, c.max);
            let mut mechanism = trial(c.max, &mut session, timings, &mut last_prepared)?;
            if mechanism.is_none() {
                lo = c.max;
            } else {
                while hi - lo > c.tolerance {
                    let mid = 0.5 * (lo + hi);
                    match trial(mid, &mut session, timings, &mut last_prepared)? {
                        None => lo = mid,
                        Some(e) => {
                            hi = mid;
                            mechanism = Some(e);
                        }
                    }
                }
            }
            let collapses = mechanism.is_some();
            collapse_info = Some(serde_json::json!({
                "multiplier": lo,
                "collapses_at": if collapses { serde_json::json!(hi) } else { serde_json::Value::Null },
                "tolerance": c.tolerance,
                "max": c.max,
                "mechanism": mechanism.map(|e| e.message().to_string()),
                "trials": trials,
                "state": "the results are those of the largest multiplier with an equilibrium",
            }));
            (vec![(1.0, lo)], 0)
        }
    };
    let mut state = session.initial();
    let mut acc = StepAcc::default();
    let ctx = StepContext {
        scene,
        model,
        main,
        checks: &checks,
        last,
        steps: steps.len(),
        tol,
        maxit,
        stage: &stage,
    };
    for (step, &to) in steps.iter().enumerate() {
        // Where the step starts, for substeps: the previous step, or (timed paths aside)
        // the unloaded state.
        let from = match step {
            0 if timed => None,
            0 => Some((0.0, to.1)),
            _ => Some(steps[step - 1]),
        };
        load_step(
            &stepper,
            &mut session,
            &ctx,
            (step, from, to, 0),
            &mut state,
            &mut acc,
            timings,
            &mut last_prepared,
        )?;
        if acc.failure.is_some() {
            break;
        }
    }
    stage.finish();
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
        ..
    } = acc;
    let converged = failure.is_none();
    let contact = serde_json::json!({
        "solver": main.name(),
        "problem": "nodal contact forces against nodal gaps on the symmetric Steklov-Poincare stiffness (one LCP; Tresca fixed point for friction)",
        "iterations": iterations,
        "converged": converged,
        "complementarity_residual": residual,
        "load_steps": steps.len(),
        "opening_stiffness_columns": session.cols.computed(),
        "interface_system_size": session.problem.base_size(),
        "cross_checks": cross,
    });
    let mut contact = contact;
    if let Some(c) = collapse_info {
        contact["collapse"] = c;
    }
    let Some((load_factor, time, body_force, fields, interfaces, nodal_force)) = final_sol else {
        return Err(Error::numerical("the contact stage produced no state"));
    };
    let junctions = session.model.junctions();
    if !junctions.is_empty() {
        let implied = &session.problem.implied;
        contact["junctions"] = junctions_json(session.model, &junctions, implied);
        contact["junctions"]["implied_slipping"] =
            implied_slipping(session.model, implied, &interfaces);
    }
    let result = RunResult {
        status: if converged {
            "converged".into()
        } else {
            "not converged".into()
        },
        load_factor,
        time,
        body_force,
        fields,
        interfaces,
        nodal_force,
        history,
        states,
        contact,
        qp: qp_block,
        notes,
        failure,
    };
    drop(session);
    Ok((last_prepared.unwrap_or(prepared), result))
}

/// What every load step of a contact run shares.
struct StepContext<'a> {
    scene: &'a crate::input::scene::Scene,
    model: &'a Model,
    main: crate::contact::Method,
    checks: &'a [crate::contact::Method],
    last: usize,
    steps: usize,
    tol: f64,
    maxit: usize,
    stage: &'a crate::output::progress::Stage,
}

/// The `contact.junctions` block: how many points join three or more bodies, and the pair
/// components there that the kept rows imply (no row of their own; see
/// `contact::problem::Problem::new`), by interface.
fn junctions_json(
    model: &Model,
    junctions: &[([f64; 2], Vec<usize>)],
    implied: &[crate::contact::problem::Implied],
) -> serde_json::Value {
    let mut by_iface: std::collections::BTreeMap<String, Vec<serde_json::Value>> =
        std::collections::BTreeMap::new();
    for i in implied {
        let it = &model.interfaces[i.iface];
        by_iface
            .entry(it.spec.name.clone())
            .or_default()
            .push(serde_json::json!({
                "x": it.pairs[i.pair].x,
                "component": if i.comp == 1 { "normal" } else { "tangential" },
            }));
    }
    let most = junctions.iter().map(|j| j.1.len()).max().unwrap_or(0);
    serde_json::json!({
        "points": junctions.len(),
        "most_bodies_at_a_point": most,
        "rule": "at a point where bodies meet in a cycle of pairs, rows are kept bonded first (normal components first), then unilateral normal, then tangential, while independent; the others are implied by the kept rows while these are closed, and carry no force of their own",
        "implied_components": implied.len(),
        "implied": by_iface,
    })
}

/// The implied tangential components of closed pairs with friction (`friction` or `stick`)
/// whose tangential jump is not zero (above 1e-9 of the model's size) in the final state:
/// there the pair slides at its junction node without a friction force of its own, since an
/// implied component has no row (it slides by the opening of a joint of its cycle, e.g. a
/// bed joint beside a head joint that opens). A one-node approximation of each such joint,
/// counted and located so that it is seen.
fn implied_slipping(
    model: &Model,
    implied: &[crate::contact::problem::Implied],
    interfaces: &[crate::solution::InterfaceResult],
) -> serde_json::Value {
    use crate::input::scene::Tangential;
    let tol = 1e-9 * model.scale;
    let mut at = Vec::new();
    let mut largest = 0.0f64;
    for i in implied.iter().filter(|i| i.comp == 0) {
        let it = &model.interfaces[i.iface];
        if !matches!(it.spec.tangential, Tangential::Friction | Tangential::Stick) {
            continue;
        }
        let Some(p) = interfaces.get(i.iface).and_then(|r| r.pairs.get(i.pair)) else {
            continue;
        };
        let slip = p.jump[0].abs();
        if p.status == crate::solution::PairStatus::Closed && slip > tol {
            largest = largest.max(slip);
            at.push(serde_json::json!({
                "interface": it.spec.name,
                "x": it.pairs[i.pair].x,
                "slip": p.jump[0],
            }));
        }
    }
    serde_json::json!({
        "count": at.len(),
        "largest_slip": largest,
        "meaning": "closed pairs whose tangential component is implied at a junction and slips there: at that node the pair slides without a friction force of its own",
        "at": at,
    })
}

/// The final boundary solution of a step: load factor, time, body forces, fields,
/// interfaces and nodal forces.
type FinalSolution = (
    f64,
    f64,
    Vec<Option<[f64; 2]>>,
    Vec<crate::solution::BodyField>,
    Vec<crate::solution::InterfaceResult>,
    Vec<Vec<f64>>,
);

/// What a load step needs to evaluate the model at another pseudo-time.
struct Stepper<'a> {
    scene: &'a crate::input::scene::Scene,
    model: &'a Model,
    settings: &'a crate::bem::quadrature::QuadratureSettings,
    timed: bool,
    cause: &'a dyn Fn(Error) -> Error,
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
    session: &mut crate::contact::Session,
    ctx: &StepContext,
    at: StepSpan,
    state: &mut crate::contact::StepState,
    acc: &mut StepAcc,
    timings: &mut Timings,
    last_prepared: &mut Option<crate::contact::solve::Prepared>,
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
        last_prepared,
    )?;
    let Some(from) = from else { return Ok(()) };
    if acc.failure.is_none() || acc.mechanism || level >= MAX_SUBDIVISION {
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
        last_prepared,
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
            last_prepared,
        )?;
    }
    if level == 0 {
        acc.notes.push(format!(
            "load step {} (load factor {}, t = {}) did not converge in one step ({why}); it \
             was solved again in {} substeps from load factor {}, t = {}{}",
            step + 1,
            crate::input::model::fmt_num(to.0),
            crate::input::model::fmt_num(to.1),
            acc.substeps,
            crate::input::model::fmt_num(from.0),
            crate::input::model::fmt_num(from.1),
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
fn step_at(
    stp: &Stepper,
    session: &mut crate::contact::Session,
    ctx: &StepContext,
    step: usize,
    (f, time): (f64, f64),
    state: &mut crate::contact::StepState,
    acc: &mut StepAcc,
    timings: &mut Timings,
    last_prepared: &mut Option<crate::contact::solve::Prepared>,
) -> Result<()> {
    use crate::contact::solve::prepare;
    use crate::contact::Session;
    use std::time::Instant;
    if !stp.timed || time == stp.model.time {
        contact_step(session, ctx, step, f, state, acc, timings);
        return Ok(());
    }
    let (scene, model) = (stp.scene, stp.model);
    let model_t = model.at_time(scene, time)?;
    let prepared_t = prepare(
        &model_t,
        scene.plane,
        stp.settings,
        1.0,
        &scene.path,
        &|_| {},
    )
    .map_err(stp.cause)?;
    timings.add("assemble", prepared_t.assemble_seconds);
    timings.add("condense", prepared_t.condense_seconds);
    let t1 = Instant::now();
    {
        let mut s = Session::new(&model_t, &prepared_t).map_err(stp.cause)?;
        s.cols = std::mem::take(&mut session.cols);
        s.coupled_after = session.coupled_after;
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
    }
    *last_prepared = Some(prepared_t);
    Ok(())
}

/// Lengths and values of a [`StepAcc`] to go back to.
struct AccMark {
    iterations: usize,
    residual: f64,
    final_sol: Option<FinalSolution>,
    cross: usize,
    qp_block: Option<serde_json::Value>,
    notes: usize,
    rows: usize,
    states: usize,
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
        self.failure = None;
        self.mechanism = false;
    }
}

/// What the load steps of a contact run accumulate.
#[derive(Default)]
struct StepAcc {
    iterations: usize,
    residual: f64,
    final_sol: Option<FinalSolution>,
    cross: Vec<serde_json::Value>,
    qp_block: Option<serde_json::Value>,
    notes: Vec<String>,
    history: crate::solution::History,
    states: Vec<crate::contact::RecordedState>,
    failure: Option<Error>,
    /// The failure is a mechanism (no equilibrium): no substeps help.
    mechanism: bool,
    /// Substeps solved since the last load step that was subdivided.
    substeps: usize,
}

/// One load step of a contact run: the main solver, the cross-checks, the history.
fn contact_step(
    session: &mut crate::contact::Session,
    ctx: &StepContext,
    step: usize,
    f: f64,
    state: &mut crate::contact::StepState,
    acc: &mut StepAcc,
    timings: &mut Timings,
) {
    use crate::contact::Method as Solver;
    use std::time::Instant;
    let (scene, model, main) = (ctx.scene, ctx.model, ctx.main);
    let (tol, maxit) = (ctx.tol, ctx.maxit);
    let t = Instant::now();
    let full = scene.output.history == crate::input::scene::History::Full;
    let mut r = session.solve_step(state, main, tol, maxit, step, f, full);
    timings.add(
        if main == Solver::Qp {
            "contact_qp"
        } else {
            "contact_lcp"
        },
        t.elapsed().as_secs_f64(),
    );
    let t = Instant::now();
    session.expand(&mut r);
    timings.add("contact_record", t.elapsed().as_secs_f64());
    for &c in ctx.checks {
        let t = Instant::now();
        let x = session.solve_step(state, c, tol, maxit, step, f, false);
        timings.add(
            match c {
                Solver::ActiveSet => "contact_active_set",
                Solver::Qp => "contact_qp",
                Solver::Lemke => "contact_lemke",
                Solver::Evolutive => "contact_lcp",
            },
            t.elapsed().as_secs_f64(),
        );
        let (all, degenerate) =
            crate::contact::status_differences(&x.interfaces, &r.interfaces, model.scale);
        let differing = all - degenerate;
        acc.cross.push(serde_json::json!({
            "solver": c.name(), "load_step": step, "iterations": x.iterations,
            "outer_iterations": x.outer_iterations, "converged": x.converged,
            "differing_pairs": differing, "degenerate_pairs": degenerate, "info": x.info,
            "failure": x.failure.as_ref().map(|e| e.message()),
        }));
        if c == Solver::Qp && step == ctx.last {
            acc.qp_block = Some(serde_json::json!({
                "form": "primal (openings, symmetric Steklov-Poincare stiffness)",
                "interfaces": crate::output::summary::interfaces(&model.interfaces, &x.interfaces, scene.thickness),
                "converged": x.converged,
                "differing_pairs_from_lcp": differing,
                "info": x.info,
            }));
        }
    }
    acc.iterations += r.iterations;
    acc.residual = acc.residual.max(r.residual);
    acc.notes.extend(r.notes.iter().cloned());
    acc.history.rows.extend(r.rows);
    if let Some(row) = acc.history.rows.last() {
        let status = row.status.iter().flatten();
        ctx.stage
            .contact_tick(&crate::output::progress::ContactTick {
                load_step: step,
                load_steps: ctx.steps,
                iteration: row.iteration,
                max_iterations: maxit,
                open_pairs: status
                    .clone()
                    .filter(|s| **s == crate::solution::PairStatus::Open)
                    .count(),
                pairs: status.count(),
                detached_length: row.detached_length.iter().sum(),
                step_done: true,
            });
    }
    acc.states.extend(r.states);
    if main == Solver::Qp && step == ctx.last {
        acc.qp_block = Some(serde_json::json!({
            "form": "primal (openings, symmetric Steklov-Poincare stiffness)",
            "interfaces": crate::output::summary::interfaces(&model.interfaces, &r.interfaces, scene.thickness),
            "converged": r.converged,
            "info": r.info,
        }));
    }
    *state = r.state;
    acc.final_sol = Some((
        f,
        session.model.time,
        session.body_forces(),
        r.fields,
        r.interfaces,
        r.nodal_force,
    ));
    if let Some(e) = r.failure {
        acc.failure = Some(e);
        acc.mechanism = r.mechanism;
    }
}

/// The status of the final state (closed where the interface result says so).
fn final_status(model: &Model, result: &RunResult) -> Vec<Vec<[crate::solution::PairStatus; 2]>> {
    use crate::solution::PairStatus;
    model
        .interfaces
        .iter()
        .zip(&result.interfaces)
        .map(|(it, r)| {
            r.pairs
                .iter()
                .map(|p| {
                    let slide = it.spec.tangential == crate::input::scene::Tangential::Slide
                        && it.spec.model == crate::input::scene::InterfaceModel::Unilateral;
                    match p.status {
                        PairStatus::Closed if slide => [PairStatus::Open, PairStatus::Closed],
                        s => [s, s],
                    }
                })
                .collect()
        })
        .collect()
}

/// The post-processing input of every body for a boundary solution with the body forces
/// `body_force` (of its step) at a load factor.
fn body_inputs<'a>(
    model: &'a Model,
    plane: crate::input::scene::Plane,
    fields: &'a [crate::solution::BodyField],
    body_force: &[Option<[f64; 2]>],
    factor: f64,
) -> Vec<crate::post::BodyInput<'a>> {
    model
        .bodies
        .iter()
        .zip(fields)
        .zip(body_force)
        .map(|((b, field), bf)| crate::post::BodyInput {
            body: b,
            material: crate::bem::assembly::material(b, plane),
            field,
            body_force: bf
                .filter(|v| *v != [0.0, 0.0])
                .map(|v| [factor * v[0], factor * v[1]]),
        })
        .collect()
}

/// Reads, validates, solves and writes every output of a scene.
pub fn run(scene_path: &Path, opts: &RunOptions) -> Result<RunReport> {
    use crate::bem::quadrature::QuadratureSettings;
    use crate::output::archive::{ArchivePart, ArchiveWriter};
    use crate::output::record::{RunRecord, StateRecord};
    use crate::output::{csv, summary, write_staged};
    use crate::post::{section_points, PointSampler};
    use rayon::prelude::*;
    use std::fmt::Write as _;
    use std::time::Instant;

    let mut timings = Timings::default();
    let t0 = Instant::now();
    let scratch = crate::input::gmsh::Scratch::new("run");
    let mut loaded = load_with(
        scene_path,
        &LoadOptions {
            mesh: opts.mesh.clone(),
            sets: opts.sets.clone(),
            mesh_dir: Some(scratch.path().to_path_buf()),
        },
    )?;
    if let Some(m) = opts.method {
        loaded.scene.solve.method = m;
    }
    if let Some(o) = &opts.out {
        loaded.scene.output.directory = o.clone();
    }
    timings.add("read", t0.elapsed().as_secs_f64());
    // Refuse what cannot fit before allocating any of it.
    crate::estimate::estimate(&loaded.model, &loaded.scene)
        .check_fits(&loaded.model, scene_path)?;
    // The run writes into a staging folder, swapped in when complete (output/folder.rs).
    let folder = crate::output::folder::RunFolder::acquire(&loaded.scene.output.directory)?;
    // A .geo scene mesh was meshed into a scratch folder: keep it in the run's mesh/.
    let meshed = scratch.path();
    if crate::input::gmsh::is_geo(loaded.scene.mesh.as_deref().unwrap_or(Path::new("")))
        && meshed.is_dir()
    {
        let dest = folder.staging().join("mesh");
        std::fs::create_dir_all(&dest)
            .map_err(|e| Error::io(&dest, format!("cannot create the mesh folder: {e}")))?;
        for entry in std::fs::read_dir(&meshed).into_iter().flatten().flatten() {
            let _ = std::fs::copy(entry.path(), dest.join(entry.file_name()));
        }
    }
    let settings = QuadratureSettings::from_name(loaded.scene.solve.quadrature.name())
        .unwrap_or_else(QuadratureSettings::standard);
    let progress = crate::output::progress::Progress::new(opts.quiet);
    // The archive is written on a thread of its own from the moment the body operators
    // exist (output::archive::ArchiveWriter): the model now, the contact results before
    // post-processing, the final state at the end.
    let mut rec = RunRecord::from_model(&loaded.scene, &loaded.mesh, &loaded.model)?;
    let archive_path = folder.staging().join("archive.h5");
    let mut archive: Option<ArchiveWriter> = None;
    let (prepared, mut result) =
        solve_loaded_then(&loaded, &settings, &mut timings, &progress, &mut |p| {
            let mut model = rec.clone();
            if loaded.scene.output.operators {
                model.set_operators(&p.systems, &p.condensed);
            }
            archive = Some(ArchiveWriter::start(&archive_path, model));
        })?;
    let archive = archive.unwrap_or_else(|| ArchiveWriter::start(&archive_path, rec.clone()));
    let Loaded {
        scene, model, plan, ..
    } = &loaded;
    // The contact results of the archive: the paper's mixed interface operators of the final
    // status (dense over every interface: for scenes of up to 3000 interface unknowns only),
    // the history and the states.
    let t1 = Instant::now();
    let mut contact_operators = None;
    // Junctions have no place in the paper's mixed layout (one displacement per pair).
    if scene.output.operators && model.junctions().is_empty() {
        let final_status = final_status(model, &result);
        let layout = crate::contact::interface::layout(model, &prepared.maps, &final_status)?;
        if layout.n <= 3000 {
            let (k, l) = crate::contact::interface::assemble_scaled(
                &layout,
                &prepared.condensed,
                result.load_factor,
            );
            contact_operators = Some(
                crate::contact::interface::reduced_operators(&layout, &k, &l)
                    .into_iter()
                    .map(|(n, m)| (n, crate::output::record::Array::from_mat(&m)))
                    .collect(),
            );
        }
    }
    // The final state belongs to the last step solved (the failing one after a failure).
    let final_step = result
        .states
        .last()
        .map_or(scene.solve.steps().len() - 1, |s| s.load_step);
    // What the section paths need of each recorded state besides its fields, which move
    // into the record (a full history of hundreds of bodies is most of a run's memory).
    type StateLoads = (usize, usize, f64, Vec<Option<[f64; 2]>>);
    let recorded_loads: Vec<StateLoads> = result
        .states
        .iter()
        .map(|s| {
            (
                s.iteration,
                s.load_step,
                s.load_factor,
                s.body_force.clone(),
            )
        })
        .collect();
    let mut states: Vec<StateRecord> = Vec::new();
    if scene.output.history == crate::input::scene::History::Full {
        let recorded = result.states.len().saturating_sub(1);
        for st in std::mem::take(&mut result.states)
            .into_iter()
            .take(recorded)
        {
            states.push(StateRecord::new(
                states.len(),
                st.load_step,
                st.load_factor,
                st.fields,
                st.interfaces,
            ));
        }
    }
    states.push(StateRecord::new(
        states.len(),
        final_step,
        result.load_factor,
        result.fields.clone(),
        result.interfaces.clone(),
    ));
    rec.states = states;
    // The archive's thread gets the states' fields shared, not copied (StateRecord); the
    // history goes there alone (the VTK files do not need it).
    archive.send(ArchivePart::Solved {
        contact_operators,
        history: result.history.clone(),
        states: rec.states.clone(),
    });
    timings.add("write", t1.elapsed().as_secs_f64());
    if let Some(where_) = non_finite(model, &result) {
        result.status = "failed: non-finite results".into();
        if result.failure.is_none() {
            result.failure = Some(non_finite_error(&where_, scene));
        }
    }
    let out_dir = folder.staging().to_path_buf();
    let factor = result.load_factor;
    let mut notes = plan.advice.clone();
    notes.extend(result.notes.iter().cloned());
    let balances = crate::post::equilibrium::balances(
        model,
        &result.fields,
        &result.interfaces,
        &result.body_force,
        factor,
        scene.thickness,
    );
    if result.failure.is_none() {
        notes.extend(crate::post::equilibrium::unbalanced_note(model, &balances));
        notes.extend(crate::post::plausibility::displacement_note(
            model,
            &result.fields,
        ));
    }

    // Post-processing.
    let t2 = Instant::now();
    let inputs = body_inputs(
        model,
        scene.plane,
        &result.fields,
        &result.body_force,
        factor,
    );
    // Each section's points are located, planned and integrated once (post::PointSampler),
    // then evaluated for the final state and, with history = "full", for every recorded
    // iteration (the path, for plots like the paper's Fig. 6), the iterations in parallel.
    let full_path =
        scene.output.history == crate::input::scene::History::Full && !recorded_loads.is_empty();
    let mut sections = Vec::new();
    let mut section_paths = Vec::new();
    for s in &scene.output.sections {
        let pts = section_points(s.from, s.to, s.points);
        let sampler = PointSampler::new(&inputs, &settings, &pts);
        let vals = sampler.evaluate(&inputs);
        let rows: Vec<csv::SectionRow> = pts
            .iter()
            .zip(vals)
            .map(|(x, v)| {
                (
                    *x,
                    v.map(|p| (p.u, [p.sigma[0][0], p.sigma[1][1], p.sigma[0][1]])),
                )
            })
            .collect();
        if result.failure.is_none() {
            if let Some(x) = rows.iter().find_map(|(x, v)| {
                v.filter(|(u, sg)| !u.iter().chain(sg.iter()).all(|c| c.is_finite()))
                    .map(|_| *x)
            }) {
                result.status = "failed: non-finite results".into();
                result.failure = Some(non_finite_error(
                    &format!("section {} at ({:e}, {:e})", s.name, x[0], x[1]),
                    scene,
                ));
            }
        }
        if rows.iter().any(|r| r.1.is_none()) {
            notes.push(format!(
                "section {}: some points lie outside every body (written as nan)",
                s.name
            ));
        }
        sections.push((s.name.clone(), rows));
        if full_path {
            // The recorded states are those of the record, the last being the final one.
            let blocks: Vec<String> = rec
                .states
                .par_iter()
                .zip(&recorded_loads)
                .zip(&result.history.rows)
                .map(|((record, st), row)| {
                    let (iteration, load_step, load_factor, body_force) = st;
                    let inputs =
                        body_inputs(model, scene.plane, &record.fields, body_force, *load_factor);
                    let detached: f64 = row.detached_length.iter().sum::<f64>() + 0.0;
                    let mut text = String::new();
                    for (x, v) in pts.iter().zip(sampler.evaluate(&inputs)) {
                        let vals = match v {
                            Some(p) => format!(
                                "{:e},{:e},{:e},{:e},{:e}",
                                p.u[0], p.u[1], p.sigma[0][0], p.sigma[1][1], p.sigma[0][1]
                            ),
                            None => "nan,nan,nan,nan,nan".into(),
                        };
                        let _ = writeln!(
                            text,
                            "{},{},{:e},{:e},{:e},{:e},{vals}",
                            iteration, load_step, load_factor, detached, x[0], x[1]
                        );
                    }
                    text
                })
                .collect();
            let mut text = String::from(
                "iteration,load_step,load_factor,detached_length,x,y,ux,uy,sxx,syy,sxy\n",
            );
            text.extend(blocks);
            section_paths.push((s.name.clone(), text));
        }
    }
    let mut field_nodes = 0usize;
    let mut interior = Vec::new();
    if scene.output.field {
        let total: usize = model.bodies.iter().map(crate::post::field_node_count).sum();
        let stage = progress.bar("field points", total as u64);
        for input in &inputs {
            let values =
                crate::post::field_at_nodes_with(input, &settings, &loaded.mesh.nodes, &|n| {
                    stage.inc(n)
                });
            field_nodes += values.len();
            let bad = values.iter().find(|v| {
                !(v.u.iter().all(|c| c.is_finite())
                    && v.sigma.iter().flatten().all(|c| c.is_finite()))
            });
            if let (Some(v), None) = (bad, &result.failure) {
                result.status = "failed: non-finite results".into();
                result.failure = Some(non_finite_error(
                    &format!(
                        "body \"{}\": interior field at mesh node {}",
                        input.body.name, v.mesh_node
                    ),
                    scene,
                ));
            }
            interior.push(crate::output::record::InteriorRecord::from_values(&values));
        }
        stage.finish();
    }
    timings.add("postprocess", t2.elapsed().as_secs_f64());

    // Outputs.
    let t3 = Instant::now();
    for (it, r) in model.interfaces.iter().zip(&result.interfaces) {
        write_staged(
            &out_dir
                .join("interfaces")
                .join(format!("{}.csv", it.spec.name)),
            csv::interface_table(it, r).as_bytes(),
        )?;
    }
    for (name, rows) in &sections {
        write_staged(
            &out_dir.join("sections").join(format!("{name}.csv")),
            csv::section_table(rows).as_bytes(),
        )?;
    }
    for (name, text) in &section_paths {
        write_staged(
            &out_dir.join("sections").join(format!("{name}_path.csv")),
            text.as_bytes(),
        )?;
    }
    timings.add("write", t3.elapsed().as_secs_f64());
    let dofs: usize = prepared.systems.iter().map(|s| s.n()).sum();
    let asym = prepared
        .condensed
        .iter()
        .map(|c| c.asymmetry)
        .fold(0.0, f64::max);
    let pivot = prepared
        .condensed
        .iter()
        .map(|c| c.pivot_ratio)
        .fold(1.0, f64::min);
    let mut summary = serde_json::json!({
        "title": scene.title,
        "status": result.status,
        "method": if plan.problem == crate::plan::ContactProblem::None { "linear" } else { scene.solve.method.name() },
        "effects": plan.effects,
        "problem": format!("{:?}", plan.problem).to_lowercase(),
        "plane": match scene.plane { crate::input::scene::Plane::Strain => "strain", crate::input::scene::Plane::Stress => "stress" },
        "thickness": scene.thickness,
        "units": {"length": scene.units.length, "force": scene.units.force},
        "load_factor": factor,
        "quadrature": scene.solve.quadrature.name(),
        "counts": {
            "bodies": model.bodies.len(),
            "boundary_elements": model.element_count(),
            "interface_pairs": model.pair_count(),
            "dofs": dofs,
            "field_nodes": field_nodes,
        },
        "interfaces": summary::interfaces(&model.interfaces, &result.interfaces, scene.thickness),
        "contact": result.contact,
        "diagnostics": {
            "d00_asymmetry": asym,
            "min_pivot_ratio": pivot,
        },
        "notes": notes,
        "overrides": scene.overrides,
    });
    summary["equilibrium"] = crate::post::equilibrium::summary(&balances);
    if let Some(curves) = summary::interface_curves(&model.interfaces, &summary["interfaces"]) {
        summary["interface_curves"] = curves;
    }
    if let Some(qp) = &result.qp {
        summary["qp"] = qp.clone();
    }
    if let Some(ts) = &scene.solve.time {
        // The load path: the pseudo-time of the final state and every step's.
        summary["time"] = serde_json::json!(result.time);
        summary["load_path"] = serde_json::json!({
            "time": ts,
            "depends_on_t": crate::plan::time_dependent(scene),
        });
    }
    // Figures that overflow (serialised as null): a resultant of finite tractions can.
    if result.failure.is_none() {
        let overflow = summary["interfaces"].as_object().and_then(|m| {
            m.iter().find_map(|(name, fig)| {
                fig.as_object()?
                    .iter()
                    .find(|(_, v)| v.is_null())
                    .map(|(k, _)| format!("interface \"{name}\": {k}"))
            })
        });
        if let Some(where_) = overflow {
            result.status = "failed: non-finite results".into();
            summary["status"] = serde_json::json!(result.status);
            result.failure = Some(non_finite_error(&where_, scene));
        }
    }
    let text = serde_json::to_string_pretty(&summary)
        .map_err(|e| Error::io(&out_dir, format!("cannot serialise the summary: {e}")))?;

    // Archive and VTK files.
    let t4 = Instant::now();
    let stage = progress.spinner("archive and VTK");
    if let Some(last) = rec.states.last_mut() {
        last.interior = interior;
    }
    rec.status = result.status.clone();
    rec.timings = timings.0.iter().map(|(s, t)| (s.to_string(), *t)).collect();
    rec.summary_json = text.clone();
    archive.send(ArchivePart::Finished {
        interior: rec
            .states
            .last()
            .map(|l| l.interior.clone())
            .unwrap_or_default(),
        status: rec.status.clone(),
        timings: rec.timings.clone(),
        summary_json: text.clone(),
    });
    // The VTK files (in parallel) while the archive's thread writes the final state.
    let vtk = if scene.output.vtk {
        crate::output::vtk::write_vtk_staged(&out_dir.join("vtk"), &rec).map(|_| ())
    } else {
        Ok(())
    };
    archive.finish()?;
    vtk?;
    stage.finish();
    timings.add("write", t4.elapsed().as_secs_f64());
    // Dates and timings in their own file: summary.json stays byte-identical between runs.
    let timing_text = serde_json::to_string_pretty(&serde_json::json!({
        "created": rec.created,
        "stages": timings.json(),
    }))
    .map_err(|e| Error::io(&out_dir, format!("cannot serialise the timings: {e}")))?;
    write_staged(&out_dir.join("timings.json"), timing_text.as_bytes())?;
    // The summary last, then the whole folder swapped in.
    write_staged(&out_dir.join("summary.json"), text.as_bytes())?;
    let out_dir = folder.target().to_path_buf();
    folder.commit()?;
    if let Some(f) = result.failure {
        return Err(f);
    }
    Ok(RunReport {
        out_dir,
        summary,
        notes,
    })
}

/// Where a result holds a number that is not finite ("body \"A\" displacement", ...).
fn non_finite(model: &Model, result: &RunResult) -> Option<String> {
    let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
    for (b, f) in model.bodies.iter().zip(&result.fields) {
        if let Some(n) = f.u.iter().position(|u| !finite(u)) {
            return Some(format!(
                "body \"{}\": displacement at node ({:e}, {:e})",
                b.name, b.nodes[n][0], b.nodes[n][1]
            ));
        }
        if let Some(e) = f.t.iter().position(|t| !t.iter().all(|x| finite(x))) {
            let p = b.nodes[b.elements[e].nodes[0]];
            return Some(format!(
                "body \"{}\": traction on the element at ({:e}, {:e})",
                b.name, p[0], p[1]
            ));
        }
    }
    for (it, r) in model.interfaces.iter().zip(&result.interfaces) {
        if r.pairs
            .iter()
            .any(|p| !finite(&p.traction) || !finite(&p.jump))
        {
            return Some(format!(
                "interface \"{}\": traction or opening",
                it.spec.name
            ));
        }
    }
    None
}

/// The numerical failure for a non-finite result at `where_`.
fn non_finite_error(where_: &str, scene: &Scene) -> Error {
    let largest = scene
        .solve
        .load_factors
        .iter()
        .fold(0.0f64, |m, f| m.max(f.abs()));
    Error::numerical(format!(
        "the results hold numbers that are not finite ({where_}): the load factors (largest \
         {largest:e}), prescribed values or material constants overflow double precision; \
         scale the scene's units so that values stay well within 1e-100..1e100"
    ))
}
