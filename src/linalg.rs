//! Small dense linear algebra shared by the stages, and the assembly of a symmetric sparse
//! matrix from its entries.

use faer::linalg::solvers::Solve;
use faer::{Mat, MatRef};

/// `m x` by faer's product (vectorised, parallel on large blocks).
pub fn matvec(m: &Mat<f64>, x: &[f64]) -> Vec<f64> {
    if m.nrows() == 0 {
        return Vec::new();
    }
    let y = m * faer::ColRef::from_slice(x);
    y.iter().copied().collect()
}

/// The symmetric diagonal (Jacobi) scaling of a matrix from its diagonal: `D = diag(1/√|a_ii|)`,
/// so that `D A D` has a unit diagonal, which keeps the pivots of a factorisation O(1). A zero
/// (or NaN) diagonal entry keeps the factor 1.
pub(crate) fn jacobi_scaling(diag: impl Iterator<Item = f64>) -> Vec<f64> {
    diag.map(|a| {
        let d = a.abs();
        if d > 0.0 {
            1.0 / d.sqrt()
        } else {
            1.0
        }
    })
    .collect()
}

/// `X = K⁻¹ B` by LU with partial pivoting after the symmetric Jacobi scaling S of K
/// ([`jacobi_scaling`]): `X = S (S K S)⁻¹ S B`, with the smallest over the largest pivot of the
/// scaled LU and the relative residual of the scaled solve.
pub(crate) struct ScaledSolve {
    pub x: Mat<f64>,
    pub pivot_ratio: f64,
    pub residual: f64,
}

/// Why [`scaled_lu_solve`] refused a system.
#[derive(Debug, Clone, Copy)]
pub(crate) enum ScaledSolveFailure {
    /// A pivot ratio of at most 1e-14 (or NaN): K is singular.
    Singular { pivot_ratio: f64 },
    /// A relative residual of 1e-8 or more (or NaN): K is ill-conditioned.
    Inaccurate { residual: f64 },
}

/// Solves `K X = B` for a square K (see [`ScaledSolve`]); an empty K gives an empty X with a
/// pivot ratio of 1 and no residual.
pub(crate) fn scaled_lu_solve(
    k: MatRef<'_, f64>,
    b: MatRef<'_, f64>,
) -> Result<ScaledSolve, ScaledSolveFailure> {
    let n = k.nrows();
    if n == 0 {
        return Ok(ScaledSolve {
            x: Mat::zeros(0, b.ncols()),
            pivot_ratio: 1.0,
            residual: 0.0,
        });
    }
    let s = jacobi_scaling((0..n).map(|i| k[(i, i)]));
    let a = Mat::<f64>::from_fn(n, n, |i, j| s[i] * k[(i, j)] * s[j]);
    let rhs = Mat::<f64>::from_fn(n, b.ncols(), |i, j| s[i] * b[(i, j)]);
    let lu = a.partial_piv_lu();
    let u = lu.U();
    let (mut pmin, mut pmax) = (f64::INFINITY, 0.0f64);
    for i in 0..n {
        pmin = pmin.min(u[(i, i)].abs());
        pmax = pmax.max(u[(i, i)].abs());
    }
    let pivot_ratio = if pmax > 0.0 { pmin / pmax } else { 0.0 };
    if pivot_ratio.is_nan() || pivot_ratio <= 1e-14 {
        return Err(ScaledSolveFailure::Singular { pivot_ratio });
    }
    let y = lu.solve(&rhs);
    let res = &a * &y - &rhs;
    let residual = res.norm_max() / rhs.norm_max().max(f64::MIN_POSITIVE);
    if residual.is_nan() || residual >= 1e-8 {
        return Err(ScaledSolveFailure::Inaccurate { residual });
    }
    Ok(ScaledSolve {
        x: Mat::<f64>::from_fn(n, b.ncols(), |i, j| s[i] * y[(i, j)]),
        pivot_ratio,
        residual,
    })
}

/// The solution of the 3 × 3 system `a x = b` by elimination with partial pivoting; None
/// where a pivot vanishes against the largest entry.
pub(crate) fn solve3(a: [[f64; 3]; 3], b: [f64; 3]) -> Option<[f64; 3]> {
    let x = solve_small(a.iter().map(|r| r.to_vec()).collect(), b.to_vec())?;
    Some([x[0], x[1], x[2]])
}

/// The solution of a small dense system `a x = b` (rows of `a`) by elimination with partial
/// pivoting; None where a pivot vanishes against the largest entry.
pub(crate) fn solve_small(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Option<Vec<f64>> {
    let n = b.len();
    let big = a.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    for k in 0..n {
        let p = (k..n).max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))?;
        if a[p][k].abs() <= 1e-14 * big || big == 0.0 {
            return None;
        }
        a.swap(k, p);
        b.swap(k, p);
        let pivot = a[k].clone();
        for i in k + 1..n {
            let f = a[i][k] / pivot[k];
            for (x, p) in a[i].iter_mut().zip(&pivot).skip(k) {
                *x -= f * p;
            }
            b[i] -= f * b[k];
        }
    }
    let mut x = vec![0.0; n];
    for k in (0..n).rev() {
        let s: f64 = (k + 1..n).map(|j| a[k][j] * x[j]).sum();
        x[k] = (b[k] - s) / a[k][k];
    }
    Some(x)
}

/// A triangle (`side`) of a symmetric sparse matrix of order `n` in compressed columns (rows
/// sorted, each position once), from the entries `(row, col, value)` within it (`row ≥ col`
/// for the lower one) that `emit` hands to its sink; entries at the same position are summed
/// in the order given. `emit` runs twice, once to count the entries of each column and once
/// to place them, so the entries are never held as triplets (whose global sort cost more
/// than the rest of the assembly). None where an entry lies outside the triangle or the
/// memory cannot be had.
pub(crate) fn triangle_from_entries(
    n: usize,
    side: faer::Side,
    emit: impl Fn(&mut dyn FnMut(usize, usize, f64)),
) -> Option<faer::sparse::SparseColMat<usize, f64>> {
    let mut start = vec![0usize; n + 1];
    let mut outside = false;
    let inside = |r: usize, c: usize| match side {
        faer::Side::Lower => c <= r && r < n,
        faer::Side::Upper => r <= c && c < n,
    };
    emit(&mut |r, c, _| {
        if inside(r, c) {
            start[c + 1] += 1;
        } else {
            outside = true;
        }
    });
    if outside {
        return None;
    }
    for c in 0..n {
        start[c + 1] += start[c];
    }
    let total = start[n];
    let (mut rows, mut vals) = (Vec::new(), Vec::new());
    rows.try_reserve_exact(total).ok()?;
    vals.try_reserve_exact(total).ok()?;
    rows.resize(total, 0usize);
    vals.resize(total, 0.0f64);
    let mut next = start.clone();
    emit(&mut |r, c, v| {
        rows[next[c]] = r;
        vals[next[c]] = v;
        next[c] += 1;
    });
    // Each column sorted by row (stable: repeated positions keep their order) and merged.
    let mut col_ptr = Vec::with_capacity(n + 1);
    col_ptr.push(0);
    let mut column: Vec<(usize, f64)> = Vec::new();
    let mut kept = 0;
    for c in 0..n {
        column.clear();
        column.extend((start[c]..start[c + 1]).map(|p| (rows[p], vals[p])));
        column.sort_by_key(|e| e.0);
        let first = kept;
        for &(r, v) in &column {
            if kept > first && rows[kept - 1] == r {
                vals[kept - 1] += v;
            } else {
                rows[kept] = r;
                vals[kept] = v;
                kept += 1;
            }
        }
        col_ptr.push(kept);
    }
    rows.truncate(kept);
    vals.truncate(kept);
    let symbolic = faer::sparse::SymbolicSparseColMat::new_checked(n, n, col_ptr, None, rows);
    Some(faer::sparse::SparseColMat::new(symbolic, vals))
}

/// The sparse Cholesky factor of a symmetric positive definite matrix, ordered by
/// approximate minimum degree and factored on one thread: the factor's fronts on the
/// interface systems of walls are small, and two threads waiting on each other cost more
/// than they gain (45 × 45 wall: 0.94 s on one thread against 1.3 s on two).
pub(crate) struct SparseLlt {
    symbolic: faer::sparse::linalg::cholesky::SymbolicCholesky<usize>,
    l: Vec<f64>,
}

impl SparseLlt {
    /// The factor of `a` given by its lower triangle; None where `a` is not positive
    /// definite or the memory cannot be had.
    pub(crate) fn new(a: &faer::sparse::SparseColMat<usize, f64>) -> Option<SparseLlt> {
        use faer::dyn_stack::{MemBuffer, MemStack};
        use faer::sparse::linalg::cholesky;
        let symbolic = cholesky::factorize_symbolic_cholesky(
            a.symbolic(),
            faer::Side::Lower,
            cholesky::SymmetricOrdering::Amd,
            Default::default(),
        )
        .ok()?;
        let mut l = Vec::new();
        l.try_reserve_exact(symbolic.len_val()).ok()?;
        l.resize(symbolic.len_val(), 0.0);
        let par = faer::Par::Seq;
        let req = symbolic
            .factorize_numeric_llt_scratch::<f64>(par, Default::default())
            .or(symbolic.solve_in_place_scratch::<f64>(1, par));
        let mut buffer = MemBuffer::try_new(req).ok()?;
        symbolic
            .factorize_numeric_llt(
                &mut l,
                a.as_ref(),
                faer::Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut buffer),
                Default::default(),
            )
            .ok()?;
        Some(SparseLlt { symbolic, l })
    }

    /// The solution of `A x = b`, each column of `b`.
    pub(crate) fn solve(&self, b: &Mat<f64>) -> Mat<f64> {
        use faer::dyn_stack::{MemBuffer, MemStack};
        let par = faer::Par::Seq;
        let mut x = b.clone();
        let req = self.symbolic.solve_in_place_scratch::<f64>(b.ncols(), par);
        let mut buffer = MemBuffer::new(req);
        faer::sparse::linalg::cholesky::LltRef::new(&self.symbolic, &self.l)
            .solve_in_place_with_conj(faer::Conj::No, x.as_mut(), par, MemStack::new(&mut buffer));
        x
    }
}

#[cfg(test)]
mod tests {
    use super::{solve3, triangle_from_entries};

    #[test]
    fn solve3_needs_its_pivoting_and_refuses_a_singular_matrix() {
        // The first pivot is zero: without row exchanges the elimination would divide by it.
        let a = [[0.0, 2.0, 1.0], [1.0, 1.0, 0.0], [3.0, 0.0, 1.0]];
        let x = [1.0, -2.0, 0.5];
        let b = [
            a[0][0] * x[0] + a[0][1] * x[1] + a[0][2] * x[2],
            a[1][0] * x[0] + a[1][1] * x[1] + a[1][2] * x[2],
            a[2][0] * x[0] + a[2][1] * x[1] + a[2][2] * x[2],
        ];
        let got = solve3(a, b).expect("regular");
        for i in 0..3 {
            assert!((got[i] - x[i]).abs() < 1e-14, "{got:?}");
        }
        assert!(solve3([[1.0, 2.0, 3.0], [2.0, 4.0, 6.0], [0.0, 1.0, 1.0]], b).is_none());
    }

    #[test]
    fn triangle_from_entries_sums_repeats_sorts_rows_and_refuses_the_other_triangle() {
        // Entries out of order, (2, 0) given three times and (1, 1) twice.
        let entries = [
            (2, 0, 1.5),
            (0, 0, 4.0),
            (1, 1, 2.0),
            (2, 0, 0.25),
            (2, 2, 3.0),
            (1, 0, -1.0),
            (1, 1, 0.5),
            (2, 0, -0.75),
        ];
        let m = triangle_from_entries(3, faer::Side::Lower, |sink| {
            for &(r, c, v) in &entries {
                sink(r, c, v);
            }
        })
        .expect("inside the lower triangle");
        let sym = m.symbolic();
        assert_eq!(sym.col_ptr(), &[0, 3, 4, 5]);
        assert_eq!(sym.row_idx(), &[0, 1, 2, 1, 2]);
        assert_eq!(m.val(), &[4.0, -1.0, 1.0, 2.5, 3.0]);
        // The same entries as an upper triangle, transposed; a lower entry is refused there.
        let up = triangle_from_entries(3, faer::Side::Upper, |sink| {
            for &(r, c, v) in &entries {
                sink(c, r, v);
            }
        })
        .expect("inside the upper triangle");
        assert_eq!(up.symbolic().col_ptr(), &[0, 1, 3, 5]);
        assert_eq!(up.symbolic().row_idx(), &[0, 0, 1, 0, 2]);
        assert_eq!(up.val(), &[4.0, -1.0, 2.5, 1.0, 3.0]);
        assert!(triangle_from_entries(3, faer::Side::Upper, |sink| sink(2, 0, 1.0)).is_none());
        assert!(triangle_from_entries(3, faer::Side::Lower, |sink| sink(3, 0, 1.0)).is_none());
    }
}
