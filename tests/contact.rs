//! Contact and detachment (docs/formulation.md §6, §7 items 12 and 16): trivial cases, the paper's
//! example 2, agreement of the solvers, independence of the initial status, and operators
//! that never change during the iterations.

mod support;

use sgbem::bem::quadrature::QuadratureSettings;
use sgbem::contact::{Session, Solver};
use sgbem::pipeline::{load, solve_loaded, Loaded};
use sgbem::solution::{ContactSummary, PairStatus};
use sgbem::timings::Timings;
use support::*;

fn loaded(dir: &std::path::Path, scene: &str, mesh: &std::path::Path) -> Loaded {
    let sc = write(dir, "s.toml", scene);
    load(&sc, Some(mesh)).unwrap_or_else(|e| panic!("{e}"))
}

/// Stacked blocks with rollers on the base and on the left sides: a uniform stress state.
fn rollers_scene(top: &str, joint: &str) -> String {
    format!(
        "plane = \"strain\"\n[body.lower]\nyoung = 1.0\npoisson = 0.3\n[body.upper]\nyoung = 3.0\n\
         poisson = 0.2\n[boundary.base]\nuy = 0.0\n[boundary.left]\nux = 0.0\n[boundary.top]\n{top}\n\
         [interface.joint]\nmodel = \"unilateral\"\n{joint}\n[solve]\nmethod = \"both\"\n"
    )
}

fn rollers_mesh(n: usize) -> Msh {
    let mut m = Msh::default();
    m.line(1, [0.0, 0.0], [1.0, 0.0], n, &[1]);
    m.line(2, [1.0, 0.0], [1.0, 1.0], n, &[2]);
    m.line(3, [1.0, 1.0], [0.0, 1.0], n, &[3]);
    m.line(4, [0.0, 1.0], [0.0, 0.0], n, &[5]);
    m.line(5, [1.0, 1.0], [1.0, 2.0], n, &[2]);
    m.line(6, [1.0, 2.0], [0.0, 2.0], n, &[4]);
    m.line(7, [0.0, 2.0], [0.0, 1.0], n, &[5]);
    m.surface(1, &[1, 2, 3, 4], &[1]);
    m.surface(2, &[-3, 5, 6, 7], &[2]);
    for (t, name) in [
        (1, "base"),
        (2, "right"),
        (3, "joint"),
        (4, "top"),
        (5, "left"),
    ] {
        m.name(1, t, name);
    }
    m.name(2, 1, "lower");
    m.name(2, 2, "upper");
    m
}

fn run(l: &Loaded) -> sgbem::contact::driver::ContactRun {
    let q = QuadratureSettings::standard();
    let mut t = Timings::default();
    solve_loaded(l, &q, &mut t)
        .unwrap_or_else(|e| panic!("{e}"))
        .1
}

#[test]
fn uniform_compression_closes_everything_with_uniform_pressure() {
    let dir = tmpdir("compression");
    let msh = rollers_mesh(6).save(&dir, "m.msh");
    // Different materials: frictionless, so that their different lateral expansions do
    // not load the joint in shear.
    for initial in ["initial = \"closed\"", "initial = \"open\""] {
        let joint = format!("{initial}\ntangential = \"slide\"");
        let l = loaded(&dir, &rollers_scene("ty = -2.5", &joint), &msh);
        let r = run(&l);
        assert_eq!(r.status.as_str(), "converged");
        for p in &r.interfaces[0].pairs {
            assert_eq!(p.status, PairStatus::Closed, "{initial}");
            assert!(
                (p.traction[1] + 2.5).abs() < 1e-8 * 2.5,
                "pressure {}",
                p.traction[1]
            );
            assert!(p.traction[0].abs() < 1e-8, "shear {}", p.traction[0]);
        }
        let qp = r.qp.expect("qp ran");
        assert_eq!(qp.differing_pairs, Some(0));
    }
}

#[test]
fn uniform_tension_opens_everything_with_zero_forces() {
    let dir = tmpdir("tension");
    let msh = rollers_mesh(6).save(&dir, "m.msh");
    // The upper block is pulled up by a displacement on its top: it lifts off rigidly.
    let l = loaded(
        &dir,
        &rollers_scene("uy = 0.01\nux = 0.0", "initial = \"closed\""),
        &msh,
    );
    let r = run(&l);
    assert_eq!(r.status.as_str(), "converged");
    for p in &r.interfaces[0].pairs {
        assert_eq!(p.status, PairStatus::Open);
        // Each body's own weak compatibility gives its tractions: zero up to roundoff for a
        // rigid lift.
        assert!(
            p.traction[0].abs() < 1e-9 && p.traction[1].abs() < 1e-9,
            "{:?}",
            p.traction
        );
        assert!((p.jump[1] - 0.01).abs() < 1e-9, "opening {}", p.jump[1]);
    }
    let mut worst = 0.0f64;
    for f in &r.fields {
        for t in f.t.iter().flatten() {
            worst = worst.max(t[0].abs()).max(t[1].abs());
        }
    }
    assert!(worst < 1e-9, "largest traction {worst:e}");
}

#[test]
fn an_open_gap_under_no_load_stays_open() {
    let dir = tmpdir("gap");
    let msh = rollers_mesh(6).save(&dir, "m.msh");
    // The upper block is held by its top (an open interface holds nothing).
    let gap = "initial = \"open\"\ngap = \"0.01 + 0.02*x\"";
    let l = loaded(&dir, &rollers_scene("uy = 0.0", gap), &msh);
    let r = run(&l);
    for (p, pair) in r.interfaces[0]
        .pairs
        .iter()
        .zip(&l.model.interfaces[0].pairs)
    {
        assert_eq!(p.status, PairStatus::Open);
        assert!((p.jump[1]).abs() < 1e-12 && pair.gap > 0.009);
    }
    // Pushed down by less than the smallest gap: still open everywhere, the opening reduced
    // by the push.
    let l = loaded(&dir, &rollers_scene("uy = -0.005", gap), &msh);
    let r = run(&l);
    for (p, pair) in r.interfaces[0]
        .pairs
        .iter()
        .zip(&l.model.interfaces[0].pairs)
    {
        assert_eq!(p.status, PairStatus::Open);
        assert!((pair.gap + p.jump[1] - (pair.gap - 0.005)).abs() < 1e-9);
    }
}

fn beam() -> Loaded {
    let dir = tmpdir("beam");
    let msh = gmsh(
        &root().join("geo/clamped_beam_joint.geo"),
        &dir,
        "beam.msh",
        false,
        &[],
    );
    load(
        &root().join("pipelines/clamped_beam_joint.toml"),
        Some(&msh),
    )
    .unwrap_or_else(|e| panic!("{e}"))
}

/// The paper's example 2: 33.85 cm detached (88 of the 104 joint elements), the closed zone
/// at the top; the evolutive path opens one pair at a time, monotonically; the active set
/// and the polished QP reach the same statuses.
#[test]
fn example_2_detachment() {
    let l = beam();
    let r = run(&l);
    let joint = &l.model.interfaces[0];
    let el = 40.0 / 104.0;
    let det = sgbem::output::summary::interface_figures(joint, &r.interfaces[0], 1.0);
    let d = det.detached_length;
    println!(
        "example 2: detached {d:.4} cm, closed {}",
        det.closed_length
    );
    assert!((d - 33.85).abs() <= el + 1e-9, "detached length {d}");
    // The closed pairs are the top ones (largest y), contiguous.
    let closed: Vec<f64> = joint
        .pairs
        .iter()
        .zip(&r.interfaces[0].pairs)
        .filter(|(_, q)| q.status == PairStatus::Closed)
        .map(|(p, _)| p.x[1])
        .collect();
    assert!(
        closed.iter().all(|&y| y > 33.0),
        "closed pairs at {closed:?}"
    );
    // Monotone path: the detached length never decreases.
    let lengths: Vec<f64> = r
        .history
        .rows
        .iter()
        .map(|row| row.detached_length[0])
        .collect();
    assert!(
        lengths.windows(2).all(|w| w[1] >= w[0] - 1e-12),
        "{lengths:?}"
    );
    // Every solver on the same problem: active set, QP and Lemke reach the same statuses.
    let ContactSummary::Contact(contact) = &r.contact else {
        panic!("a contact run's block: {:?}", r.contact)
    };
    let checks = &contact.cross_checks;
    assert_eq!(checks.len(), 3, "{checks:?}");
    for c in checks {
        assert_eq!(c.differing_pairs, 0, "{c:?}");
        assert!(c.converged, "{c:?}");
    }
    assert_eq!(r.qp.as_ref().unwrap().differing_pairs, Some(0));
    assert!(contact.complementarity_residual <= 1e-10);
}

/// Along the evolutive path of example 2, σx at the bottom fibre of section a-a (x = 100)
/// changes sign when the detached length passes about 16.92 cm (the paper's Fig. 6).
#[test]
fn example_2_bottom_fibre_changes_sign_along_the_path() {
    use sgbem::bem::assembly::material;
    use sgbem::post::{evaluate_points, BodyInput};
    let l = beam();
    let r = run(&l);
    let q = QuadratureSettings::standard();
    let mut previous: Option<(f64, f64)> = None;
    let mut crossing = None;
    for (state, row) in r.states.iter().zip(&r.history.rows) {
        let inputs: Vec<BodyInput> = l
            .model
            .bodies
            .iter()
            .zip(&state.fields)
            .map(|(b, f)| BodyInput {
                body: b,
                material: material(b, l.scene.plane),
                field: f,
                body_force: None,
            })
            .collect();
        let v = evaluate_points(&inputs, &q, &[[100.0, 0.0]]);
        let sx = v[0].as_ref().expect("point in body A").sigma[0][0];
        let d = row.detached_length[0];
        if let Some((d0, s0)) = previous {
            if s0 > 0.0 && sx <= 0.0 && crossing.is_none() {
                crossing = Some((d0, d));
            }
        }
        previous = Some((d, sx));
    }
    let (d0, d1) = crossing.expect("σx changes sign along the path");
    println!("example 2: σx at (100, 0) changes sign between d = {d0:.2} and {d1:.2} cm");
    assert!(
        d0 <= 16.92 + 2.0 && d1 >= 16.92 - 2.0,
        "sign change at {d0}..{d1}"
    );
}

/// The same physical state is reached from different initial statuses by every solver
/// (evolutive, active set, Lemke, QP: one discrete problem), and the per-body operators are
/// the same bits before and after the iterations (no integral recomputed).
#[test]
fn final_state_does_not_depend_on_the_initial_status_or_the_solver() {
    let l = beam();
    let q = QuadratureSettings::standard();
    let prep =
        sgbem::bem::prepare(&l.model, l.scene.plane, &q, 1.0, &l.scene.path, &|_| {}).unwrap();
    let hash = |p: &sgbem::bem::Operators| -> Vec<u64> {
        p.condensed
            .iter()
            .map(|c| {
                let mut h: u64 = 1469598103934665603;
                for i in 0..c.d00.nrows() {
                    for j in 0..c.d00.ncols() {
                        h = (h ^ c.d00[(i, j)].to_bits()).wrapping_mul(1099511628211);
                    }
                }
                h
            })
            .collect()
    };
    let before = hash(&prep);
    let mut session = Session::new(&l.model, &prep).unwrap();
    let init = session.initial();
    let n = init.open.len();
    let starts: Vec<Vec<bool>> = vec![
        vec![false; n],
        vec![true; n],
        (0..n).map(|r| r % 3 == 0).collect(),
    ];
    let mut finals = Vec::new();
    for (i, open) in starts.into_iter().enumerate() {
        for m in [
            Solver::Evolutive,
            Solver::ActiveSet,
            Solver::Lemke,
            Solver::Qp,
        ] {
            let start = sgbem::contact::StepState {
                open: open.clone(),
                ..init.clone()
            };
            let r = session.solve_step(&start, m, 1e-10, 1000, 0, 1.0, false);
            assert!(r.converged, "start {i} {m:?}: {:?}", r.notes);
            finals.push((
                r.interfaces[0]
                    .pairs
                    .iter()
                    .map(|p| p.status)
                    .collect::<Vec<_>>(),
                r.nodal_force[0].clone(),
            ));
        }
    }
    for (s, t) in &finals[1..] {
        assert_eq!(s, &finals[0].0);
        let scale = finals[0].1.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (a, b) in t.iter().zip(&finals[0].1) {
            assert!((a - b).abs() <= 1e-8 * scale, "{a} vs {b}");
        }
    }
    assert_eq!(hash(&prep), before, "D00 changed during the iterations");
}

fn beam_with(joint_extra: &str, solve_extra: &str) -> Loaded {
    let dir = tmpdir("beam-variant");
    let msh = gmsh(
        &root().join("geo/clamped_beam_joint.geo"),
        &dir,
        "beam.msh",
        false,
        &["-setnumber", "n_joint", "52"],
    );
    let text = std::fs::read_to_string(root().join("pipelines/clamped_beam_joint.toml"))
        .unwrap()
        .replace("cohesion = 0.0\n", joint_extra)
        .replace("[solve]\n", &format!("[solve]\n{solve_extra}"));
    loaded(&dir, &text, &msh)
}

/// Brittle cohesion: a strong joint stays closed, a weaker one detaches less than a joint
/// without cohesion, and the detached length never grows with the cohesion.
#[test]
fn cohesion_delays_detachment() {
    let mut lengths = Vec::new();
    for c in [1000.0, 200.0, 100.0, 0.0] {
        let l = beam_with(&format!("cohesion = {c}\n"), "");
        let r = run(&l);
        assert_eq!(r.status.as_str(), "converged", "c = {c}");
        let d = sgbem::output::summary::interface_figures(
            &l.model.interfaces[0],
            &r.interfaces[0],
            1.0,
        )
        .detached_length;
        // Closed pairs hold a tension of at most c per tributary length (the nodal force
        // of the complementarity conditions, compression positive).
        let it = &l.model.interfaces[0];
        let mut w = vec![0.0; it.pairs.len()];
        for e in &it.elements {
            let (a, b) = (it.pairs[e.pairs[0]].x, it.pairs[e.pairs[1]].x);
            let len = (b[0] - a[0]).hypot(b[1] - a[1]);
            w[e.pairs[0]] += 0.5 * len;
            w[e.pairs[1]] += 0.5 * len;
        }
        let fmax = r.nodal_force[0].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (j, p) in r.interfaces[0].pairs.iter().enumerate() {
            let lambda = r.nodal_force[0][j];
            if p.status == PairStatus::Closed {
                assert!(
                    lambda + c * w[j] >= -1e-9 * fmax,
                    "c = {c}: pair {j} force {lambda}"
                );
            } else {
                assert!(
                    lambda.abs() <= 1e-9 * fmax,
                    "open pair {j} carries {lambda}"
                );
            }
        }
        lengths.push((c, d));
    }
    println!("cohesion sweep (c, detached): {lengths:?}");
    assert_eq!(lengths[0].1, 0.0, "c = 1000 keeps the joint closed");
    assert!(lengths.windows(2).all(|w| w[1].1 >= w[0].1), "{lengths:?}");
    assert!(lengths[3].1 > lengths[1].1, "{lengths:?}");
}

/// A quasi-static load history ending at the same load reaches the same state when there
/// is no cohesion (the frictionless-like problem has one solution); every step is recorded.
#[test]
fn load_history_reaches_the_same_final_state() {
    let one = run(&beam_with("cohesion = 0.0\n", ""));
    let steps = run(&beam_with(
        "cohesion = 0.0\n",
        "load_factors = [0.25, 0.5, 0.75, 1.0]\n",
    ));
    let st = |r: &sgbem::contact::driver::ContactRun| {
        r.interfaces[0]
            .pairs
            .iter()
            .map(|p| p.status)
            .collect::<Vec<_>>()
    };
    assert_eq!(st(&one), st(&steps));
    let steps_seen: std::collections::BTreeSet<usize> =
        steps.history.rows.iter().map(|r| r.load_step).collect();
    assert_eq!(steps_seen.len(), 4);
    // The detached length of a linear problem's contact zone does not depend on the load
    // level: each step ends where the first did.
    let finals: Vec<f64> = (0..4)
        .map(|s| {
            steps
                .history
                .rows
                .iter()
                .rfind(|r| r.load_step == s)
                .unwrap()
                .detached_length[0]
        })
        .collect();
    assert!(
        finals.windows(2).all(|w| (w[0] - w[1]).abs() < 1e-12),
        "{finals:?}"
    );
}

/// Example 1 with the paper's stick model: pairs at the contact edge that open once tied and
/// close once untied are kept closed and slipping; every solver reaches the same statuses.
#[test]
fn stick_edge_pairs_slip_and_every_solver_agrees() {
    let dir = tmpdir("ex1-stick");
    let msh = gmsh(
        &root().join("geo/beam_on_blocks.geo"),
        &dir,
        "m.msh",
        false,
        &[],
    );
    let l = load(&root().join("pipelines/beam_on_blocks.toml"), Some(&msh)).unwrap();
    let q = QuadratureSettings::standard();
    let prep =
        sgbem::bem::prepare(&l.model, l.scene.plane, &q, 1.0, &l.scene.path, &|_| {}).unwrap();
    let mut session = Session::new(&l.model, &prep).unwrap();
    let start = session.initial();
    let e = session.solve_step(&start, Solver::Evolutive, 1e-10, 1000, 0, 1.0, false);
    assert!(e.converged, "{:?}", e.notes);
    assert!(
        e.notes.iter().any(|n| n.contains("slipping")),
        "{:?}",
        e.notes
    );
    for m in [Solver::ActiveSet, Solver::Lemke, Solver::Qp] {
        let r = session.solve_step(&start, m, 1e-10, 1000, 0, 1.0, false);
        assert!(r.converged, "{m:?}: {:?}", r.notes);
        assert_eq!(
            sgbem::contact::differing_pairs(&r.interfaces, &e.interfaces),
            0,
            "{m:?}"
        );
    }
}

/// Stick joints that start open and close: every solver follows the stick law from the
/// moment a pair closes where the LCP with the stick rows of open pairs free leaves a body
/// free (docs/formulation.md §6.4: the pivoting solvers switch the pair's two rows
/// together, Lemke and the QP tie the rows of the pairs they close and solve again). Two
/// blocks with a gap of 1e-3 under uniform compression and the arch of 6 voussoirs with
/// open, zero-gap joints (before, every solver but the sparse one stopped at a false
/// mechanism there: the untied stick rows left a body free): each solver's step gives the
/// same statuses as the sparse solver's, and nodal forces and tractions within 1e-8 of the
/// largest.
#[test]
fn stick_joints_that_start_open_every_solver_ties_them_as_they_close() {
    let dir = tmpdir("stick-open-solvers");
    let blocks = gmsh(
        &root().join("geo/two_blocks.geo"),
        &dir,
        "two_blocks.msh",
        false,
        &[],
    );
    let cases: [(&str, Option<&std::path::Path>, &[&str]); 2] = [
        (
            "two_blocks",
            Some(&blocks),
            &["interface.joint.initial=open", "interface.joint.gap=0.001"],
        ),
        (
            "arch",
            None,
            &[
                "mesh.nv=6",
                "defaults.interface.initial=open",
                "defaults.interface.gap=0.0",
            ],
        ),
    ];
    for (scene, mesh, sets) in cases {
        let opts = sgbem::pipeline::LoadOptions {
            mesh: mesh.map(|m| m.to_path_buf()),
            sets: sets.iter().map(|s| s.to_string()).collect(),
            mesh_dir: Some(dir.clone()),
            method: None,
        };
        let l = sgbem::pipeline::load_with(&root().join(format!("pipelines/{scene}.toml")), &opts)
            .unwrap_or_else(|e| panic!("{scene}: {e}"));
        let q = QuadratureSettings::standard();
        let prep =
            sgbem::bem::prepare(&l.model, l.scene.plane, &q, 1.0, &l.scene.path, &|_| {}).unwrap();
        let mut session = Session::new(&l.model, &prep).unwrap();
        let start = session.initial();
        assert!(start.open.iter().all(|&o| o), "{scene}: an open start");
        let reference = session.solve_step(&start, Solver::Sparse, 1e-10, 1000, 0, 1.0, false);
        assert!(reference.converged, "{scene}: {:?}", reference.failure);
        let scale = reference
            .nodal_force
            .iter()
            .flatten()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        for m in [
            Solver::Evolutive,
            Solver::ActiveSet,
            Solver::Lemke,
            Solver::Qp,
        ] {
            let r = session.solve_step(&start, m, 1e-10, 1000, 0, 1.0, false);
            assert!(r.converged, "{scene} {m:?}: {:?}", r.failure);
            assert_eq!(
                sgbem::contact::differing_pairs(&r.interfaces, &reference.interfaces),
                0,
                "{scene} {m:?}"
            );
            for (a, b) in r
                .nodal_force
                .iter()
                .flatten()
                .zip(reference.nodal_force.iter().flatten())
            {
                assert!((a - b).abs() <= 1e-8 * scale, "{scene} {m:?}: {a} vs {b}");
            }
            // The tangential tractions too (the stick rows' forces).
            for (x, y) in r.interfaces.iter().zip(&reference.interfaces) {
                for (p, q) in x.pairs.iter().zip(&y.pairs) {
                    for c in 0..2 {
                        let t = p.traction[c] - q.traction[c];
                        let s = y
                            .pairs
                            .iter()
                            .map(|p| p.traction[0].abs().max(p.traction[1].abs()))
                            .fold(0.0f64, f64::max);
                        assert!(t.abs() <= 1e-8 * s, "{scene} {m:?}: {p:?} vs {q:?}");
                    }
                }
            }
        }
    }
}
