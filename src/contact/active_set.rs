//! The primal–dual active set method (semismooth Newton with c → ∞, Hintermüller–Ito–Kunisch)
//! on the inner LCP: every violated row switches at once.
//!
//! Place in the flow: `lcp` → **`active_set`** → `contact`. Usually a handful of iterations;
//! it can cycle on P-matrices of order ≥ 3 (docs/formulation.md §6.4), so a repeated status
//! ends it without a verdict (`stalled`): the driver hands over to the evolutive iteration
//! (least-index rule after its own cycle), which terminates.

use std::collections::HashSet;

use crate::contact::lcp::{status_key, Inner, InnerOutcome, OpeningColumns};

/// Solves the inner problem from the statuses `open` and slip directions `sign`.
pub fn solve(
    inner: &Inner,
    cols: &mut OpeningColumns,
    open: &[bool],
    sign: &[f64],
    max_iterations: usize,
) -> InnerOutcome {
    let mut sign = sign.to_vec();
    let mut open = inner.start_open(open, &sign);
    let mut seen: HashSet<Vec<i8>> = HashSet::new();
    let mut iterations = 0;
    loop {
        let (o, refused) = inner.factor(cols, &open);
        let st = inner.state(cols, &o, &sign);
        let v = inner.violations(&st);
        if v.is_empty() && refused.is_empty() {
            return InnerOutcome::converged(st, iterations);
        }
        if !seen.insert(status_key(&st)) || iterations >= max_iterations || v.is_empty() {
            return InnerOutcome::stalled(st, iterations, Vec::new());
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
