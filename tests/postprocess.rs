//! Post-processing against exact fields (docs/formulation.md §2.1, §2.4 "Interior points", §4,
//! §8.5): boundary data are set from an exact elastic field, no solver runs, and the recovered
//! boundary stresses and interior fields are compared with the same field.
#![allow(clippy::needless_range_loop)]

use sgbem::bem::assembly::scaling;
use sgbem::bem::kernels::{sigma_kernel, u_kernel, Mat2, Material, Vec2};
use sgbem::bem::quadrature::QuadratureSettings;
use sgbem::input::model::{Body, DofClass, Element, Loop, NodeDofs, Role};
use sgbem::post::*;
use sgbem::solution::BodyField;

/// The quadrilateral of docs/formulation.md Appendix A1.
const QUAD: [Vec2; 4] = [[0.0, 0.0], [1.0, 0.0], [1.2, 0.6], [0.1, 0.8]];

/// A body from polygons (outer counter-clockwise, holes clockwise), each side cut into `n`
/// equal elements.
fn polygon_body(loops: &[&[Vec2]], n: usize, young: f64, poisson: f64) -> Body {
    let mut nodes = Vec::new();
    let mut elements = Vec::new();
    let mut lps = Vec::new();
    for (li, verts) in loops.iter().enumerate() {
        let first = nodes.len();
        for (i, p) in verts.iter().enumerate() {
            let q = verts[(i + 1) % verts.len()];
            for k in 0..n {
                let t = k as f64 / n as f64;
                nodes.push([p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])]);
            }
        }
        let count = nodes.len() - first;
        let mut elems = Vec::new();
        let mut area = 0.0;
        for k in 0..count {
            let (a, b) = (first + k, first + (k + 1) % count);
            let (p, q) = (nodes[a], nodes[b]);
            area += 0.5 * (p[0] * q[1] - q[0] * p[1]);
            let len = (q[0] - p[0]).hypot(q[1] - p[1]);
            let tangent = [(q[0] - p[0]) / len, (q[1] - p[1]) / len];
            elems.push(elements.len());
            elements.push(Element {
                nodes: [a, b],
                tag: elements.len() + 1,
                curve: (k / n) as i32 + 1,
                role: Role::Boundary(0),
                length: len,
                tangent,
                normal: [tangent[1], -tangent[0]],
                loop_index: li,
                traction_break: k % n == 0,
                reversed: false,
            });
        }
        lps.push(Loop {
            elements: elems,
            area,
            is_hole: area < 0.0,
        });
    }
    let area = lps.iter().map(|l| l.area).sum();
    let nn = nodes.len();
    Body {
        name: "test".into(),
        young,
        poisson,
        body_force: None,
        body_force_spec: None,
        surfaces: vec![1],
        mesh_nodes: (0..nn).collect(),
        nodes,
        elements,
        loops: lps,
        dofs: vec![
            NodeDofs {
                frame: [[1.0, 0.0], [0.0, 1.0]],
                class: [DofClass::Free; 2],
            };
            nn
        ],
        triangles: Vec::new(),
        area,
    }
}

/// Boundary data of an exact field: nodal displacements and `σn` at every element end.
fn exact_field(body: &Body, u: &dyn Fn(Vec2) -> Vec2, s: &dyn Fn(Vec2) -> Mat2) -> BodyField {
    BodyField {
        u: body.nodes.iter().map(|&p| u(p)).collect(),
        t: body
            .elements
            .iter()
            .map(|e| {
                let n = e.normal;
                let end = |a: usize| {
                    let sg = s(body.nodes[e.nodes[a]]);
                    [
                        sg[0][0] * n[0] + sg[0][1] * n[1],
                        sg[1][0] * n[0] + sg[1][1] * n[1],
                    ]
                };
                [end(0), end(1)]
            })
            .collect(),
        ..Default::default()
    }
}

const G: Mat2 = [[0.3, -0.2], [0.5, -0.1]];
const U0: Vec2 = [0.01, -0.02];

/// Linear field `u = Gx + u0` and its constant stress.
fn linear(m: Material) -> (impl Fn(Vec2) -> Vec2, impl Fn(Vec2) -> Mat2) {
    let s = m.stress_from_gradient(G);
    (
        |x: Vec2| {
            [
                G[0][0] * x[0] + G[0][1] * x[1] + U0[0],
                G[1][0] * x[0] + G[1][1] * x[1] + U0[1],
            ]
        },
        move |_: Vec2| s,
    )
}

/// Field of a Kelvin point force `f` at `y0` (outside the body).
fn kelvin(m: Material, y0: Vec2, f: Vec2) -> (impl Fn(Vec2) -> Vec2, impl Fn(Vec2) -> Mat2) {
    (
        move |x: Vec2| {
            let k = u_kernel(&m, [x[0] - y0[0], x[1] - y0[1]]);
            [
                k[0][0] * f[0] + k[0][1] * f[1],
                k[1][0] * f[0] + k[1][1] * f[1],
            ]
        },
        move |x: Vec2| {
            let k = sigma_kernel(&m, [x[0] - y0[0], x[1] - y0[1]]);
            let mut s = [[0.0; 2]; 2];
            for i in 0..2 {
                for j in 0..2 {
                    s[i][j] = k[i][j][0] * f[0] + k[i][j][1] * f[1];
                }
            }
            s
        },
    )
}

/// Self-weight particular field of docs/formulation.md §4.2 for `b = (0, −γ)`, with the effective ν
/// (so it holds in both planes).
fn self_weight(m: Material, gamma: f64, y0: f64) -> (impl Fn(Vec2) -> Vec2, impl Fn(Vec2) -> Mat2) {
    let (mu, nu) = (m.mu, m.nu);
    (
        move |x: Vec2| {
            let dy = x[1] - y0;
            [
                -nu * gamma * dy * x[0] / (2.0 * mu),
                (1.0 - nu) * gamma * dy * dy / (4.0 * mu) + nu * gamma * x[0] * x[0] / (4.0 * mu),
            ]
        },
        move |x: Vec2| [[0.0, 0.0], [0.0, gamma * (x[1] - y0)]],
    )
}

fn max_abs_mat(s: &Mat2) -> f64 {
    s.iter().flatten().fold(0.0, |m: f64, v| m.max(v.abs()))
}
fn mat_err(a: &Mat2, b: &Mat2) -> f64 {
    let mut e: f64 = 0.0;
    for i in 0..2 {
        for j in 0..2 {
            e = e.max((a[i][j] - b[i][j]).abs());
        }
    }
    e
}
fn vec_err(a: Vec2, b: Vec2) -> f64 {
    (a[0] - b[0]).abs().max((a[1] - b[1]).abs())
}
fn vec_norm(a: Vec2) -> f64 {
    a[0].abs().max(a[1].abs())
}

fn planes() -> [(&'static str, bool); 2] {
    [("plane strain", false), ("plane stress", true)]
}

/// Interior points of the A1 quadrilateral, well inside.
const INSIDE: [Vec2; 4] = [[0.5, 0.4], [0.3, 0.2], [0.9, 0.5], [0.2, 0.6]];

#[test]
fn boundary_stress_reproduces_linear_field() {
    for (name, ps) in planes() {
        let m = Material::new(2.0, 0.3, ps);
        let body = polygon_body(&[&QUAD], 3, 2.0, 0.3);
        let (uf, sf) = linear(m);
        let field = exact_field(&body, &uf, &sf);
        let s0 = sf([0.0, 0.0]);
        let ends = boundary_stress(&body, &m, &field);
        let mut worst: f64 = 0.0;
        for e in &ends {
            for s in e {
                worst = worst.max(mat_err(s, &s0));
            }
        }
        let nodal = nodal_boundary_stress(&body, &m, &field);
        for s in &nodal {
            worst = worst.max(mat_err(s, &s0));
        }
        println!(
            "{name}: boundary stress error {:.1e}",
            worst / max_abs_mat(&s0)
        );
        assert!(worst < 1e-14 * max_abs_mat(&s0), "{name}: {worst:e}");
    }
}

#[test]
fn recovery_uses_the_plane_moduli() {
    // Uniaxial strain along the boundary with σ_nn = 0 gives σ_ss = E'ε_ss: E/(1−ν²) in plane
    // strain, E in plane stress. Side y = 0 of a square, u = (εx, 0) on it, t = 0.
    let (young, poisson, eps) = (3.0, 0.25, 1e-3);
    for (ps, e_prime) in [(false, young / (1.0 - poisson * poisson)), (true, young)] {
        let m = Material::new(young, poisson, ps);
        let body = polygon_body(
            &[&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]],
            1,
            3.0,
            0.25,
        );
        let field = BodyField {
            u: body.nodes.iter().map(|p| [eps * p[0], 0.0]).collect(),
            t: vec![[[0.0; 2]; 2]; 4],
            ..Default::default()
        };
        let s = boundary_stress(&body, &m, &field)[0][0];
        assert!(
            (s[0][0] - e_prime * eps).abs() < 1e-15,
            "{s:?} vs {e_prime}"
        );
        assert!(s[1][1].abs() < 1e-18 && s[0][1].abs() < 1e-18);
        // And σ_ss = ν'σ_nn for a pure normal traction with no tangential strain.
        let field = BodyField {
            u: vec![[0.0; 2]; 4],
            t: vec![[[0.0, -1.0]; 2]; 4],
            ..Default::default()
        };
        let s = boundary_stress(&body, &m, &field)[0][0];
        let nu_prime = if ps {
            poisson
        } else {
            poisson / (1.0 - poisson)
        };
        assert!((s[0][0] - nu_prime).abs() < 1e-15, "{s:?}");
        assert!((s[1][1] - 1.0).abs() < 1e-15);
    }
}

#[test]
fn interior_reproduces_linear_field() {
    let set = QuadratureSettings::standard();
    let hole: [Vec2; 4] = [[0.4, 0.25], [0.4, 0.45], [0.7, 0.45], [0.7, 0.25]];
    for (name, ps) in planes() {
        let m = Material::new(2.0, 0.3, ps);
        let (uf, sf) = linear(m);
        let s0 = sf([0.0, 0.0]);
        for (label, body, points) in [
            ("quad", polygon_body(&[&QUAD], 4, 2.0, 0.3), INSIDE.to_vec()),
            (
                "quad with hole",
                polygon_body(&[&QUAD, &hole], 4, 2.0, 0.3),
                vec![[0.3, 0.2], [0.55, 0.15], [0.9, 0.5], [0.55, 0.6]],
            ),
        ] {
            let field = exact_field(&body, &uf, &sf);
            let sc = scaling(&body);
            let (mut eu, mut es) = (0.0f64, 0.0f64);
            for &x in &points {
                let (u, s) = interior(&body, &m, &field, sc, None, &set, x);
                eu = eu.max(vec_err(u, uf(x)) / vec_norm(uf(x)));
                es = es.max(mat_err(&s, &s0) / max_abs_mat(&s0));
            }
            println!("{name}, {label}: interior relative error u {eu:.1e}, σ {es:.1e}");
            assert!(eu < 1e-10 && es < 1e-10, "{name} {label}: {eu:e} {es:e}");
        }
    }
}

#[test]
fn linear_field_near_the_boundary() {
    // Points at d = f·L_e from the middle of an element, from a node between two elements of a
    // side, and from the corner (0,0) (on its bisector-ish diagonal and along a side). The raw
    // identities lose about ε·(L/d)² to rounding; `interior` is exact throughout, since
    // inside the boundary layer it interpolates between exact boundary values and the
    // identities at a distance ½L_e.
    let set = QuadratureSettings::standard();
    let m = Material::new(1.0, 0.3, false);
    let body = polygon_body(&[&QUAD], 4, 1.0, 0.3);
    let (uf, sf) = linear(m);
    let s0 = sf([0.0, 0.0]);
    let field = exact_field(&body, &uf, &sf);
    let sc = scaling(&body);
    // Bottom side: elements of length L_e = 0.25.
    let le = 0.25;
    for (f, tol_raw) in [
        (3e-1, 1e-13),
        (1e-1, 1e-12),
        (1e-2, 1e-12),
        (1e-3, 1e-10),
        (1e-4, 1e-8),
        (1e-6, 1e-4),
    ] {
        let mut raw = Vec::new();
        let (mut worst, mut worst_u) = (0.0f64, 0.0f64);
        for x in [
            [0.375, f * le],
            [0.5, f * le],
            [f * le, f * le],
            [0.3 * le, f * le],
        ] {
            let (_, s) = somigliana(&body, &m, &field, sc, None, &set, x);
            raw.push(mat_err(&s, &s0) / max_abs_mat(&s0));
            let (u, s) = interior(&body, &m, &field, sc, None, &set, x);
            worst = worst.max(mat_err(&s, &s0) / max_abs_mat(&s0));
            worst_u = worst_u.max(vec_err(u, uf(x)) / vec_norm(uf(x)));
        }
        println!(
            "d = {f:.0e}·L_e: raw σ error {:.1e} {:.1e} {:.1e} {:.1e} (mid, node, corner, side \
             near corner); interior σ {worst:.1e}, u {worst_u:.1e}",
            raw[0], raw[1], raw[2], raw[3]
        );
        let worst_raw = raw.iter().fold(0.0f64, |a, &b| a.max(b));
        assert!(worst_raw < tol_raw, "raw at {f:e}: {worst_raw:e}");
        assert!(worst < 1e-12, "interior at {f:e}: {worst:e}");
        assert!(worst_u < 1e-13, "u at {f:e}: {worst_u:e}");
    }
    // On the boundary itself (and just outside, within tolerance): boundary values.
    for (x, foot) in [
        ([0.375, 0.0], [0.375, 0.0]),
        ([0.0, 0.0], [0.0, 0.0]),
        ([0.375, -1e-12], [0.375, 0.0]),
    ] {
        let (u, s) = interior(&body, &m, &field, sc, None, &set, x);
        assert!(vec_err(u, uf(foot)) < 1e-15 && mat_err(&s, &s0) < 1e-14);
    }
}

/// Least-squares slope of log(err) against log(h).
fn slope(h: &[f64], e: &[f64]) -> f64 {
    let n = h.len() as f64;
    let (lx, ly): (Vec<f64>, Vec<f64>) = h.iter().zip(e).map(|(a, b)| (a.ln(), b.ln())).unzip();
    let mx = lx.iter().sum::<f64>() / n;
    let my = ly.iter().sum::<f64>() / n;
    let num: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    let den: f64 = lx.iter().map(|x| (x - mx).powi(2)).sum();
    num / den
}

#[test]
fn interior_converges_for_kelvin_field() {
    let set = QuadratureSettings::standard();
    for (name, ps) in planes() {
        let m = Material::new(1.0, 0.3, ps);
        let (uf, sf) = kelvin(m, [0.5, -0.35], [1.0, 0.6]);
        let mut hs = Vec::new();
        let (mut eus, mut ess) = (Vec::new(), Vec::new());
        for n in [4, 8, 16, 32, 64] {
            let body = polygon_body(&[&QUAD], n, 1.0, 0.3);
            let field = exact_field(&body, &uf, &sf);
            let sc = scaling(&body);
            let (mut eu, mut es) = (0.0f64, 0.0f64);
            for &x in &INSIDE {
                let (u, s) = interior(&body, &m, &field, sc, None, &set, x);
                eu = eu.max(vec_err(u, uf(x)) / vec_norm(uf(x)));
                es = es.max(mat_err(&s, &sf(x)) / max_abs_mat(&sf(x)));
            }
            println!("{name}, {n:>2} per side: relative error u {eu:.2e}, σ {es:.2e}");
            hs.push(1.0 / n as f64);
            eus.push(eu);
            ess.push(es);
        }
        let (su, ss) = (slope(&hs[1..], &eus[1..]), slope(&hs[1..], &ess[1..]));
        println!("{name}: slopes u {su:.2}, σ {ss:.2}");
        assert!(
            (su - 2.0).abs() < 0.3 && (ss - 2.0).abs() < 0.3,
            "{su} {ss}"
        );
        assert!(ess[4] < 4e-4 && eus[4] < 2e-4, "{ess:?} {eus:?}");
    }
}

/// Worst relative stress error over profiles of points approaching the boundary of the A1
/// quadrilateral (n elements per side) at d = f·L_e, f from 2 down to 0: towards the middle of
/// an element, a node between two elements, the corner (0,0) diagonally, and a side next to
/// that corner. `raw` evaluates the identities without the boundary layer.
fn layer_profile_error(n: usize, raw: bool) -> [f64; 4] {
    let set = QuadratureSettings::standard();
    let m = Material::new(1.0, 0.3, false);
    let (uf, sf) = kelvin(m, [0.5, -0.35], [1.0, 0.6]);
    let body = polygon_body(&[&QUAD], n, 1.0, 0.3);
    let field = exact_field(&body, &uf, &sf);
    let sc = scaling(&body);
    let le = 1.0 / n as f64;
    let scale = max_abs_mat(&sf([0.5, 0.0]));
    let xm = ((0.3 * n as f64).floor() + 0.5) * le;
    let mut worst = [0.0f64; 4];
    for f in [
        2.0, 1.0, 0.7, 0.5, 0.3, 0.2, 0.1, 0.03, 0.01, 1e-3, 1e-4, 0.0,
    ] {
        let points = [
            [xm, f * le],
            [0.5, f * le],
            [f * le, f * le],
            [0.3 * le, f * le],
        ];
        for (k, x) in points.into_iter().enumerate() {
            let (_, s) = if raw && f > 0.0 {
                somigliana(&body, &m, &field, sc, None, &set, x)
            } else {
                interior(&body, &m, &field, sc, None, &set, x)
            };
            worst[k] = worst[k].max(mat_err(&s, &sf(x)) / scale);
        }
    }
    worst
}

#[test]
fn kelvin_field_near_the_boundary() {
    // A field P1 does not represent. The raw identities are only first order within about
    // half an element of the boundary and grow like log(L_e/d) towards nodes and corners
    // (the kinks of the P1 data); `interior` interpolates across that layer between the
    // second-order boundary values and the identities at ½L_e, and keeps second order.
    let mut hs = Vec::new();
    let mut worst = Vec::new();
    for n in [8, 16, 32, 64] {
        let e = layer_profile_error(n, false);
        let r = layer_profile_error(n, true);
        println!(
            "{n:>2} per side, worst σ error near mid-element / node / corner / side at corner: \
             interior {:.1e} {:.1e} {:.1e} {:.1e}; raw {:.1e} {:.1e} {:.1e} {:.1e}",
            e[0], e[1], e[2], e[3], r[0], r[1], r[2], r[3]
        );
        assert!(r[1] > 5.0 * e[1] && r[2] > 4.0 * e[2], "{e:?} {r:?}");
        hs.push(1.0 / n as f64);
        worst.push(e.iter().fold(0.0f64, |a, &b| a.max(b)));
    }
    let sl = slope(&hs, &worst);
    println!("slope of the worst layer error: {sl:.2}");
    assert!(sl > 1.7, "{sl} {worst:?}");
    assert!(worst[3] < 2e-3, "{worst:?}");
}

#[test]
fn body_force_particular_field() {
    // docs/formulation.md §4.2: σ = diag(0, γ(y − y0)) with b = (0, −γ). u is quadratic, so P1 data
    // are not exact and the interior error converges at O(h²); without the body-force terms it
    // stalls at O(1).
    let set = QuadratureSettings::standard();
    let gamma = 2.5;
    for (name, ps) in planes() {
        let m = Material::new(1.0, 0.3, ps);
        let (uf, sf) = self_weight(m, gamma, 0.3);
        let b = Some([0.0, -gamma]);
        let mut hs = Vec::new();
        let (mut eus, mut ess) = (Vec::new(), Vec::new());
        let mut without = 0.0f64;
        for n in [4, 8, 16, 32] {
            let body = polygon_body(&[&QUAD], n, 1.0, 0.3);
            let field = exact_field(&body, &uf, &sf);
            let sc = scaling(&body);
            let (mut eu, mut es) = (0.0f64, 0.0f64);
            for &x in &INSIDE {
                let (u, s) = interior(&body, &m, &field, sc, b, &set, x);
                eu = eu.max(vec_err(u, uf(x)));
                es = es.max(mat_err(&s, &sf(x)));
                let (_, s) = interior(&body, &m, &field, sc, None, &set, x);
                without = without.max(mat_err(&s, &sf(x)));
            }
            // Relative to the largest values over the body: |u| ~ γ/μ·0.25, |σ| ~ γ·0.5.
            let (eu, es) = (eu / (gamma / m.mu * 0.25), es / (gamma * 0.5));
            println!("{name}, {n:>2} per side: relative error u {eu:.2e}, σ {es:.2e}");
            hs.push(1.0 / n as f64);
            eus.push(eu);
            ess.push(es);
        }
        let without = without / (gamma * 0.5);
        let (su, ss) = (slope(&hs[1..], &eus[1..]), slope(&hs[1..], &ess[1..]));
        println!("{name}: slopes u {su:.2}, σ {ss:.2}; without body force σ error {without:.2}");
        assert!(
            (su - 2.0).abs() < 0.3 && (ss - 2.0).abs() < 0.3,
            "{su} {ss}"
        );
        assert!(ess[3] < 1e-4 && eus[3] < 1e-4, "{ess:?} {eus:?}");
        assert!(without > 0.2, "{without}");
    }
}

#[test]
fn same_problem_at_another_position_size_and_orientation() {
    // Boundary data of geometry 1 (Kelvin field plus self-weight, coarse: not exact, not
    // exactly equilibrated) mapped to x₂ = s·Rx₁ + c: u₂ = s·Ru₁, t₂ = Rt₁, b₂ = Rb₁/s. Then
    // u₂(x₂) = s·Ru₁(x₁) and σ₂(x₂) = Rσ₁(x₁)Rᵀ must hold to rounding, which checks every
    // unit factor of the scaled evaluation (L, 1, 1, 1/L, L², L), inside the body and in the
    // boundary layer.
    let set = QuadratureSettings::standard();
    let m = Material::new(1.0, 0.25, false);
    let (uk, sk) = kelvin(m, [0.5, -0.35], [1.0, 0.6]);
    let (uw, sw) = self_weight(m, 1.5, 0.3);
    let uf = |x: Vec2| {
        let (a, b) = (uk(x), uw(x));
        [a[0] + b[0], a[1] + b[1]]
    };
    let sf = |x: Vec2| {
        let (a, b) = (sk(x), sw(x));
        [
            [a[0][0] + b[0][0], a[0][1] + b[0][1]],
            [a[1][0] + b[1][0], a[1][1] + b[1][1]],
        ]
    };
    let b1 = [0.0, -1.5];
    let body1 = polygon_body(&[&QUAD], 3, 1.0, 0.25);
    let field1 = exact_field(&body1, &uf, &sf);
    let (s, c, angle) = (13.7, [250.0, -80.0], 0.7f64);
    let (cs, sn) = (angle.cos(), angle.sin());
    let rot = |v: Vec2| [cs * v[0] - sn * v[1], sn * v[0] + cs * v[1]];
    let map = |p: Vec2| {
        let r = rot(p);
        [s * r[0] + c[0], s * r[1] + c[1]]
    };
    let rot_mat = |a: &Mat2| {
        let r = [[cs, -sn], [sn, cs]];
        let mut out = [[0.0; 2]; 2];
        for i in 0..2 {
            for j in 0..2 {
                for k in 0..2 {
                    for l in 0..2 {
                        out[i][j] += r[i][k] * a[k][l] * r[j][l];
                    }
                }
            }
        }
        out
    };
    let mut body2 = body1.clone();
    for p in &mut body2.nodes {
        *p = map(*p);
    }
    for e in &mut body2.elements {
        e.length *= s;
        e.tangent = rot(e.tangent);
        e.normal = rot(e.normal);
    }
    let field2 = BodyField {
        u: field1
            .u
            .iter()
            .map(|u| {
                let r = rot(*u);
                [s * r[0], s * r[1]]
            })
            .collect(),
        t: field1.t.iter().map(|t| [rot(t[0]), rot(t[1])]).collect(),
        ..Default::default()
    };
    let b2 = rot([b1[0] / s, b1[1] / s]);
    let (sc1, sc2) = (scaling(&body1), scaling(&body2));
    let mut points = INSIDE.to_vec();
    points.extend([[0.6, 1e-5], [0.05, 0.04], [0.6, 0.0]]);
    for x in points {
        let (u1, s1) = interior(&body1, &m, &field1, sc1, Some(b1), &set, x);
        let (u2, s2) = interior(&body2, &m, &field2, sc2, Some(b2), &set, map(x));
        let ru1 = rot(u1);
        let eu = vec_err(u2, [s * ru1[0], s * ru1[1]]) / (s * vec_norm(u1));
        let es = mat_err(&s2, &rot_mat(&s1)) / max_abs_mat(&s1);
        println!("{x:?}: relative difference u {eu:.1e}, σ {es:.1e}");
        assert!(eu < 1e-12 && es < 1e-12, "{x:?}: {eu:e} {es:e}");
    }
    // The discrete data are not exactly in equilibrium, so the additive constant of the
    // single layer is visible: evaluated in physical instead of scaled coordinates, the
    // displacement changes with the size.
    let x = INSIDE[0];
    let (u1, _) = somigliana(&body1, &m, &field1, ([0.0; 2], 1.0), Some(b1), &set, x);
    let (u2, _) = somigliana(&body2, &m, &field2, ([0.0; 2], 1.0), Some(b2), &set, map(x));
    let ru1 = rot(u1);
    let eu = vec_err(u2, [s * ru1[0], s * ru1[1]]) / (s * vec_norm(u1));
    println!("unscaled evaluation: relative difference u {eu:.1e}");
    assert!(eu > 1e-6, "{eu:e}");
}

#[test]
fn nodal_stress_at_corners() {
    // Kelvin field on the quadrilateral: at its four corners the traction fit uses the exact
    // nodal tractions of both sides, the plain average one-sided strains.
    let m = Material::new(1.0, 0.3, false);
    let (uf, sf) = kelvin(m, [0.5, -0.35], [1.0, 0.6]);
    for n in [4, 16] {
        let body = polygon_body(&[&QUAD], n, 1.0, 0.3);
        let field = exact_field(&body, &uf, &sf);
        let ends = boundary_stress(&body, &m, &field);
        let nodal = nodal_boundary_stress(&body, &m, &field);
        let (mut fit, mut avg, mut smooth) = (0.0f64, 0.0f64, 0.0f64);
        let mut meeting = vec![Vec::new(); body.nodes.len()];
        for (ei, e) in body.elements.iter().enumerate() {
            meeting[e.nodes[0]].push((ei, 0));
            meeting[e.nodes[1]].push((ei, 1));
        }
        for (node, p) in body.nodes.iter().enumerate() {
            let exact = sf(*p);
            let scale = max_abs_mat(&exact);
            let err = mat_err(&nodal[node], &exact) / scale;
            if node % n == 0 {
                fit = fit.max(err);
                let mut a = [[0.0; 2]; 2];
                for &(ei, end) in &meeting[node] {
                    for i in 0..2 {
                        for j in 0..2 {
                            a[i][j] += 0.5 * ends[ei][end][i][j];
                        }
                    }
                }
                avg = avg.max(mat_err(&a, &exact) / scale);
            } else {
                smooth = smooth.max(err);
            }
        }
        println!(
            "{n:>2} per side: corner error, fit {fit:.1e} / average {avg:.1e}; \
             smooth nodes {smooth:.1e}"
        );
        assert!(fit < 1e-13, "{fit:e}");
        assert!(avg > 1e3 * fit);
    }
}

/// A square [0,1]² meshed by a structured grid of right triangles; returns the body (its
/// boundary nodes referring to the grid) and the grid nodes.
fn grid_body(n: usize, young: f64, poisson: f64) -> (Body, Vec<Vec2>) {
    let sq: [Vec2; 4] = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    let mut body = polygon_body(&[&sq], n, young, poisson);
    let id = |i: usize, j: usize| j * (n + 1) + i;
    let mut grid = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            grid.push([i as f64 / n as f64, j as f64 / n as f64]);
        }
    }
    body.mesh_nodes = body
        .nodes
        .iter()
        .map(|p| {
            let (i, j) = (
                (p[0] * n as f64).round() as usize,
                (p[1] * n as f64).round() as usize,
            );
            id(i, j)
        })
        .collect();
    for j in 0..n {
        for i in 0..n {
            body.triangles
                .push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            body.triangles
                .push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (body, grid)
}

#[test]
fn field_at_triangle_nodes() {
    let set = QuadratureSettings::standard();
    let n = 6;
    for (name, ps) in planes() {
        let m = Material::new(1.0, 0.3, ps);
        let (body, grid) = grid_body(n, 1.0, 0.3);
        // Linear field: every node exact, boundary nodes included.
        let (uf, sf) = linear(m);
        let field = exact_field(&body, &uf, &sf);
        let input = BodyInput {
            body: &body,
            material: m,
            field: &field,
            body_force: None,
        };
        let values = field_at_nodes(&input, &set, &grid);
        assert_eq!(values.len(), grid.len());
        let s0 = sf([0.0, 0.0]);
        let (mut eu, mut es) = (0.0f64, 0.0f64);
        for (k, v) in values.iter().enumerate() {
            assert_eq!(v.mesh_node, k, "one entry per mesh node, in order");
            let x = grid[k];
            eu = eu.max(vec_err(v.u, uf(x)) / vec_norm(uf(x)));
            es = es.max(mat_err(&v.sigma, &s0) / max_abs_mat(&s0));
        }
        println!("{name}: linear field at triangle nodes, relative error u {eu:.1e}, σ {es:.1e}");
        assert!(eu < 1e-12 && es < 1e-11, "{eu:e} {es:e}");

        // Kelvin field: boundary nodes take exactly the boundary values, the others exactly
        // what `interior` gives.
        let (uf, sf) = kelvin(m, [0.5, -0.6], [1.0, 0.6]);
        let field = exact_field(&body, &uf, &sf);
        let input = BodyInput {
            field: &field,
            ..input
        };
        let values = field_at_nodes(&input, &set, &grid);
        let nodal = nodal_boundary_stress(&body, &m, &field);
        let mut interior_err = 0.0f64;
        for v in &values {
            match body.mesh_nodes.iter().position(|&k| k == v.mesh_node) {
                Some(bn) => {
                    assert_eq!(v.u, field.u[bn]);
                    assert_eq!(v.sigma, nodal[bn]);
                }
                None => {
                    let x = grid[v.mesh_node];
                    let (u, s) = interior(&body, &m, &field, scaling(&body), None, &set, x);
                    assert_eq!((v.u, v.sigma), (u, s));
                    interior_err = interior_err.max(mat_err(&s, &sf(x)) / max_abs_mat(&sf(x)));
                }
            }
        }
        println!(
            "{name}: Kelvin field at interior triangle nodes, relative σ error {interior_err:.1e}"
        );
        assert!(interior_err < 3e-2, "{interior_err:e}");
    }
}

/// A = [0,1]×[0,0.5] (E = 1, ν = 0.3) and B = [0,1]×[0.5,1] (E = 5, ν = 0.2) with a hole
/// [0.4,0.6]×[0.7,0.8], n elements per side, with their materials.
fn two_bodies(n: usize) -> (Body, Body, Material, Material) {
    let a = polygon_body(
        &[&[[0.0, 0.0], [1.0, 0.0], [1.0, 0.5], [0.0, 0.5]]],
        n,
        1.0,
        0.3,
    );
    let hole: [Vec2; 4] = [[0.4, 0.7], [0.4, 0.8], [0.6, 0.8], [0.6, 0.7]];
    let b = polygon_body(
        &[&[[0.0, 0.5], [1.0, 0.5], [1.0, 1.0], [0.0, 1.0]], &hole],
        n,
        5.0,
        0.2,
    );
    let (ma, mb) = (
        Material::new(1.0, 0.3, false),
        Material::new(5.0, 0.2, false),
    );
    (a, b, ma, mb)
}

#[test]
fn points_are_located_in_bodies() {
    let set = QuadratureSettings::standard();
    // Different materials, each with the exact linear field of its own stiffness.
    let (a, b, ma, mb) = two_bodies(4);
    let (ua, sa) = linear(ma);
    let (ub, sb) = linear(mb);
    let (fa, fb) = (exact_field(&a, &ua, &sa), exact_field(&b, &ub, &sb));
    let inputs = [
        BodyInput {
            body: &a,
            material: ma,
            field: &fa,
            body_force: None,
        },
        BodyInput {
            body: &b,
            material: mb,
            field: &fb,
            body_force: None,
        },
    ];
    let pts = [
        [0.3, 0.2],         // A
        [0.3, 0.9],         // B
        [0.5, 0.5],         // on the interface: A, the first body
        [0.5, 0.75],        // in the hole of B: none
        [1.2, 0.3],         // outside: none
        [1.0 + 1e-12, 0.3], // on A's boundary within tolerance: A
        [0.5, 0.8],         // on the hole's boundary: B
        [0.45, 0.65],       // B, near the hole
    ];
    let want = [
        Some(0),
        Some(1),
        Some(0),
        None,
        None,
        Some(0),
        Some(1),
        Some(1),
    ];
    let got = evaluate_points(&inputs, &set, &pts);
    for ((x, g), w) in pts.iter().zip(&got).zip(want) {
        assert_eq!(g.map(|v| v.body), w, "{x:?}");
        if let Some(v) = g {
            let (uf, s0): (Vec2, Mat2) = if v.body == 0 {
                (ua(*x), sa(*x))
            } else {
                (ub(*x), sb(*x))
            };
            let eu = vec_err(v.u, uf) / vec_norm(uf);
            let es = mat_err(&v.sigma, &s0) / max_abs_mat(&s0);
            assert!(eu < 1e-10 && es < 1e-10, "{x:?}: {eu:e} {es:e}");
        }
    }
    // A section across both bodies and the hole.
    let section = section_points([0.5, 0.1], [0.5, 0.95], 18);
    let vals = evaluate_points(&inputs, &set, &section);
    let bodies: Vec<Option<usize>> = vals.iter().map(|v| v.map(|v| v.body)).collect();
    assert_eq!(bodies[0], Some(0));
    assert_eq!(bodies[17], Some(1));
    assert!(bodies.contains(&None));
}

#[test]
fn a_point_sampler_gives_the_values_of_evaluate_points_for_every_state() {
    // Two bodies with a hole; states with different fields and body forces; points inside,
    // in the boundary layer (rays from elements and from corners), on boundaries, in the
    // hole and outside. The sampler plans and integrates once; its values must be those of
    // evaluate_points bit for bit, state after state.
    let set = QuadratureSettings::standard();
    let (a, b, ma, mb) = two_bodies(6);
    let mut pts = section_points([0.5, -0.1], [0.5, 1.1], 31);
    pts.extend(section_points([0.0, 0.01], [1.0, 0.49], 23));
    pts.extend([
        [0.002, 0.003],
        [0.999, 0.25],
        [0.41, 0.69],
        [0.6, 0.75],
        [1.0, 0.3],
    ]);
    let states: Vec<State> = (0..3)
        .map(|k| {
            let f = [1.0 + k as f64, 0.6 - 0.4 * k as f64];
            let (ua, sa) = kelvin(ma, [0.5, -0.35 - 0.1 * k as f64], f);
            let (ub, sb) = kelvin(mb, [1.3, 1.2], [-0.2, f[0]]);
            let bf = (k == 2).then_some([0.0, -0.7]);
            (exact_field(&a, &ua, &sa), exact_field(&b, &ub, &sb), bf)
        })
        .collect();
    type State = (BodyField, BodyField, Option<Vec2>);
    fn pair<'a>(a: &'a Body, b: &'a Body, m: [Material; 2], st: &'a State) -> [BodyInput<'a>; 2] {
        let (fa, fb, bf) = st;
        [
            BodyInput {
                body: a,
                material: m[0],
                field: fa,
                body_force: *bf,
            },
            BodyInput {
                body: b,
                material: m[1],
                field: fb,
                body_force: *bf,
            },
        ]
    }
    let sampler = PointSampler::new(&pair(&a, &b, [ma, mb], &states[0]), &set, &pts);
    let mut located = 0;
    for st in &states {
        let inputs = pair(&a, &b, [ma, mb], st);
        let got = sampler.evaluate(&inputs);
        let want = evaluate_points(&inputs, &set, &pts);
        assert_eq!(got, want);
        located = want.iter().flatten().count();
    }
    // Some points lie in the hole or outside, most in a body.
    assert!(located > 40 && located < pts.len(), "{located}");
}

#[test]
#[ignore = "timing report, run with --release --ignored --nocapture"]
fn interior_point_timing() {
    use std::hint::black_box;
    use std::time::Instant;
    let set = QuadratureSettings::standard();
    let m = Material::new(1.0, 0.3, false);
    let sq: [Vec2; 4] = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    let body = polygon_body(&[&sq], 100, 1.0, 0.3);
    let (uf, sf) = kelvin(m, [0.5, -0.35], [1.0, 0.6]);
    let field = exact_field(&body, &uf, &sf);
    let sc = scaling(&body);
    for (label, x, b) in [
        ("centre", [0.5, 0.5], None),
        ("centre, body force", [0.5, 0.5], Some([0.0, -1.0])),
        ("0.1·L_e from the boundary", [0.503, 0.001], None),
    ] {
        let reps = 200;
        let t0 = Instant::now();
        for _ in 0..reps {
            black_box(interior(&body, &m, &field, sc, b, &set, black_box(x)));
        }
        let dt = t0.elapsed().as_secs_f64() / reps as f64;
        println!("400 elements, {label}: {:.3} ms per point", dt * 1e3);
    }
}
#[test]
fn boundary_stress_convergence() {
    // Kelvin field: the plain recovery of each element end uses the one-sided strain of its
    // element (first order); the smoothed and nodal values use the centred strain at smooth
    // nodes and the traction fit at corners (second order).
    let m = Material::new(1.0, 0.3, false);
    let (uf, sf) = kelvin(m, [0.5, -0.35], [1.0, 0.6]);
    let scale = max_abs_mat(&sf([0.5, 0.0]));
    let (mut hs, mut plain, mut smooth, mut nodal) = (vec![], vec![], vec![], vec![]);
    for n in [8, 16, 32, 64] {
        let body = polygon_body(&[&QUAD], n, 1.0, 0.3);
        let field = exact_field(&body, &uf, &sf);
        let ends = boundary_stress(&body, &m, &field);
        let sm = smoothed_boundary_stress(&body, &m, &field);
        let nv = nodal_boundary_stress(&body, &m, &field);
        let (mut a, mut b, mut c) = (0.0f64, 0.0f64, 0.0f64);
        for (ei, e) in body.elements.iter().enumerate() {
            for k in 0..2 {
                let exact = sf(body.nodes[e.nodes[k]]);
                a = a.max(mat_err(&ends[ei][k], &exact) / scale);
                b = b.max(mat_err(&sm[ei][k], &exact) / scale);
            }
        }
        for (node, p) in body.nodes.iter().enumerate() {
            c = c.max(mat_err(&nv[node], &sf(*p)) / scale);
        }
        println!("{n:>2} per side: boundary σ error, plain ends {a:.2e}, smoothed ends {b:.2e}, nodes {c:.2e}");
        hs.push(1.0 / n as f64);
        plain.push(a);
        smooth.push(b);
        nodal.push(c);
    }
    let (sp, ss, sn) = (slope(&hs, &plain), slope(&hs, &smooth), slope(&hs, &nodal));
    println!("slopes: plain {sp:.2}, smoothed {ss:.2}, nodal {sn:.2}");
    assert!((sp - 1.0).abs() < 0.2, "{sp}");
    assert!(ss > 1.8 && sn > 1.8, "{ss} {sn}");
}
