//! The inner complementarity problem of one outer iteration, shared by every solver.
//!
//! Place in the flow: `problem` → **`lcp`** → `evolutive`, `active_set`, `lemke`, `qp`.
//! With the load factor, the cohesion left at each pair and the tangential ties of `stick`
//! pairs fixed (the outer loop in `contact` updates them), the problem is the LCP of
//! `problem` over the unilateral normal rows, plus *free* rows (stick rows whose pair is not
//! tied: opening unconstrained, force zero):
//!
//! ```text
//!   λ = λ⁰ + A s;   normal rows: s ≥ 0, λ ≥ 0, sλ = 0;   free rows: λ = 0
//! ```

use std::collections::HashMap;

use crate::contact::problem::{Base, Opening, Problem, RowKind};

/// Columns of the opening stiffness, computed once per row and kept for the whole run.
#[derive(Default)]
pub struct Columns {
    cols: HashMap<usize, Vec<f64>>,
}

impl Columns {
    pub fn get(&mut self, problem: &Problem, j: usize) -> &[f64] {
        self.cols.entry(j).or_insert_with(|| problem.column(j))
    }
    pub fn computed(&self) -> usize {
        self.cols.len()
    }
}

/// The inner problem.
pub struct Inner<'a> {
    pub problem: &'a Problem,
    pub base: &'a Base,
    /// Rows that are open whatever happens (untied stick rows).
    pub free: Vec<bool>,
    /// Relative tolerance of the violation checks.
    pub tol: f64,
}

/// A solution of the inner problem for one open set.
#[derive(Debug, Clone)]
pub struct InnerState {
    /// Open rows (normal rows that are open, and the free rows).
    pub open: Vec<bool>,
    /// Opening of every row (zero where closed).
    pub s: Vec<f64>,
    /// Force of every row (λ; zero on open rows up to roundoff).
    pub lambda: Vec<f64>,
}

/// A switch of one normal row.
#[derive(Debug, Clone, Copy)]
pub struct Violation {
    pub row: usize,
    /// Relative size.
    pub size: f64,
}

impl<'a> Inner<'a> {
    pub fn n(&self) -> usize {
        self.problem.n_open_rows
    }

    pub fn is_normal(&self, r: usize) -> bool {
        self.problem.rows[r].kind == RowKind::Normal
    }

    /// Builds the factor of A_OO for the free rows and the normal rows `open` (in order of
    /// decreasing initial gap, so that a row whose opening would leave a body free — the
    /// smallest gaps come last — stays closed). Returns the factor and the rows refused.
    pub fn factor(&self, cols: &mut Columns, open: &[bool]) -> (Opening, Vec<usize>) {
        let mut o = Opening::default();
        let mut refused = Vec::new();
        let mut order: Vec<usize> = (0..self.n()).filter(|&r| self.free[r]).collect();
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
        for r in order {
            let col = cols.get(self.problem, r);
            if !o.append(r, col) {
                refused.push(r);
            }
        }
        (o, refused)
    }

    /// Openings and forces of the status whose factor is `o`.
    pub fn state(&self, cols: &mut Columns, o: &Opening) -> InnerState {
        let n = self.n();
        let rhs: Vec<f64> = o.rows.iter().map(|&r| -self.base.lambda0[r]).collect();
        let so = o.solve(&rhs);
        let mut s = vec![0.0; n];
        let mut open = vec![false; n];
        let mut lambda = self.base.lambda0.clone();
        for (&r, &sr) in o.rows.iter().zip(&so) {
            s[r] = sr;
            open[r] = true;
            let col = cols.get(self.problem, r);
            for (l, c) in lambda.iter_mut().zip(col) {
                *l += c * sr;
            }
        }
        for &r in &o.rows {
            lambda[r] = 0.0;
        }
        InnerState { open, s, lambda }
    }

    /// Scales of forces and openings for relative checks.
    pub fn scales(&self, st: &InnerState) -> (f64, f64) {
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

    /// Violated normal rows, largest first: tension beyond the cohesion on a closed row,
    /// interpenetration on an open one.
    pub fn violations(&self, st: &InnerState) -> Vec<Violation> {
        let (fs, ss) = self.scales(st);
        let mut v = Vec::new();
        for r in 0..self.n() {
            if !self.is_normal(r) || self.free[r] {
                continue;
            }
            let size = if st.open[r] {
                -st.s[r] / ss
            } else {
                -st.lambda[r] / fs
            };
            if size > self.tol {
                v.push(Violation { row: r, size });
            }
        }
        v.sort_by(|a, b| b.size.total_cmp(&a.size).then(a.row.cmp(&b.row)));
        v
    }

    /// Complementarity residual `max(−λ, −s, λ·s)` over the normal rows, relative.
    pub fn residual(&self, st: &InnerState) -> f64 {
        let (fs, ss) = self.scales(st);
        let mut r = 0.0f64;
        for j in 0..self.n() {
            if !self.is_normal(j) || self.free[j] {
                continue;
            }
            let (l, s) = (st.lambda[j] / fs, st.s[j] / ss);
            r = r.max(-l).max(-s).max(l.max(0.0) * s.max(0.0));
        }
        r
    }

    /// The dense LCP over the normal rows with the free rows eliminated:
    /// `M = A_NN − A_NF A_FF⁻¹ A_FN`, `q = λ⁰_N − A_NF A_FF⁻¹ λ⁰_F` (for Lemke and the QP,
    /// which need every column). Returns the normal rows, M (row-major) and q, or None when
    /// A_FF is singular.
    pub fn dense(&self, cols: &mut Columns) -> Option<(Vec<usize>, Vec<f64>, Vec<f64>)> {
        let normal: Vec<usize> = (0..self.n())
            .filter(|&r| self.is_normal(r) && !self.free[r])
            .collect();
        let free: Vec<usize> = (0..self.n()).filter(|&r| self.free[r]).collect();
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
            let mut o = Opening::default();
            for &r in &free {
                let col = cols.get(self.problem, r);
                if !o.append(r, col) {
                    return None;
                }
            }
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
        Some((normal, m, q))
    }
}
