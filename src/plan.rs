//! The effects plan: which effects a scene calls for and which stages a run performs.
//!
//! Place in the flow: after `model`; read by `sgbem check` (printed) and by the run
//! pipeline (followed). README "Effects plan": effects are simulated only where the scene
//! calls for them: no body-force terms without `body_force`; no contact solver without a
//! `unilateral` interface; only the detachment problem when every unilateral zone starts
//! closed, only the contact problem when every one starts open, both otherwise; the cohesion
//! loop only where `cohesion > 0`; interior fields only with `field = true`; sections only
//! where listed.

use crate::error::{Error, Result};
use crate::input::model::Model;
use crate::input::scene::{
    HistoryLevel, InitialState, InterfaceModel, Method, MethodChoice, Scene, SPARSE_FROM_PAIRS,
};

/// Which unilateral problem the contact solver faces.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ContactProblem {
    /// No unilateral interface: a linear solve.
    None,
    /// Every unilateral zone starts closed: zones can only open.
    Detachment,
    /// Every unilateral zone starts open: zones can only close.
    Contact,
    /// Some start closed, some open.
    Both,
}

impl ContactProblem {
    pub(crate) fn describe(self) -> &'static str {
        match self {
            ContactProblem::None => "none (no unilateral interface): one linear solve",
            ContactProblem::Detachment => {
                "detachment only (every unilateral zone starts closed): closed zones may open"
            }
            ContactProblem::Contact => {
                "contact only (every unilateral zone starts open): open zones may close"
            }
            ContactProblem::Both => {
                "contact and detachment (zones start both closed and open): the coupled problem"
            }
        }
    }
}

/// What a run will simulate and do.
#[derive(Debug, Clone)]
pub struct Plan {
    /// Physical effects simulated, in a fixed order: elastic, body_force, detachment,
    /// contact, cohesion. (Load steps, interior fields and sections are stages, below.)
    pub effects: Vec<&'static str>,
    pub problem: ContactProblem,
    /// Effects left out and why.
    pub omitted: Vec<String>,
    /// Stages in order, with what each does.
    pub stages: Vec<(&'static str, String)>,
    /// Advice on the settings (printed by `check`, kept in the summary by `run`).
    pub advice: Vec<String>,
    /// The largest Young's modulus ratio across an interface, and that interface.
    pub contrast: (f64, String),
}

impl Plan {
    pub fn has(&self, effect: &str) -> bool {
        self.effects.contains(&effect)
    }

    /// "elastic + detachment".
    pub fn effects_line(&self) -> String {
        self.effects.join(" + ")
    }

    /// A numerical failure of the operators, naming the stiffness contrast when it is the
    /// likely cause.
    pub(crate) fn explain(&self, e: Error) -> Error {
        let (c, iface) = &self.contrast;
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
    }
}

/// The prescribed values that depend on the pseudo-time `t`, as key paths.
pub(crate) fn time_dependent(scene: &Scene) -> Vec<String> {
    let mut out = Vec::new();
    // Exact tables, glob tables and defaults (named as in the scene).
    let t = &scene.tables;
    let bodies = scene
        .bodies
        .iter()
        .map(|b| (format!("body.{}", b.name), b))
        .chain(
            t.bodies
                .iter()
                .map(|p| (format!("body.\"{}\"", p.spec.name), &p.spec)),
        )
        .chain(
            t.default_body
                .iter()
                .map(|b| ("defaults.body".to_string(), b)),
        );
    for (key, b) in bodies {
        if let Some(f) = &b.body_force {
            for (c, v) in f.iter().enumerate() {
                if v.uses_time() {
                    out.push(format!("{key}.body_force[{c}]"));
                }
            }
        }
    }
    for b in &scene.boundaries {
        let names = match b.frame {
            crate::input::scene::Frame::Global => [("ux", "tx"), ("uy", "ty")],
            crate::input::scene::Frame::Local => [("ut", "tt"), ("un", "tn")],
        };
        for (c, cond) in b.components.iter().enumerate() {
            let (crate::input::scene::Condition::Displacement(v)
            | crate::input::scene::Condition::Traction(v)) = cond;
            if v.uses_time() {
                let key = if cond.is_displacement() {
                    names[c].0
                } else {
                    names[c].1
                };
                out.push(format!("boundary.{}.{key}", b.name));
            }
        }
    }
    let interfaces = scene
        .interfaces
        .iter()
        .map(|i| (format!("interface.{}", i.name), i))
        .chain(
            t.interfaces
                .iter()
                .map(|p| (format!("interface.\"{}\"", p.spec.name), &p.spec)),
        )
        .chain(
            t.default_interface
                .iter()
                .map(|i| ("defaults.interface".to_string(), i)),
        );
    for (key, i) in interfaces {
        for (what, v) in [
            ("gap", &i.gap),
            ("cohesion", &i.cohesion),
            ("friction", &i.friction),
        ] {
            if v.uses_time() {
                out.push(format!("{key}.{what}"));
            }
        }
    }
    out
}

/// Whether any prescribed value depends on the pseudo-time `t`.
pub(crate) fn uses_time(scene: &Scene) -> bool {
    !time_dependent(scene).is_empty()
}

/// Decides the plan of a scene on its model.
pub fn plan(scene: &Scene, model: &Model) -> Result<Plan> {
    let fx = effects(scene, model)?;
    let steps = scene.solve.steps().len();

    // Stages.
    let mut stages: Vec<(&'static str, String)> = Vec::new();
    stages.push((
        "read",
        format!(
            "scene and mesh ({} bodies, {} boundary elements)",
            model.bodies.len(),
            model.element_count()
        ),
    ));
    let mut assemble = format!(
        "Galerkin blocks per body ({} quadrature), parallel over element pairs",
        scene.solve.quadrature.name()
    );
    if !fx.loaded.is_empty() {
        assemble.push_str(&format!("; body-force loads for {}", named(&fx.loaded)));
    }
    stages.push(("assemble", assemble));
    stages.push(("condense", condense_stage(model, scene.solve.method)));
    let steps_note = if steps > 1 {
        format!(", {steps} load steps")
    } else {
        String::new()
    };
    pseudo_time_stages(scene, &mut stages)?;
    let solve = Solve {
        problem: fx.problem,
        cohesive: fx.cohesive,
        frictional: fx.frictional,
        steps_note: &steps_note,
    };
    solve.stages(scene, &mut stages);
    stages.push(("postprocess", postprocess_stage(scene, model)));
    stages.push(("write", write_stage(scene, model)));

    let (advice, worst) = advice(scene, model);
    Ok(Plan {
        effects: fx.effects,
        problem: fx.problem,
        omitted: fx.omitted,
        stages,
        advice,
        contrast: worst,
    })
}

/// What a scene calls for: the effects simulated and those left out, with what the stages
/// say of them.
struct Effects<'m> {
    effects: Vec<&'static str>,
    omitted: Vec<String>,
    problem: ContactProblem,
    /// The bodies with a non-zero body force.
    loaded: Vec<&'m str>,
    /// Whether a unilateral pair has cohesion.
    cohesive: bool,
    /// Whether a unilateral interface has friction.
    frictional: bool,
}

/// The effects a scene calls for, and those left out and why; `output.field` needs the
/// triangles of every body.
fn effects<'m>(scene: &Scene, model: &'m Model) -> Result<Effects<'m>> {
    let mut effects = vec!["elastic"];
    let mut omitted = Vec::new();

    let loaded: Vec<&str> = model
        .bodies
        .iter()
        .filter(|b| b.body_force.is_some_and(|f| f != [0.0, 0.0]))
        .map(|b| b.name.as_str())
        .collect();
    if loaded.is_empty() {
        omitted.push("body forces: no body has a non-zero body_force".to_string());
    } else {
        effects.push("body_force");
    }

    let unilateral: Vec<_> = model
        .interfaces
        .iter()
        .filter(|i| i.spec.model == InterfaceModel::Unilateral)
        .collect();
    let closed = unilateral
        .iter()
        .any(|i| i.spec.initial == InitialState::Closed);
    let open = unilateral
        .iter()
        .any(|i| i.spec.initial == InitialState::Open);
    let problem = match (closed, open) {
        (false, false) => ContactProblem::None,
        (true, false) => ContactProblem::Detachment,
        (false, true) => ContactProblem::Contact,
        (true, true) => ContactProblem::Both,
    };
    if closed {
        effects.push("detachment");
    }
    if open {
        effects.push("contact");
    }
    match problem {
        ContactProblem::None => {
            omitted.push("contact and detachment: no unilateral interface".to_string())
        }
        ContactProblem::Detachment => {
            omitted.push("contact closing: no unilateral zone starts open".to_string())
        }
        ContactProblem::Contact => {
            omitted.push("detachment: no unilateral zone starts closed".to_string())
        }
        ContactProblem::Both => {}
    }
    let cohesive = unilateral
        .iter()
        .any(|i| i.pairs.iter().any(|p| p.cohesion > 0.0));
    if cohesive {
        effects.push("cohesion");
    } else if closed {
        omitted.push("cohesion loop: cohesion = 0 on every closed zone".to_string());
    }
    let frictional = unilateral
        .iter()
        .any(|i| i.spec.tangential == crate::input::scene::Tangential::Friction);
    if frictional {
        effects.push("friction");
    }
    if scene.output.field {
        if let Some(b) = model.bodies.iter().find(|b| b.triangles.is_empty()) {
            return Err(Error::input(
                &scene.path,
                format!(
                    "`output.field` = true needs the triangles of every body, but body \"{}\" has \
                     none in {}: mesh with `gmsh -2`, or set field = false",
                    b.name,
                    model.mesh_path.display()
                ),
            ));
        }
    } else {
        omitted.push("interior field: output.field = false".to_string());
    }
    Ok(Effects {
        effects,
        omitted,
        problem,
        loaded,
        cohesive,
        frictional,
    })
}

/// The condensation stage: onto the interface nodes, with the junctions where several
/// bodies meet; none without an interface.
fn condense_stage(model: &Model, method: Method) -> String {
    let pairs = model.pair_count();
    if model.interfaces.is_empty() {
        "none (no interface): one solve per body".into()
    } else {
        let junctions = model.junctions();
        let at = if junctions.is_empty() {
            String::new()
        } else {
            let most = junctions.iter().map(|j| j.1.len()).max().unwrap_or(0);
            let rows = if method == Method::Exact {
                "every joint component there keeps its own row"
            } else {
                "the dependent joint components there are implied by the others, see \
                 contact.junctions"
            };
            format!(
                "; {} junctions (points where up to {most} bodies meet: {rows})",
                junctions.len()
            )
        };
        format!("each body onto its interface nodes ({pairs} pairs): D00, Z0{at}")
    }
}

/// The stages in pseudo-time: the collapse bisection (which needs a value that depends on
/// t) and the load path of `solve.time`.
fn pseudo_time_stages(scene: &Scene, stages: &mut Vec<(&'static str, String)>) -> Result<()> {
    if let Some(c) = scene.solve.collapse {
        let dep = time_dependent(scene);
        if dep.is_empty() {
            return Err(Error::input(
                &scene.path,
                "`solve.collapse` increases the load multiplier t, but no prescribed value \
                 depends on t: write the load to increase as an expression in t, e.g. \
                 tx = \"2.5*t\" or body_force = [\"0.2*t\", -20.0]"
                    .to_string(),
            ));
        }
        stages.push((
            "collapse",
            format!(
                "bisection on the load multiplier t in [0, {}] to {} (depending on t: {}), \
                 each trial one step from the unloaded state; the results are those of the \
                 largest t with an equilibrium",
                crate::input::model::fmt_num(c.max),
                crate::input::model::fmt_num(c.tolerance),
                dep.join(", ")
            ),
        ));
    }
    if let Some(ts) = &scene.solve.time {
        let dep = time_dependent(scene);
        let list: Vec<String> = ts
            .iter()
            .map(|t| crate::input::model::fmt_num(*t))
            .collect();
        stages.push((
            "load_path",
            if dep.is_empty() {
                format!(
                    "pseudo-time t = {}: no prescribed value depends on t (the same loads at \
                     every step)",
                    crate::report::shortened_list(&list, ", ")
                )
            } else {
                format!(
                    "pseudo-time t = {}, each step from the previous state; depending on t: {} \
                     (evaluated and assembled again at each step)",
                    crate::report::shortened_list(&list, ", "),
                    dep.join(", ")
                )
            },
        ));
    }
    Ok(())
}

/// What the solve stages depend on.
struct Solve<'a> {
    problem: ContactProblem,
    cohesive: bool,
    frictional: bool,
    /// ", N load steps" with more than one step.
    steps_note: &'a str,
}

impl Solve<'_> {
    /// The solve stages: the linear bonded solve, or one stage per contact solver the
    /// scene's method runs.
    fn stages(&self, scene: &Scene, stages: &mut Vec<(&'static str, String)>) {
        let (problem, cohesive, frictional) = (self.problem, self.cohesive, self.frictional);
        let steps_note = self.steps_note;
        if problem == ContactProblem::None {
            stages.push((
                "solve",
                format!("bonded interface system, linear (no contact solver){steps_note}"),
            ));
        } else {
            let mut cohesion_note = if cohesive {
                "; brittle-cohesion outer loop (a node that detaches loses c)"
            } else {
                ""
            }
            .to_string();
            if frictional {
                cohesion_note.push_str(
                    "; Coulomb friction by a Tresca fixed point (slip bound mu*normal force from \
                     the last outer iterate), stick/slip statuses per pair",
                );
            }
            let what = match problem {
                ContactProblem::Detachment => "detachment",
                ContactProblem::Contact => "contact",
                _ => "contact-detachment",
            };
            if matches!(scene.solve.method, Method::Lcp | Method::Both) {
                stages.push((
                    "contact_lcp",
                    format!(
                        "evolutive LCP ({what}): real/virtual status switching, every iteration \
                         recorded{cohesion_note}{steps_note}"
                    ),
                ));
            }
            if matches!(scene.solve.method, Method::Qp | Method::Both) {
                let form = "convex QP on the openings (the same discrete problem as the LCP)";
                stages.push((
                    "contact_qp",
                    format!("{form} with Clarabel{cohesion_note}{steps_note}"),
                ));
            }
            if scene.solve.method == Method::Sparse {
                let coulomb = if frictional {
                    "; within the active set each iterate takes its slip bounds from the last \
                     iterate's normal forces (Coulomb), the fixed point only where that does not \
                     settle"
                } else {
                    ""
                };
                let chosen = if scene.solve.method_choice == MethodChoice::Size {
                    format!(
                        "; chosen for the scene's size (over {SPARSE_FROM_PAIRS} unilateral \
                         pairs; `method` sets another)"
                    )
                } else {
                    String::new()
                };
                stages.push((
                    "contact_sparse",
                    format!(
                        "active set on the sparse system of displacements and openings \
                         ({what}; the evolutive LCP cross-checks it up to 2000 rows){cohesion_note}\
                         {coulomb}{steps_note}{chosen}"
                    ),
                ));
            }
            if scene.solve.method == Method::Exact {
                let coulomb = if frictional {
                    "; Coulomb's law as a fixed point on the slip bounds (Anderson-accelerated), finished by a linear solve of its statuses"
                } else {
                    ""
                };
                let chosen = if scene.solve.method_choice == MethodChoice::Junctions {
                    "; chosen because unilateral joints meet at junctions, where the other \
                     solvers leave a component without a row of its own (`method` sets another)"
                } else {
                    ""
                };
                stages.push((
                    "contact_exact",
                    format!(
                        "every pair component its own row, junctions included ({what}): one \
                         sparse convex programme per set of slip bounds with Clarabel, an \
                         unbounded one is the mechanism{coulomb}{steps_note}{chosen}"
                    ),
                ));
            }
        }
    }
}

/// The post-processing stage: boundary stresses, the interior field and the sections.
fn postprocess_stage(scene: &Scene, model: &Model) -> String {
    let mut post = vec!["boundary stresses and interface tractions".to_string()];
    if scene.output.field {
        let nodes: usize = model.bodies.iter().map(|b| b.triangle_node_count()).sum();
        post.push(format!("interior field at {nodes} triangle nodes"));
    }
    for s in &scene.output.sections {
        post.push(format!("section {} ({} points)", s.name, s.points));
    }
    post.join("; ")
}

/// The write stage: the files a run writes.
fn write_stage(scene: &Scene, model: &Model) -> String {
    let mut write = vec!["summary.json".to_string()];
    write.push(if scene.output.operators {
        "archive.h5 (with operators)".into()
    } else {
        "archive.h5".into()
    });
    if scene.output.vtk {
        let compressed = if scene.output.vtk_style.compressed {
            ", compressed"
        } else {
            ""
        };
        write.push(match (scene.output.history, scene.output.every) {
            (HistoryLevel::Full, 1) => format!("vtk (every iteration{compressed})"),
            (HistoryLevel::Full, n) => {
                format!("vtk (every {n}-th iteration and the last of each load step{compressed})")
            }
            (HistoryLevel::Steps, _) => format!("vtk (the end of each load step{compressed})"),
            (HistoryLevel::Final, _) => format!("vtk (final state{compressed})"),
        });
    }
    if !model.interfaces.is_empty() {
        write.push("interfaces/*.csv".into());
    }
    if !scene.output.sections.is_empty() {
        write.push("sections/*.csv".into());
    }
    write.join(", ")
}

/// Advice on the settings, and the largest stiffness contrast across an interface with that
/// interface's name.
fn advice(scene: &Scene, model: &Model) -> (Vec<String>, (f64, String)) {
    // Stiffness contrast across interfaces amplifies the quadrature floor (about 1e-12 of
    // the operators with "standard") in the stiff body's tractions.
    let mut advice = Vec::new();
    let worst = model
        .interfaces
        .iter()
        .map(|i| {
            let (a, b) = (model.bodies[i.body_a].young, model.bodies[i.body_b].young);
            (a.max(b) / a.min(b), i.spec.name.clone())
        })
        .fold((1.0, String::new()), |m, c| if c.0 > m.0 { c } else { m });
    let contrast = worst.0;
    if contrast > 1e3 && scene.solve.quadrature != crate::input::scene::Quadrature::Accurate {
        advice.push(format!(
            "the stiffness contrast across an interface is {contrast:.1e}: the quadrature floor \
             is amplified by it in the stiffer body's tractions; consider solve.quadrature = \
             \"accurate\""
        ));
    }
    advice.extend(crate::post::plausibility::input_notes(scene, model));
    (advice, worst)
}

/// Up to 8 names in full; more as their count with the first three and the last.
fn named(names: &[&str]) -> String {
    match names {
        [a, b, c, .., z] if names.len() > 8 => {
            format!("{} bodies ({a}, {b}, {c}, …, {z})", names.len())
        }
        _ => names.join(", "),
    }
}
