//! The updated Cholesky factor of the opening stiffness A_OO (see the module `problem`).

// Index loops mirror the block formulas.
#![allow(clippy::needless_range_loop)]

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
    pub(crate) fn append(&mut self, r: usize, col: &[f64]) -> bool {
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
