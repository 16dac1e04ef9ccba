//! The hint given when the glued system is singular: which body can move and how.

// Index loops mirror the block formulas.
#![allow(clippy::needless_range_loop)]

use super::{BodyOp, Row};
use crate::input::model::Model;

/// Names the bodies that nothing but interfaces holds and the rigid motion that the closed
/// rows leave free (translation along a direction, or rotation).
pub(crate) fn mechanism_hint(
    model: &Model,
    ops: &[BodyOp],
    rows: &[Row],
    dof_start: &[usize],
) -> String {
    let mut out = Vec::new();
    for (b, body) in model.bodies.iter().enumerate() {
        // Gram matrix of the rigid modes (x, y translation, rotation about the centroid)
        // seen by the rows touching body b.
        let n = ops[b].u_idx.len();
        let (lo, hi) = (dof_start[b], dof_start[b] + n);
        let c = centroid(&body.nodes);
        let scale = model.scale.max(f64::MIN_POSITIVE);
        let mut g = [[0.0f64; 3]; 3];
        let mut touched = false;
        for r in rows {
            if !(lo..hi).contains(&r.dof_a) && !(lo..hi).contains(&r.dof_b) {
                continue;
            }
            touched = true;
            let it = &model.interfaces[r.iface];
            let pr = &it.pairs[r.pair];
            let dir = if r.comp == 1 { pr.normal } else { pr.tangent };
            let m = rigid_row(pr.x, &c, dir, scale);
            for i in 0..3 {
                for j in 0..3 {
                    g[i][j] += m[i] * m[j];
                }
            }
        }
        let held_elsewhere = body_has_support(model, b);
        if held_elsewhere || (!touched && n == 0) {
            continue;
        }
        // Smallest eigenvector of the 3×3 Gram matrix by a few inverse-free sweeps (Jacobi).
        let (val, vec) = smallest_eigen(g);
        let tr = g[0][0] + g[1][1] + g[2][2];
        if val <= 1e-10 * tr.max(f64::MIN_POSITIVE) || !touched {
            let motion = if vec[2].abs() > 0.9 {
                "a rotation".to_string()
            } else {
                let l = vec[0].hypot(vec[1]).max(f64::MIN_POSITIVE);
                format!("a translation along ({:.3}, {:.3})", vec[0] / l, vec[1] / l)
            };
            out.push(format!("body \"{}\" is free to move ({motion})", body.name));
        }
    }
    if out.is_empty() {
        "a body or group of bodies is held by interfaces alone and can move freely: hold it \
         with a displacement condition, or use tangential = \"stick\" where it can slide"
            .into()
    } else {
        format!(
            "{}: with every pair closed the interfaces do not hold it (frictionless pairs on a \
             straight interface leave sliding free); hold it with a displacement condition \
             (e.g. a symmetry plane or ux = 0 on a point-like boundary), or use tangential = \
             \"stick\"",
            out.join("; ")
        )
    }
}

/// A body's centroid, held relative to an anchor `o`: far from the origin (a body farther
/// from it than 1024 times its own extent) `o` is its first node, so that the arm of a point
/// is a difference of nearby coordinates (exact) less the small centroid `c` (the absolute
/// sum of the coordinates of n nodes there loses digits: its rounding grows with n × the
/// coordinates' spacing, 0.19 for 400 nodes of a unit circle at 1e14); near it `o` is the
/// origin, and the arms are those of the plain sum, bit for bit (as post::equilibrium's
/// `Pivot`, kept here on its own).
#[derive(Debug, Clone, Copy)]
pub(super) struct Centre {
    o: [f64; 2],
    c: [f64; 2],
}

impl Centre {
    /// The arm from the centroid to `x`.
    pub(super) fn arm(&self, x: [f64; 2]) -> [f64; 2] {
        [
            (x[0] - self.o[0]) - self.c[0],
            (x[1] - self.o[1]) - self.c[1],
        ]
    }

    /// The centroid in absolute coordinates (rounded far from the origin).
    pub(super) fn point(&self) -> [f64; 2] {
        [self.o[0] + self.c[0], self.o[1] + self.c[1]]
    }

    /// The velocity at [`Centre::point`] of the rigid motion whose velocity at the centroid
    /// is `t` and whose rotation is `omega`: with the rounded point, the motion is the same
    /// at every node (near the origin the point is the centroid, and `t` is returned as is).
    pub(super) fn translation_at_point(&self, t: [f64; 2], omega: f64) -> [f64; 2] {
        // The point's rounding: exact, a difference of nearby numbers less `c`.
        let d = self.arm(self.point());
        if d == [0.0, 0.0] {
            return t;
        }
        [t[0] - omega * d[1], t[1] + omega * d[0]]
    }
}

/// The centroid of a body's nodes (see [`Centre`]).
pub(super) fn centroid(nodes: &[[f64; 2]]) -> Centre {
    let first = nodes.first().copied().unwrap_or([0.0; 2]);
    let (lo, hi) = nodes.iter().fold((first, first), |(lo, hi), p| {
        (
            [lo[0].min(p[0]), lo[1].min(p[1])],
            [hi[0].max(p[0]), hi[1].max(p[1])],
        )
    });
    let extent = (hi[0] - lo[0]).hypot(hi[1] - lo[1]);
    let far = first[0].abs().max(first[1].abs()) > 1024.0 * extent;
    let o = if far { first } else { [0.0; 2] };
    let m = nodes.len().max(1) as f64;
    let (sx, sy) = nodes.iter().fold((0.0, 0.0), |a, p| {
        (a.0 + (p[0] - o[0]), a.1 + (p[1] - o[1]))
    });
    Centre {
        o,
        c: [sx / m, sy / m],
    }
}

/// What the rigid modes (x, y translation, rotation about the centroid `c` scaled by
/// `scale`) move a point `x` along the direction `dir`.
pub(super) fn rigid_row(x: [f64; 2], c: &Centre, dir: [f64; 2], scale: f64) -> [f64; 3] {
    let r = c.arm(x);
    [dir[0], dir[1], (-r[1] * dir[0] + r[0] * dir[1]) / scale]
}

pub(crate) fn body_has_support(model: &Model, b: usize) -> bool {
    model.bodies[b].dof_counts()[0] > 0
}

fn smallest_eigen(mut a: [[f64; 3]; 3]) -> (f64, [f64; 3]) {
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..50 {
        let mut off = 0.0;
        for p in 0..3 {
            for q in (p + 1)..3 {
                off += a[p][q].abs();
                if a[p][q].abs() < 1e-300 {
                    continue;
                }
                let theta = 0.5 * (a[q][q] - a[p][p]) / a[p][q];
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let cs = 1.0 / (t * t + 1.0).sqrt();
                let sn = t * cs;
                for k in 0..3 {
                    let (akp, akq) = (a[k][p], a[k][q]);
                    a[k][p] = cs * akp - sn * akq;
                    a[k][q] = sn * akp + cs * akq;
                }
                for k in 0..3 {
                    let (apk, aqk) = (a[p][k], a[q][k]);
                    a[p][k] = cs * apk - sn * aqk;
                    a[q][k] = sn * apk + cs * aqk;
                }
                for k in 0..3 {
                    let (vkp, vkq) = (v[k][p], v[k][q]);
                    v[k][p] = cs * vkp - sn * vkq;
                    v[k][q] = sn * vkp + cs * vkq;
                }
            }
        }
        if off < 1e-14 {
            break;
        }
    }
    let i = (0..3)
        .min_by(|&x, &y| a[x][x].total_cmp(&a[y][y]))
        .unwrap_or(0);
    (a[i][i], [v[0][i], v[1][i], v[2][i]])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 400 nodes of a unit circle moved by 1e14 (rounded to the coordinates' spacing there,
    /// 1/64) against the same nodes near the origin (the exact differences): the arms from
    /// the centroid agree to 1e-12, where the plain sum of the absolute coordinates puts the
    /// centroid 0.1 to 0.2 off; the rigid motion told from the rounded absolute point moves
    /// every node as the one about the centroid does.
    #[test]
    fn arms_far_from_the_origin_keep_their_digits() {
        let x0 = 1e14;
        let far: Vec<[f64; 2]> = (0..400)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / 400.0;
                [x0 + a.cos(), x0 + 0.5 + a.sin()]
            })
            .collect();
        let near: Vec<[f64; 2]> = far.iter().map(|p| [p[0] - x0, p[1] - x0]).collect();
        let (cn, cf) = (centroid(&near), centroid(&far));
        let m = far.len() as f64;
        let plain = far
            .iter()
            .fold([0.0, 0.0], |s, p| [s[0] + p[0], s[1] + p[1]]);
        let plain = [plain[0] / m - x0, plain[1] / m - x0];
        let exact = cn.point();
        let off = (plain[0] - exact[0]).hypot(plain[1] - exact[1]);
        assert!(off > 1e-2, "the plain sum is {off} off");
        for (p, q) in near.iter().zip(&far) {
            let (a, b) = (cn.arm(*p), cf.arm(*q));
            assert!((a[0] - b[0]).abs() <= 1e-12 && (a[1] - b[1]).abs() <= 1e-12);
            let (ra, rb) = (
                rigid_row(*p, &cn, [0.6, 0.8], 1.0),
                rigid_row(*q, &cf, [0.6, 0.8], 1.0),
            );
            assert!((ra[2] - rb[2]).abs() <= 1e-12);
        }
        // A rotation ω with velocity t at the centroid, told from the rounded point.
        let (t, omega) = ([0.3, -0.2], 0.7);
        let tp = cf.translation_at_point(t, omega);
        let pt = cf.point();
        for q in &far {
            let r = cf.arm(*q);
            let exact = [t[0] - omega * r[1], t[1] + omega * r[0]];
            let told = [
                tp[0] - omega * (q[1] - pt[1]),
                tp[1] + omega * (q[0] - pt[0]),
            ];
            assert!((exact[0] - told[0]).abs() <= 1e-12 && (exact[1] - told[1]).abs() <= 1e-12);
        }
        // Near the origin the point is the centroid and the translation is kept as is.
        assert_eq!(cn.translation_at_point(t, omega), t);
    }
}
