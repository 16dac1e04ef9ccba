//! Contact and detachment as one convex quadratic programme ([paper §3.2, eqs. 30–33]), solved
//! with Clarabel. The only module that touches Clarabel.
//!
//! Place in the flow: `solve` (per-body operators) → **`qp`** → results. The statuses of the
//! scene (`initial`) are the pre-partition: closed pairs carry forces F (real), open pairs
//! the displacements x = −U of both sides (virtual). With the shared displacements of the
//! closed pairs eliminated, the interface functional is [paper eq. 31]
//!
//! ```text
//!   Π(F, x) = ½FᵀK_rr F + FᵀK_rv x + ½xᵀK_vv x + FᵀL_r + xᵀL_v      (K_vv negative definite)
//!   min over F, max over x   subject to   F_n ≤ c (closed pairs),  n·(U_A − U_B) ≤ h (open)
//! ```
//!
//! Dualising the gap constraints `B x ≤ H` with ν ≥ 0 and eliminating x (Q = −K_vv⁻¹ SPD)
//! gives one jointly convex QP in (F, ν) (formulation §6.3):
//!
//! ```text
//!   P = [[K_rr + K_rv Q K_vr, −K_rv Q Bᵀ], [−B Q K_vr, B Q Bᵀ]]
//!   q = [L_r + K_rv Q L_v ; H − B Q L_v],   N F ≤ C,  ν ≥ 0
//! ```
//!
//! With every unilateral pair closed this is the detachment QP [paper eq. 32b] (min over F);
//! with every one open, the contact QP [paper eq. 32a] (max over x, through its dual). An
//! active force constraint marks a pair that opens, a positive ν one that closes. As the
//! paper says, the QP gives the zones, not the path; the zones are then re-analysed with the
//! mixed system and polished by the active-set iteration (formulation §6.5: the QPs are
//! consistent predictors, the mixed system the reference). With `tangential = "stick"` a
//! closed pair's tangential force is a free variable, so a pair the QP opens stays
//! tangentially bonded in the QP — the paper's QPP, and one reason its lengths differ
//! slightly from the LCP's (formulation §5.4). Variables are Jacobi-scaled to O(1).

// Index loops mirror the block formulas.
#![allow(clippy::needless_range_loop)]

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus,
};
use faer::linalg::solvers::Solve;
use faer::Mat;

use crate::contact::interface;
use crate::contact::solve::Prepared;
use crate::contact::Status;
use crate::error::{Error, Result};
use crate::input::model::Model;
use crate::input::scene::InterfaceModel;
use crate::solution::PairStatus;

/// What the QP found.
pub struct QpResult {
    /// Statuses from the active constraints.
    pub status: Status,
    /// Which of the paper's forms the partition gave: "32b", "32a" or "30".
    pub form: &'static str,
    /// Clarabel's iterations and status.
    pub iterations: u32,
    pub solver_status: String,
    pub objective: f64,
    /// Number of variables and constraints.
    pub variables: usize,
    pub constraints: usize,
    /// The same problem as an LCP solved by Lemke's pivoting: its statuses, and its pivots.
    pub lemke: Option<(Status, usize)>,
}

/// Solves the QP for the loads times `factor`, the cohesions `cohesion[k][j]` and the
/// pre-partition `partition` (usually the initial statuses).
pub fn solve_qp(
    model: &Model,
    prepared: &Prepared,
    factor: f64,
    cohesion: &[Vec<f64>],
    tolerance: f64,
    partition: &Status,
) -> Result<QpResult> {
    let layout = interface::layout(model, &prepared.maps, partition)?;
    let (k, l) = interface::assemble_scaled(&layout, &prepared.condensed, factor);
    // Closed pairs' shared displacements eliminated: K00 over [open (v); forces (r)].
    let interface::Reduced {
        k00,
        l00,
        open: xv,
        forces: fr,
    } = interface::eliminate_shared(&layout, &k, &l);
    let (nv, nr) = (xv.len(), fr.len());
    let blk = |r0: usize, nrow: usize, c0: usize, ncol: usize| {
        Mat::<f64>::from_fn(nrow, ncol, |i, j| k00[(r0 + i, c0 + j)])
    };
    let kvv = blk(0, nv, 0, nv);
    let kvr = blk(0, nv, nv, nr);
    let krr = blk(nv, nr, nv, nr);
    let lv = Mat::<f64>::from_fn(nv, 1, |i, _| l00[(i, 0)]);
    let lr = Mat::<f64>::from_fn(nr, 1, |i, _| l00[(nv + i, 0)]);

    // Gap constraints of the open unilateral pairs: n·(U_A − U_B) = x_B − x_A ≤ h.
    let pos_v = |y: usize| xv.iter().position(|&q| q == y);
    let pos_r = |y: usize| fr.iter().position(|&q| q == y);
    let mut gaps: Vec<(usize, usize, f64, usize, usize)> = Vec::new(); // (a, b, h, k, j)
    let mut forces: Vec<(usize, f64, usize, usize)> = Vec::new(); // (r, c, k, j)
    for (kk, it) in model.interfaces.iter().enumerate() {
        if it.spec.model != InterfaceModel::Unilateral {
            continue;
        }
        for j in 0..it.pairs.len() {
            let sl = layout.slots[kk][j][1];
            match partition[kk][j][1] {
                PairStatus::Closed => {
                    if let Some(r) = sl.f.and_then(pos_r) {
                        forces.push((r, cohesion[kk][j], kk, j));
                    }
                }
                PairStatus::Open => match (sl.u_a.and_then(pos_v), sl.u_b.and_then(pos_v)) {
                    (Some(a), Some(b)) => gaps.push((a, b, it.pairs[j].gap, kk, j)),
                    _ => {
                        return Err(Error::numerical(format!(
                            "the contact QP needs both normal displacements at the open pairs;                              interface \"{}\" prescribes one at {:?}",
                            it.spec.name, it.pairs[j].x
                        )))
                    }
                },
            }
        }
    }
    let m_v = gaps.len();
    let form = match (forces.is_empty(), m_v == 0) {
        (false, true) | (true, true) => "32b",
        (true, false) => "32a",
        (false, false) => "30",
    };
    // Q = −K_vv⁻¹ (K_vv negative definite: each open side is held elastically).
    let (q_kvr, q_lv, q_bt) = if nv > 0 {
        let neg = Mat::<f64>::from_fn(nv, nv, |i, j| -kvv[(i, j)]);
        let llt = neg.llt(faer::Side::Lower).map_err(|_| {
            Error::numerical(
                "the open side of an interface is not held (the virtual stiffness K_fvfv is not \
                 negative definite): the QP cannot eliminate its displacements",
            )
        })?;
        let mut bt = Mat::<f64>::zeros(nv, m_v);
        for (g, &(a, b, _, _, _)) in gaps.iter().enumerate() {
            bt[(a, g)] = -1.0;
            bt[(b, g)] = 1.0;
        }
        (llt.solve(&kvr), llt.solve(&lv), llt.solve(&bt))
    } else {
        (Mat::zeros(0, nr), Mat::zeros(0, 1), Mat::zeros(0, m_v))
    };
    // Variables z = [F (nr); ν (m_v)].
    let n = nr + m_v;
    let mut p = Mat::<f64>::zeros(n, n);
    let mut q = vec![0.0; n];
    // K_rv Q = K_vrᵀ Q: with Q K_vr = q_kvr, K_rv Q K_vr = K_vrᵀ q_kvr.
    let a11 = &krr + kvr.transpose() * &q_kvr;
    let a12 = kvr.transpose() * &q_bt; // K_rv Q Bᵀ
    let bmat = |g: usize, row: &Mat<f64>, c: usize| -> f64 {
        // (B M)[g, c] for M with nv rows: x_B − x_A.
        let (a, b, _, _, _) = gaps[g];
        row[(b, c)] - row[(a, c)]
    };
    for i in 0..nr {
        for j in 0..nr {
            p[(i, j)] = a11[(i, j)];
        }
        for g in 0..m_v {
            p[(i, nr + g)] = -a12[(i, g)];
            p[(nr + g, i)] = -a12[(i, g)];
        }
    }
    for g in 0..m_v {
        for h in 0..m_v {
            p[(nr + g, nr + h)] = bmat(g, &q_bt, h);
        }
    }
    let rq = kvr.transpose() * &q_lv;
    for i in 0..nr {
        q[i] = lr[(i, 0)] + rq[(i, 0)];
    }
    for g in 0..m_v {
        q[nr + g] = gaps[g].2 - bmat(g, &q_lv, 0);
    }
    for i in 0..n {
        for j in 0..i {
            let m = 0.5 * (p[(i, j)] + p[(j, i)]);
            p[(i, j)] = m;
            p[(j, i)] = m;
        }
    }
    if (0..n).any(|i| p[(i, i)] <= 0.0) {
        return Err(Error::numerical(
            "the contact QP is not positive definite (a body may be free to move along an \
             interface)",
        ));
    }
    let lemke = lemke_statuses(model, partition, &p, &q, &forces, &gaps, nr)?;
    // Jacobi scaling z = D w, and the objective scaled to O(1).
    let d: Vec<f64> = (0..n).map(|i| 1.0 / p[(i, i)].sqrt()).collect();
    let qscale = q
        .iter()
        .zip(&d)
        .map(|(v, di)| (v * di).abs())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let mut colptr = vec![0usize];
    let (mut rowval, mut nzval) = (Vec::new(), Vec::new());
    for j in 0..n {
        for i in 0..=j {
            let v = d[i] * p[(i, j)] * d[j];
            if v != 0.0 {
                rowval.push(i);
                nzval.push(v);
            }
        }
        colptr.push(rowval.len());
    }
    let pm = CscMatrix::new(n, n, colptr, rowval, nzval);
    let qv: Vec<f64> = (0..n).map(|i| d[i] * q[i] / qscale).collect();
    // Constraints: F_n ≤ c (rows on F), −ν ≤ 0.
    let m = forces.len() + m_v;
    let mut acol: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n];
    let mut b = Vec::with_capacity(m);
    for (row, &(r, c, _, _)) in forces.iter().enumerate() {
        acol[r].push((row, 1.0));
        b.push(c / d[r] / qscale);
    }
    for g in 0..m_v {
        acol[nr + g].push((forces.len() + g, -1.0));
        b.push(0.0);
    }
    let mut colptr = vec![0usize];
    let (mut rowval, mut nzval) = (Vec::new(), Vec::new());
    for c in &acol {
        for &(r, v) in c {
            rowval.push(r);
            nzval.push(v);
        }
        colptr.push(rowval.len());
    }
    let am = CscMatrix::new(m, n, colptr, rowval, nzval);
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .tol_gap_abs(tolerance.max(1e-12))
        .tol_gap_rel(tolerance.max(1e-12))
        .tol_feas(tolerance.max(1e-12))
        .max_iter(500)
        .build()
        .map_err(|e| Error::numerical(format!("QP settings rejected: {e:?}")))?;
    let cones = [NonnegativeConeT(m)];
    let mut solver = DefaultSolver::new(&pm, &qv, &am, &b, &cones, settings)
        .map_err(|e| Error::numerical(format!("the QP could not be set up: {e:?}")))?;
    solver.solve();
    let st = solver.solution.status;
    if !matches!(st, SolverStatus::Solved | SolverStatus::AlmostSolved) {
        return Err(Error::numerical(format!(
            "the contact QP did not solve: Clarabel status {st:?}"
        )));
    }
    let (z, s, x) = (&solver.solution.z, &solver.solution.s, &solver.solution.x);
    let xmax = x
        .iter()
        .map(|v| v.abs())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let zf = z[..forces.len()]
        .iter()
        .copied()
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let nu_max = x[nr..]
        .iter()
        .copied()
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let mut out = partition.clone();
    let flip = |out: &mut Status, kk: usize, j: usize, to: PairStatus| {
        let slide = model.interfaces[kk].spec.tangential == crate::input::scene::Tangential::Slide;
        let t = if slide { PairStatus::Open } else { to };
        out[kk][j] = [t, to];
    };
    for (row, &(_, _, kk, j)) in forces.iter().enumerate() {
        if s[row] <= 1e-6 * xmax && z[row] > 1e-6 * zf {
            flip(&mut out, kk, j, PairStatus::Open);
        }
    }
    for (g, &(_, _, _, kk, j)) in gaps.iter().enumerate() {
        if x[nr + g] > 1e-6 * nu_max && x[nr + g] > 0.0 {
            flip(&mut out, kk, j, PairStatus::Closed);
        }
    }
    Ok(QpResult {
        status: out,
        form,
        iterations: solver.info.iterations,
        solver_status: format!("{st:?}"),
        objective: solver.solution.obj_val * qscale * qscale,
        variables: n,
        constraints: m,
        lemke,
    })
}

/// The QP's optimality conditions as an LCP in y = [c − F_n (closed pairs); ν (open pairs)]
/// after eliminating the free forces (tangential, bonded), solved by Lemke's method: an
/// exact, finite alternative to the interior-point solution (formulation §6.4).
fn lemke_statuses(
    model: &Model,
    partition: &Status,
    p: &Mat<f64>,
    q: &[f64],
    forces: &[(usize, f64, usize, usize)],
    gaps: &[(usize, usize, f64, usize, usize)],
    nr: usize,
) -> Result<Option<(Status, usize)>> {
    let n = p.nrows();
    let mut constrained: Vec<(usize, f64, f64)> = Vec::new(); // (variable, a, e)
    for &(r, c, _, _) in forces {
        constrained.push((r, c, -1.0));
    }
    for g in 0..gaps.len() {
        constrained.push((nr + g, 0.0, 1.0));
    }
    if constrained.is_empty() {
        return Ok(None);
    }
    let is_c: Vec<bool> = {
        let mut v = vec![false; n];
        for &(i, _, _) in &constrained {
            v[i] = true;
        }
        v
    };
    let free: Vec<usize> = (0..n).filter(|&i| !is_c[i]).collect();
    let cidx: Vec<usize> = constrained.iter().map(|c| c.0).collect();
    let nc = cidx.len();
    let sub =
        |r: &[usize], c: &[usize]| Mat::<f64>::from_fn(r.len(), c.len(), |i, j| p[(r[i], c[j])]);
    let mut s_mat = sub(&cidx, &cidx);
    let mut r_vec: Vec<f64> = cidx.iter().map(|&i| q[i]).collect();
    if !free.is_empty() {
        let pff = sub(&free, &free);
        let pfc = sub(&free, &cidx);
        let qf = Mat::<f64>::from_fn(free.len(), 1, |i, _| q[free[i]]);
        let lu = pff.partial_piv_lu();
        let x = lu.solve(&pfc);
        let y = lu.solve(&qf);
        s_mat = &s_mat - pfc.transpose() * &x;
        let py = pfc.transpose() * &y;
        for i in 0..nc {
            r_vec[i] -= py[(i, 0)];
        }
    }
    // M = E S E, q = E (S a + r), Jacobi-scaled.
    let mut mm = vec![0.0; nc * nc];
    let mut qq = vec![0.0; nc];
    for i in 0..nc {
        let sa: f64 = (0..nc).map(|j| s_mat[(i, j)] * constrained[j].1).sum();
        qq[i] = constrained[i].2 * (sa + r_vec[i]);
        for j in 0..nc {
            mm[i * nc + j] = constrained[i].2 * s_mat[(i, j)] * constrained[j].2;
        }
    }
    let d: Vec<f64> = (0..nc)
        .map(|i| 1.0 / mm[i * nc + i].abs().sqrt().max(f64::MIN_POSITIVE))
        .collect();
    for i in 0..nc {
        qq[i] *= d[i];
        for j in 0..nc {
            mm[i * nc + j] *= d[i] * d[j];
        }
    }
    let sol = crate::contact::lemke::lemke(&mm, &qq, 20 * nc + 100).map_err(|f| {
        Error::numerical(format!("Lemke's method failed on the contact LCP: {f:?}"))
    })?;
    let mut out = partition.clone();
    let slide =
        |kk: usize| model.interfaces[kk].spec.tangential == crate::input::scene::Tangential::Slide;
    let wmax = sol
        .w
        .iter()
        .copied()
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let zmax = sol
        .z
        .iter()
        .copied()
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    for (i, &(_, _, kk, j)) in forces.iter().enumerate() {
        // λ = 0 with a positive multiplier: the force constraint is active, the pair opens.
        if sol.z[i] <= 1e-9 * zmax && sol.w[i] > 1e-9 * wmax {
            out[kk][j] = [PairStatus::Open, PairStatus::Open];
        }
    }
    for (g, &(_, _, _, kk, j)) in gaps.iter().enumerate() {
        if sol.z[forces.len() + g] > 1e-9 * zmax {
            let t = if slide(kk) {
                PairStatus::Open
            } else {
                PairStatus::Closed
            };
            out[kk][j] = [t, PairStatus::Closed];
        }
    }
    Ok(Some((out, sol.pivots)))
}
