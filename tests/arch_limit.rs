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

/// Runs `sgbem run SCENE ARGS --out DIR/out --quiet`, which must succeed; its summary.
fn run_summary(dir: &std::path::Path, scene: &std::path::Path, args: &[&str]) -> serde_json::Value {
    let out = dir.join("out");
    let mut all = vec!["run", scene.to_str().unwrap()];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--out", out.to_str().unwrap(), "--quiet"]);
    let (code, _, stderr) = support::sgbem(&all);
    assert_eq!(code, 0, "{stderr}");
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

/// `[solve] collapse`: the multiplier t of a lateral body force at which a block on a base
/// (b × h = 1 × 0.5, friction 10: it cannot slide) tips, against the rigid-block limit
/// analysis value b/h = 2 (overturning about the toe: t·W·h/2 = W·b/2).
#[test]
fn collapse_multiplier_of_a_tilting_block_is_the_rigid_block_limit() {
    let dir = support::tmpdir("collapse_block");
    support::gmsh(
        &support::root().join("geo/two_blocks.geo"),
        &dir,
        "tb.msh",
        false,
        &["-setnumber", "n", "16"],
    );
    let scene = support::write(
        &dir,
        "col.toml",
        r#"
mesh = "tb.msh"
plane = "strain"
[body.lower]
young = 1000.0
poisson = 0.3
[body.upper]
young = 1000.0
poisson = 0.3
body_force = ["t", -1.0]
[boundary.base]
ux = 0.0
uy = 0.0
[interface.joint]
model = "unilateral"
initial = "closed"
tangential = "friction"
friction = 10.0
[solve]
collapse = { max = 5.0, tolerance = 0.001 }
[output]
directory = "out"
field = false
"#,
    );
    let s = run_summary(&dir, &scene, &[]);
    let c = &s["contact"]["collapse"];
    let (lo, hi) = (
        c["multiplier"].as_f64().unwrap(),
        c["collapses_at"].as_f64().unwrap(),
    );
    let rigid = 1.0 / 0.5;
    eprintln!("tilting block: collapse multiplier {lo:.4} .. {hi:.4}, rigid block {rigid}");
    assert!(hi - lo <= 0.001 + 1e-12, "bisection to the tolerance");
    assert!((lo / rigid - 1.0).abs() < 0.01, "{lo} vs {rigid}");
    let mech = c["mechanism"].as_str().unwrap();
    assert!(
        mech.contains("body \"upper\"") && mech.contains("tipping"),
        "{mech}"
    );
    // The reported state is the standing one at the multiplier.
    assert_eq!(s["status"], "converged");
}

/// The same for a pier of two blocks on a clamped one (`pipelines/wall.toml`, 3 courses of
/// 0.4 × 0.2 blocks): the two upper blocks tip together about the toe of the first joint at
/// the rigid-block limit t = b / (2h) = 1 (a lateral acceleration t·g); the top joint alone
/// would need b/h = 2.
#[test]
fn collapse_multiplier_of_a_two_block_pier_is_the_rigid_block_limit() {
    let dir = support::tmpdir("collapse_pier");
    let scene = support::root().join("pipelines/wall.toml");
    let s = run_summary(
        &dir,
        &scene,
        &[
            "--set",
            "mesh.courses=3",
            "--set",
            "body.brick_*.body_force=[\"20*t\", -20.0]",
            "--set",
            "boundary.left.tx=0.0",
            "--set",
            "solve.collapse={ max = 5.0, tolerance = 0.001 }",
        ],
    );
    let c = &s["contact"]["collapse"];
    let lo = c["multiplier"].as_f64().unwrap();
    let rigid = 0.4 / (2.0 * 0.2);
    eprintln!("two-block pier: collapse multiplier {lo:.4}, rigid blocks {rigid}");
    assert!((lo / rigid - 1.0).abs() < 0.01, "{lo} vs {rigid}");
    let mech = c["mechanism"].as_str().unwrap();
    assert!(mech.contains("joints[brick_1|brick_2]"), "{mech}");
}
