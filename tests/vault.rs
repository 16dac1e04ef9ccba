//! The paper's example 3 end to end: a depressed vault (four bodies) on two masonry piers
//! under its own weight, five radial joints with brittle cohesion (`geo/vault.geo`,
//! `pipelines/vault_c0.toml`). gmsh meshes the geometry into a temporary folder and
//! `sgbem run --set 'interface.*.cohesion=C'` solves the scene for c = 0.4, 0.2 and 0 MPa
//! (4, 2 and 0 daN/cm²).
//!
//! What the physics requires, not the paper's exact lengths (its geometry is only drawn in a
//! figure; ours is reconstructed):
//!
//! * c = 0.4 MPa: no joint opens (as in the paper), and no closed joint carries more tension
//!   than the cohesion;
//! * c = 0: some joints open; closed pairs carry no tension, open pairs no traction and a
//!   non-negative opening;
//! * lowering the cohesion never closes a joint: the detached length of every joint is
//!   monotone over c = 0.4, 0.2, 0;
//! * the structure and its load are symmetric: s1 and s5, s2 and s4 open alike;
//! * a depressed arch on yielding piers opens from the crown's intrados and from the
//!   springings' extrados;
//! * the half vault is in equilibrium: the force through a springing (or a haunch) joint is
//!   the weight of the vault bodies above it combined with the crown thrust;
//! * every run reports its contact iteration converged.
//!
//! Run with `cargo test --release --test vault -- --nocapture` to see the numbers beside the
//! paper's Tables 3 and 4.

mod support;

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde_json::Value;
use support::{read_interface_csv as read_rows, InterfaceRow as Row};

/// The geometry the test meshes (passed to gmsh explicitly; geo/vault.geo's defaults).
const SPAN: f64 = 600.0;
const RISE: f64 = 120.0;
const DEPTH: f64 = 50.0;
/// Self-weight (daN/cm³) and the out-of-plane thickness of the scenes (cm).
const GAMMA: f64 = 0.0018;
const THICKNESS: f64 = 100.0;
const JOINTS: [&str; 5] = ["s1", "s2", "s3", "s4", "s5"];

struct Run {
    cohesion_mpa: &'static str,
    summary: Value,
    rows: Vec<Vec<Row>>, // per joint, JOINTS order
    seconds: f64,
}

impl Run {
    fn iface(&self, joint: &str, key: &str) -> f64 {
        self.summary["interfaces"][joint][key]
            .as_f64()
            .unwrap_or_else(|| panic!("c = {}: no interfaces.{joint}.{key}", self.cohesion_mpa))
    }
    fn detached(&self, joint: &str) -> f64 {
        self.iface(joint, "detached_length")
    }
}

fn run(mesh: &Path, dir: &Path, cohesion_mpa: &'static str) -> Run {
    let scene = support::root().join("pipelines").join("vault_c0.toml");
    let out = dir.join(format!("c{cohesion_mpa}"));
    let c: f64 = cohesion_mpa.parse().expect("a cohesion in MPa");
    let set = format!("interface.*.cohesion={}", 10.0 * c);
    let t = Instant::now();
    let (code, _, stderr) = support::sgbem(&[
        "run",
        scene.to_str().unwrap(),
        "--set",
        &set,
        "--mesh",
        mesh.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    let seconds = t.elapsed().as_secs_f64();
    assert_eq!(
        code, 0,
        "c = {cohesion_mpa} MPa: sgbem run failed: {stderr}"
    );
    let summary: Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("summary.json")).expect("summary.json written"),
    )
    .expect("summary.json is JSON");
    let rows = JOINTS
        .iter()
        .map(|j| read_rows(&out.join("interfaces").join(format!("{j}.csv"))))
        .collect();
    Run {
        cohesion_mpa,
        summary,
        rows,
        seconds,
    }
}

/// Intrados radius, centre height and half opening angle of the segmental arch.
fn arch() -> (f64, f64, f64) {
    let r = (SPAN * SPAN / 4.0 + RISE * RISE) / (2.0 * RISE);
    (r, RISE - r, (SPAN / (2.0 * r)).asin())
}

fn mesh(dir: &Path) -> PathBuf {
    let geo = support::root().join("geo").join("vault.geo");
    let (span, rise, depth) = (SPAN.to_string(), RISE.to_string(), DEPTH.to_string());
    support::gmsh(
        &geo,
        dir,
        "vault.msh",
        false,
        &[
            "-setnumber",
            "span",
            &span,
            "-setnumber",
            "rise",
            &rise,
            "-setnumber",
            "depth",
            &depth,
            "-setnumber",
            "n_joint",
            "17",
        ],
    )
}

#[test]
fn vault_cohesion_sweep() {
    let dir = support::tmpdir("vault");
    let mesh = mesh(&dir);
    let runs: Vec<Run> = ["0.4", "0.2", "0"]
        .into_iter()
        .map(|c| run(&mesh, &dir, c))
        .collect();

    // Numbers first, beside the paper's Tables 3 and 4 (section groups 1-5, 2-4, 3).
    let paper_t3 = [
        ("0.4", [0.0, 0.0, 0.0]),
        ("0.2", [35.29, 0.0, 0.0]),
        ("0", [35.29, 11.76, 38.24]),
    ];
    let paper_t4 = [
        ("0.4", [-0.39674, -0.16843, -0.20383]),
        ("0", [-0.49140, -0.16372, -0.33641]),
    ];
    for r in &runs {
        let t3 = paper_t3.iter().find(|p| p.0 == r.cohesion_mpa).unwrap().1;
        println!(
            "vault c = {} MPa: {} in {} contact iterations, {:.2} s; detached (cm) s1 {:.2} s2 \
             {:.2} s3 {:.2} s4 {:.2} s5 {:.2} (paper 1-5 {}, 2-4 {}, 3 {})",
            r.cohesion_mpa,
            r.summary["status"],
            r.summary["contact"]["iterations"],
            r.seconds,
            r.detached("s1"),
            r.detached("s2"),
            r.detached("s3"),
            r.detached("s4"),
            r.detached("s5"),
            t3[0],
            t3[1],
            t3[2]
        );
        if let Some((_, t4)) = paper_t4.iter().find(|p| p.0 == r.cohesion_mpa) {
            println!(
                "  largest compression on the joints (MPa): 1-5 {:.5} (paper {}), 2-4 {:.5} \
                 (paper {}), 3 {:.5} (paper {})",
                r.iface("s1", "min_normal_traction") / 10.0,
                t4[0],
                r.iface("s2", "min_normal_traction") / 10.0,
                t4[1],
                r.iface("s3", "min_normal_traction") / 10.0,
                t4[2]
            );
        }
    }

    // Converged, with every joint present and 18 pairs each.
    for r in &runs {
        let c = r.cohesion_mpa;
        assert_eq!(
            r.summary["status"], "converged",
            "c = {c}: {}",
            r.summary["status"]
        );
        assert_eq!(
            r.summary["contact"]["converged"],
            Value::Bool(true),
            "c = {c}: contact block {}",
            r.summary["contact"]
        );
        for (j, rows) in JOINTS.iter().zip(&r.rows) {
            assert_eq!(
                rows.len(),
                18,
                "c = {c}: joint {j} has {} pairs",
                rows.len()
            );
            assert_eq!(r.iface(j, "pairs"), 18.0);
        }
    }

    // Cohesion (daN/cm²) respected: closed pairs carry at most c in tension; open pairs
    // carry nothing and do not interpenetrate.
    for r in &runs {
        let c: f64 = r.cohesion_mpa.parse::<f64>().unwrap() * 10.0;
        for (j, rows) in JOINTS.iter().zip(&r.rows) {
            let scale = rows.iter().map(|w| w.tn.abs()).fold(0.0, f64::max);
            for w in rows {
                if w.closed {
                    assert!(
                        w.tn <= c + 1e-8 * scale,
                        "c = {}: closed pair of {j} at ({}, {}) carries {} > c",
                        r.cohesion_mpa,
                        w.x,
                        w.y,
                        w.tn
                    );
                } else {
                    assert_eq!(
                        w.tn, 0.0,
                        "c = {}: open pair of {j} carries {}",
                        r.cohesion_mpa, w.tn
                    );
                    assert!(
                        w.opening >= -1e-9,
                        "c = {}: open pair of {j} at ({}, {}) interpenetrates: {}",
                        r.cohesion_mpa,
                        w.x,
                        w.y,
                        w.opening
                    );
                }
            }
        }
    }

    // c = 0.4 MPa: no joint opens, as in the paper.
    let strong = &runs[0];
    for j in JOINTS {
        assert_eq!(strong.detached(j), 0.0, "c = 0.4: joint {j} opened");
        assert_eq!(
            strong.iface(j, "open_pairs"),
            0.0,
            "c = 0.4: joint {j} has open pairs"
        );
    }

    // c = 0: some joints open.
    let none = &runs[2];
    let total0: f64 = JOINTS.iter().map(|j| none.detached(j)).sum();
    assert!(total0 > 0.0, "c = 0: no joint opened");

    // Monotone: less cohesion never closes a joint.
    for j in JOINTS {
        let d: Vec<f64> = runs.iter().map(|r| r.detached(j)).collect();
        assert!(
            d[0] <= d[1] + 1e-9 && d[1] <= d[2] + 1e-9,
            "joint {j}: detached length not monotone over c = 0.4, 0.2, 0: {d:?}"
        );
    }

    // Symmetry: the mirror joints open alike.
    for r in &runs {
        for (a, b) in [("s1", "s5"), ("s2", "s4")] {
            assert!(
                (r.detached(a) - r.detached(b)).abs() < 1e-6,
                "c = {}: {a} detached {} but {b} {}",
                r.cohesion_mpa,
                r.detached(a),
                r.detached(b)
            );
        }
    }

    // Mechanism: the crown opens from its intrados, the springings from their extrados
    // (the open pairs of each are one run from that face).
    let (radius, yc, alpha) = arch();
    for r in &runs {
        for (k, j) in JOINTS.iter().enumerate() {
            let from_extrados = match *j {
                "s1" | "s5" => true,
                "s3" => false,
                _ => continue,
            };
            let mut by_radius: Vec<(f64, bool)> = r.rows[k]
                .iter()
                .map(|w| (w.x.hypot(w.y - yc), w.closed))
                .collect();
            by_radius.sort_by(|a, b| a.0.total_cmp(&b.0));
            if from_extrados {
                by_radius.reverse();
            }
            // From the opening face inwards: open pairs, then closed ones only.
            let first_closed = by_radius
                .iter()
                .position(|p| p.1)
                .unwrap_or(by_radius.len());
            let stray = by_radius[first_closed..].iter().find(|p| !p.1);
            assert!(
                stray.is_none(),
                "c = {}: joint {j} has an open pair at radius {:.2} beyond closed ones; \
                 expected one open run from the {}",
                r.cohesion_mpa,
                stray.map_or(0.0, |p| p.0),
                if from_extrados {
                    "extrados"
                } else {
                    "intrados"
                }
            );
        }
    }

    // Equilibrium of the half vault (per unit of the scene's thickness): the crown joint
    // carries a horizontal thrust only; the force through s1 (s2) combines it with the
    // weight of v1 + v2 (of v2).
    let body_weight =
        GAMMA * THICKNESS * ((radius + DEPTH).powi(2) - radius * radius) / 2.0 * (alpha / 2.0);
    for r in &runs {
        let force = |j: &str| {
            r.iface(j, "normal_resultant")
                .hypot(r.iface(j, "tangential_resultant"))
        };
        let thrust = r.iface("s3", "normal_resultant").abs();
        assert!(
            r.iface("s3", "tangential_resultant").abs() <= 1e-6 * thrust,
            "c = {}: shear at the crown {}",
            r.cohesion_mpa,
            r.iface("s3", "tangential_resultant")
        );
        for (j, bodies) in [("s1", 2.0), ("s2", 1.0)] {
            let want = (bodies * body_weight).hypot(thrust);
            let got = force(j);
            println!(
                "  c = {}: force through {j} {got:.1} daN, weight {:.1} with thrust {thrust:.1}: \
                 {want:.1} ({:+.2} %)",
                r.cohesion_mpa,
                bodies * body_weight,
                100.0 * (got / want - 1.0)
            );
            assert!(
                (got / want - 1.0).abs() <= 0.02,
                "c = {}: force through {j} {got} vs weight and thrust {want}",
                r.cohesion_mpa
            );
        }
    }
}
