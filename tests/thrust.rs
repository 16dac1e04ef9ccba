//! The thrust line (`thrust.csv`, summary.json `thrust`, the VTK block `thrust`;
//! post/thrust.rs) against statics: a block on a base under its weight, a pressure on its top
//! and a lateral force there. The joint's resultant must balance the loads of the upper
//! block, N = W + P, T = Q, and its point of application lies at e = M / N from the joint's
//! mid-point (M the loads' moment about it), whether the joint is closed or partly open; a
//! fully open joint has no point. And the shipped arch stands: every joint compressed, every
//! point within its joint.

mod support;

use serde_json::Value;
use support::*;

/// The block on a base of geo/two_blocks.geo (upper [0,1] × [0.5,1] on lower
/// [0,1] × [0,0.5], joint at y = 0.5), elastic, the joint unilateral and sticking.
fn block_scene(top: &str) -> String {
    format!(
        r#"
mesh = "tb.msh"
plane = "strain"
units = {{ length = "m", force = "kN" }}
[body.lower]
young = 1000.0
poisson = 0.25
[body.upper]
young = 1000.0
poisson = 0.25
body_force = [0.0, -2.0]
[boundary.base]
ux = 0.0
uy = 0.0
[boundary.top]
{top}
[interface.joint]
model = "unilateral"
initial = "closed"
tangential = "stick"
[output]
directory = "out"
field = false
history = "final"
"#
    )
}

/// Runs the block with the top condition `top`; returns its run folder and summary.
fn run_block(name: &str, top: &str) -> (std::path::PathBuf, Value) {
    let dir = tmpdir(name);
    gmsh(
        &root().join("geo/two_blocks.geo"),
        &dir,
        "tb.msh",
        false,
        &["-setnumber", "n", "16"],
    );
    let scene = write(&dir, "block.toml", &block_scene(top));
    let out = dir.join("out");
    let summary = run(&scene, &out);
    (out, summary)
}

/// `sgbem run SCENE --out OUT`, which must succeed; returns the summary.
fn run(scene: &std::path::Path, out: &std::path::Path) -> Value {
    let s = |p: &std::path::Path| p.to_str().unwrap_or_default().to_string();
    let (code, _, err) = sgbem(&["run", &s(scene), "--out", &s(out), "--quiet"]);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(out.join("summary.json")).expect("summary.json");
    serde_json::from_str(&text).expect("JSON")
}

/// The rows of `thrust.csv` as (header, fields).
fn thrust_csv(out: &std::path::Path) -> (String, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(out.join("thrust.csv")).expect("thrust.csv");
    let mut lines = text.lines();
    let header = lines.next().unwrap_or_default().to_string();
    let rows = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    (header, rows)
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// Checks the joint of the block against statics for the top traction (Q, −P); returns its
/// summary figures.
fn check_statics(name: &str, q: f64, p: f64) -> Value {
    let (out, s) = run_block(name, &format!("tx = {q}\nty = {}", -p));
    assert_eq!(s["status"], "converged");
    let t = &s["thrust"]["joint"];
    // Weight 2 × 0.5; the loads' moment about the joint's centre (0.5, 0.5): Q at 0.5 above
    // it (the pressure and the weight act on the centre line).
    let (n, m) = (2.0 * 0.5 + p, q * 0.5);
    let f = |k: &str| t[k].as_f64().unwrap_or(f64::NAN);
    assert!(
        rel(f("normal_force"), n) < 1e-6,
        "N {} against {n}",
        f("normal_force")
    );
    // The force on the first body (lower) along the pairs' tangent (−n_y, n_x) = (−1, 0).
    assert!(
        rel(-f("tangential_force"), q) < 1e-6,
        "T {}",
        f("tangential_force")
    );
    let x = 0.5 + m / n;
    assert!(rel(f("x"), x) < 1e-6, "x {} against {x}", f("x"));
    assert!((f("y") - 0.5).abs() < 1e-12);
    assert!(
        rel(f("e").abs(), m / n) < 1e-6,
        "e {} against {}",
        f("e"),
        m / n
    );
    assert!(rel(f("e_over_half_length").abs(), m / n / 0.5) < 1e-6);
    assert_eq!(
        (&t["inside"], &t["in_closed_part"]),
        (&Value::Bool(true), &Value::Bool(true))
    );
    // The CSV holds the same numbers, with the units in its header.
    let (header, rows) = thrust_csv(&out);
    assert_eq!(
        header,
        "joint,body_a,body_b,N [kN],T [kN],x [m],y [m],s [m],e [m],e_over_half_length,inside,\
         in_closed_part"
    );
    assert_eq!(rows.len(), 1);
    assert_eq!(&rows[0][..3], ["joint", "lower", "upper"]);
    assert_eq!(rows[0][3].parse::<f64>().ok(), Some(f("normal_force")));
    assert_eq!(rows[0][5].parse::<f64>().ok(), Some(f("x")));
    assert_eq!(&rows[0][10..], ["true", "true"]);
    s
}

/// Closed joint (e = 0.05 within the middle third): the BEM tractions reproduce statics.
#[test]
fn closed_joint_reproduces_statics() {
    let s = check_statics("thrust-closed", 0.2, 1.0);
    assert_eq!(s["interfaces"]["joint"]["open_pairs"], 0);
}

/// Partly open joint (e = 0.3, 0.6 of the half length): still e = M / N, the point within
/// the closed part.
#[test]
fn partly_open_joint_keeps_e_equal_m_over_n() {
    let s = check_statics("thrust-open", 1.2, 1.0);
    let open = s["interfaces"]["joint"]["open_pairs"].as_u64().unwrap_or(0);
    assert!(
        open > 0,
        "the windward end should open: {}",
        s["interfaces"]["joint"]
    );
}

/// Fully open joint (the upper block lifted): N = 0, no point (null in the summary, empty
/// fields in the CSV, no point in the VTK block).
#[test]
fn fully_open_joint_has_no_point() {
    let (out, s) = run_block("thrust-lifted", "ux = 0.0\nuy = 0.01");
    let t = &s["thrust"]["joint"];
    assert_eq!(t["normal_force"].as_f64(), Some(0.0), "{t}");
    for k in [
        "x",
        "y",
        "s",
        "e",
        "e_over_half_length",
        "inside",
        "in_closed_part",
    ] {
        assert!(t[k].is_null(), "{k}: {t}");
    }
    let (_, rows) = thrust_csv(&out);
    assert!(rows[0][5..].iter().all(String::is_empty), "{:?}", rows[0]);
    let vtu = std::fs::read_to_string(out.join("vtk/thrust_0000.vtu")).expect("thrust_0000.vtu");
    assert!(
        vtu.contains("NumberOfPoints=\"0\" NumberOfCells=\"0\""),
        "{vtu}"
    );
}

/// The shipped arch (20 voussoirs, t/R = 0.12) stands: every joint compressed, its point
/// within the joint; the crown joint is a hinge (the point at its edge), the thrust line is
/// symmetric, and the VTK block joins the 21 points by 20 segments.
#[test]
fn arch_thrust_line_stays_in_the_ring() {
    let out = tmpdir("thrust-arch").join("out");
    let summary = run(&root().join("pipelines/arch.toml"), &out);
    let thrust = summary["thrust"].as_object().expect("thrust block");
    assert_eq!(thrust.len(), 21);
    for (name, t) in thrust {
        let n = t["normal_force"].as_f64().unwrap_or(f64::NAN);
        let r = t["e_over_half_length"].as_f64().unwrap_or(f64::NAN);
        assert!(n > 0.0, "{name}: N = {n}");
        assert!(r.abs() <= 1.0 + 1e-9 && t["inside"] == true, "{name}: {t}");
    }
    let crown = &thrust["joints[voussoir_10|voussoir_11]"];
    let r = crown["e_over_half_length"].as_f64().unwrap_or(0.0);
    assert!((r.abs() - 1.0).abs() < 1e-9, "crown: {crown}");
    // Mirror images: the springings, the haunches.
    for (a, b) in [
        ("voussoir_1|abutment_L", "voussoir_20|abutment_R"),
        ("voussoir_4|voussoir_5", "voussoir_16|voussoir_17"),
    ] {
        for key in ["normal_force", "e_over_half_length"] {
            let v = |k: &str| thrust[&format!("joints[{k}]")][key].as_f64().unwrap_or(0.0);
            assert!(rel(v(a), v(b)) < 1e-9, "{key}: {a} {} {b} {}", v(a), v(b));
        }
    }
    let vtm = std::fs::read_to_string(out.join("vtk/state_0000.vtm")).unwrap();
    assert!(
        vtm.contains("name=\"thrust\" file=\"thrust_0000.vtu\""),
        "{vtm}"
    );
    let vtu = std::fs::read_to_string(out.join("vtk/thrust_0000.vtu")).unwrap();
    assert!(vtu.contains("NumberOfPoints=\"21\" NumberOfCells=\"41\""));
    let marker = std::fs::read_to_string(out.join(".sgbem-run.json")).unwrap();
    assert!(marker.contains("\"thrust.csv\"") && marker.contains("\"vtk/thrust_0000.vtu\""));
}
