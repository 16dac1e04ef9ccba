//! Small 2-vector helpers shared by the stages: points and directions as `[f64; 2]`.

/// `a − b`.
#[inline]
pub(crate) fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

/// `a · b`.
#[inline]
pub(crate) fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

/// The z component of `a × b`.
#[inline]
pub(crate) fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// `|a|`, by `hypot`.
#[inline]
pub(crate) fn norm(a: [f64; 2]) -> f64 {
    a[0].hypot(a[1])
}
