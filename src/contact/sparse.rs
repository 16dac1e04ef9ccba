//! The inner problem on the sparse system of glued displacements and row openings: no column
//! of the opening stiffness, memory linear in the number of bodies.
//!
//! Place in the flow: `lcp` (the inner problem) → **`sparse`** → `contact` (the driver). The
//! opening stiffness A of `problem` is the Schur complement of the bodies' energy over the
//! unknowns `w = (v, s)` — the glued displacements v and the openings s of the rows that can
//! open (docs/formulation.md §6.2):
//!
//! ```text
//!   E(w) = ½ wᵀ H w + cᵀ w,   H = Σ_b T_bᵀ S_b T_b,   λ = ∂E/∂s = (H w + c)_s
//! ```
//!
//! with `U_b = T_b w` plus the closed gaps (`Problem::dof_unknowns`), `c` the gradient at
//! w = 0 with the rows' cohesion terms (`Problem::linear_term`). H is sparse (bodies couple
//! only through their rows). A status is solved by one sparse Cholesky factorisation of H
//! over the glued displacements and the openings of its open rows, the closed rows' openings
//! fixed at their offsets and left out of the factor (on a wall most rows are closed, and
//! their couplings would only add fill). H is stored once in a fill-reducing order of its
//! whole pattern (approximate minimum degree, every row open); a status's matrix is a
//! principal submatrix in that order, so each factorisation skips the ordering, and the
//! factor's storage and work space are reused from one factorisation to the next. A status
//! within a few rows of the last factor with its proximal weight is solved from that
//! factor by bordering (`border`), without a factorisation of its own.
//!
//! The statuses are found by the primal–dual active set iteration (semismooth Newton,
//! Hintermüller–Ito–Kunisch): every violated row switches at once. A status met on the way
//! can leave a body free (on a wall with little friction, a top brick whose bed joint slips
//! everywhere: its place is fixed only by the one row that should stick). Such an iterate
//! gets a proximal spring `ε H_rr (s_r − s̄_r)` on its open rows, anchored at the last
//! iterate s̄: the free body moves a finite step towards what stops it, and the rows it
//! reaches switch. Whether a status leaves a body free is told before its factorisation,
//! from the bodies' rigid motions alone (`rigid`: a factor of order three times the
//! bodies), so that the exact form is attempted only where its closed rows hold every
//! body. The weight ε is a trust region: from 1e-2, it falls tenfold after an
//! iterate whose statuses hold or whose switches touch no row that moves with a free body,
//! so a body under a small unbalanced force reaches its stop in a few iterates, and rises
//! tenfold after one that switches many rows (a body thrown too far); a
//! state whose spring forces are within the tolerance is a solution (the free body's place
//! is then not unique). A repeated status halves the step; the iteration limit or a repeated
//! status ends it without a verdict (`stalled`), and the driver hands over to the evolutive
//! iteration.
//!
//! Friction follows Coulomb's law within the iteration (docs/formulation.md §6.4): each
//! iterate's slip bounds are μ·max(λ_n − c, 0) of the last iterate's normal forces (zero
//! where the pair is open), and an iterate whose statuses hold while its bounds still moved
//! is solved again with the new bounds — the same factor, two triangular solves. The outer
//! Tresca fixed point then finds its bounds settled after one pass instead of refactoring
//! for every outer iteration (64 × 64 wall: 79 → 32 iterations). Where the lagged bounds do
//! not settle, the iteration starts again with each slipping row's force tied to its pair's
//! normal force within the solve, `λ_r = −σ μ (λ_k − c_k)` (semismooth Newton: H's row r plus
//! σμ times row k, not symmetric, one sparse LU per status; docs/formulation.md §6.5).

use std::collections::HashSet;
use std::sync::Arc;

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::{amd, cholesky, lu, SupernodalThreshold};
use faer::sparse::{SparseColMat, SparseColMatRef, SymbolicSparseColMatRef, Triplet};
use faer::{Conj, Mat, Par, Side};

use crate::contact::lcp::{
    bound_change, status_key, Inner, InnerOutcome, InnerState, Violation, BOUNDS_SETTLED,
};
use crate::contact::problem::Problem;

mod border;
mod rigid;

/// H over w = (v, s) (lower triangle) and its symbolic factorisation.
pub struct SparseSystem {
    n_glued: usize,
    /// Rows that can open.
    n: usize,
    /// H in its elimination order.
    ordered: Ordered,
    /// The rows of H of the rows' openings (both triangles).
    rows: RowsOfH,
    /// The diagonal of H.
    diag: Vec<f64>,
    /// The factorisation of the last status solved, with that status (`None` where it
    /// left a body free): the outer loop's next iterate often keeps the status and changes
    /// only the loads (slip bounds, cohesion), which then costs two triangular solves.
    last: Option<Factored>,
    scratch: Scratch,
    work: Work,
    /// The storage of the last factor that failed, for the next.
    spare: Vec<f64>,
    /// The last factor that succeeded, with its status and weight, kept while an exact
    /// attempt is made from a proximal one: where that fails (a body left free), the next
    /// iterate solves the same status proximally, bordered from it.
    held: Option<(Vec<bool>, f64, Reduced)>,
    /// The bordered solve of the last status solved from the factor of another.
    border: Option<border::Border>,
    /// The storage of the last bordered solve's columns, for the next.
    border_spare: Mat<f64>,
    /// The analysis of the last status factored.
    analysis: Option<Arc<Analysis>>,
    /// The values of the last LU of the Newton attempt, whose storage the next reuses.
    lu: lu::NumericLu<usize, f64>,
    /// The rows' rigid-motion rows: whether a status holds every body, without H.
    rigid: rigid::RigidRows,
}

/// A status (open rows, regularisation) and its factorisation, if positive definite.
type Factored = (Vec<bool>, f64, Option<Reduced>);

/// The factor of H over the unknowns a status leaves free: the glued displacements and the
/// openings of its open rows; the closed rows' openings are fixed.
struct Reduced {
    analysis: Arc<Analysis>,
    /// The values of the factor L.
    l: Vec<f64>,
}

impl Reduced {
    /// Replaces `x` (one column per right-hand side, over the status's unknowns in `kept`
    /// order) by the solution; None where the work space cannot be had.
    fn solve_in_place(&self, scratch: &mut Scratch, x: faer::MatMut<'_, f64>) -> Option<()> {
        let symbolic = &self.analysis.symbolic;
        let req = symbolic.solve_in_place_scratch::<f64>(x.ncols().max(1), PAR);
        let stack = scratch.stack(req)?;
        cholesky::LltRef::new(symbolic, &self.l).solve_in_place_with_conj(Conj::No, x, PAR, stack);
        Some(())
    }
}

/// The unknowns a status keeps (`kept`, in the elimination order) and the symbolic
/// factorisation of H over them. It depends on the open rows alone, so a status solved
/// again with another proximal weight, or proximally after its exact factorisation failed,
/// reuses it (45 × 45 wall: 0.11–0.19 s of 0.75–1.2 s per factorisation).
struct Analysis {
    open: Vec<bool>,
    kept: Vec<usize>,
    /// Places in `kept` of the unknowns in the elimination order (`usize::MAX` where left
    /// out).
    index: Vec<usize>,
    symbolic: cholesky::SymbolicCholesky<usize>,
}

/// Work space of the factorisations and solves, kept between them (a fresh one per
/// factorisation would map and clear its pages again every time).
#[derive(Default)]
struct Scratch {
    /// The buffer and the largest request it was made for.
    buffer: Option<(StackReq, MemBuffer)>,
}

impl Scratch {
    /// A stack of at least `req`; None where the memory cannot be had.
    fn stack(&mut self, req: StackReq) -> Option<&mut MemStack> {
        let want = match &self.buffer {
            Some((have, _)) if have.or(req) == *have => None,
            Some((have, _)) => Some(have.or(req)),
            None => Some(req),
        };
        if let Some(want) = want {
            // The old buffer goes first: two at once would add to the peak.
            self.buffer = None;
            self.buffer = Some((want, MemBuffer::try_new(want).ok()?));
        }
        self.buffer.as_mut().map(|(_, b)| MemStack::new(b))
    }
}

/// H with its unknowns in a fill-reducing elimination order (approximate minimum degree of
/// the whole pattern, every row open), lower triangle: a status's matrix is a principal
/// submatrix, factored in this order without another analysis of the order. faer's
/// supernodal factorisation reads the lower triangle as it is (an upper one it transposes
/// first, every factorisation).
struct Ordered {
    h: SparseColMat<usize, f64>,
    /// The unknown at each place of the order.
    unknown: Vec<usize>,
    /// The place of each unknown in the order.
    place: Vec<usize>,
}

impl Ordered {
    /// The lower triangle, in its elimination order, of H given by its lower triangle; None
    /// where the analysis fails (memory).
    fn new(h: &SparseColMat<usize, f64>) -> Option<Ordered> {
        let n = h.nrows();
        let nnz = h.val().len();
        // The order alone: a symbolic factorisation of the whole pattern would also count
        // its factor, which no status uses.
        let mut fwd = vec![0usize; n];
        let mut inv = vec![0usize; n];
        let req = amd::order_maybe_unsorted_scratch::<usize>(n, nnz);
        let mut buffer = MemBuffer::try_new(req).ok()?;
        let stack = MemStack::new(&mut buffer);
        amd::order_maybe_unsorted(&mut fwd, &mut inv, h.symbolic(), Default::default(), stack)
            .ok()?;
        drop(buffer);
        // H in that order, its lower triangle: entry (i, j) of H goes to (place i, place j).
        let sym = h.symbolic();
        let (cp, ri, val) = (sym.col_ptr(), sym.row_idx(), h.val());
        let h = crate::linalg::triangle_from_entries(n, Side::Lower, |sink| {
            for c in 0..n {
                for q in cp[c]..cp[c + 1] {
                    let (a, b) = (inv[ri[q]], inv[c]);
                    sink(a.max(b), a.min(b), val[q]);
                }
            }
        })?;
        Some(Ordered {
            h,
            unknown: fwd,
            place: inv,
        })
    }
}

/// The rows of H of the rows' openings, whole (both triangles), by row: the rows' forces
/// (H w)_s of a state and the products with the closed rows' fixed openings cost a pass over
/// these instead of over H (on the 45 × 45 wall about a third of its entries).
struct RowsOfH {
    start: Vec<usize>,
    col: Vec<u32>,
    val: Vec<f64>,
}

impl RowsOfH {
    /// From H in its elimination order; None where the memory cannot be had or an unknown's
    /// index does not fit 32 bits.
    fn new(ord: &Ordered, ng: usize, n: usize) -> Option<RowsOfH> {
        let size = ord.unknown.len();
        u32::try_from(size).ok()?;
        let sym = ord.h.symbolic();
        let (cp, ri, val) = (sym.col_ptr(), sym.row_idx(), ord.h.val());
        // Each entry (i, j) of the triangle, and (j, i) off the diagonal, where its row is
        // an opening.
        let each = |f: &mut dyn FnMut(usize, usize, f64)| {
            for b in 0..size {
                for q in cp[b]..cp[b + 1] {
                    let (i, j) = (ord.unknown[ri[q]], ord.unknown[b]);
                    if i >= ng {
                        f(i - ng, j, val[q]);
                    }
                    if j >= ng && i != j {
                        f(j - ng, i, val[q]);
                    }
                }
            }
        };
        let mut start = vec![0usize; n + 1];
        each(&mut |r, _, _| start[r + 1] += 1);
        for r in 0..n {
            start[r + 1] += start[r];
        }
        let total = start[n];
        let (mut col, mut vals) = (Vec::new(), Vec::new());
        col.try_reserve_exact(total).ok()?;
        vals.try_reserve_exact(total).ok()?;
        col.resize(total, 0u32);
        vals.resize(total, 0.0f64);
        let mut next = start[..n].to_vec();
        each(&mut |r, j, v| {
            col[next[r]] = j as u32;
            vals[next[r]] = v;
            next[r] += 1;
        });
        Some(RowsOfH {
            start,
            col,
            val: vals,
        })
    }

    /// (H w) over the openings.
    fn times(&self, w: &[f64]) -> Vec<f64> {
        (0..self.start.len() - 1)
            .map(|r| {
                let e = self.start[r]..self.start[r + 1];
                self.col[e.clone()]
                    .iter()
                    .zip(&self.val[e])
                    .map(|(&j, &v)| v * w[j as usize])
                    .sum()
            })
            .collect()
    }

    /// H x over all `size` unknowns for an x that is zero but on the openings (`xs`).
    fn times_transposed(&self, xs: &[f64], size: usize) -> Vec<f64> {
        let mut y = vec![0.0; size];
        for (r, &x) in xs.iter().enumerate().filter(|(_, &x)| x != 0.0) {
            let e = self.start[r]..self.start[r + 1];
            for (&j, &v) in self.col[e.clone()].iter().zip(&self.val[e]) {
                y[j as usize] += v * x;
            }
        }
        y
    }
}

/// The storage of the matrix of a status, kept between factorisations: its pattern is the one
/// of the last [`Analysis`] made, its values those of the last factorisation.
#[derive(Default)]
struct Work {
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    values: Vec<f64>,
}

/// The parallelism of the sparse factorisations: the factor's fronts on a wall are small,
/// and the threads' waiting cost more than they gained (measured, docs/performance.md).
const PAR: Par = Par::Seq;

impl SparseSystem {
    /// Assembles H of `problem` and analyses its pattern.
    pub fn new(problem: &Problem) -> Result<SparseSystem, String> {
        let (n_glued, n) = (problem.n_glued(), problem.n_open_rows);
        let size = n_glued + n;
        let h = crate::linalg::triangle_from_entries(size, Side::Lower, |sink| {
            for (b, op) in problem.ops.iter().enumerate() {
                let m = op.u_idx.len();
                let t: Vec<Vec<(usize, f64)>> = (0..m)
                    .map(|l| problem.dof_unknowns(problem.dof_start[b] + l))
                    .collect();
                for i in 0..m {
                    for j in 0..m {
                        let sij = op.s[(i, j)];
                        if sij == 0.0 {
                            continue;
                        }
                        for &(gi, xi) in &t[i] {
                            for &(gj, xj) in &t[j] {
                                if gj >= gi {
                                    sink(gj, gi, xi * xj * sij);
                                }
                            }
                        }
                    }
                }
            }
            // Every diagonal entry exists, so that every unknown has its place in the pattern.
            for k in 0..size {
                sink(k, k, 0.0);
            }
        })
        .ok_or_else(|| {
            format!("assembling the sparse contact system of {size} unknowns: out of memory")
        })?;
        Self::from_matrix(h, n_glued, n, rigid::RigidRows::new(problem))
    }

    /// The system of H (lower triangle) over `n_glued` glued displacements and `n` rows that
    /// can open, in this order, with the rows' rigid-motion rows `rigid`.
    fn from_matrix(
        h: SparseColMat<usize, f64>,
        n_glued: usize,
        n: usize,
        rigid: rigid::RigidRows,
    ) -> Result<SparseSystem, String> {
        let size = n_glued + n;
        let ordered = Ordered::new(&h).ok_or_else(|| {
            format!("analysing the sparse contact system of {size} unknowns: out of memory")
        })?;
        let rows = RowsOfH::new(&ordered, n_glued, n).ok_or_else(|| {
            format!("storing the rows of the sparse contact system's {n} openings: out of memory")
        })?;
        let (cp, ri) = (h.symbolic().col_ptr(), h.symbolic().row_idx());
        let diag = (0..size)
            .map(|k| {
                (cp[k]..cp[k + 1])
                    .find(|&p| ri[p] == k)
                    .map_or(0.0, |p| h.val()[p])
            })
            .collect();
        Ok(SparseSystem {
            n_glued,
            n,
            ordered,
            rows,
            diag,
            last: None,
            scratch: Scratch::default(),
            work: Work::default(),
            spare: Vec::new(),
            held: None,
            border: None,
            border_spare: Mat::new(),
            analysis: None,
            lu: lu::NumericLu::new(),
            rigid,
        })
    }

    /// Whether the status `open` may hold every body: false where its closed rows leave a
    /// rigid motion free ([`rigid`]), so that its exact form is singular and only its
    /// proximal form can be solved.
    fn may_hold(&self, inner: &Inner, open: &[bool]) -> bool {
        self.rigid.holds(&inner.follow(open)).unwrap_or(true)
    }

    /// The factorisation of H over the glued displacements and the `open` rows, with `reg`
    /// added to the diagonal of the open rows; None where it is not positive definite. The
    /// closed rows are left out (not pinned in place), so that their couplings add no fill:
    /// on walls most rows are closed. The elimination order is the one of the whole pattern
    /// (every row open), found once, restricted to the unknowns kept; the factor's storage
    /// is the one of the factor it replaces.
    fn factor(&mut self, open: &[bool], reg: f64) -> Option<Reduced> {
        let ng = self.n_glued;
        let analysis = match self.analysis.take() {
            Some(a) if a.open == open => a,
            _ => Arc::new(self.analyse(open)?),
        };
        self.analysis = Some(Arc::clone(&analysis));
        let ord = &self.ordered;
        let index = &analysis.index;
        let sym = ord.h.symbolic();
        let (cp, ri, val) = (sym.col_ptr(), sym.row_idx(), ord.h.val());
        let w = &mut self.work;
        w.values.clear();
        for p in (0..index.len()).filter(|&p| index[p] != usize::MAX) {
            for q in cp[p]..cp[p + 1] {
                let row = ri[q];
                if index[row] == usize::MAX {
                    continue;
                }
                let mut v = val[q];
                if row == p && ord.unknown[p] >= ng && reg > 0.0 {
                    v += reg * v.abs().max(f64::MIN_POSITIVE);
                }
                w.values.push(v);
            }
        }
        let symbolic = &analysis.symbolic;
        let m = analysis.kept.len();
        let pattern = SymbolicSparseColMatRef::new_checked(m, m, &w.col_ptr, None, &w.row_idx);
        let mut l = std::mem::take(&mut self.spare);
        // faer's supernodal factorisation clears the factor's storage itself; its simplicial
        // one writes every entry of the pattern.
        l.truncate(symbolic.len_val());
        if l.try_reserve_exact(symbolic.len_val() - l.len()).is_err() {
            return None;
        }
        l.resize(symbolic.len_val(), 0.0);
        let req = symbolic.factorize_numeric_llt_scratch::<f64>(PAR, Default::default());
        let Some(stack) = self.scratch.stack(req) else {
            self.spare = l;
            return None;
        };
        let mat = SparseColMatRef::new(pattern, &w.values);
        let ok = symbolic
            .factorize_numeric_llt(
                &mut l,
                mat,
                Side::Lower,
                Default::default(),
                PAR,
                stack,
                Default::default(),
            )
            .is_ok();
        if ok {
            Some(Reduced { analysis, l })
        } else {
            self.spare = l;
            None
        }
    }

    /// The unknowns the status `open` keeps, the pattern of H over them (in `work`) and its
    /// symbolic factorisation in the elimination order of the whole pattern; None where the
    /// memory cannot be had.
    fn analyse(&mut self, open: &[bool]) -> Option<Analysis> {
        let ng = self.n_glued;
        let ord = &self.ordered;
        let size = ord.unknown.len();
        let keep = |k: usize| k < ng || open[k - ng];
        let mut index = vec![usize::MAX; size];
        let mut kept = Vec::new();
        for p in 0..size {
            if keep(ord.unknown[p]) {
                index[p] = kept.len();
                kept.push(ord.unknown[p]);
            }
        }
        let sym = ord.h.symbolic();
        let (cp, ri) = (sym.col_ptr(), sym.row_idx());
        let w = &mut self.work;
        w.col_ptr.clear();
        w.row_idx.clear();
        w.col_ptr.push(0);
        for p in (0..size).filter(|&p| index[p] != usize::MAX) {
            for q in cp[p]..cp[p + 1] {
                if index[ri[q]] != usize::MAX {
                    w.row_idx.push(index[ri[q]]);
                }
            }
            w.col_ptr.push(w.row_idx.len());
        }
        let m = kept.len();
        // The analysis in the matrix's own order reads an upper triangle: the transposed
        // pattern (each column's rows come out sorted).
        let mut up_ptr = vec![0usize; m + 1];
        for &r in &w.row_idx {
            up_ptr[r + 1] += 1;
        }
        for c in 0..m {
            up_ptr[c + 1] += up_ptr[c];
        }
        let mut next = up_ptr[..m].to_vec();
        let mut up_idx = vec![0usize; w.row_idx.len()];
        for c in 0..m {
            for &r in &w.row_idx[w.col_ptr[c]..w.col_ptr[c + 1]] {
                up_idx[next[r]] = c;
                next[r] += 1;
            }
        }
        let pattern = SymbolicSparseColMatRef::new_checked(m, m, &up_ptr, None, &up_idx);
        let symbolic = cholesky::factorize_symbolic_cholesky(
            pattern,
            Side::Upper,
            cholesky::SymmetricOrdering::Identity,
            Default::default(),
        )
        .ok()?;
        Some(Analysis {
            open: open.to_vec(),
            kept,
            index,
            symbolic,
        })
    }

    /// `H x` with the full symmetric H from its triangle in the elimination order.
    fn apply(&self, x: &[f64]) -> Vec<f64> {
        let ord = &self.ordered;
        let xp: Vec<f64> = ord.unknown.iter().map(|&k| x[k]).collect();
        let mut yp = vec![0.0; x.len()];
        let sym = ord.h.symbolic();
        let (cp, ri, val) = (sym.col_ptr(), sym.row_idx(), ord.h.val());
        for c in 0..x.len() {
            for p in cp[c]..cp[c + 1] {
                let r = ri[p];
                yp[r] += val[p] * xp[c];
                if r != c {
                    yp[c] += val[p] * xp[r];
                }
            }
        }
        let mut y = vec![0.0; x.len()];
        for (p, &k) in ord.unknown.iter().enumerate() {
            y[k] = yp[p];
        }
        y
    }

    /// The unknowns `w = (v, s)` of the status `open` (free rows open whatever `open`
    /// says, stick rows of open pairs following them), with the slip directions of slipping
    /// friction rows and the proximal term `prox` as for [`SparseSystem::state`]; None where
    /// the status leaves a body free. Also the statuses followed and the directions used.
    #[allow(clippy::type_complexity)]
    fn solve_w(
        &mut self,
        inner: &Inner,
        c: &[f64],
        open: &[bool],
        sign: &[f64],
        prox: Option<(f64, &[f64])>,
    ) -> Option<(Vec<bool>, Vec<f64>, Vec<f64>)> {
        let reg = prox.map_or(0.0, |p| p.0);
        let (ng, n) = (self.n_glued, self.n);
        // A stick row of an open pair ties as its pair closes.
        let open = inner.follow(open);
        let mut sg = vec![0.0; n];
        // Fixed openings of the closed rows, the others zero.
        let mut x = vec![0.0; ng + n];
        for r in 0..n {
            if open[r] {
                if inner.is_friction(r) {
                    sg[r] = if sign[r] < 0.0 { -1.0 } else { 1.0 };
                }
            } else {
                x[ng + r] = inner.base.offset[r];
            }
        }
        let hx = self.rows.times_transposed(&x[ng..], ng + n);
        let target = |r: usize| open_target(inner, r, &open, &sg);
        if (0..n).any(|r| inner.coupling(r, &open).is_some()) {
            let w = self.solve_coupled(inner, c, (&open, &sg), (&x, &hx), prox)?;
            return Some((open, sg, w));
        }
        let rhs: Vec<f64> = (0..ng + n)
            .map(|k| {
                if k >= ng && !open[k - ng] {
                    x[k]
                } else {
                    let t = match (k >= ng, prox) {
                        (false, _) => 0.0,
                        (true, None) => target(k - ng),
                        (true, Some((eps, centre))) => {
                            target(k - ng) + eps * self.diag[k].abs() * centre[k - ng]
                        }
                    };
                    t - c[k] - hx[k]
                }
            })
            .collect();
        let w = self.solve_status(&open, reg, &rhs, x)?;
        // A factorisation can pass on a matrix that is singular up to roundoff (a body left
        // free): its displacements then run to about 1/ε of the loaded state's.
        let size = |v: &[f64]| v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let reference = size(&inner.base.v0).max(size(&inner.base.offset));
        if !w.iter().all(|v| v.is_finite()) || (reg == 0.0 && size(&w) > SINGULAR * reference) {
            return None;
        }
        Some((open, sg, w))
    }

    /// `w` of the status `open` with the proximal weight `reg`: the closed rows' openings as
    /// given in `w`, the other unknowns solved with the right-hand side `rhs` — by the factor
    /// of this status where it is the last one made, else bordered from the factor of
    /// another status with the same weight that differs in a few rows ([`border`]), else by
    /// a factorisation. None where the status's matrix is not positive definite (a body left
    /// free) or the memory cannot be had.
    fn solve_status(
        &mut self,
        open: &[bool],
        reg: f64,
        rhs: &[f64],
        mut w: Vec<f64>,
    ) -> Option<Vec<f64>> {
        let same = matches!(&self.last, Some((o, g, _)) if *o == open && *g == reg);
        if !same {
            if let Some(w) = border::solve(self, open, reg, rhs, &w) {
                return Some(w);
            }
            self.refactor(open, reg);
        }
        let red = self.last.as_ref().and_then(|(_, _, f)| f.as_ref())?;
        let an = &red.analysis;
        let mut sol = Mat::<f64>::from_fn(an.kept.len(), 1, |i, _| rhs[an.kept[i]]);
        red.solve_in_place(&mut self.scratch, sol.as_mut())?;
        for (i, &k) in an.kept.iter().enumerate() {
            w[k] = sol[(i, 0)];
        }
        Some(w)
    }

    /// Factors the status `open` with the weight `reg` into `last`. The factor it replaces
    /// gives its storage to the new one (two at once would double the peak memory), except
    /// that an exact attempt from a proximal factor keeps that factor in `held` until the
    /// attempt succeeds.
    fn refactor(&mut self, open: &[bool], reg: f64) {
        self.release_border();
        let freed = match self.last.take() {
            Some((o, g, Some(f))) if reg == 0.0 && g > 0.0 => self.held.replace((o, g, f)),
            Some((o, g, Some(f))) => Some((o, g, f)),
            _ => None,
        };
        if reg > 0.0 {
            let held = self.held.take().map(|h| h.2);
            self.recycle(held);
        }
        self.recycle(freed.map(|f| f.2));
        let llt = self.factor(open, reg);
        if llt.is_some() {
            let held = self.held.take().map(|h| h.2);
            self.recycle(held);
        }
        self.last = Some((open.to_vec(), reg, llt));
    }

    /// Lets the last bordered solve go, keeping the storage of its columns for the next.
    fn release_border(&mut self) {
        if let Some(b) = self.border.take() {
            self.border_spare = b.into_storage();
        }
    }

    /// Keeps the storage of a factor no longer used for the next factorisation, where it
    /// is larger than the one kept (fresh storage costs its pages again: on the 45 × 45
    /// wall the kernel's clearing of fresh pages was a tenth of the contact stage).
    fn recycle(&mut self, f: Option<Reduced>) {
        if let Some(f) = f {
            if f.l.capacity() > self.spare.capacity() {
                self.spare = f.l;
            }
        }
    }

    /// The unknowns `w` of the status `open` where slipping rows follow Coulomb's law within
    /// the solve ([`Inner::coupling`]): row r of such a row's equation is
    /// `(H w)_r + σ μ (H w)_k = σ μ c_k' − c_r − σ μ c_k` for its pair's closed normal row k
    /// (λ_r = −σ μ (λ_k − c_k'), c' the cohesion) — H plus μ-weighted normal rows, not
    /// symmetric: one sparse LU with partial pivoting per status. The closed rows' openings
    /// are fixed in `x` (`hx = H x`); `prox` as for [`SparseSystem::solve_w`]. None where
    /// the matrix is singular (a body left free) or the memory cannot be had.
    fn solve_coupled(
        &mut self,
        inner: &Inner,
        c: &[f64],
        (open, sg): (&[bool], &[f64]),
        (x, hx): (&[f64], &[f64]),
        prox: Option<(f64, &[f64])>,
    ) -> Option<Vec<f64>> {
        let (ng, n) = (self.n_glued, self.n);
        let size = ng + n;
        let mut index = vec![usize::MAX; size];
        let mut m = 0;
        for k in (0..size).filter(|&k| k < ng || open[k - ng]) {
            index[k] = m;
            m += 1;
        }
        let mut rhs = vec![0.0; m];
        for k in (0..size).filter(|&k| index[k] != usize::MAX) {
            let t = if k < ng {
                0.0
            } else {
                open_target(inner, k - ng, open, sg)
            };
            rhs[index[k]] = t - c[k] - hx[k];
        }
        // The slipping rows tied to each closed normal row, with σ μ.
        let mut tied: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n];
        for r in 0..n {
            if let Some((k, mu)) = inner.coupling(r, open) {
                let f = sg[r] * mu;
                tied[k].push((index[ng + r], f));
                rhs[index[ng + r]] = f * inner.base.cohesion[k]
                    - c[ng + r]
                    - hx[ng + r]
                    - f * (c[ng + k] + hx[ng + k]);
            }
        }
        let ord = &self.ordered;
        let sym = ord.h.symbolic();
        let (cp, ri, val) = (sym.col_ptr(), sym.row_idx(), ord.h.val());
        let mut trip = Vec::with_capacity(2 * val.len());
        // H_ij = v: in row i's equation where i is free, in the tied rows' where i is a
        // closed normal row; column j where j is free.
        let mut add = |i: usize, j: usize, v: f64| {
            let col = index[j];
            if col == usize::MAX {
                return;
            }
            if index[i] != usize::MAX {
                trip.push(Triplet::new(index[i], col, v));
            }
            if i >= ng {
                for &(row, f) in &tied[i - ng] {
                    trip.push(Triplet::new(row, col, f * v));
                }
            }
        };
        for p in 0..size {
            for q in cp[p]..cp[p + 1] {
                let (a, b) = (ord.unknown[ri[q]], ord.unknown[p]);
                add(a, b, val[q]);
                if a != b {
                    add(b, a, val[q]);
                }
            }
        }
        if let Some((eps, centre)) = prox {
            for r in (0..n).filter(|&r| open[r]) {
                let d = eps * self.diag[ng + r].abs().max(f64::MIN_POSITIVE);
                let i = index[ng + r];
                trip.push(Triplet::new(i, i, d));
                rhs[i] += d * centre[r];
            }
        }
        let mat = SparseColMat::<usize, f64>::try_new_from_triplets(m, m, &trip).ok()?;
        drop(trip);
        // Sequential, as the Cholesky factors are; the LU's values and work space are kept
        // from one status to the next (fresh ones cost their pages again every time: on the
        // 220-stone wall 13 M page faults and 23 s of system time of 93 s). Kept only in
        // faer's supernodal LU, which clears its storage before use: its simplicial one
        // keeps column pointers of a larger earlier matrix (faer 0.24), so small systems,
        // which cost little anyway, take fresh storage.
        let reuse = m >= LU_REUSE_FROM;
        if !reuse {
            self.lu = lu::NumericLu::new();
        }
        let params = lu::LuSymbolicParams {
            supernodal_flop_ratio_threshold: if reuse {
                SupernodalThreshold::FORCE_SUPERNODAL
            } else {
                SupernodalThreshold::AUTO
            },
            ..Default::default()
        };
        let symbolic = lu::factorize_symbolic_lu(mat.symbolic(), params).ok()?;
        let req = symbolic
            .factorize_numeric_lu_scratch::<f64>(PAR, Default::default())
            .or(symbolic.solve_in_place_scratch::<f64>(1, PAR));
        let stack = self.scratch.stack(req)?;
        let lu = symbolic
            .factorize_numeric_lu(&mut self.lu, mat.as_ref(), PAR, stack, Default::default())
            .ok()?;
        let mut sol = Mat::<f64>::from_fn(m, 1, |i, _| rhs[i]);
        lu.solve_in_place_with_conj(Conj::No, sol.as_mut(), PAR, stack);
        let mut w = x.to_vec();
        for k in (0..size).filter(|&k| index[k] != usize::MAX) {
            w[k] = sol[(index[k], 0)];
        }
        let big = |v: &[f64]| v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let reference = big(&inner.base.v0).max(big(&inner.base.offset));
        if !w.iter().all(|v| v.is_finite()) || (prox.is_none() && big(&w) > SINGULAR * reference) {
            return None;
        }
        Some(w)
    }

    /// The state of the status `open` (free rows open whatever `open` says) with the slip
    /// directions `sign` of slipping friction rows; None when the status leaves a body free.
    /// With a proximal term `(ε, s̄)` every open row r gets the spring `ε H_rr (s_r − s̄_r)`:
    /// a body that the status leaves free then moves by a finite step from s̄ towards what
    /// stops it (iterates only: a result is a state without it, or one whose spring force is
    /// within the tolerance).
    fn state(
        &mut self,
        inner: &Inner,
        c: &[f64],
        open: &[bool],
        sign: &[f64],
        prox: Option<(f64, &[f64])>,
    ) -> Option<InnerState> {
        let (ng, n) = (self.n_glued, self.n);
        if prox.is_none() && !inner.follow(open).contains(&true) {
            // Every row closed: the base state, which the problem's own factor solved (on a
            // wall from rest the first iterate; its factorisation here cost as much as any).
            return Some(closed_state(inner));
        }
        let (open, sg, w) = self.solve_w(inner, c, open, sign, prox)?;
        let hw = self.rows.times(&w);
        let mut lambda: Vec<f64> = (0..n).map(|r| hw[r] + c[ng + r]).collect();
        for r in 0..n {
            if open[r] {
                lambda[r] = match inner.coupling(r, &open) {
                    // −σ μ (λ_n − c) of the closed normal row, as solved.
                    Some((k, mu)) => -sg[r] * mu * (lambda[k] - inner.base.cohesion[k]),
                    None => open_target(inner, r, &open, &sg),
                };
            }
        }
        Some(InnerState {
            open,
            sign: sg,
            s: w[ng..].to_vec(),
            lambda,
        })
    }
}

/// The force an open row `r` holds in the status `open` with slip directions `sg`: −σ g on a
/// slipping friction row (zero where its bound follows Coulomb's law within the solve and its
/// pair is open), 0 elsewhere; a row tied to its normal force within the solve
/// ([`Inner::coupling`]) gets its force from the solve instead.
fn open_target(inner: &Inner, r: usize, open: &[bool], sg: &[f64]) -> f64 {
    if !inner.is_friction(r) {
        return 0.0;
    }
    if inner.coupled && inner.pair_open(r, open) {
        0.0
    } else {
        -sg[r] * inner.bound[r]
    }
}

/// Relative proximal weight on the open rows of an iterate that leaves a body free, and the
/// lightest it is made while the statuses hold and the free bodies still drift.
const REGULARISATION: f64 = 1e-2;
const REGULARISATION_MIN: f64 = 1e-10;
/// Switches after a proximal iterate up to which its weight is not made heavier.
const FEW_SWITCHES: usize = 16;

/// Iterations of one inner solve, and halvings of the step after repeated statuses, before
/// the evolutive path takes over (the active set ends in a few where it converges).
const MAX_ITERATIONS: usize = 200;
/// Iterations of the attempt with Coulomb's law within the iteration before the bounds are
/// held fixed: the running-bond walls settle in at most 32 (4 128 bricks); a trial beyond a
/// collapse multiplier, where no equilibrium exists, spends all of them.
const COULOMB_ITERATIONS: usize = 50;
/// Or one per this many rows that can open where that is more: the 64 × 64 wall on joint
/// cuts (about 150 000 rows) reached an exact status with no violation at its 50th iterate,
/// its bounds still moving.
const COULOMB_ROWS_PER_ITERATION: usize = 1000;
const MAX_HALVINGS: u32 = 8;
/// After an exact attempt fails (its status leaves a body free), the next 1, then 2, then
/// at most this many iterates go straight to their proximal form; an attempt that succeeds
/// resets it. On the walls nearly every attempt between the first free status and the last
/// few iterates fails part-way through a factorisation (45 × 45 on joint cuts: 16 of 18,
/// 5.9 s of a 32 s contact stage); skipping them left every status the same (tractions
/// within 3e-13 of the largest at 45 × 45, bitwise at 64 × 64), and the contact stage took
/// 27.5 s against 32.3 s at 45 × 45, 105 s against 179 s at 64 × 64.
const MAX_BACKOFF: u32 = 4;
/// The rows the semismooth Newton attempt switches at most per iterate, the largest
/// violations first: with every violation switching at once its iterates wander (the
/// 220-stone wall with μ = 0.7: 200–2 300 violations); with 100 it settles there in 375.
const COUPLED_SWITCHES: usize = 100;
/// Its iterations: `COULOMB_ITERATIONS`, or one per this many rows that can open where that
/// is more (the stone wall: 5 110 rows, 511 iterations; a trial beyond a collapse
/// multiplier spends all of them, so a small wall keeps 50).
const COUPLED_ROWS_PER_ITERATION: usize = 10;

/// Unknowns from which the Newton attempt's LU keeps its storage between statuses (in faer's
/// supernodal LU, which the systems of walls take anyway: the 220-stone wall's 8 000).
const LU_REUSE_FROM: usize = 1000;

/// Displacements this many times those of the loaded, all-closed state mean a body is free.
const SINGULAR: f64 = 1e7;

/// Solves the inner problem from the statuses `open` and slip directions `sign` by the
/// primal–dual active set iteration on the sparse system. Every violated row switches at
/// once; after a repeated status only the larger half of the violations switch (then a
/// quarter, …), which breaks the cycles of the full step; a status that leaves a body free
/// is passed through with a proximal spring (module header).
pub fn solve(
    inner: &Inner,
    sys: &mut SparseSystem,
    open: &[bool],
    sign: &[f64],
    max_iterations: usize,
) -> InnerOutcome {
    if inner.coulomb.is_empty() {
        return iterate(inner.clone(), sys, open, sign, max_iterations, MAX_HALVINGS);
    }
    // Coulomb's law within the iteration: stopped at its first repeated status (a cycle of
    // the lagged bounds, seen with μ = 10 near collapse) or `COULOMB_ITERATIONS`; then the
    // semismooth Newton iteration with the slip forces tied to the normal forces, and where
    // that does not settle either, the iteration with the bounds held fixed (Tresca, the
    // outer loop's fixed point) starts again from the same statuses.
    let limit = max_iterations.min(COULOMB_ITERATIONS.max(inner.n() / COULOMB_ROWS_PER_ITERATION));
    let first = iterate(inner.coulomb_form(), sys, open, sign, limit, 0);
    if !first.stalled {
        return first;
    }
    // The lagged bounds cycle where a sliding body wedges itself (its normal forces rise as
    // it slides): the semismooth Newton iteration with each slipping row's force tied to its
    // normal force within the solve follows that.
    let coupled_limit =
        max_iterations.min(COULOMB_ITERATIONS.max(inner.n() / COUPLED_ROWS_PER_ITERATION));
    let second = iterate(
        inner.coupled_form(),
        sys,
        open,
        sign,
        coupled_limit,
        MAX_HALVINGS,
    );
    if !second.stalled {
        let mut out = second;
        out.notes.insert(
            0,
            format!(
                "Coulomb's law with each iterate's slip bounds from the last did not settle in \
                 {} iterations; with the slipping rows' forces tied to their normal forces \
                 within each solve (semismooth Newton) it settled in {}",
                first.iterations, out.iterations
            ),
        );
        out.iterations += first.iterations;
        return out;
    }
    let first = InnerOutcome {
        iterations: first.iterations + second.iterations,
        notes: [first.notes, second.notes].concat(),
        ..first
    };
    let budget = max_iterations.saturating_sub(first.iterations);
    let mut out = iterate(inner.clone(), sys, open, sign, budget, MAX_HALVINGS);
    out.iterations += first.iterations;
    let why = first.notes.join("; ");
    out.notes.insert(
        0,
        format!(
            "Coulomb's law within the sparse iteration did not settle in {} iterations \
             ({why}): the slip bounds were held fixed (Tresca) for this step",
            first.iterations
        ),
    );
    out
}

/// The iteration of [`solve`] on `cur`, whose slip bounds follow Coulomb's law where it has
/// Coulomb rows; the outcome carries the bounds of its state.
fn iterate(
    mut cur: Inner,
    sys: &mut SparseSystem,
    open: &[bool],
    sign: &[f64],
    max_iterations: usize,
    max_halvings: u32,
) -> InnerOutcome {
    let c = cur.problem.linear_term(cur.base.factor, &cur.base.cohesion);
    let mut sign = sign.to_vec();
    let mut open = cur.start_open(open, &sign);
    let mut seen: HashSet<Vec<i8>> = HashSet::new();
    let mut iterations = 0;
    let mut damping = 0u32;
    let mut last: Option<InnerState> = None;
    // The proximal weight of the next iterate that leaves a body free.
    let mut reg = REGULARISATION;
    // The Newton attempt has its own budget (`COUPLED_ROWS_PER_ITERATION`).
    let limit = if cur.coupled {
        max_iterations
    } else {
        max_iterations.min(MAX_ITERATIONS)
    };
    let mut attempts = ExactAttempts::default();
    loop {
        // The exact form is tried where the closed rows hold every body (a status that
        // leaves one free fails part-way through its factorisation: 1.2-3.3 s each, 11 times
        // on the 64 x 64 wall), unless a factorisation failed just before.
        let skipped = attempts.skips();
        let exact = if skipped || !sys.may_hold(&cur, &open) {
            None
        } else {
            attempts.record(sys.state(&cur, &c, &open, &sign, None))
        };
        let mut center = Vec::new();
        let (st, regularised) = match exact {
            Some(st) => (st, false),
            None => {
                center = last.as_ref().map_or(&cur.base.offset, |st| &st.s).clone();
                match sys.state(&cur, &c, &open, &sign, Some((reg, &center))) {
                    Some(st) => (st, true),
                    None => {
                        let state = last.unwrap_or_else(|| closed_state(&cur));
                        return stalled(state, iterations, "a status leaves a body free");
                    }
                }
            }
        };
        // Coulomb's law: the next iterate's slip bounds from this one's normal forces; the
        // statuses are checked against them.
        // The bounds this iterate was solved with (Coulomb rows only).
        let mut used = None;
        let moved = match cur.coulomb_bounds(&st) {
            // Coupled within the solve, the state's own bounds are those it was solved with.
            Some(b) if cur.coupled => {
                cur.bound.clone_from(&b);
                used = Some(b);
                false
            }
            Some(b) => {
                let moved = bound_change(&cur.bound, &b) > BOUNDS_SETTLED;
                used = Some(std::mem::replace(&mut cur.bound, b));
                moved
            }
            None => false,
        };
        let mut v = cur.violations(&st);
        if v.is_empty() && moved {
            // The statuses hold but the bounds moved: the same status again with the new
            // bounds (the same factor: two triangular solves).
            if iterations >= limit {
                return stalled(st, iterations, "the iteration limit");
            }
            seen.clear();
            if regularised {
                reg = (reg * 0.1).max(REGULARISATION_MIN);
            }
            last = Some(st);
            iterations += 1;
            continue;
        }
        if v.is_empty() && !regularised {
            return converged(st, iterations, used);
        }
        if v.is_empty() {
            // The statuses hold with the proximal term: where its force is within the
            // tolerance the state solves the problem (a free body's place is not unique),
            // else the next iterate starts from this one.
            let (fs, _) = cur.scales(&st);
            let prox = (0..cur.n())
                .filter(|&r| st.open[r])
                .map(|r| reg * sys.diag[sys.n_glued + r].abs() * (st.s[r] - center[r]).abs())
                .fold(0.0f64, f64::max);
            if prox <= cur.tol * fs {
                return converged(st, iterations, used);
            }
            if iterations >= limit {
                return stalled(st, iterations, "a status leaves a body free");
            }
            // The free bodies drift by a step inversely proportional to the proximal weight:
            // a lighter weight lets them reach what stops them sooner. A status whose exact
            // attempt was skipped is tried now: it may hold every body.
            reg = (reg * 0.1).max(REGULARISATION_MIN);
            if skipped {
                attempts.skip = 0;
            }
            last = Some(st);
            iterations += 1;
            continue;
        }
        if iterations >= limit {
            return stalled(st, iterations, "the iteration limit");
        }
        if !seen.insert(status_key(&st)) {
            damping += 1;
            if damping > max_halvings {
                return stalled(st, iterations, "a repeated status");
            }
        }
        // Measured with the joint cuts (28 × 28 wall: 34 → 21 iterations); the tangential
        // cut's path is left as it was (there it took 18 iterations instead of 15).
        let moving = if regularised {
            moving_rows(&st, &center)
        } else {
            Vec::new()
        };
        if regularised && !cur.problem.cuts.is_empty() {
            keep_first_stops(&cur, &st, &center, &moving, &mut v);
        }
        let mut take = if damping == 0 {
            v.len()
        } else {
            (v.len() >> damping.min(31)).max(1)
        };
        if cur.coupled {
            // The Newton iteration's globalisation: the largest violations first.
            take = take.min(COUPLED_SWITCHES);
        }
        let free = regularised && v[..take].iter().all(|x| !moving[x.row]);
        (open, sign) = switched(&st, &v[..take]);
        reg = next_weight(reg, regularised, take, free);
        last = Some(st);
        iterations += 1;
    }
}

/// The exact attempts of [`iterate`]: after one fails, the next 1, 2, then up to
/// `MAX_BACKOFF` iterates skip theirs; one that succeeds resets the count.
#[derive(Default)]
struct ExactAttempts {
    /// Iterates left that skip their attempt.
    skip: u32,
    /// The last such count.
    backoff: u32,
}

impl ExactAttempts {
    /// Whether this iterate skips its attempt (counted).
    fn skips(&mut self) -> bool {
        let skips = self.skip > 0;
        self.skip = self.skip.saturating_sub(1);
        skips
    }

    /// Counts the outcome of an attempt, and passes it on.
    fn record(&mut self, state: Option<InnerState>) -> Option<InnerState> {
        if state.is_some() {
            self.backoff = 0;
        } else {
            self.backoff = (self.backoff * 2).clamp(1, MAX_BACKOFF);
            self.skip = self.backoff;
        }
        state
    }
}

/// The proximal weight after an iterate that switched `take` rows (`free`: none of them
/// moved with a free body). The weight is a trust region. An exact iterate starts again from
/// the heaviest. A proximal iterate that switched many rows, which a free body thrown too
/// far does, makes it tenfold heavier; one that switched none that moved with a free body
/// (the body reached nothing) tenfold lighter, so that it reaches its stop sooner; one that
/// switched a few, some of them moving with a free body, keeps it (measured against a reset
/// to the heaviest after many switches, 45 × 45 wall on joint cuts: 47 → 39 iterations,
/// 62 → 50 factorisations; 28 × 28: 20 → 17).
fn next_weight(reg: f64, regularised: bool, take: usize, free: bool) -> f64 {
    if !regularised {
        REGULARISATION
    } else if take > FEW_SWITCHES {
        (reg * 10.0).min(REGULARISATION)
    } else if free {
        (reg * 0.1).max(REGULARISATION_MIN)
    } else {
        reg
    }
}

/// A free body thrown past what stops it: of the open rows it moved (`moving`), only the
/// first it reached ([`first_stops`]) keeps its violation in `v`; the other violations
/// stay. Where none would be left, `v` stays whole.
fn keep_first_stops(
    cur: &Inner,
    st: &InnerState,
    center: &[f64],
    moving: &[bool],
    v: &mut Vec<Violation>,
) {
    let first = first_stops(cur, st, center, moving);
    let keep = |x: &Violation| !st.open[x.row] || !moving[x.row] || first.contains(&x.row);
    if v.iter().any(keep) {
        v.retain(keep);
    }
}

/// Where a proximal iterate `st` leaves bodies free (it moved them from `center`): of the
/// open rows that move with a free body (`moving`, [`moving_rows`]), per body, the one that
/// the motion closes first (an open normal row reaching zero
/// opening, a slipping friction row whose slip ends). Only those cross their limits in the
/// exact motion; the rows behind them were reached because the proximal step overshot.
fn first_stops(cur: &Inner, st: &InnerState, center: &[f64], moving: &[bool]) -> HashSet<usize> {
    let n = cur.n();
    let d = |r: usize| st.s[r] - center[r];
    let starts = &cur.problem.dof_start;
    let body_of = |dof: usize| starts.partition_point(|&s| s <= dof).saturating_sub(1);
    // Per body: the step (1 at `st`) at which its first row closes, and that row.
    let mut first: std::collections::HashMap<usize, (f64, usize)> = Default::default();
    for r in (0..n).filter(|&r| moving[r]) {
        let (value, rate) = if cur.is_friction(r) {
            let sg = st.sign[r];
            (sg * (center[r] - cur.base.offset[r]), sg * d(r))
        } else if cur.is_normal(r) && !cur.free[r] {
            (center[r], d(r))
        } else {
            continue;
        };
        if rate >= 0.0 {
            continue;
        }
        let alpha = value.max(0.0) / -rate;
        let row = cur.problem.rows[r];
        for b in [body_of(row.dof_a), body_of(row.dof_b)] {
            let e = first.entry(b).or_insert((f64::INFINITY, r));
            if alpha < e.0 {
                *e = (alpha, r);
            }
        }
    }
    first.values().filter(|x| x.0 <= 1.0).map(|x| x.1).collect()
}

/// The open rows that a proximal iterate `st` moved from `center` by at least a tenth of
/// the largest motion: those that move with a free body.
fn moving_rows(st: &InnerState, center: &[f64]) -> Vec<bool> {
    let d: Vec<f64> = (0..st.open.len())
        .map(|r| if st.open[r] { st.s[r] - center[r] } else { 0.0 })
        .collect();
    let big = d.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    d.iter()
        .map(|x| big > 0.0 && x.abs() >= 0.1 * big)
        .collect()
}

/// A solution, with the slip bounds it was solved with (its forces on slipping rows) where
/// they followed Coulomb's law.
fn converged(state: InnerState, iterations: usize, bound: Option<Vec<f64>>) -> InnerOutcome {
    let mut out = InnerOutcome::converged(state, iterations);
    out.bound = bound;
    out
}

/// The statuses of `st` with the rows of `v` switched (a sticking friction row to slipping
/// in the direction of its violation).
fn switched(st: &InnerState, v: &[Violation]) -> (Vec<bool>, Vec<f64>) {
    let (mut open, mut sign) = (st.open.clone(), st.sign.clone());
    for x in v {
        open[x.row] = !open[x.row];
        sign[x.row] = if open[x.row] { x.sign } else { 0.0 };
    }
    (open, sign)
}

fn stalled(state: InnerState, iterations: usize, why: &str) -> InnerOutcome {
    InnerOutcome::stalled(
        state,
        iterations,
        vec![format!("the sparse active set stopped: {why}")],
    )
}

/// Every row closed at its offset, with the forces of the base.
fn closed_state(inner: &Inner) -> InnerState {
    let n = inner.n();
    InnerState {
        open: vec![false; n],
        sign: vec![0.0; n],
        s: inner.base.offset.clone(),
        lambda: inner.base.lambda0.clone(),
    }
}

/// The motion of a mechanism: the direction in which the unknowns `w = (v, s)` of the status
/// `open` (slip directions `sign`) run as the proximal weight on its open rows falls from
/// 1e-6 to 1e-8 of their diagonal, anchored at the openings `centre` — the loaded motion of
/// the bodies that the status leaves free, the part of `w` that the weight alone holds.
/// Normalised to a largest entry of 1; None where the status holds every body (then `w`
/// hardly changes) or a factorisation fails.
pub(crate) fn mechanism_motion(
    inner: &Inner,
    sys: &mut SparseSystem,
    open: &[bool],
    sign: &[f64],
    centre: &[f64],
) -> Option<Vec<f64>> {
    let c = inner
        .problem
        .linear_term(inner.base.factor, &inner.base.cohesion);
    let (_, _, w1) = sys.solve_w(inner, &c, open, sign, Some((1e-6, centre)))?;
    let (_, _, w2) = sys.solve_w(inner, &c, open, sign, Some((1e-8, centre)))?;
    let size = |v: &[f64]| v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    let dw: Vec<f64> = w2.iter().zip(&w1).map(|(a, b)| a - b).collect();
    let big = size(&dw);
    // A free body's part grows a hundredfold; the rest changes by about 1e-6 of itself.
    (big > 0.5 * size(&w2) && big > 0.0).then(|| dw.iter().map(|x| x / big).collect())
}
