//! Output writers on small fabricated records: the archive layout (groups, shapes,
//! attributes, read back with hdf5-metno), archive → read → export giving byte-identical VTK
//! files, atomic writes, and errors (never panics) on damaged archives.

mod support;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use hdf5_metno as h5;
use sgbem::input::scene::{Plane, Units};
use sgbem::output::archive::{read_archive, write_archive, ArchivePart, ArchiveWriter, FORMAT};
use sgbem::output::record::{
    Array, BodyOperators, BodyRecord, InterfaceRecord, InteriorRecord, IterateRecord, MeshRecord,
    RunRecord, FORMAT_VERSION,
};
use sgbem::output::vtk::{export, write_vtk};
use sgbem::solution::{BodyField, BodyMotion, HistoryRow, InterfaceResult, PairResult, PairStatus};
use support::{
    mechanism_block, read_summary, run_shipped, sgbem, stacked_blocks, tmpdir, STACKED_SCENE,
};

/// A deterministic "random" value in [-1, 1).
fn val(k: usize) -> f64 {
    let x = (k as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 11;
    2.0 * (x as f64 / (1u64 << 53) as f64) - 1.0
}

fn matrix(rows: usize, cols: usize, seed: usize) -> Array {
    Array::matrix(
        rows,
        cols,
        (0..rows * cols).map(|k| val(seed * 7919 + k)).collect(),
    )
}

/// Two unit squares stacked along y (lower [0,1]², upper [0,1]×[1,2]) with one interface
/// `joint`, a centre node in each, three states (the last with interior values), three
/// history rows, operators and timings.
fn fabricated(big_operator: usize) -> RunRecord {
    let mut r = RunRecord::empty("Two blocks, fabricated", Plane::Strain);
    r.scene_text = "title = \"Two blocks\"\n[body.lower]\nyoung = 1.0\n".into();
    r.mesh_sha256 = "ab".repeat(32);
    r.units = Units {
        length: "cm".into(),
        force: "daN".into(),
    };
    r.thickness = 2.5;
    r.created = "2025-01-31T12:00:00Z".into();
    let nodes = vec![
        [0.0, 0.0],
        [1.0, 0.0],
        [1.0, 1.0],
        [0.0, 1.0],
        [1.0, 2.0],
        [0.0, 2.0],
        [0.5, 0.5],
        [0.5, 1.5],
    ];
    r.mesh = MeshRecord {
        node_tags: (1..=nodes.len()).collect(),
        nodes,
        lines: vec![[0, 1], [1, 2], [2, 3], [3, 0], [2, 4], [4, 5], [5, 3]],
        line_group: vec![
            Some(0),
            Some(1),
            Some(2),
            Some(1),
            Some(1),
            Some(3),
            Some(1),
        ],
        triangles: vec![
            [0, 1, 6],
            [1, 2, 6],
            [2, 3, 6],
            [3, 0, 6],
            [3, 2, 7],
            [2, 4, 7],
            [4, 5, 7],
            [5, 3, 7],
        ],
        triangle_group: vec![
            Some(4),
            Some(4),
            Some(4),
            Some(4),
            None,
            Some(5),
            Some(5),
            Some(5),
        ],
        group_names: ["base", "sides", "joint", "top", "lower", "upper"]
            .map(String::from)
            .to_vec(),
        group_dims: vec![1, 1, 1, 1, 2, 2],
    };
    let square = |y0: f64| vec![[0.0, y0], [1.0, y0], [1.0, y0 + 1.0], [0.0, y0 + 1.0]];
    let elements = vec![[0, 1], [1, 2], [2, 3], [3, 0]];
    let n0 = big_operator.max(3);
    r.bodies = vec![
        BodyRecord {
            name: "lower".into(),
            young: 5000.0,
            poisson: 0.2,
            body_force: Some([0.0, -0.0018]),
            nodes: square(0.0),
            mesh_nodes: vec![0, 1, 2, 3],
            elements: elements.clone(),
            triangles: r.mesh.triangles[..4].to_vec(),
            operators: Some(BodyOperators {
                unknowns: (0..5 + n0).map(|i| format!("unknown {i}")).collect(),
                n_x: 5,
                a: matrix(5, 5, 1),
                a0: matrix(5, n0, 2),
                a00: matrix(n0, n0, 3),
                load: (0..5 + n0).map(|k| val(100 + k)).collect(),
                d00: matrix(n0, n0, 4),
                z0: (0..n0).map(|k| val(200 + k)).collect(),
            }),
        },
        BodyRecord {
            name: "upper/part".into(),
            young: 1e4,
            poisson: 0.3,
            body_force: None,
            nodes: square(1.0),
            mesh_nodes: vec![3, 2, 4, 5],
            elements,
            triangles: r.mesh.triangles[4..].to_vec(),
            operators: None,
        },
    ];
    r.interfaces = vec![InterfaceRecord {
        name: "joint".into(),
        body_a: 0,
        body_b: 1,
        model: "unilateral".into(),
        initial: "closed".into(),
        tangential: "stick".into(),
        node_a: vec![3, 2],
        node_b: vec![0, 1],
        x: vec![[0.0, 1.0], [1.0, 1.0]],
        normal: vec![[0.0, 1.0]; 2],
        tangent: vec![[-1.0, 0.0]; 2],
        s: vec![0.0, 1.0],
        gap: vec![0.0, 0.01],
        cohesion: vec![0.5, 0.5],
        elements: vec![[1, 0]],
        pairing: None,
    }];
    let statuses = [
        [PairStatus::Closed, PairStatus::Closed],
        [PairStatus::Closed, PairStatus::Open],
        [PairStatus::Open, PairStatus::Open],
    ];
    for (k, st) in statuses.iter().enumerate() {
        let seed = 1000 * (k + 1);
        let fields = (0..2)
            .map(|b| BodyField {
                u: (0..4)
                    .map(|i| [val(seed + 10 * b + 2 * i), val(seed + 10 * b + 2 * i + 1)])
                    .collect(),
                t: (0..4)
                    .map(|e| {
                        let s = seed + 100 + 20 * b + 4 * e;
                        [[val(s), val(s + 1)], [val(s + 2), val(s + 3)]]
                    })
                    .collect(),
                ..Default::default()
            })
            .collect();
        let pairs = (0..2)
            .map(|j| PairResult {
                status: st[j],
                traction: [val(seed + 500 + j), val(seed + 510 + j)],
                jump: [val(seed + 520 + j), val(seed + 530 + j)],
                slipping: None,
                slip: 0.0,
            })
            .collect();
        let mut state = IterateRecord::new(k, 0, 1.0, fields, vec![InterfaceResult { pairs }]);
        if k == 2 {
            state.interior = (0..2)
                .map(|b| {
                    let ids: Vec<usize> = if b == 0 {
                        vec![0, 1, 2, 3, 6]
                    } else {
                        vec![2, 3, 4, 5, 7]
                    };
                    InteriorRecord {
                        u: ids.iter().map(|&m| [val(m), val(m + 50)]).collect(),
                        sigma: ids
                            .iter()
                            .map(|&m| [val(m + 60), val(m + 70), val(m + 80)])
                            .collect(),
                        mesh_nodes: ids,
                    }
                })
                .collect();
        }
        r.states.push(state);
        r.history.rows.push(HistoryRow {
            load_step: 0,
            load_factor: 1.0,
            iteration: k,
            solver: "lcp",
            status: vec![st.to_vec()],
            normal_traction: vec![vec![val(seed + 600), val(seed + 601)]],
            normal_opening: vec![vec![0.0, val(seed + 602).abs()]],
            detached_length: vec![[0.0, 0.0, 1.0][k]],
        });
    }
    r.contact_operators = Some(vec![
        ("K00".into(), matrix(4, 4, 9)),
        ("Ktilde_urur".into(), matrix(2, 2, 10)),
        ("L".into(), Array::vector(vec![1.0, 2.0, 3.0, 4.0])),
    ]);
    r.status = "converged".into();
    r.timings = vec![
        ("read".into(), 0.001),
        ("assemble".into(), 0.5),
        ("write".into(), 0.02),
    ];
    r.summary_json = "{\"title\": \"Two blocks, fabricated\", \"status\": \"converged\"}".into();
    r
}

fn files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .expect("read dir")
        .map(|e| {
            let p = e.expect("entry").path();
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read(&p).expect("read"),
            )
        })
        .collect()
}

/// A string attribute, which must be fixed-length (no global heap).
fn attr_string(loc: &h5::Location, name: &str) -> String {
    let a = loc.attr(name).unwrap();
    match a.dtype().unwrap().to_descriptor().unwrap() {
        h5::types::TypeDescriptor::FixedUnicode(n) if n <= 1 << 16 => {
            let v: h5::types::FixedUnicode<65536> = a.read_scalar().unwrap();
            v.as_str().to_string()
        }
        d => panic!("attribute {name} is {d}, not a fixed-length string"),
    }
}

#[test]
fn archive_layout_attributes_and_shapes() {
    let dir = tmpdir("outputs-layout");
    let path = dir.join("archive.h5");
    let rec = fabricated(3);
    write_archive(&path, &rec).expect("write");
    let f = h5::File::open(&path).expect("open");
    assert_eq!(attr_string(&f, "format"), FORMAT);
    let v: i64 = f.attr("format_version").unwrap().read_scalar().unwrap();
    assert_eq!(v, FORMAT_VERSION);
    assert_eq!(attr_string(&f, "tool_version"), env!("CARGO_PKG_VERSION"));
    // The date sits with the timings, the only parts that differ between identical runs.
    assert!(f.attr("created").is_err(), "created is a root attribute");
    let timings = f.group("timings").unwrap();
    assert_eq!(attr_string(&timings, "created"), "2025-01-31T12:00:00Z");
    assert_eq!(attr_string(&f, "overrides"), "[]");
    assert_eq!(attr_string(&f, "scene"), rec.scene_text);
    assert_eq!(attr_string(&f, "mesh_sha256"), rec.mesh_sha256);
    let units: serde_json::Value = serde_json::from_str(&attr_string(&f, "units")).unwrap();
    assert_eq!(units["length"], "cm");
    assert_eq!(units["force"], "daN");

    let shape = |p: &str| f.dataset(p).unwrap_or_else(|_| panic!("{p}")).shape();
    assert_eq!(shape("mesh/nodes"), [8, 2]);
    assert_eq!(shape("mesh/lines"), [7, 2]);
    assert_eq!(shape("mesh/line_group"), [7]);
    assert_eq!(shape("mesh/group_names"), [6]);
    assert_eq!(shape("mesh/triangles"), [8, 3]);
    assert_eq!(shape("bodies/lower/nodes"), [4, 2]);
    assert_eq!(shape("bodies/lower/elements"), [4, 2]);
    assert_eq!(shape("bodies/lower/A"), [5, 5]);
    assert_eq!(shape("bodies/lower/A0"), [5, 3]);
    assert_eq!(shape("bodies/lower/D00"), [3, 3]);
    assert_eq!(shape("bodies/lower/Z0"), [3]);
    // A name with a slash becomes a group with the slash replaced; its name is kept.
    let upper = f.group("bodies/upper_part").unwrap();
    assert_eq!(attr_string(&upper, "name"), "upper/part");
    assert!(
        !upper.link_exists("D00"),
        "no operators were given for upper"
    );
    let young: f64 = f
        .group("bodies/lower")
        .unwrap()
        .attr("young")
        .unwrap()
        .read_scalar()
        .unwrap();
    assert_eq!(young, 5000.0);
    assert_eq!(shape("interfaces/joint/x"), [2, 2]);
    assert_eq!(shape("interfaces/joint/normal"), [2, 2]);
    assert_eq!(shape("interfaces/joint/gap"), [2]);
    assert_eq!(shape("interfaces/joint/cohesion"), [2]);
    assert_eq!(
        attr_string(&f.group("interfaces/joint").unwrap(), "body_b"),
        "upper/part"
    );
    assert_eq!(shape("contact/operators/K00"), [4, 4]);
    assert_eq!(shape("contact/operators/L"), [4]);
    assert_eq!(shape("history/load_factor"), [3]);
    assert_eq!(shape("history/detached_length"), [3, 1]);
    assert_eq!(shape("history/interfaces/joint/status"), [3, 2]);
    assert_eq!(shape("history/interfaces/joint/normal_traction"), [3, 2]);
    assert_eq!(shape("solution/bodies/lower/u"), [4, 2]);
    assert_eq!(shape("solution/bodies/lower/t"), [4, 2, 2]);
    assert_eq!(shape("solution/interfaces/joint/traction"), [2, 2]);
    assert_eq!(shape("solution/interior/upper_part/sigma"), [5, 3]);
    // States hold each quantity for all bodies (interfaces) in one dataset, in /bodies
    // (/interfaces) order; the offsets say where each starts.
    let n_upper = rec.bodies[1].nodes.len();
    assert_eq!(shape("states/0000/u"), [4 + n_upper, 2]);
    assert_eq!(shape("states/0000/traction"), [2, 2]);
    let offsets: Vec<u64> = f.dataset("states/node_offset").unwrap().read_raw().unwrap();
    assert_eq!(offsets, [0, 4, 4 + n_upper as u64]);
    assert!(!f.link_exists("states/0000/interior"));
    assert!(!f.link_exists("states/0000/bodies"));
    assert_eq!(shape("timings/assemble"), Vec::<usize>::new());

    // /solution is the final state.
    let u: Vec<f64> = f
        .dataset("solution/bodies/upper_part/u")
        .unwrap()
        .read_raw()
        .unwrap();
    let want: Vec<f64> = rec.states[2].fields[1]
        .u
        .iter()
        .flatten()
        .copied()
        .collect();
    assert_eq!(u, want);
    let st: Vec<i8> = f
        .dataset("history/interfaces/joint/status")
        .unwrap()
        .read_raw()
        .unwrap();
    assert_eq!(st, [1, 1, 1, 0, 0, 0]);
    let dl: Vec<f64> = f
        .dataset("history/detached_length")
        .unwrap()
        .read_raw()
        .unwrap();
    assert_eq!(dl, [0.0, 0.0, 1.0]);

    // Every dataset has a description and units.
    let mut checked = 0;
    let mut stack = vec![f.group("/").unwrap()];
    while let Some(g) = stack.pop() {
        for name in g.member_names().unwrap() {
            if let Ok(ds) = g.dataset(&name) {
                for a in ["description", "units"] {
                    assert!(ds.attr(a).is_ok(), "{}/{name} lacks {a}", g.name());
                    attr_string(&ds, a);
                }
                // Chunked with checksums, but the scalars (which cannot be).
                assert!(
                    ds.is_chunked() || ds.ndim() == 0,
                    "{}/{name} is not chunked",
                    g.name()
                );
                checked += 1;
            } else if let Ok(sub) = g.group(&name) {
                stack.push(sub);
            }
        }
    }
    assert!(checked > 60, "only {checked} datasets found");
    // Only the archive in the folder: the temporary file was renamed.
    assert_eq!(files(&dir).into_keys().collect::<Vec<_>>(), ["archive.h5"]);
}

#[test]
fn large_datasets_are_chunked_and_compressed() {
    // Compressed only with output.compress = true; chunked with checksums always.
    let dir = tmpdir("outputs-chunks");
    let plain = dir.join("plain.h5");
    write_archive(&plain, &fabricated(80)).expect("write");
    let f = h5::File::open(&plain).unwrap();
    let a00 = f.dataset("bodies/lower/A00").unwrap();
    assert!(a00.is_chunked());
    assert_eq!(a00.filters(), [h5::filters::Filter::Fletcher32]);
    drop((a00, f));
    let path = dir.join("archive.h5");
    let mut rec = fabricated(80);
    rec.compress = true;
    write_archive(&path, &rec).expect("write");
    let f = h5::File::open(&path).unwrap();
    let big = f.dataset("bodies/lower/A00").unwrap();
    assert_eq!(big.shape(), [80, 80]);
    let small = f.dataset("bodies/lower/A").unwrap();
    assert!(small.is_chunked());
    assert_eq!(small.filters(), [h5::filters::Filter::Fletcher32]);
    if h5::filters::deflate_available() {
        assert!(big.is_chunked());
        assert!(!big.filters().is_empty());
    }
    // Close the file first: HDF5 refuses to open one file twice with different locking.
    drop((big, small, f));
    let back = read_archive(&path).unwrap();
    let op = back.bodies[0].operators.as_ref().unwrap();
    assert_eq!(op.a00, matrix(80, 80, 3));
}

#[test]
fn an_archive_written_part_by_part_is_the_archive_written_at_once() {
    // The run hands its archive over in three parts (model and operators, contact results,
    // the end) to a writer thread; what it reads back must be what write_archive writes.
    let dir = tmpdir("outputs-parts");
    let mut rec = fabricated(80);
    rec.mechanism = upper_turns();
    assert!(rec.states.len() > 1 && rec.states.last().is_some_and(|s| !s.interior.is_empty()));
    write_archive(&dir.join("whole.h5"), &rec).expect("write");
    let mut model = rec.clone();
    (model.states, model.history, model.contact_operators) = (Vec::new(), Default::default(), None);
    let writer = ArchiveWriter::start(&dir.join("parts.h5"), model);
    let mut states = rec.states.clone();
    let interior = std::mem::take(&mut states.last_mut().unwrap().interior);
    writer.send(ArchivePart::Solved {
        contact_operators: rec.contact_operators.clone(),
        history: rec.history.clone(),
        states,
        mechanism: rec.mechanism.clone(),
    });
    writer.send(ArchivePart::Finished {
        interior,
        status: rec.status.clone(),
        timings: rec.timings.clone(),
        summary_json: rec.summary_json.clone(),
    });
    writer.finish().expect("finish");
    let (whole, parts) = (
        read_archive(&dir.join("whole.h5")).unwrap(),
        read_archive(&dir.join("parts.h5")).unwrap(),
    );
    assert_eq!(format!("{parts:?}"), format!("{whole:?}"));
    // A writer dropped before the end (a failed run) leaves no archive and no temporary.
    let writer = ArchiveWriter::start(&dir.join("dropped.h5"), rec.clone());
    drop(writer);
    assert_eq!(
        files(&dir).into_keys().collect::<Vec<_>>(),
        ["parts.h5", "whole.h5"]
    );
}

/// The upper block of [`fabricated`] turning anticlockwise about its centre node
/// (0.5, 1.5), its farthest nodes at 1.
fn upper_turns() -> Vec<BodyMotion> {
    vec![BodyMotion {
        body: 1,
        centroid: [0.5, 1.5],
        translation: [0.0, 0.0],
        rotation: 2f64.sqrt(),
    }]
}

/// A record with a mechanism: the archive keeps it (`/mechanism`, read back exactly), the
/// VTK files draw it with the last state only (block "mechanism" of its multiblock, the
/// rigid velocity at every node, zero on the body at rest), `sgbem export` writes the same
/// bytes from the archive and `sgbem inspect` names the moving body; a mechanism naming a
/// body the archive does not hold is an error, not a panic. A record without one has no
/// group and no block.
#[test]
fn a_mechanism_is_archived_and_drawn_with_the_last_state() {
    let dir = tmpdir("outputs-mechanism");
    let mut rec = fabricated(3);
    rec.mechanism = upper_turns();
    let path = dir.join("run").join("archive.h5");
    write_archive(&path, &rec).expect("write");
    let back = read_archive(&path).expect("read");
    assert_eq!(back.mechanism, rec.mechanism);
    write_vtk(&dir.join("run").join("vtk"), &rec).expect("vtk");
    let nodes = mechanism_block(&dir.join("run")).expect("a mechanism block");
    assert_eq!(nodes.len(), 8);
    for n in &nodes {
        let (dx, dy) = (n.x[0] - 0.5, n.x[1] - 1.5);
        let want = if n.body == 1 {
            [-2f64.sqrt() * dy, 2f64.sqrt() * dx, 0.0]
        } else {
            [0.0; 3]
        };
        assert_eq!(n.v, want, "at {:?}", n.x);
    }
    let top = nodes
        .iter()
        .map(|n| n.v[0].hypot(n.v[1]))
        .fold(0.0, f64::max);
    assert!((top - 1.0).abs() < 1e-15, "{top}");
    export(&path, &dir.join("export")).expect("export");
    let exported = files(&dir.join("export"));
    for (name, bytes) in files(&dir.join("run").join("vtk")) {
        assert_eq!(Some(&bytes), exported.get(&name), "{name}");
    }
    let p = damaged_copy(&path, &dir, "body.h5", |f| {
        let g = f.group("mechanism").unwrap();
        g.unlink("body").unwrap();
        g.new_dataset_builder()
            .with_data(&ndarray::arr1(&[7i64]))
            .create("body")
            .unwrap();
    });
    inspect_fails(&p, "mechanism refers to index 7");
    let (code, text, err) = sgbem(&["inspect", path.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(text.contains("\n  mechanism moves upper/part\n"), "{text}");
    let plain = dir.join("plain.h5");
    write_archive(&plain, &fabricated(3)).unwrap();
    assert!(!h5::File::open(&plain).unwrap().link_exists("mechanism"));
    write_vtk(&dir.join("plain").join("vtk"), &fabricated(3)).unwrap();
    assert!(mechanism_block(&dir.join("plain")).is_none());
}

/// The shipped collapse search (`wall_collapse`): `contact.collapse.motion` lists the
/// bodies that the mechanism's message names, in its order and kinds (the message names the
/// first four and counts the others), each moving as the VTK block "mechanism" of the state
/// at the multiplier draws it: at every node of a listed body the velocity of its summary
/// record (a translation: `magnitude` along `direction`; a rotation: about `centre`, its
/// fastest node at `magnitude`) to 1e-9, zero on every other body, the fastest node at 1;
/// no top-level `mechanism` (the run converged at the multiplier).
#[test]
fn wall_collapse_names_and_draws_its_mechanism() {
    let out = tmpdir("outputs-wall-collapse").join("out");
    let (code, err) = run_shipped("wall_collapse", &out);
    assert_eq!(code, 0, "{err}");
    let s = read_summary(&out);
    assert!(s.get("mechanism").is_none());
    let c = &s["contact"]["collapse"];
    let message = c["mechanism"].as_str().unwrap();
    let motion = c["motion"].as_array().expect("collapse.motion");
    let words = message.split("; the motion: ").nth(1).expect("the motion");
    let (named, more) = match words.split_once(" and ") {
        Some((named, more)) => (named, more.split(' ').next().unwrap().parse().unwrap()),
        None => (words, 0usize),
    };
    let named: Vec<(&str, &str)> = named
        .split(", body ")
        .map(|w| {
            let name = w.split('"').nth(1).unwrap();
            (
                name,
                if w.contains(" turns ") {
                    "rotation"
                } else {
                    "translation"
                },
            )
        })
        .collect();
    assert_eq!(motion.len(), named.len() + more, "{message}");
    for (b, (name, kind)) in motion.iter().zip(&named) {
        assert_eq!(
            (b["body"].as_str().unwrap(), b["kind"].as_str().unwrap()),
            (*name, *kind)
        );
    }
    let names: Vec<String> = read_archive(&out.join("archive.h5"))
        .unwrap()
        .bodies
        .iter()
        .map(|b| b.name.clone())
        .collect();
    let nodes = mechanism_block(&out).expect("a mechanism block");
    let mut top = 0.0f64;
    for b in motion {
        let name = b["body"].as_str().unwrap();
        let body = names.iter().position(|n| n == name).unwrap() as i32;
        let mine: Vec<_> = nodes.iter().filter(|n| n.body == body).collect();
        let pair = |k: &str| [b[k][0].as_f64().unwrap(), b[k][1].as_f64().unwrap()];
        let magnitude = b["magnitude"].as_f64().unwrap();
        let velocity: Box<dyn Fn([f64; 2]) -> [f64; 2]> = if b["kind"] == "translation" {
            let d = pair("direction");
            Box::new(move |_| [magnitude * d[0], magnitude * d[1]])
        } else {
            let c = pair("centre");
            let far = mine
                .iter()
                .map(|n| (n.x[0] - c[0]).hypot(n.x[1] - c[1]))
                .fold(0.0, f64::max);
            let w = if b["sense"] == "clockwise" { -1.0 } else { 1.0 } * magnitude / far;
            Box::new(move |x| [-w * (x[1] - c[1]), w * (x[0] - c[0])])
        };
        for n in mine {
            let want = velocity(n.x);
            let off = (n.v[0] - want[0]).hypot(n.v[1] - want[1]);
            assert!(
                off <= 1e-9,
                "{name} at {:?}: {:?} against {want:?}",
                n.x,
                n.v
            );
            top = top.max(n.v[0].hypot(n.v[1]));
        }
    }
    let moving: Vec<i32> = motion
        .iter()
        .map(|b| {
            names
                .iter()
                .position(|n| n == b["body"].as_str().unwrap())
                .unwrap() as i32
        })
        .collect();
    for n in nodes.iter().filter(|n| !moving.contains(&n.body)) {
        assert_eq!(n.v, [0.0; 3], "body {} at {:?}", n.body, n.x);
    }
    assert!((top - 1.0).abs() <= 1e-12, "fastest node {top}");
}

#[test]
fn archive_round_trip_is_exact() {
    let dir = tmpdir("outputs-roundtrip");
    let path = dir.join("archive.h5");
    let rec = fabricated(3);
    write_archive(&path, &rec).expect("write");
    let back = read_archive(&path).expect("read");
    assert_eq!(back.title, rec.title);
    assert_eq!(back.scene_text, rec.scene_text);
    assert_eq!(back.mesh_sha256, rec.mesh_sha256);
    assert_eq!(back.units.length, "cm");
    assert_eq!(back.units.force, "daN");
    assert_eq!(back.plane, Plane::Strain);
    assert_eq!(back.thickness, 2.5);
    assert_eq!(back.created, rec.created);
    assert_eq!(back.status, "converged");
    assert_eq!(back.summary_json, rec.summary_json);
    assert_eq!(back.timings, rec.timings);
    assert_eq!(back.mesh.nodes, rec.mesh.nodes);
    assert_eq!(back.mesh.node_tags, rec.mesh.node_tags);
    assert_eq!(back.mesh.lines, rec.mesh.lines);
    assert_eq!(back.mesh.line_group, rec.mesh.line_group);
    assert_eq!(back.mesh.triangle_group, rec.mesh.triangle_group);
    assert_eq!(back.mesh.group_names, rec.mesh.group_names);
    assert_eq!(back.mesh.group_dims, rec.mesh.group_dims);
    assert_eq!(back.bodies.len(), 2);
    for (a, b) in back.bodies.iter().zip(&rec.bodies) {
        assert_eq!(a.name, b.name);
        assert_eq!(
            (a.young, a.poisson, a.body_force),
            (b.young, b.poisson, b.body_force)
        );
        assert_eq!(a.nodes, b.nodes);
        assert_eq!(a.mesh_nodes, b.mesh_nodes);
        assert_eq!(a.elements, b.elements);
        assert_eq!(a.triangles, b.triangles);
        assert_eq!(a.operators.is_some(), b.operators.is_some());
        if let (Some(p), Some(q)) = (&a.operators, &b.operators) {
            assert_eq!(p.unknowns, q.unknowns);
            assert_eq!(p.n_x, q.n_x);
            assert_eq!((&p.a, &p.a0, &p.a00, &p.d00), (&q.a, &q.a0, &q.a00, &q.d00));
            assert_eq!((&p.load, &p.z0), (&q.load, &q.z0));
        }
    }
    let (i, j) = (&back.interfaces[0], &rec.interfaces[0]);
    assert_eq!((&i.name, i.body_a, i.body_b), (&j.name, j.body_a, j.body_b));
    assert_eq!(
        (&i.model, &i.initial, &i.tangential),
        (&j.model, &j.initial, &j.tangential)
    );
    assert_eq!(
        (&i.node_a, &i.node_b, &i.elements),
        (&j.node_a, &j.node_b, &j.elements)
    );
    assert_eq!((&i.x, &i.normal, &i.tangent), (&j.x, &j.normal, &j.tangent));
    assert_eq!((&i.s, &i.gap, &i.cohesion), (&j.s, &j.gap, &j.cohesion));
    assert_eq!(back.contact_operators, rec.contact_operators);
    assert_eq!(back.states.len(), 3);
    for (s, t) in back.states.iter().zip(&rec.states) {
        assert_eq!(
            (s.iteration, s.load_step, s.load_factor),
            (t.iteration, t.load_step, t.load_factor)
        );
        for (f, g) in s.fields.iter().zip(t.fields.iter()) {
            assert_eq!((&f.u, &f.t), (&g.u, &g.t));
        }
        for (p, q) in s.interfaces[0].pairs.iter().zip(&t.interfaces[0].pairs) {
            assert_eq!(
                (p.status, p.traction, p.jump),
                (q.status, q.traction, q.jump)
            );
        }
        assert_eq!(s.interior.len(), t.interior.len());
        for (p, q) in s.interior.iter().zip(&t.interior) {
            assert_eq!(
                (&p.mesh_nodes, &p.u, &p.sigma),
                (&q.mesh_nodes, &q.u, &q.sigma)
            );
        }
    }
    assert_eq!(back.history.rows.len(), 3);
    for (a, b) in back.history.rows.iter().zip(&rec.history.rows) {
        assert_eq!(
            (a.load_step, a.load_factor, a.iteration, a.solver),
            (b.load_step, b.load_factor, b.iteration, b.solver)
        );
        assert_eq!(a.status, b.status);
        assert_eq!(a.normal_traction, b.normal_traction);
        assert_eq!(a.normal_opening, b.normal_opening);
        assert_eq!(a.detached_length, b.detached_length);
    }
}

#[test]
fn export_rebuilds_identical_vtk_files() {
    let dir = tmpdir("outputs-export");
    let rec = fabricated(3);
    let run_vtk = dir.join("run").join("vtk");
    let written = write_vtk(&run_vtk, &rec).expect("vtk");
    let names: Vec<String> = written
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(
        names,
        [
            "boundary_0000.vtu",
            "thrust_0000.vtu",
            "contact_0000.vtu",
            "state_0000.vtm",
            "boundary_0001.vtu",
            "thrust_0001.vtu",
            "contact_0001.vtu",
            "state_0001.vtm",
            "boundary_0002.vtu",
            "field_0002.vtu",
            "thrust_0002.vtu",
            "contact_0002.vtu",
            "state_0002.vtm",
            "states.pvd",
            "history.pvd"
        ]
    );
    let archive = dir.join("run").join("archive.h5");
    write_archive(&archive, &rec).expect("archive");
    let again = dir.join("again");
    export(&archive, &again).expect("export");
    let (a, mut b) = (files(&run_vtk), files(&again));
    // The export folder holds the marker of the files the tool wrote (output/owned.rs).
    assert!(b.remove(".sgbem-run.json").is_some());
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
    for (name, bytes) in &a {
        assert!(b[name] == *bytes, "{name} differs after export");
    }
    // The command line does the same.
    let cli = dir.join("cli");
    let (code, out, err) = sgbem(&[
        "export",
        archive.to_str().unwrap(),
        "--vtk",
        cli.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("15 VTK files"), "{out}");
    let mut c = files(&cli);
    assert!(c.remove(".sgbem-run.json").is_some());
    assert_eq!(c, a);
}

#[test]
fn vtk_content() {
    let dir = tmpdir("outputs-vtk");
    let rec = fabricated(3);
    write_vtk(&dir, &rec).expect("vtk");
    let b = std::fs::read_to_string(dir.join("boundary_0001.vtu")).unwrap();
    assert!(b.contains("type=\"UnstructuredGrid\""), "{b}");
    assert!(b.contains("byte_order=\"LittleEndian\""));
    assert!(
        b.contains("NumberOfPoints=\"8\" NumberOfCells=\"8\""),
        "{b}"
    );
    for name in [
        "displacement",
        "traction",
        "normal",
        "contact_status",
        "normal_traction",
        "normal_opening",
        "body",
    ] {
        assert!(b.contains(&format!("Name=\"{name}\"")), "{name} missing");
    }
    // contact_status: four interface nodes (1 closed and 1 open pair on both sides), four
    // other nodes at -1.
    let cs = b.split("Name=\"contact_status\"").nth(1).unwrap();
    assert!(cs.contains("RangeMin=\"-1\" RangeMax=\"1\""), "{cs}");
    let fld = std::fs::read_to_string(dir.join("field_0002.vtu")).unwrap();
    assert!(
        fld.contains("NumberOfPoints=\"10\" NumberOfCells=\"8\""),
        "{fld}"
    );
    for name in [
        "displacement",
        "stress",
        "von_mises",
        "principal_stress",
        "body",
    ] {
        assert!(fld.contains(&format!("Name=\"{name}\"")), "{name} missing");
    }
    // The stress tensor as ParaView orders a symmetric tensor, with component names, and
    // the scalars beside it.
    let stress = fld.split("Name=\"stress\"").nth(1).unwrap();
    assert!(
        stress.starts_with(
            " NumberOfComponents=\"6\" ComponentName0=\"XX\" ComponentName1=\"YY\" \
             ComponentName2=\"ZZ\" ComponentName3=\"XY\" ComponentName4=\"YZ\" \
             ComponentName5=\"XZ\""
        ),
        "{stress}"
    );
    assert!(fld.contains("Tensors=\"stress\""), "{fld}");
    for name in ["sxx", "syy", "szz", "sxy"] {
        assert!(fld.contains(&format!("Name=\"{name}\"")), "{name} missing");
    }
    // Title and units as field data (UTF-8 bytes), and the state.
    let bytes = |s: &str| {
        s.bytes()
            .map(|b| b.to_string())
            .collect::<Vec<_>>()
            .join(" ")
    };
    for text in [&b, &fld] {
        assert!(
            text.contains(&format!(
                "Name=\"title\" NumberOfTuples=\"22\" format=\"ascii\">{}</DataArray>",
                bytes("Two blocks, fabricated")
            )),
            "{text}"
        );
        assert!(text.contains(&format!(
            "format=\"ascii\">{}</DataArray>",
            bytes("daN/cm^2")
        )));
    }
    assert!(b.contains("Name=\"iteration\" NumberOfTuples=\"1\" format=\"ascii\">1.0<"));
    // Both parts at every time (ParaView reads a part only when it is listed at every
    // time); the field, computed for the last state only, repeated. Times: one load step
    // of three states at 1/3, 2/3, 1.
    let pvd = std::fs::read_to_string(dir.join("history.pvd")).unwrap();
    let entries: Vec<&str> = pvd.lines().filter(|l| l.contains("<DataSet")).collect();
    let t = ["0.3333333333333333", "0.6666666666666666", "1"];
    let mut want = Vec::new();
    for (k, t) in t.iter().enumerate() {
        want.push(format!(
            "    <DataSet timestep=\"{t}\" group=\"\" part=\"0\" file=\"boundary_000{k}.vtu\"/>"
        ));
        want.push(format!(
            "    <DataSet timestep=\"{t}\" group=\"\" part=\"1\" file=\"field_0002.vtu\"/>"
        ));
    }
    assert_eq!(entries, want);
    // states.pvd: one multiblock per time, the field block only in the state that has it.
    let series = std::fs::read_to_string(dir.join("states.pvd")).unwrap();
    let entries: Vec<&str> = series.lines().filter(|l| l.contains("<DataSet")).collect();
    let want: Vec<String> = t
        .iter()
        .enumerate()
        .map(|(k, t)| {
            format!(
                "    <DataSet timestep=\"{t}\" group=\"\" part=\"0\" file=\"state_000{k}.vtm\"/>"
            )
        })
        .collect();
    assert_eq!(entries, want);
    for k in 0..3 {
        let vtm = std::fs::read_to_string(dir.join(format!("state_000{k}.vtm"))).unwrap();
        let blocks: Vec<&str> = vtm.lines().filter(|l| l.contains("<DataSet")).collect();
        let mut want = vec![format!(
            "    <DataSet index=\"0\" name=\"boundary\" file=\"boundary_000{k}.vtu\"/>"
        )];
        if k == 2 {
            want.push("    <DataSet index=\"1\" name=\"field\" file=\"field_0002.vtu\"/>".into());
        }
        // The thrust line, where the run has interfaces (this one has).
        let index = if k == 2 { 2 } else { 1 };
        want.push(format!(
            "    <DataSet index=\"{index}\" name=\"thrust\" file=\"thrust_000{k}.vtu\"/>"
        ));
        // The contact rows, beside it.
        want.push(format!(
            "    <DataSet index=\"{}\" name=\"contact\" file=\"contact_000{k}.vtu\"/>",
            index + 1
        ));
        assert_eq!(blocks, want, "state_000{k}.vtm");
        assert!(vtm.contains("<VTKFile type=\"vtkMultiBlockDataSet\""));
        // Title and units as text for ParaView's Information panel: string arrays (each
        // string's bytes and a 0) in the multiblock's own field data, named apart from the
        // blocks' UInt8 arrays (ParaView merges field data by name).
        let fd = vtm
            .split("<FieldData>")
            .nth(1)
            .expect("field data of the multiblock");
        for (name, text) in [
            ("run title", "Two blocks, fabricated"),
            ("length unit", "cm"),
            ("force unit", "daN"),
            ("stress unit", "daN/cm^2"),
        ] {
            let array = format!(
                "<Array type=\"String\" Name=\"{name}\" NumberOfTuples=\"1\" \
                 format=\"ascii\">{} 0</Array>",
                bytes(text)
            );
            assert!(fd.contains(&array), "state_000{k}.vtm: {array} not in {fd}");
        }
    }
    // A second write leaves no temporary files behind.
    write_vtk(&dir, &rec).expect("vtk");
    assert!(files(&dir).keys().all(|n| !n.starts_with('.')));
}

#[test]
fn state_times_are_load_step_plus_iteration_fraction() {
    // Two load steps: two states in the first, three in the second.
    let mut rec = fabricated(3);
    let extra = rec.states[..2].to_vec();
    rec.states.extend(extra);
    for (k, st) in rec.states.iter_mut().enumerate() {
        st.load_step = usize::from(k >= 2);
    }
    let t = sgbem::output::vtk::state_times(&rec);
    let want = [0.5, 1.0, 1.0 + 1.0 / 3.0, 1.0 + 2.0 / 3.0, 2.0];
    assert_eq!(t.len(), want.len());
    for (a, b) in t.iter().zip(want) {
        assert!((a - b).abs() < 1e-15, "{t:?}");
    }
    // Only the final state kept (history = "final"): the end of its load step.
    rec.states.drain(..4);
    assert_eq!(sgbem::output::vtk::state_times(&rec), [2.0]);
}

#[test]
fn states_must_advance() {
    let dir = tmpdir("outputs-order");
    let mut rec = fabricated(3);
    rec.states[2].iteration = 1;
    let e = write_vtk(&dir, &rec).unwrap_err();
    assert_eq!(e.exit_code(), 1);
    assert!(e.to_string().contains("iterations must increase"), "{e}");
}

#[test]
fn failed_writes_leave_no_finished_file() {
    let dir = tmpdir("outputs-atomic");
    // The final name is taken by a folder: the rename fails, the temporary file goes.
    let path = dir.join("archive.h5");
    std::fs::create_dir(&path).unwrap();
    let e = write_archive(&path, &fabricated(3)).unwrap_err();
    assert_eq!(e.exit_code(), 1);
    assert!(path.is_dir());
    let left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left, ["archive.h5"], "a temporary file was left");
    // A folder that cannot be created (a file is in the way).
    let blocker = dir.join("blocker");
    std::fs::write(&blocker, "x").unwrap();
    let e = write_archive(&blocker.join("archive.h5"), &fabricated(3)).unwrap_err();
    assert_eq!(e.exit_code(), 1);
    let e = write_vtk(&blocker.join("vtk"), &fabricated(3)).unwrap_err();
    assert_eq!(e.exit_code(), 1);
    // An inconsistent record writes nothing.
    let mut rec = fabricated(3);
    rec.bodies[0].elements[0] = [0, 99];
    let ok = dir.join("ok.h5");
    let e = write_archive(&ok, &rec).unwrap_err();
    assert!(e.to_string().contains("index 99"), "{e}");
    assert!(!ok.exists());
    // Writing over an older archive replaces it only when complete.
    write_archive(&ok, &fabricated(3)).unwrap();
    let before = std::fs::read(&ok).unwrap();
    assert!(write_archive(&ok, &rec).is_err());
    assert_eq!(std::fs::read(&ok).unwrap(), before);
}

/// Runs `sgbem inspect` and asserts exit status 1, one message, no panic.
fn inspect_fails(path: &Path, needle: &str) {
    let (code, _, err) = sgbem(&["inspect", path.to_str().unwrap()]);
    assert_eq!(code, 1, "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(err.starts_with("sgbem: "), "{err}");
    assert!(err.contains(needle), "expected {needle:?} in: {err}");
    let e = read_archive(path).unwrap_err();
    assert_eq!(e.exit_code(), 1);
}

fn damaged_copy(src: &Path, dir: &Path, name: &str, edit: impl FnOnce(&h5::File)) -> PathBuf {
    let p = dir.join(name);
    std::fs::copy(src, &p).unwrap();
    // Without libhdf5's file lock, as the archive code opens files: a test running in
    // parallel that starts `sgbem` while this file is open hands the child a copy of its
    // descriptor (libhdf5 opens without O_CLOEXEC), and with it the lock, which then
    // refuses the next open of this file here (errno 11) until that child ends.
    let f = h5::File::with_options()
        .with_fapl(|a| a.file_locking(false))
        .open_rw(&p)
        .unwrap();
    edit(&f);
    f.close().unwrap();
    p
}

#[test]
fn damaged_archives_are_errors() {
    let dir = tmpdir("outputs-damaged");
    let good = dir.join("good.h5");
    write_archive(&good, &fabricated(3)).unwrap();
    let bytes = std::fs::read(&good).unwrap();

    inspect_fails(&dir.join("missing.h5"), "no such archive");
    let garbage = dir.join("garbage.h5");
    std::fs::write(&garbage, b"this is not HDF5 at all").unwrap();
    inspect_fails(&garbage, "not an HDF5 file");
    for cut in [16, 512, bytes.len() / 2, bytes.len() - 200] {
        let p = dir.join(format!("cut{cut}.h5"));
        std::fs::write(&p, &bytes[..cut]).unwrap();
        let (code, _, err) = sgbem(&["inspect", p.to_str().unwrap()]);
        assert_eq!(code, 1, "cut at {cut}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    let other = dir.join("other.h5");
    h5::File::create(&other).unwrap().create_group("x").unwrap();
    inspect_fails(&other, "not an sgbem archive");

    let p = damaged_copy(&good, &dir, "nodes.h5", |f| {
        f.unlink("bodies/lower/nodes").unwrap();
    });
    inspect_fails(&p, "bodies/lower/nodes");
    let p = damaged_copy(&good, &dir, "shape.h5", |f| {
        let g = f.group("bodies/lower").unwrap();
        g.unlink("nodes").unwrap();
        g.new_dataset_builder()
            .with_data(&ndarray::arr2(&[[0.0, 1.0, 2.0]]))
            .create("nodes")
            .unwrap();
    });
    inspect_fails(&p, "expected");
    let p = damaged_copy(&good, &dir, "index.h5", |f| {
        let g = f.group("bodies/lower").unwrap();
        g.unlink("elements").unwrap();
        g.new_dataset_builder()
            .with_data(&ndarray::arr2(&[[0i64, 1], [1, 2], [2, 3], [3, 40]]))
            .create("elements")
            .unwrap();
    });
    inspect_fails(&p, "index 40");
    let p = damaged_copy(&good, &dir, "negative.h5", |f| {
        let g = f.group("interfaces/joint").unwrap();
        g.unlink("node_a").unwrap();
        g.new_dataset_builder()
            .with_data(&ndarray::arr1(&[3i64, -2]))
            .create("node_a")
            .unwrap();
    });
    inspect_fails(&p, "negative");
    let p = damaged_copy(&good, &dir, "state.h5", |f| {
        f.unlink("states/0001").unwrap();
    });
    inspect_fails(&p, "states/0001");
    let p = damaged_copy(&good, &dir, "type.h5", |f| {
        let g = f.group("mesh").unwrap();
        g.unlink("nodes").unwrap();
        let s: Vec<h5::types::VarLenUnicode> = (0..16).map(|_| "x".parse().unwrap()).collect();
        g.new_dataset_builder()
            .with_data(&ndarray::Array2::from_shape_vec((8, 2), s).unwrap())
            .create("nodes")
            .unwrap();
    });
    inspect_fails(&p, "mesh/nodes");
    let (code, _, err) = sgbem(&[
        "export",
        p.to_str().unwrap(),
        "--vtk",
        dir.join("vtk").to_str().unwrap(),
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(!dir.join("vtk").join("history.pvd").exists());
}

#[test]
fn inspect_prints_what_the_archive_holds() {
    let dir = tmpdir("outputs-inspect");
    let path = dir.join("archive.h5");
    write_archive(&path, &fabricated(3)).unwrap();
    let (code, out, err) = sgbem(&["inspect", path.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    for needle in [
        "Two blocks, fabricated",
        "converged",
        "bodies (2)",
        "lower",
        "upper/part",
        "E = 5000",
        "interfaces (1)",
        "joint",
        "lower | upper/part, unilateral, starts closed, stick; 2 pairs, length 1",
        "states (3): iterations 0 to 2; interior field in 1",
        "detached length 1, 2 of 2 pairs open",
        "iterations (3)",
        "joint detached",
        "timings (s)",
        "assemble",
    ] {
        assert!(out.contains(needle), "{needle:?} missing from:\n{out}");
    }
    // One row per iteration with its detached length.
    let rows: Vec<&str> = out
        .lines()
        .skip_while(|l| !l.starts_with("iterations"))
        .skip(2)
        .take(3)
        .collect();
    let last: Vec<&str> = rows
        .iter()
        .map(|r| r.split_whitespace().last().unwrap())
        .collect();
    assert_eq!(last, ["0", "0", "1"], "{out}");
}

#[test]
fn record_from_a_model() {
    let dir = tmpdir("outputs-model");
    let msh = stacked_blocks(3).save(&dir, "m.msh");
    let scene = support::write(
        &dir,
        "s.toml",
        &format!(
            "title = \"stacked\"\nunits = {{ length = \"m\", force = \"N\" }}\n{STACKED_SCENE}"
        ),
    );
    let loaded = sgbem::pipeline::load(&scene, Some(&msh)).expect("load");
    let mut rec = RunRecord::from_model(&loaded.scene, &loaded.mesh, &loaded.model).unwrap();
    assert_eq!(
        rec.mesh_sha256,
        sgbem::output::record::sha256_hex(&std::fs::read(&msh).unwrap())
    );
    assert_eq!(rec.mesh_sha256.len(), 64);
    assert_eq!(rec.bodies.len(), 2);
    assert_eq!(rec.interfaces.len(), 1);
    assert_eq!(rec.interfaces[0].node_a.len(), 4);
    assert_eq!(rec.units.length, "m");
    assert!(rec.mesh.group_names.contains(&"joint".to_string()));
    assert!(rec.mesh.line_group.iter().all(|g| g.is_some()));
    // Zero fields of the right sizes.
    let fields = rec
        .bodies
        .iter()
        .map(|b| BodyField {
            u: vec![[0.0; 2]; b.nodes.len()],
            t: vec![[[0.0; 2]; 2]; b.elements.len()],
            ..Default::default()
        })
        .collect();
    let pairs = vec![
        PairResult {
            status: PairStatus::Closed,
            traction: [0.0; 2],
            jump: [0.0; 2],
            slipping: None,
            slip: 0.0,
        };
        4
    ];
    rec.states.push(IterateRecord::new(
        0,
        0,
        1.0,
        fields,
        vec![InterfaceResult { pairs }],
    ));
    rec.validate().expect("consistent");
    write_archive(&dir.join("archive.h5"), &rec).unwrap();
    let back = read_archive(&dir.join("archive.h5")).unwrap();
    assert_eq!(back.mesh.nodes, loaded.mesh.nodes);
    assert_eq!(back.scene_text, loaded.scene.text);
    // One state without a field: its boundary, its thrust line, its contact rows, its
    // multiblock and the two series.
    let files = write_vtk(&dir.join("vtk"), &back).unwrap();
    assert_eq!(files.len(), 6);
}

/// A complete run folder (summary.json, CSV tables, archive, VTK files) from a real model
/// with fabricated values, for `pipelines/check_outputs.py`.
fn fabricated_run(dir: &Path) -> PathBuf {
    let msh = stacked_blocks(3).save(dir, "m.msh");
    let scene = support::write(
        dir,
        "s.toml",
        &format!("title = \"stacked\"\n{STACKED_SCENE}"),
    );
    let loaded = sgbem::pipeline::load(&scene, Some(&msh)).expect("load");
    let model = &loaded.model;
    let mut rec = RunRecord::from_model(&loaded.scene, &loaded.mesh, model).unwrap();
    // Fan triangles from a centre node of each body, to have an interior grid.
    for (b, centre) in [[0.5, 0.5], [0.5, 1.5]].into_iter().enumerate() {
        let c = rec.mesh.nodes.len();
        rec.mesh.nodes.push(centre);
        rec.mesh.node_tags.push(1000 + b);
        let body = &mut rec.bodies[b];
        body.triangles = body
            .elements
            .iter()
            .map(|e| [body.mesh_nodes[e[0]], body.mesh_nodes[e[1]], c])
            .collect();
        rec.mesh.triangles.extend(body.triangles.clone());
        rec.mesh
            .triangle_group
            .extend(vec![None; body.triangles.len()]);
    }
    let pattern = [
        vec![PairStatus::Closed; 4],
        vec![
            PairStatus::Closed,
            PairStatus::Open,
            PairStatus::Open,
            PairStatus::Closed,
        ],
        vec![
            PairStatus::Open,
            PairStatus::Open,
            PairStatus::Open,
            PairStatus::Closed,
        ],
    ];
    for (k, st) in pattern.iter().enumerate() {
        let seed = 5000 * (k + 1);
        let fields = rec
            .bodies
            .iter()
            .enumerate()
            .map(|(b, body)| BodyField {
                u: (0..body.nodes.len())
                    .map(|i| [val(seed + 97 * b + 2 * i), val(seed + 97 * b + 2 * i + 1)])
                    .collect(),
                t: (0..body.elements.len())
                    .map(|e| {
                        let s = seed + 1000 + 97 * b + 4 * e;
                        [[val(s), val(s + 1)], [val(s + 2), val(s + 3)]]
                    })
                    .collect(),
                ..Default::default()
            })
            .collect();
        let pairs: Vec<PairResult> = (0..4)
            .map(|j| PairResult {
                status: st[j],
                traction: [val(seed + 3000 + j), val(seed + 3100 + j)],
                jump: [val(seed + 3200 + j), val(seed + 3300 + j).abs()],
                slipping: None,
                slip: 0.0,
            })
            .collect();
        let result = InterfaceResult { pairs };
        let it = &rec.interfaces[0];
        rec.history.rows.push(HistoryRow {
            load_step: 0,
            load_factor: 1.0,
            iteration: k,
            solver: "lcp",
            status: vec![st.clone()],
            normal_traction: vec![result.pairs.iter().map(|p| p.traction[1]).collect()],
            normal_opening: vec![(0..4).map(|j| it.opening(&result, j)).collect()],
            detached_length: vec![it.detached_length(&result)],
        });
        let mut state = IterateRecord::new(k, 0, 1.0, fields, vec![result]);
        if k == 2 {
            state.interior = rec
                .bodies
                .iter()
                .map(|b| {
                    let mut ids: Vec<usize> = b.triangles.iter().flatten().copied().collect();
                    ids.sort_unstable();
                    ids.dedup();
                    InteriorRecord {
                        u: ids.iter().map(|&m| [val(m + 7), val(m + 8)]).collect(),
                        sigma: ids
                            .iter()
                            .map(|&m| [val(m), val(m + 1), val(m + 2)])
                            .collect(),
                        mesh_nodes: ids,
                    }
                })
                .collect();
        }
        rec.states.push(state);
    }
    rec.status = "converged".into();
    rec.timings = vec![("read".into(), 0.25), ("write".into(), 0.5)];
    let last = rec.states.last().unwrap();
    let thrusts: Vec<sgbem::post::thrust::Thrust> = model
        .interfaces
        .iter()
        .zip(last.interfaces.iter())
        .map(|(it, r)| sgbem::post::thrust::thrust(&sgbem::post::thrust::Joint::of(it), r, 1.0))
        .collect();
    let summary = serde_json::json!({
        "title": "stacked",
        "status": "converged",
        "counts": {
            "bodies": 2,
            "boundary_elements": model.element_count(),
            "interface_pairs": model.pair_count(),
            "field_nodes": last.interior.iter().map(|i| i.mesh_nodes.len()).sum::<usize>(),
        },
        "interfaces": sgbem::output::summary::interfaces(&model.interfaces, &last.interfaces, 1.0),
        "thrust": sgbem::output::summary::thrust(&model.interfaces, &thrusts),
    });
    rec.summary_json = summary.to_string();
    let run = dir.join("run");
    std::fs::create_dir_all(run.join("interfaces")).unwrap();
    std::fs::write(run.join("summary.json"), rec.summary_json.as_bytes()).unwrap();
    let timings = serde_json::json!({
        "created": rec.created,
        "stages": {"read": 0.25, "write": 0.5, "total": 0.75},
    });
    std::fs::write(run.join("timings.json"), timings.to_string()).unwrap();
    std::fs::write(
        run.join("interfaces").join("joint.csv"),
        sgbem::output::csv::interface_table(
            &model.interfaces[0],
            &last.interfaces[0],
            &model.bodies,
        ),
    )
    .unwrap();
    let name = |b: usize| model.bodies[b].name.as_str();
    let rows: Vec<sgbem::output::csv::ThrustRow> = model
        .interfaces
        .iter()
        .zip(&thrusts)
        .map(|(it, t)| (it.spec.name.as_str(), name(it.body_a), name(it.body_b), t))
        .collect();
    std::fs::write(
        run.join("thrust.csv"),
        sgbem::output::csv::thrust_table(&rows, "", ""),
    )
    .unwrap();
    // The hubs, as `sgbem run` writes them beside thrust.csv.
    let pairs: Vec<(usize, usize)> = model
        .interfaces
        .iter()
        .map(|it| (it.body_a, it.body_b))
        .collect();
    let forces: Vec<Option<[f64; 2]>> = model.bodies.iter().map(|b| b.body_force).collect();
    let down = sgbem::post::thrust::down(&forces);
    let hubs = sgbem::post::thrust::hubs(&pairs, &thrusts, &down);
    let named: Vec<(&str, &sgbem::post::thrust::Hub)> =
        hubs.iter().map(|h| (name(h.body), h)).collect();
    std::fs::write(
        run.join("thrust_hubs.csv"),
        sgbem::output::csv::hub_table(&named, "", ""),
    )
    .unwrap();
    write_archive(&run.join("archive.h5"), &rec).unwrap();
    write_vtk(&run.join("vtk"), &rec).unwrap();
    run
}

#[test]
fn python_checks_agree_with_the_writers() {
    let python = support::root().join(".venv/bin/python");
    if !python.exists() {
        eprintln!("skipped: no .venv (make setup installs h5py, meshio and pyvista)");
        return;
    }
    let dir = tmpdir("outputs-python");
    let run = fabricated_run(&dir);
    let script = support::root().join("pipelines/check_outputs.py");
    let check = |run: &Path| {
        let o = std::process::Command::new(&python)
            .arg(&script)
            .arg(run)
            .output()
            .expect("run python");
        (
            o.status.code().unwrap_or(-1),
            String::from_utf8_lossy(&o.stdout).into_owned() + &String::from_utf8_lossy(&o.stderr),
        )
    };
    let (code, out) = check(&run);
    assert_eq!(code, 0, "{out}");
    assert!(out.contains("checks passed"), "{out}");
    // A summary that disagrees with the archive is caught, with the figure named.
    let path = run.join("summary.json");
    let mut s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    s["interfaces"]["joint"]["detached_length"] = serde_json::json!(123.0);
    std::fs::write(&path, s.to_string()).unwrap();
    let (code, out) = check(&run);
    assert_eq!(code, 1, "{out}");
    assert!(out.contains("detached_length"), "{out}");
    // So is a missing VTK file.
    let run2 = fabricated_run(&tmpdir("outputs-python2"));
    std::fs::remove_file(run2.join("vtk").join("field_0002.vtu")).unwrap();
    let (code, out) = check(&run2);
    assert_eq!(code, 1, "{out}");
    assert!(out.contains("field_0002.vtu"), "{out}");
}

#[test]
fn progress_is_hidden_when_quiet() {
    use sgbem::output::progress::Progress;
    let p = Progress::new(true);
    assert!(!p.enabled());
    let bar = p.bar("assemble", 10);
    bar.inc(3);
    bar.set_message("body A");
    assert_eq!(bar.position(), 3);
    bar.finish();
    let spin = Progress::hidden().spinner("contact");
    spin.inc(1);
    spin.finish();
}

/// Rewrites the fixed-length strings under `g` (attributes and string datasets, with their
/// attributes) as variable-length ones, as archives were written before.
fn strings_to_varlen(g: &h5::Group) {
    use h5::types::{FixedUnicode, TypeDescriptor, VarLenUnicode};
    let is_fixed =
        |t: h5::Datatype| matches!(t.to_descriptor().unwrap(), TypeDescriptor::FixedUnicode(_));
    let varlen = |v: Vec<FixedUnicode<65536>>| -> Vec<VarLenUnicode> {
        v.iter().map(|s| s.as_str().parse().unwrap()).collect()
    };
    let attrs = |loc: &h5::Location| {
        for name in loc.attr_names().unwrap() {
            let a = loc.attr(&name).unwrap();
            if !is_fixed(a.dtype().unwrap()) {
                continue;
            }
            let (scalar, v) = (a.is_scalar(), varlen(a.read_raw().unwrap()));
            drop(a);
            loc.delete_attr(&name).unwrap();
            if scalar {
                let a = loc
                    .new_attr::<VarLenUnicode>()
                    .shape(())
                    .create(name.as_str());
                a.unwrap().write_scalar(&v[0]).unwrap();
            } else {
                let v = ndarray::Array1::from(v);
                loc.new_attr_builder()
                    .with_data(&v)
                    .create(name.as_str())
                    .unwrap();
            }
        }
    };
    attrs(g);
    for name in g.member_names().unwrap() {
        if let Ok(sub) = g.group(&name) {
            strings_to_varlen(&sub);
        } else if let Ok(ds) = g.dataset(&name) {
            if is_fixed(ds.dtype().unwrap()) {
                let v = ndarray::Array1::from(varlen(ds.read_raw().unwrap()));
                let texts: Vec<Vec<VarLenUnicode>> = ["description", "units"]
                    .iter()
                    .map(|a| varlen(ds.attr(a).unwrap().read_raw().unwrap()))
                    .collect();
                drop(ds);
                g.unlink(&name).unwrap();
                let ds = g.new_dataset_builder().with_data(&v);
                let ds = ds.create(name.as_str()).unwrap();
                for (a, t) in ["description", "units"].iter().zip(&texts) {
                    let a = ds.new_attr::<VarLenUnicode>().shape(()).create(*a);
                    a.unwrap().write_scalar(&t[0]).unwrap();
                }
            }
            attrs(&g.dataset(&name).unwrap());
        }
    }
}

#[test]
fn archives_with_variable_length_strings_are_still_read() {
    let dir = tmpdir("outputs-varlen");
    let good = dir.join("good.h5");
    write_archive(&good, &fabricated(3)).unwrap();
    let old = damaged_copy(&good, &dir, "old.h5", |f| strings_to_varlen(f));
    let f = h5::File::open(&old).unwrap();
    let t = f
        .attr("title")
        .unwrap()
        .dtype()
        .unwrap()
        .to_descriptor()
        .unwrap();
    assert_eq!(t, h5::types::TypeDescriptor::VarLenUnicode);
    let solver = f.dataset("history/solver").unwrap().dtype().unwrap();
    assert_eq!(
        solver.to_descriptor().unwrap(),
        h5::types::TypeDescriptor::VarLenUnicode
    );
    drop((solver, f));
    let (a, b) = (read_archive(&good).unwrap(), read_archive(&old).unwrap());
    assert_eq!(format!("{a:?}"), format!("{b:?}"));
    let (code, out, err) = sgbem(&["inspect", old.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("Two blocks, fabricated"), "{out}");
}
