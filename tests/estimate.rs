//! The estimate of a run (`src/estimate.rs`) against what the run uses, on running-bond walls
//! of many small bodies: the engine forms no dense matrix over all interfaces, and the
//! estimate must not pretend it does (a 410-brick wall was estimated at 33 GB and refused;
//! it runs in 0.7 GB). Its own binary: the peak resident memory measured here is this
//! process's.

mod support;

use std::path::{Path, PathBuf};

use support::*;

/// A running-bond wall of `geo/NAME.geo` meshed with nj = 6.
fn mesh(dir: &Path, name: &str, courses: usize, bricks: usize) -> PathBuf {
    let (c, b) = (courses.to_string(), bricks.to_string());
    gmsh(
        &root().join(format!("geo/{name}.geo")),
        dir,
        &format!("{name}{courses}x{bricks}.msh"),
        false,
        &[
            "-setnumber",
            "courses",
            &c,
            "-setnumber",
            "bricks",
            &b,
            "-setnumber",
            "nj",
            "6",
        ],
    )
}

/// The walls' scene: self-weight, wind on the left end, Coulomb joints without tension.
const WALL_SCENE: &str = r#"title = "running-bond wall"
plane = "strain"
[defaults.body]
young = 5.0e6
poisson = 0.2
body_force = [0.0, -20.0]
[defaults.interface]
model = "unilateral"
tangential = "friction"
friction = 0.7
[boundary.base]
ux = 0.0
uy = 0.0
[boundary.left]
tx = 1.0
[output]
history = "final"
"#;

fn wall(dir: &Path, courses: usize, bricks: usize) -> (PathBuf, PathBuf) {
    let msh = mesh(dir, "wall", courses, bricks);
    (write(dir, "wall.toml", WALL_SCENE), msh)
}

fn estimate(scene: &Path, msh: &Path) -> (f64, usize) {
    let l = sgbem::pipeline::load(scene, Some(msh)).unwrap_or_else(|e| panic!("{e}"));
    (
        sgbem::estimate::estimate(&l.model, &l.scene).peak_bytes,
        l.model.bodies.len(),
    )
}

#[test]
fn the_estimate_of_a_many_body_wall_follows_its_peak_memory() {
    let dir = tmpdir("estimate-wall");
    // 105 bodies, run here: the estimate covers the measured peak, within a factor 2.5.
    let (scene, msh) = wall(&dir, 10, 10);
    let (est, bodies) = estimate(&scene, &msh);
    assert_eq!(bodies, 105);
    reset_peak();
    let report = sgbem::pipeline::run(
        &scene,
        &sgbem::pipeline::RunOptions {
            mesh: Some(msh),
            out: Some(dir.join("out")),
            quiet: true,
            ..Default::default()
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(report.summary.status.as_str(), "converged");
    let peak = peak_kb() as f64 * 1024.0;
    println!(
        "105-body wall: estimate {:.0} MB, measured peak {:.0} MB",
        est / 1e6,
        peak / 1e6
    );
    assert!(
        est >= peak && est <= 2.5 * peak,
        "estimate {est:e}, peak {peak:e}"
    );
    // 410 bodies, estimated only (solved by the sparse solver, as a scene without `method`
    // of over 3000 unilateral pairs is: 0.72 GB measured with history "final"): no dense
    // matrix over its 8050 pairs (8 · (8 · 8050)² bytes = 33 GB), under 2.5 GB.
    let (scene, msh) = wall(&dir, 20, 20);
    let (big, bodies) = estimate(&scene, &msh);
    assert_eq!(bodies, 410);
    println!("410-body wall: estimate {:.0} MB", big / 1e6);
    assert!(big < 2.5e9 && big > 0.72e9, "{big:e}");
}

/// The estimate of the full-row solver (`method = "exact"`), which factors the sparse LU of
/// its statuses' system besides Clarabel's KKT system, against the peak resident memory of
/// a run in a process of its own (the kernel's count for the child, `wait4`): the 105-brick
/// wall with Coulomb joints within 30 % (342 MB against 329 MB measured with wind; 222 B per
/// Σ n_u² fitted at 105, 410 and 798 bricks: src/estimate.rs).
#[test]
fn the_estimate_of_the_full_row_solver_follows_its_peak_memory() {
    let dir = tmpdir("estimate-exact");
    let (scene, msh) = wall(&dir, 10, 10);
    let text = std::fs::read_to_string(&scene).unwrap();
    let scene = write(
        &dir,
        "wall_exact.toml",
        &format!("{text}[solve]\nmethod = \"exact\"\n"),
    );
    let (est, peak) = measured(&scene, &msh, &dir, 105, "exact");
    assert!(
        est >= 0.9 * peak && est <= 1.3 * peak,
        "estimate {est:e}, peak {peak:e}"
    );
}

/// The estimate as `sgbem check --json` gives it (in a process of its own: the first test
/// measures this one's peak), with the number of bodies.
fn checked_estimate(scene: &Path, msh: &Path) -> (f64, usize) {
    let (code, out, err) = sgbem(&[
        "check",
        scene.to_str().unwrap(),
        "--mesh",
        msh.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let report: serde_json::Value = serde_json::from_str(&out).unwrap();
    let bodies = report["bodies"].as_array().map_or(0, |b| b.len());
    (report["cost"]["peak_bytes"].as_f64().unwrap(), bodies)
}

/// The estimate of `sgbem check` and the peak of `sgbem run` (bytes) of a scene of `bodies`
/// bodies that `solver` solves (as summary.json names it).
fn measured(scene: &Path, msh: &Path, dir: &Path, bodies: usize, solver: &str) -> (f64, f64) {
    let (est, found) = checked_estimate(scene, msh);
    assert_eq!(found, bodies);
    let peak = child_peak(scene, msh, &dir.join("out"));
    let summary = std::fs::read_to_string(dir.join("out/summary.json")).unwrap();
    assert!(
        summary.contains(&format!("\"{solver}\"")),
        "the {solver} solver ran"
    );
    println!(
        "{bodies}-body wall, {solver}: estimate {:.0} MB, measured peak {:.0} MB",
        est / 1e6,
        peak / 1e6
    );
    (est, peak)
}

/// The peak resident memory in bytes of `sgbem run` in a process of its own (the kernel's
/// count for the child, `wait4`), which must succeed.
fn child_peak(scene: &Path, msh: &Path, out: &Path) -> f64 {
    // Waited for by wait4 below, which also gives the child's peak.
    #[allow(clippy::zombie_processes)]
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_sgbem"))
        .arg("run")
        .arg(scene)
        .arg("--mesh")
        .arg(msh)
        .arg("--out")
        .arg(out)
        .arg("--quiet")
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("run sgbem");
    let mut status = 0;
    // SAFETY: rusage is plain data that wait4 fills; the pid is our own child's, waited once.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let pid = unsafe { libc::wait4(child.id() as libc::pid_t, &mut status, 0, &mut usage) };
    assert_eq!(pid, child.id() as libc::pid_t);
    assert!(
        libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 0,
        "{status}"
    );
    usage.ru_maxrss as f64 * 1024.0
}

/// A running-bond wall drawn brick by brick (`geo/wall_drawn.geo`, 14 courses of 14 bricks
/// on a foundation, nj = 6; `[contact]` finds the joints, non-matching, and pairs node to
/// segment), solved by the sparse solver: each dof of a joint's second side moves several
/// glued unknowns, so the sparse systems hold more entries than the conforming wall's, and
/// the estimate counts them from the rows. Within 30 % above the peak of a run in a process
/// of its own (this 14 × 14 wall on 2026-12-06, b1fe7ec: 628 MB against 547–557 MB
/// measured; larger ones in docs/performance.md).
#[test]
fn the_estimate_of_a_wall_drawn_brick_by_brick_follows_its_peak_memory() {
    let dir = tmpdir("estimate-drawn");
    let msh = mesh(&dir, "wall_drawn", 14, 14);
    // The same scene on a foundation (stiffer, clamped at its base), the joints found from
    // the drawing; no VTK.
    let text = format!(
        "{}vtk = false\n[body.foundation]\nyoung = 3.0e7\npoisson = 0.2\n[contact]\n\
         search = 1e-6\n",
        WALL_SCENE
    );
    let scene = write(&dir, "drawn.toml", &text);
    // 7 courses of 14 bricks and 7 of 13 with two half bricks, and the foundation.
    let (est, peak) = measured(&scene, &msh, &dir, 204, "sparse");
    assert!(
        est >= peak && est <= 1.3 * peak,
        "estimate {est:e}, peak {peak:e}"
    );
}
