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
    use crate::contact::solve::prepare;
    use crate::contact::{differing_pairs, Method as Solver, Session};
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
    let factors = &scene.solve.load_factors;
    let last = factors.len() - 1;
    let mut notes = Vec::new();
    let mut history = crate::solution::History::default();
    let mut states = Vec::new();
    let method = scene.solve.method;
    let tol = scene.solve.tolerance;
    let maxit = scene.solve.max_iterations;

    let t = Instant::now();
    let mut session = Session::new(model, &prepared).map_err(cause)?;
    timings.add("interface_system", t.elapsed().as_secs_f64());
    if plan.problem == ContactProblem::None {
        let t = Instant::now();
        let start = session.initial();
        let f = factors[last];
        let n = session.problem.n_open_rows;
        let (fields, interfaces, nodal_force) =
            session
                .problem
                .state(model, &prepared, f, &vec![0.0; n], &start.open);
        timings.add("solve", t.elapsed().as_secs_f64());
        let result = RunResult {
            status: "solved".into(),
            load_factor: f,
            fields,
            interfaces,
            nodal_force,
            history,
            states,
            contact: serde_json::json!({"solver": "linear (no unilateral interface)"}),
            qp: None,
            notes,
            failure: None,
        };
        return Ok((prepared, result));
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
    let stage = progress.contact(factors.len());
    let mut state = session.initial();
    let mut iterations = 0;
    let mut converged = true;
    let mut failure = None;
    let mut residual = 0.0f64;
    let mut final_sol = None;
    let mut cross = Vec::new();
    let mut qp_block = None;
    for (step, &f) in factors.iter().enumerate() {
        let t = Instant::now();
        let full = scene.output.history == crate::input::scene::History::Full;
        let mut r = session.solve_step(&state, main, tol, maxit, step, f, full);
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
        for &c in &checks {
            let t = Instant::now();
            let x = session.solve_step(&state, c, tol, maxit, step, f, false);
            timings.add(
                match c {
                    Solver::ActiveSet => "contact_active_set",
                    Solver::Qp => "contact_qp",
                    Solver::Lemke => "contact_lemke",
                    Solver::Evolutive => "contact_lcp",
                },
                t.elapsed().as_secs_f64(),
            );
            let differing = differing_pairs(&x.interfaces, &r.interfaces);
            cross.push(serde_json::json!({
                "solver": c.name(), "load_step": step, "iterations": x.iterations,
                "outer_iterations": x.outer_iterations, "converged": x.converged,
                "differing_pairs": differing, "info": x.info,
                "failure": x.failure.as_ref().map(|e| e.message()),
            }));
            if c == Solver::Qp && step == last {
                qp_block = Some(serde_json::json!({
                    "form": "primal (openings, symmetric Steklov-Poincare stiffness)",
                    "interfaces": crate::output::summary::interfaces(&model.interfaces, &x.interfaces, scene.thickness),
                    "converged": x.converged,
                    "differing_pairs_from_lcp": differing,
                    "info": x.info,
                }));
            }
        }
        iterations += r.iterations;
        residual = residual.max(r.residual);
        notes.extend(r.notes.iter().cloned());
        history.rows.extend(r.rows);
        if let Some(row) = history.rows.last() {
            let status = row.status.iter().flatten();
            stage.contact_tick(&crate::output::progress::ContactTick {
                load_step: step,
                load_steps: factors.len(),
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
        states.extend(r.states);
        if main == Solver::Qp && step == last {
            qp_block = Some(serde_json::json!({
                "form": "primal (openings, symmetric Steklov-Poincare stiffness)",
                "interfaces": crate::output::summary::interfaces(&model.interfaces, &r.interfaces, scene.thickness),
                "converged": r.converged,
                "info": r.info,
            }));
        }
        state = r.state;
        final_sol = Some((f, r.fields, r.interfaces, r.nodal_force));
        if let Some(e) = r.failure {
            converged = false;
            failure = Some(e);
            break;
        }
    }
    stage.finish();
    let contact = serde_json::json!({
        "solver": main.name(),
        "problem": "nodal contact forces against nodal gaps on the symmetric Steklov-Poincare stiffness (one LCP)",
        "iterations": iterations,
        "converged": converged,
        "complementarity_residual": residual,
        "load_steps": factors.len(),
        "opening_stiffness_columns": session.cols.computed(),
        "interface_system_size": session.problem.base_size(),
        "cross_checks": cross,
    });
    let (load_factor, fields, interfaces, nodal_force) = match final_sol {
        Some(x) => x,
        None => return Err(Error::numerical("the contact stage produced no state")),
    };
    let result = RunResult {
        status: if converged {
            "converged".into()
        } else {
            "not converged".into()
        },
        load_factor,
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
    Ok((prepared, result))
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

/// The post-processing input of every body for a boundary solution at a load factor.
fn body_inputs<'a>(
    model: &'a Model,
    plane: crate::input::scene::Plane,
    fields: &'a [crate::solution::BodyField],
    factor: f64,
) -> Vec<crate::post::BodyInput<'a>> {
    model
        .bodies
        .iter()
        .zip(fields)
        .map(|(b, field)| crate::post::BodyInput {
            body: b,
            material: crate::bem::assembly::material(b, plane),
            field,
            body_force: b
                .body_force
                .filter(|v| *v != [0.0, 0.0])
                .map(|v| [factor * v[0], factor * v[1]]),
        })
        .collect()
}

/// Reads, validates, solves and writes every output of a scene.
pub fn run(scene_path: &Path, opts: &RunOptions) -> Result<RunReport> {
    use crate::bem::quadrature::QuadratureSettings;
    use crate::output::{csv, summary, write_atomic};
    use crate::post::{evaluate_points, section_points};
    use std::time::Instant;

    let mut timings = Timings::default();
    let t0 = Instant::now();
    let mut loaded = load_with(
        scene_path,
        &LoadOptions {
            mesh: opts.mesh.clone(),
            sets: opts.sets.clone(),
            mesh_dir: opts.out.as_ref().map(|o| o.join("mesh")),
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
    // A .geo scene mesh was meshed into the target's mesh/ folder: keep it in the new run.
    let meshed = loaded.scene.output.directory.join("mesh");
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
    let (prepared, mut result) = solve_loaded_with(&loaded, &settings, &mut timings, &progress)?;
    let Loaded {
        scene, model, plan, ..
    } = &loaded;
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
        factor,
        scene.thickness,
    );
    if result.failure.is_none() {
        notes.extend(crate::post::equilibrium::unbalanced_note(model, &balances));
    }

    // Post-processing.
    let t2 = Instant::now();
    let inputs = body_inputs(model, scene.plane, &result.fields, factor);
    let mut sections = Vec::new();
    for s in &scene.output.sections {
        let pts = section_points(s.from, s.to, s.points);
        let vals = evaluate_points(&inputs, &settings, &pts);
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
    }
    // Sections along the contact path (history = "full"): the same points at every
    // recorded iteration, for plots like the paper's Fig. 6.
    let mut section_paths = Vec::new();
    if scene.output.history == crate::input::scene::History::Full && !result.states.is_empty() {
        for s in &scene.output.sections {
            let pts = section_points(s.from, s.to, s.points);
            let mut text = String::from(
                "iteration,load_step,load_factor,detached_length,x,y,ux,uy,sxx,syy,sxy\n",
            );
            for (st, row) in result.states.iter().zip(&result.history.rows) {
                let inputs = body_inputs(model, scene.plane, &st.fields, st.load_factor);
                let detached: f64 = row.detached_length.iter().sum::<f64>() + 0.0;
                for (x, v) in pts.iter().zip(evaluate_points(&inputs, &settings, &pts)) {
                    let vals = match v {
                        Some(p) => format!(
                            "{:e},{:e},{:e},{:e},{:e}",
                            p.u[0], p.u[1], p.sigma[0][0], p.sigma[1][1], p.sigma[0][1]
                        ),
                        None => "nan,nan,nan,nan,nan".into(),
                    };
                    text += &format!(
                        "{},{},{:e},{:e},{:e},{:e},{vals}\n",
                        st.iteration, st.load_step, st.load_factor, detached, x[0], x[1]
                    );
                }
            }
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
        write_atomic(
            &out_dir
                .join("interfaces")
                .join(format!("{}.csv", it.spec.name)),
            csv::interface_table(it, r).as_bytes(),
        )?;
    }
    for (name, rows) in &sections {
        write_atomic(
            &out_dir.join("sections").join(format!("{name}.csv")),
            csv::section_table(rows).as_bytes(),
        )?;
    }
    for (name, text) in &section_paths {
        write_atomic(
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
    let mut rec = crate::output::record::RunRecord::from_model(scene, &loaded.mesh, model)?;
    if scene.output.operators {
        rec.set_operators(&prepared.systems, &prepared.condensed);
        let final_status = final_status(model, &result);
        let layout = crate::contact::interface::layout(model, &prepared.maps, &final_status)?;
        // The paper's mixed interface operators of the final status (dense over every
        // interface): archived for scenes of up to 3000 interface unknowns only.
        if layout.n <= 3000 {
            let (k, l) = crate::contact::interface::assemble_scaled(
                &layout,
                &prepared.condensed,
                result.load_factor,
            );
            rec.contact_operators = Some(
                crate::contact::interface::reduced_operators(&layout, &k, &l)
                    .into_iter()
                    .map(|(n, m)| (n, crate::output::record::Array::from_mat(&m)))
                    .collect(),
            );
        }
    }
    let mut states: Vec<crate::output::record::StateRecord> = Vec::new();
    if scene.output.history == crate::input::scene::History::Full {
        let recorded = result.states.len().saturating_sub(1);
        for st in &result.states[..recorded] {
            states.push(crate::output::record::StateRecord::new(
                states.len(),
                st.load_step,
                st.load_factor,
                st.fields.clone(),
                st.interfaces.clone(),
            ));
        }
    }
    let mut last = crate::output::record::StateRecord::new(
        states.len(),
        scene.solve.load_factors.len() - 1,
        result.load_factor,
        result.fields.clone(),
        result.interfaces.clone(),
    );
    last.interior = interior;
    states.push(last);
    rec.states = states;
    rec.history = result.history.clone();
    rec.status = result.status.clone();
    rec.timings = timings.0.iter().map(|(s, t)| (s.to_string(), *t)).collect();
    rec.summary_json = text.clone();
    crate::output::archive::write_archive(&out_dir.join("archive.h5"), &rec)?;
    if scene.output.vtk {
        crate::output::vtk::write_vtk(&out_dir.join("vtk"), &rec)?;
    }
    stage.finish();
    timings.add("write", t4.elapsed().as_secs_f64());
    // Dates and timings in their own file: summary.json stays byte-identical between runs.
    let timing_text = serde_json::to_string_pretty(&serde_json::json!({
        "created": rec.created,
        "stages": timings.json(),
    }))
    .map_err(|e| Error::io(&out_dir, format!("cannot serialise the timings: {e}")))?;
    write_atomic(&out_dir.join("timings.json"), timing_text.as_bytes())?;
    // The summary last, then the whole folder swapped in.
    write_atomic(&out_dir.join("summary.json"), text.as_bytes())?;
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
