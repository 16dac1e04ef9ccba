//! Coulomb's law as a fixed point on the slip bounds of the full-row solver: the next bounds
//! from a programme's normal forces, Anderson's mixing of them, and the residual that says
//! when the fixed point has settled (docs/formulation.md §6.10).

use super::Programme;

/// The next slip bounds of the Coulomb rows: their new bounds, Anderson-mixed over the
/// slipping rows (only theirs act on the solution; a sticking row's bound is its new one),
/// the mixing restarted when the slipping set changes by more than a few rows.
pub(super) struct SlipBounds {
    anderson: Anderson,
    slipping: Vec<usize>,
    /// Per Coulomb row: how it settles where its pair opens and closes by turns.
    edges: Vec<Edge>,
}

/// A Coulomb row at the edge of a contact, whose pair the fixed point opens and closes by
/// turns: held by its bound it opens (G = 0), free it closes with a small normal force
/// (G > 0). Coulomb's law lies between, a row slipping at μ λ_n: after `EDGE_FLIPS` turns
/// its bound is the root of `G(x) − x` by regula falsi over the bracket the turns give
/// (Illinois' variant), not the next G, which would repeat the turn (the 4 × 5 wall at
/// 0.85 of its weight sideways with μ = 1 000: three such rows, 100 programmes of a
/// two-cycle).
#[derive(Clone, Copy, Default)]
struct Edge {
    /// The last programme's pair was open (G = 0).
    open: Option<bool>,
    turns: u8,
    /// The bracket: the bounds where G(x) − x was positive (side 0) and negative (side 1),
    /// with those values.
    ends: [Option<(f64, f64)>; 2],
    /// The side the last proposal replaced (Illinois: where the same side is replaced
    /// twice, the other end's value is halved).
    kept: Option<usize>,
}

impl Edge {
    /// Records x and G(x); the next bound where the row is an edge row, else None.
    fn next(&mut self, x: f64, gx: f64) -> Option<f64> {
        let open = gx <= 0.0;
        if self.open.is_some_and(|o| o != open) {
            self.turns = self.turns.saturating_add(1);
        }
        self.open = Some(open);
        if self.turns < EDGE_FLIPS || x.is_nan() {
            return None;
        }
        let f = gx - x;
        let side = match f {
            f if f > 0.0 => 0,
            f if f < 0.0 => 1,
            _ => return Some(x),
        };
        // The same bound on both sides of the root: the row's G moved with the other
        // rows' statuses; the bracket starts again.
        if self.ends[1 - side].is_some_and(|e| e.0 == x) {
            *self = Edge::default();
            return None;
        }
        if self.kept == Some(side) {
            if let Some(other) = self.ends[1 - side].as_mut() {
                other.1 *= 0.5;
            }
        }
        self.ends[side] = Some((x, f));
        self.kept = Some(side);
        match self.ends {
            [Some((a, fa)), Some((b, fb))] => Some(a - fa * (b - a) / (fb - fa)),
            _ => None,
        }
    }
}

impl SlipBounds {
    pub(super) fn new() -> SlipBounds {
        SlipBounds {
            anderson: Anderson::new(ANDERSON_DEPTH),
            slipping: Vec::new(),
            edges: Vec::new(),
        }
    }

    /// From the bounds `x` of the programme `sol` (NaN where tied) and the new ones `gx`.
    pub(super) fn next(
        &mut self,
        friction: &[usize],
        sol: &Programme,
        x: &[f64],
        gx: &[f64],
    ) -> Vec<f64> {
        self.edges.resize(friction.len(), Edge::default());
        let edge: Vec<Option<f64>> = (0..friction.len())
            .map(|i| self.edges[i].next(x[i], gx[i]))
            .collect();
        if x.iter().any(|v| v.is_nan()) {
            self.anderson.reset();
            return gx.to_vec();
        }
        let slip: Vec<usize> = (0..friction.len())
            .filter(|&i| sol.slipping[friction[i]] && gx[i] > 0.0 && edge[i].is_none())
            .collect();
        // Mixing restarts where the slipping set changed by more than a few rows: a row at
        // the cone's edge that flips every programme or two must not discard the history
        // (the 220-stone wall at 0.117 g on the cut mesh: not settled in 100 programmes,
        // residual 6e-4 to 5e-3, with every change restarting it; 58 programmes keeping it).
        if slip != self.slipping {
            if changed(&slip, &self.slipping) > (slip.len() / KEEP_PER).max(KEEP_MIN) {
                self.anderson.reset();
            }
            self.slipping = slip.clone();
        }
        let mut y = gx.to_vec();
        if !slip.is_empty() {
            for (k, v) in slip.iter().zip(self.anderson.mix(x, gx, &slip)) {
                y[*k] = v;
            }
        }
        // The mixed bounds stay non-negative and zero where the pair is open, but for the
        // edge rows' roots.
        for ((v, g), e) in y.iter_mut().zip(gx).zip(&edge) {
            if let Some(root) = e {
                *v = root.max(0.0);
            } else if *g <= 0.0 || !v.is_finite() {
                *v = 0.0;
            } else {
                *v = v.max(0.0);
            }
        }
        y
    }
}

/// The turns between open and closed after which a Coulomb row is an edge row.
const EDGE_FLIPS: u8 = 2;

/// The changes of the slipping set that keep Anderson's history: one row in `KEEP_PER` of
/// the set, at least `KEEP_MIN`.
const KEEP_PER: usize = 100;
const KEEP_MIN: usize = 2;

/// The differences Anderson's mixing keeps (measured on the 220-stone wall at 0.04 g,
/// μ = 0.7: 52 programmes with 10, 60 with 5, not settled in 150 without).
const ANDERSON_DEPTH: usize = 10;

/// The relative residual of Coulomb's law at which the fixed point has settled (the
/// interior point's own accuracy is 1e-10).
pub(super) const SETTLED: f64 = 1e-8;

/// How far the programme's solution `sol` (bounds `x`, NaN where tied) is from Coulomb's law
/// with the bounds `gx` its normal forces give, relative to the largest normal force: a
/// slipping row must have slipped at its new bound, a sticking row must hold its force within
/// it. Sticking rows whose bound moved but still hold are settled: at a junction the forces of
/// a sticking cycle are not unique, and the interior point picks one of them.
pub(super) fn coulomb_residual(
    friction: &[usize],
    normal: &[Option<usize>],
    sol: &Programme,
    x: &[f64],
    gx: &[f64],
) -> f64 {
    let scale = normal
        .iter()
        .flatten()
        .map(|&n| sol.force[n].abs())
        .fold(0.0f64, f64::max);
    if scale == 0.0 {
        return 0.0;
    }
    let mut worst = 0.0f64;
    for (i, &r) in friction.iter().enumerate() {
        // A tied row (x NaN) holds like a sticking one: within its new bound.
        let e = if sol.slipping[r] && !x[i].is_nan() {
            (x[i] - gx[i]).abs()
        } else {
            (sol.force[r].abs() - gx[i]).max(0.0)
        };
        worst = worst.max(e);
    }
    worst / scale
}

/// Anderson's acceleration of the fixed point x = G(x) (type II, the last `m` differences).
struct Anderson {
    m: usize,
    xs: Vec<Vec<f64>>,
    fs: Vec<Vec<f64>>,
}

impl Anderson {
    fn new(m: usize) -> Anderson {
        Anderson {
            m,
            xs: Vec::new(),
            fs: Vec::new(),
        }
    }

    fn reset(&mut self) {
        self.xs.clear();
        self.fs.clear();
    }

    /// The next iterate from x and G(x) (every row), over the rows `idx`: their mixed values.
    fn mix(&mut self, x_all: &[f64], gx_all: &[f64], idx: &[usize]) -> Vec<f64> {
        let pick = |v: &[f64]| -> Vec<f64> { idx.iter().map(|&i| v[i]).collect() };
        let f_all: Vec<f64> = gx_all.iter().zip(x_all).map(|(g, x)| g - x).collect();
        let f = pick(&f_all);
        let gx = pick(gx_all);
        self.xs.push(x_all.to_vec());
        self.fs.push(f_all);
        if self.xs.len() > self.m + 1 {
            self.xs.remove(0);
            self.fs.remove(0);
        }
        let k = self.xs.len() - 1;
        if k == 0 {
            return gx;
        }
        // Differences of the last iterates and residuals.
        let xs: Vec<Vec<f64>> = self.xs.iter().map(|v| pick(v)).collect();
        let fs: Vec<Vec<f64>> = self.fs.iter().map(|v| pick(v)).collect();
        let dx: Vec<Vec<f64>> = (0..k).map(|i| diff(&xs[i + 1], &xs[i])).collect();
        let df: Vec<Vec<f64>> = (0..k).map(|i| diff(&fs[i + 1], &fs[i])).collect();
        // γ = argmin |f − ΔF γ| by the normal equations, lightly regularised.
        let mut g = vec![vec![0.0; k]; k];
        let mut h = vec![0.0; k];
        for i in 0..k {
            h[i] = dot(&df[i], &f);
            for j in 0..k {
                g[i][j] = dot(&df[i], &df[j]);
            }
        }
        let tr: f64 = (0..k).map(|i| g[i][i]).sum::<f64>().max(f64::MIN_POSITIVE);
        for (i, row) in g.iter_mut().enumerate() {
            row[i] += 1e-10 * tr;
        }
        let Some(gamma) = crate::linalg::solve_small(g, h) else {
            self.reset();
            return gx;
        };
        (0..idx.len())
            .map(|n| {
                let mut v = gx[n];
                for i in 0..k {
                    v -= gamma[i] * (dx[i][n] + df[i][n]);
                }
                v
            })
            .collect()
    }
}

/// How many rows are in one of two sorted sets and not in the other.
fn changed(a: &[usize], b: &[usize]) -> usize {
    let (mut i, mut j, mut n) = (0, 0, 0);
    while i < a.len() && j < b.len() {
        match a[i].cmp(&b[j]) {
            std::cmp::Ordering::Equal => (i, j) = (i + 1, j + 1),
            std::cmp::Ordering::Less => (i, n) = (i + 1, n + 1),
            std::cmp::Ordering::Greater => (j, n) = (j + 1, n + 1),
        }
    }
    n + (a.len() - i) + (b.len() - j)
}

fn diff(a: &[f64], b: &[f64]) -> Vec<f64> {
    a.iter().zip(b).map(|(a, b)| a - b).collect()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(a, b)| a * b).sum()
}
