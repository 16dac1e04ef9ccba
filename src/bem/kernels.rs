//! Kelvin fundamental solutions of 2D elasticity and the closed-form body-force potentials.
//!
//! Place in the flow: `model` → **`kernels`** → `quadrature` → `galerkin`. This module knows
//! nothing about quadrature: every function is a pointwise kernel or an exact closed form.
//!
//! Conventions (docs/formulation.md §1, §2.1): `x` is the effect (field, test) point, `y` the cause
//! (source, trial) point, `r = x − y`. Plane stress is handled once, in [`Material::new`], by
//! the substitution `ν̄ = ν/(1+ν)`; every formula below then reads as plane strain.
//!
//! * `U_ik = c_U [−(3−4ν) ln r δ_ik + r̂_i r̂_k]` — [`u_kernel`] (G_uu, [paper eq. 1a]).
//! * `Σ_ijk` — stress at x due to a unit force k at y — [`sigma_kernel`].
//! * `G_tu,ik = Σ_ijk n_j(x)` — [`tu_kernel`]; `G_ut = T` (normal at y) — [`t_kernel`].
//! * `S_kij` — stress at x due to a double-layer density k at y — [`s_kernel`] ([paper eq. 1b]).
//! * `B = c_S(−ln r I + r̂r̂ᵀ)` — regularised hypersingular kernel of the by-parts form of
//!   `G_tt` (docs/formulation.md §0.2, §2.3) — [`b_kernel`].
//! * Body forces by the Galerkin-vector transformation (docs/formulation.md §4.1): the domain
//!   integral `∫_Ω U b dΩ` and its gradient become boundary integrals whose integrands are at worst
//!   log-singular. On straight segments these boundary integrals have closed forms, so
//!   [`body_force_displacement`] and [`body_force_gradient`] are exact for any point, including
//!   points on or next to the boundary, with no quadrature at all.

// Index loops mirror the component formulas (δ_ik, r̂_i r̂_k, …) and read better than iterators.
#![allow(clippy::needless_range_loop)]

use std::f64::consts::PI;

/// A 2-vector (position, displacement, traction).
pub type Vec2 = [f64; 2];
/// A 2×2 matrix, indexed `[row][column]`.
pub type Mat2 = [[f64; 2]; 2];
/// A third-order 2D tensor, indexed `[first][second][third]`.
pub(crate) type Tensor3 = [[[f64; 2]; 2]; 2];

/// Isotropic linear elastic material in the plane-strain form used by all kernels.
///
/// `nu` is the *effective* Poisson ratio: the given ν in plane strain, `ν/(1+ν)` in plane
/// stress (docs/formulation.md §1.2). The shear modulus is the same in both.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    pub mu: f64,
    pub nu: f64,
}

impl Material {
    /// Material from Young's modulus and Poisson's ratio.
    ///
    /// `μ = E/(2(1+ν))` always; `plane_stress` replaces ν by `ν/(1+ν)` so that the plane-strain
    /// kernels give the plane-stress fields (the plane-strain λ with ν̄ equals `2μν/(1−ν)`).
    pub fn new(young: f64, poisson: f64, plane_stress: bool) -> Self {
        assert!(young > 0.0, "Young's modulus must be positive, got {young}");
        assert!(
            poisson > -1.0 && poisson < 0.5,
            "Poisson's ratio must lie in (-1, 0.5), got {poisson}"
        );
        let mu = young / (2.0 * (1.0 + poisson));
        let nu = if plane_stress {
            poisson / (1.0 + poisson)
        } else {
            poisson
        };
        Material { mu, nu }
    }

    /// `c_U = 1/(8πμ(1−ν))`, the factor of the Kelvin displacement kernel.
    pub fn c_u(&self) -> f64 {
        1.0 / (8.0 * PI * self.mu * (1.0 - self.nu))
    }

    /// `c_T = 1/(4π(1−ν))`, the factor of the stress and double-layer kernels.
    pub fn c_t(&self) -> f64 {
        1.0 / (4.0 * PI * (1.0 - self.nu))
    }

    /// `c_S = μ/(2π(1−ν))`, the factor of the hypersingular kernels S and B.
    pub fn c_s(&self) -> f64 {
        self.mu / (2.0 * PI * (1.0 - self.nu))
    }

    /// Plane-strain Lamé constant `λ = 2μν/(1−2ν)` (with the effective ν).
    pub fn lambda(&self) -> f64 {
        2.0 * self.mu * self.nu / (1.0 - 2.0 * self.nu)
    }

    /// The body-force constant `κ = (7−8ν)/(16πμ(1−ν))` of the Galerkin-vector identity
    /// (docs/formulation.md §4.1); it exists because U as normalised here has no additive constant.
    pub(crate) fn body_force_kappa(&self) -> f64 {
        (7.0 - 8.0 * self.nu) / (16.0 * PI * self.mu * (1.0 - self.nu))
    }

    /// Hooke's law `σ = λ tr(ε) I + 2μ ε` for a symmetric strain.
    pub fn stress_from_strain(&self, eps: Mat2) -> Mat2 {
        let lt = self.lambda() * (eps[0][0] + eps[1][1]);
        let tm = 2.0 * self.mu;
        [
            [lt + tm * eps[0][0], tm * eps[0][1]],
            [tm * eps[1][0], lt + tm * eps[1][1]],
        ]
    }

    /// Hooke's law applied to a displacement gradient `g[i][k] = ∂u_i/∂x_k`; only its
    /// symmetric part (the strain) matters.
    pub fn stress_from_gradient(&self, g: Mat2) -> Mat2 {
        let shear = 0.5 * (g[0][1] + g[1][0]);
        self.stress_from_strain([[g[0][0], shear], [shear, g[1][1]]])
    }
}

/// `√(a² + b²)`: the kernels' distances, without `hypot`'s guard against overflow (the
/// boundary lies within a unit disk during assembly, and within the model's coordinates,
/// far below 1e150, after it), which costs several times a square root.
#[inline(always)]
pub(crate) fn norm2(a: f64, b: f64) -> f64 {
    (a * a + b * b).sqrt()
}

/// `|r|` and `r̂ = r/|r|`.
#[inline(always)]
fn split(r: Vec2) -> (f64, Vec2) {
    let len = norm2(r[0], r[1]);
    (len, [r[0] / len, r[1] / len])
}

#[inline(always)]
fn delta(i: usize, j: usize) -> f64 {
    if i == j {
        1.0
    } else {
        0.0
    }
}

/// Kelvin displacement kernel `U_ik` (G_uu): displacement i at x due to a unit force k at y.
/// Symmetric in (i,k) and even in r.
#[inline]
pub fn u_kernel(m: &Material, r: Vec2) -> Mat2 {
    let (len, e) = split(r);
    u_kernel_split(m, len, e)
}

#[inline(always)]
fn u_kernel_split(m: &Material, len: f64, e: Vec2) -> Mat2 {
    let c = m.c_u();
    let diag = -(3.0 - 4.0 * m.nu) * len.ln();
    let off = c * e[0] * e[1];
    [
        [c * (diag + e[0] * e[0]), off],
        [off, c * (diag + e[1] * e[1])],
    ]
}

/// Stress kernel `Σ_ijk` (indexed `[i][j][k]`): stress ij at x due to a unit force k at y.
/// A force in +x compresses the material ahead of it: `σ_xx = −(3−2ν)c_T/r` on the +x axis.
#[inline]
pub fn sigma_kernel(m: &Material, r: Vec2) -> Tensor3 {
    let (len, e) = split(r);
    sigma_kernel_split(m, len, e)
}

#[inline(always)]
fn sigma_kernel_split(m: &Material, len: f64, e: Vec2) -> Tensor3 {
    let c = -m.c_t() / len;
    let a = 1.0 - 2.0 * m.nu;
    let mut s = [[[0.0; 2]; 2]; 2];
    for (i, si) in s.iter_mut().enumerate() {
        for (j, sij) in si.iter_mut().enumerate() {
            for (k, sijk) in sij.iter_mut().enumerate() {
                *sijk = c
                    * (a * (delta(i, k) * e[j] + delta(j, k) * e[i] - delta(i, j) * e[k])
                        + 2.0 * e[i] * e[j] * e[k]);
            }
        }
    }
    s
}

/// Adjoint double-layer kernel `G_tu,ik = Σ_ijk n_j(x)`: traction i at x (outward normal
/// `n_x`) due to a unit force k at y. Reciprocity: `G_tu(x,y) = T(y,x)ᵀ`.
#[inline]
pub fn tu_kernel(m: &Material, r: Vec2, n_x: Vec2) -> Mat2 {
    let (len, e) = split(r);
    let c = -m.c_t() / len;
    let a = 1.0 - 2.0 * m.nu;
    let q = e[0] * n_x[0] + e[1] * n_x[1];
    let mut g = [[0.0; 2]; 2];
    for (i, gi) in g.iter_mut().enumerate() {
        for (k, gik) in gi.iter_mut().enumerate() {
            *gik =
                c * (a * (delta(i, k) * q + e[i] * n_x[k] - n_x[i] * e[k]) + 2.0 * e[i] * e[k] * q);
        }
    }
    g
}

/// Double-layer kernel `G_ut,ik = T_ik` (Brebbia's traction kernel) with the outward normal
/// `n_y` at the cause point: displacement i at x due to a unit double-layer density k at y.
/// Integrates to `−I`, `−½I`, `0` for x inside, on a smooth boundary, outside
/// (docs/formulation.md §2.1).
#[inline]
pub fn t_kernel(m: &Material, r: Vec2, n_y: Vec2) -> Mat2 {
    let (len, e) = split(r);
    t_kernel_split(m, len, e, n_y)
}

#[inline(always)]
fn t_kernel_split(m: &Material, len: f64, e: Vec2, n_y: Vec2) -> Mat2 {
    let c = m.c_t() / len;
    let a = 1.0 - 2.0 * m.nu;
    let q = e[0] * n_y[0] + e[1] * n_y[1];
    // The antisymmetric part n_i r̂_k − n_k r̂_i has a single independent entry in 2D.
    let anti = n_y[0] * e[1] - n_y[1] * e[0];
    [
        [
            c * (a * q + 2.0 * e[0] * e[0] * q),
            c * (a * anti + 2.0 * e[0] * e[1] * q),
        ],
        [
            c * (-a * anti + 2.0 * e[1] * e[0] * q),
            c * (a * q + 2.0 * e[1] * e[1] * q),
        ],
    ]
}

/// Hypersingular stress kernel `S_kij` (indexed `[k][i][j]`) with the normal `n_y` at the
/// cause point: stress ij at x due to a unit double-layer density k at y. It enters the stress
/// Somigliana identity with a minus sign, and `S_k = Hooke(∇_x (T e_k))`. `G_tt,ik = S_kij n_j(x)`.
#[inline]
pub fn s_kernel(m: &Material, r: Vec2, n_y: Vec2) -> Tensor3 {
    let (len, e) = split(r);
    s_kernel_split(m, len, e, n_y)
}

#[inline(always)]
fn s_kernel_split(m: &Material, len: f64, e: Vec2, n_y: Vec2) -> Tensor3 {
    let c = m.c_s() / (len * len);
    let nu = m.nu;
    let a = 1.0 - 2.0 * nu;
    let q = e[0] * n_y[0] + e[1] * n_y[1];
    let n = n_y;
    let mut s = [[[0.0; 2]; 2]; 2];
    for (k, sk) in s.iter_mut().enumerate() {
        for (i, ski) in sk.iter_mut().enumerate() {
            for (j, skij) in ski.iter_mut().enumerate() {
                let d_ij = delta(i, j);
                let d_ik = delta(i, k);
                let d_jk = delta(j, k);
                *skij = c
                    * (2.0
                        * q
                        * (a * d_ij * e[k] + nu * (d_ik * e[j] + d_jk * e[i])
                            - 4.0 * e[i] * e[j] * e[k])
                        + 2.0 * nu * (n[i] * e[j] * e[k] + n[j] * e[i] * e[k])
                        + a * (2.0 * n[k] * e[i] * e[j] + n[j] * d_ik + n[i] * d_jk)
                        - (1.0 - 4.0 * nu) * n[k] * d_ij);
            }
        }
    }
    s
}

/// The four kernels of the Somigliana identities at one pair of points, `(U, T, Σ, S)` with
/// the normal `n_y` at the cause point: the values of [`u_kernel`], [`t_kernel`],
/// [`sigma_kernel`] and [`s_kernel`] bit for bit, with `|r|` and `r̂` computed once (the
/// post-processing evaluates all four at every quadrature point).
#[inline]
pub fn point_kernels(m: &Material, r: Vec2, n_y: Vec2) -> (Mat2, Mat2, Tensor3, Tensor3) {
    let (len, e) = split(r);
    (
        u_kernel_split(m, len, e),
        t_kernel_split(m, len, e, n_y),
        sigma_kernel_split(m, len, e),
        s_kernel_split(m, len, e, n_y),
    )
}

/// Regularised hypersingular kernel `B = c_S(−ln r I + r̂r̂ᵀ)`: the Galerkin hypersingular
/// form is `⟨D u, v⟩ = ∫∫ v'(x)ᵀ B(x,y) u'(y)` for displacements continuous around each loop.
#[inline]
pub fn b_kernel(m: &Material, r: Vec2) -> Mat2 {
    let (len, e) = split(r);
    let c = m.c_s();
    let lg = -len.ln();
    let off = c * e[0] * e[1];
    [[c * (lg + e[0] * e[0]), off], [off, c * (lg + e[1] * e[1])]]
}

/// A straight boundary element from `p` to `q` (docs/formulation.md §1.1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    pub p: Vec2,
    pub q: Vec2,
}

impl Segment {
    pub fn new(p: Vec2, q: Vec2) -> Self {
        Segment { p, q }
    }

    /// `Q − P`.
    #[inline]
    pub fn chord(&self) -> Vec2 {
        [self.q[0] - self.p[0], self.q[1] - self.p[1]]
    }

    #[inline]
    pub fn length(&self) -> f64 {
        let c = self.chord();
        norm2(c[0], c[1])
    }

    /// Unit tangent `τ = (Q−P)/L`.
    #[inline]
    pub fn tangent(&self) -> Vec2 {
        let c = self.chord();
        let l = norm2(c[0], c[1]);
        [c[0] / l, c[1] / l]
    }

    /// Outward normal `n = (τ_y, −τ_x)`: outward for counter-clockwise outer loops and
    /// clockwise holes.
    #[inline]
    pub fn normal(&self) -> Vec2 {
        let t = self.tangent();
        [t[1], -t[0]]
    }

    /// `x(ξ) = P + ξ(Q−P)`, ξ ∈ \[0,1\].
    #[inline]
    pub fn point(&self, xi: f64) -> Vec2 {
        [
            self.p[0] + xi * (self.q[0] - self.p[0]),
            self.p[1] + xi * (self.q[1] - self.p[1]),
        ]
    }

    /// The sub-segment between parameters `xi0` and `xi1`.
    #[inline]
    pub fn sub(&self, xi0: f64, xi1: f64) -> Segment {
        Segment {
            p: self.point(xi0),
            q: self.point(xi1),
        }
    }

    /// Euclidean distance from `x` to the closed segment.
    pub(crate) fn distance_to_point(&self, x: Vec2) -> f64 {
        let c = self.chord();
        let w = [x[0] - self.p[0], x[1] - self.p[1]];
        let cc = c[0] * c[0] + c[1] * c[1];
        let s = if cc > 0.0 {
            ((w[0] * c[0] + w[1] * c[1]) / cc).clamp(0.0, 1.0)
        } else {
            0.0
        };
        norm2(w[0] - s * c[0], w[1] - s * c[1])
    }

    /// Distance between two closed segments. Zero if they touch or cross.
    pub(crate) fn distance_to_segment(&self, other: &Segment) -> f64 {
        if segments_cross(self, other) {
            return 0.0;
        }
        self.distance_to_point(other.p)
            .min(self.distance_to_point(other.q))
            .min(other.distance_to_point(self.p))
            .min(other.distance_to_point(self.q))
    }
}

/// Proper crossing test (strict orientation changes on both segments).
fn segments_cross(a: &Segment, b: &Segment) -> bool {
    let orient =
        |p: Vec2, q: Vec2, r: Vec2| (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]);
    let d1 = orient(a.p, a.q, b.p);
    let d2 = orient(a.p, a.q, b.q);
    let d3 = orient(b.p, b.q, a.p);
    let d4 = orient(b.p, b.q, a.q);
    d1 * d2 < 0.0 && d3 * d4 < 0.0
}

/// Area enclosed by the boundary of a body, `|Ω| = ½∮ (x n_x + y n_y) ds` (all loops,
/// outward normals), exact for polygons.
pub fn boundary_area(boundary: &[Segment]) -> f64 {
    boundary
        .iter()
        .map(|s| {
            let mid = s.point(0.5);
            let n = s.normal();
            0.5 * s.length() * (mid[0] * n[0] + mid[1] * n[1])
        })
        .sum()
}

/// Exact integrals over one straight segment of the functions the body-force formulas need.
///
/// With `a = (x−P)·τ`, `h = (x−P)·n` and `u = a − t` (t the arc coordinate from P), the
/// vector `r = x − y = u τ + h n` and `r² = u² + h²`, so every integral is elementary.
struct SegmentMoments {
    /// ∫ ln r ds
    ln: f64,
    /// ∫ u ln r ds
    u_ln: f64,
    /// ∫ u ds
    u: f64,
    /// h ∫ u/r² ds = h (ln|x−P| − ln|x−Q|)
    h_u_r2: f64,
    /// h² ∫ 1/r² ds
    h2_r2: f64,
    /// ∫ u²/r² ds
    u2_r2: f64,
}

/// `ln(u² + h²)`, replaced by 0 where it vanishes: it is only ever multiplied by u, h or
/// u² + h², which are then 0 as well (the limits of `u ln u` and `u² ln u²`).
#[inline]
fn ln_r2(r2: f64) -> f64 {
    if r2 > 0.0 {
        r2.ln()
    } else {
        0.0
    }
}

fn segment_moments(seg: &Segment, x: Vec2) -> (SegmentMoments, f64, f64) {
    let c = seg.chord();
    let len = c[0].hypot(c[1]);
    let tau = [c[0] / len, c[1] / len];
    let n = [tau[1], -tau[0]];
    let w = [x[0] - seg.p[0], x[1] - seg.p[1]];
    let a = w[0] * tau[0] + w[1] * tau[1];
    let h = w[0] * n[0] + w[1] * n[1];
    let ah = h.abs();
    let h2 = h * h;
    // t ∈ [0, L] ↔ u ∈ [a − L, a]; ∫_0^L g(a − t) dt = ∫_{a−L}^{a} g(u) du.
    let (u1, u2) = (a - len, a);
    let (r2_1, r2_2) = (u1 * u1 + h2, u2 * u2 + h2);
    let (lg1, lg2) = (ln_r2(r2_1), ln_r2(r2_2));
    // atan2(u, |h|) is the continuous branch of atan(u/|h|); it is harmless when h = 0
    // because it always appears multiplied by |h|.
    let at = u2.atan2(ah) - u1.atan2(ah);
    // Antiderivative of ln r = ½ ln(u²+h²): ½ u ln(u²+h²) − u + |h| atan(u/|h|).
    let ln = 0.5 * (u2 * lg2 - u1 * lg1) - len + ah * at;
    // Antiderivative of u ln r: ¼((u²+h²) ln(u²+h²) − u²).
    let u_ln = 0.25 * ((r2_2 * lg2 - u2 * u2) - (r2_1 * lg1 - u1 * u1));
    let u = 0.5 * (u2 * u2 - u1 * u1);
    let h_u_r2 = 0.5 * h * (lg2 - lg1);
    let h2_r2 = ah * at;
    let u2_r2 = len - ah * at;
    (
        SegmentMoments {
            ln,
            u_ln,
            u,
            h_u_r2,
            h2_r2,
            u2_r2,
        },
        h,
        len,
    )
}

/// Body-force displacement `u^b(x)` and its gradient `g[i][k] = ∂u^b_i/∂x_k` at once, for a
/// constant body force `b` over the body bounded by `boundary` (all loops, outward normals),
/// whose area is `area` (see [`boundary_area`]).
///
/// docs/formulation.md §4.1 with `n = n(y)`:
/// `u^b_i = (1/8πμ) ∮ (2 ln r + 1)[b_i (r·n) − r_i (b·n)/(2(1−ν))] ds + κ b_i |Ω|` and
/// `∂_k u^b_i = (1/8πμ) ∮ { b_i[(2 ln r + 1) n_k + 2 r̂_k (r̂·n)]
///                         − (b·n)[(2 ln r + 1) δ_ik + 2 r̂_i r̂_k]/(2(1−ν)) } ds`,
/// integrated exactly segment by segment. Valid for x anywhere: inside, on the boundary (where
/// both fields are continuous) and outside (where the formula gives the potential's extension).
pub fn body_force_fields(
    m: &Material,
    x: Vec2,
    boundary: &[Segment],
    b: Vec2,
    area: f64,
) -> (Vec2, Mat2) {
    let c0 = 1.0 / (8.0 * PI * m.mu);
    let c1 = 1.0 / (2.0 * (1.0 - m.nu));
    let mut u = [0.0; 2];
    let mut g = [[0.0; 2]; 2];
    for seg in boundary {
        let (mo, h, len) = segment_moments(seg, x);
        let c = seg.chord();
        let tau = [c[0] / len, c[1] / len];
        let n = [tau[1], -tau[0]];
        let bn = b[0] * n[0] + b[1] * n[1];
        // ∫(2 ln r + 1) and ∫(2 ln r + 1) u.
        let l0 = 2.0 * mo.ln + len;
        let l1 = 2.0 * mo.u_ln + mo.u;
        // r·n = h is constant on the segment; r_i = u τ_i + h n_i.
        for i in 0..2 {
            let r_i_l = tau[i] * l1 + n[i] * h * l0;
            u[i] += c0 * (b[i] * h * l0 - c1 * bn * r_i_l);
        }
        // ∫ r̂_k (r̂·n) = h ∫ r_k/r² = τ_k h∫u/r² + n_k h²∫1/r².
        let rk_q = [
            tau[0] * mo.h_u_r2 + n[0] * mo.h2_r2,
            tau[1] * mo.h_u_r2 + n[1] * mo.h2_r2,
        ];
        for i in 0..2 {
            for k in 0..2 {
                // ∫ r̂_i r̂_k = τ_iτ_k ∫u²/r² + (τ_i n_k + n_i τ_k) h∫u/r² + n_i n_k h²∫1/r².
                let rr = tau[i] * tau[k] * mo.u2_r2
                    + (tau[i] * n[k] + n[i] * tau[k]) * mo.h_u_r2
                    + n[i] * n[k] * mo.h2_r2;
                g[i][k] += c0
                    * (b[i] * (l0 * n[k] + 2.0 * rk_q[k])
                        - c1 * bn * (l0 * delta(i, k) + 2.0 * rr));
            }
        }
    }
    let kappa = m.body_force_kappa();
    u[0] += kappa * b[0] * area;
    u[1] += kappa * b[1] * area;
    (u, g)
}

/// Body-force displacement `u^b(x) = ∫_Ω U(x,y) b dΩ_y` for a constant body force `b`
/// (docs/formulation.md §4.1), by exact boundary integrals over `boundary`.
pub fn body_force_displacement(m: &Material, x: Vec2, boundary: &[Segment], b: Vec2) -> Vec2 {
    body_force_fields(m, x, boundary, b, boundary_area(boundary)).0
}

/// Gradient `g[i][k] = ∂u^b_i/∂x_k` of the body-force displacement (docs/formulation.md §4.1). The
/// log-singular integrand is integrated exactly, so x may lie on or near the boundary.
pub fn body_force_gradient(m: &Material, x: Vec2, boundary: &[Segment], b: Vec2) -> Mat2 {
    body_force_fields(m, x, boundary, b, 0.0).1
}

/// Body-force stress `σ^b = ∫_Ω Σ b dΩ = Hooke(∇u^b)`.
pub fn body_force_stress(m: &Material, x: Vec2, boundary: &[Segment], b: Vec2) -> Mat2 {
    m.stress_from_gradient(body_force_gradient(m, x, boundary, b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn point_kernels_are_the_four_kernels_bit_for_bit() {
        let m = Material::new(210.0, 0.3, true);
        let n = [0.6, -0.8];
        for r in [
            [1.0, 0.0],
            [0.3, -2.0],
            [-1e-7, 3e-8],
            [123.0, 45.6],
            [0.0, -0.5],
        ] {
            let (u, t, sg, s) = point_kernels(&m, r, n);
            assert_eq!(u, u_kernel(&m, r));
            assert_eq!(t, t_kernel(&m, r, n));
            assert_eq!(sg, sigma_kernel(&m, r));
            assert_eq!(s, s_kernel(&m, r, n));
        }
    }
}
