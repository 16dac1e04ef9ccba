//! Condensation of a body onto its interface unknowns, and recovery of the rest
//! ([paper eqs. 11–14], docs/formulation.md §3.3, with the sign of eq. 14a fixed).
//!
//! Place in the flow: `assembly` → **`condensation`** → `interface`. From
//! `0 = A X + A0 X0 + L̂` and `Z0 = A0ᵀ X + A00 X0 + L̂0`:
//!
//! ```text
//!   Z0 = D00 X0 + Z̄0,   D00 = A00 − A0ᵀ A⁻¹ A0,   Z̄0 = L̂0 − A0ᵀ A⁻¹ L̂
//!   X  = R X0 + r,       R = −A⁻¹ A0,              r = −A⁻¹ L̂
//! ```
//!
//! A is symmetric indefinite (V positive definite, −D negative definite); it is factorised by
//! LU with partial pivoting after symmetric diagonal (Jacobi) scaling, which evens out the
//! traction (F) and displacement (U) scales. A singular A (a body not held, or a degenerate
//! scale) is reported as a numerical failure naming the body, never hidden.

use faer::Mat;

use crate::bem::assembly::{BodySystem, Unknown};
use crate::error::{Error, Result};
use crate::input::model::Model;
use crate::linalg::{scaled_lu_solve, ScaledSolveFailure};
use crate::solution::BodyField;

/// A body condensed onto its interface unknowns.
pub struct Condensed {
    /// D00 (symmetrised), n_x0 × n_x0.
    pub d00: Mat<f64>,
    /// Z̄0.
    pub z0: Vec<f64>,
    /// R = −A⁻¹A0 (n_x × n_x0) and r = −A⁻¹L̂, for X = R X0 + r.
    pub recover: Mat<f64>,
    pub recover_load: Vec<f64>,
    /// Relative asymmetry of D00 before symmetrisation.
    pub asymmetry: f64,
    /// Smallest over largest pivot of the scaled LU of A (small: nearly singular).
    pub pivot_ratio: f64,
    /// Relative residual of the solve with A.
    pub residual: f64,
}

/// Condenses one body's system.
pub fn condense(sys: &BodySystem, body: &str) -> Result<Condensed> {
    let (nx, n) = (sys.n_x, sys.n());
    let nx0 = n - nx;
    let g = &sys.g;
    // A⁻¹ [A0 | L̂] by the Jacobi-scaled LU of A.
    let rhs = Mat::<f64>::from_fn(nx, nx0 + 1, |i, j| {
        if j < nx0 {
            g[(i, nx + j)]
        } else {
            sys.load[i]
        }
    });
    let solved =
        scaled_lu_solve(g.as_ref().submatrix(0, 0, nx, nx), rhs.as_ref()).map_err(|f| match f {
            ScaledSolveFailure::Singular { pivot_ratio: ratio } => Error::numerical(format!(
                "the boundary system of body \"{body}\" is singular (pivot ratio {ratio:.1e}): \
                 the body may not be held, or its size meets a degenerate scale"
            )),
            ScaledSolveFailure::Inaccurate { residual } => Error::numerical(format!(
                "solving the boundary system of body \"{body}\" left a relative residual of \
                 {residual:.1e} (ill-conditioned)"
            )),
        })?;
    let (ainv, pivot_ratio, residual) = (solved.x, solved.pivot_ratio, solved.residual);
    // [D00 | Z̄0] = [A00 | L̂0] − A0ᵀ A⁻¹ [A0 | L̂]  (one dense product).
    let a0t = g.as_ref().submatrix(0, nx, nx, nx0).transpose();
    let prod = a0t * ainv.as_ref();
    let mut d00 = Mat::<f64>::from_fn(nx0, nx0, |i, j| g[(nx + i, nx + j)] - prod[(i, j)]);
    let z0: Vec<f64> = (0..nx0)
        .map(|i| sys.load[nx + i] - prod[(i, nx0)])
        .collect();
    let mut max = 0.0f64;
    let mut diff = 0.0f64;
    for i in 0..nx0 {
        for j in 0..nx0 {
            max = max.max(d00[(i, j)].abs());
            diff = diff.max((d00[(i, j)] - d00[(j, i)]).abs());
        }
    }
    let asymmetry = if max > 0.0 { diff / max } else { 0.0 };
    for i in 0..nx0 {
        for j in 0..i {
            let m = 0.5 * (d00[(i, j)] + d00[(j, i)]);
            d00[(i, j)] = m;
            d00[(j, i)] = m;
        }
    }
    let recover = Mat::<f64>::from_fn(nx, nx0, |i, j| -ainv[(i, j)]);
    let recover_load = (0..nx).map(|i| -ainv[(i, nx0)]).collect();
    Ok(Condensed {
        d00,
        z0,
        recover,
        recover_load,
        asymmetry,
        pivot_ratio,
        residual,
    })
}

impl Condensed {
    /// X = R X0 + factor·r (loads scaled by `factor`).
    pub(crate) fn recover_x_scaled(&self, x0: &[f64], factor: f64) -> Vec<f64> {
        if self.recover.nrows() == 0 {
            return Vec::new();
        }
        let rx = &self.recover * faer::ColRef::from_slice(x0);
        rx.iter()
            .zip(&self.recover_load)
            .map(|(v, r)| v + factor * r)
            .collect()
    }
}

/// Nodal displacements and element-end tractions of a body from its unknowns.
pub(crate) fn recover(
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
                let node = it.point(it.body_a == b, pair).0;
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
        let r = crate::linalg::matvec(&sys.held_rows, &all);
        for ((&(node, dir), rq), lq) in sys.held.iter().zip(&r).zip(&sys.held_load) {
            let f = rq + factor * lq;
            reaction[node][0] += f * dir[0];
            reaction[node][1] += f * dir[1];
        }
    }
    BodyField { u, t, reaction }
}
