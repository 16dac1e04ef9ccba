//! The inner complementarity problem of one outer iteration, shared by every solver.
//!
//! Place in the flow: `problem` → **`lcp`** → `evolutive`, `active_set`, `lemke`, `qp`.
//! With the load factor, the cohesion left at each pair and the tangential ties of `stick`
//! pairs fixed (the outer loop in `contact` updates them), the problem is the LCP of
//! `problem` over the unilateral normal rows, plus *free* rows (stick rows whose pair is not
//! tied: opening unconstrained, force zero):
//!
//! ```text
//!   λ = λ⁰ + A (s − s̄);   normal rows: s ≥ 0, λ ≥ 0, sλ = 0;   free rows: λ = 0
//! ```
//!
//! **Friction rows** (the tangential rows of `tangential = "friction"` pairs) carry a Tresca
//! problem with the slip bound g_r = μ_r λ_n fixed by the outer loop (from the normal force of
//! the last outer iterate), so the inner problem keeps the symmetric A: with the slip
//! increment Δs_r = s_r − s̄_r from the accumulated slip s̄_r of the previous load step,
//!
//! ```text
//!   stick: Δs_r = 0, |λ_r| ≤ g_r;   slip+: Δs_r ≥ 0, λ_r = −g_r;   slip−: Δs_r ≤ 0, λ_r = g_r
//! ```
//!
//! i.e. the optimality system of `min ½ΔsᵀAΔs + λ⁰ᵀΔs + Σ g_r |Δs_r|` (s ≥ 0 on normal rows):
//! unique for positive definite A. A friction row whose bound is zero (its pair open or
//! without compression) is free. Slipping rows are "open" rows with a target force −σ g_r.
//!
//! **Stick from the moment a pair closes.** The free stick row of an open pair may tie as
//! its pair closes within the inner problem (`tie_on_close`: free while the pair's normal
//! row is open, tied once it closes), which a body that starts open above a stick joint
//! needs (with its stick rows free it is left free as it comes down). That is no LCP over
//! fixed variables: the pivoting solvers switch the pair's two rows together, and Lemke and
//! the QP iterate on which rows they tie (`Inner::dense_with_ties`).

use std::collections::HashMap;

use crate::contact::problem::{Base, Opening, Problem, RowKind};

/// What a pivoting solver (`evolutive`, `active_set`) returns, and what the statuses of a
/// solver that does not pivot (`lemke`, `qp`) become once their state is computed exactly.
pub struct InnerOutcome {
    pub state: InnerState,
    pub iterations: usize,
    pub converged: bool,
    pub notes: Vec<String>,
    /// Violated rows that could not open without leaving a body free (a mechanism).
    pub blocked: Vec<usize>,
    /// The solver stopped without a verdict (the active set cycled or ran out of
    /// iterations): the driver goes on from `state` with the evolutive iteration.
    pub stalled: bool,
    /// The slip bounds of `state` where the solver followed Coulomb's law
    /// ([`Inner::coulomb`]) and so changed them.
    pub bound: Option<Vec<f64>>,
}

impl InnerOutcome {
    /// A solution found after `iterations`.
    pub fn converged(state: InnerState, iterations: usize) -> Self {
        InnerOutcome {
            state,
            iterations,
            converged: true,
            notes: Vec::new(),
            blocked: Vec::new(),
            stalled: false,
            bound: None,
        }
    }

    /// Not converged after `iterations`, with the rows that could not switch (`blocked`,
    /// a mechanism where not empty) and why in `notes`: a verdict, no hand-over.
    pub fn failed(
        state: InnerState,
        iterations: usize,
        notes: Vec<String>,
        blocked: Vec<usize>,
    ) -> Self {
        InnerOutcome {
            state,
            iterations,
            converged: false,
            notes,
            blocked,
            stalled: false,
            bound: None,
        }
    }

    /// No verdict after `iterations` (the driver hands over to the evolutive path).
    pub fn stalled(state: InnerState, iterations: usize, notes: Vec<String>) -> Self {
        InnerOutcome {
            state,
            iterations,
            converged: false,
            notes,
            blocked: Vec::new(),
            stalled: true,
            bound: None,
        }
    }
}

/// The statuses a solver that does not pivot found: open rows and slip directions.
pub struct Statuses {
    pub open: Vec<bool>,
    pub sign: Vec<f64>,
}

/// Why a solver that does not pivot found no statuses.
#[derive(Debug, Clone, PartialEq)]
pub enum InnerFailure {
    /// The free tangential openings leave a body free (no dense form exists).
    LeavesBodyFree,
    /// Lemke's method ended on a secondary ray: no equilibrium exists.
    SecondaryRay { pivots: usize },
    /// Lemke's method reached its pivot limit.
    PivotLimit { pivots: usize },
    /// The QP is unbounded (dual infeasible): no equilibrium exists.
    Unbounded,
    /// The QP could not be set up or ended with another status.
    Qp { message: String },
    /// Lemke or the QP found no statuses whose closed pairs are those whose stick rows it
    /// tied (`Inner::dense_with_ties`): `tried` says what each start gave. A dense LCP
    /// poses each row tied or free before it solves, so this alone proves nothing about the
    /// equilibrium.
    StickClosure { tried: String },
    /// The state of the statuses found could not be computed.
    State { message: String },
}

impl std::fmt::Display for InnerFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            InnerFailure::LeavesBodyFree => write!(
                f,
                "the free tangential openings leave a body free: no equilibrium exists"
            ),
            InnerFailure::SecondaryRay { pivots } => write!(
                f,
                "Lemke's method ended on a secondary ray after {pivots} pivots: no equilibrium \
                 exists (a mechanism)"
            ),
            InnerFailure::PivotLimit { pivots } => {
                write!(
                    f,
                    "Lemke's method reached its pivot limit ({pivots} pivots)"
                )
            }
            InnerFailure::Unbounded => write!(
                f,
                "the QP is unbounded: no equilibrium exists (a body can move freely under its \
                 loads)"
            ),
            InnerFailure::Qp { message } | InnerFailure::State { message } => {
                write!(f, "{message}")
            }
            InnerFailure::StickClosure { tried } => write!(
                f,
                "not applicable to this step: the dense LCP found no statuses whose closed \
                 pairs are those whose stick rows it tied ({tried}); a dense LCP poses every \
                 row tied or free before it solves and cannot tie a stick row as its pair \
                 closes, so this alone proves nothing about the equilibrium"
            ),
        }
    }
}

/// Columns of the opening stiffness, computed once per row and kept for the whole run.
#[derive(Default)]
pub struct OpeningColumns {
    cols: HashMap<usize, Vec<f64>>,
    /// The factor of A_OO of the last status solved: the next solve starts from it and
    /// removes or appends the rows by which its status differs (the outer iterations of
    /// the friction fixed point and the active set's iterations change few rows).
    last: Option<Opening>,
}

impl OpeningColumns {
    /// Keeps `o` as the factor the next [`Inner::factor`] starts from.
    pub fn keep(&mut self, o: &Opening) {
        self.last = Some(o.clone());
    }
    pub fn get(&mut self, problem: &Problem, j: usize) -> &[f64] {
        self.cols.entry(j).or_insert_with(|| problem.column(j))
    }
    /// Computes the columns of `rows` not yet computed, in parallel (each is a sparse solve
    /// and a product with every body's operator, independent of the others; the values do
    /// not depend on the order).
    pub(crate) fn ensure(&mut self, problem: &Problem, rows: &[usize]) {
        use rayon::prelude::*;
        let mut missing: Vec<usize> = rows
            .iter()
            .copied()
            .filter(|r| !self.cols.contains_key(r))
            .collect();
        missing.sort_unstable();
        missing.dedup();
        if missing.len() < 2 {
            for r in missing {
                self.get(problem, r);
            }
            return;
        }
        let computed: Vec<(usize, Vec<f64>)> = missing
            .par_iter()
            .map(|&r| (r, problem.column(r)))
            .collect();
        self.cols.extend(computed);
    }
    pub fn computed(&self) -> usize {
        self.cols.len()
    }
    /// Column j if it has been computed.
    pub(crate) fn peek(&self, j: usize) -> Option<&[f64]> {
        self.cols.get(&j).map(|c| c.as_slice())
    }
}

/// The change of the slip bounds below which they are settled (the Tresca fixed point and
/// Coulomb's law within an inner problem).
pub(crate) const BOUNDS_SETTLED: f64 = 1e-10;

/// The relative change of the slip bounds, over the largest finite bound (1 from the tied
/// first iteration).
pub(crate) fn bound_change(old: &[f64], new: &[f64]) -> f64 {
    let scale = old
        .iter()
        .chain(new)
        .filter(|v| v.is_finite())
        .fold(0.0f64, |a, v| a.max(v.abs()))
        .max(f64::MIN_POSITIVE);
    old.iter().zip(new).fold(0.0f64, |a, (x, y)| {
        a.max(if x.is_finite() {
            (x - y).abs() / scale
        } else {
            1.0
        })
    })
}

/// The inner problem.
#[derive(Clone)]
pub struct Inner<'a> {
    pub problem: &'a Problem,
    pub base: &'a Base,
    /// Rows that are open whatever happens (untied stick rows, friction rows without a
    /// slip bound).
    pub free: Vec<bool>,
    /// Free stick rows whose pair is open: tied once the pair's normal row closes, within
    /// the inner problem. The sparse solver poses it so; the pivoting solvers switch the
    /// pair's two rows together and Lemke and the QP tie the rows of the pairs they close
    /// and solve again, each where the problem without it ([`Inner::relaxed`]) fails.
    pub tie_on_close: Vec<bool>,
    /// Slip bound g_r = μ_r λ_n of each friction row (0 on other rows).
    pub bound: Vec<f64>,
    /// Relative tolerance of the violation checks.
    pub tol: f64,
    /// Coulomb's law within the inner problem (empty: the bounds are fixed, Tresca): for
    /// each friction row whose pair's normal row can open, that row and μ. A solver that
    /// follows it takes each iterate's slip bounds from the normal forces of the last
    /// ([`Inner::coulomb_bounds`]).
    pub coulomb: Vec<Option<(usize, f64)>>,
    /// Coulomb's law in the solve itself (semismooth Newton): a slipping Coulomb row's force
    /// is −σ μ (λ_n − c) of its pair's normal force in the same solve, not a bound from the
    /// last iterate ([`Inner::coupled_form`]).
    pub coupled: bool,
}

/// A solution of the inner problem for one open set.
#[derive(Debug, Clone)]
pub struct InnerState {
    /// Open rows (normal rows that are open, slipping friction rows, and the free rows).
    pub open: Vec<bool>,
    /// Slip direction σ = ±1 of each slipping friction row (0 elsewhere).
    pub sign: Vec<f64>,
    /// Opening of every row (zero on closed normal rows; the accumulated slip s̄ on sticking
    /// friction rows).
    pub s: Vec<f64>,
    /// Force of every row (λ; zero on open rows up to roundoff).
    pub lambda: Vec<f64>,
}

/// A switch of one row.
#[derive(Debug, Clone, Copy)]
pub struct Violation {
    pub row: usize,
    /// Relative size.
    pub size: f64,
    /// The slip direction a sticking friction row takes (0 for other switches).
    pub sign: f64,
}

/// The status of every row in one comparable key: 0 closed/stick, 1 open, ±2 slipping.
pub(crate) fn status_key(st: &InnerState) -> Vec<i8> {
    st.open
        .iter()
        .zip(&st.sign)
        .map(|(&o, &g)| match (o, g) {
            (false, _) => 0,
            (true, g) if g > 0.0 => 2,
            (true, g) if g < 0.0 => -2,
            _ => 1,
        })
        .collect()
}

impl<'a> Inner<'a> {
    pub fn n(&self) -> usize {
        self.problem.n_open_rows
    }

    pub(crate) fn is_normal(&self, r: usize) -> bool {
        self.problem.rows[r].kind == RowKind::Normal
    }

    /// The inner problem on `problem` and `base` with its free and tie-on-close rows
    /// (`rows`), slip bounds and tolerance.
    pub fn new(
        problem: &'a Problem,
        base: &'a Base,
        (free, tie_on_close): (Vec<bool>, Vec<bool>),
        bound: Vec<f64>,
        tol: f64,
    ) -> Inner<'a> {
        Inner {
            problem,
            base,
            free,
            tie_on_close,
            bound,
            tol,
            coulomb: Vec::new(),
            coupled: false,
        }
    }

    /// The same problem with its friction rows' normal rows and μ (`coulomb`), for a
    /// solver that follows Coulomb's law within it ([`Inner::coulomb_form`]).
    pub(crate) fn with_coulomb(mut self, coulomb: Vec<Option<(usize, f64)>>) -> Inner<'a> {
        self.coulomb = coulomb;
        self
    }

    /// The problem under Coulomb's law: its friction rows are no longer free where their
    /// bound is zero (an open pair's row slips without force, as any row whose bound is
    /// zero), and their bounds follow the normal forces ([`Inner::coulomb_bounds`]).
    pub(crate) fn coulomb_form(&self) -> Inner<'a> {
        let mut c = self.clone();
        for (r, m) in self.coulomb.iter().enumerate() {
            if m.is_some() {
                c.free[r] = false;
            }
        }
        c
    }

    /// The problem under Coulomb's law with each slipping row's force tied to its pair's
    /// normal force within the solve ([`Inner::coupled`]).
    pub fn coupled_form(&self) -> Inner<'a> {
        Inner {
            coupled: true,
            ..self.coulomb_form()
        }
    }

    /// The Coulomb coupling of row `r` in the status `open`: its pair's closed normal row and
    /// μ, where `r` slips under Coulomb's law within the solve ([`Inner::coupled`]).
    pub(crate) fn coupling(&self, r: usize, open: &[bool]) -> Option<(usize, f64)> {
        if !self.coupled || !open[r] || !self.is_friction(r) {
            return None;
        }
        self.coulomb
            .get(r)
            .copied()
            .flatten()
            .filter(|&(k, _)| !open[k])
    }

    /// Whether the Coulomb row `r`'s pair's normal row is open in `open`.
    pub(crate) fn pair_open(&self, r: usize, open: &[bool]) -> bool {
        matches!(self.coulomb.get(r), Some(Some((k, _))) if open[*k])
    }

    /// The slip bounds μ·max(λ_n − c, 0) of the Coulomb rows from the normal forces of
    /// `st` (zero where the pair's normal row is open), the other rows' as they are; None
    /// without Coulomb rows.
    pub fn coulomb_bounds(&self, st: &InnerState) -> Option<Vec<f64>> {
        if self.coulomb.is_empty() {
            return None;
        }
        let mut b = self.bound.clone();
        for (r, c) in self.coulomb.iter().enumerate() {
            if let Some((k, mu)) = *c {
                b[r] = if st.open[k] {
                    0.0
                } else {
                    mu * (st.lambda[k] - self.base.cohesion[k]).max(0.0)
                };
            }
        }
        Some(b)
    }

    /// Whether a stick row ties as its pair closes in this problem.
    pub(crate) fn has_ties(&self) -> bool {
        self.tie_on_close.iter().any(|&t| t)
    }

    /// The same problem with the stick rows of open pairs free until the outer loop ties
    /// them (no row ties within it): the LCP of `problem`, whose solution the pivoting
    /// solvers reach wherever A is positive definite.
    pub fn relaxed(&self) -> Inner<'a> {
        self.with_free(self.free.clone())
    }

    /// The same problem with the rows `free` free and no row that ties within it.
    fn with_free(&self, free: Vec<bool>) -> Inner<'a> {
        Inner::new(
            self.problem,
            self.base,
            (free, vec![false; self.n()]),
            self.bound.clone(),
            self.tol,
        )
    }

    /// The normal row of the pair whose stick row `r` ties as that pair closes
    /// (`tie_on_close`); None for every other row.
    pub(crate) fn tied_to(&self, r: usize) -> Option<usize> {
        if !self.tie_on_close[r] {
            return None;
        }
        let row = &self.problem.rows[r];
        self.problem.row_of[row.iface][row.pair][1].filter(|&q| q < self.n())
    }

    /// The stick row that ties as the normal row `q` closes, if any.
    pub(crate) fn tie_of(&self, q: usize) -> Option<usize> {
        let row = &self.problem.rows[q];
        if row.kind != RowKind::Normal {
            return None;
        }
        self.problem.row_of[row.iface][row.pair][0]
            .filter(|&r| r < self.n() && self.tied_to(r) == Some(q))
    }

    /// The open rows of the status whose normal rows are `open`: free rows open, and a stick
    /// row that ties on closing open exactly where its pair's normal row is.
    pub fn follow(&self, open: &[bool]) -> Vec<bool> {
        (0..self.n())
            .map(|r| match self.tied_to(r) {
                Some(q) => open[q],
                None => open[r] || self.free[r],
            })
            .collect()
    }

    /// Opens row `r` in `o`, and with it the stick row that ties as `r`'s pair closes (the
    /// pair's two rows switch together). False, with `o` unchanged, where either would
    /// leave a body free.
    pub(crate) fn open_row(&self, cols: &mut OpeningColumns, o: &mut Opening, r: usize) -> bool {
        if !o.append(r, cols.get(self.problem, r)) {
            return false;
        }
        if let Some(t) = self.tie_of(r) {
            if !o.append(t, cols.get(self.problem, t)) {
                o.remove(r);
                return false;
            }
        }
        true
    }

    /// Closes row `r` in `o`, and with it the stick row that ties as `r`'s pair closes.
    pub(crate) fn close_row(&self, o: &mut Opening, r: usize) {
        o.remove(r);
        if let Some(t) = self.tie_of(r) {
            o.remove(t);
        }
    }

    /// The open rows of a start status: a friction row that slips without a direction (a
    /// row that was free) starts sticking.
    pub(crate) fn start_open(&self, open: &[bool], sign: &[f64]) -> Vec<bool> {
        (0..self.n())
            .map(|r| open[r] && !(self.is_friction(r) && sign[r] == 0.0))
            .collect()
    }

    /// A friction row with a positive slip bound (not free).
    pub(crate) fn is_friction(&self, r: usize) -> bool {
        self.problem.rows[r].kind == RowKind::Friction && !self.free[r]
    }

    /// The force a row holds while open: −σ g on slipping friction rows, 0 elsewhere.
    fn target(&self, r: usize, sign: &[f64]) -> f64 {
        if self.is_friction(r) {
            -sign[r] * self.bound[r]
        } else {
            0.0
        }
    }

    /// Builds the factor of A_OO for the free rows and the normal rows `open` (in order of
    /// decreasing initial gap, so that a row whose opening would leave a body free — the
    /// smallest gaps come last — stays closed). A stick row that ties as its pair closes is
    /// free where its pair's normal row is in `open` (appended with the free rows) and tied
    /// elsewhere; a pair whose two rows cannot both open stays closed, its stick row tied.
    /// Returns the factor and the rows refused (normal rows for such pairs).
    pub fn factor(&self, cols: &mut OpeningColumns, open: &[bool]) -> (Opening, Vec<usize>) {
        let mut o = Opening::default();
        let mut refused = Vec::new();
        let mut order: Vec<usize> = (0..self.n())
            .filter(|&r| self.free[r] && self.tied_to(r).is_none_or(|q| open[q]))
            .collect();
        let mut normal: Vec<usize> = (0..self.n())
            .filter(|&r| !self.free[r] && open[r])
            .collect();
        normal.sort_by(|&a, &b| {
            self.problem.rows[b]
                .gap
                .total_cmp(&self.problem.rows[a].gap)
                .then(a.cmp(&b))
        });
        order.extend(normal);
        // From the last factor, when few rows differ and none is refused (a refusal depends
        // on the order of the appends: then the factor is built afresh in `order`).
        if let Some(mut prev) = cols.last.take() {
            let want: std::collections::HashSet<usize> = order.iter().copied().collect();
            let have: std::collections::HashSet<usize> = prev.rows.iter().copied().collect();
            let remove: Vec<usize> = prev
                .rows
                .iter()
                .copied()
                .filter(|r| !want.contains(r))
                .collect();
            let add: Vec<usize> = order
                .iter()
                .copied()
                .filter(|r| !have.contains(r))
                .collect();
            if remove.len() + add.len() < prev.len() / 2 {
                for r in remove {
                    prev.remove(r);
                }
                cols.ensure(self.problem, &add);
                let mut ok = true;
                for r in add {
                    let col = cols.get(self.problem, r);
                    if !prev.append(r, col) {
                        ok = false;
                        break;
                    }
                }
                if ok {
                    cols.keep(&prev);
                    return (prev, refused);
                }
            }
        }
        cols.ensure(self.problem, &order);
        // Normal rows whose pair stays closed because its stick row cannot be free.
        let mut closed = vec![false; self.n()];
        for r in order {
            if closed[r] {
                continue;
            }
            let col = cols.get(self.problem, r);
            if o.append(r, col) {
                continue;
            }
            match self.tied_to(r) {
                Some(q) => {
                    closed[q] = true;
                    refused.push(q);
                }
                None => {
                    refused.push(r);
                    if let Some(t) = self.tie_of(r) {
                        o.remove(t);
                    }
                }
            }
        }
        cols.keep(&o);
        (o, refused)
    }

    /// Openings and forces of the status whose factor is `o`, with the slip directions
    /// `sign` of its friction rows.
    pub fn state(&self, cols: &mut OpeningColumns, o: &Opening, sign: &[f64]) -> InnerState {
        let n = self.n();
        let rhs: Vec<f64> = o
            .rows
            .iter()
            .map(|&r| self.target(r, sign) - self.base.lambda0[r])
            .collect();
        let so = o.solve(&rhs);
        let mut s = self.base.offset.clone();
        let mut open = vec![false; n];
        let mut sg = vec![0.0; n];
        let mut lambda = self.base.lambda0.clone();
        for (&r, &sr) in o.rows.iter().zip(&so) {
            s[r] += sr;
            open[r] = true;
            if self.is_friction(r) {
                sg[r] = if sign[r] < 0.0 { -1.0 } else { 1.0 };
            }
            cols.get(self.problem, r);
        }
        // λ = λ⁰ + A_{:,O} s_O: the largest piece of a switch on walls of hundreds of
        // bricks (16 100 rows × a thousand open ones), in parallel over blocks of rows; each
        // entry sums the columns in the same order whatever the blocks.
        let terms: Vec<(&[f64], f64)> = o
            .rows
            .iter()
            .zip(&so)
            .filter_map(|(&r, &sr)| cols.peek(r).map(|c| (c, sr)))
            .collect();
        let add = |off: usize, chunk: &mut [f64]| {
            let len = chunk.len();
            for (col, sr) in &terms {
                for (l, c) in chunk.iter_mut().zip(&col[off..off + len]) {
                    *l += c * sr;
                }
            }
        };
        const BLOCK: usize = 2048;
        if n * terms.len() > 1 << 20 {
            use rayon::prelude::*;
            lambda
                .par_chunks_mut(BLOCK)
                .enumerate()
                .for_each(|(k, chunk)| add(k * BLOCK, chunk));
        } else {
            add(0, &mut lambda);
        }
        for &r in &o.rows {
            lambda[r] = self.target(r, &sg);
        }
        InnerState {
            open,
            sign: sg,
            s,
            lambda,
        }
    }

    /// Scales of forces and openings for relative checks.
    pub(crate) fn scales(&self, st: &InnerState) -> (f64, f64) {
        let f = self
            .base
            .lambda0
            .iter()
            .chain(&st.lambda)
            .fold(0.0f64, |a, v| a.max(v.abs()));
        let s = st.s.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let v = self.base.v0.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        (f.max(f64::MIN_POSITIVE), s.max(v).max(f64::MIN_POSITIVE))
    }

    /// Violated rows, largest first: tension beyond the cohesion on a closed normal row,
    /// interpenetration on an open one; a sticking friction row whose force exceeds its
    /// bound, a slipping one whose slip increment runs against its direction.
    pub fn violations(&self, st: &InnerState) -> Vec<Violation> {
        let (fs, ss) = self.scales(st);
        let mut v = Vec::new();
        for r in 0..self.n() {
            let (size, sign) = if self.is_friction(r) {
                if self.coupled && st.open[r] && self.pair_open(r, &st.open) {
                    // An open pair's friction row slips freely, either way.
                    continue;
                }
                let ds = st.s[r] - self.base.offset[r];
                if st.open[r] {
                    (-st.sign[r] * ds / ss, 0.0)
                } else {
                    let l = st.lambda[r];
                    // λ > g: the row slips backwards (σ = −1, λ = g), and vice versa.
                    ((l.abs() - self.bound[r]) / fs, -l.signum())
                }
            } else if self.is_normal(r) && !self.free[r] {
                let size = if st.open[r] {
                    -st.s[r] / ss
                } else {
                    -st.lambda[r] / fs
                };
                (size, 0.0)
            } else {
                continue;
            };
            if size > self.tol {
                v.push(Violation { row: r, size, sign });
            }
        }
        v.sort_by(|a, b| b.size.total_cmp(&a.size).then(a.row.cmp(&b.row)));
        v
    }

    /// Complementarity residual `max(−λ, −s, λ·s)` over the normal rows, and over the
    /// friction rows the excess of |λ| over its bound and the slip against its force,
    /// relative.
    pub fn residual(&self, st: &InnerState) -> f64 {
        let (fs, ss) = self.scales(st);
        let mut r = 0.0f64;
        for j in 0..self.n() {
            if self.is_friction(j) {
                let (l, ds) = (st.lambda[j] / fs, (st.s[j] - self.base.offset[j]) / ss);
                let g = self.bound[j] / fs;
                // Dissipation is λ·Δs = −g|Δs| exactly when the row slips against its force.
                r = r.max(l.abs() - g);
                if g.is_finite() {
                    r = r.max((l * ds + g * ds.abs()).abs());
                }
                continue;
            }
            if !self.is_normal(j) || self.free[j] {
                continue;
            }
            let (l, s) = (st.lambda[j] / fs, st.s[j] / ss);
            r = r.max(-l).max(-s).max(l.max(0.0) * s.max(0.0));
        }
        r
    }

    /// The dense LCP `w = M z + q, z ≥ 0, w ≥ 0, zᵀw = 0` of the inner problem with the free
    /// rows eliminated (for Lemke and the QP, which need every column). Its variables are
    /// the openings of the normal rows and, per friction row, the slip increments
    /// `p, m ≥ 0` forwards and backwards (`Δs = p − m`, `w = ±λ + g`):
    /// `M = σσᵀ ∘ (A_NN − A_NF A_FF⁻¹ A_FN)` over the variables' rows with signs σ = ±1, and
    /// `q = σ (λ⁰ − A_NF A_FF⁻¹ λ⁰_F) + g`. M is symmetric positive semidefinite, so the LCP
    /// is the QP `min ½zᵀMz + qᵀz, z ≥ 0`.
    pub fn dense(&self, cols: &mut OpeningColumns) -> Option<Dense> {
        // Friction rows tied without a bound (the first outer iteration) are no variables.
        let normal: Vec<usize> = (0..self.n())
            .filter(|&r| {
                (self.is_normal(r) && !self.free[r])
                    || (self.is_friction(r) && self.bound[r].is_finite())
            })
            .collect();
        // Free rows whose opening would leave a body free stay tied, as in `factor` (the
        // first contact of a body held by friction alone).
        let mut o = Opening::default();
        let mut free = Vec::new();
        let all: Vec<usize> = (0..self.n())
            .filter(|&r| self.free[r] || normal.binary_search(&r).is_ok())
            .collect();
        cols.ensure(self.problem, &all);
        for r in (0..self.n()).filter(|&r| self.free[r]) {
            let col = cols.get(self.problem, r);
            if o.append(r, col) {
                free.push(r);
            }
        }
        let nn = normal.len();
        let mut m = vec![0.0; nn * nn];
        let mut q: Vec<f64> = normal.iter().map(|&r| self.base.lambda0[r]).collect();
        for (b, &rb) in normal.iter().enumerate() {
            let col = cols.get(self.problem, rb);
            for (a, &ra) in normal.iter().enumerate() {
                m[a * nn + b] = col[ra];
            }
        }
        if !free.is_empty() {
            // X = A_FF⁻¹ A_FN column by column, then M −= A_NF X.
            let anf: Vec<Vec<f64>> = free
                .iter()
                .map(|&f| {
                    let col = cols.get(self.problem, f);
                    normal.iter().map(|&r| col[r]).collect()
                })
                .collect();
            let xq = o.solve(
                &free
                    .iter()
                    .map(|&f| self.base.lambda0[f])
                    .collect::<Vec<_>>(),
            );
            for b in 0..nn {
                let rhs: Vec<f64> = (0..free.len()).map(|f| anf[f][b]).collect();
                let x = o.solve(&rhs);
                for a in 0..nn {
                    m[a * nn + b] -= (0..free.len()).map(|f| anf[f][a] * x[f]).sum::<f64>();
                }
            }
            for a in 0..nn {
                q[a] -= (0..free.len()).map(|f| anf[f][a] * xq[f]).sum::<f64>();
            }
        }
        // Expand the friction rows into their two slip variables.
        let mut vars: Vec<(usize, usize, f64)> = Vec::with_capacity(nn);
        for (a, &r) in normal.iter().enumerate() {
            vars.push((a, r, 1.0));
            if self.is_friction(r) {
                vars.push((a, r, -1.0));
            }
        }
        let nv = vars.len();
        let mut mv = vec![0.0; nv * nv];
        let mut qv = vec![0.0; nv];
        for (i, &(a, r, sa)) in vars.iter().enumerate() {
            qv[i] = sa * q[a]
                + if self.is_friction(r) {
                    self.bound[r]
                } else {
                    0.0
                };
            for (j, &(b, _, sb)) in vars.iter().enumerate() {
                mv[i * nv + j] = sa * sb * m[a * nn + b];
            }
        }
        Some(Dense {
            vars: vars.iter().map(|&(_, r, s)| (r, s)).collect(),
            m: mv,
            q: qv,
        })
    }

    /// Lemke's or the QP's statuses (`solve` on a dense form, `statuses` of its outcome)
    /// where stick rows tie as their pairs close (`tie_on_close`). A dense LCP poses each
    /// row tied or free before it solves, so the stick rows that tie on closing are tied
    /// where the last solution closed their pair and free elsewhere, and the problem is
    /// solved again until the pairs closed are those tied: then the statuses solve the
    /// inner problem with the stick law from the moment a pair closes, as the pivoting
    /// solvers do. `relaxed` is the solution of the problem with every such row free (the
    /// first start ties the rows of the pairs it closed), or why there is none; where that
    /// start fails or does not settle, a second start ties them all. Returns the outcome and
    /// the solves made.
    pub(crate) fn dense_with_ties<T>(
        &self,
        cols: &mut OpeningColumns,
        solve: impl Fn(&Inner, &mut OpeningColumns) -> Result<T, InnerFailure>,
        statuses: impl Fn(&T) -> &Statuses,
        relaxed: Result<&Statuses, &str>,
    ) -> Result<(T, usize), InnerFailure> {
        let n = self.n();
        let closing = |open: &[bool]| -> Vec<bool> {
            (0..n)
                .map(|r| self.tied_to(r).is_some_and(|q| !open[q]))
                .collect()
        };
        let all: Vec<bool> = (0..n).map(|r| self.tied_to(r).is_some()).collect();
        let pairs = all.iter().filter(|&&t| t).count();
        let mut tried = Vec::new();
        let mut starts = Vec::new();
        match relaxed {
            Ok(st) => starts.push((
                "the stick rows of the pairs it closed tied",
                closing(&st.open),
            )),
            Err(why) => tried.push(format!(
                "with the stick rows of the {pairs} open pair(s) free: {why}"
            )),
        }
        if starts.first().is_none_or(|(_, t)| *t != all) {
            starts.push(("every such stick row tied", all));
        }
        let mut solves = 0;
        for (start, mut tied) in starts {
            let mut seen = std::collections::HashSet::new();
            let why = loop {
                seen.insert(tied.clone());
                let posed = self.with_free((0..n).map(|r| self.free[r] && !tied[r]).collect());
                solves += 1;
                let out = match solve(&posed, cols) {
                    Ok(out) => out,
                    Err(e) => break e.to_string(),
                };
                let closed = closing(&statuses(&out).open);
                if closed == tied {
                    return Ok((out, solves));
                }
                if seen.contains(&closed) || seen.len() >= TIE_SOLVES {
                    break format!(
                        "the pairs closed and the stick rows tied did not settle in {} solves",
                        seen.len()
                    );
                }
                tied = closed;
            };
            tried.push(format!("from {start}: {why}"));
        }
        Err(InnerFailure::StickClosure {
            tried: tried.join("; "),
        })
    }

    /// The statuses of a solution of the dense LCP: `active[i]` says that variable i is the
    /// positive one of its complementary pair. Returns the open rows and slip directions.
    pub fn statuses(&self, dense: &Dense, active: &[bool]) -> (Vec<bool>, Vec<f64>) {
        let mut open = self.free.clone();
        let mut sign = vec![0.0; self.n()];
        for (&(r, s), &on) in dense.vars.iter().zip(active) {
            if !on {
                continue;
            }
            if self.is_friction(r) {
                // Both directions active only without a bound: then the row is free anyway.
                if open[r] {
                    open[r] = false;
                    sign[r] = 0.0;
                } else {
                    open[r] = true;
                    sign[r] = s;
                }
            } else {
                open[r] = true;
            }
        }
        (open, sign)
    }
}

/// Solves of the dense LCP from one start of `Inner::dense_with_ties` before it gives up.
const TIE_SOLVES: usize = 20;

/// The dense LCP of an inner problem: variables (row, sign) and M (row-major), q.
pub struct Dense {
    pub vars: Vec<(usize, f64)>,
    pub m: Vec<f64>,
    pub q: Vec<f64>,
}
