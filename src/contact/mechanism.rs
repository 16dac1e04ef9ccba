//! The mechanism of a load step without an equilibrium, for the message and the outputs:
//! its words (the rows that cannot open or slip, the bodies they leave free, the
//! resultants) and its motion (each moving body's rigid motion, from the sparse system's
//! null direction under the loads: summary.json's `mechanism`, the VTK block "mechanism").
//!
//! Place in the flow: the outer loop of a load step (`Session::solve_step`) → **`mechanism`**
//! where an inner solve stops at a mechanism → the step's failure and
//! `ContactResult::motion`.

use super::lcp::{Inner, InnerState};
use super::problem::RowKind;
use super::{sparse, Session};
use crate::input::model::{fmt_num, Model};
use crate::solution::{BodyMotion, MechanismBody};

impl Session<'_> {
    /// The body of interface k that nothing else holds (no displacement condition), if
    /// exactly one of its two bodies is such.
    fn free_body(&self, k: usize) -> Option<usize> {
        let it = &self.model.interfaces[k];
        let held = |b: usize| self.model.bodies[b].dof_counts()[0] > 0;
        match (held(it.body_a), held(it.body_b)) {
            (true, false) => Some(it.body_b),
            (false, true) => Some(it.body_a),
            _ => None,
        }
    }

    /// "; " and the mechanism of the rows `blocked`, or nothing where none is.
    pub(super) fn hint(&self, blocked: &[usize], st: &InnerState, inner: &Inner) -> String {
        if blocked.is_empty() {
            String::new()
        } else {
            format!("; {}", self.mechanism(blocked, st, inner))
        }
    }

    /// Names the bodies and the motion that opening (or letting slip) the `blocked` rows
    /// would leave free, with the resultants of the last state `st`.
    pub(super) fn mechanism(&self, blocked: &[usize], st: &InnerState, inner: &Inner) -> String {
        let n = self.problem.n_open_rows;
        // Sliding: a friction row that cannot slip without a rigid motion.
        if let Some(&r) = blocked
            .iter()
            .find(|&&r| self.problem.rows[r].kind == RowKind::Friction && !inner.free[r])
        {
            let k = self.problem.rows[r].iface;
            let it = &self.model.interfaces[k];
            // Resultants of the last state: normal force, the tangential force the loads
            // ask of the interface, and the friction it can hold (Σ μ N per pair).
            let (mut t, mut nf, mut hold) = (0.0, 0.0, 0.0);
            for q in 0..n {
                let row = self.problem.rows[q];
                if row.iface != k {
                    continue;
                }
                match row.kind {
                    RowKind::Normal if !st.open[q] => {
                        let f = st.lambda[q] - inner.base.cohesion[q];
                        nf += f;
                        hold += self.model.interfaces[k].pairs[row.pair].friction * f.max(0.0);
                    }
                    RowKind::Friction => t += st.lambda[q],
                    _ => {}
                }
            }
            let mu = if nf > 0.0 { hold / nf } else { 0.0 };
            let ratio = if nf > 0.0 {
                t.abs() / nf
            } else {
                f64::INFINITY
            };
            let body = self.free_body(k).map_or("a body".to_string(), |b| {
                format!("body \"{}\"", self.model.bodies[b].name)
            });
            if ratio > mu {
                return format!(
                    "no equilibrium exists (a sliding mechanism): {body} slides on interface \
                     \"{}\": the tangential force it needs exceeds what friction holds, \
                     tangential/normal resultant {ratio:.3} > mu = {mu:.3}; reduce the \
                     tangential load or raise the friction coefficient",
                    it.spec.name,
                );
            }
            // The interface as a whole holds: the mechanism slides part of it and opens
            // other joints (a wedge of blocks, a rocking block that slides at its toe).
            let pr = &it.pairs[self.problem.rows[r].pair];
            let open: Vec<usize> = (0..n)
                .filter(|&q| self.problem.rows[q].kind == RowKind::Normal && st.open[q])
                .collect();
            let mut ifaces: Vec<&str> = open
                .iter()
                .map(|&q| {
                    self.model.interfaces[self.problem.rows[q].iface]
                        .spec
                        .name
                        .as_str()
                })
                .collect();
            ifaces.sort_unstable();
            ifaces.dedup();
            let shown: Vec<String> = ifaces.iter().take(4).map(|s| format!("\"{s}\"")).collect();
            return format!(
                "no equilibrium exists (a mechanism of sliding and opening): interface \"{}\" \
                 cannot slip at ({}, {}) without leaving {body} free, while {} pairs are open \
                 on {} interfaces ({}{}); the interface as a whole is below its friction limit \
                 (tangential/normal resultant {ratio:.3}, mu = {mu:.3}): the blocks move as a \
                 mechanism that combines sliding with the open joints; reduce the load or raise \
                 the friction coefficient",
                it.spec.name,
                fmt_num(pr.x[0]),
                fmt_num(pr.x[1]),
                open.len(),
                ifaces.len(),
                shown.join(", "),
                if ifaces.len() > 4 { ", ..." } else { "" },
            );
        }
        let mut parts = Vec::new();
        for &r in blocked.iter().take(3) {
            let row = self.problem.rows[r];
            let it = &self.model.interfaces[row.iface];
            let pr = &it.pairs[row.pair];
            let dir = if row.comp == 1 { pr.normal } else { pr.tangent };
            let who = match self.free_body(row.iface) {
                Some(b) => format!("body \"{}\"", self.model.bodies[b].name),
                None => format!(
                    "body \"{}\" or body \"{}\"",
                    self.model.bodies[it.body_b].name, self.model.bodies[it.body_a].name
                ),
            };
            parts.push(format!(
                "interface \"{}\" at ({}, {}) cannot open without leaving {who} free: the free \
                 motion is a translation or rotation (tipping about the last closed point) \
                 that opens it along ({:.3}, {:.3})",
                it.spec.name,
                fmt_num(pr.x[0]),
                fmt_num(pr.x[1]),
                dir[0],
                dir[1],
            ));
        }
        format!(
            "no equilibrium exists (a mechanism): the loads pull the bodies apart where nothing \
             else holds them: {}; hold the body with a displacement condition or change the \
             loads",
            parts.join("; ")
        )
    }
}

/// The motion of the mechanism that the rows `blocked` open from the state `st`: its words
/// for the message (`"; the motion: ..."`, each moving body's rigid motion from the sparse
/// system's null direction under the loads, [`sparse::mechanism_motion`] — translation
/// along a unit vector, or rotation about a point, the instantaneous centre, and its sense)
/// and the moving bodies' motions, largest first, scaled so that the fastest boundary node
/// of them moves at 1 (a translation has no rotation); nothing where it cannot be found.
pub(super) fn motion(
    model: &Model,
    inner: &Inner,
    system: &mut Option<sparse::SparseSystem>,
    (st, blocked): (&InnerState, &[usize]),
) -> (String, Option<Vec<BodyMotion>>) {
    if blocked.is_empty() {
        return (String::new(), None);
    }
    if system.is_none() {
        *system = sparse::SparseSystem::new(inner.problem).ok();
    }
    let Some(sys) = system.as_mut() else {
        return (String::new(), None);
    };
    let (mut open, mut sign) = (st.open.clone(), st.sign.clone());
    for &r in blocked {
        open[r] = true;
        if inner.is_friction(r) {
            // A sticking row slips against its excess force.
            sign[r] = -st.lambda[r].signum();
        }
    }
    let Some(dw) = sparse::mechanism_motion(inner, sys, &open, &sign, &st.s) else {
        return (String::new(), None);
    };
    motion_of(model, inner.problem.rigid_motions(model, &dw))
}

/// The words and the scaled motions of the bodies that move in `motions` (every body's
/// rigid motion along a mechanism's direction), as [`motion`] gives them.
pub(super) fn motion_of(
    model: &Model,
    motions: Vec<BodyMotion>,
) -> (String, Option<Vec<BodyMotion>>) {
    let size = model.scale.max(f64::MIN_POSITIVE);
    let amount =
        |m: &BodyMotion| m.translation[0].hypot(m.translation[1]) + m.rotation.abs() * size;
    let largest = motions.iter().map(amount).fold(0.0f64, f64::max);
    let mut moving: Vec<BodyMotion> = motions
        .into_iter()
        .filter(|m| amount(m) > 1e-3 * largest)
        .collect();
    moving.sort_by(|a, b| amount(b).total_cmp(&amount(a)));
    if moving.is_empty() {
        return (String::new(), None);
    }
    let words = motion_words(model, &moving);
    let bodies = scaled(model, moving);
    (words, (!bodies.is_empty()).then_some(bodies))
}

/// Whether a body's motion is a translation: its rotation moves no point within the model's
/// size by more than 1 % of its translation (its centre lies beyond a hundred model sizes).
/// An interior-point certificate's direction carries such rotations where the bodies slide:
/// the 105-brick wall without friction under wind, `method = "exact"`, had every brick turning
/// about a point 3 700 to 3.4e6 away (about 1e-3 of its translation).
fn translates(m: &BodyMotion, size: f64) -> bool {
    m.rotation.abs() * size <= 1e-2 * m.translation[0].hypot(m.translation[1])
}

/// The words of the motions `moving` (largest first; the first four named).
fn motion_words(model: &Model, moving: &[BodyMotion]) -> String {
    let size = model.scale.max(f64::MIN_POSITIVE);
    let words: Vec<String> = moving
        .iter()
        .take(4)
        .map(|m| {
            let name = &model.bodies[m.body].name;
            let t = m.translation;
            let tl = t[0].hypot(t[1]);
            if translates(m, size) {
                // Components that print as zero print without a sign.
                let c = |v: f64| if v.abs() < 5e-4 { 0.0 } else { v };
                format!(
                    "body \"{name}\" moves along ({:.3}, {:.3})",
                    c(t[0] / tl),
                    c(t[1] / tl)
                )
            } else {
                let p = centre(m);
                format!(
                    "body \"{name}\" turns {} about ({}, {})",
                    sense(m),
                    fmt_num((p[0] * 1e6).round() / 1e6),
                    fmt_num((p[1] * 1e6).round() / 1e6)
                )
            }
        })
        .collect();
    let more = if moving.len() > 4 {
        format!(" and {} more bodies", moving.len() - 4)
    } else {
        String::new()
    };
    format!("; the motion: {}{more}", words.join(", "))
}

/// The point of a rotating body that does not move: c + k × t / ω.
fn centre(m: &BodyMotion) -> [f64; 2] {
    [
        m.centroid[0] - m.translation[1] / m.rotation,
        m.centroid[1] + m.translation[0] / m.rotation,
    ]
}

fn sense(m: &BodyMotion) -> &'static str {
    if m.rotation > 0.0 {
        "anticlockwise"
    } else {
        "clockwise"
    }
}

/// The motions `moving` with the translations' rotation set to zero, scaled so that the
/// fastest boundary node of them moves at 1 (empty where none moves).
fn scaled(model: &Model, mut moving: Vec<BodyMotion>) -> Vec<BodyMotion> {
    let size = model.scale.max(f64::MIN_POSITIVE);
    for m in &mut moving {
        if translates(m, size) {
            m.rotation = 0.0;
        }
    }
    let top = moving
        .iter()
        .map(|m| m.top_speed(&model.bodies[m.body].nodes))
        .fold(0.0f64, f64::max);
    if !(top > 0.0 && top.is_finite()) {
        return Vec::new();
    }
    for m in &mut moving {
        m.translation = [m.translation[0] / top, m.translation[1] / top];
        m.rotation /= top;
    }
    moving
}

/// The summary's records of the moving bodies `motion` (scaled as a step's motion is): kind,
/// direction or centre, sense, and the largest speed of each body's boundary nodes.
pub(crate) fn mechanism_bodies(model: &Model, motion: &[BodyMotion]) -> Vec<MechanismBody> {
    motion
        .iter()
        .filter_map(|m| {
            let body = model.bodies.get(m.body)?;
            let t = m.translation;
            let turns = m.rotation != 0.0;
            let tl = t[0].hypot(t[1]);
            Some(MechanismBody {
                body: body.name.clone(),
                centre: turns.then(|| centre(m)),
                direction: (!turns && tl > 0.0).then(|| [t[0] / tl, t[1] / tl]),
                kind: if turns { "rotation" } else { "translation" },
                magnitude: m.top_speed(&body.nodes),
                sense: turns.then(|| sense(m)),
            })
        })
        .collect()
}
