//! Where the cycles of pairs at junction points are cut (`[solve] junctions`): after a
//! load path on one cut, the implied components whose law the state breaks, the components
//! of their cycles to cut instead, and the state's statuses on the new rows for the sparse
//! solver's start. Place in the flow: `driver` (the load path) → **`cuts`** → `driver`
//! (the path again on `Problem::with_cuts`).

use std::collections::HashSet;

use crate::contact::problem::{Component, Implied, Problem, RowKind};
use crate::contact::Guess;
use crate::input::model::Model;
use crate::input::scene::{JunctionCuts, Method, Scene, Tangential};
use crate::solution::{InterfaceResult, PairStatus};

/// The statuses and slip bounds of `interfaces` (a state of the same model on another cut
/// of its junctions) on the rows of `problem`, for the sparse solver's start at `step`.
pub(super) fn guess(
    model: &Model,
    problem: &Problem,
    interfaces: &[InterfaceResult],
    step: usize,
) -> Guess {
    let n = problem.n_open_rows;
    let tol = RECUT_TOL * model.scale;
    let mut open = vec![false; n];
    let mut sign = vec![0.0; n];
    let mut bound = vec![0.0; n];
    for (r, row) in problem.rows[..n].iter().enumerate() {
        let Some(p) = interfaces
            .get(row.iface)
            .and_then(|x| x.pairs.get(row.pair))
        else {
            continue;
        };
        let closed = p.status == PairStatus::Closed;
        match row.kind {
            RowKind::Friction => {
                let normal = problem.row_of[row.iface][row.pair][1];
                let force = normal.map_or(0.0, |k| -p.traction[1] * problem.rows[k].weight);
                let mu = model.interfaces[row.iface].pairs[row.pair].friction;
                bound[r] = if closed { mu * force.max(0.0) } else { 0.0 };
                let slips = p.slipping.unwrap_or(p.jump[0].abs() > tol);
                if bound[r] <= 0.0 || slips {
                    // Slipping, or without a bound (its pair open).
                    open[r] = true;
                    sign[r] = if p.jump[0] < 0.0 { -1.0 } else { 1.0 };
                }
            }
            _ => open[r] = !closed,
        }
    }
    Guess {
        step,
        open,
        sign,
        bound,
    }
}

/// Interface pairs up to which the sparse solver cuts junction cycles at whole joints and
/// moves the cuts where an implied component breaks its law (`recut`): exact junctions.
/// Measured on running-bond walls (history "final", one run each, 2026-12-07): 20 × 20
/// (8 050 pairs) exact at once, 4.7 s whole run against 5.2 s with the tangential cut;
/// 28 × 28 (15 974 pairs) exact, 13.6 s against 11.3 s; 45 × 45 (41 734 pairs) exact in
/// 60 s against 41 s (39 iterations against 25, since the proximal weight became a trust
/// region; 68 s and 47 before); 64 × 64 (84 896 pairs) exact in 61 iterations against 34,
/// 142 s whole against 95 s since the sparse iteration skips its doomed exact attempts
/// (218 s before). Above, the tangential cut (not measured on joints), with
/// `implied_slipping` reported.
pub const JOINT_CUTS_MAX_PAIRS: usize = 90_000;

/// Whether `scene` on `model` cuts its junction cycles at whole joints and moves the cuts
/// (`[solve] junctions`; "auto": the sparse solver up to [`JOINT_CUTS_MAX_PAIRS`] pairs,
/// collapse searches included: `wall_collapse` then stands to 0.5996, the full rows'
/// multiplier, where the tangential cut stood to 0.500 with 15 bed joints sliding at
/// T-junctions without a friction force of their own). The full rows have no cut.
pub fn at_joints(scene: &Scene, model: &Model) -> bool {
    match scene.solve.junctions {
        JunctionCuts::Joints => scene.solve.method != Method::Exact,
        JunctionCuts::Tangential => false,
        JunctionCuts::Auto => {
            scene.solve.method == Method::Sparse && model.pair_count() <= JOINT_CUTS_MAX_PAIRS
        }
    }
}

/// Whether a slip of the implied tangential component `i` of a closed pair breaks the pair's
/// law at that node: a stick pair may not slip; a friction pair may where its normal
/// component is implied too (it then carries no normal force there, and Coulomb's law lets
/// a pair without normal force slide), not where the normal component has a row of its own.
pub(crate) fn slip_breaks_law(model: &Model, problem: &Problem, i: &Implied) -> bool {
    match model.interfaces[i.iface].spec.tangential {
        Tangential::Stick => true,
        Tangential::Friction => problem.row_of[i.iface][i.pair][1].is_some(),
        Tangential::Slide => false,
    }
}

/// Slips and penetrations of implied components below this fraction of the model's size
/// are round-off ([`recut`]).
const RECUT_TOL: f64 = 1e-12;

/// Rounds of [`recut`] after the first solve.
pub(super) const MAX_RECUTS: usize = 4;

/// The implied components of `problem` whose law the final state breaks (a tangential
/// component of a closed pair with friction or stick that slips while its normal component
/// has a row; a normal component that penetrates), and for each the component of its cycle
/// to cut instead, added to `demoted`: a normal component of an open pair (with its
/// tangential one), else a tangential component that does not slip. Returns how many
/// components break their law and how many cuts moved.
pub(super) fn recut(
    model: &Model,
    problem: &Problem,
    interfaces: &[InterfaceResult],
    demoted: &mut HashSet<Component>,
) -> (usize, usize) {
    let tol = RECUT_TOL * model.scale;
    let pair = |k: usize, j: usize| interfaces.get(k).and_then(|r| r.pairs.get(j));
    let mut broken = 0;
    let mut moved = 0;
    for i in &problem.implied {
        let it = &model.interfaces[i.iface];
        let Some(p) = pair(i.iface, i.pair) else {
            continue;
        };
        let closed = p.status == PairStatus::Closed;
        let breaks = if i.comp == 0 {
            closed && p.jump[0].abs() > tol && slip_breaks_law(model, problem, i)
        } else {
            it.pairs[i.pair].gap + p.jump[1] < -tol
        };
        if !breaks {
            continue;
        }
        broken += 1;
        let score = |&(k, j, c): &(usize, usize, usize)| -> Option<usize> {
            let q = pair(k, j)?;
            if demoted.contains(&(k, j, c)) {
                return None;
            }
            match c {
                1 if q.status == PairStatus::Open => Some(0),
                0 if q.status == PairStatus::Open || q.jump[0].abs() <= tol => Some(1),
                _ => None,
            }
        };
        let Some(best) = i
            .cycle
            .iter()
            .filter_map(|c| score(c).map(|s| (s, *c)))
            .min_by_key(|x| x.0)
        else {
            continue;
        };
        let (k, j, c) = best.1;
        demoted.remove(&(i.iface, i.pair, i.comp));
        if c == 1 {
            demoted.insert((k, j, 0));
        }
        demoted.insert((k, j, c));
        moved += 1;
    }
    (broken, moved)
}
