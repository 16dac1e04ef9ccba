//! The interfaces of the model: node pairs matched between two bodies, the pair frames, and
//! the check that an interface is not held on one side only.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::Path;

use crate::error::{Error, Result};
use crate::input::mesh::Mesh;
use crate::input::scene::{InterfaceSpec, Scene};

use super::body::constrained_directions;
use super::{
    dot, first_time, fmt_point, norm, pair_values, sub, unit, Body, DofClass, Interface,
    InterfaceElement, Pair, Part, Role, SideNode,
};
use crate::input::pairing::{mortar_rows, Reach, SegmentGrid, Side};

#[allow(clippy::too_many_arguments)]
pub(super) fn build_interface(
    k: usize,
    (spec, group): (&InterfaceSpec, &str),
    curves: &BTreeSet<i32>,
    bodies: &[Body],
    mesh: &Mesh,
    curve_bodies: &BTreeMap<i32, Vec<usize>>,
    scene: &Scene,
    mfile: &Path,
    search: Option<f64>,
) -> Result<Interface> {
    let sfile = scene.path.as_path();
    let name = spec.name.as_str();
    let t0 = first_time(scene);
    let (ba, bb) = interface_bodies(name, curves, bodies, curve_bodies, sfile, mfile)?;
    let (a, b) = (&bodies[ba], &bodies[bb]);
    let on_interface = |body: &Body| -> Vec<usize> {
        (0..body.elements.len())
            .filter(|&e| body.elements[e].role == Role::Interface(k))
            .collect()
    };
    let sides = Sides {
        name,
        a,
        b,
        elems_a: on_interface(a),
        elems_b: on_interface(b),
        mfile,
    };
    // Where a node of A has no node of B at its place, the sides were meshed on their own:
    // rows over B's segments (`independent_sides`).
    let (a_to_b, by_position, matching) = sides.match_nodes();
    let (order, s_of) = sides.curve_order(a_to_b.len())?;
    let pair_of: HashMap<usize, usize> = order.iter().enumerate().map(|(j, &n)| (n, j)).collect();

    // Pairs with averaged normals of A.
    let mut normals = vec![[0.0f64; 2]; order.len()];
    for &e in &sides.elems_a {
        let el = &a.elements[e];
        for n in el.nodes {
            let j = pair_of[&n];
            normals[j][0] += el.normal[0];
            normals[j][1] += el.normal[1];
        }
    }
    let normals: Vec<[f64; 2]> = normals.into_iter().map(unit).collect();
    let rows = if matching {
        None
    } else {
        Some(independent_sides(
            name,
            (a, &sides.elems_a, &order, &normals),
            (b, &sides.elems_b),
            sides.reach(search),
            mfile,
        )?)
    };
    let mut pairs = Vec::with_capacity(order.len());
    for (j, &na) in order.iter().enumerate() {
        let normal = normals[j];
        let x = a.nodes[na];
        let (gap, cohesion, friction) = pair_values(spec, x, t0).map_err(|m| {
            Error::input(
                sfile,
                format!("{m} (node {})", mesh.node_tags[a.mesh_nodes[na]]),
            )
        })?;
        let mut pair = Pair {
            node_a: na,
            node_b: a_to_b[&na],
            x,
            normal,
            tangent: [-normal[1], normal[0]],
            s: s_of[j],
            gap,
            cohesion,
            friction,
            partners: Vec::new(),
            segment: None,
            gap_geometry: 0.0,
            weight: 0.0,
        };
        if let Some((rows, _)) = &rows {
            rows[j].apply(&mut pair, spec);
        }
        pairs.push(pair);
    }

    let (elements, b_nodes) = match rows {
        Some((rows, b_side)) => (sides.facing_elements(&rows, &pair_of), b_side),
        None => (sides.elements(&a_to_b, &pair_of)?, Vec::new()),
    };
    let length = sides.elems_a.iter().map(|&e| a.elements[e].length).sum();
    Ok(Interface {
        spec: spec.clone(),
        group: group.to_string(),
        body_a: ba,
        body_b: bb,
        pairs,
        elements,
        length,
        matched_by_position: by_position,
        b_nodes,
    })
}

/// The two bodies an interface joins, lower index first: every curve of the interface
/// bounds at most two bodies, and all its curves together exactly two.
fn interface_bodies(
    name: &str,
    curves: &BTreeSet<i32>,
    bodies: &[Body],
    curve_bodies: &BTreeMap<i32, Vec<usize>>,
    sfile: &Path,
    mfile: &Path,
) -> Result<(usize, usize)> {
    let mut involved: BTreeSet<usize> = BTreeSet::new();
    for c in curves {
        let on = curve_bodies.get(c).cloned().unwrap_or_default();
        if on.len() > 2 {
            return Err(Error::input(
                mfile,
                format!(
                    "interface \"{name}\": curve {c} bounds {} bodies; an interface joins exactly two",
                    on.len()
                ),
            ));
        }
        involved.extend(on);
    }
    let names = |set: &BTreeSet<usize>| -> String {
        set.iter()
            .map(|&b| format!("\"{}\"", bodies[b].name))
            .collect::<Vec<_>>()
            .join(", ")
    };
    if involved.len() != 2 {
        return Err(Error::input(
            sfile,
            format!(
                "[interface.{name}]: its curves bound {} bod{} ({}); an interface must be a curve \
                 shared by exactly two bodies (draw the joint once and use it in both surfaces' \
                 curve loops)",
                involved.len(),
                if involved.len() == 1 { "y" } else { "ies" },
                names(&involved)
            ),
        ));
    }
    let mut it = involved.iter();
    match (it.next(), it.next()) {
        (Some(&a), Some(&b)) => Ok((a.min(b), a.max(b))),
        _ => Err(Error::input(
            sfile,
            format!("[interface.{name}]: needs two bodies"),
        )),
    }
}

/// The two sides of one interface: its bodies A and B and their elements on it.
struct Sides<'a> {
    name: &'a str,
    a: &'a Body,
    b: &'a Body,
    elems_a: Vec<usize>,
    elems_b: Vec<usize>,
    mfile: &'a Path,
}

impl Sides<'_> {
    /// Matches B's interface nodes to A's: same mesh node, else same position. Returns A's
    /// node → B's node (`usize::MAX` where none), whether any pair was matched by position,
    /// and whether every node found its partner (else the sides were meshed on their own).
    fn match_nodes(&self) -> (BTreeMap<usize, usize>, bool, bool) {
        let (a, b) = (self.a, self.b);
        let (elems_a, elems_b) = (&self.elems_a, &self.elems_b);
        let mut b_by_mesh: HashMap<usize, usize> = HashMap::new();
        for &e in elems_b {
            for n in b.elements[e].nodes {
                b_by_mesh.insert(b.mesh_nodes[n], n);
            }
        }
        let min_len = elems_a
            .iter()
            .map(|&e| a.elements[e].length)
            .chain(elems_b.iter().map(|&e| b.elements[e].length))
            .fold(f64::INFINITY, f64::min);
        let tol = 1e-6 * min_len;
        let b_nodes: Vec<usize> = b_by_mesh.values().copied().collect();
        let mut a_to_b: BTreeMap<usize, usize> = BTreeMap::new();
        let mut by_position = false;
        let mut matching = true;
        for &e in elems_a {
            for n in a.elements[e].nodes {
                if a_to_b.contains_key(&n) {
                    continue;
                }
                let partner = match b_by_mesh.get(&a.mesh_nodes[n]) {
                    Some(&m) => Some(m),
                    None => {
                        by_position = true;
                        let x = a.nodes[n];
                        b_nodes
                            .iter()
                            .copied()
                            .find(|&m| norm(sub(b.nodes[m], x)) <= tol)
                    }
                };
                matching &= partner.is_some();
                a_to_b.insert(n, partner.unwrap_or(usize::MAX));
            }
        }
        if a_to_b.len() != b_nodes.len() {
            matching = false;
        }
        (a_to_b, by_position && matching, matching)
    }

    /// How far B may lie from A: `search` for a found interface; for a declared one any gap,
    /// and an interference up to the size of the elements.
    fn reach(&self, search: Option<f64>) -> Reach {
        match search {
            Some(d) => Reach {
                ahead: d,
                behind: d,
            },
            None => Reach {
                ahead: f64::INFINITY,
                behind: self
                    .elems_a
                    .iter()
                    .map(|&e| self.a.elements[e].length)
                    .chain(self.elems_b.iter().map(|&e| self.b.elements[e].length))
                    .fold(0.0, f64::max),
            },
        }
    }

    /// Orders A's interface nodes along the curve direction as drawn (mesh order), with
    /// their arc length; all `matched` nodes must lie on simple chains.
    fn curve_order(&self, matched: usize) -> Result<(Vec<usize>, Vec<f64>)> {
        let (name, a, mfile) = (self.name, self.a, self.mfile);
        let mut next_of: HashMap<usize, (usize, usize)> = HashMap::new(); // node → (elem, next node)
        let mut has_incoming: BTreeSet<usize> = BTreeSet::new();
        for &e in &self.elems_a {
            let el = &a.elements[e];
            let (s, t) = if !el.reversed {
                (el.nodes[0], el.nodes[1])
            } else {
                (el.nodes[1], el.nodes[0])
            };
            next_of.insert(s, (e, t));
            has_incoming.insert(t);
        }
        let mut starts: Vec<usize> = next_of
            .keys()
            .copied()
            .filter(|n| !has_incoming.contains(n))
            .collect();
        starts.sort_by_key(|&n| a.mesh_nodes[n]);
        if starts.is_empty() {
            // A closed interface (a whole inclusion): start anywhere.
            if let Some(&n) = next_of.keys().min() {
                starts.push(n);
            }
        }
        let mut order: Vec<usize> = Vec::new(); // A nodes in curve order
        let mut s_of: Vec<f64> = Vec::new();
        let mut seen: BTreeSet<usize> = BTreeSet::new();
        let mut s_acc = 0.0;
        for &s0 in &starts {
            let mut n = s0;
            if seen.insert(n) {
                order.push(n);
                s_of.push(s_acc);
            }
            while let Some(&(e, t)) = next_of.get(&n) {
                s_acc += a.elements[e].length;
                if !seen.insert(t) {
                    break;
                }
                order.push(t);
                s_of.push(s_acc);
                n = t;
            }
        }
        if order.len() != matched {
            return Err(Error::input(
                mfile,
                format!(
                    "interface \"{name}\": its elements on body \"{}\" do not form simple chains \
                     (a node joins more than two interface elements)",
                    a.name
                ),
            ));
        }
        Ok((order, s_of))
    }

    /// Interface elements where the sides were meshed on their own: A's elements, each with
    /// the element of B facing its start.
    fn facing_elements(
        &self,
        rows: &[IndependentRow],
        pair_of: &HashMap<usize, usize>,
    ) -> Vec<InterfaceElement> {
        self.elems_a
            .iter()
            .map(|&e| {
                let [s, t] = self.a.elements[e].nodes;
                let first = pair_of[&s];
                InterfaceElement {
                    elem_a: e,
                    elem_b: rows[first].segment.unwrap_or(self.elems_b[0]),
                    pairs: [first, pair_of[&t]],
                }
            })
            .collect()
    }

    /// Interface elements: A's element and B's element on the same node pair, which must
    /// lie on opposite sides.
    fn elements(
        &self,
        a_to_b: &BTreeMap<usize, usize>,
        pair_of: &HashMap<usize, usize>,
    ) -> Result<Vec<InterfaceElement>> {
        let (name, a, b, mfile) = (self.name, self.a, self.b, self.mfile);
        let mut b_elem_of: HashMap<(usize, usize), usize> = HashMap::new();
        for &e in &self.elems_b {
            let [s, t] = b.elements[e].nodes;
            b_elem_of.insert((s.min(t), s.max(t)), e);
        }
        let mut elements = Vec::with_capacity(self.elems_a.len());
        for &e in &self.elems_a {
            let [s, t] = a.elements[e].nodes;
            let (bs, bt) = (a_to_b[&s], a_to_b[&t]);
            let elem_b = match b_elem_of.get(&(bs.min(bt), bs.max(bt))) {
                Some(&eb) => eb,
                None => {
                    return Err(Error::input(
                        mfile,
                        format!(
                            "interface \"{name}\": element {} of body \"{}\" has no counterpart \
                             on body \"{}\" joining the same nodes",
                            a.elements[e].tag, a.name, b.name
                        ),
                    ))
                }
            };
            let ea = &a.elements[e];
            let eb = &b.elements[elem_b];
            if dot(ea.normal, eb.normal) > -0.999 {
                return Err(Error::input(
                    mfile,
                    format!(
                        "interface \"{name}\": bodies \"{}\" and \"{}\" lie on the same side of \
                         element {}: the bodies overlap there",
                        a.name, b.name, ea.tag
                    ),
                ));
            }
            elements.push(InterfaceElement {
                elem_a: e,
                elem_b,
                pairs: [pair_of[&s], pair_of[&t]],
            });
        }
        Ok(elements)
    }
}

/// The row of one pair of an interface whose sides were meshed on their own.
struct IndependentRow {
    partners: Vec<(usize, f64)>,
    /// B's node with the largest coefficient (the nearest interface node of B where none).
    main: usize,
    segment: Option<usize>,
    gap: f64,
    weight: f64,
}

impl IndependentRow {
    /// Gives `pair` this row over B's nodes; its gap takes the one measured from the geometry.
    fn apply(&self, pair: &mut Pair, spec: &InterfaceSpec) {
        pair.node_b = self.main;
        pair.partners = self.partners.clone();
        pair.segment = self.segment;
        pair.gap_geometry = self.gap;
        pair.weight = self.weight;
        pair.gap = super::with_geometry(spec, self.gap, pair.gap);
    }
}

/// The rows of A's interface nodes (in pair order) over B's interface elements, and B's
/// interface nodes with their frames (docs/formulation.md §5.6). Refused when nothing of B
/// faces A within `reach`.
fn independent_sides(
    name: &str,
    (a, elems_a, order, normals): (&Body, &[usize], &[usize], &[[f64; 2]]),
    (b, elems_b): (&Body, &[usize]),
    reach: Reach,
    mfile: &Path,
) -> Result<(Vec<IndependentRow>, Vec<SideNode>)> {
    let seg = |body: &Body, list: &[usize]| -> Vec<[usize; 2]> {
        list.iter().map(|&e| body.elements[e].nodes).collect()
    };
    let (seg_a, seg_b) = (seg(a, elems_a), seg(b, elems_b));
    let mut node_normal = vec![[0.0; 2]; a.nodes.len()];
    for (j, &n) in order.iter().enumerate() {
        node_normal[n] = normals[j];
    }
    let lines: Vec<([f64; 2], [f64; 2])> = seg_b
        .iter()
        .map(|&[p, q]| (b.nodes[p], b.nodes[q]))
        .collect();
    let mean =
        lines.iter().map(|(p, q)| norm(sub(*q, *p))).sum::<f64>() / lines.len().max(1) as f64;
    let grid = SegmentGrid::new(&lines, mean);
    let far = if reach.ahead.is_finite() {
        reach.ahead.max(reach.behind)
    } else {
        f64::INFINITY
    };
    let cands = |p: [f64; 2], q: [f64; 2]| -> Vec<usize> {
        if far.is_finite() {
            grid.near(p, q, far)
        } else {
            (0..seg_b.len()).collect()
        }
    };
    let found = mortar_rows(
        &Side {
            x: &a.nodes,
            segments: &seg_a,
        },
        &node_normal,
        &Side {
            x: &b.nodes,
            segments: &seg_b,
        },
        reach,
        &cands,
    );
    if found.is_empty() {
        return Err(Error::input(
            mfile,
            format!(
                "interface \"{name}\": no part of body \"{}\" faces body \"{}\" along the \
                 interface (the curves of its two sides must face each other, outward normals \
                 opposed within 60°); check the curves the interface holds",
                b.name, a.name
            ),
        ));
    }
    let b_side = side_nodes(b, elems_b);
    let rows = order
        .iter()
        .map(|&n| match found.get(&n) {
            Some(r) => IndependentRow {
                main: r
                    .coefs
                    .iter()
                    .max_by(|x, y| x.1.total_cmp(&y.1))
                    .map_or(b_side[0].node, |c| c.0),
                partners: r.coefs.clone(),
                segment: Some(elems_b[r.segment]),
                gap: r.gap,
                weight: r.weight,
            },
            None => IndependentRow {
                main: b_side
                    .iter()
                    .map(|p| p.node)
                    .min_by(|&x, &y| {
                        norm(sub(b.nodes[x], a.nodes[n]))
                            .total_cmp(&norm(sub(b.nodes[y], a.nodes[n])))
                    })
                    .unwrap_or(0),
                partners: Vec::new(),
                segment: None,
                gap: 0.0,
                weight: 0.0,
            },
        })
        .collect();
    Ok((rows, b_side))
}

/// B's interface nodes, in node order, with the frame of their unknowns: the normal opposite
/// to B's averaged outward normal (A's direction).
fn side_nodes(b: &Body, elems_b: &[usize]) -> Vec<SideNode> {
    let mut b_normal: BTreeMap<usize, [f64; 2]> = BTreeMap::new();
    for &e in elems_b {
        let el = &b.elements[e];
        for n in el.nodes {
            let v = b_normal.entry(n).or_insert([0.0; 2]);
            v[0] -= el.normal[0];
            v[1] -= el.normal[1];
        }
    }
    b_normal
        .iter()
        .map(|(&node, &v)| {
            let normal = unit(v);
            SideNode {
                node,
                normal,
                tangent: [-normal[1], normal[0]],
            }
        })
        .collect()
}

/// The name of the part of Physical Curve `group` between bodies `a` and `b` (a first), when
/// the curve joins several pairs of bodies: `joints[brick_1|brick_2]`.
pub(super) fn split_name(group: &str, a: &str, b: &str) -> String {
    format!("{group}[{a}|{b}]")
}

/// The curves of an interface group per pair of bodies that share them (bodies by index,
/// smaller first). When the group joins two or more pairs, each of its curves must be
/// shared by exactly two bodies.
pub(super) fn pairs_of_bodies(
    group: &str,
    curves: &[i32],
    curve_bodies: &BTreeMap<i32, Vec<usize>>,
    scene: &Scene,
    sfile: &Path,
) -> Result<BTreeMap<(usize, usize), BTreeSet<i32>>> {
    let mut by_pair: BTreeMap<(usize, usize), BTreeSet<i32>> = BTreeMap::new();
    for c in curves {
        if let Some([a, b]) = curve_bodies.get(c).map(Vec::as_slice) {
            by_pair
                .entry(((*a).min(*b), (*a).max(*b)))
                .or_default()
                .insert(*c);
        }
    }
    if by_pair.len() > 1 {
        for c in curves {
            let on = curve_bodies.get(c).map(Vec::as_slice).unwrap_or(&[]);
            if on.len() != 2 {
                let names: Vec<&str> = on.iter().map(|&b| scene.bodies[b].name.as_str()).collect();
                return Err(Error::input(
                    sfile,
                    format!(
                        "interface \"{group}\" joins several pairs of bodies, but its curve {c} \
                         bounds {} bod{} ({}): each curve of an interface is shared by exactly \
                         two bodies; move curve {c} to another Physical Curve",
                        on.len(),
                        if on.len() == 1 { "y" } else { "ies" },
                        if names.is_empty() {
                            "none".to_string()
                        } else {
                            names.join(", ")
                        }
                    ),
                ));
            }
        }
    }
    Ok(by_pair)
}

/// Where an interface ends on a displacement condition that fixes one direction (a symmetry
/// plane crossing a curved joint), the pair frame is turned onto that direction: the averaged
/// normal of a chord differs from the plane's by half an element's angle, and the frame of a
/// pair must contain the prescribed direction. Turns larger than 30° are left to the
/// assembly, which reports an oblique condition.
pub(super) fn align_pair_frames(bodies: &[Body], interfaces: &mut [Interface]) {
    for it in interfaces.iter_mut() {
        let a = &bodies[it.body_a];
        for p in it.pairs.iter_mut() {
            align(a, p.node_a, &mut p.normal, &mut p.tangent);
        }
        // B's own nodes where the sides were meshed on their own.
        let b = &bodies[it.body_b];
        for p in it.b_nodes.iter_mut() {
            align(b, p.node, &mut p.normal, &mut p.tangent);
        }
    }
}

/// Turns the frame (normal, tangent) of node n of a body onto its one prescribed direction
/// (see [`align_pair_frames`]).
fn align(body: &Body, n: usize, normal: &mut [f64; 2], tangent: &mut [f64; 2]) {
    let limit = 30f64.to_radians().cos();
    let d = body.dofs[n];
    let one_known = d.class[1] == DofClass::Known && d.class[0] != DofClass::Known;
    if !one_known {
        return;
    }
    let k = d.frame[1];
    let (cn, ct) = (dot(k, *normal), dot(k, *tangent));
    if cn.abs() >= ct.abs() && cn.abs() >= limit {
        *normal = [k[0] * cn.signum(), k[1] * cn.signum()];
        *tangent = [-normal[1], normal[0]];
    } else if ct.abs() > cn.abs() && ct.abs() >= limit {
        *tangent = [k[0] * ct.signum(), k[1] * ct.signum()];
        *normal = [tangent[1], -tangent[0]];
    }
}

/// A displacement condition that reaches an interface node must hold both sides of the
/// pair along each of the pair's directions, or neither (the assembly cannot join a known
/// displacement on one side to an unknown one on the other): refused here, so that `check`
/// says what `run` would.
pub(super) fn check_one_sided(
    bodies: &[Body],
    interfaces: &[Interface],
    parts: &[Part],
    sfile: &Path,
) -> Result<()> {
    // The share of direction e that the known components of a node cover (0 to 1).
    let known = |b: &Body, n: usize, e: [f64; 2]| -> f64 {
        let d = b.dofs[n];
        (0..2)
            .filter(|&k| d.class[k] == DofClass::Known)
            .map(|k| dot(d.frame[k], e).powi(2))
            .sum()
    };
    // The boundary conditions of a body that reach node n.
    let held_by = |b: &Body, n: usize| -> Vec<String> {
        let mut names: Vec<String> = b
            .elements
            .iter()
            .filter(|e| e.nodes.contains(&n))
            .flat_map(|e| constrained_directions(e, parts))
            .map(|(_, pi, _)| parts[pi].spec.name.clone())
            .collect();
        names.dedup();
        names
    };
    // Sides meshed on their own: the rows leave out what is held (docs/formulation.md §5.6).
    for it in interfaces.iter().filter(|it| !it.independent()) {
        let (a, b) = (&bodies[it.body_a], &bodies[it.body_b]);
        for p in &it.pairs {
            for (e, what) in [(p.normal, "normal"), (p.tangent, "tangential")] {
                let (ka, kb) = (known(a, p.node_a, e), known(b, p.node_b, e));
                let whole = |k: f64| !(1e-9..=1.0 - 1e-9).contains(&k);
                if whole(ka) && whole(kb) && (ka > 0.5) == (kb > 0.5) {
                    continue;
                }
                let (held, loose) = if ka >= kb { (a, b) } else { (b, a) };
                let node = if ka >= kb { p.node_a } else { p.node_b };
                let by = held_by(held, node)
                    .iter()
                    .map(|n| format!("`boundary.{n}`"))
                    .collect::<Vec<_>>()
                    .join(", ");
                return Err(Error::input(
                    sfile,
                    format!(
                        "interface \"{}\" at {}: {by} prescribes the {what} displacement of body \
                         \"{}\" there, but nothing prescribes it on body \"{}\" across the \
                         interface: a displacement component at an interface node is prescribed \
                         on both bodies or on neither; extend the condition to the other body's \
                         boundary that ends there, or end it before the interface",
                        it.spec.name,
                        fmt_point(p.x),
                        held.name,
                        loose.name
                    ),
                ));
            }
        }
    }
    Ok(())
}
