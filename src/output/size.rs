//! The size of the files a run writes, estimated from the model before anything is solved
//! (`sgbem check`, text and `--json`).
//!
//! Place in the flow: after `model` and [`crate::estimate`]; nothing here reads a result.
//! The sizes are sums of the payloads the writers produce, counted from the model, and the
//! number of states kept ([`kept_states`]):
//!
//! * **archive.h5**: per kept state the boundary solution (16 B per node, 32 B per element)
//!   and the pairs (41 B each, 50 with friction); once the final state again (`/solution`),
//!   the history rows (17 B per pair and row), the bodies (nodes, elements, triangles) with
//!   their Galerkin blocks when `operators = true` (8 B × (n² + n_x·n_x0 + n_x0² + n + n_x0)
//!   per body) and the mixed interface operators where archived (16 B × n_i²), the
//!   interfaces (about 100 B per pair), the mesh (as large as the mesh file)
//!   and the attributes (the scene and the summary); plus about 700 B per dataset (HDF5's
//!   headers and the `description` and `units` attributes).
//! * **vtk/**: per kept state a boundary file: 4/3 (base64) of 24 B per node for the
//!   points and of each array written (displacement, traction, normal: 24 B; statuses and
//!   `body`: 4 B; the scalars: 8 B per node), 13 B per element for the cells, about 2.5 kB
//!   of XML, and about 0.5 kB of multiblock and PVD entries; the final state's field file
//!   where `field = true` (188 B per triangle node and 17 B per triangle with every array).
//!   `vtk = "compressed"`: the binary part taken as 0.3 of its size (measured 0.24 on the
//!   105-brick wall, 0.32 on the clamped beam; it depends on the numbers). With interfaces,
//!   per kept state a thrust file: about 2.75 kB and 270 B per interface (measured 3.0 kB
//!   for 1 joint, 8.4 kB for the arch's 21), and a contact file: about 3 kB, 30 B per
//!   interface and 4/3 of 137 B per pair (measured 4.9 kB for two_blocks' 9 pairs, 359 kB
//!   for the 1 925 pairs of the 105-brick wall). With `[solve] collapse`, once the file
//!   of the mechanism (block "mechanism" of the last state; a run that fails at a mechanism
//!   writes it too, but that is not known before): 4/3 of 52 B per node (points,
//!   `mechanism_velocity`, `body`), 13 B per element and about 2.5 kB (measured 34.6 kB
//!   for `wall_collapse`'s 17 bricks, 35.1 kB estimated).
//! * **CSV**: `interfaces/*.csv` about 105 B per pair, sections 115 B per point and, with
//!   a history, 145 B per point and kept state (`sections/NAME_path.csv`); `thrust.csv`
//!   about 120 B and 215 B per interface; `thrust_hubs.csv` 50 B and 95 B per body with
//!   more than two interfaces (measured 9.0 kB for the 96 hubs of the 105-brick wall).
//! * **mesh/**: the mesh file, where the scene meshes a `.geo`.
//! * **summary.json** and **timings.json**: about 2.5 kB, 1.3 kB per interface and 1.5 kB per
//!   further load step of a contact run; with `[solve] collapse` the mechanism's motion,
//!   about 150 B per body that moves (taken as every body; the archive keeps 48 B each in
//!   four datasets).
//!
//! A full history's number of states is the contact estimate's count of switches (every
//! pair once per load step; measured: 91 states where it says 106 on the clamped beam, 240
//! for 1926 on the 105-brick wall, but 297 for 181 with the friction of the collapsing
//! wall): the estimate of a full history is as rough as that count. With "steps" or "final"
//! the number of states is exact, and the estimate within 30 % on the shipped scenes.

use serde::Serialize;

use crate::estimate::{fmt_bytes, BodySize, ContactEstimate};
use crate::input::model::Model;
use crate::input::scene::{HistoryLevel, InterfaceModel, Scene, Tangential};

/// The estimated sizes, in bytes.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputSize {
    /// States kept (archive and VTK).
    pub states: usize,
    pub archive: f64,
    pub vtk: f64,
    pub csv: f64,
    /// `mesh/`: the mesh of a `.geo`.
    pub mesh: f64,
    /// summary.json and timings.json.
    pub summary: f64,
}

impl OutputSize {
    pub fn total(&self) -> f64 {
        self.archive + self.vtk + self.csv + self.mesh + self.summary
    }

    /// One line for `sgbem check`.
    pub fn line(&self, scene: &Scene) -> String {
        let states = if scene.output.history == HistoryLevel::Full && self.states > 1 {
            format!(
                "a full history of about {} states, as many as the contact estimate's switches",
                self.states
            )
        } else if self.states == 1 {
            "1 state".to_string()
        } else {
            format!("{} states, one per load step", self.states)
        };
        format!(
            "about {} of outputs ({states}): archive {}, vtk {}, csv {}, mesh {}, summary {} \
             (an estimate)",
            fmt_bytes(self.total()),
            fmt_bytes(self.archive),
            fmt_bytes(self.vtk),
            fmt_bytes(self.csv),
            fmt_bytes(self.mesh),
            fmt_bytes(self.summary),
        )
    }

    /// The sizes as `sgbem check --json` writes them (`outputs.estimate`), rounded to
    /// bytes.
    pub fn figures(&self) -> SizeFigures {
        SizeFigures {
            archive_bytes: self.archive.round(),
            csv_bytes: self.csv.round(),
            mesh_bytes: self.mesh.round(),
            states: self.states,
            summary_bytes: self.summary.round(),
            total_bytes: self.total().round(),
            vtk_bytes: self.vtk.round(),
        }
    }
}

/// The estimated sizes in `sgbem check --json`, in bytes; fields in alphabetical order,
/// the order of the keys as the file has always been written.
#[derive(Debug, Clone, Serialize)]
pub struct SizeFigures {
    pub archive_bytes: f64,
    pub csv_bytes: f64,
    pub mesh_bytes: f64,
    pub states: usize,
    pub summary_bytes: f64,
    pub total_bytes: f64,
    pub vtk_bytes: f64,
}

/// HDF5's bytes per dataset besides its values.
const PER_DATASET: f64 = 700.0;

/// The states the archive and the VTK files keep, and the rows of the history.
pub fn kept_states(scene: &Scene, contact: Option<&ContactEstimate>) -> (usize, usize) {
    let steps = scene.solve.steps().len();
    match contact {
        None => (1, 0),
        Some(_) if scene.output.history == HistoryLevel::Final => (1, steps),
        Some(c) => (c.states.max(1), c.states.max(1)),
    }
}

/// The sizes of the outputs of a run of `scene` on `model` (see the module doc).
pub(crate) fn output_size(
    scene: &Scene,
    model: &Model,
    bodies: &[BodySize],
    contact: Option<&ContactEstimate>,
) -> OutputSize {
    let (states, rows) = kept_states(scene, contact);
    let (s, r) = (states as f64, rows as f64);
    let nodes: f64 = model.bodies.iter().map(|b| b.nodes.len() as f64).sum();
    let elements: f64 = model.bodies.iter().map(|b| b.elements.len() as f64).sum();
    let triangles: f64 = model.bodies.iter().map(|b| b.triangles.len() as f64).sum();
    let friction = model.interfaces.iter().any(|i| {
        i.spec.model == InterfaceModel::Unilateral && i.spec.tangential != Tangential::Slide
    });
    let pairs = model.pair_count() as f64;
    let (nb, ni) = (model.bodies.len() as f64, model.interfaces.len() as f64);
    let mesh_file = std::fs::metadata(&model.mesh_path).map_or(0.0, |m| m.len() as f64);
    // Archive.
    let pair_bytes = if friction { 50.0 } else { 41.0 };
    let state = 16.0 * nodes + 32.0 * elements + pair_bytes * pairs;
    let state_sets = if friction { 8.0 } else { 6.0 };
    let mut archive = (s + 1.0) * state + PER_DATASET * (s * state_sets + 2.0 * nb + 6.0 * ni);
    archive += r * (17.0 * pairs + 8.0 * ni + 40.0) + PER_DATASET * (5.0 + 3.0 * ni);
    archive += 24.0 * nodes + 16.0 * elements + 24.0 * triangles + PER_DATASET * 5.0 * nb;
    if scene.output.operators {
        for b in bodies {
            let (x, x0) = (b.n_x as f64, b.n_x0 as f64);
            let n = x + x0;
            archive += 8.0 * (n * n + x * x0 + x0 * x0 + n + x0) + 24.0 * n;
            archive += PER_DATASET * 7.0;
        }
    }
    // The mixed interface operators: K, K00 and the blocks, about 2 n_i² values.
    if let Some(n) = crate::estimate::mixed_unknowns(model, scene) {
        archive += 16.0 * n * n + PER_DATASET * 8.0;
    }
    archive += 100.0 * pairs + PER_DATASET * 11.0 * ni + mesh_file;
    let summary = 2500.0 + 1300.0 * ni + 1500.0 * (scene.solve.steps().len() as f64 - 1.0);
    archive += summary + scene.text.len() as f64 + PER_DATASET * 20.0;
    // VTK.
    let style = &scene.output.vtk_style;
    let per = |names: &[(&str, f64)]| -> f64 {
        names
            .iter()
            .filter(|(n, _)| style.writes(n))
            .map(|(_, b)| b)
            .sum()
    };
    let mut boundary_arrays = vec![
        ("displacement", 24.0),
        ("traction", 24.0),
        ("normal", 24.0),
        ("contact_status", 4.0),
        ("normal_traction", 8.0),
        ("normal_opening", 8.0),
        ("body", 4.0),
    ];
    if friction {
        boundary_arrays.extend([("tangential_status", 4.0), ("slip", 8.0)]);
    }
    let zip = if style.compressed { 0.3 } else { 1.0 };
    let boundary = 4.0 / 3.0 * zip * ((24.0 + per(&boundary_arrays)) * nodes + 13.0 * elements);
    let mut vtk = s * (boundary + 3000.0);
    if ni > 0.0 {
        // The thrust file; the contact rows' file (every array, base64: 4/3 of 137 B per
        // pair, or 0.3 of it compressed, and the interface names).
        vtk += s * (2750.0 + 270.0 * ni);
        vtk += s * (3000.0 + 30.0 * ni + 4.0 / 3.0 * zip * 137.0 * pairs);
    }
    let collapse = scene.solve.collapse.is_some() && contact.is_some();
    if collapse {
        vtk += 4.0 / 3.0 * zip * (52.0 * nodes + 13.0 * elements) + 2500.0;
        archive += 48.0 * nb + PER_DATASET * 4.0;
    }
    if scene.output.field {
        let field_arrays = [
            ("displacement", 24.0),
            ("stress", 48.0),
            ("sxx", 8.0),
            ("syy", 8.0),
            ("szz", 8.0),
            ("sxy", 8.0),
            ("von_mises", 8.0),
            ("principal_stress", 24.0),
            ("principal_direction", 24.0),
            ("body", 4.0),
        ];
        let field_nodes: f64 = model
            .bodies
            .iter()
            .map(|b| b.triangle_node_count() as f64)
            .sum();
        vtk += 4.0 / 3.0 * zip * ((24.0 + per(&field_arrays)) * field_nodes + 17.0 * triangles);
        vtk += 2500.0;
    }
    if !scene.output.vtk {
        vtk = 0.0;
    }
    // CSV.
    let mut csv = 105.0 * pairs + 100.0 * ni;
    if ni > 0.0 {
        // thrust.csv; thrust_hubs.csv: a row per body with more than two joints.
        let mut joints = vec![0usize; model.bodies.len()];
        for it in &model.interfaces {
            for b in [it.body_a, it.body_b] {
                if let Some(j) = joints.get_mut(b) {
                    *j += 1;
                }
            }
        }
        let many = joints.iter().filter(|&&j| j > 2).count() as f64;
        csv += 120.0 + 215.0 * ni + 50.0 + 95.0 * many;
    }
    for sec in &scene.output.sections {
        let p = sec.points as f64;
        csv += 115.0 * p;
        if scene.output.history != HistoryLevel::Final && contact.is_some() {
            csv += 145.0 * p * s;
        }
    }
    let geo = crate::input::gmsh::is_geo(scene.mesh.as_deref().unwrap_or(&model.mesh_path));
    OutputSize {
        states,
        archive,
        vtk,
        csv,
        mesh: if geo { mesh_file } else { 0.0 },
        summary: summary + 1500.0 + if collapse { 150.0 * nb } else { 0.0 },
    }
}
