//! Equilibrium of each body: the resultant force and moment of every load acting on it and
//! their imbalance, for `summary.json` (`equilibrium`).
//!
//! Place in the flow: reads the model and one solved state (boundary fields, interface
//! results, load factor); writes plain records. Moments are about the body's centroid (of
//! its polygonal boundary, the domain the boundary elements integrate over), counter-clockwise
//! positive; forces and moments are per unit thickness times `thickness`.
//!
//! Each load is integrated the way the discretisation holds it, so that a balanced discrete
//! solution shows an imbalance at round-off level:
//!
//! * **Boundary parts**, prescribed tractions: the element-end tractions are linear along
//!   each element, so for an element from `x0` to `x1` of length `L` with end tractions
//!   `t0`, `t1` and `r = x − c`: `F = L (t0 + t1)/2`,
//!   `M = L/6 (2 r0×t0 + r0×t1 + r1×t0 + 2 r1×t1)` (exact).
//! * **Reactions of displacement conditions**: the nodal forces `R_n = ∫ψ_n t·d` of the held
//!   nodes, each the hypersingular row its displacement would have (assembled with the
//!   body, `BodySystem::held_rows`), at the node, given to the first held part there. The
//!   element tractions of held edges, integrated, balanced only to the discretisation error
//!   (first order: 0.86 / 0.34 / 0.17 % for an arch's abutments at 3 / 6 / 12 elements per
//!   joint); the nodal forces balance to round-off. An interface component held on a side
//!   is in that node's reaction and left out of the interface's load.
//! * **Interfaces**: the nodal forces of the contact problem, `P_j = ∫ψ_j t ds = t_j w_j`
//!   (the reported pair traction times the tributary length), acting at the pair's node on
//!   the first body and opposite on the second. `Σ P_j = ∫t ds` and `Σ x_j × P_j = ∫x × t ds`
//!   hold exactly for the P1 hats, so no quadrature enters.
//! * **Body force**: `b |Ω|` at the centroid (no moment about it).

use crate::input::model::wrench::{
    body_force_wrench, centroid, pair_arm, segment_wrench, Pivot, Wrench,
};
use crate::input::model::{Body, Interface, Model, Role};
use crate::solution::{BodyField, InterfaceResult};
use crate::vec2::cross;

/// The loads of one body and their imbalance.
#[derive(Debug, Clone)]
pub struct BodyBalance {
    pub body: String,
    /// The point moments are taken about: the centroid (rounded to the spacing of
    /// coordinates there; the moments are about the exact one).
    pub point: [f64; 2],
    /// (what, wrench): `body_force`, `boundary NAME` (tractions and reactions of a Physical
    /// Curve), `interface NAME` (the interface's nodal forces on this body).
    pub loads: Vec<(String, Wrench)>,
    /// The sum of the loads.
    pub imbalance: Wrench,
    /// `max(|ΣF| / S, |ΣM| / (S d))` with `S` the sum of the loads' force magnitudes and
    /// `d` the diagonal of the body's bounding box; 0 for an unloaded body.
    pub relative: f64,
}

/// The global directions in which element `e` of boundary part `pi` prescribes
/// displacement (orthonormal: x and y, or the element's tangent and normal).
fn held_directions(model: &Model, e: &crate::input::model::Element, pi: usize) -> Vec<[f64; 2]> {
    use crate::input::scene::{Condition, Frame};
    let spec = &model.parts[pi].spec;
    spec.components
        .iter()
        .enumerate()
        .filter(|(_, cond)| matches!(cond, Condition::Displacement(_)))
        .map(|(c, _)| match (spec.frame, c) {
            (Frame::Global, 0) => [1.0, 0.0],
            (Frame::Global, _) => [0.0, 1.0],
            (Frame::Local, 0) => e.tangent,
            (Frame::Local, _) => e.normal,
        })
        .collect()
}

/// Every body's loads and imbalance in one solved state, with the state's body forces
/// `body_force` (before the load factor).
pub fn balances(
    model: &Model,
    fields: &[BodyField],
    interfaces: &[InterfaceResult],
    body_force: &[Option<[f64; 2]>],
    load_factor: f64,
    thickness: f64,
) -> Vec<BodyBalance> {
    let mut out = Vec::with_capacity(model.bodies.len());
    for (bi, (body, field)) in model.bodies.iter().zip(fields).enumerate() {
        let (area, c) = centroid(body);
        let mut loads: Vec<(String, Wrench)> = Vec::new();
        let mut add = |what: String, w: Wrench| match loads.iter_mut().find(|(n, _)| *n == what) {
            Some((_, acc)) => acc.add(w),
            None => loads.push((what, w)),
        };
        // The body force of the solved state (its load step's pseudo-time).
        if let Some(b) = body_force.get(bi).copied().flatten() {
            add(
                "body_force".into(),
                body_force_wrench([b[0] * load_factor, b[1] * load_factor], area),
            );
        }
        // Where the reactions of the held nodes are known, the held components of the
        // element tractions are replaced by them (nodal forces, each given to the first held
        // boundary part at its node).
        let reactions = field.reaction.len() == body.nodes.len();
        let mut part_of_node: Vec<Option<usize>> = vec![None; body.nodes.len()];
        for (e, t) in body.elements.iter().zip(&field.t) {
            if let Role::Boundary(pi) = e.role {
                let mut t = *t;
                if reactions {
                    let held = held_directions(model, e, pi);
                    if !held.is_empty() {
                        for n in e.nodes {
                            part_of_node[n].get_or_insert(pi);
                        }
                        for te in t.iter_mut() {
                            for d in &held {
                                let x = te[0] * d[0] + te[1] * d[1];
                                te[0] -= x * d[0];
                                te[1] -= x * d[1];
                            }
                        }
                    }
                }
                let w = segment_wrench(
                    body.nodes[e.nodes[0]],
                    body.nodes[e.nodes[1]],
                    t[0],
                    t[1],
                    &c,
                );
                add(format!("boundary {}", model.parts[pi].spec.name), w);
            }
        }
        if reactions {
            // A held node's reaction ∫ψ_n t·d is its hypersingular row: it gathers the
            // tractions of every element around the node (a loaded face, an interface) as
            // the discrete problem does, so the node's force in a held direction is the
            // reaction alone (interface components held on both sides are left out below).
            let reaction = &field.reaction;
            for (n, (f, part)) in reaction.iter().zip(&part_of_node).enumerate() {
                let Some(pi) = part else { continue };
                let x = body.nodes[n];
                add(
                    format!("boundary {}", model.parts[*pi].spec.name),
                    Wrench {
                        fx: f[0],
                        fy: f[1],
                        m: cross(c.arm(x), *f),
                    },
                );
            }
        }
        for (it, r) in model.interfaces.iter().zip(interfaces) {
            if let Some(total) = interface_wrench(body, bi, it, r, &c, reactions) {
                add(format!("interface {}", it.spec.name), total);
            }
        }
        out.push(balance(body, c, loads, thickness));
    }
    out
}

/// The wrench of interface `it` (its solved result `r`) on body `bi`, about `c`: its pair
/// tractions as nodal forces, without the components held on this side where the nodes'
/// reactions are known; `None` when the interface does not touch the body.
fn interface_wrench(
    body: &Body,
    bi: usize,
    it: &Interface,
    r: &InterfaceResult,
    c: &Pivot,
    reactions: bool,
) -> Option<Wrench> {
    let sign = if it.body_a == bi {
        1.0
    } else if it.body_b == bi {
        -1.0
    } else {
        return None;
    };
    let w = it.weights();
    let mut total = Wrench::default();
    for (j, ((p, res), wj)) in it.pairs.iter().zip(&r.pairs).zip(&w).enumerate() {
        let [mut ts, mut tn] = res.traction;
        if reactions {
            // A component held on this side is in the node's reaction.
            let node = if it.body_a == bi { p.node_a } else { p.node_b };
            let d = body.dofs[node];
            for k in 0..2 {
                if d.class[k] != crate::input::model::DofClass::Known {
                    continue;
                }
                let h = d.frame[k];
                if (h[0] * p.tangent[0] + h[1] * p.tangent[1]).abs() > 1.0 - 1e-9 {
                    ts = 0.0;
                }
                if (h[0] * p.normal[0] + h[1] * p.normal[1]).abs() > 1.0 - 1e-9 {
                    tn = 0.0;
                }
            }
        }
        let f = [
            sign * wj * (ts * p.tangent[0] + tn * p.normal[0]),
            sign * wj * (ts * p.tangent[1] + tn * p.normal[1]),
        ];
        // Where the sides were meshed on their own, B takes the force where its partners are.
        let arm = pair_arm(c, it, body, j, sign > 0.0);
        total.add(Wrench {
            fx: f[0],
            fy: f[1],
            m: cross(arm, f),
        });
    }
    Some(total)
}

/// A body's balance: its loads (summed per name, in first-seen order) times the thickness,
/// their imbalance about `c`, and that imbalance relative to the loads.
fn balance(body: &Body, c: Pivot, loads: Vec<(String, Wrench)>, thickness: f64) -> BodyBalance {
    let loads: Vec<(String, Wrench)> = loads
        .into_iter()
        .map(|(n, w)| (n, w.scaled(thickness)))
        .collect();
    let mut imbalance = Wrench::default();
    for (_, w) in &loads {
        imbalance.add(*w);
    }
    let scale: f64 = loads.iter().map(|(_, w)| w.force()).sum();
    let d = diagonal(body);
    let relative = if scale > 0.0 && d > 0.0 {
        (imbalance.force() / scale).max(imbalance.m.abs() / (scale * d))
    } else {
        0.0
    };
    BodyBalance {
        body: body.name.clone(),
        point: c.point(),
        loads,
        imbalance,
        relative,
    }
}

/// Relative imbalance above which a body that no displacement condition holds is reported:
/// such bodies balance to round-off in a solved discrete problem.
pub(crate) const UNBALANCED: f64 = 1e-6;

/// A note naming the bodies held by interfaces and tractions only whose loads do not
/// balance (a contact solution that is no equilibrium, e.g. past the collapse load); `None`
/// when every such body balances. Bodies with displacement conditions are left out: their
/// reactions balance only up to the discretisation error (module doc).
pub(crate) fn unbalanced_note(model: &Model, balances: &[BodyBalance]) -> Option<String> {
    let held = |body: &Body| {
        body.elements.iter().any(|e| match e.role {
            Role::Boundary(pi) => model.parts[pi]
                .spec
                .components
                .iter()
                .any(|c| c.is_displacement()),
            Role::Interface(_) => false,
        })
    };
    let bad: Vec<String> = model
        .bodies
        .iter()
        .zip(balances)
        .filter(|(body, b)| !held(body) && (b.relative > UNBALANCED || b.relative.is_nan()))
        .map(|(_, b)| format!("{} {:.1e}", b.body, b.relative))
        .collect();
    if bad.is_empty() {
        return None;
    }
    let shown = bad.iter().take(5).cloned().collect::<Vec<_>>().join(", ");
    Some(format!(
        "equilibrium: {} bod{} held only by interfaces and tractions do not balance (relative \
         imbalance above {UNBALANCED:e}: {shown}{}): the contact solution is no equilibrium; \
         the loads may exceed what the joints can carry (a mechanism): reduce the loads or \
         check the supports",
        bad.len(),
        if bad.len() == 1 { "y" } else { "ies" },
        if bad.len() > 5 { ", ..." } else { "" }
    ))
}

fn diagonal(body: &Body) -> f64 {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in &body.nodes {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (hi[0] - lo[0]).hypot(hi[1] - lo[1])
}
