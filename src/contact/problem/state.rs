//! The state of the bodies and interfaces for given openings (see the module `problem`).

use super::{Problem, RowKind};
use crate::bem::condensation::recover;
use crate::bem::operators::Operators;
use crate::input::model::{Interface, Model, Pair};
use crate::input::scene::{InterfaceModel, Tangential};
use crate::linalg::matvec;
use crate::solution::{BodyField, InterfaceResult, PairResult, PairStatus};

/// What the interface results are read from: the bodies' boundary solutions, their X0
/// (traction hats where no row exists), the nodal forces P and the row statuses.
struct Solved<'s> {
    fields: &'s [BodyField],
    tractions: &'s [Vec<f64>],
    p: &'s [Vec<f64>],
    open: &'s [bool],
}

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
        let (fields, tractions) = self.body_fields(model, prepared, factor, &u);
        let p = self.forces(&u, factor);
        let solved = Solved {
            fields: &fields,
            tractions: &tractions,
            p: &p,
            open,
        };
        let mut nodal = Vec::with_capacity(model.interfaces.len());
        let interfaces = model
            .interfaces
            .iter()
            .enumerate()
            .map(|(k, it)| {
                let mut nk = Vec::with_capacity(it.pairs.len());
                let pairs = (0..it.pairs.len())
                    .map(|j| {
                        // Nodal normal force on B (compression positive).
                        nk.push(match self.row_of[k][j][1] {
                            Some(r) => self.row_force(&p, r),
                            None => 0.0,
                        });
                        self.pair_result(model, prepared, &solved, k, j)
                    })
                    .collect();
                nodal.push(nk);
                InterfaceResult { pairs }
            })
            .collect();
        (fields, interfaces, nodal)
    }

    /// The boundary solution of every body for the dofs `u`, and its X0.
    pub(crate) fn body_fields(
        &self,
        model: &Model,
        prepared: &Operators,
        factor: f64,
        u: &[Vec<f64>],
    ) -> (Vec<BodyField>, Vec<Vec<f64>>) {
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
        (fields, tractions)
    }

    /// The result of pair `j` of interface `k`.
    fn pair_result(
        &self,
        model: &Model,
        prepared: &Operators,
        solved: &Solved,
        k: usize,
        j: usize,
    ) -> PairResult {
        let it = &model.interfaces[k];
        let pr = &it.pairs[j];
        let open = solved.open;
        let traction = self.pair_traction(prepared, solved, it, k, j);
        let jump = pair_jump(it, pr, solved.fields);
        let closed = match self.row_of[k][j][1] {
            Some(r) if r < self.n_open_rows => !open[r],
            // Implied at a junction: closed where the kept rows close it.
            None if self.implied_at.contains(&(k, j, 1)) => pr.gap + jump[1] <= 1e-9 * model.scale,
            // Nothing of B faces the node: no row, open.
            None if it.independent() && pr.partners.is_empty() => false,
            _ => true,
        };
        // A friction pair slips where its tangential row is open.
        let slipping = match self.row_of[k][j][0] {
            Some(r) if r < self.n_open_rows && self.rows[r].kind == RowKind::Friction => {
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
    }

    /// The traction on A of the discrete problem: the nodal force of the row over the pair's
    /// tributary length (∫ψ_j t = t w_j for a uniform traction; zero exactly where a row is
    /// open or frictionless); the body's own traction hat where no row exists (prescribed
    /// both sides).
    fn pair_traction(
        &self,
        prepared: &Operators,
        solved: &Solved,
        it: &Interface,
        k: usize,
        j: usize,
    ) -> [f64; 2] {
        let mut traction = [0.0; 2];
        for (c, t) in traction.iter_mut().enumerate() {
            match self.row_of[k][j][c] {
                // An open row carries no force (exactly: it is the stationarity condition of
                // its opening), except a slipping friction row, which carries its slip bound.
                Some(r)
                    if r < self.n_open_rows
                        && solved.open[r]
                        && self.rows[r].kind != RowKind::Friction => {}
                Some(r) => {
                    *t = -self.row_force(solved.p, r) / self.rows[r].weight;
                }
                // Implied at a junction: the kept rows carry its force.
                None if self.implied_at.contains(&(k, j, c)) => {}
                None => *t = traction_without_row(prepared, solved.tractions, it, k, j, c),
            }
        }
        traction
    }
}

/// Component `c` of pair `j` of interface `k` where it has no row: zero for the tangential
/// component of a frictionless pair, else the body A's own traction hat there (a component
/// prescribed on both sides), from the bodies' X0 `tractions`.
fn traction_without_row(
    prepared: &Operators,
    tractions: &[Vec<f64>],
    it: &Interface,
    k: usize,
    j: usize,
    c: usize,
) -> f64 {
    let slide = c == 0
        && it.spec.model == InterfaceModel::Unilateral
        && it.spec.tangential == Tangential::Slide;
    match prepared.maps[it.body_a].get(k, j, c, true) {
        Some(i) if !slide => tractions[it.body_a][i],
        _ => 0.0,
    }
}

/// The relative displacement `[u] = u_B − u_A` of a pair in its frame (tangential, normal);
/// on independently meshed sides u_B interpolated from the partners (zero jump where none).
fn pair_jump(it: &Interface, pr: &Pair, fields: &[BodyField]) -> [f64; 2] {
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
    [
        d[0] * pr.tangent[0] + d[1] * pr.tangent[1],
        d[0] * pr.normal[0] + d[1] * pr.normal[1],
    ]
}

/// What the full-row solver (`contact::exact`) gives for every full row (`Problem::full`).
pub(crate) struct FullRowSolution<'s> {
    /// Every dof's displacement.
    pub u: &'s [f64],
    /// `λ_r = ∂E/∂[u]_r` with the cohesion term (normal rows: compression positive).
    pub force: &'s [f64],
    pub closed: &'s [bool],
    pub slipping: &'s [bool],
    /// The cohesion term `c w` of every full row (zero but on unilateral normal rows).
    pub cohesion: &'s [f64],
}

impl Problem {
    /// The boundary solution of every body and the interface results of a full-row
    /// solution: each pair's traction from its own rows' forces (junctions included), the
    /// nodal normal force of each pair (on B, compression positive).
    pub(crate) fn full_row_state(
        &self,
        model: &Model,
        prepared: &Operators,
        factor: f64,
        sol: &FullRowSolution,
    ) -> (Vec<BodyField>, Vec<InterfaceResult>, Vec<Vec<f64>>) {
        let u: Vec<Vec<f64>> = self
            .ops
            .iter()
            .enumerate()
            .map(|(b, op)| sol.u[self.dof_start[b]..self.dof_start[b] + op.u_idx.len()].to_vec())
            .collect();
        let (fields, tractions) = self.body_fields(model, prepared, factor, &u);
        let mut nodal = Vec::with_capacity(model.interfaces.len());
        let interfaces = model
            .interfaces
            .iter()
            .enumerate()
            .map(|(k, it)| {
                let mut nk = Vec::with_capacity(it.pairs.len());
                let pairs = (0..it.pairs.len())
                    .map(|j| {
                        let pr = &it.pairs[j];
                        let [rt, rn] = self.full_of[k][j];
                        let closed = match rn {
                            Some(r) => sol.closed[r],
                            None => !(it.independent() && pr.partners.is_empty()),
                        };
                        nk.push(rn.map_or(0.0, |r| {
                            if closed {
                                sol.force[r] - sol.cohesion[r]
                            } else {
                                0.0
                            }
                        }));
                        let mut traction = [0.0; 2];
                        for (c, t) in traction.iter_mut().enumerate() {
                            let row = if c == 1 { rn } else { rt };
                            match row {
                                // An open pair carries nothing (its rows' forces are the
                                // interior point's residue).
                                Some(_) if !closed => {}
                                Some(r) => {
                                    *t = -(sol.force[r] - sol.cohesion[r]) / self.full[r].row.weight
                                }
                                None => {
                                    *t = traction_without_row(prepared, &tractions, it, k, j, c)
                                }
                            }
                        }
                        let slipping = match rt {
                            Some(r) if self.full[r].row.kind == RowKind::Friction => {
                                Some(closed && sol.slipping[r])
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
                            jump: pair_jump(it, pr, &fields),
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
