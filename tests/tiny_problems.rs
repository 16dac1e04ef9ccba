//! Tiny hand-written contact problems with known answers, run through the command line with
//! every contact solver (`--method lcp`, `qp`, `both`, `sparse`): a unique
//! solution, a degenerate one (rows that touch without pressing, dependent rows at a
//! junction), infeasible ones (a block pulled off, pushed beyond friction, tipped over: exit 3
//! with the mechanism named, never "converged") and bodies left free (a frictionless joint
//! that does not hold a block sideways; a block whose start statuses hold it nowhere).
//!
//! The expected numbers follow from statics, so that they hold whatever the discretisation:
//! the joint's normal and tangential resultants balance the loads of the upper block, and its
//! point of application balances their moment (tangential forces on the joint line have no
//! moment about points on it). With ν = 0 the exact elastic fields are linear, which the
//! boundary elements reproduce, so tractions and displacements are exact pair by pair.
//!
//! The scenes: `blocks` — "lower" [0,1] × [0,0.5] clamped at its base y = 0, "upper"
//! [0,1] × [0.5,1] on it, the joint y = 0.5 (8 elements, 9 pairs); the top of "upper" is
//! "load" over x ∈ [0.75, 1] and "top" over [0, 0.75], its left side "push", its right side
//! "right". `tee` — a base block [0,2] × [0,0.5] clamped at y = 0 under two blocks "left"
//! [0,1] × [0.5,1] and "right" [1,2] × [0.5,1]: bed joints "bed_left", "bed_right" and the
//! head joint "head" at x = 1, which meet at the T-junction (1, 0.5).

mod support;

use std::path::{Path, PathBuf};

use serde_json::Value;
use support::*;

/// Every `--method` of `sgbem run`.
const METHODS: [&str; 4] = ["lcp", "qp", "both", "sparse"];

/// Relative tolerance of the answers that statics gives exactly.
const EXACT: f64 = 1e-10;

/// Joint laws: Coulomb friction with μ = 0.5, and stick.
const FRICTION: &str = "tangential = \"friction\"\nfriction = 0.5";
const STICK: &str = "tangential = \"stick\"";

/// ty = −1 over the whole top of the upper block: P = 1 at x = 0.5.
const PRESSED: &str = "[boundary.load]\nty = -1.0\n[boundary.top]\nty = -1.0\n";

/// [`PRESSED`] and a push `tx` on the upper block's left side (its resultant Q = tx / 2 acts
/// 0.25 above the joint).
fn pushed(tx: f64) -> String {
    format!("{PRESSED}[boundary.push]\ntx = {tx:?}\n")
}

/// The two stacked blocks (module comment), `n` elements along the joint.
fn blocks_mesh(n: usize) -> Msh {
    let mut m = Msh::default();
    m.line(1, [0.0, 0.0], [1.0, 0.0], n, &[1]);
    m.line(2, [1.0, 0.0], [1.0, 0.5], n / 2, &[2]);
    m.line(3, [1.0, 0.5], [0.0, 0.5], n, &[3]);
    m.line(4, [0.0, 0.5], [0.0, 0.0], n / 2, &[2]);
    m.line(5, [1.0, 0.5], [1.0, 1.0], n / 2, &[4]);
    m.line(6, [1.0, 1.0], [0.75, 1.0], n / 4, &[5]);
    m.line(7, [0.75, 1.0], [0.0, 1.0], 3 * n / 4, &[6]);
    m.line(8, [0.0, 1.0], [0.0, 0.5], n / 2, &[7]);
    m.surface(1, &[1, 2, 3, 4], &[1]);
    m.surface(2, &[-3, 5, 6, 7, 8], &[2]);
    for (tag, name) in [
        (1, "base"),
        (2, "lower_sides"),
        (3, "joint"),
        (4, "right"),
        (5, "load"),
        (6, "top"),
        (7, "push"),
    ] {
        m.name(1, tag, name);
    }
    m.name(2, 1, "lower");
    m.name(2, 2, "upper");
    m
}

/// The scene of [`blocks_mesh`]: E = 1000, Poisson's ratio `nu`, the base clamped; `loads`
/// (boundary tables of the upper block) and `joint` (keys of the unilateral joint) added.
fn blocks_scene(nu: f64, loads: &str, joint: &str) -> String {
    format!(
        r#"plane = "strain"
[body.lower]
young = 1000.0
poisson = {nu:?}
[body.upper]
young = 1000.0
poisson = {nu:?}
[boundary.base]
ux = 0.0
uy = 0.0
{loads}
[interface.joint]
model = "unilateral"
{joint}
[output]
vtk = false
history = "final"
"#
    )
}

/// The T-junction (module comment), `n` elements along each bed joint.
fn tee_mesh(n: usize) -> Msh {
    let mut m = Msh::default();
    m.line(1, [0.0, 0.0], [2.0, 0.0], 2 * n, &[1]);
    m.line(2, [2.0, 0.0], [2.0, 0.5], n / 2, &[2]);
    m.line(3, [2.0, 0.5], [1.0, 0.5], n, &[4]);
    m.line(4, [1.0, 0.5], [0.0, 0.5], n, &[5]);
    m.line(5, [0.0, 0.5], [0.0, 0.0], n / 2, &[2]);
    m.line(6, [2.0, 0.5], [2.0, 1.0], n / 2, &[2]);
    m.line(7, [2.0, 1.0], [1.0, 1.0], n, &[3]);
    m.line(8, [1.0, 1.0], [1.0, 0.5], n / 2, &[6]);
    m.line(9, [1.0, 1.0], [0.0, 1.0], n, &[3]);
    m.line(10, [0.0, 1.0], [0.0, 0.5], n / 2, &[2]);
    m.surface(1, &[1, 2, 3, 4, 5], &[1]);
    m.surface(2, &[-3, 6, 7, 8], &[2]);
    m.surface(3, &[-4, -8, 9, 10], &[3]);
    for (tag, name) in [
        (1, "base"),
        (2, "sides"),
        (3, "top"),
        (4, "bed_right"),
        (5, "bed_left"),
        (6, "head"),
    ] {
        m.name(1, tag, name);
    }
    m.name(2, 1, "base_block");
    m.name(2, 2, "right");
    m.name(2, 3, "left");
    m
}

/// What one `sgbem run --method METHOD` left.
struct Run {
    method: &'static str,
    code: i32,
    err: String,
    out: PathBuf,
    /// summary.json, where written.
    summary: Option<Value>,
}

impl Run {
    fn summary(&self) -> &Value {
        self.summary
            .as_ref()
            .unwrap_or_else(|| panic!("{}: no summary.json; stderr: {}", self.method, self.err))
    }

    fn figure(&self, iface: &str, key: &str) -> f64 {
        self.summary()["interfaces"][iface][key]
            .as_f64()
            .unwrap_or_else(|| panic!("{}: interfaces.{iface}.{key}", self.method))
    }

    fn thrust_x(&self, iface: &str) -> f64 {
        self.summary()["thrust"][iface]["x"]
            .as_f64()
            .unwrap_or_else(|| panic!("{}: thrust.{iface}.x", self.method))
    }

    fn rows(&self, iface: &str) -> Vec<InterfaceRow> {
        read_interface_csv(&self.out.join(format!("interfaces/{iface}.csv")))
    }

    /// A converged run: exit 0 and status "converged".
    fn assert_converged(&self) {
        assert_eq!(self.code, 0, "{}: {}", self.method, self.err);
        assert!(!self.err.contains("panicked"), "{}", self.err);
        assert_eq!(self.summary()["status"], "converged", "{}", self.method);
    }

    /// The cross-checks the method runs (README, "How it solves"), each converged with no
    /// differing pair; `degenerate` bounds the degenerate pairs each may report.
    fn assert_cross_checks_agree(&self, degenerate: u64) {
        let checks = self.summary()["contact"]["cross_checks"]
            .as_array()
            .unwrap_or_else(|| panic!("{}: no cross_checks", self.method));
        let solvers: Vec<&str> = checks
            .iter()
            .map(|c| c["solver"].as_str().unwrap())
            .collect();
        let expected: &[&str] = match self.method {
            "lcp" | "qp" => &["active-set"],
            "both" => &["active-set", "qp", "lemke"],
            _ => &["lcp"],
        };
        assert_eq!(solvers, expected, "{}", self.method);
        for c in checks {
            assert_eq!(c["converged"], true, "{}: {c}", self.method);
            assert_eq!(c["differing_pairs"], 0, "{}: {c}", self.method);
            let d = c["degenerate_pairs"].as_u64().unwrap();
            assert!(d <= degenerate, "{}: {c}", self.method);
        }
    }

    /// The joint's resultants against statics: N to EXACT of |n|, T to EXACT of the larger
    /// of |n| and |t| (where T vanishes its scale is N), and the thrust point x to EXACT of
    /// `x_scale`.
    fn assert_statics(&self, (n, t): (f64, f64), x: f64, x_scale: f64) {
        let m = self.method;
        let (got_n, got_t) = (
            self.figure("joint", "normal_resultant"),
            self.figure("joint", "tangential_resultant"),
        );
        assert_exact(&format!("{m}: N"), got_n, n, n.abs());
        assert_exact(&format!("{m}: T"), got_t, t, t.abs().max(n.abs()));
        assert_exact(
            &format!("{m}: thrust x"),
            self.thrust_x("joint"),
            x,
            x_scale,
        );
    }

    /// A converged run whose cross-checks agree and whose joint balances the loads: normal
    /// and tangential resultants `nt`, thrust point `x`.
    fn assert_solved(&self, nt: (f64, f64), x: f64) {
        self.assert_converged();
        self.assert_cross_checks_agree(0);
        self.assert_statics(nt, x, 1.0);
    }

    /// A run that found no equilibrium: exit 3, one message naming every word of `words`,
    /// and no output that says "converged".
    fn assert_mechanism(&self, words: &[&str]) {
        expect_exit(&(self.code, String::new(), self.err.clone()), 3, words);
        if let Some(s) = &self.summary {
            assert_eq!(s["status"], "not converged", "{}", self.method);
            assert_eq!(s["contact"]["converged"], false, "{}", self.method);
            // summary.json says why, with the same words as stderr.
            let failure = s["failure"].as_str().unwrap_or_default();
            for w in words {
                assert!(
                    failure.contains(w),
                    "{}: summary failure {failure}",
                    self.method
                );
            }
            assert!(self.err.contains(failure), "{}: {failure}", self.method);
        }
    }
}

/// Runs `scene` on `mesh` with every method, each into its own folder of `dir`.
fn run_all(dir: &Path, scene: &str, mesh: &Msh) -> Vec<Run> {
    let msh = mesh.save(dir, "m.msh");
    let scene = write(dir, "scene.toml", scene);
    METHODS
        .iter()
        .map(|&method| {
            let out = dir.join(method);
            let (code, err, summary) = run_method(&scene, &msh, &out, method);
            Run {
                method,
                code,
                err,
                out,
                summary,
            }
        })
        .collect()
}

/// [`blocks_scene`] on [`blocks_mesh`] with 8 joint elements, with every method, in a fresh
/// folder named after `name`.
fn run_blocks(name: &str, nu: f64, loads: &str, joint: &str) -> Vec<Run> {
    run_all(
        &tmpdir(name),
        &blocks_scene(nu, loads, joint),
        &blocks_mesh(8),
    )
}

/// |got − want| ≤ EXACT · scale.
fn assert_exact(what: &str, got: f64, want: f64, scale: f64) {
    assert!(
        (got - want).abs() <= EXACT * scale,
        "{what}: {got} against {want} (tolerance {:e})",
        EXACT * scale
    );
}

/// The runs give the same statuses pair by pair on `iface` (with friction, the same
/// stick/slip too), and the same tractions within 1e-8 of the largest.
fn assert_same_joint(runs: &[Run], iface: &str) {
    let first = runs[0].rows(iface);
    let scale = first
        .iter()
        .fold(0.0f64, |a, r| a.max(r.tn.abs()).max(r.tt.abs()));
    for run in &runs[1..] {
        let rows = run.rows(iface);
        assert_eq!(rows.len(), first.len(), "{}", run.method);
        for (a, b) in first.iter().zip(&rows) {
            let at = format!("{} against {} at x = {}", run.method, runs[0].method, a.x);
            assert_eq!(a.closed, b.closed, "{at}");
            assert_eq!(a.tangential_status, b.tangential_status, "{at}");
            assert!((a.tn - b.tn).abs() <= 1e-8 * scale, "{at}: {a:?} {b:?}");
            assert!((a.tt - b.tt).abs() <= 1e-8 * scale, "{at}: {a:?} {b:?}");
        }
    }
}

/// (1) Unique solution. The upper block is pressed by ty = −4 over x ∈ [0.75, 1] of its
/// top: P = 4 × 0.25 = 1 at x = 0.875; stick joint, ν = 0.3. The LCP has one solution: the
/// forces of every solution of a symmetric positive semidefinite LCP are the same, and the
/// openings too, since every rigid motion of the upper block that only opens the joint works
/// against P, which lies within the base. Every solver must find it.
///
/// Statics of the upper block (its sides and the rest of its top are free): the joint
/// carries N = P = 1 (normal resultant −1, tension positive), T = 0, and its point of
/// application balances the moment of P: x = 0.875, beyond the kern (1/2 + 1/6), so the heel
/// of the joint opens: open pairs form one run from x = 0 and carry exactly zero, the closed
/// ones at the toe are in compression.
#[test]
fn unique_an_eccentric_load_opens_the_heel_the_same_for_every_solver() {
    let runs = run_blocks("tiny-unique", 0.3, "[boundary.load]\nty = -4.0", STICK);
    for r in &runs {
        r.assert_solved((-1.0, 0.0), 0.875);
        let rows = r.rows("joint");
        let open: Vec<f64> = rows.iter().filter(|p| !p.closed).map(|p| p.x).collect();
        let closed: Vec<f64> = rows.iter().filter(|p| p.closed).map(|p| p.x).collect();
        assert!(!open.is_empty() && closed.contains(&1.0), "{open:?}");
        let heel = open.iter().fold(f64::NEG_INFINITY, |a, &x| a.max(x));
        assert!(closed.iter().all(|&x| x > heel), "{open:?} {closed:?}");
        for p in &rows {
            if p.closed {
                assert!(p.tn <= 1e-10 && p.opening == 0.0, "{}: {p:?}", r.method);
            } else {
                assert!(p.tn == 0.0 && p.tt == 0.0 && p.opening > 0.0, "{p:?}");
            }
        }
    }
    assert_same_joint(&runs, "joint");
}

/// (1) Unique solution with friction, sticking. P = 1 (ty = −1 over the whole top, at
/// x = 0.5) and a push tx = 0.6 on the upper block's left side: Q = 0.6 × 0.5 = 0.3 < μP =
/// 0.5 (μ = 0.5), at height 0.25 above the joint. Statics: N = P = 1, the joint's friction
/// balances the push, T = −Q = −0.3 (the joint's tangent runs along −x on the lower block,
/// which the upper one drags towards +x), and the moment about a point x₀ of the joint,
/// (x − x₀)N − (0.5 − x₀)P − 0.25 Q = 0, puts the resultant at x = 0.5 + 0.25 Q / P =
/// 0.575. Coulomb's law holds pair by pair: |t_t| ≤ μ|t_n|, with equality where a pair slips.
#[test]
fn unique_friction_holds_a_push_below_mu_n() {
    let runs = run_blocks("tiny-stick", 0.3, &pushed(0.6), FRICTION);
    for r in &runs {
        r.assert_solved((-1.0, -0.3), 0.575);
        for p in r.rows("joint") {
            let cone = 0.5 * p.tn.abs();
            assert!(p.tt.abs() <= cone * (1.0 + EXACT), "{}: {p:?}", r.method);
            if p.tangential_status.as_deref() == Some("slip") {
                assert_exact("slipping pair", p.tt.abs(), cone, cone);
            }
        }
    }
    assert_same_joint(&runs, "joint");
}

/// (1) Unique solution, the whole joint slipping. The top of the upper block is driven
/// sideways, ux = 0.01 (twenty times the elastic shear displacement μP/E × size), under
/// ty = −1 (P = 1 at x = 0.5), μ = 0.5. Vertical statics: N = P = 1 (the top's ty is given,
/// the sides are free). Every closed pair slips, so each carries t_t = μ t_n (both negative:
/// compression, and the upper block dragging the lower one towards +x along its tangent −x),
/// and T = μN = 0.5 exactly. The top's horizontal force F = T acts 0.5 above the joint, so
/// the resultant lies at x = 0.5 + 0.5 F / P = 0.75: beyond the kern, the heel opens.
#[test]
fn unique_a_sliding_joint_carries_mu_n() {
    let loads = "[boundary.load]\nty = -1.0\nux = 0.01\n[boundary.top]\nty = -1.0\nux = 0.01";
    let runs = run_blocks("tiny-slip", 0.3, loads, FRICTION);
    for r in &runs {
        r.assert_solved((-1.0, -0.5), 0.75);
        assert_exact("stick length", r.figure("joint", "stick_length"), 0.0, 1.0);
        let rows = r.rows("joint");
        assert!(
            rows.iter().any(|p| !p.closed),
            "{}: the heel opens",
            r.method
        );
        for p in rows.iter().filter(|p| p.closed) {
            assert_eq!(p.tangential_status.as_deref(), Some("slip"), "{p:?}");
            assert!(p.tn < 0.0 && p.slip < 0.0, "{}: {p:?}", r.method);
            assert_exact("t_t = mu t_n", p.tt, 0.5 * p.tn, p.tn.abs());
        }
    }
    assert_same_joint(&runs, "joint");
}

/// (2) Degenerate: rows that touch without pressing, and dependent rows. The T-junction
/// under ty = −1 on both tops, ν = 0 everywhere, stick bed joints. With ν = 0 the uniform
/// vertical compression σ_yy = −1, σ_xx = σ_xy = 0 has no lateral strain, so u_x = 0 in every
/// body (the clamped base included) and u_y = −y/E: an exact, linear field. The head joint
/// then has zero gap and zero force at every pair: open and closed both solve its rows, and a
/// solver may report either (the cross-checks count them as degenerate, never differing).
/// The answer is the same: each bed joint carries its block's load, N = 1 with a uniform
/// pressure t_n = −1 and t_t = 0 at every pair; the head joint carries nothing and does not
/// open. At (1, 0.5) the three joints form a cycle: their relative displacements sum to zero
/// in x and in y, so two of the six rows there are dependent (implied), from a closed and from
/// an open start of the head joint alike.
#[test]
fn degenerate_a_head_joint_that_touches_without_pressing() {
    for (k, head) in ["", "initial = \"open\"\ngap = 0.0"].iter().enumerate() {
        let dir = tmpdir(&format!("tiny-degenerate-{k}"));
        let scene = format!(
            r#"plane = "strain"
[body.base_block]
young = 1000.0
poisson = 0.0
[body.left]
young = 1000.0
poisson = 0.0
[body.right]
young = 1000.0
poisson = 0.0
[boundary.base]
ux = 0.0
uy = 0.0
[boundary.top]
ty = -1.0
[interface.bed_left]
model = "unilateral"
[interface.bed_right]
model = "unilateral"
[interface.head]
model = "unilateral"
{head}
[output]
vtk = false
history = "final"
"#
        );
        let runs = run_all(&dir, &scene, &tee_mesh(8));
        for r in &runs {
            r.assert_converged();
            // Every head pair may be degenerate.
            r.assert_cross_checks_agree(5);
            let junctions = &r.summary()["contact"]["junctions"];
            assert_eq!(junctions["points"], 1, "{}", r.method);
            assert_eq!(junctions["implied_components"], 2, "{}", r.method);
            for bed in ["bed_left", "bed_right"] {
                assert_exact(bed, r.figure(bed, "normal_resultant"), -1.0, 1.0);
                assert_exact(bed, r.figure(bed, "tangential_resultant"), 0.0, 1.0);
                for p in r.rows(bed) {
                    assert!(p.closed, "{} {bed}: {p:?}", r.method);
                    assert_exact("bed pressure", p.tn, -1.0, 1.0);
                    assert_exact("bed shear", p.tt, 0.0, 1.0);
                }
            }
            assert_exact("head N", r.figure("head", "normal_resultant"), 0.0, 1.0);
            let rows = r.rows("head");
            assert_eq!(rows.len(), 5);
            for p in rows {
                assert_exact("head t_n", p.tn, 0.0, 1.0);
                assert_exact("head t_t", p.tt, 0.0, 1.0);
                // Openings relative to the largest displacement, 1e-3.
                assert_exact("head opening", p.opening, 0.0, 1e-3);
            }
        }
        for bed in ["bed_left", "bed_right"] {
            assert_same_joint(&runs, bed);
        }
    }
}

/// (3) Infeasible: the block pulled off. The load of the unique case reversed, ty = +4 over
/// [0.75, 1]: nothing holds the upper block against an upward pull, so no equilibrium
/// exists. Every method ends with exit 3 and names the body and the motion (the joint opens
/// along its normal (0, 1)); the QP proves it by an unbounded problem and Lemke's method, the
/// cross-check of `both`, by a secondary ray (docs/formulation.md §6.3, §6.4).
#[test]
fn infeasible_a_block_pulled_off_is_a_named_mechanism() {
    let runs = run_blocks("tiny-pulled", 0.3, "[boundary.load]\nty = 4.0", STICK);
    for r in &runs {
        r.assert_mechanism(&[
            "no equilibrium exists (a mechanism)",
            "leaving body \"upper\" free",
            "opens it along (0.000, 1.000)",
            // The pull at the right end turns the block about its heel, the joint's left
            // end, the one point still closed.
            "the motion: body \"upper\" turns anticlockwise about (0, 0.5)",
        ]);
        if r.method == "qp" {
            assert!(r.err.contains("the QP is unbounded"), "{}", r.err);
        }
        if r.method == "both" {
            let checks = r.summary()["contact"]["cross_checks"].as_array().unwrap();
            let failure = |name: &str| {
                let c = checks.iter().find(|c| c["solver"] == name).unwrap();
                assert_eq!(c["converged"], false, "{c}");
                c["failure"].as_str().unwrap().to_string()
            };
            assert!(failure("qp").contains("the QP is unbounded"));
            assert!(failure("lemke").contains("secondary ray"));
        }
    }
}

/// (3) Infeasible: a push beyond friction. As the sticking case, with tx = 1.2 on the left
/// side: Q = 0.6 > μP = 0.5. The block slides; every method names it, with the ratio of the
/// resultants T/N = Q/P = 0.600 against μ = 0.500 (the tipping limit, Q = 2P, is far).
#[test]
fn infeasible_a_push_beyond_mu_n_slides() {
    let runs = run_blocks("tiny-slides", 0.3, &pushed(1.2), FRICTION);
    for r in &runs {
        r.assert_mechanism(&[
            "no equilibrium exists (a sliding mechanism)",
            "body \"upper\" slides on interface \"joint\"",
            "tangential/normal resultant 0.600 > mu = 0.500",
            "the motion: body \"upper\" moves along (1.000, 0.000)",
        ]);
    }
}

/// (3) Infeasible and feasible: tipping. A stick joint (no sliding), P = 1 at x = 0.5 and a
/// push Q at height 0.25 above the joint. The resultant lies at x = 0.5 + 0.25 Q / P (as in
/// the sticking case); it leaves the base beyond the toe x = 1 when Q > 2P. Q = 1: the block
/// stands, T = −1, x = 0.75. Q = 3: it tips about the toe; every method names the body and
/// the rotation that opens the joint along (0, 1), and the last state the run writes has its
/// resultant at x = 1.25, beyond the toe (its balance holds whatever the statuses).
#[test]
fn infeasible_a_push_beyond_the_tipping_limit_tips() {
    // Q = tx / 2.
    let runs = run_blocks("tiny-stands", 0.3, &pushed(2.0), STICK);
    for r in &runs {
        r.assert_solved((-1.0, -1.0), 0.75);
    }
    assert_same_joint(&runs, "joint");
    let runs = run_blocks("tiny-tips", 0.3, &pushed(6.0), STICK);
    for r in &runs {
        r.assert_mechanism(&[
            "no equilibrium exists (a mechanism)",
            "leaving body \"upper\" free",
            "tipping about the last closed point",
            "opens it along (0.000, 1.000)",
            // About the toe, the joint's right end.
            "the motion: body \"upper\" turns clockwise about (1, 0.5)",
        ]);
        // x = Σ x_i F_i / Σ F_i over nodal forces F_i that here are larger than their sum
        // (the toe pushes, its neighbour pulls): its rounding grows by Σ|F_i| / |Σ F_i|.
        let forces = nodal_normal_forces(&r.rows("joint"));
        let gain = forces.iter().map(|f| f.abs()).sum::<f64>() / forces.iter().sum::<f64>().abs();
        r.assert_statics((-1.0, -3.0), 1.25, 1.25 * gain);
    }
}

/// The motion of a mechanism in closed form: the upper block's rigid velocity at a point.
#[derive(Debug, Clone, Copy)]
enum Rigid {
    /// A translation along the unit vector.
    Along([f64; 2]),
    /// A rotation about the point, clockwise where `true`.
    About([f64; 2], bool),
}

/// (3) The mechanism as data and as a picture: the block that tips about its toe (1, 0.5) and
/// the block that slides along (1, 0), with every method and VTK on. summary.json's
/// `mechanism` names the upper block alone, with the closed-form motion (direction or centre
/// to 1e-6 of the block's size 1, the sense, magnitude 1); the last state's multiblock has the
/// block "mechanism" (no other state has one) whose `mechanism_velocity` is the rigid
/// velocity field of that motion at every node of the upper block to 1e-6, scaled so that the
/// fastest node moves at 1 (the tipping block's farthest node from the toe: its heel's top
/// (0, 1), at √1.25), and exactly zero on the clamped lower block; `sgbem export` writes the
/// block again from the archive alone, byte for byte.
#[test]
fn infeasible_mechanisms_are_drawn_as_their_rigid_motions() {
    let cases = [
        (
            "tiny-tips-drawn",
            pushed(6.0),
            STICK,
            Rigid::About([1.0, 0.5], true),
        ),
        (
            "tiny-slides-drawn",
            pushed(1.2),
            FRICTION,
            Rigid::Along([1.0, 0.0]),
        ),
    ];
    for (name, loads, joint, want) in cases {
        let scene = blocks_scene(0.3, &loads, joint).replace("vtk = false", "vtk = true");
        for r in run_all(&tmpdir(name), &scene, &blocks_mesh(8)) {
            let m = r.method;
            assert_eq!(r.code, 3, "{m}: {}", r.err);
            let bodies = r.summary()["mechanism"].as_array().expect("mechanism");
            assert_eq!(bodies.len(), 1, "{m}: {bodies:?}");
            let b = &bodies[0];
            assert_eq!(b["body"], "upper", "{m}");
            assert!(
                (b["magnitude"].as_f64().unwrap() - 1.0).abs() <= 1e-12,
                "{m}: {b}"
            );
            let pair = |k: &str| [b[k][0].as_f64().unwrap(), b[k][1].as_f64().unwrap()];
            let speed = match want {
                Rigid::Along(d) => {
                    assert_eq!(b["kind"], "translation", "{m}: {b}");
                    assert!(
                        b.get("centre").is_none() && b.get("sense").is_none(),
                        "{m}: {b}"
                    );
                    let got = pair("direction");
                    assert!(dist(got, d) <= 1e-6, "{m}: direction {got:?}");
                    1.0
                }
                Rigid::About(c, clockwise) => {
                    assert_eq!(b["kind"], "rotation", "{m}: {b}");
                    assert!(b.get("direction").is_none(), "{m}: {b}");
                    let sense = if clockwise {
                        "clockwise"
                    } else {
                        "anticlockwise"
                    };
                    assert_eq!(b["sense"], sense, "{m}: {b}");
                    let got = pair("centre");
                    assert!(dist(got, c) <= 1e-6, "{m}: centre {got:?}");
                    // The fastest node: the upper block's corner farthest from the centre.
                    let far = [[0.0, 0.5], [1.0, 0.5], [0.0, 1.0], [1.0, 1.0]]
                        .iter()
                        .map(|&x| dist(x, c))
                        .fold(0.0, f64::max);
                    1.0 / far
                }
            };
            let nodes = mechanism_block(&r.out).expect("a mechanism block");
            // The upper block: the body whose nodes lie above the joint.
            let upper = nodes.iter().find(|n| n.x[1] > 0.75).unwrap().body;
            let mut top = 0.0f64;
            for n in &nodes {
                let v = [n.v[0], n.v[1]];
                top = top.max(v[0].hypot(v[1]));
                assert_eq!(n.v[2], 0.0);
                if n.body != upper {
                    assert_eq!(v, [0.0, 0.0], "{m}: the lower block at {:?}", n.x);
                    continue;
                }
                let exact = match want {
                    Rigid::Along(d) => d,
                    Rigid::About(c, clockwise) => {
                        let w = if clockwise { -speed } else { speed };
                        [-w * (n.x[1] - c[1]), w * (n.x[0] - c[0])]
                    }
                };
                assert!(
                    dist(v, exact) <= 1e-6,
                    "{m}: at {:?} {v:?} against {exact:?}",
                    n.x
                );
            }
            assert!((top - 1.0).abs() <= 1e-12, "{m}: fastest node {top}");
            // The archive holds the mechanism: `sgbem export` draws the same block.
            let again = r.out.with_file_name(format!("{m}-export"));
            let archive = r.out.join("archive.h5");
            let (code, _, err) = sgbem(&[
                "export",
                archive.to_str().unwrap(),
                "--vtk",
                again.to_str().unwrap(),
            ]);
            assert_eq!(code, 0, "{m}: {err}");
            for f in std::fs::read_dir(r.out.join("vtk")).unwrap() {
                let f = f.unwrap().file_name();
                let same = std::fs::read(r.out.join("vtk").join(&f)).unwrap()
                    == std::fs::read(again.join(&f)).unwrap_or_default();
                assert!(same, "{m}: {f:?} differs after export");
            }
        }
    }
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// The nodal normal forces of an interface's pairs: each traction times its pair's
/// tributary length (half of each adjacent interface element; README, "Interface
/// tractions").
fn nodal_normal_forces(rows: &[InterfaceRow]) -> Vec<f64> {
    let s: Vec<f64> = rows.iter().map(|p| p.s).collect();
    (0..rows.len())
        .map(|i| {
            let before = if i > 0 { s[i] - s[i - 1] } else { 0.0 };
            let after = if i + 1 < s.len() {
                s[i + 1] - s[i]
            } else {
                0.0
            };
            rows[i].tn * 0.5 * (before + after)
        })
        .collect()
}

/// (4) A body left free: a frictionless joint does not hold the upper block sideways. With
/// every pair closed the horizontal translation of "upper" is free, whether a load pushes it
/// that way (tx = 0.4 on its left side: no equilibrium) or not (only ty: equilibria in any
/// horizontal place, none preferred). The glued system is singular, and every method refuses
/// the scene with exit 3, naming the body and the translation along x (docs/formulation.md
/// §6.2).
#[test]
fn free_a_frictionless_joint_leaves_the_block_free_to_slide() {
    for (k, push) in ["", "[boundary.push]\ntx = 0.4"].iter().enumerate() {
        let loads = format!("{PRESSED}{push}");
        let runs = run_blocks(
            &format!("tiny-free-{k}"),
            0.3,
            &loads,
            "tangential = \"slide\"",
        );
        for r in &runs {
            r.assert_mechanism(&["body \"upper\" is free to move (a translation along ("]);
            assert!(
                r.err.contains("along (1.000, 0.000)") || r.err.contains("along (-1.000, 0.000)"),
                "{}: {}",
                r.method,
                r.err
            );
        }
    }
}

/// Reads `sections/NAME.csv`: (y, ux, uy) per point.
fn section(out: &Path, name: &str) -> Vec<(f64, f64, f64)> {
    let text = std::fs::read_to_string(out.join(format!("sections/{name}.csv"))).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("x,y,ux,uy,sxx,syy,sxy"));
    lines
        .map(|l| {
            let f: Vec<f64> = l.split(',').map(|v| v.parse().unwrap()).collect();
            (f[1], f[2], f[3])
        })
        .collect()
}

/// (4) A body that its start statuses leave free: the joint starts open with a gap
/// h = 0.001, so at the start nothing holds the upper block in any direction; ty = −1 on its
/// whole top, ν = 0. The block must come down by h and rest on the lower one, with the
/// joint's law (stick, or Coulomb with μ = 0.5) from the moment it closes. Exact answer
/// (ν = 0: linear fields, no lateral strain, so no shear on the joint): every pair closed
/// with t_n = −1, t_t = 0, N = 1 at x = 0.5; along the axis x = 0.5, u_x = 0 and u_y = −y/E
/// in the lower block (y < 0.5), u_y = −h − 0.5/E − (y − 0.5)/E in the upper one: at
/// y = 0.125, 0.375, 0.625, 0.875: −1.25e-4, −3.75e-4, −1.625e-3, −1.875e-3. (With stick,
/// `--method qp` and `lcp` once ended here with exit 3, "no equilibrium exists": the first
/// outer iteration left the stick rows of the open pairs untied as the pairs closed, which
/// leaves the block free; every solver now ties a stick row as its pair closes.)
#[test]
fn free_at_the_start_a_block_with_a_gap_comes_down_and_rests() {
    for (k, law) in [FRICTION, STICK].iter().enumerate() {
        let runs = gap_runs(&format!("tiny-gap-{k}"), law);
        for r in &runs {
            let what = format!("{} with {law:?}", r.method);
            r.assert_converged();
            if *law == FRICTION {
                r.assert_cross_checks_agree(0);
            }
            r.assert_statics((-1.0, 0.0), 0.5, 1.0);
            for p in r.rows("joint") {
                assert!(p.closed, "{what}: {p:?}");
                assert_exact("t_n", p.tn, -1.0, 1.0);
                assert_exact("t_t", p.tt, 0.0, 1.0);
            }
            let want = [
                (0.125, -1.25e-4),
                (0.375, -3.75e-4),
                (0.625, -1.625e-3),
                (0.875, -1.875e-3),
            ];
            let got = section(&r.out, "axis");
            assert_eq!(got.len(), want.len());
            for ((y, ux, uy), (wy, wuy)) in got.into_iter().zip(want) {
                assert_exact("section y", y, wy, 1.0);
                assert_exact("u_x", ux, 0.0, 2e-3);
                assert_exact("u_y", uy, wuy, 2e-3);
            }
        }
        assert_same_joint(&runs, "joint");
    }
}

/// The block that starts with a gap (the test above) under the joint law `law`, run with
/// every method into `tmpdir(name)`.
fn gap_runs(name: &str, law: &str) -> Vec<Run> {
    let dir = tmpdir(name);
    let joint = format!("initial = \"open\"\ngap = 0.001\n{law}");
    let mut scene = blocks_scene(0.0, PRESSED, &joint);
    scene.push_str(
        "[[output.section]]\nname = \"axis\"\nfrom = [0.5, 0.125]\nto = [0.5, 0.875]\npoints = 4\n",
    );
    run_all(&dir, &scene, &blocks_mesh(8))
}

/// The cross-checks of the stick case of the test above. Each solves the step from the same
/// state as the main solver, without the hand-over to the sparse solver. They once stopped
/// at the false mechanism of the untied stick rows — active set ("cycled", then the
/// evolutive iteration's "no equilibrium exists"), QP and Lemke ("1 pair(s) found open would
/// leave a body free; no equilibrium exists"), the evolutive path under `sparse` (7
/// differing pairs) — while the main solver converged to the exact answer. Now each follows
/// the stick law from the moment a pair closes (docs/formulation.md §6.4): the pivoting
/// solvers switch a pair's two rows together, Lemke and the QP tie the rows of the pairs
/// they close and solve again.
#[test]
fn free_at_the_start_every_cross_check_finds_the_stick_equilibrium() {
    for r in &gap_runs("tiny-gap-checks", STICK) {
        r.assert_converged();
        r.assert_cross_checks_agree(0);
    }
}

/// The mechanisms of (3) and (4) far from the origin: the blocks, scaled
/// by 4 (elements 0.5 long, so that at 2⁴⁷ the coordinates' spacing is below a tenth of
/// them), moved by 2⁴⁰ ≈ 1.1e12, 2⁴⁴ ≈ 1.8e13 and 2⁴⁷ ≈ 1.4e14 along both axes (every node,
/// on a grid of 1/2, still exact) are told and drawn as the same blocks near the origin. The block free to slide: every method's
/// message the same, word for word (the hint of the singular glued system, from the rigid
/// modes about each body's centroid). The block that tips: summary.json's mechanism the same
/// kind, sense and magnitude, its centre less the shift within the coordinates' spacing
/// there (2⁻⁵ at 2⁴⁷: the centre is written in absolute coordinates), and the
/// `mechanism_velocity` of every node within 1e-9 of the run near the origin.
#[test]
fn mechanisms_far_from_the_origin_are_told_and_drawn_as_near_it() {
    let moved = |x0: f64| {
        let mut m = blocks_mesh(8);
        for p in m.nodes.iter_mut() {
            *p = [4.0 * p[0] + x0, 4.0 * p[1] + x0];
        }
        m
    };
    let free = blocks_scene(0.3, PRESSED, "tangential = \"slide\"");
    let tips = blocks_scene(0.3, &pushed(6.0), STICK).replace("vtk = false", "vtk = true");
    let near_free = run_all(&tmpdir("tiny-far-free"), &free, &moved(0.0));
    let near_tips = run_all(&tmpdir("tiny-far-tips"), &tips, &moved(0.0));
    for x0 in [2f64.powi(40), 2f64.powi(44), 2f64.powi(47)] {
        let far = run_all(&tmpdir("tiny-far-free"), &free, &moved(x0));
        for (a, b) in near_free.iter().zip(&far) {
            b.assert_mechanism(&["body \"upper\" is free to move (a translation along ("]);
            assert_eq!(a.err, b.err, "{} moved by {x0:e}", a.method);
        }
        let far = run_all(&tmpdir("tiny-far-tips"), &tips, &moved(x0));
        for (a, b) in near_tips.iter().zip(&far) {
            let at = format!("{} moved by {x0:e}", a.method);
            assert_eq!((a.code, b.code), (3, 3), "{at}: {}", b.err);
            let (ma, mb) = (&a.summary()["mechanism"][0], &b.summary()["mechanism"][0]);
            for key in ["body", "kind", "sense"] {
                assert_eq!(ma[key], mb[key], "{at}: {key}");
            }
            let num = |v: &Value| v.as_f64().unwrap();
            assert!(
                (num(&ma["magnitude"]) - num(&mb["magnitude"])).abs() <= 1e-12,
                "{at}"
            );
            let spacing = x0 * f64::EPSILON;
            for k in 0..2 {
                let (ca, cb) = (num(&ma["centre"][k]), num(&mb["centre"][k]) - x0);
                assert!((ca - cb).abs() <= spacing, "{at}: centre {ca} against {cb}");
            }
            let (na, nb) = (
                mechanism_block(&a.out).expect("a mechanism block"),
                mechanism_block(&b.out).expect("a mechanism block"),
            );
            assert_eq!(na.len(), nb.len(), "{at}");
            for (p, q) in na.iter().zip(&nb) {
                assert_eq!([p.x[0] + x0, p.x[1] + x0], q.x, "{at}");
                let dv = (p.v[0] - q.v[0]).hypot(p.v[1] - q.v[1]);
                assert!(dv <= 1e-9, "{at}: at {:?} {:?} against {:?}", p.x, q.v, p.v);
            }
        }
    }
}
