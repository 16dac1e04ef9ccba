//! The user's workflow around a scene: `--set` overrides, `.geo` meshes through gmsh,
//! byte-identical reruns, sweeps.

mod support;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use support::*;

/// The two-blocks example meshed from its .geo: `[mesh]` names the file and `n`.
fn geo_scene(dir: &Path, extra: &str) -> PathBuf {
    let geo = root().join("geo").join("two_blocks.geo");
    let text = format!(
        r#"title = "Two blocks from a .geo"
plane = "strain"
units = {{ length = "m", force = "kN" }}
[mesh]
file = "{}"
n = 4
[body.lower]
young = 1000.0
poisson = 0.3
[body.upper]
young = 1000.0
poisson = 0.3
[boundary.base]
ux = 0.0
uy = 0.0
[boundary.top]
ty = -1.0
[interface.joint]
model = "unilateral"
initial = "closed"
{extra}"#,
        geo.display()
    );
    write(dir, "scene.toml", &text)
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).expect("summary"))
        .expect("summary.json is JSON")
}

fn run(args: &[&str]) -> (i32, String, String) {
    let mut a = vec!["run"];
    a.extend_from_slice(args);
    a.push("--quiet");
    sgbem(&a)
}

/// Every file under `dir` (relative path → bytes).
fn tree(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).expect("read dir") {
            let p = e.expect("entry").path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let rel = p.strip_prefix(dir).unwrap().to_string_lossy().into_owned();
                out.insert(rel, std::fs::read(&p).expect("read"));
            }
        }
    }
    out
}

#[test]
fn set_overrides_change_the_run_and_are_recorded() {
    let dir = tmpdir("workflow-set");
    let scene = geo_scene(&dir, "");
    let s = scene.to_str().unwrap();
    let base = dir.join("base");
    let (code, _, err) = run(&[s, "--out", base.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let doubled = dir.join("doubled");
    let sets = [
        "boundary.top.ty=-2.0",        // a number
        "solve.method=\"qp\"",         // a quoted string
        "output.vtk=false",            // a boolean
        "solve.load_factors=[0.5, 1]", // an array
        "title=Overridden",            // a bare string
    ];
    let mut args = vec![s, "--out", doubled.to_str().unwrap()];
    for x in &sets {
        args.extend(["--set", x]);
    }
    let (code, _, err) = run(&args);
    assert_eq!(code, 0, "{err}");
    let (a, b) = (summary(&base), summary(&doubled));
    let ra = a["interfaces"]["joint"]["normal_resultant"]
        .as_f64()
        .unwrap();
    let rb = b["interfaces"]["joint"]["normal_resultant"]
        .as_f64()
        .unwrap();
    // Top traction −1 kN/m on a 1 m wide block: resultant −1 (to the mesh's accuracy), and
    // twice that with the override; the problem is linear while the joint stays closed.
    assert!((ra + 1.0).abs() < 5e-3, "{ra}");
    assert!((rb - 2.0 * ra).abs() < 1e-9 * ra.abs(), "{ra} {rb}");
    assert_eq!(b["method"], "qp");
    assert_eq!(b["title"], "Overridden");
    assert_eq!(b["contact"]["load_steps"], 2);
    assert!(
        !doubled.join("vtk").exists(),
        "output.vtk = false was not applied"
    );
    assert_eq!(a["overrides"], serde_json::json!([]));
    assert_eq!(b["overrides"], serde_json::json!(sets));
    // The archive keeps them too (root attribute `overrides`, shown by inspect).
    let (code, out, err) = sgbem(&["inspect", doubled.join("archive.h5").to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("overrides   --set boundary.top.ty=-2.0 --set solve.method=\"qp\""),
        "{out}"
    );
    // check shows them.
    let (code, out, err) = sgbem(&["check", s, "--set", "boundary.top.ty=-2.0"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("overrides --set boundary.top.ty=-2.0"),
        "{out}"
    );
}

#[test]
fn set_errors_name_the_override() {
    let dir = tmpdir("workflow-set-errors");
    let scene = geo_scene(&dir, "");
    let s = scene.to_str().unwrap();
    let cases: [(&str, &[&str]); 6] = [
        (
            "interface.joint.cohesin=2.0",
            &[
                "--set interface.joint.cohesin=2.0",
                "unknown key",
                "cohesion",
            ],
        ),
        (
            "solve.method=fast",
            &["--set solve.method=fast", "\"lcp\", \"qp\", \"both\""],
        ),
        (
            "solve.tolerance=abc",
            &["--set solve.tolerance=abc", "tolerance"],
        ),
        ("title.x=1", &["--set title.x=1", "`title` is not a table"]),
        ("solve", &["--set solve", "KEY=VALUE"]),
        ("body..young=1", &["--set body..young=1", "dotted key path"]),
    ];
    for (set, culprits) in cases {
        for cmd in ["check", "run"] {
            let out = dir.join("out");
            let (code, _, err) = sgbem(
                &[cmd, s, "--set", set, "--out", out.to_str().unwrap()]
                    [..if cmd == "check" { 4 } else { 6 }],
            );
            assert_eq!(code, 2, "{cmd} --set {set}: {err}");
            assert!(!err.contains("panicked"), "{err}");
            for c in culprits {
                assert!(
                    err.contains(c),
                    "{cmd} --set {set}: should name {c:?}: {err}"
                );
            }
            assert!(!out.exists(), "{cmd} --set {set} wrote {}", out.display());
        }
    }
    // An error of the file itself is reported as such, even with overrides.
    let broken = write(&dir, "broken.toml", "plane = \"strain\"\nyoung = 1\n");
    let (code, _, err) = sgbem(&["check", broken.to_str().unwrap(), "--set", "title=x"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("unknown key `young`") && !err.contains("--set title"),
        "{err}"
    );
    // An override may also repair the file: the merged document is what is validated.
    let (code, _, err) = sgbem(&[
        "check",
        scene.to_str().unwrap(),
        "--set",
        "interface.joint.model=bonded",
    ]);
    assert_eq!(code, 0, "{err}");
}

#[test]
fn geo_meshes_are_made_with_gmsh() {
    let dir = tmpdir("workflow-geo");
    let scene = geo_scene(&dir, "");
    let s = scene.to_str().unwrap();
    // check meshes into a temporary folder; the element count follows `n`.
    let elements = |out: &str| -> usize {
        // the body lines: "..., 1 loop (outer counter-clockwise), 12 elements, ..."
        out.lines()
            .filter(|l| l.contains(" loop") && l.contains(" elements,"))
            .filter_map(|l| {
                l.split(" elements,")
                    .next()?
                    .rsplit(' ')
                    .next()?
                    .parse::<usize>()
                    .ok()
            })
            .sum()
    };
    let (code, out4, err) = sgbem(&["check", s]);
    assert_eq!(code, 0, "{err}");
    assert!(out4.contains("meshed    by gmsh with n = 4"), "{out4}");
    let (code, out8, err) = sgbem(&["check", s, "--set", "mesh.n=8"]);
    assert_eq!(code, 0, "{err}");
    assert!(out8.contains("n = 8"), "{out8}");
    // Per body: 4 n boundary elements at n elements per unit length (1 × 0.5 block).
    assert_eq!(elements(&out4), 2 * 12, "{out4}");
    assert_eq!(elements(&out8), 2 * 24, "{out8}");
    // run meshes into the output folder.
    let out = dir.join("run");
    let (code, _, err) = run(&[s, "--out", out.to_str().unwrap(), "--set", "mesh.n=6"]);
    assert_eq!(code, 0, "{err}");
    let msh = std::fs::read_to_string(out.join("mesh").join("two_blocks.msh")).unwrap();
    assert!(msh.starts_with("$MeshFormat\n4.1"), "{}", &msh[..40]);
    assert_eq!(summary(&out)["counts"]["boundary_elements"], 2 * 18);
    // A top-level `mesh = "x.geo"` takes parameters from --set too.
    let plain = std::fs::read_to_string(&scene)
        .unwrap()
        .replace("[mesh]\nfile = ", "mesh = ")
        .replace("n = 4\n", "");
    let plain = write(&dir, "plain.toml", &plain);
    let (code, out, err) = sgbem(&["check", plain.to_str().unwrap(), "--set", "mesh.n=8"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(elements(&out), 2 * 24, "{out}");
    // gmsh failing, gmsh missing, parameters on a .msh, a parameter that is no number.
    let broken = write(&dir, "broken.geo", "Point(1) = {0, 0, 0;\n");
    let set = format!("mesh.file={}", broken.display());
    let (code, _, err) = sgbem(&["check", s, "--set", &set]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("gmsh failed") && err.contains("broken.geo"),
        "{err}"
    );
    assert!(
        err.contains("Error"),
        "gmsh's message should be shown: {err}"
    );
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_sgbem"))
        .args(["check", s])
        .env("GMSH", dir.join("no-such-gmsh"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("cannot run gmsh") && err.contains("install gmsh"),
        "{err}"
    );
    let (code, _, err) = sgbem(&["check", s, "--set", "mesh.file=m.msh"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("`mesh.n`") && err.contains(".geo file only"),
        "{err}"
    );
    let (code, _, err) = sgbem(&["check", s, "--set", "mesh.n=\"fine\""]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("`mesh.n` must be a number"), "{err}");
}

#[test]
fn identical_runs_give_identical_files() {
    let dir = tmpdir("workflow-identical");
    // A contact problem with history, sections and the interior field.
    let scene = geo_scene(
        &dir,
        r#"[boundary.top]
tx = "0.6 * (x - 0.5)"
[solve]
method = "both"
[output]
history = "full"
field = true
[[output.section]]
name = "mid"
from = [0.5, 0.0]
to = [0.5, 1.0]
points = 5
"#,
    );
    // [boundary.top] appears twice above: keep the second one only.
    let text = std::fs::read_to_string(&scene)
        .unwrap()
        .replacen("[boundary.top]\nty = -1.0\n", "", 1)
        .replace("tx = \"0.6", "ty = -1.0\ntx = \"0.6");
    std::fs::write(&scene, text).unwrap();
    let s = scene.to_str().unwrap();
    let (a, b) = (dir.join("a"), dir.join("b"));
    for out in [&a, &b] {
        let (code, _, err) = run(&[s, "--out", out.to_str().unwrap()]);
        assert_eq!(code, 0, "{err}");
    }
    let (ta, tb) = (tree(&a), tree(&b));
    assert_eq!(ta.keys().collect::<Vec<_>>(), tb.keys().collect::<Vec<_>>());
    let mut compared = 0;
    for (name, bytes) in &ta {
        if name == "archive.h5" || name == "timings.json" {
            continue;
        }
        assert!(tb[name] == *bytes, "{name} differs between identical runs");
        compared += 1;
    }
    // summary, interface and section tables, mesh, several VTK files and the pvd.
    assert!(compared >= 8, "{:?}", ta.keys().collect::<Vec<_>>());
    for f in [
        "summary.json",
        "interfaces/joint.csv",
        "sections/mid.csv",
        "vtk/history.pvd",
    ] {
        assert!(
            ta.contains_key(f),
            "{f} missing: {:?}",
            ta.keys().collect::<Vec<_>>()
        );
    }
    // The timings and the date live in timings.json.
    let s = summary(&a);
    assert!(s.get("timings").is_none(), "{s}");
    let t: serde_json::Value =
        serde_json::from_slice(&ta["timings.json"]).expect("timings.json is JSON");
    assert!(t["created"].as_str().unwrap().ends_with('Z'), "{t}");
    let stages = t["stages"].as_object().unwrap();
    let total = stages["total"].as_f64().unwrap();
    let sum: f64 = stages
        .iter()
        .filter(|(k, _)| *k != "total")
        .map(|(_, v)| v.as_f64().unwrap())
        .sum();
    assert!((total - sum).abs() <= 1e-9 * total.max(1.0), "{t}");
    // inspect still shows the timings and the date, from the archive.
    let (code, out, err) = sgbem(&["inspect", a.join("archive.h5").to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("timings (s)") && out.contains(t["created"].as_str().unwrap()),
        "{out}"
    );
}

/// `sgbem sweep SCENE --set S... --out OUT EXTRA...`.
fn sweep_into(scene: &str, sets: &[&str], out: &Path, extra: &[&str]) -> (i32, String, String) {
    let mut args = vec!["sweep", scene];
    for s in sets {
        args.extend(["--set", s]);
    }
    args.extend(["--out", out.to_str().unwrap()]);
    args.extend_from_slice(extra);
    sgbem(&args)
}

/// `--columns` picks the figures of each interface, a Physical Curve split per pair of
/// bodies is tabulated by its totals (`interface_curves`; `--parts` lists each part), the
/// Markdown headers carry the units, and an unknown figure is refused naming the valid ones.
#[test]
fn sweep_columns_tabulate_curve_totals_with_units() {
    let dir = tmpdir("workflow-sweep-columns");
    let scene = support::root().join("pipelines/wall_running_bond.toml");
    let s = scene.to_str().unwrap();
    let sets = [
        "mesh.courses=2",
        "mesh.bricks=2",
        "defaults.interface.friction=0.5,0.7",
        "output.vtk=false",
    ];
    let sweep = |out: &Path, extra: &[&str]| sweep_into(s, &sets, out, extra);
    let out = dir.join("curves");
    let keys = "detached_length,slip_length,tangential_resultant";
    let (code, _, err) = sweep(&out, &["--columns", keys]);
    assert_eq!(code, 0, "{err}");
    let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    let head: Vec<&str> = lines[0].split(',').collect();
    assert_eq!(
        &head[head.len() - 3..],
        [
            "joints.detached_length",
            "joints.slip_length",
            "joints.tangential_resultant"
        ],
        "{csv}"
    );
    for line in &lines[1..] {
        let c: Vec<&str> = line.split(',').collect();
        let sm = summary(&out.join(c[0]));
        let curve = &sm["interface_curves"]["joints"];
        for (k, v) in keys.split(',').zip(&c[c.len() - 3..]) {
            assert_eq!(v.parse::<f64>().unwrap(), curve[k].as_f64().unwrap(), "{k}");
        }
        // The curve's slip length is the sum over its parts.
        let parts: f64 = curve["parts"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| {
                sm["interfaces"][p.as_str().unwrap()]["slip_length"]
                    .as_f64()
                    .unwrap()
            })
            .sum();
        assert!((parts - curve["slip_length"].as_f64().unwrap()).abs() < 1e-12);
    }
    let md = std::fs::read_to_string(out.join("sweep.md")).unwrap();
    assert!(
        md.contains("joints.slip_length (m)") && md.contains("joints.tangential_resultant (kN)"),
        "{md}"
    );
    let out = dir.join("parts");
    assert_eq!(sweep(&out, &["--parts"]).0, 0);
    let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    let head = csv.lines().next().unwrap();
    assert!(
        head.contains("joints[brick_1|brick_2].normal_resultant")
            && !head.contains("joints.normal_resultant"),
        "{head}"
    );
    let (code, _, err) = sweep(&dir.join("bad"), &["--columns", "slip_lenght"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("slip_length") && err.contains("tangential_resultant"),
        "{err}"
    );
}

/// A sweep as a job array: `--list` numbers the points, `--point K` runs one (as a SLURM
/// task would, side by side with the others), `--table` tabulates what has run; the table
/// of all points equals the one of the whole sweep.
#[test]
fn sweep_points_run_one_by_one_and_tabulate_as_the_whole_sweep() {
    let dir = tmpdir("workflow-sweep-points");
    let scene = geo_scene(&dir, "");
    let s = scene.to_str().unwrap();
    let sweep =
        |out: &Path, extra: &[&str]| sweep_into(s, &["boundary.top.ty=-1,-2,-3"], out, extra);
    let whole = dir.join("whole");
    assert_eq!(sweep(&whole, &[]).0, 0);
    let arr = dir.join("array");
    let (code, listed, err) = sweep(&arr, &["--list"]);
    assert_eq!(code, 0, "{err}");
    let lines: Vec<&str> = listed.lines().collect();
    assert_eq!(lines.len(), 3, "{listed}");
    assert!(
        lines[1].starts_with("2\t") && lines[1].contains("ty=-2"),
        "{listed}"
    );
    assert!(lines[1].contains("--set 'boundary.top.ty=-2'"), "{listed}");
    assert!(!arr.exists(), "--list runs nothing");
    for bad in ["0", "4"] {
        let (code, _, err) = sweep(&arr, &["--point", bad]);
        assert_eq!(code, 2, "{err}");
        assert!(
            err.contains("points 1 to 3") && err.contains("--list"),
            "{err}"
        );
    }
    let (code, _, err) = sweep(&arr, &["--point", "2"]);
    assert_eq!(code, 0, "{err}");
    assert!(arr.join("ty=-2").join("summary.json").is_file());
    assert!(!arr.join("ty=-1").exists() && !arr.join("ty=-3").exists());
    assert_eq!(sweep(&arr, &["--table"]).0, 0);
    let partial = std::fs::read_to_string(arr.join("sweep.csv")).unwrap();
    assert!(
        partial.lines().nth(1).unwrap().contains("not finished"),
        "{partial}"
    );
    for k in ["3", "1"] {
        assert_eq!(sweep(&arr, &["--point", k]).0, 0);
    }
    assert_eq!(sweep(&arr, &["--table"]).0, 0);
    let read = |d: &Path| std::fs::read_to_string(d.join("sweep.csv")).unwrap();
    assert_eq!(read(&arr), read(&whole));
}

#[test]
fn sweep_runs_every_point_and_tabulates() {
    let dir = tmpdir("workflow-sweep");
    let scene = geo_scene(&dir, "");
    let s = scene.to_str().unwrap();
    let out = dir.join("sweep");
    let (code, stdout, err) = sgbem(&[
        "sweep",
        s,
        "--set",
        "boundary.top.ty=-1,-2,-3",
        "--set",
        "interface.*.initial=closed",
        "--jobs",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(stdout.contains("sweep.csv"), "{stdout}");
    let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(
        lines[0],
        "point,boundary.top.ty,interface.*.initial,exit_code,status,contact_iterations,\
         joint.detached_length,joint.normal_resultant"
    );
    assert_eq!(lines.len(), 4, "{csv}");
    let mut resultants = Vec::new();
    for (line, ty) in lines[1..].iter().zip([-1.0, -2.0, -3.0]) {
        let c: Vec<&str> = line.split(',').collect();
        let name = format!("ty={ty}_initial=closed");
        assert_eq!(c[0], name, "{csv}");
        assert_eq!(&c[3..5], ["0", "converged"], "{csv}");
        assert_eq!(c[6], "0", "{csv}");
        // Each point's folder is a whole run whose summary gives the table's figures.
        let sm = summary(&out.join(&name));
        let r: f64 = c[7].parse().unwrap();
        assert_eq!(
            r,
            sm["interfaces"]["joint"]["normal_resultant"]
                .as_f64()
                .unwrap()
        );
        assert_eq!(
            sm["overrides"],
            serde_json::json!([
                format!("boundary.top.ty={ty}"),
                "interface.*.initial=closed"
            ])
        );
        resultants.push(r);
    }
    // Linear in the load while the joint stays closed.
    assert!(
        (resultants[1] - 2.0 * resultants[0]).abs() < 1e-9,
        "{resultants:?}"
    );
    assert!(
        (resultants[2] - 3.0 * resultants[0]).abs() < 1e-9,
        "{resultants:?}"
    );
    let md = std::fs::read_to_string(out.join("sweep.md")).unwrap();
    assert_eq!(md.lines().count(), 5, "{md}");
    // A bad key fails every point before any runs, naming the override.
    let out2 = dir.join("bad");
    let (code, _, err) = sgbem(&[
        "sweep",
        s,
        "--set",
        "interface.*.cohesin=1,2",
        "--out",
        out2.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("--set interface.*.cohesin=1") && err.contains("cohesion"),
        "{err}"
    );
    assert!(!out2.exists());
    // Values with commas inside brackets stay whole.
    let a = sgbem::sweep::parse_axis("solve.load_factors=[0.5, 1],[1]").unwrap();
    assert_eq!(a.values, ["[0.5, 1]", "[1]"]);
}

/// A sweep file (`sgbem sweep --file`) is the sweep of its command line: the same points
/// and byte for byte the same sweep.csv and sweep.md, with the scene and the folder relative
/// to the file. The command line's `--set` replaces the file's entry for the same key in its
/// place or adds a key, `--out` replaces its folder.
#[test]
fn sweep_file_gives_the_tables_of_its_command_line() {
    let dir = tmpdir("workflow-sweep-file");
    let scene = geo_scene(&dir, "");
    std::fs::create_dir_all(dir.join("sweeps")).unwrap();
    let file = write(
        &dir.join("sweeps"),
        "ty.toml",
        "# two loads, two starts\n\
         scene = \"../scene.toml\"\n\
         set = [\"boundary.top.ty=-1,-2\", \"interface.*.initial=closed,open\"]\n\
         out = \"../from_file\"\n\
         columns = [\"detached_length\", \"normal_resultant\", \"tangential_resultant\"]\n",
    );
    let f = file.to_str().unwrap();
    let (code, _, err) = sgbem(&["sweep", "--file", f, "--jobs", "2"]);
    assert_eq!(code, 0, "{err}");
    let by_file = dir.join("from_file");
    let by_line = dir.join("from_line");
    let sets = ["boundary.top.ty=-1,-2", "interface.*.initial=closed,open"];
    let columns = [
        "--columns",
        "detached_length,normal_resultant,tangential_resultant",
    ];
    let (code, _, err) = sweep_into(scene.to_str().unwrap(), &sets, &by_line, &columns);
    assert_eq!(code, 0, "{err}");
    for t in ["sweep.csv", "sweep.md"] {
        let (a, b) = (
            std::fs::read(by_file.join(t)),
            std::fs::read(by_line.join(t)),
        );
        assert_eq!(a.unwrap(), b.unwrap(), "{t}");
    }
    let csv = std::fs::read_to_string(by_file.join("sweep.csv")).unwrap();
    assert_eq!(csv.lines().count(), 5, "{csv}");
    assert!(csv.contains("joint.tangential_resultant"), "{csv}");
    // The command line over the file: a key of the file replaced in its place, one added,
    // the folder replaced.
    let other = dir.join("other");
    let (code, listed, err) = sgbem(&[
        "sweep",
        "--file",
        f,
        "--set",
        "solve.method=qp",
        "--set",
        "boundary.top.ty=-3",
        "--out",
        other.to_str().unwrap(),
        "--list",
    ]);
    assert_eq!(code, 0, "{err}");
    let first = listed.lines().next().unwrap_or_default();
    assert_eq!(
        first,
        format!(
            "1\t{}\t--set 'boundary.top.ty=-3' --set 'interface.*.initial=closed' --set \
             'solve.method=qp'",
            other.join("ty=-3_initial=closed_method=qp").display()
        )
    );
    assert_eq!(listed.lines().count(), 2, "{listed}");
}

/// A sweep file's mistakes are input errors (exit 2) naming the file and what to fix, before
/// anything runs: an unknown key (with the allowed keys), a scene that is not there, a
/// missing `set`, a value of the wrong type, a scene given twice.
#[test]
fn sweep_file_errors_name_the_file_and_the_key() {
    let dir = tmpdir("workflow-sweep-file-errors");
    geo_scene(&dir, "");
    let out = dir.join("out");
    let cases = [
        (
            "scene = \"scene.toml\"\nset = [\"boundary.top.ty=-1\"]\ncolums = [\"pairs\"]\n",
            vec![
                "unknown key `colums`",
                "did you mean `columns`",
                "allowed keys: scene, set, out, columns, parts, allow_geo_shell",
            ],
        ),
        (
            "scene = \"../scene.toml\"\nset = [\"boundary.top.ty=-1\"]\n",
            vec![
                "scene = \"../scene.toml\": no such scene file",
                "relative to the sweep file",
            ],
        ),
        (
            "scene = \"scene.toml\"\n",
            vec!["`set = [\"KEY=V1,V2,...\", ...]` is required"],
        ),
        (
            "scene = \"scene.toml\"\nset = [\"boundary.top.ty=-1\"]\nparts = \"yes\"\n",
            vec!["`parts` must be true or false"],
        ),
    ];
    for (k, (text, words)) in cases.iter().enumerate() {
        let name = format!("bad{k}.toml");
        let file = write(&dir, &name, text);
        let o = out.to_str().unwrap();
        let (code, _, err) = sgbem(&["sweep", "--file", file.to_str().unwrap(), "--out", o]);
        assert_eq!(code, 2, "{name}: {err}");
        assert!(err.contains(&name), "{name}: {err}");
        for w in words {
            assert!(err.contains(w), "{name}: `{w}` not in {err}");
        }
        assert!(!out.exists(), "{name}: nothing runs");
    }
    let file = write(
        &dir,
        "good.toml",
        "scene = \"scene.toml\"\nset = [\"a=1\"]\n",
    );
    let scene = dir.join("scene.toml");
    let (code, _, err) = sgbem(&[
        "sweep",
        scene.to_str().unwrap(),
        "--file",
        file.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("cannot be used with"), "{err}");
    let missing = dir.join("none.toml");
    let (code, _, err) = sgbem(&["sweep", "--file", missing.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("none.toml: no such sweep file"), "{err}");
}

/// timings.json counts every second once: the collapse search's trials (each a step with
/// its own assembly and contact stages) are itemised under `within.collapse_search`, not
/// added to the top-level stages again, so that `stages.total` is the run's wall time (the
/// shipped `wall_collapse`: 22.7 s of stages against 13.1 s of wall time before). Measured
/// into a fresh folder: replacing a previous run also deletes its files after timings.json
/// is written.
#[test]
fn timings_total_is_the_wall_time_with_the_collapse_trials_inside() {
    let dir = tmpdir("workflow-timings");
    let scene = root().join("pipelines/wall_collapse.toml");
    let out = dir.join("run");
    let start = std::time::Instant::now();
    let (code, _, err) = sgbem(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    let wall = start.elapsed().as_secs_f64();
    assert_eq!(code, 0, "{err}");
    let t: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("timings.json")).unwrap()).unwrap();
    let total = t["stages"]["total"].as_f64().unwrap();
    eprintln!("wall_collapse: wall {wall:.3} s, timings total {total:.3} s");
    assert!(
        (total - wall).abs() <= 0.05 * wall + 0.05,
        "timings total {total} s against a wall time of {wall} s: {t}"
    );
    let search = t["stages"]["collapse_search"].as_f64().unwrap();
    let inside = &t["within"]["collapse_search"];
    let inside_total = inside["total"].as_f64().unwrap();
    eprintln!("collapse search {search:.3} s, {inside_total:.3} s of it in its trials' stages");
    // The trials' stages lie within the search, and are its bulk.
    assert!(inside_total <= search && inside_total > 0.5 * search, "{t}");
    // The wall's default is the full rows (its joints meet at T-junctions).
    for stage in ["assemble", "contact_exact", "contact_record"] {
        assert!(inside[stage].as_f64().unwrap() > 0.0, "{stage}: {t}");
    }
}

/// The lock of the output folder is taken when `run` starts, before a `.geo` is meshed or
/// anything computed: a run into a folder another live run holds is refused at once and
/// writes nothing (it used to mesh into the folder's mesh/ first and be refused only once
/// its model was built).
#[test]
fn a_locked_folder_refuses_the_run_before_meshing() {
    let dir = tmpdir("workflow-lock");
    let scene = geo_scene(&dir, "");
    let s = scene.to_str().unwrap();
    let out = dir.join("run");
    let lock = dir.join(".run.lock");
    // A live process (this test) holds the lock: an flock on the lock file.
    let held = std::fs::File::create(&lock).unwrap();
    held.lock().unwrap();
    // A fine mesh: meshing and building the model would take a while.
    let start = std::time::Instant::now();
    let (code, _, err) = run(&[s, "--out", out.to_str().unwrap(), "--set", "mesh.n=200"]);
    let seconds = start.elapsed().as_secs_f64();
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("another sgbem run") && err.contains(".run.lock"),
        "{err}"
    );
    assert!(
        !out.exists(),
        "the refused run wrote {:?}",
        tree(&out).keys()
    );
    assert!(lock.exists());
    let mut left: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    assert_eq!(left, [".run.lock", "scene.toml"]);
    eprintln!("refused after {seconds:.3} s");
    // The scene's own folder (output.directory) is locked the same way.
    let own = geo_scene(&dir, "[output]\ndirectory = \"own\"\n");
    let held_own = std::fs::File::create(dir.join(".own.lock")).unwrap();
    held_own.lock().unwrap();
    let (code, _, err) = run(&[own.to_str().unwrap()]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains(".own.lock") && !dir.join("own").exists(),
        "{err}"
    );
    // Once the lock is released the same run goes through and meshes into its folder.
    drop(held);
    drop(held_own);
    let (code, _, err) = run(&[s, "--out", out.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(out.join("mesh").join("two_blocks.msh").is_file());
}

/// Snakemake where `make setup` installed it (`.venv`), else on the PATH.
fn snakemake() -> Option<PathBuf> {
    let venv = root().join(".venv/bin/snakemake");
    if venv.is_file() {
        return Some(venv);
    }
    let o = std::process::Command::new("snakemake")
        .arg("--version")
        .output()
        .ok()?;
    o.status.success().then(|| PathBuf::from("snakemake"))
}

/// The generic Snakefile (`pipelines/Snakefile`) on the shipped sweep file
/// `pipelines/sweeps/wall_friction.toml`, two jobs at a time: a job per point (`--point K`;
/// the point that slides ends with exit 3 and is a result, as in the whole sweep), then
/// `--table`, whose sweep.csv and sweep.md are byte for byte those of `sgbem sweep` run
/// whole. A rerun does nothing; a value added in the middle of the sweep (K shifts for the
/// points after it) runs that point alone. Skipped where Snakemake is not installed.
#[test]
fn snakefile_runs_a_sweep_file_point_by_point_as_the_whole_sweep() {
    let Some(snakemake) = snakemake() else {
        eprintln!("skipped: no snakemake (make setup installs it into .venv)");
        return;
    };
    let dir = tmpdir("workflow-snakefile");
    let file = root().join("pipelines/sweeps/wall_friction.toml");
    let spec: toml::Table = std::fs::read_to_string(&file).unwrap().parse().unwrap();
    let scene = file.parent().unwrap().join(spec["scene"].as_str().unwrap());
    let strings = |key: &str| -> Vec<String> {
        let list = spec[key].as_array().unwrap();
        list.iter()
            .map(|v| v.as_str().unwrap().to_string())
            .collect()
    };
    let (sets, columns) = (strings("set"), strings("columns").join(","));
    let whole = |sets: &[String], out: &Path| {
        let sets: Vec<&str> = sets.iter().map(String::as_str).collect();
        let s = scene.to_str().unwrap();
        let (code, _, err) = sweep_into(s, &sets, out, &["--columns", &columns]);
        assert_eq!(code, 3, "the point at mu = 0.05 slides: {err}");
    };
    let snake = |sweep: &Path, out: &Path| -> String {
        let o = std::process::Command::new(&snakemake)
            .arg("-s")
            .arg(root().join("pipelines/Snakefile"))
            .arg("--directory")
            .arg(&dir)
            .args(["--cores", "2", "--config"])
            .arg(format!("sweep={}", sweep.display()))
            .arg(format!("sgbem={}", env!("CARGO_BIN_EXE_sgbem")))
            .arg(format!("out={}", out.display()))
            .output()
            .expect("run snakemake");
        let text =
            String::from_utf8_lossy(&o.stdout).into_owned() + &String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{text}");
        text
    };
    let same_tables = |a: &Path, b: &Path| {
        for f in ["sweep.csv", "sweep.md"] {
            let (x, y) = (std::fs::read(a.join(f)).unwrap(), std::fs::read(b.join(f)));
            let y = y.unwrap();
            assert!(
                x == y,
                "{f} differs:\n{}\n{}",
                String::from_utf8_lossy(&x),
                String::from_utf8_lossy(&y)
            );
        }
    };
    // The summaries the jobs wrote and when.
    let written = |out: &Path| -> BTreeMap<String, std::time::SystemTime> {
        let mut m = BTreeMap::new();
        for e in std::fs::read_dir(out).unwrap() {
            let p = e.unwrap().path().join("summary.json");
            if let Ok(meta) = std::fs::metadata(&p) {
                let name = p.parent().unwrap().file_name().unwrap();
                m.insert(name.to_string_lossy().into(), meta.modified().unwrap());
            }
        }
        m
    };
    let snaked = dir.join("snake");
    whole(&sets, &dir.join("whole"));
    snake(&file, &snaked);
    same_tables(&dir.join("whole"), &snaked);
    let csv = std::fs::read_to_string(snaked.join("sweep.csv")).unwrap();
    assert!(csv.contains(",0.05,3,not converged,"), "{csv}");
    let first = written(&snaked);
    assert_eq!(first.len(), 3, "{first:?}");
    let again = snake(&file, &snaked);
    assert!(again.contains("Nothing to be done"), "{again}");
    assert_eq!(written(&snaked), first, "a rerun redoes no point");
    // mu = 0.5 between 0.3 and 0.7: one new job; the others keep their results.
    let more: Vec<String> = sets
        .iter()
        .map(|s| s.replace("=0.05,0.3,0.7", "=0.05,0.3,0.5,0.7"))
        .collect();
    let mut extended = spec.clone();
    extended.insert("scene".into(), scene.to_str().unwrap().into());
    extended.insert("set".into(), more.clone().into());
    let ext = write(&dir, "extended.toml", &extended.to_string());
    snake(&ext, &snaked);
    let second = written(&snaked);
    assert_eq!(second.len(), 4, "{second:?}");
    for (name, t) in &first {
        assert_eq!(second[name], *t, "{name} ran again");
    }
    whole(&more, &dir.join("whole_more"));
    same_tables(&dir.join("whole_more"), &snaked);
}
