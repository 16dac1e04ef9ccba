//! Contact scenes end to end: gmsh meshes a `.geo` into a temporary folder, `sgbem run`
//! solves the scene, the test reads `summary.json` and `interfaces/<name>.csv`.
//!
//! * Hertz line contact (`pipelines/hertz_contact.toml`): the contact half-width and the
//!   peak pressure against Johnson's formulas for the load P of the run, and the pressure
//!   against the semi-ellipse inside the zone.
//! * Contact patch test (`pipelines/contact_patch.toml`): every pair closes with the exact
//!   uniform pressure.
//! * The paper's example 1 (`pipelines/beam_on_blocks*.toml`), stick and slide.
//! * Stability: a stiffness ratio of 1e6, an interface 20 times finer than its neighbours,
//!   thin bodies (aspect 1:50); each scene run as drawn and rotated, translated and rescaled
//!   (loads in the local frame follow), with the same statuses and resultants.
//!
//! Run with `cargo test --release --test contact_scenes -- --nocapture` to see the numbers.

mod support;

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde_json::Value;
use support::{read_interface_csv as read_rows, InterfaceRow as Row};

/// What a run left: its exit code, stderr, summary and interface rows.
struct Run {
    code: i32,
    stderr: String,
    summary: Value,
    rows: Vec<Row>,
    seconds: f64,
}

impl Run {
    fn iface(&self, name: &str, key: &str) -> f64 {
        self.summary["interfaces"][name][key]
            .as_f64()
            .unwrap_or_else(|| panic!("summary.json has no interfaces.{name}.{key}"))
    }
    fn converged(&self) -> bool {
        self.summary["status"] == "converged"
    }
}

/// Runs `sgbem run SCENE --mesh MESH --out DIR --quiet`; reads the summary (written even on
/// a contact failure) and the interface's CSV when present.
fn run(scene: &Path, mesh: &Path, out: &Path, iface: &str) -> Run {
    let t = Instant::now();
    let (code, _, stderr) = support::sgbem(&[
        "run",
        scene.to_str().unwrap(),
        "--mesh",
        mesh.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    let seconds = t.elapsed().as_secs_f64();
    let summary: Value = match std::fs::read_to_string(out.join("summary.json")) {
        Ok(s) => serde_json::from_str(&s).expect("summary.json is JSON"),
        Err(_) => panic!(
            "{}: no summary.json (exit {code}): {stderr}",
            scene.display()
        ),
    };
    let csv = out.join("interfaces").join(format!("{iface}.csv"));
    let rows = if csv.is_file() {
        let mut r = read_rows(&csv);
        r.sort_by(|a, b| a.s.total_cmp(&b.s));
        r
    } else {
        Vec::new()
    };
    Run {
        code,
        stderr,
        summary,
        rows,
        seconds,
    }
}

fn geo(name: &str) -> PathBuf {
    support::root().join("geo").join(format!("{name}.geo"))
}

fn scene(name: &str) -> PathBuf {
    support::root()
        .join("pipelines")
        .join(format!("{name}.toml"))
}

// ------------------------------------------------------------------------------------------
// Hertz line contact

#[test]
fn hertz_half_width_and_pressure_match_johnson() {
    let dir = support::tmpdir("hertz_contact");
    let h_fine = 0.1;
    let mesh = support::gmsh(
        &geo("hertz_contact"),
        &dir,
        "hertz.msh",
        false,
        &["-setnumber", "h_fine", "0.1"],
    );
    let r = run(&scene("hertz_contact"), &mesh, &dir.join("out"), "contact");
    assert_eq!(r.code, 0, "sgbem run failed: {}", r.stderr);
    assert!(r.converged(), "not converged: {}", r.summary["contact"]);

    // Johnson (1985) for the scene's materials and radius; P of the full model.
    let (e1, n1, e2, n2, radius) = (1000.0, 0.3, 2000.0, 0.25, 100.0);
    let e_star = 1.0 / ((1.0f64 - n1 * n1) / e1 + (1.0 - n2 * n2) / e2);
    let p = -2.0 * r.iface("contact", "normal_resultant");
    let pi = std::f64::consts::PI;
    let b = (4.0 * p * radius / (pi * e_star)).sqrt();
    let p0 = 2.0 * p / (pi * b);

    // The zone: the closed pairs form one run from the axis.
    let last_closed = r
        .rows
        .iter()
        .filter(|w| w.closed)
        .map(|w| w.x)
        .fold(f64::NEG_INFINITY, f64::max);
    let first_open = r
        .rows
        .iter()
        .filter(|w| !w.closed)
        .map(|w| w.x)
        .fold(f64::INFINITY, f64::min);
    assert!(
        last_closed < first_open,
        "the closed pairs are not one zone from the axis"
    );
    let peak = -r.rows.iter().map(|w| w.tn).fold(f64::INFINITY, f64::min);
    // The semi-ellipse in the interior of the zone (|x| < 0.8 b), relative to p0.
    let dev: Vec<f64> = r
        .rows
        .iter()
        .filter(|w| w.closed && w.x < 0.8 * b)
        .map(|w| (-w.tn - p0 * (1.0 - w.x * w.x / (b * b)).sqrt()) / p0)
        .collect();
    let rms = (dev.iter().map(|d| d * d).sum::<f64>() / dev.len() as f64).sqrt();
    let tangential = r.rows.iter().map(|w| w.tt.abs()).fold(0.0, f64::max);
    println!(
        "hertz: P = {p:.5} (E* = {e_star:.4}, R = {radius}): b Johnson {b:.4}, last closed \
         pair {last_closed:.4}, first open {first_open:.4} (elements {h_fine}); p0 Johnson \
         {p0:.4}, peak {peak:.4} ({:+.3} %); semi-ellipse RMS deviation {rms:.2e} p0 over {} \
         pairs (x < 0.8 b); {} iterations, {:.2} s",
        100.0 * (peak / p0 - 1.0),
        dev.len(),
        r.summary["contact"]["iterations"],
        r.seconds
    );
    assert!(
        tangential == 0.0,
        "frictionless: tangential traction {tangential}"
    );
    assert!(
        (last_closed - b).abs() <= h_fine && last_closed <= b && b <= first_open,
        "half-width: last closed pair at {last_closed}, Johnson b = {b} (one element is {h_fine})"
    );
    assert!(
        (peak / p0 - 1.0).abs() <= 0.03,
        "peak pressure {peak} vs Johnson p0 = {p0}"
    );
    // Measured 6.5e-4 (25 pairs); the margin is a factor 3.
    assert!(
        rms <= 2e-3,
        "pressure vs the semi-ellipse: RMS deviation {rms:.2e} p0"
    );
}

// ------------------------------------------------------------------------------------------
// Contact patch test

#[test]
fn contact_patch_closes_every_pair_with_the_exact_pressure() {
    let dir = support::tmpdir("contact_patch");
    let mesh = support::gmsh(&geo("contact_patch"), &dir, "patch.msh", false, &[]);
    let r = run(&scene("contact_patch"), &mesh, &dir.join("out"), "contact");
    assert_eq!(r.code, 0, "sgbem run failed: {}", r.stderr);
    assert!(r.converged());
    // Oedometric moduli M = E(1 − ν)/((1 + ν)(1 − 2ν)); heights 1; the top pushed by 0.01.
    let m = |e: f64, nu: f64| e * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let p = 0.01 / (1.0 / m(1000.0, 0.3) + 1.0 / m(3000.0, 0.2));
    assert!(!r.rows.is_empty());
    let mut worst = 0.0f64;
    for w in &r.rows {
        assert!(w.closed, "pair at x = {} stayed open", w.x);
        worst = worst.max((w.tn + p).abs() / p);
        assert!(
            w.tt.abs() <= 1e-8 * p,
            "tangential traction {} at x = {}",
            w.tt,
            w.x
        );
    }
    let resultant = r.iface("contact", "normal_resultant");
    let err_resultant = (resultant + 2.0 * p).abs() / (2.0 * p);
    println!(
        "contact patch: {} pairs closed, pressure {p:.8}: largest relative error {worst:.1e}, \
         resultant {resultant:.8} (error {err_resultant:.1e}), {} iterations",
        r.rows.len(),
        r.summary["contact"]["iterations"]
    );
    assert!(
        worst <= 1e-8,
        "pressure not uniform: relative error {worst:.1e}"
    );
    assert!(err_resultant <= 1e-8);
}

// ------------------------------------------------------------------------------------------
// The paper's example 1

/// Runs a beam_on_blocks scene on the paper's mesh (2 cm, 0.1 cm on the interface).
fn example1(name: &str) -> Run {
    let dir = support::tmpdir(name);
    let mesh = support::gmsh(&geo("beam_on_blocks"), &dir, "beam.msh", false, &[]);
    let r = run(&scene(name), &mesh, &dir.join("out"), "support");
    let det = r.summary["interfaces"]["support"]["detached_length"].as_f64();
    let res = r.summary["interfaces"]["support"]["normal_resultant"].as_f64();
    let qp = &r.summary["qp"];
    println!(
        "{name}: exit {}, status {}, detached length {det:?} cm (paper: 8.4 LCP, 8.3 Vodicka, \
         8.2 QP), normal resultant {res:?} daN (load 306), {} iterations, residual {}, \
         {:.2} s; QP: raw {} cm, polished {} cm ({} pairs differ from the LCP); {}",
        r.code,
        r.summary["status"],
        r.summary["contact"]["iterations"],
        r.summary["contact"]["complementarity_residual"],
        r.seconds,
        qp["raw"]["interfaces"]["support"]["detached_length"],
        qp["interfaces"]["support"]["detached_length"],
        qp["differing_pairs_from_lcp"],
        r.stderr.trim()
    );
    r
}

/// The open pairs form one run ending at the beam's end x = 30 (lift-off from the end).
fn lifts_off_from_the_end(r: &Run) -> bool {
    let last_closed = r
        .rows
        .iter()
        .filter(|w| w.closed)
        .map(|w| w.x)
        .fold(f64::NEG_INFINITY, f64::max);
    r.rows.iter().all(|w| w.closed == (w.x <= last_closed)) && !r.rows.last().unwrap().closed
}

#[test]
fn example1_beam_on_blocks_slide() {
    let r = example1("beam_on_blocks_slide");
    assert_eq!(r.code, 0, "sgbem run failed: {}", r.stderr);
    assert!(r.converged());
    assert!(
        lifts_off_from_the_end(&r),
        "the open pairs are not one run from the end"
    );
    // Measured 8.3 cm (84 open pairs) at this mesh and at h = 1, 0.5 cm with 0.05 cm on the
    // interface; the paper's stick model gives 8.4 (LCP), 8.2 (QP). One element either way.
    let det = r.iface("support", "detached_length");
    assert!((det - 8.3).abs() <= 0.1 + 1e-9, "detached length {det} cm");
    // Vertical equilibrium of the beam: q L = 10.2 × 30 = 306 daN. Not exact in the
    // discrete problem (the beam's vertical rigid motion is not a test function once the
    // interface normal components are shared); measured 296.7 (−3.0 %) at this mesh,
    // 301.1 at h = 1, 303.5 at h = 0.5 cm.
    let res = r.iface("support", "normal_resultant");
    assert!(
        (res + 306.0).abs() / 306.0 <= 0.04,
        "normal resultant {res} daN vs the load 306"
    );
    assert_eq!(r.iface("support", "tangential_resultant"), 0.0);
    // The QP's zone, once polished by the mixed system, is the LCP's.
    assert_eq!(
        r.summary["qp"]["differing_pairs_from_lcp"], 0,
        "{}",
        r.summary["qp"]
    );
}

#[test]
fn example1_beam_on_blocks_stick() {
    let r = example1("beam_on_blocks");
    // The paper's model must converge (README "Command line": exit 3 only for a numerical failure).
    assert!(
        r.code == 0 && r.converged(),
        "the stick model did not converge (exit {}): {}",
        r.code,
        r.stderr
    );
    assert!(
        lifts_off_from_the_end(&r),
        "the open pairs are not one run from the end"
    );
    let res = r.iface("support", "normal_resultant");
    assert!(
        (res + 306.0).abs() / 306.0 <= 0.01,
        "normal resultant {res} daN vs the load 306"
    );
    // The detached length is reported above; it is compared with the paper's 8.4 cm only
    // in the report (ours is about 5.5 cm with this model), not asserted.
}

// ------------------------------------------------------------------------------------------
// Stability under rotation, translation and rescaling

/// Two blocks of width `w` stacked along y: "lower" [0,w] x [0,hl] with a clamped base,
/// "upper" [0,w] x [hl,hl+hu] loaded by a normal pressure on its top over [0, load]; the
/// left sides x = 0 form the group "left", the other sides "free". Element sizes: `h`
/// on the outer curves, `h_if` on the interface. The whole drawing is then dilated by
/// `scale` about the origin, rotated by `angle` degrees and translated by `shift`.
#[allow(clippy::too_many_arguments)]
fn blocks_geo(
    w: f64,
    hl: f64,
    hu: f64,
    load: f64,
    h: f64,
    h_if: f64,
    scale: f64,
    angle: f64,
    shift: [f64; 2],
) -> String {
    let n = |len: f64, size: f64| ((len / size).round() as usize).max(1) + 1;
    let top = hl + hu;
    format!(
        "Point(1) = {{0, 0, 0}};\n\
         Point(2) = {{{w}, 0, 0}};\n\
         Point(3) = {{{w}, {hl}, 0}};\n\
         Point(4) = {{0, {hl}, 0}};\n\
         Point(5) = {{{w}, {top}, 0}};\n\
         Point(6) = {{{load}, {top}, 0}};\n\
         Point(7) = {{0, {top}, 0}};\n\
         Line(1) = {{1, 2}};\n\
         Line(2) = {{2, 3}};\n\
         Line(3) = {{4, 3}};\n\
         Line(4) = {{4, 1}};\n\
         Line(5) = {{3, 5}};\n\
         Line(6) = {{5, 6}};\n\
         Line(7) = {{6, 7}};\n\
         Line(8) = {{7, 4}};\n\
         Transfinite Curve{{1}} = {};\n\
         Transfinite Curve{{3}} = {};\n\
         Transfinite Curve{{2, 4}} = {};\n\
         Transfinite Curve{{5, 8}} = {};\n\
         Transfinite Curve{{6}} = {};\n\
         Transfinite Curve{{7}} = {};\n\
         Curve Loop(1) = {{1, 2, -3, 4}};\n\
         Curve Loop(2) = {{3, 5, 6, 7, 8}};\n\
         Plane Surface(1) = {{1}};\n\
         Plane Surface(2) = {{2}};\n\
         Dilate {{{{0, 0, 0}}, {scale}}} {{ Surface{{1, 2}}; }}\n\
         Rotate {{{{0, 0, 1}}, {{0, 0, 0}}, {angle}*Pi/180}} {{ Surface{{1, 2}}; }}\n\
         Translate {{{}, {}, 0}} {{ Surface{{1, 2}}; }}\n\
         Physical Surface(\"upper\") = {{2}};\n\
         Physical Surface(\"lower\") = {{1}};\n\
         Physical Curve(\"contact\") = {{3}};\n\
         Physical Curve(\"base\") = {{1}};\n\
         Physical Curve(\"load\") = {{7}};\n\
         Physical Curve(\"left\") = {{4, 8}};\n\
         Physical Curve(\"free\") = {{2, 5, 6}};\n\
         Mesh.MeshSizeMax = {};\n",
        n(w, h),
        n(w, h_if),
        n(hl, h),
        n(hu, h),
        n(w - load, h),
        n(load, h),
        shift[0],
        shift[1],
        // Coarse triangles: the BEM does not use them.
        4.0 * h * scale,
    )
}

/// The scene for [`blocks_geo`], loads and supports in frame-free form (clamped base,
/// normal pressure 1 on "load"). `stick`: the interface does not slide and the left sides
/// are free (the upper block is held by the interface alone, and may tilt); otherwise the
/// interface is frictionless and the left sides are a symmetry plane (un = 0, tt = 0), which
/// holds the upper block against sliding.
fn blocks_scene(e_upper: f64, e_lower: f64, stick: bool) -> String {
    let (tangential, left) = if stick {
        ("stick", "")
    } else {
        ("slide", "[boundary.left]\nun = 0.0\ntt = 0.0\n")
    };
    format!(
        "plane = \"strain\"\n\
         [body.upper]\nyoung = {e_upper:e}\npoisson = 0.3\n\
         [body.lower]\nyoung = {e_lower:e}\npoisson = 0.25\n\
         [boundary.base]\nux = 0.0\nuy = 0.0\n\
         [boundary.load]\ntn = -1.0\n\
         {left}\
         [interface.contact]\nmodel = \"unilateral\"\ninitial = \"closed\"\n\
         tangential = \"{tangential}\"\n\
         [solve]\ntolerance = 1e-10\n\
         [output]\nhistory = \"final\"\nvtk = false\n"
    )
}

/// Runs a block scene as drawn and transformed; compares statuses (pair by pair along the
/// interface) and the resultants divided by the scale.
#[allow(clippy::too_many_arguments)]
fn stability(
    tag: &str,
    w: f64,
    hl: f64,
    hu: f64,
    load: f64,
    h: f64,
    h_if: f64,
    e: [f64; 2],
    stick: bool,
) {
    let dir = support::tmpdir(&format!("stability-{tag}"));
    let scene = support::write(&dir, "scene.toml", &blocks_scene(e[0], e[1], stick));
    let cases = [
        ("drawn", 1.0, 0.0, [0.0, 0.0]),
        ("moved", 2.5, 37.0, [1234.5, -678.9]),
    ];
    let mut runs = Vec::new();
    for (name, scale, angle, shift) in cases {
        let g = support::write(
            &dir,
            &format!("{name}.geo"),
            &blocks_geo(w, hl, hu, load, h, h_if, scale, angle, shift),
        );
        let mesh = support::gmsh(&g, &dir, &format!("{name}.msh"), false, &[]);
        let r = run(&scene, &mesh, &dir.join(name), "contact");
        assert_eq!(r.code, 0, "{tag} {name}: sgbem run failed: {}", r.stderr);
        assert!(r.converged(), "{tag} {name}: {}", r.summary["contact"]);
        runs.push((scale, r));
    }
    let (s0, a) = &runs[0];
    let (s1, b) = &runs[1];
    assert_eq!(a.rows.len(), b.rows.len());
    let open = a.rows.iter().filter(|w| !w.closed).count();
    let differing = a
        .rows
        .iter()
        .zip(&b.rows)
        .filter(|(p, q)| p.closed != q.closed)
        .count();
    let rel = |k: &str| {
        let (x, y) = (a.iface("contact", k) / s0, b.iface("contact", k) / s1);
        (x, y, (x - y).abs() / x.abs().max(f64::MIN_POSITIVE))
    };
    let (n0, n1, dn) = rel("normal_resultant");
    let (d0, d1, dd) = rel("detached_length");
    let tmax = a.rows.iter().map(|w| w.tn.abs()).fold(0.0, f64::max);
    let dt = a
        .rows
        .iter()
        .zip(&b.rows)
        .map(|(p, q)| (p.tn - q.tn).abs())
        .fold(0.0, f64::max)
        / tmax;
    println!(
        "stability {tag}: {} pairs, {open} open as drawn, {differing} statuses differ after \
         the move; normal resultant / scale {n0:.10} vs {n1:.10} (relative {dn:.1e}); \
         detached length / scale {d0:.6} vs {d1:.6}; pair tractions differ by {dt:.1e} of \
         the largest; {:.2} s and {:.2} s",
        a.rows.len(),
        a.seconds,
        b.seconds
    );
    assert!(
        open > 0 && open < a.rows.len(),
        "{tag}: no partial detachment ({open} open)"
    );
    assert_eq!(differing, 0, "{tag}: statuses changed under the move");
    assert!(dn <= 1e-6, "{tag}: normal resultant changed by {dn:.1e}");
    assert!(dd <= 1e-6, "{tag}: detached length changed by {dd:.1e}");
    assert!(
        dt <= 1e-6,
        "{tag}: pair tractions changed by {dt:.1e} of the largest"
    );
    // Sanity: a pressure on the top pushes the upper block onto the lower one, and the
    // moved pairs are the drawn ones dilated, rotated and translated.
    assert!(n0 < 0.0);
    let (scale, angle, shift) = (cases[1].1, cases[1].2.to_radians(), cases[1].3);
    for (p, q) in a.rows.iter().zip(&b.rows) {
        let x = scale * (angle.cos() * p.x - angle.sin() * p.y) + shift[0];
        let y = scale * (angle.sin() * p.x + angle.cos() * p.y) + shift[1];
        assert!(
            (x - q.x).hypot(y - q.y) <= 1e-9 * w * scale,
            "{tag}: pair ({}, {}) moved to ({}, {}), expected ({x}, {y})",
            p.x,
            p.y,
            q.x,
            q.y
        );
    }
}

#[test]
fn stability_stiffness_ratio_1e6() {
    // A nearly rigid block (E 1e6) tilting on a soft one (E 1) under an eccentric load.
    stability("stiffness", 2.0, 1.0, 1.0, 0.5, 0.1, 0.1, [1e6, 1.0], true);
}

#[test]
fn stability_interface_20_times_finer() {
    // Half model of a plate 4 x 0.5 on a block under a central load of width 1: the plate's
    // ends lift off. Interface elements 0.0125 next to 0.25 on the sides.
    stability(
        "fine-interface",
        2.0,
        1.0,
        0.5,
        0.5,
        0.25,
        0.0125,
        [1.0, 1.0],
        false,
    );
}

#[test]
fn stability_thin_bodies() {
    // Half model of a strip 100 x 1 on a layer 100 x 1 (each 1:50 in the half model), a
    // central load of width 20: the strip's ends lift off.
    stability("thin", 50.0, 1.0, 1.0, 10.0, 0.5, 0.5, [1.0, 1.0], false);
}
