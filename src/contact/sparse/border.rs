//! A status solved from the factor of another that differs from it in a few rows, without a
//! factorisation of its own (bordering).
//!
//! The factor M = L Lᵀ is of H (plus the proximal weight) over the unknowns K of a status:
//! the glued displacements and the openings of its open rows. A status with the same weight
//! that opens the rows A and closes the rows R of it keeps the unknowns K' = K \ R ∪ A. Its
//! system is the one over K ∪ A with the openings of R held at zero (their equations taken
//! up by multipliers μ):
//!
//! ```text
//!   [ M   B   J ] [y]   [b]        B = H[K, A], C = H[A, A] + weight,
//!   [ Bᵀ  C   0 ] [a] = [b_A]      J = the columns of R in the identity
//!   [ Jᵀ  0   0 ] [μ]   [0]
//! ```
//!
//! With Z = [B J] and P = M⁻¹ Z (one triangular solve pair for each of the k = |A| + |R|
//! columns at once), the k unknowns (a, μ) solve the Schur complement
//! `S = [C 0; 0 0] − Zᵀ P` (dense, symmetric, indefinite: LU), and y = M⁻¹ b − P (a, μ).
//! On the 45 × 45 wall an exact attempt that fails (a brick left free) is most often followed
//! by the same status with the proximal weight of the last factor, 10–66 rows away from it:
//! k + 1 right-hand sides in one pass over L instead of a factorisation of 35 million values.
//! Every solve is checked against H itself (one product): a residual above [`RESIDUAL`] of
//! the right-hand side hands the status to a factorisation.

use faer::Mat;

use super::{Factored, Reduced, SparseSystem};

/// Rows in which a status may differ from the factor it is solved from: the triangular
/// solves for the k columns cost about k / 10 of a factorisation on walls (supernodes of
/// up to a few hundred columns), so beyond this the factorisation is cheaper.
const MAX_ROWS: usize = 64;

/// The largest residual of a bordered solve, relative to its right-hand side, that is
/// taken (a factorisation's is about 1e-14).
const RESIDUAL: f64 = 1e-9;

/// The bordered system of one status against the factor it is solved from.
pub(super) struct Border {
    open: Vec<bool>,
    reg: f64,
    /// The rows opened (A) against the factor's status.
    added: Vec<usize>,
    /// The places in the factor's unknowns of the rows closed (R).
    removed: Vec<usize>,
    /// The columns of B: per row of A, (place in the factor's unknowns, value).
    cols: Vec<Vec<(usize, f64)>>,
    /// P = M⁻¹ Z, a column per row of A, then per row of R.
    p: Mat<f64>,
    /// The Schur complement S = [C 0; 0 0] − Zᵀ P.
    s: Mat<f64>,
}

impl Border {
    /// The storage of its columns, for the next bordered solve.
    pub(super) fn into_storage(self) -> Mat<f64> {
        self.p
    }
}

/// The factor a status with the weight `reg` can be bordered from: the last one made where
/// it has that weight, else the one held while an exact attempt failed.
fn base<'a>(
    last: &'a Option<Factored>,
    held: &'a Option<(Vec<bool>, f64, Reduced)>,
    reg: f64,
) -> Option<(&'a [bool], &'a Reduced)> {
    if let Some((o, g, Some(f))) = last {
        if *g == reg {
            return Some((o, f));
        }
    }
    match held {
        Some((o, g, f)) if *g == reg => Some((o, f)),
        _ => None,
    }
}

/// `w` of the status `open` with the weight `reg` ([`SparseSystem::solve_status`]) from the
/// factor of another status with the same weight; None where there is none within
/// [`MAX_ROWS`] rows, the bordered system is singular (a body left free) or its solution
/// fails the residual check.
pub(super) fn solve(
    sys: &mut SparseSystem,
    open: &[bool],
    reg: f64,
    rhs: &[f64],
    w: &[f64],
) -> Option<Vec<f64>> {
    let cached = sys
        .border
        .as_ref()
        .is_some_and(|b| b.open == open && b.reg == reg);
    if !cached {
        sys.release_border();
        sys.border = Some(build(sys, open, reg)?);
    }
    let ng = sys.n_glued;
    let (_, red) = base(&sys.last, &sys.held, reg)?;
    let b = sys.border.as_ref()?;
    let an = &red.analysis;
    let m = an.kept.len();
    let (na, k) = (b.added.len(), b.added.len() + b.removed.len());
    // u = M⁻¹ b, the equations of R taken up by their multipliers (any right-hand side).
    let mut u = Mat::<f64>::from_fn(m, 1, |i, _| rhs[an.kept[i]]);
    for &i in &b.removed {
        u[(i, 0)] = 0.0;
    }
    red.solve_in_place(&mut sys.scratch, u.as_mut())?;
    let rz = Mat::<f64>::from_fn(k, 1, |i, _| {
        if i < na {
            let zu: f64 = b.cols[i].iter().map(|&(q, v)| v * u[(q, 0)]).sum();
            rhs[ng + b.added[i]] - zu
        } else {
            -u[(b.removed[i - na], 0)]
        }
    });
    let z = crate::linalg::scaled_lu_solve(b.s.as_ref(), rz.as_ref())
        .ok()?
        .x;
    let y = &u - &b.p * &z;
    let mut out = w.to_vec();
    for (i, &unknown) in an.kept.iter().enumerate() {
        if unknown < ng || open[unknown - ng] {
            out[unknown] = y[(i, 0)];
        }
    }
    for (j, &r) in b.added.iter().enumerate() {
        out[ng + r] = z[(j, 0)];
    }
    (residual(sys, open, reg, rhs, &out) <= RESIDUAL).then_some(out)
}

/// The largest residual of the equations of the status `open` (weight `reg`) at `w`,
/// relative to the largest right-hand side: H over its unknowns times their values, plus
/// the weight on its open rows, against `rhs` (the closed rows' fixed openings are in it).
fn residual(sys: &SparseSystem, open: &[bool], reg: f64, rhs: &[f64], w: &[f64]) -> f64 {
    let ng = sys.n_glued;
    let kept = |k: usize| k < ng || open[k - ng];
    let y: Vec<f64> = (0..w.len())
        .map(|k| if kept(k) { w[k] } else { 0.0 })
        .collect();
    let hy = sys.apply(&y);
    let (mut worst, mut scale) = (0.0f64, 0.0f64);
    for k in (0..w.len()).filter(|&k| kept(k)) {
        let mut a = hy[k];
        if k >= ng && reg > 0.0 {
            a += reg * sys.diag[k].abs().max(f64::MIN_POSITIVE) * y[k];
        }
        worst = worst.max((a - rhs[k]).abs());
        scale = scale.max(rhs[k].abs());
    }
    if scale > 0.0 {
        worst / scale
    } else {
        worst
    }
}

/// The bordered system of the status `open` against the factor it can be solved from; None
/// where there is none within [`MAX_ROWS`] rows or the memory cannot be had.
fn build(sys: &mut SparseSystem, open: &[bool], reg: f64) -> Option<Border> {
    let ng = sys.n_glued;
    let (bopen, red) = base(&sys.last, &sys.held, reg)?;
    if (0..open.len())
        .filter(|&r| open[r] != bopen[r])
        .nth(MAX_ROWS)
        .is_some()
    {
        return None;
    }
    let added: Vec<usize> = (0..open.len()).filter(|&r| open[r] && !bopen[r]).collect();
    let an = &red.analysis;
    let ord = &sys.ordered;
    let pos = |u: usize| Some(an.index[ord.place[u]]).filter(|&i| i != usize::MAX);
    let removed: Vec<usize> = (0..open.len())
        .filter(|&r| bopen[r] && !open[r])
        .map(|r| pos(ng + r))
        .collect::<Option<_>>()?;
    let (na, k) = (added.len(), added.len() + removed.len());
    // Column j of B for the unknown ng + added[j]; C from the entries among them.
    let mut slot = vec![usize::MAX; ord.unknown.len()];
    for (j, &r) in added.iter().enumerate() {
        slot[ng + r] = j;
    }
    let mut cols: Vec<Vec<(usize, f64)>> = vec![Vec::new(); na];
    let mut c = Mat::<f64>::zeros(na, na);
    let sym = ord.h.symbolic();
    let (cp, ri, val) = (sym.col_ptr(), sym.row_idx(), ord.h.val());
    for col in 0..ord.unknown.len() {
        let ja = slot[ord.unknown[col]];
        for q in cp[col]..cp[col + 1] {
            let row = ri[q];
            let jr = slot[ord.unknown[row]];
            let v = val[q];
            match (ja != usize::MAX, jr != usize::MAX) {
                (false, false) => {}
                (true, true) if row == col => {
                    c[(ja, ja)] += if reg > 0.0 {
                        v + reg * v.abs().max(f64::MIN_POSITIVE)
                    } else {
                        v
                    };
                }
                (true, true) => {
                    c[(ja, jr)] += v;
                    c[(jr, ja)] += v;
                }
                (true, false) => {
                    if let Some(i) = pos(ord.unknown[row]) {
                        cols[ja].push((i, v));
                    }
                }
                (false, true) => {
                    if let Some(i) = pos(ord.unknown[col]) {
                        cols[jr].push((i, v));
                    }
                }
            }
        }
    }
    let m = an.kept.len();
    // The storage of the last bordered solve's columns, cleared (fresh storage costs its
    // pages again: up to 64 columns of the factor's order each time).
    let mut p = std::mem::replace(&mut sys.border_spare, Mat::new());
    p.resize_with(m, k, |_, _| 0.0);
    p.fill(0.0);
    for (j, col) in cols.iter().enumerate() {
        for &(i, v) in col {
            p[(i, j)] += v;
        }
    }
    for (t, &i) in removed.iter().enumerate() {
        p[(i, na + t)] = 1.0;
    }
    red.solve_in_place(&mut sys.scratch, p.as_mut())?;
    let s = Mat::<f64>::from_fn(k, k, |i, j| {
        let d = if i < na && j < na { c[(i, j)] } else { 0.0 };
        let zp: f64 = if i < na {
            cols[i].iter().map(|&(q, v)| v * p[(q, j)]).sum()
        } else {
            p[(removed[i - na], j)]
        };
        d - zp
    });
    Some(Border {
        open: open.to_vec(),
        reg,
        added,
        removed,
        cols,
        p,
        s,
    })
}

#[cfg(test)]
mod tests {
    use super::super::SparseSystem;
    use faer::sparse::{SparseColMat, Triplet};

    /// H = G Gᵀ + I over 5 glued displacements and 6 rows (lower triangle), dense.
    fn system() -> SparseSystem {
        let size = 11;
        let g = |i: usize, k: usize| (((i * 7 + k * 13) % 17) as f64) / 9.0 - 0.8;
        let h = |i: usize, j: usize| -> f64 {
            (0..size).map(|k| g(i, k) * g(j, k)).sum::<f64>() + if i == j { 1.0 } else { 0.0 }
        };
        let entries: Vec<_> = (0..size)
            .flat_map(|j| (j..size).map(move |i| Triplet::new(i, j, h(i, j))))
            .collect();
        let m = SparseColMat::<usize, f64>::try_new_from_triplets(size, size, &entries)
            .expect("matrix");
        SparseSystem::from_matrix(m, 5, 6, crate::contact::sparse::rigid::RigidRows::none())
            .expect("system")
    }

    /// A status that opens two rows and closes one of a factored status, with the same
    /// proximal weight, is solved from that factor by bordering (no factorisation of its
    /// own) and agrees with its own factorisation to round-off; with another weight it is
    /// not bordered.
    #[test]
    fn a_bordered_status_is_its_own_factorisation() {
        let rhs: Vec<f64> = (0..11).map(|k| (k as f64 * 0.7).sin() + 0.3).collect();
        let first = [true, false, true, false, true, false];
        let second = [true, true, false, true, true, false];
        // The closed rows' fixed openings.
        let fixed = |open: &[bool]| -> Vec<f64> {
            (0..11)
                .map(|k: usize| match k.checked_sub(5) {
                    Some(r) if !open[r] => 0.1 * (r as f64 + 1.0),
                    _ => 0.0,
                })
                .collect()
        };
        let reg = 1e-2;
        let mut sys = system();
        sys.solve_status(&first, reg, &rhs, fixed(&first))
            .expect("first status");
        let bordered = sys
            .solve_status(&second, reg, &rhs, fixed(&second))
            .expect("second status");
        assert!(sys.border.is_some(), "the second status was not bordered");
        let factored_status = sys.last.as_ref().map(|l| l.0.clone());
        assert_eq!(factored_status.as_deref(), Some(&first[..]));
        let mut fresh = system();
        let own = fresh
            .solve_status(&second, reg, &rhs, fixed(&second))
            .expect("second status, factored");
        assert!(fresh.border.is_none());
        let diff = bordered
            .iter()
            .zip(&own)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f64, f64::max);
        let size = own.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        assert!(diff <= 1e-12 * size, "{diff} of {size}");
        // The closed rows keep their openings.
        assert_eq!(bordered[5 + 2], fixed(&second)[5 + 2]);
        // Another weight: a factorisation.
        sys.solve_status(&second, 1e-3, &rhs, fixed(&second))
            .expect("another weight");
        assert!(sys.border.is_none());
        assert_eq!(sys.last.as_ref().map(|l| l.1), Some(1e-3));
    }
}
