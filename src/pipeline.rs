//! The stage order of a run; the only module that knows it.
//!
//! Place in the flow: the top. `load` reads the scene and the mesh, builds the model and
//! decides the plan; `check` is `load` plus the report.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use rayon::prelude::*;

use crate::bem::quadrature::QuadratureSettings;
use crate::bem::{prepare, Operators};
use crate::contact::driver::{self, Case, ContactRun};
use crate::contact::interface;
use crate::error::{Error, Result};
use crate::input::mesh::{self, Mesh};
use crate::input::model::{self, Model};
use crate::input::scene::HistoryLevel;
use crate::input::scene::{self, Scene};
use crate::output::archive::{ArchivePart, ArchiveWriter};
use crate::output::folder::RunFolder;
use crate::output::progress::Progress;
use crate::output::record::{Array, InteriorRecord, IterateRecord, RunRecord};
use crate::output::{csv, summary, write_staged};
use crate::plan::{self, Plan};
use crate::post::{section_offsets, section_points, PointSampler};
use crate::solution::{History, RunStatus};
use crate::timings::{Timings, TimingsFile};

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
    /// Replaces the scene's `solve.method` (`--method`), before the defaults that depend on
    /// it (the method for the scene's size, the history's level).
    pub method: Option<crate::input::scene::Method>,
}

/// [`load`] with `--set` overrides; a `.geo` mesh is meshed with gmsh first.
pub fn load_with(scene_path: &Path, opts: &LoadOptions) -> Result<Loaded> {
    if !scene_path.is_file() {
        return Err(Error::input(
            scene_path,
            "no such scene file: give the path of a .toml scene",
        ));
    }
    let mut scene = scene::read_scene_with(scene_path, &opts.sets)?;
    // `--method` over the scene's, before the defaults that depend on it.
    if let Some(m) = opts.method {
        scene.solve.method = m;
        scene.solve.method_choice = crate::input::scene::MethodChoice::Given;
    }
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
    // The user's .geo, where gmsh made the mesh: errors in the mesh name it.
    let mut geo: Option<PathBuf> = None;
    if crate::input::gmsh::is_geo(&mesh_path) {
        let dir = opts
            .mesh_dir
            .clone()
            .unwrap_or_else(|| scene.output.directory.join("mesh"));
        let made = crate::input::gmsh::mesh_geo(&mesh_path, &scene.mesh_parameters, &dir)?;
        geo = Some(std::mem::replace(&mut mesh_path, made));
    } else {
        // A mesh given as such: the scene's gmsh parameters did not make it.
        scene.mesh_parameters.clear();
    }
    if !mesh_path.is_file() {
        return Err(Error::input(
            &mesh_path,
            "no such mesh file: mesh the .geo first (make mesh, or gmsh -2 -format msh41 FILE.geo)",
        ));
    }
    let said_of_geo = |e| in_geo(e, &mesh_path, geo.as_deref());
    let mut mesh = mesh::read_msh(&mesh_path).map_err(said_of_geo)?;
    let model = model::build(&scene, &mut mesh, &mesh_path).map_err(said_of_geo)?;
    scene.solve.choose_method(
        model.unilateral_pair_count(),
        model.has_unilateral_junction(),
    );
    let scaled = crate::estimate::scale_history(&mut scene, &model);
    let mut plan = plan::plan(&scene, &model)?;
    plan.advice.extend(scaled);
    Ok(Loaded {
        scene,
        mesh,
        model,
        plan,
    })
}

/// An input error in the mesh gmsh made of the user's `.geo`, said of the `.geo` (the mesh
/// of `sgbem check` is gone when the message is read).
fn in_geo(e: Error, mesh: &Path, geo: Option<&Path>) -> Error {
    match (e, geo) {
        (Error::Input { file, message }, Some(geo)) if Path::new(&file) == mesh => Error::input(
            geo,
            format!("{message} (in the mesh gmsh made of this .geo)"),
        ),
        (e, _) => e,
    }
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
    pub summary: summary::Summary,
    pub notes: Vec<String>,
}

/// Assembles and condenses every body (the bem stage), with a bar per body.
pub(crate) fn prepare_bodies(
    loaded: &Loaded,
    settings: &QuadratureSettings,
    timings: &mut Timings,
    progress: &Progress,
) -> Result<Operators> {
    let Loaded {
        scene, model, plan, ..
    } = loaded;
    // One step per body, counted as each is assembled and condensed (in parallel).
    let stage = progress.bar("assemble", model.bodies.len() as u64);
    stage.set_message(format!(
        "assembling and condensing {} bodies",
        model.bodies.len()
    ));
    let ops = prepare(model, scene.plane, settings, 1.0, &scene.path, &|body| {
        stage.inc(1);
        stage.set_message(format!("last done: {body}"));
    })
    .map_err(|e| plan.explain(e))?;
    stage.finish();
    timings.add("assemble", ops.assemble_seconds);
    timings.add("condense", ops.condense_seconds);
    Ok(ops)
}

/// The contact stage (or one linear solve) on the bodies' operators, for every load step.
pub(crate) fn solve_contact(
    loaded: &Loaded,
    settings: &QuadratureSettings,
    ops: &Operators,
    timings: &mut Timings,
    progress: &Progress,
) -> Result<ContactRun> {
    let case = Case {
        scene: &loaded.scene,
        model: &loaded.model,
        plan: &loaded.plan,
        settings,
    };
    driver::solve(case, ops, timings, progress)
}

/// The solve stages without output: assembly and condensation once, then the contact
/// problem (or one linear solve) for each load step, each step starting from the previous
/// state. Returns the operators of the final state with the solution.
pub fn solve_loaded(
    loaded: &Loaded,
    settings: &QuadratureSettings,
    timings: &mut Timings,
) -> Result<(Operators, ContactRun)> {
    let progress = Progress::hidden();
    let ops = prepare_bodies(loaded, settings, timings, &progress)?;
    let mut solved = solve_contact(loaded, settings, &ops, timings, &progress)?;
    Ok((solved.operators.take().unwrap_or(ops), solved))
}

/// The status of the final state (closed where the interface result says so).
fn final_status(model: &Model, result: &ContactRun) -> Vec<Vec<[crate::solution::PairStatus; 2]>> {
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

/// Reads, validates, solves and writes every output of a scene: the README's pipeline.
pub fn run(scene_path: &Path, opts: &RunOptions) -> Result<RunReport> {
    let mut timings = Timings::default();
    let folder = lock_run_folder(scene_path, opts)?;
    // A .geo is meshed into a scratch folder, never into the output folder before the run
    // owns it; the mesh then goes into the run's mesh/.
    let scratch = crate::input::gmsh::Scratch::new("run");
    let mut loaded = load_for_run(scene_path, opts, scratch.path(), &mut timings)?;
    check_fits_and_keep_mesh(&mut loaded, scene_path, &folder, scratch.path())?;
    let settings = quadrature(&loaded.scene);
    let progress = Progress::new(opts.quiet);
    let mut rec = RunRecord::from_model(&loaded.scene, &loaded.mesh, &loaded.model)?;
    let ops = prepare_bodies(&loaded, &settings, &mut timings, &progress)?;
    let archive = start_archive(&folder, &loaded.scene, &rec, &ops)?;
    let mut solved = solve_contact(&loaded, &settings, &ops, &mut timings, &progress)?;
    let ops = solved.operators.take().unwrap_or(ops);
    let loads = record_solution(&loaded, &ops, &mut solved, &mut rec, &archive, &mut timings)?;
    let mut post = postprocess(&loaded, &settings, &mut solved, &rec, &loads, &progress);
    timings.add("postprocess", post.seconds);
    write_tables(folder.staging(), &loaded, &solved, &post, &mut timings)?;
    let summary = summary_of(&loaded, &ops, &mut solved, &post);
    if let Some(last) = rec.states.last_mut() {
        last.interior = std::mem::take(&mut post.interior);
    }
    let out_dir = write_run(
        folder, archive, rec, &loaded, &solved, &summary, &progress, timings,
    )?;
    match solved.failure {
        Some(f) => Err(f),
        None => Ok(RunReport {
            summary,
            out_dir,
            notes: post.notes,
        }),
    }
}

/// Reads the scene and the mesh with the command line's overrides.
fn load_for_run(
    scene_path: &Path,
    opts: &RunOptions,
    mesh_dir: &Path,
    timings: &mut Timings,
) -> Result<Loaded> {
    let t0 = Instant::now();
    let mut loaded = load_with(
        scene_path,
        &LoadOptions {
            mesh: opts.mesh.clone(),
            sets: opts.sets.clone(),
            mesh_dir: Some(mesh_dir.to_path_buf()),
            method: opts.method,
        },
    )?;
    if let Some(o) = &opts.out {
        loaded.scene.output.directory = o.clone();
    }
    timings.add("read", t0.elapsed().as_secs_f64());
    Ok(loaded)
}

/// The folder's lock first, before meshing a .geo or computing anything: a second run into
/// the same folder is refused at once, not after the first one has computed. The run writes
/// into a staging folder, swapped in when complete (output/folder.rs). The scene is read
/// first, so that its errors come before any folder is touched.
fn lock_run_folder(scene_path: &Path, opts: &RunOptions) -> Result<RunFolder> {
    let scene = crate::input::scene::read_scene_with(scene_path, &opts.sets)?;
    let target = opts.out.clone().unwrap_or(scene.output.directory);
    let mesh = opts.mesh.as_ref().or(scene.mesh.as_ref());
    let inputs: Vec<&Path> = std::iter::once(scene_path)
        .chain(mesh.map(PathBuf::as_path))
        .collect();
    RunFolder::acquire(&target, &inputs)
}

/// The resources a run of `loaded` needs against what this machine has, as `sgbem run` and
/// `sgbem check` both ask: the memory (`Estimate::check_fits`: exit 2 when the estimate
/// exceeds the memory available, exit 1 when the system refuses to reserve it) and the free
/// space of the file system that holds `on` (a folder on the output folder's file system;
/// the output folder is named as `scene.output.directory`: exit 2 when the outputs cannot
/// fit, output::space). A full history that may not fit is advice (`plan.advice`: check's
/// `advice:` lines, run's notes), not a refusal.
pub fn check_resources(loaded: &mut Loaded, scene_path: &Path, on: &Path) -> Result<()> {
    let cost = crate::estimate::estimate(&loaded.model, &loaded.scene);
    cost.check_fits(&loaded.model, scene_path)?;
    let floor = if loaded.scene.output.history == HistoryLevel::Full {
        let mut steps = loaded.scene.clone();
        steps.output.history = HistoryLevel::Steps;
        crate::estimate::estimate(&loaded.model, &steps).outputs
    } else {
        cost.outputs.clone()
    };
    let space = crate::output::space::Space {
        outputs: &cost.outputs,
        floor: &floor,
        folder: &loaded.scene.output.directory,
        on,
    };
    if let Some(note) = space.check(scene_path)? {
        loaded.plan.advice.push(note);
    }
    Ok(())
}

/// Refuses what cannot fit before allocating any of it; keeps the mesh a .geo scene was
/// meshed into (`meshed`, a scratch folder) in the new run's mesh/.
fn check_fits_and_keep_mesh(
    loaded: &mut Loaded,
    scene_path: &Path,
    folder: &RunFolder,
    meshed: &Path,
) -> Result<()> {
    check_resources(loaded, scene_path, folder.staging())?;
    if crate::input::gmsh::is_geo(loaded.scene.mesh.as_deref().unwrap_or(Path::new("")))
        && meshed.is_dir()
    {
        let dest = folder.staging().join("mesh");
        std::fs::create_dir_all(&dest)
            .map_err(|e| Error::io(&dest, format!("cannot create the mesh folder: {e}")))?;
        for entry in std::fs::read_dir(meshed).into_iter().flatten().flatten() {
            let _ = std::fs::copy(entry.path(), dest.join(entry.file_name()));
        }
    }
    Ok(())
}

/// The quadrature of the scene's `[solve] quadrature`.
fn quadrature(scene: &Scene) -> QuadratureSettings {
    QuadratureSettings::from_name(scene.solve.quadrature.name())
        .unwrap_or_else(QuadratureSettings::standard)
}

/// Starts the archive's thread with the model (and, with `operators = true`, the bodies'
/// operators), while the contact stage runs.
fn start_archive(
    folder: &RunFolder,
    scene: &Scene,
    rec: &RunRecord,
    ops: &Operators,
) -> Result<ArchiveWriter> {
    let mut model = rec.clone();
    if scene.output.operators {
        model.set_operators(&ops.systems, &ops.condensed)?;
    }
    Ok(ArchiveWriter::start(
        &folder.staging().join("archive.h5"),
        model,
    ))
}

/// What the section paths need of each recorded state besides its fields (iteration, load
/// step, load factor, body forces).
type StateLoads = (usize, usize, f64, Vec<Option<[f64; 2]>>);

/// The contact results of the archive: the paper's mixed interface operators of the final
/// status (dense over every interface: for scenes of up to 3000 interface unknowns only), the
/// history and the recorded states, which move into the record (a full history of hundreds of
/// bodies is most of a run's memory). Returns what the section paths need of each state.
fn record_solution(
    loaded: &Loaded,
    ops: &Operators,
    solved: &mut ContactRun,
    rec: &mut RunRecord,
    archive: &ArchiveWriter,
    timings: &mut Timings,
) -> Result<Vec<StateLoads>> {
    let Loaded { scene, model, .. } = loaded;
    let t1 = Instant::now();
    let contact_operators = if scene.output.operators {
        mixed_operators(model, ops, solved)?
    } else {
        None
    };
    // The final state belongs to the last step solved (the failing one after a failure).
    let final_step = solved
        .states
        .last()
        .map_or(scene.solve.steps().len() - 1, |s| s.load_step);
    let loads: Vec<StateLoads> = solved
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
    let mut states: Vec<IterateRecord> = Vec::new();
    // The last recorded state is the final one: it is replaced by the run's final state
    // (the step that failed, after a failure), under the same number.
    let mut final_index = 0;
    if scene.output.history != HistoryLevel::Final {
        let recorded = solved.states.len().saturating_sub(1);
        final_index = solved.states.last().map_or(0, |s| s.index);
        for st in std::mem::take(&mut solved.states)
            .into_iter()
            .take(recorded)
        {
            states.push(
                IterateRecord::new(
                    st.index,
                    st.load_step,
                    st.load_factor,
                    st.fields,
                    st.interfaces,
                )
                .with_body_force(&st.body_force, &rec.bodies),
            );
        }
    }
    states.push(
        IterateRecord::new(
            final_index,
            final_step,
            solved.load_factor,
            solved.fields.clone(),
            solved.interfaces.clone(),
        )
        .with_body_force(&solved.body_force, &rec.bodies),
    );
    rec.states = states;
    // The mechanism drawn with the last state: the failure's, or the collapse search's.
    rec.mechanism = (solved.mechanism.as_ref())
        .or(solved.collapse_mechanism.as_ref())
        .cloned()
        .unwrap_or_default();
    // The archive's thread gets the states' fields shared, not copied (IterateRecord); the
    // history goes there alone (the VTK files do not need it).
    archive.send(ArchivePart::Solved {
        contact_operators,
        history: solved.history.clone(),
        states: rec.states.clone(),
        mechanism: rec.mechanism.clone(),
    });
    timings.add("write", t1.elapsed().as_secs_f64());
    if let Some(where_) = non_finite(model, solved) {
        solved.status = RunStatus::NonFinite;
        if solved.failure.is_none() {
            solved.failure = Some(non_finite_error(&where_, scene));
        }
    }
    Ok(loads)
}

/// The paper's mixed interface operators of the final status, where they are archived:
/// scenes without junctions (no place in the paper's layout, one displacement per pair) and
/// with node pairs only (the paper pairs nodes), of up to 3000 interface unknowns.
fn mixed_operators(
    model: &Model,
    ops: &Operators,
    solved: &ContactRun,
) -> Result<Option<Vec<(String, Array)>>> {
    if !model.junctions().is_empty() || model.interfaces.iter().any(|i| i.independent()) {
        return Ok(None);
    }
    let final_status = final_status(model, solved);
    let layout = interface::layout(model, &ops.maps, &final_status)?;
    if layout.n > 3000 {
        return Ok(None);
    }
    let (k, l) = interface::assemble_scaled(&layout, &ops.condensed, solved.load_factor);
    Ok(Some(
        interface::reduced_operators(&layout, &k, &l)
            .into_iter()
            .map(|(n, m)| (n, Array::from_mat(&m)))
            .collect(),
    ))
}

/// What post-processing computed.
struct Post {
    /// Per section: its name and rows.
    sections: Vec<(String, Vec<csv::SectionRow>)>,
    /// Per section with a full history: its name and the `_path.csv` text.
    section_paths: Vec<(String, String)>,
    interior: Vec<InteriorRecord>,
    field_nodes: usize,
    balances: Vec<crate::post::equilibrium::BodyBalance>,
    /// Per interface (joint): its resultant and point of application.
    thrust: Vec<crate::post::thrust::Thrust>,
    notes: Vec<String>,
    seconds: f64,
}

/// Equilibrium per body, sections (and their paths over the recorded states) and the interior
/// field.
fn postprocess(
    loaded: &Loaded,
    settings: &QuadratureSettings,
    solved: &mut ContactRun,
    rec: &RunRecord,
    loads: &[StateLoads],
    progress: &Progress,
) -> Post {
    let Loaded {
        scene, model, plan, ..
    } = loaded;
    let factor = solved.load_factor;
    let mut notes = plan.advice.clone();
    notes.extend(solved.notes.iter().cloned());
    let balances = crate::post::equilibrium::balances(
        model,
        &solved.fields,
        &solved.interfaces,
        &solved.body_force,
        factor,
        scene.thickness,
    );
    if solved.failure.is_none() {
        notes.extend(crate::post::equilibrium::unbalanced_note(model, &balances));
        notes.extend(crate::post::plausibility::displacement_note(
            model,
            &solved.fields,
        ));
    }
    let t2 = Instant::now();
    let mut post = Post {
        sections: Vec::new(),
        section_paths: Vec::new(),
        interior: Vec::new(),
        field_nodes: 0,
        balances,
        thrust: model
            .interfaces
            .iter()
            .zip(&solved.interfaces)
            .map(|(it, r)| {
                let joint = crate::post::thrust::Joint::of(it);
                crate::post::thrust::thrust(&joint, r, scene.thickness)
            })
            .collect(),
        notes,
        seconds: 0.0,
    };
    let inputs = body_inputs(
        model,
        scene.plane,
        &solved.fields,
        &solved.body_force,
        factor,
    );
    // Each section's points are located, planned and integrated once (post::PointSampler),
    // then evaluated for the final state and, but with history = "final", for every kept
    // state (the path, for plots like the paper's Fig. 6), the states in parallel.
    let full_path = scene.output.history != HistoryLevel::Final && !loads.is_empty();
    for s in &scene.output.sections {
        // Evaluated at `from + t (to − from)` taken relative to each body: far from the
        // origin the points written (`pts`) are those rounded to the nearest coordinates.
        let pts = section_points(s.from, s.to, s.points);
        let offsets = section_offsets(s.from, s.to, s.points);
        let sampler = PointSampler::with_offsets(&inputs, settings, s.from, &offsets);
        let rows = section_rows(&pts, sampler.evaluate(&inputs));
        if solved.failure.is_none() {
            if let Some(x) = rows.iter().find_map(|(x, v)| {
                v.filter(|(u, sg)| !u.iter().chain(sg.iter()).all(|c| c.is_finite()))
                    .map(|_| *x)
            }) {
                solved.status = RunStatus::NonFinite;
                solved.failure = Some(non_finite_error(
                    &format!("section {} at ({:e}, {:e})", s.name, x[0], x[1]),
                    scene,
                ));
            }
        }
        if rows.iter().any(|r| r.1.is_none()) {
            post.notes.push(format!(
                "section {}: some points lie outside every body (written as nan)",
                s.name
            ));
        }
        post.sections.push((s.name.clone(), rows));
        if full_path {
            let text = section_path(loaded, &pts, &sampler, rec, loads, &solved.history);
            post.section_paths.push((s.name.clone(), text));
        }
    }
    if scene.output.field {
        let failed = solved.failure.is_some();
        if let Some(e) = interior_field(loaded, settings, &inputs, failed, &mut post, progress) {
            solved.status = RunStatus::NonFinite;
            solved.failure = Some(e);
        }
    }
    post.seconds = t2.elapsed().as_secs_f64();
    post
}

/// The rows of a section's table from its points and their values.
fn section_rows(
    pts: &[[f64; 2]],
    vals: Vec<Option<crate::post::PointValue>>,
) -> Vec<csv::SectionRow> {
    pts.iter()
        .zip(vals)
        .map(|(x, v)| {
            (
                *x,
                v.map(|p| (p.u, [p.sigma[0][0], p.sigma[1][1], p.sigma[0][1]])),
            )
        })
        .collect()
}

/// A section's values at every recorded state (`sections/<name>_path.csv`); the recorded
/// states are those of the record, the last being the final one.
fn section_path(
    loaded: &Loaded,
    pts: &[[f64; 2]],
    sampler: &PointSampler,
    rec: &RunRecord,
    loads: &[StateLoads],
    history: &History,
) -> String {
    let Loaded { scene, model, .. } = loaded;
    let blocks: Vec<String> = rec
        .states
        .par_iter()
        .zip(loads)
        .zip(&history.rows)
        .map(|((record, st), row)| {
            let (iteration, load_step, load_factor, body_force) = st;
            let inputs = body_inputs(model, scene.plane, &record.fields, body_force, *load_factor);
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
    let mut text =
        String::from("iteration,load_step,load_factor,detached_length,x,y,ux,uy,sxx,syy,sxy\n");
    text.extend(blocks);
    text
}

/// The interior field at the mesh nodes of every body (`field = true`); the failure of the
/// first non-finite value where the run has not `failed` already.
fn interior_field(
    loaded: &Loaded,
    settings: &QuadratureSettings,
    inputs: &[crate::post::BodyInput],
    failed: bool,
    post: &mut Post,
    progress: &Progress,
) -> Option<Error> {
    let mut failure = None;
    let total: usize = loaded
        .model
        .bodies
        .iter()
        .map(crate::post::field_node_count)
        .sum();
    let stage = progress.bar("field points", total as u64);
    for input in inputs {
        let values = crate::post::field_at_nodes_with(input, settings, &loaded.mesh.nodes, &|n| {
            stage.inc(n)
        });
        post.field_nodes += values.len();
        let bad = values.iter().find(|v| {
            !(v.u.iter().all(|c| c.is_finite()) && v.sigma.iter().flatten().all(|c| c.is_finite()))
        });
        if let (Some(v), false) = (bad, failed || failure.is_some()) {
            failure = Some(non_finite_error(
                &format!(
                    "body \"{}\": interior field at mesh node {}",
                    input.body.name, v.mesh_node
                ),
                &loaded.scene,
            ));
        }
        post.interior.push(InteriorRecord::from_values(&values));
    }
    stage.finish();
    failure
}

/// The interface and section tables (CSV).
fn write_tables(
    out_dir: &Path,
    loaded: &Loaded,
    solved: &ContactRun,
    post: &Post,
    timings: &mut Timings,
) -> Result<()> {
    let t3 = Instant::now();
    for (it, r) in loaded.model.interfaces.iter().zip(&solved.interfaces) {
        write_staged(
            &out_dir
                .join("interfaces")
                .join(format!("{}.csv", it.spec.name)),
            csv::interface_table(it, r, &loaded.model.bodies).as_bytes(),
        )?;
    }
    if !post.thrust.is_empty() {
        let bodies = &loaded.model.bodies;
        let rows: Vec<csv::ThrustRow> = loaded
            .model
            .interfaces
            .iter()
            .zip(&post.thrust)
            .map(|(it, t)| {
                let name = |b: usize| bodies.get(b).map_or("", |b| b.name.as_str());
                (it.spec.name.as_str(), name(it.body_a), name(it.body_b), t)
            })
            .collect();
        let units = &loaded.scene.units;
        write_staged(
            &out_dir.join("thrust.csv"),
            csv::thrust_table(&rows, &units.force, &units.length).as_bytes(),
        )?;
        // The hubs as the final state's VTK thrust block draws them.
        let pairs: Vec<(usize, usize)> = loaded
            .model
            .interfaces
            .iter()
            .map(|it| (it.body_a, it.body_b))
            .collect();
        let down = crate::post::thrust::down(&solved.body_force);
        let hubs = crate::post::thrust::hubs(&pairs, &post.thrust, &down);
        let named: Vec<(&str, &crate::post::thrust::Hub)> = hubs
            .iter()
            .map(|h| (bodies.get(h.body).map_or("", |b| b.name.as_str()), h))
            .collect();
        write_staged(
            &out_dir.join("thrust_hubs.csv"),
            csv::hub_table(&named, &units.force, &units.length).as_bytes(),
        )?;
    }
    for (name, rows) in &post.sections {
        write_staged(
            &out_dir.join("sections").join(format!("{name}.csv")),
            csv::section_table(rows).as_bytes(),
        )?;
    }
    for (name, text) in &post.section_paths {
        write_staged(
            &out_dir.join("sections").join(format!("{name}_path.csv")),
            text.as_bytes(),
        )?;
    }
    timings.add("write", t3.elapsed().as_secs_f64());
    Ok(())
}

/// `summary.json`'s content; a figure that overflows (serialised as null) fails the run.
fn summary_of(
    loaded: &Loaded,
    ops: &Operators,
    solved: &mut ContactRun,
    post: &Post,
) -> summary::Summary {
    let Loaded {
        scene, model, plan, ..
    } = loaded;
    let dofs: usize = ops.systems.iter().map(|s| s.n()).sum();
    let asym = ops
        .condensed
        .iter()
        .map(|c| c.asymmetry)
        .fold(0.0, f64::max);
    let pivot = ops
        .condensed
        .iter()
        .map(|c| c.pivot_ratio)
        .fold(1.0, f64::min);
    let interfaces = summary::interfaces(&model.interfaces, &solved.interfaces, scene.thickness);
    let mut out = summary::Summary {
        contact: solved.contact.clone(),
        counts: summary::Counts {
            bodies: model.bodies.len(),
            boundary_elements: model.element_count(),
            contact_cuts: model.contact_cuts,
            dofs,
            field_nodes: post.field_nodes,
            interface_pairs: model.pair_count(),
        },
        diagnostics: summary::Diagnostics {
            d00_asymmetry: asym,
            min_pivot_ratio: pivot,
        },
        effects: plan.effects.clone(),
        equilibrium: summary::equilibrium(&post.balances),
        failure: solved.failure.as_ref().map(|e| e.message().to_string()),
        interface_curves: summary::interface_curves(&model.interfaces, &interfaces),
        interfaces,
        load_factor: solved.load_factor,
        // The load path: the pseudo-time of the final state and every step's.
        load_path: scene.solve.time.as_ref().map(|ts| summary::LoadPath {
            depends_on_t: crate::plan::time_dependent(scene),
            time: ts.clone(),
        }),
        mechanism: solved
            .mechanism
            .as_ref()
            .map(|m| crate::contact::mechanism::mechanism_bodies(model, m)),
        method: if plan.problem == crate::plan::ContactProblem::None {
            "linear"
        } else {
            scene.solve.method.name()
        },
        notes: post.notes.clone(),
        overrides: scene.overrides.clone(),
        plane: match scene.plane {
            crate::input::scene::Plane::Strain => "strain",
            crate::input::scene::Plane::Stress => "stress",
        },
        problem: format!("{:?}", plan.problem).to_lowercase(),
        qp: solved
            .qp
            .as_ref()
            .map(|qp| summary::qp(&model.interfaces, qp, scene.thickness)),
        quadrature: scene.solve.quadrature.name(),
        status: solved.status,
        thickness: scene.thickness,
        thrust: summary::thrust(&model.interfaces, &post.thrust),
        time: scene.solve.time.as_ref().map(|_| solved.time),
        title: scene.title.clone(),
        units: scene.units.clone(),
    };
    // Figures that overflow (serialised as null): a resultant of finite tractions can.
    if solved.failure.is_none() {
        if let Some(where_) = summary::non_finite_figure(&out.interfaces) {
            solved.status = RunStatus::NonFinite;
            out.status = solved.status;
            solved.failure = Some(non_finite_error(&where_, scene));
        }
    }
    out
}

/// The archive's last part, the VTK files, `timings.json` and `summary.json` (last), then the
/// whole folder swapped in; returns where the run now is.
#[allow(clippy::too_many_arguments)]
fn write_run(
    folder: RunFolder,
    archive: ArchiveWriter,
    mut rec: RunRecord,
    loaded: &Loaded,
    solved: &ContactRun,
    summary: &summary::Summary,
    progress: &Progress,
    mut timings: Timings,
) -> Result<PathBuf> {
    let out_dir = folder.staging().to_path_buf();
    let text = serde_json::to_string_pretty(summary)
        .map_err(|e| Error::io(&out_dir, format!("cannot serialise the summary: {e}")))?;
    let t4 = Instant::now();
    let stage = progress.spinner("archive and VTK");
    rec.status = solved.status.as_str().to_string();
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
    let vtk = if loaded.scene.output.vtk {
        crate::output::vtk::write_vtk_staged(&out_dir.join("vtk"), &rec).map(|_| ())
    } else {
        Ok(())
    };
    archive.finish()?;
    vtk?;
    stage.finish();
    timings.add("write", t4.elapsed().as_secs_f64());
    // Dates and timings in their own file: summary.json stays byte-identical between runs.
    let timing_text = serde_json::to_string_pretty(&TimingsFile {
        created: &rec.created,
        stages: timings.seconds(),
        within: timings.within(),
    })
    .map_err(|e| Error::io(&out_dir, format!("cannot serialise the timings: {e}")))?;
    write_staged(&out_dir.join("timings.json"), timing_text.as_bytes())?;
    // The summary last, then the whole folder swapped in.
    write_staged(&out_dir.join("summary.json"), text.as_bytes())?;
    let target = folder.target().to_path_buf();
    folder.commit()?;
    Ok(target)
}

/// Where a result holds a number that is not finite ("body \"A\" displacement", ...).
fn non_finite(model: &Model, result: &ContactRun) -> Option<String> {
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
