//! The evolutive iteration (the paper's iterative LCP, §3.1): one status switch per
//! iteration, every state recorded.
//!
//! Place in the flow: `lcp` (the inner problem) → **`evolutive`** → `contact` (the driver).
//! From a start status, the most violated normal row switches (a closed row in tension beyond
//! its cohesion opens, an open row that interpenetrates closes), the status is re-solved by
//! updating the Cholesky factor of A_OO (O(|O|²), no refactorisation), and the state is
//! recorded. Each switch is a principal pivot of the LCP; the most-violated rule follows the
//! detachment front but can cycle (Ben Gharbia–Gilbert), so a repeated status turns the rule
//! into Murty's least-index rule, which terminates on the unique solution of an LCP with a
//! P-matrix (A positive definite).

use std::collections::HashSet;

use crate::contact::lcp::{Columns, Inner, InnerState};

/// Outcome of an inner solve.
pub struct Outcome {
    pub state: InnerState,
    pub iterations: usize,
    pub converged: bool,
    pub notes: Vec<String>,
}

/// Solves the inner problem from the normal statuses `open`; `record` is called with every
/// state (the start included).
pub fn solve(
    inner: &Inner,
    cols: &mut Columns,
    open: &[bool],
    max_iterations: usize,
    record: &mut dyn FnMut(&InnerState),
) -> Outcome {
    let mut notes = Vec::new();
    let (mut o, refused) = inner.factor(cols, open);
    if !refused.is_empty() {
        notes.push(format!(
            "{} pair(s) of the start status could not be open without leaving a body free; \
             the iteration started with them closed (first contact)",
            refused.len()
        ));
    }
    let mut st = inner.state(cols, &o);
    record(&st);
    let mut seen: HashSet<Vec<bool>> = HashSet::new();
    seen.insert(st.open.clone());
    let mut least_index = false;
    let mut iterations = 0;
    let mut blocked: HashSet<usize> = HashSet::new();
    while iterations < max_iterations {
        let v = inner.violations(&st);
        if v.is_empty() {
            return Outcome {
                state: st,
                iterations,
                converged: true,
                notes,
            };
        }
        let mut candidates: Vec<usize> = v.iter().map(|x| x.row).collect();
        if least_index {
            candidates.sort_unstable();
        }
        let mut switched = false;
        for r in candidates {
            if st.open[r] {
                o.remove(r);
                switched = true;
                break;
            }
            if blocked.contains(&r) {
                continue;
            }
            let col = cols.get(inner.problem, r);
            if o.append(r, col) {
                switched = true;
                break;
            }
            blocked.insert(r);
        }
        if !switched {
            notes.push(format!(
                "every violated pair would leave a body free if it opened ({} pairs): the \
                 loads cannot be carried (a mechanism)",
                blocked.len()
            ));
            return Outcome {
                state: st,
                iterations,
                converged: false,
                notes,
            };
        }
        iterations += 1;
        st = inner.state(cols, &o);
        blocked.clear();
        record(&st);
        if !seen.insert(st.open.clone()) {
            if least_index {
                notes.push(format!(
                    "the least-index rule returned to an earlier status after {iterations} \
                     iterations (the opening stiffness is not positive definite)"
                ));
                return Outcome {
                    state: st,
                    iterations,
                    converged: false,
                    notes,
                };
            }
            notes.push(format!(
                "the most-violated rule returned to an earlier status after {iterations} \
                 iterations; continued with the least-index rule"
            ));
            least_index = true;
            seen.clear();
            seen.insert(st.open.clone());
        }
    }
    notes.push(format!(
        "the contact iteration did not converge in {max_iterations} iterations \
         (solve.max_iterations)"
    ));
    Outcome {
        state: st,
        iterations,
        converged: false,
        notes,
    }
}
