//! The linear system of one set of statuses (newton's module doc): every dof and the force
//! of every row with a status, factored by a sparse LU on one thread.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::lu;
use faer::sparse::{SparseColMat, SparseColMatRef, Triplet};
use faer::{Conj, Mat, Par};

use super::newton::{Finish, Status};
use super::Exact;

/// The compliance of the fixed rows in the scaled unknowns (unit diagonal, unit rows).
const COMPLIANCE: f64 = 1e-10;

/// Iterative refinement steps against the unregularised equations.
const REFINE: usize = 4;

impl Exact<'_> {
    /// The factored linear system of the statuses (see the module doc), or None where it is
    /// singular.
    pub(super) fn status_system(
        &self,
        f: &Finish,
        status: &[Status],
        prox: Option<(f64, &[f64])>,
    ) -> Option<StatusSystem> {
        let pb = self.problem;
        let n = pb.n_dofs;
        let (q, qs) = self.linear_term(f.factor, f.cohesion);
        // Unknowns: x (U = d qs x), then y_r = λ_r ρ_r / qs of the rows with a force.
        let mut var = vec![usize::MAX; pb.full.len()];
        let mut nv = n;
        for (r, s) in status.iter().enumerate() {
            if *s != Status::Off {
                var[r] = nv;
                nv += 1;
            }
        }
        let mut exact: Vec<Triplet<usize, usize, f64>> = Vec::new();
        for (j, w) in self.p_cols.windows(2).enumerate() {
            for k in w[0]..w[1] {
                let i = self.p_rows[k];
                exact.push(Triplet::new(i, j, self.p_vals[k]));
                if i != j {
                    exact.push(Triplet::new(j, i, self.p_vals[k]));
                }
            }
        }
        let mut rhs = vec![0.0; nv];
        for k in 0..n {
            rhs[k] = -q[k] / qs;
        }
        if let Some((w, centre)) = prox {
            for k in 0..n {
                exact.push(Triplet::new(k, k, w));
                rhs[k] += w * centre[k];
            }
        }
        let mut compliance = Vec::new();
        for (r, s) in status.iter().enumerate() {
            let i = var[r];
            if i == usize::MAX {
                continue;
            }
            let rho = self.rho[r];
            for &(k, c) in &pb.full[r].coefs {
                let a = c * self.d[k] / rho;
                exact.push(Triplet::new(k, i, -a));
                if let Status::Fixed(_) = s {
                    exact.push(Triplet::new(i, k, a));
                }
            }
            match *s {
                Status::Fixed(v) => {
                    rhs[i] = v / (rho * qs);
                    compliance.push(Triplet::new(i, i, -COMPLIANCE));
                }
                Status::Slip(sense) => {
                    let nr = f.normal[r]?;
                    let jn = var[nr];
                    if jn == usize::MAX {
                        return None;
                    }
                    let mu = self.mu(f.model, r);
                    exact.push(Triplet::new(i, i, 1.0));
                    exact.push(Triplet::new(i, jn, -sense * mu * rho / self.rho[nr]));
                    rhs[i] = -sense * mu * rho * f.cohesion[nr] / qs;
                }
                Status::Off => {}
            }
        }
        let k_exact = SparseColMat::<usize, f64>::try_new_from_triplets(nv, nv, &exact).ok()?;
        let mut reg = exact;
        reg.extend(compliance);
        let k_reg = SparseColMat::<usize, f64>::try_new_from_triplets(nv, nv, &reg).ok()?;
        let lu = SeqLu::new(k_reg.as_ref())?;
        Some(StatusSystem {
            k_exact,
            lu,
            var,
            rhs,
            qs,
        })
    }
}

/// The factored linear system of one set of statuses.
pub(super) struct StatusSystem {
    k_exact: SparseColMat<usize, f64>,
    /// The LU factors of the system with the fixed rows' compliance.
    pub(super) lu: SeqLu,
    /// The unknown of each row's force (usize::MAX: none).
    pub(super) var: Vec<usize>,
    rhs: Vec<f64>,
    /// The scale of the loads.
    pub(super) qs: f64,
}

impl StatusSystem {
    /// The number of unknowns.
    pub(super) fn size(&self) -> usize {
        self.rhs.len()
    }

    /// Every dof's displacement, every row's force and the scaled unknowns x, forces nearest
    /// `prior`, or None where the solution is not finite or drifts.
    pub(super) fn solve(
        &self,
        ex: &Exact,
        prior: &[f64],
    ) -> Option<(Vec<f64>, Vec<f64>, Vec<f64>)> {
        let n = ex.problem.n_dofs;
        let nv = self.rhs.len();
        let qs = self.qs;
        // z = z₀ + w with z₀ the prior forces: w the least-norm correction (refinement
        // against the unregularised system converges to it).
        let mut z0 = Mat::<f64>::zeros(nv, 1);
        for (r, &i) in self.var.iter().enumerate() {
            if i != usize::MAX {
                z0[(i, 0)] = prior[r] * ex.rho[r] / qs;
            }
        }
        let b = Mat::<f64>::from_fn(nv, 1, |i, _| self.rhs[i]) - &self.k_exact * &z0;
        let mut z = self.lu.solve(&b)?;
        for _ in 0..REFINE {
            let res = &b - &self.k_exact * &z;
            z += self.lu.solve(&res)?;
        }
        z += &z0;
        let z: Vec<f64> = (0..nv).map(|i| z[(i, 0)]).collect();
        if z.iter().any(|v| !v.is_finite()) || z[..n].iter().any(|v| v.abs() > super::DRIFT_LIMIT) {
            return None;
        }
        let u: Vec<f64> = (0..n).map(|k| ex.d[k] * qs * z[k]).collect();
        let force: Vec<f64> = (0..ex.problem.full.len())
            .map(|r| match self.var[r] {
                usize::MAX => 0.0,
                i => z[i] * qs / ex.rho[r],
            })
            .collect();
        Some((u, force, z[..n].to_vec()))
    }
}

/// A sparse LU factorisation made and used on one thread: faer's threads (its global
/// parallelism) cost more in waiting than they gained on these systems (the 798-brick wall's
/// 83 500 unknowns: 2.0–2.6 s a factorisation with two threads, 1.4–1.5 s with one, on a
/// quiet 2-core machine), as on the sparse solver's (`sparse.rs`).
pub(super) struct SeqLu {
    symbolic: lu::SymbolicLu<usize>,
    numeric: lu::NumericLu<usize, f64>,
}

impl SeqLu {
    /// The factors of `mat`, or None where it is singular or memory is short.
    fn new(mat: SparseColMatRef<'_, usize, f64>) -> Option<SeqLu> {
        let symbolic = lu::factorize_symbolic_lu(mat.symbolic(), Default::default()).ok()?;
        let req = symbolic.factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default());
        let mut buf = MemBuffer::try_new(req).ok()?;
        let mut numeric = lu::NumericLu::new();
        symbolic
            .factorize_numeric_lu(
                &mut numeric,
                mat,
                Par::Seq,
                MemStack::new(&mut buf),
                Default::default(),
            )
            .ok()?;
        Some(SeqLu { symbolic, numeric })
    }

    /// The solution of the factored system for the columns of `b` (None where memory for
    /// the work space is short).
    pub(super) fn solve(&self, b: &Mat<f64>) -> Option<Mat<f64>> {
        let mut x = b.clone();
        let req = self
            .symbolic
            .solve_in_place_scratch::<f64>(x.ncols(), Par::Seq);
        let mut buf = MemBuffer::try_new(req).ok()?;
        lu::LuRef::new_unchecked(&self.symbolic, &self.numeric).solve_in_place_with_conj(
            Conj::No,
            x.as_mut(),
            Par::Seq,
            MemStack::new(&mut buf),
        );
        Some(x)
    }
}
