//! The elastic solve of a model for one status of its interfaces: assembly and condensation
//! of every body, the interface system, and recovery of every body's boundary solution.
//!
//! Place in the flow: `assembly`, `condensation`, `interface` → **`solve`** → post-processing.
//! The per-body work (the expensive part) is done once by [`prepare`]; the contact problem
//! (`problem`) is built on it, and [`solve_all_closed`] solves it with every pair closed.

use std::time::Instant;

use crate::bem::assembly::{assemble_body, check_single_layer, BodySystem, Unknown};
use crate::bem::condensation::{condense, Condensed};
use crate::bem::quadrature::QuadratureSettings;
use crate::contact::interface::X0Map;
use crate::error::Result;
use crate::input::model::Model;
use crate::input::scene::Plane;
use crate::solution::{BodyField, InterfaceResult};

/// Every body assembled and condensed.
pub struct Prepared {
    pub systems: Vec<BodySystem>,
    pub condensed: Vec<Condensed>,
    pub maps: Vec<X0Map>,
    /// Seconds spent assembling and condensing.
    pub assemble_seconds: f64,
    pub condense_seconds: f64,
}

/// Assembles and condenses every body for the loads scaled by `load_factor`.
pub fn prepare(
    model: &Model,
    plane: Plane,
    settings: &QuadratureSettings,
    load_factor: f64,
    scene_file: &std::path::Path,
    progress: &dyn Fn(&str),
) -> Result<Prepared> {
    let t_start = Instant::now();
    use rayon::prelude::*;
    // Bodies are independent: assembled and condensed in parallel (a wall of many small
    // bricks keeps both cores busy; a large body's assembly is parallel inside too).
    progress(&format!(
        "assembling and condensing {} bodies",
        model.bodies.len()
    ));
    let done: Vec<Result<(BodySystem, Condensed, f64, f64)>> = (0..model.bodies.len())
        .into_par_iter()
        .map(|bi| {
            let body = &model.bodies[bi];
            let t0 = Instant::now();
            let sys = assemble_body(model, bi, plane, settings, load_factor, scene_file)?;
            check_single_layer(&sys, &body.name)?;
            let ta = t0.elapsed().as_secs_f64();
            let t1 = Instant::now();
            let c = condense(&sys, &body.name)?;
            Ok((sys, c, ta, t1.elapsed().as_secs_f64()))
        })
        .collect();
    let mut systems = Vec::with_capacity(model.bodies.len());
    let mut condensed = Vec::with_capacity(model.bodies.len());
    let (mut ta, mut tc) = (0.0, 0.0);
    for d in done {
        let (sys, c, a, b) = d?;
        systems.push(sys);
        condensed.push(c);
        ta += a;
        tc += b;
    }
    // Seconds of CPU over the bodies, shared out in proportion to the wall-clock time.
    let wall = t_start.elapsed().as_secs_f64();
    let cpu = (ta + tc).max(f64::MIN_POSITIVE);
    let (ta, tc) = (wall * ta / cpu, wall * tc / cpu);
    let maps = systems.iter().map(X0Map::new).collect();
    Ok(Prepared {
        systems,
        condensed,
        maps,
        assemble_seconds: ta,
        condense_seconds: tc,
    })
}

/// The solution with every interface pair closed.
pub struct StatusSolution {
    pub fields: Vec<BodyField>,
    pub interfaces: Vec<InterfaceResult>,
}

/// Solves the model with every interface pair closed (bonded interfaces, and unilateral ones
/// held closed) through the contact problem's glued system, for the loads of [`prepare`].
pub fn solve_all_closed(model: &Model, prepared: &Prepared) -> Result<StatusSolution> {
    let problem = crate::contact::problem::Problem::new(model, prepared)?;
    let n = problem.n_open_rows;
    let (fields, interfaces, _) =
        problem.state(model, prepared, 1.0, &vec![0.0; n], &vec![false; n]);
    Ok(StatusSolution { fields, interfaces })
}

/// Nodal displacements and element-end tractions of a body from its unknowns.
pub fn body_field(
    model: &Model,
    b: usize,
    sys: &BodySystem,
    x: &[f64],
    x0: &[f64],
    factor: f64,
) -> BodyField {
    let body = &model.bodies[b];
    let mut u: Vec<[f64; 2]> = sys
        .known_u
        .iter()
        .map(|v| [factor * v[0], factor * v[1]])
        .collect();
    let mut t: Vec<[[f64; 2]; 2]> = sys
        .known_t
        .iter()
        .map(|e| e.map(|v| [factor * v[0], factor * v[1]]))
        .collect();
    let value = |i: usize| if i < sys.n_x { x[i] } else { x0[i - sys.n_x] };
    for (i, unk) in sys.unknowns.iter().enumerate() {
        let v = value(i);
        match *unk {
            Unknown::Displacement { node, dir, .. } => {
                // The unknown is −U.
                u[node][0] -= v * dir[0];
                u[node][1] -= v * dir[1];
            }
            Unknown::LoopMode { loop_index, .. } => {
                for &ei in &body.loops[loop_index].elements {
                    let nodes = body.elements[ei].nodes;
                    for (te, node) in t[ei].iter_mut().zip(nodes) {
                        let dir = unk.loop_mode_value(body.nodes[node]);
                        te[0] += v * dir[0];
                        te[1] += v * dir[1];
                    }
                }
            }
            Unknown::Traction1 { elem, end, dir } => {
                t[elem][end][0] += v * dir[0];
                t[elem][end][1] += v * dir[1];
            }
            Unknown::Traction0 {
                iface, pair, dir, ..
            } => {
                let it = &model.interfaces[iface];
                let node = if it.body_a == b {
                    it.pairs[pair].node_a
                } else {
                    it.pairs[pair].node_b
                };
                for (e, el) in body.elements.iter().enumerate() {
                    if el.role != crate::input::model::Role::Interface(iface) {
                        continue;
                    }
                    for (end, te) in t[e].iter_mut().enumerate() {
                        if el.nodes[end] == node {
                            te[0] += v * dir[0];
                            te[1] += v * dir[1];
                        }
                    }
                }
            }
        }
    }
    // Reactions of the held components: their hypersingular rows applied to the unknowns.
    let mut reaction = vec![[0.0; 2]; body.nodes.len()];
    if !sys.held.is_empty() {
        let all: Vec<f64> = (0..sys.n()).map(value).collect();
        let r = crate::contact::problem::matvec(&sys.held_rows, &all);
        for ((&(node, dir), rq), lq) in sys.held.iter().zip(&r).zip(&sys.held_load) {
            let f = rq + factor * lq;
            reaction[node][0] += f * dir[0];
            reaction[node][1] += f * dir[1];
        }
    }
    BodyField { u, t, reaction }
}
