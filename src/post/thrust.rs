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

use crate::solution::{InterfaceResult, PairStatus};

/// Relative tolerance of `inside` and `in_closed_part`: a point at the edge of the joint
/// (a hinge) is inside up to the rounding of the sums.
const EDGE_TOLERANCE: f64 = 1e-9;

/// The pairs of one joint: positions (of the first body's nodes), arc lengths from the
/// curve's first node and tributary lengths.
#[derive(Debug, Clone)]
pub struct Joint {
    pub x: Vec<[f64; 2]>,
    pub s: Vec<f64>,
    pub weights: Vec<f64>,
}

impl Joint {
    /// The pairs of a model interface.
    pub fn of(it: &crate::input::model::Interface) -> Joint {
        Joint {
            x: it.pairs.iter().map(|p| p.x).collect(),
            s: it.pairs.iter().map(|p| p.s).collect(),
            weights: it.weights(),
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
    pub fn at_point(&self, v: &[[f64; 2]]) -> Option<[f64; 2]> {
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
    let (lo, hi) = span(false);
    let length = if hi >= lo { hi - lo } else { 0.0 };
    let point = (magnitude > 0.0 && total != 0.0 && length > 0.0).then(|| {
        let mean = |v: &[f64]| v.iter().zip(&forces).map(|(a, p)| a * p).sum::<f64>() / total;
        let xs: Vec<f64> = j.x.iter().map(|x| x[0]).collect();
        let ys: Vec<f64> = j.x.iter().map(|x| x[1]).collect();
        let s = mean(&j.s);
        let half = 0.5 * length;
        let e = s - 0.5 * (lo + hi);
        let slack = EDGE_TOLERANCE * length;
        let (c_lo, c_hi) = span(true);
        Application {
            x: [mean(&xs), mean(&ys)],
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
    }
}

/// The bodies whose joints' points of application the thrust line joins: each body with
/// exactly two joints that carry a point, as (joint, joint) in run order. A body with more
/// joints (a brick in a bond) is left out: its load paths branch.
pub fn segments(bodies: &[(usize, usize)], has_point: &[bool], n_bodies: usize) -> Vec<[usize; 2]> {
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
        .into_iter()
        .filter(|l| l.len() == 2)
        .map(|l| [l[0], l[1]])
        .collect()
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
}
