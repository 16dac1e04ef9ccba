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
