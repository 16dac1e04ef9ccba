//! Contact and detachment on unilateral interfaces by status iteration ([paper §3.1],
//! formulation §6).
//!
//! Place in the flow: `solve` (per-body operators, prepared once) → **`contact`** → results.
//! Conditions per pair j, with the traction t_n on the first body (tension positive), the
//! cohesion c_j, the initial gap h_j and the current normal distance g_j = h_j + n·(u_B − u_A):
//!
//! * closed (real): g_j = 0 and t_n ≤ c_j — a closed pair in tension beyond c_j violates;
//! * open (virtual): t_n = 0 and g_j ≥ 0 — an open pair with g_j < 0 (interpenetration)
//!   violates.
//!
//! Statuses switch by moving rows and columns of the interface system only (`interface`):
//! no boundary integral is recomputed. With `tangential = "stick"` (the paper's "no friction
//! and no sliding") both components of a pair switch together; with `"slide"` the tangential
//! component is always open (frictionless) and only the normal one switches.
//!
//! Two iterations on the same mixed system:
//!
//! * **evolutive** (the paper's iterative LCP): from the initial statuses, switch the one
//!   most violated pair per iteration (violations measured relative to the traction scale or
//!   the displacement scale), re-solve, record the state. Opening one pair at a time follows
//!   the detachment front as it advances, so every intermediate detached length appears in
//!   the history; it stops when no pair violates its condition;
//! * **active set** (primal–dual active set, the semismooth Newton method with c → ∞):
//!   switch every violating pair at once; converges in a few iterations; a repeated status
//!   set (detected by hashing) is a cycle: the iteration restarts once from the zones of
//!   Lemke's method on the QP's LCP (`qp`, `lcp`), and a second cycle hands over to the
//!   evolutive iteration.
//!
//! Brittle cohesion [paper §3.1.1]: a pair that opens loses its cohesion for good (c_j := 0);
//! the active-set solver repeats until no new pair opens (the outer loop of formulation §6.1).

pub mod interface;
pub mod lemke;
pub mod qp;
pub mod solve;

use std::collections::HashSet;

use crate::contact::solve::{solve_status_scaled, Prepared, StatusSolution};
use crate::error::{Error, Result};
use crate::input::model::Model;
use crate::input::scene::{InterfaceModel, Tangential};
use crate::solution::{HistoryRow, PairStatus};

/// Largest relative violation accepted when the iteration cycles between states that differ
/// at the contact edge only (see [`solve_contact`]).
pub const CYCLE_ACCEPT: f64 = 1e-3;

/// Statuses `[k][j][c]` of every interface pair component (c = 0 tangential, 1 normal).
pub type Status = Vec<Vec<[PairStatus; 2]>>;

/// Which iteration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Iteration {
    Evolutive,
    ActiveSet,
}

impl Iteration {
    pub fn name(self) -> &'static str {
        match self {
            Iteration::Evolutive => "lcp",
            Iteration::ActiveSet => "active-set",
        }
    }
}

/// The outcome of a contact solve.
pub struct ContactResult {
    pub status: Status,
    pub solution: StatusSolution,
    /// Number of status changes (iterations) made.
    pub iterations: usize,
    pub converged: bool,
    /// Which iteration produced the final state (after any fallback).
    pub solver: &'static str,
    /// Largest violation left, relative to its scale: max over pairs of
    /// (t_n − c)/T on closed pairs, −g/U on open ones, and |t_n|·g/(T·U) (complementarity).
    pub residual: f64,
    /// Cohesion left at each pair (zero where a pair has opened).
    pub cohesion: Vec<Vec<f64>>,
    pub rows: Vec<HistoryRow>,
    /// With `record`: the boundary solution of every iteration (iteration, fields, interfaces).
    pub states: Vec<RecordedState>,
    pub notes: Vec<String>,
}

/// The solution after one iteration, kept for output.
#[derive(Debug, Clone)]
pub struct RecordedState {
    pub load_step: usize,
    pub load_factor: f64,
    pub iteration: usize,
    pub fields: Vec<crate::solution::BodyField>,
    pub interfaces: Vec<crate::solution::InterfaceResult>,
}

/// The initial status of every pair from the interfaces' `initial` and `tangential`.
pub fn initial_status(model: &Model) -> Status {
    model
        .interfaces
        .iter()
        .map(|it| {
            let closed = match it.spec.model {
                InterfaceModel::Bonded => true,
                InterfaceModel::Unilateral => {
                    it.spec.initial == crate::input::scene::InitialState::Closed
                }
            };
            let n = if closed {
                PairStatus::Closed
            } else {
                PairStatus::Open
            };
            let t = tangential_status(it, n);
            vec![[t, n]; it.pairs.len()]
        })
        .collect()
}

fn tangential_status(it: &crate::input::model::Interface, normal: PairStatus) -> PairStatus {
    match (it.spec.model, it.spec.tangential) {
        (InterfaceModel::Unilateral, Tangential::Slide) => PairStatus::Open,
        _ => normal,
    }
}

/// Normal distance `g = h + n·(u_B − u_A)` of an open pair (0 for a closed one).
fn gap_of(model: &Model, k: usize, j: usize, sol: &StatusSolution, status: PairStatus) -> f64 {
    match status {
        PairStatus::Closed => 0.0,
        PairStatus::Open => model.interfaces[k].pairs[j].gap + sol.interfaces[k].pairs[j].jump[1],
    }
}

/// Scales for relative violations: the largest interface traction and displacement.
fn scales(sol: &StatusSolution) -> (f64, f64) {
    let t = sol
        .interfaces
        .iter()
        .flat_map(|i| i.pairs.iter())
        .map(|p| p.traction[0].abs().max(p.traction[1].abs()))
        .fold(0.0, f64::max);
    let u = sol
        .fields
        .iter()
        .flat_map(|f| f.u.iter())
        .map(|u| u[0].abs().max(u[1].abs()))
        .fold(0.0, f64::max);
    (t.max(f64::MIN_POSITIVE), u.max(f64::MIN_POSITIVE))
}

/// Violations `(k, j, relative size)` of the unilateral pairs, largest first.
fn violations(
    model: &Model,
    sol: &StatusSolution,
    status: &Status,
    cohesion: &[Vec<f64>],
    tol: f64,
) -> Vec<(usize, usize, f64)> {
    let (ts, us) = scales(sol);
    let mut v = Vec::new();
    for (k, it) in model.interfaces.iter().enumerate() {
        if it.spec.model != InterfaceModel::Unilateral {
            continue;
        }
        for j in 0..it.pairs.len() {
            let s = status[k][j][1];
            let size = match s {
                PairStatus::Closed => {
                    (sol.interfaces[k].pairs[j].traction[1] - cohesion[k][j]) / ts
                }
                PairStatus::Open => -gap_of(model, k, j, sol, s) / us,
            };
            if size > tol {
                v.push((k, j, size));
            }
        }
    }
    v.sort_by(|a, b| b.2.total_cmp(&a.2));
    v
}

/// Complementarity residual of a state (see [`ContactResult::residual`]).
pub fn complementarity(
    model: &Model,
    sol: &StatusSolution,
    status: &Status,
    cohesion: &[Vec<f64>],
) -> f64 {
    let (ts, us) = scales(sol);
    let mut r = 0.0f64;
    for (k, it) in model.interfaces.iter().enumerate() {
        if it.spec.model != InterfaceModel::Unilateral {
            continue;
        }
        for j in 0..it.pairs.len() {
            let s = status[k][j][1];
            let tn = sol.interfaces[k].pairs[j].traction[1];
            let g = gap_of(model, k, j, sol, s);
            let lambda = cohesion[k][j] - tn; // ≥ 0
            r = r
                .max(-lambda / ts)
                .max(-g / us)
                .max((lambda.max(0.0) * g.max(0.0)) / (ts * us));
            if s == PairStatus::Open {
                r = r.max(tn.abs() / ts);
            }
        }
    }
    r
}

fn switch(model: &Model, status: &mut Status, cohesion: &mut [Vec<f64>], k: usize, j: usize) {
    let it = &model.interfaces[k];
    let n = match status[k][j][1] {
        PairStatus::Closed => {
            // Brittle cohesion: a pair that detaches loses its strength for good.
            cohesion[k][j] = 0.0;
            PairStatus::Open
        }
        PairStatus::Open => PairStatus::Closed,
    };
    status[k][j] = [tangential_status(it, n), n];
}

/// A history row of a state.
pub fn history_row(
    model: &Model,
    sol: &StatusSolution,
    status: &Status,
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
        st.push(status[k].iter().map(|s| s[1]).collect());
        tn.push(
            sol.interfaces[k]
                .pairs
                .iter()
                .map(|p| p.traction[1])
                .collect(),
        );
        op.push(
            (0..it.pairs.len())
                .map(|j| gap_of(model, k, j, sol, status[k][j][1]))
                .collect(),
        );
        det.push(detached_length(model, k, status));
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
pub fn detached_length(model: &Model, k: usize, status: &Status) -> f64 {
    let it = &model.interfaces[k];
    it.elements
        .iter()
        .filter(|e| e.pairs.iter().all(|&j| status[k][j][1] == PairStatus::Open))
        .map(|e| {
            let (a, b) = (it.pairs[e.pairs[0]].x, it.pairs[e.pairs[1]].x);
            (b[0] - a[0]).hypot(b[1] - a[1])
        })
        .sum()
}

/// Solves contact and detachment from `status` with the given iteration; `cohesion[k][j]`
/// is the strength left at each pair on entry.
#[allow(clippy::too_many_arguments)]
pub fn solve_contact(
    model: &Model,
    prepared: &Prepared,
    mut status: Status,
    mut cohesion: Vec<Vec<f64>>,
    iteration: Iteration,
    tol: f64,
    max_iterations: usize,
    load_step: usize,
    load_factor: f64,
    record: bool,
) -> Result<ContactResult> {
    let mut notes = Vec::new();
    let mut rows = Vec::new();
    let mut seen: HashSet<Vec<u8>> = HashSet::new();
    let key = |s: &Status| -> Vec<u8> {
        s.iter()
            .flat_map(|i| i.iter().map(|p| (p[1] == PairStatus::Closed) as u8))
            .collect()
    };
    let mut mode = iteration;
    let solve = |s: &Status| solve_status_scaled(model, prepared, s, load_factor);
    let mut states = Vec::new();
    let keep = |sol: &StatusSolution, it: usize, states: &mut Vec<RecordedState>| {
        states.push(RecordedState {
            load_step,
            load_factor,
            iteration: it,
            fields: sol.fields.clone(),
            interfaces: sol.interfaces.clone(),
        })
    };
    let record_state = |sol: &StatusSolution,
                        status: &Status,
                        it: usize,
                        mode: Iteration,
                        rows: &mut Vec<HistoryRow>,
                        states: &mut Vec<RecordedState>| {
        rows.push(history_row(
            model,
            sol,
            status,
            load_step,
            load_factor,
            it,
            mode.name(),
        ));
        keep(sol, it, states);
    };
    let mut sol = match solve(&status) {
        Ok(s) => s,
        Err(e) if e.exit_code() == 3 => {
            // Bodies held only by open interfaces float: start from first contact instead,
            // closing the pairs of smallest gap (then, if that is not enough, every pair).
            let open: Vec<(usize, usize, f64)> = model
                .interfaces
                .iter()
                .enumerate()
                .filter(|(_, it)| it.spec.model == InterfaceModel::Unilateral)
                .flat_map(|(k, it)| it.pairs.iter().enumerate().map(move |(j, p)| (k, j, p.gap)))
                .filter(|&(k, j, _)| status[k][j][1] == PairStatus::Open)
                .collect();
            let hmin = open.iter().map(|o| o.2).fold(f64::INFINITY, f64::min);
            let hmax = open.iter().map(|o| o.2).fold(0.0, f64::max);
            for &(k, j, h) in &open {
                if h <= hmin + 1e-9 * hmax.max(f64::MIN_POSITIVE) {
                    switch(model, &mut status, &mut cohesion, k, j);
                }
            }
            notes.push(
                "the initial status leaves a body held by open interfaces only; the iteration \
                 started from first contact (the pairs of smallest gap closed)"
                    .into(),
            );
            match solve(&status) {
                Ok(s) => s,
                Err(e2) if e2.exit_code() == 3 => {
                    for &(k, j, _) in &open {
                        if status[k][j][1] == PairStatus::Open {
                            switch(model, &mut status, &mut cohesion, k, j);
                        }
                    }
                    solve(&status).map_err(|_| e)?
                }
                Err(e2) => return Err(e2),
            }
        }
        Err(e) => return Err(e),
    };
    if record {
        rows.push(history_row(
            model,
            &sol,
            &status,
            load_step,
            load_factor,
            0,
            mode.name(),
        ));
        keep(&sol, 0, &mut states);
    }
    seen.insert(key(&status));
    let mut count = 0;
    let mut converged = false;
    // The state of smallest largest-violation met so far: where the iteration cycles (a pair
    // at the contact edge that carries tension when closed and overlaps slightly when open,
    // formulation §6.4), it is the answer if its violation is small enough.
    let mut best: Option<(f64, Status)> = None;
    let mut lemke_tried = false;
    while count < max_iterations {
        let v = violations(model, &sol, &status, &cohesion, tol);
        if v.is_empty() {
            converged = true;
            break;
        }
        if best.as_ref().is_none_or(|b| v[0].2 < b.0) {
            best = Some((v[0].2, status.clone()));
        }
        match mode {
            Iteration::Evolutive => {
                let (k, j, _) = v[0];
                switch(model, &mut status, &mut cohesion, k, j);
            }
            Iteration::ActiveSet => {
                for &(k, j, _) in &v {
                    switch(model, &mut status, &mut cohesion, k, j);
                }
            }
        }
        count += 1;
        if !seen.insert(key(&status)) {
            match mode {
                Iteration::ActiveSet if !lemke_tried => {
                    // Fall back to Lemke's pivoting on the QP's LCP with the current status
                    // as the pre-partition, then resume the active set from its zones.
                    lemke_tried = true;
                    match crate::contact::qp::solve_qp(
                        model,
                        prepared,
                        load_factor,
                        &cohesion,
                        tol,
                        &status,
                    ) {
                        Ok(q) => {
                            let (st, pivots) = q.lemke.unwrap_or((q.status, 0));
                            notes.push(format!(
                                "the active-set iteration cycled after {count} iterations; \
                                 restarted from the zones of Lemke's method ({pivots} pivots)"
                            ));
                            for (k, it) in st.iter().enumerate() {
                                for (j, p) in it.iter().enumerate() {
                                    if p[1] != status[k][j][1] {
                                        switch(model, &mut status, &mut cohesion, k, j);
                                    }
                                }
                            }
                        }
                        Err(e) => notes.push(format!(
                            "the active-set iteration cycled after {count} iterations; Lemke's \
                             method could not help ({})",
                            e.message()
                        )),
                    }
                    seen.clear();
                    seen.insert(key(&status));
                }
                Iteration::ActiveSet => {
                    notes.push(format!(
                        "the active-set iteration cycled again after {count} iterations; \
                         continued with the evolutive iteration"
                    ));
                    mode = Iteration::Evolutive;
                    seen.clear();
                    seen.insert(key(&status));
                }
                Iteration::Evolutive => {
                    let (worst, best_status) =
                        best.take().unwrap_or((f64::INFINITY, status.clone()));
                    status = best_status;
                    sol = solve(&status)?;
                    converged = worst <= CYCLE_ACCEPT;
                    notes.push(format!(
                        "the status iteration returned to an earlier status after {count} \
                         iterations (pairs at the contact edge switch back and forth); kept the \
                         state of smallest violation, {worst:.1e} of its scale{}",
                        if converged {
                            " (above solve.tolerance, below the 1e-3 accepted for such cycles)"
                        } else {
                            ": too large, not converged"
                        }
                    ));
                    if record {
                        record_state(&sol, &status, count, mode, &mut rows, &mut states);
                    }
                    break;
                }
            }
        }
        sol = solve(&status)?;
        if record {
            record_state(&sol, &status, count, mode, &mut rows, &mut states);
        }
    }
    if !converged && count >= max_iterations {
        notes.push(format!(
            "the contact iteration did not converge in {max_iterations} iterations \
             (solve.max_iterations)"
        ));
    }
    let residual = complementarity(model, &sol, &status, &cohesion);
    Ok(ContactResult {
        status,
        solution: sol,
        iterations: count,
        converged,
        solver: mode.name(),
        residual,
        cohesion,
        rows,
        states,
        notes,
    })
}

/// The cohesion of every pair at the start (zero on open and bonded interfaces).
pub fn initial_cohesion(model: &Model) -> Vec<Vec<f64>> {
    model
        .interfaces
        .iter()
        .map(|it| it.pairs.iter().map(|p| p.cohesion).collect())
        .collect()
}

impl ContactResult {
    /// The failure of a solve that did not converge, as a numerical error naming what failed.
    pub fn failure(&self) -> Option<Error> {
        (!self.converged).then(|| {
            Error::numerical(format!(
                "the contact solver did not converge after {} iterations (largest violation \
                 {:.1e} of its scale): {}",
                self.iterations,
                self.residual,
                self.notes.join("; ")
            ))
        })
    }
}
