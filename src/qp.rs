//! Contact and detachment as one convex quadratic programme ([paper §3.2, eq. 32b]), solved
//! with Clarabel. The only module that touches Clarabel.
//!
//! Place in the flow: `solve` (per-body operators) → **`qp`** → results. Every unilateral
//! pair is put in the closed (real) state — with its initial gap built in, so that "closed"
//! means the gap has closed — and every displacement unknown of the interface system
//! `K Y + L = 0` is eliminated:
//!
//! ```text
//!   K̃ = K_FF − K_FU K_UU⁻¹ K_UF,   L̃ = L_F − K_FU K_UU⁻¹ L_U      (K̃ SPD: flexibility)
//!   min ½ Fᵀ K̃ F + Fᵀ L̃   subject to   F_n,j ≤ c_j on every unilateral pair
//! ```
//!
//! The multiplier of an active constraint is the weighted normal opening of that pair, so the
//! pairs whose constraint is active are the detached ones (formulation §6.2–§6.3). This force
//! form covers detachment (zones that start closed) and contact (zones that start open with a
//! gap) alike: an open zone is one whose contact force would be tensile.
//!
//! With `tangential = "stick"` the tangential force of every pair stays a free variable, so a
//! detached pair remains tangentially bonded in the QP: this is the paper's QPP and the reason
//! its detached lengths differ slightly from the iterative LCP (formulation §5.4). The QP's
//! zones are then re-analysed with the mixed system ("a classical analysis on two bodies
//! whose contact zone is known", [paper §3.2]) and, for comparison, polished by the active-set
//! iteration. Lengths are scaled to O(1) by Jacobi scaling of K̃ before Clarabel sees it.

// Index loops mirror the block formulas.
#![allow(clippy::needless_range_loop)]
use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus,
};
use faer::linalg::solvers::Solve;
use faer::Mat;

use crate::contact::Status;
use crate::error::{Error, Result};
use crate::interface;
use crate::model::Model;
use crate::scene::{InterfaceModel, Tangential};
use crate::solution::PairStatus;
use crate::solve::Prepared;

/// What the QP found.
pub struct QpResult {
    /// Statuses from the active constraints.
    pub status: Status,
    /// Clarabel's iterations and status.
    pub iterations: u32,
    pub solver_status: String,
    pub objective: f64,
    /// Number of variables and constraints.
    pub variables: usize,
    pub constraints: usize,
}

/// The all-closed status of the QP (tangential components open with "slide").
pub fn qp_status(model: &Model) -> Status {
    model
        .interfaces
        .iter()
        .map(|it| {
            let t = match (it.spec.model, it.spec.tangential) {
                (InterfaceModel::Unilateral, Tangential::Slide) => PairStatus::Open,
                _ => PairStatus::Closed,
            };
            vec![[t, PairStatus::Closed]; it.pairs.len()]
        })
        .collect()
}

/// Solves the force QP for the loads times `factor` and cohesions `cohesion[k][j]`.
pub fn solve_qp(
    model: &Model,
    prepared: &Prepared,
    factor: f64,
    cohesion: &[Vec<f64>],
    tolerance: f64,
) -> Result<QpResult> {
    let status = qp_status(model);
    let layout = interface::layout(model, &prepared.maps, &status)?;
    let (k, l) = interface::assemble_scaled(&layout, &prepared.condensed, factor);
    // Partition Y into forces F and displacements U.
    let mut is_f = vec![false; layout.n];
    for iface in &layout.slots {
        for pair in iface {
            for slot in pair {
                if let Some(i) = slot.f {
                    is_f[i] = true;
                }
            }
        }
    }
    let fi: Vec<usize> = (0..layout.n).filter(|&i| is_f[i]).collect();
    let ui: Vec<usize> = (0..layout.n).filter(|&i| !is_f[i]).collect();
    let (nf, nu) = (fi.len(), ui.len());
    let sub = |rows: &[usize], cols: &[usize]| {
        Mat::<f64>::from_fn(rows.len(), cols.len(), |i, j| k[(rows[i], cols[j])])
    };
    let kff = sub(&fi, &fi);
    let kfu = sub(&fi, &ui);
    let kuu = sub(&ui, &ui);
    // [K_UU⁻¹ K_UF | K_UU⁻¹ L_U]
    let rhs = Mat::<f64>::from_fn(nu, nf + 1, |i, j| {
        if j < nf {
            k[(ui[i], fi[j])]
        } else {
            l[ui[i]]
        }
    });
    let sol = if nu > 0 {
        kuu.partial_piv_lu().solve(&rhs)
    } else {
        Mat::<f64>::zeros(0, nf + 1)
    };
    let prod = &kfu * &sol;
    let mut kt = Mat::<f64>::from_fn(nf, nf, |i, j| kff[(i, j)] - prod[(i, j)]);
    for i in 0..nf {
        for j in 0..i {
            let m = 0.5 * (kt[(i, j)] + kt[(j, i)]);
            kt[(i, j)] = m;
            kt[(j, i)] = m;
        }
    }
    let lt: Vec<f64> = (0..nf).map(|i| l[fi[i]] - prod[(i, nf)]).collect();

    // Constraints F_n ≤ c on unilateral pairs.
    let mut rows: Vec<(usize, f64, usize, usize)> = Vec::new(); // (var, c, k, j)
    for (kk, it) in model.interfaces.iter().enumerate() {
        if it.spec.model != InterfaceModel::Unilateral {
            continue;
        }
        for j in 0..it.pairs.len() {
            if let Some(y) = layout.slots[kk][j][1].f {
                if let Some(v) = fi.iter().position(|&q| q == y) {
                    rows.push((v, cohesion[kk][j], kk, j));
                }
            }
        }
    }
    // Jacobi scaling: F = D x.
    let d: Vec<f64> = (0..nf)
        .map(|i| {
            let v = kt[(i, i)];
            if v > 0.0 {
                1.0 / v.sqrt()
            } else {
                1.0
            }
        })
        .collect();
    if (0..nf).any(|i| kt[(i, i)] <= 0.0) {
        return Err(Error::numerical(
            "the interface flexibility of the QP is not positive definite (a body may be free \
             to move along an interface)",
        ));
    }
    let qscale = lt
        .iter()
        .zip(&d)
        .map(|(v, di)| (v * di).abs())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    // P upper triangle in CSC, q, A (one row per constraint), b.
    let mut colptr = vec![0usize];
    let mut rowval = Vec::new();
    let mut nzval = Vec::new();
    for j in 0..nf {
        for i in 0..=j {
            let v = d[i] * kt[(i, j)] * d[j];
            if v != 0.0 {
                rowval.push(i);
                nzval.push(v);
            }
        }
        colptr.push(rowval.len());
    }
    let p = CscMatrix::new(nf, nf, colptr, rowval, nzval);
    let q: Vec<f64> = (0..nf).map(|i| d[i] * lt[i] / qscale).collect();
    let m = rows.len();
    let mut acol: Vec<Vec<(usize, f64)>> = vec![Vec::new(); nf];
    let mut b = Vec::with_capacity(m);
    for (r, &(v, c, _, _)) in rows.iter().enumerate() {
        acol[v].push((r, 1.0));
        b.push(c / d[v] / qscale);
    }
    let mut colptr = vec![0usize];
    let mut rowval = Vec::new();
    let mut nzval = Vec::new();
    for col in &acol {
        for &(r, v) in col {
            rowval.push(r);
            nzval.push(v);
        }
        colptr.push(rowval.len());
    }
    let a = CscMatrix::new(m, nf, colptr, rowval, nzval);
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .tol_gap_abs(tolerance.max(1e-12))
        .tol_gap_rel(tolerance.max(1e-12))
        .tol_feas(tolerance.max(1e-12))
        .max_iter(500)
        .build()
        .map_err(|e| Error::numerical(format!("QP settings rejected: {e:?}")))?;
    let cones = [NonnegativeConeT(m)];
    let mut solver = DefaultSolver::new(&p, &q, &a, &b, &cones, settings)
        .map_err(|e| Error::numerical(format!("the QP could not be set up: {e:?}")))?;
    solver.solve();
    let st = solver.solution.status;
    if !matches!(st, SolverStatus::Solved | SolverStatus::AlmostSolved) {
        return Err(Error::numerical(format!(
            "the contact QP did not solve: Clarabel status {st:?}"
        )));
    }
    let z = &solver.solution.z;
    let s = &solver.solution.s;
    let zmax = z.iter().copied().fold(0.0, f64::max).max(f64::MIN_POSITIVE);
    let xmax = solver
        .solution
        .x
        .iter()
        .map(|v| v.abs())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    // Active constraint with a positive multiplier: detached (open).
    let mut out = status.clone();
    for (r, &(_, _, kk, j)) in rows.iter().enumerate() {
        let active = s[r] <= 1e-6 * xmax && z[r] > 1e-6 * zmax;
        if active {
            out[kk][j] = [PairStatus::Open, PairStatus::Open];
        } else {
            let t = match model.interfaces[kk].spec.tangential {
                Tangential::Slide => PairStatus::Open,
                Tangential::Stick => PairStatus::Closed,
            };
            out[kk][j] = [t, PairStatus::Closed];
        }
    }
    Ok(QpResult {
        status: out,
        iterations: solver.info.iterations,
        solver_status: format!("{st:?}"),
        objective: solver.solution.obj_val * qscale * qscale,
        variables: nf,
        constraints: m,
    })
}
