//! Integrals shared by bodies of one shape: in a masonry wall most bricks are copies of a few
//! (whole bricks, the part bricks at the ends), and a body's element-pair integrals and
//! body-force loads depend only on its boundary in its own scaled coordinates
//! ([`crate::bem::assembly::Scaling`]: relative to one of its nodes), its material, the body
//! force and the quadrature — not on where it lies or how it is held.
//!
//! Place in the flow: `galerkin` → **`shapes`** → `assembly` (called from
//! `operators::prepare`). Bodies whose boundaries agree to 1e-11 of their size in those
//! coordinates (node for node, element for element) share one table, computed once; a shape
//! met once is integrated by its body as before. The tables are kept within
//! [`SHARED_BYTES`].

use std::collections::HashMap;
use std::sync::Arc;

use rayon::prelude::*;

use crate::bem::assembly::{material, scaled_elements, scaling};
use crate::bem::galerkin::{body_force_loads, pair_blocks, BodyForceLoads, PairBlocks};
use crate::bem::kernels::boundary_area;
use crate::bem::quadrature::QuadratureSettings;
use crate::input::model::{Body, Model};
use crate::input::scene::Plane;

/// The most memory the shared tables take (a 36-element brick's is 0.5 MB).
pub const SHARED_BYTES: usize = 256 << 20;

/// Scaled coordinates this close count as equal (they are O(1)).
const GRID: f64 = 1e11;

/// The shape-only integrals of a body: every ordered element pair's blocks (row-major over
/// test, trial element) and, where it has a body force, each element's body-force loads.
pub struct ShapeIntegrals {
    pub ne: usize,
    pub pairs: Vec<PairBlocks>,
    pub body_force: Option<Vec<BodyForceLoads>>,
}

impl ShapeIntegrals {
    pub fn pair(&self, ei: usize, fi: usize) -> PairBlocks {
        self.pairs[ei * self.ne + fi]
    }
}

/// The shared table of each body, where its shape is shared.
pub struct SharedShapes {
    of: Vec<Option<Arc<ShapeIntegrals>>>,
    /// Shapes shared, and the bodies that share them.
    pub shapes: usize,
    pub bodies: usize,
}

impl SharedShapes {
    /// None: every body integrated on its own.
    pub fn none(n: usize) -> SharedShapes {
        SharedShapes {
            of: vec![None; n],
            shapes: 0,
            bodies: 0,
        }
    }

    /// Integrates each shape of [`groups`] once (in parallel over its element pairs).
    pub fn new(
        model: &Model,
        plane: Plane,
        settings: &QuadratureSettings,
        load_factor: f64,
    ) -> SharedShapes {
        let mut out = SharedShapes::none(model.bodies.len());
        for group in groups(model, plane, load_factor) {
            let body = &model.bodies[group[0]];
            let table = Arc::new(integrate(body, plane, settings, load_factor));
            out.shapes += 1;
            out.bodies += group.len();
            for bi in group {
                out.of[bi] = Some(table.clone());
            }
        }
        out
    }

    /// The shared table of body `bi`, if any.
    pub fn of(&self, bi: usize) -> Option<&ShapeIntegrals> {
        self.of[bi].as_deref()
    }
}

/// The bodies of `model` grouped by shape, for the shapes that two or more share, largest
/// groups first (in body order among equals), as many as [`SHARED_BYTES`] holds.
pub fn groups(model: &Model, plane: Plane, load_factor: f64) -> Vec<Vec<usize>> {
    let keys: Vec<Vec<i64>> = model
        .bodies
        .par_iter()
        .map(|b| shape_key(b, plane, load_factor))
        .collect();
    let mut by_key: HashMap<&[i64], Vec<usize>> = HashMap::new();
    for (bi, k) in keys.iter().enumerate() {
        by_key.entry(k.as_slice()).or_default().push(bi);
    }
    let mut shared: Vec<Vec<usize>> = by_key.into_values().filter(|g| g.len() > 1).collect();
    shared.sort_by_key(|g| (std::cmp::Reverse(g.len()), g[0]));
    let mut bytes = 0usize;
    shared.retain(|g| {
        let ne = model.bodies[g[0]].elements.len();
        let size = ne * ne * std::mem::size_of::<PairBlocks>();
        let fits = bytes + size <= SHARED_BYTES;
        if fits {
            bytes += size;
        }
        fits
    });
    shared
}

/// What the shape-only integrals of `body` depend on: its material, its body force, and its
/// elements (node indices and scaled end points, to [`GRID`]).
fn shape_key(body: &Body, plane: Plane, load_factor: f64) -> Vec<i64> {
    let m = material(body, plane);
    let force = body
        .body_force
        .filter(|b| *b != [0.0, 0.0])
        .map_or([0.0; 2], |b| [load_factor * b[0], load_factor * b[1]]);
    let bits = |x: f64| x.to_bits() as i64;
    let mut key = vec![
        bits(m.mu),
        bits(m.nu),
        bits(force[0]),
        bits(force[1]),
        body.nodes.len() as i64,
    ];
    let s = scaling(body);
    let q = |x: f64| (x * GRID).round() as i64;
    for e in &body.elements {
        key.extend([e.nodes[0] as i64, e.nodes[1] as i64]);
        for p in e.nodes.map(|k| s.scaled(body.nodes[k])) {
            key.extend([q(p[0]), q(p[1])]);
        }
    }
    key
}

/// The shape-only integrals of `body`, as its assembly computes them.
fn integrate(
    body: &Body,
    plane: Plane,
    settings: &QuadratureSettings,
    load_factor: f64,
) -> ShapeIntegrals {
    let mat = material(body, plane);
    let elems = scaled_elements(body, &scaling(body));
    let ne = elems.len();
    let pairs: Vec<PairBlocks> = (0..ne * ne)
        .into_par_iter()
        .map(|k| pair_blocks(&mat, &elems[k / ne], &elems[k % ne], settings))
        .collect();
    let body_force = body.body_force.filter(|b| *b != [0.0, 0.0]).map(|b| {
        let b = [load_factor * b[0], load_factor * b[1]];
        let boundary: Vec<_> = elems.iter().map(|e| e.seg).collect();
        let area = boundary_area(&boundary);
        elems
            .par_iter()
            .map(|e| body_force_loads(&mat, &e.seg, &boundary, b, area, settings))
            .collect()
    });
    ShapeIntegrals {
        ne,
        pairs,
        body_force,
    }
}
