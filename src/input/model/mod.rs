//! The model: bodies with oriented boundary loops, boundary parts, interfaces with matched
//! node pairs, and the class of every displacement degree of freedom.
//!
//! Place in the flow: `scene` + `mesh` → [`Model`] → assembly. Everything geometric that
//! the boundary element method needs is decided here, once:
//!
//! * **Bodies** are Physical Surfaces. A body's boundary is the set of bounding curves of its
//!   surfaces (a curve bounding two surfaces of the same body is internal and dropped); its
//!   2-node line elements are chained into closed loops. The outer loop is oriented
//!   counter-clockwise and holes clockwise, by signed area and nesting, whatever direction
//!   gmsh drew each curve in (docs/formulation.md §1.1).
//! * **Nodes are per body**: a mesh node on an interface appears once in each of the two
//!   bodies (docs/formulation.md §5.1).
//! * **Boundary parts** are Physical Curves with per-component conditions; curves the scene
//!   does not list are traction-free.
//! * **Interfaces** are Physical Curves shared by exactly two bodies, turned into node pairs
//!   (matched by mesh node, or by position when the two sides were drawn as separate
//!   coincident curves) with the outward normal of the first body (docs/formulation.md §5.4–§5.5).
//! * **Double traction nodes** (`traction_break`) at corners and changes of condition
//!   (docs/formulation.md §2.2, §8.3).
//! * **Node classes** per displacement component (docs/formulation.md §2.2): U1 known (touching a
//!   displacement condition in that direction), U0 unknown on an interface, U2 unknown
//!   elsewhere.
//!
//! Checks made here (all input errors, exit 2): group names and kinds, open loops (with the
//! gmsh hint about untagged curves), zero-length elements, crossing or overlapping bodies,
//! interface nodes that do not match, expressions undefined at a node, and bodies that
//! nothing holds against rigid motion.
//!
//! Files: this one holds the types and [`build`]; `body.rs` builds one body (loops, traction
//! breaks, node classes), `interface.rs` the interfaces, `overlap.rs` and `checks.rs` the
//! checks on the built bodies.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::{Path, PathBuf};

use crate::error::{did_you_mean, Error, Result};
use crate::input::mesh::Mesh;
use crate::input::scene::{BoundarySpec, InitialState, InterfaceSpec, Scene, Tangential};
use crate::input::tables::{self, Resolved};
use crate::vec2::{cross, dot, norm, sub};

mod body;
mod checks;
mod curves;
mod detect;
mod interface;
mod overlap;
pub(crate) mod wrench;

pub(crate) use body::winding;
use body::{build_body, mark_traction_breaks, node_dofs};
use checks::{check_held, check_values};
use curves::*;
use interface::split_name;
use interface::{align_pair_frames, build_interface, check_one_sided, pairs_of_bodies};
use overlap::check_overlaps;

/// Where a boundary element belongs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// A boundary part (index into [`Model::parts`]).
    Boundary(usize),
    /// An interface (index into [`Model::interfaces`]).
    Interface(usize),
}

/// A straight 2-node boundary element of one body, oriented along its loop (body on the left).
#[derive(Debug, Clone)]
pub struct Element {
    /// Body-local node indices, start then end.
    pub nodes: [usize; 2],
    /// gmsh element tag.
    pub tag: usize,
    /// gmsh curve entity the element lies on.
    pub curve: i32,
    pub role: Role,
    pub length: f64,
    /// Unit tangent, start → end.
    pub tangent: [f64; 2],
    /// Unit outward normal `(τ_y, −τ_x)`.
    pub normal: [f64; 2],
    /// Index of the loop the element belongs to.
    pub loop_index: usize,
    /// True when tractions are discontinuous at the start node: a double traction node
    /// (corner, or change of part or condition).
    pub traction_break: bool,
    /// True when the element runs against the direction gmsh drew its curve in.
    pub reversed: bool,
}

/// A closed boundary loop: element indices in traversal order.
#[derive(Debug, Clone)]
pub struct Loop {
    pub elements: Vec<usize>,
    /// Signed area enclosed (positive: counter-clockwise outer loop; negative: hole).
    pub area: f64,
    pub is_hole: bool,
}

/// Class of one displacement component at a node (docs/formulation.md §2.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DofClass {
    /// U1: prescribed by a displacement condition.
    Known,
    /// U0: unknown, on an interface.
    Interface,
    /// U2: unknown, elsewhere.
    Free,
}

/// The two displacement components of a node: their directions and classes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodeDofs {
    /// Unit directions of components 0 and 1 (orthonormal).
    pub frame: [[f64; 2]; 2],
    pub class: [DofClass; 2],
}

/// One elastic body: a Physical Surface.
#[derive(Debug, Clone)]
pub struct Body {
    pub name: String,
    pub young: f64,
    pub poisson: f64,
    pub body_force: Option<[f64; 2]>,
    /// The scene's body force (numbers or expressions in t), evaluated into `body_force` at
    /// the model's pseudo-time.
    pub body_force_spec: Option<[crate::input::expr::Scalar; 2]>,
    /// gmsh surface entities of the body.
    pub surfaces: Vec<i32>,
    /// Boundary node coordinates (body-local numbering).
    pub nodes: Vec<[f64; 2]>,
    /// Index into `Mesh::nodes` of each body node.
    pub mesh_nodes: Vec<usize>,
    pub elements: Vec<Element>,
    pub loops: Vec<Loop>,
    pub dofs: Vec<NodeDofs>,
    /// Mesh triangles of the body (mesh node indices), the grid for interior fields.
    pub triangles: Vec<[usize; 3]>,
    pub area: f64,
}

impl Body {
    pub fn perimeter(&self) -> f64 {
        self.elements.iter().map(|e| e.length).sum()
    }

    /// The mesh nodes of the body's triangles, each once (the interior field's points).
    pub(crate) fn triangle_node_count(&self) -> usize {
        let mut v: Vec<usize> = self.triangles.iter().flatten().copied().collect();
        v.sort_unstable();
        v.dedup();
        v.len()
    }

    /// Winding number of the boundary around x: non-zero inside the body (holes cancel).
    pub(crate) fn winding_number(&self, x: [f64; 2]) -> i32 {
        winding(
            x,
            self.elements
                .iter()
                .map(|e| (self.nodes[e.nodes[0]], self.nodes[e.nodes[1]])),
        )
    }

    /// Number of nodes in each class (U1, U0, U2), counting a node once per component.
    pub fn dof_counts(&self) -> [usize; 3] {
        let mut c = [0; 3];
        for d in &self.dofs {
            for k in d.class {
                match k {
                    DofClass::Known => c[0] += 1,
                    DofClass::Interface => c[1] += 1,
                    DofClass::Free => c[2] += 1,
                }
            }
        }
        c
    }
}

/// A boundary part: a Physical Curve that is not an interface.
#[derive(Debug, Clone)]
pub struct Part {
    pub spec: BoundarySpec,
    /// False for a Physical Curve the scene does not list (traction-free).
    pub listed: bool,
    /// Elements per body (body index → count).
    pub elements: BTreeMap<usize, usize>,
    pub length: f64,
}

/// The tributary length of each of the points `x`: half of each segment `[j, k]` of
/// `elements` that joins it to another (∫ψ_j ds of the P1 hats).
pub(crate) fn tributary_lengths(
    x: &[[f64; 2]],
    elements: impl Iterator<Item = [usize; 2]>,
) -> Vec<f64> {
    let mut w = vec![0.0; x.len()];
    for [j, k] in elements {
        let l = (x[k][0] - x[j][0]).hypot(x[k][1] - x[j][1]);
        w[j] += 0.5 * l;
        w[k] += 0.5 * l;
    }
    w
}

/// A matched interface node pair.
#[derive(Debug, Clone)]
pub struct Pair {
    /// Body-local node index in the first body (A) and in the second (B).
    pub node_a: usize,
    pub node_b: usize,
    /// Position (of A's node).
    pub x: [f64; 2],
    /// Unit outward normal of A at the node (averaged over A's adjacent interface elements).
    pub normal: [f64; 2],
    /// Unit tangent `(−n_y, n_x)`.
    pub tangent: [f64; 2],
    /// Arc length from the curve's first node.
    pub s: f64,
    /// Initial normal gap h ≥ 0 (open zones).
    pub gap: f64,
    /// Cohesion c ≥ 0 (closed zones).
    pub cohesion: f64,
    /// Coulomb coefficient μ ≥ 0 (`tangential = "friction"`; 0 otherwise).
    pub friction: f64,
    /// Where the two sides were meshed on their own (docs/formulation.md §5.6): B's nodes and
    /// the coefficients of the pair's rows, `u^B = Σ c_k u^B_k` (they sum to one). Empty for
    /// a node pair (B's node is `node_b`) and for a node of A that faces nothing of B (no
    /// rows: reported open).
    pub partners: Vec<(usize, f64)>,
    /// Sides meshed on their own: B's element facing the node (body-local index).
    pub segment: Option<usize>,
    /// Sides meshed on their own: the normal gap measured from the geometry, which `gap`
    /// includes on unilateral interfaces (0 for node pairs).
    pub gap_geometry: f64,
    /// Sides meshed on their own: the tributary length of the rows, ∫ψ_j ds over the part of
    /// the node's elements that faces B (node pairs: see [`Interface::weights`]).
    pub weight: f64,
}

/// A node of body B on an interface whose sides were meshed on their own, with the frame of
/// its interface unknowns: `normal` is the opposite of B's outward normal (A's direction).
#[derive(Debug, Clone, Copy)]
pub struct SideNode {
    pub node: usize,
    pub normal: [f64; 2],
    pub tangent: [f64; 2],
}

/// An interface element: the same segment seen from both bodies.
#[derive(Debug, Clone, Copy)]
pub struct InterfaceElement {
    /// Element index in body A and in body B (sides meshed on their own: B's element facing
    /// the start of A's).
    pub elem_a: usize,
    pub elem_b: usize,
    /// Pair indices at A's start and end nodes.
    pub pairs: [usize; 2],
}

/// A Physical Curve shared by two bodies.
#[derive(Debug, Clone)]
pub struct Interface {
    /// Its table; `spec.name` is the Physical Curve's name, or `CURVE[A|B]` for the part
    /// between bodies A and B of a curve that joins several pairs of bodies.
    pub spec: InterfaceSpec,
    /// The Physical Curve.
    pub group: String,
    /// Body indices; A comes first in the scene.
    pub body_a: usize,
    pub body_b: usize,
    /// Pairs in order of arc length.
    pub pairs: Vec<Pair>,
    pub elements: Vec<InterfaceElement>,
    pub length: f64,
    /// True when the two sides were separate coincident curves matched by position.
    pub matched_by_position: bool,
    /// B's interface nodes where the two sides were meshed on their own (their nodes do not
    /// pair up): the pairs are then A's nodes, whose rows reach B's nodes through
    /// [`Pair::partners`]. Empty for node pairs.
    pub b_nodes: Vec<SideNode>,
}

impl Interface {
    /// True when the two sides were meshed on their own (rows over B's segments).
    pub fn independent(&self) -> bool {
        !self.b_nodes.is_empty()
    }

    /// The number of interface points of side A (`side_a`) or B: the index range of the
    /// `pair` of that body's interface unknowns.
    pub(crate) fn point_count(&self, side_a: bool) -> usize {
        if side_a || !self.independent() {
            self.pairs.len()
        } else {
            self.b_nodes.len()
        }
    }

    /// Interface point j of side A (`side_a`) or B: its body-local node and the frame
    /// `[tangent, normal]` of its unknowns.
    pub fn point(&self, side_a: bool, j: usize) -> (usize, [[f64; 2]; 2]) {
        if !side_a && self.independent() {
            let p = &self.b_nodes[j];
            return (p.node, [p.tangent, p.normal]);
        }
        let p = &self.pairs[j];
        (
            if side_a { p.node_a } else { p.node_b },
            [p.tangent, p.normal],
        )
    }

    /// The tributary length of each pair: half of each adjacent element of A (node pairs),
    /// or the part of that which faces B (sides meshed on their own).
    pub fn weights(&self) -> Vec<f64> {
        if self.independent() {
            return self.pairs.iter().map(|p| p.weight).collect();
        }
        let x: Vec<[f64; 2]> = self.pairs.iter().map(|p| p.x).collect();
        tributary_lengths(&x, self.elements.iter().map(|e| e.pairs))
    }

    /// Where B meets the rows of pair j, relative to the point `from`: B's node (node pairs)
    /// or the point `Σ c_k x_k` of B's partners (sides meshed on their own; A's node where
    /// it has none), summed as `Σ c_k (x_k − from)` (the coefficients sum to one) so that it
    /// keeps its digits far from the origin.
    pub(crate) fn b_offset(&self, b: &Body, j: usize, from: [f64; 2]) -> [f64; 2] {
        let p = &self.pairs[j];
        if !self.independent() {
            return sub(b.nodes[p.node_b], from);
        }
        if p.partners.is_empty() {
            return sub(p.x, from);
        }
        p.partners.iter().fold([0.0, 0.0], |acc, &(k, c)| {
            let d = sub(b.nodes[k], from);
            [acc[0] + c * d[0], acc[1] + c * d[1]]
        })
    }
}

/// Element size figures for `sgbem check`.
#[derive(Debug, Clone, Default)]
pub struct SizeStats {
    pub smallest: (f64, String),
    pub largest: (f64, String),
    /// Largest length ratio between neighbouring elements of a loop.
    pub grading: (f64, String),
}

/// The validated model.
#[derive(Debug, Clone)]
pub struct Model {
    pub mesh_path: PathBuf,
    pub bodies: Vec<Body>,
    pub parts: Vec<Part>,
    pub interfaces: Vec<Interface>,
    /// Diagonal of the bounding box of all boundary nodes.
    pub scale: f64,
    pub sizes: SizeStats,
    /// Physical Curves that lie on no body boundary (ignored).
    pub unused_curves: Vec<String>,
    /// The pseudo-time at which the prescribed values (gaps, cohesions, friction
    /// coefficients, body forces, boundary values) are evaluated.
    pub time: f64,
    /// Which scene table applies to each body and interface group (exact, glob, default).
    pub tables: Vec<Resolved>,
    /// Cuts that `[contact]` made in line elements that face more than one body
    /// (`detect::cuts`): the mesh has that many line elements more.
    pub contact_cuts: usize,
}

impl Model {
    pub fn element_count(&self) -> usize {
        self.bodies.iter().map(|b| b.elements.len()).sum()
    }
    pub fn pair_count(&self) -> usize {
        self.interfaces.iter().map(|i| i.pairs.len()).sum()
    }

    /// The pairs of unilateral interfaces (the contact problem's complementarity rows).
    pub(crate) fn unilateral_pair_count(&self) -> usize {
        self.interfaces
            .iter()
            .filter(|i| i.spec.model == crate::input::scene::InterfaceModel::Unilateral)
            .map(|i| i.pairs.len())
            .sum()
    }

    /// Whether a unilateral interface meets another at a junction (a node of one body in
    /// pairs of two or more interfaces, one of them unilateral): there the solvers other
    /// than the full rows leave a dependent component without a row of its own.
    pub(crate) fn has_unilateral_junction(&self) -> bool {
        self.interface_nodes()
            .values()
            .any(|&(count, unilateral)| count >= 2 && unilateral)
    }

    /// Per (body, node) in any interface's pairs: the pairs it is in, and whether one of
    /// them is of a unilateral interface.
    fn interface_nodes(&self) -> BTreeMap<(usize, usize), (usize, bool)> {
        let mut seen: BTreeMap<(usize, usize), (usize, bool)> = BTreeMap::new();
        for it in &self.interfaces {
            let unilateral = it.spec.model == crate::input::scene::InterfaceModel::Unilateral;
            for (side_a, body) in [(true, it.body_a), (false, it.body_b)] {
                for j in 0..it.point_count(side_a) {
                    let e = seen.entry((body, it.point(side_a, j).0)).or_default();
                    e.0 += 1;
                    e.1 |= unilateral;
                }
            }
        }
        seen
    }

    /// The junctions: points where a body meets two or more others (a node of one body in
    /// pairs of two or more interfaces), as (point, bodies meeting there), in body order.
    pub fn junctions(&self) -> Vec<([f64; 2], Vec<usize>)> {
        let count = self.interface_nodes();
        // Group the junction nodes by position (the nodes of all bodies there coincide).
        let mut out: Vec<([f64; 2], Vec<usize>)> = Vec::new();
        let tol = 1e-9 * self.scale;
        for (&(b, n), &(c, _)) in &count {
            if c < 2 {
                continue;
            }
            let x = self.bodies[b].nodes[n];
            match out
                .iter_mut()
                .find(|(y, _)| (y[0] - x[0]).abs() <= tol && (y[1] - x[1]).abs() <= tol)
            {
                Some((_, bodies)) => bodies.push(b),
                None => out.push((x, vec![b])),
            }
        }
        out
    }

    /// The model with its prescribed values evaluated at pseudo-time `t` (a load step of
    /// `[solve] time`): body forces, and the gap, cohesion and friction coefficient of
    /// every pair; boundary values are evaluated at `time` by the assembly. Values that are
    /// not finite or negative where they must not be are input errors naming the step.
    pub(crate) fn at_time(&self, scene: &Scene, t: f64) -> Result<Model> {
        let mut m = self.clone();
        m.time = t;
        for body in m.bodies.iter_mut() {
            body.body_force = body
                .body_force_spec
                .as_ref()
                .map(|b| [b[0].eval([0.0, 0.0], t), b[1].eval([0.0, 0.0], t)]);
            if let Some(b) = body.body_force {
                if !b.iter().all(|c| c.is_finite()) {
                    return Err(Error::input(
                        &scene.path,
                        format!(
                            "`body.{}.body_force` is not finite at t = {}: it must be finite at \
                             every step",
                            body.name,
                            fmt_num(t)
                        ),
                    ));
                }
            }
        }
        for it in &mut m.interfaces {
            for p in &mut it.pairs {
                let (gap, cohesion, friction) =
                    pair_values(&it.spec, p.x, t).map_err(|msg| Error::input(&scene.path, msg))?;
                p.gap = with_geometry(&it.spec, p.gap_geometry, gap);
                p.cohesion = cohesion;
                p.friction = friction;
            }
        }
        check_values(&m.bodies, &m.parts, &scene.path, t)?;
        Ok(m)
    }
}

/// The gap of a pair: the scene's `gap`, plus the gap measured from the geometry on a
/// unilateral interface whose sides were meshed on their own (a bonded one joins the sides
/// as drawn).
fn with_geometry(spec: &InterfaceSpec, geometry: f64, gap: f64) -> f64 {
    if geometry == 0.0 || spec.model != crate::input::scene::InterfaceModel::Unilateral {
        gap
    } else {
        geometry + gap
    }
}

/// The pseudo-time of the first load step (1 without `[solve] time`).
fn first_time(scene: &Scene) -> f64 {
    scene.solve.steps().first().map_or(1.0, |s| s.1)
}

/// Gap, cohesion and friction coefficient of a pair at x and pseudo-time t (each only where
/// its interface's settings use it); an error message when one is not finite and >= 0.
fn pair_values(
    spec: &InterfaceSpec,
    x: [f64; 2],
    t: f64,
) -> std::result::Result<(f64, f64, f64), String> {
    let gap = spec.gap.eval(x, t);
    let cohesion = spec.cohesion.eval(x, t);
    let friction = spec.friction.eval(x, t);
    if !gap.is_finite() {
        return Err(format!(
            "`interface.{}.gap` is {} at {} (t = {}): it must be a finite number at every \
             interface node and step (negative: an interference)",
            spec.name,
            fmt_num(gap),
            fmt_point(x),
            fmt_num(t)
        ));
    }
    for (what, v) in [("cohesion", cohesion), ("friction", friction)] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(format!(
                "`interface.{}.{what}` is {} at {} (t = {}): it must be a finite number >= 0 \
                 at every interface node and step",
                spec.name,
                fmt_num(v),
                fmt_point(x),
                fmt_num(t)
            ));
        }
    }
    Ok((
        if spec.initial == InitialState::Open {
            gap
        } else {
            0.0
        },
        if spec.initial == InitialState::Closed {
            cohesion
        } else {
            0.0
        },
        if spec.tangential == Tangential::Friction {
            friction
        } else {
            0.0
        },
    ))
}

// ---------------------------------------------------------------------------------------
// Small 2-vector helpers.

fn unit(a: [f64; 2]) -> [f64; 2] {
    let n = norm(a);
    [a[0] / n, a[1] / n]
}
fn fmt_point(p: [f64; 2]) -> String {
    format!("({}, {})", fmt_num(p[0]), fmt_num(p[1]))
}
/// Compact number formatting for messages and reports.
pub(crate) fn fmt_num(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if (1e-3..1e6).contains(&a) {
        let s = format!("{v:.6}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else {
        format!("{v:.4e}")
    }
}

const OPEN_LOOP_HINT: &str = "gmsh drops the elements of curves that are in no Physical Curve \
once any physical group exists: add every boundary curve to a named Physical Curve \
(e.g. Physical Curve(\"free\") = {...};) and mesh again";

/// The `group` of the interfaces found by `[contact]`.
pub(crate) const FOUND_GROUP: &str = "[contact]";

/// What each physical curve of the mesh is, after reading the scene.
enum CurveUse {
    Boundary(usize),
    Interface(usize),
    /// A Physical Curve joining several pairs of bodies: the interface of each pair.
    Split(BTreeMap<(usize, usize), usize>),
}

/// Builds and validates the model of a scene on a mesh. With `[contact]`, the line elements
/// that face more than one body are first cut where the body they face changes
/// (`detect::cuts`): `mesh` gains those nodes and elements.
pub fn build(scene: &Scene, mesh: &mut Mesh, mesh_path: &Path) -> Result<Model> {
    match build_once(scene, mesh, mesh_path, true)? {
        Built::Model(m) => Ok(*m),
        Built::Cut(cuts) => {
            detect::apply_cuts(mesh, &cuts);
            match build_once(scene, mesh, mesh_path, false)? {
                Built::Model(mut m) => {
                    m.contact_cuts = cuts.iter().map(|c| c.points.len()).sum();
                    Ok(*m)
                }
                Built::Cut(_) => Err(Error::input(
                    mesh_path,
                    "[contact]: the elements cut where the body they face changes still face \
                     several bodies; mesh the facing curves finer",
                )),
            }
        }
    }
}

/// A model, or the cuts its mesh needs first.
enum Built {
    Model(Box<Model>),
    Cut(Vec<detect::Cut>),
}

/// [`build`] on the mesh as it is; with `cut`, returns the cuts [`detect::cuts`] asks for
/// instead where there are any.
fn build_once(scene: &Scene, mesh: &Mesh, mesh_path: &Path, cut: bool) -> Result<Built> {
    let t0 = first_time(scene);
    let (with_bodies, mut resolved) = tables::resolve_bodies(scene, mesh)?;
    let scene = &with_bodies;
    let mfile = mesh_path;
    let sfile = scene.path.as_path();
    let groups = Groups { mesh, mfile, sfile };

    let body_surfaces = body_surfaces(scene, &groups)?;
    let body_curves = boundary_curves(scene, mesh, &body_surfaces, mfile)?;
    let curve_bodies = curve_bodies(&body_curves);

    // --- Interface tables from globs and defaults, now that shared curves are known -------
    let shared_groups = shared_groups(mesh, &curve_bodies);
    let (with_interfaces, from_tables) = tables::resolve_interfaces(scene, mesh, &shared_groups)?;
    resolved.extend(from_tables);
    let scene = &with_interfaces;

    let found = classify_curves(scene, &groups, &curve_bodies)?;
    let curve_role = curve_roles(scene, &groups, &body_curves, &curve_bodies, &found)?;
    let CurveUses {
        mut parts,
        interfaces: mut interfaces_found,
        unused: unused_curves,
        ..
    } = found;

    let curve_lines = curve_lines(mesh);
    let scale = model_scale(mesh, &body_curves, &curve_lines, mfile)?;

    // --- Bodies: nodes, loops, orientation -------------------------------------------------
    let mut bodies: Vec<Body> = Vec::new();
    let mut triangles = body_triangles(mesh, &body_surfaces);
    for (bi, spec) in scene.bodies.iter().enumerate() {
        let mut body = build_body(
            spec.name.as_str(),
            &body_curves[bi],
            &curve_lines,
            &curve_role,
            mesh,
            mfile,
            scale,
        )?;
        body.young = spec.young;
        body.poisson = spec.poisson;
        body.body_force = spec.body_force_at(t0);
        body.body_force_spec = spec.body_force.clone();
        body.surfaces = body_surfaces[bi].clone();
        body.triangles = std::mem::take(&mut triangles[bi]);
        bodies.push(body);
    }
    if let (true, Some(cs)) = (cut, &scene.contact) {
        let cuts = detect::cuts(cs, &bodies, &parts);
        if !cuts.is_empty() {
            return Ok(Built::Cut(cuts));
        }
    }
    // Interfaces found from the drawing ([contact]) follow the declared ones.
    let declared = interfaces_found.len();
    detect::add_found(
        scene,
        (&mut bodies, &parts),
        &mut interfaces_found,
        &mut resolved,
    )?;
    part_statistics(&bodies, &mut parts);

    // --- Interfaces ---------------------------------------------------------------------------
    let mut interfaces = Vec::new();
    for (k, (spec, group, curves)) in interfaces_found.iter().enumerate() {
        let search = scene.contact.as_ref().filter(|_| k >= declared);
        interfaces.push(build_interface(
            k,
            (spec, group),
            curves,
            &bodies,
            mesh,
            &curve_bodies,
            scene,
            mfile,
            search.map(|c| c.search),
        )?);
    }

    check_overlaps(&bodies, &interfaces[..declared], mfile, scale)?;
    detect::check_found_gaps(&bodies, &interfaces[declared..], mfile, scale)?;
    mark_traction_breaks(&mut bodies);
    for body in bodies.iter_mut() {
        body.dofs = node_dofs(body, &parts);
    }
    align_pair_frames(&bodies, &mut interfaces);
    check_one_sided(&bodies, &interfaces, &parts, sfile)?;
    check_values(&bodies, &parts, sfile, t0)?;
    check_held(&bodies, &interfaces, sfile, scale)?;
    let sizes = size_stats(&bodies);

    let model = Model {
        tables: resolved,
        mesh_path: mesh_path.to_path_buf(),
        bodies,
        parts,
        interfaces,
        scale,
        sizes,
        unused_curves,
        time: t0,
        contact_cuts: 0,
    };
    // Every step's values must be valid, not only the first's.
    if scene.solve.time.is_some() {
        for (_, t) in scene.solve.steps().into_iter().skip(1) {
            model.at_time(scene, t)?;
        }
    }
    Ok(Built::Model(Box::new(model)))
}

/// The line elements of the mesh per curve, as indices into `mesh.lines`.
fn curve_lines(mesh: &Mesh) -> HashMap<i32, Vec<usize>> {
    let mut curve_lines: HashMap<i32, Vec<usize>> = HashMap::new();
    for (li, l) in mesh.lines.iter().enumerate() {
        curve_lines.entry(l.curve).or_default().push(li);
    }
    curve_lines
}

/// The model's length scale: the diagonal of the bounding box of the bodies' boundary
/// nodes, which must be positive and finite; the mesh must also resolve its coordinates.
fn model_scale(
    mesh: &Mesh,
    body_curves: &[BTreeSet<i32>],
    curve_lines: &HashMap<i32, Vec<usize>>,
    mfile: &Path,
) -> Result<f64> {
    let mut all_nodes: Vec<[f64; 2]> = Vec::new();
    for curves in body_curves {
        for c in curves {
            for &li in curve_lines.get(c).map(Vec::as_slice).unwrap_or(&[]) {
                for &n in &mesh.lines[li].nodes {
                    all_nodes.push(mesh.nodes[n]);
                }
            }
        }
    }
    let scale = bbox_diagonal(&all_nodes);
    check_resolution(mesh, body_curves, curve_lines, mfile)?;
    if !(scale > 0.0 && scale.is_finite()) {
        return Err(Error::input(
            mfile,
            "the bodies have no boundary elements of positive size: mesh with `gmsh -2` (or -1)",
        ));
    }
    Ok(scale)
}

/// Part statistics: each part's element count per body and its total length.
fn part_statistics(bodies: &[Body], parts: &mut [Part]) {
    for (bi, body) in bodies.iter().enumerate() {
        for e in &body.elements {
            if let Role::Boundary(pi) = e.role {
                *parts[pi].elements.entry(bi).or_default() += 1;
                parts[pi].length += e.length;
            }
        }
    }
}

fn list_or_none(names: &[&str]) -> String {
    if names.is_empty() {
        "none".into()
    } else {
        names
            .iter()
            .map(|n| format!("\"{n}\""))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// The spacing of floating-point numbers at magnitude `x`: the unit in the last place of
/// `|x|` (2⁻⁵ at 2⁴⁷ = 1.4e14, 0.25 at 2⁵⁰ = 1.1e15); `x` itself where it is not finite.
pub fn spacing(x: f64) -> f64 {
    let x = x.abs();
    if !x.is_finite() {
        return x;
    }
    if x < f64::MIN_POSITIVE {
        return f64::from_bits(1);
    }
    f64::from_bits((x.to_bits() >> 52) << 52) * f64::EPSILON
}

/// How far from the origin the body lines lie (largest coordinate), the spacing of
/// floating-point coordinates there ([`spacing`]), and their shortest positive element.
///
/// The solver works in coordinates relative to each body (differences of nearby numbers,
/// exact), so it loses nothing far from the origin; what is lost there is in the node
/// positions themselves, which can only be multiples of that spacing.
pub fn resolution(lines: impl Iterator<Item = ([f64; 2], [f64; 2])>) -> (f64, f64, f64) {
    let (mut far, mut h) = (0.0f64, f64::INFINITY);
    for (a, b) in lines {
        far = far
            .max(a[0].abs())
            .max(a[1].abs())
            .max(b[0].abs())
            .max(b[1].abs());
        let l = norm(sub(b, a));
        if l > 0.0 {
            h = h.min(l);
        }
    }
    (far, if far > 0.0 { spacing(far) } else { 0.0 }, h)
}

/// Refuses a mesh so far from the origin that floating-point coordinates there are spaced
/// more than a tenth of its shortest element apart: node positions cannot hold the
/// elements' lengths (nodes round onto one another), so the geometry is lost. The reason,
/// not a symptom (zero-length elements, "duplicate points").
fn check_resolution(
    mesh: &Mesh,
    body_curves: &[BTreeSet<i32>],
    curve_lines: &HashMap<i32, Vec<usize>>,
    mfile: &Path,
) -> Result<()> {
    let lines = body_curves
        .iter()
        .flatten()
        .flat_map(|c| curve_lines.get(c).map(Vec::as_slice).unwrap_or(&[]))
        .map(|&li| {
            let n = mesh.lines[li].nodes;
            (mesh.nodes[n[0]], mesh.nodes[n[1]])
        });
    let (far, step, h) = resolution(lines);
    if far.is_finite() && far > 0.0 && !h.is_finite() {
        // Every element has zero length: a mesh of points, or one so far out that its
        // elements rounded away (1e16 for elements of 0.1).
        return Err(Error::input(
            mfile,
            format!(
                "every boundary element has zero length; its nodes lie up to {} from the \
                 origin, where floating-point coordinates are spaced {} apart, so elements \
                 shorter than that collapse: move the model near the origin and mesh again \
                 (or, if the mesh has no elements of positive size, mesh with `gmsh -2`)",
                fmt_num(far),
                fmt_num(step)
            ),
        ));
    }
    if !far.is_finite() || (far > 0.0 && (step > 0.1 * h || step.is_nan())) {
        let shortest = format!("a tenth of its shortest element ({})", fmt_num(h));
        return Err(Error::input(
            mfile,
            format!(
                "the mesh lies {} from the origin, where floating-point coordinates are spaced \
                 {} apart, more than {shortest}: node positions there hold the elements' \
                 lengths to less than a tenth (nodes round onto one another) and the geometry \
                 is lost; move the model near the origin (e.g. Translate in the .geo, or \
                 subtract a reference point from the coordinates) and mesh again",
                fmt_num(far),
                fmt_num(step)
            ),
        ));
    }
    Ok(())
}

fn bbox_diagonal(points: &[[f64; 2]]) -> f64 {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in points {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    if points.is_empty() {
        0.0
    } else {
        norm(sub(hi, lo))
    }
}

fn size_stats(bodies: &[Body]) -> SizeStats {
    let mut s = SizeStats {
        smallest: (f64::INFINITY, String::new()),
        largest: (0.0, String::new()),
        grading: (1.0, String::new()),
    };
    for body in bodies {
        for e in &body.elements {
            let place = format!("body \"{}\", element {}", body.name, e.tag);
            if e.length < s.smallest.0 {
                s.smallest = (e.length, place.clone());
            }
            if e.length > s.largest.0 {
                s.largest = (e.length, place);
            }
        }
        for l in &body.loops {
            let n = l.elements.len();
            for k in 0..n {
                let (p, q) = (
                    &body.elements[l.elements[k]],
                    &body.elements[l.elements[(k + 1) % n]],
                );
                let r = p.length.max(q.length) / p.length.min(q.length);
                if r > s.grading.0 {
                    s.grading = (
                        r,
                        format!("body \"{}\", elements {} and {}", body.name, p.tag, q.tag),
                    );
                }
            }
        }
    }
    s
}

/// The mesh triangles of each body (those of its surfaces), in the mesh's order: one pass
/// over the triangles (a pass per body cost 4 128 × 130 000 tests on a 64 × 64 wall).
fn body_triangles(mesh: &Mesh, body_surfaces: &[Vec<i32>]) -> Vec<Vec<[usize; 3]>> {
    let mut owners: HashMap<i32, Vec<usize>> = HashMap::new();
    for (bi, surfaces) in body_surfaces.iter().enumerate() {
        for &s in surfaces {
            owners.entry(s).or_default().push(bi);
        }
    }
    let mut out = vec![Vec::new(); body_surfaces.len()];
    for t in &mesh.triangles {
        for &bi in owners.get(&t.surface).map_or(&[][..], |v| v.as_slice()) {
            out[bi].push(t.nodes);
        }
    }
    out
}
