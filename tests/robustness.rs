//! Hard to break: hostile or careless use ends in an exit status and a message, never a
//! panic, a crash, a hang or a half-written run folder.

mod support;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use support::*;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_sgbem"))
}

fn output(cmd: &mut Command) -> (i32, String, String) {
    let o = cmd.output().expect("run sgbem");
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// Asserts an exit status and a message (first line of stderr) naming every word.
fn expect(out: &(i32, String, String), code: i32, words: &[&str]) {
    expect_exit(out, code, words);
    assert!(out.2.starts_with("sgbem: "), "{}", out.2);
}

/// The names in a folder, sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .map(|r| {
            r.filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

/// A stacked-blocks scene and mesh in `dir`; returns (scene, mesh).
fn stacked(dir: &Path, scene: &str, n: usize) -> (PathBuf, PathBuf) {
    let msh = stacked_blocks(n).save(dir, "m.msh");
    (write(dir, "scene.toml", scene), msh)
}

fn check(scene: &Path, mesh: &Path) -> (i32, String, String) {
    sgbem(&["check", s(scene), "--mesh", s(mesh)])
}

fn run(scene: &Path, mesh: &Path, out: &Path) -> (i32, String, String) {
    run_quiet(scene, mesh, out)
}

// --- 1. No panic, abort, crash or hang --------------------------------------------------

#[test]
fn plane_stress_poisson_half_is_an_input_error() {
    let dir = tmpdir("rb-poisson");
    let scene = STACKED_SCENE
        .replace("plane = \"strain\"", "plane = \"stress\"")
        .replacen("poisson = 0.3", "poisson = 0.5", 1);
    let (sc, msh) = stacked(&dir, &scene, 4);
    expect(
        &check(&sc, &msh),
        2,
        &["body.lower.poisson", "plane stress", "0.499"],
    );
    let out = dir.join("out");
    expect(&run(&sc, &msh, &out), 2, &["body.lower.poisson"]);
    assert!(!out.exists(), "nothing written for an input error");
    // 0.499 runs.
    let (sc, msh) = stacked(&dir, &scene.replace("poisson = 0.5", "poisson = 0.499"), 4);
    let (code, _, err) = run(&sc, &msh, &out);
    assert_eq!(code, 0, "{err}");
    assert!(out.join("summary.json").is_file());
}

#[test]
fn expressions_are_bounded_in_size_and_depth() {
    let dir = tmpdir("rb-expr");
    let msh = stacked_blocks(2).save(&dir, "m.msh");
    let cases = [
        (vec!["x"; 30_000].join("+"), "characters long"),
        (vec!["x"; 3_000].join("+"), "operations deep"),
        (
            format!("{}x{}", "(".repeat(60_000), ")".repeat(60_000)),
            "characters long",
        ),
        (
            format!("{}x{}", "(".repeat(300), ")".repeat(300)),
            "parentheses 300 deep",
        ),
        (format!("{}x", "-".repeat(5_000)), "run of 5000 signs"),
    ];
    for (expr, words) in cases {
        let scene = STACKED_SCENE.replace("ty = -1.0", &format!("ty = \"{expr}\""));
        let sc = write(&dir, "scene.toml", &scene);
        let t = Instant::now();
        expect(&check(&sc, &msh), 2, &["boundary.top", words]);
        assert!(t.elapsed() < Duration::from_secs(5), "{words}");
    }
}

/// Runs `sgbem ARGS` with stdout (or stderr) on /dev/full.
fn to_dev_full(args: &[&str], stderr: bool) -> (i32, String) {
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .expect("/dev/full");
    let mut cmd = bin();
    cmd.args(args);
    if stderr {
        cmd.stderr(full).stdout(Stdio::piped());
        let o = cmd.output().expect("run");
        (
            o.status.code().unwrap_or(-1),
            String::from_utf8_lossy(&o.stdout).into_owned(),
        )
    } else {
        cmd.stdout(full).stderr(Stdio::piped());
        let o = cmd.output().expect("run");
        (
            o.status.code().unwrap_or(-1),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    }
}

/// Runs `sgbem ARGS` with stdout a pipe whose reader has gone.
fn to_closed_pipe(args: &[&str]) -> (i32, String) {
    let mut child = bin()
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run");
    drop(child.stdout.take());
    let o = child.wait_with_output().expect("wait");
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn full_or_closed_output_streams_do_not_panic() {
    let dir = tmpdir("rb-streams");
    let (sc, msh) = stacked(&dir, STACKED_SCENE, 3);
    let out = dir.join("out");
    let (code, _, err) = run(&sc, &msh, &out);
    assert_eq!(code, 0, "{err}");
    let archive = out.join("archive.h5");
    for args in [
        vec!["check", s(&sc), "--mesh", s(&msh)],
        vec!["inspect", s(&archive)],
        vec!["--help"],
    ] {
        // A full device: exit 1 and a message naming standard output.
        let (code, err) = to_dev_full(&args, false);
        assert_eq!(code, 1, "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
        assert!(
            err.contains("standard output") && err.contains("cannot write"),
            "{err}"
        );
        // A closed pipe (`| head -1`): quiet success.
        let (code, err) = to_closed_pipe(&args);
        assert_eq!(code, 0, "{args:?}: {err}");
        assert!(err.is_empty(), "{args:?}: {err}");
    }
    // An input error with stderr on a full device: still exit 2, no panic (101).
    let (code, stdout) = to_dev_full(&["check", s(&dir.join("absent.toml"))], true);
    assert_eq!(code, 2, "{stdout}");
    // A successful run printing to a full device: the run is complete, the report fails.
    let (code, err) = to_dev_full(&["run", s(&sc), "--mesh", s(&msh), "--out", s(&out)], false);
    assert_eq!(code, 1, "{err}");
    assert!(out.join("summary.json").is_file());
}

#[test]
fn a_run_too_large_for_memory_is_refused_before_assembling() {
    let dir = tmpdir("rb-memory");
    let (sc, msh) = stacked(&dir, STACKED_SCENE, 4);
    let (code, text, err) = check(&sc, &msh);
    assert_eq!(code, 0, "{err}");
    let cost = text
        .lines()
        .find(|l| l.contains("cost:"))
        .expect("a cost line");
    assert!(
        cost.contains("peak memory") && cost.contains("to assemble"),
        "{cost}"
    );
    // 4 elements per side: 16 per body; each body has 2·9 free + 2·4 interface ... unknowns.
    assert!(cost.contains("unknowns"), "{cost}");

    // A limit below the estimate: refused, naming the estimate, the limit and the fix.
    let out = dir.join("out");
    let r = output(
        bin()
            .args([
                "run",
                s(&sc),
                "--mesh",
                s(&msh),
                "--out",
                s(&out),
                "--quiet",
            ])
            .env("SGBEM_MEMORY_LIMIT", "1000000"),
    );
    expect(
        &r,
        2,
        &[
            "needs about",
            "1.0 MB are available",
            "SGBEM_MEMORY_LIMIT",
            "coarsen the mesh",
        ],
    );
    assert!(!out.exists());
    assert!(
        listing(&dir).iter().all(|n| !n.starts_with('.')),
        "{:?}",
        listing(&dir)
    );

    // 200 000 boundary elements (a dense system of 10¹¹ entries per body) against the
    // machine's real memory: refused in seconds, nothing allocated.
    let big = stacked_blocks(30_000).save(&dir, "big.msh");
    let t = Instant::now();
    let r = run(&sc, &big, &out);
    let secs = t.elapsed().as_secs_f64();
    expect(
        &r,
        2,
        &["needs about", "TB", "are available", "body \"", "coarsen"],
    );
    assert!(secs < 20.0, "refused after {secs} s");
    // `check` refuses it as `run` does: the report (with the estimate), then the same message.
    let c = check(&sc, &big);
    assert_eq!(c.0, 2, "{}", c.2);
    assert!(c.1.contains("peak memory"), "{}", c.1);
    // The same words; the memory available is read by each process at its own time.
    let room = |e: &str| e.split(" are available").nth(1).map(str::to_string);
    assert!(
        room(&c.2).is_some() && room(&c.2) == room(&r.2),
        "{}\n{}",
        c.2,
        r.2
    );
    assert_eq!(c.2.split(" but ").next(), r.2.split(" but ").next());
}

// --- 2. Run folders ------------------------------------------------------------------------

#[test]
fn a_rerun_replaces_the_whole_folder_and_leaves_nothing_beside_it() {
    let dir = tmpdir("rb-rerun");
    let (sc, msh) = stacked(&dir, STACKED_SCENE, 3);
    let out = dir.join("out");
    std::fs::create_dir_all(out.join("vtk")).expect("mkdir");
    std::fs::write(out.join("vtk").join("boundary_0099.vtu"), "stale").expect("write");
    std::fs::write(out.join("summary.json"), "{\"status\": \"old\"}").expect("write");
    // The marker of an earlier run that wrote these files (output/owned.rs).
    std::fs::write(
        out.join(".sgbem-run.json"),
        r#"{"files": ["vtk/", "vtk/boundary_0099.vtu", "summary.json"]}"#,
    )
    .expect("write");
    let (code, _, err) = run(&sc, &msh, &out);
    assert_eq!(code, 0, "{err}");
    assert!(!out.join("vtk").join("boundary_0099.vtu").exists());
    let summary = std::fs::read_to_string(out.join("summary.json")).expect("summary");
    assert!(summary.contains("\"status\": \"converged\""), "{summary}");
    assert_eq!(listing(&dir), ["m.msh", "out", "scene.toml"]);
    let inside = listing(&out);
    // No temporary is left; the one hidden file is the marker of the tool's files.
    assert!(
        inside
            .iter()
            .all(|n| !n.starts_with('.') || n == ".sgbem-run.json"),
        "{inside:?}"
    );
    assert!(inside.contains(&"archive.h5".to_string()), "{inside:?}");
}

#[test]
fn a_folder_that_is_not_a_run_folder_is_never_replaced() {
    let dir = tmpdir("rb-foreign");
    let (sc, msh) = stacked(&dir, STACKED_SCENE, 3);
    // `--out` the folder holding the scene and the mesh: refused, everything kept.
    let r = run(&sc, &msh, &dir);
    expect(
        &r,
        2,
        &["holds `m.msh`", "sgbem did not write", "a new folder"],
    );
    assert_eq!(listing(&dir), ["m.msh", "scene.toml"]);
    let r = output(bin().current_dir(&dir).args([
        "run",
        "scene.toml",
        "--mesh",
        "m.msh",
        "--out",
        ".",
        "--quiet",
    ]));
    expect(&r, 2, &["`m.msh`"]);
    assert_eq!(listing(&dir), ["m.msh", "scene.toml"]);
}

#[test]
fn a_second_run_into_a_locked_folder_is_refused() {
    let dir = tmpdir("rb-lock");
    let (sc, msh) = stacked(&dir, STACKED_SCENE, 3);
    let out = dir.join("out");
    // A live process holds the lock (this test's own flock).
    let lock = dir.join(".out.lock");
    let held = std::fs::File::create(&lock).expect("lock");
    held.lock().expect("flock");
    let r = run(&sc, &msh, &out);
    expect(&r, 1, &["another sgbem run", "another --out", ".out.lock"]);
    assert!(!out.exists());
    assert!(lock.exists(), "someone else's lock is left alone");
    // A lock file nobody holds is no lock: taken, and removed at the end.
    drop(held);
    std::fs::write(&lock, "4000000000\n").expect("lock");
    let (code, _, err) = run(&sc, &msh, &out);
    assert_eq!(code, 0, "{err}");
    assert!(!lock.exists());
    assert!(out.join("summary.json").is_file());
}

#[test]
fn two_concurrent_runs_leave_one_whole_run() {
    let dir = tmpdir("rb-concurrent");
    let (sc, msh) = stacked(&dir, STACKED_SCENE, 12);
    let out = dir.join("out");
    let spawn = || {
        bin()
            .args([
                "run",
                s(&sc),
                "--mesh",
                s(&msh),
                "--out",
                s(&out),
                "--quiet",
            ])
            .stderr(Stdio::piped())
            .spawn()
            .expect("run")
    };
    let (a, b) = (spawn(), spawn());
    let (a, b) = (
        a.wait_with_output().expect("a"),
        b.wait_with_output().expect("b"),
    );
    let codes = [a.status.code(), b.status.code()];
    // Either one was refused by the lock, or they ran one after the other.
    assert!(codes.contains(&Some(0)), "{codes:?}");
    for o in [&a, &b] {
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!err.contains("panicked"), "{err}");
        if o.status.code() == Some(1) {
            assert!(err.contains("another sgbem run"), "{err}");
        }
    }
    assert_eq!(listing(&dir), ["m.msh", "out", "scene.toml"]);
    assert!(out.join("summary.json").is_file() && out.join("archive.h5").is_file());
}

#[test]
fn a_signal_during_a_run_leaves_the_previous_folder_whole() {
    let dir = tmpdir("rb-signal");
    let (sc, msh) = stacked(&dir, STACKED_SCENE, 3);
    let out = dir.join("out");
    let (code, _, err) = run(&sc, &msh, &out);
    assert_eq!(code, 0, "{err}");
    let before = std::fs::read(out.join("summary.json")).expect("summary");
    // A slower run (field on a finer mesh) into the same folder, interrupted.
    let slow = stacked_blocks(60).save(&dir, "fine.msh");
    for signal in ["TERM", "INT"] {
        let child = bin()
            .args([
                "run",
                s(&sc),
                "--mesh",
                s(&slow),
                "--out",
                s(&out),
                "--quiet",
            ])
            .stderr(Stdio::piped())
            .spawn()
            .expect("run");
        // Wait until the staging folder exists: the run is writing.
        let t = Instant::now();
        while !listing(&dir).iter().any(|n| n.starts_with(".out.staging-"))
            && t.elapsed() < Duration::from_secs(20)
        {
            std::thread::sleep(Duration::from_millis(5));
        }
        let k = Command::new("kill")
            .args([&format!("-{signal}"), &child.id().to_string()])
            .status()
            .expect("kill");
        assert!(k.success());
        let o = child.wait_with_output().expect("wait");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(130), "{signal}: {err}");
        assert!(err.contains("interrupted"), "{err}");
        assert_eq!(listing(&dir), ["fine.msh", "m.msh", "out", "scene.toml"]);
        assert_eq!(
            std::fs::read(out.join("summary.json")).expect("summary"),
            before
        );
    }
}

#[test]
fn a_killed_run_leaves_the_previous_folder_and_the_next_run_cleans_up() {
    let dir = tmpdir("rb-kill");
    let (sc, msh) = stacked(&dir, STACKED_SCENE, 3);
    let out = dir.join("out");
    let (code, _, err) = run(&sc, &msh, &out);
    assert_eq!(code, 0, "{err}");
    let before = std::fs::read(out.join("summary.json")).expect("summary");
    let slow = stacked_blocks(60).save(&dir, "fine.msh");
    let mut child = bin()
        .args([
            "run",
            s(&sc),
            "--mesh",
            s(&slow),
            "--out",
            s(&out),
            "--quiet",
        ])
        .spawn()
        .expect("run");
    let t = Instant::now();
    while !listing(&dir).iter().any(|n| n.starts_with(".out.staging-"))
        && t.elapsed() < Duration::from_secs(20)
    {
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().expect("SIGKILL");
    let _ = child.wait();
    // SIGKILL cannot be handled: the staging folder and the lock stay, the folder is whole.
    let left = listing(&dir);
    assert!(
        left.iter().any(|n| n.starts_with(".out.staging-")),
        "{left:?}"
    );
    assert!(left.contains(&".out.lock".to_string()), "{left:?}");
    assert_eq!(
        std::fs::read(out.join("summary.json")).expect("summary"),
        before
    );
    // The next run takes the stale lock over and removes what the killed one left.
    let (code, _, err) = run(&sc, &msh, &out);
    assert_eq!(code, 0, "{err}");
    assert_eq!(listing(&dir), ["fine.msh", "m.msh", "out", "scene.toml"]);
}

#[test]
fn names_that_become_file_names_are_checked() {
    let dir = tmpdir("rb-names");
    let msh = stacked_blocks(2).save(&dir, "m.msh");
    let cases = [
        (
            STACKED_SCENE.replace("[interface.joint]", "[interface.\"../../x\"]"),
            vec!["interface.../../x", "starts with `.`", "file name"],
        ),
        (
            STACKED_SCENE.replace("[interface.joint]", "[interface.\"a/b\"]"),
            vec!["interface.a/b", "holds `/`"],
        ),
        (
            STACKED_SCENE.replace("[interface.joint]", "[interface.\"\"]"),
            vec!["the name is empty"],
        ),
        (
            STACKED_SCENE.replace("[interface.joint]", "[interface.\".joint\"]"),
            vec!["starts with `.`"],
        ),
        (
            STACKED_SCENE.replace("[body.upper]", "[body.\"up per\"]"),
            vec!["body.up per", "group name"],
        ),
        (
            format!(
                "{STACKED_SCENE}[[output.section]]\nname = \"a\"\nfrom = [0.5, 0.1]\n\
                 to = [0.5, 1.9]\npoints = 5\n[[output.section]]\nname = \"a_path\"\nfrom = [0.1, 0.5]\n\
                 to = [0.9, 0.5]\npoints = 5\n"
            ),
            vec!["\"a\" and \"a_path\"", "same file"],
        ),
    ];
    for (scene, words) in cases {
        let sc = write(&dir, "scene.toml", &scene);
        expect(&check(&sc, &msh), 2, &words);
    }
}

// --- 3. Non-finite results -----------------------------------------------------------------

#[test]
fn non_finite_results_are_a_numerical_failure() {
    let dir = tmpdir("rb-nonfinite");
    let scene = format!("{STACKED_SCENE}[solve]\nload_factors = [1e308]\n");
    let (sc, msh) = stacked(&dir, &scene, 3);
    let out = dir.join("out");
    let r = run(&sc, &msh, &out);
    expect(&r, 3, &["not finite (", "load factors (largest 1e308)"]);
    // Where: a body's displacement or traction, or an interface figure.
    assert!(
        r.2.contains("(body \"") || r.2.contains("(interface \"joint\""),
        "{}",
        r.2
    );
    assert!(
        out.join("archive.h5").is_file(),
        "a failed run writes every output"
    );
    let summary = std::fs::read_to_string(out.join("summary.json")).expect("summary");
    assert!(
        summary.contains("\"status\": \"failed: non-finite results\""),
        "{summary}"
    );
    assert!(!summary.contains("\"status\": \"converged\""), "{summary}");
}

// --- 4. Messages -----------------------------------------------------------------------------

#[test]
fn files_that_are_not_scenes_get_a_hint() {
    let dir = tmpdir("rb-notscene");
    let (sc, msh) = stacked(&dir, STACKED_SCENE, 2);
    let out = dir.join("out");
    let (code, _, err) = run(&sc, &msh, &out);
    assert_eq!(code, 0, "{err}");
    let geo = write(
        &dir,
        "b.geo",
        "SetFactory(\"OpenCASCADE\");\nRectangle(1) = {0,0,0,1,1};\n",
    );
    let latin1 = dir.join("latin1.toml");
    std::fs::write(&latin1, b"title = \"Tr\xe4ger\"\nplane = \"strain\"\n").expect("write");
    for (file, words) in [
        (geo, vec!["gmsh geometry", "gmsh -2"]),
        (msh.clone(), vec!["gmsh mesh", "--mesh"]),
        (
            out.join("archive.h5"),
            vec!["HDF5 archive", "sgbem inspect"],
        ),
        (latin1, vec!["not UTF-8", "offset 11"]),
    ] {
        expect(&sgbem(&["check", s(&file)]), 2, &words);
        expect(&sgbem(&["run", s(&file), "--quiet"]), 2, &words);
    }
}

#[test]
fn extreme_young_modulus_is_named() {
    let dir = tmpdir("rb-young");
    let (sc, msh) = stacked(
        &dir,
        &STACKED_SCENE.replacen("young = 1.0", "young = 1e308", 1),
        2,
    );
    expect(
        &check(&sc, &msh),
        2,
        &["body.lower.young", "extreme value", "units"],
    );
}

#[test]
fn a_mesh_far_from_the_origin_is_not_refused_as_overlapping() {
    let dir = tmpdir("rb-far");
    let mut m = stacked_blocks(4);
    for p in m.nodes.iter_mut() {
        p[0] += 1e9;
        p[1] += 1e9;
    }
    let far = m.save(&dir, "far.msh");
    let sc = write(&dir, "scene.toml", STACKED_SCENE);
    let (code, _, err) = check(&sc, &far);
    assert!(!err.contains("overlap"), "{err}");
    assert_eq!(code, 0, "{err}");
}

#[test]
fn a_boundary_crossing_itself_at_a_node_is_refused() {
    let dir = tmpdir("rb-bowtie");
    // A bow tie: the loop (0,0) → (2,2) → (2,0) → (0,2) → back crosses itself at (1,1), a
    // node of both diagonals.
    let mut m = Msh::default();
    let c = [1.0, 1.0];
    m.line(1, [0.0, 0.0], c, 1, &[1]);
    m.line(2, c, [2.0, 2.0], 1, &[1]);
    m.line(3, [2.0, 2.0], [2.0, 0.0], 2, &[2]);
    m.line(4, [2.0, 0.0], c, 1, &[1]);
    m.line(5, c, [0.0, 2.0], 1, &[1]);
    m.line(6, [0.0, 2.0], [0.0, 0.0], 2, &[3]);
    m.surface(1, &[1, 2, 3, 4, 5, 6], &[1]);
    m.name(1, 1, "diagonals");
    m.name(1, 2, "right");
    m.name(1, 3, "left");
    m.name(2, 1, "tie");
    let msh = m.save(&dir, "bowtie.msh");
    // The same bow tie with two distinct nodes at (1, 1): no node joins four elements and
    // no two segments cross properly, yet the boundary crosses itself there.
    let mut m2 = Msh::default();
    let a = m2.new_node([0.0, 0.0]);
    let c1 = m2.new_node(c);
    let b = m2.new_node([2.0, 2.0]);
    let bd = m2.new_node([2.0, 1.0]);
    let d = m2.new_node([2.0, 0.0]);
    let c2 = m2.new_node(c);
    let e = m2.new_node([0.0, 2.0]);
    let ea = m2.new_node([0.0, 1.0]);
    m2.curves.push((1, vec![a, c1, b], vec![1]));
    m2.curves.push((2, vec![b, bd, d], vec![2]));
    m2.curves.push((3, vec![d, c2, e], vec![1]));
    m2.curves.push((4, vec![e, ea, a], vec![3]));
    m2.surface(1, &[1, 2, 3, 4], &[1]);
    m2.name(1, 1, "diagonals");
    m2.name(1, 2, "right");
    m2.name(1, 3, "left");
    m2.name(2, 1, "tie");
    let msh2 = m2.save(&dir, "bowtie2.msh");
    let sc = write(
        &dir,
        "scene.toml",
        "plane = \"strain\"\n[body.tie]\nyoung = 1.0\npoisson = 0.3\n[boundary.left]\n\
         ux = 0.0\nuy = 0.0\n[boundary.right]\ntx = 1.0\n",
    );
    expect(
        &check(&sc, &msh),
        2,
        &["node 2 (1, 1)", "body \"tie\"", "touches itself"],
    );
    expect(
        &check(&sc, &msh2),
        2,
        &["body \"tie\" crosses itself at (1, 1)", "nodes coincide"],
    );
}

// --- 5. Damaged archives ------------------------------------------------------------------

#[test]
fn damaged_archives_end_in_a_message() {
    let dir = tmpdir("rb-archive");
    let (sc, msh) = stacked(&dir, STACKED_SCENE, 3);
    let out = dir.join("out");
    let (code, _, err) = run(&sc, &msh, &out);
    assert_eq!(code, 0, "{err}");
    let good = std::fs::read(out.join("archive.h5")).expect("archive");
    let n = good.len();
    let mut damaged: Vec<(String, Vec<u8>)> = Vec::new();
    for k in 0..12 {
        let at = (k * 7919 + 100) % n;
        let mut b = good.clone();
        b[at] ^= 1 << (k % 8);
        damaged.push((format!("bit {} at {at}", k % 8), b));
    }
    for at in [
        0,
        4096,
        n / 3 / 4096 * 4096,
        n / 2 / 4096 * 4096,
        (n - 1) / 4096 * 4096,
    ] {
        let mut b = good.clone();
        for x in &mut b[at..(at + 4096).min(n)] {
            *x = 0;
        }
        damaged.push((format!("4 KB zeroed at {at}"), b));
    }
    damaged.push(("cut in half".into(), good[..n / 2].to_vec()));
    let mut refused = 0;
    for (what, bytes) in &damaged {
        let file = dir.join("damaged.h5");
        std::fs::write(&file, bytes).expect("write");
        for args in [
            vec!["inspect", s(&file)],
            vec!["export", s(&file), "--vtk", s(&dir.join("vtk"))],
        ] {
            let r = output(bin().args(&args).env("SGBEM_ARCHIVE_TIMEOUT", "5"));
            assert!(
                r.0 == 0 || r.0 == 1,
                "{what}, {}: exit {} (crash?): {}",
                args[0],
                r.0,
                r.2
            );
            assert!(!r.2.contains("panicked"), "{what}: {}", r.2);
            if r.0 == 1 {
                assert!(r.2.contains("sgbem: "), "{what}: {}", r.2);
                refused += 1;
            }
        }
    }
    // The header and the truncation at least are always caught.
    assert!(refused >= 4, "{refused} refusals");
}

/// The estimate's unknown counts are those the assembly numbers (up to the rigid-mode
/// unknowns, at most 3 per loop), on bodies with clamped, loaded, free and interface parts.
#[test]
fn the_estimate_counts_the_unknowns_the_assembly_numbers() {
    use sgbem::bem::quadrature::QuadratureSettings;
    let dir = tmpdir("rb-estimate");
    for (scene, n) in [
        (STACKED_SCENE.to_string(), 5),
        (
            STACKED_SCENE.replace(
                "ux = 0.0\nuy = 0.0\n",
                "uy = 0.0\n[boundary.sides]\nux = 0.0\n",
            ),
            3,
        ),
        (STACKED_SCENE.replace("\"unilateral\"", "\"bonded\""), 4),
    ] {
        let (sc, msh) = stacked(&dir, &scene, n);
        let l = sgbem::pipeline::load(&sc, Some(&msh)).unwrap_or_else(|e| panic!("{e}"));
        let q = QuadratureSettings::standard();
        let p = sgbem::bem::prepare(&l.model, l.scene.plane, &q, 1.0, &sc, &|_| {})
            .unwrap_or_else(|e| panic!("{e}"));
        let est = sgbem::estimate::estimate(&l.model, &l.scene);
        for ((b, sys), size) in l.model.bodies.iter().zip(&p.systems).zip(&est.bodies) {
            assert_eq!(size.n_x0, sys.n_x0(), "body {}", b.name);
            assert!(
                size.n_x >= sys.n_x && size.n_x <= sys.n_x + 3 * b.loops.len(),
                "body {}: estimated {} of {}",
                b.name,
                size.n_x,
                sys.n_x
            );
            assert_eq!(size.elements, b.elements.len());
        }
        let dense: f64 = p.systems.iter().map(|s| 8.0 * (s.n() * s.n()) as f64).sum();
        assert!(est.peak_bytes > dense, "the peak holds every G");
    }
}

/// An archive the `archive` fuzz target found to crash libhdf5 (SEGV in H5HG_read, a
/// variable-length string through the global heap): `inspect` and `export` end in exit 1
/// and a message.
#[test]
fn an_archive_that_crashes_libhdf5_ends_in_a_message() {
    let dir = tmpdir("rb-segv");
    let file = root().join("tests/fixtures/fuzz_archive_hdf5_segv.h5");
    for args in [
        vec!["inspect", s(&file)],
        vec!["export", s(&file), "--vtk", s(&dir.join("vtk"))],
    ] {
        let r = output(bin().args(&args).env("SGBEM_ARCHIVE_TIMEOUT", "10"));
        expect(
            &r,
            1,
            &[
                "fuzz_archive_hdf5_segv.h5",
                "the archive is damaged",
                "again",
            ],
        );
    }
}

/// A stiffness contrast that the boundary systems cannot carry is named as the likely cause.
#[test]
fn an_extreme_stiffness_contrast_is_named() {
    let dir = tmpdir("contrast");
    let msh = gmsh(
        &root().join("geo/two_blocks.geo"),
        &dir,
        "m.msh",
        false,
        &[],
    );
    let (code, _, err) = sgbem(&[
        "run",
        root().join("pipelines/two_blocks.toml").to_str().unwrap(),
        "--mesh",
        msh.to_str().unwrap(),
        "--out",
        dir.join("out").to_str().unwrap(),
        "--set",
        "body.upper.young=1e12",
        "--quiet",
    ]);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("stiffness contrast across interface \"joint\" is 1.0e9"),
        "{err}"
    );
}

/// The estimate of the contact stage grows with refinement as its model says (src/estimate.rs):
/// with n elements per side the joint has n + 1 unilateral pairs (stick: two rows each) and
/// every pair is expected to switch once; the evolutive path and the cross-checks grow with
/// the cube of the pairs, the glued system with the cube of the interface unknowns, and the
/// recording with the states times Σ n·n_x0. `check` prints it; history = "final" records one
/// state; bonded joints have no contact stage.
#[test]
fn the_contact_estimate_grows_with_refinement_as_its_model_says() {
    use sgbem::estimate::{estimate, ContactEstimate};
    let dir = tmpdir("rb-contact-estimate");
    let close = |a: f64, b: f64| (a / b - 1.0).abs() < 1e-9;
    let expand = |e: &sgbem::estimate::Estimate| -> f64 {
        e.bodies
            .iter()
            .map(|b| ((b.n_x + b.n_x0) * b.n_x0) as f64)
            .sum()
    };
    let mut last: Option<(ContactEstimate, f64)> = None;
    for n in [4, 8, 16, 32] {
        let (sc, msh) = stacked(&dir, STACKED_SCENE, n);
        let l = sgbem::pipeline::load(&sc, Some(&msh)).unwrap_or_else(|e| panic!("{e}"));
        let e = estimate(&l.model, &l.scene);
        let c = e.contact.clone().expect("a unilateral interface");
        let p = n + 1;
        assert_eq!((c.pairs, c.rows, c.switches), (p, 2 * p, p));
        // Both components of every pair node on both bodies.
        assert_eq!(c.interface_unknowns, 4 * p);
        if let Some((prev, prev_expand)) = &last {
            let q = c.pairs as f64 / prev.pairs as f64;
            assert!(close(c.path / prev.path, q.powi(3)), "{c:?} {prev:?}");
            assert!(close(c.checks / prev.checks, q.powi(3)), "{c:?} {prev:?}");
            let qu = c.interface_unknowns as f64 / prev.interface_unknowns as f64;
            assert!(close(c.system / prev.system, qu.powi(3)), "{c:?} {prev:?}");
            let states = (c.switches + 1) as f64 / (prev.switches + 1) as f64;
            assert!(close(
                c.record / prev.record,
                states * expand(&e) / prev_expand
            ));
            // Σ n·n_x0 grows at least like the square of the refinement.
            assert!(expand(&e) / prev_expand > 0.9 * q * q);
            // Pairs 5, 9, 17, 33: every term grows by at least 1.8³ ≈ 5.8.
            assert!(c.seconds() > 5.0 * prev.seconds() && c.bytes > prev.bytes);
        }
        last = Some((c, expand(&e)));
    }
    let (sc, msh) = stacked(&dir, STACKED_SCENE, 16);
    let (code, text, err) = check(&sc, &msh);
    assert_eq!(code, 0, "{err}");
    assert!(
        text.lines().any(|l| l.contains("cost:")
            && l.contains("for the contact stage (17 unilateral pairs, 34 rows")),
        "{text}"
    );
    let load = |scene: &str| {
        let (sc, msh) = stacked(&dir, scene, 16);
        let l = sgbem::pipeline::load(&sc, Some(&msh)).unwrap_or_else(|e| panic!("{e}"));
        estimate(&l.model, &l.scene)
    };
    let full = load(STACKED_SCENE).contact.unwrap();
    let final_only = load(&format!("{STACKED_SCENE}[output]\nhistory = \"final\"\n"))
        .contact
        .unwrap();
    assert!(close(final_only.record * 18.0, full.record));
    assert!(load(&STACKED_SCENE.replace("\"unilateral\"", "\"bonded\""))
        .contact
        .is_none());
}
