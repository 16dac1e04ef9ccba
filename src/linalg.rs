//! Small dense linear algebra shared by the stages.

use faer::Mat;

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
pub fn jacobi_scaling(diag: impl Iterator<Item = f64>) -> Vec<f64> {
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
