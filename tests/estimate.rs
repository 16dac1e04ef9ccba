//! The estimate of a run (`src/estimate.rs`) against what the run uses, on running-bond walls
//! of many small bodies: the engine forms no dense matrix over all interfaces, and the
//! estimate must not pretend it does (a 410-brick wall was estimated at 33 GB and refused;
//! it runs in 0.7 GB). Its own binary: the peak resident memory measured here is this
//! process's.

mod support;

use std::path::{Path, PathBuf};

use support::*;

fn wall(dir: &Path, courses: usize, bricks: usize) -> (PathBuf, PathBuf) {
    let (c, b) = (courses.to_string(), bricks.to_string());
    let msh = gmsh(
        &root().join("geo/wall.geo"),
        dir,
        &format!("wall{courses}x{bricks}.msh"),
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
    );
    let scene = write(
        dir,
        "wall.toml",
        r#"title = "running-bond wall"
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
"#,
    );
    (scene, msh)
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
    // The estimate as `sgbem check --json` gives it (in a process of its own: the other
    // test measures this one's peak).
    let (code, out, err) = sgbem(&[
        "check",
        scene.to_str().unwrap(),
        "--mesh",
        msh.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let report: serde_json::Value = serde_json::from_str(&out).unwrap();
    let est = report["cost"]["peak_bytes"].as_f64().unwrap();
    assert_eq!(report["bodies"].as_array().map(|b| b.len()), Some(105));
    // Waited for by wait4 below, which also gives the child's peak.
    #[allow(clippy::zombie_processes)]
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_sgbem"))
        .arg("run")
        .arg(&scene)
        .arg("--mesh")
        .arg(&msh)
        .arg("--out")
        .arg(dir.join("out"))
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
    let summary = std::fs::read_to_string(dir.join("out/summary.json")).unwrap();
    assert!(summary.contains("\"exact\""), "the full-row solver ran");
    let peak = usage.ru_maxrss as f64 * 1024.0;
    println!(
        "105-body wall, exact: estimate {:.0} MB, measured peak {:.0} MB",
        est / 1e6,
        peak / 1e6
    );
    assert!(
        est >= 0.9 * peak && est <= 1.3 * peak,
        "estimate {est:e}, peak {peak:e}"
    );
}
