//! The full-row solver as a load step of the contact session: its result in the form every
//! solver gives, and the verdict on a step that did not settle (docs/formulation.md §6.10).

use super::{Exact, Programme, StepFailure, FULL_ROW_PROGRAMMES};
use crate::contact::problem::RowKind;

impl crate::contact::Session<'_> {
    /// One load step of the full-row solver from `start` (see the module doc): the result
    /// in the form every solver gives, one recorded state per step.
    ///
    /// On the solver's first step (no anchors yet) the sparse solver's statuses for the same
    /// step are the seed of the linear solve of Coulomb's law (`newton`): where they settle
    /// there, no convex programme is needed (the sparse solver leaves a junction's dependent
    /// components without a row; the linear solve gives each its own law).
    pub(in crate::contact) fn solve_step_full(
        &mut self,
        start: &crate::contact::StepState,
        (tol, max_iterations): (f64, usize),
        load_step: usize,
        factor: f64,
        record: bool,
    ) -> crate::contact::ContactResult {
        use crate::contact::{ContactResult, Iterate, Solver};
        // The seed: the sparse solver's pairs for this step, or where it does not settle
        // them, those of the last step solved from rest (in a collapse search, the last
        // trial that stood: where the load changes little, so do the statuses).
        let from_rest = start.full_anchor.is_empty();
        let sparse = if from_rest {
            let x = self.solve_step(
                start,
                Solver::Sparse,
                tol,
                max_iterations.min(SEED_ITERATIONS),
                load_step,
                factor,
                false,
            );
            (x.converged && x.failure.is_none()).then_some(x.interfaces)
        } else {
            None
        };
        let (warm, seeded_by) = match (&sparse, &self.last_from_rest) {
            (Some(w), _) => (Some(w), "the sparse solver's statuses"),
            (None, Some(w)) if from_rest => (
                Some(w),
                "the statuses of the last step solved from rest (the last trial that stood)",
            ),
            _ => (None, ""),
        };
        let (model, pb) = (self.model, &self.problem);
        let mut ex = Exact::new(pb);
        ex.show_in(self.stage.as_ref(), load_step);
        let n_full = pb.full.len();
        // Before the solver's first step: no slip yet.
        let or_zeros = |v: &[f64]| {
            if v.len() == n_full {
                v.to_vec()
            } else {
                vec![0.0; n_full]
            }
        };
        let (anchor, path0) = (or_zeros(&start.full_anchor), or_zeros(&start.full_path));
        // The cohesion term c w of unilateral normal rows, with the cohesion left.
        let mut cohesion: Vec<f64> = pb
            .full
            .iter()
            .map(|f| match f.row.kind {
                RowKind::Normal => start.cohesion[f.row.iface][f.row.pair] * f.row.weight,
                _ => 0.0,
            })
            .collect();
        let seed = warm.map(|w| ex.seed(model, w, &cohesion, &anchor));
        let out = ex.step(
            model,
            factor,
            (&anchor, seed),
            &mut cohesion,
            FULL_ROW_PROGRAMMES,
        );
        let info = crate::solution::SolverInfo {
            iterations: Some(u32::try_from(out.ipm_iterations).unwrap_or(u32::MAX)),
            variables: Some(pb.n_dofs),
            constraints: Some(n_full),
            ..Default::default()
        };
        let mut notes = Vec::new();
        let (programmes, residual) = (out.programmes, out.residual);
        let StepVerdict {
            sol,
            failure,
            mechanism,
            motion,
            undecided,
        } = self.verdict(out.result, load_step, programmes, residual);
        if out.programmes > 1 || out.finished {
            notes.push(format!(
                "load step {}: the full-row solver took {} convex programme{} ({} interior \
                 point iterations){}",
                load_step + 1,
                out.programmes,
                if out.programmes == 1 { "" } else { "s" },
                out.ipm_iterations,
                match (out.finished, out.programmes) {
                    (true, 0) => format!("; settled by the linear solve of {seeded_by}"),
                    (true, _) =>
                        "; Coulomb's law settled by the linear solve of the last statuses".into(),
                    _ => String::new(),
                }
            ));
        }
        // Without a solution (a mechanism, a failure): the state of every pair tied, for
        // the record, at zero displacement.
        let zero = Programme {
            u: vec![0.0; pb.n_dofs],
            force: vec![0.0; n_full],
            closed: vec![true; n_full],
            slipping: vec![false; n_full],
            iterations: 0,
        };
        let solved = sol.is_some();
        let sol = sol.unwrap_or(zero);
        let frs = crate::contact::problem::FullRowSolution {
            u: &sol.u,
            force: &sol.force,
            closed: &sol.closed,
            slipping: &sol.slipping,
            cohesion: &cohesion,
        };
        let (fields, mut interfaces, nodal_force) =
            pb.full_row_state(model, self.prepared, factor, &frs);
        // The next step's anchors and the slip paths of closed friction pairs.
        let jumps = ex.jumps(&sol.u);
        let mut path = path0;
        let friction = pb
            .full
            .iter()
            .enumerate()
            .filter(|(_, f)| f.row.kind == RowKind::Friction);
        for (r, f) in friction.filter(|_| solved) {
            let res = &mut interfaces[f.row.iface].pairs[f.row.pair];
            if res.status == crate::solution::PairStatus::Closed {
                path[r] += (jumps[r] - anchor[r]).abs();
            }
            res.slip = path[r];
        }
        if solved && from_rest {
            self.last_from_rest = Some(interfaces.clone());
        }
        let mut state = start.clone();
        if solved {
            state.full_anchor = jumps;
            state.full_path = path;
            for (k, it) in interfaces.iter().enumerate() {
                for (j, p) in it.pairs.iter().enumerate() {
                    if p.status == crate::solution::PairStatus::Open {
                        state.cohesion[k][j] = 0.0;
                        state.broken[k][j] = true;
                    }
                }
            }
        }
        let method = Solver::Exact;
        let rows = vec![crate::contact::history_row(
            model,
            &interfaces,
            load_step,
            factor,
            out.programmes,
            method.name(),
        )];
        let states = if record {
            vec![Iterate {
                load_step,
                load_factor: factor,
                time: model.time,
                body_force: self.body_forces(),
                iteration: out.programmes,
                index: 0,
                fields: fields.clone(),
                interfaces: interfaces.clone(),
            }]
        } else {
            Vec::new()
        };
        ContactResult {
            state,
            fields,
            interfaces,
            nodal_force,
            iterations: out.programmes,
            outer_iterations: out.programmes,
            converged: failure.is_none(),
            solver: method.name(),
            residual: if solved { out.residual } else { f64::INFINITY },
            rows,
            states,
            notes,
            failure,
            mechanism,
            motion,
            undecided,
            info,
            recorded: Vec::new(),
            start: start.clone(),
            load_step,
            load_factor: factor,
        }
    }

    /// The step's solution and its failure, if any, from the full-row step's result.
    fn verdict(
        &self,
        result: Result<Programme, StepFailure>,
        load_step: usize,
        programmes: usize,
        residual: f64,
    ) -> StepVerdict {
        let step = load_step + 1;
        let failed = |message: String, sol, undecided| StepVerdict {
            sol,
            failure: Some(crate::error::Error::numerical(message)),
            mechanism: false,
            motion: None,
            undecided,
        };
        match result {
            Ok(sol) => StepVerdict {
                sol: Some(sol),
                failure: None,
                mechanism: false,
                motion: None,
                undecided: false,
            },
            Err(StepFailure::NotSettled(sol)) => failed(
                format!(
                    "the contact solver (exact) did not settle Coulomb's law at load step \
                     {step} in {programmes} convex programmes{}: the last relative residual \
                     of the law was {residual:.1e}; use smaller load steps (more values in \
                     solve.time or load_factors)",
                    if programmes < FULL_ROW_PROGRAMMES {
                        " (the last 50 did not halve its residual)"
                    } else {
                        ""
                    }
                ),
                Some(sol),
                true,
            ),
            Err(StepFailure::Mechanism(du)) => {
                let motions = self.problem.rigid_fit(self.model, &du);
                let (words, found) = crate::contact::mechanism::motion_of(self.model, motions);
                StepVerdict {
                    sol: None,
                    failure: Some(crate::error::Error::numerical(format!(
                        "the contact solver (exact) at load step {step}: no equilibrium \
                         exists, the bodies' energy with every pair's law has no minimum (a \
                         mechanism){words}"
                    ))),
                    mechanism: true,
                    motion: found,
                    undecided: false,
                }
            }
            Err(StepFailure::Failed(m)) => failed(
                format!(
                    "the contact solver (exact) failed at load step {step}: the convex \
                     programme did not solve ({m})"
                ),
                None,
                true,
            ),
        }
    }
}

/// What a full-row step gives the driver: its solution (none at a mechanism or a failure)
/// and its failure.
struct StepVerdict {
    sol: Option<Programme>,
    failure: Option<crate::error::Error>,
    mechanism: bool,
    motion: Option<Vec<crate::solution::BodyMotion>>,
    undecided: bool,
}

/// The iterations the sparse solver may spend on the seed of a step (its walls of up to 4 128
/// bricks take 12–32; a step without equilibrium can take thousands in its evolutive
/// fallback, and the seed is only a start).
const SEED_ITERATIONS: usize = 60;
