//! Interfaces found from the drawing (`[contact]`, docs/scene.md §6b): the traction-free
//! boundary pieces of two bodies that face each other within `search` become an interface
//! `contact[A|B]` with the `[defaults.interface]` table.
//!
//! [`facing_pairs`] (a uniform grid over the candidate elements) finds the pairs of elements
//! of different bodies that face each other within `search`. Elements on a declared interface, on a displacement condition or under a load are
//! not candidates: a declared interface between the same boundaries wins.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use crate::error::{Error, Result};
use crate::input::mesh::{Line, Mesh};
use crate::input::pairing::{facing_pairs, BodySegment};
use crate::input::scene::{Condition, ContactSpec, InterfaceSpec, Scene};

use super::overlap::overlap_depth;
use super::{fmt_num, fmt_point, split_name, Body, Interface, Part, Role, FOUND_GROUP};
use crate::input::tables::Resolved;

/// One interface found: its table and the elements of each body (A first).
pub(super) struct Found {
    pub spec: InterfaceSpec,
    pub body_a: usize,
    pub body_b: usize,
    pub elems_a: Vec<usize>,
    pub elems_b: Vec<usize>,
}

/// With `[contact]`: finds the interfaces, gives their elements the role of their interface
/// and appends them to `found` (table, group [`FOUND_GROUP`], curves) and to `resolved`.
pub(super) fn add_found(
    scene: &Scene,
    (bodies, parts): (&mut [Body], &[Part]),
    found: &mut Vec<(InterfaceSpec, String, BTreeSet<i32>)>,
    resolved: &mut Vec<Resolved>,
) -> Result<()> {
    let Some(cs) = &scene.contact else {
        return Ok(());
    };
    for f in find_contacts(scene, cs, bodies, parts, &scene.path)? {
        let curves = f.assign(found.len(), bodies);
        resolved.push(Resolved {
            table: "[defaults.interface]".into(),
            group: f.spec.name.clone(),
        });
        found.push((f.spec, FOUND_GROUP.to_string(), curves));
    }
    Ok(())
}

impl Found {
    /// Gives the found elements the role of interface k; returns their curves.
    pub(crate) fn assign(&self, k: usize, bodies: &mut [Body]) -> BTreeSet<i32> {
        let mut curves = BTreeSet::new();
        for (b, list) in [(self.body_a, &self.elems_a), (self.body_b, &self.elems_b)] {
            for &e in list {
                let el = &mut bodies[b].elements[e];
                el.role = Role::Interface(k);
                curves.insert(el.curve);
            }
        }
        curves
    }
}

/// True when a boundary part leaves its elements free to touch another body: traction-free
/// (not listed, or only zero tractions).
fn traction_free(part: &Part) -> bool {
    !part.listed
        || part
            .spec
            .components
            .iter()
            .all(|c| matches!(c, Condition::Traction(v) if v.is_zero()))
}

/// The candidate elements of `[contact]`, as (body, element), and their segments: the
/// traction-free boundary elements of the bodies that `spec.bodies` names.
fn candidates(
    spec: &ContactSpec,
    bodies: &[Body],
    parts: &[Part],
) -> (Vec<(usize, usize)>, Vec<BodySegment>) {
    let mut cand: Vec<(usize, usize)> = Vec::new();
    let mut segs: Vec<BodySegment> = Vec::new();
    for (bi, body) in bodies.iter().enumerate() {
        if !spec.bodies.matches(&body.name) {
            continue;
        }
        for (ei, e) in body.elements.iter().enumerate() {
            let Role::Boundary(pi) = e.role else { continue };
            if !traction_free(&parts[pi]) {
                continue;
            }
            cand.push((bi, ei));
            segs.push(BodySegment {
                body: bi,
                a: body.nodes[e.nodes[0]],
                b: body.nodes[e.nodes[1]],
                normal: e.normal,
            });
        }
    }
    (cand, segs)
}

/// A piece shorter than this share of its element is not cut off (no sliver elements): the
/// element goes to the body it faces the longest (`find_contacts`).
const MIN_CUT_SHARE: f64 = 0.05;

/// Where a line element of the mesh must be cut so that each piece faces one body.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Cut {
    /// gmsh tag of the line element.
    pub tag: usize,
    /// The points of the element where the body it faces changes, from its start.
    pub points: Vec<[f64; 2]>,
}

/// The elements that face more than one body across `[contact]`'s search (a foundation's
/// top under two stones, a brick's top under the two bricks of the course above): each is
/// cut where the body it faces changes, half-way between the ends of the bodies' facing
/// pieces in projection, so that every element of an interface found faces its other body
/// only (an element belongs to one interface: uncut, it would leave one of them without
/// support over its length).
pub(super) fn cuts(spec: &ContactSpec, bodies: &[Body], parts: &[Part]) -> Vec<Cut> {
    let (cand, segs) = candidates(spec, bodies, parts);
    let pairs = facing_pairs(&segs, spec.search);
    let mut out = Vec::new();
    for (i, hull) in facing_hulls(&segs, &pairs) {
        if hull.len() < 2 {
            continue;
        }
        let mut spans: Vec<(f64, f64)> = hull.into_values().collect();
        spans.sort_by(|a, b| (a.0 + a.1).total_cmp(&(b.0 + b.1)));
        let mut params: Vec<f64> = Vec::new();
        for w in spans.windows(2) {
            let t = 0.5 * (w[0].1 + w[1].0);
            let last = params.last().copied().unwrap_or(0.0);
            if t - last >= MIN_CUT_SHARE && t <= 1.0 - MIN_CUT_SHARE {
                params.push(t);
            }
        }
        if params.is_empty() {
            continue;
        }
        let (s, (bi, ei)) = (&segs[i], cand[i]);
        let d = [s.b[0] - s.a[0], s.b[1] - s.a[1]];
        out.push(Cut {
            tag: bodies[bi].elements[ei].tag,
            points: params
                .iter()
                .map(|&t| [s.a[0] + t * d[0], s.a[1] + t * d[1]])
                .collect(),
        });
    }
    out
}

/// Per segment that faces others: each body it faces, with the hull of that body's facing
/// segments projected on it (parameters along it from its start, within [0, 1]).
fn facing_hulls(
    segs: &[BodySegment],
    pairs: &[(usize, usize)],
) -> BTreeMap<usize, BTreeMap<usize, (f64, f64)>> {
    let mut out: BTreeMap<usize, BTreeMap<usize, (f64, f64)>> = BTreeMap::new();
    for &(i, j) in pairs {
        for (x, y) in [(i, j), (j, i)] {
            let (s, t) = (&segs[x], &segs[y]);
            let d = [s.b[0] - s.a[0], s.b[1] - s.a[1]];
            let l2 = d[0] * d[0] + d[1] * d[1];
            let at = |p: [f64; 2]| ((p[0] - s.a[0]) * d[0] + (p[1] - s.a[1]) * d[1]) / l2;
            let (ta, tb) = (at(t.a), at(t.b));
            let (lo, hi) = (ta.min(tb).max(0.0), ta.max(tb).min(1.0));
            let h = out.entry(x).or_default().entry(t.body).or_insert((lo, hi));
            *h = (h.0.min(lo), h.1.max(hi));
        }
    }
    out
}

/// Cuts the mesh's line elements at the points of `cuts`: each new node and element takes
/// the next free gmsh tag; the pieces keep their element's curve and direction. Triangles
/// are left as they are (the new node lies on their edge: the boundary is the same line).
pub(super) fn apply_cuts(mesh: &mut Mesh, cuts: &[Cut]) {
    let mut node_tag = mesh.node_tags.iter().max().copied().unwrap_or(0);
    let mut elem_tag = mesh
        .lines
        .iter()
        .map(|l| l.tag)
        .chain(mesh.triangles.iter().map(|t| t.tag))
        .max()
        .unwrap_or(0);
    let line_of: BTreeMap<usize, usize> = mesh
        .lines
        .iter()
        .enumerate()
        .map(|(i, l)| (l.tag, i))
        .collect();
    for cut in cuts {
        let Some(&li) = line_of.get(&cut.tag) else {
            continue;
        };
        let Line {
            nodes: [n0, n1],
            curve,
            ..
        } = mesh.lines[li];
        let (p, q) = (mesh.nodes[n0], mesh.nodes[n1]);
        let d = [q[0] - p[0], q[1] - p[1]];
        let l2 = d[0] * d[0] + d[1] * d[1];
        let mut params: Vec<f64> = cut
            .points
            .iter()
            .map(|x| ((x[0] - p[0]) * d[0] + (x[1] - p[1]) * d[1]) / l2)
            .collect();
        params.sort_by(f64::total_cmp);
        let mut prev = n0;
        for (k, t) in params.into_iter().enumerate() {
            node_tag += 1;
            mesh.nodes.push([p[0] + t * d[0], p[1] + t * d[1]]);
            mesh.node_tags.push(node_tag);
            let m = mesh.nodes.len() - 1;
            if k == 0 {
                mesh.lines[li].nodes = [n0, m];
            } else {
                elem_tag += 1;
                mesh.lines.push(Line {
                    tag: elem_tag,
                    nodes: [prev, m],
                    curve,
                });
            }
            prev = m;
        }
        elem_tag += 1;
        mesh.lines.push(Line {
            tag: elem_tag,
            nodes: [prev, n1],
            curve,
        });
    }
}

/// Finds the facing pieces of the bodies that `spec.bodies` names. Each found interface is
/// named `contact[A|B]` (bodies in scene order) and takes `[defaults.interface]`.
pub(super) fn find_contacts(
    scene: &Scene,
    spec: &ContactSpec,
    bodies: &[Body],
    parts: &[Part],
    sfile: &Path,
) -> Result<Vec<Found>> {
    let (cand, segs) = candidates(spec, bodies, parts);
    let pairs = facing_pairs(&segs, spec.search);
    // An element belongs to one interface: where it still faces several bodies (a piece
    // too short to cut off, `cuts`), the body it faces the longest.
    let best: BTreeMap<usize, usize> = facing_hulls(&segs, &pairs)
        .into_iter()
        .filter_map(|(i, hull)| {
            let longest = hull
                .into_iter()
                .max_by(|a, b| (a.1 .1 - a.1 .0).total_cmp(&(b.1 .1 - b.1 .0)))?;
            Some((i, longest.0))
        })
        .collect();
    // Per pair of bodies (scene order): the elements of each that face the other.
    let mut by_pair: BTreeMap<(usize, usize), [Vec<usize>; 2]> = BTreeMap::new();
    for (i, j) in pairs {
        let ((bi, ei), (bj, ej)) = (cand[i], cand[j]);
        let sides = by_pair.entry((bi, bj)).or_default();
        if best.get(&i) == Some(&bj) {
            sides[0].push(ei);
        }
        if best.get(&j) == Some(&bi) {
            sides[1].push(ej);
        }
    }
    // Bodies that face each other only over such short pieces touch at a point.
    by_pair.retain(|_, sides| !sides[0].is_empty() && !sides[1].is_empty());
    if by_pair.is_empty() {
        return Ok(Vec::new());
    }
    let Some(default) = &scene.tables.default_interface else {
        return Err(Error::input(
            sfile,
            "[contact] found facing boundaries and gives each such interface the \
             [defaults.interface] table, but the scene has none: add [defaults.interface] \
             (e.g. model = \"unilateral\", tangential = \"friction\", friction = 0.6)",
        ));
    };
    Ok(by_pair
        .into_iter()
        .map(|((a, b), [mut ea, mut eb])| {
            ea.sort_unstable();
            ea.dedup();
            eb.sort_unstable();
            eb.dedup();
            Found {
                spec: InterfaceSpec {
                    name: split_name("contact", &bodies[a].name, &bodies[b].name),
                    ..default.clone()
                },
                body_a: a,
                body_b: b,
                elems_a: ea,
                elems_b: eb,
            }
        })
        .collect())
}

/// Bodies that [contact] pairs must touch or lie apart: a found interface whose gap from
/// the geometry is negative beyond rounding is an overlap of the drawing (an interference
/// fit is declared as an `[interface.NAME]`).
pub(super) fn check_found_gaps(
    bodies: &[Body],
    found: &[Interface],
    mfile: &Path,
    scale: f64,
) -> Result<()> {
    for it in found {
        let Some(p) = it
            .pairs
            .iter()
            .filter(|p| !p.partners.is_empty())
            .min_by(|a, b| a.gap_geometry.total_cmp(&b.gap_geometry))
        else {
            continue;
        };
        if p.gap_geometry >= -1e-9 * scale {
            continue;
        }
        let (a, b) = (&bodies[it.body_a], &bodies[it.body_b]);
        let depth = overlap_depth(a, b)
            .max(overlap_depth(b, a))
            .max(-p.gap_geometry);
        return Err(Error::input(
            mfile,
            format!(
                "bodies \"{}\" and \"{}\" overlap by {} (at {}): [contact] pairs bodies that \
                 touch or lie apart; fix the drawing, or declare the interference fit as an \
                 [interface.NAME] between their two curves",
                a.name,
                b.name,
                fmt_num(depth),
                fmt_point(p.x)
            ),
        ));
    }
    Ok(())
}
