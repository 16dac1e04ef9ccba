//! Element-pair Galerkin integrals of the SGBEM operators on straight P1 elements.
//!
//! Place in the flow: `kernels`, `quadrature` → **`galerkin`** → assembly. Inputs are element
//! geometry (with node indices), a [`Material`] and [`QuadratureSettings`]; outputs are the
//! 2×2 blocks of one ordered element pair, which the caller scatters into global matrices.
//!
//! For a test element e (coordinate x, shape functions N_a) and a trial element f (coordinate
//! y, shape functions N_b), a, b ∈ {1, 2} (stored at indices 0, 1), docs/formulation.md §2.3:
//!
//! * `V_ab = ∫_e∫_f N_a(x) U(x,y) N_b(y)` — single layer (G_uu, [paper eq. 10] A_uu);
//! * `K_ab = ∫_e∫_f N_a(x) T(x,y) N_b(y)` — double layer, normal of f (G_ut); the adjoint
//!   block of G_tu is `K'(e,f)_ab = K(f,e)_baᵀ`, so it is never integrated separately;
//! * `D_ab = ∫_e∫_f N_a'(x) B(x,y) N_b'(y)` — regularised hypersingular form with the
//!   arc-length derivatives `N_1' = −1/L`, `N_2' = +1/L` of each element's own direction
//!   (the Galerkin block of G_tt is `−D`);
//! * `M_ab = ∫_e N_a N_b` — [`element_mass`].
//!
//! Pair kinds (docs/formulation.md §2.4), decided by [`classify`] from the caller's node indices:
//! coincident pairs use closed forms; vertex-adjacent pairs the graded Duffy rule, its angular
//! variable split towards the pole that acute corners and unequal lengths bring close; near pairs
//! (distance < η·longer length) recursive bisection of the *longer* element with Gauss leaves;
//! far pairs plain Gauss with orders by distance.
//!
//! Also here: point–element integrals for the Somigliana identities at interior points
//! ([paper eqs. 1a,b], adaptive bisection by distance, docs/formulation.md §8.5), and the Galerkin
//! body-force loads `W^b`, `P^b` of docs/formulation.md §4.1.

// Index loops mirror the component formulas (δ_ik, r̂_i r̂_k, …) and read better than iterators.
#![allow(clippy::needless_range_loop)]

use crate::bem::kernels::{body_force_fields, Mat2, Material, Tensor3, Vec2};
use crate::bem::quadrature::{gauss, graded_point, split_towards_pole, QuadratureSettings, Rule};

pub use crate::bem::kernels::Segment;

/// An element as the pair integrator sees it: its geometry and the caller's indices of its
/// start and end nodes (P, Q).
///
/// Node indices, not coordinates, decide whether two elements share a vertex: nodes of
/// different loops or bodies may coincide in space without being the same node. Indices
/// must be unique within the set of elements that are integrated against each other (one
/// body). If two elements touch geometrically without sharing an index, [`classify`] still
/// treats them as adjacent, because the integrals depend on the geometry only.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ElementRef {
    pub seg: Segment,
    pub nodes: [usize; 2],
}

impl ElementRef {
    pub fn new(seg: Segment, nodes: [usize; 2]) -> Self {
        ElementRef { seg, nodes }
    }
}

/// How an ordered element pair is integrated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PairKind {
    /// e = f: closed forms (docs/formulation.md §2.4a).
    Coincident,
    /// One shared vertex: end `e_end` of e (0 = P, 1 = Q) is end `f_end` of f (§2.4b).
    Adjacent { e_end: usize, f_end: usize },
    /// Distance below η·max(L_e, L_f): bisection (§2.4c).
    Near,
    /// Plain Gauss (§2.4d).
    Far,
}

/// Relative tolerance under which two end points count as the same vertex geometrically.
const TOUCH_TOL: f64 = 1e-12;

/// Classifies the ordered pair (e, f); see [`PairKind`] and [`ElementRef`].
pub fn classify(e: &ElementRef, f: &ElementRef, settings: &QuadratureSettings) -> PairKind {
    if e.nodes == f.nodes {
        return PairKind::Coincident;
    }
    let mut shared = None;
    let mut count = 0;
    for ie in 0..2 {
        for jf in 0..2 {
            if e.nodes[ie] == f.nodes[jf] {
                shared = Some((ie, jf));
                count += 1;
            }
        }
    }
    assert!(
        count < 2,
        "elements {:?} and {:?} join the same two nodes in opposite directions",
        e.nodes,
        f.nodes
    );
    if let Some((e_end, f_end)) = shared {
        return PairKind::Adjacent { e_end, f_end };
    }
    let lmax = e.seg.length().max(f.seg.length());
    let d = e.seg.distance_to_segment(&f.seg);
    if d <= TOUCH_TOL * lmax {
        let ends_e = [e.seg.p, e.seg.q];
        let ends_f = [f.seg.p, f.seg.q];
        for (ie, pe) in ends_e.iter().enumerate() {
            for (jf, pf) in ends_f.iter().enumerate() {
                if (pe[0] - pf[0]).hypot(pe[1] - pf[1]) <= TOUCH_TOL * lmax {
                    return PairKind::Adjacent {
                        e_end: ie,
                        f_end: jf,
                    };
                }
            }
        }
    }
    if d < settings.near_factor * lmax {
        PairKind::Near
    } else {
        PairKind::Far
    }
}

/// The 2×2 blocks of one ordered pair, indexed `[a][b][i][k]`: a = shape function of the
/// test element e, b = shape function of the trial element f, i, k = components.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PairBlocks {
    pub v: [[Mat2; 2]; 2],
    pub k: [[Mat2; 2]; 2],
    pub d: [[Mat2; 2]; 2],
}

/// All blocks of the ordered pair (e, f), with the kind chosen by [`classify`].
pub fn pair_blocks(
    m: &Material,
    e: &ElementRef,
    f: &ElementRef,
    settings: &QuadratureSettings,
) -> PairBlocks {
    let kind = classify(e, f, settings);
    pair_blocks_of_kind(m, &e.seg, &f.seg, kind, settings)
}

/// All blocks of the ordered pair (e, f) integrated as `kind` (for tests and callers that
/// classify themselves).
pub fn pair_blocks_of_kind(
    m: &Material,
    e: &Segment,
    f: &Segment,
    kind: PairKind,
    settings: &QuadratureSettings,
) -> PairBlocks {
    match kind {
        PairKind::Coincident => coincident_blocks(m, e),
        PairKind::Adjacent { e_end, f_end } => {
            adjacent_blocks(m, e, e_end, f, f_end, settings.duffy_order)
        }
        PairKind::Near => {
            let mut acc = Accumulator::default();
            let (le, lf) = (e.length(), f.length());
            near_recursive(&mut acc, e, (0.0, 1.0), le, f, (0.0, 1.0), lf, 0, settings);
            acc.finish(m, le, lf)
        }
        PairKind::Far => {
            let (le, lf) = (e.length(), f.length());
            let d = e.distance_to_segment(f);
            let ge = gauss(settings.far_order(d, le));
            let gf = gauss(settings.far_order(d, lf));
            let mut acc = Accumulator::default();
            acc.gauss_tensor(e, (0.0, 1.0), f, (0.0, 1.0), ge, gf);
            acc.finish(m, le, lf)
        }
    }
}

/// `∫₀¹∫₀¹ N_a(ξ) N_b(η) ln|ξ−η| dξ dη` (docs/formulation.md §2.4a; their sum is −3/2).
pub const LOG_INTEGRALS: [[f64; 2]; 2] = [[-7.0 / 16.0, -5.0 / 16.0], [-5.0 / 16.0, -7.0 / 16.0]];

/// Sign of `N_a' · L`: `N_1' = −1/L`, `N_2' = +1/L`.
const DERIVATIVE_SIGN: [f64; 2] = [-1.0, 1.0];

/// Closed forms for e = f (docs/formulation.md §2.4a). On a straight element `r = L|ξ−η|`,
/// `r̂ = ±τ` and `r̂·n = 0`, so U reduces to log integrals, T to its antisymmetric part
/// `(1−2ν)c_T J/(s−t)` (a CPV whose symmetrised value is `∓L/2` off the diagonal of (a,b)),
/// and B to `∫∫ ln|s−t| = L²(ln L − 3/2)`.
pub fn coincident_blocks(m: &Material, e: &Segment) -> PairBlocks {
    let l = e.length();
    let t = e.tangent();
    let ln_l = l.ln();
    let tt = [[t[0] * t[0], t[0] * t[1]], [t[1] * t[0], t[1] * t[1]]];
    let mut out = PairBlocks::default();
    let cu = m.c_u() * l * l;
    let kap = 3.0 - 4.0 * m.nu;
    let k12 = -m.c_t() * (1.0 - 2.0 * m.nu) * l / 2.0;
    let cs = m.c_s();
    for a in 0..2 {
        for b in 0..2 {
            let diag_v = -kap * (LOG_INTEGRALS[a][b] + 0.25 * ln_l);
            let sab = DERIVATIVE_SIGN[a] * DERIVATIVE_SIGN[b];
            for i in 0..2 {
                for k in 0..2 {
                    let id = if i == k { 1.0 } else { 0.0 };
                    out.v[a][b][i][k] = cu * (diag_v * id + 0.25 * tt[i][k]);
                    out.d[a][b][i][k] = sab * cs * (-(ln_l - 1.5) * id + tt[i][k]);
                }
            }
        }
    }
    // J = [[0, 1], [−1, 0]] for n = (τ_y, −τ_x).
    out.k[0][1] = [[0.0, k12], [-k12, 0.0]];
    out.k[1][0] = [[0.0, -k12], [k12, 0.0]];
    out
}

/// Smallest Bernstein parameter accepted for the angular Duffy variable: Gauss error
/// `≲ 4^(−2n)` relative on each piece (1e-12 at n = 10).
const DUFFY_RHO_MIN: f64 = 4.0;

/// `a / b` for 2-vectors read as complex numbers.
#[inline]
fn complex_div(a: Vec2, b: Vec2) -> Vec2 {
    let bb = b[0] * b[0] + b[1] * b[1];
    [
        (a[0] * b[0] + a[1] * b[1]) / bb,
        (a[1] * b[0] - a[0] * b[1]) / bb,
    ]
}

/// Radial grading exponent p of `ρ = u^p` for a Duffy rule of order n. The `ρ ln ρ` part
/// becomes `p² u^(2p−1) ln u` (smoother for larger p) while the polynomial part has degree
/// `4p − 1`, which n-point Gauss integrates exactly only for n ≥ 2p. Cubic grading (formulation
/// §2.4b) is best up to n = 7; quartic from n = 8 on. Measured on adjacent pairs with entries up
/// to 0.17: max abs error 8.8e-8 (n = 6, cubic), 2.3e-12 (n = 10, quartic; 9.4e-11 cubic),
/// 1.5e-15 (n = 16, quartic; 3.6e-13 cubic).
#[inline]
pub fn duffy_grading(order: usize) -> i32 {
    if order >= 8 {
        4
    } else {
        3
    }
}

/// Vertex-adjacent pair (docs/formulation.md §2.4b): end `e_end` of e coincides with end
/// `f_end` of f.
///
/// Both elements are re-parametrised from the shared vertex V, `x = V + s E_e`,
/// `y = V + t E_f` (E = edge vectors from V), the square is split along its diagonal, and
/// each triangle is mapped by Duffy, `(s,t) = (ρ, ρw)` or `(ρw, ρ)`, with `ρ = u^p`
/// ([`duffy_grading`]); order
/// `order` Gauss in u and in w. Then `r = ρ(E_e − wE_f)` (or `ρ(wE_e − E_f)`): the ρ-part is
/// exact up to the graded `ρ^k ln ρ`, and the w-part is analytic except at the complex point
/// `w₀ = E_e/E_f` (or `E_f/E_e`), towards which the w-interval is bisected
/// ([`split_towards_pole`]). That split is what keeps acute corners and unequal element
/// lengths (a fine interface mesh next to a coarse side) at the accuracy of the plain rule;
/// for the usual obtuse or right-angled, similar-length neighbours it does nothing.
/// `r` is formed from the edge vectors, not by subtracting nearby points, so it keeps full
/// relative precision at the vertex.
pub fn adjacent_blocks(
    m: &Material,
    e: &Segment,
    e_end: usize,
    f: &Segment,
    f_end: usize,
    order: usize,
) -> PairBlocks {
    let edge = |s: &Segment, end: usize| {
        let c = s.chord();
        if end == 0 {
            c
        } else {
            [-c[0], -c[1]]
        }
    };
    let ee = edge(e, e_end);
    let ef = edge(f, f_end);
    let nf = f.normal();
    let g = gauss(order);
    let grading = duffy_grading(order);
    let mut acc = Accumulator::default();
    for lower in [true, false] {
        let pole = if lower {
            complex_div(ee, ef)
        } else {
            complex_div(ef, ee)
        };
        let split = split_towards_pole(pole, DUFFY_RHO_MIN);
        for &(wa, wb) in split.intervals() {
            let hw = wb - wa;
            for (u, wu) in g.iter() {
                let rho = u.powi(grading);
                let jac = grading as f64 * u.powi(grading - 1) * rho * wu * hw;
                for (v, wv) in g.iter() {
                    let w = wa + hw * v;
                    let (s, t) = if lower {
                        (rho, rho * w)
                    } else {
                        (rho * w, rho)
                    };
                    // N at parameter ξ = s from P, or ξ = 1 − s from Q.
                    let na = if e_end == 0 {
                        [1.0 - s, s]
                    } else {
                        [s, 1.0 - s]
                    };
                    let nb = if f_end == 0 {
                        [1.0 - t, t]
                    } else {
                        [t, 1.0 - t]
                    };
                    let r = [s * ee[0] - t * ef[0], s * ee[1] - t * ef[1]];
                    acc.add(r, nf, na, nb, jac * wv);
                }
            }
        }
    }
    acc.finish(m, e.length(), f.length())
}

/// Running sums of the kernel parts over quadrature points in the parameter square
/// (weights are `dξ dη`). Index `ab = 2a + b`. The kernels are split into scalar factors so
/// that one logarithm and one square root serve U, T and B at once.
#[derive(Default)]
struct Accumulator {
    /// Σ w N_a N_b ln r
    ln: [f64; 4],
    /// Σ w N_a N_b r̂r̂ᵀ as (xx, xy, yy)
    rr: [[f64; 3]; 4],
    /// Σ w N_a N_b (r̂·n)/r
    q: [f64; 4],
    /// Σ w N_a N_b (n_x r̂_y − n_y r̂_x)/r
    anti: [f64; 4],
    /// Σ w N_a N_b (r̂·n) r̂r̂ᵀ / r
    qrr: [[f64; 3]; 4],
}

impl Accumulator {
    #[inline(always)]
    fn add(&mut self, r: Vec2, n: Vec2, na: [f64; 2], nb: [f64; 2], w: f64) {
        let r2 = r[0] * r[0] + r[1] * r[1];
        let inv = 1.0 / r2.sqrt();
        let ln = 0.5 * r2.ln();
        let e = [r[0] * inv, r[1] * inv];
        let q = (e[0] * n[0] + e[1] * n[1]) * inv;
        let anti = (n[0] * e[1] - n[1] * e[0]) * inv;
        let ee = [e[0] * e[0], e[0] * e[1], e[1] * e[1]];
        for a in 0..2 {
            for b in 0..2 {
                let ab = 2 * a + b;
                let wab = w * na[a] * nb[b];
                self.ln[ab] += wab * ln;
                self.q[ab] += wab * q;
                self.anti[ab] += wab * anti;
                let wq = wab * q;
                for c in 0..3 {
                    self.rr[ab][c] += wab * ee[c];
                    self.qrr[ab][c] += wq * ee[c];
                }
            }
        }
    }

    /// Tensor Gauss rule over the parameter rectangle `[ξ0,ξ1]×[η0,η1]` of (e, f).
    #[inline]
    fn gauss_tensor(
        &mut self,
        e: &Segment,
        (xi0, xi1): (f64, f64),
        f: &Segment,
        (eta0, eta1): (f64, f64),
        ge: &Rule,
        gf: &Rule,
    ) {
        let he = xi1 - xi0;
        let hf = eta1 - eta0;
        let nf = f.normal();
        for (u, wu) in ge.iter() {
            let xi = xi0 + he * u;
            let x = e.point(xi);
            let na = [1.0 - xi, xi];
            let wx = wu * he * hf;
            for (v, wv) in gf.iter() {
                let eta = eta0 + hf * v;
                let y = f.point(eta);
                let r = [x[0] - y[0], x[1] - y[1]];
                self.add(r, nf, na, [1.0 - eta, eta], wx * wv);
            }
        }
    }

    fn finish(&self, m: &Material, le: f64, lf: f64) -> PairBlocks {
        let jac = le * lf;
        let cu = m.c_u() * jac;
        let ct = m.c_t() * jac;
        let kap = 3.0 - 4.0 * m.nu;
        let a1 = 1.0 - 2.0 * m.nu;
        let mut out = PairBlocks::default();
        let mut bln = 0.0;
        let mut brr = [0.0; 3];
        for a in 0..2 {
            for b in 0..2 {
                let ab = 2 * a + b;
                let rr = self.rr[ab];
                let lg = -kap * self.ln[ab];
                out.v[a][b] = [
                    [cu * (lg + rr[0]), cu * rr[1]],
                    [cu * rr[1], cu * (lg + rr[2])],
                ];
                let qrr = self.qrr[ab];
                let (q, an) = (self.q[ab], self.anti[ab]);
                out.k[a][b] = [
                    [ct * (a1 * q + 2.0 * qrr[0]), ct * (a1 * an + 2.0 * qrr[1])],
                    [ct * (-a1 * an + 2.0 * qrr[1]), ct * (a1 * q + 2.0 * qrr[2])],
                ];
                bln += self.ln[ab];
                for c in 0..3 {
                    brr[c] += rr[c];
                }
            }
        }
        // D_ab = s_a s_b/(L_e L_f) ∫∫ B ds_x ds_y = s_a s_b ∫∫ B dξ dη.
        let cs = m.c_s();
        let bsum = [
            [cs * (-bln + brr[0]), cs * brr[1]],
            [cs * brr[1], cs * (-bln + brr[2])],
        ];
        for a in 0..2 {
            for b in 0..2 {
                let s = DERIVATIVE_SIGN[a] * DERIVATIVE_SIGN[b];
                out.d[a][b] = [
                    [s * bsum[0][0], s * bsum[0][1]],
                    [s * bsum[1][0], s * bsum[1][1]],
                ];
            }
        }
        out
    }
}

/// Recursive bisection for near pairs (docs/formulation.md §2.4c). The parameter intervals refer to
/// the parent elements, so the parent shape functions are evaluated directly on the leaves
/// (the same as carrying them over as combinations of the children's). The longer piece is
/// split; pieces of equal length are split together, which keeps the (e,f) and (f,e)
/// subdivisions mirror images and hence V and D symmetric to rounding.
#[allow(clippy::too_many_arguments)]
fn near_recursive(
    acc: &mut Accumulator,
    e: &Segment,
    ie: (f64, f64),
    le: f64,
    f: &Segment,
    jf: (f64, f64),
    lf: f64,
    depth: usize,
    settings: &QuadratureSettings,
) {
    let se = e.sub(ie.0, ie.1);
    let sf = f.sub(jf.0, jf.1);
    let lse = le * (ie.1 - ie.0);
    let lsf = lf * (jf.1 - jf.0);
    let lmax = lse.max(lsf);
    let d = se.distance_to_segment(&sf);
    if d >= settings.near_factor * lmax || depth >= settings.max_depth {
        let g = gauss(settings.near_order);
        acc.gauss_tensor(e, ie, f, jf, g, g);
        return;
    }
    let split_e = lse >= lsf * (1.0 - 1e-12);
    let split_f = lsf >= lse * (1.0 - 1e-12);
    let halves = |(a, b): (f64, f64)| {
        let mid = 0.5 * (a + b);
        [(a, mid), (mid, b)]
    };
    let (he, hf) = (halves(ie), halves(jf));
    let parts_e = if split_e {
        &he[..]
    } else {
        std::slice::from_ref(&ie)
    };
    let parts_f = if split_f {
        &hf[..]
    } else {
        std::slice::from_ref(&jf)
    };
    for &pe in parts_e {
        for &pf in parts_f {
            near_recursive(acc, e, pe, le, f, pf, lf, depth + 1, settings);
        }
    }
}

/// Consistent mass matrix of one element, `∫ N_a N_b ds = L [[1/3, 1/6], [1/6, 1/3]]`
/// (times I₂ per component pair).
pub fn element_mass(e: &Segment) -> [[f64; 2]; 2] {
    let l = e.length();
    [[l / 3.0, l / 6.0], [l / 6.0, l / 3.0]]
}

/// Point–element integrals for the displacement Somigliana identity at a point x off the
/// element, indexed `[b][i][k]`:
/// `u_i(x) = Σ_f Σ_b (single[b][i][k] t_k^b − double[b][i][k] u_k^b) + u^b_i(x)`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PointDisplacement {
    /// `∫_f U_ik(x,y) N_b(y) ds_y`
    pub single: [Mat2; 2],
    /// `∫_f T_ik(x,y) N_b(y) ds_y` (normal of f)
    pub double: [Mat2; 2],
}

/// Point–element integrals for the stress Somigliana identity ([paper eq. 1b]):
/// `σ_ij(x) = Σ_f Σ_b (single[b][i][j][k] t_k^b − double[b][k][i][j] u_k^b) + σ^b_ij(x)`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PointStress {
    /// `∫_f Σ_ijk(x,y) N_b(y) ds_y`, indexed `[b][i][j][k]`
    pub single: [Tensor3; 2],
    /// `∫_f S_kij(x,y) N_b(y) ds_y`, indexed `[b][k][i][j]`
    pub double: [Tensor3; 2],
}

/// Bisection cap of the point–element rule: resolves points down to about 1e-14·L from the
/// element. Deliberately independent of `max_depth` (which bounds the quadratic cost of pair
/// bisection): here the cost is linear in the depth, and points close to the boundary are
/// the whole purpose (docs/formulation.md §8.5).
const POINT_MAX_DEPTH: usize = 48;

/// Visits the quadrature points `(η, weight in ds)` of an adaptive rule on f for a field
/// point x: f is bisected until every piece lies at a distance of at least η·(its length)
/// from x, then each piece gets the far-pair Gauss order for its distance ratio. The work
/// grows like log(L/d) as x approaches the element, and the accuracy does not degrade.
fn point_rule(
    x: Vec2,
    f: &Segment,
    lf: f64,
    (eta0, eta1): (f64, f64),
    depth: usize,
    settings: &QuadratureSettings,
    visit: &mut impl FnMut(f64, f64),
) {
    let sub = f.sub(eta0, eta1);
    let ls = lf * (eta1 - eta0);
    let d = sub.distance_to_point(x);
    if d >= settings.near_factor * ls || depth >= POINT_MAX_DEPTH {
        let g = gauss(settings.far_order(d, ls));
        for (u, w) in g.iter() {
            visit(eta0 + (eta1 - eta0) * u, w * ls);
        }
        return;
    }
    let mid = 0.5 * (eta0 + eta1);
    point_rule(x, f, lf, (eta0, mid), depth + 1, settings, visit);
    point_rule(x, f, lf, (mid, eta1), depth + 1, settings, visit);
}

/// Displacement-identity integrals of element f at the field point x (x not on f): the
/// first half of [`point_integrals`].
pub fn point_displacement_integrals(
    m: &Material,
    x: Vec2,
    f: &Segment,
    settings: &QuadratureSettings,
) -> PointDisplacement {
    point_integrals(m, x, f, settings).0
}

/// Stress-identity integrals of element f at the field point x (x not on f): the second
/// half of [`point_integrals`].
pub fn point_stress_integrals(
    m: &Material,
    x: Vec2,
    f: &Segment,
    settings: &QuadratureSettings,
) -> PointStress {
    point_integrals(m, x, f, settings).1
}

/// Point–element integrals of both Somigliana identities of element f at the field point x
/// (x not on f), from one pass of the adaptive rule with the four kernels evaluated together
/// ([`crate::bem::kernels::point_kernels`]).
pub fn point_integrals(
    m: &Material,
    x: Vec2,
    f: &Segment,
    settings: &QuadratureSettings,
) -> (PointDisplacement, PointStress) {
    point_integrals_on(m, x, &ElementFrame::new(*f), settings)
}

/// A segment with its unit normal and length, computed once for the many field points of
/// the post-processing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ElementFrame {
    pub segment: Segment,
    pub normal: Vec2,
    pub length: f64,
}

impl ElementFrame {
    pub fn new(segment: Segment) -> Self {
        ElementFrame {
            segment,
            normal: segment.normal(),
            length: segment.length(),
        }
    }
}

/// [`point_integrals`] on an element whose normal and length are known.
pub(crate) fn point_integrals_on(
    m: &Material,
    x: Vec2,
    frame: &ElementFrame,
    settings: &QuadratureSettings,
) -> (PointDisplacement, PointStress) {
    let (f, n, lf) = (&frame.segment, frame.normal, frame.length);
    // r = (x − P) − η(Q − P): the large coordinates cancel once, before the quadrature.
    let xp = [x[0] - f.p[0], x[1] - f.p[1]];
    let c = f.chord();
    let mut pd = PointDisplacement::default();
    let mut ps = PointStress::default();
    point_rule(x, f, lf, (0.0, 1.0), 0, settings, &mut |eta, w| {
        let r = [xp[0] - eta * c[0], xp[1] - eta * c[1]];
        let (u, t, sg, s) = crate::bem::kernels::point_kernels(m, r, n);
        let nb = [1.0 - eta, eta];
        for b in 0..2 {
            let wb = w * nb[b];
            for i in 0..2 {
                for k in 0..2 {
                    pd.single[b][i][k] += wb * u[i][k];
                    pd.double[b][i][k] += wb * t[i][k];
                }
                for j in 0..2 {
                    for k in 0..2 {
                        ps.single[b][i][j][k] += wb * sg[i][j][k];
                        ps.double[b][i][j][k] += wb * s[i][j][k];
                    }
                }
            }
        }
    });
    (pd, ps)
}

/// Galerkin body-force loads of one test element e (docs/formulation.md §4.1), per shape function
/// a: `w[a] = ∫_e N_a u^b ds` (added to W-rows) and `p[a] = ∫_e N_a σ^b n_e ds` (added to P-rows).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BodyForceLoads {
    pub w: [Vec2; 2],
    pub p: [Vec2; 2],
}

/// Body-force loads of test element `e` for a constant body force `b` over the body bounded
/// by `boundary` with area `area` ([`crate::bem::kernels::boundary_area`]).
///
/// `u^b` and `∇u^b` are exact at every point (closed-form segment integrals, see
/// [`body_force_fields`]); along e they are continuous but behave like `d ln d` near corners,
/// so the x-integral uses the Gauss rule of order `near_order` graded towards both ends
/// ([`crate::bem::quadrature::graded_both_ends`]). Cost:
/// `near_order × boundary.len()` closed forms per element.
pub fn body_force_loads(
    m: &Material,
    e: &Segment,
    boundary: &[Segment],
    b: Vec2,
    area: f64,
    settings: &QuadratureSettings,
) -> BodyForceLoads {
    let l = e.length();
    let n = e.normal();
    let mut out = BodyForceLoads::default();
    for (u, wu) in gauss(settings.near_order).iter() {
        let (xi, wxi) = graded_point(u, wu);
        let w = wxi * l;
        let (ub, g) = body_force_fields(m, e.point(xi), boundary, b, area);
        let s = m.stress_from_gradient(g);
        let t = [
            s[0][0] * n[0] + s[0][1] * n[1],
            s[1][0] * n[0] + s[1][1] * n[1],
        ];
        let na = [1.0 - xi, xi];
        for a in 0..2 {
            for i in 0..2 {
                out.w[a][i] += w * na[a] * ub[i];
                out.p[a][i] += w * na[a] * t[i];
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn el(p: Vec2, q: Vec2, nodes: [usize; 2]) -> ElementRef {
        ElementRef::new(Segment::new(p, q), nodes)
    }

    #[test]
    fn classification() {
        let s = QuadratureSettings::standard();
        let a = el([0.0, 0.0], [1.0, 0.0], [0, 1]);
        let b = el([1.0, 0.0], [1.0, 1.0], [1, 2]);
        let c = el([2.5, 0.0], [2.5, 1.0], [5, 6]);
        let d = el([30.0, 0.0], [30.0, 1.0], [7, 8]);
        // Same place as b's end, different index: geometric adjacency.
        let g = el([1.0, 1.0], [0.0, 1.0], [9, 10]);
        assert_eq!(classify(&a, &a, &s), PairKind::Coincident);
        assert_eq!(
            classify(&a, &b, &s),
            PairKind::Adjacent { e_end: 1, f_end: 0 }
        );
        assert_eq!(
            classify(&b, &a, &s),
            PairKind::Adjacent { e_end: 0, f_end: 1 }
        );
        assert_eq!(classify(&a, &c, &s), PairKind::Near);
        assert_eq!(classify(&a, &d, &s), PairKind::Far);
        assert_eq!(
            classify(&b, &g, &s),
            PairKind::Adjacent { e_end: 1, f_end: 0 }
        );
    }

    #[test]
    fn mass_sums_to_length() {
        let e = Segment::new([0.0, 0.0], [3.0, 4.0]);
        let m = element_mass(&e);
        let total: f64 = m.iter().flatten().sum();
        assert!((total - 5.0).abs() < 1e-15);
    }
}
