//! Body forces by the Galerkin-vector transformation (docs/formulation.md §4, §7 item 8,
//! Appendix A6).
#![allow(clippy::needless_range_loop)]

mod common;

use common::*;
use sgbem::bem::galerkin::{body_force_loads, BodyForceLoads, Segment};
use sgbem::bem::kernels::{
    body_force_displacement, body_force_fields, body_force_gradient, body_force_stress,
    boundary_area, sigma_kernel, u_kernel, Mat2, Material, Vec2,
};
use sgbem::bem::quadrature::{gauss, QuadratureSettings};

fn material() -> Material {
    // Appendix A6: E = 1, ν = 0.3, plane strain, μ = 1/2.6.
    let m = Material::new(1.0, 0.3, false);
    assert!((m.mu - 1.0 / 2.6).abs() < 1e-15);
    m
}

fn quad_segments() -> Vec<Segment> {
    (0..4)
        .map(|i| Segment::new(QUAD[i], QUAD[(i + 1) % 4]))
        .collect()
}

/// Direct domain quadrature of `∫_Ω U(x0,y) b dΩ_y` and `∫_Ω Σ(x0,y) b dΩ_y` over a polygon
/// star-shaped about x0: polar coordinates about x0, one fan per edge, four angular pieces
/// of 30 Gauss points each, and 40 radial points with `ρ = R v⁴` (so `ρ ln ρ dρ` becomes a
/// `v⁷ ln v` integrand).
fn domain_quadrature(m: &Material, x0: Vec2, poly: &[Vec2], b: Vec2) -> (Vec2, Mat2) {
    let gt = gauss(30);
    let gr = gauss(40);
    let mut u = [0.0; 2];
    let mut s = [[0.0; 2]; 2];
    for i in 0..poly.len() {
        let p = poly[i];
        let q = poly[(i + 1) % poly.len()];
        let seg = Segment::new(p, q);
        let n = seg.normal();
        let h = (p[0] - x0[0]) * n[0] + (p[1] - x0[1]) * n[1];
        assert!(h > 0.0, "x0 must see every edge from inside");
        let th_n = n[1].atan2(n[0]);
        let mut a0 = (p[1] - x0[1]).atan2(p[0] - x0[0]);
        let mut a1 = (q[1] - x0[1]).atan2(q[0] - x0[0]);
        // Angles relative to the normal direction, in (−π/2, π/2).
        let wrap = |a: f64| {
            let mut d = a - th_n;
            while d > std::f64::consts::PI {
                d -= 2.0 * std::f64::consts::PI;
            }
            while d < -std::f64::consts::PI {
                d += 2.0 * std::f64::consts::PI;
            }
            d
        };
        a0 = wrap(a0);
        a1 = wrap(a1);
        let pieces = 4;
        for piece in 0..pieces {
            let lo = a0 + (a1 - a0) * piece as f64 / pieces as f64;
            let hi = a0 + (a1 - a0) * (piece + 1) as f64 / pieces as f64;
            for (ut, wt) in gt.iter() {
                let d = lo + (hi - lo) * ut;
                let th = th_n + d;
                let dir = [th.cos(), th.sin()];
                let rmax = h / d.cos();
                let wth = wt * (hi - lo);
                for (v, wv) in gr.iter() {
                    let rho = rmax * v.powi(4);
                    let drho = 4.0 * rmax * v.powi(3) * wv;
                    let r = [-rho * dir[0], -rho * dir[1]];
                    let w = wth * drho * rho;
                    let uk = u_kernel(m, r);
                    let sk = sigma_kernel(m, r);
                    for i in 0..2 {
                        u[i] += w * (uk[i][0] * b[0] + uk[i][1] * b[1]);
                        for j in 0..2 {
                            s[i][j] += w * (sk[i][j][0] * b[0] + sk[i][j][1] * b[1]);
                        }
                    }
                }
            }
        }
    }
    (u, s)
}

#[test]
fn boundary_formula_matches_domain_quadrature() {
    let m = material();
    let segs = quad_segments();
    let b = [0.3, -1.0];
    for x0 in [[0.45, 0.3], [0.9, 0.5], [0.2, 0.65]] {
        let (ud, sd) = domain_quadrature(&m, x0, &QUAD, b);
        let ub = body_force_displacement(&m, x0, &segs, b);
        let sb = body_force_stress(&m, x0, &segs, b);
        let eu = (ub[0] - ud[0]).abs().max((ub[1] - ud[1]).abs()) / ud[0].abs().max(ud[1].abs());
        let mut es: f64 = 0.0;
        let mut ss: f64 = 0.0;
        for i in 0..2 {
            for j in 0..2 {
                es = es.max((sb[i][j] - sd[i][j]).abs());
                ss = ss.max(sd[i][j].abs());
            }
        }
        println!(
            "x0 = {x0:?}: u^b = {ub:?} (rel err {eu:.1e}), σ^b rel err {:.1e}",
            es / ss
        );
        assert!(eu <= 1e-10 && es / ss <= 1e-10, "{eu:e} {:e}", es / ss);
    }
}

#[test]
fn gradient_is_derivative_of_displacement_everywhere() {
    // Fourth-order differences of u^b against the closed-form gradient, inside, next to an
    // edge and a corner (from both sides), and outside.
    let m = material();
    let segs = quad_segments();
    let b = [0.3, -1.0];
    for x in [
        [0.45, 0.3],
        [0.5, 1e-3],
        [0.5, -1e-3],
        [0.02, 0.01],
        [1.0, 0.7],
        [2.0, -1.0],
    ] {
        let h = 1e-4;
        let g = body_force_gradient(&m, x, &segs, b);
        let mut scale: f64 = 0.0;
        let mut err: f64 = 0.0;
        for k in 0..2 {
            let at = |s: f64| {
                let mut y = x;
                y[k] += s * h;
                body_force_displacement(&m, y, &segs, b)
            };
            let (p2, p1, m1, m2) = (at(2.0), at(1.0), at(-1.0), at(-2.0));
            for i in 0..2 {
                let fd = (-p2[i] + 8.0 * p1[i] - 8.0 * m1[i] + m2[i]) / (12.0 * h);
                err = err.max((fd - g[i][k]).abs());
                scale = scale.max(g[i][k].abs());
            }
        }
        println!("x = {x:?}: |FD − ∇u^b| / |∇u^b| = {:.1e}", err / scale);
        assert!(err <= 1e-8 * scale, "{x:?}: {err:e}");
    }
}

#[test]
fn fields_are_continuous_onto_the_boundary() {
    // On an edge and at a vertex the closed forms hit r = 0 and h = 0 exactly; the values must
    // be the limits from inside.
    let m = material();
    let segs = quad_segments();
    let area = boundary_area(&segs);
    let b = [0.3, -1.0];
    for (on, inside) in [
        ([0.5, 0.0], [0.5, 1e-10]),
        ([1.0, 0.0], [1.0 - 1e-10, 1e-10]),
        ([0.1, 0.8], [0.1, 0.8 - 1e-10]),
    ] {
        let (u0, g0) = body_force_fields(&m, on, &segs, b, area);
        let (u1, g1) = body_force_fields(&m, inside, &segs, b, area);
        for i in 0..2 {
            assert!(
                u0[i].is_finite() && (u0[i] - u1[i]).abs() < 1e-9,
                "{on:?}: {u0:?} {u1:?}"
            );
            for k in 0..2 {
                assert!(
                    g0[i][k].is_finite() && (g0[i][k] - g1[i][k]).abs() < 1e-8,
                    "{on:?}: {g0:?} {g1:?}"
                );
            }
        }
    }
    // Shoelace area of the quadrilateral.
    let shoelace: f64 = 0.5
        * (0..4)
            .map(|i| {
                let (p, q) = (QUAD[i], QUAD[(i + 1) % 4]);
                p[0] * q[1] - q[0] * p[1]
            })
            .sum::<f64>();
    assert!((area - shoelace).abs() < 1e-15);
}

/// Particular field of §4.2 for b = (0, −γ): σ^p = diag(0, γ(y − y0)).
fn particular(m: &Material, gamma: f64, y0: f64) -> (impl Fn(Vec2) -> Vec2, impl Fn(Vec2) -> Mat2) {
    let (mu, nu) = (m.mu, m.nu);
    let u = move |x: Vec2| {
        let dy = x[1] - y0;
        [
            -nu * gamma * dy * x[0] / (2.0 * mu),
            (1.0 - nu) * gamma * dy * dy / (4.0 * mu) + nu * gamma * x[0] * x[0] / (4.0 * mu),
        ]
    };
    let s = move |x: Vec2| [[0.0, 0.0], [0.0, gamma * (x[1] - y0)]];
    (u, s)
}

#[test]
fn particular_field_satisfies_navier() {
    // Hooke(∇u^p) = σ^p (the field of §4.2 is consistent), by central differences (exact for
    // a quadratic field).
    let m = material();
    let (uf, sf) = particular(&m, 1.0, 0.3);
    let x = [0.37, 0.61];
    let h = 1e-3;
    let mut g = [[0.0; 2]; 2];
    for k in 0..2 {
        let (mut xp, mut xm) = (x, x);
        xp[k] += h;
        xm[k] -= h;
        let (up, um) = (uf(xp), uf(xm));
        for i in 0..2 {
            g[i][k] = (up[i] - um[i]) / (2.0 * h);
        }
    }
    let s = m.stress_from_gradient(g);
    let want = sf(x);
    for i in 0..2 {
        for j in 0..2 {
            assert!((s[i][j] - want[i][j]).abs() < 1e-12);
        }
    }
}

#[test]
fn body_force_calderon_residuals_converge() {
    // Appendix A6: V t − (½M + K)u + W^b = 0 and D u − (½Mᵀ − Kᵀ)t + P^b = 0 for the particular
    // field of §4.2 with b = (0, −1), y0 = 0.3, on the A1 quadrilateral.
    let m = material();
    let s = QuadratureSettings::standard();
    let b = [0.0, -1.0];
    let (uf, sf) = particular(&m, 1.0, 0.3);
    let (mut hs, mut w1s, mut w2s, mut l1s, mut l2s, mut bare) =
        (vec![], vec![], vec![], vec![], vec![], vec![]);
    for per_side in [2, 4, 8, 16, 32] {
        let lp = Loop::polygon(&QUAD, per_side);
        let ops = assemble(&lp, &m, &s);
        let segs = lp.segments();
        let area = boundary_area(&segs);
        let loads: Vec<BodyForceLoads> = segs
            .iter()
            .map(|e| body_force_loads(&m, e, &segs, b, area, &s))
            .collect();
        let u = nodal_displacement(&lp, &uf);
        let t = element_tractions(&lp, &sf);
        let (mut r1, mut r2) = calderon_residuals(&ops, &u, &t);
        let (b1, b2) = weak_residuals(&lp, &r1, &r2);
        for (e, ld) in loads.iter().enumerate() {
            for a in 0..2 {
                let j = lp.node(e, a);
                for i in 0..2 {
                    r1[4 * e + 2 * a + i] += ld.w[a][i];
                    r2[2 * j + i] += ld.p[a][i];
                }
            }
        }
        let (w1, w2) = weak_residuals(&lp, &r1, &r2);
        let (e1, e2) = (traction_row_norm(&lp, &r1), hat_row_norm(&lp, &r2));
        let l2 = (r1.iter().chain(&r2).map(|v| v * v).sum::<f64>()).sqrt();
        println!("{per_side:>2}/side: weak {w1:.2e} {w2:.2e} | L² {e1:.2e} {e2:.2e} | ℓ² both {l2:.2e} | without b-terms weak {b1:.2e} {b2:.2e}");
        hs.push(1.0 / per_side as f64);
        w1s.push(w1);
        w2s.push(w2);
        l1s.push(e1);
        l2s.push(e2);
        bare.push(b1.max(b2));
    }
    let slopes = [
        loglog_slope(&hs, &w1s),
        loglog_slope(&hs, &w2s),
        loglog_slope(&hs, &l1s),
        loglog_slope(&hs, &l2s),
    ];
    println!(
        "slopes: weak r1 {:.2}, weak r2 {:.2}, L² r1 {:.2}, L² r2 {:.2}",
        slopes[0], slopes[1], slopes[2], slopes[3]
    );
    // Same expectations as for the Kelvin field (tests/operators.rs): O(h²) weakly and for the
    // W-rows in L², O(h^{3/2}) for the P-rows in L².
    for (slope, want) in slopes.iter().zip([2.0, 2.0, 2.0, 1.5]) {
        assert!(
            (slope - want).abs() <= 0.3,
            "slope {slope} vs {want}: {slopes:?}"
        );
    }
    // Without the body-force terms the residuals stall (docs/formulation.md §4.1).
    assert!(bare[bare.len() - 1] > 0.5 * bare[0], "{bare:?}");
}

#[test]
#[ignore = "timing report, run with --ignored --nocapture"]
fn load_timings() {
    let m = material();
    let s = QuadratureSettings::standard();
    let lp = Loop::circle([0.0, 0.0], 0.5, 4000);
    let segs = lp.segments();
    let area = boundary_area(&segs);
    let t0 = std::time::Instant::now();
    let mut acc = 0.0;
    for e in segs.iter().take(200) {
        acc += body_force_loads(&m, e, &segs, [0.0, -1.0], area, &s).p[0][1];
    }
    let dt = t0.elapsed().as_secs_f64() / 200.0;
    println!(
        "body-force loads, 4000-element boundary: {:.2} ms per test element ({acc:.3e})",
        dt * 1e3
    );
}
