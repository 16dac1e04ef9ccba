//! The hint given when the glued system is singular: which body can move and how.

// Index loops mirror the block formulas.
#![allow(clippy::needless_range_loop)]

use super::{BodyOp, Row};
use crate::input::model::Model;

/// Names the bodies that nothing but interfaces holds and the rigid motion that the closed
/// rows leave free (translation along a direction, or rotation).
pub fn mechanism_hint(model: &Model, ops: &[BodyOp], rows: &[Row], dof_start: &[usize]) -> String {
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
            let m = rigid_row(pr.x, c, dir, scale);
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

/// The centroid of a body's nodes.
pub(super) fn centroid(nodes: &[[f64; 2]]) -> [f64; 2] {
    let m = nodes.len().max(1) as f64;
    let (sx, sy) = nodes
        .iter()
        .fold((0.0, 0.0), |a, p| (a.0 + p[0], a.1 + p[1]));
    [sx / m, sy / m]
}

/// What the rigid modes (x, y translation, rotation about `c` scaled by `scale`) move a
/// point `x` along the direction `dir`.
pub(super) fn rigid_row(x: [f64; 2], c: [f64; 2], dir: [f64; 2], scale: f64) -> [f64; 3] {
    [
        dir[0],
        dir[1],
        (-(x[1] - c[1]) * dir[0] + (x[0] - c[0]) * dir[1]) / scale,
    ]
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
