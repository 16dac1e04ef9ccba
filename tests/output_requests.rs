//! Output requests on shipped scenes (docs/scene.md §10 `[output]`): `history = "steps"` and
//! `every = n` keep the states of a full run bitwise, the VTK field selection and
//! compression, `sgbem check`'s size of the outputs against a real run, the default scaled to
//! the scene, and the errors of bad requests.

mod support;

use std::path::{Path, PathBuf};

use sgbem::output::archive::read_archive;
use sgbem::output::record::{IterateRecord, RunRecord};
use support::{binary_arrays, gmsh, root, sgbem, tmpdir};

/// Meshes `geo/NAME.geo` into `dir` as `make mesh` does.
fn mesh(dir: &Path, name: &str) -> PathBuf {
    gmsh(
        &root().join(format!("geo/{name}.geo")),
        dir,
        &format!("{name}.msh"),
        false,
        &[],
    )
}

/// `sgbem COMMAND pipelines/SCENE.toml [--mesh MSH] ARGS --set SET…`: (exit code, standard
/// output, standard error).
fn sgbem_on(
    command: &str,
    scene: &str,
    msh: Option<&Path>,
    args: &[&str],
    sets: &[&str],
) -> (i32, String, String) {
    let scene = root().join(format!("pipelines/{scene}.toml"));
    let mut all: Vec<String> = vec![command.into(), scene.display().to_string()];
    if let Some(m) = msh {
        all.extend(["--mesh".into(), m.display().to_string()]);
    }
    all.extend(args.iter().map(|a| a.to_string()));
    for s in sets {
        all.extend(["--set".into(), s.to_string()]);
    }
    let all: Vec<&str> = all.iter().map(String::as_str).collect();
    sgbem(&all)
}

/// Runs `pipelines/SCENE.toml` on `msh` into `dir/out` with `--set` overrides; returns the
/// run folder and the standard error.
fn run(scene: &str, msh: &Path, dir: &Path, out: &str, sets: &[&str]) -> (PathBuf, String) {
    let folder = dir.join(out);
    let f = folder.display().to_string();
    let (code, _, err) = sgbem_on("run", scene, Some(msh), &["--out", &f, "--quiet"], sets);
    assert_eq!(code, 0, "sgbem run {scene} {sets:?}: {err}");
    (folder, err)
}

fn archive(folder: &Path) -> RunRecord {
    read_archive(&folder.join("archive.h5")).expect("read the archive")
}

/// Every number of a state (displacements, tractions, pair results), as bits.
fn bits(st: &IterateRecord) -> Vec<u64> {
    let mut v = Vec::new();
    for f in st.fields.iter() {
        v.extend(f.u.iter().flatten().map(|x| x.to_bits()));
        v.extend(f.t.iter().flatten().flatten().map(|x| x.to_bits()));
    }
    for r in st.interfaces.iter() {
        for p in &r.pairs {
            v.extend(p.traction.iter().chain(&p.jump).map(|x| x.to_bits()));
            v.push(p.slip.to_bits());
            v.push(u64::from(p.status == sgbem::solution::PairStatus::Closed));
        }
    }
    v
}

fn iterations(rec: &RunRecord) -> Vec<usize> {
    rec.states.iter().map(|s| s.iteration).collect()
}

/// The state of `full` numbered `iteration`.
fn same_numbered(full: &RunRecord, iteration: usize) -> &IterateRecord {
    full.states
        .iter()
        .find(|s| s.iteration == iteration)
        .unwrap_or_else(|| panic!("no state {iteration} in the full history"))
}

/// `pipelines/SCENE.toml` on `geo/GEO.geo` run with history "full" and "steps": (the
/// folder, the mesh, the two run folders).
fn full_and_steps(scene: &str, geo: &str) -> (PathBuf, PathBuf, PathBuf, PathBuf) {
    let dir = tmpdir(&format!("requests-{scene}"));
    let msh = mesh(&dir, geo);
    let (full, _) = run(scene, &msh, &dir, "full", &[]);
    let (steps, _) = run(scene, &msh, &dir, "steps", &["output.history=\"steps\""]);
    (dir, msh, full, steps)
}

/// The incline block (5 load steps, friction): "steps" keeps one state per load step, the
/// last of each step of the full run, bitwise; `every = 3` keeps iterations 0, 3, 6, … of
/// each step and its last, bitwise too; the history rows and the VTK series follow.
#[test]
fn steps_and_every_keep_states_of_the_full_run() {
    let (dir, msh, full, steps) = full_and_steps("incline_block", "two_blocks");
    let (every, _) = run("incline_block", &msh, &dir, "every", &["output.every=3"]);
    let (f, s, e) = (archive(&full), archive(&steps), archive(&every));
    let steps_of = |r: &RunRecord| r.states.iter().map(|s| s.load_step).collect::<Vec<_>>();
    // Full: 14 states over the 5 steps (3 iterations in step 4, 2 in step 5).
    assert_eq!(iterations(&f), (0..14).collect::<Vec<_>>());
    assert_eq!(steps_of(&f), [0, 1, 2, 3, 3, 3, 3, 3, 3, 3, 3, 4, 4, 4]);
    // Steps: the last state of each load step.
    assert_eq!(steps_of(&s), [0, 1, 2, 3, 4]);
    assert_eq!(iterations(&s), [0, 1, 2, 10, 13]);
    for st in &s.states {
        let last = f
            .states
            .iter()
            .rfind(|x| x.load_step == st.load_step)
            .unwrap();
        assert_eq!(st.iteration, last.iteration);
        assert_eq!(bits(st), bits(last), "state {}", st.iteration);
    }
    assert_eq!(s.history.rows.len(), 5);
    // every = 3: per step the iterations 0, 3, 6, … from its first, and its last.
    assert_eq!(iterations(&e), [0, 1, 2, 3, 6, 9, 10, 11, 13]);
    for st in &e.states {
        assert_eq!(bits(st), bits(same_numbered(&f, st.iteration)));
    }
    assert_eq!(e.history.rows.len(), 9);
    let row_iterations: Vec<usize> = e.history.rows.iter().map(|r| r.iteration).collect();
    assert_eq!(row_iterations, [0, 0, 0, 0, 3, 6, 7, 0, 2]);
    // The final state is the full run's, bitwise, in all three.
    let last = f.states.last().unwrap();
    assert_eq!(bits(s.states.last().unwrap()), bits(last));
    assert_eq!(bits(e.states.last().unwrap()), bits(last));
    let summary = |d: &Path| std::fs::read_to_string(d.join("summary.json")).unwrap();
    let (fs, ss) = (summary(&full), summary(&steps));
    let drop_overrides = |t: &str| {
        let mut v: serde_json::Value = serde_json::from_str(t).unwrap();
        v["overrides"] = serde_json::json!([]);
        v
    };
    assert_eq!(drop_overrides(&fs), drop_overrides(&ss));
    // The VTK series: one time per state kept, at the end of each load step for "steps".
    let pvd = std::fs::read_to_string(steps.join("vtk/states.pvd")).unwrap();
    let times: Vec<&str> = pvd
        .split("timestep=\"")
        .skip(1)
        .map(|t| t.split('"').next().unwrap())
        .collect();
    assert_eq!(times, ["1", "2", "3", "4", "5"]);
    assert!(steps.join("vtk/boundary_0004.vtu").is_file());
    assert!(!steps.join("vtk/boundary_0005.vtu").exists());
    let pvd = std::fs::read_to_string(every.join("vtk/history.pvd")).unwrap();
    assert_eq!(pvd.matches("part=\"0\"").count(), 9);
}

/// The clamped beam's section path (`sections/a-a_path.csv`) with "steps": the one block of
/// the final state, the same text as the last block of the full run's path.
#[test]
fn steps_section_path_is_the_last_block_of_the_full_one() {
    let (_, _, full, steps) = full_and_steps("clamped_beam_joint", "clamped_beam_joint");
    let read = |d: &Path| std::fs::read_to_string(d.join("sections/a-a_path.csv")).unwrap();
    let (f, s) = (read(&full), read(&steps));
    let s_lines: Vec<&str> = s.lines().collect();
    let f_lines: Vec<&str> = f.lines().collect();
    // The header and the 41 points of one state: the full run's last block.
    let mut expected = vec![f_lines[0]];
    expected.extend(&f_lines[f_lines.len() - 41..]);
    assert_eq!(s_lines, expected);
    assert_eq!(f_lines.len(), 1 + 41 * 91);
}

/// Names of the point arrays of a VTK XML file, in order.
fn point_arrays(xml: &str) -> Vec<String> {
    let pd = xml.split("<PointData").nth(1).unwrap();
    let pd = pd.split("</PointData>").next().unwrap();
    pd.split("Name=\"")
        .skip(1)
        .map(|t| t.split('"').next().unwrap().to_string())
        .collect()
}

/// `vtk_fields` writes only the arrays named (the boundary's and the field's); `vtk =
/// "compressed"` writes the same numbers, zlib-compressed, in fewer bytes, and
/// `sgbem export` rebuilds the compressed files from the archive.
#[test]
fn vtk_field_selection_and_compression() {
    let dir = tmpdir("requests-vtk");
    let msh = mesh(&dir, "clamped_beam_joint");
    let fields = "output.vtk_fields=[\"displacement\", \"contact_status\", \"von_mises\"]";
    let (plain, _) = run("clamped_beam_joint", &msh, &dir, "plain", &[]);
    let (sel, _) = run("clamped_beam_joint", &msh, &dir, "sel", &[fields]);
    let (zip, _) = run(
        "clamped_beam_joint",
        &msh,
        &dir,
        "zip",
        &["output.vtk=\"compressed\""],
    );
    let read = |d: &Path, f: &str| std::fs::read_to_string(d.join("vtk").join(f)).unwrap();
    let all = point_arrays(&read(&plain, "boundary_0090.vtu"));
    assert_eq!(
        all.join(" "),
        "displacement traction normal contact_status normal_traction normal_opening body"
    );
    assert_eq!(
        point_arrays(&read(&sel, "boundary_0090.vtu")),
        ["displacement", "contact_status"]
    );
    assert_eq!(
        point_arrays(&read(&sel, "field_0090.vtu")),
        ["displacement", "von_mises"]
    );
    assert!(read(&sel, "field_0090.vtu")
        .contains("<PointData Scalars=\"von_mises\" Vectors=\"displacement\">"));
    // The selected arrays hold the same numbers as the full files.
    for file in ["boundary_0000.vtu", "boundary_0090.vtu", "field_0090.vtu"] {
        let p = binary_arrays(&read(&plain, file), false);
        let s = binary_arrays(&read(&sel, file), false);
        let names: Vec<&str> = p.iter().map(|(n, _)| n.as_str()).collect();
        assert!(
            names.contains(&"displacement") && names.contains(&"Points"),
            "{names:?}"
        );
        assert!(p.iter().all(|(_, v)| !v.is_empty()), "{file}");
        for (name, v) in &s {
            assert_eq!(
                Some(v),
                p.iter().find(|(n, _)| n == name).map(|x| &x.1),
                "{name}"
            );
        }
        // Compressed: every array, the same bytes.
        let z = read(&zip, file);
        assert!(z.contains("compressor=\"vtkZLibDataCompressor\""));
        assert_eq!(binary_arrays(&z, true), p, "{file}");
    }
    let size = |d: &Path| -> u64 {
        std::fs::read_dir(d.join("vtk"))
            .unwrap()
            .map(|e| e.unwrap().metadata().unwrap().len())
            .sum()
    };
    let (ps, zs) = (size(&plain), size(&zip));
    assert!(zs * 2 < ps, "compressed {zs} B, plain {ps} B");
    // export follows the archived scene: the same compressed bytes.
    let exported = dir.join("exported");
    let (code, _, err) = sgbem(&[
        "export",
        zip.join("archive.h5").to_str().unwrap(),
        "--vtk",
        exported.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    for file in ["boundary_0045.vtu", "field_0090.vtu", "states.pvd"] {
        assert_eq!(
            std::fs::read(exported.join(file)).unwrap(),
            std::fs::read(zip.join("vtk").join(file)).unwrap(),
            "{file}"
        );
    }
    python_reads_compressed(&plain, &zip);
}

/// meshio and pyvista read the compressed files to the same numbers (where `make setup`
/// made the venv).
fn python_reads_compressed(plain: &Path, zip: &Path) {
    let python = root().join(".venv/bin/python");
    if !python.exists() {
        eprintln!("skipped: no .venv (make setup installs meshio and pyvista)");
        return;
    }
    let script = r#"
import sys, numpy as np, meshio, pyvista as pv
a, b = sys.argv[1], sys.argv[2]
for f in ["boundary_0000.vtu", "boundary_0090.vtu", "field_0090.vtu"]:
    m, n = meshio.read(f"{a}/vtk/{f}"), meshio.read(f"{b}/vtk/{f}")
    assert sorted(m.point_data) == sorted(n.point_data), f
    assert all(np.array_equal(m.point_data[k], n.point_data[k]) for k in m.point_data), f
    assert np.array_equal(m.points, n.points), f
    p, q = pv.read(f"{a}/vtk/{f}"), pv.read(f"{b}/vtk/{f}")
    assert all(np.array_equal(p.point_data[k], q.point_data[k]) for k in p.point_data), f
    assert q.n_points == p.n_points > 0 and q.n_cells == p.n_cells > 0, f
print("same numbers")
"#;
    let o = std::process::Command::new(&python)
        .args(["-c", script])
        .arg(plain)
        .arg(zip)
        .output()
        .expect("run python");
    let text =
        String::from_utf8_lossy(&o.stdout).into_owned() + &String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.success() && text.contains("same numbers"),
        "{text}"
    );
}

/// The size of a run folder's files: (archive, vtk, csv, total).
fn sizes(folder: &Path) -> (f64, f64, f64, f64) {
    fn du(p: &Path) -> f64 {
        match std::fs::metadata(p) {
            Ok(m) if m.is_file() => m.len() as f64,
            Ok(_) => std::fs::read_dir(p)
                .unwrap()
                .map(|e| du(&e.unwrap().path()))
                .sum(),
            Err(_) => 0.0,
        }
    }
    let csv = du(&folder.join("interfaces")) + du(&folder.join("sections"));
    (
        du(&folder.join("archive.h5")),
        du(&folder.join("vtk")),
        csv,
        du(folder),
    )
}

/// `sgbem check --json`'s size of the outputs against real runs: the total within 30 %
/// (and the archive and the VTK files within 30 % each) on three shipped scenes.
#[test]
fn check_estimates_the_outputs_within_30_percent() {
    let dir = tmpdir("requests-size");
    for (scene, geo, sets) in [
        ("kirsch_plate", "kirsch_plate", vec![]),
        (
            "incline_block",
            "two_blocks",
            vec!["output.history=\"steps\""],
        ),
        (
            "incline_block",
            "two_blocks",
            vec!["output.history=\"steps\"", "output.vtk=\"compressed\""],
        ),
        ("clamped_beam_joint", "clamped_beam_joint", vec![]),
    ] {
        let msh = mesh(&dir, geo);
        let out = format!("{scene}-{}", sets.len());
        let (folder, _) = run(scene, &msh, &dir, &out, &sets);
        let (code, json, err) = sgbem_on("check", scene, Some(&msh), &["--json"], &sets);
        assert_eq!(code, 0, "{err}");
        let v: serde_json::Value = serde_json::from_str(&json).unwrap();
        let e = &v["outputs"]["estimate"];
        let (archive, vtk, _, total) = sizes(&folder);
        let near = |what: &str, est: f64, act: f64| {
            let r = est / act;
            assert!(
                (0.7..1.3).contains(&r),
                "{scene} {sets:?} {what}: estimated {est} B, wrote {act} B"
            );
        };
        near("archive", e["archive_bytes"].as_f64().unwrap(), archive);
        near("vtk", e["vtk_bytes"].as_f64().unwrap(), vtk);
        near("total", e["total_bytes"].as_f64().unwrap(), total);
        let text = v["outputs"]["text"].as_str().unwrap();
        assert!(text.contains("(an estimate)"), "{text}");
    }
}

/// The default scaled to the scene: the 105-brick wall on the evolutive path (3.0e7
/// recorded unknowns) keeps "steps" and says so; on the full rows (its default: its joints
/// meet at junctions), which record one state per load step, it keeps the full history of
/// that one state; the clamped beam (1.4e5) keeps every iteration; `history` or `every` set
/// by the user wins.
#[test]
fn large_scenes_default_to_steps() {
    let check = |scene: &str, sets: &[&str]| -> serde_json::Value {
        let (code, json, err) = sgbem_on("check", scene, None, &["--json"], sets);
        assert_eq!(code, 0, "{err}");
        serde_json::from_str(&json).unwrap()
    };
    let exact = check("wall_running_bond", &[]);
    assert_eq!(exact["outputs"]["history"], "full");
    assert_eq!(exact["outputs"]["estimate"]["states"], 1);
    assert!(!exact["plan"]["advice"].to_string().contains("was chosen"));
    let wall = check("wall_running_bond", &["solve.method=\"lcp\""]);
    assert_eq!(wall["outputs"]["history"], "steps");
    let advice = wall["plan"]["advice"].to_string();
    assert!(
        advice.contains("output.history = \\\"steps\\\"")
            && advice.contains("15555 boundary unknowns")
            && advice.contains("history = \\\"full\\\""),
        "{advice}"
    );
    assert_eq!(wall["outputs"]["estimate"]["states"], 1);
    let full = check(
        "wall_running_bond",
        &["solve.method=\"lcp\"", "output.history=\"full\""],
    );
    assert_eq!(full["outputs"]["history"], "full");
    assert!(!full["plan"]["advice"].to_string().contains("was chosen"));
    let every = check(
        "wall_running_bond",
        &["solve.method=\"lcp\"", "output.every=50"],
    );
    assert_eq!(every["outputs"]["history"], "full");
    assert_eq!(every["outputs"]["every"], 50);
}

/// Bad requests exit 2 naming the key and the fix.
#[test]
fn bad_requests_name_the_key() {
    let dir = tmpdir("requests-bad");
    let msh = mesh(&dir, "two_blocks");
    for (set, words) in [
        ("output.every=0", vec!["`output.every` = 0", "at least 1"]),
        (
            "output.history=\"final\"\0output.every=2",
            vec!["`output.every` = 2", "\"final\"", "set history = \"full\""],
        ),
        (
            "output.history=\"step\"",
            vec!["`output.history`", "\"steps\"", "did you mean"],
        ),
        (
            "output.vtk=\"zlib\"",
            vec!["`output.vtk` = \"zlib\"", "true, false or \"compressed\""],
        ),
        (
            "output.vtk_fields=[\"vonmises\"]",
            vec![
                "`output.vtk_fields`",
                "\"vonmises\"",
                "von_mises",
                "valid names",
            ],
        ),
        ("output.vtk_fields=[]", vec!["`output.vtk_fields` is empty"]),
        ("output.every=1.5", vec!["every"]),
    ] {
        let sets: Vec<&str> = set.split('\0').collect();
        let (code, _, err) = sgbem_on("check", "incline_block", Some(&msh), &[], &sets);
        assert_eq!(code, 2, "{set}: {err}");
        for w in words {
            assert!(err.contains(w), "{set}: `{w}` not in {err}");
        }
        assert!(!err.contains("panicked"), "{err}");
    }
}

/// A tmpfs of `size` mounted at `at` for one test, unmounted when dropped (also when the
/// test fails); None, with a message, where the test cannot mount one (not root, no mount).
struct SmallFs(PathBuf);

impl SmallFs {
    fn mount(at: &Path, size: &str) -> Option<SmallFs> {
        // SAFETY: geteuid has no preconditions.
        if unsafe { libc::geteuid() } != 0 {
            eprintln!("SKIPPED: mounting a small tmpfs needs root");
            return None;
        }
        std::fs::create_dir_all(at).unwrap();
        let o = std::process::Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={size}"), "tmpfs"])
            .arg(at)
            .output();
        match o {
            Ok(o) if o.status.success() => Some(SmallFs(at.to_path_buf())),
            Ok(o) => {
                let why = String::from_utf8_lossy(&o.stderr);
                eprintln!("SKIPPED: cannot mount a tmpfs: {why}");
                None
            }
            Err(e) => {
                eprintln!("SKIPPED: cannot run mount: {e}");
                None
            }
        }
    }

    /// The names in the file system's root.
    fn names(&self) -> Vec<String> {
        let mut n: Vec<String> = std::fs::read_dir(&self.0)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        n.sort();
        n
    }
}

impl Drop for SmallFs {
    fn drop(&mut self) {
        let _ = std::process::Command::new("umount").arg(&self.0).status();
    }
}

/// Outputs larger than the free space of the output folder's file system (a 2 MB tmpfs) are
/// refused before anything is computed, by `run` and `check` alike (exit 2, the same
/// message: the folder, the size needed and free, the output requests that write less);
/// outputs that fit run. A full history whose expected size exceeds the free space while
/// one state per load step fits is advice, and a run that meets a full device all the same
/// ends in exit 1 with the fix, leaving nothing behind. Skipped (said on stderr) without
/// root.
#[test]
fn outputs_larger_than_the_free_space_are_refused_by_check_and_run() {
    let dir = tmpdir("requests-disk");
    let Some(fs) = SmallFs::mount(&dir.join("small"), "2m") else {
        return;
    };
    let msh = mesh(&dir, "clamped_beam_joint");
    let out = fs.0.join("beam");
    let o = out.display().to_string();
    let at = format!("output.directory={:?}", o);
    // The default requests: 15.5 MB with one state per load step (the operators).
    let run_err = sgbem_on("run", "clamped_beam_joint", Some(&msh), &["--out", &o], &[]);
    let check = sgbem_on("check", "clamped_beam_joint", Some(&msh), &[], &[&at]);
    assert_eq!(run_err.0, 2, "{}", run_err.2);
    assert_eq!(check.0, 2, "{}", check.2);
    assert_eq!(check.2, run_err.2);
    assert!(check.1.contains("outputs: about"), "{}", check.1);
    for words in [
        o.as_str(),
        "writes at least about 15.",
        "MB of outputs",
        "2.1 MB free",
        "history = \"steps\"",
        "every = N",
        "vtk_fields",
        "--out DIR",
    ] {
        assert!(run_err.2.contains(words), "{words}: {}", run_err.2);
    }
    // Nothing written: no folder, no staging folder, no lock.
    assert!(fs.names().is_empty(), "{:?}", fs.names());

    // A full history that may not fit, while its last state per step does: advice.
    let lean = ["output.operators=false"];
    let c = sgbem_on(
        "check",
        "clamped_beam_joint",
        Some(&msh),
        &[],
        &[&at, lean[0]],
    );
    assert_eq!(c.0, 0, "{}", c.2);
    assert!(
        c.1.contains("advice: the outputs, about")
            && c.1.contains("a full history of about")
            && c.1.contains("may not fit in the 2.1 MB free"),
        "{}",
        c.1
    );
    // Run, it meets the full device: exit 1, the fix, nothing left.
    let r = sgbem_on(
        "run",
        "clamped_beam_joint",
        Some(&msh),
        &["--out", &o, "--quiet"],
        &lean,
    );
    assert_eq!(r.0, 1, "{}", r.2);
    assert!(
        r.2.contains("No space left on device") && r.2.contains("the file system is full"),
        "{}",
        r.2
    );
    assert!(fs.names().is_empty(), "{:?}", fs.names());

    // Outputs that fit: check and run succeed.
    let fit = ["output.operators=false", "output.history=\"final\""];
    let c = sgbem_on(
        "check",
        "clamped_beam_joint",
        Some(&msh),
        &[],
        &[&at, fit[0], fit[1]],
    );
    assert_eq!(c.0, 0, "{}", c.2);
    assert!(!c.1.contains("free on its file system"), "{}", c.1);
    let r = sgbem_on(
        "run",
        "clamped_beam_joint",
        Some(&msh),
        &["--out", &o, "--quiet"],
        &fit,
    );
    assert_eq!(r.0, 0, "{}", r.2);
    assert!(out.join("summary.json").is_file());
}
