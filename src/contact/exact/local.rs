//! The stick/slip statuses about a few bodies as one small Tresca problem: where the linear
//! solve's corrections (`newton`) change the status of Coulomb rows at closed pairs, the rows
//! of the bodies concerned are decided together instead of row by row
//! (docs/formulation.md §6.10, "Local Tresca step").
//!
//! Row by row, the primal-dual active set cycles where a body's contact slips at both ends
//! and sticks over a few rows between: a sticking row whose force exceeds its bound turns
//! slipping, and the body is then free (every row slipping, its head joints open) or the
//! others slip against their force and turn sticking again. Together the rows of those bodies
//! are the minimiser of `½ sᵀK s + λ₀ᵀs + Σ g|s|` over their slips s, with K the stiffness of
//! the rows (the rest of the model held in its statuses), λ₀ their forces with every one of
//! them stuck at its anchor and g the bounds of those forces' normal rows: a small convex
//! programme whose solution slips a row only where its force is on its bound, and never leaves
//! a body free while an equilibrium exists.

use clarabel::solver::{DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT};
use faer::Mat;

use super::newton::{Finish, Status};
use super::{csc, Exact};
use crate::contact::problem::RowKind;

/// The most rows a local step decides together (their stiffness is dense).
const LOCAL_ROWS: usize = 600;

impl Exact<'_> {
    /// The statuses `next` with the Coulomb rows about the bodies where `next` changes the
    /// status of one at a closed pair decided together (the normal rows as `next` has them),
    /// or None where there is no such change, the rows are too many, or the small programme
    /// does not solve.
    pub(super) fn local_statuses(
        &self,
        f: &Finish,
        status: &[Status],
        next: &[Status],
        prior: &[f64],
    ) -> Option<Vec<Status>> {
        let full = &self.problem.full;
        let model = f.model;
        let mut bodies = std::collections::BTreeSet::new();
        for r in 0..full.len() {
            let closed = f.normal[r].is_some_and(|n| matches!(next[n], Status::Fixed(_)));
            if next[r] == status[r] || full[r].row.kind != RowKind::Friction || !closed {
                continue;
            }
            let it = &model.interfaces[full[r].row.iface];
            bodies.insert(it.body_a);
            bodies.insert(it.body_b);
        }
        if bodies.is_empty() {
            return None;
        }
        // A dof of two pairs is a junction's (or a body's corner between two joints): rows
        // there are dependent on others and keep the statuses they have.
        let mut owner: std::collections::HashMap<usize, (usize, usize)> = Default::default();
        let mut junction = std::collections::HashSet::new();
        for fr in full {
            let id = (fr.row.iface, fr.row.pair);
            for &(dof, _) in &fr.coefs {
                let o = owner.entry(dof).or_insert(id);
                if *o != id {
                    junction.insert(dof);
                }
            }
        }
        // The Coulomb rows of closed pairs on the interfaces of those bodies.
        let set: Vec<usize> = (0..full.len())
            .filter(|&r| !full[r].coefs.iter().any(|(dof, _)| junction.contains(dof)))
            .filter(|&r| {
                let it = &model.interfaces[full[r].row.iface];
                full[r].row.kind == RowKind::Friction
                    && self.mu(model, r) > 0.0
                    && f.normal[r].is_some_and(|n| matches!(next[n], Status::Fixed(_)))
                    && (bodies.contains(&it.body_a) || bodies.contains(&it.body_b))
            })
            .collect();
        let k = set.len();
        if k == 0 || k > LOCAL_ROWS {
            return None;
        }
        // Every row of the set stuck at its anchor: the forces λ₀, the bounds g, and the
        // stiffness K_ij = ∂λ_i/∂v_j of the rows (the system's inverse at the rows).
        let mut held = next.to_vec();
        for &r in &set {
            held[r] = Status::Fixed(f.start[r]);
        }
        let sys = self.status_system(f, &held, None)?;
        let (_, force, _) = sys.solve(self, prior)?;
        let cols: Vec<usize> = set.iter().map(|&r| sys.var[r]).collect();
        let nrows = sys.size();
        // inv[a][b]: the system's inverse at rows a, b of the set, 64 columns at a time.
        let mut inv = vec![0.0; k * k];
        for c0 in (0..k).step_by(64) {
            let c1 = (c0 + 64).min(k);
            let e = Mat::<f64>::from_fn(
                nrows,
                c1 - c0,
                |i, j| {
                    if i == cols[c0 + j] {
                        1.0
                    } else {
                        0.0
                    }
                },
            );
            let x = sys.solve_columns(&e)?;
            for a in 0..k {
                for b in c0..c1 {
                    inv[a * k + b] = x[(cols[a], b - c0)];
                }
            }
        }
        let mut stiff = vec![0.0; k * k];
        for a in 0..k {
            for b in 0..k {
                let rr = self.rho[set[a]] * self.rho[set[b]];
                stiff[a * k + b] = 0.5 * (inv[a * k + b] + inv[b * k + a]) / rr;
            }
        }
        let bound: Vec<f64> = set
            .iter()
            .map(|&r| {
                let nr = f.normal[r].unwrap_or(r);
                self.mu(model, r) * (force[nr] - f.cohesion[nr]).max(0.0)
            })
            .collect();
        let lambda0: Vec<f64> = set.iter().map(|&r| force[r]).collect();
        let slips = tresca(&stiff, &lambda0, &bound)?;
        // Statuses: a row slips where it moves (beyond the law checks' tolerance on
        // displacements) with its force on its bound.
        let big_u = slips.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let tol = (1e-6 * big_u).max(f64::MIN_POSITIVE);
        let mut out = next.to_vec();
        for (a, &r) in set.iter().enumerate() {
            let lam = lambda0[a] + (0..k).map(|b| stiff[a * k + b] * slips[b]).sum::<f64>();
            out[r] = if slips[a].abs() > tol && bound[a] > 0.0 {
                Status::Slip(if lam != 0.0 {
                    lam.signum()
                } else {
                    -slips[a].signum()
                })
            } else {
                Status::Fixed(f.start[r])
            };
        }
        Some(out)
    }
}

/// The minimiser s of `½ sᵀK s + λ₀ᵀs + Σ g|s|` (K dense, k × k, symmetric positive
/// semidefinite), or None where the programme does not solve (unbounded: the rows leave a
/// body free under these bounds).
fn tresca(stiff: &[f64], lambda0: &[f64], bound: &[f64]) -> Option<Vec<f64>> {
    let k = lambda0.len();
    // s = d s̃ with d = K_ii^(−½): a unit diagonal; the linear terms over their largest.
    let d: Vec<f64> = (0..k)
        .map(|i| {
            let kii = stiff[i * k + i];
            if kii > 0.0 {
                1.0 / kii.sqrt()
            } else {
                1.0
            }
        })
        .collect();
    let scale = (0..k)
        .map(|i| (d[i] * lambda0[i]).abs().max(d[i] * bound[i]))
        .fold(0.0f64, f64::max)
        .max(f64::MIN_POSITIVE);
    // The stiffness is symmetrised from a system that is not symmetric where other rows
    // slip, and its rigid modes are zero only to round-off: its negative eigenvalues are
    // set to zero (a positive semidefinite programme).
    let scaled = Mat::<f64>::from_fn(k, k, |i, j| d[i] * stiff[i * k + j] * d[j]);
    let eig = scaled.self_adjoint_eigen(faer::Side::Lower).ok()?;
    let (vecs, vals) = (eig.U(), eig.S().column_vector());
    let mut p = Vec::new();
    for j in 0..k {
        for i in 0..=j {
            let v: f64 = (0..k)
                .filter(|&m| vals[m] > 0.0)
                .map(|m| vecs[(i, m)] * vals[m] * vecs[(j, m)])
                .sum::<f64>()
                / scale;
            if v != 0.0 {
                p.push((i, j, v));
            }
        }
    }
    let p = csc(2 * k, 2 * k, p);
    let mut q = vec![0.0; 2 * k];
    for i in 0..k {
        q[i] = d[i] * lambda0[i] / scale;
        q[k + i] = d[i] * bound[i] / scale;
    }
    // w ≥ |s̃|:  s̃ − w ≤ 0,  −s̃ − w ≤ 0.
    let mut a = Vec::new();
    for i in 0..k {
        a.push((i, i, 1.0));
        a.push((i, k + i, -1.0));
        a.push((k + i, i, -1.0));
        a.push((k + i, k + i, -1.0));
    }
    let a = csc(2 * k, 2 * k, a);
    let b = vec![0.0; 2 * k];
    let cones = [NonnegativeConeT(2 * k)];
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .tol_gap_abs(1e-12)
        .tol_gap_rel(1e-12)
        .tol_feas(1e-12)
        .max_iter(200)
        .build()
        .ok()?;
    let mut solver = DefaultSolver::new(&p, &q, &a, &b, &cones, settings).ok()?;
    solver.solve();
    use clarabel::solver::SolverStatus;
    match solver.solution.status {
        SolverStatus::Solved
        | SolverStatus::AlmostSolved
        | SolverStatus::InsufficientProgress
        | SolverStatus::MaxIterations => {}
        _ => return None,
    }
    Some((0..k).map(|i| d[i] * solver.solution.x[i]).collect())
}

#[cfg(test)]
mod tests {
    use super::tresca;

    fn close(a: &[f64], b: &[f64]) -> bool {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 1e-7)
    }

    /// One row: `s² + 3s + |s|` is least at s = −1 (its force 3 + 2s = 1 on its bound,
    /// against the slip); with a force 0.5 within the bound 1 it sticks.
    #[test]
    fn one_row_slips_only_beyond_its_bound() {
        let s = tresca(&[2.0], &[3.0], &[1.0]).unwrap();
        assert!(close(&s, &[-1.0]), "{s:?}");
        let s = tresca(&[2.0], &[0.5], &[1.0]).unwrap();
        assert!(close(&s, &[0.0]), "{s:?}");
    }

    /// Two rows of a body free to move along (1, −1) (K = [[1, 1], [1, 1]]): with bounds
    /// 0.55 and 0.7 against forces 1 and −0.2 the first slips by −0.45 (its force
    /// 1 + s₁ = 0.55 on its bound), the second sticks (force −0.65 within 0.7); with bounds
    /// 0.5 and 0.5 the net force 1.2 exceeds what both can hold: no minimum.
    #[test]
    fn a_free_body_slips_on_one_row_and_sticks_on_the_other() {
        let k = [1.0, 1.0, 1.0, 1.0];
        let s = tresca(&k, &[1.0, -0.2], &[0.55, 0.7]).unwrap();
        assert!(close(&s, &[-0.45, 0.0]), "{s:?}");
        assert!(tresca(&k, &[1.0, -0.2], &[0.5, 0.5]).is_none());
    }
}
