//! Quadrature rules for the Galerkin double integrals of straight P1 elements.
//!
//! Place in the flow: `kernels` → **`quadrature`** → `galerkin`. Inputs are orders; outputs are
//! plain point/weight tables on the unit interval or unit square, built once and cached.
//!
//! * Gauss–Legendre on \[0,1\] for any order (nodes by Newton iteration on the Legendre
//!   three-term recurrence) — [`gauss`].
//! * Vertex-adjacent element pairs (docs/formulation.md §2.4b): the singularity sits at the corner
//!   (0,0) of the parameter square. Split the square along its diagonal, map each triangle by
//!   Duffy's transformation `(s,t) = (ρ, ρw)` / `(ρw, ρ)` (Jacobian ρ) and grade `ρ = u³`.
//!   A `1/r` integrand becomes smooth and `ln r` becomes `u⁵ ln u`, so n×n Gauss points in
//!   (u, w) converge fast: about 1e-8 / 3e-11 / 1e-13 absolute at n = 6 / 10 / 16 (better
//!   still with quartic grading from n = 8 on, `galerkin::duffy_grading`) —
//!   [`duffy_graded`]. After the map the integrand separates into a function of ρ (handled by
//!   the grading) and one of w whose only near-singularity is a complex pole; acute corners
//!   and unequal lengths bring that pole close to \[0,1\], so the w-interval is bisected
//!   towards it ([`split_towards_pole`]).
//! * A rule graded at both ends of \[0,1\] for integrands with `d ln d` end-point behaviour (the
//!   body-force traction near corners) — [`graded_both_ends`].
//! * [`QuadratureSettings`] groups the orders and the near-pair factor η of §2.4c–d.

use std::sync::OnceLock;

/// Largest order kept in the caches; higher orders are computed on demand by
/// [`gauss_legendre`].
pub const MAX_CACHED_ORDER: usize = 64;

/// A one-dimensional rule on \[0,1\]: `∫₀¹ f ≈ Σ w_i f(x_i)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Rule {
    pub nodes: Vec<f64>,
    pub weights: Vec<f64>,
}

impl Rule {
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// `(node, weight)` pairs.
    pub fn iter(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.nodes.iter().copied().zip(self.weights.iter().copied())
    }
}

/// Legendre polynomial `P_n(x)` and its derivative by the three-term recurrence.
fn legendre(n: usize, x: f64) -> (f64, f64) {
    let mut p0 = 1.0;
    let mut p1 = x;
    for k in 2..=n {
        let kf = k as f64;
        let p2 = ((2.0 * kf - 1.0) * x * p1 - (kf - 1.0) * p0) / kf;
        p0 = p1;
        p1 = p2;
    }
    let nf = n as f64;
    // P_n' = n (x P_n − P_{n−1}) / (x² − 1); never evaluated at ±1.
    (p1, nf * (x * p1 - p0) / (x * x - 1.0))
}

/// n-point Gauss–Legendre rule on \[0,1\], exact for polynomials of degree 2n−1.
///
/// The roots of `P_n` come from Newton iteration started at Tricomi's estimate
/// `cos(π(i − ¼)/(n + ½))`; the nodes are then mapped to \[0,1\] symmetrically so the rule is
/// exactly symmetric about ½.
pub fn gauss_legendre(n: usize) -> Rule {
    assert!(n >= 1, "a Gauss rule needs at least one point");
    let mut nodes = vec![0.0; n];
    let mut weights = vec![0.0; n];
    if n == 1 {
        nodes[0] = 0.5;
        weights[0] = 1.0;
        return Rule { nodes, weights };
    }
    let nf = n as f64;
    for i in 0..n.div_ceil(2) {
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (nf + 0.5)).cos();
        let mut dp = 0.0;
        for _ in 0..100 {
            let (p, d) = legendre(n, x);
            dp = d;
            let dx = p / d;
            x -= dx;
            if dx.abs() <= 1e-16 * x.abs().max(1.0) {
                break;
            }
        }
        // Final derivative at the converged root for the weight 2/((1−x²)P_n'²) on [−1,1].
        let (_, d) = legendre(n, x);
        if d.is_finite() {
            dp = d;
        }
        let w = 1.0 / ((1.0 - x * x) * dp * dp);
        // x > 0 here (or 0 for the middle node of odd n): left node ½(1−x), right ½(1+x).
        nodes[i] = 0.5 * (1.0 - x);
        nodes[n - 1 - i] = 0.5 * (1.0 + x);
        weights[i] = w;
        weights[n - 1 - i] = w;
    }
    Rule { nodes, weights }
}

fn gauss_cache() -> &'static [Rule] {
    static CACHE: OnceLock<Vec<Rule>> = OnceLock::new();
    CACHE.get_or_init(|| (1..=MAX_CACHED_ORDER).map(gauss_legendre).collect())
}

/// Cached n-point Gauss–Legendre rule on \[0,1\] (n ≤ [`MAX_CACHED_ORDER`]).
pub fn gauss(n: usize) -> &'static Rule {
    assert!(
        (1..=MAX_CACHED_ORDER).contains(&n),
        "Gauss order {n} outside the cached range 1..={MAX_CACHED_ORDER}"
    );
    &gauss_cache()[n - 1]
}

/// A two-dimensional rule on the unit square: points `[s, t, weight]`.
#[derive(Debug, Clone, PartialEq)]
pub struct SquareRule {
    pub points: Vec<[f64; 3]>,
}

/// Duffy rule with cubic grading for a singularity at the corner (0,0) of the unit square,
/// n Gauss points in each of u and w and both triangles: 2n² points. (The pair integrator
/// applies the same map with the w-interval split by [`split_towards_pole`].)
///
/// Triangle t ≤ s: `(s,t) = (ρ, ρw)`; triangle s ≤ t: `(s,t) = (ρw, ρ)`; Jacobian ρ;
/// `ρ = u³`, `dρ = 3u² du`, so each weight is `w_u w_w · 3u⁵`. The point set is symmetric
/// under s ↔ t, which keeps the (e,f) and (f,e) integrals mirror images.
pub fn duffy_graded(n: usize) -> SquareRule {
    let g = gauss(n);
    let mut points = Vec::with_capacity(2 * n * n);
    for (u, wu) in g.iter() {
        let rho = u * u * u;
        let jac = 3.0 * u * u * rho;
        for (w, ww) in g.iter() {
            let wt = wu * ww * jac;
            points.push([rho, rho * w, wt]);
            points.push([rho * w, rho, wt]);
        }
    }
    SquareRule { points }
}

/// Bernstein-ellipse parameter of the complex point `z` with respect to the interval
/// `[a, b]`: Gauss–Legendre with n points on `[a, b]` has error `O(ρ^(−2n))` for an integrand
/// analytic inside the ellipse with foci a, b through z.
#[inline]
pub(crate) fn bernstein_rho(z: [f64; 2], a: f64, b: f64) -> f64 {
    let h = 0.5 * (b - a);
    let x = (z[0] - 0.5 * (a + b)) / h;
    let y = z[1] / h;
    // Semi-major axis of the ellipse through (x, y) with foci ±1.
    let semi = 0.5 * ((x - 1.0).hypot(y) + (x + 1.0).hypot(y));
    semi + (semi * semi - 1.0).max(0.0).sqrt()
}

/// Most sub-intervals [`split_towards_pole`] produces.
pub(crate) const MAX_POLE_INTERVALS: usize = 40;

/// Sub-intervals of \[0,1\] produced by [`split_towards_pole`].
#[derive(Debug, Clone, Copy)]
pub struct PoleSplit {
    buf: [(f64, f64); MAX_POLE_INTERVALS],
    len: usize,
}

impl PoleSplit {
    pub(crate) fn intervals(&self) -> &[(f64, f64)] {
        &self.buf[..self.len]
    }
}

/// Bisects \[0,1\] until every piece sees the complex point `pole` (a near-singularity of the
/// integrand) outside its Bernstein ellipse of parameter `rho_min`, so that Gauss rules on
/// the pieces converge at least like `rho_min^(−2n)`. Pieces shorter than 1e-9 are kept as
/// they are; no allocation.
///
/// Used for the angular Duffy variable of vertex-adjacent pairs: there `r = ρ|E_e − w E_f|`
/// (edge vectors as complex numbers) vanishes at `w₀ = E_e/E_f`, which approaches \[0,1\] for
/// acute corners (w₀ near e^{iθ}) and for very unequal lengths (|w₀| ≪ 1).
pub fn split_towards_pole(pole: [f64; 2], rho_min: f64) -> PoleSplit {
    let mut out = PoleSplit {
        buf: [(0.0, 0.0); MAX_POLE_INTERVALS],
        len: 0,
    };
    let mut stack = [(0.0, 0.0); MAX_POLE_INTERVALS];
    stack[0] = (0.0, 1.0);
    let mut top = 1;
    while top > 0 {
        top -= 1;
        let (a, b) = stack[top];
        // Room for this piece's two halves plus everything already pending or produced.
        let room = out.len + top + 2 <= MAX_POLE_INTERVALS;
        if bernstein_rho(pole, a, b) < rho_min && b - a > 1e-9 && room {
            let mid = 0.5 * (a + b);
            stack[top] = (a, mid);
            stack[top + 1] = (mid, b);
            top += 2;
        } else {
            out.buf[out.len] = (a, b);
            out.len += 1;
        }
    }
    out
}

/// n-point rule on \[0,1\] graded towards both ends by the quintic smoothstep
/// `ξ = 10u³ − 15u⁴ + 6u⁵` (`dξ = 30u²(1−u)² du`), for integrands with `d ln d` behaviour
/// at the end points: `ξ ln ξ dξ` becomes `900 u⁵ ln u`, integrated to 3e-8 at n = 10, 1e-10 at
/// n = 16.
pub fn graded_both_ends(n: usize) -> Rule {
    let (nodes, weights) = gauss(n).iter().map(|(u, w)| graded_point(u, w)).unzip();
    Rule { nodes, weights }
}

/// Maps one Gauss point `(u, w)` of \[0,1\] to the [`graded_both_ends`] rule.
#[inline]
pub(crate) fn graded_point(u: f64, w: f64) -> (f64, f64) {
    let v = 1.0 - u;
    (
        u * u * u * (10.0 - 15.0 * u + 6.0 * u * u),
        w * 30.0 * u * u * v * v,
    )
}

/// Orders and tolerances of the element-pair and point-element integration (formulation
/// §2.4, Appendix A: closed-form coincident pairs, Duffy n = 10, η = 2, 10-point leaves).
#[derive(Debug, Clone, PartialEq)]
pub struct QuadratureSettings {
    /// Gauss order in each Duffy variable for vertex-adjacent pairs.
    pub duffy_order: usize,
    /// η: a pair is *near* when its distance is below η·(longer length); near pairs (and
    /// point–element integrals) are bisected until every leaf satisfies the opposite.
    pub near_factor: f64,
    /// Gauss order per element on the leaves of the near-pair bisection.
    pub near_order: usize,
    /// Far-pair orders by distance: the order of an element of length L at distance d is the
    /// order of the first entry whose bound exceeds d/L (the last entry catches the rest).
    pub far_orders: [(f64, usize); 3],
    /// Maximum bisection depth (guards against touching elements that share no node).
    pub max_depth: usize,
}

impl QuadratureSettings {
    /// Cheap rules for previews: operator residuals about 1e-7 relative (patch test on graded
    /// and thin meshes, tests/operators.rs).
    pub fn fast() -> Self {
        QuadratureSettings {
            duffy_order: 6,
            near_factor: 1.5,
            near_order: 6,
            far_orders: [(4.0, 6), (10.0, 4), (f64::INFINITY, 3)],
            max_depth: 12,
        }
    }

    /// The verified default (docs/formulation.md Appendix A): operator residuals about 1e-11
    /// relative.
    pub fn standard() -> Self {
        QuadratureSettings {
            duffy_order: 10,
            near_factor: 2.0,
            near_order: 10,
            far_orders: [(4.0, 8), (8.0, 6), (f64::INFINITY, 4)],
            max_depth: 16,
        }
    }

    /// Rich rules for reference runs: operator residuals about 1e-13 relative.
    pub fn accurate() -> Self {
        QuadratureSettings {
            duffy_order: 16,
            near_factor: 3.0,
            near_order: 12,
            far_orders: [(6.0, 12), (12.0, 8), (f64::INFINITY, 6)],
            max_depth: 20,
        }
    }

    /// Preset by name: `fast`, `standard` or `accurate`.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "fast" => Some(Self::fast()),
            "standard" => Some(Self::standard()),
            "accurate" => Some(Self::accurate()),
            _ => None,
        }
    }

    /// Gauss order for an element of length `length` at distance `distance` from the other
    /// element (or point).
    #[inline]
    pub(crate) fn far_order(&self, distance: f64, length: f64) -> usize {
        let ratio = distance / length;
        for &(bound, order) in &self.far_orders {
            if ratio < bound {
                return order;
            }
        }
        self.far_orders[self.far_orders.len() - 1].1
    }
}

impl Default for QuadratureSettings {
    fn default() -> Self {
        Self::standard()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_integrates_polynomials_exactly() {
        for n in 1..=MAX_CACHED_ORDER {
            let g = gauss(n);
            // ∫₀¹ x^k = 1/(k+1) for k ≤ 2n−1.
            for k in 0..(2 * n).min(40) {
                let s: f64 = g.iter().map(|(x, w)| w * x.powi(k as i32)).sum();
                let exact = 1.0 / (k as f64 + 1.0);
                assert!(
                    (s - exact).abs() <= 4e-15 * (n as f64).sqrt(),
                    "n = {n}, k = {k}: {s} vs {exact}"
                );
            }
            assert!(g.nodes.iter().all(|&x| x > 0.0 && x < 1.0));
            assert!(g.nodes.windows(2).all(|p| p[0] < p[1]));
        }
    }

    #[test]
    fn gauss_known_nodes() {
        let g = gauss(2);
        let x = 0.5 - 0.5 / 3f64.sqrt();
        assert!((g.nodes[0] - x).abs() < 1e-16);
        assert!((g.weights[0] - 0.5).abs() < 1e-15);
        let g = gauss(3);
        assert!((g.nodes[1] - 0.5).abs() < 1e-16);
        assert!((g.weights[1] - 4.0 / 9.0).abs() < 1e-15);
    }

    #[test]
    fn duffy_integrates_corner_singularities() {
        // ∫∫ 1 = 1, ∫∫ 1/√(s²+t²) = 2 asinh(1), ∫∫ ln(s²+t²) = ln 2 − 3 + π/2.
        let r = duffy_graded(10);
        let area: f64 = r.points.iter().map(|p| p[2]).sum();
        assert!((area - 1.0).abs() < 1e-14);
        let inv: f64 = r.points.iter().map(|p| p[2] / p[0].hypot(p[1])).sum();
        assert!((inv - 2.0 * 1f64.asinh()).abs() < 1e-12, "{inv}");
        // ln r becomes 18 u⁵ ln u after the map: algebraic convergence, 7e-10 at n = 10.
        let exact = 2f64.ln() - 3.0 + std::f64::consts::FRAC_PI_2;
        for (n, tol) in [(10, 1e-9), (16, 5e-12), (24, 5e-14)] {
            let lg: f64 = duffy_graded(n)
                .points
                .iter()
                .map(|p| p[2] * (p[0] * p[0] + p[1] * p[1]).ln())
                .sum();
            assert!((lg - exact).abs() < tol, "n = {n}: {lg} vs {exact}");
        }
    }

    #[test]
    fn pole_splitting() {
        // A pole far from [0,1] needs no split; one at 0.3 + 0.01i is bracketed finely.
        assert_eq!(
            split_towards_pole([-1.0, 0.0], 4.0).intervals(),
            &[(0.0, 1.0)]
        );
        let sp = split_towards_pole([0.3, 0.01], 4.0);
        let iv = sp.intervals();
        let total: f64 = iv.iter().map(|(a, b)| b - a).sum();
        assert!((total - 1.0).abs() < 1e-15);
        assert!(iv
            .iter()
            .all(|&(a, b)| bernstein_rho([0.3, 0.01], a, b) >= 4.0));
        // ∫₀¹ dw/((w−0.3)² + 0.01²) = (atan(70) + atan(30))/0.01.
        let g = gauss(10);
        let mut s = 0.0;
        for &(a, b) in iv {
            for (u, w) in g.iter() {
                let x = a + (b - a) * u;
                s += w * (b - a) / ((x - 0.3) * (x - 0.3) + 1e-4);
            }
        }
        let exact = (70f64.atan() + 30f64.atan()) / 0.01;
        assert!((s - exact).abs() < 1e-10 * exact, "{s} vs {exact}");
    }

    #[test]
    fn graded_rule_handles_end_logs() {
        for (n, tol) in [(10, 5e-8), (16, 2e-10)] {
            let r = graded_both_ends(n);
            let s: f64 = r.iter().map(|(x, w)| w * x * x.ln()).sum();
            assert!((s + 0.25).abs() < tol, "n = {n}: {s}");
        }
        let r = graded_both_ends(10);
        let s: f64 = r.iter().map(|(x, w)| w * x * x).sum();
        assert!((s - 1.0 / 3.0).abs() < 1e-15);
    }

    #[test]
    fn presets_by_name() {
        assert_eq!(
            QuadratureSettings::from_name("standard"),
            Some(QuadratureSettings::standard())
        );
        assert!(QuadratureSettings::from_name("fast").is_some());
        assert!(QuadratureSettings::from_name("accurate").is_some());
        assert!(QuadratureSettings::from_name("exact").is_none());
        let s = QuadratureSettings::standard();
        assert_eq!(s.far_order(2.5, 1.0), 8);
        assert_eq!(s.far_order(5.0, 1.0), 6);
        assert_eq!(s.far_order(50.0, 1.0), 4);
    }
}
