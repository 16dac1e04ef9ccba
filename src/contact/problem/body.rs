//! The per-body Steklov–Poincaré operators of the contact problem and their glued assembly
//! (see the module `problem`).

// Index loops mirror the block formulas.
#![allow(clippy::needless_range_loop)]

use faer::linalg::solvers::Solve;
use faer::sparse::SparseColMat;
use faer::Mat;
use rayon::prelude::*;

use super::BodyOp;
use crate::bem::assembly::{BodySystem, Unknown};
use crate::bem::operators::Operators;
use crate::error::{Error, Result};
use crate::input::model::Model;

/// A body's interface nodes → their displacement dofs (global index, direction).
pub(super) type NodeDofMap = std::collections::HashMap<usize, Vec<(usize, [f64; 2])>>;

/// X0 indices of a body's displacement and traction unknowns, and the (interface, pair,
/// component) of each displacement.
type X0Maps = (Vec<usize>, Vec<usize>, Vec<(usize, usize, usize)>);

fn x0_maps(sys: &BodySystem) -> X0Maps {
    let (mut u_idx, mut f_idx, mut on) = (Vec::new(), Vec::new(), Vec::new());
    for (i, u) in sys.unknowns[sys.n_x..].iter().enumerate() {
        match *u {
            Unknown::Displacement { on: Some(o), .. } => {
                u_idx.push(i);
                on.push(o);
            }
            Unknown::Traction0 { .. } => f_idx.push(i),
            _ => {}
        }
    }
    (u_idx, f_idx, on)
}

/// The Steklov–Poincaré operator of one body from its condensed operator.
fn body_op(sys: &BodySystem, d00: &Mat<f64>, z0: &[f64], name: &str) -> Result<BodyOp> {
    let (u_idx, f_idx, _) = x0_maps(sys);
    let (nu, nf) = (u_idx.len(), f_idx.len());
    let sub =
        |r: &[usize], c: &[usize]| Mat::<f64>::from_fn(r.len(), c.len(), |i, j| d00[(r[i], c[j])]);
    let dwf = sub(&f_idx, &f_idx);
    let dwu = sub(&f_idx, &u_idx);
    let dpu = sub(&u_idx, &u_idx);
    let (gu, gz) = if nf > 0 {
        let llt = dwf.llt(faer::Side::Lower).map_err(|_| {
            Error::numerical(format!(
                "body \"{name}\": the single-layer block of its interface tractions is not \
                 positive definite (degenerate scale or a badly graded interface mesh)"
            ))
        })?;
        let zw = Mat::<f64>::from_fn(nf, 1, |i, _| z0[f_idx[i]]);
        let gz = llt.solve(&zw);
        (
            llt.solve(&dwu),
            (0..nf).map(|i| gz[(i, 0)]).collect::<Vec<_>>(),
        )
    } else {
        (Mat::zeros(0, nu), Vec::new())
    };
    let prod = dwu.transpose() * &gu;
    let mut s = Mat::<f64>::from_fn(nu, nu, |i, j| -dpu[(i, j)] + prod[(i, j)]);
    for i in 0..nu {
        for j in 0..i {
            let m = 0.5 * (s[(i, j)] + s[(j, i)]);
            s[(i, j)] = m;
            s[(j, i)] = m;
        }
    }
    let p = (0..nu)
        .map(|i| z0[u_idx[i]] - (0..nf).map(|k| dwu[(k, i)] * gz[k]).sum::<f64>())
        .collect();
    Ok(BodyOp {
        u_idx,
        f_idx,
        s,
        p,
        gu,
        gz,
    })
}

/// Every body's operator and the numbering of the dofs (the bodies' U unknowns in order).
pub(super) struct BodyBlocks {
    pub(super) ops: Vec<BodyOp>,
    pub(super) dof_start: Vec<usize>,
    pub(super) n_dofs: usize,
    /// Per body: node → [(global dof, direction)].
    pub(super) node_dofs: Vec<NodeDofMap>,
}

/// Step 1 of [`Problem::new`]: the Steklov–Poincaré operator of every body and its dofs.
pub(super) fn body_operators(model: &Model, prepared: &Operators) -> Result<BodyBlocks> {
    let mut ops = Vec::with_capacity(model.bodies.len());
    let mut dof_start = Vec::with_capacity(model.bodies.len());
    let mut n_dofs = 0;
    let mut node_dofs: Vec<NodeDofMap> = Vec::new();
    // Each body's operator on its own (a few dense products and a Cholesky factor of its
    // traction block), in parallel: 1.9 s of the 4 128-brick wall's set-up in sequence.
    // The first body that fails is reported, as in sequence.
    let built: Vec<Result<BodyOp>> = prepared
        .systems
        .par_iter()
        .enumerate()
        .map(|(b, sys)| {
            let c = &prepared.condensed[b];
            body_op(sys, &c.d00, &c.z0, &model.bodies[b].name)
        })
        .collect();
    for (sys, op) in prepared.systems.iter().zip(built) {
        let op = op?;
        dof_start.push(n_dofs);
        let mut map = NodeDofMap::new();
        for (l, &i) in op.u_idx.iter().enumerate() {
            if let Unknown::Displacement { node, dir, .. } = sys.unknowns[sys.n_x + i] {
                map.entry(node).or_default().push((n_dofs + l, dir));
            }
        }
        node_dofs.push(map);
        n_dofs += op.u_idx.len();
        ops.push(op);
    }
    Ok(BodyBlocks {
        ops,
        dof_start,
        n_dofs,
        node_dofs,
    })
}

/// Step 6 of [`Problem::new`]: the glued stiffness K_g = Σ_b T_bᵀ S_b T_b (lower triangle).
pub(super) fn glued_matrix(
    ops: &[BodyOp],
    dof_start: &[usize],
    tmap: &[Vec<(usize, f64)>],
    n_glued: usize,
) -> Result<SparseColMat<usize, f64>> {
    crate::linalg::triangle_from_entries(n_glued, faer::Side::Lower, |sink| {
        for (b, op) in ops.iter().enumerate() {
            let n = op.u_idx.len();
            for i in 0..n {
                for &(gi, xi) in &tmap[dof_start[b] + i] {
                    for j in 0..n {
                        for &(gj, xj) in &tmap[dof_start[b] + j] {
                            if gj >= gi {
                                sink(gj, gi, xi * xj * op.s[(i, j)]);
                            }
                        }
                    }
                }
            }
        }
    })
    .ok_or_else(|| {
        Error::numerical(format!(
            "assembling the interface system of {n_glued} unknowns: out of memory"
        ))
    })
}
