//! Plausibility notes: a run that is valid but whose input or results are unlikely to be
//! what the user meant still succeeds (exit 0) and says so, on stderr and in
//! `summary.json` `notes`. Input notes (units, Young's modulus, nothing loading the model)
//! join the plan's advice, so `sgbem check` prints them too; the displacement note needs
//! the results.

use crate::input::model::{fmt_num, Model};
use crate::input::scene::{Condition, Scene};
use crate::solution::BodyField;

/// Length units sgbem recognises, in metres.
const LENGTHS: [(&str, f64); 12] = [
    ("m", 1.0),
    ("km", 1e3),
    ("dm", 0.1),
    ("cm", 1e-2),
    ("mm", 1e-3),
    ("um", 1e-6),
    ("µm", 1e-6),
    ("nm", 1e-9),
    ("in", 0.0254),
    ("inch", 0.0254),
    ("ft", 0.3048),
    ("yd", 0.9144),
];

/// Force units sgbem recognises, in newtons.
const FORCES: [(&str, f64); 14] = [
    ("N", 1.0),
    ("uN", 1e-6),
    ("µN", 1e-6),
    ("mN", 1e-3),
    ("daN", 10.0),
    ("kN", 1e3),
    ("MN", 1e6),
    ("GN", 1e9),
    ("kgf", 9.806_65),
    ("tf", 9_806.65),
    ("lbf", 4.448_221_615_260_5),
    ("kip", 4_448.221_615_260_5),
    ("kips", 4_448.221_615_260_5),
    ("dyn", 1e-5),
];

/// Young's moduli of solids, in Pa: soft foams and gels (1 kPa) to diamond (1.2 TPa).
const YOUNG_PA: (f64, f64) = (1e3, 2e12);

/// The largest displacement, as a share of the model's size, within small-displacement
/// theory's reach. The error of the linear theory grows with the square of the rotations
/// (about u/size): at 5 % it is a few tenths of a percent. (1 % would flag the paper's own
/// example 2, 4.55 cm on a 4 m clamped beam: 1.13 %.)
pub(crate) const SMALL_DISPLACEMENT: f64 = 0.05;

/// One note per implausible Young's modulus (`pa`: Pa per unit of stress), naming the
/// bodies that have it: a wall of 410 bricks of one material is one note, not 410.
fn young_notes(model: &Model, pa: f64, len: &str, force: &str) -> Vec<String> {
    let mut moduli: Vec<(f64, Vec<&str>)> = Vec::new();
    for b in &model.bodies {
        let e = b.young * pa;
        if (YOUNG_PA.0..=YOUNG_PA.1).contains(&e) {
            continue;
        }
        match moduli.iter_mut().find(|(y, _)| *y == b.young) {
            Some((_, names)) => names.push(&b.name),
            None => moduli.push((b.young, vec![&b.name])),
        }
    }
    moduli
        .into_iter()
        .map(|(young, names)| {
            let shown: Vec<String> = names.iter().take(4).map(|n| format!("\"{n}\"")).collect();
            let who = match names.len() {
                1 => format!("body {}", shown[0]),
                n if n <= 4 => format!("bodies {}", shown.join(", ")),
                n => format!("bodies {} and {} more", shown.join(", "), n - 4),
            };
            format!(
                "{who}: young = {} {force}/{len}² is {} Pa, outside the moduli of solids \
                 ({:.0e} to {:.0e} Pa; rubber about 1e6, concrete 3e10, steel 2.1e11): check \
                 the value and `units` (or keep it, for a body meant to be nearly rigid or \
                 nearly void)",
                fmt_num(young),
                fmt_num(young * pa),
                YOUNG_PA.0,
                YOUNG_PA.1
            )
        })
        .collect()
}

fn factor(list: &[(&str, f64)], unit: &str) -> Option<f64> {
    list.iter()
        .find(|(u, _)| *u == unit.trim())
        .map(|(_, f)| *f)
}

/// Notes on the scene: units that are not units, Young's moduli implausible for the
/// declared units, and a model that nothing loads.
pub(crate) fn input_notes(scene: &Scene, model: &Model) -> Vec<String> {
    let mut notes = Vec::new();
    let names = |list: &[(&str, f64)]| list.iter().map(|(u, _)| *u).collect::<Vec<_>>().join(" ");
    let (len, force) = (&scene.units.length, &scene.units.force);
    for (key, unit, list) in [
        ("units.length", len, &LENGTHS[..]),
        ("units.force", force, &FORCES[..]),
    ] {
        if !unit.trim().is_empty() && factor(list, unit).is_none() {
            let like = list
                .iter()
                .find(|(u, _)| u.eq_ignore_ascii_case(unit.trim()))
                .map(|(u, _)| format!(" (did you mean \"{u}\"?)"))
                .unwrap_or_default();
            notes.push(format!(
                "`{key}` = \"{unit}\" is not a unit sgbem knows{like}: it knows {}; units are \
                 recorded in the outputs, never converted, so check the spelling",
                names(list)
            ));
        }
    }
    if let (Some(l), Some(f)) = (factor(&LENGTHS, len), factor(&FORCES, force)) {
        notes.extend(young_notes(model, f / (l * l), len, force));
    }
    notes.extend(far_note(model));
    notes.extend(crate::estimate::memory_limit_note());
    if !loaded(model) {
        notes.push(
            "nothing loads the model: every prescribed displacement and traction is zero, no \
             body has a body_force and no interface starts in interference, so every result is \
             zero; add a load (e.g. [boundary.NAME] ty = -1.0)"
                .into(),
        );
    }
    notes
}

/// The share of its smallest element's length to which a node position is held (half the
/// spacing of floating-point coordinates where the model lies), above which a note says so
/// (six digits of the geometry kept).
const RESOLUTION: f64 = 1e-6;

/// A note when the model lies so far from the origin that a node position there is held
/// only to within more than [`RESOLUTION`] of its smallest element's length. The solver
/// computes in coordinates relative to each body and loses nothing more there: the note is
/// about the positions themselves (`check` refuses a mesh whose spacing exceeds a tenth of
/// an element).
fn far_note(model: &Model) -> Option<String> {
    let lines = model.bodies.iter().flat_map(|b| {
        b.elements
            .iter()
            .map(|e| (b.nodes[e.nodes[0]], b.nodes[e.nodes[1]]))
    });
    let (far, step, h) = crate::input::model::resolution(lines);
    let held = 0.5 * step;
    if !(h.is_finite() && h > 0.0 && held > RESOLUTION * h) {
        return None;
    }
    Some(format!(
        "the model lies {} from the origin, where floating-point coordinates are spaced {} \
         apart: a node position there is held only to within {}, {:.1e} of its smallest \
         element ({}), so its geometry, and with it its results, may keep fewer than six \
         digits (the solver works in coordinates relative to each body and loses nothing \
         more); move the model near the origin (e.g. Translate in the .geo)",
        fmt_num(far),
        fmt_num(step),
        fmt_num(held),
        held / h,
        fmt_num(h)
    ))
}

/// Whether anything loads the model: a non-zero (or varying) prescribed value, a body
/// force, or an interference.
fn loaded(model: &Model) -> bool {
    let nonzero = |s: &crate::input::expr::Scalar| !s.is_zero();
    let boundary = model.parts.iter().any(|p| {
        p.spec.components.iter().any(|c| match c {
            Condition::Displacement(v) | Condition::Traction(v) => nonzero(v),
        })
    });
    let body = model.bodies.iter().any(|b| {
        b.body_force.is_some_and(|f| f != [0.0, 0.0])
            || b.body_force_spec
                .as_ref()
                .is_some_and(|f| f.iter().any(nonzero))
    });
    let interference = model
        .interfaces
        .iter()
        .any(|i| i.pairs.iter().any(|p| p.gap < 0.0));
    boundary || body || interference
}

/// A note when the largest displacement exceeds [`SMALL_DISPLACEMENT`] of the model's size
/// (its bounding box's diagonal).
pub(crate) fn displacement_note(model: &Model, fields: &[BodyField]) -> Option<String> {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for b in &model.bodies {
        for p in &b.nodes {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
    }
    let size = (hi[0] - lo[0]).hypot(hi[1] - lo[1]);
    let mut worst = (0.0, 0, 0);
    for (b, f) in fields.iter().enumerate() {
        for (n, u) in f.u.iter().enumerate() {
            let m = u[0].hypot(u[1]);
            if m > worst.0 {
                worst = (m, b, n);
            }
        }
    }
    let (u, b, n) = worst;
    if !(size > 0.0 && u.is_finite() && u > SMALL_DISPLACEMENT * size) {
        return None;
    }
    let body = model.bodies.get(b)?;
    let x = body.nodes.get(n)?;
    Some(format!(
        "the largest displacement, {} at ({}, {}) of body \"{}\", is {:.3} % of the model's \
         size {}: beyond small-displacement theory ({} %), so the results describe no real \
         deformation; check the loads, `young` and `units`",
        fmt_num(u),
        fmt_num(x[0]),
        fmt_num(x[1]),
        body.name,
        100.0 * u / size,
        fmt_num(size),
        100.0 * SMALL_DISPLACEMENT
    ))
}
