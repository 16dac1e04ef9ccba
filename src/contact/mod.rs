//! Contact and detachment on unilateral interfaces: the driver of load steps and of the outer
//! loop, over one discrete problem (`problem`) that every solver solves.
//!
//! Place in the flow: `bem` (per-body operators, prepared once by `solve::prepare`) →
//! **`contact`** → results. Conditions per unilateral pair j, with the nodal contact force
//! λ_j (compression positive, cohesion included) and the nodal gap g_j = h_j + n·(u_B − u_A)
//! (see `problem` for the pairing):
//!
//! * closed: g_j = 0 and λ_j ≥ 0 (tension up to c_j times the pair's tributary length);
//! * open: λ_j = 0 and g_j ≥ 0.
//!
//! **Outer loop.** Two data of the problem depend on the state itself: the brittle cohesion
//! of the paper (§3.1.1: a pair that opens loses its cohesion for good) and, with
//! `tangential = "stick"`, the tangential tie of a pair (tied while closed). The driver fixes
//! both, solves the inner LCP (unique when the opening stiffness is positive definite), then
//! drops the cohesion of the pairs found open and ties exactly the closed stick pairs, and
//! repeats until nothing changes (formulation §6.1). Every solver runs the same outer loop,
//! so they reach the same statuses:
//!
//! * `evolutive` — the paper's iterative LCP: one switch per iteration, every state recorded;
//! * `active_set` — every violator at once (PDAS), falling back to the evolutive iteration;
//! * `lemke` — complementary pivoting on the dense LCP: exact and finite;
//! * `qp` — the same LCP as a convex QP (Clarabel).
//!
//! A repeated outer state is a stick edge cycle (a pair at the contact edge that opens once
//! untied and closes once tied): reported, not hidden.

// Index loops over rows mirror the problem's row numbering.
#![allow(clippy::needless_range_loop)]

pub mod active_set;
pub mod evolutive;
pub mod interface;
pub mod lcp;
pub mod lemke;
pub mod problem;
pub mod qp;
pub mod solve;

use std::collections::HashSet;

use crate::error::Error;
use crate::input::model::Model;
use crate::input::scene::InterfaceModel;
use crate::solution::{BodyField, HistoryRow, InterfaceResult, PairStatus};
use lcp::{Columns, Inner, InnerState};
use problem::{Problem, RowKind};
use solve::Prepared;

/// Which solver.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    Evolutive,
    ActiveSet,
    Lemke,
    Qp,
}

impl Method {
    pub fn name(self) -> &'static str {
        match self {
            Method::Evolutive => "lcp",
            Method::ActiveSet => "active-set",
            Method::Lemke => "lemke",
            Method::Qp => "qp",
        }
    }
}

/// The state carried from one load step (and outer iteration) to the next: open rows,
/// tangential ties of stick rows, and the cohesion left at each pair.
#[derive(Debug, Clone, PartialEq)]
pub struct StepState {
    /// Per row that can open: open (normal rows) or untied (stick rows).
    pub open: Vec<bool>,
    pub cohesion: Vec<Vec<f64>>,
}

/// The solution after one iteration, kept for output.
#[derive(Debug, Clone)]
pub struct RecordedState {
    pub load_step: usize,
    pub load_factor: f64,
    pub iteration: usize,
    pub fields: Vec<BodyField>,
    pub interfaces: Vec<InterfaceResult>,
}

/// The outcome of one load step.
pub struct ContactResult {
    pub state: StepState,
    pub fields: Vec<BodyField>,
    pub interfaces: Vec<InterfaceResult>,
    /// Nodal normal force of each pair (on B, compression positive).
    pub nodal_force: Vec<Vec<f64>>,
    /// Status switches made (inner iterations summed over the outer loop).
    pub iterations: usize,
    pub outer_iterations: usize,
    pub converged: bool,
    pub solver: &'static str,
    /// Largest relative complementarity violation left.
    pub residual: f64,
    pub rows: Vec<HistoryRow>,
    pub states: Vec<RecordedState>,
    pub notes: Vec<String>,
    pub failure: Option<Error>,
    /// Extra figures of the solver (QP: iterations, status; Lemke: pivots).
    pub info: serde_json::Value,
    /// The states of the evolutive path in compact form (iteration, open rows, openings),
    /// expanded into `rows` and `states` by [`Session::expand`].
    pub recorded: Vec<(usize, Vec<bool>, Vec<f64>)>,
    pub load_step: usize,
    pub load_factor: f64,
}

/// A contact run: the problem and the columns of its opening stiffness, shared by every
/// solver and load step.
pub struct Session<'a> {
    pub model: &'a Model,
    pub prepared: &'a Prepared,
    pub problem: Problem,
    pub cols: Columns,
}

impl<'a> Session<'a> {
    pub fn new(model: &'a Model, prepared: &'a Prepared) -> crate::error::Result<Self> {
        Ok(Session {
            model,
            prepared,
            problem: Problem::new(model, prepared)?,
            cols: Columns::default(),
        })
    }

    /// The scene's initial statuses and cohesions.
    pub fn initial(&self) -> StepState {
        let open = self.problem.rows[..self.problem.n_open_rows]
            .iter()
            .map(|r| {
                let it = &self.model.interfaces[r.iface];
                it.spec.model == InterfaceModel::Unilateral
                    && it.spec.initial == crate::input::scene::InitialState::Open
            })
            .collect();
        let cohesion = self
            .model
            .interfaces
            .iter()
            .map(|it| it.pairs.iter().map(|p| p.cohesion).collect())
            .collect();
        StepState { open, cohesion }
    }

    /// Whether pair (k, j)'s normal row is open in `open`.
    fn pair_open(&self, open: &[bool], k: usize, j: usize) -> bool {
        match self.problem.row_of[k][j][1] {
            Some(r) if r < self.problem.n_open_rows => open[r],
            _ => false,
        }
    }

    /// Solves one load step from `start` with `method`.
    #[allow(clippy::too_many_arguments)]
    pub fn solve_step(
        &mut self,
        start: &StepState,
        method: Method,
        tol: f64,
        max_iterations: usize,
        load_step: usize,
        factor: f64,
        record: bool,
    ) -> ContactResult {
        let n = self.problem.n_open_rows;
        let mut st = start.clone();
        let mut notes = Vec::new();
        let mut compact: Vec<(usize, Vec<bool>, Vec<f64>)> = Vec::new();
        let mut edge_slip = vec![false; n];
        let mut slipping = 0;
        let mut seen: HashSet<Vec<bool>> = HashSet::new();
        let mut iterations = 0;
        let mut outer = 0;
        let mut converged = false;
        let mut failure = None;
        let mut info = serde_json::json!({});
        let mut last: Option<(InnerState, f64)> = None;
        // The outer iterates' open rows, to find the rows of a stick edge cycle.
        let mut iterates: Vec<Vec<bool>> = Vec::new();
        loop {
            outer += 1;
            let base = self.problem.base(factor, &st.cohesion);
            let free: Vec<bool> = (0..n)
                .map(|r| self.problem.rows[r].kind == RowKind::Stick && st.open[r])
                .collect();
            let inner = Inner {
                problem: &self.problem,
                base: &base,
                free,
                tol,
            };
            let start_open = st.open.clone();
            let it0 = iterations;
            let outcome: Result<evolutive::Outcome, String> = match method {
                Method::Evolutive => {
                    let mut k = it0;
                    let first = compact.is_empty();
                    let out = evolutive::solve(
                        &inner,
                        &mut self.cols,
                        &start_open,
                        max_iterations.saturating_sub(it0),
                        &mut |s: &InnerState| {
                            // Later outer iterations start where the last one ended.
                            if record && (first || k > it0) {
                                compact.push((k, s.open.clone(), s.s.clone()));
                            }
                            k += 1;
                        },
                    );
                    Ok(out)
                }
                Method::ActiveSet => Ok(active_set::solve(
                    &inner,
                    &mut self.cols,
                    &start_open,
                    max_iterations.saturating_sub(it0),
                )),
                Method::Lemke => {
                    lemke::solve_inner(&inner, &mut self.cols).and_then(|(open, pivots)| {
                        info = serde_json::json!({ "pivots": pivots });
                        exact_state(&inner, &mut self.cols, &open)
                    })
                }
                Method::Qp => qp::solve(&inner, &mut self.cols, tol).and_then(|q| {
                    info = serde_json::json!({
                        "iterations": q.iterations, "solver_status": q.solver_status,
                        "objective": q.objective, "variables": q.variables,
                        "constraints": q.constraints,
                    });
                    exact_state(&inner, &mut self.cols, &q.open)
                }),
            };
            let outcome = match outcome {
                Ok(o) => o,
                Err(e) => {
                    // Name the mechanism: the pivoting path finds the rows that cannot open.
                    let probe = evolutive::solve(
                        &inner,
                        &mut self.cols,
                        &start_open,
                        max_iterations,
                        &mut |_| {},
                    );
                    let hint = if probe.blocked.is_empty() {
                        String::new()
                    } else {
                        format!("; {}", self.mechanism(&probe.blocked))
                    };
                    failure = Some(Error::numerical(format!(
                        "the contact solver ({}) failed at load step {}: {e}{hint}",
                        method.name(),
                        load_step + 1
                    )));
                    break;
                }
            };
            iterations += outcome.iterations;
            notes.extend(outcome.notes.iter().cloned());
            let residual = inner.residual(&outcome.state);
            let ok = outcome.converged;
            let outcome_blocked = outcome.blocked.clone();
            let state = outcome.state;
            if !ok {
                let hint = if outcome_blocked.is_empty() {
                    String::new()
                } else {
                    format!("; {}", self.mechanism(&outcome_blocked))
                };
                failure = Some(Error::numerical(format!(
                    "the contact solver ({}) did not converge at load step {} (largest \
                     violation {residual:.1e} of its scale): {}{}",
                    method.name(),
                    load_step + 1,
                    notes.join("; "),
                    hint
                )));
                last = Some((state, residual));
                break;
            }
            // Outer update: brittle cohesion and stick ties.
            let mut next = st.clone();
            for r in 0..n {
                let row = self.problem.rows[r];
                let pair_open = self.pair_open(&state.open, row.iface, row.pair);
                next.open[r] = match row.kind {
                    RowKind::Normal => state.open[r],
                    _ => pair_open || edge_slip[r],
                };
                if row.kind == RowKind::Normal && pair_open {
                    next.cohesion[row.iface][row.pair] = 0.0;
                }
            }
            iterates.push(st.open.clone());
            last = Some((state, residual));
            if next == st {
                converged = true;
                break;
            }
            if !seen.insert(next.open.clone()) {
                // A stick edge cycle: a pair at the contact edge opens once tied and closes
                // once untied. Such a pair is closed and slipping (the μ → ∞ limit of Coulomb
                // friction where the normal force vanishes): keep it untied from now on.
                let k0 = iterates.iter().position(|o| *o == next.open).unwrap_or(0);
                let cycle = &iterates[k0..];
                let flipping: Vec<usize> = (0..n)
                    .filter(|&r| {
                        self.problem.rows[r].kind == RowKind::Stick
                            && !edge_slip[r]
                            && cycle.iter().any(|o| o[r] != next.open[r])
                    })
                    .collect();
                if flipping.is_empty() || outer > 200 {
                    failure = Some(Error::numerical(format!(
                        "the stick ties cycle at the contact edge after {outer} outer \
                         iterations: tangential = \"stick\" has no consistent state there; use \
                         \"slide\", or friction when available"
                    )));
                    st = next;
                    break;
                }
                for &r in &flipping {
                    edge_slip[r] = true;
                    next.open[r] = true;
                }
                slipping += flipping.len();
                seen.clear();
                iterates.clear();
            }
            st = next;
        }
        let (final_state, residual) = last.unwrap_or_else(|| (all_closed_state(n), f64::INFINITY));
        if slipping > 0 {
            notes.push(format!(
                "{slipping} stick pair(s) at the contact edge neither stay tied (they open) nor \
                 stay open once untied (they close): kept closed and slipping (tangentially \
                 free), the μ → ∞ limit of Coulomb friction where the normal force vanishes"
            ));
        }
        let (fields, interfaces, nodal_force) = self.problem.state(
            self.model,
            self.prepared,
            factor,
            &final_state.s,
            &final_state.open,
        );
        let mut rows = Vec::new();
        let mut states = Vec::new();
        if !record || compact.is_empty() {
            rows.push(history_row(
                self.model,
                &interfaces,
                load_step,
                factor,
                iterations,
                method.name(),
            ));
            if record {
                states.push(RecordedState {
                    load_step,
                    load_factor: factor,
                    iteration: iterations,
                    fields: fields.clone(),
                    interfaces: interfaces.clone(),
                });
            }
        }
        // The final state of the step: the statuses found (even when not converged).
        let mut out_state = st.clone();
        for r in 0..n {
            if self.problem.rows[r].kind == RowKind::Normal {
                out_state.open[r] = final_state.open[r];
            }
        }
        ContactResult {
            state: out_state,
            fields,
            interfaces,
            nodal_force,
            iterations,
            outer_iterations: outer,
            converged: converged && failure.is_none(),
            solver: method.name(),
            residual,
            rows,
            states,
            notes,
            failure,
            info,
            recorded: compact,
            load_step,
            load_factor: factor,
        }
    }

    /// Expands the compact states of an evolutive path into history rows and boundary
    /// solutions of every body (one sparse solve and one recovery per body each).
    pub fn expand(&self, result: &mut ContactResult) {
        let (step, factor) = (result.load_step, result.load_factor);
        for (it, open, s) in std::mem::take(&mut result.recorded) {
            let (f, i, _) = self
                .problem
                .state(self.model, self.prepared, factor, &s, &open);
            result
                .rows
                .push(history_row(self.model, &i, step, factor, it, result.solver));
            result.states.push(RecordedState {
                load_step: step,
                load_factor: factor,
                iteration: it,
                fields: f,
                interfaces: i,
            });
        }
    }

    /// Names the bodies and the motion that opening the `blocked` rows would leave free.
    fn mechanism(&self, blocked: &[usize]) -> String {
        let mut parts = Vec::new();
        for &r in blocked.iter().take(3) {
            let row = self.problem.rows[r];
            let it = &self.model.interfaces[row.iface];
            let pr = &it.pairs[row.pair];
            let dir = if row.comp == 1 { pr.normal } else { pr.tangent };
            parts.push(format!(
                "interface \"{}\" at ({}, {}) cannot open without leaving body \"{}\" or \
                 body \"{}\" free: the free motion is a translation or rotation that opens it \
                 along ({:.3}, {:.3})",
                it.spec.name,
                crate::input::model::fmt_num(pr.x[0]),
                crate::input::model::fmt_num(pr.x[1]),
                self.model.bodies[it.body_b].name,
                self.model.bodies[it.body_a].name,
                dir[0],
                dir[1],
            ));
        }
        format!(
            "no equilibrium exists (a mechanism): the loads pull the bodies apart where nothing \
             else holds them: {}; hold the body with a displacement condition or change the \
             loads",
            parts.join("; ")
        )
    }
}

/// Every row closed, nothing open: the state reported when no inner solve finished.
fn all_closed_state(n: usize) -> InnerState {
    InnerState {
        open: vec![false; n],
        s: vec![0.0; n],
        lambda: vec![0.0; n],
    }
}

/// The exact state of the statuses `open` found by a solver that does not pivot (Lemke, QP).
fn exact_state(
    inner: &Inner,
    cols: &mut Columns,
    open: &[bool],
) -> Result<evolutive::Outcome, String> {
    let (o, refused) = inner.factor(cols, open);
    let state = inner.state(cols, &o);
    let converged = refused.is_empty() && inner.violations(&state).is_empty();
    let mut notes = Vec::new();
    if !refused.is_empty() {
        notes.push(format!(
            "{} pair(s) found open would leave a body free",
            refused.len()
        ));
    }
    Ok(evolutive::Outcome {
        state,
        iterations: 0,
        converged,
        notes,
        blocked: refused,
    })
}

/// A history row of a state.
pub fn history_row(
    model: &Model,
    interfaces: &[InterfaceResult],
    load_step: usize,
    load_factor: f64,
    iteration: usize,
    solver: &'static str,
) -> HistoryRow {
    let mut st = Vec::new();
    let mut tn = Vec::new();
    let mut op = Vec::new();
    let mut det = Vec::new();
    for (k, it) in model.interfaces.iter().enumerate() {
        let r = &interfaces[k];
        st.push(r.pairs.iter().map(|p| p.status).collect());
        tn.push(r.pairs.iter().map(|p| p.traction[1]).collect());
        op.push(
            r.pairs
                .iter()
                .zip(&it.pairs)
                .map(|(p, pr)| match p.status {
                    PairStatus::Closed => 0.0,
                    PairStatus::Open => pr.gap + p.jump[1],
                })
                .collect(),
        );
        det.push(detached_length(model, k, r));
    }
    HistoryRow {
        load_step,
        load_factor,
        iteration,
        solver,
        status: st,
        normal_traction: tn,
        normal_opening: op,
        detached_length: det,
    }
}

/// Length of the elements of interface k whose two end pairs are open.
pub fn detached_length(model: &Model, k: usize, r: &InterfaceResult) -> f64 {
    let it = &model.interfaces[k];
    it.elements
        .iter()
        .filter(|e| {
            e.pairs
                .iter()
                .all(|&j| r.pairs[j].status == PairStatus::Open)
        })
        .map(|e| {
            let (a, b) = (it.pairs[e.pairs[0]].x, it.pairs[e.pairs[1]].x);
            (b[0] - a[0]).hypot(b[1] - a[1])
        })
        .sum()
}

/// Number of unilateral pairs whose statuses differ between two results.
pub fn differing_pairs(a: &[InterfaceResult], b: &[InterfaceResult]) -> usize {
    a.iter()
        .zip(b)
        .map(|(x, y)| {
            x.pairs
                .iter()
                .zip(&y.pairs)
                .filter(|(p, q)| p.status != q.status)
                .count()
        })
        .sum()
}
