//! Wrenches of loads on a body about its centroid, integrated the way the discretisation
//! holds them: the post-processing's equilibrium (`post::equilibrium`) and the contact
//! stage's rigid-block statics (`contact::statics`) both use them, so they live below both.
//!
//! Moments are about the body's centroid (of its polygonal boundary, the domain the boundary
//! elements integrate over), counter-clockwise positive, per unit thickness:
//!
//! * a traction linear along a segment `x0 → x1` of length `L` with end values `t0`, `t1`:
//!   `F = L (t0 + t1)/2`, `M = L/6 (2 r0×t0 + r0×t1 + r1×t0 + 2 r1×t1)` (`r = x − c`, exact);
//! * a body force `b`: `b |Ω|` at the centroid (no moment about it);
//! * an interface pair's nodal force: at the pair's node on the first body, and on the
//!   second where its partners are (`pair_arm`).

use super::{Body, Interface, Model, Role};
use crate::input::scene::{Condition, Frame};
use crate::vec2::cross;

/// Force (x, y) and moment of one load.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Wrench {
    pub fx: f64,
    pub fy: f64,
    pub m: f64,
}

impl Wrench {
    pub fn add(&mut self, o: Wrench) {
        self.fx += o.fx;
        self.fy += o.fy;
        self.m += o.m;
    }
    pub fn scaled(self, k: f64) -> Wrench {
        Wrench {
            fx: self.fx * k,
            fy: self.fy * k,
            m: self.m * k,
        }
    }
    pub fn force(&self) -> f64 {
        self.fx.hypot(self.fy)
    }
}

/// The centroid moments are taken about, kept as one of the body's nodes `o` and the
/// centroid relative to it, `c`: far from the origin the centroid itself rounds to the
/// spacing of coordinates there, but an arm `(x − o) − c` keeps every digit.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Pivot {
    pub o: [f64; 2],
    pub c: [f64; 2],
}

impl Pivot {
    /// The arm from the centroid to `x`.
    pub(crate) fn arm(&self, x: [f64; 2]) -> [f64; 2] {
        [
            (x[0] - self.o[0]) - self.c[0],
            (x[1] - self.o[1]) - self.c[1],
        ]
    }
    /// The arm from the centroid to a point given relative to `o`.
    pub(crate) fn arm_rel(&self, r: [f64; 2]) -> [f64; 2] {
        [r[0] - self.c[0], r[1] - self.c[1]]
    }
    /// The centroid in absolute coordinates (rounded far from the origin).
    pub fn point(&self) -> [f64; 2] {
        [self.o[0] + self.c[0], self.o[1] + self.c[1]]
    }
}

/// Area and centroid of a body's polygonal boundary (the body is on the left of every
/// element, so holes subtract), relative to its first node to keep the digits.
pub fn centroid(body: &Body) -> (f64, Pivot) {
    let o = body.nodes.first().copied().unwrap_or([0.0; 2]);
    let (mut a, mut cx, mut cy) = (0.0, 0.0, 0.0);
    for e in &body.elements {
        let p = body.nodes[e.nodes[0]];
        let q = body.nodes[e.nodes[1]];
        let (p, q) = ([p[0] - o[0], p[1] - o[1]], [q[0] - o[0], q[1] - o[1]]);
        let w = cross(p, q);
        a += 0.5 * w;
        cx += (p[0] + q[0]) * w / 6.0;
        cy += (p[1] + q[1]) * w / 6.0;
    }
    if a == 0.0 {
        return (0.0, Pivot { o, c: [0.0; 2] });
    }
    (
        a,
        Pivot {
            o,
            c: [cx / a, cy / a],
        },
    )
}

/// The wrench about `c` of a traction linear along the segment `x0 → x1`.
pub(crate) fn segment_wrench(
    x0: [f64; 2],
    x1: [f64; 2],
    t0: [f64; 2],
    t1: [f64; 2],
    c: &Pivot,
) -> Wrench {
    let l = (x1[0] - x0[0]).hypot(x1[1] - x0[1]);
    let (r0, r1) = (c.arm(x0), c.arm(x1));
    Wrench {
        fx: 0.5 * l * (t0[0] + t1[0]),
        fy: 0.5 * l * (t0[1] + t1[1]),
        m: l / 6.0 * (2.0 * cross(r0, t0) + cross(r0, t1) + cross(r1, t0) + 2.0 * cross(r1, t1)),
    }
}

/// The wrench of the body force `b` (per unit area) over a body of area `area`: at the
/// centroid, so without moment about it.
pub(crate) fn body_force_wrench(b: [f64; 2], area: f64) -> Wrench {
    Wrench {
        fx: b[0] * area,
        fy: b[1] * area,
        m: 0.0,
    }
}

/// The arm from the centroid `c` of `body` to where the nodal force of pair `j` of
/// interface `it` acts on it: the pair's node on the first body (`on_a`), and on the second
/// its node (node pairs) or where its partners are (sides meshed on their own).
pub(crate) fn pair_arm(c: &Pivot, it: &Interface, body: &Body, j: usize, on_a: bool) -> [f64; 2] {
    if !on_a && it.independent() {
        c.arm_rel(it.b_offset(body, j, c.o))
    } else {
        c.arm(it.pairs[j].x)
    }
}

/// The wrench of the loads given on body `bi` at load factor `f` and pseudo-time `t`, about
/// its centroid, per unit thickness: the prescribed tractions of its boundary parts, linear
/// along each element between their values at its nodes (as the assembly holds them,
/// `bem::assembly`), and its body force times its area. Reactions of displacement
/// conditions and interface forces are not in it.
pub(crate) fn body_load(model: &Model, bi: usize, f: f64, t: f64) -> Wrench {
    let body = &model.bodies[bi];
    let (area, c) = centroid(body);
    let mut total = Wrench::default();
    let b = match &body.body_force_spec {
        Some(s) => Some([s[0].eval([0.0, 0.0], t), s[1].eval([0.0, 0.0], t)]),
        None => body.body_force,
    };
    if let Some(b) = b {
        total.add(body_force_wrench([b[0] * f, b[1] * f], area));
    }
    for e in &body.elements {
        let Role::Boundary(pi) = e.role else { continue };
        let spec = &model.parts[pi].spec;
        let mut tr = [[0.0; 2]; 2];
        for (k, cond) in spec.components.iter().enumerate() {
            let Condition::Traction(v) = cond else {
                continue;
            };
            let dir = match (spec.frame, k) {
                (Frame::Global, 0) => [1.0, 0.0],
                (Frame::Global, _) => [0.0, 1.0],
                (Frame::Local, 0) => e.tangent,
                (Frame::Local, _) => e.normal,
            };
            for (end, te) in tr.iter_mut().enumerate() {
                let val = f * v.eval(body.nodes[e.nodes[end]], t);
                te[0] += val * dir[0];
                te[1] += val * dir[1];
            }
        }
        if tr != [[0.0; 2]; 2] {
            let (x0, x1) = (body.nodes[e.nodes[0]], body.nodes[e.nodes[1]]);
            total.add(segment_wrench(x0, x1, tr[0], tr[1], &c));
        }
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_traction_on_a_segment_integrates_exactly() {
        // t = (0, s) along x from 0 to 2 (s = x): F = 2, M about 0 = ∫ x·x dx = 8/3.
        let at = |c: [f64; 2]| Pivot { o: [0.0; 2], c };
        let w = segment_wrench(
            [0.0, 0.0],
            [2.0, 0.0],
            [0.0, 0.0],
            [0.0, 2.0],
            &at([0.0; 2]),
        );
        assert!((w.fy - 2.0).abs() < 1e-15 && w.fx == 0.0);
        assert!((w.m - 8.0 / 3.0).abs() < 1e-15, "{}", w.m);
        // About the resultant's line of action x = 4/3 the moment vanishes.
        let w = segment_wrench(
            [0.0, 0.0],
            [2.0, 0.0],
            [0.0, 0.0],
            [0.0, 2.0],
            &at([4.0 / 3.0, 5.0]),
        );
        assert!(w.m.abs() < 1e-15, "{}", w.m);
    }
}
