//! The one discrete contact problem that every solver solves (docs/formulation.md §6.2 (ii)).
//!
//! Place in the flow: `bem` (per-body condensed operators D00, Z̄0) → **`problem`** → the
//! solvers (`evolutive`, `active_set`, `lemke`, `qp`) → results.
//!
//! # The discrete problem
//!
//! **Per body: the symmetric Steklov–Poincaré stiffness.** Each body's condensed system
//! `Z0 = D00 X0 + Z̄0` over its interface unknowns `X0 = [F; −U]` (traction hats and nodal
//! displacements in the pair frames) is reduced by imposing the body's own weak
//! compatibility `W = 0`:
//!
//! ```text
//!   F = G_U U − G_z,        G_U = D_WF⁻¹ D_WU,  G_z = D_WF⁻¹ Z̄_W
//!   P = S U + p̂,           S = −D_PU + D_WUᵀ G_U (symmetric PSD),  p̂ = Z̄_P − D_WUᵀ G_z
//! ```
//!
//! `P` is the Galerkin-weighted traction `∫ψ_j t` of the body at its interface nodes: the
//! **nodal force** that the neighbour exerts on it. Each body's energy is
//! `E_b(U) = ½ UᵀS U + p̂ᵀU`; S is singular only for a body held by interfaces alone.
//!
//! **Pairing.** Every interface pair component with a displacement unknown on both sides is a
//! row r with the relative displacement `[u]_r = U^B_r − U^A_r` (pair frame of A: tangential
//! s, normal n). Unilateral normal rows pair the **nodal gap** `g_r = h_r + [u]_n ≥ 0` with
//! the **nodal contact force** `λ_r = P^B_n + c_r w_r ≥ 0` (compression positive; `w_r` is
//! the tributary length ∫ψ_j ds of the pair, so a closed pair holds a tension up to the
//! cohesion c_r times its tributary length):
//!
//! ```text
//!   g_r ≥ 0,   λ_r ≥ 0,   g_r λ_r = 0       (one complementarity per unilateral pair)
//! ```
//!
//! Bonded rows and the tangential rows of tangentially tied pairs are equalities `[u] = 0`
//! (`stick`: tied while the pair is closed; `slide`: never tied). With every row closed the
//! bodies are glued into one assembled stiffness K_g over shared nodal displacements (sparse:
//! bodies couple only through their shared nodes), factorised once by sparse Cholesky.
//! Opening a set O of rows adds the openings s_O as unknowns; eliminating the glued
//! displacements gives
//!
//! ```text
//!   λ = λ⁰ + A s,    A = ∂λ/∂s  (the opening stiffness, symmetric PSD; PD unless a body
//!                                 can move freely once the rows of O are open)
//! ```
//!
//! so the frictionless problem is the LCP `λ = λ⁰ + A s, s ≥ 0, λ ≥ 0, sᵀλ = 0` over the
//! unilateral rows: unique when A is positive definite (a P-matrix; Cottle–Pang–Stone), and
//! equivalently the convex QP `min ½sᵀA s + λ⁰ᵀs, s ≥ 0`. A status (open set O) is solved by
//! `A_OO s_O = −λ⁰_O` with the columns of A computed on demand (one sparse solve each) and a
//! Cholesky factor of A_OO that is updated, not refactorised, when one row switches
//! ([`Opening`]): O(|O|²) per switch. No dense matrix over all interfaces is formed, except
//! by Lemke's method and the QP, which need A over every unilateral row.
//!
//! Why this pairing: the paper's mixed status system shares the traction F of a closed pair
//! and checks nodal gaps of open ones, so its statuses are not the principal pivots of one
//! LCP (its open state balances nodal forces P = 0, its closed state weak compatibility), and
//! the force QP (32b) checks Galerkin-weighted gaps instead: the solvers solved different
//! problems. Here every body satisfies W = 0 in every status, the only status-dependent
//! conditions are the rows above, and the status systems are exactly the principal pivots of
//! one symmetric LCP. The mixed system remains available for the archive (`interface`).

// Index loops mirror the block formulas.
#![allow(clippy::needless_range_loop)]

use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, Triplet};
use faer::Mat;

use crate::bem::assembly::{BodySystem, Unknown};
use crate::bem::condensation::recover;
use crate::bem::operators::Operators;
use crate::error::{Error, Result};
use crate::input::model::Model;
use crate::input::scene::{InterfaceModel, Tangential};
use crate::linalg::matvec;
use crate::solution::{BodyField, InterfaceResult, PairResult, PairStatus};

/// One body's Steklov–Poincaré operator.
pub struct BodyOp {
    /// X0 indices of the displacement unknowns (the body's dofs) and of the tractions.
    pub u_idx: Vec<usize>,
    pub f_idx: Vec<usize>,
    /// S (n_u × n_u) and p̂ for the unit load.
    pub s: Mat<f64>,
    pub p: Vec<f64>,
    /// Traction recovery F = G_U U − factor·G_z.
    pub gu: Mat<f64>,
    pub gz: Vec<f64>,
}

/// What a row ties.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RowKind {
    /// Bonded interface: always closed.
    Bonded,
    /// Normal component of a unilateral pair: the complementarity row.
    Normal,
    /// Tangential component of a `stick` pair: tied while the pair is closed.
    Stick,
    /// Tangential component of a `friction` pair: sticks or slips (Coulomb).
    Friction,
}

/// A relative-displacement row `[u]_r = U^B − U^A` of one pair component.
#[derive(Debug, Clone, Copy)]
pub struct Row {
    pub iface: usize,
    pub pair: usize,
    /// 0 tangential, 1 normal.
    pub comp: usize,
    pub kind: RowKind,
    /// Global dof indices of A's and B's displacement component.
    pub dof_a: usize,
    pub dof_b: usize,
    /// Initial gap (normal rows).
    pub gap: f64,
    /// Tributary length ∫ψ_j ds of the pair on A's side.
    pub weight: f64,
}

/// A body's interface nodes → their displacement dofs (global index, direction).
type NodeDofMap = std::collections::HashMap<usize, Vec<(usize, [f64; 2])>>;

/// A pair component at a junction left without a row (see [`Problem::new`]).
#[derive(Debug, Clone, Copy)]
pub struct Implied {
    pub iface: usize,
    pub pair: usize,
    pub comp: usize,
    pub kind: RowKind,
}

/// A candidate row before the junction cycles are cut: its coefficients over the dofs.
struct Candidate {
    row: Row,
    /// `[u]_r = Σ coef·U_d` (B's dofs positive, A's negative).
    coefs: Vec<(usize, f64)>,
    /// How many of `coefs` are B's (they come first).
    n_b: usize,
}

/// One eliminated dof: `U_d = Σ m·U_master + Σ r·(s_q − h_q)` over candidate rows q.
#[derive(Debug, Clone, Default)]
struct Expr {
    m: Vec<(usize, f64)>,
    r: Vec<(usize, f64)>,
}

fn add_to(list: &mut Vec<(usize, f64)>, k: usize, x: f64) {
    match list.iter_mut().find(|(q, _)| *q == k) {
        Some(e) => e.1 += x,
        None => list.push((k, x)),
    }
}

/// The contact problem of a model: per-body operators, rows, and the glued base factor.
pub struct Problem {
    pub ops: Vec<BodyOp>,
    /// First global dof of each body (dofs are the bodies' U unknowns in order).
    pub dof_start: Vec<usize>,
    pub n_dofs: usize,
    /// Rows that can open (normal and stick rows), then bonded rows.
    pub rows: Vec<Row>,
    /// Number of rows that can open (a prefix of `rows`).
    pub n_open_rows: usize,
    /// `row_of[k][j][c]`: the row of a pair component, if any.
    pub row_of: Vec<Vec<[Option<usize>; 2]>>,
    /// Each global dof in the glued unknowns v and the row openings:
    /// `U_d = Σ tmap[d]·v + Σ offs[d]·(s_r − h_r)` (a single `(g, 1)` for a dof that is not
    /// eliminated; the two sides of a closed row share their glued unknowns).
    tmap: Vec<Vec<(usize, f64)>>,
    offs: Vec<Vec<(usize, f64)>>,
    /// `t_r = ∂U/∂s_r` of each row (the dofs its opening moves with every other row held):
    /// the row's force is `λ_r = t_rᵀ P`.
    row_t: Vec<Vec<(usize, f64)>>,
    /// Pair components at junctions whose relative displacement the kept rows already
    /// fix while they are closed (a cycle of pairs around the point): no row of their own.
    pub implied: Vec<Implied>,
    implied_at: std::collections::HashSet<(usize, usize, usize)>,
    n_glued: usize,
    factor: faer::sparse::linalg::solvers::Llt<usize, f64>,
}

/// The all-closed state for one load factor and cohesion: glued displacements v⁰ and row
/// forces λ⁰ (over the rows that can open).
pub struct Base {
    pub factor: f64,
    pub v0: Vec<f64>,
    /// Row forces with every row closed at its offset.
    pub lambda0: Vec<f64>,
    /// The opening each row keeps while closed: the accumulated slip s̄ of friction rows,
    /// zero on other rows.
    pub offset: Vec<f64>,
    /// Offsets (initial gaps closed) and cohesion terms per row.
    pub cohesion: Vec<f64>,
}

/// X0 indices of a body's displacement and traction unknowns, and the (interface, pair,
/// component) of each displacement.
type X0Maps = (Vec<usize>, Vec<usize>, Vec<(usize, usize, usize)>);

fn x0_maps(sys: &BodySystem) -> X0Maps {
    let (mut u_idx, mut f_idx, mut on) = (Vec::new(), Vec::new(), Vec::new());
    for (i, u) in sys.unknowns[sys.n_x..].iter().enumerate() {
        match *u {
            Unknown::Displacement { on: Some(o), .. } => {
                u_idx.push(i);
                on.push(o);
            }
            Unknown::Traction0 { .. } => f_idx.push(i),
            _ => {}
        }
    }
    (u_idx, f_idx, on)
}

/// The Steklov–Poincaré operator of one body from its condensed operator.
fn body_op(sys: &BodySystem, d00: &Mat<f64>, z0: &[f64], name: &str) -> Result<BodyOp> {
    let (u_idx, f_idx, _) = x0_maps(sys);
    let (nu, nf) = (u_idx.len(), f_idx.len());
    let sub =
        |r: &[usize], c: &[usize]| Mat::<f64>::from_fn(r.len(), c.len(), |i, j| d00[(r[i], c[j])]);
    let dwf = sub(&f_idx, &f_idx);
    let dwu = sub(&f_idx, &u_idx);
    let dpu = sub(&u_idx, &u_idx);
    let (gu, gz) = if nf > 0 {
        let llt = dwf.llt(faer::Side::Lower).map_err(|_| {
            Error::numerical(format!(
                "body \"{name}\": the single-layer block of its interface tractions is not \
                 positive definite (degenerate scale or a badly graded interface mesh)"
            ))
        })?;
        let zw = Mat::<f64>::from_fn(nf, 1, |i, _| z0[f_idx[i]]);
        let gz = llt.solve(&zw);
        (
            llt.solve(&dwu),
            (0..nf).map(|i| gz[(i, 0)]).collect::<Vec<_>>(),
        )
    } else {
        (Mat::zeros(0, nu), Vec::new())
    };
    let prod = dwu.transpose() * &gu;
    let mut s = Mat::<f64>::from_fn(nu, nu, |i, j| -dpu[(i, j)] + prod[(i, j)]);
    for i in 0..nu {
        for j in 0..i {
            let m = 0.5 * (s[(i, j)] + s[(j, i)]);
            s[(i, j)] = m;
            s[(j, i)] = m;
        }
    }
    let p = (0..nu)
        .map(|i| z0[u_idx[i]] - (0..nf).map(|k| dwu[(k, i)] * gz[k]).sum::<f64>())
        .collect();
    Ok(BodyOp {
        u_idx,
        f_idx,
        s,
        p,
        gu,
        gz,
    })
}

/// Every body's operator and the numbering of the dofs (the bodies' U unknowns in order).
struct BodyOperators {
    ops: Vec<BodyOp>,
    dof_start: Vec<usize>,
    n_dofs: usize,
    /// Per body: node → [(global dof, direction)].
    node_dofs: Vec<NodeDofMap>,
}

/// Step 1 of [`Problem::new`]: the Steklov–Poincaré operator of every body and its dofs.
fn body_operators(model: &Model, prepared: &Operators) -> Result<BodyOperators> {
    let mut ops = Vec::with_capacity(model.bodies.len());
    let mut dof_start = Vec::with_capacity(model.bodies.len());
    let mut n_dofs = 0;
    let mut node_dofs: Vec<NodeDofMap> = Vec::new();
    for (b, sys) in prepared.systems.iter().enumerate() {
        let c = &prepared.condensed[b];
        let op = body_op(sys, &c.d00, &c.z0, &model.bodies[b].name)?;
        dof_start.push(n_dofs);
        let mut map = NodeDofMap::new();
        for (l, &i) in op.u_idx.iter().enumerate() {
            if let Unknown::Displacement { node, dir, .. } = sys.unknowns[sys.n_x + i] {
                map.entry(node).or_default().push((n_dofs + l, dir));
            }
        }
        node_dofs.push(map);
        n_dofs += op.u_idx.len();
        ops.push(op);
    }
    Ok(BodyOperators {
        ops,
        dof_start,
        n_dofs,
        node_dofs,
    })
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
fn candidates(model: &Model, node_dofs: &[NodeDofMap]) -> Result<Vec<Candidate>> {
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

/// The elimination class of a row: bonded (normal components first), then normal, then
/// tangential.
fn class(r: &Row) -> usize {
    match (r.kind, r.comp) {
        (RowKind::Bonded, 1) => 0,
        (RowKind::Bonded, _) => 1,
        (RowKind::Normal, _) => 2,
        (RowKind::Stick | RowKind::Friction, _) => 3,
    }
}

/// Step 3 of [`Problem::new`]: eliminates the closed rows in class order. Returns the
/// expression of every eliminated dof and which candidates are kept as rows.
fn eliminate(cands: &[Candidate], n_dofs: usize) -> (Vec<Option<Expr>>, Vec<bool>) {
    let mut order: Vec<usize> = (0..cands.len()).collect();
    order.sort_by_key(|&q| class(&cands[q].row));
    let mut expr: Vec<Option<Expr>> = vec![None; n_dofs];
    let mut refs: Vec<Vec<usize>> = vec![Vec::new(); n_dofs];
    let mut kept = vec![false; cands.len()];
    let mut normal_dropped = std::collections::HashSet::new();
    for &q in &order {
        let cand = &cands[q];
        let row = cand.row;
        if class(&row) == 3 && normal_dropped.contains(&(row.iface, row.pair)) {
            continue;
        }
        let Expr { m: am, r: ar } = reduce(cand, &expr);
        let scale = cand.coefs.iter().map(|c| c.1.abs()).fold(0.0, f64::max);
        let big = am.iter().map(|c| c.1.abs()).fold(0.0, f64::max);
        if big <= 1e-9 * scale {
            if row.kind == RowKind::Normal {
                normal_dropped.insert((row.iface, row.pair));
            }
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
        let mut new = Expr::default();
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
    (expr, kept)
}

/// A candidate's coefficients over the dofs still free (`m`) and the earlier rows'
/// openings (`r`), with the eliminated dofs replaced by their expressions.
fn reduce(cand: &Candidate, expr: &[Option<Expr>]) -> Expr {
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
    Expr { m: am, r: ar }
}

/// Eliminates dof `p` by its expression `new`: substitutes it in every expression that uses
/// it (`refs[m]`: the dofs whose expression uses free dof m).
fn substitute(expr: &mut [Option<Expr>], refs: &mut [Vec<usize>], p: usize, new: Expr) {
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
struct RowSet {
    rows: Vec<Row>,
    /// The row of each candidate (`usize::MAX` where it is implied).
    index_of: Vec<usize>,
    n_open_rows: usize,
    row_of: Vec<Vec<[Option<usize>; 2]>>,
    implied: Vec<Implied>,
    implied_at: std::collections::HashSet<(usize, usize, usize)>,
}

fn implied_of(row: &Row) -> Implied {
    Implied {
        iface: row.iface,
        pair: row.pair,
        comp: row.comp,
        kind: row.kind,
    }
}

/// Step 4 of [`Problem::new`]: the final rows, those kept, the rows that can open first (in
/// interface order), then the bonded ones; the others are implied.
fn final_rows(model: &Model, cands: &[Candidate], kept: &[bool]) -> RowSet {
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
                implied.push(implied_of(&cand.row));
            }
        }
    }
    for (q, cand) in cands.iter().enumerate() {
        if cand.row.kind == RowKind::Bonded && !kept[q] {
            implied.push(implied_of(&cand.row));
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
struct GluedMaps {
    tmap: Vec<Vec<(usize, f64)>>,
    offs: Vec<Vec<(usize, f64)>>,
    row_t: Vec<Vec<(usize, f64)>>,
    n_glued: usize,
}

/// Step 5 of [`Problem::new`]: the glued unknowns are the dofs left free, numbered in dof
/// order; every dof is expressed through them and the rows' openings.
fn glued_maps(expr: &[Option<Expr>], index_of: &[usize], n_rows: usize) -> GluedMaps {
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

/// Step 6 of [`Problem::new`]: the glued stiffness K_g = Σ_b T_bᵀ S_b T_b (lower triangle).
fn glued_matrix(
    ops: &[BodyOp],
    dof_start: &[usize],
    tmap: &[Vec<(usize, f64)>],
    n_glued: usize,
) -> Result<SparseColMat<usize, f64>> {
    let mut trip = Vec::new();
    for (b, op) in ops.iter().enumerate() {
        let n = op.u_idx.len();
        for i in 0..n {
            for &(gi, xi) in &tmap[dof_start[b] + i] {
                for j in 0..n {
                    for &(gj, xj) in &tmap[dof_start[b] + j] {
                        if gj >= gi {
                            trip.push(Triplet::new(gj, gi, xi * xj * op.s[(i, j)]));
                        }
                    }
                }
            }
        }
    }
    SparseColMat::<usize, f64>::try_new_from_triplets(n_glued, n_glued, &trip)
        .map_err(|e| Error::numerical(format!("assembling the interface system: {e:?}")))
}

impl Problem {
    /// Builds the problem from the prepared bodies and factorises the glued base.
    ///
    /// **Rows and junctions.** Every pair component with a displacement unknown on both
    /// sides is a candidate row `[u]_r = e_r·(u_B − u_A)` over the dofs of the two nodes
    /// (at a junction node, whose unknowns are in the frame of its first pair, projected onto
    /// the pair's direction e_r). The closed rows are eliminated one by one: each expresses
    /// one still-free dof (B's, or the largest coefficient) through the others and its
    /// opening. Where three or more bodies meet, the pairs around the point form a cycle
    /// and their rows are linearly dependent (at a T-junction, bed joint A–B, bed joint A–C
    /// and head joint B–C: the vertical relative displacements satisfy
    /// `[u]_AB − [u]_AC + [u]_BC = 0`): a row whose coefficients vanish after elimination
    /// is *implied* by the rows kept before it while they are closed, and gets no row of its
    /// own. Rows are taken bonded first (normal components before tangential ones), then
    /// normal, then tangential, so that a cycle is cut at a tangential component of a head
    /// joint rather than at a normal one, and a component that bonded rows imply stays
    /// implied (bonded rows never open); a tangential row whose pair lost its normal row goes
    /// too. The kept rows are
    /// independent, so their forces (Lagrange multipliers) are unique and the opening
    /// stiffness A stays symmetric positive (semi)definite: the LCP of the module doc
    /// holds unchanged. The nodal force of the junction node is carried by the kept rows;
    /// implied components report zero force (each body's balance stays exact).
    pub fn new(model: &Model, prepared: &Operators) -> Result<Problem> {
        let bodies = body_operators(model, prepared)?;
        let cands = candidates(model, &bodies.node_dofs)?;
        let (expr, kept) = eliminate(&cands, bodies.n_dofs);
        let set = final_rows(model, &cands, &kept);
        let glued = glued_maps(&expr, &set.index_of, set.rows.len());
        let BodyOperators {
            ops,
            dof_start,
            n_dofs,
            ..
        } = bodies;
        let kg = glued_matrix(&ops, &dof_start, &glued.tmap, glued.n_glued)?;
        let factor = kg.sp_cholesky(faer::Side::Lower).map_err(|_| {
            Error::numerical(format!(
                "the interface system with every pair closed is singular: {}",
                mechanism_hint(model, &ops, &set.rows, &dof_start)
            ))
        })?;
        let problem = Problem {
            ops,
            dof_start,
            n_dofs,
            rows: set.rows,
            n_open_rows: set.n_open_rows,
            row_of: set.row_of,
            tmap: glued.tmap,
            offs: glued.offs,
            row_t: glued.row_t,
            implied: set.implied,
            implied_at: set.implied_at,
            n_glued: glued.n_glued,
            factor,
        };
        problem.check_base(&kg, model)?;
        Ok(problem)
    }

    /// A Cholesky factor can succeed on a matrix that is singular up to roundoff: the
    /// residual of one solve with a rough right-hand side tells.
    fn check_base(&self, kg: &SparseColMat<usize, f64>, model: &Model) -> Result<()> {
        let n = self.n_glued;
        if n == 0 {
            return Ok(());
        }
        let b = Mat::<f64>::from_fn(n, 1, |i, _| 1.0 + (i % 7) as f64);
        let x = self.factor.solve(&b);
        // K x with the full symmetric matrix from its lower triangle.
        let mut kx = vec![0.0; n];
        let sym = kg.symbolic();
        let (cp, ri) = (sym.col_ptr(), sym.row_idx());
        let vals = kg.val();
        for c in 0..n {
            for p in cp[c]..cp[c + 1] {
                let r = ri[p];
                kx[r] += vals[p] * x[(c, 0)];
                if r != c {
                    kx[c] += vals[p] * x[(r, 0)];
                }
            }
        }
        let res = (0..n)
            .map(|i| (kx[i] - b[(i, 0)]).abs())
            .fold(0.0, f64::max)
            / 7.0;
        if res.is_finite() && (1e-6..1e-2).contains(&res) {
            return Err(Error::numerical(format!(
                "the interface system with every pair closed is ill-conditioned (relative \
                 residual {res:.1e} after solving)"
            )));
        }
        if res.is_nan() || res >= 1e-6 {
            return Err(Error::numerical(format!(
                "the interface system with every pair closed is singular (relative residual \
                 {res:.1e}): {}",
                mechanism_hint(model, &self.ops, &self.rows, &self.dof_start)
            )));
        }
        Ok(())
    }

    /// Number of glued unknowns (the size of the sparse base system).
    pub fn base_size(&self) -> usize {
        self.n_glued
    }

    fn body_of(&self, dof: usize) -> (usize, usize) {
        let b = self.dof_start.partition_point(|&s| s <= dof) - 1;
        (b, dof - self.dof_start[b])
    }

    /// Body displacements for glued displacements `v`, openings `s` (over rows that can
    /// open, zero where closed) and the closed initial gaps.
    fn displacements(&self, v: &[f64], s: &[f64]) -> Vec<Vec<f64>> {
        self.ops
            .iter()
            .enumerate()
            .map(|(b, op)| {
                (0..op.u_idx.len())
                    .map(|l| {
                        let d = self.dof_start[b] + l;
                        let mut u: f64 = self.tmap[d].iter().map(|&(g, x)| x * v[g]).sum();
                        for &(r, x) in &self.offs[d] {
                            // The row's relative displacement is s − h: the gap h closed
                            // when s = 0.
                            let open = if r < self.n_open_rows { s[r] } else { 0.0 };
                            u += x * (open - self.rows[r].gap);
                        }
                        u
                    })
                    .collect()
            })
            .collect()
    }

    /// The number of glued unknowns v.
    pub(crate) fn n_glued(&self) -> usize {
        self.n_glued
    }

    /// The unknowns w = (v, s) that dof `d` moves (`U_d = Σ x·w_k` plus the closed gaps): the
    /// glued unknowns, then the openings of the rows that can open at `n_glued + r`.
    pub(crate) fn dof_unknowns(&self, d: usize) -> Vec<(usize, f64)> {
        let mut out = self.tmap[d].clone();
        for &(r, x) in &self.offs[d] {
            if r < self.n_open_rows {
                out.push((self.n_glued + r, x));
            }
        }
        out
    }

    /// The gradient over w = (v, s) of the bodies' energy at w = 0 (every gap closed) for a
    /// load factor, with the cohesion terms of the rows (`Base::cohesion`) added to the rows'
    /// part: the row forces are `λ = H w + c` on the rows' part.
    pub(crate) fn linear_term(&self, factor: f64, cohesion: &[f64]) -> Vec<f64> {
        let u0 = self.displacements(&vec![0.0; self.n_glued], &vec![0.0; self.n_open_rows]);
        let p0 = self.forces(&u0, factor);
        let mut c = self.gather(&p0);
        c.extend((0..self.n_open_rows).map(|r| self.row_force(&p0, r) + cohesion[r]));
        c
    }

    /// The force of row r from the nodal forces `p` of every body: `λ_r = t_rᵀ P`.
    fn row_force(&self, p: &[Vec<f64>], r: usize) -> f64 {
        self.row_t[r]
            .iter()
            .map(|&(d, x)| {
                let (b, l) = self.body_of(d);
                x * p[b][l]
            })
            .sum()
    }

    /// `Tᵀ f` for per-body vectors `f` over the dofs: the glued load.
    fn gather(&self, f: &[Vec<f64>]) -> Vec<f64> {
        let mut out = vec![0.0; self.n_glued];
        for (b, fb) in f.iter().enumerate() {
            for (i, v) in fb.iter().enumerate() {
                for &(g, x) in &self.tmap[self.dof_start[b] + i] {
                    out[g] += x * v;
                }
            }
        }
        out
    }

    /// Right-hand side of the glued system: Tᵀ(S U_fixed + factor p̂), where U_fixed holds
    /// the parts of U that are not glued unknowns (gap offsets, openings).
    fn glued_load(&self, factor: f64, s: &[f64]) -> Vec<f64> {
        let zero = vec![0.0; self.n_glued];
        let u = self.displacements(&zero, s);
        let f: Vec<Vec<f64>> = self
            .ops
            .iter()
            .zip(&u)
            .map(|(op, ub)| {
                matvec(&op.s, ub)
                    .iter()
                    .zip(&op.p)
                    .map(|(v, p)| factor * p + v)
                    .collect()
            })
            .collect();
        self.gather(&f)
    }

    fn solve_glued(&self, rhs: &[f64]) -> Vec<f64> {
        let n = self.n_glued;
        let b = Mat::<f64>::from_fn(n, 1, |i, _| -rhs[i]);
        let x = self.factor.solve(&b);
        (0..n).map(|i| x[(i, 0)]).collect()
    }

    /// Nodal forces P = S U + factor·p̂ of each body.
    fn forces(&self, u: &[Vec<f64>], factor: f64) -> Vec<Vec<f64>> {
        self.ops
            .iter()
            .zip(u)
            .map(|(op, ub)| {
                matvec(&op.s, ub)
                    .iter()
                    .zip(&op.p)
                    .map(|(v, p)| v + factor * p)
                    .collect()
            })
            .collect()
    }

    /// The all-closed state for a load factor, the cohesion left at each pair and the
    /// accumulated slip `offset` of friction rows (zero elsewhere; empty for none).
    pub fn base(&self, factor: f64, cohesion: &[Vec<f64>], offset: &[f64]) -> Base {
        let s = if offset.is_empty() {
            vec![0.0; self.n_open_rows]
        } else {
            offset.to_vec()
        };
        let v0 = self.solve_glued(&self.glued_load(factor, &s));
        let u = self.displacements(&v0, &s);
        let p = self.forces(&u, factor);
        let coh: Vec<f64> = self.rows[..self.n_open_rows]
            .iter()
            .map(|r| match r.kind {
                RowKind::Normal => cohesion[r.iface][r.pair] * r.weight,
                _ => 0.0,
            })
            .collect();
        let lambda0 = (0..self.n_open_rows)
            .map(|r| self.row_force(&p, r) + coh[r])
            .collect();
        Base {
            factor,
            v0,
            lambda0,
            offset: s,
            cohesion: coh,
        }
    }

    /// Column j of the opening stiffness A over the rows that can open: the change of
    /// every row force per unit opening of row j (one sparse solve and a product with the
    /// operator of each body that is the second side of a row).
    pub fn column(&self, j: usize) -> Vec<f64> {
        // t_j = ∂U/∂s_j over the dofs it moves, per body.
        let mut tj: Vec<Vec<(usize, f64)>> = vec![Vec::new(); self.ops.len()];
        for &(d, x) in &self.row_t[j] {
            let (b, l) = self.body_of(d);
            tj[b].push((l, x));
        }
        // Tᵀ S t_j: the glued load of a unit opening.
        let f: Vec<Vec<f64>> = self
            .ops
            .iter()
            .enumerate()
            .map(|(b, op)| {
                if tj[b].is_empty() {
                    return Vec::new();
                }
                (0..op.u_idx.len())
                    .map(|i| tj[b].iter().map(|&(l, x)| op.s[(i, l)] * x).sum())
                    .collect()
            })
            .collect();
        let y = self.solve_glued(&self.gather(&f)); // = ∂v/∂s_j
        let mut need = vec![false; self.ops.len()];
        for r in 0..self.n_open_rows {
            for &(d, _) in &self.row_t[r] {
                need[self.body_of(d).0] = true;
            }
        }
        let t: Vec<Vec<f64>> = self
            .ops
            .iter()
            .enumerate()
            .map(|(b, op)| {
                if !need[b] {
                    return Vec::new();
                }
                let n = op.u_idx.len();
                let mut du: Vec<f64> = (0..n)
                    .map(|l| {
                        self.tmap[self.dof_start[b] + l]
                            .iter()
                            .map(|&(g, x)| x * y[g])
                            .sum()
                    })
                    .collect();
                for &(l, x) in &tj[b] {
                    du[l] += x;
                }
                matvec(&op.s, &du)
            })
            .collect();
        (0..self.n_open_rows)
            .map(|r| self.row_force(&t, r))
            .collect()
    }

    /// The boundary solution of every body and the interface results for openings `s`
    /// (over the rows that can open; zero on closed rows) and the row statuses `open`.
    pub fn state(
        &self,
        model: &Model,
        prepared: &Operators,
        factor: f64,
        s: &[f64],
        open: &[bool],
    ) -> (Vec<BodyField>, Vec<InterfaceResult>, Vec<Vec<f64>>) {
        let v = self.solve_glued(&self.glued_load(factor, s));
        let u = self.displacements(&v, s);
        let mut fields = Vec::with_capacity(self.ops.len());
        let mut tractions = Vec::with_capacity(self.ops.len());
        for (b, op) in self.ops.iter().enumerate() {
            let sys = &prepared.systems[b];
            let mut x0 = vec![0.0; sys.n_x0()];
            for (l, &i) in op.u_idx.iter().enumerate() {
                x0[i] = -u[b][l];
            }
            let gu = matvec(&op.gu, &u[b]);
            for (m, &i) in op.f_idx.iter().enumerate() {
                x0[i] = -factor * op.gz[m] + gu[m];
            }
            let x = prepared.condensed[b].recover_x_scaled(&x0, factor);
            fields.push(recover(model, b, sys, &x, &x0, factor));
            tractions.push(x0);
        }
        let p = self.forces(&u, factor);
        let mut nodal = Vec::with_capacity(model.interfaces.len());
        let interfaces = model
            .interfaces
            .iter()
            .enumerate()
            .map(|(k, it)| {
                let mut nk = Vec::with_capacity(it.pairs.len());
                let pairs = it
                    .pairs
                    .iter()
                    .enumerate()
                    .map(|(j, pr)| {
                        // The traction on A of the discrete problem: the nodal force of the
                        // row over the pair's tributary length (∫ψ_j t = t w_j for a uniform
                        // traction; zero exactly where a row is open or frictionless); the
                        // body's own traction hat where no row exists (prescribed both sides).
                        let mut traction = [0.0; 2];
                        for (c, t) in traction.iter_mut().enumerate() {
                            match self.row_of[k][j][c] {
                                // An open row carries no force (exactly: it is the
                                // stationarity condition of its opening), except a slipping
                                // friction row, which carries its slip bound.
                                Some(r)
                                    if r < self.n_open_rows
                                        && open[r]
                                        && self.rows[r].kind != RowKind::Friction => {}
                                Some(r) => {
                                    *t = -self.row_force(&p, r) / self.rows[r].weight;
                                }
                                // Implied at a junction: the kept rows carry its force.
                                None if self.implied_at.contains(&(k, j, c)) => {}
                                None => {
                                    // Frictionless tangential component: no row, no force.
                                    let slide = c == 0
                                        && it.spec.model == InterfaceModel::Unilateral
                                        && it.spec.tangential == Tangential::Slide;
                                    if !slide {
                                        if let Some(i) = prepared.maps[it.body_a].get(k, j, c, true)
                                        {
                                            *t = tractions[it.body_a][i];
                                        }
                                    }
                                }
                            }
                        }
                        let ua = fields[it.body_a].u[pr.node_a];
                        let ub = if !it.independent() {
                            fields[it.body_b].u[pr.node_b]
                        } else if pr.partners.is_empty() {
                            ua
                        } else {
                            pr.partners.iter().fold([0.0, 0.0], |acc, &(n, c)| {
                                let u = fields[it.body_b].u[n];
                                [acc[0] + c * u[0], acc[1] + c * u[1]]
                            })
                        };
                        let d = [ub[0] - ua[0], ub[1] - ua[1]];
                        let jump = [
                            d[0] * pr.tangent[0] + d[1] * pr.tangent[1],
                            d[0] * pr.normal[0] + d[1] * pr.normal[1],
                        ];
                        let closed = match self.row_of[k][j][1] {
                            Some(r) if r < self.n_open_rows => !open[r],
                            // Implied at a junction: closed where the kept rows close it.
                            None if self.implied_at.contains(&(k, j, 1)) => {
                                pr.gap + jump[1] <= 1e-9 * model.scale
                            }
                            // Nothing of B faces the node: no row, open.
                            None if it.independent() && pr.partners.is_empty() => false,
                            _ => true,
                        };
                        // Nodal normal force on B (compression positive).
                        nk.push(match self.row_of[k][j][1] {
                            Some(r) => self.row_force(&p, r),
                            None => 0.0,
                        });
                        // A friction pair slips where its tangential row is open.
                        let slipping = match self.row_of[k][j][0] {
                            Some(r)
                                if r < self.n_open_rows
                                    && self.rows[r].kind == RowKind::Friction =>
                            {
                                Some(open[r])
                            }
                            _ => None,
                        };
                        PairResult {
                            status: if closed {
                                PairStatus::Closed
                            } else {
                                PairStatus::Open
                            },
                            traction,
                            jump,
                            slipping,
                            slip: 0.0,
                        }
                    })
                    .collect();
                nodal.push(nk);
                InterfaceResult { pairs }
            })
            .collect();
        (fields, interfaces, nodal)
    }
}

/// Names the bodies that nothing but interfaces holds and the rigid motion that the closed
/// rows leave free (translation along a direction, or rotation).
pub fn mechanism_hint(model: &Model, ops: &[BodyOp], rows: &[Row], dof_start: &[usize]) -> String {
    let mut out = Vec::new();
    for (b, body) in model.bodies.iter().enumerate() {
        // Gram matrix of the rigid modes (x, y translation, rotation about the centroid)
        // seen by the rows touching body b.
        let n = ops[b].u_idx.len();
        let (lo, hi) = (dof_start[b], dof_start[b] + n);
        let nodes = &body.nodes;
        let c = {
            let m = nodes.len().max(1) as f64;
            let (sx, sy) = nodes
                .iter()
                .fold((0.0, 0.0), |a, p| (a.0 + p[0], a.1 + p[1]));
            [sx / m, sy / m]
        };
        let scale = model.scale.max(f64::MIN_POSITIVE);
        let mut g = [[0.0f64; 3]; 3];
        let mut touched = false;
        for r in rows {
            if !(lo..hi).contains(&r.dof_a) && !(lo..hi).contains(&r.dof_b) {
                continue;
            }
            touched = true;
            let it = &model.interfaces[r.iface];
            let pr = &it.pairs[r.pair];
            let dir = if r.comp == 1 { pr.normal } else { pr.tangent };
            let m = [
                dir[0],
                dir[1],
                (-(pr.x[1] - c[1]) * dir[0] + (pr.x[0] - c[0]) * dir[1]) / scale,
            ];
            for i in 0..3 {
                for j in 0..3 {
                    g[i][j] += m[i] * m[j];
                }
            }
        }
        let held_elsewhere = body_has_support(model, b);
        if held_elsewhere || (!touched && n == 0) {
            continue;
        }
        // Smallest eigenvector of the 3×3 Gram matrix by a few inverse-free sweeps (Jacobi).
        let (val, vec) = smallest_eigen(g);
        let tr = g[0][0] + g[1][1] + g[2][2];
        if val <= 1e-10 * tr.max(f64::MIN_POSITIVE) || !touched {
            let motion = if vec[2].abs() > 0.9 {
                "a rotation".to_string()
            } else {
                let l = vec[0].hypot(vec[1]).max(f64::MIN_POSITIVE);
                format!("a translation along ({:.3}, {:.3})", vec[0] / l, vec[1] / l)
            };
            out.push(format!("body \"{}\" is free to move ({motion})", body.name));
        }
    }
    if out.is_empty() {
        "a body or group of bodies is held by interfaces alone and can move freely: hold it \
         with a displacement condition, or use tangential = \"stick\" where it can slide"
            .into()
    } else {
        format!(
            "{}: with every pair closed the interfaces do not hold it (frictionless pairs on a \
             straight interface leave sliding free); hold it with a displacement condition \
             (e.g. a symmetry plane or ux = 0 on a point-like boundary), or use tangential = \
             \"stick\"",
            out.join("; ")
        )
    }
}

fn body_has_support(model: &Model, b: usize) -> bool {
    model.bodies[b].dof_counts()[0] > 0
}

fn smallest_eigen(mut a: [[f64; 3]; 3]) -> (f64, [f64; 3]) {
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..50 {
        let mut off = 0.0;
        for p in 0..3 {
            for q in (p + 1)..3 {
                off += a[p][q].abs();
                if a[p][q].abs() < 1e-300 {
                    continue;
                }
                let theta = 0.5 * (a[q][q] - a[p][p]) / a[p][q];
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let cs = 1.0 / (t * t + 1.0).sqrt();
                let sn = t * cs;
                for k in 0..3 {
                    let (akp, akq) = (a[k][p], a[k][q]);
                    a[k][p] = cs * akp - sn * akq;
                    a[k][q] = sn * akp + cs * akq;
                }
                for k in 0..3 {
                    let (apk, aqk) = (a[p][k], a[q][k]);
                    a[p][k] = cs * apk - sn * aqk;
                    a[q][k] = sn * apk + cs * aqk;
                }
                for k in 0..3 {
                    let (vkp, vkq) = (v[k][p], v[k][q]);
                    v[k][p] = cs * vkp - sn * vkq;
                    v[k][q] = sn * vkp + cs * vkq;
                }
            }
        }
        if off < 1e-14 {
            break;
        }
    }
    let i = (0..3)
        .min_by(|&x, &y| a[x][x].total_cmp(&a[y][y]))
        .unwrap_or(0);
    (a[i][i], [v[0][i], v[1][i], v[2][i]])
}

/// Relative pivot below which A_OO counts as singular. A rigid motion left free shows as a
/// pivot of 1e-15 to 1e-9 (roundoff of the boundary operators, larger along a chain of
/// bodies: a pier of 8 blocks past overturning gave 1.2e-9); genuine pivots of the opening
/// stiffness are above 1e-6 on every shipped pipeline and test scene.
const SINGULAR_PIVOT: f64 = 1e-7;

/// The Cholesky factor of A_OO for an open set O, updated one row at a time.
///
/// Rows are kept in insertion order; `append` adds a row and column (O(m²)), `remove`
/// deletes one with a rank-one update of the trailing factor (O(m²)). A pivot below
/// `SINGULAR_PIVOT` of the column's diagonal means A_OO is singular: opening that row would leave a
/// body free (a mechanism), and the row is refused.
#[derive(Debug, Clone, Default)]
pub struct Opening {
    /// Row indices of O in factor order.
    pub rows: Vec<usize>,
    /// Lower-triangular factor, row-major rows of growing length.
    l: Vec<Vec<f64>>,
}

impl Opening {
    pub fn len(&self) -> usize {
        self.rows.len()
    }
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// Appends row `r` whose column of A is `col` (over all rows that can open). Returns
    /// false (and changes nothing) if A_OO would become singular.
    pub fn append(&mut self, r: usize, col: &[f64]) -> bool {
        let m = self.rows.len();
        let a: Vec<f64> = self.rows.iter().map(|&q| col[q]).collect();
        // Solve L x = a.
        let mut x = vec![0.0; m];
        for i in 0..m {
            let mut acc = a[i];
            for k in 0..i {
                acc -= self.l[i][k] * x[k];
            }
            x[i] = acc / self.l[i][i];
        }
        let d2 = col[r] - x.iter().map(|v| v * v).sum::<f64>();
        if d2.is_nan() || d2 <= SINGULAR_PIVOT * col[r].abs() {
            return false;
        }
        x.push(d2.sqrt());
        self.l.push(x);
        self.rows.push(r);
        true
    }

    /// Removes row `r` from O.
    pub fn remove(&mut self, r: usize) {
        let Some(k) = self.rows.iter().position(|&q| q == r) else {
            return;
        };
        // The column below the removed diagonal updates the trailing factor:
        // L33' L33'ᵀ = L33 L33ᵀ + l32 l32ᵀ.
        let mut w: Vec<f64> = (k + 1..self.rows.len()).map(|i| self.l[i][k]).collect();
        self.rows.remove(k);
        self.l.remove(k);
        for row in self.l.iter_mut().skip(k) {
            row.remove(k);
        }
        let m = self.rows.len();
        for (t, i) in (k..m).enumerate() {
            let lii = self.l[i][i];
            let wi = w[t];
            let rr = lii.hypot(wi);
            let (c, s) = (rr / lii, wi / lii);
            self.l[i][i] = rr;
            for (t2, j) in (i + 1..m).enumerate() {
                let idx = t + 1 + t2;
                self.l[j][i] = (self.l[j][i] + s * w[idx]) / c;
                w[idx] = c * w[idx] - s * self.l[j][i];
            }
        }
    }

    /// Solves A_OO s = rhs (rhs in factor order).
    pub fn solve(&self, rhs: &[f64]) -> Vec<f64> {
        let m = self.rows.len();
        let mut y = vec![0.0; m];
        for i in 0..m {
            let mut acc = rhs[i];
            for k in 0..i {
                acc -= self.l[i][k] * y[k];
            }
            y[i] = acc / self.l[i][i];
        }
        // Lᵀ x = y by columns of Lᵀ, i.e. the stored rows of L (contiguous).
        for k in (0..m).rev() {
            y[k] /= self.l[k][k];
            let yk = y[k];
            let row = &self.l[k];
            for i in 0..k {
                y[i] -= row[i] * yk;
            }
        }
        y
    }
}

/// The solution with every interface pair closed.
pub struct StatusSolution {
    pub fields: Vec<BodyField>,
    pub interfaces: Vec<InterfaceResult>,
}

/// Solves the model with every interface pair closed (bonded interfaces, and unilateral ones
/// held closed) through the contact problem's glued system, for the loads of `bem::prepare`.
pub fn solve_all_closed(model: &Model, ops: &Operators) -> Result<StatusSolution> {
    let problem = Problem::new(model, ops)?;
    let n = problem.n_open_rows;
    let (fields, interfaces, _) = problem.state(model, ops, 1.0, &vec![0.0; n], &vec![false; n]);
    Ok(StatusSolution { fields, interfaces })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn opening_factor_follows_appends_and_removals() {
        // A = B Bᵀ + I over 6 rows; compare with a fresh factor after each change.
        let n = 6;
        let b: Vec<f64> = (0..n * n)
            .map(|i| ((i * 37 % 11) as f64) / 7.0 - 0.6)
            .collect();
        let a = |i: usize, j: usize| -> f64 {
            (0..n).map(|k| b[i * n + k] * b[j * n + k]).sum::<f64>()
                + if i == j { 1.0 } else { 0.0 }
        };
        let col = |j: usize| (0..n).map(|i| a(i, j)).collect::<Vec<_>>();
        let mut o = Opening::default();
        for r in [3, 0, 5, 1, 4] {
            assert!(o.append(r, &col(r)));
        }
        o.remove(0);
        o.remove(4);
        assert!(o.append(2, &col(2)));
        // Check A_OO s = rhs.
        let rhs: Vec<f64> = (0..o.len()).map(|i| i as f64 - 1.5).collect();
        let s = o.solve(&rhs);
        for (i, &ri) in o.rows.iter().enumerate() {
            let lhs: f64 = o.rows.iter().zip(&s).map(|(&rj, sj)| a(ri, rj) * sj).sum();
            assert!(
                (lhs - rhs[i]).abs() < 1e-12,
                "row {ri}: {lhs} vs {}",
                rhs[i]
            );
        }
    }

    #[test]
    fn singular_opening_is_refused() {
        // A = v vᵀ (rank one): the second row cannot be appended.
        let v = [1.0, 2.0];
        let col = |j: usize| vec![v[0] * v[j], v[1] * v[j]];
        let mut o = Opening::default();
        assert!(o.append(0, &col(0)));
        assert!(!o.append(1, &col(1)));
        assert_eq!(o.rows, vec![0]);
    }
}
