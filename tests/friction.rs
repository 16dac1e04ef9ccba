//! Coulomb friction on unilateral interfaces, and load paths in pseudo-time, end to end:
//! gmsh meshes a `.geo` into a temporary folder, `sgbem run` solves a scene written here,
//! the test reads `summary.json` and `interfaces/<name>.csv`.
//!
//! * Cattaneo–Mindlin: two elastically similar bodies in Hertzian line contact under a
//!   normal force P, then a tangential force Q < μP at the top (held at uniform vertical
//!   displacement, so the upper body does not rotate): the stick zone's half-width c and the
//!   tangential traction against Johnson §7.1, for Q/(μP) = 0.19, 0.5, 0.75.
//! * Path dependence (Mindlin–Deresiewicz): Q up to 0.75 μP and back to 0.25 μP leaves
//!   reversed traction at the contact edges and a slip that the direct path to 0.25 μP does
//!   not have.
//! * Sliding and tipping thresholds: a block on a base under a body force tilted by θ stands
//!   for tan θ = 0.9 μ (0.9 b/h) and ends with exit 3 naming the body for 1.1 μ (1.1 b/h).
//!
//! Every run uses `method = "both"`: the evolutive path, the active set, Lemke and the QP
//! solve the same problem and must agree pair by pair (open/closed and stick/slip).
//!
//! Run with `cargo test --release --test friction -- --nocapture` to see the numbers.

mod support;

use std::path::{Path, PathBuf};

use serde_json::Value;
use support::{read_interface_csv, InterfaceRow};

struct Run {
    code: i32,
    stderr: String,
    summary: Value,
    rows: Vec<InterfaceRow>,
}

impl Run {
    fn iface(&self, name: &str, key: &str) -> f64 {
        self.summary["interfaces"][name][key]
            .as_f64()
            .unwrap_or_else(|| panic!("summary.json has no interfaces.{name}.{key}"))
    }

    /// Every cross-check converged and agrees with the main solver on every pair.
    fn solvers_agree(&self) {
        let checks = self.summary["contact"]["cross_checks"]
            .as_array()
            .expect("cross_checks");
        let solvers: Vec<&str> = checks.iter().filter_map(|c| c["solver"].as_str()).collect();
        for s in ["active-set", "qp", "lemke"] {
            assert!(solvers.contains(&s), "no {s} cross-check: {solvers:?}");
        }
        for c in checks {
            assert_eq!(c["converged"], true, "cross-check did not converge: {c}");
            assert_eq!(c["differing_pairs"], 0, "cross-check differs: {c}");
        }
    }
}

fn run(dir: &Path, name: &str, scene: &str, iface: &str) -> Run {
    let path = support::write(dir, &format!("{name}.toml"), scene);
    let out = dir.join(format!("out_{name}"));
    let (code, _, stderr) = support::sgbem(&[
        "run",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    let summary: Value = match std::fs::read_to_string(out.join("summary.json")) {
        Ok(s) => serde_json::from_str(&s).expect("summary.json is JSON"),
        Err(_) => panic!("{name}: no summary.json (exit {code}): {stderr}"),
    };
    let csv = out.join("interfaces").join(format!("{iface}.csv"));
    let mut rows = if csv.is_file() {
        read_interface_csv(&csv)
    } else {
        Vec::new()
    };
    rows.sort_by(|a, b| a.x.total_cmp(&b.x));
    Run {
        code,
        stderr,
        summary,
        rows,
    }
}

fn geo(name: &str) -> PathBuf {
    support::root().join("geo").join(format!("{name}.geo"))
}

// ------------------------------------------------------------------------------------------
// Cattaneo–Mindlin

const MU: f64 = 0.5;
const RADIUS: f64 = 100.0;
const H_FINE: f64 = 0.1;
/// Width of the loaded top face of the upper block.
const TOP: f64 = 100.0;

/// Two equal blocks (E 1000, ν 0.3), the upper pushed down by 0.1 and loaded on its top by
/// the shear traction `tx` (an expression in t) at the pseudo-times `time`.
fn cm_scene(mesh: &Path, tx: &str, time: &str) -> String {
    format!(
        r#"
title = "Cattaneo-Mindlin"
mesh = "{}"
plane = "strain"
[body.upper]
young = 1000.0
poisson = 0.3
[body.lower]
young = 1000.0
poisson = 0.3
[boundary.top]
uy = -0.1
tx = "{tx}"
[boundary.base]
ux = 0.0
uy = 0.0
[interface.contact]
model = "unilateral"
initial = "open"
gap = "x^2/(2*{RADIUS})"
tangential = "friction"
friction = {MU}
[solve]
time = {time}
method = "both"
[output]
directory = "out"
history = "final"
field = false
vtk = false
"#,
        mesh.display()
    )
}

/// Hertz for the full-model load P of two equal bodies: (a, p0).
fn hertz(p: f64) -> (f64, f64) {
    let e_star = 1000.0 / (2.0 * (1.0 - 0.3f64 * 0.3));
    let a = (4.0 * p * RADIUS / (std::f64::consts::PI * e_star)).sqrt();
    (a, 2.0 * p / (std::f64::consts::PI * a))
}

/// Half-width of the run of rows satisfying `pick` (from the axis), to the midpoint between
/// its last row and the next: the zone boundary lies inside that element.
fn half_width(rows: &[InterfaceRow], pick: impl Fn(&InterfaceRow) -> bool) -> (f64, f64) {
    let xs: Vec<f64> = rows.iter().filter(|r| pick(r)).map(|r| r.x).collect();
    assert!(!xs.is_empty(), "no row in the zone");
    let (lo, hi) = (xs[0], xs[xs.len() - 1]);
    // Every row between the extremes belongs to the zone (one connected run).
    let inside = rows.iter().filter(|r| r.x >= lo && r.x <= hi).count();
    assert_eq!(inside, xs.len(), "the zone is not one connected run");
    (0.5 * (hi - lo) + 0.5 * H_FINE, 0.5 * (hi + lo))
}

/// Meshes the Cattaneo–Mindlin blocks into a fresh folder and runs the normal load alone
/// (t = 0: no shear): the folder, the mesh and that run.
fn cm_normal(name: &str) -> (PathBuf, PathBuf, Run) {
    let dir = support::tmpdir(name);
    let mesh = support::gmsh(
        &geo("cattaneo_mindlin"),
        &dir,
        "cm.msh",
        false,
        &["-setnumber", "h_fine", &H_FINE.to_string()],
    );
    let normal = run(
        &dir,
        "normal",
        &cm_scene(&mesh, "0.0*t", "[0.0]"),
        "contact",
    );
    assert_eq!(normal.code, 0, "{}", normal.stderr);
    normal.solvers_agree();
    (dir, mesh, normal)
}

#[test]
fn cattaneo_mindlin_stick_zone_and_traction() {
    let (dir, mesh, normal) = cm_normal("cattaneo_mindlin");
    let p = -normal.iface("contact", "normal_resultant");
    let (a, p0) = hertz(p);
    let (a_run, centre) = half_width(&normal.rows, |r| r.closed);
    eprintln!("P = {p:.4}: Hertz a = {a:.4}, p0 = {p0:.4}; closed half-width {a_run:.4}");
    assert!(
        (a_run - a).abs() <= H_FINE,
        "contact half-width {a_run} vs Hertz {a}"
    );
    assert!(centre.abs() < 1e-9, "contact zone centred: {centre}");
    // With no shear the interface carries almost none: only the clamped base makes the two
    // blocks differ from half-spaces of the same material (where normal and tangential
    // problems decouple exactly); the contact edges may slip under that small shear.
    let tt_max = normal.rows.iter().map(|r| r.tt.abs()).fold(0.0, f64::max);
    eprintln!(
        "normal load alone: largest shear {:.4} of μp0",
        tt_max / (MU * p0)
    );
    assert!(tt_max < 0.02 * MU * p0, "shear under normal load: {tt_max}");

    for ratio in [0.19, 0.5, 0.75] {
        // Q = ratio μ P as a uniform shear on the top face, reached in one step t = 1.
        let tx = format!("{:.10}*t", ratio * MU * p / TOP);
        let r = run(
            &dir,
            &format!("q{ratio}"),
            &cm_scene(&mesh, &tx, "[0.0, 1.0]"),
            "contact",
        );
        assert_eq!(r.code, 0, "Q/μP = {ratio}: {}", r.stderr);
        r.solvers_agree();
        // Similar bodies: the normal problem does not change with the shear (Dundurs β = 0).
        let p1 = -r.iface("contact", "normal_resultant");
        assert!((p1 - p).abs() < 1e-3 * p, "P changed with Q: {p} → {p1}");
        let q = r.iface("contact", "tangential_resultant").abs();
        assert!(
            (q - ratio * MU * p).abs() < 1e-9 * p,
            "Q = {q} vs {}",
            ratio * MU * p
        );
        let (c_run, c_centre) =
            half_width(&r.rows, |x| x.tangential_status.as_deref() == Some("stick"));
        let c = a * (1.0 - ratio).sqrt();
        eprintln!(
            "Q/μP = {ratio}: stick half-width {c_run:.4} (centre {c_centre:.2e}) vs \
             c = a sqrt(1 - Q/μP) = {c:.4}; c/a {:.4} vs {:.4}",
            c_run / a,
            c / a
        );
        assert!(
            (c_run - c).abs() <= H_FINE,
            "stick half-width {c_run} vs {c} (one element = {H_FINE})"
        );
        assert!(
            c_centre.abs() <= 0.5 * H_FINE,
            "stick zone centred: {c_centre}"
        );
        // Slip zones on both sides of the stick zone, inside the contact.
        assert!(r
            .rows
            .iter()
            .any(|x| x.tangential_status.as_deref() == Some("slip")));
        // The tangential traction in the stick zone against Johnson's q(x).
        let sign = if r.rows.iter().map(|x| x.tt).sum::<f64>() > 0.0 {
            1.0
        } else {
            -1.0
        };
        let (mut sum, mut count) = (0.0, 0);
        for x in r
            .rows
            .iter()
            .filter(|x| x.tangential_status.as_deref() == Some("stick"))
        {
            let xi = x.x;
            let exact = MU
                * p0
                * ((1.0 - xi * xi / (a * a)).max(0.0).sqrt()
                    - (c / a) * (1.0 - xi * xi / (c * c)).max(0.0).sqrt());
            sum += (sign * x.tt - exact).powi(2);
            count += 1;
        }
        let rms = (sum / count as f64).sqrt() / (MU * p0);
        eprintln!("Q/μP = {ratio}: RMS error of q in the stick zone {rms:.4} of μp0");
        assert!(rms < 0.03, "RMS error {rms} of μp0 in the stick zone");
        // In the slip zones the traction is μ times the pressure, exactly (nodal forces).
        for x in r
            .rows
            .iter()
            .filter(|x| x.tangential_status.as_deref() == Some("slip"))
        {
            assert!(
                (x.tt.abs() - MU * x.tn.abs()).abs() <= 1e-9 * MU * p0,
                "slip at x = {}: |q| {} vs μ|p| {}",
                x.x,
                x.tt.abs(),
                MU * x.tn.abs()
            );
        }
        // Sticking pairs hold less than μ times their pressure.
        for x in r
            .rows
            .iter()
            .filter(|x| x.tangential_status.as_deref() == Some("stick"))
        {
            assert!(x.tt.abs() <= MU * x.tn.abs() * (1.0 + 1e-9) + 1e-12);
        }
    }
}

#[test]
fn unloading_leaves_reversed_traction_and_slip_and_depends_on_path() {
    let (dir, mesh, normal) = cm_normal("mindlin_deresiewicz");
    let p = -normal.iface("contact", "normal_resultant");
    let (_, p0) = hertz(p);
    let qmax = 0.75 * MU * p / TOP;
    // Up to Q = 0.75 μP at t = 1, back down to 0.25 μP at t = 2.
    let cycle = run(
        &dir,
        "cycle",
        &cm_scene(
            &mesh,
            &format!("{qmax:.10}*min(t, (5 - 2*t)/3)"),
            "[0.0, 1.0, 2.0]",
        ),
        "contact",
    );
    assert_eq!(cycle.code, 0, "{}", cycle.stderr);
    cycle.solvers_agree();
    // Straight to Q = 0.25 μP.
    let direct = run(
        &dir,
        "direct",
        &cm_scene(&mesh, &format!("{:.10}*t", qmax / 3.0), "[0.0, 1.0]"),
        "contact",
    );
    assert_eq!(direct.code, 0, "{}", direct.stderr);
    let qc = cycle.iface("contact", "tangential_resultant");
    let qd = direct.iface("contact", "tangential_resultant");
    assert!((qc - qd).abs() < 1e-9 * p, "same final load: {qc} vs {qd}");
    // The sign of the net shear on the lower body.
    let sign = qd.signum();
    // Direct loading: the traction has the sign of Q everywhere in the contact.
    let closed = |r: &Run| -> Vec<(f64, f64)> {
        r.rows
            .iter()
            .filter(|x| x.closed)
            .map(|x| (x.x, x.tt))
            .collect()
    };
    let d = closed(&direct);
    assert!(
        d.iter().all(|(_, t)| t * sign >= -1e-9 * p0),
        "direct: {d:?}"
    );
    // Unloaded: the traction is reversed at the contact edges (Mindlin–Deresiewicz).
    let c = closed(&cycle);
    let (first, last) = (c[0], c[c.len() - 1]);
    eprintln!(
        "unloaded: edge tractions {:.4} at {:.2}, {:.4} at {:.2}; Q sign {sign}",
        first.1, first.0, last.1, last.0
    );
    assert!(
        first.1 * sign < 0.0 && last.1 * sign < 0.0,
        "no reversal at the edges"
    );
    // Different states for the same final load, and slip left by the cycle.
    let diff = c
        .iter()
        .zip(&d)
        .map(|(a, b)| (a.1 - b.1).abs())
        .fold(0.0, f64::max);
    eprintln!(
        "largest traction difference between the paths {:.4} of μp0",
        diff / (MU * p0)
    );
    assert!(diff > 0.1 * MU * p0, "the two paths give the same state");
    let slip_c = cycle.iface("contact", "max_accumulated_slip");
    let slip_d = direct.iface("contact", "max_accumulated_slip");
    eprintln!("accumulated slip: cycle {slip_c:.3e}, direct {slip_d:.3e}");
    assert!(
        slip_c > 2.0 * slip_d,
        "cycle slip {slip_c} vs direct {slip_d}"
    );
    let tangential_slip_differs = cycle
        .rows
        .iter()
        .zip(&direct.rows)
        .any(|(a, b)| a.closed && (a.slip - b.slip).abs() > 1e-6);
    assert!(tangential_slip_differs, "residual slip");
}

// ------------------------------------------------------------------------------------------
// Sliding and tipping thresholds

/// A block 1 × 0.5 (`upper`) on a base (`lower`, clamped at its bottom) under a unit body
/// force tilted by θ from the vertical, with friction μ on the joint, every solver.
fn block_scene(tan: f64, mu: f64) -> String {
    support::two_blocks_scene(
        &support::tilted(tan),
        mu,
        "[solve]\nmethod = \"both\"",
        false,
    )
}

#[test]
fn block_slides_beyond_the_friction_angle_and_not_below() {
    let dir = support::two_blocks_mesh("sliding_block");
    let mu = 0.5;
    let stands = run(&dir, "below", &block_scene(0.9 * mu, mu), "joint");
    assert_eq!(stands.code, 0, "tan θ = 0.9 μ: {}", stands.stderr);
    stands.solvers_agree();
    // Equilibrium: the joint carries the block's weight and the tilted component.
    let (n, t) = (
        stands.iface("joint", "normal_resultant"),
        stands.iface("joint", "tangential_resultant"),
    );
    let th = (0.9 * mu).atan();
    eprintln!(
        "tan θ = 0.9 μ: N = {n:.6}, T = {t:.6}, stick length {:.4}, slip length {:.4}, \
         max accumulated slip {:.3e}",
        stands.iface("joint", "stick_length"),
        stands.iface("joint", "slip_length"),
        stands.iface("joint", "max_accumulated_slip"),
    );
    // The block's weight is 0.5 (area) × 1 (body force): N = 0.5 cos θ, |T| = 0.5 sin θ.
    assert!((n.abs() - 0.5 * th.cos()).abs() < 1e-9, "N = {n}");
    assert!((t.abs() - 0.5 * th.sin()).abs() < 1e-9, "T = {t}");
    // The block stands: a stick zone holds it (local microslip where the pressure is low).
    assert!(stands.iface("joint", "stick_length") > 0.0);

    let slides = run(&dir, "above", &block_scene(1.1 * mu, mu), "joint");
    assert_eq!(slides.code, 3, "tan θ = 1.1 μ must end with exit 3");
    eprintln!("tan θ = 1.1 μ: {}", slides.stderr.trim());
    assert!(
        slides
            .stderr
            .contains("body \"upper\" slides on interface \"joint\""),
        "{}",
        slides.stderr
    );
    assert!(
        slides.stderr.contains("0.550 > mu = 0.500"),
        "{}",
        slides.stderr
    );
    assert_eq!(slides.summary["status"], "not converged");
    // Every output is written.
    assert!(!slides.rows.is_empty());
}

#[test]
fn block_tips_beyond_its_aspect_and_not_below() {
    let dir = support::two_blocks_mesh("tipping_block");
    // b / h = 1 / 0.5; friction high enough that the block cannot slide.
    let bh = 2.0;
    let stands = run(&dir, "below", &block_scene(0.9 * bh, 10.0), "joint");
    assert_eq!(stands.code, 0, "tan θ = 0.9 b/h: {}", stands.stderr);
    stands.solvers_agree();
    assert!(
        stands.iface("joint", "detached_length") > 0.5,
        "the heel lifts"
    );
    let tips = run(&dir, "above", &block_scene(1.1 * bh, 10.0), "joint");
    assert_eq!(tips.code, 3, "tan θ = 1.1 b/h must end with exit 3");
    eprintln!("tan θ = 1.1 b/h: {}", tips.stderr.trim());
    assert!(
        tips.stderr.contains("without leaving body \"upper\" free")
            && tips.stderr.contains("tipping"),
        "{}",
        tips.stderr
    );
}

// ------------------------------------------------------------------------------------------
// Shrink fit

/// A hollow shaft (radii a = 0.25, b = 0.5) pressed into a hub (b, c = 1) by the radial
/// interference `delta` (a negative gap), plane stress, E 2e5, ν 0.3, friction μ on the fit;
/// at t = 1 the hole carries the uniform shear `tau` (a torque 2π a² τ per unit thickness).
fn fit_scene(delta: f64, mu: f64, tau: f64) -> String {
    format!(
        r#"
mesh = "sf.msh"
plane = "stress"
[body.shaft]
young = 2e5
poisson = 0.3
[body.hub]
young = 2e5
poisson = 0.3
[boundary.outer]        # held tangentially (rigid modes), free radially
ut = 0.0
tn = 0.0
[boundary.hole]
tt = "{tau}*t"
[interface.fit]
model = "unilateral"
initial = "open"
gap = -{delta}
tangential = "friction"
friction = {mu}
[solve]
time = [0.0, 1.0]
method = "both"
[output]
directory = "out"
field = false
vtk = false
"#
    )
}

#[test]
fn shrink_fit_pressure_is_lame_and_friction_holds_the_torque_below_its_limit() {
    let dir = support::tmpdir("shrink_fit");
    support::gmsh(
        &geo("shrink_fit"),
        &dir,
        "sf.msh",
        false,
        &["-setnumber", "n", "32"],
    );
    let (e, delta, mu) = (2e5, 0.6667e-3, 0.2);
    let (a, b, c) = (0.25f64, 0.5f64, 1.0f64);
    // Lamé, plane stress, equal materials: p = E δ (c² − b²)(b² − a²) / (2 b³ (c² − a²)).
    let p = e * delta * (c * c - b * b) * (b * b - a * a) / (2.0 * b.powi(3) * (c * c - a * a));
    let pi = std::f64::consts::PI;
    let t_hold = 2.0 * pi * b * b * mu * p;
    for (k, holds) in [(0.9, true), (1.1, false)] {
        let tau = k * t_hold / (2.0 * pi * a * a);
        let r = run(&dir, &format!("k{k}"), &fit_scene(delta, mu, tau), "fit");
        if holds {
            assert_eq!(r.code, 0, "torque {k} of the limit: {}", r.stderr);
            r.solvers_agree();
            let (lo, hi) = r.rows.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), x| {
                (lo.min(-x.tn), hi.max(-x.tn))
            });
            eprintln!("shrink fit: pressure {lo:.4} .. {hi:.4} vs Lamé {p:.4}");
            assert!(
                (lo - p).abs() < 0.01 * p && (hi - p).abs() < 0.01 * p,
                "pressure {lo} .. {hi} vs {p}"
            );
            // The torque is carried by sticking pairs: the shear is T/(2π b²) < μp.
            assert!(r
                .rows
                .iter()
                .all(|x| x.tangential_status.as_deref() == Some("stick")));
            let shear = k * t_hold / (2.0 * pi * b * b);
            let worst = r
                .rows
                .iter()
                .map(|x| (x.tt.abs() - shear).abs())
                .fold(0.0, f64::max);
            assert!(worst < 0.01 * shear, "fit shear vs {shear}: off by {worst}");
        } else {
            assert_eq!(r.code, 3, "torque {k} of the limit must slip");
            eprintln!("shrink fit, torque 1.1: {}", r.stderr.trim());
            assert!(
                r.stderr
                    .contains("body \"shaft\" slides on interface \"fit\""),
                "{}",
                r.stderr
            );
            assert!(r.stderr.contains("0.220 > mu = 0.200"), "{}", r.stderr);
        }
    }
}

// ------------------------------------------------------------------------------------------
// Klarbring's coupled friction LCP against the Tresca fixed point

#[test]
fn coupled_friction_lcp_reaches_the_fixed_point_state() {
    use sgbem::bem::quadrature::QuadratureSettings;
    use sgbem::contact::{Session, Solver};
    let dir = support::two_blocks_mesh("klarbring");
    // Dissimilar bodies (normal and tangential problems coupled) with partial slip.
    let scene = block_scene(0.8, 1.0)
        .replacen("young = 1000.0", "young = 5000.0", 1)
        .replacen("poisson = 0.3", "poisson = 0.45", 1);
    let path = support::write(&dir, "k.toml", &scene);
    let l =
        sgbem::pipeline::load(&path, Some(&dir.join("tb.msh"))).unwrap_or_else(|e| panic!("{e}"));
    let q = QuadratureSettings::standard();
    let prep = sgbem::bem::prepare(&l.model, l.scene.plane, &q, 1.0, &l.scene.path, &|_| {})
        .unwrap_or_else(|e| panic!("{e}"));
    let mut fixed = Session::new(&l.model, &prep).unwrap_or_else(|e| panic!("{e}"));
    fixed.coupled_after = usize::MAX;
    let start = fixed.initial();
    let a = fixed.solve_step(&start, Solver::Evolutive, 1e-10, 1000, 0, 1.0, false);
    assert!(a.converged, "{:?}", a.failure.as_ref().map(|e| e.message()));
    let mut coupled = Session::new(&l.model, &prep).unwrap_or_else(|e| panic!("{e}"));
    coupled.coupled_after = 1;
    let b = coupled.solve_step(&start, Solver::Evolutive, 1e-10, 1000, 0, 1.0, false);
    assert!(b.converged, "{:?}", b.failure.as_ref().map(|e| e.message()));
    assert!(
        b.notes.iter().any(|n| n.contains("Klarbring")),
        "the coupled LCP was not used: {:?}",
        b.notes
    );
    eprintln!(
        "fixed point: {} outer iterations; restarted from Klarbring's LCP: {}",
        a.outer_iterations, b.outer_iterations
    );
    assert!(
        b.outer_iterations <= 3,
        "{} outer iterations",
        b.outer_iterations
    );
    assert_eq!(
        sgbem::contact::differing_pairs(&a.interfaces, &b.interfaces),
        0
    );
    let slipping = a.interfaces[0]
        .pairs
        .iter()
        .filter(|p| p.slipping == Some(true))
        .count();
    assert!(
        slipping > 0,
        "no pair slips: the test would not test friction"
    );
    let scale = a.nodal_force[0].iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (x, y) in a.nodal_force[0].iter().zip(&b.nodal_force[0]) {
        assert!((x - y).abs() < 1e-8 * scale, "nodal force {x} vs {y}");
    }
    for (p, r) in a.interfaces[0].pairs.iter().zip(&b.interfaces[0].pairs) {
        assert!((p.traction[0] - r.traction[0]).abs() < 1e-8 * scale / 0.0625);
    }
}

// ------------------------------------------------------------------------------------------
// Load paths: a step that does not converge is solved again in substeps

#[test]
fn a_step_that_does_not_converge_is_subdivided_and_reaches_the_same_state() {
    let dir = support::tmpdir("substeps");
    let mesh = support::gmsh(
        &geo("hertz_contact"),
        &dir,
        "hertz.msh",
        false,
        &["-setnumber", "h_fine", "0.1"],
    );
    // The Hertz scene with its indentation as a load path t = 0 → 1; closing about 30
    // pairs at once needs about 30 switches, more than max_iterations = 12 allows.
    let base = std::fs::read_to_string(support::root().join("pipelines/hertz_contact.toml"))
        .expect("hertz scene")
        .replace(
            "mesh = \"../out/mesh/hertz_contact.msh\"",
            &format!("mesh = \"{}\"", mesh.display()),
        )
        .replace("\nuy = -0.17\n", "\nuy = \"-0.17*t\"\n")
        .replace(
            "tolerance = 1e-10",
            "tolerance = 1e-10\ntime = [0.0, 1.0]\nmax_iterations = MAXIT",
        );
    let direct = run(&dir, "direct", &base.replace("MAXIT", "1000"), "contact");
    assert_eq!(direct.code, 0, "{}", direct.stderr);
    let switches = direct.summary["contact"]["iterations"]
        .as_u64()
        .unwrap_or(0);
    assert!(switches > 12, "the direct step needs {switches} switches");
    let sub = run(&dir, "sub", &base.replace("MAXIT", "12"), "contact");
    assert_eq!(sub.code, 0, "{}", sub.stderr);
    let notes = sub.summary["notes"].to_string();
    eprintln!("{notes}");
    assert!(
        notes.contains("substeps") && notes.contains("which converged"),
        "{notes}"
    );
    // The same final state (frictionless contact is path-independent).
    assert_eq!(sub.rows.len(), direct.rows.len());
    for (a, b) in sub.rows.iter().zip(&direct.rows) {
        assert_eq!(a.closed, b.closed, "status at x = {}", a.x);
        assert!(
            (a.tn - b.tn).abs() < 1e-8 * (1.0 + b.tn.abs()),
            "pressure at x = {}",
            a.x
        );
    }
}

#[test]
fn a_pier_of_blocks_past_overturning_ends_with_the_tipping_mechanism() {
    // The pier of 8 stacked blocks (pipelines/wall.toml, stick joints) stands under its
    // wind of 1.5 kN/m²; at 4 kN/m² the resultant on the 1.4 m of blocks above the first
    // joint falls outside it. Rigid blocks 0.4 wide, about the joint's leeward edge: wind
    // 1.5 · 1.4² / 2 = 1.47 (stands) and 4 · 1.4² / 2 = 3.92 kNm per m (tips) against the
    // weight's 0.4 · 1.4 · 20 · 0.2 = 2.24 kNm per m.
    let dir = support::tmpdir("pier_overturning");
    let scene = support::root().join("pipelines/wall.toml");
    for (wind, code) in [("1.5", 0), ("4.0", 3)] {
        let out = dir.join(format!("w{wind}"));
        let (c, _, stderr) = support::sgbem(&[
            "run",
            scene.to_str().unwrap(),
            "--set",
            &format!("boundary.left.tx={wind}"),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ]);
        assert_eq!(c, code, "wind {wind}: {stderr}");
        if code == 3 {
            eprintln!("wind {wind}: {}", stderr.trim());
            assert!(
                stderr.contains("no equilibrium exists") && stderr.contains("tipping"),
                "{stderr}"
            );
            assert!(stderr.contains("body \"brick_2\""), "{stderr}");
        }
    }
}

// ------------------------------------------------------------------------------------------
// Large friction tends to stick

/// A running-bond wall of 4 courses of 5 bricks (geo/wall.geo, 0.4 × 0.2 m, E = 5 MPa) on a
/// clamped base under its weight (20 kN/m³) and the lateral body force `lateral` (a TOML
/// value: 12.5 is 0.625 of the weight, "20*t" a collapse search's), with Coulomb friction μ
/// on every joint, against the same wall with stick joints (the limit μ → ∞).
fn large_friction_scene(tangential: &str, lateral: &str) -> String {
    format!(
        r#"title = "4 x 5 wall under a lateral load"
plane = "strain"
[mesh]
file = "{}"
courses = 4
bricks = 5
[defaults.body]
young = 5.0e6
poisson = 0.2
body_force = [{lateral}, -20.0]
[defaults.interface]
model = "unilateral"
{tangential}
[boundary.base]
ux = 0.0
uy = 0.0
[output]
history = "final"
vtk = false
operators = false
"#,
        geo("wall").display()
    )
}

/// Every interface table of a run, in file order.
fn all_rows(out: &Path) -> Vec<InterfaceRow> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(out.join("interfaces"))
        .expect("interfaces/")
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    files.iter().flat_map(|f| read_interface_csv(f)).collect()
}

/// Coulomb's law on every closed row of `rows` (a run's interface tables, `summary` its
/// summary) that has a friction law: |t_t| ≤ μ|t_n| to 1e-8 of `scale`, equal to 1e-6 where
/// the row slips; the number of slipping rows.
fn coulomb_holds(rows: &[InterfaceRow], summary: &Value, mu: f64, st: f64) -> usize {
    let mut slipping = 0;
    // Tangential components implied at a junction carry no friction law of their own
    // (docs/formulation.md §6.7); they are listed in the summary and left out here.
    let implied: Vec<(f64, f64)> = summary["contact"]["junctions"]["implied"]
        .as_object()
        .map(|m| {
            m.values()
                .flat_map(|v| v.as_array().cloned().unwrap_or_default())
                .filter(|c| c["component"] == "tangential")
                .map(|c| (c["x"][0].as_f64().unwrap(), c["x"][1].as_f64().unwrap()))
                .collect()
        })
        .unwrap_or_default();
    let at_junction = |r: &InterfaceRow| {
        implied
            .iter()
            .any(|p| (p.0 - r.x).abs() + (p.1 - r.y).abs() < 1e-9)
    };
    eprintln!("μ = {mu}: {} implied tangential components", implied.len());
    // Rows with a friction law: not the ends of joints on the clamped base, whose
    // displacements are held (tangential status "none").
    let law = |r: &InterfaceRow| matches!(r.tangential_status.as_deref(), Some("stick" | "slip"));
    for r in rows
        .iter()
        .filter(|r| r.closed && law(r) && !at_junction(r))
    {
        let excess = r.tt.abs() - mu * r.tn.abs();
        assert!(
            excess <= 1e-8 * st,
            "μ {mu} at {:?}: |t_t| {} > μ|t_n|",
            (r.x, r.y),
            r.tt
        );
        if r.tangential_status.as_deref() == Some("slip") {
            slipping += 1;
            assert!(
                excess.abs() <= 1e-6 * st,
                "μ {mu} slips below μ|t_n| at {:?}",
                (r.x, r.y)
            );
        }
    }
    slipping
}

/// The 4 × 5 wall at 0.625 of its weight sideways (its collapse multiplier is 0.636 for
/// μ = 3) with μ = 3, 10, 100 and 1000: each converges (μ = 1000 did not settle in 300
/// outer iterations before Anderson's acceleration of the Tresca fixed point), obeys
/// Coulomb's law on every row with a friction law (|t_t| ≤ μ|t_n|, equal where the row
/// slips), and its tractions approach those of stick joints as μ grows.
#[test]
fn large_friction_converges_and_tends_to_stick() {
    let dir = support::tmpdir("large_friction");
    let solve = |name: &str, tangential: &str| -> (Vec<InterfaceRow>, Value) {
        // All interfaces are read below (`run` reads one).
        let r = run(&dir, name, &large_friction_scene(tangential, "12.5"), "");
        assert_eq!(r.code, 0, "{name}: {}", r.stderr);
        assert_eq!(r.summary["contact"]["converged"], true, "{name}");
        (all_rows(&dir.join(format!("out_{name}"))), r.summary)
    };
    let (stick, _) = solve("stick", "tangential = \"stick\"");
    let st = stick.iter().fold(0.0f64, |a, r| a.max(r.tt.abs()));
    let mut last = (f64::INFINITY, f64::INFINITY);
    for mu in [3.0, 10.0, 100.0, 1000.0] {
        let (rows, summary) = solve(
            &format!("mu{mu}"),
            &format!("tangential = \"friction\"\nfriction = {mu}"),
        );
        assert_eq!(rows.len(), stick.len());
        let slipping = coulomb_holds(&rows, &summary, mu, st);
        // Σ|t(μ) − t(stick)| / Σ|t(stick)| over every row.
        let dist = |f: fn(&InterfaceRow) -> f64| {
            let d: f64 = rows
                .iter()
                .zip(&stick)
                .map(|(r, s)| (f(r) - f(s)).abs())
                .sum();
            d / stick.iter().map(|s| f(s).abs()).sum::<f64>()
        };
        let d = (dist(|r| r.tn), dist(|r| r.tt));
        eprintln!(
            "μ = {mu}: {slipping} slipping rows; difference to stick (L1, relative): normal \
             {:.4}, tangential {:.4}",
            d.0, d.1
        );
        if mu <= 100.0 {
            assert!(d.0 < last.0 && d.1 < last.1, "μ {mu}: {d:?} after {last:?}");
        }
        if mu >= 100.0 {
            // Measured 0.0054 / 0.016 (μ = 100) and 0.0063 / 0.019 (μ = 1000): from μ = 100
            // on the states differ from stick by the one edge row that slips, which stick
            // keeps closed and tangentially free.
            assert!(
                d.0 < 0.01 && d.1 < 0.03,
                "μ = {mu} is far from stick: {d:?}"
            );
        }
        last = d;
    }
    // At half the weight sideways the statuses of μ = 1000 alternate around a row at the
    // point of opening (the history is then kept across them): it settles too.
    let scene = large_friction_scene("tangential = \"friction\"\nfriction = 1000.0", "10.0");
    let r = run(&dir, "mu1000_half", &scene, "");
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert_eq!(r.summary["contact"]["converged"], true);
}

/// The 4 × 5 wall's collapse search under t × its weight sideways with μ = 1 000 completes
/// with the evolutive path (`method = "lcp"`; the wall's default since its T-junctions is the
/// full rows, whose search `full_rows::a_frictional_wall_collapses_below_its_stick_limit_as_mu_grows`
/// tests; the evolutive path stopped at t = 0.7266, then 0.6875, where the friction fixed
/// point cycled: near collapse the lagged bounds μλ_n amplify every change of the normal
/// forces a thousandfold; the driver now hands such a step to the sparse solver, whose
/// semismooth Newton iteration ties the slip forces to the normal forces within each
/// solve). Its multiplier lies within 1 % of the stick joints' (measured 0.7383 against
/// 0.7334), and its reported state obeys Coulomb's law row by row.
#[test]
fn collapse_with_very_large_friction_completes_near_stick() {
    let dir = support::tmpdir("collapse_mu1000");
    let collapse = "[solve]\nmethod = \"lcp\"\ncollapse = { max = 2.0, tolerance = 0.002 }\n";
    let search = |name: &str, tangential: &str| -> (f64, f64, Value) {
        let scene = large_friction_scene(tangential, "\"20*t\"") + collapse;
        let r = run(&dir, name, &scene, "");
        assert_eq!(r.code, 0, "{name}: {}", r.stderr);
        let c = &r.summary["contact"]["collapse"];
        let (lo, hi) = (
            c["multiplier"].as_f64().unwrap(),
            c["collapses_at"].as_f64().unwrap(),
        );
        // The rigid-block statics bounds the multiplier from above.
        let bound = c["upper_bound"].as_f64().expect("upper_bound");
        eprintln!("{name}: collapse multiplier {lo:.4} .. {hi:.4}, upper bound {bound:.4}");
        assert!(
            lo <= bound,
            "{name}: multiplier {lo} above the bound {bound}"
        );
        (lo, hi, r.summary)
    };
    let (stick, _, _) = search("stick", "tangential = \"stick\"");
    let (lo, hi, summary) = search("mu1000", "tangential = \"friction\"\nfriction = 1000.0");
    assert!(hi > lo && hi - lo <= 0.002 + 1e-12, "bracket {lo} .. {hi}");
    assert!(
        (lo - stick).abs() <= 0.01 * stick,
        "μ = 1000 collapses at {lo}, stick at {stick}"
    );
    let rows = all_rows(&dir.join("out_mu1000"));
    let st = rows.iter().fold(0.0f64, |a, r| a.max(r.tt.abs()));
    coulomb_holds(&rows, &summary, 1000.0, st);
}

/// The 220-stone wall of `pipelines/stone_wall.toml` (joints found from the drawing, 389
/// junctions, 12 foundation elements cut where two stones meet on them) with Coulomb joints,
/// μ = 0.7, under its own weight, on the full rows (`method = "exact"`: every pair its own
/// rows at the junctions, Coulomb's law settled by the linear solve of the last statuses;
/// 95 programmes, 41 before the fixed point kept Anderson's history over small changes of
/// the slipping set). Every closed row with a friction law obeys Coulomb's law (slipping rows
/// at μ|t_n|), some rows slip, and every stone balances.
///
/// On the default solver this wall settled through the semismooth Newton iteration until
/// `[contact]` cut the foundation's elements under two stones (before, each such element
/// belonged to one joint only and the other stone lost its support over it); on the cut
/// mesh that iteration does not settle and the run ends "undecided" (exit 3, 436 s, the
/// rigid-block check proving that forces in the friction cones exist): an open item
/// (README "Friction").
///
/// Long: 3–5 minutes on a 2-core machine, too long for CI's 30 minutes beside the rest;
/// `make test-long` runs it, and the same scene at 0.117 g sideways
/// (`full_rows::the_stone_wall_with_coulomb_joints_stands_where_a_stone_was_left_free`).
/// CI keeps Coulomb's law at junctions on running-bond walls (`full_rows`, `sparse`).
#[test]
#[ignore = "long (3-5 min): make test-long"]
fn stone_wall_with_coulomb_joints_stands_under_its_weight() {
    let dir = support::tmpdir("stone_wall_friction");
    let out = dir.join("out");
    let scene = support::root().join("pipelines/stone_wall.toml");
    let (code, _, stderr) = support::sgbem(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        "--method",
        "exact",
        "--set",
        "defaults.interface.tangential=friction",
        "--set",
        "defaults.interface.friction=0.7",
        "--set",
        "defaults.body.body_force=[0.0, -25.0]",
        "--set",
        "output.vtk=false",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["contact"]["converged"], true);
    let rows = all_rows(&out);
    let st = rows.iter().fold(0.0f64, |a, r| a.max(r.tt.abs()));
    let slipping = coulomb_holds(&rows, &summary, 0.7, st);
    assert!(slipping > 100, "{slipping} rows slip");
    for (body, e) in summary["equilibrium"].as_object().unwrap() {
        if let Some(r) = e.get("relative_imbalance").and_then(Value::as_f64) {
            assert!(r < 1e-6, "{body}: relative imbalance {r}");
        }
    }
}
