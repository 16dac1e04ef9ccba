//! What `sgbem check` prints: the model and the plan, for a person to read.
//!
//! Place in the flow: reads `Scene`, `Model` and `Plan`; writes text. Nothing depends on it.

use std::collections::BTreeMap;
use std::fmt::Write;

use serde::Serialize;

use crate::input::model::{fmt_num, DofClass, Model};
use crate::input::scene::{InitialState, InterfaceModel, Plane, Scene, Tangential};
use crate::plan::Plan;

/// The check report as text.
pub fn check_report(scene: &Scene, model: &Model, plan: &Plan, mesh_binary: bool) -> String {
    let mut o = String::new();
    let len_unit = if scene.units.length.is_empty() {
        String::new()
    } else {
        format!(" {}", scene.units.length)
    };
    write_scene(&mut o, scene, model, mesh_binary, &len_unit);
    write_bodies(&mut o, model);
    write_sizes(&mut o, model, &len_unit);
    write_parts(&mut o, model);
    if !scene.tables.is_empty() {
        write_tables(&mut o, model);
    }
    write_interfaces(&mut o, model);
    write_plan(&mut o, scene, model, plan);
    o
}

/// The scene, its mesh, the plane and the units.
fn write_scene(o: &mut String, scene: &Scene, model: &Model, mesh_binary: bool, len_unit: &str) {
    let _ = writeln!(
        o,
        "scene     {} — \"{}\"",
        scene.path.display(),
        scene.title
    );
    if !scene.overrides.is_empty() {
        let sets: Vec<String> = scene
            .overrides
            .iter()
            .map(|s| crate::input::scene::shown_set(s))
            .collect();
        let _ = writeln!(o, "overrides --set {}", shortened_list(&sets, " --set "));
    }
    if !scene.mesh_parameters.is_empty() {
        let p: Vec<String> = scene
            .mesh_parameters
            .iter()
            .map(|(k, v)| format!("{k} = {v}"))
            .collect();
        let _ = writeln!(o, "meshed    by gmsh with {}", p.join(", "));
    }
    let _ = writeln!(
        o,
        "mesh      {} (MSH 4.1 {})",
        model.mesh_path.display(),
        if mesh_binary { "binary" } else { "ASCII" }
    );
    if model.contact_cuts > 0 {
        let _ = writeln!(
            o,
            "          {} cuts by [contact] where the body a line element faces changes (as many \
             line elements more)",
            model.contact_cuts
        );
    }
    let plane = match scene.plane {
        Plane::Strain => "strain",
        Plane::Stress => "stress",
    };
    let units = if scene.units.length.is_empty() && scene.units.force.is_empty() {
        "unspecified".to_string()
    } else {
        format!("length {}, force {}", scene.units.length, scene.units.force)
    };
    let _ = writeln!(
        o,
        "plane     {plane}, thickness {}{len_unit}; units {units}",
        fmt_num(scene.thickness)
    );
}

/// The bodies: material, loops, elements and the classes of their displacement components.
fn write_bodies(o: &mut String, model: &Model) {
    let _ = writeln!(o, "\nbodies ({})", model.bodies.len());
    for b in &model.bodies {
        let holes = b.loops.iter().filter(|l| l.is_hole).count();
        let force = match b.body_force {
            Some(f) => format!(", body force ({}, {})", fmt_num(f[0]), fmt_num(f[1])),
            None => String::new(),
        };
        let _ = writeln!(
            o,
            "  {:<12} E {} ν {}{force}; {} loop{} (outer counter-clockwise{}), {} elements, \
             {} nodes; area {}, perimeter {}; {} triangles",
            b.name,
            fmt_num(b.young),
            fmt_num(b.poisson),
            b.loops.len(),
            if b.loops.len() == 1 { "" } else { "s" },
            if holes > 0 {
                format!(
                    ", {holes} hole{} clockwise",
                    if holes == 1 { "" } else { "s" }
                )
            } else {
                String::new()
            },
            b.elements.len(),
            b.nodes.len(),
            fmt_num(b.area),
            fmt_num(b.perimeter()),
            b.triangles.len()
        );
        let [u1, u0, u2] = b.dof_counts();
        let doubles = b.elements.iter().filter(|e| e.traction_break).count();
        let _ = writeln!(
            o,
            "  {:<12} displacement components: {u1} known (U1), {u0} on interfaces (U0), {u2} \
             free (U2); {doubles} double traction nodes",
            ""
        );
        let partial = b
            .dofs
            .iter()
            .filter(|d| (d.class[0] == DofClass::Known) != (d.class[1] == DofClass::Known))
            .count();
        if partial > 0 {
            let _ = writeln!(
                o,
                "  {:<12} {partial} nodes with one known direction (normal/tangential or single \
                 component conditions)",
                ""
            );
        }
    }
}

/// The boundary elements' sizes and grading.
fn write_sizes(o: &mut String, model: &Model, len_unit: &str) {
    let s = &model.sizes;
    let _ = writeln!(
        o,
        "\nboundary elements {}; smallest {}{len_unit} ({}), largest {}{len_unit} ({}); \
         largest neighbour ratio {} ({})",
        model.element_count(),
        fmt_num(s.smallest.0),
        s.smallest.1,
        fmt_num(s.largest.0),
        s.largest.1,
        fmt_num((s.grading.0 * 100.0).round() / 100.0),
        s.grading.1
    );
    if s.grading.0 > 3.0 {
        let _ = writeln!(
            o,
            "  note: neighbouring elements differ by more than 3×; a geometric grading of at \
             most 2–3× keeps tractions accurate (near-pair quadrature handles it either way)"
        );
    }
}

/// The boundary parts, the Physical Curves absent from the scene and those on no body.
fn write_parts(o: &mut String, model: &Model) {
    let _ = writeln!(o, "\nboundary parts ({})", model.parts.len());
    for p in &model.parts {
        let on: Vec<String> = p
            .elements
            .iter()
            .map(|(b, n)| format!("{} {n}", model.bodies[*b].name))
            .collect();
        let _ = writeln!(
            o,
            "  {:<14} {:<11} {:<28} elements: {}; length {}{}",
            p.spec.name,
            p.spec.role(),
            p.spec.describe(),
            on.join(", "),
            fmt_num(p.length),
            if p.listed {
                ""
            } else {
                "  (not in the scene: traction-free)"
            }
        );
    }
    let absent: Vec<&str> = model
        .parts
        .iter()
        .filter(|p| !p.listed)
        .map(|p| p.spec.name.as_str())
        .collect();
    if !absent.is_empty() {
        let _ = writeln!(
            o,
            "  Physical Curves absent from the scene (traction-free): {}",
            absent.join(", ")
        );
    }
    if !model.unused_curves.is_empty() {
        let _ = writeln!(
            o,
            "  Physical Curves on no body boundary (ignored): {}",
            model.unused_curves.join(", ")
        );
    }
}

/// The interfaces: model, bodies, elements and pairs.
fn write_interfaces(o: &mut String, model: &Model) {
    let _ = writeln!(o, "\ninterfaces ({})", model.interfaces.len());
    for (k, i) in model.interfaces.iter().enumerate() {
        let sp = &i.spec;
        let kind = match sp.model {
            InterfaceModel::Bonded => "bonded".to_string(),
            InterfaceModel::Unilateral => {
                let state = match sp.initial {
                    InitialState::Closed => "starts closed",
                    InitialState::Open => "starts open",
                };
                let tang = match sp.tangential {
                    Tangential::Friction => format!("friction {}", sp.friction),
                    other => other.name().to_string(),
                };
                let extra = match sp.initial {
                    InitialState::Closed => format!("cohesion {}", sp.cohesion),
                    InitialState::Open => format!("gap {}", sp.gap),
                };
                format!("unilateral, {state}, {extra}, {tang}")
            }
        };
        let _ = writeln!(
            o,
            "  {:<14} {kind}; {} | {} (normal out of {}); {} elements, {} pairs, length {}{}",
            sp.name,
            model.bodies[i.body_a].name,
            model.bodies[i.body_b].name,
            model.bodies[i.body_a].name,
            i.elements.len(),
            i.pairs.len(),
            fmt_num(i.length),
            if i.matched_by_position {
                "; sides matched by position".to_string()
            } else if i.independent() {
                let found = if i.group == crate::input::model::FOUND_GROUP {
                    "; found by [contact]"
                } else {
                    ""
                };
                let (facing, lo, hi) = independent_figures(i);
                format!(
                    "{found}; sides meshed on their own, paired from the geometry: {facing} of \
                     {} pairs face {} ({} elements), gap from the geometry {} to {}",
                    i.pairs.len(),
                    model.bodies[i.body_b].name,
                    model.bodies[i.body_b]
                        .elements
                        .iter()
                        .filter(|e| e.role == crate::input::model::Role::Interface(k))
                        .count(),
                    fmt_num(lo),
                    fmt_num(hi)
                )
            } else {
                String::new()
            }
        );
    }
    if model.interfaces.is_empty() {
        let _ = writeln!(o, "  none");
    }
}

/// The plan: effects, problem, method, stages, cost, advice and what is not simulated.
fn write_plan(o: &mut String, scene: &Scene, model: &Model, plan: &Plan) {
    let _ = writeln!(o, "\nplan");
    let _ = writeln!(o, "  effects: {}", plan.effects_line());
    let _ = writeln!(o, "  problem: {}", plan.problem.describe());
    let _ = writeln!(o, "  method:  {}", scene.solve.method.name());
    let _ = writeln!(o, "  stages:");
    for (name, what) in &plan.stages {
        let _ = writeln!(o, "    {name:<12} {what}");
    }
    let cost = crate::estimate::estimate(model, scene);
    let unknowns: usize = cost.bodies.iter().map(|b| b.n_x + b.n_x0).sum();
    let _ = writeln!(o, "  cost:    {} ({unknowns} unknowns)", cost.line());
    if let Some(line) = cost.contact_line() {
        let _ = writeln!(o, "  cost:    {line}");
    }
    let _ = writeln!(o, "  outputs: {}", cost.outputs.line(scene));
    for a in &plan.advice {
        let _ = writeln!(o, "  advice: {a}");
    }
    if !plan.omitted.is_empty() {
        let _ = writeln!(o, "  not simulated:");
        for w in &plan.omitted {
            let _ = writeln!(o, "    {w}");
        }
    }
}

/// Which table applies to each body and interface group, one line per table (scenes with
/// glob or default tables).
fn write_tables(o: &mut String, model: &Model) {
    let mut by_table: Vec<(&str, Vec<&str>)> = Vec::new();
    for r in &model.tables {
        match by_table.iter_mut().find(|(t, _)| *t == r.table) {
            Some((_, groups)) => groups.push(&r.group),
            None => by_table.push((&r.table, vec![&r.group])),
        }
    }
    let _ = writeln!(
        o,
        "\ntables (exact name > most specific pattern > defaults)"
    );
    for (table, groups) in by_table {
        let _ = writeln!(o, "  {table:<24} {} ({})", groups.join(", "), groups.len());
    }
}

/// A scene value that may be an expression: its number, or its text.
#[derive(Debug, Clone, Serialize)]
#[serde(untagged)]
pub enum ScalarJson {
    Number(f64),
    Text(String),
}

impl From<&crate::input::expr::Scalar> for ScalarJson {
    fn from(s: &crate::input::expr::Scalar) -> ScalarJson {
        match s.as_const() {
            Some(v) => ScalarJson::Number(v),
            None => ScalarJson::Text(s.to_string()),
        }
    }
}

// What `sgbem check --json` prints, as typed records. Key order: the report has always
// been written with the keys of every object sorted (serde_json's map), and a struct is
// written in the order of its fields, so every record here declares its fields in
// alphabetical order; a key that is sometimes absent is skipped when `None`, one that is
// `null` is an `Option` written as it is.

/// The whole of `sgbem check --json`.
#[derive(Debug, Clone, Serialize)]
pub struct CheckJson<'a> {
    pub bodies: Vec<BodyJson<'a>>,
    pub boundary_elements: ElementSizes<'a>,
    pub boundary_parts: Vec<PartJson<'a>>,
    pub cost: CostJson,
    pub interfaces: Vec<InterfaceJson<'a>>,
    pub mesh: MeshJson<'a>,
    pub outputs: OutputsJson,
    pub overrides: &'a [String],
    pub plan: PlanJson<'a>,
    pub plane: &'static str,
    pub scene: String,
    pub thickness: f64,
    pub title: &'a str,
    pub units: crate::input::scene::Units,
    pub unused_curves: &'a [String],
}

/// The mesh file: its path, format and the Gmsh parameters the scene sets.
#[derive(Debug, Clone, Serialize)]
pub struct MeshJson<'a> {
    /// Cuts that `[contact]` made where the body a line element faces changes (the mesh
    /// has as many line elements more).
    pub contact_cuts: usize,
    pub format: &'static str,
    /// Each parameter's value as text, by name.
    pub gmsh_parameters: BTreeMap<&'a str, String>,
    pub path: String,
}

/// One body's material, load and sizes.
#[derive(Debug, Clone, Serialize)]
pub struct BodyJson<'a> {
    pub area: f64,
    pub body_force: Option<[f64; 2]>,
    pub displacement_components: DofJson,
    pub elements: usize,
    pub holes: usize,
    pub loops: usize,
    pub name: &'a str,
    pub nodes: usize,
    pub perimeter: f64,
    pub poisson: f64,
    pub triangles: usize,
    pub young: f64,
}

/// A body's displacement components by kind.
#[derive(Debug, Clone, Serialize)]
pub struct DofJson {
    pub free: usize,
    pub interface: usize,
    pub known: usize,
}

/// The boundary elements: their count and extreme sizes.
#[derive(Debug, Clone, Serialize)]
pub struct ElementSizes<'a> {
    pub count: usize,
    pub largest: SizeAt<'a>,
    pub largest_neighbour_ratio: SizeAt<'a>,
    pub smallest: SizeAt<'a>,
}

/// A size and where it is.
#[derive(Debug, Clone, Serialize)]
pub struct SizeAt<'a> {
    pub at: &'a str,
    pub value: f64,
}

impl<'a> From<&'a (f64, String)> for SizeAt<'a> {
    fn from((value, at): &'a (f64, String)) -> SizeAt<'a> {
        SizeAt { at, value: *value }
    }
}

/// One boundary part: its condition and where it lies.
#[derive(Debug, Clone, Serialize)]
pub struct PartJson<'a> {
    pub condition: String,
    /// Its elements per body, by body name.
    pub elements: BTreeMap<&'a str, usize>,
    pub in_scene: bool,
    pub length: f64,
    pub name: &'a str,
    pub role: &'static str,
}

/// One interface: its model, values and sizes.
#[derive(Debug, Clone, Serialize)]
pub struct InterfaceJson<'a> {
    pub body_a: &'a str,
    pub body_b: &'a str,
    pub cohesion: ScalarJson,
    pub elements: usize,
    pub friction: ScalarJson,
    pub gap: ScalarJson,
    /// Sides meshed on their own only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub independent_sides: Option<IndependentJson>,
    pub initial: &'static str,
    pub length: f64,
    pub matched_by_position: bool,
    pub model: &'static str,
    pub name: &'a str,
    pub pairs: usize,
    pub tangential: &'static str,
}

/// An interface with independent sides: B's nodes, the pairs that face B and the range
/// of their gaps measured from the geometry.
#[derive(Debug, Clone, Serialize)]
pub struct IndependentJson {
    pub b_nodes: usize,
    pub facing_pairs: usize,
    pub gap_geometry: [f64; 2],
}

/// The plan: effects, problem, method and stages.
#[derive(Debug, Clone, Serialize)]
pub struct PlanJson<'a> {
    pub advice: &'a [String],
    pub effects: &'a [&'static str],
    pub method: &'static str,
    pub not_simulated: &'a [String],
    pub problem: &'static str,
    pub stages: Vec<StageJson<'a>>,
}

/// One stage of the plan.
#[derive(Debug, Clone, Serialize)]
pub struct StageJson<'a> {
    pub does: &'a str,
    pub name: &'static str,
}

/// The estimated cost of the run.
#[derive(Debug, Clone, Serialize)]
pub struct CostJson {
    /// `null` without a contact stage.
    pub contact: Option<ContactCostJson>,
    pub peak_bytes: f64,
    pub post_seconds: f64,
    pub seconds: f64,
    pub text: String,
    pub unknowns: usize,
}

/// The contact stage's estimated cost.
#[derive(Debug, Clone, Serialize)]
pub struct ContactCostJson {
    pub bytes: f64,
    pub history_bytes: f64,
    pub pairs: usize,
    pub seconds: f64,
    pub states: usize,
}

/// The outputs asked for and their estimated sizes.
#[derive(Debug, Clone, Serialize)]
pub struct OutputsJson {
    pub estimate: crate::output::size::SizeFigures,
    pub every: usize,
    pub history: &'static str,
    pub text: String,
    pub vtk_compressed: bool,
}

/// What `sgbem check --json` prints: the check report as data, for scripts and editors.
/// Lengths in the scene's length unit, stresses in its force per length squared.
pub fn check_json<'a>(
    scene: &'a Scene,
    model: &'a Model,
    plan: &'a Plan,
    mesh_binary: bool,
) -> CheckJson<'a> {
    let cost = crate::estimate::estimate(model, scene);
    let unknowns: usize = cost.bodies.iter().map(|b| b.n_x + b.n_x0).sum();
    let s = &model.sizes;
    CheckJson {
        bodies: model.bodies.iter().map(body_json).collect(),
        boundary_elements: ElementSizes {
            count: model.element_count(),
            largest: SizeAt::from(&s.largest),
            largest_neighbour_ratio: SizeAt::from(&s.grading),
            smallest: SizeAt::from(&s.smallest),
        },
        boundary_parts: model.parts.iter().map(|p| part_json(model, p)).collect(),
        cost: CostJson {
            contact: cost.contact.as_ref().map(|c| ContactCostJson {
                bytes: c.bytes,
                history_bytes: c.history_bytes,
                pairs: c.pairs,
                seconds: c.seconds(),
                states: c.states,
            }),
            peak_bytes: cost.peak_bytes,
            post_seconds: cost.post_seconds,
            seconds: cost.seconds,
            text: cost.line(),
            unknowns,
        },
        interfaces: model
            .interfaces
            .iter()
            .map(|i| interface_json(model, i))
            .collect(),
        mesh: MeshJson {
            contact_cuts: model.contact_cuts,
            format: if mesh_binary { "binary" } else { "ascii" },
            gmsh_parameters: scene
                .mesh_parameters
                .iter()
                .map(|(k, v)| (k.as_str(), v.to_string()))
                .collect(),
            path: model.mesh_path.display().to_string(),
        },
        outputs: OutputsJson {
            estimate: cost.outputs.figures(),
            every: scene.output.every,
            history: scene.output.history.name(),
            text: cost.outputs.line(scene),
            vtk_compressed: scene.output.vtk_style.compressed,
        },
        overrides: &scene.overrides,
        plan: PlanJson {
            advice: &plan.advice,
            effects: &plan.effects,
            method: scene.solve.method.name(),
            not_simulated: &plan.omitted,
            problem: plan.problem.describe(),
            stages: plan
                .stages
                .iter()
                .map(|(name, does)| StageJson { does, name })
                .collect(),
        },
        plane: match scene.plane {
            Plane::Strain => "strain",
            Plane::Stress => "stress",
        },
        scene: scene.path.display().to_string(),
        thickness: scene.thickness,
        title: &scene.title,
        units: scene.units.clone(),
        unused_curves: &model.unused_curves,
    }
}

fn body_json(b: &crate::input::model::Body) -> BodyJson<'_> {
    let [known, interface, free] = b.dof_counts();
    BodyJson {
        area: b.area,
        body_force: b.body_force,
        displacement_components: DofJson {
            free,
            interface,
            known,
        },
        elements: b.elements.len(),
        holes: b.loops.iter().filter(|l| l.is_hole).count(),
        loops: b.loops.len(),
        name: &b.name,
        nodes: b.nodes.len(),
        perimeter: b.perimeter(),
        poisson: b.poisson,
        triangles: b.triangles.len(),
        young: b.young,
    }
}

fn part_json<'a>(model: &'a Model, p: &'a crate::input::model::Part) -> PartJson<'a> {
    PartJson {
        condition: p.spec.describe(),
        elements: p
            .elements
            .iter()
            .map(|(b, n)| (model.bodies[*b].name.as_str(), *n))
            .collect(),
        in_scene: p.listed,
        length: p.length,
        name: &p.spec.name,
        role: p.spec.role(),
    }
}

/// Pairs of an interface with independent sides that face B, and the range of their
/// gaps measured from the geometry.
fn independent_figures(i: &crate::input::model::Interface) -> (usize, f64, f64) {
    let facing: Vec<f64> = i
        .pairs
        .iter()
        .filter(|p| !p.partners.is_empty())
        .map(|p| p.gap_geometry)
        .collect();
    let lo = facing.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = facing.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    (facing.len(), lo, hi)
}

fn interface_json<'a>(
    model: &'a Model,
    i: &'a crate::input::model::Interface,
) -> InterfaceJson<'a> {
    let sp = &i.spec;
    InterfaceJson {
        body_a: &model.bodies[i.body_a].name,
        body_b: &model.bodies[i.body_b].name,
        cohesion: ScalarJson::from(&sp.cohesion),
        elements: i.elements.len(),
        friction: ScalarJson::from(&sp.friction),
        gap: ScalarJson::from(&sp.gap),
        independent_sides: i.independent().then(|| {
            let (facing, lo, hi) = independent_figures(i);
            IndependentJson {
                b_nodes: i.b_nodes.len(),
                facing_pairs: facing,
                gap_geometry: [lo, hi],
            }
        }),
        initial: match sp.initial {
            InitialState::Closed => "closed",
            InitialState::Open => "open",
        },
        length: i.length,
        matched_by_position: i.matched_by_position,
        model: match sp.model {
            InterfaceModel::Bonded => "bonded",
            InterfaceModel::Unilateral => "unilateral",
        },
        name: &sp.name,
        pairs: i.pairs.len(),
        tangential: sp.tangential.name(),
    }
}

/// `items` joined by `sep`, at most [`SHOWN`] of them: a long list (200 000 load steps,
/// 50 000 `--set`) shows its first ones, its last two and how many there are in all.
pub(crate) fn shortened_list(items: &[String], sep: &str) -> String {
    const SHOWN: usize = 12;
    if items.len() <= SHOWN {
        return items.join(sep);
    }
    format!(
        "{}{sep}…{sep}{} ({} in all)",
        items[..SHOWN - 2].join(sep),
        items[items.len() - 2..].join(sep),
        items.len()
    )
}
