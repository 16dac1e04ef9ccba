//! The linear system of one set of statuses (newton's module doc), factored by a sparse LU
//! on one thread.
//!
//! Every set of statuses has the same pattern ([`Layout`]): the unknowns x of every dof,
//! then y_r of every full row — an open row's by its own equation `y_r = 0` — with every
//! entry a status can give (a row's coefficients in its row and its column, a slipping row's
//! coupling to its normal row). The pattern and its symbolic LU (the column ordering and
//! the supernodes) are made once per step, and each status's values are written into it
//! at known positions: a status costs the numeric factorisation alone, where the triplets'
//! assembly and a symbolic analysis per status came to 0.5 s of the 3 s of each of the
//! 798-brick wall's factorisations (docs/performance.md).

use std::cell::RefCell;
use std::rc::Rc;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::lu;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, Mat, Par};

use super::newton::{Finish, Status};
use super::Exact;

/// The compliance of the fixed rows in the scaled unknowns (unit diagonal, unit rows).
const COMPLIANCE: f64 = 1e-10;

/// Iterative refinement steps against the unregularised equations.
const REFINE: usize = 4;

/// The pattern of every status's system and where each entry sits in it.
pub(super) struct Layout {
    size: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// The positions of P's entries (upper triangle, in `Exact::p_rows` order) and of their
    /// mirrors (`usize::MAX` on the diagonal).
    p_pos: Vec<[usize; 2]>,
    /// The position of every unknown's diagonal entry.
    diag: Vec<usize>,
    /// From `coef_start[r]`: the positions of the entries (k, n + r) and (n + r, k) of row
    /// r's coefficients.
    coef_start: Vec<usize>,
    col_pos: Vec<usize>,
    row_pos: Vec<usize>,
    /// The position of (n + r, n + normal row) of a row with a normal row of its own pair
    /// (`usize::MAX`: none).
    slip_pos: Vec<usize>,
    symbolic: lu::SymbolicLu<usize>,
}

impl Layout {
    fn new(ex: &Exact, normal: &[Option<usize>]) -> Option<Layout> {
        let pb = ex.problem;
        let (n, m) = (pb.n_dofs, pb.full.len());
        let size = n + m;
        // (column, row) of every entry.
        let mut entries: Vec<(usize, usize)> = Vec::new();
        for (j, w) in ex.p_cols.windows(2).enumerate() {
            for &i in &ex.p_rows[w[0]..w[1]] {
                entries.push((j, i));
                entries.push((i, j));
            }
        }
        entries.extend((0..size).map(|k| (k, k)));
        for (r, fr) in pb.full.iter().enumerate() {
            for &(k, _) in &fr.coefs {
                entries.push((n + r, k));
                entries.push((k, n + r));
            }
            if let Some(nr) = normal[r].filter(|&nr| nr != r) {
                entries.push((n + nr, n + r));
            }
        }
        entries.sort_unstable();
        entries.dedup();
        let mut col_ptr = vec![0usize; size + 1];
        for &(c, _) in &entries {
            col_ptr[c + 1] += 1;
        }
        for c in 0..size {
            col_ptr[c + 1] += col_ptr[c];
        }
        let row_idx: Vec<usize> = entries.iter().map(|&(_, r)| r).collect();
        drop(entries);
        let at = |row: usize, col: usize| {
            let rows = &row_idx[col_ptr[col]..col_ptr[col + 1]];
            col_ptr[col] + rows.binary_search(&row).unwrap_or_else(|_| unreachable!())
        };
        let mut p_pos = Vec::with_capacity(ex.p_rows.len());
        for (j, w) in ex.p_cols.windows(2).enumerate() {
            for &i in &ex.p_rows[w[0]..w[1]] {
                p_pos.push([at(i, j), if i == j { usize::MAX } else { at(j, i) }]);
            }
        }
        let diag = (0..size).map(|k| at(k, k)).collect();
        let (mut coef_start, mut col_pos, mut row_pos) = (vec![0], Vec::new(), Vec::new());
        for (r, fr) in pb.full.iter().enumerate() {
            for &(k, _) in &fr.coefs {
                col_pos.push(at(k, n + r));
                row_pos.push(at(n + r, k));
            }
            coef_start.push(col_pos.len());
        }
        let slip_pos = (0..m)
            .map(|r| match normal[r].filter(|&nr| nr != r) {
                Some(nr) => at(n + r, n + nr),
                None => usize::MAX,
            })
            .collect();
        let pattern = SymbolicSparseColMatRef::new_checked(size, size, &col_ptr, None, &row_idx);
        let symbolic = lu::factorize_symbolic_lu(pattern, Default::default()).ok()?;
        Some(Layout {
            size,
            col_ptr,
            row_idx,
            p_pos,
            diag,
            coef_start,
            col_pos,
            row_pos,
            slip_pos,
            symbolic,
        })
    }

    /// `K x` for the values `vals` in this pattern.
    fn apply(&self, vals: &[f64], x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.size];
        for (c, &xc) in x.iter().enumerate() {
            if xc == 0.0 {
                continue;
            }
            for p in self.col_ptr[c]..self.col_ptr[c + 1] {
                y[self.row_idx[p]] += vals[p] * xc;
            }
        }
        y
    }
}

/// The pattern of a step's status systems, made on first use.
pub(super) type LayoutCell = RefCell<Option<Rc<Layout>>>;

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
        let layout = self.layout(f)?;
        let (q, qs) = self.linear_term(f.factor, f.cohesion);
        // Unknowns: x (U = d qs x), then y_r = λ_r ρ_r / qs of every row (zero where Off).
        let var: Vec<usize> = (0..pb.full.len())
            .map(|r| match status[r] {
                Status::Off => usize::MAX,
                _ => n + r,
            })
            .collect();
        let mut rhs = vec![0.0; layout.size];
        for k in 0..n {
            rhs[k] = -q[k] / qs;
        }
        if let Some((w, centre)) = prox {
            for k in 0..n {
                rhs[k] += w * centre[k];
            }
        }
        for (r, s) in status.iter().enumerate() {
            rhs[n + r] = match *s {
                Status::Fixed(v) => v / (self.rho[r] * qs),
                Status::Slip(sense) => {
                    let nr = f.normal[r]?;
                    -sense * self.mu(f.model, r) * self.rho[r] * f.cohesion[nr] / qs
                }
                Status::Off => 0.0,
            };
        }
        let vals = self.status_values(&layout, f, status, prox.map(|p| p.0))?;
        let fixed: Vec<usize> = (0..pb.full.len())
            .filter(|&r| matches!(status[r], Status::Fixed(_)))
            .map(|r| n + r)
            .collect();
        let lu = SeqLu::new(&layout, &vals)?;
        Some(StatusSystem {
            layout,
            vals,
            fixed,
            lu,
            var,
            rhs,
            qs,
        })
    }

    /// The pattern of the step's systems, analysed on first use.
    fn layout(&self, f: &Finish) -> Option<Rc<Layout>> {
        let mut cell = self.layout_cell.borrow_mut();
        if cell.is_none() {
            *cell = Some(Rc::new(Layout::new(self, f.normal)?));
        }
        cell.clone()
    }

    /// The values of the system of `status` (with the fixed rows' compliance) in `layout`,
    /// with the proximal weight `prox` on every dof; None where a slipping row's pair is open.
    fn status_values(
        &self,
        layout: &Layout,
        f: &Finish,
        status: &[Status],
        prox: Option<f64>,
    ) -> Option<Vec<f64>> {
        let n = self.problem.n_dofs;
        let mut v = vec![0.0; layout.row_idx.len()];
        for (e, &[a, b]) in layout.p_pos.iter().enumerate() {
            v[a] += self.p_vals[e];
            if b != usize::MAX {
                v[b] += self.p_vals[e];
            }
        }
        if let Some(w) = prox {
            for k in 0..n {
                v[layout.diag[k]] += w;
            }
        }
        for (r, &s) in status.iter().enumerate() {
            let diag = layout.diag[n + r];
            let span = layout.coef_start[r]..layout.coef_start[r + 1];
            let coefs = self.problem.full[r].coefs.iter();
            // A row with force: its column −a_r in the dofs' equations.
            if s != Status::Off {
                for (&(k, c), &p) in coefs.clone().zip(&layout.col_pos[span.clone()]) {
                    v[p] -= c * self.d[k] / self.rho[r];
                }
            }
            // Its own equation.
            match s {
                Status::Off => v[diag] += 1.0,
                Status::Fixed(_) => {
                    for (&(k, c), &p) in coefs.zip(&layout.row_pos[span]) {
                        v[p] += c * self.d[k] / self.rho[r];
                    }
                    v[diag] -= COMPLIANCE;
                }
                Status::Slip(sense) => {
                    let nr = f.normal[r]?;
                    if status[nr] == Status::Off || layout.slip_pos[r] == usize::MAX {
                        return None;
                    }
                    v[diag] += 1.0;
                    v[layout.slip_pos[r]] -=
                        sense * self.mu(f.model, r) * self.rho[r] / self.rho[nr];
                }
            }
        }
        Some(v)
    }
}

/// The factored linear system of one set of statuses.
pub(super) struct StatusSystem {
    layout: Rc<Layout>,
    /// The values of the system with the fixed rows' compliance.
    vals: Vec<f64>,
    /// The unknowns of the fixed rows (whose compliance the exact system has not).
    fixed: Vec<usize>,
    /// The LU factors of the system with the compliance.
    lu: SeqLu,
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

    /// The solution for the columns of `b` of the system with the compliance.
    pub(super) fn solve_columns(&self, b: &Mat<f64>) -> Option<Mat<f64>> {
        self.lu.solve(b)
    }

    /// `K z` of the exact system (without the compliance).
    fn apply_exact(&self, z: &[f64]) -> Vec<f64> {
        let mut y = self.layout.apply(&self.vals, z);
        for &i in &self.fixed {
            y[i] += COMPLIANCE * z[i];
        }
        y
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
        let mut z0 = vec![0.0; nv];
        for (r, &i) in self.var.iter().enumerate() {
            if i != usize::MAX {
                z0[i] = prior[r] * ex.rho[r] / qs;
            }
        }
        let kz0 = self.apply_exact(&z0);
        let b: Vec<f64> = (0..nv).map(|i| self.rhs[i] - kz0[i]).collect();
        let column = |v: &[f64]| Mat::<f64>::from_fn(nv, 1, |i, _| v[i]);
        let mut z = self.lu.solve(&column(&b))?;
        for _ in 0..REFINE {
            let zv: Vec<f64> = z.col(0).iter().copied().collect();
            let kz = self.apply_exact(&zv);
            let res: Vec<f64> = (0..nv).map(|i| b[i] - kz[i]).collect();
            z += self.lu.solve(&column(&res))?;
        }
        let z: Vec<f64> = (0..nv).map(|i| z[(i, 0)] + z0[i]).collect();
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
/// quiet 2-core machine), as on the sparse solver's (`sparse.rs`). Its symbolic analysis is
/// the step's `Layout`'s.
pub(super) struct SeqLu {
    layout: Rc<Layout>,
    numeric: lu::NumericLu<usize, f64>,
}

impl SeqLu {
    /// The factors of the values `vals` in `layout`, or None where memory is short or the
    /// factorisation fails.
    fn new(layout: &Rc<Layout>, vals: &[f64]) -> Option<SeqLu> {
        let symbolic = &layout.symbolic;
        let req = symbolic.factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default());
        let mut buf = MemBuffer::try_new(req).ok()?;
        let mut numeric = lu::NumericLu::new();
        let pattern = SymbolicSparseColMatRef::new_checked(
            layout.size,
            layout.size,
            &layout.col_ptr,
            None,
            &layout.row_idx,
        );
        symbolic
            .factorize_numeric_lu(
                &mut numeric,
                SparseColMatRef::new(pattern, vals),
                Par::Seq,
                MemStack::new(&mut buf),
                Default::default(),
            )
            .ok()?;
        Some(SeqLu {
            layout: Rc::clone(layout),
            numeric,
        })
    }

    /// The solution of the factored system for the columns of `b` (None where memory for
    /// the work space is short).
    fn solve(&self, b: &Mat<f64>) -> Option<Mat<f64>> {
        let mut x = b.clone();
        let symbolic = &self.layout.symbolic;
        let req = symbolic.solve_in_place_scratch::<f64>(x.ncols(), Par::Seq);
        let mut buf = MemBuffer::try_new(req).ok()?;
        lu::LuRef::new_unchecked(symbolic, &self.numeric).solve_in_place_with_conj(
            Conj::No,
            x.as_mut(),
            Par::Seq,
            MemStack::new(&mut buf),
        );
        Some(x)
    }
}
