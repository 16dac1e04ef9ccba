//! The evolutive iteration (the paper's iterative LCP, §3.1): one status switch per
//! iteration, every state recorded.
//!
//! Place in the flow: `lcp` (the inner problem) → **`evolutive`** → `contact` (the driver).
//! From a start status, the most violated normal row switches (a closed row in tension beyond
//! its cohesion opens, an open row that interpenetrates closes), the status is re-solved by
//! updating the Cholesky factor of A_OO (O(|O|²), no refactorisation), and the state is
//! recorded. A stick row that ties as its pair closes (`Inner::tie_on_close`) switches with
//! its pair's normal row (a block pivot of the two). Each switch is a principal pivot of the
//! LCP; the most-violated rule follows the detachment front but can cycle (Ben
//! Gharbia–Gilbert), so a repeated status turns the rule into Murty's least-index rule,
//! which terminates on the unique solution of an LCP with a P-matrix (A positive definite).

use std::collections::HashSet;

use crate::contact::lcp::{status_key, Inner, InnerOutcome, InnerState, OpeningColumns};

/// Solves the inner problem from the statuses `open` (with the slip directions `sign` of
/// slipping friction rows); `record` is called with every state (the start included).
pub fn solve(
    inner: &Inner,
    cols: &mut OpeningColumns,
    open: &[bool],
    sign: &[f64],
    max_iterations: usize,
    record: &mut dyn FnMut(&InnerState),
) -> InnerOutcome {
    let mut notes = Vec::new();
    let open = inner.start_open(open, sign);
    let mut sign = sign.to_vec();
    let (mut o, refused) = inner.factor(cols, &open);
    // A free row (an untied stick row, a friction row without a slip bound) that cannot
    // open leaves a body free: no equilibrium (the body tips over or comes loose).
    let loose: Vec<usize> = refused.iter().copied().filter(|&r| inner.free[r]).collect();
    if !loose.is_empty() {
        let st = inner.state(cols, &o, &sign);
        let why = format!(
            "{} free tangential row(s) cannot be free without leaving a body free",
            loose.len()
        );
        return InnerOutcome::failed(st, 0, vec![why], loose);
    }
    if !refused.is_empty() {
        notes.push(format!(
            "{} pair(s) of the start status could not be open without leaving a body free; \
             the iteration started with them closed (first contact)",
            refused.len()
        ));
    }
    let mut st = inner.state(cols, &o, &sign);
    record(&st);
    let mut seen: HashSet<Vec<i8>> = HashSet::new();
    seen.insert(status_key(&st));
    let mut least_index = false;
    let mut iterations = 0;
    let mut blocked: HashSet<usize> = HashSet::new();
    while iterations < max_iterations {
        let v = inner.violations(&st);
        if v.is_empty() {
            cols.keep(&o);
            let mut out = InnerOutcome::converged(st, iterations);
            out.notes = notes;
            return out;
        }
        let mut candidates = v.clone();
        if least_index {
            candidates.sort_unstable_by_key(|x| x.row);
        }
        let mut switched = false;
        for (i, x) in candidates.iter().enumerate() {
            let r = x.row;
            if st.open[r] {
                inner.close_row(&mut o, r);
                sign[r] = 0.0;
                switched = true;
                break;
            }
            if blocked.contains(&r) {
                continue;
            }
            // A missing column is computed with the next closed candidates' missing ones
            // beside it, one per core (the front moves on to them: on the 410-brick wall
            // every column computed so was used later): a column is a sparse solve, the
            // largest serial part of a switch on walls of hundreds of bricks.
            if cols.peek(r).is_none() {
                let ahead: Vec<usize> = std::iter::once(r)
                    .chain(
                        candidates[i + 1..]
                            .iter()
                            .map(|y| y.row)
                            .filter(|&y| {
                                !st.open[y] && !blocked.contains(&y) && cols.peek(y).is_none()
                            })
                            .take(rayon::current_num_threads().saturating_sub(1)),
                    )
                    .collect();
                cols.ensure(inner.problem, &ahead);
            }
            if inner.open_row(cols, &mut o, r) {
                sign[r] = x.sign;
                switched = true;
                break;
            }
            blocked.insert(r);
        }
        if !switched {
            cols.keep(&o);
            let mut rows: Vec<usize> = blocked.iter().copied().collect();
            rows.sort_unstable();
            return InnerOutcome::failed(st, iterations, notes, rows);
        }
        iterations += 1;
        st = inner.state(cols, &o, &sign);
        blocked.clear();
        record(&st);
        if !seen.insert(status_key(&st)) {
            if least_index {
                notes.push(format!(
                    "the least-index rule returned to an earlier status after {iterations} \
                     iterations (the opening stiffness is not positive definite)"
                ));
                return InnerOutcome::failed(st, iterations, notes, Vec::new());
            }
            notes.push(format!(
                "the most-violated rule returned to an earlier status after {iterations} \
                 iterations; continued with the least-index rule"
            ));
            least_index = true;
            seen.clear();
            seen.insert(status_key(&st));
        }
    }
    cols.keep(&o);
    notes.push(format!(
        "the contact iteration did not converge in {max_iterations} iterations \
         (solve.max_iterations)"
    ));
    InnerOutcome::failed(st, iterations, notes, Vec::new())
}
