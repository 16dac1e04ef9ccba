//! The inner problem's dispatch for the outer loop of `Session::solve_step`: which solver
//! runs, the hand-over of a stalled sparse or active-set iteration to the evolutive path, the
//! QP rescue of a blocked pivoting path, the exact states of the statuses Lemke and the QP
//! return, the relaxation of the Tresca fixed point, and the failures of a step
//! (docs/formulation.md §6.4–§6.5).
//!
//! Place in the flow: `contact` (the session's outer loop) → **`inner`** → the solvers.

use super::*;
/// Outer iterations of the Tresca fixed point before a step is reported as not converged.
pub(super) const FRICTION_OUTER_LIMIT: usize = 300;
/// Largest number of rows for the dense coupled LCP (Lemke's tableau is dense).
pub(super) const COUPLED_MAX_ROWS: usize = 3000;
/// At most this many rows that can open for the QP that checks a blocked pivoting path
/// (a dense QP over them).
pub(super) const RESCUE_ROWS: usize = 3000;
/// Outer iterations of the Tresca fixed point after which the exact coupled problem
/// (Klarbring's LCP) is solved to restart it.
pub(super) const FRICTION_COUPLED_AFTER: usize = 10;

/// One inner solve by `method` from the statuses of `st`, within `budget` iterations;
/// the evolutive path records its states in `lp`.
#[allow(clippy::too_many_arguments)]
pub(super) fn inner_solve(
    inner: &Inner,
    cols: &mut OpeningColumns,
    system: &mut Option<sparse::SparseSystem>,
    method: Solver,
    st: &StepState,
    budget: usize,
    lp: &mut StepLoop,
) -> Result<InnerOutcome, InnerFailure> {
    match method {
        Solver::Evolutive => {
            let it0 = lp.iterations_recorded;
            let mut k = it0;
            let first = lp.compact.is_empty();
            let record = lp.record;
            let compact = &mut lp.compact;
            let out = pivoting(
                inner,
                cols,
                (&st.open, &st.sign),
                budget,
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
        Solver::ActiveSet => {
            // With the stick rows of open pairs free until the outer loop ties them, as the
            // evolutive path's first try (`pivoting`), to which a stall hands over.
            let out = active_set::solve(&inner.relaxed(), cols, &st.open, &st.sign, budget);
            Ok(if out.stalled {
                hand_over(inner, cols, out, budget, "active-set iteration cycled")
            } else {
                out
            })
        }
        Solver::Sparse => {
            if system.is_none() {
                let built = sparse::SparseSystem::new(inner.problem)
                    .map_err(|message| InnerFailure::State { message })?;
                *system = Some(built);
            }
            let Some(sys) = system.as_mut() else {
                return Err(InnerFailure::State {
                    message: "the sparse contact system is missing".into(),
                });
            };
            let mut out = sparse::solve(inner, sys, &st.open, &st.sign, budget);
            if out.stalled && inner.n() > EVOLUTIVE_FALLBACK_ROWS {
                // The evolutive path's columns cost the square of the rows: at this size the
                // step ends here, not converged, with the reason in its notes.
                out.notes.push(format!(
                    "the evolutive path does not take over above {EVOLUTIVE_FALLBACK_ROWS} rows \
                     ({} here)",
                    inner.n()
                ));
                return Ok(out);
            }
            Ok(if out.stalled {
                // The evolutive path starts again from the step's statuses, with the whole
                // budget: the sparse iterates may have gone far from a solution.
                out.state.open = st.open.clone();
                out.state.sign = st.sign.clone();
                let budget = budget + out.iterations;
                let mut taken = hand_over(
                    inner,
                    cols,
                    out,
                    budget,
                    "sparse active-set iteration stopped",
                );
                if !taken.converged && !inner.problem.cuts.is_empty() {
                    // Junction cycles cut at whole joints: the evolutive path's opening
                    // stiffness may then not be positive definite (its least-index rule cycles
                    // on the 4 x 5 wall), so where it finds nothing either the step ends
                    // undecided, not at a mechanism.
                    taken.stalled = true;
                    taken.blocked.clear();
                }
                taken
            } else {
                out
            })
        }
        Solver::Lemke => {
            let ((_, pivots), out, finish, resolves) =
                dense_outcome(inner, cols, lemke::solve, |(s, _)| s)?;
            lp.finishing += finish;
            lp.tie_resolves += resolves;
            lp.info = SolverInfo {
                friction_finishing_pivots: Some(lp.finishing),
                pivots: Some(pivots),
                stick_tie_resolves: (lp.tie_resolves > 0).then_some(lp.tie_resolves),
                ..SolverInfo::default()
            };
            Ok(out)
        }
        // The full-row solver solves whole steps (`Session::solve_step_full`).
        Solver::Exact => Err(InnerFailure::State {
            message: "the full-row solver has no inner problem of the eliminated rows".into(),
        }),
        Solver::Qp => {
            let (q, out, finish, resolves) = qp_outcome(inner, cols)?;
            lp.finishing += finish;
            lp.tie_resolves += resolves;
            lp.info = SolverInfo {
                constraints: Some(q.constraints),
                friction_finishing_pivots: Some(lp.finishing),
                iterations: Some(q.iterations),
                objective: Some(q.objective),
                solver_status: Some(q.solver_status),
                stick_tie_resolves: (lp.tie_resolves > 0).then_some(lp.tie_resolves),
                variables: Some(q.variables),
                ..SolverInfo::default()
            };
            Ok(out)
        }
    }
}

/// Lemke's or the QP's outcome (`solve` on a dense form, `statuses` of its result): the
/// statuses of the inner problem with the stick rows of open pairs free until the outer loop
/// ties them (the LCP of §6.2, as these solvers always posed it), their state computed
/// exactly. Where that fails — no solution, or statuses whose state is not one (a pair that
/// closes with its stick row free can leave a body free: a block that starts above a stick
/// joint) — and stick rows tie on closing, the stick law from the moment a pair closes by
/// the fixed point on the ties (`Inner::dense_with_ties`). Returns the solver's result, the
/// outcome, the pivots that finished its friction rows and the dense solves made for the
/// ties.
fn dense_outcome<T>(
    inner: &Inner,
    cols: &mut OpeningColumns,
    solve: impl Fn(&Inner, &mut OpeningColumns) -> Result<T, InnerFailure>,
    statuses: impl Fn(&T) -> &Statuses,
) -> Result<(T, InnerOutcome, usize, usize), InnerFailure> {
    let relaxed = inner.relaxed();
    let first = match solve(&relaxed, cols) {
        Ok(t) => {
            let (out, finish) = exact_state(&relaxed, cols, statuses(&t));
            if out.converged || !inner.has_ties() {
                return Ok((t, out, finish, 0));
            }
            Ok(t)
        }
        Err(e) if !inner.has_ties() => return Err(e),
        Err(e) => Err(e.to_string()),
    };
    let first = first.as_ref().map(&statuses).map_err(String::as_str);
    let (t, solves) = inner.dense_with_ties(cols, &solve, &statuses, first)?;
    let (out, finish) = exact_state(inner, cols, statuses(&t));
    Ok((t, out, finish, solves))
}

/// The QP's outcome of the inner problem (`dense_outcome`).
fn qp_outcome(
    inner: &Inner,
    cols: &mut OpeningColumns,
) -> Result<(qp::QpOutcome, InnerOutcome, usize, usize), InnerFailure> {
    dense_outcome(
        inner,
        cols,
        |p, c| qp::solve(p, c, inner.tol),
        |q| &q.statuses,
    )
}

/// The evolutive path on the inner problem (the pivoting solvers' path, and every hand-over
/// to it): first with the stick rows of open pairs free until the outer loop ties them (the
/// LCP of §6.2, whose least-index rule terminates where A is positive definite; a stick pair
/// at the contact edge that neither stays open untied nor closed tied is left to the outer
/// loop's edge rule). Where that path stops at a row that cannot switch without leaving a
/// body free and stick rows tie on closing, it runs again from the same statuses with each
/// such row tied as its pair closes (the stick law from the moment a pair closes: a block
/// that starts above a stick joint comes down and is held), and its equilibrium is taken
/// if it finds one. `record` sees the states of both paths.
pub(super) fn pivoting(
    inner: &Inner,
    cols: &mut OpeningColumns,
    (open, sign): (&[bool], &[f64]),
    budget: usize,
    record: &mut dyn FnMut(&InnerState),
) -> InnerOutcome {
    if !inner.has_ties() {
        return evolutive::solve(inner, cols, open, sign, budget, record);
    }
    let out = evolutive::solve(&inner.relaxed(), cols, open, sign, budget, record);
    if out.converged || out.blocked.is_empty() {
        return out;
    }
    let rest = budget.saturating_sub(out.iterations);
    let mut tied = evolutive::solve(inner, cols, open, sign, rest, record);
    if !tied.converged {
        return out;
    }
    let why = if out.notes.is_empty() {
        String::new()
    } else {
        format!(" ({})", out.notes.join("; "))
    };
    let mut notes = vec![format!(
        "with the stick rows of the pairs that closed left free, the evolutive path stopped \
         after {} iterations at {} row(s) that could not switch without leaving a body \
         free{why}; from the same statuses, with each stick row tied as its pair closes, it \
         found an equilibrium",
        out.iterations,
        out.blocked.len(),
    )];
    notes.append(&mut tied.notes);
    tied.notes = notes;
    // The return to the start statuses counts as one iteration (the history numbers it).
    tied.iterations += out.iterations + 1;
    tied
}

/// The active set stalled (a cycle or its iteration limit): the evolutive iteration goes
/// on from where it stopped (the least-index rule after its own cycle terminates).
pub(super) fn hand_over(
    inner: &Inner,
    cols: &mut OpeningColumns,
    stalled: InnerOutcome,
    budget: usize,
    why: &str,
) -> InnerOutcome {
    let mut notes = stalled.notes;
    notes.push(format!(
        "the {why} after {} iterations; continued with the evolutive iteration",
        stalled.iterations
    ));
    let st = &stalled.state;
    let mut out = pivoting(
        inner,
        cols,
        (&st.open, &st.sign),
        budget.saturating_sub(stalled.iterations),
        &mut |_| {},
    );
    out.iterations += stalled.iterations;
    notes.append(&mut out.notes);
    out.notes = notes;
    out
}

/// The pivoting path stops where the row to switch cannot open without leaving a body
/// free; for a positive semidefinite opening stiffness that does not prove that no
/// solution exists (another order of pivots may reach one). The convex QP of the same
/// inner problem decides it: a bounded minimiser, checked exactly from its statuses, is
/// the solution, and the iteration goes on from it; an unbounded QP confirms the
/// mechanism (`outcome` is returned as it is).
pub(super) fn qp_rescue(
    inner: &Inner,
    cols: &mut OpeningColumns,
    method: Solver,
    outcome: InnerOutcome,
    it0: usize,
    lp: &mut StepLoop,
) -> InnerOutcome {
    let rescued = qp_outcome(inner, cols).map(|(_, out, _, _)| out);
    match rescued {
        Ok(rescued) if rescued.converged => {
            let k = it0 + outcome.iterations + 1;
            if method == Solver::Evolutive && lp.record {
                lp.compact
                    .push((k, rescued.state.open.clone(), rescued.state.s.clone()));
            }
            lp.rescues += 1;
            let mut notes = outcome.notes;
            notes.extend(rescued.notes);
            InnerOutcome {
                state: rescued.state,
                iterations: outcome.iterations + 1,
                converged: true,
                notes,
                blocked: Vec::new(),
                stalled: false,
                bound: None,
            }
        }
        _ => outcome,
    }
}

/// One inner solve by `method` (`budget` iterations), and where a pivoting path stops at
/// a row that cannot open, the QP's check of it (`qp_rescue`). A failure comes with the
/// evolutive path's probe from the start statuses (`max_iterations`), which names the
/// mechanism where there is one.
pub(super) fn solve_inner(
    inner: &Inner,
    (cols, sparse): (&mut OpeningColumns, &mut Option<sparse::SparseSystem>),
    method: Solver,
    st: &StepState,
    (budget, max_iterations): (usize, usize),
    lp: &mut StepLoop,
) -> Result<InnerOutcome, (InnerFailure, Box<InnerOutcome>)> {
    let it0 = lp.iterations_recorded;
    match inner_solve(inner, cols, sparse, method, st, budget, lp) {
        Ok(outcome)
            if !outcome.converged
                && !outcome.blocked.is_empty()
                && matches!(method, Solver::Evolutive | Solver::ActiveSet)
                && inner.n() <= RESCUE_ROWS =>
        {
            Ok(qp_rescue(inner, cols, method, outcome, it0, lp))
        }
        Ok(outcome) => Ok(outcome),
        Err(e) => {
            let probe = pivoting(
                inner,
                cols,
                (&st.open, &st.sign),
                max_iterations,
                &mut |_| {},
            );
            Err((e, Box::new(probe)))
        }
    }
}

/// The failure of a friction fixed point that did not settle in `outer` iterations.
pub(super) fn unsettled(outer: usize, load_step: usize, change: f64) -> Error {
    Error::numerical(format!(
        "the friction fixed point (slip bounds μλ_n from the normal forces) did not settle in \
         {outer} outer iterations at load step {}: the last relative change of the bounds was \
         {change:.1e}; use smaller load steps (more values in solve.time or load_factors)",
        load_step + 1,
    ))
}

/// The failure of an inner solve that did not converge, with its notes and the mechanism
/// `hint` (empty, or "; " and the motion).
/// A step whose inner solve failed with `err`.
pub(super) fn failed(method: Solver, load_step: usize, err: &str) -> Error {
    Error::numerical(format!(
        "the contact solver ({}) failed at load step {}: {err}",
        method.name(),
        load_step + 1
    ))
}

pub(super) fn not_converged(
    method: Solver,
    load_step: usize,
    residual: f64,
    notes: &[String],
    hint: &str,
) -> Error {
    Error::numerical(format!(
        "the contact solver ({}) did not converge at load step {} (largest violation \
         {residual:.1e} of its scale){}{hint}",
        method.name(),
        load_step + 1,
        if notes.is_empty() {
            String::new()
        } else {
            format!(": {}", notes.join("; "))
        },
    ))
}

/// Rows above which the evolutive path does not take over where the sparse active set stops
/// (its dense columns would cost about 8 n² bytes and hours).
pub(super) const EVOLUTIVE_FALLBACK_ROWS: usize = 40_000;

/// Outer iterations of the Tresca fixed point taken whole whatever happens; after them, a
/// change of the bounds that does not fall (an oscillating fixed point: large μ, where the
/// slip of one pair moves the normal force of its neighbours) halves the step the new
/// bounds take from the old ones (down to 1/64), and only a run of changes that each halve
/// doubles it again (`RELAX_FALLS`). The settled bounds are the same fixed point.
pub(super) const RELAX_AFTER: usize = 20;

/// Changes in a row, each at most half the last, after which the step doubles. One such
/// change is no sign of convergence: a fixed point that cycles between two statuses
/// halves its change right after the step halved, and doubling the step then brings the
/// cycle back (μ = 100 on a 4 × 5 wall: the change went 1.7e-2, 8.4e-3, 1.7e-2, … for
/// 300 iterations; with 8 it settles in about 160).
const RELAX_FALLS: u32 = 8;

/// The smallest step of the relaxed fixed point.
const RELAX_MIN: f64 = 1.0 / 64.0;

/// Outer iterates with the same statuses that Anderson's acceleration combines.
const ANDERSON_MEMORY: usize = 8;

/// Outer iterations after which the history is kept across changes of status: a fixed point
/// whose statuses keep alternating around a row at the point of opening never gathers 5
/// iterates of one status, and the map of the bounds is continuous (piecewise affine), so
/// the iterates of both statuses serve (the 4 × 5 wall with μ = 1000 at t = 0.5 settles;
/// from the start, t = 0.625 did not; after 60 or 100 both do, after 150 not t = 0.5).
const ANDERSON_ACROSS_AFTER: usize = 100;

/// Iterates in a row with the same statuses before Anderson's steps begin: where the fixed
/// point lies at a change of status (a row at the point of opening), the affine map of one
/// status extrapolates past it, and damped steps must have settled the statuses first
/// (3 and 5 measured on the 4 × 5 wall: μ = 100 at t = 0.5 in 76 and 62 outer iterations).
const ANDERSON_AFTER: usize = 5;

/// The step of the Tresca fixed point. While the statuses stay the same the map from the
/// bounds to the new bounds is affine (the state depends on the bounds of its slipping rows
/// only, linearly), and Anderson's acceleration over the iterates of those statuses reaches
/// its fixed point in about as many iterations as rows slip (it is GMRES on the affine
/// map; the damped steps alone contract by 1 − ω per iteration, ω down to 1/64: hundreds of
/// iterations for μ = 10³); a damped step from the halving rule is taken otherwise.
pub(super) struct Relaxation {
    weight: f64,
    last_change: f64,
    /// Changes in a row that fell to half of the last or less.
    falls: u32,
    /// The statuses of the iterates in `xs`, `fs`.
    key: Vec<i8>,
    /// Bounds g_i and residuals F(g_i) − g_i of the last iterates with the statuses `key`.
    xs: Vec<Vec<f64>>,
    fs: Vec<Vec<f64>>,
}

impl Relaxation {
    pub(super) fn new() -> Self {
        Relaxation {
            weight: 1.0,
            last_change: f64::INFINITY,
            falls: 0,
            key: Vec::new(),
            xs: Vec::new(),
            fs: Vec::new(),
        }
    }

    pub(super) fn update(&mut self, outer: usize, change: f64) {
        if outer > RELAX_AFTER {
            if change >= 0.95 * self.last_change {
                self.weight = (0.5 * self.weight).max(RELAX_MIN);
                self.falls = 0;
            } else if change <= 0.5 * self.last_change {
                self.falls += 1;
                if self.falls >= RELAX_FALLS {
                    self.weight = (2.0 * self.weight).min(1.0);
                    self.falls = 0;
                }
            }
        }
        self.last_change = change;
    }

    /// The next slip bounds from the old ones and those of the new normal forces, for an
    /// iterate with the statuses `key` at outer iteration `outer`.
    pub(super) fn next(
        &mut self,
        outer: usize,
        key: Vec<i8>,
        old: &[f64],
        new: Vec<f64>,
    ) -> Vec<f64> {
        if outer <= RELAX_AFTER || old.len() != new.len() || old.iter().any(|g| !g.is_finite()) {
            return self.apply(old, new);
        }
        if key != self.key && outer <= ANDERSON_ACROSS_AFTER {
            self.key = key;
            self.xs.clear();
            self.fs.clear();
        }
        let f: Vec<f64> = new.iter().zip(old).map(|(y, x)| y - x).collect();
        self.xs.push(old.to_vec());
        self.fs.push(f);
        if self.xs.len() > ANDERSON_MEMORY + 1 {
            self.xs.remove(0);
            self.fs.remove(0);
        }
        if self.xs.len() < ANDERSON_AFTER {
            return self.apply(old, new);
        }
        match anderson(&self.xs, &self.fs) {
            Some(g) => g,
            None => self.apply(old, new),
        }
    }

    /// The next slip bounds from the old ones and those of the new normal forces.
    pub(super) fn apply(&self, old: &[f64], new: Vec<f64>) -> Vec<f64> {
        if self.weight >= 1.0 || old.len() != new.len() {
            return new;
        }
        let w = self.weight;
        old.iter()
            .zip(new)
            .map(|(&x, y)| if x.is_finite() { x + w * (y - x) } else { y })
            .collect()
    }
}

/// Anderson's step from the iterates `xs` and their residuals `fs` (oldest first; at least
/// two): γ minimises |f_m − ΔF γ| over the differences of consecutive residuals, and the
/// next iterate is x_m + f_m − (ΔX + ΔF) γ, with bounds kept ≥ 0. None with one iterate or
/// where the differences are degenerate.
fn anderson(xs: &[Vec<f64>], fs: &[Vec<f64>]) -> Option<Vec<f64>> {
    let m = xs.len().checked_sub(1).filter(|&m| m > 0)?;
    let n = xs[m].len();
    let diff =
        |v: &[Vec<f64>], j: usize| -> Vec<f64> { (0..n).map(|k| v[j + 1][k] - v[j][k]).collect() };
    let df: Vec<Vec<f64>> = (0..m).map(|j| diff(fs, j)).collect();
    let dx: Vec<Vec<f64>> = (0..m).map(|j| diff(xs, j)).collect();
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    // The normal equations (ΔFᵀΔF) γ = ΔFᵀ f_m, m ≤ ANDERSON_MEMORY.
    let mut a = faer::Mat::<f64>::from_fn(m, m, |i, j| dot(&df[i], &df[j]));
    let trace: f64 = (0..m).map(|i| a[(i, i)]).sum();
    if trace.is_nan() || trace <= 0.0 {
        return None;
    }
    for i in 0..m {
        a[(i, i)] += 1e-12 * trace;
    }
    let rhs = faer::Mat::<f64>::from_fn(m, 1, |i, _| dot(&df[i], &fs[m]));
    let gamma = faer::linalg::solvers::Solve::solve(&a.as_ref().llt(faer::Side::Lower).ok()?, &rhs);
    let next: Vec<f64> = (0..n)
        .map(|k| {
            let c: f64 = (0..m).map(|j| (dx[j][k] + df[j][k]) * gamma[(j, 0)]).sum();
            (xs[m][k] + fs[m][k] - c).max(0.0)
        })
        .collect();
    next.iter().all(|g| g.is_finite()).then_some(next)
}

/// Every row closed, nothing open: the state reported when no inner solve finished.
pub(super) fn all_closed_state(n: usize) -> InnerState {
    InnerState {
        open: vec![false; n],
        sign: vec![0.0; n],
        s: vec![0.0; n],
        lambda: vec![0.0; n],
    }
}

/// The exact state of the statuses `open` found by a solver that does not pivot (Lemke, QP).
///
/// With friction, a row at the stick/slip threshold whose slip increment is below the
/// solver's precision can come out with the wrong slip direction (where most pairs slip, the
/// slipping block of A is nearly singular and amplifies the last digits): such friction rows
/// only are finished by the pivoting iteration from the solver's statuses, and the number of
/// pivots is returned (0 when the statuses were exact).
pub(super) fn exact_state(
    inner: &Inner,
    cols: &mut OpeningColumns,
    statuses: &Statuses,
) -> (InnerOutcome, usize) {
    let (o, refused) = inner.factor(cols, &statuses.open);
    let state = inner.state(cols, &o, &statuses.sign);
    let violations = inner.violations(&state);
    if refused.is_empty()
        && !violations.is_empty()
        && violations.iter().all(|v| inner.is_friction(v.row))
    {
        let out = evolutive::solve(inner, cols, &state.open, &state.sign, 100, &mut |_| {});
        let pivots = out.iterations;
        return (out, pivots);
    }
    let converged = refused.is_empty() && violations.is_empty();
    let mut notes = Vec::new();
    if !refused.is_empty() {
        notes.push(format!(
            "{} pair(s) found open would leave a body free",
            refused.len()
        ));
    }
    (
        InnerOutcome {
            state,
            iterations: 0,
            converged,
            notes,
            blocked: refused,
            stalled: false,
            bound: None,
        },
        0,
    )
}
