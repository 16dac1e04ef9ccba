//! The sparse solver (`method = "sparse"`: the active set on the sparse system of
//! displacements and openings, no column of the opening stiffness) against the paper's
//! evolutive path: the same statuses pair by pair and the same tractions, on the shipped
//! scenes of every law (frictionless, stick, friction, cohesion, junctions), and the same
//! mechanism where none exists.

mod support;

use std::path::{Path, PathBuf};

use support::*;

/// `--set` of the evolutive path's cut of junction cycles, for the sparse solver's runs that
/// are compared with it pair by pair (by default the sparse solver cuts them at joints).
const TANGENTIAL: [&str; 2] = ["--set", "solve.junctions=\"tangential\""];

/// Runs `scene` with `method` into `out`; the mesh is meshed from `geo` unless the scene
/// meshes its own `.geo`.
fn run(scene: &str, geo: Option<&str>, out: &Path, method: &str) -> (i32, String) {
    run_with(scene, geo, out, method, &[])
}

/// [`run`] with more arguments.
fn run_with(
    scene: &str,
    geo: Option<&str>,
    out: &Path,
    method: &str,
    more: &[&str],
) -> (i32, String) {
    let scene_path = root().join(format!("pipelines/{scene}.toml"));
    let mut args: Vec<String> = vec!["run".into(), scene_path.to_string_lossy().into_owned()];
    if let Some(g) = geo {
        let msh: PathBuf = gmsh(
            &root().join(format!("geo/{g}.geo")),
            out.parent().expect("a parent folder"),
            &format!("{g}.msh"),
            false,
            &[],
        );
        args.push("--mesh".into());
        args.push(msh.to_string_lossy().into_owned());
    }
    for a in [
        "--out",
        &out.to_string_lossy(),
        "--method",
        method,
        "--quiet",
    ] {
        args.push(a.to_string());
    }
    args.extend(more.iter().map(|a| a.to_string()));
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    let (code, _, err) = sgbem(&refs);
    (code, err)
}

fn summary(out: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(out.join("summary.json")).expect("summary.json");
    serde_json::from_str(&text).expect("summary JSON")
}

/// The same statuses pair by pair and tractions within `1e-8` of the largest traction of the
/// run, on every interface of two runs of one scene.
fn assert_same_interfaces(scene: &str, a: &Path, b: &Path) {
    let mut files: Vec<PathBuf> = std::fs::read_dir(a.join("interfaces"))
        .expect("interfaces folder")
        .map(|e| e.expect("entry").path())
        .collect();
    files.sort();
    assert!(!files.is_empty(), "{scene}: no interface table");
    let tables: Vec<_> = files
        .iter()
        .map(|f| {
            let name = f.file_name().expect("a file name");
            (
                read_interface_csv(f),
                read_interface_csv(&b.join("interfaces").join(name)),
            )
        })
        .collect();
    let scale = tables
        .iter()
        .flat_map(|(_, rows)| rows.iter().map(|r| r.tn.abs().max(r.tt.abs())))
        .fold(0.0f64, f64::max);
    assert!(scale > 0.0, "{scene}: no traction at all");
    for (sparse, lcp) in &tables {
        assert_eq!(sparse.len(), lcp.len(), "{scene}");
        for (p, q) in sparse.iter().zip(lcp) {
            assert_eq!(p.closed, q.closed, "{scene}: status at ({}, {})", p.x, p.y);
            assert_eq!(
                p.tangential_status, q.tangential_status,
                "{scene}: tangential status at ({}, {})",
                p.x, p.y
            );
            for (u, v, what) in [(p.tn, q.tn, "normal"), (p.tt, q.tt, "tangential")] {
                assert!(
                    (u - v).abs() <= 1e-8 * scale,
                    "{scene}: {what} traction at ({}, {}): sparse {u}, evolutive {v} \
                     (scale {scale})",
                    p.x,
                    p.y
                );
            }
        }
    }
}

/// Coulomb's law on every closed row of a run with friction coefficient `mu`: a slipping row
/// carries μ times its normal traction, a sticking one at most that (within 1e-8 of the
/// largest traction); returns the slipping rows, so that a caller can ask for some.
fn assert_coulomb(scene: &str, out: &Path, mu: f64) -> usize {
    let rows: Vec<_> = std::fs::read_dir(out.join("interfaces"))
        .expect("interfaces folder")
        .flat_map(|e| read_interface_csv(&e.expect("entry").path()))
        .collect();
    let scale = rows
        .iter()
        .map(|r| r.tn.abs().max(r.tt.abs()))
        .fold(0.0f64, f64::max);
    let mut slipping = 0;
    for r in rows.iter().filter(|r| r.closed) {
        let limit = mu * (-r.tn).max(0.0);
        match r.tangential_status.as_deref() {
            Some("slip") => {
                slipping += 1;
                assert!(
                    (r.tt.abs() - limit).abs() <= 1e-8 * scale,
                    "{scene}: slipping at ({}, {}) with |t| = {} against mu·p = {limit}",
                    r.x,
                    r.y,
                    r.tt.abs()
                );
            }
            Some("stick") => assert!(
                r.tt.abs() <= limit + 1e-8 * scale,
                "{scene}: sticking at ({}, {}) with |t| = {} above mu·p = {limit}",
                r.x,
                r.y,
                r.tt.abs()
            ),
            _ => {}
        }
    }
    slipping
}

/// The sparse solver follows Coulomb's law within its own iteration (each iterate's slip
/// bounds from the last one's normal forces): its results obey the law row by row, with
/// rows slipping on the running-bond wall and the frictional beam on blocks.
#[test]
fn sparse_solver_obeys_coulomb_row_by_row() {
    for (scene, geo, mu) in [
        ("wall_running_bond", None, 0.7),
        ("beam_on_blocks_friction", Some("beam_on_blocks"), 0.6),
    ] {
        let out = tmpdir(&format!("sparse-coulomb-{scene}")).join("out");
        let (code, err) = run(scene, geo, &out, "sparse");
        assert_eq!(code, 0, "{scene}: {err}");
        let slipping = assert_coulomb(scene, &out, mu);
        assert!(slipping > 0, "{scene}: no row slips");
        // Junctions exact: no implied component slides without a friction force.
        if let Some(j) = summary(&out)["contact"]["junctions"].as_object() {
            assert_eq!(j["implied_slipping"]["count"], 0, "{scene}: {j:?}");
        }
    }
}

/// `wall_collapse` (μ = 0.8): the sparse solver, following Coulomb's law within its
/// iteration on junction cycles cut at whole joints (at every trial), finds the collapse
/// multiplier of the full rows (every pair component its own row), within the search's
/// tolerance; on the tangential cut, whose bed joints slide at T-junctions without a
/// friction force of their own, it stood only to 0.500 against 0.5996. The state reported
/// at the multiplier obeys Coulomb's law row by row, and every brick balances.
#[test]
fn wall_collapse_stands_where_coulomb_has_an_equilibrium() {
    let dir = tmpdir("sparse-wall-collapse");
    let multiplier = |method: &str| {
        let out = dir.join(method);
        let (code, err) = run("wall_collapse", None, &out, method);
        assert_eq!(code, 0, "{method}: {err}");
        let s = summary(&out);
        let c = &s["contact"]["collapse"];
        let t = c["multiplier"].as_f64().expect("multiplier");
        let at = c["collapses_at"].as_f64().expect("collapses_at");
        assert!(at - t <= 0.001 + 1e-12, "{method}: {t}, collapses at {at}");
        (t, out, s)
    };
    let (exact, _, _) = multiplier("exact");
    let (t, out, s) = multiplier("sparse");
    println!("multiplier: full rows {exact}, sparse {t}");
    assert!(
        (t - exact).abs() <= 0.001 + 1e-12,
        "sparse {t} against the full rows' {exact}"
    );
    assert_eq!(s["contact"]["junctions"]["implied_slipping"]["count"], 0);
    assert!(
        assert_coulomb("wall_collapse", &out, 0.8) > 0,
        "no row slips"
    );
    assert_balanced("wall_collapse", &s);
}

/// Every body of a run's summary `s` balances to round-off (1e-8 of its loads).
fn assert_balanced(scene: &str, s: &serde_json::Value) {
    for (body, b) in s["equilibrium"].as_object().expect("equilibrium") {
        if let Some(r) = b["relative_imbalance"].as_f64() {
            assert!(r <= 1e-8, "{scene}: body {body} imbalance {r}");
        }
    }
}

/// Frictionless contact (Hertz, the contact patch), stick joints from closed starts
/// (example 2, beam on blocks), Coulomb friction (beam on blocks, incline, vault), cohesion
/// and frictional junctions (the running-bond wall, the arch): the sparse solver and the
/// evolutive path agree pair by pair, and the evolutive cross-check inside the sparse run
/// finds no differing pair.
#[test]
fn sparse_solver_agrees_with_the_evolutive_path() {
    for (scene, geo) in [
        ("clamped_beam_joint", Some("clamped_beam_joint")),
        ("beam_on_blocks", Some("beam_on_blocks")),
        ("beam_on_blocks_friction", Some("beam_on_blocks")),
        ("hertz_contact", Some("hertz_contact")),
        ("contact_patch", Some("contact_patch")),
        ("incline_block", Some("two_blocks")),
        ("vault_friction", Some("vault")),
        ("wall", None),
        ("wall_running_bond", None),
        ("arch", None),
    ] {
        let dir = tmpdir(&format!("sparse-{scene}"));
        let (sparse, lcp) = (dir.join("sparse"), dir.join("lcp"));
        let (code, err) = run_with(scene, geo, &sparse, "sparse", &TANGENTIAL);
        assert_eq!(code, 0, "{scene} (sparse): {err}");
        let (code, err) = run(scene, geo, &lcp, "lcp");
        assert_eq!(code, 0, "{scene} (lcp): {err}");
        let s = summary(&sparse);
        assert_eq!(s["status"], "converged", "{scene}");
        assert_eq!(s["contact"]["solver"], "sparse", "{scene}");
        let n_rows = s["contact"]["interface_system_size"].as_u64().unwrap_or(0);
        for c in s["contact"]["cross_checks"]
            .as_array()
            .expect("cross checks")
        {
            assert_eq!(c["solver"], "lcp", "{scene}");
            assert_eq!(c["differing_pairs"], 0, "{scene}: {c}");
            assert_eq!(c["converged"], true, "{scene}: {c}");
        }
        assert!(n_rows > 0, "{scene}");
        assert_same_interfaces(scene, &sparse, &lcp);
        // Every body balances to round-off with the sparse solver too.
        assert_balanced(scene, &s);
    }
}

/// A block on an incline whose load exceeds what friction holds: no equilibrium, and the
/// sparse solver names the same mechanism as the evolutive path (exit 3). Up to the step
/// at the friction angle (t = μ = 0.5) the evolutive cross-check agrees pair by pair; at
/// that step the block's slide is free (no force drives or resists it), and the one pair
/// that sticks in one solution and slips in the other, with the same tractions, is counted
/// as degenerate, not as differing.
#[test]
fn sparse_solver_names_the_sliding_mechanism() {
    let dir = tmpdir("sparse-incline-slides");
    let out = dir.join("out");
    let (code, err) = run("incline_block_slides", Some("two_blocks"), &out, "sparse");
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("no equilibrium exists (a sliding mechanism): body \"upper\" slides"),
        "{err}"
    );
    let s = summary(&out);
    let checks = s["contact"]["cross_checks"]
        .as_array()
        .expect("cross checks");
    // t = 0.1, 0.2, 0.3, 0.4, 0.45, 0.5, then the failing step at 0.55.
    assert_eq!(checks.len(), 7, "{checks:?}");
    for c in &checks[..6] {
        assert_eq!(c["solver"], "lcp");
        assert_eq!(c["converged"], true, "{c}");
        assert_eq!(c["differing_pairs"], 0, "{c}");
    }
    let degenerate: Vec<u64> = checks[..6]
        .iter()
        .map(|c| c["degenerate_pairs"].as_u64().expect("count"))
        .collect();
    assert!(degenerate[..5].iter().all(|&d| d == 0), "{degenerate:?}");
    assert!(degenerate[5] <= 1, "{degenerate:?}");
}

/// A stick joint that starts open with zero gap under compression closes and ties at once:
/// the same state as the joint that starts closed (the evolutive path alone stopped at a
/// false mechanism there: the untied joint leaves the upper block free to slide), with the
/// default solver and with the sparse one.
#[test]
fn a_stick_joint_that_starts_open_ties_as_it_closes() {
    let dir = tmpdir("sparse-stick-open");
    let closed = dir.join("closed");
    let (code, err) = run("two_blocks", Some("two_blocks"), &closed, "lcp");
    assert_eq!(code, 0, "{err}");
    for method in ["lcp", "sparse"] {
        let out = dir.join(format!("open-{method}"));
        let scene = root().join("pipelines/two_blocks.toml");
        let msh = dir.join("two_blocks.msh");
        let (code, _, err) = sgbem(&[
            "run",
            scene.to_str().unwrap(),
            "--mesh",
            msh.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--method",
            method,
            "--set",
            "interface.joint.initial=open",
            "--set",
            "interface.joint.gap=0.0",
            "--quiet",
        ]);
        assert_eq!(code, 0, "{method}: {err}");
        assert_eq!(summary(&out)["status"], "converged", "{method}");
        assert_same_interfaces(&format!("open start, {method}"), &out, &closed);
    }
}

/// The collapse multiplier of a 4-course, 5-brick running-bond wall under a lateral body
/// force grows with the friction coefficient and stays below that of stick joints (the
/// limit μ → ∞): the Tresca fixed point settles at μ = 10 (it oscillated without the
/// relaxation of its bounds). The junctions are exact at every multiplier.
#[test]
fn collapse_multipliers_grow_with_friction_towards_stick() {
    let dir = tmpdir("sparse-collapse-mu");
    let text = std::fs::read_to_string(root().join("pipelines/wall_collapse.toml"))
        .expect("wall_collapse.toml")
        .replace(
            "../geo/wall.geo",
            &root().join("geo/wall.geo").to_string_lossy(),
        )
        .replace("courses = 5", "courses = 4")
        .replace("bricks = 3", "bricks = 5")
        .replace("tolerance = 0.001", "tolerance = 0.002");
    let stick = text.replace(
        "tangential = \"friction\"\nfriction = 0.8",
        "tangential = \"stick\"",
    );
    assert_ne!(
        stick, text,
        "the scene's interface table changed: update this test"
    );
    let mut multipliers = Vec::new();
    for (name, scene) in [
        ("mu1", text.replace("friction = 0.8", "friction = 1.0")),
        ("mu3", text.replace("friction = 0.8", "friction = 3.0")),
        ("mu10", text.replace("friction = 0.8", "friction = 10.0")),
        ("stick", stick),
    ] {
        let path = write(&dir, &format!("{name}.toml"), &scene);
        let out = dir.join(name);
        let (code, _, err) = sgbem(&[
            "run",
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--method",
            "sparse",
            "--quiet",
        ]);
        assert_eq!(code, 0, "{name}: {err}");
        let s = summary(&out);
        let m = s["contact"]["collapse"]["multiplier"]
            .as_f64()
            .expect("a multiplier");
        multipliers.push((name, m));
        // The search cuts the junction cycles at whole joints, at every trial: at the
        // multiplier no implied component slides against its law (the tangential cut left
        // 21, 24, 18 and 17 with μ = 1, 3, 10 and stick), and the joints obey Coulomb's law
        // row by row.
        let j = &s["contact"]["junctions"];
        assert!(
            j["rule"]
                .as_str()
                .is_some_and(|r| r.contains("at a whole pair")),
            "{name}: {j}"
        );
        assert_eq!(j["implied_slipping"]["count"], 0, "{name}: {j}");
        if name != "stick" {
            let mu: f64 = name[2..].parse().expect("mu");
            let slipping = assert_coulomb(name, &out, mu);
            println!("{name}: {slipping} rows slip at the multiplier");
        }
    }
    println!("{multipliers:?}");
    for w in multipliers.windows(2) {
        assert!(
            w[0].1 <= w[1].1 + 0.002,
            "the multiplier falls from {} to {}: {multipliers:?}",
            w[0].0,
            w[1].0
        );
    }
    // Friction matters: μ = 1 is well below stick.
    assert!(
        multipliers[0].1 < multipliers[3].1 - 0.02,
        "{multipliers:?}"
    );
}

/// A scene without `method` is solved by the sparse solver above 3000 unilateral pairs (the
/// 203-brick wall: 3 871); below, by the full rows where unilateral joints meet at junctions
/// (the 105-brick wall: 1 925 pairs, T-junctions; a single pier of blocks: none) and by the
/// evolutive path elsewhere (two blocks; the pier); a `method` given wins. `sgbem check`
/// says which, and why.
#[test]
fn the_method_follows_the_size_unless_given() {
    let of = |scene: &str, sets: &[&str]| -> String {
        let path = root().join("pipelines").join(scene);
        let mut args = vec!["check", path.to_str().unwrap()];
        for x in sets {
            args.push("--set");
            args.push(x);
        }
        let (code, out, err) = sgbem(&args);
        assert_eq!(code, 0, "{err}");
        out.lines()
            .find_map(|l| l.trim().strip_prefix("method:"))
            .map(|m| m.trim().to_string())
            .unwrap_or_else(|| panic!("no method line in {out}"))
    };
    let method = |sets: &[&str]| of("wall_running_bond.toml", sets);
    assert_eq!(method(&[]), "exact");
    assert_eq!(of("two_blocks.toml", &[]), "lcp");
    assert_eq!(of("wall.toml", &[]), "lcp");
    assert_eq!(method(&["mesh.courses=14", "mesh.bricks=14"]), "sparse");
    assert_eq!(method(&["solve.method=lcp"]), "lcp");
    assert_eq!(
        method(&["mesh.courses=14", "mesh.bricks=14", "solve.method=lcp"]),
        "lcp"
    );
}

/// A 10 × 10 running-bond wall with μ = 0.02: the bed joints slip nearly everywhere, so
/// statuses met on the way leave a brick free (every tangential row of it slipping). The
/// sparse solver passes through them with a proximal spring and ends on exact statuses
/// (before it, it stopped after 1 505 iterations, not converged): converged, every brick in
/// balance to round-off, complementarity exact; the default path (whose evolutive iteration
/// stops there at a false mechanism and hands the step to the sparse solver; `lcp`) gives the same
/// state pair by pair.
#[test]
fn statuses_that_leave_a_brick_free_are_passed_through() {
    let dir = tmpdir("sparse-low-friction");
    let scene = root().join("pipelines/wall_running_bond.toml");
    let mut outs = Vec::new();
    let mut counts = Vec::new();
    // The sparse solver on the evolutive path's cut of the junctions (compared pair by pair
    // below), the evolutive path, and the sparse solver's own exact junctions.
    for (name, method, cuts) in [
        ("sparse", "sparse", "tangential"),
        ("lcp", "lcp", "auto"),
        ("sparse-joints", "sparse", "auto"),
    ] {
        let out = dir.join(name);
        let cuts = format!("solve.junctions=\"{cuts}\"");
        let (code, _, err) = sgbem(&[
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--method",
            method,
            "--set",
            "defaults.interface.friction=0.02",
            "--set",
            "output.history=\"final\"",
            "--set",
            &cuts,
            "--quiet",
        ]);
        assert_eq!(code, 0, "{method}: {err}");
        let s = summary(&out);
        assert_eq!(s["status"], "converged", "{method}");
        assert_eq!(
            s["contact"]["complementarity_residual"].as_f64(),
            Some(0.0),
            "{method}"
        );
        let bodies = s["equilibrium"].as_object().expect("equilibrium per body");
        assert_eq!(bodies.len(), 105);
        for (name, b) in bodies {
            let load = b["loads"]
                .as_object()
                .expect("loads")
                .values()
                .flat_map(|l| {
                    [
                        l["fx"].as_f64().unwrap().abs(),
                        l["fy"].as_f64().unwrap().abs(),
                    ]
                })
                .fold(0.0f64, f64::max);
            let im = &b["imbalance"];
            for k in ["fx", "fy"] {
                let x = im[k].as_f64().expect("imbalance");
                assert!(x.abs() <= 1e-8 * load, "{method}: {name} {k} {x} of {load}");
            }
        }
        let slipping = s["contact"]["junctions"]["implied_slipping"]["count"]
            .as_u64()
            .expect("implied_slipping.count");
        counts.push(slipping);
        assert!(assert_coulomb("wall, μ = 0.02", &out, 0.02) > 0);
        outs.push(out);
    }
    // Nearly every bed joint slips: many cycles have no component that carries no force,
    // so the joint cuts leave some implied components slipping, but fewer.
    println!("implied components slipping (tangential cut, lcp, joints): {counts:?}");
    assert!(counts[0] > 0 && counts[2] < counts[0], "{counts:?}");
    assert_same_interfaces("wall, μ = 0.02", &outs[0], &outs[1]);
}
