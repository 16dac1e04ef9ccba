//! The state of the bodies and interfaces for given openings (see the module `problem`).

use super::{Problem, RowKind};
use crate::bem::condensation::recover;
use crate::bem::operators::Operators;
use crate::input::model::Model;
use crate::input::scene::{InterfaceModel, Tangential};
use crate::linalg::matvec;
use crate::solution::{BodyField, InterfaceResult, PairResult, PairStatus};

impl Problem {
    /// The boundary solution of every body and the interface results for openings `s`
    /// (over the rows that can open; zero on closed rows) and the row statuses `open`.
    pub fn state(
        &self,
        model: &Model,
        prepared: &Operators,
        factor: f64,
        s: &[f64],
        open: &[bool],
    ) -> (Vec<BodyField>, Vec<InterfaceResult>, Vec<Vec<f64>>) {
        let v = self.solve_glued(&self.glued_load(factor, s));
        let u = self.displacements(&v, s);
        let mut fields = Vec::with_capacity(self.ops.len());
        let mut tractions = Vec::with_capacity(self.ops.len());
        for (b, op) in self.ops.iter().enumerate() {
            let sys = &prepared.systems[b];
            let mut x0 = vec![0.0; sys.n_x0()];
            for (l, &i) in op.u_idx.iter().enumerate() {
                x0[i] = -u[b][l];
            }
            let gu = matvec(&op.gu, &u[b]);
            for (m, &i) in op.f_idx.iter().enumerate() {
                x0[i] = -factor * op.gz[m] + gu[m];
            }
            let x = prepared.condensed[b].recover_x_scaled(&x0, factor);
            fields.push(recover(model, b, sys, &x, &x0, factor));
            tractions.push(x0);
        }
        let p = self.forces(&u, factor);
        let mut nodal = Vec::with_capacity(model.interfaces.len());
        let interfaces = model
            .interfaces
            .iter()
            .enumerate()
            .map(|(k, it)| {
                let mut nk = Vec::with_capacity(it.pairs.len());
                let pairs = it
                    .pairs
                    .iter()
                    .enumerate()
                    .map(|(j, pr)| {
                        // The traction on A of the discrete problem: the nodal force of the
                        // row over the pair's tributary length (∫ψ_j t = t w_j for a uniform
                        // traction; zero exactly where a row is open or frictionless); the
                        // body's own traction hat where no row exists (prescribed both sides).
                        let mut traction = [0.0; 2];
                        for (c, t) in traction.iter_mut().enumerate() {
                            match self.row_of[k][j][c] {
                                // An open row carries no force (exactly: it is the
                                // stationarity condition of its opening), except a slipping
                                // friction row, which carries its slip bound.
                                Some(r)
                                    if r < self.n_open_rows
                                        && open[r]
                                        && self.rows[r].kind != RowKind::Friction => {}
                                Some(r) => {
                                    *t = -self.row_force(&p, r) / self.rows[r].weight;
                                }
                                // Implied at a junction: the kept rows carry its force.
                                None if self.implied_at.contains(&(k, j, c)) => {}
                                None => {
                                    // Frictionless tangential component: no row, no force.
                                    let slide = c == 0
                                        && it.spec.model == InterfaceModel::Unilateral
                                        && it.spec.tangential == Tangential::Slide;
                                    if !slide {
                                        if let Some(i) = prepared.maps[it.body_a].get(k, j, c, true)
                                        {
                                            *t = tractions[it.body_a][i];
                                        }
                                    }
                                }
                            }
                        }
                        let ua = fields[it.body_a].u[pr.node_a];
                        let ub = if !it.independent() {
                            fields[it.body_b].u[pr.node_b]
                        } else if pr.partners.is_empty() {
                            ua
                        } else {
                            pr.partners.iter().fold([0.0, 0.0], |acc, &(n, c)| {
                                let u = fields[it.body_b].u[n];
                                [acc[0] + c * u[0], acc[1] + c * u[1]]
                            })
                        };
                        let d = [ub[0] - ua[0], ub[1] - ua[1]];
                        let jump = [
                            d[0] * pr.tangent[0] + d[1] * pr.tangent[1],
                            d[0] * pr.normal[0] + d[1] * pr.normal[1],
                        ];
                        let closed = match self.row_of[k][j][1] {
                            Some(r) if r < self.n_open_rows => !open[r],
                            // Implied at a junction: closed where the kept rows close it.
                            None if self.implied_at.contains(&(k, j, 1)) => {
                                pr.gap + jump[1] <= 1e-9 * model.scale
                            }
                            // Nothing of B faces the node: no row, open.
                            None if it.independent() && pr.partners.is_empty() => false,
                            _ => true,
                        };
                        // Nodal normal force on B (compression positive).
                        nk.push(match self.row_of[k][j][1] {
                            Some(r) => self.row_force(&p, r),
                            None => 0.0,
                        });
                        // A friction pair slips where its tangential row is open.
                        let slipping = match self.row_of[k][j][0] {
                            Some(r)
                                if r < self.n_open_rows
                                    && self.rows[r].kind == RowKind::Friction =>
                            {
                                Some(open[r])
                            }
                            _ => None,
                        };
                        PairResult {
                            status: if closed {
                                PairStatus::Closed
                            } else {
                                PairStatus::Open
                            },
                            traction,
                            jump,
                            slipping,
                            slip: 0.0,
                        }
                    })
                    .collect();
                nodal.push(nk);
                InterfaceResult { pairs }
            })
            .collect();
        (fields, interfaces, nodal)
    }
}
