//! The record of a run: plain data that the archive and VTK writers serialise and that
//! `sgbem inspect` and `sgbem export` read back.
//!
//! Place in the flow: the pipeline fills a [`RunRecord`] from its objects (scene, mesh,
//! model, per-body systems, the states of the contact iterations, the history, timings and
//! the summary) and hands it to [`super::archive::write_archive`] and
//! [`super::vtk::write_vtk`]. [`super::archive::read_archive`] gives the same record back,
//! so that every VTK file can be rebuilt from the archive alone: nothing a writer uses is
//! left out of the record, and nothing in it is computed by the writers but from the
//! record itself.
//!
//! Conventions: indices are 0-based; body node indices are body-local (as
//! [`crate::input::model::Body::nodes`]); mesh node indices index [`MeshRecord::nodes`]; pair
//! quantities are in the pair frame (s, n) of the first body, tractions tension positive.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::sync::Arc;

use faer::Mat;

use crate::bem::assembly::{BodySystem, Unknown};
use crate::bem::condensation::Condensed;
use crate::error::{Error, Result};
use crate::input::mesh::Mesh;
use crate::input::model::{fmt_num, Interface, Model};
use crate::input::scene::{InitialState, InterfaceModel, Plane, Scene, Units, VtkStyle};
use crate::post::NodeValue;
use crate::solution::{BodyField, BodyMotion, History, InterfaceResult, PairStatus};

pub use super::stamp::sha256_hex;
pub(crate) use super::stamp::{sha256_file, utc_now};

/// Version of the archive layout written by this build (root attribute `format_version`).
pub const FORMAT_VERSION: i64 = 2;

/// A dense array of `f64` in row-major order: a vector (`shape = [n]`) or a matrix
/// (`shape = [rows, cols]`).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Array {
    pub shape: Vec<usize>,
    pub data: Vec<f64>,
}

impl Array {
    /// A vector.
    pub fn vector(data: Vec<f64>) -> Array {
        Array {
            shape: vec![data.len()],
            data,
        }
    }

    /// A matrix from rows × cols values in row-major order.
    pub fn matrix(rows: usize, cols: usize, data: Vec<f64>) -> Array {
        assert_eq!(
            data.len(),
            rows * cols,
            "a {rows} x {cols} matrix needs {} values",
            rows * cols
        );
        Array {
            shape: vec![rows, cols],
            data,
        }
    }

    /// A copy of a faer matrix.
    pub(crate) fn from_mat(m: &Mat<f64>) -> Array {
        let (r, c) = (m.nrows(), m.ncols());
        let mut data = Vec::with_capacity(r * c);
        for i in 0..r {
            for j in 0..c {
                data.push(m[(i, j)]);
            }
        }
        Array::matrix(r, c, data)
    }

    /// The sub-block of rows `r0..r1`, columns `c0..c1` of a faer matrix.
    pub(crate) fn from_block(
        m: &Mat<f64>,
        rows: std::ops::Range<usize>,
        cols: std::ops::Range<usize>,
    ) -> Array {
        let (nr, nc) = (rows.len(), cols.len());
        let mut data = Vec::with_capacity(nr * nc);
        for i in rows {
            for j in cols.clone() {
                data.push(m[(i, j)]);
            }
        }
        Array::matrix(nr, nc, data)
    }

    /// "240 x 240" or "240".
    pub(crate) fn shape_text(&self) -> String {
        let s: Vec<String> = self.shape.iter().map(|d| d.to_string()).collect();
        s.join(" x ")
    }
}

/// The mesh as read.
#[derive(Debug, Clone, Default)]
pub struct MeshRecord {
    /// Node coordinates.
    pub nodes: Vec<[f64; 2]>,
    /// gmsh tag of each node.
    pub node_tags: Vec<usize>,
    /// 2-node line elements (mesh node indices).
    pub lines: Vec<[usize; 2]>,
    /// Physical group of each line (index into `group_names`), `None` when its curve is in
    /// no physical group.
    pub line_group: Vec<Option<usize>>,
    /// 3-node triangles (mesh node indices).
    pub triangles: Vec<[usize; 3]>,
    /// Physical group of each triangle (index into `group_names`).
    pub triangle_group: Vec<Option<usize>>,
    /// Names of the physical groups, in file order, and their dimensions (1 curve, 2 surface).
    pub group_names: Vec<String>,
    pub group_dims: Vec<i32>,
}

impl MeshRecord {
    /// The record of a mesh read by [`crate::input::mesh::read_msh`]. A line or triangle takes the
    /// first physical group of its entity.
    pub(crate) fn from_mesh(mesh: &Mesh) -> MeshRecord {
        let group_names = mesh.physical_names.iter().map(|p| p.name.clone()).collect();
        let group_dims = mesh.physical_names.iter().map(|p| p.dim).collect();
        let index: HashMap<(i32, i32), usize> = mesh
            .physical_names
            .iter()
            .enumerate()
            .map(|(i, p)| ((p.dim, p.tag), i))
            .collect();
        let group_of = |dim: i32, tags: Option<&Vec<i32>>| -> Option<usize> {
            tags?.iter().find_map(|t| index.get(&(dim, *t)).copied())
        };
        MeshRecord {
            nodes: mesh.nodes.clone(),
            node_tags: mesh.node_tags.clone(),
            lines: mesh.lines.iter().map(|l| l.nodes).collect(),
            line_group: mesh
                .lines
                .iter()
                .map(|l| group_of(1, mesh.curves.get(&l.curve).map(|e| &e.physical_tags)))
                .collect(),
            triangles: mesh.triangles.iter().map(|t| t.nodes).collect(),
            triangle_group: mesh
                .triangles
                .iter()
                .map(|t| group_of(2, mesh.surfaces.get(&t.surface).map(|e| &e.physical_tags)))
                .collect(),
            group_names,
            group_dims,
        }
    }
}

/// The Galerkin system of one body and its condensation (docs/formulation.md §3):
/// `G = [[A, A0], [A0ᵀ, A00]]`, load `[L̂; L̂0]`, `D00` and `Z̄0`.
#[derive(Debug, Clone, Default)]
pub struct BodyOperators {
    /// One description per unknown, X (the first `n_x`) then X0.
    pub unknowns: Vec<String>,
    pub n_x: usize,
    pub a: Array,
    pub a0: Array,
    pub a00: Array,
    /// `[L̂; L̂0]`.
    pub load: Vec<f64>,
    pub d00: Array,
    pub z0: Vec<f64>,
}

impl BodyOperators {
    /// The blocks of an assembled body and of its condensation.
    pub(crate) fn from_system(sys: &BodySystem, cond: &Condensed) -> BodyOperators {
        let (nx, n) = (sys.n_x, sys.n());
        BodyOperators {
            unknowns: sys.unknowns.iter().map(describe_unknown).collect(),
            n_x: nx,
            a: Array::from_block(&sys.g, 0..nx, 0..nx),
            a0: Array::from_block(&sys.g, 0..nx, nx..n),
            a00: Array::from_block(&sys.g, nx..n, nx..n),
            load: sys.load.clone(),
            d00: Array::from_mat(&cond.d00),
            z0: cond.z0.clone(),
        }
    }
}

/// A readable description of one unknown, e.g. `F1 element 3 end 0 dir (1, 0)`.
pub(crate) fn describe_unknown(u: &Unknown) -> String {
    let d = |v: [f64; 2]| format!("({}, {})", fmt_num(v[0]), fmt_num(v[1]));
    match *u {
        Unknown::Traction1 { elem, end, dir } => {
            format!("F1 element {elem} end {end} dir {}", d(dir))
        }
        Unknown::Traction0 {
            iface,
            pair,
            comp,
            dir,
        } => format!(
            "F0 interface {iface} pair {pair} {} dir {}",
            ["s", "n"][comp.min(1)],
            d(dir)
        ),
        Unknown::Displacement { node, dir, on } => match on {
            Some((k, j, c)) => format!(
                "-U0 node {node} interface {k} pair {j} {} dir {}",
                ["s", "n"][c.min(1)],
                d(dir)
            ),
            None => format!("-U2 node {node} dir {}", d(dir)),
        },
        Unknown::LoopMode {
            loop_index, mode, ..
        } => format!(
            "F loop {loop_index} rigid mode ({}, {}, {})",
            fmt_num(mode[0]),
            fmt_num(mode[1]),
            fmt_num(mode[2])
        ),
    }
}

/// One body.
#[derive(Debug, Clone, Default)]
pub struct BodyRecord {
    pub name: String,
    pub young: f64,
    pub poisson: f64,
    pub body_force: Option<[f64; 2]>,
    /// Boundary node coordinates (body-local numbering).
    pub nodes: Vec<[f64; 2]>,
    /// Mesh node of each boundary node.
    pub mesh_nodes: Vec<usize>,
    /// Boundary elements, oriented with the body on the left (body-local node indices).
    pub elements: Vec<[usize; 2]>,
    /// Mesh triangles of the body (mesh node indices).
    pub triangles: Vec<[usize; 3]>,
    /// The Galerkin blocks, when the scene asks for them (`output.operators`).
    pub operators: Option<BodyOperators>,
}

/// One interface: its node pairs in order of arc length.
#[derive(Debug, Clone, Default)]
pub struct InterfaceRecord {
    pub name: String,
    /// Body indices: A (first) and B.
    pub body_a: usize,
    pub body_b: usize,
    /// "bonded" | "unilateral".
    pub model: String,
    /// "closed" | "open".
    pub initial: String,
    /// "stick" | "slide".
    pub tangential: String,
    /// Body-local node of each pair in A and in B.
    pub node_a: Vec<usize>,
    pub node_b: Vec<usize>,
    pub x: Vec<[f64; 2]>,
    /// Outward unit normal of A and tangent `(−n_y, n_x)` at each pair.
    pub normal: Vec<[f64; 2]>,
    pub tangent: Vec<[f64; 2]>,
    /// Arc length from the curve's first node.
    pub s: Vec<f64>,
    pub gap: Vec<f64>,
    pub cohesion: Vec<f64>,
    /// Interface elements as pairs of pair indices (A's start, A's end).
    pub elements: Vec<[usize; 2]>,
    /// Sides meshed on their own: the rows of the pairs over B's nodes (None for node pairs).
    pub pairing: Option<PairingRecord>,
}

/// The pairing of an interface whose sides were meshed on their own (docs/formulation.md
/// §5.6): each pair's row `u^B = Σ coef·u^B_node` over B's nodes, its tributary length and
/// its gap measured from the geometry.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PairingRecord {
    /// Where each pair's partners start in `node` and `coef` (pairs + 1 offsets).
    pub offset: Vec<usize>,
    /// B's nodes (body-local) and their coefficients.
    pub node: Vec<usize>,
    pub coef: Vec<f64>,
    /// Per pair: the tributary length of its rows and the gap measured from the geometry.
    pub weight: Vec<f64>,
    pub gap_geometry: Vec<f64>,
    /// Per pair: B's element facing it (body-local), None where nothing of B faces it.
    pub segment: Vec<Option<usize>>,
    /// B's interface nodes (body-local).
    pub b_nodes: Vec<usize>,
}

impl PairingRecord {
    /// The pairing of a model interface, if its sides were meshed on their own.
    pub fn of(it: &Interface) -> Option<PairingRecord> {
        if !it.independent() {
            return None;
        }
        let mut r = PairingRecord {
            offset: vec![0],
            b_nodes: it.b_nodes.iter().map(|p| p.node).collect(),
            ..Default::default()
        };
        for p in &it.pairs {
            for &(n, c) in &p.partners {
                r.node.push(n);
                r.coef.push(c);
            }
            r.offset.push(r.node.len());
            r.weight.push(p.weight);
            r.gap_geometry.push(p.gap_geometry);
            r.segment.push(p.segment);
        }
        Some(r)
    }
}

impl InterfaceRecord {
    /// The record of a model interface.
    pub(crate) fn from_interface(it: &Interface) -> InterfaceRecord {
        InterfaceRecord {
            name: it.spec.name.clone(),
            body_a: it.body_a,
            body_b: it.body_b,
            model: match it.spec.model {
                InterfaceModel::Bonded => "bonded",
                InterfaceModel::Unilateral => "unilateral",
            }
            .into(),
            initial: match it.spec.initial {
                InitialState::Closed => "closed",
                InitialState::Open => "open",
            }
            .into(),
            tangential: it.spec.tangential.name().into(),
            node_a: it.pairs.iter().map(|p| p.node_a).collect(),
            node_b: it.pairs.iter().map(|p| p.node_b).collect(),
            x: it.pairs.iter().map(|p| p.x).collect(),
            normal: it.pairs.iter().map(|p| p.normal).collect(),
            tangent: it.pairs.iter().map(|p| p.tangent).collect(),
            s: it.pairs.iter().map(|p| p.s).collect(),
            gap: it.pairs.iter().map(|p| p.gap).collect(),
            cohesion: it.pairs.iter().map(|p| p.cohesion).collect(),
            elements: it.elements.iter().map(|e| e.pairs).collect(),
            pairing: PairingRecord::of(it),
        }
    }

    /// Length of the elements whose two end pairs are both open in `r`.
    pub fn detached_length(&self, r: &InterfaceResult) -> f64 {
        self.elements
            .iter()
            .filter(|[j, k]| {
                r.pairs.get(*j).map(|p| p.status) == Some(PairStatus::Open)
                    && r.pairs.get(*k).map(|p| p.status) == Some(PairStatus::Open)
            })
            .map(|&[j, k]| self.segment_length(j, k))
            .sum()
    }

    /// Total length of the interface.
    pub fn length(&self) -> f64 {
        self.elements
            .iter()
            .map(|&[j, k]| self.segment_length(j, k))
            .sum()
    }

    fn segment_length(&self, j: usize, k: usize) -> f64 {
        match (self.x.get(j), self.x.get(k)) {
            (Some(a), Some(b)) => (b[0] - a[0]).hypot(b[1] - a[1]),
            _ => 0.0,
        }
    }

    /// The tributary length of each pair, as [`Interface::weights`] gives it.
    pub fn weights(&self) -> Vec<f64> {
        match &self.pairing {
            Some(p) => p.weight.clone(),
            None => crate::input::model::tributary_lengths(&self.x, self.elements.iter().copied()),
        }
    }

    /// The pairs of the joint as the thrust line reads them.
    pub fn joint(&self) -> crate::post::thrust::Joint {
        crate::post::thrust::Joint {
            x: self.x.clone(),
            s: self.s.clone(),
            weights: self.weights(),
            normal: self.normal.clone(),
        }
    }

    /// Normal opening of pair `j` in `r`: the current normal distance `gap + [u]·n` where
    /// open, 0 where closed (as in the interface CSV table).
    pub fn opening(&self, r: &InterfaceResult, j: usize) -> f64 {
        let p = &r.pairs[j];
        match p.status {
            PairStatus::Closed => 0.0,
            PairStatus::Open => self.gap[j] + p.jump[1],
        }
    }
}

/// Displacement and stress at the mesh nodes of one body's triangles.
#[derive(Debug, Clone, Default)]
pub struct InteriorRecord {
    /// Mesh node indices, increasing.
    pub mesh_nodes: Vec<usize>,
    pub u: Vec<[f64; 2]>,
    /// Stress components xx, yy, xy.
    pub sigma: Vec<[f64; 3]>,
}

impl InteriorRecord {
    /// From the values of [`crate::post::field_at_nodes`].
    pub(crate) fn from_values(values: &[NodeValue]) -> InteriorRecord {
        InteriorRecord {
            mesh_nodes: values.iter().map(|v| v.mesh_node).collect(),
            u: values.iter().map(|v| v.u).collect(),
            sigma: values
                .iter()
                .map(|v| {
                    [
                        v.sigma[0][0],
                        v.sigma[1][1],
                        0.5 * (v.sigma[0][1] + v.sigma[1][0]),
                    ]
                })
                .collect(),
        }
    }
}

/// One solved state, the record of an iterate (`contact::Iterate`): the boundary
/// solution of every body and the interface results after one contact iteration (or the
/// final state).
#[derive(Debug, Clone, Default)]
pub struct IterateRecord {
    /// Iteration number counted over the whole run (strictly increasing from state to
    /// state): the time of the state in `vtk/history.pvd`.
    pub iteration: usize,
    pub load_step: usize,
    pub load_factor: f64,
    /// One per body, in body order. Shared, not copied, when the record is cloned: the
    /// archive's thread and the VTK writer hold the same states (a full history of hundreds
    /// of bodies is most of a run's memory).
    pub fields: Arc<Vec<BodyField>>,
    /// One per interface, in interface order (shared as `fields`).
    pub interfaces: Arc<Vec<InterfaceResult>>,
    /// Interior values, one per body, or empty when no field was evaluated for this state.
    pub interior: Vec<InteriorRecord>,
    /// The body forces of the state (before the load factor), one per body, where they
    /// differ from the bodies' recorded ones (a body force in pseudo-time, the collapse
    /// search's multiplier); empty: the bodies' own ([`IterateRecord::body_forces`]).
    pub body_force: Vec<Option<[f64; 2]>>,
}

impl IterateRecord {
    pub fn new(
        iteration: usize,
        load_step: usize,
        load_factor: f64,
        fields: Vec<BodyField>,
        interfaces: Vec<InterfaceResult>,
    ) -> IterateRecord {
        IterateRecord {
            iteration,
            load_step,
            load_factor,
            fields: Arc::new(fields),
            interfaces: Arc::new(interfaces),
            interior: Vec::new(),
            body_force: Vec::new(),
        }
    }

    /// The state with the body forces `body_force` (one per body of `bodies`), kept only where
    /// they differ from the bodies' recorded ones.
    pub(crate) fn with_body_force(
        mut self,
        body_force: &[Option<[f64; 2]>],
        bodies: &[BodyRecord],
    ) -> IterateRecord {
        let own: Vec<Option<[f64; 2]>> = bodies.iter().map(|b| b.body_force).collect();
        self.body_force = if body_force == own.as_slice() {
            Vec::new()
        } else {
            body_force.to_vec()
        };
        self
    }

    /// The body forces of the state, one per body of `bodies` (before the load factor).
    pub fn body_forces(&self, bodies: &[BodyRecord]) -> Vec<Option<[f64; 2]>> {
        if self.body_force.len() == bodies.len() {
            self.body_force.clone()
        } else {
            bodies.iter().map(|b| b.body_force).collect()
        }
    }
}

/// Everything a run produced that the archive keeps.
#[derive(Debug, Clone)]
pub struct RunRecord {
    pub title: String,
    /// The scene file's text.
    pub scene_text: String,
    /// The `--set KEY=VALUE` overrides applied to the scene, in command-line order.
    pub overrides: Vec<String>,
    /// SHA-256 of the mesh file, lowercase hex (empty when unknown).
    pub mesh_sha256: String,
    pub units: Units,
    pub plane: Plane,
    pub thickness: f64,
    pub tool_version: String,
    /// UTC time the record was made, ISO 8601 (`2025-01-31T12:00:00Z`).
    pub created: String,
    pub mesh: MeshRecord,
    pub bodies: Vec<BodyRecord>,
    pub interfaces: Vec<InterfaceRecord>,
    /// Solved states in order; the last one is the final solution.
    pub states: Vec<IterateRecord>,
    pub history: History,
    /// The moving bodies' rigid motions of the mechanism drawn with the last state (the run
    /// failed at it, or the collapse search found it); empty: none.
    pub mechanism: Vec<BodyMotion>,
    /// Interface operators of the final status (`K00` and its blocks, `Ktilde_urur`,
    /// `Ktilde_fvfv`, loads), by name, in the order given.
    pub contact_operators: Option<Vec<(String, Array)>>,
    /// "converged", "solved", or what failed.
    pub status: String,
    /// Seconds per stage, in stage order.
    pub timings: Vec<(String, f64)>,
    /// The text of summary.json.
    pub summary_json: String,
    /// Deflate the archive's large datasets (`output.compress`).
    pub compress: bool,
    /// How the VTK files are written (`output.vtk`, `output.vtk_fields`); not archived:
    /// `sgbem export` takes it from the archived scene.
    pub vtk: VtkStyle,
}

impl RunRecord {
    /// An empty record with the given metadata (no mesh, bodies or states).
    pub fn empty(title: &str, plane: Plane) -> RunRecord {
        RunRecord {
            title: title.into(),
            scene_text: String::new(),
            overrides: Vec::new(),
            mesh_sha256: String::new(),
            units: Units::default(),
            plane,
            thickness: 1.0,
            tool_version: env!("CARGO_PKG_VERSION").into(),
            created: utc_now(),
            mesh: MeshRecord::default(),
            bodies: Vec::new(),
            interfaces: Vec::new(),
            states: Vec::new(),
            history: History::default(),
            mechanism: Vec::new(),
            contact_operators: None,
            status: String::new(),
            timings: Vec::new(),
            summary_json: String::new(),
            compress: false,
            vtk: VtkStyle::default(),
        }
    }

    /// The record of a loaded model, before solving: metadata, mesh (with the SHA-256 of
    /// the mesh file, read again from `model.mesh_path`), bodies without operators and
    /// interfaces. States, history, status, timings and summary are for the caller to add.
    pub fn from_model(scene: &Scene, mesh: &Mesh, model: &Model) -> Result<RunRecord> {
        let mut r = RunRecord::empty(&scene.title, scene.plane);
        r.scene_text = scene.text.clone();
        r.overrides = scene.overrides.clone();
        r.compress = scene.output.compress;
        r.vtk = scene.output.vtk_style.clone();
        r.mesh_sha256 = sha256_file(&model.mesh_path)?;
        r.units = scene.units.clone();
        r.thickness = scene.thickness;
        r.mesh = MeshRecord::from_mesh(mesh);
        r.bodies = model
            .bodies
            .iter()
            .map(|b| BodyRecord {
                name: b.name.clone(),
                young: b.young,
                poisson: b.poisson,
                body_force: b.body_force,
                nodes: b.nodes.clone(),
                mesh_nodes: b.mesh_nodes.clone(),
                elements: b.elements.iter().map(|e| e.nodes).collect(),
                triangles: b.triangles.clone(),
                operators: None,
            })
            .collect();
        r.interfaces = model
            .interfaces
            .iter()
            .map(InterfaceRecord::from_interface)
            .collect();
        Ok(r)
    }

    /// Attaches the Galerkin blocks of every body (`output.operators = true`); refuses
    /// systems or condensations that are not one per body of the record.
    pub(crate) fn set_operators(
        &mut self,
        systems: &[BodySystem],
        condensed: &[Condensed],
    ) -> Result<()> {
        let n = self.bodies.len();
        if systems.len() != n || condensed.len() != n {
            return Err(Error::numerical(format!(
                "cannot record the bodies' operators: {} systems and {} condensations for {n} \
                 bodies",
                systems.len(),
                condensed.len()
            )));
        }
        for ((b, s), c) in self.bodies.iter_mut().zip(systems).zip(condensed) {
            b.operators = Some(BodyOperators::from_system(s, c));
        }
        Ok(())
    }

    /// Checks every size and cross-reference the writers rely on, so that writing a record
    /// read from a damaged archive fails with a message instead of a panic.
    pub fn validate(&self) -> std::result::Result<(), String> {
        self.validate_mesh()?;
        self.validate_bodies()?;
        self.validate_interfaces()?;
        self.validate_states()?;
        self.validate_history()?;
        self.validate_mechanism()
    }

    /// The mechanism: bodies in range, finite motions.
    fn validate_mechanism(&self) -> std::result::Result<(), String> {
        for m in &self.mechanism {
            in_range(
                "mechanism",
                std::iter::once(&m.body),
                self.bodies.len(),
                "bodies",
            )?;
            let v = [m.centroid, m.translation, [m.rotation, 0.0]];
            if !v.as_flattened().iter().all(|x| x.is_finite()) {
                return Err(format!("the mechanism of body {} is not finite", m.body));
            }
        }
        Ok(())
    }

    /// The mesh: per-node, per-line and per-triangle arrays of one length, indices in range.
    fn validate_mesh(&self) -> std::result::Result<(), String> {
        let m = &self.mesh;
        let nm = m.nodes.len();
        let ng = m.group_names.len();
        same_len("mesh node_tags", m.node_tags.len(), "mesh nodes", nm)?;
        same_len(
            "mesh line_group",
            m.line_group.len(),
            "mesh lines",
            m.lines.len(),
        )?;
        same_len(
            "mesh triangle_group",
            m.triangle_group.len(),
            "mesh triangles",
            m.triangles.len(),
        )?;
        same_len(
            "mesh group_dims",
            m.group_dims.len(),
            "mesh group_names",
            ng,
        )?;
        in_range("mesh lines", m.lines.iter().flatten(), nm, "mesh nodes")?;
        in_range(
            "mesh triangles",
            m.triangles.iter().flatten(),
            nm,
            "mesh nodes",
        )?;
        in_range(
            "mesh line_group",
            m.line_group.iter().flatten(),
            ng,
            "groups",
        )?;
        in_range(
            "mesh triangle_group",
            m.triangle_group.iter().flatten(),
            ng,
            "groups",
        )?;
        Ok(())
    }

    /// The bodies: their nodes in the mesh, their elements and triangles in range, and the
    /// shapes of their operators.
    fn validate_bodies(&self) -> std::result::Result<(), String> {
        let nm = self.mesh.nodes.len();
        for b in &self.bodies {
            let w = |s: &str| format!("body \"{}\" {s}", b.name);
            let nn = b.nodes.len();
            same_len(&w("mesh_nodes"), b.mesh_nodes.len(), &w("nodes"), nn)?;
            in_range(&w("mesh_nodes"), b.mesh_nodes.iter(), nm, "mesh nodes")?;
            in_range(&w("elements"), b.elements.iter().flatten(), nn, "its nodes")?;
            in_range(
                &w("triangles"),
                b.triangles.iter().flatten(),
                nm,
                "mesh nodes",
            )?;
            if let Some(op) = &b.operators {
                let n = op.unknowns.len();
                let nx = op.n_x;
                if nx > n {
                    return Err(format!("{} {nx} exceeds {n} unknowns", w("n_x")));
                }
                let n0 = n - nx;
                for (name, a, shape) in [
                    ("A", &op.a, [nx, nx]),
                    ("A0", &op.a0, [nx, n0]),
                    ("A00", &op.a00, [n0, n0]),
                    ("D00", &op.d00, [n0, n0]),
                ] {
                    array_shape(&w(name), a, &shape)?;
                }
                same_len(&w("load"), op.load.len(), "unknowns", n)?;
                same_len(&w("Z0"), op.z0.len(), "interface unknowns", n0)?;
            }
        }
        Ok(())
    }

    /// The interfaces: two existing bodies, one value per pair, nodes and elements in range.
    fn validate_interfaces(&self) -> std::result::Result<(), String> {
        let nb = self.bodies.len();
        for it in &self.interfaces {
            let w = |s: &str| format!("interface \"{}\" {s}", it.name);
            if it.body_a >= nb || it.body_b >= nb {
                return Err(format!("{} names a body beyond the {nb} bodies", w("")));
            }
            let np = it.node_a.len();
            for (s, l) in [
                ("node_b", it.node_b.len()),
                ("x", it.x.len()),
                ("normal", it.normal.len()),
                ("tangent", it.tangent.len()),
                ("s", it.s.len()),
                ("gap", it.gap.len()),
                ("cohesion", it.cohesion.len()),
            ] {
                same_len(&w(s), l, "pairs", np)?;
            }
            let (na, nbn) = (
                self.bodies[it.body_a].nodes.len(),
                self.bodies[it.body_b].nodes.len(),
            );
            in_range(&w("node_a"), it.node_a.iter(), na, "nodes of body A")?;
            in_range(&w("node_b"), it.node_b.iter(), nbn, "nodes of body B")?;
            in_range(&w("elements"), it.elements.iter().flatten(), np, "pairs")?;
            if let Some(pr) = &it.pairing {
                same_len(&w("pairing offsets"), pr.offset.len(), "pairs + 1", np + 1)?;
                for (s, l) in [
                    ("pairing weight", pr.weight.len()),
                    ("pairing gap_geometry", pr.gap_geometry.len()),
                    ("pairing segment", pr.segment.len()),
                ] {
                    same_len(&w(s), l, "pairs", np)?;
                }
                same_len(
                    &w("pairing coef"),
                    pr.coef.len(),
                    "partner nodes",
                    pr.node.len(),
                )?;
                if pr.offset.windows(2).any(|o| o[0] > o[1])
                    || pr.offset.last().is_some_and(|&l| l != pr.node.len())
                {
                    return Err(format!(
                        "{}: offsets must grow up to the partner count",
                        w("pairing")
                    ));
                }
                in_range(&w("pairing node"), pr.node.iter(), nbn, "nodes of body B")?;
                in_range(
                    &w("pairing b_nodes"),
                    pr.b_nodes.iter(),
                    nbn,
                    "nodes of body B",
                )?;
                let ne = self.bodies[it.body_b].elements.len();
                in_range(
                    &w("pairing segment"),
                    pr.segment.iter().flatten(),
                    ne,
                    "elements of B",
                )?;
            }
        }
        Ok(())
    }

    /// The recorded states: increasing iterations, one field per body and one result per
    /// interface of the right sizes, interior values at every triangle node.
    fn validate_states(&self) -> std::result::Result<(), String> {
        let nm = self.mesh.nodes.len();
        let nb = self.bodies.len();
        let mut last: Option<usize> = None;
        for (k, st) in self.states.iter().enumerate() {
            let w = |s: &str| format!("state {k} {s}");
            if last.is_some_and(|l| st.iteration <= l) {
                return Err(format!(
                    "state {k} has iteration {} after iteration {}: iterations must increase",
                    st.iteration,
                    last.unwrap_or(0)
                ));
            }
            last = Some(st.iteration);
            len_is(|| w("fields"), st.fields.len(), "bodies", nb)?;
            for (b, f) in self.bodies.iter().zip(st.fields.iter()) {
                len_is(
                    || w(&format!("u of \"{}\"", b.name)),
                    f.u.len(),
                    "nodes",
                    b.nodes.len(),
                )?;
                len_is(
                    || w(&format!("t of \"{}\"", b.name)),
                    f.t.len(),
                    "elements",
                    b.elements.len(),
                )?;
            }
            len_is(
                || w("interface results"),
                st.interfaces.len(),
                "interfaces",
                self.interfaces.len(),
            )?;
            for (it, r) in self.interfaces.iter().zip(st.interfaces.iter()) {
                len_is(
                    || w(&format!("pairs of \"{}\"", it.name)),
                    r.pairs.len(),
                    "pairs",
                    it.node_a.len(),
                )?;
            }
            if !st.interior.is_empty() {
                same_len(&w("interior"), st.interior.len(), "bodies", nb)?;
                for (b, f) in self.bodies.iter().zip(&st.interior) {
                    let ww = |s: &str| w(&format!("interior {s} of \"{}\"", b.name));
                    let n = f.mesh_nodes.len();
                    same_len(&ww("u"), f.u.len(), "points", n)?;
                    same_len(&ww("sigma"), f.sigma.len(), "points", n)?;
                    in_range(&ww("mesh_nodes"), f.mesh_nodes.iter(), nm, "mesh nodes")?;
                    let have: std::collections::HashSet<usize> =
                        f.mesh_nodes.iter().copied().collect();
                    if let Some(t) = b
                        .triangles
                        .iter()
                        .find(|t| t.iter().any(|n| !have.contains(n)))
                    {
                        return Err(format!(
                            "{} lacks a node of triangle {t:?}",
                            ww("mesh_nodes")
                        ));
                    }
                }
            }
        }
        Ok(())
    }

    /// The history rows: one value per interface and per pair.
    fn validate_history(&self) -> std::result::Result<(), String> {
        let ni = self.interfaces.len();
        for (k, row) in self.history.rows.iter().enumerate() {
            let w = |s: &str| format!("history row {k} {s}");
            for (name, len) in [
                ("status", row.status.len()),
                ("normal_traction", row.normal_traction.len()),
                ("normal_opening", row.normal_opening.len()),
                ("detached_length", row.detached_length.len()),
            ] {
                len_is(|| w(name), len, "interfaces", ni)?;
            }
            for (i, it) in self.interfaces.iter().enumerate() {
                let np = it.node_a.len();
                len_is(|| w("status"), row.status[i].len(), "pairs", np)?;
                len_is(
                    || w("normal_traction"),
                    row.normal_traction[i].len(),
                    "pairs",
                    np,
                )?;
                len_is(
                    || w("normal_opening"),
                    row.normal_opening[i].len(),
                    "pairs",
                    np,
                )?;
            }
        }
        Ok(())
    }

    /// What `sgbem inspect` prints: title, bodies, interfaces, states, the contact history
    /// with detached lengths per iteration, timings.
    pub(crate) fn describe(&self) -> String {
        let mut o = String::new();
        let n = fmt_num;
        let _ = writeln!(o, "title       {}", self.title);
        let _ = writeln!(o, "status      {}", self.status);
        let _ = writeln!(
            o,
            "written by  sgbem {} on {}",
            self.tool_version, self.created
        );
        if !self.overrides.is_empty() {
            let _ = writeln!(o, "overrides   --set {}", self.overrides.join(" --set "));
        }
        let _ = writeln!(
            o,
            "plane       {}, thickness {}, units: length {}, force {}",
            plane_name(self.plane),
            n(self.thickness),
            or_dash(&self.units.length),
            or_dash(&self.units.force)
        );
        let _ = writeln!(
            o,
            "mesh        {} nodes, {} lines, {} triangles, sha256 {}",
            self.mesh.nodes.len(),
            self.mesh.lines.len(),
            self.mesh.triangles.len(),
            or_dash(&self.mesh_sha256)
        );
        let _ = writeln!(o, "\nbodies ({})", self.bodies.len());
        for b in &self.bodies {
            let bf = match b.body_force {
                Some(f) => format!(", body force ({}, {})", n(f[0]), n(f[1])),
                None => String::new(),
            };
            let ops = match &b.operators {
                Some(op) => format!(
                    ", operators: {} unknowns ({} interface), D00 {}",
                    op.unknowns.len(),
                    op.unknowns.len() - op.n_x.min(op.unknowns.len()),
                    op.d00.shape_text()
                ),
                None => String::new(),
            };
            let _ = writeln!(
                o,
                "  {:<12} E = {}, nu = {}{bf}; {} nodes, {} elements, {} triangles{ops}",
                b.name,
                n(b.young),
                n(b.poisson),
                b.nodes.len(),
                b.elements.len(),
                b.triangles.len()
            );
        }
        let _ = writeln!(o, "\ninterfaces ({})", self.interfaces.len());
        let body_name = |i: usize| self.bodies.get(i).map_or("?", |b| b.name.as_str());
        for it in &self.interfaces {
            let _ = writeln!(
                o,
                "  {:<12} {} | {}, {}, starts {}, {}; {} pairs, length {}",
                it.name,
                body_name(it.body_a),
                body_name(it.body_b),
                it.model,
                it.initial,
                it.tangential,
                it.node_a.len(),
                n(it.length())
            );
        }
        let with_field = self
            .states
            .iter()
            .filter(|s| !s.interior.is_empty())
            .count();
        let _ = write!(o, "\nstates ({})", self.states.len());
        if let (Some(a), Some(b)) = (self.states.first(), self.states.last()) {
            let _ = write!(o, ": iterations {} to {}", a.iteration, b.iteration);
        }
        let _ = writeln!(o, "; interior field in {with_field}");
        if let Some(last) = self.states.last() {
            for (it, r) in self.interfaces.iter().zip(last.interfaces.iter()) {
                let open = r
                    .pairs
                    .iter()
                    .filter(|p| p.status == PairStatus::Open)
                    .count();
                let _ = writeln!(
                    o,
                    "  final {:<12} detached length {}, {open} of {} pairs open",
                    it.name,
                    n(it.detached_length(r)),
                    r.pairs.len()
                );
            }
        }
        if !self.mechanism.is_empty() {
            let moving: Vec<&str> = self.mechanism.iter().map(|m| body_name(m.body)).collect();
            let _ = writeln!(o, "  mechanism moves {}", moving.join(", "));
        }
        let _ = writeln!(o, "\niterations ({})", self.history.rows.len());
        if !self.history.rows.is_empty() {
            let mut head = String::from("  step  factor      iter  solver      ");
            for it in &self.interfaces {
                let _ = write!(head, " {:>14}", format!("{} detached", it.name));
            }
            let _ = writeln!(o, "{}", head.trim_end());
            for r in &self.history.rows {
                let mut line = format!(
                    "  {:>4}  {:<10}  {:>4}  {:<10}  ",
                    r.load_step,
                    n(r.load_factor),
                    r.iteration,
                    r.solver
                );
                for d in &r.detached_length {
                    let _ = write!(line, " {:>14}", n(*d));
                }
                let _ = writeln!(o, "{}", line.trim_end());
            }
        }
        let _ = writeln!(o, "\ntimings (s)");
        for (s, t) in &self.timings {
            let _ = writeln!(o, "  {s:<14} {}", n(*t));
        }
        o
    }
}

fn or_dash(s: &str) -> &str {
    if s.is_empty() {
        "-"
    } else {
        s
    }
}

/// "strain" | "stress".
pub(crate) fn plane_name(p: Plane) -> &'static str {
    match p {
        Plane::Strain => "strain",
        Plane::Stress => "stress",
    }
}

fn same_len(what: &str, len: usize, of: &str, want: usize) -> std::result::Result<(), String> {
    if len == want {
        Ok(())
    } else {
        Err(format!("{what} has {len} entries for {want} {of}"))
    }
}

/// [`same_len`] with the name made only on failure (the states and the history of a long
/// run are checked entry by entry).
fn len_is(
    what: impl FnOnce() -> String,
    len: usize,
    of: &str,
    want: usize,
) -> std::result::Result<(), String> {
    if len == want {
        Ok(())
    } else {
        same_len(&what(), len, of, want)
    }
}

fn in_range<'a>(
    what: &str,
    mut it: impl Iterator<Item = &'a usize>,
    n: usize,
    of: &str,
) -> std::result::Result<(), String> {
    match it.find(|&&i| i >= n) {
        Some(i) => Err(format!("{what} refers to index {i} of only {n} {of}")),
        None => Ok(()),
    }
}

fn array_shape(what: &str, a: &Array, shape: &[usize]) -> std::result::Result<(), String> {
    let n: usize = a.shape.iter().product();
    if a.shape != shape || a.data.len() != n {
        Err(format!(
            "{what} has shape {:?} ({} values), expected {shape:?}",
            a.shape,
            a.data.len()
        ))
    } else {
        Ok(())
    }
}
