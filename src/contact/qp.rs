//! The contact problem as one convex quadratic programme, solved with Clarabel (the only
//! module that touches Clarabel; [paper §3.2], formulation §6.3).
//!
//! Place in the flow: `lcp` (the inner problem) → **`qp`** → `contact`. The inner LCP of
//! `problem` is the optimality system of
//!
//! ```text
//!   min ½ sᵀA s + λ⁰ᵀ s   over the openings s,   s_r ≥ 0 on the unilateral normal rows
//! ```
//!
//! (the minimum of the bodies' energy over the openings: the primal, displacement form of
//! the paper's QP, built on the symmetric Steklov–Poincaré stiffness). The dual variable of
//! `s_r ≥ 0` is the nodal contact force λ_r. A row is open where its opening is the positive
//! one of the pair (s_r, λ_r), each relative to its largest value: the QP's own zones, with no
//! polishing. Variables are Jacobi-scaled to O(1).

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus,
};

use crate::contact::lcp::{Columns, Inner};

/// What the QP found.
pub struct QpOutcome {
    /// Open statuses of the rows.
    pub open: Vec<bool>,
    pub iterations: u32,
    pub solver_status: String,
    pub objective: f64,
    pub variables: usize,
    pub constraints: usize,
}

/// Solves the inner problem as a QP.
pub fn solve(inner: &Inner, cols: &mut Columns, tolerance: f64) -> Result<QpOutcome, String> {
    let n = inner.n();
    let mut a = vec![0.0; n * n];
    for j in 0..n {
        let col = cols.get(inner.problem, j);
        for i in 0..n {
            a[i * n + j] = col[i];
        }
    }
    // Variables: every row that can open; closed-forever rows are not here (bonded).
    // Rows that are neither normal nor free are tied stick rows: opening fixed at 0.
    let vars: Vec<usize> = (0..n)
        .filter(|&r| inner.free[r] || inner.is_normal(r))
        .collect();
    let nv = vars.len();
    let d: Vec<f64> = vars
        .iter()
        .map(|&r| 1.0 / a[r * n + r].abs().sqrt().max(f64::MIN_POSITIVE))
        .collect();
    let q: Vec<f64> = vars
        .iter()
        .zip(&d)
        .map(|(&r, di)| inner.base.lambda0[r] * di)
        .collect();
    let qscale = q
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs()))
        .max(f64::MIN_POSITIVE);
    let qv: Vec<f64> = q.iter().map(|v| v / qscale).collect();
    let mut colptr = vec![0usize];
    let (mut rowval, mut nzval) = (Vec::new(), Vec::new());
    for (jj, &rj) in vars.iter().enumerate() {
        for (ii, &ri) in vars.iter().enumerate().take(jj + 1) {
            let v = 0.5 * (a[ri * n + rj] + a[rj * n + ri]) * d[ii] * d[jj];
            if v != 0.0 {
                rowval.push(ii);
                nzval.push(v);
            }
        }
        colptr.push(rowval.len());
    }
    let pm = CscMatrix::new(nv, nv, colptr, rowval, nzval);
    // −s ≤ 0 on the normal rows.
    let cons: Vec<usize> = (0..nv).filter(|&i| !inner.free[vars[i]]).collect();
    let m = cons.len();
    let mut colptr = vec![0usize];
    let (mut rowval, mut nzval) = (Vec::new(), Vec::new());
    let mut row_of = vec![None; nv];
    for (k, &i) in cons.iter().enumerate() {
        row_of[i] = Some(k);
    }
    for r in row_of.iter() {
        if let Some(k) = r {
            rowval.push(*k);
            nzval.push(-1.0);
        }
        colptr.push(rowval.len());
    }
    let am = CscMatrix::new(m, nv, colptr, rowval, nzval);
    let b = vec![0.0; m];
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .tol_gap_abs(tolerance.min(1e-11).max(1e-12))
        .tol_gap_rel(tolerance.min(1e-11).max(1e-12))
        .tol_feas(tolerance.min(1e-11).max(1e-12))
        .max_iter(500)
        .build()
        .map_err(|e| format!("QP settings rejected: {e:?}"))?;
    let cones = [NonnegativeConeT(m)];
    let mut solver = DefaultSolver::new(&pm, &qv, &am, &b, &cones, settings)
        .map_err(|e| format!("the QP could not be set up: {e:?}"))?;
    solver.solve();
    let st = solver.solution.status;
    if !matches!(st, SolverStatus::Solved | SolverStatus::AlmostSolved) {
        return Err(match st {
            SolverStatus::DualInfeasible | SolverStatus::AlmostDualInfeasible => {
                "the QP is unbounded: no equilibrium exists (a body can move freely under \
                 its loads)"
                    .to_string()
            }
            _ => format!("the contact QP did not solve: Clarabel status {st:?}"),
        });
    }
    let (x, z) = (&solver.solution.x, &solver.solution.z);
    // On the interior point's central path every pair has x_i z_i = μ in the scaled
    // variables (unit diagonal): the larger of the two is the non-zero one of the exact
    // complementary pair.
    let mut open = inner.free.clone();
    for (k, &i) in cons.iter().enumerate() {
        open[vars[i]] = x[i] > z[k];
    }
    Ok(QpOutcome {
        open,
        iterations: solver.info.iterations,
        solver_status: format!("{st:?}"),
        objective: solver.solution.obj_val * qscale * qscale,
        variables: nv,
        constraints: m,
    })
}
