//! The sizes of the contact problem's sparse systems counted from the model alone, before
//! any operator is assembled: the memory estimate of `sgbem check` and `sgbem run`
//! (src/estimate.rs).
//!
//! The rows are eliminated exactly as [`Problem::new`](super::Problem::new) does, over the
//! same dofs (every interface displacement component of every body, in node order), so the
//! counts are the run's. Where two sides were meshed on their own, a row ties a node of A
//! to several nodes of B, and the dof it eliminates is expressed through several glued
//! unknowns: each body's block of the glued system then holds more entries than its
//! `n_u²` (a running-bond wall drawn brick by brick: about 2.4 glued unknowns per dof,
//! against one on the conforming wall).

use super::body::NodeDofMap;
use super::rows::{candidates, eliminate, final_rows, glued_maps};
use crate::input::model::{DofClass, Model};

/// Per body, the entries of its dofs' expressions.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct SparsityPattern {
    /// Σ over the body's dofs of the unknowns each moves (glued displacements and openings
    /// of the rows that can open): its block of the sparse system H over w = (v, s).
    pub unknowns: Vec<usize>,
    /// Glued unknowns and rows that can open: H is of their sum.
    pub n_glued: usize,
    pub n_open_rows: usize,
}

impl SparsityPattern {
    /// The entries the sparse solver emits to assemble H, before repeated positions are
    /// summed: `t(t + 1)/2` in the lower triangle of a body's block of t entries, and H's
    /// diagonal (the glued stiffness K_g, assembled and freed before, has fewer: its dofs
    /// move no openings).
    pub(crate) fn entries(&self) -> f64 {
        let half = |t: &usize| (*t as f64) * (*t as f64 + 1.0) / 2.0;
        self.unknowns.iter().map(half).sum::<f64>() + (self.n_glued + self.n_open_rows) as f64
    }
}

/// The pattern of the contact problem of `model`; None where its rows cannot be formed (a
/// component prescribed on one side of an interface only: the run refuses it).
pub fn pattern(model: &Model) -> Option<SparsityPattern> {
    let mut node_dofs: Vec<NodeDofMap> = Vec::with_capacity(model.bodies.len());
    let mut body_of: Vec<usize> = Vec::new();
    for (bi, b) in model.bodies.iter().enumerate() {
        let mut map = NodeDofMap::new();
        for (n, d) in b.dofs.iter().enumerate() {
            for k in 0..2 {
                if d.class[k] == DofClass::Interface {
                    map.entry(n).or_default().push((body_of.len(), d.frame[k]));
                    body_of.push(bi);
                }
            }
        }
        node_dofs.push(map);
    }
    let cands = candidates(model, &node_dofs).ok()?;
    let elim = eliminate(&cands, body_of.len(), &Default::default());
    let set = final_rows(model, &cands, &elim);
    let maps = glued_maps(&elim.expr, &set.index_of, set.rows.len());
    let mut unknowns = vec![0usize; model.bodies.len()];
    for (d, &b) in body_of.iter().enumerate() {
        let openings = maps.offs[d]
            .iter()
            .filter(|(r, _)| *r < set.n_open_rows)
            .count();
        unknowns[b] += maps.tmap[d].len() + openings;
    }
    Some(SparsityPattern {
        unknowns,
        n_glued: maps.n_glued,
        n_open_rows: set.n_open_rows,
    })
}
