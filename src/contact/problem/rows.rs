//! The rows of the contact problem: candidate rows, their elimination around junctions,
//! the final rows and the glued unknowns (see [`Problem::new`](super::Problem::new)).

// Index loops mirror the block formulas.
#![allow(clippy::needless_range_loop)]

use std::collections::HashSet;

use super::body::NodeDofMap;
use super::{Implied, Row, RowKind};
use crate::error::{Error, Result};
use crate::input::model::Model;
use crate::input::scene::{InterfaceModel, Tangential};

/// A candidate row before the junction cycles are cut: its coefficients over the dofs.
pub(super) struct Candidate {
    pub(super) row: Row,
    /// `[u]_r = Σ coef·U_d` (B's dofs positive, A's negative).
    coefs: Vec<(usize, f64)>,
    /// How many of `coefs` are B's (they come first).
    n_b: usize,
}

impl Candidate {
    pub(super) fn full(&self) -> super::FullRow {
        super::FullRow {
            row: self.row,
            coefs: self.coefs.clone(),
        }
    }
}

/// One eliminated dof: `U_d = Σ m·U_master + Σ r·(s_q − h_q)` over candidate rows q.
#[derive(Debug, Clone, Default)]
pub(super) struct RowExpr {
    m: Vec<(usize, f64)>,
    r: Vec<(usize, f64)>,
}

fn add_to(list: &mut Vec<(usize, f64)>, k: usize, x: f64) {
    match list.iter_mut().find(|(q, _)| *q == k) {
        Some(e) => e.1 += x,
        None => list.push((k, x)),
    }
}

/// The coefficients of one side's dofs at `node` along direction `e`, and how much of `e`
/// those dofs span (1 where the node moves freely along e, 0 where it is prescribed).
fn side_coefs(node_dofs: &NodeDofMap, node: usize, e: [f64; 2]) -> (Vec<(usize, f64)>, f64) {
    let list = node_dofs.get(&node).map_or(&[][..], |v| &v[..]);
    let mut coefs = Vec::new();
    let mut free = 0.0;
    for &(d, dir) in list {
        let x = e[0] * dir[0] + e[1] * dir[1];
        free += x * x;
        if x.abs() > 1e-12 {
            coefs.push((d, x));
        }
    }
    (coefs, free)
}

/// Step 2 of [`Problem::new`]: a candidate row for every pair component with a displacement
/// unknown on both sides.
pub(super) fn candidates(model: &Model, node_dofs: &[NodeDofMap]) -> Result<Vec<Candidate>> {
    let mut cands: Vec<Candidate> = Vec::new();
    for (k, it) in model.interfaces.iter().enumerate() {
        let w = it.weights();
        for j in 0..it.pairs.len() {
            for c in 0..2 {
                if let Some(cand) = candidate(model, node_dofs, k, j, c, w[j])? {
                    cands.push(cand);
                }
            }
        }
    }
    Ok(cands)
}

/// The candidate row of component `c` of pair `j` of interface `k`, if it has one.
fn candidate(
    model: &Model,
    node_dofs: &[NodeDofMap],
    k: usize,
    j: usize,
    c: usize,
    weight: f64,
) -> Result<Option<Candidate>> {
    let it = &model.interfaces[k];
    let pr = &it.pairs[j];
    let e = if c == 1 { pr.normal } else { pr.tangent };
    let (ca, fa) = side_coefs(&node_dofs[it.body_a], pr.node_a, e);
    let none = |f: f64| f < 1e-9;
    let full = |f: f64| f > 1.0 - 1e-9;
    let (cb, fb) = if it.independent() {
        // Sides meshed on their own (docs/formulation.md §5.6): B's part of
        // the row is Σ c_k u^B_k over the partners, less what B holds; no
        // row where A holds the component, or where nothing of B faces A.
        if pr.partners.is_empty() || none(fa) {
            return Ok(None);
        }
        let mut cb = Vec::new();
        for &(node, w) in &pr.partners {
            for (d, x) in side_coefs(&node_dofs[it.body_b], node, e).0 {
                add_to(&mut cb, d, w * x);
            }
        }
        let fb = if cb.is_empty() { 0.0 } else { 1.0 };
        (cb, fb)
    } else {
        side_coefs(&node_dofs[it.body_b], pr.node_b, e)
    };
    if none(fa) && none(fb) {
        return Ok(None);
    }
    if none(fa) != none(fb) || !full(fa) || !full(fb) {
        return Err(Error::input(
            &model.mesh_path,
            format!(
                "interface \"{}\" at {:?}: a displacement component is \
                 prescribed on one side only; prescribe it on both bodies \
                 or on neither",
                it.spec.name, pr.x
            ),
        ));
    }
    let kind = match (it.spec.model, c, it.spec.tangential) {
        (InterfaceModel::Bonded, _, _) => RowKind::Bonded,
        (InterfaceModel::Unilateral, 1, _) => RowKind::Normal,
        (InterfaceModel::Unilateral, _, Tangential::Slide) => return Ok(None),
        (InterfaceModel::Unilateral, _, Tangential::Friction) => RowKind::Friction,
        (InterfaceModel::Unilateral, _, Tangential::Stick) => RowKind::Stick,
    };
    let main = |l: &[(usize, f64)]| {
        l.iter()
            .max_by(|x, y| x.1.abs().total_cmp(&y.1.abs()))
            .map_or(0, |x| x.0)
    };
    let row = Row {
        iface: k,
        pair: j,
        comp: c,
        kind,
        dof_a: main(&ca),
        dof_b: main(&cb),
        gap: if c == 1 { pr.gap } else { 0.0 },
        weight,
    };
    let n_b = cb.len();
    let coefs = cb
        .into_iter()
        .chain(ca.into_iter().map(|(d, x)| (d, -x)))
        .collect();
    Ok(Some(Candidate { row, coefs, n_b }))
}

/// A pair component: interface, pair, component (0 tangential, 1 normal).
pub type Component = (usize, usize, usize);

/// The elimination class of a row: bonded (normal components first), then normal, then
/// tangential; the unilateral components in `demoted` after all others (normal, then
/// tangential), so that a cycle is cut there.
fn class(r: &Row, demoted: &HashSet<Component>) -> usize {
    let late = r.kind != RowKind::Bonded && demoted.contains(&(r.iface, r.pair, r.comp));
    match (r.kind, r.comp) {
        (_, 1) if late => 4,
        _ if late => 5,
        (RowKind::Bonded, 1) => 0,
        (RowKind::Bonded, _) => 1,
        (RowKind::Normal, _) => 2,
        (RowKind::Stick | RowKind::Friction, _) => 3,
    }
}

/// The cuts of [`super::Cuts::Joints`] from an elimination with the default order: for each
/// implied tangential component whose cycle holds both normal and tangential components,
/// both components of the pairs of those normal components.
pub(super) fn joint_cuts(cands: &[Candidate], first: &Elimination) -> HashSet<Component> {
    let mut cuts = HashSet::new();
    for (q, cycle) in first.cycle.iter().enumerate() {
        if first.kept[q] || cands[q].row.comp != 0 {
            continue;
        }
        if !cycle.iter().any(|&k| cands[k].row.comp == 0) {
            continue;
        }
        for &k in cycle {
            let r = cands[k].row;
            if r.comp == 1 && r.kind == RowKind::Normal {
                cuts.insert((r.iface, r.pair, 1));
                cuts.insert((r.iface, r.pair, 0));
            }
        }
    }
    cuts
}

/// What [`eliminate`] gives: the expression of every eliminated dof, which candidates are
/// kept as rows, and for each candidate left out the kept candidates its relative
/// displacement is a combination of (its cycle at the junction).
pub(super) struct Elimination {
    pub(super) expr: Vec<Option<RowExpr>>,
    pub(super) kept: Vec<bool>,
    pub(super) cycle: Vec<Vec<usize>>,
}

/// Step 3 of [`Problem::new`]: eliminates the closed rows in class order (see [`class`]).
pub(super) fn eliminate(
    cands: &[Candidate],
    n_dofs: usize,
    demoted: &HashSet<Component>,
) -> Elimination {
    let mut order: Vec<usize> = (0..cands.len()).collect();
    order.sort_by_key(|&q| class(&cands[q].row, demoted));
    let mut expr: Vec<Option<RowExpr>> = vec![None; n_dofs];
    let mut refs: Vec<Vec<usize>> = vec![Vec::new(); n_dofs];
    let mut kept = vec![false; cands.len()];
    let mut cycle = vec![Vec::new(); cands.len()];
    let mut normal_dropped = HashSet::new();
    for &q in &order {
        let cand = &cands[q];
        let row = cand.row;
        if matches!(row.kind, RowKind::Stick | RowKind::Friction)
            && normal_dropped.contains(&(row.iface, row.pair))
        {
            continue;
        }
        let RowExpr { m: am, r: ar } = reduce(cand, &expr);
        let scale = cand.coefs.iter().map(|c| c.1.abs()).fold(0.0, f64::max);
        let big = am.iter().map(|c| c.1.abs()).fold(0.0, f64::max);
        if big <= 1e-9 * scale {
            if row.kind == RowKind::Normal {
                normal_dropped.insert((row.iface, row.pair));
            }
            cycle[q] = ar
                .iter()
                .filter(|c| c.1.abs() > 1e-9 * scale)
                .map(|c| c.0)
                .collect();
            continue;
        }
        kept[q] = true;
        // Pivot: B's dof where it is free and as large as any, else the largest.
        let b_dofs: Vec<usize> = cand.coefs[..cand.n_b].iter().map(|c| c.0).collect();
        let pivot = am
            .iter()
            .copied()
            .filter(|(_, x)| x.abs() >= big * (1.0 - 1e-9))
            .max_by_key(|(m, _)| b_dofs.contains(m))
            .unwrap_or(am[0]);
        let (p, alpha) = pivot;
        let mut new = RowExpr::default();
        for &(m, x) in &am {
            if m != p {
                new.m.push((m, -x / alpha));
            }
        }
        new.r.push((q, 1.0 / alpha));
        for &(r, x) in &ar {
            add_to(&mut new.r, r, -x / alpha);
        }
        substitute(&mut expr, &mut refs, p, new);
    }
    Elimination { expr, kept, cycle }
}

/// A candidate's coefficients over the dofs still free (`m`) and the earlier rows'
/// openings (`r`), with the eliminated dofs replaced by their expressions.
fn reduce(cand: &Candidate, expr: &[Option<RowExpr>]) -> RowExpr {
    let mut am: Vec<(usize, f64)> = Vec::new();
    let mut ar: Vec<(usize, f64)> = Vec::new();
    for &(d, a) in &cand.coefs {
        match &expr[d] {
            Some(e) => {
                for &(m, x) in &e.m {
                    add_to(&mut am, m, a * x);
                }
                for &(r, x) in &e.r {
                    add_to(&mut ar, r, a * x);
                }
            }
            None => add_to(&mut am, d, a),
        }
    }
    RowExpr { m: am, r: ar }
}

/// Eliminates dof `p` by its expression `new`: substitutes it in every expression that uses
/// it (`refs[m]`: the dofs whose expression uses free dof m).
fn substitute(expr: &mut [Option<RowExpr>], refs: &mut [Vec<usize>], p: usize, new: RowExpr) {
    for d in std::mem::take(&mut refs[p]) {
        let Some(mut e) = expr[d].take() else {
            continue;
        };
        if let Some(pos) = e.m.iter().position(|&(m, _)| m == p) {
            let (_, x) = e.m.remove(pos);
            for &(m, y) in &new.m {
                add_to(&mut e.m, m, x * y);
                if !refs[m].contains(&d) {
                    refs[m].push(d);
                }
            }
            for &(r, y) in &new.r {
                add_to(&mut e.r, r, x * y);
            }
        }
        expr[d] = Some(e);
    }
    for &(m, _) in &new.m {
        refs[m].push(p);
    }
    expr[p] = Some(new);
}

/// The rows of the problem after elimination, and the implied components.
pub(super) struct RowSet {
    pub(super) rows: Vec<Row>,
    /// The row of each candidate (`usize::MAX` where it is implied).
    pub(super) index_of: Vec<usize>,
    pub(super) n_open_rows: usize,
    pub(super) row_of: Vec<Vec<[Option<usize>; 2]>>,
    pub(super) implied: Vec<Implied>,
    pub(super) implied_at: std::collections::HashSet<(usize, usize, usize)>,
}

fn implied_of(cands: &[Candidate], cycle: &[Vec<usize>], q: usize) -> Implied {
    let row = &cands[q].row;
    Implied {
        iface: row.iface,
        pair: row.pair,
        comp: row.comp,
        kind: row.kind,
        cycle: cycle[q]
            .iter()
            .map(|&k| (cands[k].row.iface, cands[k].row.pair, cands[k].row.comp))
            .collect(),
    }
}

/// Step 4 of [`Problem::new`]: the final rows, those kept, the rows that can open first (in
/// interface order), then the bonded ones; the others are implied.
pub(super) fn final_rows(model: &Model, cands: &[Candidate], elim: &Elimination) -> RowSet {
    let kept = &elim.kept;
    let mut index_of = vec![usize::MAX; cands.len()];
    let mut rows: Vec<Row> = Vec::new();
    let mut implied = Vec::new();
    for bonded in [false, true] {
        for (q, cand) in cands.iter().enumerate() {
            if (cand.row.kind == RowKind::Bonded) != bonded {
                continue;
            }
            if kept[q] {
                index_of[q] = rows.len();
                rows.push(cand.row);
            } else if !bonded {
                implied.push(implied_of(cands, &elim.cycle, q));
            }
        }
    }
    for (q, cand) in cands.iter().enumerate() {
        if cand.row.kind == RowKind::Bonded && !kept[q] {
            implied.push(implied_of(cands, &elim.cycle, q));
        }
    }
    let n_open_rows = rows
        .iter()
        .take_while(|r| r.kind != RowKind::Bonded)
        .count();
    let mut row_of: Vec<Vec<[Option<usize>; 2]>> = model
        .interfaces
        .iter()
        .map(|it| vec![[None; 2]; it.pairs.len()])
        .collect();
    for (r, row) in rows.iter().enumerate() {
        row_of[row.iface][row.pair][row.comp] = Some(r);
    }
    let implied_at = implied.iter().map(|i| (i.iface, i.pair, i.comp)).collect();
    RowSet {
        rows,
        index_of,
        n_open_rows,
        row_of,
        implied,
        implied_at,
    }
}

/// The dofs through the glued unknowns and the openings (see [`Problem`]'s fields).
pub(super) struct GluedMaps {
    pub(super) tmap: Vec<Vec<(usize, f64)>>,
    pub(super) offs: Vec<Vec<(usize, f64)>>,
    pub(super) row_t: Vec<Vec<(usize, f64)>>,
    pub(super) n_glued: usize,
}

/// Step 5 of [`Problem::new`]: the glued unknowns are the dofs left free, numbered in dof
/// order; every dof is expressed through them and the rows' openings.
pub(super) fn glued_maps(expr: &[Option<RowExpr>], index_of: &[usize], n_rows: usize) -> GluedMaps {
    let n_dofs = expr.len();
    let mut glued_index = vec![usize::MAX; n_dofs];
    let mut n_glued = 0;
    for d in 0..n_dofs {
        if expr[d].is_none() {
            glued_index[d] = n_glued;
            n_glued += 1;
        }
    }
    let mut tmap: Vec<Vec<(usize, f64)>> = Vec::with_capacity(n_dofs);
    let mut offs: Vec<Vec<(usize, f64)>> = Vec::with_capacity(n_dofs);
    let mut row_t: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n_rows];
    for d in 0..n_dofs {
        match &expr[d] {
            None => {
                tmap.push(vec![(glued_index[d], 1.0)]);
                offs.push(Vec::new());
            }
            Some(e) => {
                tmap.push(
                    e.m.iter()
                        .filter(|c| c.1 != 0.0)
                        .map(|&(m, x)| (glued_index[m], x))
                        .collect(),
                );
                let o: Vec<(usize, f64)> =
                    e.r.iter()
                        .filter(|c| c.1 != 0.0)
                        .map(|&(q, x)| (index_of[q], x))
                        .collect();
                for &(r, x) in &o {
                    row_t[r].push((d, x));
                }
                offs.push(o);
            }
        }
    }
    GluedMaps {
        tmap,
        offs,
        row_t,
        n_glued,
    }
}
