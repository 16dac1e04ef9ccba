//! Status-driven multidomain assembly on the interfaces ([paper eqs. 15–25],
//! docs/formulation.md §5).
//!
//! Place in the flow: `condensation` → **`interface`** → solve / contact. Every interface pair
//! j and local component c (s or n) has a status:
//!
//! * **closed (real)**: unknowns F_jc (traction on the first body A; −F on B) and −U_jc
//!   (shared); rows W^A − W^B (dual to F) and P^A + P^B (dual to −U) — [paper 16–17];
//! * **open (virtual)**: unknowns −U^A_jc and −U^B_jc, F = 0; rows P^A and P^B — [paper 18].
//!
//! With `X0_b = S_b Y` (a signed selection), `K(status) = Σ_b S_bᵀ D00_b S_b` and
//! `L(status) = Σ_b S_bᵀ Z̄0_b`, and the interface system is `K Y + L = 0`. Switching a
//! status changes only S_b: no boundary integral is ever recomputed.
//!
//! A displacement component prescribed on both sides (a symmetry plane crossing the
//! interface) has no U unknown; its F remains, closed or open.

// Index loops mirror the block formulas and read better than iterators here.
#![allow(clippy::needless_range_loop)]
use faer::linalg::solvers::Solve;
use faer::Mat;

use crate::bem::condensation::Condensed;
use crate::bem::operators::X0Map;
use crate::error::{Error, Result};
use crate::input::model::Model;
use crate::linalg::{scaled_lu_solve, ScaledSolveFailure};
use crate::solution::PairStatus;

/// Where the unknowns of one pair component sit in Y.
#[derive(Debug, Clone, Copy, Default)]
pub struct Slot {
    /// Closed: F and shared −U (None when prescribed).
    pub f: Option<usize>,
    pub u: Option<usize>,
    /// Open: −U of A and of B.
    pub u_a: Option<usize>,
    pub u_b: Option<usize>,
}

/// The interface unknowns Y for one status, and the selections S_b.
pub struct Layout {
    /// `slots[k][j][c]`.
    pub slots: Vec<Vec<[Slot; 2]>>,
    pub n: usize,
    /// Per body: (index in X0, index in Y, sign).
    pub select: Vec<Vec<(usize, usize, f64)>>,
    /// Per body: (index in X0, constant) — the initial gap of a closed normal component:
    /// in contact, `u_B·n = u_A·n − h`, so B's `−U_n` is `Y + h`.
    pub offset: Vec<Vec<(usize, f64)>>,
}

/// Builds Y and the selections for the statuses `status[k][j][c]`.
pub fn layout(model: &Model, maps: &[X0Map], status: &[Vec<[PairStatus; 2]>]) -> Result<Layout> {
    let mut slots = Vec::with_capacity(model.interfaces.len());
    let mut select: Vec<Vec<(usize, usize, f64)>> = vec![Vec::new(); model.bodies.len()];
    let mut offset: Vec<Vec<(usize, f64)>> = vec![Vec::new(); model.bodies.len()];
    let mut n = 0;
    for (k, it) in model.interfaces.iter().enumerate() {
        let (ba, bb) = (it.body_a, it.body_b);
        let mut iface_slots = Vec::with_capacity(it.pairs.len());
        for j in 0..it.pairs.len() {
            let mut pair_slots = [Slot::default(); 2];
            for c in 0..2 {
                let ua = maps[ba].get(k, j, c, false);
                let ub = maps[bb].get(k, j, c, false);
                let fa = maps[ba].get(k, j, c, true);
                let fb = maps[bb].get(k, j, c, true);
                let (Some(fa), Some(fb)) = (fa, fb) else {
                    return Err(Error::numerical(format!(
                        "interface \"{}\": pair {j} has no traction unknowns (internal layout error)",
                        it.spec.name
                    )));
                };
                let s = &mut pair_slots[c];
                match status[k][j][c] {
                    PairStatus::Closed => {
                        s.f = Some(n);
                        select[ba].push((fa, n, 1.0));
                        select[bb].push((fb, n, -1.0));
                        n += 1;
                        match (ua, ub) {
                            (Some(ua), Some(ub)) => {
                                s.u = Some(n);
                                select[ba].push((ua, n, 1.0));
                                select[bb].push((ub, n, 1.0));
                                let h = it.pairs[j].gap;
                                if c == 1 && h != 0.0 {
                                    offset[bb].push((ub, h));
                                }
                                n += 1;
                            }
                            (None, None) => {}
                            _ => {
                                return Err(Error::input(
                                    &model.mesh_path,
                                    format!(
                                        "interface \"{}\" at {:?}: a displacement component is \
                                         prescribed on one side only; prescribe it on both \
                                         bodies or on neither",
                                        it.spec.name, it.pairs[j].x
                                    ),
                                ))
                            }
                        }
                    }
                    PairStatus::Open => {
                        if let Some(ua) = ua {
                            s.u_a = Some(n);
                            select[ba].push((ua, n, 1.0));
                            n += 1;
                        }
                        if let Some(ub) = ub {
                            s.u_b = Some(n);
                            select[bb].push((ub, n, 1.0));
                            n += 1;
                        }
                    }
                }
            }
            iface_slots.push(pair_slots);
        }
        slots.push(iface_slots);
    }
    Ok(Layout {
        slots,
        n,
        select,
        offset,
    })
}

/// K(status) and L(status) (with the gap offsets: `L = Σ S_bᵀ (Z̄0_b + D00_b s_b)`).
pub fn assemble(layout: &Layout, condensed: &[Condensed]) -> (Mat<f64>, Vec<f64>) {
    assemble_scaled(layout, condensed, 1.0)
}

/// [`assemble`] with the loads Z̄0 multiplied by `factor` (the gap offsets are not loads).
pub(crate) fn assemble_scaled(
    layout: &Layout,
    condensed: &[Condensed],
    factor: f64,
) -> (Mat<f64>, Vec<f64>) {
    let n = layout.n;
    let mut k = Mat::<f64>::zeros(n, n);
    let mut l = vec![0.0; n];
    for (b, sel) in layout.select.iter().enumerate() {
        let c = &condensed[b];
        for &(xi, yi, si) in sel {
            let shift: f64 = layout.offset[b]
                .iter()
                .map(|&(xo, h)| c.d00[(xi, xo)] * h)
                .sum();
            l[yi] += si * (factor * c.z0[xi] + shift);
            for &(xj, yj, sj) in sel {
                k[(yi, yj)] += si * sj * c.d00[(xi, xj)];
            }
        }
    }
    (k, l)
}

/// Solves `K Y + L = 0` with Jacobi scaling and LU; reports a singular or inaccurate system.
pub fn solve(k: &Mat<f64>, l: &[f64], what: &str) -> Result<(Vec<f64>, f64)> {
    let n = k.nrows();
    let rhs = Mat::<f64>::from_fn(n, 1, |i, _| -l[i]);
    let solved = scaled_lu_solve(k.as_ref(), rhs.as_ref()).map_err(|f| match f {
        ScaledSolveFailure::Singular { pivot_ratio: ratio } => Error::numerical(format!(
            "the {what} system is singular (pivot ratio {ratio:.1e}): a body may be held by \
             nothing but open interfaces, or free to slide"
        )),
        ScaledSolveFailure::Inaccurate { residual } => Error::numerical(format!(
            "the {what} system left a relative residual of {residual:.1e} after solving \
             (ill-conditioned)"
        )),
    })?;
    Ok(((0..n).map(|i| solved.x[(i, 0)]).collect(), solved.residual))
}

/// The interface system with the shared displacements of the closed pairs eliminated
/// ([paper eqs. 21–24]): `K00` and `L00` over `t = [open; forces]`, with the Y indices of
/// both parts.
pub(crate) struct ReducedInterface {
    pub k00: Mat<f64>,
    pub l00: Mat<f64>,
    /// Y indices of the open pairs' displacements (−U of A and B), first in K00.
    pub open: Vec<usize>,
    /// Y indices of the closed pairs' forces, after them.
    pub forces: Vec<usize>,
}

/// Eliminates the shared displacements of the closed pairs from `K Y + L = 0`.
pub(crate) fn eliminate_shared(layout: &Layout, k: &Mat<f64>, l: &[f64]) -> ReducedInterface {
    let (mut forces, mut shared, mut open) = (Vec::new(), Vec::new(), Vec::new());
    for iface in &layout.slots {
        for pair in iface {
            for s in pair {
                forces.extend(s.f);
                shared.extend(s.u);
                open.extend(s.u_a);
                open.extend(s.u_b);
            }
        }
    }
    let sub =
        |r: &[usize], c: &[usize]| Mat::<f64>::from_fn(r.len(), c.len(), |i, j| k[(r[i], c[j])]);
    let col = |r: &[usize]| Mat::<f64>::from_fn(r.len(), 1, |i, _| l[r[i]]);
    let t: Vec<usize> = open.iter().chain(forces.iter()).copied().collect();
    let (mut k00, mut l00) = (sub(&t, &t), col(&t));
    if !shared.is_empty() {
        let lu = sub(&shared, &shared).partial_piv_lu();
        let htr = sub(&t, &shared);
        let x = lu.solve(htr.transpose().to_owned());
        let y = lu.solve(col(&shared));
        k00 = &k00 - &htr * &x;
        l00 = &l00 - &htr * &y;
    }
    ReducedInterface {
        k00,
        l00,
        open,
        forces,
    }
}

/// The paper's reduced interface operators of a status ([paper eqs. 21–27]), for the
/// archive: `K` and `L` of the whole interface system, then with the shared displacements of
/// the closed pairs eliminated, `K00 = [[K_fvfv, K_fvur], [K_urfv, K_urur]]` over
/// (−U of open pairs, F of closed pairs) with its load `L00`, and the diagonalised
/// `Ktilde_urur = K_urur − K_urfv K_fvfv⁻¹ K_fvur`, `Ktilde_fvfv = K_fvfv − K_fvur K_urur⁻¹ K_urfv`.
pub(crate) fn reduced_operators(
    layout: &Layout,
    k: &Mat<f64>,
    l: &[f64],
) -> Vec<(String, Mat<f64>)> {
    let ReducedInterface {
        k00,
        l00,
        open: fv,
        forces: f,
    } = eliminate_shared(layout, k, l);
    let nv = fv.len();
    let nr = f.len();
    let block = |m: &Mat<f64>, r0: usize, nr_: usize, c0: usize, nc: usize| {
        Mat::<f64>::from_fn(nr_, nc, |i, j| m[(r0 + i, c0 + j)])
    };
    let kvv = block(&k00, 0, nv, 0, nv);
    let kvr = block(&k00, 0, nv, nv, nr);
    let krr = block(&k00, nv, nr, nv, nr);
    let mut out = vec![
        ("K".to_string(), k.clone()),
        (
            "L".to_string(),
            Mat::<f64>::from_fn(l.len(), 1, |i, _| l[i]),
        ),
        ("K00".to_string(), k00.clone()),
        ("L00".to_string(), l00.clone()),
        ("K_fvfv".to_string(), kvv.clone()),
        ("K_urur".to_string(), krr.clone()),
    ];
    if nv > 0 && nr > 0 {
        let kt_rr = &krr - kvr.transpose() * kvv.partial_piv_lu().solve(&kvr);
        let kt_vv = &kvv - &kvr * krr.partial_piv_lu().solve(kvr.transpose().to_owned());
        out.push(("Ktilde_urur".to_string(), kt_rr));
        out.push(("Ktilde_fvfv".to_string(), kt_vv));
    } else if nr > 0 {
        out.push(("Ktilde_urur".to_string(), krr));
    } else if nv > 0 {
        out.push(("Ktilde_fvfv".to_string(), kvv));
    }
    out
}
