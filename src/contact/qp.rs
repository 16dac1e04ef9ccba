//! The contact problem as one convex quadratic programme, solved with Clarabel (with
//! `statics`, the rigid-block LP, the only modules that touch Clarabel; [paper §3.2],
//! docs/formulation.md §6.3).
//!
//! Place in the flow: `lcp` (the inner problem) → **`qp`** → `contact`. The inner LCP of
//! `problem` is the optimality system of
//!
//! ```text
//!   min ½ sᵀA s + λ⁰ᵀ s + Σ g_r |Δs_r|   over the openings s,   s_r ≥ 0 on the normal rows
//! ```
//!
//! (the minimum of the bodies' energy over the openings: the primal, displacement form of
//! the paper's QP, built on the symmetric Steklov–Poincaré stiffness; the last term is the
//! Tresca dissipation of friction rows, with Δs_r = p_r − m_r split into p, m ≥ 0), in the
//! dense form of `lcp::Inner::dense` (free rows eliminated). The dual variable of
//! `s_r ≥ 0` is the nodal contact force λ_r. A row is open where its opening is the positive
//! one of the pair (s_r, λ_r), each relative to its largest value: the QP's own zones, with no
//! polishing. Variables are Jacobi-scaled to O(1).

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus,
};

use crate::contact::lcp::{Inner, InnerFailure, OpeningColumns, Statuses};
use crate::linalg::jacobi_scaling;

/// What the QP found.
pub struct QpOutcome {
    /// Open statuses of the rows and slip directions of friction rows.
    pub statuses: Statuses,
    pub iterations: u32,
    pub solver_status: String,
    pub objective: f64,
    pub variables: usize,
    pub constraints: usize,
}

/// Solves the inner problem as a QP.
pub fn solve(
    inner: &Inner,
    cols: &mut OpeningColumns,
    tolerance: f64,
) -> Result<QpOutcome, InnerFailure> {
    let dense = inner.dense(cols).ok_or(InnerFailure::LeavesBodyFree)?;
    let nv = dense.q.len();
    let a = &dense.m;
    let d = jacobi_scaling((0..nv).map(|i| a[i * nv + i]));
    let q: Vec<f64> = dense.q.iter().zip(&d).map(|(q, di)| q * di).collect();
    let qscale = q
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs()))
        .max(f64::MIN_POSITIVE);
    let qv: Vec<f64> = q.iter().map(|v| v / qscale).collect();
    let mut colptr = vec![0usize];
    let (mut rowval, mut nzval) = (Vec::new(), Vec::new());
    for j in 0..nv {
        for i in 0..=j {
            let v = 0.5 * (a[i * nv + j] + a[j * nv + i]) * d[i] * d[j];
            if v != 0.0 {
                rowval.push(i);
                nzval.push(v);
            }
        }
        colptr.push(rowval.len());
    }
    let pm = CscMatrix::new(nv, nv, colptr, rowval, nzval);
    // −z ≤ 0 on every variable.
    let am = CscMatrix::new(
        nv,
        nv,
        (0..=nv).collect(),
        (0..nv).collect(),
        vec![-1.0; nv],
    );
    let b = vec![0.0; nv];
    // Tight enough to split every complementary pair (see below); 1e-13 fails to converge.
    let tol = if tolerance.is_finite() && tolerance < 1e-11 {
        1e-12
    } else {
        1e-11
    };
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .tol_gap_abs(tol)
        .tol_gap_rel(tol)
        .tol_feas(tol)
        .max_iter(500)
        .build()
        .map_err(|e| InnerFailure::Qp {
            message: format!("QP settings rejected: {e:?}"),
        })?;
    let cones = [NonnegativeConeT(nv)];
    let mut solver =
        DefaultSolver::new(&pm, &qv, &am, &b, &cones, settings).map_err(|e| InnerFailure::Qp {
            message: format!("the QP could not be set up: {e:?}"),
        })?;
    solver.solve();
    let st = solver.solution.status;
    if !matches!(st, SolverStatus::Solved | SolverStatus::AlmostSolved) {
        return Err(match st {
            SolverStatus::DualInfeasible | SolverStatus::AlmostDualInfeasible => {
                InnerFailure::Unbounded
            }
            _ => InnerFailure::Qp {
                message: format!("the contact QP did not solve: Clarabel status {st:?}"),
            },
        });
    }
    let (x, z) = (&solver.solution.x, &solver.solution.z);
    // On the interior point's central path every pair has x_i z_i = μ in the scaled
    // variables (unit diagonal): the larger of the two is the non-zero one of the exact
    // complementary pair.
    let active: Vec<bool> = (0..nv).map(|i| x[i] > z[i]).collect();
    let (open, sign) = inner.statuses(&dense, &active);
    Ok(QpOutcome {
        statuses: Statuses { open, sign },
        iterations: solver.info.iterations,
        solver_status: format!("{st:?}"),
        objective: solver.solution.obj_val * qscale * qscale,
        variables: nv,
        constraints: nv,
    })
}
