//! Kernel identities by finite differences (docs/formulation.md §2.1, §7 item 1).
#![allow(clippy::needless_range_loop)]

use sgbem::bem::kernels::{
    b_kernel, s_kernel, sigma_kernel, t_kernel, tu_kernel, u_kernel, Mat2, Material, Vec2,
};

fn materials() -> [Material; 3] {
    [
        Material::new(1.0, 0.3, false),
        Material::new(210e3, 0.2, false),
        Material::new(7.5, 0.3, true),
    ]
}

/// Field points and normals away from the source at the origin.
fn samples() -> Vec<(Vec2, Vec2)> {
    let mut v = Vec::new();
    for (j, rad) in [0.07, 0.4, 1.3, 5.0].iter().enumerate() {
        for i in 0..7 {
            let a = 0.37 + 0.9 * i as f64 + 0.2 * j as f64;
            let na = 1.1 * a + 0.5;
            v.push(([rad * a.cos(), rad * a.sin()], [na.cos(), na.sin()]));
        }
    }
    v
}

/// Fourth-order central difference of a matrix field along direction `dir`.
fn fd(f: &dyn Fn(Vec2) -> Mat2, x: Vec2, dir: usize, h: f64) -> Mat2 {
    let at = |s: f64| {
        let mut y = x;
        y[dir] += s * h;
        f(y)
    };
    let (p2, p1, m1, m2) = (at(2.0), at(1.0), at(-1.0), at(-2.0));
    let mut out = [[0.0; 2]; 2];
    for i in 0..2 {
        for k in 0..2 {
            out[i][k] = (-p2[i][k] + 8.0 * p1[i][k] - 8.0 * m1[i][k] + m2[i][k]) / (12.0 * h);
        }
    }
    out
}

fn norm3(t: &[[[f64; 2]; 2]; 2]) -> f64 {
    t.iter()
        .flatten()
        .flatten()
        .fold(0.0, |m: f64, v| m.max(v.abs()))
}

#[test]
fn hooke_of_grad_u_is_sigma() {
    for m in materials() {
        for (x, _) in samples() {
            let h = 1e-3 * x[0].hypot(x[1]);
            let f = |y: Vec2| u_kernel(&m, y);
            let gx = fd(&f, x, 0, h);
            let gy = fd(&f, x, 1, h);
            let sig = sigma_kernel(&m, x);
            let scale = norm3(&sig);
            for k in 0..2 {
                // Displacement field of force k: u_i = U_ik; gradient g[i][l] = ∂_l U_ik.
                let g = [[gx[0][k], gy[0][k]], [gx[1][k], gy[1][k]]];
                let s = m.stress_from_gradient(g);
                for i in 0..2 {
                    for j in 0..2 {
                        let err = (s[i][j] - sig[i][j][k]).abs() / scale;
                        assert!(err < 1e-9, "x = {x:?}, ijk = {i}{j}{k}: {err:e}");
                    }
                }
            }
        }
    }
}

#[test]
fn sigma_is_divergence_free() {
    for m in materials() {
        for (x, _) in samples() {
            let r = x[0].hypot(x[1]);
            let h = 1e-3 * r;
            let scale = norm3(&sigma_kernel(&m, x)) / r;
            for k in 0..2 {
                // Column k of Σ as a matrix field S_ij.
                let f = |y: Vec2| {
                    let s = sigma_kernel(&m, y);
                    [[s[0][0][k], s[0][1][k]], [s[1][0][k], s[1][1][k]]]
                };
                let dx = fd(&f, x, 0, h);
                let dy = fd(&f, x, 1, h);
                for i in 0..2 {
                    let div = dx[i][0] + dy[i][1];
                    assert!(div.abs() / scale < 1e-9, "x = {x:?}: {div:e}");
                }
            }
        }
    }
}

#[test]
fn sigma_traction_balances_unit_force() {
    // ∮ Σ_ijk n_j ds = −δ_ik on any circle around the source (periodic trapezoid rule).
    let m = Material::new(1.0, 0.3, false);
    for rad in [0.01, 1.0, 30.0] {
        let n = 64;
        let mut tot = [[0.0; 2]; 2];
        for q in 0..n {
            let a = 2.0 * std::f64::consts::PI * (q as f64 + 0.3) / n as f64;
            let nrm = [a.cos(), a.sin()];
            let s = sigma_kernel(&m, [rad * nrm[0], rad * nrm[1]]);
            let ds = 2.0 * std::f64::consts::PI * rad / n as f64;
            for i in 0..2 {
                for k in 0..2 {
                    tot[i][k] += ds * (s[i][0][k] * nrm[0] + s[i][1][k] * nrm[1]);
                }
            }
        }
        for i in 0..2 {
            for k in 0..2 {
                let want = if i == k { -1.0 } else { 0.0 };
                assert!((tot[i][k] - want).abs() < 1e-13, "{tot:?}");
            }
        }
    }
}

#[test]
fn sigma_sign_ahead_of_force() {
    let m = Material::new(1.0, 0.3, false);
    let r = 0.7;
    let s = sigma_kernel(&m, [r, 0.0]);
    let want = -(3.0 - 2.0 * m.nu) * m.c_t() / r;
    assert!((s[0][0][0] - want).abs() < 1e-15 * want.abs());
}

#[test]
fn double_layer_reciprocity_is_exact() {
    for m in materials() {
        for (x, n) in samples() {
            let y = [0.1, -0.2];
            let r = [x[0] - y[0], x[1] - y[1]];
            let t = t_kernel(&m, r, n);
            let tu = tu_kernel(&m, [-r[0], -r[1]], n);
            let scale = t.iter().flatten().fold(0.0, |a: f64, v| a.max(v.abs()));
            for i in 0..2 {
                for k in 0..2 {
                    assert!((t[i][k] - tu[k][i]).abs() <= 4e-16 * scale);
                }
            }
        }
    }
}

#[test]
fn hooke_of_grad_t_is_s() {
    for m in materials() {
        for (x, n) in samples() {
            let h = 1e-3 * x[0].hypot(x[1]);
            let f = |y: Vec2| t_kernel(&m, y, n);
            let gx = fd(&f, x, 0, h);
            let gy = fd(&f, x, 1, h);
            let s = s_kernel(&m, x, n);
            let scale = norm3(&s);
            for k in 0..2 {
                let g = [[gx[0][k], gy[0][k]], [gx[1][k], gy[1][k]]];
                let sig = m.stress_from_gradient(g);
                for i in 0..2 {
                    for j in 0..2 {
                        let err = (sig[i][j] - s[k][i][j]).abs() / scale;
                        assert!(err < 1e-9, "x = {x:?}, kij = {k}{i}{j}: {err:e}");
                    }
                }
            }
        }
    }
}

#[test]
fn kernel_symmetries() {
    let m = Material::new(1.0, 0.3, false);
    for (x, n) in samples() {
        let mx = [-x[0], -x[1]];
        let u = u_kernel(&m, x);
        assert_eq!(u, u_kernel(&m, mx));
        assert_eq!(u[0][1], u[1][0]);
        let b = b_kernel(&m, x);
        assert_eq!(b, b_kernel(&m, mx));
        // S is even in r̂; T and Σ are odd.
        let s = s_kernel(&m, x, n);
        let sm = s_kernel(&m, mx, n);
        assert!(norm3(&s) > 0.0);
        for (a, c) in s
            .iter()
            .flatten()
            .flatten()
            .zip(sm.iter().flatten().flatten())
        {
            assert!((a - c).abs() <= 1e-15 * norm3(&s));
        }
        let t = t_kernel(&m, x, n);
        let tm = t_kernel(&m, mx, n);
        for i in 0..2 {
            for k in 0..2 {
                assert!((t[i][k] + tm[i][k]).abs() <= 1e-15 * (t[i][k].abs() + 1e-300));
            }
        }
    }
    // B = (μ/(2π(1−ν))) (−ln r I + r̂r̂ᵀ) relates to U by the factor 4μ²: the r̂r̂ᵀ parts agree.
    let r = [0.3, 0.4];
    let b = b_kernel(&m, r);
    let u = u_kernel(&m, r);
    assert!((b[0][1] / u[0][1] - m.c_s() / m.c_u()).abs() < 1e-12 * m.c_s() / m.c_u());
}

#[test]
fn plane_stress_substitution() {
    let (e, nu) = (2.0, 0.25);
    let ps = Material::new(e, nu, true);
    let pe = Material::new(e, nu, false);
    assert_eq!(ps.mu, pe.mu);
    assert!((ps.nu - nu / (1.0 + nu)).abs() < 1e-16);
    // λ(ν̄) equals the plane-stress 2μν/(1−ν).
    assert!((ps.lambda() - 2.0 * ps.mu * nu / (1.0 - nu)).abs() < 1e-14);
    // Uniaxial plane stress: σ_xx = E ε_xx when ε_yy = −ν ε_xx.
    let s = ps.stress_from_strain([[1.0, 0.0], [0.0, -nu]]);
    assert!((s[0][0] - e).abs() < 1e-14 && s[1][1].abs() < 1e-14);
}
