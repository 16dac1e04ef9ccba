//! Scenes for many bodies: glob tables, defaults, and Physical Curves that join many pairs of
//! bodies (split per pair). Meshes come from `geo/arch.geo` (voussoir_1..N, abutment_L/R,
//! one Physical Curve "joints" for every joint).

mod support;

use sgbem::pipeline::{load, Loaded};
use support::*;

/// Meshes the arch with `nv` voussoirs and `nj` elements per joint.
fn arch_mesh(dir: &std::path::Path, nv: usize, nj: usize) -> std::path::PathBuf {
    let (nv, nj) = (nv.to_string(), nj.to_string());
    gmsh(
        &root().join("geo/arch.geo"),
        dir,
        "arch.msh",
        false,
        &["-setnumber", "nv", &nv, "-setnumber", "nj", &nj],
    )
}

const HEAD: &str = "plane = \"strain\"\n[boundary.base]\nux = 0.0\nuy = 0.0\n";
const JOINTS: &str = "[defaults.interface]\nmodel = \"unilateral\"\n";

fn body(table: &str, young: f64) -> String {
    format!("[{table}]\nyoung = {young}\npoisson = 0.2\n")
}

/// Loads `scene` on an arch of `nv` voussoirs.
fn try_load(name: &str, nv: usize, scene: &str) -> sgbem::error::Result<Loaded> {
    let dir = tmpdir(name);
    let msh = arch_mesh(&dir, nv, 2);
    let path = write(&dir, "scene.toml", scene);
    load(&path, Some(&msh))
}

fn loaded(name: &str, nv: usize, scene: &str) -> Loaded {
    try_load(name, nv, scene).unwrap_or_else(|e| panic!("{e}"))
}

fn failure(name: &str, nv: usize, scene: &str) -> String {
    match try_load(name, nv, scene) {
        Ok(_) => panic!("expected an input error for\n{scene}"),
        Err(e) => {
            assert_eq!(e.exit_code(), 2, "{e}");
            e.to_string()
        }
    }
}

fn young_of(l: &Loaded, name: &str) -> f64 {
    l.model
        .bodies
        .iter()
        .find(|b| b.name == name)
        .unwrap_or_else(|| panic!("no body {name}"))
        .young
}

fn table_of(l: &Loaded, group: &str) -> String {
    l.model
        .tables
        .iter()
        .find(|r| r.group == group)
        .unwrap_or_else(|| panic!("no table for {group}"))
        .table
        .clone()
}

#[test]
fn exact_name_beats_the_most_specific_glob_which_beats_defaults() {
    let scene = [
        HEAD,
        JOINTS,
        &body("body.\"voussoir_*\"", 2.0),
        &body("body.\"voussoir_1*\"", 3.0),
        &body("body.voussoir_11", 4.0),
        &body("defaults.body", 5.0),
        &body("body.\"*\"", 6.0),
    ]
    .concat();
    let l = loaded("tables-rank", 12, &scene);
    assert_eq!(l.model.bodies.len(), 14);
    // exact > `voussoir_1*` (10 literal characters) > `voussoir_*` (9) > `*` (0) > defaults
    assert_eq!(young_of(&l, "voussoir_11"), 4.0);
    for v in ["voussoir_1", "voussoir_10", "voussoir_12"] {
        assert_eq!(young_of(&l, v), 3.0, "{v}");
        assert_eq!(table_of(&l, v), "[body.\"voussoir_1*\"]");
    }
    for v in 2..=9 {
        assert_eq!(young_of(&l, &format!("voussoir_{v}")), 2.0);
    }
    // `*` matches the abutments, so the defaults apply to nothing here.
    assert_eq!(young_of(&l, "abutment_L"), 6.0);
    assert_eq!(table_of(&l, "abutment_R"), "[body.\"*\"]");
    assert_eq!(table_of(&l, "voussoir_11"), "[body.voussoir_11]");
    assert_eq!(table_of(&l, "joints"), "[defaults.interface]");
    // Exact tables first (scene order), then the mesh's order.
    assert_eq!(l.model.bodies[0].name, "voussoir_11");
    assert_eq!(l.model.bodies[1].name, "voussoir_1");
}

#[test]
fn defaults_apply_to_bodies_and_shared_curves_not_listed() {
    let scene = [
        HEAD,
        &body("body.\"voussoir_*\"", 2.0),
        &body("defaults.body", 5.0),
        "[interface.joints]\nmodel = \"bonded\"\n",
        // Applies to no curve: every shared curve is listed.
        "[defaults.interface]\nmodel = \"unilateral\"\ntangential = \"slide\"\n",
    ]
    .concat();
    let l = loaded("tables-defaults", 3, &scene);
    assert_eq!(young_of(&l, "abutment_L"), 5.0);
    assert_eq!(young_of(&l, "abutment_R"), 5.0);
    assert_eq!(table_of(&l, "abutment_L"), "[defaults.body]");
    assert_eq!(table_of(&l, "joints"), "[interface.joints]");
    assert!(l
        .model
        .interfaces
        .iter()
        .all(|i| i.spec.model == sgbem::input::scene::InterfaceModel::Bonded));
    // The free curves (intrados, extrados, abutment faces) stay traction-free boundaries.
    let free: Vec<&str> = l
        .model
        .parts
        .iter()
        .filter(|p| !p.listed)
        .map(|p| p.spec.name.as_str())
        .collect();
    assert_eq!(free, ["intrados", "extrados", "abutment_faces"]);

    // Without [defaults.interface] the shared curve must be listed.
    let m = failure(
        "tables-no-default",
        3,
        &[HEAD, &body("defaults.body", 5.0)].concat(),
    );
    assert!(
        m.contains("\"joints\"")
            && m.contains("[interface.joints]")
            && m.contains("[defaults.interface]"),
        "{m}"
    );
}

#[test]
fn equally_specific_globs_that_differ_are_an_error_naming_both() {
    let conflicting = [
        HEAD,
        JOINTS,
        &body("defaults.body", 1.0),
        &body("body.\"voussoir_1?\"", 2.0),
        &body("body.\"voussoir_?1\"", 3.0),
    ]
    .concat();
    let m = failure("tables-conflict", 11, &conflicting);
    assert!(
        m.contains("\"voussoir_11\"")
            && m.contains("[body.\"voussoir_1?\"]")
            && m.contains("[body.\"voussoir_?1\"]")
            && m.contains("[body.voussoir_11]"),
        "{m}"
    );
    // The same contents are no conflict, and an exact table settles a real one.
    let same = conflicting.replace("young = 3\n", "young = 2\n");
    assert_eq!(
        young_of(&loaded("tables-same", 11, &same), "voussoir_11"),
        2.0
    );
    let settled = [&conflicting, body("body.voussoir_11", 7.0).as_str()].concat();
    let l = loaded("tables-settled", 11, &settled);
    assert_eq!(young_of(&l, "voussoir_11"), 7.0);
    assert_eq!(young_of(&l, "voussoir_10"), 2.0);
}

#[test]
fn globs_that_match_nothing_or_the_wrong_kind_are_errors() {
    let base = [HEAD, JOINTS, &body("defaults.body", 1.0)].concat();
    let m = failure(
        "tables-typo",
        3,
        &[&base, body("body.\"vousoir_*\"", 2.0).as_str()].concat(),
    );
    assert!(
        m.contains("[body.\"vousoir_*\"] matches no Physical Surface") && m.contains("voussoir_1"),
        "{m}"
    );
    let m = failure(
        "tables-free-curve",
        3,
        &[&base, "[interface.\"*dos\"]\nmodel = \"bonded\"\n"].concat(),
    );
    assert!(
        m.contains("[interface.\"*dos\"]") && m.contains("which no two bodies share"),
        "{m}"
    );
    let m = failure(
        "tables-bad-pattern",
        3,
        &[&base, body("body.\"v[12]*\"", 2.0).as_str()].concat(),
    );
    assert!(m.contains("body.\"v[12]*\"") && m.contains("`[`"), "{m}");
    let m = failure(
        "tables-bad-default",
        3,
        &[&base, "[defaults.boundary]\nux = 0.0\n"].concat(),
    );
    assert!(m.contains("unknown key `defaults.boundary`"), "{m}");
    let m = failure(
        "tables-bad-default-key",
        3,
        &base.replace("young = 1\n", "yung = 1\n"),
    );
    assert!(m.contains("defaults.body.yung"), "{m}");
}

#[test]
fn a_curve_joining_many_pairs_is_split_per_pair() {
    let scene = [HEAD, JOINTS, &body("defaults.body", 1.0)].concat();
    let dir = tmpdir("tables-split");
    let msh = arch_mesh(&dir, 5, 3);
    let l = load(&write(&dir, "scene.toml", &scene), Some(&msh)).unwrap_or_else(|e| panic!("{e}"));
    let m = &l.model;
    // 4 joints between voussoirs and 2 springings, each 3 elements and 4 pairs.
    assert_eq!(m.interfaces.len(), 6);
    let mut names: Vec<String> = Vec::new();
    for i in &m.interfaces {
        assert_eq!(i.group, "joints");
        let (a, b) = (&m.bodies[i.body_a].name, &m.bodies[i.body_b].name);
        assert_eq!(i.spec.name, format!("joints[{a}|{b}]"));
        assert_eq!((i.elements.len(), i.pairs.len()), (3, 4), "{}", i.spec.name);
        assert!((i.length - 0.6).abs() < 1e-12, "{}", i.length);
        names.push(i.spec.name.clone());
    }
    names.sort();
    assert_eq!(
        names,
        [
            "joints[voussoir_1|abutment_L]",
            "joints[voussoir_1|voussoir_2]",
            "joints[voussoir_2|voussoir_3]",
            "joints[voussoir_3|voussoir_4]",
            "joints[voussoir_4|voussoir_5]",
            "joints[voussoir_5|abutment_R]",
        ]
    );
    // Each interface's elements lie on its two bodies only.
    for (k, i) in m.interfaces.iter().enumerate() {
        for (bi, b) in m.bodies.iter().enumerate() {
            let on = b
                .elements
                .iter()
                .filter(|e| e.role == sgbem::input::model::Role::Interface(k))
                .count();
            let expect = if bi == i.body_a || bi == i.body_b {
                3
            } else {
                0
            };
            assert_eq!(on, expect, "{} on {}", i.spec.name, b.name);
        }
    }

    // `sgbem check` names the parts and prints which table applies to each group.
    let (code, out, err) = sgbem(&[
        "check",
        write(&dir, "scene.toml", &scene)
            .to_str()
            .unwrap_or_default(),
        "--mesh",
        msh.to_str().unwrap_or_default(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("interfaces (6)"), "{out}");
    assert!(
        out.contains("joints[voussoir_2|voussoir_3] unilateral"),
        "{out}"
    );
    assert!(
        out.contains("tables (exact name > most specific pattern > defaults)"),
        "{out}"
    );
    let line = out
        .lines()
        .find(|l| l.trim_start().starts_with("[defaults.body]"))
        .unwrap_or_else(|| panic!("{out}"));
    assert!(
        line.contains("voussoir_1, voussoir_2") && line.ends_with("(7)"),
        "{line}"
    );
}

/// Loads `pipelines/wall.toml` on `geo/wall.geo` meshed with `opts`.
fn wall(name: &str, opts: &[&str]) -> Loaded {
    let dir = tmpdir(name);
    let msh = gmsh(&root().join("geo/wall.geo"), &dir, "wall.msh", false, opts);
    load(&root().join("pipelines/wall.toml"), Some(&msh)).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn the_wall_generator_cuts_bed_joints_at_every_head_joint() {
    // Running bond, 3 courses of 2 bricks: 2 + 3 + 2 bricks; head joints 1 + 2 + 1; each bed
    // line between courses cut at 0, 0.2, 0.4, 0.6, 0.8 into 4 pieces, one per pair of
    // bricks (half a brick long).
    let l = wall(
        "wall-running",
        &["-setnumber", "courses", "3", "-setnumber", "bricks", "2"],
    );
    let m = &l.model;
    assert_eq!(m.bodies.len(), 7);
    assert_eq!(m.interfaces.len(), 12);
    let (mut heads, mut beds) = (0, 0);
    for i in &m.interfaces {
        let horizontal = i
            .pairs
            .iter()
            .all(|p| (p.x[1] - i.pairs[0].x[1]).abs() < 1e-12);
        // Head joints a brick high, bed pieces half a brick wide: 0.2 m, 4 elements each.
        assert!(
            (i.length - 0.2).abs() < 1e-12,
            "{}: {}",
            i.spec.name,
            i.length
        );
        assert_eq!(i.pairs.len(), 5, "{}", i.spec.name);
        if horizontal {
            beds += 1;
        } else {
            heads += 1;
        }
    }
    assert_eq!((heads, beds), (4, 8));
    // brick_3 (the half brick starting course 2) sits on brick_1 and holds up brick_6.
    let names: Vec<&str> = m.interfaces.iter().map(|i| i.spec.name.as_str()).collect();
    for n in [
        "joints[brick_1|brick_3]",
        "joints[brick_3|brick_4]",
        "joints[brick_3|brick_6]",
    ] {
        assert!(names.contains(&n), "{n} not in {names:?}");
    }
    let base: f64 = m
        .parts
        .iter()
        .filter(|p| p.spec.name == "base")
        .map(|p| p.length)
        .sum();
    assert!((base - 0.8).abs() < 1e-12, "{base}");

    // Stack bond, bricks 2..3 of courses 2..3 left out: 4 × 3 − 4 bricks; the opening (a
    // notch, open at the wall's right end) has its own free Physical Curve: 0.8 below, 0.8
    // above, 0.4 on the left.
    let l = wall(
        "wall-opening",
        &[
            "-setnumber",
            "courses",
            "4",
            "-setnumber",
            "bricks",
            "3",
            "-setnumber",
            "bond",
            "0",
            "-setnumber",
            "open_from",
            "2",
            "-setnumber",
            "open_to",
            "3",
            "-setnumber",
            "open_col",
            "2",
            "-setnumber",
            "open_w",
            "2",
        ],
    );
    assert_eq!(l.model.bodies.len(), 8);
    let opening = l
        .model
        .parts
        .iter()
        .find(|p| p.spec.name == "opening")
        .expect("an opening curve");
    assert!((opening.length - 2.0).abs() < 1e-12, "{}", opening.length);
}
