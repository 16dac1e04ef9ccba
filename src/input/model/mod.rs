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

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::{Path, PathBuf};

use crate::error::{did_you_mean, Error, Result};
use crate::input::mesh::Mesh;
use crate::input::scene::{
    BoundarySpec, Condition, Frame, InitialState, InterfaceSpec, Scene, Tangential,
};
use crate::input::tables::{self, Resolved};

/// Turning angle above which two elements meet at a corner, within one gmsh curve.
const CORNER_ANGLE_IN_CURVE: f64 = 10.0 * std::f64::consts::PI / 180.0;
/// Turning angle above which two elements meet at a corner, where two gmsh curves join.
const CORNER_ANGLE_AT_JOIN: f64 = 1.0 * std::f64::consts::PI / 180.0;

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

    /// Winding number of the boundary around x: non-zero inside the body (holes cancel).
    pub fn winding_number(&self, x: [f64; 2]) -> i32 {
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
}

/// An interface element: the same segment seen from both bodies.
#[derive(Debug, Clone, Copy)]
pub struct InterfaceElement {
    /// Element index in body A and in body B.
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
}

impl Model {
    pub fn element_count(&self) -> usize {
        self.bodies.iter().map(|b| b.elements.len()).sum()
    }
    pub fn pair_count(&self) -> usize {
        self.interfaces.iter().map(|i| i.pairs.len()).sum()
    }

    /// The pairs of unilateral interfaces (the contact problem's complementarity rows).
    pub fn unilateral_pair_count(&self) -> usize {
        self.interfaces
            .iter()
            .filter(|i| i.spec.model == crate::input::scene::InterfaceModel::Unilateral)
            .map(|i| i.pairs.len())
            .sum()
    }

    /// The junctions: points where a body meets two or more others (a node of one body in
    /// pairs of two or more interfaces), as (point, bodies meeting there), in body order.
    pub fn junctions(&self) -> Vec<([f64; 2], Vec<usize>)> {
        let mut count: BTreeMap<(usize, usize), usize> = BTreeMap::new();
        for it in &self.interfaces {
            for p in &it.pairs {
                *count.entry((it.body_a, p.node_a)).or_default() += 1;
                *count.entry((it.body_b, p.node_b)).or_default() += 1;
            }
        }
        // Group the junction nodes by position (the nodes of all bodies there coincide).
        let mut out: Vec<([f64; 2], Vec<usize>)> = Vec::new();
        let tol = 1e-9 * self.scale;
        for (&(b, n), &c) in &count {
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
    pub fn at_time(&self, scene: &Scene, t: f64) -> Result<Model> {
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
                p.gap = gap;
                p.cohesion = cohesion;
                p.friction = friction;
            }
        }
        check_values(&m.bodies, &m.parts, &scene.path, t)?;
        Ok(m)
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

fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}
fn norm(a: [f64; 2]) -> f64 {
    a[0].hypot(a[1])
}
fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}
fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}
fn unit(a: [f64; 2]) -> [f64; 2] {
    let n = norm(a);
    [a[0] / n, a[1] / n]
}
fn fmt_point(p: [f64; 2]) -> String {
    format!("({}, {})", fmt_num(p[0]), fmt_num(p[1]))
}
/// Compact number formatting for messages and reports.
pub fn fmt_num(v: f64) -> String {
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

/// What each physical curve of the mesh is, after reading the scene.
enum CurveUse {
    Boundary(usize),
    Interface(usize),
    /// A Physical Curve joining several pairs of bodies: the interface of each pair.
    Split(BTreeMap<(usize, usize), usize>),
}

/// Builds and validates the model of a scene on a mesh.
pub fn build(scene: &Scene, mesh: &Mesh, mesh_path: &Path) -> Result<Model> {
    let t0 = first_time(scene);
    let (with_bodies, mut resolved) = tables::resolve_bodies(scene, mesh)?;
    let scene = &with_bodies;
    let mfile = mesh_path;
    let sfile = scene.path.as_path();
    let named = |dim: i32| -> Vec<&str> {
        mesh.physical_names
            .iter()
            .filter(|p| p.dim == dim)
            .map(|p| p.name.as_str())
            .collect()
    };
    let group_tag = |dim: i32, name: &str| -> Option<i32> {
        mesh.physical_names
            .iter()
            .find(|p| p.dim == dim && p.name == name)
            .map(|p| p.tag)
    };
    let wrong_kind = |key: &str, name: &str, want: i32| -> Error {
        let kinds = [
            "Physical Point",
            "Physical Curve",
            "Physical Surface",
            "Physical Volume",
        ];
        let found = mesh
            .physical_names
            .iter()
            .find(|p| p.name == name)
            .map(|p| kinds.get(p.dim as usize).copied().unwrap_or("group"));
        let want_s = kinds[want as usize];
        match found {
            Some(kind) => Error::input(
                sfile,
                format!(
                    "[{key}.{name}] names a {kind} of {}, but a {key} must be a {want_s}",
                    mfile.display()
                ),
            ),
            None => Error::input(
                sfile,
                format!(
                    "[{key}.{name}]: {} has no {want_s} named \"{name}\"{}; its {want_s}s are: {}",
                    mfile.display(),
                    did_you_mean(name, named(want).into_iter()),
                    list_or_none(&named(want))
                ),
            ),
        }
    };

    // --- Bodies: physical surfaces -----------------------------------------------------
    let mut surface_owner: HashMap<i32, usize> = HashMap::new();
    let mut body_surfaces: Vec<Vec<i32>> = Vec::new();
    for (bi, spec) in scene.bodies.iter().enumerate() {
        let tag = group_tag(2, &spec.name).ok_or_else(|| wrong_kind("body", &spec.name, 2))?;
        let surfaces: Vec<i32> = mesh
            .surfaces
            .values()
            .filter(|s| s.physical_tags.contains(&tag))
            .map(|s| s.tag)
            .collect();
        if surfaces.is_empty() {
            return Err(Error::input(
                mfile,
                format!(
                    "Physical Surface \"{}\" holds no surface entity: mesh the .geo again",
                    spec.name
                ),
            ));
        }
        for &s in &surfaces {
            if let Some(&other) = surface_owner.get(&s) {
                return Err(Error::input(
                    mfile,
                    format!(
                        "surface {s} belongs to both Physical Surfaces \"{}\" and \"{}\": bodies \
                         overlap; put each surface in one body only",
                        scene.bodies[other].name, spec.name
                    ),
                ));
            }
            surface_owner.insert(s, bi);
        }
        body_surfaces.push(surfaces);
    }
    for p in mesh.physical_names.iter().filter(|p| p.dim == 2) {
        if scene.body(&p.name).is_none() {
            return Err(Error::input(
                sfile,
                format!(
                    "{} has a Physical Surface \"{}\" but the scene has no [body.{}]: add it with \
                     its young and poisson (or a [body.\"PATTERN*\"] or [defaults.body] table \
                     that applies to it){}",
                    mfile.display(),
                    p.name,
                    p.name,
                    did_you_mean(&p.name, scene.bodies.iter().map(|b| b.name.as_str()))
                        .replace("did you mean", "or rename")
                ),
            ));
        }
    }

    // --- Boundary curves of each body ---------------------------------------------------
    let mut body_curves: Vec<BTreeSet<i32>> = Vec::new();
    for (bi, surfaces) in body_surfaces.iter().enumerate() {
        let mut count: BTreeMap<i32, usize> = BTreeMap::new();
        for s in surfaces {
            let ent = &mesh.surfaces[s];
            if ent.bounding.is_empty() {
                return Err(Error::input(
                    mfile,
                    format!(
                        "surface {s} of body \"{}\" has no bounding curves in $Entities",
                        scene.bodies[bi].name
                    ),
                ));
            }
            for c in &ent.bounding {
                let tag = c.checked_abs().filter(|t| *t > 0).ok_or_else(|| {
                    Error::input(
                        mfile,
                        format!("surface {s} lists an invalid bounding curve tag {c} in $Entities"),
                    )
                })?;
                *count.entry(tag).or_default() += 1;
            }
        }
        // A curve bounding two surfaces of the same body is internal to it.
        body_curves.push(
            count
                .into_iter()
                .filter(|(_, n)| n % 2 == 1)
                .map(|(c, _)| c)
                .collect(),
        );
    }
    let mut curve_bodies: BTreeMap<i32, Vec<usize>> = BTreeMap::new();
    for (bi, curves) in body_curves.iter().enumerate() {
        for &c in curves {
            curve_bodies.entry(c).or_default().push(bi);
        }
    }

    // --- Interface tables from globs and defaults, now that shared curves are known -------
    let shared_groups: BTreeSet<&str> = mesh
        .physical_names
        .iter()
        .filter(|p| p.dim == 1)
        .filter(|p| {
            mesh.curves.values().any(|c| {
                c.physical_tags.contains(&p.tag)
                    && curve_bodies.get(&c.tag).is_some_and(|b| b.len() >= 2)
            })
        })
        .map(|p| p.name.as_str())
        .collect();
    let (with_interfaces, from_tables) = tables::resolve_interfaces(scene, mesh, &shared_groups)?;
    resolved.extend(from_tables);
    let scene = &with_interfaces;

    // --- What each physical curve is -----------------------------------------------------
    for b in &scene.boundaries {
        if group_tag(1, &b.name).is_none() {
            return Err(wrong_kind("boundary", &b.name, 1));
        }
    }
    for i in &scene.interfaces {
        if group_tag(1, &i.name).is_none() {
            return Err(wrong_kind("interface", &i.name, 1));
        }
    }
    let mut parts: Vec<Part> = Vec::new();
    // (the interface's table, named after its pair of bodies when the curve is split; its curves)
    let mut interfaces_found: Vec<(InterfaceSpec, String, BTreeSet<i32>)> = Vec::new();
    let mut uses: HashMap<i32, CurveUse> = HashMap::new(); // group tag → use
    let mut unused_curves = Vec::new();
    for p in mesh.physical_names.iter().filter(|p| p.dim == 1) {
        let curves: Vec<i32> = mesh
            .curves
            .values()
            .filter(|c| c.physical_tags.contains(&p.tag))
            .map(|c| c.tag)
            .collect();
        let on_bodies: BTreeSet<usize> = curves
            .iter()
            .filter_map(|c| curve_bodies.get(c))
            .flatten()
            .copied()
            .collect();
        if on_bodies.is_empty() {
            if scene.boundary(&p.name).is_some() || scene.interface(&p.name).is_some() {
                return Err(Error::input(
                    sfile,
                    format!(
                        "Physical Curve \"{}\" lies on no body boundary in {}: check the curves \
                         it holds",
                        p.name,
                        mfile.display()
                    ),
                ));
            }
            unused_curves.push(p.name.clone());
            continue;
        }
        let shared: Vec<i32> = curves
            .iter()
            .copied()
            .filter(|c| curve_bodies.get(c).is_some_and(|b| b.len() >= 2))
            .collect();
        if let Some(spec) = scene.interface(&p.name) {
            let by_pair = pairs_of_bodies(&p.name, &curves, &curve_bodies, scene, sfile)?;
            if by_pair.len() <= 1 {
                uses.insert(p.tag, CurveUse::Interface(interfaces_found.len()));
                interfaces_found.push((
                    spec.clone(),
                    p.name.clone(),
                    curves.iter().copied().collect(),
                ));
            } else {
                let mut split = BTreeMap::new();
                for ((a, b), set) in by_pair {
                    split.insert((a, b), interfaces_found.len());
                    let name = split_name(&p.name, &scene.bodies[a].name, &scene.bodies[b].name);
                    interfaces_found.push((
                        InterfaceSpec {
                            name,
                            ..spec.clone()
                        },
                        p.name.clone(),
                        set,
                    ));
                }
                uses.insert(p.tag, CurveUse::Split(split));
            }
        } else {
            if let Some(&c) = shared.first() {
                let names: Vec<&str> = curve_bodies[&c]
                    .iter()
                    .map(|&b| scene.bodies[b].name.as_str())
                    .collect();
                let how = if scene.boundary(&p.name).is_some() {
                    format!("[boundary.{}] cannot apply to it", p.name)
                } else {
                    "the scene does not list it".to_string()
                };
                return Err(Error::input(
                    sfile,
                    format!(
                        "Physical Curve \"{}\" is shared by bodies {} (curve {c}) and {how}: \
                         declare [interface.{}] with model = \"bonded\" or \"unilateral\" (or \
                         an [interface.\"PATTERN*\"] or [defaults.interface] table)",
                        p.name,
                        names.join(" and "),
                        p.name
                    ),
                ));
            }
            let (spec, listed) = match scene.boundary(&p.name) {
                Some(s) => (s.clone(), true),
                None => (BoundarySpec::traction_free(&p.name), false),
            };
            uses.insert(p.tag, CurveUse::Boundary(parts.len()));
            parts.push(Part {
                spec,
                listed,
                elements: BTreeMap::new(),
                length: 0.0,
            });
        }
    }

    // The role of each boundary curve (through its physical group).
    let mut curve_role: HashMap<i32, Role> = HashMap::new();
    for (bi, curves) in body_curves.iter().enumerate() {
        for &c in curves {
            let ent = match mesh.curves.get(&c) {
                Some(e) => e,
                None => {
                    return Err(Error::input(
                        mfile,
                        format!(
                            "surface of body \"{}\" is bounded by curve {c}, which $Entities does \
                             not define",
                            scene.bodies[bi].name
                        ),
                    ))
                }
            };
            let roles: Vec<(Role, String)> = ent
                .physical_tags
                .iter()
                .filter_map(|t| {
                    let name = mesh.physical_name(1, *t)?.to_string();
                    match uses.get(t)? {
                        CurveUse::Boundary(pi) => Some((Role::Boundary(*pi), name)),
                        CurveUse::Interface(k) => Some((Role::Interface(*k), name)),
                        CurveUse::Split(by_pair) => {
                            let on = curve_bodies.get(&c)?;
                            let k = by_pair.get(&(on[0].min(on[1]), on[0].max(on[1])))?;
                            Some((Role::Interface(*k), name))
                        }
                    }
                })
                .collect();
            // Groups the scene uses win over unlisted (traction-free) ones.
            let used: Vec<&(Role, String)> = roles
                .iter()
                .filter(|(r, _)| match r {
                    Role::Boundary(pi) => parts[*pi].listed,
                    Role::Interface(_) => true,
                })
                .collect();
            let listed: Vec<&(Role, String)> = if used.is_empty() {
                roles.iter().take(1).collect()
            } else {
                used
            };
            match listed.as_slice() {
                [] => {
                    return Err(Error::input(
                        mfile,
                        format!(
                            "curve {c} bounds body \"{}\" but belongs to no named Physical \
                             Curve: {OPEN_LOOP_HINT}",
                            scene.bodies[bi].name
                        ),
                    ))
                }
                [(role, _)] => {
                    curve_role.insert(c, *role);
                }
                many => {
                    let names: Vec<&str> = many.iter().map(|(_, n)| n.as_str()).collect();
                    return Err(Error::input(
                        sfile,
                        format!(
                            "curve {c} belongs to Physical Curves {} which the scene all uses: \
                             a curve may carry one condition; split the groups",
                            names.join(", ")
                        ),
                    ));
                }
            }
        }
    }

    // --- Line elements per curve ----------------------------------------------------------
    let mut curve_lines: HashMap<i32, Vec<usize>> = HashMap::new();
    for (li, l) in mesh.lines.iter().enumerate() {
        curve_lines.entry(l.curve).or_default().push(li);
    }

    let mut all_nodes: Vec<[f64; 2]> = Vec::new();
    for curves in &body_curves {
        for c in curves {
            for &li in curve_lines.get(c).map(Vec::as_slice).unwrap_or(&[]) {
                for &n in &mesh.lines[li].nodes {
                    all_nodes.push(mesh.nodes[n]);
                }
            }
        }
    }
    let scale = bbox_diagonal(&all_nodes);
    check_resolution(mesh, &body_curves, &curve_lines, mfile)?;
    if !(scale > 0.0 && scale.is_finite()) {
        return Err(Error::input(
            mfile,
            "the bodies have no boundary elements of positive size: mesh with `gmsh -2` (or -1)",
        ));
    }

    // --- Bodies: nodes, loops, orientation -------------------------------------------------
    let mut bodies: Vec<Body> = Vec::new();
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
        body.triangles = mesh
            .triangles
            .iter()
            .filter(|t| body.surfaces.contains(&t.surface))
            .map(|t| t.nodes)
            .collect();
        bodies.push(body);
    }

    // Part statistics.
    for (bi, body) in bodies.iter().enumerate() {
        for e in &body.elements {
            if let Role::Boundary(pi) = e.role {
                *parts[pi].elements.entry(bi).or_default() += 1;
                parts[pi].length += e.length;
            }
        }
    }

    // --- Interfaces ---------------------------------------------------------------------------
    let mut interfaces = Vec::new();
    for (k, (spec, group, curves)) in interfaces_found.iter().enumerate() {
        interfaces.push(build_interface(
            k,
            (spec, group),
            curves,
            &bodies,
            mesh,
            &curve_bodies,
            scene,
            mfile,
        )?);
    }

    check_overlaps(&bodies, mfile, scale)?;
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
    };
    // Every step's values must be valid, not only the first's.
    if scene.solve.time.is_some() {
        for (_, t) in scene.solve.steps().into_iter().skip(1) {
            model.at_time(scene, t)?;
        }
    }
    Ok(model)
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

/// How far from the origin the body lines lie (largest coordinate), the step with which
/// floating point resolves coordinates there, and their shortest positive element.
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
    (far, far * f64::EPSILON, h)
}

/// Refuses a mesh so far from the origin that floating point resolves its coordinates to
/// no better than a tenth of its shortest element (nodes then round onto one another):
/// the reason, not a symptom (zero-length elements, "duplicate points").
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
    if !far.is_finite() || (far > 0.0 && (step > 0.1 * h || step.is_nan())) {
        let shortest = if h.is_finite() {
            format!("a tenth of its shortest element ({})", fmt_num(h))
        } else {
            "the size of any element (every element has collapsed)".to_string()
        };
        return Err(Error::input(
            mfile,
            format!(
                "the mesh lies {} from the origin, where floating point resolves coordinates \
                 only to {}, more than {shortest}: nodes round onto one another and the \
                 geometry is lost; move the model near the origin (e.g. Translate in the .geo, \
                 or subtract a reference point from the coordinates) and mesh again",
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

#[allow(clippy::too_many_arguments)]
fn build_body(
    name: &str,
    curves: &BTreeSet<i32>,
    curve_lines: &HashMap<i32, Vec<usize>>,
    curve_role: &HashMap<i32, Role>,
    mesh: &Mesh,
    mfile: &Path,
    scale: f64,
) -> Result<Body> {
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
                    "curve {c} bounds body \"{name}\" but has no line elements: {OPEN_LOOP_HINT}"
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
                        "line element {} (curve {c}, body \"{name}\") has zero length: its nodes \
                         {} and {} coincide; remove duplicate points in the .geo",
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

    // Node → incident elements; each boundary node must join exactly two elements.
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
                    "the boundary of body \"{name}\" is open at node {tag} {} (end of curve {}): \
                         {OPEN_LOOP_HINT}",
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
                        "node {tag} {} joins {k} boundary elements of body \"{name}\" (curves \
                         {curves:?}): the boundary touches itself or a curve is meshed twice; \
                         each boundary node must join exactly two elements",
                        fmt_point(nodes[n])
                    ),
                ));
            }
        }
    }

    // Chain elements into loops, flipping elements to follow the chain.
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
        let area = loop_area(&chain, &elements, &nodes);
        loops.push(Loop {
            elements: chain,
            area,
            is_hole: false,
        });
    }

    // Orientation by nesting: a loop inside an odd number of others is a hole (clockwise).
    let mut outer = 0;
    for li in 0..loops.len() {
        let probe = nodes[elements[loops[li].elements[0]].nodes[0]];
        let depth = (0..loops.len())
            .filter(|&o| o != li && point_in_loop(probe, &loops[o], &elements, &nodes))
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
                "body \"{name}\" consists of {outer} separate regions: make each region a Physical \
                 Surface (a body) of its own"
            ),
        ));
    }
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

fn winding(p: [f64; 2], segments: impl Iterator<Item = ([f64; 2], [f64; 2])>) -> i32 {
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

#[allow(clippy::too_many_arguments)]
fn build_interface(
    k: usize,
    (spec, group): (&InterfaceSpec, &str),
    curves: &BTreeSet<i32>,
    bodies: &[Body],
    mesh: &Mesh,
    curve_bodies: &BTreeMap<i32, Vec<usize>>,
    scene: &Scene,
    mfile: &Path,
) -> Result<Interface> {
    let sfile = scene.path.as_path();
    let name = spec.name.as_str();
    let t0 = first_time(scene);
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
    let (ba, bb) = match (it.next(), it.next()) {
        (Some(&a), Some(&b)) => (a.min(b), a.max(b)),
        _ => {
            return Err(Error::input(
                sfile,
                format!("[interface.{name}]: needs two bodies"),
            ))
        }
    };
    let (a, b) = (&bodies[ba], &bodies[bb]);
    let on_interface = |body: &Body| -> Vec<usize> {
        (0..body.elements.len())
            .filter(|&e| body.elements[e].role == Role::Interface(k))
            .collect()
    };
    let elems_a = on_interface(a);
    let elems_b = on_interface(b);

    // Match B's interface nodes to A's: same mesh node, else same position.
    let mut b_by_mesh: HashMap<usize, usize> = HashMap::new();
    for &e in &elems_b {
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
    for &e in &elems_a {
        for n in a.elements[e].nodes {
            if a_to_b.contains_key(&n) {
                continue;
            }
            let partner = match b_by_mesh.get(&a.mesh_nodes[n]) {
                Some(&m) => m,
                None => {
                    by_position = true;
                    let x = a.nodes[n];
                    match b_nodes
                        .iter()
                        .copied()
                        .find(|&m| norm(sub(b.nodes[m], x)) <= tol)
                    {
                        Some(m) => m,
                        None => {
                            return Err(Error::input(
                                mfile,
                                format!(
                                    "interface \"{name}\": node {} {} of body \"{}\" has no \
                                     matching node on body \"{}\": the two sides must be meshed \
                                     with the same nodes; use one curve shared by both surfaces \
                                     (or the same Transfinite count on both)",
                                    mesh.node_tags[a.mesh_nodes[n]],
                                    fmt_point(x),
                                    a.name,
                                    b.name
                                ),
                            ))
                        }
                    }
                }
            };
            a_to_b.insert(n, partner);
        }
    }
    if a_to_b.len() != b_nodes.len() {
        return Err(Error::input(
            mfile,
            format!(
                "interface \"{name}\": body \"{}\" has {} interface nodes but body \"{}\" has {}: \
                 mesh the joint as one curve shared by both surfaces",
                a.name,
                a_to_b.len(),
                b.name,
                b_nodes.len()
            ),
        ));
    }

    // Order A's interface elements along the curve direction as drawn (mesh order).
    let mut next_of: HashMap<usize, (usize, usize)> = HashMap::new(); // node → (elem, next node)
    let mut has_incoming: BTreeSet<usize> = BTreeSet::new();
    for &e in &elems_a {
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
    if order.len() != a_to_b.len() {
        return Err(Error::input(
            mfile,
            format!(
                "interface \"{name}\": its elements on body \"{}\" do not form simple chains \
                 (a node joins more than two interface elements)",
                a.name
            ),
        ));
    }
    let pair_of: HashMap<usize, usize> = order.iter().enumerate().map(|(j, &n)| (n, j)).collect();

    // Pairs with averaged normals of A.
    let mut normals = vec![[0.0f64; 2]; order.len()];
    for &e in &elems_a {
        let el = &a.elements[e];
        for n in el.nodes {
            let j = pair_of[&n];
            normals[j][0] += el.normal[0];
            normals[j][1] += el.normal[1];
        }
    }
    let mut pairs = Vec::with_capacity(order.len());
    for (j, &na) in order.iter().enumerate() {
        let normal = unit(normals[j]);
        let x = a.nodes[na];
        let (gap, cohesion, friction) = pair_values(spec, x, t0).map_err(|m| {
            Error::input(
                sfile,
                format!("{m} (node {})", mesh.node_tags[a.mesh_nodes[na]]),
            )
        })?;
        pairs.push(Pair {
            node_a: na,
            node_b: a_to_b[&na],
            x,
            normal,
            tangent: [-normal[1], normal[0]],
            s: s_of[j],
            gap,
            cohesion,
            friction,
        });
    }

    // Interface elements: A's element and B's element on the same node pair.
    let mut b_elem_of: HashMap<(usize, usize), usize> = HashMap::new();
    for &e in &elems_b {
        let [s, t] = b.elements[e].nodes;
        b_elem_of.insert((s.min(t), s.max(t)), e);
    }
    let mut elements = Vec::with_capacity(elems_a.len());
    for &e in &elems_a {
        let [s, t] = a.elements[e].nodes;
        let (bs, bt) = (a_to_b[&s], a_to_b[&t]);
        let elem_b = match b_elem_of.get(&(bs.min(bt), bs.max(bt))) {
            Some(&eb) => eb,
            None => {
                return Err(Error::input(
                    mfile,
                    format!(
                        "interface \"{name}\": element {} of body \"{}\" has no counterpart on \
                         body \"{}\" joining the same nodes",
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
                    "interface \"{name}\": bodies \"{}\" and \"{}\" lie on the same side of element \
                     {}: the bodies overlap there",
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
    let length = elems_a.iter().map(|&e| a.elements[e].length).sum();
    Ok(Interface {
        spec: spec.clone(),
        group: group.to_string(),
        body_a: ba,
        body_b: bb,
        pairs,
        elements,
        length,
        matched_by_position: by_position,
    })
}

/// The name of the part of Physical Curve `group` between bodies `a` and `b` (a first), when
/// the curve joins several pairs of bodies: `joints[brick_1|brick_2]`.
pub fn split_name(group: &str, a: &str, b: &str) -> String {
    format!("{group}[{a}|{b}]")
}

/// The curves of an interface group per pair of bodies that share them (bodies by index,
/// smaller first). When the group joins two or more pairs, each of its curves must be
/// shared by exactly two bodies.
fn pairs_of_bodies(
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

/// Elements of different bodies (or non-neighbouring elements of one body) must not cross,
/// and no body may lie inside another.
fn check_overlaps(bodies: &[Body], mfile: &Path, scale: f64) -> Result<()> {
    struct Seg {
        body: usize,
        elem: usize,
        a: [f64; 2],
        b: [f64; 2],
        ma: usize,
        mb: usize,
        xmin: f64,
    }
    let mut segs: Vec<Seg> = Vec::new();
    for (bi, body) in bodies.iter().enumerate() {
        for (ei, e) in body.elements.iter().enumerate() {
            let a = body.nodes[e.nodes[0]];
            let b = body.nodes[e.nodes[1]];
            segs.push(Seg {
                body: bi,
                elem: ei,
                a,
                b,
                ma: body.mesh_nodes[e.nodes[0]],
                mb: body.mesh_nodes[e.nodes[1]],
                xmin: a[0].min(b[0]),
            });
        }
    }
    segs.sort_by(|p, q| p.xmin.total_cmp(&q.xmin));
    // Candidate pairs from a uniform grid of cells about one mean element long (a sweep
    // along x alone is quadratic for a column of vertical elements); the first crossing in
    // sweep order is reported.
    let n = segs.len();
    let mean = segs.iter().map(|g| norm(sub(g.b, g.a))).sum::<f64>() / n.max(1) as f64;
    let h = mean.max(1e-12 * scale).max(f64::MIN_POSITIVE);
    let origin = segs.iter().fold([f64::INFINITY; 2], |o, g| {
        [o[0].min(g.xmin), o[1].min(g.a[1].min(g.b[1]))]
    });
    let cell = |p: [f64; 2]| -> (i64, i64) {
        (
            ((p[0] - origin[0]) / h).floor() as i64,
            ((p[1] - origin[1]) / h).floor() as i64,
        )
    };
    let mut grid: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
    for (i, g) in segs.iter().enumerate() {
        let (c0, c1) = (cell(g.a), cell(g.b));
        let mut cells: Vec<(i64, i64)> = Vec::new();
        let (lo, hi) = (
            (c0.0.min(c1.0), c0.1.min(c1.1)),
            (c0.0.max(c1.0), c0.1.max(c1.1)),
        );
        if (hi.0 - lo.0 + 1) * (hi.1 - lo.1 + 1) <= 64 {
            for x in lo.0..=hi.0 {
                for y in lo.1..=hi.1 {
                    cells.push((x, y));
                }
            }
        } else {
            // A long element: the cells along it (every point of it lies within h/4 of a
            // sample, so in a sample's cell or a neighbour).
            let steps = (4.0 * norm(sub(g.b, g.a)) / h).ceil() as usize;
            for k in 0..=steps {
                let t = k as f64 / steps as f64;
                let c = cell([
                    g.a[0] + t * (g.b[0] - g.a[0]),
                    g.a[1] + t * (g.b[1] - g.a[1]),
                ]);
                for dx in -1..=1 {
                    for dy in -1..=1 {
                        cells.push((c.0 + dx, c.1 + dy));
                    }
                }
            }
            cells.sort_unstable();
            cells.dedup();
        }
        for c in cells {
            grid.entry(c).or_default().push(i);
        }
    }
    let mut first: Option<(usize, usize)> = None;
    for members in grid.values() {
        for (k, &i) in members.iter().enumerate() {
            for &j in &members[k + 1..] {
                let (i, j) = (i.min(j), i.max(j));
                if first.is_some_and(|f| f <= (i, j)) {
                    continue;
                }
                let (s, t) = (&segs[i], &segs[j]);
                if [t.ma, t.mb].contains(&s.ma) || [t.ma, t.mb].contains(&s.mb) {
                    continue;
                }
                if segments_cross(s.a, s.b, t.a, t.b) {
                    first = Some((i, j));
                }
            }
        }
    }
    if let Some((i, j)) = first {
        {
            let (s, t) = (&segs[i], &segs[j]);
            {
                let (b1, b2) = (&bodies[s.body], &bodies[t.body]);
                let (e1, e2) = (&b1.elements[s.elem], &b2.elements[t.elem]);
                let what = if s.body == t.body {
                    format!("the boundary of body \"{}\" crosses itself", b1.name)
                } else {
                    format!("bodies \"{}\" and \"{}\" overlap", b1.name, b2.name)
                };
                return Err(Error::input(
                    mfile,
                    format!(
                        "{what}: element {} (curve {}) crosses element {} (curve {}); fix the \
                         geometry so that bodies meet only along shared curves",
                        e1.tag, e1.curve, e2.tag, e2.curve
                    ),
                ));
            }
        }
    }
    for body in bodies {
        check_crossing_at_coincident_nodes(body, mfile, scale)?;
    }
    // A body entirely inside another: probe a point just inside each body.
    for (bi, body) in bodies.iter().enumerate() {
        let outer = match body.loops.iter().find(|l| !l.is_hole) {
            Some(l) => l,
            None => continue,
        };
        let e = &body.elements[outer.elements[0]];
        let mid = [
            0.5 * (body.nodes[e.nodes[0]][0] + body.nodes[e.nodes[1]][0]),
            0.5 * (body.nodes[e.nodes[0]][1] + body.nodes[e.nodes[1]][1]),
        ];
        let probe = [
            mid[0] - 1e-3 * e.length * e.normal[0],
            mid[1] - 1e-3 * e.length * e.normal[1],
        ];
        for (oi, other) in bodies.iter().enumerate() {
            if oi == bi {
                continue;
            }
            let w = other.winding_number(probe);
            if w != 0 {
                return Err(Error::input(
                    mfile,
                    format!(
                        "body \"{}\" lies inside body \"{}\": bodies must not overlap; cut a hole \
                         in \"{}\" bounded by the same curves",
                        body.name, other.name, other.name
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Two distinct nodes of one body at the same point where the boundary passes twice: a
/// bow tie crosses itself there (the two passages interleave around the point), which the
/// segment test cannot see since the segments only touch. Passages that touch without
/// crossing (the two faces of a slit) are left alone.
fn check_crossing_at_coincident_nodes(body: &Body, mfile: &Path, scale: f64) -> Result<()> {
    let eps = 1e-10 * scale;
    let key = |p: [f64; 2]| ((p[0] / eps).round() as i64, (p[1] / eps).round() as i64);
    let mut neighbours: Vec<Vec<usize>> = vec![Vec::new(); body.nodes.len()];
    for e in &body.elements {
        neighbours[e.nodes[0]].push(e.nodes[1]);
        neighbours[e.nodes[1]].push(e.nodes[0]);
    }
    let mut cells: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
    for (n, &p) in body.nodes.iter().enumerate() {
        if neighbours[n].len() == 2 {
            cells.entry(key(p)).or_default().push(n);
        }
    }
    let angle = |from: [f64; 2], to: [f64; 2]| (to[1] - from[1]).atan2(to[0] - from[0]);
    let tau = std::f64::consts::TAU;
    for (&(kx, ky), here) in &cells {
        for &n in here {
            let p = body.nodes[n];
            for dx in -1..=1 {
                for dy in -1..=1 {
                    let Some(others) = cells.get(&(kx + dx, ky + dy)) else {
                        continue;
                    };
                    for &m in others.iter().filter(|&&m| m > n) {
                        let q = body.nodes[m];
                        if (p[0] - q[0]).abs() > eps || (p[1] - q[1]).abs() > eps {
                            continue;
                        }
                        // Sector swept counter-clockwise from n's first ray to its second.
                        let a0 = angle(p, body.nodes[neighbours[n][0]]);
                        let span = (angle(p, body.nodes[neighbours[n][1]]) - a0).rem_euclid(tau);
                        let side = |to: usize| {
                            let d = (angle(p, body.nodes[to]) - a0).rem_euclid(tau);
                            (
                                d > 1e-9 && d < span - 1e-9,
                                d > span + 1e-9 && d < tau - 1e-9,
                            )
                        };
                        let (s1, s2) = (side(neighbours[m][0]), side(neighbours[m][1]));
                        let crosses = (s1.0 && s2.1) || (s1.1 && s2.0);
                        if crosses {
                            return Err(Error::input(
                                mfile,
                                format!(
                                    "the boundary of body \"{}\" crosses itself at {}, where two \
                                     of its nodes coincide: a body's boundary must be simple \
                                     loops; split the bow tie into two surfaces (or fix the \
                                     curves there)",
                                    body.name,
                                    fmt_point(p)
                                ),
                            ));
                        }
                    }
                }
            }
        }
    }
    Ok(())
}

/// Proper crossing of two segments (touching end points and collinear overlap excluded).
fn segments_cross(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let scale = norm(sub(b, a)) * norm(sub(d, c));
    let tol = 1e-10 * scale;
    let o1 = cross(sub(b, a), sub(c, a));
    let o2 = cross(sub(b, a), sub(d, a));
    let o3 = cross(sub(d, c), sub(a, c));
    let o4 = cross(sub(d, c), sub(b, c));
    ((o1 > tol && o2 < -tol) || (o1 < -tol && o2 > tol))
        && ((o3 > tol && o4 < -tol) || (o3 < -tol && o4 > tol))
}

/// Marks double traction nodes: at a change of part or interface, and at corners.
fn mark_traction_breaks(bodies: &mut [Body]) {
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
fn constrained_directions(e: &Element, parts: &[Part]) -> Vec<([f64; 2], usize, usize)> {
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
fn node_dofs(body: &Body, parts: &[Part]) -> Vec<NodeDofs> {
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

/// Where an interface ends on a displacement condition that fixes one direction (a symmetry
/// plane crossing a curved joint), the pair frame is turned onto that direction: the averaged
/// normal of a chord differs from the plane's by half an element's angle, and the frame of a
/// pair must contain the prescribed direction. Turns larger than 30° are left to the
/// assembly, which reports an oblique condition.
fn align_pair_frames(bodies: &[Body], interfaces: &mut [Interface]) {
    let limit = 30f64.to_radians().cos();
    for it in interfaces.iter_mut() {
        let a = &bodies[it.body_a];
        for p in it.pairs.iter_mut() {
            let d = a.dofs[p.node_a];
            let one_known = d.class[1] == DofClass::Known && d.class[0] != DofClass::Known;
            if !one_known {
                continue;
            }
            let k = d.frame[1];
            let (cn, ct) = (dot(k, p.normal), dot(k, p.tangent));
            if cn.abs() >= ct.abs() && cn.abs() >= limit {
                p.normal = [k[0] * cn.signum(), k[1] * cn.signum()];
                p.tangent = [-p.normal[1], p.normal[0]];
            } else if ct.abs() > cn.abs() && ct.abs() >= limit {
                p.tangent = [k[0] * ct.signum(), k[1] * ct.signum()];
                p.normal = [p.tangent[1], -p.tangent[0]];
            }
        }
    }
}

/// A displacement condition that reaches an interface node must hold both sides of the
/// pair along each of the pair's directions, or neither (the assembly cannot join a known
/// displacement on one side to an unknown one on the other): refused here, so that `check`
/// says what `run` would.
fn check_one_sided(
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
    for it in interfaces {
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

/// Prescribed values must be finite at every node of their part.
fn check_values(bodies: &[Body], parts: &[Part], sfile: &Path, t: f64) -> Result<()> {
    for body in bodies {
        for e in &body.elements {
            let Role::Boundary(pi) = e.role else { continue };
            let spec = &parts[pi].spec;
            for (c, cond) in spec.components.iter().enumerate() {
                let (Condition::Displacement(v) | Condition::Traction(v)) = cond;
                if v.as_const().is_some() {
                    continue;
                }
                for n in e.nodes {
                    let x = body.nodes[n];
                    let val = v.eval(x, t);
                    if !val.is_finite() {
                        let comp = match (spec.frame, c, cond.is_displacement()) {
                            (Frame::Global, 0, true) => "ux",
                            (Frame::Global, _, true) => "uy",
                            (Frame::Local, 0, true) => "ut",
                            (Frame::Local, _, true) => "un",
                            (Frame::Global, 0, false) => "tx",
                            (Frame::Global, _, false) => "ty",
                            (Frame::Local, 0, false) => "tt",
                            (Frame::Local, _, false) => "tn",
                        };
                        return Err(Error::input(
                            sfile,
                            format!(
                                "`boundary.{}.{comp}` = {v} is {val} at {} (body \"{}\", element \
                                 {}, t = {}): the expression must be defined on the whole curve \
                                 at every step",
                                spec.name,
                                fmt_point(x),
                                body.name,
                                e.tag,
                                fmt_num(t)
                            ),
                        ));
                    }
                }
            }
        }
    }
    Ok(())
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

/// Every group of bodies linked by interfaces must be held against all rigid motions by its
/// displacement conditions.
fn check_held(bodies: &[Body], interfaces: &[Interface], sfile: &Path, scale: f64) -> Result<()> {
    // Connected components through interfaces (union–find).
    let mut parent: Vec<usize> = (0..bodies.len()).collect();
    fn find(p: &mut [usize], i: usize) -> usize {
        let mut r = i;
        while p[r] != r {
            r = p[r];
        }
        p[i] = r;
        r
    }
    for it in interfaces {
        let (ra, rb) = (find(&mut parent, it.body_a), find(&mut parent, it.body_b));
        parent[ra] = rb;
    }
    let mut groups: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for b in 0..bodies.len() {
        let r = find(&mut parent, b);
        groups.entry(r).or_default().push(b);
    }
    for members in groups.values() {
        // Rows [d_x, d_y, d · (−(y − yc), x − xc) / scale] of every known direction.
        let centre = {
            let pts: Vec<[f64; 2]> = members
                .iter()
                .flat_map(|&b| bodies[b].nodes.iter().copied())
                .collect();
            let n = pts.len().max(1) as f64;
            [
                pts.iter().map(|p| p[0]).sum::<f64>() / n,
                pts.iter().map(|p| p[1]).sum::<f64>() / n,
            ]
        };
        let mut basis: Vec<[f64; 3]> = Vec::new();
        'outer: for &b in members {
            let body = &bodies[b];
            for (n, d) in body.dofs.iter().enumerate() {
                for k in 0..2 {
                    if d.class[k] != DofClass::Known {
                        continue;
                    }
                    let dir = d.frame[k];
                    let r = sub(body.nodes[n], centre);
                    let mut row = [dir[0], dir[1], (-r[1] * dir[0] + r[0] * dir[1]) / scale];
                    for q in &basis {
                        let p = row[0] * q[0] + row[1] * q[1] + row[2] * q[2];
                        for i in 0..3 {
                            row[i] -= p * q[i];
                        }
                    }
                    let len = (row[0] * row[0] + row[1] * row[1] + row[2] * row[2]).sqrt();
                    if len > 1e-6 {
                        basis.push([row[0] / len, row[1] / len, row[2] / len]);
                        if basis.len() == 3 {
                            break 'outer;
                        }
                    }
                }
            }
        }
        if basis.len() == 3 {
            continue;
        }
        let names: Vec<String> = members
            .iter()
            .map(|&b| format!("\"{}\"", bodies[b].name))
            .collect();
        let who = if members.len() == 1 {
            format!("body {}", names[0])
        } else {
            format!("bodies {} (joined by interfaces)", names.join(", "))
        };
        let free = free_mode(&basis);
        let what = if basis.is_empty() {
            "it has no displacement condition".to_string()
        } else {
            format!("its displacement conditions leave {free} free")
        };
        let no_iface = members.len() == 1
            && !interfaces
                .iter()
                .any(|i| i.body_a == members[0] || i.body_b == members[0]);
        let extra = if no_iface { " and no interface" } else { "" };
        return Err(Error::input(
            sfile,
            format!(
                "{who} is not held: {what}{extra}; prescribe displacements on a boundary \
                 (e.g. [boundary.NAME] ux = 0, uy = 0) or join it to a held body with an interface"
            ),
        ));
    }
    Ok(())
}

/// Describes a rigid mode orthogonal to the given rows (fewer than 3 orthonormal rows).
fn free_mode(basis: &[[f64; 3]]) -> String {
    let candidates = [
        ([1.0, 0.0, 0.0], "a translation along x"),
        ([0.0, 1.0, 0.0], "a translation along y"),
        ([0.0, 0.0, 1.0], "a rotation"),
    ];
    // The candidate with the largest component outside the span of the basis.
    let mut best = ("a rigid motion", 0.0);
    for (v, name) in candidates {
        let mut r = v;
        for q in basis {
            let p = r[0] * q[0] + r[1] * q[1] + r[2] * q[2];
            for i in 0..3 {
                r[i] -= p * q[i];
            }
        }
        let len = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
        if len > best.1 + 1e-9 {
            best = (name, len);
        }
    }
    best.0.to_string()
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
