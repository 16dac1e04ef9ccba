//! The primal–dual active set method (semismooth Newton with c → ∞, Hintermüller–Ito–Kunisch)
//! on the inner LCP: every violated row switches at once.
//!
//! Place in the flow: `lcp` → **`active_set`** → `contact`. Usually a handful of iterations;
//! it can cycle on P-matrices of order ≥ 3 (formulation §6.4), so a repeated status hands
//! over to the evolutive iteration (least-index rule after its own cycle), which terminates.

use std::collections::HashSet;

use crate::contact::evolutive::{self, Outcome};
use crate::contact::lcp::{status_key, Columns, Inner};

/// Solves the inner problem from the statuses `open` and slip directions `sign`.
pub fn solve(
    inner: &Inner,
    cols: &mut Columns,
    open: &[bool],
    sign: &[f64],
    max_iterations: usize,
) -> Outcome {
    let mut sign = sign.to_vec();
    let mut open = inner.start_open(open, &sign);
    let mut seen: HashSet<Vec<i8>> = HashSet::new();
    let mut iterations = 0;
    let mut notes = Vec::new();
    loop {
        let (o, refused) = inner.factor(cols, &open);
        let st = inner.state(cols, &o, &sign);
        let v = inner.violations(&st);
        if v.is_empty() && refused.is_empty() {
            return Outcome {
                state: st,
                iterations,
                converged: true,
                notes,
                blocked: Vec::new(),
            };
        }
        if !seen.insert(status_key(&st)) || iterations >= max_iterations || v.is_empty() {
            notes.push(format!(
                "the active-set iteration cycled after {iterations} iterations; continued \
                 with the evolutive iteration"
            ));
            let mut out = evolutive::solve(
                inner,
                cols,
                &st.open,
                &st.sign,
                max_iterations.saturating_sub(iterations),
                &mut |_| {},
            );
            out.iterations += iterations;
            notes.append(&mut out.notes);
            out.notes = notes;
            return out;
        }
        open = st.open.clone();
        sign = st.sign.clone();
        for x in &v {
            open[x.row] = !open[x.row];
            sign[x.row] = if open[x.row] { x.sign } else { 0.0 };
        }
        iterations += 1;
    }
}
