//! Contact from the geometry: interfaces whose two sides were drawn and meshed on their own
//! (docs/formulation.md §5.6), end to end through `sgbem run`.
//!
//! * The patch test of Code_Aster's SSNP170 set-up (`geo/patch_nonmatching.geo`): two
//!   stacked blocks, 10 elements under the interface and 7 above, and 13 / 5. On rollers
//!   with the top pushed down, the exact state is a uniform oedometric compression; with
//!   free sides and a pressure on the top, a uniform compression whose lateral displacement
//!   is linear along the interface (a tied tangential row must reproduce it). The interface
//!   pressure must be exact to 1e-8 and the tangential traction zero.
//! * Hertz line contact from the drawing (`geo/hertz_drawn.geo`): a half cylinder drawn
//!   0.01 above a flat block, meshed on its own, with no gap in the scene: the gap on the
//!   axis as drawn, the half-width within one element and the peak pressure within 1 % of
//!   Johnson's, for the load of the run.
//! * A pin in a hole with clearance (`geo/pin_in_hole.geo`): a pin drawn touching the hole
//!   of a large plate, the two circles meshed on their own, frictionless, loaded through
//!   its centre: the contact half-angle within 2 % of the closed form of conforming contact
//!   (Persson 1964) from about 20° to 80°, and the contact resultant equal to the load.
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

/// `sgbem run` of a scene written into `dir`, into `dir/out`: the exit code, stderr and the
/// run folder.
fn sgbem_run(dir: &Path, scene: &str) -> (i32, String, std::path::PathBuf) {
    let s = support::write(dir, "scene.toml", scene);
    let out = dir.join("out");
    let (code, _, err) = support::sgbem(&[
        "run",
        s.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    (code, err, out)
}

/// Runs a scene written into `dir`; returns the rows of interface `iface` and the summary.
fn run(dir: &Path, scene: &str, iface: &str) -> (Vec<Row>, serde_json::Value) {
    let (code, err, out) = sgbem_run(dir, scene);
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

/// A half cylinder of radius 100 (a quarter disc in the half model) drawn 0.01 above a flat
/// block, each meshed on its own (0.08 on the arc, 0.1 on the flat near the contact); the
/// diametral plane pushed down by 0.2. The gap comes from the drawing alone.
#[test]
fn hertz_with_the_gap_from_the_drawing() {
    let dir = support::tmpdir("hertz_drawn");
    let (e1, n1, e2, n2, radius) = (1000.0, 0.3, 2000.0, 0.25, 100.0);
    let scene = format!(
        "title = \"Hertz from the drawing\"\nplane = \"strain\"\n\
         [mesh]\nfile = \"{}\"\nh_fine = 0.1\n\
         [body.cylinder]\nyoung = {e1}\npoisson = {n1}\n\
         [body.flat]\nyoung = {e2}\npoisson = {n2}\n\
         [boundary.top]\nuy = -0.2\ntx = 0.0\n\
         [boundary.base]\nuy = 0.0\ntx = 0.0\n\
         [boundary.symmetry]\nun = 0.0\ntt = 0.0\n\
         [interface.contact]\nmodel = \"unilateral\"\ninitial = \"open\"\n\
         tangential = \"slide\"\n\
         [solve]\ntolerance = 1e-10\n[output]\nvtk = false\n",
        geo("hertz_drawn")
    );
    let (mut rows, summary) = run(&dir, &scene, "contact");
    assert_eq!(summary["status"], "converged");
    rows.sort_by(|a, b| a.num("s").total_cmp(&b.num("s")));
    // The rows are the cylinder's nodes; on the axis the gap is the drawn 0.01 (the arc's
    // chords lie within 1e-5 of the circle there).
    let axis = &rows[0];
    assert!(axis.num("x").abs() < 1e-12);
    assert!(
        (axis.num("gap") - 0.01).abs() < 1e-6,
        "gap on the axis {}",
        axis.num("gap")
    );
    // Johnson (1985) for the load of the run (full model: twice the half's).
    let e_star = 1.0 / ((1.0f64 - n1 * n1) / e1 + (1.0 - n2 * n2) / e2);
    let p = -2.0
        * summary["interfaces"]["contact"]["normal_resultant"]
            .as_f64()
            .unwrap();
    let pi = std::f64::consts::PI;
    let b = (4.0 * p * radius / (pi * e_star)).sqrt();
    let p0 = 2.0 * p / (pi * b);
    let last_closed = rows
        .iter()
        .filter(|r| r.closed())
        .map(|r| r.num("x"))
        .fold(f64::NEG_INFINITY, f64::max);
    let first_open = rows
        .iter()
        .filter(|r| !r.closed())
        .map(|r| r.num("x"))
        .fold(f64::INFINITY, f64::min);
    let peak = -rows
        .iter()
        .map(|r| r.num("normal_traction"))
        .fold(f64::INFINITY, f64::min);
    let element = first_open - last_closed;
    println!(
        "hertz from the drawing: P = {p:.5}: b Johnson {b:.4}, last closed pair {last_closed:.4}, \
         first open {first_open:.4}; p0 Johnson {p0:.4}, peak {peak:.4} ({:+.3} %)",
        100.0 * (peak / p0 - 1.0)
    );
    assert!(
        last_closed < first_open,
        "the closed pairs are not one zone"
    );
    assert!(
        element < 0.1,
        "elements of the arc near the contact: {element}"
    );
    assert!(
        last_closed <= b && b <= first_open,
        "half-width: Johnson b = {b} not between the last closed pair {last_closed} and the \
         first open one {first_open}"
    );
    assert!(
        (peak / p0 - 1.0).abs() <= 0.01,
        "peak pressure {peak} vs Johnson p0 = {p0}"
    );
    let tangential = rows
        .iter()
        .map(|r| r.num("tangential_traction").abs())
        .fold(0.0, f64::max);
    assert_eq!(tangential, 0.0, "frictionless: tangential traction");
}

/// The closed form of the frictionless pin in a hole, the problem solved by Persson (1964)
/// and by Ciavarella & Decuzzi (Int. J. Solids Struct. 38, 2001, the case of elastic
/// similarity), derived anew for this test (below; checked against the mode sum, which it
/// zeroes on the arc to 1e-8 of ΔR and leaves open outside it): a pin of radius R1 in a
/// hole of radius R2 = R1 + ΔR (ΔR ≪ R2) of an infinite plate of the same material, pushed
/// against it by a force P per unit thickness through its centre, touches it over the arc
/// |θ| ≤ ε with
///
/// ```text
/// π E* ΔR / P = cos⁴(ε/2) (1 + ln cos(ε/2)) / sin²(ε/2) − sin²(ε/2),
/// 1/E* = (1 − ν₁²)/E₁ + (1 − ν₂²)/E₂ = 2 (1 − ν²)/E   (plane strain)
/// ```
///
/// (linear theory: the contact conditions on the circle of radius R; small ε gives Hertz,
/// ε² = 4P/(π E* ΔR); the neat fit ΔR = 0 gives ε = 84.8°). Derivation (docs/formulation.md
/// §5.6): per Fourier mode cos nθ of the pressure, the disc and the hole together close the
/// gap by (2R/E*) n/(n² − 1) (n ≥ 2) and R/E* (n = 0); mode 1 is the pin's approach;
/// (d²/dθ² + 1) of the gap condition is a finite Hilbert transform on the arc, which
/// x = tan(θ/2) maps onto a straight crack, and the two conditions p₁ = P/(πR) and the mean
/// pressure give the relation. Returns π E* ΔR / P for the half-angle ε (radians).
fn persson_clearance(eps: f64) -> f64 {
    let (c, s2) = ((eps / 2.0).cos(), (eps / 2.0).sin().powi(2));
    c.powi(4) * (1.0 + c.ln()) / s2 - s2
}

/// The half-angle ε of `persson_clearance(ε) = π E* ΔR / P` (decreasing in ε), by bisection.
fn persson_angle(p: f64, e_star: f64, clearance: f64) -> f64 {
    let target = std::f64::consts::PI * e_star * clearance / p;
    let (mut lo, mut hi) = (1e-9, std::f64::consts::FRAC_PI_2);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if persson_clearance(mid) > target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// `geo/pin_in_hole.geo`, half model: a pin of radius 9.99 drawn touching the hole of radius
/// 10 (ΔR = 0.01, the pin's centre at (ΔR, 0)) of a plate held on its outer circle of radius
/// 200, one material (E = 1000, ν = 0.3, plane strain); 400 uniform elements on the pin's
/// circle and 360 on the hole's over 0 ≤ θ ≤ 100° (0.25° and 0.28°), frictionless and
/// unilateral with the gap from the drawing. The pin is pushed along x by a uniform traction
/// on a small hole of radius 0.5 at its centre (a force through the centre, up to
/// (0.5/10)²). For loads P/(E* ΔR) = 0.1, 0.5, 2 and 15 the contact half-angle, measured at
/// the pin's centre midway between the last closed pair and the first open one (within half
/// an element, 0.125°, of the pairs' edge), is within 2 % of Persson's for the applied load;
/// the closed pairs are one arc from θ = 0; the contact forces on the pin balance the load to
/// 1e-6 and the tangential tractions are zero.
#[test]
fn pin_in_a_hole_follows_persson() {
    let (young, poisson, clearance, r0) = (1000.0, 0.3, 0.01, 0.5);
    let e_star = young / (2.0 * (1.0 - poisson * poisson));
    let mut angles = Vec::new();
    for load in [0.1, 0.5, 2.0, 15.0] {
        let dir = support::tmpdir("pin_in_hole");
        // The half of P on the half of the small hole's circumference.
        let q = load * e_star * clearance / (2.0 * std::f64::consts::PI * r0);
        let scene = format!(
            "title = \"pin in a hole\"\nplane = \"strain\"\n\
             [mesh]\nfile = \"{}\"\ndR = {clearance}\nr0 = {r0}\n\
             [body.pin]\nyoung = {young}\npoisson = {poisson}\n\
             [body.plate]\nyoung = {young}\npoisson = {poisson}\n\
             [boundary.load]\ntx = {q}\nty = 0.0\n\
             [boundary.symmetry]\nun = 0.0\ntt = 0.0\n\
             [boundary.outer]\nux = 0.0\nuy = 0.0\n\
             [interface.contact]\nmodel = \"unilateral\"\ninitial = \"open\"\n\
             tangential = \"slide\"\nbetween = [\"pin_side\", \"hole\"]\n\
             [solve]\ntolerance = 1e-10\n[output]\nvtk = false\noperators = false\nhistory = \"final\"\n",
            geo("pin_in_hole")
        );
        let (rows, summary) = run(&dir, &scene, "contact");
        assert_eq!(summary["status"], "converged");
        // The load as applied (on the drawn polygon) and the contact forces on the pin.
        let pin = &summary["equilibrium"]["pin"]["loads"];
        let applied = pin["boundary load"]["fx"].as_f64().unwrap();
        let contact = pin["interface contact"]["fx"].as_f64().unwrap();
        let p = 2.0 * applied;
        let mut rows: Vec<(f64, bool, f64)> = rows
            .iter()
            .map(|r| {
                let theta = r.num("y").atan2(r.num("x") - clearance).to_degrees();
                (theta, r.closed(), r.num("tangential_traction"))
            })
            .collect();
        rows.sort_by(|a, b| a.0.total_cmp(&b.0));
        let closed = rows.iter().take_while(|r| r.1).count();
        assert!(closed > 1, "the pin does not touch the hole");
        assert!(
            rows[closed..].iter().all(|r| !r.1),
            "the closed pairs are not one arc from θ = 0"
        );
        let (last_closed, first_open) = (rows[closed - 1].0, rows[closed].0);
        let measured = 0.5 * (last_closed + first_open);
        let persson = persson_angle(p, e_star, clearance).to_degrees();
        let error = measured / persson - 1.0;
        println!(
            "pin in a hole: P/(E* ΔR) = {:.4}: contact half-angle {measured:.3}° (last closed \
             {last_closed:.3}°, first open {first_open:.3}°), Persson {persson:.3}° \
             ({:+.2} %); contact resultant + load = {:.1e} of the load",
            p / (e_star * clearance),
            100.0 * error,
            (contact + applied).abs() / applied
        );
        assert!(
            error.abs() <= 0.02,
            "P/(E* ΔR) = {load}: half-angle {measured}° vs Persson's {persson}°"
        );
        assert!(
            (contact + applied).abs() <= 1e-6 * applied,
            "contact resultant {contact} vs the load {applied}"
        );
        let tangential = rows.iter().map(|r| r.2.abs()).fold(0.0, f64::max);
        assert_eq!(tangential, 0.0, "frictionless: tangential traction");
        angles.push(persson);
    }
    // The loads span small to large arcs.
    assert!(angles[0] < 25.0 && angles[3] > 75.0, "{angles:?}");
}

/// `geo/stacked_blocks.geo` with `nb` blocks and `[contact]`, the other keys in `rest`.
fn stack_scene(nb: usize, mesh_extra: &str, rest: &str) -> String {
    stack_scene_with(nb, mesh_extra, "[0.0, -2.0]", rest)
}

/// `stack_scene` with the blocks' body force `force`.
fn stack_scene_with(nb: usize, mesh_extra: &str, force: &str, rest: &str) -> String {
    format!(
        "title = \"stacked blocks found by [contact]\"\nplane = \"strain\"\n\
         [mesh]\nfile = \"{}\"\nnb = {nb}\n{mesh_extra}\n\
         [defaults.body]\nyoung = 1000.0\npoisson = 0.2\nbody_force = {force}\n\
         [boundary.base]\nux = 0.0\nuy = 0.0\n{rest}",
        geo("stacked_blocks")
    )
}

/// `sgbem check` of `scene` written into `dir` as `name`, which must refuse it (exit 2): its
/// message.
fn refused(dir: &Path, name: &str, scene: &str) -> String {
    let s = support::write(dir, name, scene);
    let (code, _, err) = support::sgbem(&["check", s.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    err
}

/// Five blocks drawn and meshed on their own (no joint with matching nodes, every other
/// block shifted by a quarter of its width) under self-weight γ = 2: `[contact]` finds the
/// four joints, and each carries the weight of the blocks above it, γ w h (5 − i), to 1e-8
/// with no tangential resultant.
#[test]
fn contact_finds_the_joints_of_separately_drawn_blocks() {
    let dir = support::tmpdir("stack_found");
    let nb = 5;
    let rest = "[contact]\nsearch = 1e-6\n\
                [defaults.interface]\nmodel = \"unilateral\"\ntangential = \"friction\"\n\
                friction = 0.6\n[output]\nvtk = false\n";
    let scene = stack_scene(nb, "", rest);
    let s = support::write(&dir, "check.toml", &scene);
    let (code, text, err) = support::sgbem(&["check", s.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    for i in 1..nb {
        let name = format!("contact[block_{}|block_{i}]", i - 1);
        assert!(text.contains(&name), "check does not list {name}: {text}");
    }
    assert!(text.contains("found by [contact]"), "{text}");
    let (_, summary) = run(&dir, &scene, "contact[block_0|block_1]");
    assert_eq!(summary["status"], "converged");
    let found = summary["interfaces"].as_object().unwrap();
    assert_eq!(found.len(), nb - 1, "{found:?}");
    for i in 1..nb {
        let f = &summary["interfaces"][format!("contact[block_{}|block_{i}]", i - 1)];
        let weight = 2.0 * 1.0 * 0.5 * (nb - i) as f64;
        let n = f["normal_resultant"].as_f64().unwrap();
        let t = f["tangential_resultant"].as_f64().unwrap();
        println!(
            "joint {i}: normal resultant {n:.12} (weight above {weight}), relative error \
             {:.1e}; tangential {t:.1e}; open pairs {} of {}",
            (n + weight).abs() / weight,
            f["open_pairs"],
            f["pairs"]
        );
        assert!(
            (n + weight).abs() <= 1e-8 * weight,
            "joint {i}: {n} vs {weight}"
        );
        assert!(t.abs() <= 1e-8 * weight, "joint {i}: tangential {t}");
    }
}

/// Two blocks 1 × 0.5 drawn side by side on a base block 2 wide, each meshed on its own: 4 and
/// 5 elements under the blocks, `nbase` on the base's top. With `nbase` = 7 the base's
/// element across the head joint (x = 1) faces both blocks; `[contact]` cuts it there
/// (`detect::cuts`), so that each block's joint with the base takes its own part of it.
/// Each block then rests on its own joint: its weight γ w h = 0.5 to 1e-6, the head joint
/// open. Before the cut the element went to one joint only and the other block lost its
/// support over it: 8.4 % of the left block's weight went through the head joint into
/// its neighbour (0.4578 on its own joint). The evolutive path (`method = "lcp"`, not the
/// default here: the three bodies meet at a junction), whose head joint carries nothing at the
/// junction node; with every row (`exact`) its closed stick rows there pass 6.8e-6 (1.4e-5 of
/// a block's weight 0.5) from one block to the other.
#[test]
fn blocks_drawn_side_by_side_rest_each_on_its_own_joint() {
    let dir = support::tmpdir("side_by_side");
    let geo_text = "Geometry.AutoCoherence = 0;\n\
        DefineConstant[ nbase = {7, Name \"Parameters/nbase\"} ];\n\
        Point(1) = {0, -0.5, 0}; Point(2) = {2, -0.5, 0}; Point(3) = {2, 0, 0}; Point(4) = {0, 0, 0};\n\
        Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};\n\
        Transfinite Curve{3} = nbase + 1; Transfinite Curve{1} = 9; Transfinite Curve{2, 4} = 4;\n\
        Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};\n\
        Point(11) = {0, 0, 0}; Point(12) = {1, 0, 0}; Point(13) = {1, 0.5, 0}; Point(14) = {0, 0.5, 0};\n\
        Line(11) = {11, 12}; Line(12) = {12, 13}; Line(13) = {13, 14}; Line(14) = {14, 11};\n\
        Transfinite Curve{11, 13} = 5; Transfinite Curve{12, 14} = 4;\n\
        Curve Loop(2) = {11, 12, 13, 14}; Plane Surface(2) = {2};\n\
        Point(21) = {1, 0, 0}; Point(22) = {2, 0, 0}; Point(23) = {2, 0.5, 0}; Point(24) = {1, 0.5, 0};\n\
        Line(21) = {21, 22}; Line(22) = {22, 23}; Line(23) = {23, 24}; Line(24) = {24, 21};\n\
        Transfinite Curve{21, 23} = 6; Transfinite Curve{22, 24} = 4;\n\
        Curve Loop(3) = {21, 22, 23, 24}; Plane Surface(3) = {3};\n\
        Physical Surface(\"base\") = {1}; Physical Surface(\"left\") = {2};\n\
        Physical Surface(\"right\") = {3}; Physical Curve(\"bottom\") = {1};\n\
        Physical Curve(\"faces\") = {2, 3, 4, 11, 12, 13, 14, 21, 22, 23, 24};\n";
    support::write(&dir, "side_by_side.geo", geo_text);
    for (nbase, cuts) in [(7, 1), (8, 0)] {
        let scene = format!(
            "title = \"two blocks on one\"\nplane = \"strain\"\n\
             [mesh]\nfile = \"side_by_side.geo\"\nnbase = {nbase}\n\
             [defaults.body]\nyoung = 1.0e4\npoisson = 0.2\nbody_force = [0.0, -1.0]\n\
             [boundary.bottom]\nux = 0.0\nuy = 0.0\n[contact]\nsearch = 1e-6\n\
             [defaults.interface]\nmodel = \"unilateral\"\ntangential = \"stick\"\n\
             [solve]\nmethod = \"lcp\"\n[output]\nvtk = false\n"
        );
        let s = support::write(&dir, "scene.toml", &scene);
        let (code, text, err) = support::sgbem(&["check", s.to_str().unwrap(), "--json"]);
        assert_eq!(code, 0, "{err}");
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(v["mesh"]["contact_cuts"], cuts, "nbase {nbase}");
        let (_, summary) = run(&dir, &scene, "contact[base|left]");
        assert_eq!(summary["counts"]["contact_cuts"], cuts, "nbase {nbase}");
        for block in ["left", "right"] {
            let f = &summary["interfaces"][format!("contact[base|{block}]")];
            let n = f["normal_resultant"].as_f64().unwrap();
            println!("nbase {nbase}: {block} block's joint carries {n:.10} of its weight 0.5");
            if cuts > 0 {
                assert!((n + 0.5).abs() < 1e-6, "{block}: {n}");
            } else {
                // Matching nodes at the head joint, no cut: the base's deformation leans the
                // blocks on each other slightly (measured 0.2 %).
                assert!((n + 0.5).abs() < 5e-3, "{block}: {n}");
            }
        }
    }
}

/// A declared interface between the same boundaries wins over `[contact]`; a scene whose
/// bodies overlap is refused naming both bodies and the depth; `[contact]` needs
/// `[defaults.interface]`.
#[test]
fn contact_declared_interfaces_win_and_overlaps_are_refused() {
    let dir = support::tmpdir("stack_rules");
    let iface = "[defaults.interface]\nmodel = \"unilateral\"\n";
    // Two blocks; the Physical Curve "faces" declared as the interface.
    let scene = stack_scene(
        2,
        "",
        &format!("[contact]\nsearch = 1e-6\n{iface}[interface.faces]\nmodel = \"bonded\"\n"),
    );
    let s = support::write(&dir, "declared.toml", &scene);
    let (code, text, err) = support::sgbem(&["check", s.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let names: Vec<&str> = v["interfaces"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| i["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["faces"]);

    // Block 1 drawn 0.01 into block 0.
    let scene = stack_scene(
        2,
        "sink = 0.01",
        &format!("[contact]\nsearch = 1e-3\n{iface}"),
    );
    let err = refused(&dir, "overlap.toml", &scene);
    assert!(
        err.contains("\"block_0\"")
            && err.contains("\"block_1\"")
            && err.contains("overlap by 0.01"),
        "{err}"
    );
    // The user's .geo is named, not the mesh gmsh made of it in a folder since removed.
    assert!(
        err.contains("stacked_blocks.geo") && err.contains("in the mesh gmsh made of this .geo"),
        "{err}"
    );
    assert!(!err.contains("sgbem-check"), "{err}");

    // A block drawn inside another: refused with both names and the depth, the distance of
    // its deepest node (a corner 0.3 from every side of the outer block) from the outer one's
    // boundary.
    let nested = "Geometry.AutoCoherence = 0;\n\
        Point(1) = {0, 0, 0}; Point(2) = {1, 0, 0}; Point(3) = {1, 1, 0}; Point(4) = {0, 1, 0};\n\
        Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};\n\
        Point(5) = {0.3, 0.3, 0}; Point(6) = {0.7, 0.3, 0}; Point(7) = {0.7, 0.7, 0};\n\
        Point(8) = {0.3, 0.7, 0};\n\
        Line(5) = {5, 6}; Line(6) = {6, 7}; Line(7) = {7, 8}; Line(8) = {8, 5};\n\
        Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};\n\
        Curve Loop(2) = {5, 6, 7, 8}; Plane Surface(2) = {2};\n\
        Transfinite Curve{1:8} = 3;\n\
        Physical Surface(\"outer\") = {1}; Physical Surface(\"inner\") = {2};\n\
        Physical Curve(\"base\") = {1}; Physical Curve(\"faces\") = {2, 3, 4, 5, 6, 7, 8};\n";
    let g = support::write(&dir, "nested.geo", nested);
    let scene = format!(
        "title = \"nested\"\nplane = \"strain\"\n[mesh]\nfile = \"{}\"\n\
         [defaults.body]\nyoung = 1000.0\npoisson = 0.2\n[boundary.base]\nux = 0.0\nuy = 0.0\n\
         [contact]\nsearch = 1e-3\n{iface}",
        g.display()
    );
    let err = refused(&dir, "nested.toml", &scene);
    assert!(
        err.contains("body \"inner\" lies inside body \"outer\"")
            && err.contains("overlap by 0.3")
            && err.contains("nested.geo"),
        "{err}"
    );

    // No [defaults.interface].
    let scene = stack_scene(2, "", "[contact]\nsearch = 1e-6\n");
    let err = refused(&dir, "nodefault.toml", &scene);
    assert!(err.contains("[defaults.interface]"), "{err}");
}

/// `between = [A, B]`: the interface over two Physical Curves, one on each block; the same
/// exact pressure as the curve that holds both. Its mistakes are input errors.
#[test]
fn between_names_the_two_sides_of_an_interface() {
    let dir = support::tmpdir("between");
    let q = 2.5;
    let rest = |joint: &str| {
        format!(
            "[body.upper]\nyoung = 1000.0\npoisson = 0.3\n\
             [body.lower]\nyoung = 1000.0\npoisson = 0.3\n\
             [boundary.top]\nty = -{q}\n[boundary.base]\nuy = 0.0\n[boundary.left]\nux = 0.0\n\
             [interface.joint]\n{joint}\n"
        )
    };
    let good = rest("model = \"bonded\"\nbetween = [\"upper_bottom\", \"lower_top\"]");
    let (rows, _) = run(&dir, &patch_scene(10, 7, &good), "joint");
    let (dev, tt) = deviations(&rows, q);
    assert!(dev <= 1e-8 * q && tt <= 1e-8 * q, "{dev:e} {tt:e}");
    // The CSV says which body each row is at and the element of the other that it faces.
    for r in &rows {
        assert_eq!(r.0["side"], "upper");
        let tag: usize = r.0["segment"].parse().expect("a gmsh element tag");
        assert!(tag > 0);
    }
    // The archive keeps the pairing: per pair its row over the lower block's nodes, whose
    // coefficients sum to one and reproduce the pair's position; the weights add up to the
    // interface's length.
    let rec = sgbem::output::archive::read_archive(&dir.join("out").join("archive.h5")).unwrap();
    let it = &rec.interfaces[0];
    let pr = it.pairing.as_ref().expect("the archive keeps the pairing");
    assert_eq!(pr.offset.len(), 8 + 1);
    let lower = &rec.bodies[it.body_b].nodes;
    for j in 0..8 {
        let (lo, hi) = (pr.offset[j], pr.offset[j + 1]);
        let sum: f64 = pr.coef[lo..hi].iter().sum();
        let x: f64 = (lo..hi).map(|m| pr.coef[m] * lower[pr.node[m]][0]).sum();
        assert!(
            (sum - 1.0).abs() < 1e-14 && (x - it.x[j][0]).abs() < 1e-12,
            "pair {j}"
        );
    }
    assert!((pr.weight.iter().sum::<f64>() - 2.0).abs() < 1e-12);
    assert_eq!(pr.b_nodes.len(), 11);
    for (joint, culprit) in [
        (
            "model = \"bonded\"\nbetween = [\"upper_bottom\", \"nope\"]",
            "no Physical Curve named so",
        ),
        (
            "model = \"bonded\"\nbetween = [\"upper_bottom\"]",
            "must name two different Physical Curves",
        ),
    ] {
        let s = support::write(&dir, "bad.toml", &patch_scene(10, 7, &rest(joint)));
        let (code, _, err) = support::sgbem(&["check", s.to_str().unwrap()]);
        assert_eq!(code, 2, "{err}");
        assert!(
            err.contains("interface.joint.between") && err.contains(culprit),
            "{err}"
        );
    }
}

/// The joint count that `pipelines/stones.py` writes into a .geo's header.
fn joints_drawn(geo_text: &str) -> usize {
    geo_text
        .lines()
        .find_map(|l| l.strip_prefix("// Joints: "))
        .and_then(|l| l.split_whitespace().next())
        .and_then(|n| n.parse().ok())
        .expect("the generator's joint count in the .geo header")
}

/// Walls of other seeds and sizes from `pipelines/stones.py`, as a user would generate
/// them: `[contact]` finds exactly the joints drawn. Before faces that touch at one point
/// at an angle were kept apart, 14 of 21 such walls failed: seed 1 and 4 ("no part of body
/// stone_N faces body foundation": a stone's corner on the foundation), 5 (151 joints of
/// 150), 7 (a false overlap of stones 55 and 56 by 0.0028: a wedge's face lent to their joint).
#[test]
fn generated_stone_walls_have_exactly_their_joints_found() {
    let dir = support::tmpdir("stones_generated");
    let scene_text =
        std::fs::read_to_string(support::root().join("pipelines/stone_wall.toml")).unwrap();
    // (stones, seed, Lloyd iterations): plain Voronoi cells (0) have small faces and
    // corners on the foundation: with 60 stones seed 2, a stone whose bottom (1.5 elements
    // long) lay on two elements of the foundation that each faced a neighbour too ("no part
    // of body stone_8 faces body foundation" before the cuts of `detect::cuts`); with 100
    // seed 3, a stone's corner on the foundation with a face rising at 20° (a pair with no
    // rows before `apart_mid_overlap`).
    for (stones, seed, lloyd) in [
        (60, 1, 4),
        (60, 4, 4),
        (60, 5, 4),
        (60, 7, 4),
        (60, 2, 0),
        (100, 3, 0),
    ] {
        let geo_path = dir.join(format!("wall_{stones}_{seed}_{lloyd}.geo"));
        let o = std::process::Command::new("python3")
            .arg(support::root().join("pipelines/stones.py"))
            .args([
                "--stones",
                &stones.to_string(),
                "--width",
                "3",
                "--height",
                "1.5",
            ])
            .args(["--lloyd", &lloyd.to_string()])
            .args(["--seed", &seed.to_string(), "--out"])
            .arg(&geo_path)
            .output()
            .expect("python3 runs pipelines/stones.py");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let joints = joints_drawn(&std::fs::read_to_string(&geo_path).unwrap());
        let scene = dir.join(format!("wall_{stones}_{seed}_{lloyd}.toml"));
        std::fs::write(
            &scene,
            scene_text.replace("../geo/stone_wall.geo", geo_path.to_str().unwrap()),
        )
        .unwrap();
        let (code, out, err) = support::sgbem(&["check", scene.to_str().unwrap(), "--json"]);
        assert_eq!(
            code, 0,
            "{stones} stones, seed {seed}, lloyd {lloyd}: {err}"
        );
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        let found = v["interfaces"].as_array().unwrap().len();
        println!(
            "stones.py --stones {stones} --seed {seed} --lloyd {lloyd}: {found} joints found \
             of {joints} drawn"
        );
        assert_eq!(found, joints, "{stones} stones, seed {seed}, lloyd {lloyd}");
    }
}

/// The shipped stone wall (`pipelines/stone_wall.toml` on `geo/stone_wall.geo`, written by
/// `pipelines/stones.py`): `[contact]` finds every joint that the generator counted, and
/// every stone is in one.
#[test]
fn stone_wall_joints_are_all_found() {
    let joints = joints_drawn(&std::fs::read_to_string(geo("stone_wall")).unwrap());
    let scene = support::root().join("pipelines/stone_wall.toml");
    let (code, out, err) = support::sgbem(&["check", scene.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let bodies = v["bodies"].as_array().unwrap().len();
    let found = v["interfaces"].as_array().unwrap();
    println!(
        "stone wall: {bodies} bodies, {} interfaces found, {joints} joints drawn",
        found.len()
    );
    assert!(bodies > 200);
    assert_eq!(found.len(), joints);
    let mut in_joint = std::collections::BTreeSet::new();
    for i in found {
        assert!(i["name"].as_str().unwrap().starts_with("contact["));
        in_joint.insert(i["body_a"].as_str().unwrap().to_string());
        in_joint.insert(i["body_b"].as_str().unwrap().to_string());
    }
    assert_eq!(in_joint.len(), bodies);
}

/// The bricks of a wall of `courses` courses of `bricks` whole bricks 0.4 wide, odd courses
/// shifted by `bond` bricks with a part brick at each end (none with bond = 0), in the order
/// of `geo/wall.geo` and `geo/wall_drawn.geo`: brick_1, brick_2, ... is (course, x0, x1).
fn running_bond(courses: usize, bricks: usize, bond: f64) -> Vec<(usize, f64, f64)> {
    let w = 0.4;
    let mut out = Vec::new();
    for c in 0..courses {
        let mut edges: Vec<f64> = if c % 2 == 1 && bond > 0.0 {
            std::iter::once(0.0)
                .chain((0..bricks).map(|i| (i as f64 + bond) * w))
                .collect()
        } else {
            (0..bricks).map(|i| i as f64 * w).collect()
        };
        edges.push(bricks as f64 * w);
        out.extend(edges.windows(2).map(|e| (c, e[0], e[1])));
    }
    out
}

/// The cuts that `[contact]` makes in `geo/wall_drawn.geo` with nj = 4 (element size
/// hs = 0.05): at each end of a head joint, the element of the brick (or the foundation)
/// across the bed that spans it, unless the joint meets that element within 5 % of its
/// length from a node. A brick w wide has n = ceil(w / hs) elements on its bottom and n + 1
/// on its top, the foundation L wide ceil(L / hs) + 1 on its top.
fn drawn_wall_cuts(layout: &[(usize, f64, f64)], courses: usize, length: f64) -> usize {
    let hs = 0.05;
    let n = |w: f64| (w / hs - 1e-9).ceil();
    // Whether x falls inside an element of [x0, x1] cut into m equal ones, clear of its ends.
    let cut = |x: f64, (x0, x1): (f64, f64), m: f64| {
        let t = (x - x0) / ((x1 - x0) / m);
        x0 < x && x < x1 && (t - t.round()).abs() >= 0.05 - 1e-9
    };
    let spans = |c: usize| layout.iter().filter(move |b| b.0 == c).map(|b| (b.1, b.2));
    let mut count = 0;
    for k in 1..layout.len() {
        let (c, x) = (layout[k].0, layout[k].1);
        if layout[k - 1].0 != c {
            continue;
        }
        count += if c == 0 {
            usize::from(cut(x, (0.0, length), n(length) + 1.0))
        } else {
            spans(c - 1)
                .filter(|&s| cut(x, s, n(s.1 - s.0) + 1.0))
                .count()
        };
        if c + 1 < courses {
            count += spans(c + 1).filter(|&s| cut(x, s, n(s.1 - s.0))).count();
        }
    }
    count
}

/// The course of a body of the drawn wall by name: `brick_K` from `running_bond`, the
/// foundation below the first course (None).
fn course_of(bricks: &[(usize, f64, f64)], name: &str) -> Option<usize> {
    let k: usize = name.strip_prefix("brick_")?.parse().ok()?;
    Some(bricks[k - 1].0)
}

/// The two bodies of an interface `contact[A|B]` (or `joints[A|B]`).
fn bodies_of(name: &str) -> (String, String) {
    let inner = name
        .split_once('[')
        .and_then(|(_, r)| r.strip_suffix(']'))
        .unwrap_or_else(|| panic!("not a joint between two bodies: {name}"));
    let (a, b) = inner.split_once('|').expect("A|B");
    (a.to_string(), b.to_string())
}

/// A wall of `courses` x `bricks` under self-weight 20 (0.4 x 0.2 bricks: 1.6 each) and a
/// wind `wind` on its left end; drawn brick by brick on a foundation (`geo/wall_drawn.geo`,
/// `[contact]`, the foundation 1000 times stiffer than the bricks) or conforming on a clamped
/// base (`geo/wall.geo`, its Physical Curve `joints`); odd courses shifted by `bond` bricks;
/// every joint `law`.
fn brick_wall_scene(
    drawn: bool,
    (courses, bricks, bond): (usize, usize, f64),
    wind: f64,
    law: &str,
) -> String {
    let (file, extra) = if drawn {
        (
            geo("wall_drawn"),
            "[body.foundation]\nyoung = 5.0e9\npoisson = 0.2\n[contact]\nsearch = 1e-6\n",
        )
    } else {
        (geo("wall"), "")
    };
    format!(
        "title = \"running-bond wall\"\nplane = \"strain\"\n\
         [mesh]\nfile = \"{file}\"\ncourses = {courses}\nbricks = {bricks}\nbond = {bond}\n\
         nj = 4\n\
         [defaults.body]\nyoung = 5.0e6\npoisson = 0.2\nbody_force = [0.0, -20.0]\n{extra}\
         [boundary.base]\nux = 0.0\nuy = 0.0\n[boundary.left]\ntx = {wind}\n\
         [defaults.interface]\nmodel = \"unilateral\"\n{law}\n\
         [output]\nvtk = false\nhistory = \"final\"\n"
    )
}

/// A running-bond wall drawn brick by brick (`geo/wall_drawn.geo`: every brick its own
/// rectangle, meshed on its own) is found joint by joint: `[contact]` finds exactly the
/// joints drawn, b on the foundation, 2b per bed between courses (b in a stack bond) and
/// b - 1 or b head joints per course, each between bricks that touch in the drawing; the
/// elements across a bed from the ends of each head joint are cut there (`drawn_wall_cuts`:
/// with half a brick's bond only the brick's top, or the foundation's, under the joint);
/// every curve drawn is in the mesh.
#[test]
fn a_wall_drawn_brick_by_brick_has_exactly_its_joints_found() {
    let dir = support::tmpdir("wall_drawn_check");
    for (courses, bricks, bond) in [
        (4, 3, 0.5),
        (5, 2, 0.5),
        (3, 5, 0.5),
        (4, 3, 0.3),
        (3, 3, 0.0),
    ] {
        let layout = running_bond(courses, bricks, bond);
        let in_course = |c: usize| layout.iter().filter(|b| b.0 == c).count();
        let heads: usize = (0..courses).map(|c| in_course(c) - 1).sum();
        let per_bed = if bond > 0.0 { 2 * bricks } else { bricks };
        let joints = bricks + (courses - 1) * per_bed + heads;
        let cuts = drawn_wall_cuts(&layout, courses, 0.4 * bricks as f64);
        if bond == 0.5 {
            assert_eq!(cuts, heads);
        }
        let scene = brick_wall_scene(true, (courses, bricks, bond), 1.0, "tangential = \"stick\"");
        let s = support::write(&dir, "scene.toml", &scene);
        let (code, out, err) = support::sgbem(&["check", s.to_str().unwrap(), "--json"]);
        assert_eq!(code, 0, "{err}");
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        let found = v["interfaces"].as_array().unwrap();
        println!(
            "drawn wall {courses} x {bricks}, bond {bond}: {} bricks, {} joints found of \
             {joints} drawn, {} cuts ({cuts} expected)",
            layout.len(),
            found.len(),
            v["mesh"]["contact_cuts"]
        );
        assert_eq!(v["bodies"].as_array().unwrap().len(), layout.len() + 1);
        // Every curve drawn is meshed (gmsh 4.8 drops a curve of no Physical group): with
        // hs = 0.05, a brick w wide has ceil(w / hs) elements on its bottom, one more on its
        // top, 4 and 5 on its sides; the foundation L wide and 0.2 high ceil(L / hs), one
        // more, and 4 on each side; each cut adds one.
        let sides = |w: f64| {
            let n = (w / 0.05 - 1e-9).ceil() as usize;
            2 * n + 1
        };
        let drawn: usize = layout.iter().map(|b| sides(b.2 - b.1) + 9).sum::<usize>()
            + sides(0.4 * bricks as f64)
            + 8;
        assert_eq!(v["boundary_elements"]["count"], drawn + cuts);
        assert_eq!(found.len(), joints, "{courses} x {bricks}, bond {bond}");
        assert_eq!(
            v["mesh"]["contact_cuts"], cuts,
            "{courses} x {bricks}, bond {bond}"
        );
        // Every joint found joins bricks that touch in the drawing: neighbours in a course,
        // or bricks of consecutive courses whose spans overlap (the foundation: course 0).
        for i in found {
            let (a, b) = bodies_of(i["name"].as_str().unwrap());
            let span = |n: &str| match n.strip_prefix("brick_") {
                Some(k) => {
                    let (c, x0, x1) = layout[k.parse::<usize>().unwrap() - 1];
                    (c as i64, x0, x1)
                }
                None => (-1, 0.0, 0.4 * bricks as f64),
            };
            let ((ca, a0, a1), (cb, b0, b1)) = (span(&a), span(&b));
            let touch = if ca == cb {
                (a1 - b0).abs() < 1e-12 || (b1 - a0).abs() < 1e-12
            } else {
                (ca - cb).abs() == 1 && a0.max(b0) < a1.min(b1) - 1e-12
            };
            assert!(touch, "{a} and {b} do not touch");
        }
    }
}

/// The force of interface `iface` (or of boundary part `part`) on `body`: summary.json's
/// `equilibrium`, (fx, fy).
fn load_on(summary: &serde_json::Value, body: &str, key: &str) -> (f64, f64) {
    let l = &summary["equilibrium"][body]["loads"][key];
    let f = |c: &str| {
        l[c].as_f64()
            .unwrap_or_else(|| panic!("{body}: no load {key}"))
    };
    (f("fx"), f("fy"))
}

/// The drawn wall of 4 courses of 3 bricks (14 bricks, every joint found by `[contact]`, no
/// joint with matching nodes) under self-weight only, stick joints: the bed joints under
/// each course together carry the weight of that course and the courses above it, 4.8 per
/// course, to 1e-8, and the foundation carries the whole wall's.
#[test]
fn a_wall_drawn_brick_by_brick_carries_its_weight_course_by_course() {
    let dir = support::tmpdir("wall_drawn_weight");
    let (courses, bricks) = (4, 3);
    let layout = running_bond(courses, bricks, 0.5);
    let scene = brick_wall_scene(true, (courses, bricks, 0.5), 0.0, "tangential = \"stick\"");
    let (_, summary) = run(&dir, &scene, "contact[foundation|brick_1]");
    assert_eq!(summary["status"], "converged");
    let course_weight = 20.0 * 0.4 * 0.2 * bricks as f64;
    let mut below = vec![0.0; courses];
    let mut tangential = vec![0.0; courses];
    for (name, f) in summary["interfaces"].as_object().unwrap() {
        let (a, b) = bodies_of(name);
        let (ca, cb) = (course_of(&layout, &a), course_of(&layout, &b));
        let upper = match (ca, cb) {
            (None, Some(c)) | (Some(c), None) => c,
            (Some(x), Some(y)) if x != y => x.max(y),
            _ => continue,
        };
        below[upper] += f["normal_resultant"].as_f64().unwrap();
        tangential[upper] += f["tangential_resultant"].as_f64().unwrap();
    }
    for c in 0..courses {
        let weight = course_weight * (courses - c) as f64;
        let error = (below[c] + weight).abs() / weight;
        println!(
            "drawn wall, course {}: its bed joints carry {:.12} (weight above {weight:.1}), \
             relative error {error:.1e}; tangential {:.1e}",
            c + 1,
            -below[c],
            tangential[c]
        );
        assert!(error <= 1e-8, "course {}: {} vs {weight}", c + 1, below[c]);
        assert!(tangential[c].abs() <= 1e-8 * weight, "course {}", c + 1);
    }
    let weight = course_weight * courses as f64;
    let (mut fx, mut fy) = (0.0, 0.0);
    for k in 0..bricks {
        let (x, y) = load_on(
            &summary,
            "foundation",
            &format!("interface contact[foundation|brick_{}]", k + 1),
        );
        fx += x;
        fy += y;
    }
    let (bx, by) = load_on(&summary, "foundation", "boundary base");
    println!(
        "drawn wall: the bricks on the foundation ({fx:.1e}, {fy:.12}), its base \
         ({bx:.1e}, {by:.12}); weight {weight}"
    );
    assert!((fy + weight).abs() <= 1e-8 * weight && fx.abs() <= 1e-8 * weight);
    assert!((by - weight).abs() <= 1e-8 * weight && bx.abs() <= 1e-8 * weight);
}

/// The same wall of 4 courses of 3 bricks drawn brick by brick (`geo/wall_drawn.geo`,
/// `[contact]`, on a foundation 1000 times stiffer than the bricks) and conforming
/// (`geo/wall.geo`, clamped base), self-weight and a wind of 1 on the left end, stick
/// joints. Both put on the ground the weight 19.2 and the wind 0.8 to 1e-8 (equilibrium);
/// the bed joints under bricks 5 and 8 (their overlaps with bricks 2 and 5) carry nearly
/// the same: measured |ΔN| = 1.9e-3 and 3.2e-3 of N, |ΔT| = 3.1e-3 and 3.7e-3 of N (the
/// meshes differ, and the foundation is stiff, not rigid); asserted within 1e-2 of N.
#[test]
fn a_wall_drawn_brick_by_brick_matches_the_conforming_one() {
    let (courses, bricks, wind) = (4, 3, 1.0);
    let law = "tangential = \"stick\"";
    let weight = 20.0 * 0.4 * 0.2 * (courses * bricks) as f64;
    let push = wind * 0.2 * courses as f64;
    let (_, drawn) = run(
        &support::tmpdir("wall_drawn_vs_conforming"),
        &brick_wall_scene(true, (courses, bricks, 0.5), wind, law),
        "contact[brick_2|brick_5]",
    );
    let (_, conforming) = run(
        &support::tmpdir("wall_conforming_vs_drawn"),
        &brick_wall_scene(false, (courses, bricks, 0.5), wind, law),
        "joints[brick_2|brick_5]",
    );
    assert_eq!(drawn["status"], "converged");
    assert_eq!(conforming["status"], "converged");
    // The force of the wall on what holds it: the foundation's joints, the clamped base.
    let (mut d, mut c) = ((0.0, 0.0), (0.0, 0.0));
    for k in 1..=bricks {
        let x = load_on(
            &drawn,
            "foundation",
            &format!("interface contact[foundation|brick_{k}]"),
        );
        let y = load_on(&conforming, &format!("brick_{k}"), "boundary base");
        d = (d.0 + x.0, d.1 + x.1);
        c = (c.0 - y.0, c.1 - y.1);
    }
    println!(
        "on the ground: drawn ({:.12}, {:.12}), conforming ({:.12}, {:.12}); wind {push}, \
         weight {weight}",
        d.0, d.1, c.0, c.1
    );
    for (fx, fy) in [d, c] {
        assert!((fx - push).abs() <= 1e-8 * weight, "horizontal {fx}");
        assert!((fy + weight).abs() <= 1e-8 * weight, "vertical {fy}");
    }
    for (a, b) in [(2, 5), (5, 8)] {
        let f = |s: &serde_json::Value, name: &str, key: &str| {
            s["interfaces"][format!("{name}[brick_{a}|brick_{b}]")][key]
                .as_f64()
                .unwrap_or_else(|| panic!("{name}[brick_{a}|brick_{b}]"))
        };
        let (nd, td) = (
            f(&drawn, "contact", "normal_resultant"),
            f(&drawn, "contact", "tangential_resultant"),
        );
        let (nc, tc) = (
            f(&conforming, "joints", "normal_resultant"),
            f(&conforming, "joints", "tangential_resultant"),
        );
        let (dn, dt) = ((nd - nc).abs() / nc.abs(), (td - tc).abs() / nc.abs());
        println!(
            "bed joint brick_{a}|brick_{b}: drawn N {nd:.6} T {td:.6}, conforming N {nc:.6} \
             T {tc:.6}: |ΔN|/|N| {dn:.2e}, |ΔT|/|N| {dt:.2e}"
        );
        assert!(nd < 0.0 && nc < 0.0, "the bed joint is compressed");
        assert!(dn <= 1e-2 && dt <= 1e-2, "brick_{a}|brick_{b}");
    }
}

/// `geo/stacked_blocks.geo` (`nb` blocks, `shift` of every other one) with `[contact]`, the
/// blocks' body force `force`, the interface law `law` and the rest of the scene `rest`.
fn found_stack(nb: usize, shift: f64, force: &str, law: &str, rest: &str) -> String {
    stack_scene_with(
        nb,
        &format!("shift = {shift}"),
        force,
        &format!(
            "[contact]\nsearch = 1e-6\n[defaults.interface]\nmodel = \"unilateral\"\n{law}\n\
             {rest}\n[output]\nvtk = false\n"
        ),
    )
}

/// The rows of every interface of a run folder.
fn all_rows(out: &Path) -> Vec<Row> {
    let mut rows = Vec::new();
    for e in std::fs::read_dir(out.join("interfaces")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "csv") {
            rows.extend(read_rows(&p));
        }
    }
    rows
}

/// Coulomb's law on every row: |τ| ≤ μ|σ| on closed rows and |τ| = μ|σ| where a row slips,
/// both to `tol`; the number of slipping rows.
fn coulomb_holds(rows: &[Row], mu: f64, tol: f64) -> usize {
    let mut slipping = 0;
    for r in rows.iter().filter(|r| r.closed()) {
        let (n, t) = (r.num("normal_traction"), r.num("tangential_traction"));
        assert!(n <= tol, "a closed row in tension: {n}");
        assert!(
            t.abs() <= mu * n.abs() + tol,
            "|τ| {t} beyond μ|σ| {}",
            mu * n.abs()
        );
        if r.0["tangential_status"] == "slip" {
            slipping += 1;
            assert!(
                (t.abs() - mu * n.abs()).abs() <= tol,
                "a slipping row off its bound: |τ| {t} vs μ|σ| {}",
                mu * n.abs()
            );
        }
    }
    slipping
}

/// Coulomb friction on rows from the geometry, with every solver: three blocks drawn and
/// meshed on their own (no matching nodes, every other block shifted by a quarter of its
/// width) under their weight γ = 2 and 0.45 g sideways, μ = 0.6. Each joint carries the
/// weight above it and 0.45 of it sideways to 1e-8 (measured 1.4e-9 and 3.2e-9), Coulomb's
/// law holds row by row (the rows at the joints' ends slip: 6 of them), and the solvers give
/// the same statuses and tractions (measured within 9.4e-11 of the largest; asserted 1e-8).
#[test]
fn coulomb_friction_on_rows_from_the_drawing_with_every_solver() {
    let (nb, t, mu) = (3, 0.45, 0.6);
    let mut first: Option<Vec<Row>> = None;
    for method in ["lcp", "sparse", "qp", "exact", "both"] {
        let dir = support::tmpdir(&format!("found_coulomb_{method}"));
        let scene = found_stack(
            nb,
            0.25,
            &format!("[{}, -2.0]", 2.0 * t),
            &format!("tangential = \"friction\"\nfriction = {mu}"),
            &format!("[solve]\nmethod = \"{method}\""),
        );
        let (_, summary) = run(&dir, &scene, "contact[block_0|block_1]");
        assert_eq!(summary["status"], "converged", "{method}");
        for i in 1..nb {
            let f = &summary["interfaces"][format!("contact[block_{}|block_{i}]", i - 1)];
            let weight = 2.0 * 0.5 * (nb - i) as f64;
            let (n, s) = (
                f["normal_resultant"].as_f64().unwrap(),
                f["tangential_resultant"].as_f64().unwrap(),
            );
            println!(
                "{method}, joint {i}: N {n:.12} (weight {weight}), T {s:.12} ({})",
                t * weight
            );
            assert!(
                (n + weight).abs() <= 1e-8 * weight,
                "{method}, joint {i}: {n}"
            );
            assert!(
                (s.abs() - t * weight).abs() <= 1e-8 * weight,
                "{method}, joint {i}: {s}"
            );
        }
        let rows = all_rows(&dir.join("out"));
        let big = rows
            .iter()
            .map(|r| r.num("normal_traction").abs())
            .fold(0.0, f64::max);
        let slipping = coulomb_holds(&rows, mu, 1e-8 * big);
        println!("{method}: {slipping} rows slip on their bound");
        assert!(slipping > 0, "{method}: friction is not engaged");
        match &first {
            None => first = Some(rows),
            Some(lcp) => {
                let d = lcp.iter().zip(&rows).fold(0.0f64, |d, (a, b)| {
                    assert_eq!(a.0["status"], b.0["status"], "{method}");
                    assert_eq!(
                        a.0["tangential_status"], b.0["tangential_status"],
                        "{method}"
                    );
                    d.max((a.num("normal_traction") - b.num("normal_traction")).abs())
                        .max((a.num("tangential_traction") - b.num("tangential_traction")).abs())
                });
                println!(
                    "{method} against lcp: tractions within {:.1e} of the largest",
                    d / big
                );
                assert!(d <= 1e-8 * big, "{method}: {d}");
            }
        }
    }
}

/// Cohesion on rows from the geometry: two blocks drawn on their own (5 and 7 elements across
/// the joint), the upper one pulled up by a body force. With a mean tension 0.5 below the
/// cohesion 1 the joint holds closed and carries the pull to 1e-8 with every solver (its
/// largest row traction 0.51); with 1.5 no equilibrium exists: exit 3, and the full rows name
/// the upper block moving up.
#[test]
fn cohesion_on_rows_from_the_drawing_holds_and_breaks() {
    let law = "cohesion = 1.0";
    let upper = |pull: f64| {
        format!("[body.block_1]\nyoung = 1000.0\npoisson = 0.2\nbody_force = [0.0, {pull}]")
    };
    for method in ["lcp", "sparse", "qp", "exact"] {
        let dir = support::tmpdir(&format!("found_cohesion_{method}"));
        let rest = format!("{}\n[solve]\nmethod = \"{method}\"", upper(1.0));
        let scene = found_stack(2, 0.0, "[0.0, -2.0]", law, &rest);
        let (rows, summary) = run(&dir, &scene, "contact[block_1|block_0]");
        assert_eq!(summary["status"], "converged", "{method}");
        let f = &summary["interfaces"]["contact[block_1|block_0]"];
        let n = f["normal_resultant"].as_f64().unwrap();
        println!("{method}: the joint carries {n:.12} in tension (the pull 0.5)");
        assert!((n - 0.5).abs() <= 1e-8 * 0.5, "{method}: {n}");
        assert_eq!(f["open_pairs"], 0, "{method}");
        assert!(rows
            .iter()
            .all(|r| r.closed() && r.num("normal_traction") < 1.0));
    }
    for method in ["lcp", "exact"] {
        let dir = support::tmpdir(&format!("found_cohesion_breaks_{method}"));
        let rest = format!("{}\n[solve]\nmethod = \"{method}\"", upper(3.0));
        let (code, err, _) = sgbem_run(&dir, &found_stack(2, 0.0, "[0.0, -2.0]", law, &rest));
        assert_eq!(code, 3, "{method}: {err}");
        assert!(err.contains("no equilibrium"), "{method}: {err}");
        if method == "exact" {
            assert!(
                err.contains("body \"block_1\" moves along (0.000, 1.000)"),
                "{err}"
            );
        }
    }
}

/// The collapse search on rows from the geometry: a block drawn on its own on another, μ =
/// 0.5, pushed sideways by t times its weight. It slides at t = μ (it would tip only at t =
/// 2): with every solver the search brackets 0.5 within its tolerance, the rigid-block
/// bound is 0.5, and the mechanism is the upper block's translation along x.
#[test]
fn collapse_on_rows_from_the_drawing_slides_at_mu() {
    for method in ["lcp", "sparse", "qp", "exact"] {
        let dir = support::tmpdir(&format!("found_collapse_{method}"));
        let rest =
            format!("[solve]\nmethod = \"{method}\"\ncollapse = {{ max = 0.9, tolerance = 0.01 }}");
        let scene = found_stack(
            2,
            0.0,
            "[\"2*t\", -2.0]",
            "tangential = \"friction\"\nfriction = 0.5",
            &rest,
        );
        let (_, summary) = run(&dir, &scene, "contact[block_0|block_1]");
        let c = &summary["contact"]["collapse"];
        let (lo, hi, bound) = (
            c["multiplier"].as_f64().unwrap(),
            c["collapses_at"].as_f64().unwrap(),
            c["upper_bound"].as_f64().unwrap(),
        );
        println!("{method}: multiplier {lo}, collapses at {hi}, statics bound {bound}");
        assert!(
            lo <= 0.5 && 0.5 <= hi && hi - lo <= 0.01,
            "{method}: [{lo}, {hi}]"
        );
        assert!((bound - 0.5).abs() <= 1e-6, "{method}: {bound}");
        let motion = c["motion"].as_array().unwrap();
        assert_eq!(motion.len(), 1, "{method}: {motion:?}");
        assert_eq!(motion[0]["body"], "block_1");
        assert_eq!(motion[0]["kind"], "translation");
        let d = &motion[0]["direction"];
        assert!(d[0].as_f64().unwrap() > 0.999, "{method}: {d}");
    }
}

/// The shipped `wall_drawn` scene (52 bricks drawn on their own, 134 joints found, Coulomb
/// μ = 0.7, weight and wind; its joints meet at junctions, so the full rows solve it): every
/// body balances to 1e-8 of its loads and every row obeys Coulomb's law to 1e-8 of the
/// largest traction, junction rows included.
#[test]
fn the_shipped_drawn_wall_balances_with_coulomb_on_every_row() {
    let out = support::tmpdir("wall_drawn_shipped").join("out");
    let (code, err) = support::run_shipped("wall_drawn", &out);
    assert_eq!(code, 0, "{err}");
    let summary = support::read_summary(&out);
    assert_eq!(summary["status"], "converged");
    assert_eq!(summary["interfaces"].as_object().unwrap().len(), 134);
    let mut worst: f64 = 0.0;
    for (body, e) in summary["equilibrium"].as_object().unwrap() {
        let scale = e["loads"]
            .as_object()
            .unwrap()
            .values()
            .flat_map(|l| {
                [
                    l["fx"].as_f64().unwrap().abs(),
                    l["fy"].as_f64().unwrap().abs(),
                ]
            })
            .fold(0.0, f64::max);
        for c in ["fx", "fy"] {
            let r = e["imbalance"][c].as_f64().unwrap().abs() / scale;
            worst = worst.max(r);
            assert!(r <= 1e-8, "{body}: imbalance {c} {r:.1e} of its loads");
        }
    }
    let rows = all_rows(&out);
    let big = rows
        .iter()
        .map(|r| r.num("normal_traction").abs())
        .fold(0.0, f64::max);
    let slipping = coulomb_holds(&rows, 0.7, 1e-8 * big);
    println!(
        "wall_drawn: worst imbalance {worst:.1e} of a body's loads; {slipping} of {} rows slip",
        rows.len()
    );
}

/// `sgbem check` states the gmsh parameters it meshed the scene's .geo with, and none where
/// `--mesh` gives a mesh made otherwise (it printed the scene's, which did not make it).
#[test]
fn check_states_gmsh_parameters_only_for_the_mesh_they_made() {
    let dir = support::tmpdir("check_mesh_parameters");
    let scene = stack_scene(
        5,
        "",
        "[contact]\nsearch = 1e-6\n[defaults.interface]\nmodel = \"unilateral\"\n",
    );
    let s = support::write(&dir, "stack.toml", &scene);
    let (code, text, err) = support::sgbem(&["check", s.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(text.contains("by gmsh with nb = 5"), "{text}");
    assert!(text.contains("contact[block_3|block_4]"), "{text}");
    let msh = support::gmsh(
        Path::new(&geo("stacked_blocks")),
        &dir,
        "three.msh",
        false,
        &["-setnumber", "nb", "3"],
    );
    let (code, text, err) = support::sgbem(&[
        "check",
        s.to_str().unwrap(),
        "--mesh",
        msh.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(!text.contains("by gmsh with"), "{text}");
    assert!(
        text.contains("contact[block_1|block_2]") && !text.contains("block_3"),
        "{text}"
    );
}

/// Where the nodes of two sides drawn on their own coincide, pairing from the geometry gives
/// the rows and the results of a shared curve: two blocks 1 × 0.5 drawn (a) on one shared
/// joint curve, declared `[interface.joint]`, and (b) each on its own with 6 elements on
/// either side of the joint, found by `[contact]`; weight and 0.45 g sideways, μ = 0.6. The
/// rows' positions, statuses and tractions agree to 1e-10 of the largest (measured
/// 5.0e-12), and so do the normal resultants.
#[test]
fn coincident_nodes_drawn_apart_give_the_shared_curve_results() {
    let dir = support::tmpdir("coincident_vs_shared");
    let lower = "Point(1) = {0, 0, 0}; Point(2) = {1, 0, 0}; Point(3) = {1, 0.5, 0};\n\
                 Point(4) = {0, 0.5, 0};\n\
                 Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};\n\
                 Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};\n\
                 Point(7) = {1, 1, 0}; Point(8) = {0, 1, 0};\n\
                 Line(6) = {3, 7}; Line(7) = {7, 8}; Line(8) = {8, 4};\n";
    // (a) The upper block's bottom is the lower block's top, line 3 (reversed).
    let shared = format!(
        "{lower}Curve Loop(2) = {{-3, 6, 7, 8}}; Plane Surface(2) = {{2}};\n\
         Transfinite Curve{{1:4, 6:8}} = 7;\n\
         Physical Surface(\"lower\") = {{1}}; Physical Surface(\"upper\") = {{2}};\n\
         Physical Curve(\"base\") = {{1}}; Physical Curve(\"joint\") = {{3}};\n\
         Physical Curve(\"faces\") = {{2, 4, 6, 7, 8}};\n"
    );
    // (b) The upper block on its own: its bottom is its own line 5 between its own points.
    let apart = "Geometry.AutoCoherence = 0;\n\
                 Point(1) = {0, 0, 0}; Point(2) = {1, 0, 0}; Point(3) = {1, 0.5, 0};\n\
                 Point(4) = {0, 0.5, 0};\n\
                 Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};\n\
                 Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};\n\
                 Point(5) = {0, 0.5, 0}; Point(6) = {1, 0.5, 0}; Point(7) = {1, 1, 0};\n\
                 Point(8) = {0, 1, 0};\n\
                 Line(5) = {5, 6}; Line(6) = {6, 7}; Line(7) = {7, 8}; Line(8) = {8, 5};\n\
                 Curve Loop(2) = {5, 6, 7, 8}; Plane Surface(2) = {2};\n\
                 Transfinite Curve{1:8} = 7;\n\
                 Physical Surface(\"lower\") = {1}; Physical Surface(\"upper\") = {2};\n\
                 Physical Curve(\"base\") = {1};\n\
                 Physical Curve(\"faces\") = {2, 3, 4, 5, 6, 7, 8};\n"
        .to_string();
    let law = "model = \"unilateral\"\ntangential = \"friction\"\nfriction = 0.6\n";
    let scene = |geo: &Path, rest: &str| {
        format!(
            "title = \"two blocks\"\nplane = \"strain\"\n[mesh]\nfile = \"{}\"\n\
             [defaults.body]\nyoung = 1000.0\npoisson = 0.2\nbody_force = [0.9, -2.0]\n\
             [boundary.base]\nux = 0.0\nuy = 0.0\n{rest}[output]\nvtk = false\n",
            geo.display()
        )
    };
    let g = support::write(&dir, "shared.geo", &shared);
    let (a, sa) = run(
        &support::tmpdir("coincident_vs_shared_a"),
        &scene(&g, &format!("[interface.joint]\n{law}")),
        "joint",
    );
    let g = support::write(&dir, "apart.geo", &apart);
    let (b, sb) = run(
        &support::tmpdir("coincident_vs_shared_b"),
        &scene(
            &g,
            &format!("[contact]\nsearch = 1e-6\n[defaults.interface]\n{law}"),
        ),
        "contact[lower|upper]",
    );
    assert_eq!(sa["status"], "converged");
    assert_eq!(sb["status"], "converged");
    assert_eq!(a.len(), 7);
    assert_eq!(a.len(), b.len());
    let by_x = |rows: &[Row]| {
        let mut v: Vec<(f64, f64, f64, String, String)> = rows
            .iter()
            .map(|r| {
                (
                    r.num("x"),
                    r.num("normal_traction"),
                    r.num("tangential_traction"),
                    r.0["status"].clone(),
                    r.0["tangential_status"].clone(),
                )
            })
            .collect();
        v.sort_by(|p, q| p.0.total_cmp(&q.0));
        v
    };
    let (a, b) = (by_x(&a), by_x(&b));
    let big = a.iter().map(|r| r.1.abs()).fold(0.0, f64::max);
    let mut d: f64 = 0.0;
    for (p, q) in a.iter().zip(&b) {
        assert!(
            (p.0 - q.0).abs() <= 1e-12,
            "row positions {} vs {}",
            p.0,
            q.0
        );
        assert_eq!((&p.3, &p.4), (&q.3, &q.4), "statuses at x = {}", p.0);
        d = d.max((p.1 - q.1).abs()).max((p.2 - q.2).abs());
    }
    // The interface's orientation may differ between the two (which block is side a): the
    // tractions are per row in its own frame, compared as such above, and so are the
    // resultants' sizes.
    let res = |s: &serde_json::Value, k: &str, key: &str| s["interfaces"][k][key].as_f64().unwrap();
    let (na, nb) = (
        res(&sa, "joint", "normal_resultant"),
        res(&sb, "contact[lower|upper]", "normal_resultant"),
    );
    println!(
        "shared curve against drawn apart: tractions within {:.1e} of the largest; N {na} / {nb}",
        d / big
    );
    assert!(d <= 1e-10 * big, "{d}");
    assert!((na - nb).abs() <= 1e-10 * na.abs(), "{na} vs {nb}");
}
