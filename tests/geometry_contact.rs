//! Contact from the geometry: interfaces whose two sides were drawn and meshed on their own
//! (docs/formulation.md §5.6), end to end through `sgbem run`.
//!
//! * The patch test of Code_Aster's SSNP170 set-up (`geo/patch_nonmatching.geo`): two
//!   stacked blocks, 10 elements under the interface and 7 above, and 13 / 5. On rollers
//!   with the top pushed down, the exact state is a uniform oedometric compression; with
//!   free sides and a pressure on the top, a uniform compression whose lateral displacement
//!   is linear along the interface (a tied tangential row must reproduce it). The interface
//!   pressure must be exact to 1e-8 and the tangential traction zero.
//!
//! Run with `cargo test --release --test geometry_contact -- --nocapture` to see the numbers.

mod support;

use std::collections::HashMap;
use std::path::Path;

/// One row of `interfaces/<name>.csv`, by column name.
struct Row(HashMap<String, String>);

impl Row {
    fn num(&self, key: &str) -> f64 {
        self.0[key]
            .parse()
            .unwrap_or_else(|_| panic!("column {key}: not a number: {}", self.0[key]))
    }
    fn closed(&self) -> bool {
        self.0["status"] == "closed"
    }
}

fn read_rows(path: &Path) -> Vec<Row> {
    let text = std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap_or("")
        .split(',')
        .map(str::to_string)
        .collect();
    lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            Row(header
                .iter()
                .cloned()
                .zip(l.split(',').map(str::to_string))
                .collect())
        })
        .collect()
}

/// Runs a scene written into `dir`; returns the rows of interface `iface` and the summary.
fn run(dir: &Path, scene: &str, iface: &str) -> (Vec<Row>, serde_json::Value) {
    let s = support::write(dir, "scene.toml", scene);
    let out = dir.join("out");
    let (code, _, err) = support::sgbem(&[
        "run",
        s.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "sgbem run failed: {err}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    (
        read_rows(&out.join("interfaces").join(format!("{iface}.csv"))),
        summary,
    )
}

fn geo(name: &str) -> String {
    support::root()
        .join("geo")
        .join(format!("{name}.geo"))
        .to_string_lossy()
        .into_owned()
}

/// The largest deviation of the normal traction from the pressure −p, and the largest
/// tangential traction.
fn deviations(rows: &[Row], p: f64) -> (f64, f64) {
    rows.iter().fold((0.0f64, 0.0f64), |(d, t), r| {
        (
            d.max((r.num("normal_traction") + p).abs()),
            t.max(r.num("tangential_traction").abs()),
        )
    })
}

/// The SSNP170-like blocks with `n_lower` / `n_upper` elements across the interface.
fn patch_scene(n_lower: usize, n_upper: usize, rest: &str) -> String {
    format!(
        "title = \"patch test, independent meshes\"\nplane = \"strain\"\n\
         [mesh]\nfile = \"{}\"\nn_lower = {n_lower}\nn_upper = {n_upper}\n{rest}",
        geo("patch_nonmatching")
    )
}

/// Rollers on every side, the base held, the top pushed down by 0.01: every pair of the
/// open, stick interface closes with the oedometric pressure p = d / (H/M_upper + H/M_lower).
#[test]
fn patch_test_on_rollers_gives_the_exact_pressure() {
    let m = |e: f64, nu: f64| e * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let p = 0.01 / (1.0 / m(1000.0, 0.3) + 1.0 / m(3000.0, 0.2));
    for (n_lower, n_upper) in [(10, 7), (13, 5)] {
        let dir = support::tmpdir("patch_rollers");
        let rest = "[body.upper]\nyoung = 1000.0\npoisson = 0.3\n\
                    [body.lower]\nyoung = 3000.0\npoisson = 0.2\n\
                    [boundary.top]\nuy = -0.01\ntx = 0.0\n\
                    [boundary.base]\nuy = 0.0\ntx = 0.0\n\
                    [boundary.left]\nux = 0.0\nty = 0.0\n\
                    [boundary.right]\nux = 0.0\nty = 0.0\n\
                    [interface.contact]\nmodel = \"unilateral\"\ninitial = \"open\"\n\
                    tangential = \"stick\"\n[solve]\ntolerance = 1e-10\n";
        let (rows, summary) = run(&dir, &patch_scene(n_lower, n_upper, rest), "contact");
        assert_eq!(summary["status"], "converged");
        // The rows are the upper block's nodes (the first body).
        assert_eq!(rows.len(), n_upper + 1);
        let (dev, tt) = deviations(&rows, p);
        println!(
            "patch {n_lower}/{n_upper} on rollers: p = {p:.12}, largest deviation {dev:.2e}, \
             largest tangential traction {tt:.2e}"
        );
        assert!(rows.iter().all(Row::closed));
        assert!(dev <= 1e-8 * p, "pressure off by {dev:e} (p = {p})");
        assert!(tt <= 1e-8 * p, "tangential traction {tt:e}");
        let resultant = summary["interfaces"]["contact"]["normal_resultant"]
            .as_f64()
            .unwrap();
        assert!(
            (resultant + 2.0 * p).abs() <= 1e-8 * p,
            "resultant {resultant}"
        );
    }
}

/// Free right sides, the left ones on rollers, a pressure q on the top, one material: a
/// uniform compression σ_yy = −q whose lateral displacement grows linearly along the
/// interface. Bonded, and unilateral with stick (the tangential rows tie it), the pressure
/// is q at every pair and the tangential traction zero.
#[test]
fn patch_test_with_free_sides_reproduces_a_linear_field() {
    let q = 2.5;
    for (n_lower, n_upper) in [(10, 7), (13, 5)] {
        for joint in [
            "model = \"bonded\"",
            "model = \"unilateral\"\ninitial = \"closed\"\ntangential = \"stick\"",
        ] {
            let dir = support::tmpdir("patch_free");
            let rest = format!(
                "[body.upper]\nyoung = 1000.0\npoisson = 0.3\n\
                 [body.lower]\nyoung = 1000.0\npoisson = 0.3\n\
                 [boundary.top]\nty = -{q}\ntx = 0.0\n\
                 [boundary.base]\nuy = 0.0\ntx = 0.0\n\
                 [boundary.left]\nux = 0.0\nty = 0.0\n\
                 [interface.contact]\n{joint}\n"
            );
            let (rows, _) = run(&dir, &patch_scene(n_lower, n_upper, &rest), "contact");
            let (dev, tt) = deviations(&rows, q);
            println!(
                "patch {n_lower}/{n_upper}, free sides, {}: largest deviation {dev:.2e}, \
                 largest tangential traction {tt:.2e}",
                joint.lines().next().unwrap_or("")
            );
            assert!(rows.iter().all(Row::closed));
            assert!(dev <= 1e-8 * q, "pressure off by {dev:e} (q = {q})");
            assert!(tt <= 1e-8 * q, "tangential traction {tt:e}");
        }
    }
}
