//! The one discrete contact problem that every solver solves (docs/formulation.md §6.2 (ii)).
//!
//! Place in the flow: `bem` (per-body condensed operators D00, Z̄0) → **`problem`** → the
//! solvers (`evolutive`, `active_set`, `lemke`, `qp`) → results.
//!
//! # The discrete problem
//!
//! **Per body: the symmetric Steklov–Poincaré stiffness.** Each body's condensed system
//! `Z0 = D00 X0 + Z̄0` over its interface unknowns `X0 = [F; −U]` (traction hats and nodal
//! displacements in the pair frames) is reduced by imposing the body's own weak
//! compatibility `W = 0`:
//!
//! ```text
//!   F = G_U U − G_z,        G_U = D_WF⁻¹ D_WU,  G_z = D_WF⁻¹ Z̄_W
//!   P = S U + p̂,           S = −D_PU + D_WUᵀ G_U (symmetric PSD),  p̂ = Z̄_P − D_WUᵀ G_z
//! ```
//!
//! `P` is the Galerkin-weighted traction `∫ψ_j t` of the body at its interface nodes: the
//! **nodal force** that the neighbour exerts on it. Each body's energy is
//! `E_b(U) = ½ UᵀS U + p̂ᵀU`; S is singular only for a body held by interfaces alone.
//!
//! **Pairing.** Every interface pair component with a displacement unknown on both sides is a
//! row r with the relative displacement `[u]_r = U^B_r − U^A_r` (pair frame of A: tangential
//! s, normal n). Unilateral normal rows pair the **nodal gap** `g_r = h_r + [u]_n ≥ 0` with
//! the **nodal contact force** `λ_r = P^B_n + c_r w_r ≥ 0` (compression positive; `w_r` is
//! the tributary length ∫ψ_j ds of the pair, so a closed pair holds a tension up to the
//! cohesion c_r times its tributary length):
//!
//! ```text
//!   g_r ≥ 0,   λ_r ≥ 0,   g_r λ_r = 0       (one complementarity per unilateral pair)
//! ```
//!
//! Bonded rows and the tangential rows of tangentially tied pairs are equalities `[u] = 0`
//! (`stick`: tied while the pair is closed; `slide`: never tied). With every row closed the
//! bodies are glued into one assembled stiffness K_g over shared nodal displacements (sparse:
//! bodies couple only through their shared nodes), factorised once by sparse Cholesky.
//! Opening a set O of rows adds the openings s_O as unknowns; eliminating the glued
//! displacements gives
//!
//! ```text
//!   λ = λ⁰ + A s,    A = ∂λ/∂s  (the opening stiffness, symmetric PSD; PD unless a body
//!                                 can move freely once the rows of O are open)
//! ```
//!
//! so the frictionless problem is the LCP `λ = λ⁰ + A s, s ≥ 0, λ ≥ 0, sᵀλ = 0` over the
//! unilateral rows: unique when A is positive definite (a P-matrix; Cottle–Pang–Stone), and
//! equivalently the convex QP `min ½sᵀA s + λ⁰ᵀs, s ≥ 0`. A status (open set O) is solved by
//! `A_OO s_O = −λ⁰_O` with the columns of A computed on demand (one sparse solve each) and a
//! Cholesky factor of A_OO that is updated, not refactorised, when one row switches
//! ([`Opening`]): O(|O|²) per switch. No dense matrix over all interfaces is formed, except
//! by Lemke's method and the QP, which need A over every unilateral row.
//!
//! Why this pairing: the paper's mixed status system shares the traction F of a closed pair
//! and checks nodal gaps of open ones, so its statuses are not the principal pivots of one
//! LCP (its open state balances nodal forces P = 0, its closed state weak compatibility), and
//! the force QP (32b) checks Galerkin-weighted gaps instead: the solvers solved different
//! problems. Here every body satisfies W = 0 in every status, the only status-dependent
//! conditions are the rows above, and the status systems are exactly the principal pivots of
//! one symmetric LCP. The mixed system remains available for the archive (`interface`).

// Index loops mirror the block formulas.
#![allow(clippy::needless_range_loop)]

use faer::sparse::SparseColMat;
use faer::Mat;

use crate::bem::operators::Operators;
use crate::error::{Error, Result};
use crate::input::model::Model;
use crate::linalg::matvec;
use crate::solution::{BodyField, BodyMotion, InterfaceResult};

pub(crate) use mechanism::body_has_support;
pub(crate) use mechanism::mechanism_hint;
pub use opening::Opening;
pub(crate) use pattern::pattern;
pub(crate) use state::FullRowSolution;

use body::{body_operators, glued_matrix, BodyBlocks};
use std::collections::HashSet;

pub use rows::Component;
use rows::{candidates, eliminate, final_rows, glued_maps, joint_cuts};

mod body;
mod mechanism;
mod opening;
mod pattern;
mod rows;
mod state;

/// One body's Steklov–Poincaré operator.
pub struct BodyOp {
    /// X0 indices of the displacement unknowns (the body's dofs) and of the tractions.
    pub u_idx: Vec<usize>,
    pub f_idx: Vec<usize>,
    /// S (n_u × n_u) and p̂ for the unit load.
    pub s: Mat<f64>,
    pub p: Vec<f64>,
    /// Traction recovery F = G_U U − factor·G_z.
    pub gu: Mat<f64>,
    pub gz: Vec<f64>,
}

/// What a row ties.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RowKind {
    /// Bonded interface: always closed.
    Bonded,
    /// Normal component of a unilateral pair: the complementarity row.
    Normal,
    /// Tangential component of a `stick` pair: tied while the pair is closed.
    Stick,
    /// Tangential component of a `friction` pair: sticks or slips (Coulomb).
    Friction,
}

/// A relative-displacement row `[u]_r = U^B − U^A` of one pair component.
#[derive(Debug, Clone, Copy)]
pub struct Row {
    pub iface: usize,
    pub pair: usize,
    /// 0 tangential, 1 normal.
    pub comp: usize,
    pub kind: RowKind,
    /// Global dof indices of A's and B's displacement component.
    pub dof_a: usize,
    pub dof_b: usize,
    /// Initial gap (normal rows).
    pub gap: f64,
    /// Tributary length ∫ψ_j ds of the pair on A's side.
    pub weight: f64,
}

/// A candidate row with its coefficients over the dofs, before any elimination: every pair
/// component with a displacement unknown on both sides, junctions included
/// (`[u]_r = Σ coef·U_d`, B's dofs positive). The full rows of `contact::exact`.
#[derive(Debug, Clone)]
pub struct FullRow {
    pub row: Row,
    pub coefs: Vec<(usize, f64)>,
}

/// Where the elimination cuts a junction's cycle of pairs: which of its components are
/// implied (see [`Problem::new`]).
#[derive(Debug, Clone, Copy)]
pub enum Cuts<'a> {
    /// Rows bonded first, then normal, then tangential: at a T-junction of a running bond,
    /// the head joint's tangential component and a bed joint's.
    Tangential,
    /// As `Tangential`, except that where a cycle joins a normal component to tangential
    /// ones (at a T-junction: the head joint's normal and the bed joints' tangential
    /// components), the pair of that normal component is cut whole: at a T-junction the
    /// head joint has no row at the corner node and each bed joint keeps its friction
    /// there. Exact wherever the head joint does not press at its corner.
    Joints,
    /// The components of this set are taken after every other row, so that a cycle
    /// through one of them is cut there.
    At(&'a HashSet<Component>),
}

/// A pair component at a junction left without a row (see [`Problem::new`]).
#[derive(Debug, Clone)]
pub struct Implied {
    pub iface: usize,
    pub pair: usize,
    pub comp: usize,
    pub kind: RowKind,
    /// The kept components whose openings give its relative displacement (its cycle).
    pub cycle: Vec<Component>,
}

/// The contact problem of a model: per-body operators, rows, and the glued base factor.
pub struct Problem {
    pub ops: Vec<BodyOp>,
    /// First global dof of each body (dofs are the bodies' U unknowns in order).
    pub dof_start: Vec<usize>,
    pub n_dofs: usize,
    /// Rows that can open (normal and stick rows), then bonded rows.
    pub rows: Vec<Row>,
    /// Number of rows that can open (a prefix of `rows`).
    pub n_open_rows: usize,
    /// `row_of[k][j][c]`: the row of a pair component, if any.
    pub row_of: Vec<Vec<[Option<usize>; 2]>>,
    /// Each global dof in the glued unknowns v and the row openings:
    /// `U_d = Σ tmap[d]·v + Σ offs[d]·(s_r − h_r)` (a single `(g, 1)` for a dof that is not
    /// eliminated; the two sides of a closed row share their glued unknowns).
    tmap: Vec<Vec<(usize, f64)>>,
    offs: Vec<Vec<(usize, f64)>>,
    /// `t_r = ∂U/∂s_r` of each row (the dofs its opening moves with every other row held):
    /// the row's force is `λ_r = t_rᵀ P`.
    row_t: Vec<Vec<(usize, f64)>>,
    /// Pair components at junctions whose relative displacement the kept rows already
    /// fix while they are closed (a cycle of pairs around the point): no row of their own.
    pub implied: Vec<Implied>,
    implied_at: std::collections::HashSet<(usize, usize, usize)>,
    /// The components the junction cycles were cut at before any other ([`Cuts`]).
    pub cuts: HashSet<Component>,
    /// Every candidate row, junctions included, over the dofs.
    pub full: Vec<FullRow>,
    /// `full_of[k][j][c]`: the full row of a pair component, if any.
    pub full_of: Vec<Vec<[Option<usize>; 2]>>,
    n_glued: usize,
    factor: crate::linalg::SparseLlt,
    /// What each global dof moves by under its body's rigid modes (x, y translation,
    /// rotation about the centroid scaled by the model's size).
    dof_rigid: Vec<[f64; 3]>,
    /// Per body, whether it has rigid modes in the contact problem (no displacement
    /// condition holds it).
    floating: Vec<bool>,
}

/// The all-closed state for one load factor and cohesion: glued displacements v⁰ and row
/// forces λ⁰ (over the rows that can open).
pub struct Base {
    pub factor: f64,
    pub v0: Vec<f64>,
    /// Row forces with every row closed at its offset.
    pub lambda0: Vec<f64>,
    /// The opening each row keeps while closed: the accumulated slip s̄ of friction rows,
    /// zero on other rows.
    pub offset: Vec<f64>,
    /// Offsets (initial gaps closed) and cohesion terms per row.
    pub cohesion: Vec<f64>,
}

impl Problem {
    /// Builds the problem from the prepared bodies and factorises the glued base.
    ///
    /// **Rows and junctions.** Every pair component with a displacement unknown on both
    /// sides is a candidate row `[u]_r = e_r·(u_B − u_A)` over the dofs of the two nodes
    /// (at a junction node, whose unknowns are in the frame of its first pair, projected onto
    /// the pair's direction e_r). The closed rows are eliminated one by one: each expresses
    /// one still-free dof (B's, or the largest coefficient) through the others and its
    /// opening. Where three or more bodies meet, the pairs around the point form a cycle
    /// and their rows are linearly dependent (at a T-junction, bed joint A–B, bed joint A–C
    /// and head joint B–C: the vertical relative displacements satisfy
    /// `[u]_AB − [u]_AC + [u]_BC = 0`): a row whose coefficients vanish after elimination
    /// is *implied* by the rows kept before it while they are closed, and gets no row of its
    /// own. Rows are taken bonded first (normal components before tangential ones), then
    /// normal, then tangential, so that a cycle is cut at a tangential component of a head
    /// joint rather than at a normal one, and a component that bonded rows imply stays
    /// implied (bonded rows never open); a tangential row whose pair lost its normal row goes
    /// too. The kept rows are
    /// independent, so their forces (Lagrange multipliers) are unique and the opening
    /// stiffness A stays symmetric positive (semi)definite: the LCP of the module doc
    /// holds unchanged. The nodal force of the junction node is carried by the kept rows;
    /// implied components report zero force (each body's balance stays exact).
    pub fn new(model: &Model, prepared: &Operators) -> Result<Problem> {
        Problem::with_cuts(model, prepared, Cuts::Tangential)
    }

    /// The problem of [`Problem::new`] with its junction cycles cut as `cuts` says (which
    /// components are implied; [`Cuts`]).
    pub fn with_cuts(model: &Model, prepared: &Operators, cuts: Cuts) -> Result<Problem> {
        let bodies = body_operators(model, prepared)?;
        let cands = candidates(model, &bodies.node_dofs)?;
        let full: Vec<FullRow> = cands.iter().map(rows::Candidate::full).collect();
        let mut full_of: Vec<Vec<[Option<usize>; 2]>> = model
            .interfaces
            .iter()
            .map(|it| vec![[None; 2]; it.pairs.len()])
            .collect();
        for (r, f) in full.iter().enumerate() {
            full_of[f.row.iface][f.row.pair][f.row.comp] = Some(r);
        }
        let demoted = match cuts {
            Cuts::Tangential => HashSet::new(),
            Cuts::Joints => {
                let first = eliminate(&cands, bodies.n_dofs, &HashSet::new());
                joint_cuts(&cands, &first)
            }
            Cuts::At(set) => set.clone(),
        };
        let elim = eliminate(&cands, bodies.n_dofs, &demoted);
        let set = final_rows(model, &cands, &elim);
        let glued = glued_maps(&elim.expr, &set.index_of, set.rows.len());
        let mut dof_at = vec![(0, [0.0; 2]); bodies.n_dofs];
        for map in &bodies.node_dofs {
            for (&node, dofs) in map {
                for &(d, dir) in dofs {
                    dof_at[d] = (node, dir);
                }
            }
        }
        let BodyBlocks {
            ops,
            dof_start,
            n_dofs,
            ..
        } = bodies;
        let dof_rigid = rigid_dofs(model, &ops, &dof_start, &dof_at);
        let floating = (0..ops.len())
            .map(|b| !mechanism::body_has_support(model, b))
            .collect();
        let kg = glued_matrix(&ops, &dof_start, &glued.tmap, glued.n_glued)?;
        let factor = crate::linalg::SparseLlt::new(&kg).ok_or_else(|| {
            Error::numerical(format!(
                "the interface system with every pair closed is singular: {}",
                mechanism_hint(model, &ops, &set.rows, &dof_start)
            ))
        })?;
        let problem = Problem {
            ops,
            dof_start,
            n_dofs,
            rows: set.rows,
            n_open_rows: set.n_open_rows,
            row_of: set.row_of,
            tmap: glued.tmap,
            offs: glued.offs,
            row_t: glued.row_t,
            implied: set.implied,
            implied_at: set.implied_at,
            cuts: demoted,
            full,
            full_of,
            n_glued: glued.n_glued,
            factor,
            dof_rigid,
            floating,
        };
        problem.check_base(&kg, model)?;
        Ok(problem)
    }

    /// A Cholesky factor can succeed on a matrix that is singular up to roundoff: the
    /// residual of one solve with a rough right-hand side tells.
    fn check_base(&self, kg: &SparseColMat<usize, f64>, model: &Model) -> Result<()> {
        let n = self.n_glued;
        if n == 0 {
            return Ok(());
        }
        let b = Mat::<f64>::from_fn(n, 1, |i, _| 1.0 + (i % 7) as f64);
        let x = self.factor.solve(&b);
        // K x with the full symmetric matrix from its lower triangle.
        let mut kx = vec![0.0; n];
        let sym = kg.symbolic();
        let (cp, ri) = (sym.col_ptr(), sym.row_idx());
        let vals = kg.val();
        for c in 0..n {
            for p in cp[c]..cp[c + 1] {
                let r = ri[p];
                kx[r] += vals[p] * x[(c, 0)];
                if r != c {
                    kx[c] += vals[p] * x[(r, 0)];
                }
            }
        }
        let res = (0..n)
            .map(|i| (kx[i] - b[(i, 0)]).abs())
            .fold(0.0, f64::max)
            / 7.0;
        if res.is_finite() && (1e-6..1e-2).contains(&res) {
            return Err(Error::numerical(format!(
                "the interface system with every pair closed is ill-conditioned (relative \
                 residual {res:.1e} after solving)"
            )));
        }
        if res.is_nan() || res >= 1e-6 {
            return Err(Error::numerical(format!(
                "the interface system with every pair closed is singular (relative residual \
                 {res:.1e}): {}",
                mechanism_hint(model, &self.ops, &self.rows, &self.dof_start)
            )));
        }
        Ok(())
    }

    /// Number of glued unknowns (the size of the sparse base system).
    pub(crate) fn base_size(&self) -> usize {
        self.n_glued
    }

    fn body_of(&self, dof: usize) -> (usize, usize) {
        let b = self.dof_start.partition_point(|&s| s <= dof) - 1;
        (b, dof - self.dof_start[b])
    }

    /// Body displacements for glued displacements `v`, openings `s` (over rows that can
    /// open, zero where closed) and the closed initial gaps.
    fn displacements(&self, v: &[f64], s: &[f64]) -> Vec<Vec<f64>> {
        self.ops
            .iter()
            .enumerate()
            .map(|(b, op)| {
                (0..op.u_idx.len())
                    .map(|l| {
                        let d = self.dof_start[b] + l;
                        let mut u: f64 = self.tmap[d].iter().map(|&(g, x)| x * v[g]).sum();
                        for &(r, x) in &self.offs[d] {
                            // The row's relative displacement is s − h: the gap h closed
                            // when s = 0.
                            let open = if r < self.n_open_rows { s[r] } else { 0.0 };
                            u += x * (open - self.rows[r].gap);
                        }
                        u
                    })
                    .collect()
            })
            .collect()
    }

    /// The rigid motion of each body under the change `dw = (dv, ds)` of the glued
    /// displacements and the openings (a mechanism's motion): per body the least-squares
    /// translation and rotation of its interface dofs' displacements.
    pub(crate) fn rigid_motions(&self, model: &Model, dw: &[f64]) -> Vec<BodyMotion> {
        let (dv, ds) = dw.split_at(self.n_glued.min(dw.len()));
        let du: Vec<f64> = (0..self.n_dofs)
            .map(|d| {
                let mut u: f64 = self.tmap[d].iter().map(|&(g, x)| x * dv[g]).sum();
                for &(r, x) in &self.offs[d] {
                    if r < self.n_open_rows {
                        u += x * ds[r];
                    }
                }
                u
            })
            .collect();
        self.rigid_fit(model, &du)
    }

    /// Per body the least-squares translation and rotation of the dof displacements `du`
    /// (over every dof in order).
    pub(crate) fn rigid_fit(&self, model: &Model, du: &[f64]) -> Vec<BodyMotion> {
        let scale = model.scale.max(f64::MIN_POSITIVE);
        let mut out = Vec::with_capacity(self.ops.len());
        for (b, op) in self.ops.iter().enumerate() {
            let c = mechanism::centroid(&model.bodies[b].nodes);
            // Normal equations of d·(t + ω k × (x − c)) = U over the body's dofs.
            let mut g = [[0.0f64; 3]; 3];
            let mut h = [0.0f64; 3];
            for l in 0..op.u_idx.len() {
                let d = self.dof_start[b] + l;
                let u = du[d];
                let a = self.dof_rigid[d];
                for i in 0..3 {
                    h[i] += a[i] * u;
                    for j in 0..3 {
                        g[i][j] += a[i] * a[j];
                    }
                }
            }
            // A body whose dofs leave a mode unseen (all along one line): that mode is zero.
            let tr = g[0][0] + g[1][1] + g[2][2];
            for (i, row) in g.iter_mut().enumerate() {
                row[i] += 1e-12 * tr;
            }
            let q = crate::linalg::solve3(g, h).unwrap_or([0.0; 3]);
            let rotation = q[2] / scale;
            out.push(BodyMotion {
                body: b,
                centroid: c.point(),
                translation: c.translation_at_point([q[0], q[1]], rotation),
                rotation,
            });
        }
        out
    }

    /// The rigid-motion row of row `r` (of `rows`): per body that has rigid modes
    /// (`floating`), what its translation and rotation ([`Problem::dof_rigid`]) move the
    /// row's relative displacement by, from the row's coefficients over the dofs (its full
    /// row: at a junction node, the dofs of its first pair's frame). A status holds every
    /// body iff the closed rows' rigid-motion rows leave no rigid motion free.
    pub(crate) fn row_rigid(&self, r: usize) -> Vec<(usize, [f64; 3])> {
        let row = &self.rows[r];
        let Some(f) = self.full_of[row.iface][row.pair][row.comp] else {
            return Vec::new();
        };
        let mut out: Vec<(usize, [f64; 3])> = Vec::new();
        for &(d, x) in &self.full[f].coefs {
            let (b, _) = self.body_of(d);
            if !self.floating[b] {
                continue;
            }
            let m = self.dof_rigid[d];
            let add = [x * m[0], x * m[1], x * m[2]];
            match out.iter_mut().find(|e| e.0 == b) {
                Some(e) => (0..3).for_each(|i| e.1[i] += add[i]),
                None => out.push((b, add)),
            }
        }
        out
    }

    /// The number of glued unknowns v.
    pub(crate) fn n_glued(&self) -> usize {
        self.n_glued
    }

    /// The unknowns w = (v, s) that dof `d` moves (`U_d = Σ x·w_k` plus the closed gaps): the
    /// glued unknowns, then the openings of the rows that can open at `n_glued + r`.
    pub(crate) fn dof_unknowns(&self, d: usize) -> Vec<(usize, f64)> {
        let mut out = self.tmap[d].clone();
        for &(r, x) in &self.offs[d] {
            if r < self.n_open_rows {
                out.push((self.n_glued + r, x));
            }
        }
        out
    }

    /// The gradient over w = (v, s) of the bodies' energy at w = 0 (every gap closed) for a
    /// load factor, with the cohesion terms of the rows (`Base::cohesion`) added to the rows'
    /// part: the row forces are `λ = H w + c` on the rows' part.
    pub(crate) fn linear_term(&self, factor: f64, cohesion: &[f64]) -> Vec<f64> {
        let u0 = self.displacements(&vec![0.0; self.n_glued], &vec![0.0; self.n_open_rows]);
        let p0 = self.forces(&u0, factor);
        let mut c = self.gather(&p0);
        c.extend((0..self.n_open_rows).map(|r| self.row_force(&p0, r) + cohesion[r]));
        c
    }

    /// The force of row r from the nodal forces `p` of every body: `λ_r = t_rᵀ P`.
    fn row_force(&self, p: &[Vec<f64>], r: usize) -> f64 {
        self.row_t[r]
            .iter()
            .map(|&(d, x)| {
                let (b, l) = self.body_of(d);
                x * p[b][l]
            })
            .sum()
    }

    /// `Tᵀ f` for per-body vectors `f` over the dofs: the glued load.
    fn gather(&self, f: &[Vec<f64>]) -> Vec<f64> {
        let mut out = vec![0.0; self.n_glued];
        for (b, fb) in f.iter().enumerate() {
            for (i, v) in fb.iter().enumerate() {
                for &(g, x) in &self.tmap[self.dof_start[b] + i] {
                    out[g] += x * v;
                }
            }
        }
        out
    }

    /// Right-hand side of the glued system: Tᵀ(S U_fixed + factor p̂), where U_fixed holds
    /// the parts of U that are not glued unknowns (gap offsets, openings).
    fn glued_load(&self, factor: f64, s: &[f64]) -> Vec<f64> {
        let zero = vec![0.0; self.n_glued];
        let u = self.displacements(&zero, s);
        let f: Vec<Vec<f64>> = self
            .ops
            .iter()
            .zip(&u)
            .map(|(op, ub)| {
                matvec(&op.s, ub)
                    .iter()
                    .zip(&op.p)
                    .map(|(v, p)| factor * p + v)
                    .collect()
            })
            .collect();
        self.gather(&f)
    }

    fn solve_glued(&self, rhs: &[f64]) -> Vec<f64> {
        let n = self.n_glued;
        let b = Mat::<f64>::from_fn(n, 1, |i, _| -rhs[i]);
        let x = self.factor.solve(&b);
        (0..n).map(|i| x[(i, 0)]).collect()
    }

    /// Nodal forces P = S U + factor·p̂ of each body.
    fn forces(&self, u: &[Vec<f64>], factor: f64) -> Vec<Vec<f64>> {
        self.ops
            .iter()
            .zip(u)
            .map(|(op, ub)| {
                matvec(&op.s, ub)
                    .iter()
                    .zip(&op.p)
                    .map(|(v, p)| v + factor * p)
                    .collect()
            })
            .collect()
    }

    /// The all-closed state for a load factor, the cohesion left at each pair and the
    /// accumulated slip `offset` of friction rows (zero elsewhere; empty for none).
    pub fn base(&self, factor: f64, cohesion: &[Vec<f64>], offset: &[f64]) -> Base {
        let s = if offset.is_empty() {
            vec![0.0; self.n_open_rows]
        } else {
            offset.to_vec()
        };
        let v0 = self.solve_glued(&self.glued_load(factor, &s));
        let u = self.displacements(&v0, &s);
        let p = self.forces(&u, factor);
        let coh: Vec<f64> = self.rows[..self.n_open_rows]
            .iter()
            .map(|r| match r.kind {
                RowKind::Normal => cohesion[r.iface][r.pair] * r.weight,
                _ => 0.0,
            })
            .collect();
        let lambda0 = (0..self.n_open_rows)
            .map(|r| self.row_force(&p, r) + coh[r])
            .collect();
        Base {
            factor,
            v0,
            lambda0,
            offset: s,
            cohesion: coh,
        }
    }

    /// Column j of the opening stiffness A over the rows that can open: the change of
    /// every row force per unit opening of row j (one sparse solve and a product with the
    /// operator of each body that is the second side of a row).
    pub fn column(&self, j: usize) -> Vec<f64> {
        // t_j = ∂U/∂s_j over the dofs it moves, per body.
        let mut tj: Vec<Vec<(usize, f64)>> = vec![Vec::new(); self.ops.len()];
        for &(d, x) in &self.row_t[j] {
            let (b, l) = self.body_of(d);
            tj[b].push((l, x));
        }
        // Tᵀ S t_j: the glued load of a unit opening.
        let f: Vec<Vec<f64>> = self
            .ops
            .iter()
            .enumerate()
            .map(|(b, op)| {
                if tj[b].is_empty() {
                    return Vec::new();
                }
                (0..op.u_idx.len())
                    .map(|i| tj[b].iter().map(|&(l, x)| op.s[(i, l)] * x).sum())
                    .collect()
            })
            .collect();
        let y = self.solve_glued(&self.gather(&f)); // = ∂v/∂s_j
        let mut need = vec![false; self.ops.len()];
        for r in 0..self.n_open_rows {
            for &(d, _) in &self.row_t[r] {
                need[self.body_of(d).0] = true;
            }
        }
        let t: Vec<Vec<f64>> = self
            .ops
            .iter()
            .enumerate()
            .map(|(b, op)| {
                if !need[b] {
                    return Vec::new();
                }
                let n = op.u_idx.len();
                let mut du: Vec<f64> = (0..n)
                    .map(|l| {
                        self.tmap[self.dof_start[b] + l]
                            .iter()
                            .map(|&(g, x)| x * y[g])
                            .sum()
                    })
                    .collect();
                for &(l, x) in &tj[b] {
                    du[l] += x;
                }
                matvec(&op.s, &du)
            })
            .collect();
        (0..self.n_open_rows)
            .map(|r| self.row_force(&t, r))
            .collect()
    }
}

/// The solution with every interface pair closed.
pub struct StatusSolution {
    pub fields: Vec<BodyField>,
    pub interfaces: Vec<InterfaceResult>,
}

/// Solves the model with every interface pair closed (bonded interfaces, and unilateral ones
/// held closed) through the contact problem's glued system, for the loads of `bem::prepare`.
pub fn solve_all_closed(model: &Model, ops: &Operators) -> Result<StatusSolution> {
    let problem = Problem::new(model, ops)?;
    let n = problem.n_open_rows;
    let (fields, interfaces, _) = problem.state(model, ops, 1.0, &vec![0.0; n], &vec![false; n]);
    Ok(StatusSolution { fields, interfaces })
}

/// [`Problem::dof_rigid`]: per global dof (`dof_at`: its body-local node and direction), what
/// its body's rigid modes move it by.
fn rigid_dofs(
    model: &Model,
    ops: &[BodyOp],
    dof_start: &[usize],
    dof_at: &[(usize, [f64; 2])],
) -> Vec<[f64; 3]> {
    let scale = model.scale.max(f64::MIN_POSITIVE);
    let mut out = vec![[0.0; 3]; dof_at.len()];
    for (b, op) in ops.iter().enumerate() {
        let nodes = &model.bodies[b].nodes;
        let c = mechanism::centroid(nodes);
        for d in dof_start[b]..dof_start[b] + op.u_idx.len() {
            let (node, dir) = dof_at[d];
            let x = nodes.get(node).copied().unwrap_or(c.point());
            out[d] = mechanism::rigid_row(x, &c, dir, scale);
        }
    }
    out
}
