//! One body of the model: its boundary elements chained into oriented loops, the double
//! traction nodes at corners and changes of condition, and the class of every displacement
//! degree of freedom.

use std::collections::{BTreeSet, HashMap};
use std::path::Path;

use crate::error::{Error, Result};
use crate::input::mesh::Mesh;
use crate::input::scene::Frame;

use super::{
    cross, dot, fmt_point, norm, sub, unit, Body, DofClass, Element, Loop, NodeDofs, Part, Role,
    OPEN_LOOP_HINT,
};

/// Turning angle above which two elements meet at a corner, within one gmsh curve.
const CORNER_ANGLE_IN_CURVE: f64 = 10.0 * std::f64::consts::PI / 180.0;
/// Turning angle above which two elements meet at a corner, where two gmsh curves join.
const CORNER_ANGLE_AT_JOIN: f64 = 1.0 * std::f64::consts::PI / 180.0;

/// One body of the model from its boundary curves: its elements, chained into loops and
/// oriented by nesting (docs/formulation.md §1.1). Material, body force and surfaces are the
/// caller's to set.
#[allow(clippy::too_many_arguments)]
pub(super) fn build_body(
    name: &str,
    curves: &BTreeSet<i32>,
    curve_lines: &HashMap<i32, Vec<usize>>,
    curve_role: &HashMap<i32, Role>,
    mesh: &Mesh,
    mfile: &Path,
    scale: f64,
) -> Result<Body> {
    // The line elements of the boundary curves, their nodes numbered per body.
    let mut node_of_mesh: HashMap<usize, usize> = HashMap::new();
    let mut nodes: Vec<[f64; 2]> = Vec::new();
    let mut mesh_nodes: Vec<usize> = Vec::new();
    let mut elements: Vec<Element> = Vec::new();
    for &c in curves {
        let lines = curve_lines.get(&c).map(Vec::as_slice).unwrap_or(&[]);
        if lines.is_empty() {
            return Err(Error::input(
                mfile,
                format!(
                    "curve {c} bounds body \"{name}\" but has no line elements: \
                     {OPEN_LOOP_HINT}"
                ),
            ));
        }
        let role = match curve_role.get(&c) {
            Some(r) => *r,
            None => {
                return Err(Error::input(
                    mfile,
                    format!("curve {c} of body \"{name}\" has no role: {OPEN_LOOP_HINT}"),
                ))
            }
        };
        for &li in lines {
            let line = &mesh.lines[li];
            let mut local = [0usize; 2];
            for (k, &mn) in line.nodes.iter().enumerate() {
                local[k] = *node_of_mesh.entry(mn).or_insert_with(|| {
                    nodes.push(mesh.nodes[mn]);
                    mesh_nodes.push(mn);
                    nodes.len() - 1
                });
            }
            let d = sub(nodes[local[1]], nodes[local[0]]);
            let length = norm(d);
            if length.is_nan() || length <= 1e-12 * scale {
                return Err(Error::input(
                    mfile,
                    format!(
                        "line element {} (curve {c}, body \"{name}\") has zero length: its \
                         nodes {} and {} coincide; remove duplicate points in the .geo",
                        line.tag, mesh.node_tags[line.nodes[0]], mesh.node_tags[line.nodes[1]]
                    ),
                ));
            }
            let tangent = [d[0] / length, d[1] / length];
            elements.push(Element {
                nodes: local,
                tag: line.tag,
                curve: c,
                role,
                length,
                tangent,
                normal: [tangent[1], -tangent[0]],
                loop_index: 0,
                traction_break: false,
                reversed: false,
            });
        }
    }
    let mut boundary = Boundary {
        nodes,
        mesh_nodes,
        elements,
    };
    let incident = boundary.incidence(name, mesh, mfile, scale)?;
    let mut loops = boundary.chain_loops(&incident);
    boundary.orient_loops(&mut loops, name, mfile)?;
    boundary.check_folds(&loops, name, mesh, mfile)?;
    let Boundary {
        nodes,
        mesh_nodes,
        elements,
    } = boundary;
    let area = loops.iter().map(|l| l.area).sum();
    Ok(Body {
        name: name.to_string(),
        young: 0.0,
        poisson: 0.0,
        body_force: None,
        body_force_spec: None,
        surfaces: Vec::new(),
        nodes,
        mesh_nodes,
        elements,
        loops,
        dofs: Vec::new(),
        triangles: Vec::new(),
        area,
    })
}

/// A body's boundary while it is built: its nodes (numbered per body), the mesh node of
/// each, and its line elements.
struct Boundary {
    nodes: Vec<[f64; 2]>,
    mesh_nodes: Vec<usize>,
    elements: Vec<Element>,
}

impl Boundary {
    /// Node → incident elements; each boundary node must join exactly two elements.
    fn incidence(
        &self,
        name: &str,
        mesh: &Mesh,
        mfile: &Path,
        scale: f64,
    ) -> Result<Vec<Vec<usize>>> {
        let (nodes, mesh_nodes, elements) = (&self.nodes, &self.mesh_nodes, &self.elements);
        let mut incident: Vec<Vec<usize>> = vec![Vec::new(); nodes.len()];
        for (ei, e) in elements.iter().enumerate() {
            incident[e.nodes[0]].push(ei);
            incident[e.nodes[1]].push(ei);
        }
        for (n, inc) in incident.iter().enumerate() {
            let tag = mesh.node_tags[mesh_nodes[n]];
            match inc.len() {
                2 => {}
                1 => {
                    // Two nodes at one point, each ending a curve: duplicates, not a gap.
                    let ends = |m: usize| {
                        let curve = elements[incident[m][0]].curve;
                        (mesh.node_tags[mesh_nodes[m]], nodes[m], curve)
                    };
                    let twin = (0..nodes.len()).find(|&m| {
                        m != n
                            && incident[m].len() == 1
                            && norm(sub(nodes[m], nodes[n])) <= 1e-12 * scale
                    });
                    if let Some(m) = twin {
                        return Err(duplicate_nodes(mfile, name, ends(n), ends(m)));
                    }
                    return Err(Error::input(
                        mfile,
                        format!(
                            "the boundary of body \"{name}\" is open at node {tag} {} (end of \
                             curve {}): {OPEN_LOOP_HINT}",
                            fmt_point(nodes[n]),
                            elements[inc[0]].curve
                        ),
                    ));
                }
                k => {
                    let curves: BTreeSet<i32> = inc.iter().map(|&e| elements[e].curve).collect();
                    return Err(Error::input(
                        mfile,
                        format!(
                            "node {tag} {} joins {k} boundary elements of body \"{name}\" \
                             (curves {curves:?}): the boundary touches itself or a curve is \
                             meshed twice; each boundary node must join exactly two elements",
                            fmt_point(nodes[n])
                        ),
                    ));
                }
            }
        }
        Ok(incident)
    }

    /// Chains the elements into loops, flipping elements to follow the chain.
    fn chain_loops(&mut self, incident: &[Vec<usize>]) -> Vec<Loop> {
        let (nodes, elements) = (&self.nodes, &mut self.elements);
        let mut loops: Vec<Loop> = Vec::new();
        let mut visited = vec![false; elements.len()];
        for start in 0..elements.len() {
            if visited[start] {
                continue;
            }
            let mut chain = vec![start];
            visited[start] = true;
            let mut current = start;
            loop {
                let end = elements[current].nodes[1];
                let next = incident[end]
                    .iter()
                    .copied()
                    .find(|&e| e != current)
                    .unwrap_or(current);
                if next == start || visited[next] {
                    break;
                }
                if elements[next].nodes[0] != end {
                    flip(&mut elements[next]);
                }
                visited[next] = true;
                chain.push(next);
                current = next;
            }
            let area = loop_area(&chain, elements, nodes);
            loops.push(Loop {
                elements: chain,
                area,
                is_hole: false,
            });
        }
        loops
    }

    /// Orientation by nesting: a loop inside an odd number of others is a hole (clockwise),
    /// the rest run counter-clockwise; a body has exactly one outer loop.
    fn orient_loops(&mut self, loops: &mut [Loop], name: &str, mfile: &Path) -> Result<()> {
        let (nodes, elements) = (&self.nodes, &mut self.elements);
        let mut outer = 0;
        for li in 0..loops.len() {
            let probe = nodes[elements[loops[li].elements[0]].nodes[0]];
            let depth = (0..loops.len())
                .filter(|&o| o != li && point_in_loop(probe, &loops[o], elements, nodes))
                .count();
            let hole = depth % 2 == 1;
            let want_positive = !hole;
            if (loops[li].area > 0.0) != want_positive {
                let chain = std::mem::take(&mut loops[li].elements);
                for &e in &chain {
                    flip(&mut elements[e]);
                }
                loops[li].elements = chain.into_iter().rev().collect();
                loops[li].area = -loops[li].area;
            }
            loops[li].is_hole = hole;
            if !hole {
                outer += 1;
            }
        }
        if outer != 1 {
            return Err(Error::input(
                mfile,
                format!(
                    "body \"{name}\" consists of {outer} separate regions: make each region a \
                     Physical Surface (a body) of its own"
                ),
            ));
        }
        Ok(())
    }

    /// Sets each element's loop index, and refuses a loop that turns back on itself (two
    /// consecutive elements on top of each other): it encloses nothing there and has no
    /// normal at the fold.
    fn check_folds(&mut self, loops: &[Loop], name: &str, mesh: &Mesh, mfile: &Path) -> Result<()> {
        let (nodes, mesh_nodes, elements) = (&self.nodes, &self.mesh_nodes, &mut self.elements);
        for (li, l) in loops.iter().enumerate() {
            for &e in &l.elements {
                elements[e].loop_index = li;
            }
            // A loop that turns back on itself (two consecutive elements on top of each other)
            // encloses nothing there and has no normal at the fold.
            let n = l.elements.len();
            for k in 0..n {
                let (p, q) = (&elements[l.elements[k]], &elements[l.elements[(k + 1) % n]]);
                if dot(p.tangent, q.tangent) < -1.0 + 1e-9 {
                    let node = q.nodes[0];
                    return Err(Error::input(
                        mfile,
                        format!(
                            "the boundary of body \"{name}\" folds back on itself at node {} {} \
                             (elements {} and {} overlap): fix the curves there",
                            mesh.node_tags[mesh_nodes[node]],
                            fmt_point(nodes[node]),
                            p.tag,
                            q.tag
                        ),
                    ));
                }
            }
        }
        Ok(())
    }
}

fn flip(e: &mut Element) {
    e.nodes.swap(0, 1);
    e.reversed = !e.reversed;
    e.tangent = [-e.tangent[0], -e.tangent[1]];
    e.normal = [-e.normal[0], -e.normal[1]];
}

/// Signed area of a loop, in coordinates relative to its first node so that a mesh far
/// from the origin (1e9) keeps its digits.
fn loop_area(chain: &[usize], elements: &[Element], nodes: &[[f64; 2]]) -> f64 {
    let Some(&first) = chain.first() else {
        return 0.0;
    };
    let o = nodes[elements[first].nodes[0]];
    chain
        .iter()
        .map(|&e| {
            let [a, b] = elements[e].nodes;
            cross(sub(nodes[a], o), sub(nodes[b], o))
        })
        .sum::<f64>()
        * 0.5
}

/// Winding-number test of a point against one loop (orientation ignored).
fn point_in_loop(p: [f64; 2], l: &Loop, elements: &[Element], nodes: &[[f64; 2]]) -> bool {
    winding(
        p,
        l.elements.iter().map(|&e| {
            let [a, b] = elements[e].nodes;
            (nodes[a], nodes[b])
        }),
    ) != 0
}

pub(crate) fn winding(p: [f64; 2], segments: impl Iterator<Item = ([f64; 2], [f64; 2])>) -> i32 {
    let mut w = 0;
    for (a, b) in segments {
        let side = cross(sub(b, a), sub(p, a));
        if a[1] <= p[1] {
            if b[1] > p[1] && side > 0.0 {
                w += 1;
            }
        } else if b[1] <= p[1] && side < 0.0 {
            w -= 1;
        }
    }
    w
}

/// Marks double traction nodes: at a change of part or interface, and at corners.
pub(super) fn mark_traction_breaks(bodies: &mut [Body]) {
    for body in bodies.iter_mut() {
        for l in 0..body.loops.len() {
            let chain = body.loops[l].elements.clone();
            let n = chain.len();
            for k in 0..n {
                let prev = &body.elements[chain[(k + n - 1) % n]];
                let cur = &body.elements[chain[k]];
                let turn = cross(prev.tangent, cur.tangent)
                    .atan2(dot(prev.tangent, cur.tangent))
                    .abs();
                let limit = if prev.curve == cur.curve {
                    CORNER_ANGLE_IN_CURVE
                } else {
                    CORNER_ANGLE_AT_JOIN
                };
                let brk = prev.role != cur.role || turn > limit;
                body.elements[chain[k]].traction_break = brk;
            }
        }
    }
}

/// The directions in which a boundary element prescribes displacement.
pub(super) fn constrained_directions(e: &Element, parts: &[Part]) -> Vec<([f64; 2], usize, usize)> {
    let mut out = Vec::new();
    if let Role::Boundary(pi) = e.role {
        let spec = &parts[pi].spec;
        for (c, cond) in spec.components.iter().enumerate() {
            if cond.is_displacement() {
                let d = match (spec.frame, c) {
                    (Frame::Global, 0) => [1.0, 0.0],
                    (Frame::Global, _) => [0.0, 1.0],
                    (Frame::Local, 0) => e.tangent,
                    (Frame::Local, _) => e.normal,
                };
                out.push((d, pi, c));
            }
        }
    }
    out
}

/// Directions and classes of the displacement components at each node (docs/formulation.md §2.2):
/// directions prescribed by the adjacent elements are known (U1), the others unknown, U0 on
/// an interface and U2 elsewhere. Nearly parallel directions of the same condition on a
/// curved boundary (un on an arc) are averaged into one.
pub(super) fn node_dofs(body: &Body, parts: &[Part]) -> Vec<NodeDofs> {
    let mut dirs: Vec<Vec<([f64; 2], usize, usize)>> = vec![Vec::new(); body.nodes.len()];
    let mut on_interface = vec![false; body.nodes.len()];
    for e in &body.elements {
        for n in e.nodes {
            dirs[n].extend(constrained_directions(e, parts));
            if matches!(e.role, Role::Interface(_)) {
                on_interface[n] = true;
            }
        }
    }
    let mut out = Vec::with_capacity(body.nodes.len());
    for (n, list) in dirs.into_iter().enumerate() {
        // Merge directions of the same part and component that are nearly parallel.
        let mut merged: Vec<([f64; 2], usize, usize)> = Vec::new();
        for (d, pi, c) in list {
            if let Some(m) = merged.iter_mut().find(|(md, mp, mc)| {
                *mp == pi && *mc == c && dot(*md, d).abs() > (20f64.to_radians()).cos()
            }) {
                let s = dot(m.0, d).signum();
                m.0 = unit([m.0[0] + s * d[0], m.0[1] + s * d[1]]);
            } else {
                merged.push((d, pi, c));
            }
        }
        let unknown = if on_interface[n] {
            DofClass::Interface
        } else {
            DofClass::Free
        };
        let first = merged.first().map(|m| m.0);
        let independent = merged
            .iter()
            .any(|(d, _, _)| first.is_some_and(|f| cross(f, *d).abs() > 1e-6));
        let dofs = match (first, independent) {
            (None, _) => NodeDofs {
                frame: [[1.0, 0.0], [0.0, 1.0]],
                class: [unknown, unknown],
            },
            (Some(_), true) => NodeDofs {
                frame: [[1.0, 0.0], [0.0, 1.0]],
                class: [DofClass::Known, DofClass::Known],
            },
            (Some(d), false) => NodeDofs {
                // Component 0 unknown along the perpendicular, component 1 known along d.
                frame: [[d[1], -d[0]], d],
                class: [unknown, DofClass::Known],
            },
        };
        out.push(dofs);
    }
    out
}

/// The error for two nodes `(tag, point, curve)` of body `name` at one point.
fn duplicate_nodes(
    mfile: &Path,
    name: &str,
    a: (usize, [f64; 2], i32),
    b: (usize, [f64; 2], i32),
) -> Error {
    Error::input(
        mfile,
        format!(
            "nodes {} and {} of body \"{name}\" are duplicates: both lie at {} (ends of curves {} \
             and {}), so the boundary does not join there; merge them (gmsh: Coherence; or one \
             Point per corner in the .geo, or Geometry.Tolerance)",
            a.0,
            b.0,
            fmt_point(a.1),
            a.2,
            b.2
        ),
    )
}
