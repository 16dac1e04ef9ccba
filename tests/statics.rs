//! The rigid-block statics certificate (docs/formulation.md §6.9) end to end: a block on a
//! base (geo/two_blocks.geo, 1 × 0.5 on a clamped base, 16 elements per unit length) with
//! Coulomb friction μ on the joint under a unit body force tilted by θ (an incline).
//!
//! * The statics is exact here: forces within the friction cone exist iff tan θ ≤ μ (the
//!   block cannot tip before b/h = 2). Beyond μ the run's "no equilibrium" is confirmed
//!   (its message says so); the collapse search's `upper_bound` is μ to 1e-6.
//! * A collapse search with Coulomb joints (`pipelines/wall_collapse.toml`, smaller):
//!   `upper_bound` ≥ the multiplier, and the message at `collapses_at` is confirmed above
//!   the bound and undecided at or below it.
//!
//! Run with `cargo test --release --test statics -- --nocapture` to see the numbers.

mod support;

use std::path::{Path, PathBuf};

use sgbem::contact::statics::{certify, Verdict};

const MU: f64 = 0.5;

/// The block under the body force `body_force` (TOML), friction μ, and `solve` (a TOML
/// `[solve]` table or nothing).
fn block_scene(body_force: &str, solve: &str) -> String {
    support::two_blocks_scene(body_force, MU, solve, false)
}

/// The statics' verdict on the block at tan θ = `tan`, from the model alone.
fn verdict(dir: &Path, tan: f64) -> Verdict {
    let path = support::write(dir, "v.toml", &block_scene(&support::tilted(tan), ""));
    let l = sgbem::pipeline::load(&path, None).unwrap_or_else(|e| panic!("{e}"));
    certify(&l.model, 1.0)
}

/// Runs the scene text `scene` as `DIR/NAME.toml` into `DIR/NAME`: exit code, stderr and
/// the output folder.
fn run(dir: &Path, name: &str, scene: &str) -> (i32, String, PathBuf) {
    let path = support::write(dir, &format!("{name}.toml"), scene);
    let out = dir.join(name);
    let (code, stderr) = support::run_scene(&path, &out);
    (code, stderr, out)
}

#[test]
fn a_block_on_an_incline_has_forces_up_to_its_friction_angle_and_slides_by_proof_beyond() {
    let dir = support::two_blocks_mesh("statics_incline");
    for (tan, want) in [
        (0.9 * MU, Verdict::Feasible),
        (0.999 * MU, Verdict::Feasible),
        (1.001 * MU, Verdict::Infeasible),
        (1.1 * MU, Verdict::Infeasible),
    ] {
        let v = verdict(&dir, tan);
        eprintln!("tan θ = {:.4} μ: {v:?}", tan / MU);
        assert_eq!(v, want, "tan θ = {tan}");
    }
    // The run beyond the friction angle: the solver's sliding mechanism, confirmed.
    let (code, stderr, out) = run(&dir, "slides", &block_scene(&support::tilted(1.1 * MU), ""));
    eprintln!("tan θ = 1.1 μ: {}", stderr.trim());
    assert_eq!(code, 3, "{stderr}");
    assert!(
        stderr.contains("no equilibrium exists (a sliding mechanism): body \"upper\" slides")
            && stderr.contains("; the rigid-block check confirms it: no interface forces"),
        "{stderr}"
    );
    let s = support::read_summary(&out);
    assert!(s["mechanism"].is_array(), "the motion is kept: {s}");
    // The collapse search of t sideways on the unit weight: slides at t = μ.
    let scene = block_scene(
        "[\"t\", -1.0]",
        "[solve]\ncollapse = { max = 1.0, tolerance = 0.002 }",
    );
    let (code, stderr, out) = run(&dir, "collapse", &scene);
    assert_eq!(code, 0, "{stderr}");
    let c = &support::read_summary(&out)["contact"]["collapse"];
    let (t, bound) = (
        c["multiplier"].as_f64().unwrap(),
        c["upper_bound"].as_f64().expect("upper_bound"),
    );
    eprintln!("collapse multiplier {t:.4}, rigid-block upper bound {bound:.9}");
    assert!((bound - MU).abs() < 1e-6, "{bound}");
    assert!(t <= bound && t > 0.99 * MU, "{t}");
    assert!(
        c["upper_bound_meaning"]
            .as_str()
            .unwrap()
            .starts_with("the largest t at which interface forces"),
        "{c}"
    );
}

/// `pipelines/wall_collapse.toml` at 3 courses of 3 bricks (μ = 0.8): the statics' bound is
/// above the multiplier; trials that fail above it are confirmed, those at or below it
/// undecided (the associative cone is only an upper bound for Coulomb's law).
#[test]
fn the_collapse_search_upper_bound_lies_above_the_multiplier() {
    let dir = support::tmpdir("statics_wall_collapse");
    let out = dir.join("out");
    let scene = support::root().join("pipelines/wall_collapse.toml");
    let (code, _, stderr) = support::sgbem(&[
        "run",
        scene.to_str().unwrap(),
        "--set",
        "mesh.courses=3",
        "--set",
        "mesh.bricks=3",
        "--set",
        "solve.collapse.tolerance=0.01",
        "--set",
        "output.vtk=false",
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let c = &support::read_summary(&out)["contact"]["collapse"];
    let t = c["multiplier"].as_f64().unwrap();
    let at = c["collapses_at"].as_f64().unwrap();
    let bound = c["upper_bound"].as_f64().expect("upper_bound");
    let mech = c["mechanism"].as_str().unwrap();
    eprintln!(
        "3 x 3 wall, μ = 0.8: multiplier {t:.4}, collapses at {at:.4}, upper bound {bound:.6}"
    );
    assert!(bound >= t, "{bound} < {t}");
    let trial = c["trials"]
        .as_array()
        .expect("trials")
        .iter()
        .find(|x| x["t"].as_f64() == Some(at))
        .expect("the trial at collapses_at");
    if at > bound {
        assert!(mech.contains("the rigid-block check confirms it"), "{mech}");
    } else {
        assert_eq!(trial["undecided"], true, "{mech}");
        assert!(
            mech.starts_with("undecided: the solver found no equilibrium"),
            "{mech}"
        );
        assert!(!mech.contains("no equilibrium exists"), "{mech}");
    }
}

/// A frictionless 4 × 5 running-bond wall under wind (`pipelines/wall_running_bond.toml`,
/// `method = "lcp"`): the evolutive path ends at a mechanism, the rigid-block LP proves it
/// (no forces without tension balance the wind) and the run reports it without the sparse
/// solver's retry (which on the 105-brick wall took 176 s of the run's 192 s): no
/// `contact_sparse` stage in timings.json, the LP's stage present, the confirmation in the
/// message and every moving brick translating along +x. (Fails before: the retry ran and
/// the message had no confirmation without Coulomb pairs.)
#[test]
fn a_proven_mechanism_is_reported_without_the_sparse_retry() {
    let dir = support::tmpdir("statics_frictionless_wall");
    let out = dir.join("out");
    let scene = support::root().join("pipelines/wall_running_bond.toml");
    let mut args = vec!["run", scene.to_str().unwrap()];
    for set in [
        "solve.method=\"lcp\"",
        "defaults.interface.friction=0.0",
        "mesh.courses=4",
        "mesh.bricks=5",
        "output.vtk=false",
    ] {
        args.extend(["--set", set]);
    }
    args.extend(["--out", out.to_str().unwrap(), "--quiet"]);
    let (code, _, stderr) = support::sgbem(&args);
    assert_eq!(code, 3, "{stderr}");
    assert!(stderr.contains("no equilibrium exists"), "{stderr}");
    let summary = support::read_summary(&out);
    let failure = summary["failure"].as_str().expect("failure");
    // A long message keeps its head and tail (error.rs): the confirmation's end.
    assert!(
        failure.contains(
            "where a pair has it) balance every body that no displacement condition holds; \
             the motion: "
        ),
        "{failure}"
    );
    let timings: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("timings.json")).expect("timings.json"),
    )
    .expect("timings.json is JSON");
    let stages = timings["stages"].as_object().expect("stages");
    assert!(stages.contains_key("contact_statics"), "{timings}");
    assert!(!stages.contains_key("contact_sparse"), "{timings}");
    let moving = summary["mechanism"].as_array().expect("the mechanism");
    assert!(moving.len() > 12, "{}", moving.len());
    for m in moving {
        assert_eq!(m["kind"], "translation", "{m}");
        assert!(m["direction"][0].as_f64().unwrap() > 0.999, "{m}");
    }
}
