//! Lemke's complementary pivoting for the linear complementarity problem
//! `w = M z + q, w ≥ 0, z ≥ 0, wᵀz = 0` (Cottle–Pang–Stone 1992; docs/formulation.md §6.4).
//!
//! Place in the flow: `lcp` (the inner contact problem) → **`lemke`** → `contact`: the exact,
//! finite cross-check of the other solvers and the fallback of the outer loop. For a P-matrix (every SPD matrix is one) Lemke's
//! method terminates with the unique solution; the lexicographic ratio test (ties broken by
//! the rows of the basis inverse) rules out cycling under degeneracy. A secondary ray —
//! which certifies that no solution exists for a merely copositive M — is reported as an
//! error, never hidden.

use crate::contact::lcp::{Inner, InnerFailure, OpeningColumns, Statuses};
use crate::linalg::jacobi_scaling;

/// Outcome of Lemke's method.
#[derive(Debug, Clone)]
pub struct LemkeSolution {
    pub z: Vec<f64>,
    pub w: Vec<f64>,
    pub pivots: usize,
}

/// Why Lemke's method stopped without a solution.
#[derive(Debug, Clone, PartialEq)]
pub enum LemkeFailure {
    /// A secondary ray: no solution for this q (possible only if M is not a P-matrix).
    SecondaryRay { pivots: usize },
    /// The pivot limit was reached.
    PivotLimit { pivots: usize },
}

/// Solves the LCP (M, q) with covering vector 1. `m` is row-major n×n.
pub fn lemke(m: &[f64], q: &[f64], max_pivots: usize) -> Result<LemkeSolution, LemkeFailure> {
    let n = q.len();
    assert_eq!(m.len(), n * n, "LCP matrix must be n×n");
    if q.iter().all(|&v| v >= 0.0) {
        return Ok(LemkeSolution {
            z: vec![0.0; n],
            w: q.to_vec(),
            pivots: 0,
        });
    }
    // Tableau columns: w (0..n), z (n..2n), z0 (2n), rhs (2n+1). Rows: w − M z − 1 z0 = q.
    let cols = 2 * n + 2;
    let mut t = vec![0.0; n * cols];
    for i in 0..n {
        t[i * cols + i] = 1.0;
        for j in 0..n {
            t[i * cols + n + j] = -m[i * n + j];
        }
        t[i * cols + 2 * n] = -1.0;
        t[i * cols + 2 * n + 1] = q[i];
    }
    let mut basis: Vec<usize> = (0..n).collect(); // variable index basic in each row
    let scale = m
        .iter()
        .chain(q)
        .fold(0.0f64, |a, v| a.max(v.abs()))
        .max(1.0);
    let eps = 1e-12 * scale;

    let pivot = |t: &mut Vec<f64>, r: usize, c: usize| {
        let p = t[r * cols + c];
        for k in 0..cols {
            t[r * cols + k] /= p;
        }
        for i in 0..n {
            if i == r {
                continue;
            }
            let f = t[i * cols + c];
            if f != 0.0 {
                for k in 0..cols {
                    t[i * cols + k] -= f * t[r * cols + k];
                }
            }
        }
    };

    // First pivot: z0 enters, the row of the most negative q leaves.
    let mut r = (0..n).min_by(|&a, &b| q[a].total_cmp(&q[b])).unwrap_or(0);
    let mut entering = 2 * n;
    let mut pivots = 0;
    loop {
        pivot(&mut t, r, entering);
        let leaving = basis[r];
        basis[r] = entering;
        pivots += 1;
        if leaving == 2 * n {
            break; // z0 left: a complementary solution
        }
        if pivots >= max_pivots {
            return Err(LemkeFailure::PivotLimit { pivots });
        }
        // The complement of the variable that left enters.
        entering = if leaving < n {
            leaving + n
        } else {
            leaving - n
        };
        // Lexicographic minimum ratio test over rows with a positive entry.
        let mut best: Option<usize> = None;
        for i in 0..n {
            let a = t[i * cols + entering];
            if a <= eps {
                continue;
            }
            best = Some(match best {
                None => i,
                Some(b) => {
                    let ab = t[b * cols + entering];
                    // Compare (rhs, B⁻¹ row) / a lexicographically.
                    let key = |row: usize, k: usize, den: f64| -> f64 {
                        if k == 0 {
                            t[row * cols + 2 * n + 1] / den
                        } else {
                            t[row * cols + (k - 1)] / den
                        }
                    };
                    let mut choice = b;
                    for k in 0..=n {
                        let (x, y) = (key(i, k, a), key(b, k, ab));
                        let tol = 1e-13 * (1.0 + x.abs().max(y.abs()));
                        if x < y - tol {
                            choice = i;
                            break;
                        }
                        if x > y + tol {
                            choice = b;
                            break;
                        }
                    }
                    choice
                }
            });
        }
        match best {
            Some(i) => r = i,
            None => return Err(LemkeFailure::SecondaryRay { pivots }),
        }
    }
    let mut z = vec![0.0; n];
    let mut w = vec![0.0; n];
    for (i, &b) in basis.iter().enumerate() {
        let v = t[i * cols + 2 * n + 1].max(0.0);
        if b < n {
            w[b] = v;
        } else if b < 2 * n {
            z[b - n] = v;
        }
    }
    Ok(LemkeSolution { z, w, pivots })
}

/// Scales the LCP (M, q) to `D M D, D q` with D = diag(1/√|M_ii|), which keeps the pivots
/// O(1); returns D (the solution's z is D z̃, its w is w̃ / D).
fn jacobi_scale(m: &mut [f64], q: &mut [f64]) -> Vec<f64> {
    let n = q.len();
    let d = jacobi_scaling((0..n).map(|i| m[i * n + i]));
    for i in 0..n {
        q[i] *= d[i];
        for j in 0..n {
            m[i * n + j] *= d[i] * d[j];
        }
    }
    d
}

/// Solves the inner contact LCP (`lcp`) by Lemke's method on its dense form (every column of
/// the opening stiffness, free rows eliminated, friction rows split into their two slip
/// directions). Returns the open statuses of the rows, the slip directions and the number
/// of pivots; a secondary ray means no equilibrium exists (a mechanism).
pub fn solve(inner: &Inner, cols: &mut OpeningColumns) -> Result<(Statuses, usize), InnerFailure> {
    let dense = inner.dense(cols).ok_or(InnerFailure::LeavesBodyFree)?;
    let n = dense.q.len();
    let (mut m, mut q) = (dense.m.clone(), dense.q.clone());
    jacobi_scale(&mut m, &mut q);
    let sol = lemke(&m, &q, 20 * n + 100).map_err(|f| match f {
        LemkeFailure::SecondaryRay { pivots } => InnerFailure::SecondaryRay { pivots },
        LemkeFailure::PivotLimit { pivots } => InnerFailure::PivotLimit { pivots },
    })?;
    // z is the (scaled) opening or slip, w its force: active where z is the positive one.
    let active: Vec<bool> = (0..n).map(|i| sol.z[i] > sol.w[i]).collect();
    let (open, sign) = inner.statuses(&dense, &active);
    Ok((Statuses { open, sign }, sol.pivots))
}

/// Solves Coulomb friction exactly, without the Tresca fixed point: Klarbring's 2D
/// friction LCP (Klarbring 1986) on the dense form of the inner problem. Per friction row
/// with the normal row n of its pair, the slip variables p, m ≥ 0 are complementary to
///
/// ```text
///   w_p = μ (λ_n − c_n) + λ_t ≥ 0,   w_m = μ (λ_n − c_n) − λ_t ≥ 0
/// ```
///
/// (c_n the cohesion term), i.e. the Tresca rows with the bound μλ_n taken from the solution
/// itself. M is not symmetric, so Lemke's method may end on a secondary ray for large μ
/// (existence is known only for small μ); that is reported, not hidden. `inner` must have
/// no free friction rows (its bounds are ignored); `mu` is the coefficient of each row.
/// Returns the open rows, the slip directions and the bounds μ max(λ_n − c_n, 0) of the
/// solution.
#[allow(clippy::type_complexity)]
pub(crate) fn solve_coupled(
    inner: &Inner,
    cols: &mut OpeningColumns,
    mu: &[f64],
    normal_of: &[Option<usize>],
) -> Result<(Vec<bool>, Vec<f64>, Vec<f64>), String> {
    let dense = inner
        .dense(cols)
        .ok_or_else(|| "the free tangential openings leave a body free".to_string())?;
    let n = dense.q.len();
    let var_of_normal: std::collections::HashMap<usize, usize> = dense
        .vars
        .iter()
        .enumerate()
        .filter(|(_, (r, _))| inner.is_normal(*r))
        .map(|(i, (r, _))| (*r, i))
        .collect();
    let (mut m, mut q) = (dense.m.clone(), dense.q.clone());
    for (i, &(r, _)) in dense.vars.iter().enumerate() {
        if !inner.is_friction(r) {
            continue;
        }
        let k = normal_of[r]
            .and_then(|rn| var_of_normal.get(&rn).copied())
            .ok_or_else(|| "a friction row without a normal row".to_string())?;
        let rn = dense.vars[k].0;
        // Dense rows give λ_t (σ = +1) or −λ_t (σ = −1) and λ_n; add μ (λ_n − c_n).
        q[i] = dense.q[i] + mu[r] * (dense.q[k] - inner.base.cohesion[rn]);
        for j in 0..n {
            m[i * n + j] = dense.m[i * n + j] + mu[r] * dense.m[k * n + j];
        }
    }
    let d = jacobi_scale(&mut m, &mut q);
    let sol = lemke(&m, &q, 40 * n + 100).map_err(|f| match f {
        LemkeFailure::SecondaryRay { pivots } => format!(
            "Lemke's method on the coupled friction LCP ended on a secondary ray after \
             {pivots} pivots (no solution found: a mechanism, or a friction coefficient too \
             large for the method)"
        ),
        LemkeFailure::PivotLimit { pivots } => {
            format!("Lemke's method reached its pivot limit ({pivots} pivots)")
        }
    })?;
    let active: Vec<bool> = (0..n).map(|i| sol.z[i] > sol.w[i]).collect();
    let (open, sign) = inner.statuses(&dense, &active);
    // λ_n of each normal row from its (unscaled) complementary variable.
    let mut bound = vec![0.0; inner.n()];
    for (r, b) in bound.iter_mut().enumerate() {
        let Some(rn) = normal_of[r] else { continue };
        if let Some(&k) = var_of_normal.get(&rn) {
            if !open[rn] {
                let lambda = sol.w[k] / d[k];
                *b = mu[r] * (lambda - inner.base.cohesion[rn]).max(0.0);
            }
        }
    }
    Ok((open, sign, bound))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic pseudo-random SPD matrix A Aᵀ + δI.
    fn spd(n: usize, seed: u64) -> Vec<f64> {
        let mut s = seed;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 33) as f64 / (1u64 << 31) as f64) - 1.0
        };
        let a: Vec<f64> = (0..n * n).map(|_| rnd()).collect();
        let mut m = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                m[i * n + j] = (0..n).map(|k| a[i * n + k] * a[j * n + k]).sum::<f64>();
            }
            m[i * n + i] += 0.1;
        }
        m
    }

    #[test]
    fn solves_spd_lcps_with_complementarity() {
        for (n, seed) in [(1, 1), (2, 2), (5, 3), (20, 4), (60, 5)] {
            let m = spd(n, seed);
            let q: Vec<f64> = (0..n)
                .map(|i| ((i * 7 + seed as usize) % 11) as f64 - 5.0)
                .collect();
            let s = lemke(&m, &q, 10 * n + 10).expect("P-matrix LCP has a solution");
            for i in 0..n {
                let wi: f64 = (0..n).map(|j| m[i * n + j] * s.z[j]).sum::<f64>() + q[i];
                assert!((wi - s.w[i]).abs() < 1e-9 * (1.0 + wi.abs()), "w = Mz + q");
                assert!(s.z[i] >= 0.0 && s.w[i] >= -1e-12);
                assert!(s.z[i] * s.w[i].max(0.0) < 1e-9, "complementarity");
            }
        }
    }

    #[test]
    fn trivial_and_degenerate_cases() {
        let s = lemke(&[2.0], &[3.0], 5).unwrap();
        assert_eq!(s.z, vec![0.0]);
        let s = lemke(&[2.0], &[-4.0], 5).unwrap();
        assert!((s.z[0] - 2.0).abs() < 1e-14 && s.w[0].abs() < 1e-14);
        // Degenerate: two equal rows of q (ties in the ratio test).
        let m = [2.0, 1.0, 1.0, 2.0];
        let s = lemke(&m, &[-1.0, -1.0], 10).unwrap();
        assert!((s.z[0] - 1.0 / 3.0).abs() < 1e-12 && (s.z[1] - 1.0 / 3.0).abs() < 1e-12);
    }

    #[test]
    fn secondary_ray_is_reported() {
        // M = 0 (copositive, not P) with q < 0: no solution.
        assert!(matches!(
            lemke(&[0.0], &[-1.0], 5),
            Err(LemkeFailure::SecondaryRay { .. })
        ));
    }
}
