//! Bonded multidomain solves against exact linear fields (formulation §7 items 9–11): the
//! single-body patch test, the bonded two-body patch test for stiffness ratios up to 1e6,
//! symmetry of the condensed operators.

mod support;

use sgbem::kernels::Material;
use sgbem::pipeline::load;
use sgbem::quadrature::QuadratureSettings;
use sgbem::solve::{all_closed, prepare, solve_status};
use support::*;

/// A linear elastic field: strain, rotation, translation, stress (plane strain or stress).
#[derive(Clone, Copy)]
struct Linear {
    eps: [[f64; 2]; 2],
    omega: f64,
    c: [f64; 2],
    sigma: [[f64; 2]; 2],
}

impl Linear {
    fn u(&self, x: [f64; 2]) -> [f64; 2] {
        let e = self.eps;
        [
            e[0][0] * x[0] + e[0][1] * x[1] - self.omega * x[1] + self.c[0],
            e[1][0] * x[0] + e[1][1] * x[1] + self.omega * x[0] + self.c[1],
        ]
    }
    fn u_expr(&self) -> [String; 2] {
        let e = self.eps;
        [
            format!(
                "{:e}*x + {:e}*y + {:e}",
                e[0][0],
                e[0][1] - self.omega,
                self.c[0]
            ),
            format!(
                "{:e}*x + {:e}*y + {:e}",
                e[1][0] + self.omega,
                e[1][1],
                self.c[1]
            ),
        ]
    }
    fn t(&self, n: [f64; 2]) -> [f64; 2] {
        let s = self.sigma;
        [
            s[0][0] * n[0] + s[0][1] * n[1],
            s[1][0] * n[0] + s[1][1] * n[1],
        ]
    }
}

/// Strain from stress for an isotropic material (the effective ν of `Material`).
fn strain(m: &Material, s: [[f64; 2]; 2]) -> [[f64; 2]; 2] {
    let (mu, nu) = (m.mu, m.nu);
    let tr = s[0][0] + s[1][1];
    let f = |sij: f64, d: f64| (sij - nu * tr * d) / (2.0 * mu);
    [
        [f(s[0][0], 1.0), f(s[0][1], 0.0)],
        [f(s[1][0], 0.0), f(s[1][1], 1.0)],
    ]
}

/// Two blocks: lower [0,1]x[0,0.5] (base clamped to the exact field), upper [0,1]x[0.5,1].
fn two_block_mesh(n: usize) -> Msh {
    let mut m = Msh::default();
    let h = n / 2;
    m.line(1, [0.0, 0.0], [1.0, 0.0], n, &[1]);
    m.line(2, [1.0, 0.0], [1.0, 0.5], h, &[2]);
    m.line(3, [1.0, 0.5], [0.0, 0.5], n, &[3]);
    m.line(4, [0.0, 0.5], [0.0, 0.0], h, &[4]);
    m.line(5, [1.0, 0.5], [1.0, 1.0], h, &[5]);
    m.line(6, [1.0, 1.0], [0.0, 1.0], n, &[6]);
    m.line(7, [0.0, 1.0], [0.0, 0.5], h, &[7]);
    m.surface(1, &[1, 2, 3, 4], &[1]);
    m.surface(2, &[-3, 5, 6, 7], &[2]);
    for (t, name) in [
        (1, "base"),
        (2, "lower_right"),
        (3, "joint"),
        (4, "lower_left"),
        (5, "upper_right"),
        (6, "top"),
        (7, "upper_left"),
    ] {
        m.name(1, t, name);
    }
    m.name(2, 1, "lower");
    m.name(2, 2, "upper");
    m
}

fn traction_lines(name: &str, t: [f64; 2]) -> String {
    format!("[boundary.{name}]\ntx = {:e}\nty = {:e}\n", t[0], t[1])
}

/// The bonded patch test of formulation Appendix A2 for E_lower / E_upper = `ratio`.
fn bonded_patch(ratio: f64, n: usize, quadrature: &str) -> (f64, f64, f64) {
    let nu = 0.3;
    let (e_up, e_low) = (1.0, ratio);
    let m_low = Material::new(e_low, nu, false);
    let m_up = Material::new(e_up, nu, false);
    let s_low = [[0.1, 0.2], [0.2, -1.0]];
    let eps_low = strain(&m_low, s_low);
    // σxx of the upper block so that ε_xx matches across y = 0.5 (plane strain).
    let (mu, nue) = (m_up.mu, m_up.nu);
    let sxx_up = (2.0 * mu * eps_low[0][0] + nue * s_low[1][1]) / (1.0 - nue);
    let s_up = [[sxx_up, 0.2], [0.2, -1.0]];
    let eps_up = strain(&m_up, s_up);
    let low = Linear {
        eps: eps_low,
        omega: 0.05,
        c: [0.0, 0.0],
        sigma: s_low,
    };
    let mut up = Linear {
        eps: eps_up,
        omega: 0.05 + eps_low[0][1] - eps_up[0][1],
        c: [0.0, 0.0],
        sigma: s_up,
    };
    let (a, b) = (low.u([0.0, 0.5]), up.u([0.0, 0.5]));
    up.c = [a[0] - b[0], a[1] - b[1]];
    assert!((low.u([1.0, 0.5])[0] - up.u([1.0, 0.5])[0]).abs() < 1e-14);
    assert!((low.u([1.0, 0.5])[1] - up.u([1.0, 0.5])[1]).abs() < 1e-14);

    let [ux, uy] = low.u_expr();
    let mut scene = format!(
        "plane = \"strain\"\n[body.lower]\nyoung = {e_low:e}\npoisson = {nu}\n\
         [body.upper]\nyoung = {e_up:e}\npoisson = {nu}\n\
         [boundary.base]\nux = \"{ux}\"\nuy = \"{uy}\"\n"
    );
    scene += &traction_lines("lower_right", low.t([1.0, 0.0]));
    scene += &traction_lines("lower_left", low.t([-1.0, 0.0]));
    scene += &traction_lines("upper_right", up.t([1.0, 0.0]));
    scene += &traction_lines("upper_left", up.t([-1.0, 0.0]));
    scene += &traction_lines("top", up.t([0.0, 1.0]));
    scene += "[interface.joint]\nmodel = \"bonded\"\n";
    let dir = tmpdir(&format!("patch-{ratio:e}"));
    let msh = two_block_mesh(n).save(&dir, "m.msh");
    let sc = write(&dir, "s.toml", &scene);
    let l = load(&sc, Some(&msh)).unwrap_or_else(|e| panic!("{e}"));
    let q = QuadratureSettings::from_name(quadrature).unwrap();
    let prep =
        prepare(&l.model, l.scene.plane, &q, 1.0, &sc, &|_| {}).unwrap_or_else(|e| panic!("{e}"));
    let sol =
        solve_status(&l.model, &prep, &all_closed(&l.model)).unwrap_or_else(|e| panic!("{e}"));
    let mut err_u = 0.0f64;
    let mut err_t = 0.0f64;
    for (b, body) in l.model.bodies.iter().enumerate() {
        let exact = if body.name == "lower" { low } else { up };
        for (nd, x) in body.nodes.iter().enumerate() {
            let (ue, uh) = (exact.u(*x), sol.fields[b].u[nd]);
            err_u = err_u.max((ue[0] - uh[0]).abs().max((ue[1] - uh[1]).abs()));
        }
        for (ei, e) in body.elements.iter().enumerate() {
            let te = exact.t(e.normal);
            for end in 0..2 {
                let th = sol.fields[b].t[ei][end];
                err_t = err_t.max((te[0] - th[0]).abs().max((te[1] - th[1]).abs()));
            }
        }
    }
    let asym = prep
        .condensed
        .iter()
        .map(|c| c.asymmetry)
        .fold(0.0, f64::max);
    let scale_u = low
        .u([1.0, 0.5])
        .iter()
        .chain(up.u([1.0, 1.0]).iter())
        .fold(0.0f64, |m, v| m.max(v.abs()));
    (err_u / scale_u, err_t, asym)
}

/// The quadrature floor (about 1e-12 relative with "standard") is amplified by the stiffness
/// contrast in the stiff body's tractions: measured 4e-11, 7e-11, 1e-8, 1e-6 for ratios 1,
/// 1e2, 1e4, 1e6 with "standard", and 3e-14, 1e-13, 1.3e-11, 4.5e-10 with "accurate" — which
/// is why `sgbem check` recommends "accurate" above a contrast of 1e3.
#[test]
fn bonded_two_body_patch_test_is_exact_for_any_stiffness_ratio() {
    for (ratio, quadrature) in [
        (1.0, "standard"),
        (1e2, "standard"),
        (1e4, "accurate"),
        (1e6, "accurate"),
    ] {
        let (eu, et, asym) = bonded_patch(ratio, 6, quadrature);
        println!("ratio {ratio:e} ({quadrature}): displacement error {eu:.2e} (relative), traction error {et:.2e}, D00 asymmetry {asym:.1e}");
        assert!(eu < 1e-8, "ratio {ratio:e}: displacement error {eu:e}");
        assert!(et < 1e-8, "ratio {ratio:e}: traction error {et:e}");
        assert!(asym < 1e-10, "ratio {ratio:e}: D00 asymmetry {asym:e}");
    }
}
