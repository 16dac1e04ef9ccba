//! The finish of Coulomb's fixed point: once a programme's statuses are known, Coulomb's law
//! is linear, and one sparse solve gives the step's solution (docs/formulation.md §6.10).
//!
//! With each row's status fixed — open (no force), fixed (`[u]_r = v_r`: tied rows, closed
//! normal rows at `[u] = −h`, sticking Coulomb rows at their anchor) or slipping
//! (`λ_t = σ μ (λ_n − c w)`, σ the sense of its force) — the step's equations are
//!
//! ```text
//!   S U − Σ_r λ_r b_r = −(t p̂ + Σ_r c_r b_r)      (every dof)
//!   b_rᵀ U = v_r                                   (fixed rows)
//!   λ_r − σ_r μ_r λ_n(r) = −σ_r μ_r c_n(r)         (slipping rows)
//! ```
//!
//! a square sparse system, not symmetric where rows slip. Rows at a junction are dependent
//! (the forces of a closed cycle are not unique): the fixed rows get a compliance ε ≪ 1 in
//! the scaled unknowns, and iterative refinement against the unregularised equations
//! removes its effect on the displacements. The solution is checked against every law
//! (closed rows push, open rows do not penetrate, sticking rows within the bound, slipping
//! rows slip against their force); where one fails its status changes and the system is
//! solved again (a primal-dual active set, Hüeber–Stadler–Wohlmuth's form of Coulomb's
//! law), at most `ROUNDS` times. A status that leaves a body free makes the system singular:
//! after a programme the corrections then go on with a proximal spring about the last
//! solution (a trust region), and the system without it decides. Where it does not settle,
//! the fixed point goes on: this is an acceleration, never a verdict.

use super::{Exact, Programme, RowLaw};
use crate::contact::problem::RowKind;
use crate::input::model::Model;
use crate::solution::{InterfaceResult, PairStatus};

/// The status of one full row in the linear system.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Status {
    /// No force.
    Off,
    /// `[u]_r = v`.
    Fixed(f64),
    /// `λ_r = σ μ (λ_n − c)`.
    Slip(f64),
}

/// What the finish needs besides the solver's data.
pub(super) struct Finish<'f> {
    pub(super) model: &'f Model,
    pub(super) factor: f64,
    pub(super) cohesion: &'f [f64],
    /// The normal row of every row's pair.
    pub(super) normal: &'f [Option<usize>],
    /// The anchors (relative displacements at the step's start).
    pub(super) start: &'f [f64],
}

impl<'f> Finish<'f> {
    pub(super) fn new(
        model: &'f Model,
        factor: f64,
        cohesion: &'f [f64],
        normal: &'f [Option<usize>],
        start: &'f [f64],
    ) -> Finish<'f> {
        Finish {
            model,
            factor,
            cohesion,
            normal,
            start,
        }
    }
}

/// Statuses and forces of every full row from another solver's step: where the linear
/// solve starts.
pub struct Seed {
    pub(super) status: Vec<Status>,
    pub(super) prior: Vec<f64>,
}

impl Exact<'_> {
    /// The seed of the pair results `interfaces` of another solver (the sparse one) for the
    /// same step: each row's status from its pair's (closed, slipping with the sense of its
    /// traction), each row's force from its pair's traction, `λ_r = −t w + c w`.
    pub fn seed(
        &self,
        model: &Model,
        interfaces: &[InterfaceResult],
        cohesion: &[f64],
        start: &[f64],
    ) -> Seed {
        let full = &self.problem.full;
        let mut status = vec![Status::Off; full.len()];
        let mut prior = vec![0.0; full.len()];
        for (r, fr) in full.iter().enumerate() {
            let row = &fr.row;
            let Some(pair) = interfaces
                .get(row.iface)
                .and_then(|i| i.pairs.get(row.pair))
            else {
                continue;
            };
            let closed = pair.status == PairStatus::Closed;
            let t = pair.traction[row.comp];
            if closed || row.kind == RowKind::Bonded {
                prior[r] = -t * row.weight + cohesion[r];
            }
            status[r] = match row.kind {
                RowKind::Bonded if row.comp == 1 => Status::Fixed(-row.gap),
                RowKind::Bonded => Status::Fixed(start[r]),
                _ if !closed => Status::Off,
                RowKind::Normal => Status::Fixed(-row.gap),
                RowKind::Stick => Status::Fixed(start[r]),
                RowKind::Friction => {
                    if pair.slipping == Some(true) && self.mu(model, r) > 0.0 {
                        Status::Slip(if prior[r] < 0.0 { -1.0 } else { 1.0 })
                    } else {
                        Status::Fixed(start[r])
                    }
                }
            };
        }
        Seed { status, prior }
    }
}

/// Solves of the linear system with changed statuses before the finish gives up (the
/// 798-brick wall from the sparse solver's statuses: 9 with the local Tresca step; corrections
/// of one to five rows each after the third).
const ROUNDS: usize = 16;

/// Solves of the linear system before a finish after a programme gives up where a status
/// left a body free and the proximal spring took over (the stone wall with Coulomb joints at
/// 0.117 g settled after 15); without a spring `ROUNDS` still ends it.
const PROXIMAL_ROUNDS: usize = 20;

/// The weight of the proximal spring (scaled unknowns, unit diagonal) on every dof while a
/// status leaves a body free, and the lightest it is made while the statuses hold.
const PROXIMAL: f64 = 1e-2;
const PROXIMAL_MIN: f64 = 1e-8;
/// Changes of status after a proximal solve up to which the spring is made lighter.
const FEW_CHANGES: usize = 16;

/// Relative tolerance of the checks on forces (against the largest normal force).
const LAW_TOLERANCE: f64 = 1e-9;

/// Relative tolerance of the checks on displacements (a slip against its force, a
/// penetration, a closed gap): the solve's round-off on the 798-brick wall reached 2e-11 of
/// slip at rows on their bound (about 1e-8 of the largest displacement), which flipped them
/// between stick and slip at 1e-9.
const MOTION_TOLERANCE: f64 = 1e-6;

/// Relative tolerance of a slip against the force of a row on its bound (a slipping row whose
/// slip is zero but for the solve's round-off): the 798-brick wall's row at 1.2e-6 of the
/// largest displacement held its bound in every round and turned sticking in each.
const SLIP_TOLERANCE: f64 = 1e-5;

impl Exact<'_> {
    /// The step's solution from the statuses of the programme `sol` solved with `laws`, or
    /// None where the linear system with corrected statuses does not give one that obeys
    /// every law within `ROUNDS` solves. Returns the solution and the laws it obeys (for the
    /// distribution of junction forces).
    pub(super) fn finish(
        &self,
        f: &Finish,
        laws: &[RowLaw],
        sol: &Programme,
    ) -> Option<(Programme, Vec<RowLaw>)> {
        let status: Vec<Status> = (0..self.problem.full.len())
            .map(|r| self.first_status(f, laws, sol, r))
            .collect();
        self.settle(f, status, sol.force.clone(), true)
    }

    /// The statuses' linear solve from `status` and the forces `prior` (where the forces
    /// are not unique the solve keeps the nearest), corrected until every law holds: the
    /// solution and its laws, or None. With `proximal`, a status that leaves a body free
    /// (the system singular, or its solution drifting) does not end the solve: the next
    /// solves carry a proximal spring on every dof (a trust region about the last
    /// solution) until the statuses hold, and the solution without it decides.
    pub(super) fn settle(
        &self,
        f: &Finish,
        mut status: Vec<Status>,
        mut prior: Vec<f64>,
        proximal: bool,
    ) -> Option<(Programme, Vec<RowLaw>)> {
        let mut seen: Vec<Vec<Status>> = Vec::new();
        // The proximal weight and centre (scaled unknowns) once a status left a body free.
        let mut prox: Option<(f64, Vec<f64>)> = None;
        // The last solution (scaled unknowns): the spring's first centre.
        let mut last: Option<Vec<f64>> = None;
        // Whether the local Tresca step decides the corrections.
        let mut local = false;
        let rounds = if proximal { PROXIMAL_ROUNDS } else { ROUNDS };
        for round in 0..rounds {
            if prox.is_none() && round >= ROUNDS {
                return None;
            }
            let exact = match &prox {
                None => self.solve_statuses(f, &status, &prior, None),
                Some(_) => None,
            };
            // Row by row, the corrections of the last solve left a body free: the Coulomb
            // rows about the bodies they changed are decided together instead (`local`),
            // in this round and every one after.
            // (Before this round: the statuses `seen` last, corrected to `status`, with the
            // forces `prior`.)
            if let (None, None, false, Some(before)) = (&exact, &prox, local, seen.last()) {
                if let Some(l) = self.local_retry(f, (before, &status, &prior), &seen) {
                    local = true;
                    status = l;
                    continue;
                }
            }
            let (u, force, x, exact) = match exact {
                Some((u, force, x)) => (u, force, x, true),
                None if !proximal => return None,
                None => {
                    // A status that leaves a body free (or nearly): the proximal spring
                    // holds it near the last solution while the statuses are corrected.
                    let (w, centre) = prox.get_or_insert_with(|| {
                        let centre = last.take();
                        (
                            PROXIMAL,
                            centre.unwrap_or_else(|| vec![0.0; self.problem.n_dofs]),
                        )
                    });
                    let (u, force, x) =
                        self.solve_statuses(f, &status, &prior, Some((*w, centre.as_slice())))?;
                    (u, force, x, false)
                }
            };
            let jumps = self.jumps(&u);
            let mut next = self.corrected(f, &status, &u, &jumps, (&force, true));
            // Row by row the corrections cycle (a status set seen before): so do they where
            // the rows about the bodies concerned are decided together.
            if exact && (local || seen.contains(&next)) {
                if let Some(l) = self.local_retry(f, (&status, &next, &force), &seen) {
                    local = true;
                    next = l;
                }
            }
            let changes = next.iter().zip(&status).filter(|(a, b)| a != b).count();
            if next == status && exact {
                return self.accepted(f, &status, u, force);
            }
            if next == status {
                // The statuses hold with the spring: solved exactly they either settle the
                // step or leave a body free, which a lighter spring lets move further.
                if let Some((u, force, _)) = self.solve_statuses(f, &status, &prior, None) {
                    let jumps = self.jumps(&u);
                    if self.corrected(f, &status, &u, &jumps, (&force, true)) == status {
                        return self.accepted(f, &status, u, force);
                    }
                }
                if let Some(p) = prox.as_mut() {
                    *p = ((p.0 * 0.1).max(PROXIMAL_MIN), x);
                }
                prior = force;
                continue;
            }
            // Where only forces break a law they may be a junction's inadmissible
            // distribution: the least-norm admissible one decides.
            if exact && self.corrected(f, &status, &u, &jumps, (&force, false)) == status {
                let (trial, laws) = self.programme_of(f, &status, u.clone(), force.clone());
                let strict = (&trial, true);
                if let Some(fair) = self.distribute(f.model, &laws, f.normal, f.cohesion, strict) {
                    return self.accepted(f, &status, u, fair);
                }
            }
            // A pair with cohesion that would open changes the loads (cohesion is brittle):
            // the fixed point handles that.
            if next
                .iter()
                .zip(f.cohesion)
                .any(|(s, c)| *c != 0.0 && *s == Status::Off)
            {
                return None;
            }
            seen.push(std::mem::replace(&mut status, next));
            prior = force;
            match prox.as_mut() {
                // The spring is a trust region: its centre follows the solutions; after a
                // few changes it is made lighter (a free body creeps towards what stops it:
                // let it go further), after many it starts again from the heaviest.
                Some(p) => {
                    let w = if changes <= FEW_CHANGES {
                        (p.0 * 0.1).max(PROXIMAL_MIN)
                    } else {
                        PROXIMAL
                    };
                    *p = (w, x);
                }
                None => last = Some(x),
            }
            if seen.contains(&status) {
                return None;
            }
        }
        None
    }

    /// The corrections of one solved round (statuses, corrected statuses, forces) with the
    /// Coulomb rows about the bodies they change decided together (`local_statuses`), where
    /// that gives a status set other than the statuses and not one of `seen`.
    fn local_retry(
        &self,
        f: &Finish,
        (status, next, force): (&[Status], &[Status], &[f64]),
        seen: &[Vec<Status>],
    ) -> Option<Vec<Status>> {
        let l = self.local_statuses(f, status, next, force)?;
        (l != status && !seen.contains(&l)).then_some(l)
    }

    /// The solution of settled statuses where slipping rows are pushed (a positive normal
    /// force beyond the cohesion term) and the bodies balance in their own units (as every
    /// programme's solution must).
    fn accepted(
        &self,
        f: &Finish,
        status: &[Status],
        u: Vec<f64>,
        force: Vec<f64>,
    ) -> Option<(Programme, Vec<RowLaw>)> {
        let (tol_f, _) = self.tolerances(f, &u, &force);
        let pushed = (0..status.len()).all(|r| match (status[r], f.normal[r]) {
            (Status::Slip(_), Some(n)) => force[n] - f.cohesion[n] >= -tol_f,
            _ => true,
        });
        let balanced =
            self.balance_residual(f.factor, f.cohesion, &u, &force) <= super::BALANCE_TOLERANCE;
        (pushed && balanced).then(|| self.programme_of(f, status, u, force))
    }

    /// A row's status from the programme's.
    fn first_status(&self, f: &Finish, laws: &[RowLaw], sol: &Programme, r: usize) -> Status {
        let row = &self.problem.full[r].row;
        let normal_closed = f.normal[r].is_some_and(|n| sol.closed[n]);
        match (laws[r], row.kind) {
            (RowLaw::Tie(v), RowKind::Bonded | RowKind::Stick) => Status::Fixed(v),
            (RowLaw::Gap, _) if sol.closed[r] => Status::Fixed(-row.gap),
            (_, RowKind::Friction) if normal_closed => {
                if sol.slipping[r] || matches!(laws[r], RowLaw::Free) {
                    let slip = self.jump(r, &sol.u) - f.start[r];
                    let sense = if sol.force[r] != 0.0 {
                        sol.force[r].signum()
                    } else if slip != 0.0 {
                        -slip.signum()
                    } else {
                        1.0
                    };
                    Status::Slip(sense)
                } else {
                    Status::Fixed(f.start[r])
                }
            }
            _ => Status::Off,
        }
    }

    /// Every dof's displacement and every row's force for the statuses, or None where the
    /// system is singular or its solution is not finite. Where the forces are not unique
    /// (dependent rows at junctions) they are the ones nearest `prior` (the compliance pulls
    /// them there): the last programme's, which obey the laws.
    fn solve_statuses(
        &self,
        f: &Finish,
        status: &[Status],
        prior: &[f64],
        prox: Option<(f64, &[f64])>,
    ) -> Option<(Vec<f64>, Vec<f64>, Vec<f64>)> {
        self.status_system(f, status, prox)?.solve(self, prior)
    }

    /// The statuses the solution `u`, `force` of `status` calls for: the same where every
    /// law holds (every law on displacements only, without `forces`).
    fn corrected(
        &self,
        f: &Finish,
        status: &[Status],
        u: &[f64],
        jumps: &[f64],
        (force, forces): (&[f64], bool),
    ) -> Vec<Status> {
        let full = &self.problem.full;
        let (tol_f, tol_u) = self.tolerances(f, u, force);
        // Without `forces` only the laws on displacements are checked.
        let tol_f = if forces { tol_f } else { f64::INFINITY };
        let mut next = status.to_vec();
        // Normal rows first: the tangential rows follow their pair.
        for (r, fr) in full.iter().enumerate() {
            if fr.row.kind != RowKind::Normal {
                continue;
            }
            next[r] = match status[r] {
                Status::Fixed(_) if force[r] < -tol_f => Status::Off,
                Status::Off if jumps[r] + fr.row.gap < -tol_u => Status::Fixed(-fr.row.gap),
                s => s,
            };
        }
        for (r, fr) in full.iter().enumerate() {
            let closed = f.normal[r].map(|n| next[n] != Status::Off);
            // A stick row follows its pair where the pair's status changed (one that the
            // fixed point left untied at a closed pair stays so).
            let moved = f.normal[r].is_some_and(|n| next[n] != status[n]);
            next[r] = match (fr.row.kind, closed) {
                (RowKind::Stick, Some(true)) if moved => Status::Fixed(f.start[r]),
                (RowKind::Stick, Some(false)) => Status::Off,
                (RowKind::Friction, Some(false)) => Status::Off,
                (RowKind::Friction, Some(true)) => {
                    let nr = f.normal[r].unwrap_or(r);
                    let bound = self.mu(f.model, r) * (force[nr] - f.cohesion[nr]).max(0.0);
                    let slip = jumps[r] - f.start[r];
                    match status[r] {
                        Status::Fixed(_) if force[r].abs() > bound + tol_f => {
                            Status::Slip(force[r].signum())
                        }
                        Status::Slip(sense)
                            if sense * slip > tol_u * SLIP_TOLERANCE / MOTION_TOLERANCE =>
                        {
                            Status::Fixed(f.start[r])
                        }
                        Status::Off => Status::Slip(if slip != 0.0 { -slip.signum() } else { 1.0 }),
                        s => s,
                    }
                }
                _ => next[r],
            };
        }
        next
    }

    /// The forces' and displacements' tolerances of the law checks.
    fn tolerances(&self, f: &Finish, u: &[f64], force: &[f64]) -> (f64, f64) {
        let big_f = f
            .normal
            .iter()
            .flatten()
            .map(|&n| force[n].abs())
            .fold(0.0f64, f64::max);
        let big_u = u.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        (
            LAW_TOLERANCE * big_f.max(f64::MIN_POSITIVE),
            MOTION_TOLERANCE * big_u.max(f64::MIN_POSITIVE),
        )
    }

    /// The programme-like result of settled statuses, and the laws it obeys.
    fn programme_of(
        &self,
        f: &Finish,
        status: &[Status],
        u: Vec<f64>,
        force: Vec<f64>,
    ) -> (Programme, Vec<RowLaw>) {
        let full = &self.problem.full;
        let m = full.len();
        let (_, tol_u) = self.tolerances(f, &u, &force);
        // A normal row without force whose gap is closed (to MOTION_TOLERANCE of the largest
        // displacement) touches: at a junction it may carry force as well (the distribution
        // of junction forces is then the least-norm one over every admissible set, not only
        // over the rows the statuses happened to close).
        let jumps = self.jumps(&u);
        let touching: Vec<bool> = (0..m)
            .map(|r| {
                let row = &full[r].row;
                row.kind == RowKind::Normal
                    && (status[r] != Status::Off || (jumps[r] + row.gap).abs() <= tol_u)
            })
            .collect();
        let mut closed = vec![false; m];
        let mut slipping = vec![false; m];
        let mut laws = vec![RowLaw::Free; m];
        for (r, fr) in full.iter().enumerate() {
            let s = status[r];
            let pair_touches = f.normal[r].is_some_and(|n| touching[n]);
            let tangential = matches!(fr.row.kind, RowKind::Friction | RowKind::Stick);
            closed[r] = s != Status::Off || touching[r] || (tangential && pair_touches);
            laws[r] = match (fr.row.kind, s) {
                (RowKind::Normal, _) => RowLaw::Gap,
                (RowKind::Stick, Status::Off) if pair_touches => RowLaw::Tie(f.start[r]),
                (RowKind::Friction, Status::Off) if !pair_touches => RowLaw::Free,
                (RowKind::Friction, s) => {
                    let nr = f.normal[r].unwrap_or(r);
                    // A row at its bound that does not move is sticking as well: the
                    // distribution of junction forces keeps it within its cone, not on it.
                    slipping[r] =
                        matches!(s, Status::Slip(_)) && (jumps[r] - f.start[r]).abs() > tol_u;
                    RowLaw::Tresca {
                        bound: self.mu(f.model, r) * (force[nr] - f.cohesion[nr]).max(0.0),
                        anchor: f.start[r],
                    }
                }
                (_, Status::Fixed(v)) => RowLaw::Tie(v),
                _ => RowLaw::Free,
            };
        }
        (
            Programme {
                u,
                force,
                closed,
                slipping,
                iterations: 0,
            },
            laws,
        )
    }
}
