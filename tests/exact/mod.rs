//! Closed-form elastic fields of the analytic benchmarks (docs/formulation.md §9), with the
//! geometry of the scenes that pose them (`pipelines/<name>.toml` on `geo/<name>.geo`), for
//! `tests/convergence.rs`.
//!
//! Every benchmark gives displacement and stress at any point of its domain, its material
//! and body force, and its boundary as named curves oriented with the body on their left,
//! so that the outward normal of a curve is its tangent turned clockwise. The numbers here
//! are the ones the scenes inline into their boundary expressions; the tests check both
//! against each other and the fields against Hooke's law and equilibrium.
#![allow(dead_code)]

use std::f64::consts::FRAC_PI_2;

pub type P2 = [f64; 2];
/// Stress components `[sxx, syy, sxy]`, the column order of the sections CSV.
pub type S3 = [f64; 3];

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Plane {
    Strain,
    Stress,
}

/// A boundary or interface curve: a segment or a circular arc, traversed with the body
/// (the first body, for an interface) on its left.
#[derive(Debug, Clone, Copy)]
pub enum Curve {
    Segment(P2, P2),
    /// Centre, radius, start and end angle (end < start runs clockwise).
    Arc(P2, f64, f64, f64),
}

impl Curve {
    /// Point and outward normal at parameter `s` in [0, 1].
    pub fn at(&self, s: f64) -> (P2, P2) {
        let (p, t) = match *self {
            Curve::Segment(a, b) => {
                let d = [b[0] - a[0], b[1] - a[1]];
                let l = d[0].hypot(d[1]);
                ([a[0] + s * d[0], a[1] + s * d[1]], [d[0] / l, d[1] / l])
            }
            Curve::Arc(c, r, t0, t1) => {
                let th = t0 + s * (t1 - t0);
                let sign = (t1 - t0).signum();
                (
                    [c[0] + r * th.cos(), c[1] + r * th.sin()],
                    [-sign * th.sin(), sign * th.cos()],
                )
            }
        };
        (p, [t[1], -t[0]])
    }

    /// Distance from q to the curve.
    pub fn distance(&self, q: P2) -> f64 {
        match *self {
            Curve::Segment(a, b) => {
                let d = [b[0] - a[0], b[1] - a[1]];
                let s = (((q[0] - a[0]) * d[0] + (q[1] - a[1]) * d[1])
                    / (d[0] * d[0] + d[1] * d[1]))
                    .clamp(0.0, 1.0);
                (q[0] - a[0] - s * d[0]).hypot(q[1] - a[1] - s * d[1])
            }
            Curve::Arc(c, r, t0, t1) => {
                let (lo, hi) = (t0.min(t1), t0.max(t1));
                let th = (q[1] - c[1]).atan2(q[0] - c[0]);
                let rho = (q[0] - c[0]).hypot(q[1] - c[1]);
                if th >= lo && th <= hi {
                    (rho - r).abs()
                } else {
                    let e0 = [c[0] + r * t0.cos(), c[1] + r * t0.sin()];
                    let e1 = [c[0] + r * t1.cos(), c[1] + r * t1.sin()];
                    (q[0] - e0[0])
                        .hypot(q[1] - e0[1])
                        .min((q[0] - e1[0]).hypot(q[1] - e1[1]))
                }
            }
        }
    }
}

/// A named Physical Curve of the mesh: its pieces, and whether it is an interface.
pub struct Part {
    pub name: &'static str,
    pub curves: Vec<Curve>,
    pub interface: bool,
}

fn part(name: &'static str, curves: Vec<Curve>) -> Part {
    Part {
        name,
        curves,
        interface: false,
    }
}

/// A benchmark: exact field, material and geometry.
pub trait Exact: Sync {
    /// The scene and geo name.
    fn name(&self) -> &'static str;
    fn plane(&self) -> Plane;
    /// (body name, young, poisson) of the body containing p.
    fn body(&self, p: P2) -> (&'static str, f64, f64);
    fn body_force(&self, _p: P2) -> P2 {
        [0.0, 0.0]
    }
    fn displacement(&self, p: P2) -> P2;
    fn stress(&self, p: P2) -> S3;
    /// True for points inside the domain (any body).
    fn contains(&self, p: P2) -> bool;
    /// The named curves of the mesh (boundaries and interfaces).
    fn parts(&self) -> Vec<Part>;
    /// A length that sets the scale of the model.
    fn size(&self) -> f64 {
        1.0
    }

    /// Distance from p to the nearest boundary or interface curve.
    fn distance_to_boundary(&self, p: P2) -> f64 {
        self.parts()
            .iter()
            .flat_map(|pt| pt.curves.iter().map(|c| c.distance(p)))
            .fold(f64::INFINITY, f64::min)
    }

    /// Traction σ·n.
    fn traction(&self, p: P2, n: P2) -> P2 {
        let s = self.stress(p);
        [s[0] * n[0] + s[2] * n[1], s[2] * n[0] + s[1] * n[1]]
    }
}

/// Stress from a displacement gradient `g[i][j] = ∂u_i/∂x_j` by Hooke's law.
pub fn hooke(plane: Plane, young: f64, poisson: f64, g: [[f64; 2]; 2]) -> S3 {
    let mu = young / (2.0 * (1.0 + poisson));
    let lambda = match plane {
        Plane::Strain => 2.0 * mu * poisson / (1.0 - 2.0 * poisson),
        Plane::Stress => 2.0 * mu * poisson / (1.0 - poisson),
    };
    let tr = g[0][0] + g[1][1];
    [
        lambda * tr + 2.0 * mu * g[0][0],
        lambda * tr + 2.0 * mu * g[1][1],
        mu * (g[0][1] + g[1][0]),
    ]
}

/// Cartesian stress from polar components at angle θ.
pub fn polar_stress(srr: f64, stt: f64, srt: f64, th: f64) -> S3 {
    let (s, c) = th.sin_cos();
    [
        srr * c * c + stt * s * s - 2.0 * srt * s * c,
        srr * s * s + stt * c * c + 2.0 * srt * s * c,
        (srr - stt) * s * c + srt * (c * c - s * s),
    ]
}

/// Cartesian displacement from polar components at angle θ.
pub fn polar_displacement(ur: f64, ut: f64, th: f64) -> P2 {
    let (s, c) = th.sin_cos();
    [ur * c - ut * s, ur * s + ut * c]
}

/// σ_θθ at p (centre at the origin) from Cartesian stress.
pub fn hoop_stress(p: P2, s: S3) -> f64 {
    let th = p[1].atan2(p[0]);
    let (sn, c) = th.sin_cos();
    s[0] * sn * sn + s[1] * c * c - 2.0 * s[2] * sn * c
}

/// One Lamé ring a < r < b (plane strain) with pressures p_in on r = a and p_out on r = b.
#[derive(Debug, Clone, Copy)]
pub struct Ring {
    pub a: f64,
    pub b: f64,
    pub p_in: f64,
    pub p_out: f64,
    pub young: f64,
    pub poisson: f64,
}

impl Ring {
    /// (A, B) of σ_rr = A − B/r², σ_θθ = A + B/r².
    pub fn coefficients(&self) -> (f64, f64) {
        let (a2, b2) = (self.a * self.a, self.b * self.b);
        (
            (self.p_in * a2 - self.p_out * b2) / (b2 - a2),
            (self.p_in - self.p_out) * a2 * b2 / (b2 - a2),
        )
    }

    pub fn radial_displacement(&self, r: f64) -> f64 {
        let (ca, cb) = self.coefficients();
        let two_mu = self.young / (1.0 + self.poisson);
        ((1.0 - 2.0 * self.poisson) * ca * r + cb / r) / two_mu
    }

    pub fn displacement(&self, p: P2) -> P2 {
        let r = p[0].hypot(p[1]);
        polar_displacement(self.radial_displacement(r), 0.0, p[1].atan2(p[0]))
    }

    pub fn stress(&self, p: P2) -> S3 {
        let (ca, cb) = self.coefficients();
        let r2 = p[0] * p[0] + p[1] * p[1];
        polar_stress(ca - cb / r2, ca + cb / r2, 0.0, p[1].atan2(p[0]))
    }
}

fn in_quarter_ring(p: P2, a: f64, b: f64) -> bool {
    let r = p[0].hypot(p[1]);
    p[0] > 0.0 && p[1] > 0.0 && r > a && r < b
}

/// docs/formulation.md §9.2: the quarter thick cylinder a = 0.5 < r < b = 1, p_i = 10,
/// E = 1000, ν = 0.3.
pub struct Lame {
    pub ring: Ring,
}

impl Default for Lame {
    fn default() -> Self {
        Lame {
            ring: Ring {
                a: 0.5,
                b: 1.0,
                p_in: 10.0,
                p_out: 0.0,
                young: 1000.0,
                poisson: 0.3,
            },
        }
    }
}

impl Exact for Lame {
    fn name(&self) -> &'static str {
        "lame_cylinder"
    }
    fn plane(&self) -> Plane {
        Plane::Strain
    }
    fn body(&self, _p: P2) -> (&'static str, f64, f64) {
        ("cylinder", self.ring.young, self.ring.poisson)
    }
    fn displacement(&self, p: P2) -> P2 {
        self.ring.displacement(p)
    }
    fn stress(&self, p: P2) -> S3 {
        self.ring.stress(p)
    }
    fn contains(&self, p: P2) -> bool {
        in_quarter_ring(p, self.ring.a, self.ring.b)
    }
    fn parts(&self) -> Vec<Part> {
        let (a, b) = (self.ring.a, self.ring.b);
        vec![
            part("bore", vec![Curve::Arc([0.0; 2], a, FRAC_PI_2, 0.0)]),
            part("mantle", vec![Curve::Arc([0.0; 2], b, 0.0, FRAC_PI_2)]),
            part(
                "symmetry",
                vec![
                    Curve::Segment([a, 0.0], [b, 0.0]),
                    Curve::Segment([0.0, b], [0.0, a]),
                ],
            ),
        ]
    }
}

/// docs/formulation.md §9.2 compound cylinder: inner ring a = 0.5 < r < c = 0.75 (E = 1000) bonded
/// to the outer ring c < r < b = 1 (E = 3000), ν = 0.3, p_i = 10, p_o = 0; the interface pressure
/// p_c comes from the continuity of u_r at r = c (105/23 for these numbers).
pub struct Compound {
    pub inner: Ring,
    pub outer: Ring,
}

impl Compound {
    pub fn new(a: f64, c: f64, b: f64, p_in: f64, young: [f64; 2], poisson: f64) -> Self {
        let rings = |pc: f64| {
            (
                Ring {
                    a,
                    b: c,
                    p_in,
                    p_out: pc,
                    young: young[0],
                    poisson,
                },
                Ring {
                    a: c,
                    b,
                    p_in: pc,
                    p_out: 0.0,
                    young: young[1],
                    poisson,
                },
            )
        };
        // u1(c) − u2(c) is affine in p_c: two evaluations give its root.
        let jump = |pc: f64| {
            let (i, o) = rings(pc);
            i.radial_displacement(c) - o.radial_displacement(c)
        };
        let (j0, j1) = (jump(0.0), jump(1.0));
        let (inner, outer) = rings(-j0 / (j1 - j0));
        Compound { inner, outer }
    }

    pub fn interface_pressure(&self) -> f64 {
        self.inner.p_out
    }

    fn ring(&self, p: P2) -> &Ring {
        if p[0].hypot(p[1]) < self.inner.b {
            &self.inner
        } else {
            &self.outer
        }
    }
}

impl Default for Compound {
    fn default() -> Self {
        Compound::new(0.5, 0.75, 1.0, 10.0, [1000.0, 3000.0], 0.3)
    }
}

impl Exact for Compound {
    fn name(&self) -> &'static str {
        "compound_cylinder"
    }
    fn plane(&self) -> Plane {
        Plane::Strain
    }
    fn body(&self, p: P2) -> (&'static str, f64, f64) {
        let r = self.ring(p);
        let name = if std::ptr::eq(r, &self.inner) {
            "inner"
        } else {
            "outer"
        };
        (name, r.young, r.poisson)
    }
    fn displacement(&self, p: P2) -> P2 {
        self.ring(p).displacement(p)
    }
    fn stress(&self, p: P2) -> S3 {
        self.ring(p).stress(p)
    }
    fn contains(&self, p: P2) -> bool {
        in_quarter_ring(p, self.inner.a, self.outer.b)
    }
    fn parts(&self) -> Vec<Part> {
        let (a, c, b) = (self.inner.a, self.inner.b, self.outer.b);
        vec![
            part("bore", vec![Curve::Arc([0.0; 2], a, FRAC_PI_2, 0.0)]),
            part("mantle", vec![Curve::Arc([0.0; 2], b, 0.0, FRAC_PI_2)]),
            part(
                "symmetry_inner",
                vec![
                    Curve::Segment([a, 0.0], [c, 0.0]),
                    Curve::Segment([0.0, c], [0.0, a]),
                ],
            ),
            part(
                "symmetry_outer",
                vec![
                    Curve::Segment([c, 0.0], [b, 0.0]),
                    Curve::Segment([0.0, b], [0.0, c]),
                ],
            ),
            // Oriented for the inner ring, the first body of the interface.
            Part {
                name: "ring",
                curves: vec![Curve::Arc([0.0; 2], c, 0.0, FRAC_PI_2)],
                interface: true,
            },
        ]
    }
}

/// docs/formulation.md §9.3: the quarter plate [0, W]² with the hole r < a, remote
/// σ_xx = S (plane strain).
pub struct Kirsch {
    pub a: f64,
    pub half_width: f64,
    pub remote: f64,
    pub young: f64,
    pub poisson: f64,
}

impl Default for Kirsch {
    fn default() -> Self {
        Kirsch {
            a: 0.2,
            half_width: 1.0,
            remote: 10.0,
            young: 1000.0,
            poisson: 0.3,
        }
    }
}

impl Exact for Kirsch {
    fn name(&self) -> &'static str {
        "kirsch_plate"
    }
    fn plane(&self) -> Plane {
        Plane::Strain
    }
    fn body(&self, _p: P2) -> (&'static str, f64, f64) {
        ("plate", self.young, self.poisson)
    }
    fn displacement(&self, p: P2) -> P2 {
        let (a, s) = (self.a, self.remote);
        let mu = self.young / (2.0 * (1.0 + self.poisson));
        let kappa = 3.0 - 4.0 * self.poisson;
        let r = p[0].hypot(p[1]);
        let th = p[1].atan2(p[0]);
        let (a2, a4) = (a * a, a.powi(4));
        let ur = s / (4.0 * mu)
            * (r * (kappa - 1.0) / 2.0
                + a2 / r
                + (r + (kappa + 1.0) * a2 / r - a4 / r.powi(3)) * (2.0 * th).cos());
        let ut = -s / (4.0 * mu) * (r + (kappa - 1.0) * a2 / r + a4 / r.powi(3)) * (2.0 * th).sin();
        polar_displacement(ur, ut, th)
    }
    fn stress(&self, p: P2) -> S3 {
        let s = self.remote;
        let r = p[0].hypot(p[1]);
        let th = p[1].atan2(p[0]);
        let q2 = (self.a / r).powi(2);
        let q4 = q2 * q2;
        let (c2, s2) = ((2.0 * th).cos(), (2.0 * th).sin());
        let srr = s / 2.0 * (1.0 - q2) + s / 2.0 * (1.0 - 4.0 * q2 + 3.0 * q4) * c2;
        let stt = s / 2.0 * (1.0 + q2) - s / 2.0 * (1.0 + 3.0 * q4) * c2;
        let srt = -s / 2.0 * (1.0 + 2.0 * q2 - 3.0 * q4) * s2;
        polar_stress(srr, stt, srt, th)
    }
    fn contains(&self, p: P2) -> bool {
        let w = self.half_width;
        p[0] > 0.0 && p[1] > 0.0 && p[0] < w && p[1] < w && p[0].hypot(p[1]) > self.a
    }
    fn parts(&self) -> Vec<Part> {
        let (a, w) = (self.a, self.half_width);
        vec![
            part("hole", vec![Curve::Arc([0.0; 2], a, FRAC_PI_2, 0.0)]),
            part(
                "outer",
                vec![
                    Curve::Segment([w, 0.0], [w, w]),
                    Curve::Segment([w, w], [0.0, w]),
                ],
            ),
            part(
                "symmetry",
                vec![
                    Curve::Segment([a, 0.0], [w, 0.0]),
                    Curve::Segment([0.0, w], [0.0, a]),
                ],
            ),
        ]
    }
}

/// docs/formulation.md §9.4: the Timoshenko–Goodier cantilever [0, L] × [−c, c] (plane stress), end
/// load P on x = 0, held at x = L.
pub struct Cantilever {
    pub length: f64,
    pub c: f64,
    pub load: f64,
    pub young: f64,
    pub poisson: f64,
}

impl Default for Cantilever {
    fn default() -> Self {
        Cantilever {
            length: 1.0,
            c: 0.1,
            load: 0.01,
            young: 1000.0,
            poisson: 0.25,
        }
    }
}

impl Cantilever {
    pub fn inertia(&self) -> f64 {
        2.0 * self.c.powi(3) / 3.0
    }

    /// v(0, 0) = P L³/(3EI).
    pub fn tip_deflection(&self) -> f64 {
        self.load * self.length.powi(3) / (3.0 * self.young * self.inertia())
    }
}

impl Exact for Cantilever {
    fn name(&self) -> &'static str {
        "timoshenko_cantilever"
    }
    fn plane(&self) -> Plane {
        Plane::Stress
    }
    fn body(&self, _p: P2) -> (&'static str, f64, f64) {
        ("beam", self.young, self.poisson)
    }
    fn displacement(&self, p: P2) -> P2 {
        let (x, y) = (p[0], p[1]);
        let (pl, l, c, e, nu) = (self.load, self.length, self.c, self.young, self.poisson);
        let i = self.inertia();
        let g = e / (2.0 * (1.0 + nu));
        let u = -pl * x * x * y / (2.0 * e * i) - nu * pl * y.powi(3) / (6.0 * e * i)
            + pl * y.powi(3) / (6.0 * i * g)
            + (pl * l * l / (2.0 * e * i) - pl * c * c / (2.0 * i * g)) * y;
        let v = nu * pl * x * y * y / (2.0 * e * i) + pl * x.powi(3) / (6.0 * e * i)
            - pl * l * l * x / (2.0 * e * i)
            + pl * l.powi(3) / (3.0 * e * i);
        [u, v]
    }
    fn stress(&self, p: P2) -> S3 {
        let i = self.inertia();
        [
            -self.load * p[0] * p[1] / i,
            0.0,
            -self.load * (self.c * self.c - p[1] * p[1]) / (2.0 * i),
        ]
    }
    fn contains(&self, p: P2) -> bool {
        p[0] > 0.0 && p[0] < self.length && p[1].abs() < self.c
    }
    fn parts(&self) -> Vec<Part> {
        let (l, c) = (self.length, self.c);
        vec![
            part("bottom", vec![Curve::Segment([0.0, -c], [l, -c])]),
            part("support", vec![Curve::Segment([l, -c], [l, c])]),
            part("top", vec![Curve::Segment([l, c], [0.0, c])]),
            part("load", vec![Curve::Segment([0.0, c], [0.0, -c])]),
        ]
    }
}

/// A column [−w/2, w/2] × [0, H] under its weight γ (plane strain): σ_yy = γ(y − H),
/// σ_xx = σ_xy = 0, the displacement of docs/formulation.md §4.2 with y0 = H.
pub struct Column {
    pub width: f64,
    pub height: f64,
    pub gamma: f64,
    pub young: f64,
    pub poisson: f64,
}

impl Default for Column {
    fn default() -> Self {
        Column {
            width: 0.5,
            height: 1.0,
            gamma: 10.0,
            young: 1000.0,
            poisson: 0.3,
        }
    }
}

impl Exact for Column {
    fn name(&self) -> &'static str {
        "self_weight_column"
    }
    fn plane(&self) -> Plane {
        Plane::Strain
    }
    fn body(&self, _p: P2) -> (&'static str, f64, f64) {
        ("column", self.young, self.poisson)
    }
    fn body_force(&self, _p: P2) -> P2 {
        [0.0, -self.gamma]
    }
    fn displacement(&self, p: P2) -> P2 {
        let mu = self.young / (2.0 * (1.0 + self.poisson));
        let (nu, g, d) = (self.poisson, self.gamma, p[1] - self.height);
        [
            -nu * g * d * p[0] / (2.0 * mu),
            (1.0 - nu) * g * d * d / (4.0 * mu) + nu * g * p[0] * p[0] / (4.0 * mu),
        ]
    }
    fn stress(&self, p: P2) -> S3 {
        [0.0, self.gamma * (p[1] - self.height), 0.0]
    }
    fn contains(&self, p: P2) -> bool {
        p[0].abs() < self.width / 2.0 && p[1] > 0.0 && p[1] < self.height
    }
    fn parts(&self) -> Vec<Part> {
        let (w, h) = (self.width / 2.0, self.height);
        vec![
            part("base", vec![Curve::Segment([-w, 0.0], [w, 0.0])]),
            part(
                "sides",
                vec![
                    Curve::Segment([w, 0.0], [w, h]),
                    Curve::Segment([-w, h], [-w, 0.0]),
                ],
            ),
            part("top", vec![Curve::Segment([w, h], [-w, h])]),
        ]
    }
}

/// All benchmarks, in the order of the scenes.
pub fn all() -> Vec<Box<dyn Exact>> {
    vec![
        Box::new(Lame::default()),
        Box::new(Compound::default()),
        Box::new(Kirsch::default()),
        Box::new(Cantilever::default()),
        Box::new(Column::default()),
    ]
}
