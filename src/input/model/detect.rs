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
    pub fn assign(&self, k: usize, bodies: &mut [Body]) -> BTreeSet<i32> {
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

/// Finds the facing pieces of the bodies that `spec.bodies` names. Each found interface is
/// named `contact[A|B]` (bodies in scene order) and takes `[defaults.interface]`.
pub(super) fn find_contacts(
    scene: &Scene,
    spec: &ContactSpec,
    bodies: &[Body],
    parts: &[Part],
    sfile: &Path,
) -> Result<Vec<Found>> {
    // Candidate elements: (body, element) and their segments.
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
    // Per pair of bodies (scene order): the elements of each that face the other.
    let mut by_pair: BTreeMap<(usize, usize), [Vec<usize>; 2]> = BTreeMap::new();
    for (i, j) in facing_pairs(&segs, spec.search) {
        let ((bi, ei), (bj, ej)) = (cand[i], cand[j]);
        let sides = by_pair.entry((bi, bj)).or_default();
        sides[0].push(ei);
        sides[1].push(ej);
    }
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
