//! The command line on bad input: every class of input error exits with status 2 and one
//! message naming the culprit; nothing panics. Plus `check` on a good scene.

mod support;

use support::*;

/// Runs `sgbem check` on a scene text and a mesh; returns (code, stdout, stderr).
fn check(dir: &std::path::Path, scene: &str, mesh: &std::path::Path) -> (i32, String, String) {
    let s = write(dir, "scene.toml", scene);
    sgbem(&[
        "check",
        s.to_str().unwrap(),
        "--mesh",
        mesh.to_str().unwrap(),
    ])
}

/// Asserts exit status 2, a one-line message naming every `culprit`, and no panic.
fn bad(out: (i32, String, String), culprits: &[&str]) {
    let (code, _, err) = out;
    assert_eq!(code, 2, "exit status for: {err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(err.starts_with("sgbem: "), "{err}");
    for c in culprits {
        assert!(err.contains(c), "message should name {c:?}: {err}");
    }
}

#[test]
fn good_scene_checks() {
    let dir = tmpdir("cli-good");
    let msh = stacked_blocks(4).save(&dir, "m.msh");
    let (code, out, err) = check(&dir, STACKED_SCENE, &msh);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("bodies (2)"), "{out}");
    assert!(out.contains("effects: elastic + detachment"), "{out}");
    assert!(
        out.contains("sides") && out.contains("traction-free"),
        "{out}"
    );
    assert!(out.contains("5 pairs"), "{out}");
}

#[test]
fn version_and_help() {
    let (code, out, _) = sgbem(&["--version"]);
    assert_eq!(code, 0);
    assert!(out.contains(env!("CARGO_PKG_VERSION")));
    for cmd in ["run", "check", "inspect", "export"] {
        let (code, out, _) = sgbem(&[cmd, "--help"]);
        assert_eq!(code, 0, "{cmd} --help");
        assert!(out.contains("Usage"), "{out}");
    }
}

#[test]
fn scene_errors() {
    let dir = tmpdir("cli-scene");
    let msh = stacked_blocks(4).save(&dir, "m.msh");
    let cases: Vec<(String, Vec<&str>)> = vec![
        (
            STACKED_SCENE.replace(
                "young = 1.0\npoisson = 0.3\n[body.upper]",
                "yuong = 1.0\npoisson = 0.3\n[body.upper]",
            ),
            vec!["body.lower.yuong", "did you mean `young`"],
        ),
        (
            STACKED_SCENE.replace("ux = 0.0", "ux = 0.0\ntx = 1.0"),
            vec!["boundary.base", "`ux`", "`tx`"],
        ),
        (
            STACKED_SCENE.replacen("young = 1.0", "young = 0.0", 1),
            vec!["body.lower.young"],
        ),
        (
            STACKED_SCENE.replacen("poisson = 0.3", "poisson = 0.5", 1),
            vec!["body.lower.poisson", "plane strain"],
        ),
        (
            STACKED_SCENE.replacen("poisson = 0.3", "poisson = -1.0", 1),
            vec!["body.lower.poisson"],
        ),
        (
            STACKED_SCENE.replace(
                "model = \"unilateral\"",
                "model = \"unilateral\"\ncohesion = -0.1",
            ),
            vec!["interface.joint.cohesion"],
        ),
        (
            STACKED_SCENE.replace(
                "model = \"unilateral\"",
                "model = \"unilateral\"\ninitial = \"open\"\ngap = \"ln(0)\"",
            ),
            vec!["interface.joint.gap"],
        ),
        (
            STACKED_SCENE.replace("ty = -1.0", "ty = \"-1*(x\""),
            vec!["boundary.top.ty", "does not parse"],
        ),
        (
            STACKED_SCENE.replace("ty = -1.0", "ty = \"-1*depth\""),
            vec!["boundary.top.ty", "`depth`"],
        ),
        (
            STACKED_SCENE.replace("ty = -1.0", "ty = \"sqrt(x - 2)\""),
            vec!["boundary.top.ty", "NaN"],
        ),
        (
            STACKED_SCENE.replace(
                "model = \"unilateral\"",
                "model = \"unilateral\"\ninitial = \"open\"\ngap = \"sqrt(0.1 - x)\"",
            ),
            vec!["interface.joint.gap", "node"],
        ),
        (
            STACKED_SCENE.replace("plane = \"strain\"", "plane = \"strian\""),
            vec!["plane", "did you mean `strain`"],
        ),
        // friction and load paths
        (
            STACKED_SCENE.replace(
                "model = \"unilateral\"",
                "model = \"unilateral\"\ntangential = \"friction\"",
            ),
            vec!["interface.joint", "no `friction`", "friction = 0.6"],
        ),
        (
            STACKED_SCENE.replace(
                "model = \"unilateral\"",
                "model = \"unilateral\"\ntangential = \"slide\"\nfriction = 0.5",
            ),
            vec!["interface.joint.friction", "tangential = \"slide\""],
        ),
        (
            STACKED_SCENE.replace(
                "model = \"unilateral\"",
                "model = \"unilateral\"\ntangential = \"friction\"\nfriction = \"0.5 - x\"",
            ),
            vec!["interface.joint.friction", ">= 0"],
        ),
        (
            STACKED_SCENE.replace(
                "model = \"unilateral\"",
                "model = \"unilateral\"\ntangential = \"frictoin\"",
            ),
            vec!["interface.joint.tangential", "did you mean `friction`"],
        ),
        (
            format!("{STACKED_SCENE}\n[solve]\ntime = [1.0, 2.0]\nload_factors = [1.0]\n"),
            vec!["solve.time", "solve.load_factors", "not both"],
        ),
        (
            format!("{STACKED_SCENE}\n[solve]\ntime = [1.0, 0.5]\n"),
            vec!["solve.time", "must increase"],
        ),
        (
            format!("{STACKED_SCENE}\n[solve]\ntime = [1.0, 2.0]\n")
                .replace("ty = -1.0", "ty = \"sqrt(1.5 - t)\""),
            vec!["boundary.top.ty", "t = 2"],
        ),
        (
            STACKED_SCENE.replacen(
                "poisson = 0.3",
                "poisson = 0.3\nbody_force = [0.0, \"-y\"]",
                1,
            ),
            vec!["body_force[1]", "uniform"],
        ),
        (
            "plane = \"strain\"\n[body.lower\n".to_string(),
            vec!["not valid TOML"],
        ),
    ];
    for (scene, culprits) in cases {
        bad(check(&dir, &scene, &msh), &culprits);
    }
}

#[test]
fn scene_and_mesh_mismatch_errors() {
    let dir = tmpdir("cli-mismatch");
    let msh = stacked_blocks(4).save(&dir, "m.msh");
    let cases: Vec<(String, Vec<&str>)> = vec![
        // a physical name the scene uses and the mesh lacks
        (
            STACKED_SCENE.replace("[body.upper]", "[body.uper]"),
            vec!["body.uper", "did you mean `upper`"],
        ),
        (
            STACKED_SCENE.replace("[boundary.top]", "[boundary.roof]"),
            vec!["boundary.roof", "Physical Curve"],
        ),
        // a group of the wrong kind
        (
            STACKED_SCENE.replace("[boundary.top]", "[boundary.upper]"),
            vec!["boundary.upper", "Physical Surface", "Physical Curve"],
        ),
        (
            STACKED_SCENE.replace("[body.upper]", "[body.top]"),
            vec!["body.top", "Physical Curve"],
        ),
        // an interface whose curve is not shared by exactly two bodies
        (
            STACKED_SCENE.replace(
                "[boundary.top]\nty = -1.0",
                "[interface.top]\nmodel = \"bonded\"",
            ),
            vec!["interface.top", "exactly two bodies"],
        ),
        // a shared curve the scene does not declare as an interface
        (
            STACKED_SCENE.replace("[interface.joint]\nmodel = \"unilateral\"", ""),
            vec!["joint", "[interface.joint]"],
        ),
        (
            STACKED_SCENE.replace(
                "[interface.joint]\nmodel = \"unilateral\"",
                "[boundary.joint]\nty = 0.0",
            ),
            vec!["joint", "interface"],
        ),
        // a body that nothing holds
        (
            STACKED_SCENE.replace("[boundary.base]\nux = 0.0\nuy = 0.0", ""),
            vec!["not held", "lower", "upper"],
        ),
        (
            STACKED_SCENE.replace("uy = 0.0", ""),
            vec!["not held", "translation along y"],
        ),
        // a Physical Surface without a body
        (
            STACKED_SCENE.replace("[body.upper]\nyoung = 1.0\npoisson = 0.3\n", ""),
            vec!["\"upper\"", "[body.upper]"],
        ),
        // field output without triangles
        (
            format!("{STACKED_SCENE}\n[output]\nfield = true\n"),
            vec!["output.field", "gmsh -2"],
        ),
    ];
    for (scene, culprits) in cases {
        bad(check(&dir, &scene, &msh), &culprits);
    }
}

#[test]
fn isolated_body_is_not_held() {
    let dir = tmpdir("cli-isolated");
    let mut m = stacked_blocks(2);
    // A third block far away, touching nothing, with no condition.
    m.line(11, [3.0, 0.0], [4.0, 0.0], 2, &[2]);
    m.line(12, [4.0, 0.0], [4.0, 1.0], 2, &[2]);
    m.line(13, [4.0, 1.0], [3.0, 1.0], 2, &[2]);
    m.line(14, [3.0, 1.0], [3.0, 0.0], 2, &[2]);
    m.surface(3, &[11, 12, 13, 14], &[3]);
    m.name(2, 3, "loose");
    let msh = m.save(&dir, "m.msh");
    let scene = format!("{STACKED_SCENE}\n[body.loose]\nyoung = 1.0\npoisson = 0.3\n");
    bad(
        check(&dir, &scene, &msh),
        &[
            "body \"loose\" is not held",
            "no displacement condition and no interface",
        ],
    );
}

#[test]
fn mesh_errors() {
    let dir = tmpdir("cli-mesh");
    let good = stacked_blocks(4).to_text();

    // unreadable: missing, truncated, garbage
    let (code, _, err) = sgbem(&[
        "check",
        write(&dir, "s.toml", STACKED_SCENE).to_str().unwrap(),
        "--mesh",
        dir.join("nope.msh").to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("nope.msh") && err.contains("no such mesh file"),
        "{err}"
    );
    let cut = &good[..good.len() * 2 / 3];
    bad(
        check(&dir, STACKED_SCENE, &write(&dir, "cut.msh", cut)),
        &["cut.msh"],
    );
    bad(
        check(
            &dir,
            STACKED_SCENE,
            &write(&dir, "junk.msh", "hello\nworld\n"),
        ),
        &["junk.msh"],
    );

    // open loop: a curve whose elements are missing (untagged curve dropped by gmsh)
    let mut m = stacked_blocks(4);
    m.curves[6].1.clear();
    bad(
        check(&dir, STACKED_SCENE, &m.save(&dir, "open.msh")),
        &["open.msh", "curve 7", "Physical Curve"],
    );

    // a boundary curve in no physical group
    let mut m = stacked_blocks(4);
    m.curves[6].2.clear();
    bad(
        check(&dir, STACKED_SCENE, &m.save(&dir, "untagged.msh")),
        &["curve 7", "Physical Curve"],
    );

    // zero-length element: a curve whose two nodes coincide
    let mut m = stacked_blocks(4);
    let a = m.nodes[m.curves[5].1[1]];
    let extra = m.new_node(a);
    m.curves[5].1.insert(2, extra);
    bad(
        check(&dir, STACKED_SCENE, &m.save(&dir, "zero.msh")),
        &["zero length", "element"],
    );

    // interface nodes that do not match (the joint drawn twice, with 4 and 3 elements): the
    // sides are paired from the geometry
    let mut m = stacked_blocks(4);
    m.line(8, [0.0, 1.0], [1.0, 1.0], 3, &[3]);
    m.surfaces[1].1 = vec![8, 5, 6, 7];
    let (code, out, err) = check(&dir, STACKED_SCENE, &m.save(&dir, "mismatch.msh"));
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("sides meshed on their own, paired from the geometry"),
        "{out}"
    );

    // overlapping bodies: two squares that overlap by a quarter
    let mut m = Msh::default();
    m.line(1, [0.0, 0.0], [1.0, 0.0], 2, &[1]);
    m.line(2, [1.0, 0.0], [1.0, 1.0], 2, &[2]);
    m.line(3, [1.0, 1.0], [0.0, 1.0], 2, &[2]);
    m.line(4, [0.0, 1.0], [0.0, 0.0], 2, &[2]);
    m.line(5, [0.5, 0.5], [1.5, 0.5], 2, &[2]);
    m.line(6, [1.5, 0.5], [1.5, 1.5], 2, &[2]);
    m.line(7, [1.5, 1.5], [0.5, 1.5], 2, &[4]);
    m.line(8, [0.5, 1.5], [0.5, 0.5], 2, &[2]);
    m.surface(1, &[1, 2, 3, 4], &[1]);
    m.surface(2, &[5, 6, 7, 8], &[2]);
    for (d, t, n) in [
        (1, 1, "base"),
        (1, 2, "sides"),
        (1, 4, "top"),
        (2, 1, "lower"),
        (2, 2, "upper"),
    ] {
        m.name(d, t, n);
    }
    let scene = STACKED_SCENE
        .replace("[interface.joint]\nmodel = \"unilateral\"", "")
        .replace("ty = -1.0", "ux = 0.0\nuy = 0.0");
    bad(
        check(&dir, &scene, &m.save(&dir, "overlap.msh")),
        &["\"lower\"", "\"upper\"", "overlap"],
    );

    // second-order elements are refused
    let text = good.replace(
        "$Elements\n7 28 1 28\n1 1 1 4",
        "$Elements\n7 28 1 28\n1 1 8 4",
    );
    bad(
        check(&dir, STACKED_SCENE, &write(&dir, "order2.msh", &text)),
        &["order2.msh"],
    );
}

#[test]
fn missing_scene_file_is_an_input_error() {
    let (code, _, err) = sgbem(&["check", "/nonexistent/scene.toml"]);
    assert_eq!(code, 2);
    assert!(err.contains("/nonexistent/scene.toml"), "{err}");
}

#[test]
fn gmsh_untagged_curve_gives_the_hint() {
    // Remove a curve's Physical Curve from the .geo: gmsh then drops its elements.
    let dir = tmpdir("cli-untagged");
    let geo = std::fs::read_to_string(root().join("geo/two_blocks.geo")).unwrap();
    let geo: String = geo
        .lines()
        .filter(|l| !l.starts_with("Physical Curve(\"upper_sides\")"))
        .map(|l| format!("{l}\n"))
        .collect();
    let geo = write(&dir, "untagged.geo", &geo);
    let msh = gmsh(&geo, &dir, "untagged.msh", false, &[]);
    let scene = std::fs::read_to_string(root().join("pipelines/two_blocks.toml")).unwrap();
    bad(
        check(&dir, &scene, &msh),
        &["untagged.msh", "curve 5", "\"upper\"", "Physical Curve"],
    );
}

/// Found by the `model` fuzz target: a boundary that folds back on itself (two consecutive
/// elements on top of each other) had no normal at the fold; it is now an input error.
#[test]
fn folded_boundary_found_by_fuzzing_is_an_input_error() {
    let dir = tmpdir("cli-fold");
    let scene = "plane = \"strain\"\n[body.left]\nyoung = 1.0\npoisson = 0.3\n[body.right]\nyoung = 2.0\n\
                 poisson = 0.25\n[boundary.clamp]\nux = 0.0\nuy = \"0.01*y\"\n[boundary.free]\ntn = \"-x\"\n\
                 [interface.interface]\nmodel = \"unilateral\"\n";
    let msh = root().join("tests/fixtures/fuzz_model_folded_interface.msh");
    bad(check(&dir, scene, &msh), &["folds back", "left", "node 14"]);
}

/// Found by the `model` fuzz target: a surface listing the curve tag i32::MIN (whose
/// absolute value overflows) is an input error, not a panic.
#[test]
fn invalid_bounding_curve_tag_found_by_fuzzing_is_an_input_error() {
    let dir = tmpdir("cli-tagmin");
    let scene = "plane = \"strain\"\n[body.left]\nyoung = 1.0\npoisson = 0.3\n[body.right]\nyoung = 2.0\n\
                 poisson = 0.25\n[boundary.clamp]\nux = 0.0\nuy = \"0.01*y\"\n[boundary.free]\ntn = \"-x\"\n\
                 [interface.interface]\nmodel = \"unilateral\"\n";
    let msh = root().join("tests/fixtures/fuzz_model_curve_tag_min.msh");
    bad(
        check(&dir, scene, &msh),
        &["invalid bounding curve tag", "-2147483648"],
    );
}

/// A stiffness contrast above 1e3 across an interface makes `check` advise the accurate
/// quadrature (the floor of the standard one is amplified by the contrast).
#[test]
fn high_contrast_advises_accurate_quadrature() {
    let dir = tmpdir("cli-contrast");
    let msh = stacked_blocks(4).save(&dir, "m.msh");
    let stiff = STACKED_SCENE.replacen("young = 1.0", "young = 1e5", 1);
    let (code, out, err) = check(&dir, &stiff, &msh);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("advice") && out.contains("accurate"), "{out}");
    let accurate = format!("{stiff}\n[solve]\nquadrature = \"accurate\"\n");
    let (_, out, _) = check(&dir, &accurate, &msh);
    assert!(!out.contains("advice"), "{out}");
    let (_, out, _) = check(&dir, STACKED_SCENE, &msh);
    assert!(!out.contains("advice"), "{out}");
}

#[test]
fn completions_for_every_shell() {
    for (shell, marker) in [
        ("bash", "complete -F _sgbem"),
        ("zsh", "#compdef sgbem"),
        ("fish", "complete -c sgbem"),
        ("elvish", "edit:completion:arg-completer[sgbem]"),
        ("powershell", "Register-ArgumentCompleter"),
    ] {
        let (code, out, err) = sgbem(&["completions", shell]);
        assert_eq!(code, 0, "{shell}: {err}");
        assert!(out.contains(marker), "{shell}: {out}");
        for cmd in ["run", "check", "sweep", "inspect", "export", "completions"] {
            assert!(out.contains(cmd), "{shell} completion lacks {cmd}");
        }
    }
    // The bash script loads and registers the completion of `sgbem`, and completes the
    // subcommands and `check`'s options.
    let dir = tmpdir("cli-completions");
    let (_, script, _) = sgbem(&["completions", "bash"]);
    let file = write(&dir, "sgbem.bash", &script);
    let probe = format!(
        "source {}; complete -p sgbem; COMP_WORDS=(sgbem ch); COMP_CWORD=1; _sgbem sgbem ch \
         sgbem; echo \"words: ${{COMPREPLY[*]}}\"; COMP_WORDS=(sgbem check --j); COMP_CWORD=2; \
         _sgbem sgbem --j check; echo \"options: ${{COMPREPLY[*]}}\"",
        file.display()
    );
    let out = std::process::Command::new("bash")
        .args(["-c", &probe])
        .output()
        .expect("bash");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("-F _sgbem sgbem"), "{text}");
    assert!(text.contains("words: check"), "{text}");
    assert!(text.contains("options: --json"), "{text}");
    // An unknown shell is a usage error naming the shells.
    let (code, _, err) = sgbem(&["completions", "tcsh"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("tcsh") && err.contains("bash") && err.contains("zsh"),
        "{err}"
    );
}

#[test]
fn check_json_is_the_report_as_data() {
    let dir = tmpdir("cli-check-json");
    let msh = stacked_blocks(4).save(&dir, "m.msh");
    let s = write(&dir, "scene.toml", STACKED_SCENE);
    let args = [
        "check",
        s.to_str().unwrap(),
        "--mesh",
        msh.to_str().unwrap(),
    ];
    let (code, text, err) = sgbem(&args);
    assert_eq!(code, 0, "{err}");
    let (code, out, err) = sgbem(&[&args[..], &["--json"]].concat());
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("check --json is JSON");
    // Written with the keys of every object sorted, at every depth, as always.
    let sorted = serde_json::to_string_pretty(&v).unwrap_or_default();
    assert_eq!(out, format!("{sorted}\n"));
    let names: Vec<&str> = v["bodies"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| b["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["lower", "upper"]);
    // The same figures as the text report.
    let joint = &v["interfaces"][0];
    assert_eq!(joint["name"], "joint");
    assert_eq!(joint["pairs"], 5);
    assert!(text.contains("5 pairs"), "{text}");
    assert_eq!(joint["model"], "unilateral");
    assert_eq!(joint["initial"], "closed");
    assert_eq!(joint["body_a"], "lower");
    assert_eq!(
        v["plan"]["effects"],
        serde_json::json!(["elastic", "detachment"])
    );
    assert!(text.contains("effects: elastic + detachment"), "{text}");
    let count = v["boundary_elements"]["count"].as_u64().unwrap();
    assert!(
        text.contains(&format!("boundary elements {count};")),
        "{text}"
    );
    let per_body: u64 = v["bodies"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| b["elements"].as_u64().unwrap())
        .sum();
    assert_eq!(per_body, count);
    let unknowns = v["cost"]["unknowns"].as_u64().unwrap();
    assert!(
        text.contains(&format!("({unknowns} unknowns)")),
        "{unknowns}: {text}"
    );
    let parts: Vec<&str> = v["boundary_parts"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["name"].as_str().unwrap())
        .collect();
    assert!(
        parts.contains(&"base") && parts.contains(&"top"),
        "{parts:?}"
    );
    // Errors stay messages on stderr, exit 2, nothing on stdout.
    let (code, out, err) = sgbem(&[
        "check",
        s.to_str().unwrap(),
        "--mesh",
        msh.to_str().unwrap(),
        "--json",
        "--set",
        "body.lower.poison=0.2",
    ]);
    bad(
        (code, String::new(), err),
        &["body.lower.poison", "poisson"],
    );
    assert!(out.is_empty(), "{out}");
}

/// A scene whose bodies and joint take `[defaults.body]` and `[defaults.interface]`.
const DEFAULTS_SCENE: &str = r#"
plane = "strain"
[defaults.body]
young = 1.0
poisson = 0.3
[defaults.interface]
model = "unilateral"
[boundary.base]
ux = 0.0
uy = 0.0
[boundary.top]
ty = -1.0
"#;

#[test]
fn set_on_a_defaulted_table_points_to_the_defaults() {
    let dir = tmpdir("cli-set-defaults");
    let msh = stacked_blocks(4).save(&dir, "m.msh");
    let s = write(&dir, "scene.toml", DEFAULTS_SCENE);
    let run = |sets: &[&str]| {
        let mut args = vec![
            "check",
            s.to_str().unwrap(),
            "--mesh",
            msh.to_str().unwrap(),
        ];
        for set in sets {
            args.extend(["--set", set]);
        }
        sgbem(&args)
    };
    let (code, out, err) = run(&[]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("joint"), "{out}");
    let (code, out, err) = run(&["interface.joint.cohesion=0.5"]);
    assert!(!err.contains("missing field"), "{err}");
    bad(
        (code, out, err.clone()),
        &[
            "scene.toml",
            "--set interface.joint.cohesion=0.5",
            "[defaults.interface]",
            "--set defaults.interface.cohesion=0.5",
        ],
    );
    let (code, out, err) = run(&["body.upper.young=2.0"]);
    bad(
        (code, out, err),
        &["[defaults.body]", "--set defaults.body.young=2.0"],
    );
    // The fix it names works, and sets the value.
    let (code, out, err) = run(&["defaults.interface.cohesion=0.5"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("cohesion 0.5"), "{out}");
    // A whole new table is still accepted, and a declared one is set as before.
    let (code, _, err) = run(&[
        "interface.joint.model=unilateral",
        "interface.joint.cohesion=0.5",
    ]);
    assert_eq!(code, 0, "{err}");
    let declared = format!("{DEFAULTS_SCENE}[interface.joint]\nmodel = \"unilateral\"\n");
    let s2 = write(&dir, "declared.toml", &declared);
    let (code, out, err) = sgbem(&[
        "check",
        s2.to_str().unwrap(),
        "--mesh",
        msh.to_str().unwrap(),
        "--set",
        "interface.joint.cohesion=0.25",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("cohesion 0.25"), "{out}");
}

/// Progress that moves, seen on a terminal (a pseudo-terminal from `script`): the assembly
/// bar counts the bodies as they are done, and the contact bar's message follows the outer
/// iterations of the load step (before, the bars sat at 0/N and "load step 1" until each
/// stage ended).
#[test]
fn progress_moves_on_a_terminal() {
    let dir = support::tmpdir("progress_pty");
    let out = dir.join("run");
    let log = dir.join("terminal.log");
    let scene = support::root().join("pipelines/wall_running_bond.toml");
    let command = format!(
        "'{}' run '{}' --set mesh.courses=12 --set mesh.bricks=12 --set output.history=final \
         --set output.vtk=false --out '{}'",
        env!("CARGO_BIN_EXE_sgbem"),
        scene.display(),
        out.display()
    );
    let text = on_a_terminal(&command, &log);
    let frames: Vec<&str> = text.split(['\r', '\n']).collect();
    let distinct = |word: &str, pick: &dyn Fn(&str) -> Option<String>| {
        let mut seen: Vec<String> = frames
            .iter()
            .filter(|f| f.contains(word))
            .filter_map(|f| pick(f))
            .collect();
        seen.sort();
        seen.dedup();
        seen
    };
    // "assemble [===   ] 57/150 last done: brick_12": the counts drawn.
    let counts = distinct("assemble", &|f| {
        f.split_whitespace()
            .find(|w| w.contains('/') && w.split('/').all(|n| n.parse::<u32>().is_ok()))
            .map(str::to_string)
    });
    assert!(counts.len() >= 3, "assembly counts drawn: {counts:?}");
    let pairs: Vec<(u32, u32)> = counts
        .iter()
        .map(|c| {
            let (a, b) = c.split_once('/').unwrap();
            (a.parse().unwrap(), b.parse().unwrap())
        })
        .collect();
    let bodies = pairs[0].1;
    assert!(pairs.iter().all(|p| p.1 == bodies), "{counts:?}");
    assert!(pairs.iter().any(|p| 0 < p.0 && p.0 < bodies), "{counts:?}");
    let outer = distinct("contact", &|f| {
        let i = f.find("outer iteration ")?;
        Some(f[i..].split(':').next()?.to_string())
    });
    assert!(outer.len() >= 2, "outer iterations drawn: {outer:?}");
}

/// The full rows (the default of a wall whose joints meet at T-junctions) on a terminal: the
/// contact bar's message follows each convex programme with its open and slipping rows and
/// the residual of Coulomb's law (before, it stayed on the seed's last message for the whole
/// step: 16 s on the stone wall), and once the residual has fallen over 5 programmes, how
/// many more it needs at that rate (an upper bound: the linear solve of the statuses ends
/// most steps sooner). A 4 × 5 wall at 0.63 of its weight sideways, near its collapse: 9
/// programmes (at half its weight the linear solve settles the step after the first since
/// the local Tresca step of docs/formulation.md §6.10; it took 15 before).
#[test]
fn the_full_rows_show_each_programme_on_a_terminal() {
    let text = run_on_a_terminal(
        "progress_exact_pty",
        "wall_running_bond",
        "--set mesh.courses=4 --set mesh.bricks=5 --set 'defaults.body.body_force=[12.6,-20.0]' \
         --set output.history=final --set output.vtk=false",
    );
    let mut shown: Vec<&str> = text
        .split(['\r', '\n'])
        .filter(|f| f.contains("contact [") && f.contains("Coulomb residual"))
        .filter_map(|f| f.split("convex programme ").nth(1)?.split(':').next())
        .collect();
    shown.sort();
    shown.dedup();
    assert!(shown.len() >= 3, "programmes drawn: {shown:?}");
    assert!(shown.contains(&"1"), "{shown:?}");
    assert!(text.contains("normal rows open"), "{text}");
    // Once the residual has fallen over 5 programmes, the programmes left at its rate.
    let left: Vec<usize> = text
        .split(['\r', '\n'])
        .filter_map(|f| {
            f.split("settled in about ")
                .nth(1)?
                .split(' ')
                .next()?
                .parse()
                .ok()
        })
        .collect();
    assert!(!left.is_empty() && left.iter().all(|&n| n >= 1), "{text}");
}

/// `sgbem run` of the shipped scene `scene` with `args` under a pseudo-terminal, into a
/// fresh folder named `tmp`: what was drawn.
fn run_on_a_terminal(tmp: &str, scene: &str, args: &str) -> String {
    let dir = support::tmpdir(tmp);
    let scene = support::root().join(format!("pipelines/{scene}.toml"));
    let command = format!(
        "'{}' run '{}' {args} --out '{}'",
        env!("CARGO_BIN_EXE_sgbem"),
        scene.display(),
        dir.join("run").display()
    );
    on_a_terminal(&command, &dir.join("terminal.log"))
}

/// Runs `command` under a pseudo-terminal (`script`), its terminal's bytes logged to `log`:
/// what was drawn.
fn on_a_terminal(command: &str, log: &std::path::Path) -> String {
    let status = std::process::Command::new("script")
        .args(["-qfec", command, log.to_str().unwrap()])
        .stdout(std::process::Stdio::null())
        .status()
        .expect("script (util-linux) runs");
    assert!(status.success(), "{status}");
    String::from_utf8_lossy(&std::fs::read(log).unwrap()).into_owned()
}

/// A collapse search on a terminal: the contact bar first counts the search's trials (10
/// for max 2 bisected to 0.01), names each trial and its multiplier, gives the time left
/// once a trial is done, then counts the load step of the run at the multiplier found.
#[test]
fn a_collapse_search_counts_its_trials_on_a_terminal() {
    let text = run_on_a_terminal(
        "progress_collapse_pty",
        "wall_collapse",
        "--set mesh.courses=3 --set mesh.bricks=3 --set solve.collapse.tolerance=0.01 \
         --set output.vtk=false",
    );
    let frames: Vec<&str> = text.split(['\r', '\n']).collect();
    let search: Vec<&str> = frames
        .iter()
        .copied()
        .filter(|f| f.contains("collapse [") && f.contains("trial "))
        .collect();
    assert!(search.iter().all(|f| f.contains("/10 ")), "{search:?}");
    let mut trials: Vec<&str> = search
        .iter()
        .filter_map(|f| f.split("trial ").nth(1)?.split(':').next())
        .collect();
    trials.sort();
    trials.dedup();
    assert!(trials.contains(&"1 at t = 0"), "{trials:?}");
    assert!(trials.contains(&"2 at t = 2"), "{trials:?}");
    assert!(trials.len() >= 4, "{trials:?}");
    assert!(search.iter().any(|f| f.contains(" left")), "{search:?}");
    // The run at the multiplier: the contact bar again, one load step.
    let last = frames
        .iter()
        .rev()
        .find(|f| f.contains("contact [") || f.contains("collapse ["))
        .unwrap();
    assert!(
        last.contains("contact [") && last.contains("1/1 "),
        "{last}"
    );
}

/// `sgbem man`: a manual page that groff formats without a warning, with every subcommand
/// and every long option of the command line in it.
#[test]
fn man_page_lists_every_command_and_option() {
    let (code, page, err) = support::sgbem(&["man"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        page.starts_with(".TH SGBEM 1 "),
        "{}",
        &page[..80.min(page.len())]
    );
    for sub in [
        "run",
        "check",
        "sweep",
        "inspect",
        "export",
        "completions",
        "man",
        "schema",
    ] {
        assert!(page.contains(&format!(".SS \"sgbem {sub}\"")), "no {sub}");
    }
    for opt in [
        "set", "out", "mesh", "method", "quiet", "jobs", "list", "point", "columns",
    ] {
        assert!(page.contains(&format!("\\fB\\-\\-{opt}\\fR")), "no --{opt}");
    }
    // groff, where installed (man-db's formatter), reads it without a warning.
    let dir = support::tmpdir("man_page");
    let path = support::write(&dir, "sgbem.1", &page);
    match std::process::Command::new("groff")
        .args(["-man", "-Tutf8", "-ww", path.to_str().unwrap()])
        .output()
    {
        Ok(o) => {
            assert!(o.status.success());
            assert!(
                o.stderr.is_empty(),
                "{}",
                String::from_utf8_lossy(&o.stderr)
            );
            // Bold is overstruck (X, backspace, X): keep the last of each.
            let raw: Vec<char> = String::from_utf8_lossy(&o.stdout).chars().collect();
            let text: String = (0..raw.len())
                .filter(|&i| raw[i] != '\u{8}' && raw.get(i + 1) != Some(&'\u{8}'))
                .map(|i| raw[i])
                .collect();
            assert!(
                text.contains("EXIT STATUS") && text.contains("--columns"),
                "{text}"
            );
        }
        Err(_) => eprintln!("groff not installed: the page was not formatted (skipped)"),
    }
}

/// `check --method` plans and costs the run that `run --method` makes (the same report as
/// the scene key `solve.method`); a many-body scene's loaded bodies are counted, not listed
/// (the 798-brick wall printed 798 names on one line).
#[test]
fn check_plans_the_method_of_the_command_line() {
    let scene = root().join("pipelines/wall_running_bond.toml");
    let s = scene.to_str().unwrap();
    let (code, default, err) = sgbem(&["check", s]);
    assert_eq!(code, 0, "{err}");
    // Without `method`: the full rows, since the wall's joints meet at T-junctions (said).
    assert!(default.contains("contact_exact"), "{default}");
    assert!(
        default.contains("chosen because unilateral joints meet at junctions"),
        "{default}"
    );
    for m in ["exact", "sparse", "qp", "lcp"] {
        let (code, by_flag, err) = sgbem(&["check", s, "--method", m]);
        assert_eq!(code, 0, "{err}");
        assert!(by_flag.contains(&format!("contact_{m}")), "{m}: {by_flag}");
        assert!(!by_flag.contains("chosen because"), "{m}: {by_flag}");
        if m != "lcp" {
            assert!(!by_flag.contains("contact_lcp "), "{m}: {by_flag}");
        }
        let key = format!("solve.method=\"{m}\"");
        let (_, by_key, _) = sgbem(&["check", s, "--set", &key]);
        // The same report but for the temporary folder of the .geo's mesh.
        let lines = |t: &str| -> Vec<String> {
            t.lines()
                .filter(|l| !l.starts_with("mesh ") && !l.starts_with("overrides "))
                .map(String::from)
                .collect()
        };
        assert!(lines(&by_flag) == lines(&by_key), "{m}");
    }
    assert!(
        default
            .contains("body-force loads for 105 bodies (brick_1, brick_2, brick_3, …, brick_105)"),
        "{default}"
    );
    let (code, _, err) = sgbem(&["check", s, "--method", "newton"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("newton") && err.contains("exact"), "{err}");
}
