//! Coulomb's law as a fixed point on the slip bounds of the full-row solver: the next bounds
//! from a programme's normal forces, Anderson's mixing of them, and the residual that says
//! when the fixed point has settled (docs/formulation.md §6.10).

use super::Programme;

/// The next slip bounds of the Coulomb rows: their new bounds, Anderson-mixed over the
/// slipping rows (only theirs act on the solution; a sticking row's bound is its new one),
/// the mixing restarted when the slipping set changes.
pub(super) struct SlipBounds {
    anderson: Anderson,
    slipping: Vec<usize>,
}

impl SlipBounds {
    pub(super) fn new() -> SlipBounds {
        SlipBounds {
            anderson: Anderson::new(ANDERSON_DEPTH),
            slipping: Vec::new(),
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
        if x.iter().any(|v| v.is_nan()) {
            self.anderson.reset();
            return gx.to_vec();
        }
        let slip: Vec<usize> = (0..friction.len())
            .filter(|&i| sol.slipping[friction[i]] && gx[i] > 0.0)
            .collect();
        if slip != self.slipping {
            self.anderson.reset();
            self.slipping = slip.clone();
        }
        let mut y = gx.to_vec();
        if !slip.is_empty() {
            let xs: Vec<f64> = slip.iter().map(|&i| x[i]).collect();
            let gs: Vec<f64> = slip.iter().map(|&i| gx[i]).collect();
            for (k, v) in slip.iter().zip(self.anderson.mix(&xs, &gs)) {
                y[*k] = v;
            }
        }
        // The mixed bounds stay non-negative and zero where the pair is open.
        for (v, g) in y.iter_mut().zip(gx) {
            if *g <= 0.0 || !v.is_finite() {
                *v = 0.0;
            } else {
                *v = v.max(0.0);
            }
        }
        y
    }
}

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

    /// The next iterate from x and G(x).
    fn mix(&mut self, x: &[f64], gx: &[f64]) -> Vec<f64> {
        let f: Vec<f64> = gx.iter().zip(x).map(|(g, x)| g - x).collect();
        self.xs.push(x.to_vec());
        self.fs.push(f.clone());
        if self.xs.len() > self.m + 1 {
            self.xs.remove(0);
            self.fs.remove(0);
        }
        let k = self.xs.len() - 1;
        if k == 0 {
            return gx.to_vec();
        }
        // Differences of the last iterates and residuals.
        let dx: Vec<Vec<f64>> = (0..k).map(|i| diff(&self.xs[i + 1], &self.xs[i])).collect();
        let df: Vec<Vec<f64>> = (0..k).map(|i| diff(&self.fs[i + 1], &self.fs[i])).collect();
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
            return gx.to_vec();
        };
        (0..x.len())
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

fn diff(a: &[f64], b: &[f64]) -> Vec<f64> {
    a.iter().zip(b).map(|(a, b)| a - b).collect()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(a, b)| a * b).sum()
}
