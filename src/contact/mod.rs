//! Contact and detachment on unilateral interfaces: the driver of load steps and of the outer
//! loop, over one discrete problem (`problem`) that every solver solves.
//!
//! Place in the flow: `bem` (per-body operators, prepared once by `bem::prepare`) →
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
//! repeats until nothing changes (docs/formulation.md §6.1). Every solver runs the same outer loop,
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

pub(crate) mod active_set;
mod collapse;
pub mod cuts;
pub mod driver;
pub mod evolutive;
pub mod exact;
mod inner;
pub mod interface;
pub mod lcp;
pub mod lemke;
pub mod mechanism;
pub mod problem;
pub mod qp;
pub mod sparse;
pub mod statics;

use std::collections::HashSet;

use crate::bem::Operators;
use crate::error::Error;
use crate::input::model::Model;
use crate::input::scene::InterfaceModel;
use crate::solution::{
    BodyField, BodyMotion, HistoryRow, InterfaceResult, PairResult, PairStatus, SolverInfo,
};
use inner::*;
use lcp::{
    bound_change, status_key, Inner, InnerFailure, InnerOutcome, InnerState, OpeningColumns,
    Statuses, BOUNDS_SETTLED,
};
pub use problem::{solve_all_closed, StatusSolution};
use problem::{Problem, RowKind};

/// Which solver solves the inner problem.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Solver {
    Evolutive,
    ActiveSet,
    Lemke,
    Qp,
    /// The active set on the sparse system of displacements and openings (`sparse`).
    Sparse,
    /// Every pair component its own row, one convex programme per set of slip bounds
    /// (`exact`).
    Exact,
}

impl Solver {
    pub fn name(self) -> &'static str {
        match self {
            Solver::Evolutive => "lcp",
            Solver::ActiveSet => "active-set",
            Solver::Lemke => "lemke",
            Solver::Qp => "qp",
            Solver::Sparse => "sparse",
            Solver::Exact => "exact",
        }
    }

    /// Its entry in the run's timings.
    pub(crate) fn timing_key(self) -> &'static str {
        match self {
            Solver::Evolutive => "contact_lcp",
            Solver::ActiveSet => "contact_active_set",
            Solver::Lemke => "contact_lemke",
            Solver::Qp => "contact_qp",
            Solver::Sparse => "contact_sparse",
            Solver::Exact => "contact_exact",
        }
    }
}

/// The state carried from one load step (and outer iteration) to the next: open rows,
/// tangential ties of stick rows, slip statuses and accumulated slips of friction rows,
/// and the cohesion left at each pair.
#[derive(Debug, Clone, PartialEq)]
pub struct StepState {
    /// Per row that can open: open (normal rows), untied (stick rows) or slipping (friction
    /// rows).
    pub open: Vec<bool>,
    /// Slip direction ±1 of slipping friction rows (0 elsewhere).
    pub sign: Vec<f64>,
    /// Accumulated slip s̄ of friction rows (their opening while they stick).
    pub offset: Vec<f64>,
    /// Accumulated slip path Σ|Δs| of friction rows while closed.
    pub path: Vec<f64>,
    /// Slip bounds μλ_n of friction rows at the end of the last step (empty at the start).
    pub bound: Vec<f64>,
    pub cohesion: Vec<Vec<f64>>,
    /// Pairs that have opened (their cohesion is lost for good).
    pub broken: Vec<Vec<bool>>,
    /// The full-row solver's (`exact`): per full row, the relative displacement at the end
    /// of the last step (the anchor of tied and Tresca rows) and the accumulated slip path;
    /// empty before its first step.
    pub full_anchor: Vec<f64>,
    pub full_path: Vec<f64>,
}

/// The solution after one iteration, kept for output.
#[derive(Debug, Clone)]
pub struct Iterate {
    pub load_step: usize,
    pub load_factor: f64,
    /// Pseudo-time of the step (1 without `[solve] time`).
    pub time: f64,
    /// Body force of each body at this step (before the load factor).
    pub body_force: Vec<Option<[f64; 2]>>,
    pub iteration: usize,
    /// The state's number in the run's full history (every iteration of every load step,
    /// counted from 0): the iteration that the archive and the VTK files give it.
    pub index: usize,
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
    pub states: Vec<Iterate>,
    pub notes: Vec<String>,
    pub failure: Option<Error>,
    /// The failure is a mechanism (no equilibrium exists), not a solver's trouble.
    pub mechanism: bool,
    /// The mechanism's moving bodies, where its motion was found (`mechanism::Motion`).
    pub motion: Option<Vec<BodyMotion>>,
    /// The failure is Lemke's or the QP's that could not pose the stick law from the moment
    /// a pair closes (`InnerFailure::StickClosure`), or a friction fixed point that did not
    /// settle: no verdict on the equilibrium.
    pub undecided: bool,
    /// Extra figures of the solver (QP: iterations, status; Lemke: pivots).
    pub info: SolverInfo,
    /// The states of the evolutive path in compact form (iteration, open rows, openings),
    /// expanded into `rows` and `states` by [`Session::expand`].
    pub recorded: Vec<(usize, Vec<bool>, Vec<f64>)>,
    /// The state the step started from (for the slip paths of recorded states).
    pub start: StepState,
    pub load_step: usize,
    pub load_factor: f64,
}

/// What the outer loop of one load step carries besides the state: the recorded states of
/// the evolutive path and the solvers' figures.
struct StepLoop {
    /// (iteration, open rows, openings) of each recorded state.
    compact: Vec<(usize, Vec<bool>, Vec<f64>)>,
    record: bool,
    /// Iterations made before the current inner solve (the index of its first state).
    iterations_recorded: usize,
    /// Pivots that finished the friction rows of Lemke's and the QP's statuses.
    finishing: usize,
    /// Dense solves that Lemke and the QP repeated with the stick rows of the pairs they
    /// closed tied (`Inner::dense_with_ties`).
    tie_resolves: usize,
    /// Inner solves whose pivoting path the QP completed.
    rescues: usize,
    /// The step failed where Lemke or the QP could not pose the stick law at closure, or
    /// where the friction fixed point did not settle: no verdict on the equilibrium.
    undecided: bool,
    info: SolverInfo,
}

impl StepLoop {
    fn new(record: bool) -> Self {
        StepLoop {
            compact: Vec::new(),
            record,
            finishing: 0,
            tie_resolves: 0,
            rescues: 0,
            undecided: false,
            iterations_recorded: 0,
            info: SolverInfo::default(),
        }
    }
}

/// What the outer loop of a load step leaves for its result.
struct StepEnd {
    st: StepState,
    /// The last inner solution and its complementarity residual.
    last: Option<(InnerState, f64)>,
    lp: StepLoop,
    notes: Vec<String>,
    /// Stick pairs kept slipping at the contact edge.
    slipping: usize,
    friction: bool,
    bound_changes: Vec<f64>,
    bound: Vec<f64>,
    iterations: usize,
    outer: usize,
    converged: bool,
    failure: Option<Error>,
    mechanism: bool,
    motion: Option<Vec<BodyMotion>>,
}

/// A contact run: the problem and the columns of its opening stiffness, shared by every
/// solver and load step.
pub struct Session<'a> {
    pub model: &'a Model,
    pub prepared: &'a Operators,
    pub problem: Problem,
    pub cols: OpeningColumns,
    /// The sparse system of displacements and openings, built when `Solver::Sparse` first
    /// runs.
    pub sparse: Option<sparse::SparseSystem>,
    /// Outer iterations of the Tresca fixed point after which Coulomb's problem is solved
    /// exactly (Klarbring's LCP through Lemke) to restart it.
    pub coupled_after: usize,
    /// The contact stage's bar: each outer iteration of a load step shows on it.
    pub stage: Option<crate::output::progress::Stage>,
    /// The pairs of the last full-row step solved from rest: the seed of the next step from
    /// rest where the sparse solver's statuses are not one (a collapse search's trials).
    pub last_from_rest: Option<Vec<crate::solution::InterfaceResult>>,
    /// Statuses and slip bounds the sparse solver starts its first iterate of a load step
    /// from (the state of the same step on another cut of the junctions), used once.
    pub guess: Option<Guess>,
}

/// A start for the sparse solver at one load step ([`Session::guess`]).
#[derive(Debug, Clone)]
pub struct Guess {
    pub step: usize,
    pub open: Vec<bool>,
    pub sign: Vec<f64>,
    pub bound: Vec<f64>,
}

impl Guess {
    /// The step state `st` with the guessed statuses, and the guessed slip bounds in `bound`.
    fn start(self, st: &StepState, bound: &mut Vec<f64>) -> StepState {
        *bound = self.bound;
        StepState {
            open: self.open,
            sign: self.sign,
            ..st.clone()
        }
    }
}

impl<'a> Session<'a> {
    /// The guess for the sparse solver's load step `load_step` over `n` rows, taken once.
    fn take_guess(&mut self, load_step: usize, n: usize, method: Solver) -> Option<Guess> {
        self.guess
            .take_if(|g| g.step == load_step && g.open.len() == n && method == Solver::Sparse)
    }

    pub fn new(model: &'a Model, prepared: &'a Operators) -> crate::error::Result<Self> {
        Session::with_cuts(model, prepared, problem::Cuts::Tangential)
    }

    /// The session whose problem cuts the junction cycles as `cuts` says
    /// ([`Problem::with_cuts`]).
    pub fn with_cuts(
        model: &'a Model,
        prepared: &'a Operators,
        cuts: problem::Cuts,
    ) -> crate::error::Result<Self> {
        Ok(Session {
            model,
            prepared,
            problem: Problem::with_cuts(model, prepared, cuts)?,
            cols: OpeningColumns::default(),
            sparse: None,
            coupled_after: FRICTION_COUPLED_AFTER,
            stage: None,
            last_from_rest: None,
            guess: None,
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
        let broken = self
            .model
            .interfaces
            .iter()
            .map(|it| vec![false; it.pairs.len()])
            .collect();
        let n = self.problem.n_open_rows;
        StepState {
            open,
            sign: vec![0.0; n],
            offset: vec![0.0; n],
            path: vec![0.0; n],
            bound: Vec::new(),
            cohesion,
            broken,
            full_anchor: Vec::new(),
            full_path: Vec::new(),
        }
    }

    /// The slip bound μ·max(P_n, 0) of each friction row from the row forces `lambda`
    /// (cohesion terms `coh` removed) and the open rows; zero on other rows and where the
    /// pair is open.
    fn bounds(&self, lambda: &[f64], coh: &[f64], open: &[bool]) -> Vec<f64> {
        let n = self.problem.n_open_rows;
        (0..n)
            .map(|r| {
                let row = self.problem.rows[r];
                if row.kind != RowKind::Friction {
                    return 0.0;
                }
                let mu = self.model.interfaces[row.iface].pairs[row.pair].friction;
                match self.problem.row_of[row.iface][row.pair][1] {
                    Some(rn) if rn < n && !open[rn] => mu * (lambda[rn] - coh[rn]).max(0.0),
                    _ => 0.0,
                }
            })
            .collect()
    }

    /// Sets the slip statuses and accumulated slip paths of friction pairs in `interfaces`
    /// for openings `s` from the step's start `offset` and `path`.
    fn mark_slip(
        &self,
        interfaces: &mut [InterfaceResult],
        s: &[f64],
        open: &[bool],
        start: &StepState,
    ) -> Vec<f64> {
        let mut path = start.path.clone();
        for (r, row) in self.problem.rows[..self.problem.n_open_rows]
            .iter()
            .enumerate()
        {
            if row.kind != RowKind::Friction {
                continue;
            }
            if !self.pair_open(open, row.iface, row.pair) {
                path[r] += (s[r] - start.offset[r]).abs();
            }
            interfaces[row.iface].pairs[row.pair].slip = path[r];
        }
        path
    }

    /// The body force of each body at the model's pseudo-time.
    pub(crate) fn body_forces(&self) -> Vec<Option<[f64; 2]>> {
        self.model.bodies.iter().map(|b| b.body_force).collect()
    }

    /// For a solver that follows Coulomb's law within the inner problem (the sparse one,
    /// where `allowed`: not after it failed to in this step), each friction row's normal row
    /// and μ where that row can open; empty for the others.
    fn coulomb_rows(&self, method: Solver, allowed: bool) -> Vec<Option<(usize, f64)>> {
        if method != Solver::Sparse || !allowed {
            return Vec::new();
        }
        let n = self.problem.n_open_rows;
        let rows = &self.problem.rows[..n];
        if !rows.iter().any(|r| r.kind == RowKind::Friction) {
            return Vec::new();
        }
        rows.iter()
            .map(|row| match row.kind {
                RowKind::Friction => self.problem.row_of[row.iface][row.pair][1]
                    .filter(|&k| k < n)
                    .map(|k| (k, self.model.interfaces[row.iface].pairs[row.pair].friction)),
                _ => None,
            })
            .collect()
    }

    /// Whether pair (k, j)'s normal row is open in `open`.
    fn pair_open(&self, open: &[bool], k: usize, j: usize) -> bool {
        match self.problem.row_of[k][j][1] {
            Some(r) if r < self.problem.n_open_rows => open[r],
            _ => false,
        }
    }

    /// The slip bounds before any normal force is known: every friction row tied (an
    /// infinite bound), which gives the normal forces of the first bounds.
    fn first_bounds(&self) -> Vec<f64> {
        self.problem.rows[..self.problem.n_open_rows]
            .iter()
            .map(|r| {
                if r.kind == RowKind::Friction {
                    f64::INFINITY
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// The free rows of the inner problem (untied stick rows, friction rows without a slip
    /// bound) and the untied stick rows of open pairs, which tie as their pair closes (the
    /// sparse solver follows that within the inner problem; the others through the outer
    /// loop).
    fn inner_rows(
        &self,
        st: &StepState,
        bound: &[f64],
        edge_slip: &[bool],
    ) -> (Vec<bool>, Vec<bool>) {
        let rows = &self.problem.rows[..self.problem.n_open_rows];
        let free = rows
            .iter()
            .enumerate()
            .map(|(r, row)| match row.kind {
                RowKind::Stick => st.open[r],
                RowKind::Friction => bound[r] <= 0.0,
                _ => false,
            })
            .collect();
        let tie_on_close = rows
            .iter()
            .enumerate()
            .map(|(r, row)| row.kind == RowKind::Stick && st.open[r] && !edge_slip[r])
            .collect();
        (free, tie_on_close)
    }

    /// The message of a solver's failure, with the mechanism that the pivoting path `probe`
    /// from the start statuses found (the rows that cannot open), and whether it found one.
    fn explain(&self, e: &InnerFailure, probe: &InnerOutcome, inner: &Inner) -> (String, bool) {
        if probe.blocked.is_empty() {
            (e.to_string(), false)
        } else {
            let hint = self.mechanism(&probe.blocked, &probe.state, inner);
            (format!("{e}; {hint}"), true)
        }
    }

    /// Restarts the Tresca fixed point from Coulomb's exact solution (`coulomb_exact`): its
    /// statuses of the normal and friction rows into `next`, its slip bounds into `bound`.
    fn coulomb_restart(
        &mut self,
        base: &problem::Base,
        st: &StepState,
        tol: f64,
        (next, bound): (&mut StepState, &mut Vec<f64>),
        (outer, change): (usize, f64),
    ) -> String {
        match self.coulomb_exact(base, st, tol) {
            Ok((open, sign, b)) => {
                self.restart_from(next, bound, (open, sign, b));
                format!(
                    "the Tresca fixed point had not settled after {outer} outer iterations \
                     (last relative change {change:.1e}): restarted from the exact solution \
                     of Klarbring's friction LCP (Lemke)"
                )
            }
            Err(e) => format!(
                "the Tresca fixed point had not settled after {outer} outer iterations and \
                 Klarbring's friction LCP gave no solution ({e}); the fixed point continued"
            ),
        }
    }

    /// The next outer state and bounds from Coulomb's exact statuses and bounds.
    fn restart_from(
        &self,
        next: &mut StepState,
        bound: &mut Vec<f64>,
        (open, sign, b): (Vec<bool>, Vec<f64>, Vec<f64>),
    ) {
        for r in 0..self.problem.n_open_rows {
            if matches!(
                self.problem.rows[r].kind,
                RowKind::Normal | RowKind::Friction
            ) {
                next.open[r] = open[r];
                next.sign[r] = sign[r];
            }
        }
        *bound = b;
    }

    /// A stick edge cycle: a pair at the contact edge opens once tied and closes once untied.
    /// Such a pair is closed and slipping (the μ → ∞ limit of Coulomb friction where the
    /// normal force vanishes): it is kept untied from now on.
    ///
    /// Keeps the stick rows that flip along the cycle of outer iterates that `next` closes
    /// untied from now on (`edge_slip`, and open in `next`); how many. A cycle without such a
    /// row, or after 200 outer iterations, is a failure.
    fn untie_edge_cycle(
        &self,
        iterates: &[Vec<bool>],
        next: &mut StepState,
        edge_slip: &mut [bool],
        outer: usize,
    ) -> Result<usize, Error> {
        let flipping = self.edge_cycle(iterates, &next.open, edge_slip);
        if flipping.is_empty() || outer > 200 {
            return Err(Error::numerical(format!(
                "the stick ties cycle at the contact edge after {outer} outer iterations: \
                 tangential = \"stick\" has no consistent state there; use tangential = \
                 \"friction\" (or \"slide\")"
            )));
        }
        for &r in &flipping {
            edge_slip[r] = true;
            next.open[r] = true;
        }
        Ok(flipping.len())
    }

    /// The stick rows that flip along the cycle of outer iterates that `next_open` closes
    /// (not yet kept slipping).
    fn edge_cycle(
        &self,
        iterates: &[Vec<bool>],
        next_open: &[bool],
        edge_slip: &[bool],
    ) -> Vec<usize> {
        let k0 = iterates.iter().position(|o| o == next_open).unwrap_or(0);
        let cycle = &iterates[k0..];
        (0..self.problem.n_open_rows)
            .filter(|&r| {
                self.problem.rows[r].kind == RowKind::Stick
                    && !edge_slip[r]
                    && cycle.iter().any(|o| o[r] != next_open[r])
            })
            .collect()
    }

    /// Coulomb's problem solved exactly for the step's base: Klarbring's friction LCP
    /// through Lemke (`lemke::solve_coupled`): open rows, slip directions and slip bounds.
    #[allow(clippy::type_complexity)]
    fn coulomb_exact(
        &mut self,
        base: &problem::Base,
        st: &StepState,
        tol: f64,
    ) -> Result<(Vec<bool>, Vec<f64>, Vec<f64>), String> {
        let n = self.problem.n_open_rows;
        let free: Vec<bool> = (0..n)
            .map(|r| self.problem.rows[r].kind == RowKind::Stick && st.open[r])
            .collect();
        let exact = Inner {
            problem: &self.problem,
            base,
            free,
            tie_on_close: vec![false; n],
            bound: vec![0.0; n],
            tol,
            coulomb: Vec::new(),
            coupled: false,
        };
        let mu: Vec<f64> = self.problem.rows[..n]
            .iter()
            .map(|r| match r.kind {
                RowKind::Friction => self.model.interfaces[r.iface].pairs[r.pair].friction,
                _ => 0.0,
            })
            .collect();
        let normal_of: Vec<Option<usize>> = self.problem.rows[..n]
            .iter()
            .map(|r| self.problem.row_of[r.iface][r.pair][1].filter(|&q| q < n))
            .collect();
        lemke::solve_coupled(&exact, &mut self.cols, &mu, &normal_of)
    }

    /// The outer loop's next state from the inner solution `state`: statuses and slip
    /// directions, the brittle cohesion lost by the pairs that opened, stick ties where the
    /// pair is closed (and not slipping at the contact edge).
    fn outer_update(&self, st: &StepState, state: &InnerState, edge_slip: &[bool]) -> StepState {
        let mut next = st.clone();
        for r in 0..self.problem.n_open_rows {
            let row = self.problem.rows[r];
            let pair_open = self.pair_open(&state.open, row.iface, row.pair);
            next.open[r] = match row.kind {
                RowKind::Normal | RowKind::Friction => state.open[r],
                _ => pair_open || edge_slip[r],
            };
            next.sign[r] = state.sign[r];
            if row.kind == RowKind::Normal && pair_open {
                next.cohesion[row.iface][row.pair] = 0.0;
                next.broken[row.iface][row.pair] = true;
            }
        }
        next
    }

    /// The contact bar's message after an outer iteration: switches so far, rows open or
    /// slipping, the change of the slip bounds (with friction).
    fn show_outer(
        &self,
        load_step: usize,
        (outer, iterations): (usize, usize),
        state: &InnerState,
        change: Option<f64>,
    ) {
        if let Some(stage) = &self.stage {
            let open = state.open.iter().filter(|&&o| o).count();
            stage.contact_detail(&format!(
                "step {}, outer iteration {outer}: {iterations} switches, {open} of {} rows \
                 open or slipping{}",
                load_step + 1,
                state.open.len(),
                change.map_or(String::new(), |c| format!(", bound change {c:.1e}"))
            ));
        }
    }

    /// Solves one load step from `start` with `method`.
    #[allow(clippy::too_many_arguments)]
    pub fn solve_step(
        &mut self,
        start: &StepState,
        method: Solver,
        tol: f64,
        max_iterations: usize,
        load_step: usize,
        factor: f64,
        record: bool,
    ) -> ContactResult {
        if method == Solver::Exact {
            return self.solve_step_full(start, (tol, max_iterations), load_step, factor, record);
        }
        let n = self.problem.n_open_rows;
        let mut st = start.clone();
        let mut notes = Vec::new();
        let mut edge_slip = vec![false; n];
        let mut seen: HashSet<Vec<bool>> = HashSet::new();
        let (mut iterations, mut outer, mut slipping) = (0, 0, 0);
        let (mut converged, mut mechanism) = (false, false);
        let (mut failure, mut motion) = (None, None);
        let mut last: Option<(InnerState, f64)> = None;
        // The outer iterates' open rows, to find the rows of a stick edge cycle.
        let mut iterates: Vec<Vec<bool>> = Vec::new();
        let friction = self.has_friction();
        // Slip bounds of the Tresca fixed point: from the last step's normal forces, or
        // (first step) from those with every pair closed.
        let mut bound = start.bound.clone();
        let mut bound_changes: Vec<f64> = Vec::new();
        let mut relax = Relaxation::new();
        let mut lp = StepLoop::new(record);
        // Whether the inner solver may follow Coulomb's law within its iteration.
        let mut coulomb = true;
        let mut guess = self.take_guess(load_step, n, method);
        loop {
            outer += 1;
            let base = self.problem.base(factor, &st.cohesion, &st.offset);
            if bound.len() != n {
                bound = self.first_bounds();
            }
            let guessed = guess.take().map(|g| g.start(&st, &mut bound));
            let rows = self.inner_rows(&st, &bound, &edge_slip);
            let inner = Inner::new(&self.problem, &base, rows, bound.clone(), tol)
                .with_coulomb(self.coulomb_rows(method, coulomb));
            let asked_coulomb = !inner.coulomb.is_empty();
            lp.iterations_recorded = iterations;
            let budget = max_iterations.saturating_sub(iterations);
            let solved = solve_inner(
                &inner,
                (&mut self.cols, &mut self.sparse),
                method,
                guessed.as_ref().unwrap_or(&st),
                (budget, max_iterations),
                &mut lp,
            );
            let outcome = match solved {
                Ok(o) => o,
                Err((e, probe)) => {
                    lp.undecided = matches!(e, InnerFailure::StickClosure { .. });
                    let (err, blocked) = self.explain(&e, &probe, &inner);
                    let at = (&probe.state, if blocked { &probe.blocked[..] } else { &[] });
                    let (said, found) = mechanism::motion(self.model, &inner, &mut self.sparse, at);
                    (mechanism, motion) = (blocked, found);
                    failure = Some(failed(method, load_step, &(err + &said)));
                    break;
                }
            };
            iterations += outcome.iterations;
            notes.extend(outcome.notes.iter().cloned());
            // A solver that followed Coulomb's law hands back the bounds of its state.
            let inner = adopt_bounds(inner, outcome.bound.clone(), &mut bound);
            coulomb &= !(asked_coulomb && outcome.bound.is_none());
            let residual = inner.residual(&outcome.state);
            let ok = outcome.converged;
            lp.undecided |= !ok && outcome.stalled; // stopped without a verdict, not taken over
            let outcome_blocked = outcome.blocked.clone();
            let state = outcome.state;
            if !ok {
                let at = (&state, &outcome_blocked[..]);
                let (said, found) = mechanism::motion(self.model, &inner, &mut self.sparse, at);
                let hint = self.hint(&outcome_blocked, &state, &inner) + &said;
                (mechanism, motion) = (!outcome_blocked.is_empty(), found);
                failure = Some(not_converged(method, load_step, residual, &notes, &hint));
                last = Some((state, residual));
                break;
            }
            // Outer update: brittle cohesion, stick ties, slip bounds.
            let mut next = self.outer_update(&st, &state, &edge_slip);
            let change = self.tresca_update(
                (&base, &st, &state, tol),
                (&mut next, &mut bound, &mut relax),
                (load_step, outer, iterations),
                &mut notes,
            );
            let settled = !friction || change <= BOUNDS_SETTLED;
            bound_changes.extend(friction.then_some(change));
            iterates.push(st.open.clone());
            last = Some((state, residual));
            if self.same_statuses(&st, &next) && settled {
                converged = true;
                st = next;
                break;
            }
            if friction && outer >= FRICTION_OUTER_LIMIT {
                lp.undecided = true; // no verdict: the driver asks the sparse solver
                failure = Some(unsettled(outer, load_step, change));
                st = next;
                break;
            }
            if !settled {
                st = next;
                continue;
            }
            if !seen.insert(next.open.clone()) {
                // A stick edge cycle (see `untie_edge_cycle`).
                match self.untie_edge_cycle(&iterates, &mut next, &mut edge_slip, outer) {
                    Ok(k) => slipping += k,
                    Err(e) => {
                        failure = Some(e);
                        st = next;
                        break;
                    }
                }
                seen.clear();
                iterates.clear();
            }
            st = next;
        }
        self.finish_step(
            start,
            method,
            (load_step, factor),
            StepEnd {
                st,
                last,
                lp,
                notes,
                slipping,
                friction,
                bound_changes,
                bound,
                iterations,
                outer,
                converged,
                failure,
                mechanism,
                motion,
            },
        )
    }

    /// The Tresca fixed point's step after the inner solution `state` of `st`: the bounds
    /// from its normal forces (relaxed where the fixed point oscillates), the progress line,
    /// and after `coupled_after` unsettled outer iterations the restart from Coulomb's exact
    /// problem (into `next` and `bound`, with a note). Returns the bounds' relative change.
    fn tresca_update(
        &mut self,
        (base, st, state, tol): (&problem::Base, &StepState, &InnerState, f64),
        (next, bound, relax): (&mut StepState, &mut Vec<f64>, &mut Relaxation),
        (load_step, outer, iterations): (usize, usize, usize),
        notes: &mut Vec<String>,
    ) -> f64 {
        let n = self.problem.n_open_rows;
        let friction = self.has_friction();
        let new_bound = self.bounds(&state.lambda, &base.cohesion, &state.open);
        let change = bound_change(bound, &new_bound);
        let settled = !friction || change <= BOUNDS_SETTLED;
        self.show_outer(
            load_step,
            (outer, iterations),
            state,
            friction.then_some(change),
        );
        relax.update(outer, change);
        *bound = relax.next(outer, status_key(state), bound, new_bound);
        if friction && !settled && outer == self.coupled_after && n <= COUPLED_MAX_ROWS {
            // A slow or cycling fixed point: solve Coulomb's problem exactly (Klarbring's
            // LCP through Lemke) and restart the fixed point from its bounds.
            notes.push(self.coulomb_restart(base, st, tol, (next, bound), (outer, change)));
        }
        change
    }

    /// Whether any row that can open is a friction row.
    fn has_friction(&self) -> bool {
        self.problem.rows[..self.problem.n_open_rows]
            .iter()
            .any(|r| r.kind == RowKind::Friction)
    }

    /// True when `next` keeps the statuses of `st` (but the friction rows' and cohesion).
    fn same_statuses(&self, st: &StepState, next: &StepState) -> bool {
        (0..self.problem.n_open_rows)
            .all(|r| self.problem.rows[r].kind == RowKind::Friction || next.open[r] == st.open[r])
            && next.cohesion == st.cohesion
    }

    /// The result of a load step from what its outer loop left (`end`): the boundary
    /// solution of the final state, the history row and recorded state, the notes.
    fn finish_step(
        &self,
        start: &StepState,
        method: Solver,
        (load_step, factor): (usize, f64),
        end: StepEnd,
    ) -> ContactResult {
        let StepEnd {
            st,
            last,
            mut lp,
            mut notes,
            slipping,
            friction,
            bound_changes,
            bound,
            iterations,
            outer,
            converged,
            failure,
            mechanism,
            motion,
        } = end;
        let n = self.problem.n_open_rows;
        let record = lp.record;
        let (final_state, residual) = last.unwrap_or_else(|| (all_closed_state(n), f64::INFINITY));
        // The last outer iteration may change ties, cohesion or slip bounds without a
        // switch: then its state is not among the recorded ones, and the history must end
        // with the state the step gives.
        if record {
            if let Some((k, open, s)) = lp.compact.last() {
                if *open != final_state.open || *s != final_state.s {
                    let k = k + 1;
                    lp.compact
                        .push((k, final_state.open.clone(), final_state.s.clone()));
                }
            }
        }
        if lp.rescues > 0 {
            notes.push(format!(
                "the pivoting path stopped {} time(s) at a row that could not open \
                 without leaving a body free, although the problem had a solution: the QP of \
                 the same problem found it (checked exactly) and the iteration went on from it",
                lp.rescues
            ));
            lp.info.qp_rescues = Some(lp.rescues);
        }
        if slipping > 0 {
            notes.push(format!(
                "{slipping} stick pair(s) at the contact edge neither stay tied (they open) nor \
                 stay open once untied (they close): kept closed and slipping (tangentially \
                 free), the μ → ∞ limit of Coulomb friction where the normal force vanishes"
            ));
        }
        let (fields, mut interfaces, nodal_force) = self.problem.state(
            self.model,
            self.prepared,
            factor,
            &final_state.s,
            &final_state.open,
        );
        let path = self.mark_slip(&mut interfaces, &final_state.s, &final_state.open, start);
        if friction {
            lp.info.friction_outer_changes = Some(bound_changes);
        }
        let mut rows = Vec::new();
        let mut states = Vec::new();
        if !record || lp.compact.is_empty() {
            rows.push(history_row(
                self.model,
                &interfaces,
                load_step,
                factor,
                iterations,
                method.name(),
            ));
            if record {
                states.push(Iterate {
                    load_step,
                    load_factor: factor,
                    time: self.model.time,
                    body_force: self.body_forces(),
                    iteration: iterations,
                    index: 0,
                    fields: fields.clone(),
                    interfaces: interfaces.clone(),
                });
            }
        }
        // The final state of the step: the statuses found (even when not converged).
        let mut out_state = st.clone();
        for r in 0..n {
            match self.problem.rows[r].kind {
                RowKind::Normal => out_state.open[r] = final_state.open[r],
                RowKind::Friction => {
                    out_state.open[r] = final_state.open[r];
                    out_state.sign[r] = final_state.sign[r];
                    out_state.offset[r] = final_state.s[r];
                }
                _ => {}
            }
        }
        out_state.path = path;
        out_state.bound = bound;
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
            mechanism,
            motion,
            undecided: lp.undecided,
            info: lp.info,
            recorded: lp.compact,
            start: start.clone(),
            load_step,
            load_factor: factor,
        }
    }

    /// Expands the compact states of an evolutive path into history rows and boundary
    /// solutions of every body (one sparse solve and one recovery per body each).
    pub fn expand(&self, result: &mut ContactResult) {
        use rayon::prelude::*;
        let (step, factor) = (result.load_step, result.load_factor);
        // Each state is one sparse solve and a recovery per body: independent, in parallel.
        let recorded = std::mem::take(&mut result.recorded);
        let expanded: Vec<_> = recorded
            .par_iter()
            .map(|(_, open, s)| {
                let (f, i, _) = self
                    .problem
                    .state(self.model, self.prepared, factor, s, open);
                (f, i)
            })
            .collect();
        for ((it, open, s), (f, mut i)) in recorded.into_iter().zip(expanded) {
            self.mark_slip(&mut i, &s, &open, &result.start);
            result
                .rows
                .push(history_row(self.model, &i, step, factor, it, result.solver));
            result.states.push(Iterate {
                load_step: step,
                load_factor: factor,
                time: self.model.time,
                body_force: self.body_forces(),
                iteration: it,
                index: 0,
                fields: f,
                interfaces: i,
            });
        }
    }
}

/// The inner problem `inner` with the slip bounds `b` that a solver following Coulomb's law
/// within its iteration handed back (also the outer loop's `bound`); as it is without them.
/// One that could not follow the law leaves the bounds fixed for the rest of the step (the
/// Tresca fixed point of the outer loop).
fn adopt_bounds<'a>(inner: Inner<'a>, b: Option<Vec<f64>>, bound: &mut Vec<f64>) -> Inner<'a> {
    match b {
        Some(b) => {
            bound.clone_from(&b);
            Inner { bound: b, ..inner }
        }
        None => inner,
    }
}

/// A history row of a state.
pub(crate) fn history_row(
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

/// Number of unilateral pairs whose statuses (open/closed, and stick/slip with friction)
/// differ between two results.
pub fn differing_pairs(a: &[InterfaceResult], b: &[InterfaceResult]) -> usize {
    compare_pairs(a, b, 0.0).0
}

/// (pairs whose statuses differ, of which degenerate) between two results of a model of
/// size `length`. A degenerate pair is closed with no normal force (below 1e-8 of the
/// largest) in one result and open with no opening (below 1e-12 of `length`) in the
/// other: touching without pressing, like the head joints of a wall under vertical load.
/// Or it is closed in both, sticking in one and slipping in the other with the same
/// tractions (within 1e-8 of the largest normal one): at its friction bound, where the slip
/// is a motion that no force resists or drives (a block exactly at its friction angle).
/// Both statuses solve the LCP there, with the same forces.
pub(crate) fn status_differences(
    a: &[InterfaceResult],
    b: &[InterfaceResult],
    length: f64,
) -> (usize, usize) {
    compare_pairs(a, b, 1e-12 * length)
}

/// (pairs with different statuses, of which degenerate).
fn compare_pairs(a: &[InterfaceResult], b: &[InterfaceResult], u_tol: f64) -> (usize, usize) {
    let t_tol = 1e-8
        * a.iter()
            .chain(b)
            .flat_map(|r| r.pairs.iter())
            .map(|p| p.traction[1].abs())
            .fold(0.0, f64::max);
    let (mut all, mut degenerate) = (0, 0);
    for (x, y) in a.iter().zip(b) {
        for (p, q) in x.pairs.iter().zip(&y.pairs) {
            if p.status == q.status && p.tangential_status() == q.tangential_status() {
                continue;
            }
            all += 1;
            if u_tol > 0.0 && same_forces(p, q, t_tol, u_tol) {
                degenerate += 1;
            }
        }
    }
    (all, degenerate)
}

/// Whether two differing statuses of one pair solve the LCP with the same forces: closed
/// with no normal force against open with no opening (within `t_tol`, `u_tol`), or stick
/// against slip with the same tractions (at the friction bound).
fn same_forces(p: &PairResult, q: &PairResult, t_tol: f64, u_tol: f64) -> bool {
    let same = |k: usize| (p.traction[k] - q.traction[k]).abs() <= t_tol;
    match (p.status, q.status) {
        (PairStatus::Closed, PairStatus::Closed) => same(0) && same(1),
        (PairStatus::Closed, PairStatus::Open) | (PairStatus::Open, PairStatus::Closed) => {
            let (closed, open) = if p.status == PairStatus::Closed {
                (p, q)
            } else {
                (q, p)
            };
            closed.traction[1].abs() <= t_tol
                && (open.jump[1] - closed.jump[1]).abs() <= u_tol
                && same(0)
        }
        (PairStatus::Open, PairStatus::Open) => false,
    }
}

#[cfg(test)]
mod tests {
    use super::status_differences;
    use crate::solution::{InterfaceResult, PairResult, PairStatus};

    fn pair(status: PairStatus, traction: [f64; 2], jump: [f64; 2], slipping: bool) -> PairResult {
        PairResult {
            status,
            traction,
            jump,
            slipping: Some(slipping),
            slip: jump[0].abs(),
        }
    }

    fn one(p: PairResult) -> Vec<InterfaceResult> {
        vec![InterfaceResult {
            pairs: vec![pair(PairStatus::Closed, [0.0, -4.0], [0.0, 0.0], false), p],
        }]
    }

    /// Touching without pressing, and sticking or slipping at the friction bound with the
    /// same tractions, are degenerate differences; a different traction is not.
    #[test]
    fn degenerate_differences_are_those_with_the_same_forces() {
        let stick = pair(PairStatus::Closed, [-1.0, -2.0], [0.0, 0.0], false);
        let slip = pair(PairStatus::Closed, [-1.0, -2.0], [2.3e-10, 0.0], true);
        assert_eq!(status_differences(&one(stick), &one(slip), 1.0), (1, 1));
        let harder = pair(
            PairStatus::Closed,
            [-1.0 - 1e-6, -2.0],
            [2.3e-10, 0.0],
            true,
        );
        assert_eq!(status_differences(&one(stick), &one(harder), 1.0), (1, 0));
        let touching = pair(PairStatus::Closed, [0.0, 0.0], [0.0, 0.0], false);
        let open = pair(PairStatus::Open, [0.0, 0.0], [0.0, 1e-13], false);
        assert_eq!(status_differences(&one(touching), &one(open), 1.0), (1, 1));
        let gap = pair(PairStatus::Open, [0.0, 0.0], [0.0, 1e-6], false);
        assert_eq!(status_differences(&one(touching), &one(gap), 1.0), (1, 0));
        assert_eq!(status_differences(&one(stick), &one(stick), 1.0), (0, 0));
    }
}
