//! The thrust line of a masonry structure: per joint (interface) the resultant of its contact
//! tractions and its point of application, for `thrust.csv`, `summary.json` (`thrust`) and
//! the VTK block `thrust`.
//!
//! Place in the flow: reads one solved state of an interface (its pairs' positions, arc
//! lengths, tributary lengths and tractions); writes plain records. The same function serves
//! the run (from the model) and the VTK files (from the record, so that `sgbem export`
//! rebuilds them).
//!
//! The tractions are integrated as every other resultant of the tool is (summary.json
//! `normal_resultant`, the `equilibrium` block): the contact problem's nodal forces
//! `P_j = t_j w_j`, the pair traction times its tributary length, at the pair's node. For
//! the P1 hats `Σ P_j = ∫ t ds` and `Σ x_j P_j = ∫ x t ds` hold exactly, so the point found
//! is the one with which the body balances (to round-off).
//!
//! * `N = −Σ t_n,j w_j` (times the thickness): the normal force, **compression positive**
//!   (the pair tractions are tension positive);
//! * `T = Σ t_s,j w_j` (times the thickness): the tangential force on the first body along
//!   the pairs' tangent `(−n_y, n_x)`, as `tangential_resultant` in summary.json;
//! * the point of application, the centre of the normal forces:
//!   `x_c = Σ x_j t_n,j w_j / Σ t_n,j w_j` and its arc position `s_c` likewise. On a straight
//!   joint it is where the line of action of the joint's resultant crosses the joint;
//! * the eccentricity `e = s_c − s_m`, signed along the joint (towards its end), from the
//!   joint's mid-point `s_m`, and `e / (L/2)`: a hinge forms where |e| reaches L/2;
//! * `inside`: the point lies within the joint (|e| ≤ L/2); `in_closed_part`: within the
//!   span of its closed pairs.
//!
//! The joint spans the pairs that carry a tributary length (all of them where the nodes pair
//! up; where the sides were meshed on their own, those facing the other body). A fully open
//! joint (no normal force, `Σ |t_n,j| w_j = 0`) has no point: its figures are `None`.
//!
//! The VTK line: [`segments`] joins the two joints of a body; a body with more ([`hubs`]) gets
//! a line from each joint's point to its hub, the point where the resultant of its bed joints
//! below ("below" along the body's body force, −y without one) crosses the bed, about which
//! that resultant has no moment (docs/thrust.md); the hubs are also `thrust_hubs.csv`.

use crate::solution::{InterfaceResult, PairStatus};

/// Relative tolerance of `inside` and `in_closed_part`: a point at the edge of the joint
/// (a hinge) is inside up to the rounding of the sums.
const EDGE_TOLERANCE: f64 = 1e-9;

/// The pairs of one joint: positions (of the first body's nodes), arc lengths from the
/// curve's first node, tributary lengths and the first body's outward unit normals.
#[derive(Debug, Clone)]
pub struct Joint {
    pub x: Vec<[f64; 2]>,
    pub s: Vec<f64>,
    pub weights: Vec<f64>,
    pub normal: Vec<[f64; 2]>,
}

impl Joint {
    /// The pairs of a model interface.
    pub fn of(it: &crate::input::model::Interface) -> Joint {
        Joint {
            x: it.pairs.iter().map(|p| p.x).collect(),
            s: it.pairs.iter().map(|p| p.s).collect(),
            weights: it.weights(),
            normal: it.pairs.iter().map(|p| p.normal).collect(),
        }
    }
}

/// The resultant of one joint and, where it carries a normal force, its point of
/// application.
#[derive(Debug, Clone)]
pub struct Thrust {
    /// The normal force, compression positive, times the thickness.
    pub normal: f64,
    /// The tangential force on the first body along the pairs' tangent, times the thickness.
    pub tangential: f64,
    /// The joint's length (the span of the pairs with a tributary length).
    pub length: f64,
    /// `None` where the joint carries no normal force (fully open).
    pub point: Option<Application>,
    /// The normal nodal forces `t_n,j w_j` (tension positive, per unit thickness).
    forces: Vec<f64>,
    /// The resultant on the first body, `Σ (t_n,j n_j + t_s,j τ_j) w_j`, times the thickness.
    pub force: [f64; 2],
    /// Its moment about [`Thrust::about`], `Σ (x_j − a) × (t_n,j n_j + t_s,j τ_j) w_j`,
    /// times the thickness (counter-clockwise positive).
    pub moment: f64,
    /// The point the moment is taken about: the first pair's position (the origin for a
    /// joint without pairs). Arms from it are exact differences of nearby numbers, so a
    /// joint far from the origin keeps the digits of its moment.
    pub about: [f64; 2],
    /// The first body's outward normal averaged over the pairs by their tributary lengths.
    pub normal_mean: [f64; 2],
}

/// Where the resultant of a joint acts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Application {
    pub x: [f64; 2],
    /// Arc position from the curve's first node.
    pub s: f64,
    /// Eccentricity: `s` from the joint's mid-point, positive towards the joint's end.
    pub e: f64,
    /// `e / (L/2)`: ±1 at the joint's ends (a hinge).
    pub e_over_half_length: f64,
    /// Within the joint: |e| ≤ L/2.
    pub inside: bool,
    /// Within the span of the joint's closed pairs.
    pub in_closed_part: bool,
}

impl Thrust {
    /// `Σ v_j P_j / Σ P_j` over the normal nodal forces: the value of a per-pair quantity at
    /// the point of application (its position from the pairs' positions); `None` without
    /// a point.
    pub(crate) fn at_point(&self, v: &[[f64; 2]]) -> Option<[f64; 2]> {
        self.point?;
        let total: f64 = self.forces.iter().sum();
        let mut acc = [0.0; 2];
        for (p, vj) in self.forces.iter().zip(v) {
            acc[0] += p * vj[0];
            acc[1] += p * vj[1];
        }
        Some([acc[0] / total, acc[1] / total])
    }
}

/// The resultant of joint `j` in the solved state `r` and its point of application, the
/// forces times `thickness`.
pub fn thrust(j: &Joint, r: &InterfaceResult, thickness: f64) -> Thrust {
    let forces: Vec<f64> = r
        .pairs
        .iter()
        .zip(&j.weights)
        .map(|(p, w)| p.traction[1] * w)
        .collect();
    let tangential: f64 = r
        .pairs
        .iter()
        .zip(&j.weights)
        .map(|(p, w)| p.traction[0] * w)
        .sum();
    let total: f64 = forces.iter().sum();
    let magnitude: f64 = forces.iter().map(|f| f.abs()).sum();
    // The joint: the pairs with a tributary length; its closed part: those closed.
    let span = |closed: bool| {
        let mut lo_hi = (f64::INFINITY, f64::NEG_INFINITY);
        for ((s, w), p) in j.s.iter().zip(&j.weights).zip(&r.pairs) {
            if *w > 0.0 && (!closed || p.status == PairStatus::Closed) {
                lo_hi = (lo_hi.0.min(*s), lo_hi.1.max(*s));
            }
        }
        lo_hi
    };
    let about = j.x.first().copied().unwrap_or_default();
    let (force, moment, normal_mean) = vectors(j, r, about);
    let (lo, hi) = span(false);
    let length = if hi >= lo { hi - lo } else { 0.0 };
    let point = (magnitude > 0.0 && total != 0.0 && length > 0.0).then(|| {
        let mean = |v: &[f64]| v.iter().zip(&forces).map(|(a, p)| a * p).sum::<f64>() / total;
        // Positions relative to the first pair: exact differences, whose weighted mean keeps
        // its digits far from the origin.
        let xs: Vec<f64> = j.x.iter().map(|x| x[0] - about[0]).collect();
        let ys: Vec<f64> = j.x.iter().map(|x| x[1] - about[1]).collect();
        let s = mean(&j.s);
        let half = 0.5 * length;
        let e = s - 0.5 * (lo + hi);
        let slack = EDGE_TOLERANCE * length;
        let (c_lo, c_hi) = span(true);
        Application {
            x: [about[0] + mean(&xs), about[1] + mean(&ys)],
            s,
            e,
            e_over_half_length: e / half,
            inside: e.abs() <= half + slack,
            in_closed_part: s >= c_lo - slack && s <= c_hi + slack,
        }
    });
    Thrust {
        normal: -total * thickness,
        tangential: tangential * thickness,
        length,
        point,
        forces,
        force: [force[0] * thickness, force[1] * thickness],
        moment: moment * thickness,
        about,
        normal_mean,
    }
}

/// The resultant on the first body of joint `j` in `r` and its moment about `about` (per
/// unit thickness), and the first body's outward normal averaged by tributary length. The
/// tangent at a pair is `(−n_y, n_x)`.
fn vectors(j: &Joint, r: &InterfaceResult, about: [f64; 2]) -> ([f64; 2], f64, [f64; 2]) {
    let (mut f, mut m, mut n) = ([0.0; 2], 0.0, [0.0; 2]);
    for (((p, w), x), nj) in r.pairs.iter().zip(&j.weights).zip(&j.x).zip(&j.normal) {
        let [ts, tn] = p.traction;
        let fj = [(tn * nj[0] - ts * nj[1]) * w, (tn * nj[1] + ts * nj[0]) * w];
        f = [f[0] + fj[0], f[1] + fj[1]];
        let arm = [x[0] - about[0], x[1] - about[1]];
        m += arm[0] * fj[1] - arm[1] * fj[0];
        n = [n[0] + nj[0] * w, n[1] + nj[1] * w];
    }
    let len = n[0].hypot(n[1]);
    let n = if len > 0.0 {
        [n[0] / len, n[1] / len]
    } else {
        n
    };
    (f, m, n)
}

/// The bodies whose joints' points of application the thrust line joins: each body with
/// exactly two joints that carry a point, as (joint, joint) in run order. A body with more
/// joints (a brick in a bond) is drawn by [`hubs`] instead.
pub fn segments(bodies: &[(usize, usize)], has_point: &[bool], n_bodies: usize) -> Vec<[usize; 2]> {
    loaded_joints(bodies, has_point, n_bodies)
        .into_iter()
        .filter(|l| l.len() == 2)
        .map(|l| [l[0], l[1]])
        .collect()
}

/// Each body's joints that carry a point (`has_point`), in run order; `bodies[k]` is joint
/// k's (first, second) body.
fn loaded_joints(
    bodies: &[(usize, usize)],
    has_point: &[bool],
    n_bodies: usize,
) -> Vec<Vec<usize>> {
    let mut per_body: Vec<Vec<usize>> = vec![Vec::new(); n_bodies];
    for (k, &(a, b)) in bodies.iter().enumerate() {
        if has_point.get(k).copied().unwrap_or(false) {
            for body in [a, b] {
                if let Some(list) = per_body.get_mut(body) {
                    list.push(k);
                }
            }
        }
    }
    per_body
}

/// The force path through a body with more than two loaded joints: a segment from each
/// joint's point of application to the hub.
#[derive(Debug, Clone, PartialEq)]
pub struct Hub {
    pub body: usize,
    /// Where the resultant of the body's bed joints below (above where none is loaded)
    /// crosses the bed: on its line of action, the point nearest to the centre of those
    /// joints' normal forces.
    pub x: [f64; 2],
    /// The body's joints that carry a point, in run order.
    pub joints: Vec<usize>,
    /// The resultant on the body of its group (the joints below, or above), times the
    /// thickness: `R` of [`hubs`].
    pub resultant: [f64; 2],
    /// The group is the joints below the body (else above it).
    pub below: bool,
}

/// A joint is a bed joint below the body where the body's outward normal points down by
/// more than this (cos 60°), above where it points up by more.
const BED: f64 = 0.5;

/// Each body's "down": the direction of its body force `body_force` (of the state), −y where
/// it has none, or a zero or not finite one.
pub fn down(body_force: &[Option<[f64; 2]>]) -> Vec<[f64; 2]> {
    body_force
        .iter()
        .map(|f| {
            let f = f.unwrap_or_default();
            let len = f[0].hypot(f[1]);
            if len > 0.0 && len.is_finite() {
                [f[0] / len, f[1] / len]
            } else {
                [0.0, -1.0]
            }
        })
        .collect()
}

/// The hubs of the bodies with more than two joints that carry a point (docs/thrust.md
/// "Bodies with more joints"). `bodies[k]` is joint k's (first, second) body; `down[b]` body
/// b's unit "down" ([`down`]: its body force's direction, else −y). Body `b`'s group G: its
/// loaded joints whose outward normal n (of `b`) points down (`n · down > 0.5`), or where
/// there is none, up (`n · down < −0.5`). The hub lies on the line of action of G's resultant
/// `R = Σ F_j`: with `M` the moment of G's forces about the centre `m = Σ N_j p_j / Σ N_j` of
/// its points of application, `x = m + M (R_y, −R_x) / |R|²`, so that G's moment about the
/// hub vanishes. On a straight bed M = 0 and the hub is `m`. By the body's equilibrium the
/// rest of its loads (the other joints, its weight, loads on its sides) have the resultant
/// `−R` on the same line. No hub where G is empty, carries no compression or no resultant.
pub fn hubs(bodies: &[(usize, usize)], thrusts: &[Thrust], down: &[[f64; 2]]) -> Vec<Hub> {
    let has_point: Vec<bool> = thrusts.iter().map(|t| t.point.is_some()).collect();
    let mut out = Vec::new();
    for (body, joints) in loaded_joints(bodies, &has_point, down.len())
        .into_iter()
        .enumerate()
    {
        if joints.len() <= 2 {
            continue;
        }
        let d = down[body];
        // Force, moment (about the joint's `about`) and outward normal along "down" as body
        // `body` sees joint k.
        let seen = |k: usize| {
            let t = &thrusts[k];
            let sign = if bodies[k].0 == body { 1.0 } else { -1.0 };
            let f = [sign * t.force[0], sign * t.force[1]];
            let n = t.normal_mean;
            (f, sign * t.moment, sign * (n[0] * d[0] + n[1] * d[1]))
        };
        let group = |along: f64| -> Vec<usize> {
            joints
                .iter()
                .copied()
                .filter(|&k| along * seen(k).2 > BED)
                .collect()
        };
        let below = group(1.0);
        let (g, is_below) = if below.is_empty() {
            (group(-1.0), false)
        } else {
            (below, true)
        };
        if let Some((x, resultant)) = hub(&g, thrusts, &seen) {
            out.push(Hub {
                body,
                x,
                joints,
                resultant,
                below: is_below,
            });
        }
    }
    out
}

/// The point on the line of action of the resultant of joints `g` nearest to the centre of
/// their normal forces (see [`hubs`]), and that resultant; `seen(k)`: joint k's force and
/// moment (about its `about`) on the body. Points and moments are taken relative to the
/// first joint's `about`, to keep their digits far from the origin.
fn hub(
    g: &[usize],
    thrusts: &[Thrust],
    seen: &dyn Fn(usize) -> ([f64; 2], f64, f64),
) -> Option<([f64; 2], [f64; 2])> {
    let o = thrusts[*g.first()?].about;
    let rel = |p: [f64; 2]| [p[0] - o[0], p[1] - o[1]];
    let (mut r, mut m0, mut n, mut c) = ([0.0; 2], 0.0, 0.0, [0.0; 2]);
    for &k in g {
        let (f, mk, _) = seen(k);
        let nk = thrusts[k].normal;
        let p = rel(thrusts[k].point?.x);
        let a = rel(thrusts[k].about);
        r = [r[0] + f[0], r[1] + f[1]];
        // The joint's moment about o.
        m0 += mk + a[0] * f[1] - a[1] * f[0];
        n += nk;
        c = [c[0] + nk * p[0], c[1] + nk * p[1]];
    }
    let r2 = r[0] * r[0] + r[1] * r[1];
    if n <= 0.0 || r2 == 0.0 {
        return None;
    }
    let m = [c[0] / n, c[1] / n];
    // G's moment about m: M_o − (m − o) × R.
    let mm = m0 - (m[0] * r[1] - m[1] * r[0]);
    Some((
        [o[0] + m[0] + mm * r[1] / r2, o[1] + m[1] - mm * r[0] / r2],
        r,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solution::PairResult;

    fn pair(status: PairStatus, tn: f64, ts: f64) -> PairResult {
        PairResult {
            status,
            traction: [ts, tn],
            jump: [0.0, 0.0],
            slipping: None,
            slip: 0.0,
        }
    }

    /// A straight joint of length 2 along x, 5 pairs, a linear pressure: the centre of the
    /// nodal forces, the eccentricity from the mid-point and the open joint without a point.
    #[test]
    fn centre_of_pressure_of_a_straight_joint() {
        let x: Vec<[f64; 2]> = (0..5).map(|i| [0.5 * i as f64, 1.0]).collect();
        let joint = Joint {
            s: x.iter().map(|p| p[0]).collect(),
            weights: crate::input::model::tributary_lengths(&x, (0..4).map(|i| [i, i + 1])),
            normal: vec![[0.0, 1.0]; 5],
            x,
        };
        let closed = PairStatus::Closed;
        // Pressure 1..5 at the nodes: forces 0.25, 1, 1.5, 2, 1.25.
        let r = InterfaceResult {
            pairs: (0..5)
                .map(|i| pair(closed, -(1.0 + i as f64), 0.5))
                .collect(),
        };
        let t = thrust(&joint, &r, 2.0);
        assert_eq!(t.normal, 2.0 * 6.0);
        assert_eq!(t.tangential, 2.0 * 0.5 * 2.0);
        let p = t.point.expect("a point");
        let s = (0.5 * 1.0 + 1.0 * 1.5 + 1.5 * 2.0 + 2.0 * 1.25) / 6.0;
        assert!((p.s - s).abs() < 1e-15 && (p.x[0] - s).abs() < 1e-15 && p.x[1] == 1.0);
        assert!((p.e - (s - 1.0)).abs() < 1e-15);
        assert!((p.e_over_half_length - (s - 1.0)).abs() < 1e-15);
        assert!(p.inside && p.in_closed_part);
        // Open at the start: the point stays within the closed part; at the last pair alone
        // (a hinge) it is at the edge, e / (L/2) = 1, still inside.
        let mut r2 = r.clone();
        for q in &mut r2.pairs[..4] {
            *q = pair(PairStatus::Open, 0.0, 0.0);
        }
        let p2 = thrust(&joint, &r2, 1.0).point.expect("a point");
        assert_eq!((p2.s, p2.e_over_half_length), (2.0, 1.0));
        assert!(p2.inside && p2.in_closed_part);
        // Fully open: no normal force, no point.
        for q in &mut r2.pairs {
            *q = pair(PairStatus::Open, 0.0, 0.0);
        }
        let t3 = thrust(&joint, &r2, 1.0);
        assert!(t3.normal == 0.0 && t3.point.is_none() && t3.at_point(&joint.x).is_none());
    }

    #[test]
    fn segments_join_the_two_joints_of_a_body() {
        // A chain 0-1-2-3 of bodies by joints (0,1), (1,2), (2,3), and a body 4 with three.
        let joints = [(0, 1), (1, 2), (2, 3), (4, 0), (4, 2), (4, 3)];
        let all = [true; 6];
        assert_eq!(segments(&joints[..3], &all, 5), vec![[0, 1], [1, 2]]);
        assert!(segments(&joints[..3], &[true, false, true], 5).is_empty());
        assert_eq!(segments(&joints, &all, 5), vec![[0, 3], [0, 1], [2, 5]]);
    }

    /// Body 0 on two bed joints (to bodies 1 and 2, its normal down) under a third (body 3
    /// above, the first body there): the hub is the centre of the bed joints' normal forces,
    /// where their resultant (0, 4) crosses the bed; bodies with two joints get none.
    #[test]
    fn hub_of_a_brick_on_two_bed_joints() {
        let joint = |x0: f64, y: f64, n: [f64; 2]| Joint {
            x: vec![[x0, y], [x0 + 1.0, y]],
            s: vec![0.0, 1.0],
            weights: vec![0.5, 0.5],
            normal: vec![n; 2],
        };
        let load = |tn: f64, ts: f64| InterfaceResult {
            pairs: vec![pair(PairStatus::Closed, tn, ts); 2],
        };
        let n = [0.0, -1.0];
        let thrusts = [
            thrust(&joint(0.0, 0.0, n), &load(-1.0, 0.0), 1.0),
            thrust(&joint(1.0, 0.0, n), &load(-3.0, 0.5), 1.0),
            thrust(&joint(0.5, 1.0, n), &load(-4.0, 0.0), 1.0),
        ];
        let bodies = [(0, 1), (0, 2), (3, 0)];
        let h = hubs(&bodies, &thrusts, &down(&[None; 4]));
        assert_eq!(h.len(), 1);
        assert_eq!((h[0].body, h[0].joints.clone()), (0, vec![0, 1, 2]));
        assert!(
            (h[0].x[0] - 1.25).abs() < 1e-15 && h[0].x[1].abs() < 1e-15,
            "{:?}",
            h[0]
        );
        // The bed joints' moment about the hub vanishes (the tangential force on the bed
        // has no arm).
        let f = [thrusts[0].force, thrusts[1].force];
        assert_eq!(f, [[0.0, 1.0], [0.5, 3.0]]);
        let about: f64 = (0..2)
            .map(|k| {
                let a = [
                    thrusts[k].about[0] - h[0].x[0],
                    thrusts[k].about[1] - h[0].x[1],
                ];
                thrusts[k].moment + a[0] * f[k][1] - a[1] * f[k][0]
            })
            .sum();
        assert!(about.abs() < 1e-15, "{about}");
        assert_eq!((h[0].resultant, h[0].below), ([0.5, 4.0], true));
        // A body force along +x: no joint of body 0 is within 60° of it, or of its opposite.
        assert!(hubs(&bodies, &thrusts, &down(&[Some([5.0, 0.0]); 4])).is_empty());
        // Along −y again, scaled: the same hub; a zero or missing body force is −y.
        assert_eq!(hubs(&bodies, &thrusts, &down(&[Some([0.0, -9.0]); 4])), h);
        assert_eq!(
            down(&[Some([0.0, 0.0]), None, Some([3.0, 4.0])]),
            [[0.0, -1.0], [0.0, -1.0], [0.6, 0.8]]
        );
    }
}
