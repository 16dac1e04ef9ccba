//! Every pair component its own row: the contact problem over the bodies' interface
//! displacements as one sparse convex programme per set of slip bounds, solved by Clarabel's
//! interior point method (docs/formulation.md §6.10).
//!
//! Place in the flow: `problem` (per-body operators, the full rows) → **`exact`** → the
//! driver. The other solvers eliminate the closed rows and leave the rows that a junction's
//! cycle makes dependent without a row of their own (`Problem::implied`): such a component
//! has no force and no law. Here no row is eliminated and none is implied: the unknowns are
//! the dofs U of every body, the energy is `E(U) = Σ_b ½ U_bᵀ S_b U_b + t p̂_bᵀ U_b` (sparse:
//! one dense block per body) and every full row r, `[u]_r = Σ coef·U`, keeps its own law:
//!
//! ```text
//!   bonded, tied stick     [u]_r = a_r                  (equality)
//!   unilateral normal      [u]_r + h_r ≥ 0             (its multiplier λ_r ≥ 0)
//!   Tresca (friction)      + g_r |[u]_r − a_r| in the objective  (|λ_r| ≤ g_r, slip only at g_r)
//! ```
//!
//! with a_r the relative displacement the row keeps (the step's start). Dependent rows are
//! allowed: the interior point method needs no independent constraints, and the forces at a
//! junction are one of the admissible distributions (the central one). Coulomb's law is the
//! fixed point `g_r = μ (λ_n − c w)⁺` of the pair's normal force (`fixed_point`), finished
//! where its statuses hold by one linear solve of Coulomb's law (`newton`); `stick` ties the
//! tangential row of every pair that the last iterate closed. An unbounded programme (Clarabel's
//! certificate of dual infeasibility) is a mechanism: its direction is the motion.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus, ZeroConeT,
};

use crate::contact::problem::{Problem, RowKind};
use crate::input::model::Model;
use crate::linalg::{jacobi_scaling, matvec};

mod fixed_point;
mod local;
mod newton;
mod session;
mod system;

use fixed_point::{coulomb_residual, SlipBounds, SETTLED};
pub(crate) use newton::Seed;

/// The law of one full row in one convex programme.
#[derive(Debug, Clone, Copy, PartialEq)]
enum RowLaw {
    /// `[u] = a`.
    Tie(f64),
    /// `[u] + h ≥ 0`.
    Gap,
    /// `g |[u] − a|` in the objective (g > 0).
    Tresca { bound: f64, anchor: f64 },
    /// No condition (the tangential row of an open pair).
    Free,
}

/// The solution of one programme.
#[derive(Debug, Clone)]
pub struct Programme {
    /// Every dof's displacement.
    pub u: Vec<f64>,
    /// Every full row's force `λ_r = ∂E/∂[u]_r` (compression positive on normal rows; the
    /// cohesion term included).
    pub force: Vec<f64>,
    /// Per full row: closed (normal rows: the multiplier outweighs the gap; other rows: tied
    /// or bounded).
    pub closed: Vec<bool>,
    /// Per full row: a Tresca row that slips (its slip outweighs the margin to its bound).
    pub slipping: Vec<bool>,
    pub iterations: u32,
}

/// What one programme gave.
pub(crate) enum ProgrammeOutcome {
    Solved(Programme),
    /// Unbounded below: the direction (every dof) along which the energy falls.
    Mechanism(Vec<f64>),
    Failed(String),
}

/// What a step gave.
pub struct StepOutcome {
    pub result: Result<Programme, StepFailure>,
    /// Convex programmes solved and interior point iterations in all.
    pub programmes: usize,
    pub ipm_iterations: u64,
    /// The last residual of Coulomb's law relative to the largest normal force
    /// (`coulomb_residual`).
    pub residual: f64,
    /// Whether Coulomb's law was settled by the linear solve of the last statuses
    /// (`newton`) rather than by the fixed point itself.
    pub finished: bool,
}

pub enum StepFailure {
    Mechanism(Vec<f64>),
    NotSettled(Programme),
    Failed(String),
}

/// The constraints of one programme: `A x + s = b` with s in {0}^n_eq × R₊, the full row of
/// each equality and of each row's first inequality, the linear term over the nv unknowns.
struct Constraints {
    a: CscMatrix<f64>,
    b: Vec<f64>,
    n_eq: usize,
    eq_rows: Vec<usize>,
    ineq_of: Vec<usize>,
    q: Vec<f64>,
    nv: usize,
}

/// The scaled data of the programme that do not change with the laws.
pub struct Exact<'a> {
    problem: &'a Problem,
    /// U = d · x.
    d: Vec<f64>,
    /// Norm of each full row over x.
    rho: Vec<f64>,
    /// Upper triangle of D S D (without the objective scale).
    p_cols: Vec<usize>,
    p_rows: Vec<usize>,
    p_vals: Vec<f64>,
    /// The contact bar and the load step (from 0) its messages name, where one is shown.
    progress: Option<(&'a crate::output::progress::Stage, usize)>,
    /// The pattern of the statuses' linear systems.
    layout_cell: system::LayoutCell,
}

impl<'a> Exact<'a> {
    /// Shows each programme of the steps solved from now on in `stage`'s message, as
    /// load step `load_step` (from 0).
    pub(crate) fn show_in(
        &mut self,
        stage: Option<&'a crate::output::progress::Stage>,
        load_step: usize,
    ) {
        self.progress = stage.map(|s| (s, load_step));
    }

    /// The contact bar's message after a programme (or before the seed's linear solve):
    /// the rows open and slipping, the residual of Coulomb's law where rows have one, and
    /// `left`: the programmes and seconds the fixed point needs at the rate its residual
    /// falls ([`programmes_left`]).
    fn show(
        &self,
        programmes: usize,
        sol: Option<&Programme>,
        residual: Option<f64>,
        left: Option<(usize, f64)>,
    ) {
        let Some((stage, step)) = self.progress else {
            return;
        };
        let text = match sol {
            None => format!(
                "step {}: the linear solve of Coulomb's law from the sparse solver's statuses",
                step + 1
            ),
            Some(sol) => {
                let full = &self.problem.full;
                let open = (0..full.len())
                    .filter(|&r| full[r].row.kind == RowKind::Normal && !sol.closed[r])
                    .count();
                let normal = full
                    .iter()
                    .filter(|f| f.row.kind == RowKind::Normal)
                    .count();
                let slipping = sol.slipping.iter().filter(|&&x| x).count();
                let law = residual.map_or(String::new(), |r| format!(", Coulomb residual {r:.1e}"));
                let law = match left.filter(|_| residual.is_some()) {
                    Some((n, secs)) => format!(
                        "{law}, settled in about {n} more ({}) at its rate",
                        crate::estimate::fmt_seconds(secs)
                    ),
                    None => law,
                };
                format!(
                    "step {}, convex programme {programmes}: {open} of {normal} normal rows \
                     open, {slipping} rows slipping{law}",
                    step + 1
                )
            }
        };
        stage.contact_detail(&text);
    }

    pub fn new(problem: &'a Problem) -> Exact<'a> {
        let n = problem.n_dofs;
        // The Jacobi scaling of each body's S; an entry that is not positive and finite
        // keeps the factor 1.
        let mut d = vec![1.0; n];
        for (b, op) in problem.ops.iter().enumerate() {
            let diag = (0..op.u_idx.len()).map(|l| op.s[(l, l)]);
            let body = jacobi_scaling(diag.map(|s| if s > 0.0 && s.is_finite() { s } else { 0.0 }));
            d[problem.dof_start[b]..][..body.len()].copy_from_slice(&body);
        }
        let rho = problem
            .full
            .iter()
            .map(|f| {
                f.coefs
                    .iter()
                    .map(|&(k, c)| (c * d[k]).powi(2))
                    .sum::<f64>()
                    .sqrt()
                    .max(f64::MIN_POSITIVE)
            })
            .collect();
        let mut p_cols = vec![0usize];
        let (mut p_rows, mut p_vals) = (Vec::new(), Vec::new());
        for (b, op) in problem.ops.iter().enumerate() {
            let s0 = problem.dof_start[b];
            for j in 0..op.u_idx.len() {
                for i in 0..=j {
                    let v = 0.5 * (op.s[(i, j)] + op.s[(j, i)]) * d[s0 + i] * d[s0 + j];
                    if v != 0.0 {
                        p_rows.push(s0 + i);
                        p_vals.push(v);
                    }
                }
                p_cols.push(p_rows.len());
            }
        }
        Exact {
            problem,
            d,
            rho,
            p_cols,
            p_rows,
            p_vals,
            progress: None,
            layout_cell: system::LayoutCell::default(),
        }
    }

    /// The relative displacement of every full row for the dofs `u`.
    pub fn jumps(&self, u: &[f64]) -> Vec<f64> {
        (0..self.problem.full.len())
            .map(|r| self.jump(r, u))
            .collect()
    }

    /// The relative displacement of the full row `r` for the dofs `u`.
    fn jump(&self, r: usize, u: &[f64]) -> f64 {
        self.problem.full[r]
            .coefs
            .iter()
            .map(|&(k, c)| c * u[k])
            .sum()
    }

    /// The friction coefficient of the pair of the full row `r`.
    fn mu(&self, model: &Model, r: usize) -> f64 {
        let row = &self.problem.full[r].row;
        model.interfaces[row.iface].pairs[row.pair].friction
    }

    /// Whether the direction of `u` lowers the energy without end (`strict`) or leaves it
    /// unchanged (a neutral one): every body moves rigidly along it (its elastic forces
    /// vanish against its stiffness), no closed gap closes further and no tie moves (to 1e-6
    /// of the motion), and the loads do more work than the slip bounds dissipate (or as much,
    /// to 1e-6 of either).
    fn is_recession(
        &self,
        factor: f64,
        cohesion: &[f64],
        laws: &[RowLaw],
        u: &[f64],
        strict: bool,
    ) -> bool {
        let pb = self.problem;
        let big = u.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if !(big > 0.0 && big.is_finite()) {
            return false;
        }
        let du: Vec<f64> = u.iter().map(|v| v / big).collect();
        let mut work = 0.0;
        let mut size = 0.0f64;
        for (b, op) in pb.ops.iter().enumerate() {
            let s0 = pb.dof_start[b];
            let n = op.u_idx.len();
            let stiff = (0..n).map(|i| op.s[(i, i)].abs()).fold(0.0f64, f64::max);
            let elastic = matvec(&op.s, &du[s0..s0 + n]);
            if elastic.iter().any(|f| f.abs() > 1e-6 * stiff) {
                return false;
            }
            for i in 0..n {
                work += factor * op.p[i] * du[s0 + i];
                size += (factor * op.p[i] * du[s0 + i]).abs();
            }
        }
        let jumps = self.jumps(&du);
        for (r, law) in laws.iter().enumerate() {
            let j = jumps[r];
            work += cohesion[r] * j;
            size += (cohesion[r] * j).abs();
            match *law {
                RowLaw::Tie(_) if j.abs() > 1e-6 => return false,
                RowLaw::Gap if j < -1e-6 => return false,
                RowLaw::Tresca { bound, .. } => {
                    work += bound * j.abs();
                    size += bound * j.abs();
                }
                _ => {}
            }
        }
        if strict {
            work < 0.0
        } else {
            work <= 1e-6 * size
        }
    }

    /// The largest imbalance of a dof, `|∂E/∂U_d + Σ c_r coef − Σ λ_r coef|`, relative to
    /// the largest load or row force: the programme's stationarity checked in the bodies'
    /// own units (Clarabel checks it in its scaled variables, which a huge displacement can
    /// pass).
    fn balance_residual(&self, factor: f64, cohesion: &[f64], u: &[f64], force: &[f64]) -> f64 {
        let pb = self.problem;
        let mut g = vec![0.0; pb.n_dofs];
        let mut scale = 0.0f64;
        for (b, op) in pb.ops.iter().enumerate() {
            let s0 = pb.dof_start[b];
            let n = op.u_idx.len();
            let elastic = matvec(&op.s, &u[s0..s0 + n]);
            for ((gi, p), e) in g[s0..s0 + n].iter_mut().zip(&op.p).zip(elastic) {
                let load = factor * p;
                scale = scale.max(load.abs());
                *gi = load + e;
            }
        }
        for (r, f) in pb.full.iter().enumerate() {
            scale = scale.max(force[r].abs());
            for &(k, c) in &f.coefs {
                g[k] += (cohesion[r] - force[r]) * c;
            }
        }
        let worst = g.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if scale > 0.0 {
            worst / scale
        } else {
            worst
        }
    }

    /// One convex programme for the load factor, the cohesion term of each full row and
    /// the laws.
    fn programme(&self, factor: f64, cohesion: &[f64], laws: &[RowLaw]) -> ProgrammeOutcome {
        let n = self.problem.n_dofs;
        let (q, qs) = self.linear_term(factor, cohesion);
        let c = self.constraints(laws, q, qs);
        let mut pc = self.p_cols.clone();
        pc.resize(c.nv + 1, *self.p_cols.last().unwrap_or(&0));
        let p = CscMatrix::new(c.nv, c.nv, pc, self.p_rows.clone(), self.p_vals.clone());
        let mut cones = Vec::new();
        if c.n_eq > 0 {
            cones.push(ZeroConeT(c.n_eq));
        }
        if c.b.len() > c.n_eq {
            cones.push(NonnegativeConeT(c.b.len() - c.n_eq));
        }
        let settings = match DefaultSettingsBuilder::default()
            .verbose(false)
            .tol_gap_abs(1e-10)
            .tol_gap_rel(1e-10)
            .tol_feas(1e-10)
            .max_iter(400)
            .build()
        {
            Ok(s) => s,
            Err(e) => return ProgrammeOutcome::Failed(format!("settings rejected: {e:?}")),
        };
        let mut solver = match DefaultSolver::new(&p, &c.q, &c.a, &c.b, &cones, settings) {
            Ok(s) => s,
            Err(e) => return ProgrammeOutcome::Failed(format!("could not be set up: {e:?}")),
        };
        solver.solve();
        let sol = &solver.solution;
        match sol.status {
            // An interior point that stopped short of its tolerances (rows that depend on
            // each other at junctions leave the multipliers a face, not a point) is judged
            // by the bodies' balance below, as a solved one is: measured on a 3 × 3
            // running-bond wall's collapse trial at t = 0.71875, InsufficientProgress.
            SolverStatus::Solved
            | SolverStatus::AlmostSolved
            | SolverStatus::InsufficientProgress
            | SolverStatus::MaxIterations => {}
            SolverStatus::DualInfeasible | SolverStatus::AlmostDualInfeasible => {
                return ProgrammeOutcome::Mechanism((0..n).map(|k| self.d[k] * sol.x[k]).collect())
            }
            s => return ProgrammeOutcome::Failed(format!("Clarabel's status {s:?}")),
        }
        let read = self.read(sol, &c, laws, qs);
        // In the scaled unknowns an elastic solution is of order one; a point 1e8 times
        // farther has drifted along a direction that costs nothing (a body free to slide at
        // zero force, Clarabel's analytic centre of an unbounded set of minimisers): a
        // mechanism of neutral equilibrium where that direction is one, else no verdict.
        let drift = sol.x[..n].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if drift > DRIFT_LIMIT {
            if self.is_recession(factor, cohesion, laws, &read.u, false) {
                return ProgrammeOutcome::Mechanism(read.u);
            }
            return ProgrammeOutcome::Failed(format!(
                "Clarabel's status {:?} at a point {drift:.1e} times the elastic scale: the \
                 minimisers are not bounded",
                sol.status
            ));
        }
        let balance = self.balance_residual(factor, cohesion, &read.u, &read.force);
        if balance.is_nan() || balance > BALANCE_TOLERANCE {
            // Where the programme is unbounded Clarabel may stop at a huge point instead of
            // its certificate: that point's direction is then the mechanism.
            if self.is_recession(factor, cohesion, laws, &read.u, true) {
                return ProgrammeOutcome::Mechanism(read.u);
            }
            return ProgrammeOutcome::Failed(format!(
                "Clarabel's status {:?}, but the bodies' balance with the rows' forces is off by \
                 {balance:.1e} of the largest force",
                sol.status
            ));
        }
        ProgrammeOutcome::Solved(read)
    }

    /// The programme's linear term over the dofs, `D (t p̂ + Σ c_r coef_r)`, and its
    /// largest entry qs (1 where it vanishes). Unknowns x = U / (d qs): the objective over
    /// qs² is ½ xᵀ(DSD)x + (q/qs)ᵀx, with a unit diagonal and loads of order one; the rows'
    /// multipliers are λ = z qs / ρ.
    fn linear_term(&self, factor: f64, cohesion: &[f64]) -> (Vec<f64>, f64) {
        let pb = self.problem;
        let mut q = vec![0.0; pb.n_dofs];
        for (b, op) in pb.ops.iter().enumerate() {
            for (l, p) in op.p.iter().enumerate() {
                q[pb.dof_start[b] + l] += factor * p;
            }
        }
        for (r, f) in pb.full.iter().enumerate() {
            if cohesion[r] != 0.0 {
                for &(k, c) in &f.coefs {
                    q[k] += cohesion[r] * c;
                }
            }
        }
        for (k, qk) in q.iter_mut().enumerate() {
            *qk *= self.d[k];
        }
        let qs = q.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        (q, if qs > 0.0 && qs.is_finite() { qs } else { 1.0 })
    }

    /// The constraint rows `A x + s = b` of the laws (equalities first, then inequalities)
    /// and the objective's linear term over x and the Tresca variables.
    fn constraints(&self, laws: &[RowLaw], q: Vec<f64>, qs: f64) -> Constraints {
        let full = &self.problem.full;
        let n = self.problem.n_dofs;
        let mut z_of = vec![usize::MAX; full.len()];
        let mut nz = 0;
        for (r, law) in laws.iter().enumerate() {
            if matches!(law, RowLaw::Tresca { .. }) {
                z_of[r] = n + nz;
                nz += 1;
            }
        }
        let nv = n + nz;
        let mut qv: Vec<f64> = q.iter().map(|v| v / qs).collect();
        qv.resize(nv, 0.0);
        let mut trip: Vec<(usize, usize, f64)> = Vec::new();
        let mut b = Vec::new();
        let mut eq_rows = Vec::new();
        let scaled = |r: usize| {
            full[r]
                .coefs
                .iter()
                .map(move |&(k, c)| (k, c * self.d[k] / self.rho[r]))
        };
        for (r, law) in laws.iter().enumerate() {
            if let RowLaw::Tie(a) = *law {
                let i = b.len();
                trip.extend(scaled(r).map(|(k, v)| (i, k, v)));
                b.push(a / (self.rho[r] * qs));
                eq_rows.push(r);
            }
        }
        let n_eq = b.len();
        let mut ineq_of = vec![usize::MAX; full.len()];
        for (r, law) in laws.iter().enumerate() {
            match *law {
                RowLaw::Gap => {
                    let i = b.len();
                    ineq_of[r] = i;
                    trip.extend(scaled(r).map(|(k, v)| (i, k, -v)));
                    b.push(full[r].row.gap / (self.rho[r] * qs));
                }
                RowLaw::Tresca { bound, anchor } => {
                    let i = b.len();
                    ineq_of[r] = i;
                    trip.extend(scaled(r).map(|(k, v)| (i, k, v)));
                    trip.push((i, z_of[r], -1.0));
                    b.push(anchor / (self.rho[r] * qs));
                    trip.extend(scaled(r).map(|(k, v)| (i + 1, k, -v)));
                    trip.push((i + 1, z_of[r], -1.0));
                    b.push(-anchor / (self.rho[r] * qs));
                    qv[z_of[r]] = bound * self.rho[r] / qs;
                }
                _ => {}
            }
        }
        Constraints {
            a: csc(b.len(), nv, trip),
            b,
            n_eq,
            eq_rows,
            ineq_of,
            q: qv,
            nv,
        }
    }

    /// The displacements, forces and statuses of Clarabel's solution.
    fn read(
        &self,
        sol: &clarabel::solver::DefaultSolution<f64>,
        c: &Constraints,
        laws: &[RowLaw],
        qs: f64,
    ) -> Programme {
        let n = self.problem.n_dofs;
        let m = self.problem.full.len();
        let u: Vec<f64> = (0..n).map(|k| self.d[k] * qs * sol.x[k]).collect();
        let mut force = vec![0.0; m];
        let mut closed = vec![false; m];
        let mut slipping = vec![false; m];
        for (i, &r) in c.eq_rows.iter().enumerate() {
            force[r] = -sol.z[i] * qs / self.rho[r];
            closed[r] = true;
        }
        for (r, law) in laws.iter().enumerate() {
            let i = c.ineq_of[r];
            match law {
                RowLaw::Gap => {
                    force[r] = sol.z[i] * qs / self.rho[r];
                    // On the central path z s = μ: the larger of the two is the one of the
                    // exact complementary pair.
                    closed[r] = sol.z[i] > sol.s[i];
                }
                RowLaw::Tresca { .. } => {
                    force[r] = (sol.z[i + 1] - sol.z[i]) * qs / self.rho[r];
                    closed[r] = true;
                    // Slipping: one slack is the slip, the other side's multiplier the
                    // margin to the bound (central path: the larger is the exact one).
                    slipping[r] = sol.s[i].max(sol.s[i + 1]) > sol.z[i].min(sol.z[i + 1]);
                }
                _ => {}
            }
        }
        Programme {
            u,
            force,
            closed,
            slipping,
            iterations: sol.iterations,
        }
    }

    /// The forces of a settled step with the least norm among those that balance the same
    /// displacements within every row's law: at a junction the rows are dependent and a
    /// self-balanced set of forces around its cycle can be added (the interior point's
    /// choice grows with μ: 180 times the largest traction at μ = 1000 on the 5 × 3 wall);
    /// this one is unique. Its laws: open rows carry nothing, closed normal rows push,
    /// sticking Coulomb rows hold |λ_t| ≤ μ(λ_n − c w), slipping ones λ_t = ±μ(λ_n − c w)
    /// with the sense they slip against (with the final normal forces: Coulomb's law exactly),
    /// tied rows anything. None where Clarabel does not solve it (the forces stay).
    ///
    /// `strict`: the forces of `sol` may break the laws (the linear solve's forces at a
    /// junction, one of many distributions): the laws are then imposed as they are, to 1e-9
    /// of the largest force, and None says that no admissible distribution exists.
    fn distribute(
        &self,
        model: &Model,
        laws: &[RowLaw],
        normal: &[Option<usize>],
        cohesion: &[f64],
        (sol, strict): (&Programme, bool),
    ) -> Option<Vec<f64>> {
        let pb = self.problem;
        let full = &pb.full;
        let m = full.len();
        let scale = sol.force.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        if m == 0 || scale == 0.0 {
            return None;
        }
        // Unknowns δ (λ = λ₀ + δ, in units of `scale`) of the rows that carry force: tied
        // rows, closed normal rows, Coulomb rows of closed pairs; the others carry nothing
        // (their interior point residue is dropped from both sides of the balance).
        let l0: Vec<f64> = sol.force.iter().map(|v| v / scale).collect();
        let coh: Vec<f64> = cohesion.iter().map(|v| v / scale).collect();
        // The margin of an inequality at δ = 0: at least zero (it holds there, to round-off)
        // unless `strict`.
        let admit = |margin: f64| {
            if strict {
                margin + LAW_MARGIN
            } else {
                margin.max(0.0)
            }
        };
        let carries = |r: usize| match laws[r] {
            RowLaw::Tie(_) => true,
            RowLaw::Gap => sol.closed[r],
            RowLaw::Tresca { .. } => normal[r].is_none_or(|n| sol.closed[n]),
            RowLaw::Free => false,
        };
        let mut var = vec![usize::MAX; m];
        let mut nv = 0;
        for (r, v) in var.iter_mut().enumerate() {
            if carries(r) {
                *v = nv;
                nv += 1;
            }
        }
        if nv == 0 {
            return None;
        }
        let mut eq: Vec<(usize, usize, f64)> = Vec::new();
        let mut beq = Vec::new();
        // Balance: Σ_r coef δ_r = 0 at every dof a carrying row moves.
        let mut rows_of: Vec<Vec<(usize, f64)>> = vec![Vec::new(); pb.n_dofs];
        for (r, f) in full.iter().enumerate() {
            if var[r] != usize::MAX {
                for &(k, c) in &f.coefs {
                    rows_of[k].push((var[r], c));
                }
            }
        }
        for list in rows_of.iter().filter(|l| !l.is_empty()) {
            let i = beq.len();
            let big = list.iter().fold(0.0f64, |a, v| a.max(v.1.abs()));
            eq.extend(list.iter().map(|&(j, c)| (i, j, c / big)));
            beq.push(0.0);
        }
        let mut ineq: Vec<(usize, usize, f64)> = Vec::new();
        let mut bin = Vec::new();
        for (r, f) in full.iter().enumerate() {
            let j = var[r];
            if j == usize::MAX {
                continue;
            }
            match (laws[r], f.row.kind) {
                (RowLaw::Gap, _) => {
                    // λ₀ + δ ≥ 0 (λ holds the cohesion term: a cohesive row pulls up to c w).
                    let i = bin.len();
                    ineq.push((i, j, -1.0));
                    bin.push(admit(l0[r]));
                }
                (RowLaw::Tresca { .. }, RowKind::Friction) => {
                    let Some(n) = normal[r] else { continue };
                    let jn = var[n];
                    if jn == usize::MAX {
                        continue;
                    }
                    let mu = self.mu(model, r);
                    // Every constraint holds at δ = 0 exactly (the step's residual of
                    // Coulomb's law, below 1e-8, stays): the balance and these equalities
                    // are dependent, and a right-hand side off by round-off would leave
                    // them without a solution.
                    if sol.slipping[r] {
                        // δ_t = σ μ δ_n with σ the sense of the force: the slip bound
                        // follows the normal force.
                        let sigma = sol.force[r].signum();
                        let i = beq.len();
                        eq.push((i, j, 1.0));
                        eq.push((i, jn, -sigma * mu));
                        beq.push(0.0);
                    } else {
                        // μ(λ_n − c) ∓ λ_t ≥ 0.
                        for sign in [1.0, -1.0] {
                            let i = bin.len();
                            ineq.push((i, jn, -mu));
                            ineq.push((i, j, sign));
                            bin.push(admit(mu * (l0[n] - coh[n]) - sign * l0[r]));
                        }
                    }
                }
                _ => {}
            }
        }
        let n_eq = beq.len();
        let mut trip = eq;
        trip.extend(ineq.into_iter().map(|(i, j, v)| (i + n_eq, j, v)));
        let mut b = beq;
        b.extend(bin);
        let a = csc(b.len(), nv, trip);
        let p = CscMatrix::new(nv, nv, (0..=nv).collect(), (0..nv).collect(), vec![1.0; nv]);
        let q: Vec<f64> = (0..m)
            .filter(|&r| var[r] != usize::MAX)
            .map(|r| l0[r])
            .collect();
        let mut cones = vec![ZeroConeT(n_eq)];
        if b.len() > n_eq {
            cones.push(NonnegativeConeT(b.len() - n_eq));
        }
        let settings = DefaultSettingsBuilder::default()
            .verbose(false)
            .tol_gap_abs(1e-10)
            .tol_gap_rel(1e-10)
            .tol_feas(1e-10)
            .max_iter(200)
            .build()
            .ok()?;
        let mut solver = DefaultSolver::new(&p, &q, &a, &b, &cones, settings).ok()?;
        solver.solve();
        if !matches!(solver.solution.status, SolverStatus::Solved) {
            return None;
        }
        let force: Vec<f64> = (0..m)
            .map(|r| match var[r] {
                usize::MAX => 0.0,
                j => (l0[r] + solver.solution.x[j]) * scale,
            })
            .collect();
        Some(force)
    }

    /// The normal row of every full row's pair, and the Coulomb rows (friction rows of a
    /// pair with a normal row).
    fn normal_and_friction_rows(&self) -> (Vec<Option<usize>>, Vec<usize>) {
        let full = &self.problem.full;
        let normal: Vec<Option<usize>> = full
            .iter()
            .map(|f| self.problem.full_of[f.row.iface][f.row.pair][1])
            .collect();
        let friction = (0..full.len())
            .filter(|&r| full[r].row.kind == RowKind::Friction && normal[r].is_some())
            .collect();
        (normal, friction)
    }

    /// One load step from the relative displacements `start` of every full row (the anchors
    /// of tied and Tresca rows), with the cohesion term of every full row, and at most
    /// `max_outer` programmes. The first programme ties every tangential row (a first
    /// estimate of the normal forces); then `stick` rows are tied where their pair is closed
    /// and Coulomb's bounds follow the normal forces, the fixed point accelerated by
    /// Anderson's mixing of the last bounds while the statuses hold.
    ///
    /// With a `seed` (statuses and forces of every full row, from another solver) the linear
    /// solve of Coulomb's law is tried first; where it settles no programme is solved.
    pub fn step(
        &self,
        model: &Model,
        factor: f64,
        (start, seed): (&[f64], Option<Seed>),
        cohesion: &mut [f64],
        max_outer: usize,
    ) -> StepOutcome {
        let full = &self.problem.full;
        let (normal, friction) = self.normal_and_friction_rows();
        let mut laws = first_laws(full, start);
        let mut programmes = 0;
        let mut ipm = 0u64;
        let mut change = f64::INFINITY;
        let mut last: Option<Programme> = None;
        let mut settled = false;
        let mut mixer = SlipBounds::new();
        let mut flips = vec![0u8; full.len()];
        let mut seen: Option<(Vec<bool>, Vec<bool>)> = None;
        let mut tried: Option<usize> = None;
        let mut finished = false;
        let mut residuals = Vec::new();
        let began = std::time::Instant::now();
        let fail = |result, programmes, ipm, change| StepOutcome {
            result,
            programmes,
            ipm_iterations: ipm,
            residual: change,
            finished: false,
        };
        if let Some(seed) = seed {
            self.show(0, None, None, None);
            let fin = newton::Finish::new(model, factor, cohesion, &normal, start);
            if let Some((done, done_laws)) = self.settle(&fin, seed.status, seed.prior, false) {
                change = settled_residual(&friction, &normal, &done, &done_laws);
                (finished, settled) = (true, true);
                laws = done_laws;
                last = Some(done);
            }
        }
        let rounds = if settled { 0 } else { max_outer.max(1) };
        for _ in 0..rounds {
            let sol = match self.programme(factor, cohesion, &laws) {
                ProgrammeOutcome::Solved(s) => s,
                ProgrammeOutcome::Mechanism(du) => {
                    return fail(Err(StepFailure::Mechanism(du)), programmes + 1, ipm, change)
                }
                ProgrammeOutcome::Failed(m) => {
                    return fail(Err(StepFailure::Failed(m)), programmes + 1, ipm, change)
                }
            };
            programmes += 1;
            ipm += u64::from(sol.iterations);
            // Cohesion is brittle: a pair that opens loses it for good.
            let mut broke = false;
            for (r, c) in cohesion.iter_mut().enumerate() {
                if *c != 0.0 && !sol.closed[r] {
                    *c = 0.0;
                    broke = true;
                }
            }
            let mut next = laws.clone();
            let tie = StickTies {
                full,
                normal: &normal,
                start,
                programmes,
            };
            tie.update(&sol, &laws, &mut next, &mut flips);
            // Coulomb's bounds from the normal forces: G(x).
            let (x, gx) = self.bounds(model, &friction, &normal, &laws, &sol, cohesion);
            change = coulomb_residual(&friction, &normal, &sol, &x, &gx);
            let left = programmes_left(&residuals, change).map(|n| {
                (
                    n,
                    n as f64 * began.elapsed().as_secs_f64() / programmes as f64,
                )
            });
            let law = (!friction.is_empty()).then_some(change);
            self.show(programmes, Some(&sol), law, left);
            // Where the statuses held since the last programme, Coulomb's law with these
            // statuses is one linear solve (`newton`).
            let statuses = (sol.closed.clone(), sol.slipping.clone());
            let repeat = (programmes == 1 || seen.as_ref() == Some(&statuses))
                && tried.is_none_or(|t| programmes >= t + RETRY_FINISH);
            if !broke && change > SETTLED && repeat {
                tried = Some(programmes);
                let fin = newton::Finish::new(model, factor, cohesion, &normal, start);
                if let Some((done, done_laws)) = self.finish(&fin, &laws, &sol) {
                    change = settled_residual(&friction, &normal, &done, &done_laws);
                    (finished, settled) = (true, true);
                    laws = done_laws;
                    last = Some(done);
                    break;
                }
            }
            seen = Some(statuses);
            let mixed = mixer.next(&friction, &sol, &x, &gx);
            for (i, &r) in friction.iter().enumerate() {
                next[r] = if mixed[i] > 0.0 {
                    RowLaw::Tresca {
                        bound: mixed[i],
                        anchor: start[r],
                    }
                } else {
                    RowLaw::Free
                };
            }
            settled = !broke && kinds_held(&next, &laws) && change <= SETTLED;
            laws = next;
            last = Some(sol);
            residuals.push(change);
            if settled || stalled(&residuals) {
                break;
            }
        }
        let Some(sol) = last else {
            return fail(
                Err(StepFailure::Failed("no programme solved".into())),
                programmes,
                ipm,
                change,
            );
        };
        let mut sol = sol;
        if settled && !finished {
            // The fixed point settled on its programmes' own accuracy (an interior point's,
            // poor where the slip bounds dwarf the loads: μ = 1000 left bricks of a wall
            // unbalanced by 3.6e-6): the linear solve of its statuses polishes it.
            let fin = newton::Finish::new(model, factor, cohesion, &normal, start);
            if let Some((done, done_laws)) = self.finish(&fin, &laws, &sol) {
                change = settled_residual(&friction, &normal, &done, &done_laws);
                finished = true;
                laws = done_laws;
                sol = done;
            }
        }
        let result = if settled {
            if let Some(force) = self.distribute(model, &laws, &normal, cohesion, (&sol, false)) {
                sol.force = force;
            }
            Ok(sol)
        } else {
            Err(StepFailure::NotSettled(sol))
        };
        StepOutcome {
            finished,
            ..fail(result, programmes, ipm, change)
        }
    }
}

impl Exact<'_> {
    /// The bounds `x` of the Coulomb rows `friction` in `laws` (NaN where tied) and the new
    /// ones `G(x) = μ (λ_n − c w)⁺` of the programme `sol`'s normal forces (zero where the
    /// pair is open).
    fn bounds(
        &self,
        model: &Model,
        friction: &[usize],
        normal: &[Option<usize>],
        laws: &[RowLaw],
        sol: &Programme,
        cohesion: &[f64],
    ) -> (Vec<f64>, Vec<f64>) {
        let x = friction
            .iter()
            .map(|&r| match laws[r] {
                RowLaw::Tresca { bound, .. } => bound,
                RowLaw::Tie(_) => f64::NAN,
                _ => 0.0,
            })
            .collect();
        let gx = friction
            .iter()
            .map(|&r| {
                let nr = normal[r].unwrap_or(r);
                if sol.closed[nr] {
                    self.mu(model, r) * (sol.force[nr] - cohesion[nr]).max(0.0)
                } else {
                    0.0
                }
            })
            .collect();
        (x, gx)
    }
}

/// The laws of a step's first programme: bonded rows tied, normal rows unilateral, every
/// tangential row tied at its start (a first estimate of the normal forces).
fn first_laws(full: &[crate::contact::problem::FullRow], start: &[f64]) -> Vec<RowLaw> {
    full.iter()
        .enumerate()
        .map(|(r, f)| match f.row.kind {
            RowKind::Bonded if f.row.comp == 1 => RowLaw::Tie(-f.row.gap),
            RowKind::Normal => RowLaw::Gap,
            RowKind::Bonded | RowKind::Stick | RowKind::Friction => RowLaw::Tie(start[r]),
        })
        .collect()
}

/// Whether the fixed point has stalled: after `STALL_WINDOW` × 2 programmes, the last
/// `STALL_WINDOW` did not halve the smallest residual of those before them (a fixed point
/// that cycles near a collapse; the 4 × 5 wall with μ = 3 at t = 0.6348 sat at 1e-1 for 500
/// programmes). Settling fixed points halve it far faster: the standing trials of the
/// 220-stone wall took 52–83 programmes in all.
fn stalled(residuals: &[f64]) -> bool {
    let n = residuals.len();
    if n < 2 * STALL_WINDOW {
        return false;
    }
    let min = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
    min(&residuals[n - STALL_WINDOW..]) > 0.5 * min(&residuals[..n - STALL_WINDOW])
}

/// The programmes the fixed point needs to settle at the rate its residual fell over the
/// last `RATE_WINDOW` programmes (`residuals` before the newest, `last`): the residual is
/// taken to fall geometrically, as a fixed point that converges linearly does. None where
/// it did not fall over that window (no rate to go by) or has settled.
fn programmes_left(residuals: &[f64], last: f64) -> Option<usize> {
    if residuals.len() < RATE_WINDOW || last.is_nan() || last <= SETTLED {
        return None;
    }
    let first = residuals[residuals.len() - RATE_WINDOW];
    let q = (last / first).powf(1.0 / RATE_WINDOW as f64);
    if q.is_nan() || q >= 0.95 {
        return None;
    }
    let n = ((SETTLED / last).ln() / q.ln()).ceil();
    (n.is_finite() && n >= 1.0).then(|| n.min(1e6) as usize)
}

/// The programmes over which the fall of Coulomb's residual gives the rate shown.
const RATE_WINDOW: usize = 5;

/// The programmes over which the fixed point must make progress (`stalled`).
const STALL_WINDOW: usize = 50;

/// Programmes after a linear solve of the statuses that did not settle before the next try.
const RETRY_FINISH: usize = 5;

/// Coulomb's residual of a solution settled by the linear solve, whose laws carry the
/// bounds of its own normal forces.
fn settled_residual(
    friction: &[usize],
    normal: &[Option<usize>],
    done: &Programme,
    laws: &[RowLaw],
) -> f64 {
    let bounds: Vec<f64> = friction
        .iter()
        .map(|&r| match laws[r] {
            RowLaw::Tresca { bound, .. } => bound,
            _ => 0.0,
        })
        .collect();
    coulomb_residual(friction, normal, done, &bounds, &bounds)
}

/// Whether two sets of laws have the same kind row by row.
fn kinds_held(a: &[RowLaw], b: &[RowLaw]) -> bool {
    a.iter()
        .zip(b)
        .all(|(p, q)| std::mem::discriminant(p) == std::mem::discriminant(q))
}

/// The stick rows' laws after a programme.
struct StickTies<'s> {
    full: &'s [crate::contact::problem::FullRow],
    normal: &'s [Option<usize>],
    start: &'s [f64],
    programmes: usize,
}

impl StickTies<'_> {
    /// Stick rows follow their pair's status; one that the statuses untie and tie again (a
    /// pair at the contact's edge: tied it opens, untied it closes) stays untied, closed at
    /// zero normal force and tangentially free (the μ → ∞ limit of Coulomb's law there).
    fn update(&self, sol: &Programme, laws: &[RowLaw], next: &mut [RowLaw], flips: &mut [u8]) {
        for (r, f) in self.full.iter().enumerate() {
            if let (RowKind::Stick, Some(nr)) = (f.row.kind, self.normal[r]) {
                let tie = sol.closed[nr] && flips[r] < 2;
                if tie != matches!(laws[r], RowLaw::Tie(_)) && self.programmes > 1 {
                    flips[r] += 1;
                }
                next[r] = if tie && flips[r] < 2 {
                    RowLaw::Tie(self.start[r])
                } else {
                    RowLaw::Free
                };
            }
        }
    }
}

/// A CSC matrix from (row, column, value) triplets (duplicates summed, rows sorted).
fn csc(m: usize, n: usize, mut trip: Vec<(usize, usize, f64)>) -> CscMatrix<f64> {
    trip.sort_by_key(|t| (t.1, t.0));
    let mut colptr = vec![0usize; n + 1];
    let (mut rowval, mut nzval): (Vec<usize>, Vec<f64>) = (Vec::new(), Vec::new());
    let mut last: Option<(usize, usize)> = None;
    for (i, j, v) in trip {
        if last == Some((i, j)) {
            if let Some(x) = nzval.last_mut() {
                *x += v;
            }
            continue;
        }
        rowval.push(i);
        nzval.push(v);
        colptr[j + 1] += 1;
        last = Some((i, j));
    }
    for j in 0..n {
        colptr[j + 1] += colptr[j];
    }
    CscMatrix::new(m, n, colptr, rowval, nzval)
}

/// The margin (relative to the largest force) within which a strict distribution of junction
/// forces holds every law.
const LAW_MARGIN: f64 = 1e-9;

/// The imbalance of a dof, relative to the largest load or row force, above which a
/// programme's solution is refused.
const BALANCE_TOLERANCE: f64 = 1e-6;

/// How far (in the scaled unknowns, where an elastic solution is of order one) a solution
/// may lie before it is taken for a drift along a direction that costs nothing.
const DRIFT_LIMIT: f64 = 1e8;

/// The convex programmes a load step of the full-row solver may take.
const FULL_ROW_PROGRAMMES: usize = 500;

#[cfg(test)]
mod tests {
    use super::programmes_left;

    #[test]
    fn the_programmes_left_follow_the_residuals_rate() {
        // Halving per programme: from 1e-3 · 2^-6 to 1e-8 takes 11 more (2^-16.6).
        let r: Vec<f64> = (0..6).map(|k| 1e-3 * 0.5f64.powi(k)).collect();
        let last = 1e-3 * 0.5f64.powi(6);
        assert_eq!(programmes_left(&r, last), Some(11));
        // Not falling, too few, or settled: no estimate.
        assert_eq!(programmes_left(&[1e-3; 6], 1e-3), None);
        assert_eq!(programmes_left(&r[..3], last), None);
        assert_eq!(programmes_left(&r, 1e-9), None);
    }
}
