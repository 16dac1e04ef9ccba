//! The model built from gmsh meshes: the paper's example-2 geometry, orientation whatever the
//! drawing direction, binary = ASCII, node classes and interface pairs.

mod support;

use sgbem::input::model::{DofClass, Model, Role};
use sgbem::pipeline::load;
use support::*;

fn load_geo(
    geo: &str,
    scene: &str,
    name: &str,
    binary: bool,
    opts: &[&str],
) -> sgbem::pipeline::Loaded {
    let dir = tmpdir(name);
    let msh = gmsh(&root().join(geo), &dir, "mesh.msh", binary, opts);
    load(&root().join(scene), Some(&msh)).unwrap_or_else(|e| panic!("{e}"))
}

/// A description of a model independent of node numbering and drawing direction.
fn canonical(m: &Model) -> Vec<String> {
    let r = |v: f64| format!("{:.9}", v + 0.0);
    let p = |x: [f64; 2]| format!("({},{})", r(x[0]), r(x[1]));
    let mut out = Vec::new();
    for b in &m.bodies {
        let mut elems: Vec<String> = b
            .elements
            .iter()
            .map(|e| {
                let role = match e.role {
                    Role::Boundary(i) => m.parts[i].spec.name.clone(),
                    Role::Interface(i) => m.interfaces[i].spec.name.clone(),
                };
                format!(
                    "{} {}->{} n{} {role} break={}",
                    b.name,
                    p(b.nodes[e.nodes[0]]),
                    p(b.nodes[e.nodes[1]]),
                    p(e.normal),
                    e.traction_break
                )
            })
            .collect();
        elems.sort();
        out.extend(elems);
        let mut dofs: Vec<String> = b
            .nodes
            .iter()
            .zip(&b.dofs)
            .map(|(x, d)| {
                format!(
                    "{} {} {:?} {}{}",
                    b.name,
                    p(*x),
                    d.class,
                    p(d.frame[0]),
                    p(d.frame[1])
                )
            })
            .collect();
        dofs.sort();
        out.extend(dofs);
        let mut areas: Vec<String> = b
            .loops
            .iter()
            .map(|l| format!("{} loop {} {}", b.name, r(l.area), l.is_hole))
            .collect();
        areas.sort();
        out.extend(areas);
    }
    for i in &m.interfaces {
        for q in &i.pairs {
            out.push(format!(
                "{} {} n{} {}|{}",
                i.spec.name,
                p(q.x),
                p(q.normal),
                m.bodies[i.body_a].name,
                m.bodies[i.body_b].name
            ));
        }
        out.sort();
    }
    out
}

#[test]
fn clamped_beam_joint_model() {
    let l = load_geo(
        "geo/clamped_beam_joint.geo",
        "pipelines/clamped_beam_joint.toml",
        "beam",
        false,
        &[],
    );
    let m = &l.model;
    assert_eq!(m.bodies.len(), 2);
    assert_eq!(m.element_count(), 428, "50+50+10+104 per body");
    assert_eq!(m.interfaces.len(), 1);
    let joint = &m.interfaces[0];
    assert_eq!(joint.pairs.len(), 105);
    assert_eq!(joint.elements.len(), 104);
    assert_eq!(m.bodies[joint.body_a].name, "A");
    assert!((joint.length - 40.0).abs() < 1e-9);
    for (j, p) in joint.pairs.iter().enumerate() {
        assert!((p.x[0] - 200.0).abs() < 1e-9);
        assert!(
            (p.normal[0] - 1.0).abs() < 1e-14 && p.normal[1].abs() < 1e-14,
            "A's outward normal is +x"
        );
        assert!(
            (p.s - 40.0 * j as f64 / 104.0).abs() < 1e-9,
            "pairs ordered by arc length from the curve's first node"
        );
        assert!(
            (p.x[1] - p.s).abs() < 1e-9,
            "the joint is drawn from y = 0 up"
        );
    }
    for b in &m.bodies {
        assert_eq!(b.loops.len(), 1);
        assert!(
            (b.loops[0].area - 8000.0).abs() < 1e-6,
            "outer loop counter-clockwise"
        );
        assert!((b.perimeter() - 480.0).abs() < 1e-9);
        // Every element's outward normal points away from the body's centre.
        let cx = b.nodes.iter().map(|x| x[0]).sum::<f64>() / b.nodes.len() as f64;
        for e in &b.elements {
            let mid = b.nodes[e.nodes[0]];
            let out = (mid[0] - cx) * e.normal[0] + (mid[1] - 20.0) * e.normal[1];
            assert!(out > 0.0, "normal of element {} points inwards", e.tag);
        }
        // Node classes: 11 clamped nodes (both known), 105 joint nodes (U0), the rest U2.
        let [u1, u0, u2] = b.dof_counts();
        assert_eq!(u1, 2 * 11);
        assert_eq!(u0, 2 * 105);
        assert_eq!(u2, 2 * (b.nodes.len() - 116));
        // Double traction nodes at the 4 corners (which are also changes of part), and
        // where the joint meets top and bottom (changes of part, no corner).
        let breaks = b.elements.iter().filter(|e| e.traction_break).count();
        assert_eq!(breaks, 4);
    }
    assert!((m.sizes.smallest.0 - 40.0 / 104.0).abs() < 1e-9);
    assert!((m.sizes.largest.0 - 4.0).abs() < 1e-9);
    assert!((m.sizes.grading.0 - 4.0 / (40.0 / 104.0)).abs() < 1e-9);
    assert_eq!(l.plan.effects_line(), "elastic + detachment");
    assert_eq!(l.plan.problem, sgbem::plan::ContactProblem::Detachment);
    // Part roles
    let clamp = m.parts.iter().find(|p| p.spec.name == "clamp").unwrap();
    assert_eq!(clamp.spec.role(), "constrained");
    assert!((clamp.length - 80.0).abs() < 1e-9);
    let bottom = m.parts.iter().find(|p| p.spec.name == "bottom").unwrap();
    assert!(!bottom.listed);
}

#[test]
fn reversed_curves_give_the_same_model() {
    let a = load_geo(
        "geo/two_blocks.geo",
        "pipelines/two_blocks.toml",
        "fwd",
        false,
        &[],
    );
    let b = load_geo(
        "tests/fixtures/two_blocks_reversed.geo",
        "pipelines/two_blocks.toml",
        "rev",
        false,
        &[],
    );
    let (ca, cb) = (canonical(&a.model), canonical(&b.model));
    assert!(ca.len() > 100);
    assert_eq!(ca, cb);
    // Pairs run along the curve as drawn: geo/two_blocks.geo draws the joint from x = 1,
    // the reversed file from x = 0, so s is mirrored.
    for (pa, pb) in a.model.interfaces[0]
        .pairs
        .iter()
        .zip(b.model.interfaces[0].pairs.iter().rev())
    {
        assert!((pa.x[0] - pb.x[0]).abs() < 1e-9);
        assert!((pa.s - (1.0 - pa.x[0])).abs() < 1e-9 && (pb.s - pb.x[0]).abs() < 1e-9);
    }
}

#[test]
fn binary_and_ascii_meshes_give_identical_models() {
    for (geo, scene) in [
        (
            "geo/clamped_beam_joint.geo",
            "pipelines/clamped_beam_joint.toml",
        ),
        ("geo/two_blocks.geo", "pipelines/two_blocks.toml"),
    ] {
        let a = load_geo(geo, scene, "ascii", false, &["-setnumber", "h", "8"]);
        let b = load_geo(geo, scene, "binary", true, &["-setnumber", "h", "8"]);
        assert!(!a.mesh.binary && b.mesh.binary);
        // ASCII holds 16 significant digits: positions agree to the last digit or so.
        assert_eq!(a.mesh.nodes.len(), b.mesh.nodes.len());
        for (p, q) in a.mesh.nodes.iter().zip(&b.mesh.nodes) {
            assert!((p[0] - q[0]).abs() <= 1e-13 * p[0].abs().max(1.0));
            assert!((p[1] - q[1]).abs() <= 1e-13 * p[1].abs().max(1.0));
        }
        assert_eq!(a.mesh.node_tags, b.mesh.node_tags);
        assert_eq!(a.mesh.physical_names, b.mesh.physical_names);
        assert_eq!(a.mesh.lines, b.mesh.lines);
        assert_eq!(a.mesh.triangles, b.mesh.triangles);
        assert_eq!(canonical(&a.model), canonical(&b.model));
        assert_eq!(a.model.bodies[0].mesh_nodes, b.model.bodies[0].mesh_nodes);
    }
}

#[test]
fn symmetry_condition_gives_one_known_direction() {
    // Stacked blocks with a normal/tangential condition on the sides: un = 0 (rollers).
    let dir = tmpdir("rollers");
    let msh = stacked_blocks(4).save(&dir, "m.msh");
    let scene = STACKED_SCENE.replace(
        "[boundary.top]",
        "[boundary.sides]\nun = 0.0\n[boundary.top]",
    );
    let sc = write(&dir, "s.toml", &scene);
    let l = load(&sc, Some(&msh)).unwrap_or_else(|e| panic!("{e}"));
    let lower = &l.model.bodies[0];
    for (x, d) in lower.nodes.iter().zip(&lower.dofs) {
        let on_side = x[0] == 0.0 || x[0] == 1.0;
        let on_base = x[1] == 0.0;
        if on_base {
            assert_eq!(d.class, [DofClass::Known; 2]);
        } else if on_side {
            // known along x (the normal), unknown along y; U0 where the side meets the joint
            assert_eq!(d.class[1], DofClass::Known);
            assert!((d.frame[1][0].abs() - 1.0).abs() < 1e-14);
            let expect = if x[1] == 1.0 {
                DofClass::Interface
            } else {
                DofClass::Free
            };
            assert_eq!(d.class[0], expect);
        }
    }
}
