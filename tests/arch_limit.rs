//! The minimum thickness of a semicircular masonry arch under its own weight: the arch
//! pipeline (`pipelines/arch.toml`, `geo/arch.geo` with radial joints, centre-line radius
//! R = 5) with 40 voussoirs and friction μ = 1 on every joint (no joint slides), bisected on
//! t/R between a ring that stands (exit 0) and one that collapses (exit 3, the hinge
//! mechanism). Milankovitch: t/R = 0.1075 for a continuous semicircular arch.
//! (`pipelines/arch_min_thickness.py` is the same search as a pipeline.)

mod support;

const R: f64 = 5.0;
const MILANKOVITCH: f64 = 0.1075;

/// Runs the arch at t/R; returns (exit code, stderr).
fn arch(dir: &std::path::Path, t_over_r: f64) -> (i32, String) {
    let scene = support::root().join("pipelines/arch.toml");
    let out = dir.join(format!("t{t_over_r:.5}"));
    let (code, _, stderr) = support::sgbem(&[
        "run",
        scene.to_str().unwrap(),
        "--set",
        "mesh.nv=40",
        "--set",
        &format!("mesh.t={:.6}", t_over_r * R),
        "--set",
        "defaults.interface.tangential=friction",
        "--set",
        "defaults.interface.friction=1.0",
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(
        code == 0 || code == 3,
        "t/R = {t_over_r}: exit {code}: {stderr}"
    );
    (code, stderr)
}

#[test]
fn semicircular_arch_minimum_thickness_is_milankovitch_s() {
    let dir = support::tmpdir("arch_limit");
    // A ring at t/R = 0.12 stands; one at 0.10 ends with the hinge mechanism.
    let (code, stderr) = arch(&dir, 0.12);
    assert_eq!(code, 0, "t/R = 0.12 must stand: {stderr}");
    let (code, stderr) = arch(&dir, 0.10);
    assert_eq!(code, 3, "t/R = 0.10 must collapse");
    assert!(
        stderr.contains("no equilibrium exists") && stderr.contains("voussoir_"),
        "{stderr}"
    );
    // Bisection to 0.001 in t/R.
    let (mut lo, mut hi) = (0.10, 0.12);
    while hi - lo > 1e-3 {
        let mid = 0.5 * (lo + hi);
        if arch(&dir, mid).0 == 0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let found = 0.5 * (lo + hi);
    eprintln!(
        "minimum t/R = {found:.4} (between {lo:.4} and {hi:.4}); Milankovitch {MILANKOVITCH}: \
         {:+.1} %",
        100.0 * (found / MILANKOVITCH - 1.0)
    );
    assert!(
        (found / MILANKOVITCH - 1.0).abs() < 0.03,
        "t/R = {found} vs {MILANKOVITCH}"
    );
}
