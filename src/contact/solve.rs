//! The elastic solve of a model for one status of its interfaces: assembly and condensation
//! of every body, the interface system, and recovery of every body's boundary solution.
//!
//! Place in the flow: `assembly`, `condensation`, `interface` → **`solve`** → post-processing.
//! The per-body work (the expensive part) is done once by [`prepare`]; [`solve_status`] can
//! then be called for any number of interface statuses (the contact iterations) at the cost
//! of the interface system only.

use std::time::Instant;

use crate::bem::assembly::{assemble_body, check_single_layer, BodySystem, Unknown};
use crate::bem::condensation::{condense, Condensed};
use crate::bem::quadrature::QuadratureSettings;
use crate::contact::interface::{self, Layout, X0Map};
use crate::error::Result;
use crate::input::model::Model;
use crate::input::scene::Plane;
use crate::solution::{BodyField, InterfaceResult, PairResult, PairStatus};

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
    let mut systems = Vec::with_capacity(model.bodies.len());
    let mut condensed = Vec::with_capacity(model.bodies.len());
    let (mut ta, mut tc) = (0.0, 0.0);
    for (bi, body) in model.bodies.iter().enumerate() {
        progress(&format!("assembling body \"{}\"", body.name));
        let t0 = Instant::now();
        let sys = assemble_body(model, bi, plane, settings, load_factor, scene_file)?;
        check_single_layer(&sys, &body.name)?;
        ta += t0.elapsed().as_secs_f64();
        progress(&format!("condensing body \"{}\"", body.name));
        let t1 = Instant::now();
        condensed.push(condense(&sys, &body.name)?);
        tc += t1.elapsed().as_secs_f64();
        systems.push(sys);
    }
    let maps = systems.iter().map(X0Map::new).collect();
    Ok(Prepared {
        systems,
        condensed,
        maps,
        assemble_seconds: ta,
        condense_seconds: tc,
    })
}

/// The solution for one status of the interfaces.
pub struct StatusSolution {
    pub layout: Layout,
    pub y: Vec<f64>,
    pub residual: f64,
    pub fields: Vec<BodyField>,
    pub interfaces: Vec<InterfaceResult>,
}

/// Statuses with every pair component closed.
pub fn all_closed(model: &Model) -> Vec<Vec<[PairStatus; 2]>> {
    model
        .interfaces
        .iter()
        .map(|i| vec![[PairStatus::Closed; 2]; i.pairs.len()])
        .collect()
}

/// Solves the interface system for `status` and recovers every body, for the loads of
/// [`prepare`] (one load case).
pub fn solve_status(
    model: &Model,
    prepared: &Prepared,
    status: &[Vec<[PairStatus; 2]>],
) -> Result<StatusSolution> {
    solve_status_scaled(model, prepared, status, 1.0)
}

/// [`solve_status`] with every load of [`prepare`] multiplied by `factor` (the problem is
/// linear in the loads for a fixed status; gaps are not loads and stay as they are).
pub fn solve_status_scaled(
    model: &Model,
    prepared: &Prepared,
    status: &[Vec<[PairStatus; 2]>],
    factor: f64,
) -> Result<StatusSolution> {
    let layout = interface::layout(model, &prepared.maps, status)?;
    let (k, l) = interface::assemble_scaled(&layout, &prepared.condensed, factor);
    let (y, residual) = interface::solve(&k, &l, "interface")?;
    let mut fields = Vec::with_capacity(model.bodies.len());
    let mut x0s = Vec::with_capacity(model.bodies.len());
    for (b, sys) in prepared.systems.iter().enumerate() {
        let x0 = interface::body_x0(&layout, b, sys.n_x0(), &y);
        let x = prepared.condensed[b].recover_x_scaled(&x0, factor);
        fields.push(body_field(model, b, sys, &x, &x0, factor));
        x0s.push(x0);
    }
    let interfaces = model
        .interfaces
        .iter()
        .enumerate()
        .map(|(k, it)| {
            let (a, b) = (it.body_a, it.body_b);
            InterfaceResult {
                pairs: it
                    .pairs
                    .iter()
                    .enumerate()
                    .map(|(j, p)| {
                        let mut traction = [0.0; 2];
                        for (c, t) in traction.iter_mut().enumerate() {
                            if let Some(i) = prepared.maps[a].get(k, j, c, true) {
                                *t = x0s[a][i];
                            }
                        }
                        let (ua, ub) = (fields[a].u[p.node_a], fields[b].u[p.node_b]);
                        let d = [ub[0] - ua[0], ub[1] - ua[1]];
                        let jump = [
                            d[0] * p.tangent[0] + d[1] * p.tangent[1],
                            d[0] * p.normal[0] + d[1] * p.normal[1],
                        ];
                        let closed = status[k][j].contains(&PairStatus::Closed);
                        PairResult {
                            status: if closed {
                                PairStatus::Closed
                            } else {
                                PairStatus::Open
                            },
                            traction,
                            jump,
                        }
                    })
                    .collect(),
            }
        })
        .collect();
    Ok(StatusSolution {
        layout,
        y,
        residual,
        fields,
        interfaces,
    })
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
    BodyField { u, t }
}
