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
