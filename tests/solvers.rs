//! The contact engine: one discrete problem for every solver (evolutive, active set, Lemke,
//! QP), bodies held only by contact, mechanisms reported, detached lengths that converge
//! under refinement.

mod support;

use support::*;

fn assert_agree(name: &str, s: &serde_json::Value) {
    let checks = s["contact"]["cross_checks"].as_array().unwrap();
    let solvers: Vec<&str> = checks
        .iter()
        .map(|c| c["solver"].as_str().unwrap())
        .collect();
    assert_eq!(solvers, ["active-set", "qp", "lemke"], "{name}");
    for c in checks {
        assert_eq!(c["differing_pairs"], 0, "{name}: {c}");
        assert_eq!(c["converged"], true, "{name}: {c}");
    }
    assert_eq!(s["qp"]["differing_pairs_from_lcp"], 0, "{name}");
}

/// Evolutive = active set = Lemke = QP statuses (0 differing pairs, no polishing) on the
/// paper's examples 1 (slide) and 2, Hertz and the contact patch.
#[test]
fn every_solver_reaches_the_same_statuses() {
    for (scene, geo) in [
        ("beam_on_blocks_slide", "beam_on_blocks"),
        ("clamped_beam_joint", "clamped_beam_joint"),
        ("hertz_contact", "hertz_contact"),
        ("contact_patch", "contact_patch"),
    ] {
        let dir = tmpdir(&format!("agree-{scene}"));
        let msh = gmsh(
            &root().join(format!("geo/{geo}.geo")),
            &dir,
            "m.msh",
            false,
            &[],
        );
        let (code, err, s) = run_method(
            &root().join(format!("pipelines/{scene}.toml")),
            &msh,
            &dir.join("out"),
            "both",
        );
        assert_eq!(code, 0, "{scene}: {err}");
        let s = s.unwrap();
        assert_agree(scene, &s);
        // The QP block reports the QP's own zones: the same detached lengths.
        for (name, fig) in s["interfaces"].as_object().unwrap() {
            assert_eq!(
                fig["detached_length"], s["qp"]["interfaces"][name]["detached_length"],
                "{scene}"
            );
        }
    }
}

/// The Hertz half model with the upper body loaded by a traction: held only by contact in
/// the vertical direction, from an open start. Every method solves it; the contact forces
/// carry the load exactly; the half-width lies within one element of Johnson's.
#[test]
fn a_body_held_only_by_contact_is_solved_by_every_method() {
    let dir = tmpdir("floating-hertz");
    let msh = gmsh(
        &root().join("geo/hertz_contact.geo"),
        &dir,
        "m.msh",
        false,
        &[],
    );
    let text = std::fs::read_to_string(root().join("pipelines/hertz_contact.toml"))
        .unwrap()
        .replace("uy = -0.17\ntx = 0.0", "ty = -1.0\ntx = 0.0");
    let scene = write(&dir, "floating.toml", &text);
    let mut lengths = Vec::new();
    for method in ["lcp", "qp", "both"] {
        let (code, err, s) = run_method(&scene, &msh, &dir.join(method), method);
        assert_eq!(code, 0, "{method}: {err}");
        let s = s.unwrap();
        assert_eq!(s["status"], "converged", "{method}");
        let fig = &s["interfaces"]["contact"];
        // Top of width 50 under ty = -1: P = 50 per unit thickness.
        let res = fig["normal_resultant"].as_f64().unwrap();
        assert!(
            (res + 50.0).abs() <= 1e-8 * 50.0,
            "{method}: resultant {res}"
        );
        lengths.push(fig["detached_length"].as_f64().unwrap());
        if method == "both" {
            assert_agree("floating hertz", &s);
        }
        // Johnson: b = sqrt(4 P R / (π E*)) with the half model carrying P/2... the full
        // contact carries 2 × 50 = 100.
        let e_star = 1.0 / ((1.0 - 0.09) / 1000.0 + (1.0 - 0.0625) / 2000.0);
        let b = (4.0 * 100.0 * 100.0 / (std::f64::consts::PI * e_star)).sqrt();
        let closed = fig["closed_length"].as_f64().unwrap();
        assert!(
            (closed - b).abs() <= 0.1 + 1e-9,
            "{method}: closed {closed} vs b {b}"
        );
    }
    assert!(lengths.windows(2).all(|w| w[0] == w[1]), "{lengths:?}");
}

/// Pulled off its only support, the upper body has no equilibrium: exit 3, every output
/// written with that status, and the message names the body and its free motion.
#[test]
fn a_body_pulled_off_its_support_is_a_named_mechanism() {
    let dir = tmpdir("pulled-off");
    let msh = gmsh(
        &root().join("geo/hertz_contact.geo"),
        &dir,
        "m.msh",
        false,
        &[],
    );
    let text = std::fs::read_to_string(root().join("pipelines/hertz_contact.toml"))
        .unwrap()
        .replace("uy = -0.17\ntx = 0.0", "ty = 1.0\ntx = 0.0")
        .replace("initial = \"open\"", "initial = \"closed\"")
        .lines()
        .filter(|l| !l.starts_with("gap"))
        .collect::<Vec<_>>()
        .join("\n");
    let scene = write(&dir, "pulled.toml", &text);
    for method in ["lcp", "qp"] {
        let out = dir.join(method);
        let (code, err, s) = run_method(&scene, &msh, &out, method);
        assert_eq!(code, 3, "{method}: {err}");
        assert!(err.contains("body \"upper\""), "{method}: {err}");
        assert!(
            err.contains("translation") || err.contains("no equilibrium"),
            "{method}: {err}"
        );
        let s = s.expect("summary written");
        assert_eq!(s["status"], "not converged", "{method}");
        assert!(out.join("archive.h5").is_file(), "{method}");
    }
}

/// Detached length of example 2 under refinement of the joint (and of the outer curves with
/// it): it grows towards the continuum value (about 34.2 cm) with shrinking increments.
#[test]
fn example_2_detached_length_converges_under_refinement() {
    let dir = tmpdir("ex2-refine");
    let mut d = Vec::new();
    for (n, h) in [(104, "4"), (208, "2"), (416, "1")] {
        let msh = gmsh(
            &root().join("geo/clamped_beam_joint.geo"),
            &dir,
            &format!("m{n}.msh"),
            false,
            &[
                "-setnumber",
                "n_joint",
                &n.to_string(),
                "-setnumber",
                "h",
                h,
            ],
        );
        let text = std::fs::read_to_string(root().join("pipelines/clamped_beam_joint.toml"))
            .unwrap()
            .replace("history = \"full\"", "history = \"final\"")
            .replace("field = true", "field = false")
            .replace("operators = true", "operators = false")
            .replace("vtk = true", "vtk = false");
        let scene = write(&dir, &format!("s{n}.toml"), &text);
        let (code, err, s) = run_method(&scene, &msh, &dir.join(format!("o{n}")), "lcp");
        assert_eq!(code, 0, "{n}: {err}");
        d.push(
            s.unwrap()["interfaces"]["joint"]["detached_length"]
                .as_f64()
                .unwrap(),
        );
    }
    println!("example 2 detached length at 104 / 208 / 416 joint elements: {d:?}");
    assert!(d[0] < d[1] && d[1] < d[2], "{d:?}");
    assert!((d[2] - d[1]).abs() < (d[1] - d[0]).abs(), "{d:?}");
    // Richardson with the front's first-order resolution: d∞ ≈ 2 d416 − d208.
    let extrapolated = 2.0 * d[2] - d[1];
    assert!(
        extrapolated > 34.0 && extrapolated < 34.4,
        "{d:?} → {extrapolated}"
    );
}
