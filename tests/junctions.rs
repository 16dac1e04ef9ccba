//! Junctions: points where three or more bodies meet (the T-junctions of a running-bond
//! wall, `geo/wall.geo`), on unilateral (stick, friction) and bonded joints.
//!
//! * Patch test: a running-bond wall of equal bricks on a roller base, held by a symmetry
//!   plane on its left end, under a uniform pressure p on its top. The exact solution is
//!   uniform, `σ_yy = −p`, `σ_xx = σ_xy = 0`, `u_x = ν(1+ν) p x / E`, `u_y = −(1−ν²) p y / E`
//!   (plane strain), with every bed joint pressed by p, no shear anywhere and head joints
//!   touching without force. Linear elements hold it exactly, so every joint traction and
//!   every sampled stress and displacement must match to round-off.
//! * Equilibrium and solver agreement on a wall of 50 bricks under self-weight and a
//!   lateral load: every brick balances to round-off, those on the clamped base too; the
//!   evolutive path, the active set, Lemke and the QP give the same statuses pair by pair.

mod support;

use std::path::{Path, PathBuf};

use serde_json::Value;
use support::*;

const P: f64 = 2.0;
const E: f64 = 1000.0;
const NU: f64 = 0.25;

fn wall_geo() -> PathBuf {
    root().join("geo/wall.geo")
}

/// Runs `scene` (text) in a fresh folder; returns (exit code, stderr, summary, out dir).
fn run(name: &str, scene: &str) -> (i32, String, Value, PathBuf) {
    let dir = tmpdir(name);
    let path = write(&dir, "scene.toml", scene);
    let out = dir.join("out");
    let (code, _, err) = sgbem(&[
        "run",
        path.to_str().unwrap_or_default(),
        "--quiet",
        "--out",
        out.to_str().unwrap_or_default(),
    ]);
    let text = std::fs::read_to_string(out.join("summary.json"))
        .unwrap_or_else(|_| panic!("{name}: no summary.json: {err}"));
    (
        code,
        err,
        serde_json::from_str(&text).expect("summary.json is JSON"),
        out,
    )
}

fn patch_scene(joints: &str) -> String {
    // Sections at mid-height of each course, between head joints (x = 0.05 + 0.1 k).
    let sections: String = (0..4)
        .map(|c| {
            let y = 0.1 + 0.2 * c as f64;
            format!(
                "[[output.section]]\nname = \"course_{c}\"\nfrom = [0.05, {y}]\nto = [1.15, {y}]\npoints = 12\n"
            )
        })
        .collect();
    format!(
        r#"title = "running-bond patch test"
plane = "strain"
[mesh]
file = "{geo}"
courses = 4
bricks = 3
bond = 0.5
nj = 2
[body."brick_*"]
young = {E}
poisson = {NU}
[defaults.interface]
{joints}
[boundary.base]
uy = 0.0
[boundary.left]
ux = 0.0
[boundary.top]
ty = -{P}
[solve]
method = "both"
[output]
history = "final"
{sections}"#,
        geo = wall_geo().display()
    )
}

/// Every joint pair of the patch test: bed joints pressed by p without shear, head joints
/// without force; every section point on the exact field. Returns the junction block.
fn check_patch(name: &str, joints: &str) -> Value {
    let (code, err, s, out) = run(name, &patch_scene(joints));
    assert_eq!(code, 0, "{name}: {err}");
    let bonded = joints.contains("bonded");
    let want = if bonded { "solved" } else { "converged" };
    assert_eq!(s["status"], want, "{name}");
    let junctions = s["contact"]["junctions"].clone();
    // 4 courses of 3 bricks in running bond: 3 lines between courses, 5 T-junctions each.
    assert_eq!(junctions["points"], 15, "{name}: {junctions}");
    // Uniform compression: nothing opens, so no implied component slips (bonded joints have
    // no friction and are not counted at all).
    if !bonded {
        assert_eq!(
            junctions["implied_slipping"]["count"], 0,
            "{name}: {junctions}"
        );
    }
    assert_eq!(junctions["most_bodies_at_a_point"], 3, "{name}");
    let mut beds = 0;
    let mut heads = 0;
    for entry in std::fs::read_dir(out.join("interfaces")).expect("interfaces/") {
        let path = entry.expect("entry").path();
        let rows = read_interface_csv(&path);
        // A bed joint is horizontal: all its pairs share y.
        let bed = rows.iter().all(|r| (r.y - rows[0].y).abs() < 1e-9);
        for r in &rows {
            assert!(
                r.closed,
                "{name}: {} open at ({}, {})",
                path.display(),
                r.x,
                r.y
            );
            let (tn, tt) = if bed { (r.tn + P, r.tt) } else { (r.tn, r.tt) };
            assert!(
                tn.abs() < 1e-9 * P && tt.abs() < 1e-9 * P,
                "{name}: {} at ({}, {}): tn {} tt {}",
                path.display(),
                r.x,
                r.y,
                r.tn,
                r.tt
            );
            assert!(r.opening.abs() < 1e-12 && r.slip.abs() < 1e-12);
            if bed {
                beds += 1;
            } else {
                heads += 1;
            }
        }
    }
    assert!(beds > 0 && heads > 0, "{beds} bed and {heads} head pairs");
    // The exact field at 48 interior points.
    let (ex, ey) = (NU * (1.0 + NU) * P / E, -(1.0 - NU * NU) * P / E);
    let mut worst = [0.0f64; 2];
    for c in 0..4 {
        let text = std::fs::read_to_string(out.join(format!("sections/course_{c}.csv")))
            .expect("section csv");
        for line in text.lines().skip(1) {
            let v: Vec<f64> = line
                .split(',')
                .map(|x| x.parse().unwrap_or(f64::NAN))
                .collect();
            let (x, y) = (v[0], v[1]);
            let du = (v[2] - ex * x).abs().max((v[3] - ey * y).abs());
            let ds = v[4].abs().max((v[5] + P).abs()).max(v[6].abs());
            worst[0] = worst[0].max(du / (ey.abs() * 0.8));
            worst[1] = worst[1].max(ds / P);
        }
    }
    println!(
        "{name}: displacement error {:.1e}, stress error {:.1e}",
        worst[0], worst[1]
    );
    assert!(worst[0] < 1e-8 && worst[1] < 1e-8, "{name}: {worst:?}");
    // Every cross-check agrees (head joints touching without force count as degenerate).
    if bonded {
        return junctions;
    }
    for c in s["contact"]["cross_checks"]
        .as_array()
        .expect("cross_checks")
    {
        assert_eq!(c["converged"], true, "{name}: {c}");
        assert_eq!(c["differing_pairs"], 0, "{name}: {c}");
    }
    junctions
}

#[test]
fn running_bond_patch_test_is_exact_on_stick_friction_and_bonded_joints() {
    let stick = check_patch(
        "junction-patch-stick",
        "model = \"unilateral\"\ntangential = \"stick\"",
    );
    // Stick: the cycle of each T-junction loses one vertical and one horizontal tangential
    // component (two per junction); normal components are all kept.
    assert_eq!(stick["implied_components"], 30, "{stick}");
    for list in stick["implied"].as_object().expect("implied").values() {
        for i in list.as_array().expect("list") {
            assert_eq!(i["component"], "tangential", "{i}");
        }
    }
    let friction = check_patch(
        "junction-patch-friction",
        "model = \"unilateral\"\ntangential = \"friction\"\nfriction = 0.6",
    );
    assert_eq!(friction["implied_components"], 30);
    // Bonded: two of the six components of each junction are implied.
    let bonded = check_patch("junction-patch-bonded", "model = \"bonded\"");
    assert_eq!(bonded["implied_components"], 30);
}

fn wall_scene(geo: &Path, courses: usize, bricks: usize, joints: &str, method: &str) -> String {
    format!(
        r#"title = "running-bond wall"
plane = "strain"
units = {{ length = "m", force = "kN" }}
[mesh]
file = "{geo}"
courses = {courses}
bricks = {bricks}
bond = 0.5
nj = 4
[body."brick_*"]
young = 5.0e6
poisson = 0.2
body_force = [0.0, -20.0]
[defaults.interface]
{joints}
[boundary.base]
ux = 0.0
uy = 0.0
[boundary.left]
tx = 3.0
[solve]
method = "{method}"
[output]
history = "final"
vtk = false
"#,
        geo = geo.display()
    )
}

#[test]
fn fifty_brick_wall_balances_every_brick_and_every_solver_agrees() {
    // 10 courses of 5 bricks (odd courses: 4 whole bricks and two halves): 55 bodies.
    // Every solver on stick joints; with friction the evolutive path and the active set
    // (the QP cross-check of `both` re-solves a dense QP per outer iteration: minutes here).
    for (joints, method) in [
        ("model = \"unilateral\"\ntangential = \"stick\"", "both"),
        (
            "model = \"unilateral\"\ntangential = \"friction\"\nfriction = 0.7",
            "lcp",
        ),
    ] {
        let (code, err, s, out) = run(
            "junction-wall",
            &wall_scene(&wall_geo(), 10, 5, joints, method),
        );
        assert_eq!(code, 0, "{joints}: {err}");
        assert_eq!(s["status"], "converged");
        assert_eq!(s["counts"]["bodies"], 55);
        // The wind opens joints at the windward ends and T-junctions open with them.
        let open: u64 = s["interfaces"]
            .as_object()
            .expect("interfaces")
            .values()
            .map(|i| i["open_pairs"].as_u64().unwrap_or(0))
            .sum();
        assert!(open > 0, "{joints}: no joint opens");
        // Where a head joint opens beside a closed bed joint at a T-junction, the bed
        // joint's implied tangential component slips by the opening: every pair listed is
        // closed and slips by more than 1e-9 of the wall's size, and it is one of the
        // implied components.
        let junctions = &s["contact"]["junctions"];
        let slipping = &junctions["implied_slipping"];
        let at = slipping["at"].as_array().expect("implied_slipping.at");
        assert_eq!(slipping["count"].as_u64(), Some(at.len() as u64));
        // The model's size: the diagonal of the wall, 2.0 m wide and 2.0 m high.
        let scale = 8.0f64.sqrt();
        let mut largest = 0.0f64;
        for a in at {
            let slip = a["slip"].as_f64().expect("slip").abs();
            assert!(slip > 1e-9 * scale, "{joints}: {a}");
            largest = largest.max(slip);
            let iface = a["interface"].as_str().expect("interface");
            let x = a["x"].as_array().expect("x");
            let (px, py) = (x[0].as_f64().expect("x"), x[1].as_f64().expect("y"));
            let rows = read_interface_csv(&out.join("interfaces").join(format!("{iface}.csv")));
            let row = rows
                .iter()
                .find(|r| (r.x - px).abs() < 1e-9 && (r.y - py).abs() < 1e-9)
                .unwrap_or_else(|| panic!("{joints}: {a} not in {iface}.csv"));
            assert!(row.closed, "{joints}: {a} is open");
            let listed = junctions["implied"][iface]
                .as_array()
                .expect("implied of the interface")
                .iter()
                .any(|i| i["x"] == a["x"] && i["component"] == "tangential");
            assert!(
                listed,
                "{joints}: {a} is not an implied tangential component"
            );
        }
        assert_eq!(slipping["largest_slip"].as_f64(), Some(largest));
        println!(
            "{joints}: {} implied components slip, largest {largest:.2e} m",
            at.len()
        );
        let checks = s["contact"]["cross_checks"]
            .as_array()
            .expect("cross_checks");
        assert!(checks.len() >= if method == "both" { 3 } else { 1 });
        for c in checks {
            assert_eq!(c["converged"], true, "{joints}: {c}");
            assert_eq!(c["differing_pairs"], 0, "{joints}: {c}");
        }
        let eq = s["equilibrium"].as_object().expect("equilibrium");
        assert_eq!(eq.len(), 55);
        let (mut held, mut based) = (0.0f64, 0.0f64);
        for (name, b) in eq {
            let r = b["relative_imbalance"]
                .as_f64()
                .expect("relative_imbalance");
            let on_base = b["loads"]
                .as_object()
                .expect("loads")
                .keys()
                .any(|k| k == "boundary base");
            if on_base {
                based = based.max(r);
            } else {
                held = held.max(r);
                assert!(r <= 1e-8, "{joints}: {name}: relative imbalance {r:e}");
            }
        }
        println!("{joints}: held by joints {held:.1e}, on the base {based:.1e}");
        // The first course stands on the clamped base: its reactions are the held nodes'
        // nodal forces, balanced as exactly.
        assert!(based <= 1e-8, "{joints}: {based:e}");
    }
}

#[test]
fn a_blocked_pivoting_path_is_not_taken_for_a_mechanism() {
    // A running-bond wall of 5 courses of 3 bricks on a clamped base, stick joints, under
    // its weight and a lateral acceleration of 0.75 g. The evolutive path stops at a row
    // that cannot open without leaving a brick free; the problem has a solution all the
    // same (the opening stiffness is only semidefinite near collapse, where pivoting rules
    // can be blocked). The QP of the same inner problem finds it, checked exactly; every
    // solver then agrees, and the run converges instead of reporting a mechanism.
    let scene = format!(
        r#"title = "wall near collapse"
plane = "strain"
units = {{ length = "m", force = "kN" }}
[mesh]
file = "{geo}"
courses = 5
bricks = 3
[defaults.body]
young = 5.0e6
poisson = 0.2
body_force = [15.0, -20.0]
[defaults.interface]
model = "unilateral"
tangential = "stick"
[boundary.base]
ux = 0.0
uy = 0.0
[solve]
method = "both"
[output]
history = "final"
vtk = false
"#,
        geo = wall_geo().display()
    );
    let (code, err, s, _) = run("junction-blocked-path", &scene);
    assert_eq!(code, 0, "{err}");
    assert_eq!(s["status"], "converged", "{err}");
    let notes = s["notes"].as_array().expect("notes");
    assert!(
        notes.iter().any(|n| n
            .as_str()
            .unwrap_or("")
            .contains("the pivoting path stopped")),
        "the path was not blocked: {notes:?}"
    );
    for c in s["contact"]["cross_checks"]
        .as_array()
        .expect("cross_checks")
    {
        assert_eq!(c["converged"], true, "{c}");
        assert_eq!(c["differing_pairs"], 0, "{c}");
    }
    // Every brick balances, and the complementarity of the final state is exact.
    assert_eq!(s["contact"]["complementarity_residual"].as_f64(), Some(0.0));
    for (name, b) in s["equilibrium"].as_object().expect("equilibrium") {
        let r = b["relative_imbalance"].as_f64().expect("imbalance");
        assert!(r <= 1e-8, "{name}: {r:e}");
    }
}

/// Coulomb's law on every pair of a run's interface CSVs, with friction coefficient `mu`:
/// open pairs carry nothing; closed pairs lie in the cone; a pair that slips (by more than
/// 1e-12 of the model's size `scale`) lies on it, its traction against its slip. Returns
/// the number of slipping pairs and the largest departure, relative to the largest traction.
fn coulomb_on_every_pair(out: &Path, mu: f64, scale: f64) -> (usize, f64) {
    let mut rows = Vec::new();
    for e in std::fs::read_dir(out.join("interfaces")).expect("interfaces") {
        rows.extend(read_interface_csv(&e.expect("entry").path()));
    }
    let big = rows
        .iter()
        .map(|r| r.tn.abs().max(r.tt.abs()))
        .fold(0.0f64, f64::max);
    assert!(big > 0.0);
    let (mut slipping, mut worst) = (0, 0.0f64);
    for r in &rows {
        if !r.closed {
            worst = worst.max(r.tn.abs().max(r.tt.abs()) / big);
            continue;
        }
        // Compression is negative.
        worst = worst.max(r.tn.max(0.0) / big);
        let cone = mu * (-r.tn).max(0.0);
        worst = worst.max((r.tt.abs() - cone).max(0.0) / big);
        if r.slip.abs() > 1e-12 * scale {
            slipping += 1;
            worst = worst.max((cone - r.tt.abs()).abs() / big);
            // The traction on the first body points along its slip (u_B − u_A).
            assert!(
                r.tt * r.slip > 0.0 || r.tt.abs() <= 1e-9 * big,
                "({}, {}): traction {} against slip {}",
                r.x,
                r.y,
                r.tt,
                r.slip
            );
        }
    }
    (slipping, worst)
}

#[test]
fn the_sparse_solver_holds_coulombs_law_at_every_junction_pair() {
    // The 55-brick wall with friction under self-weight and wind: the tangential cut of the
    // junction cycles (the evolutive path's problem) leaves bed joints sliding at their
    // T-junction nodes without a friction force of their own; the sparse solver cuts the
    // cycles at whole joints and moves a cut where an implied component would break its
    // law, so that every pair obeys Coulomb's law.
    let joints = "model = \"unilateral\"\ntangential = \"friction\"\nfriction = 0.7";
    let scale = 8.0f64.sqrt();
    let (code, err, lcp, _) = run(
        "junction-wall-lcp",
        &wall_scene(&wall_geo(), 10, 5, joints, "lcp"),
    );
    assert_eq!(code, 0, "{err}");
    let approximate = lcp["contact"]["junctions"]["implied_slipping"]["count"]
        .as_u64()
        .expect("count");
    assert!(
        approximate > 0,
        "the tangential cut leaves no implied slip here"
    );
    let (code, err, s, out) = run(
        "junction-wall-sparse",
        &wall_scene(&wall_geo(), 10, 5, joints, "sparse"),
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(s["status"], "converged");
    let junctions = &s["contact"]["junctions"];
    assert_eq!(junctions["implied_slipping"]["count"], 0, "{junctions}");
    let (slipping, worst) = coulomb_on_every_pair(&out, 0.7, scale);
    println!(
        "tangential cut: {approximate} implied components slip; sparse: {slipping} pairs slip, \
         Coulomb's law to {worst:.1e} of the largest traction"
    );
    assert!(slipping > 0, "nothing slips: the test shows nothing");
    assert!(worst <= 1e-9, "Coulomb's law broken by {worst:e}");
    // The evolutive path cross-checks the same problem pair by pair.
    for c in s["contact"]["cross_checks"]
        .as_array()
        .expect("cross_checks")
    {
        assert_eq!(c["converged"], true, "{c}");
        assert_eq!(c["differing_pairs"], 0, "{c}");
    }
    for (name, b) in s["equilibrium"].as_object().expect("equilibrium") {
        let r = b["relative_imbalance"].as_f64().expect("imbalance");
        assert!(r <= 1e-8, "{name}: relative imbalance {r:e}");
    }
}
