//! Pairing two sides of an interface that were meshed independently (docs/formulation.md
//! §5.6): the rows of the first side's nodes over the second side's segments (dual mortar),
//! the normal gap of each row measured from the geometry, and a uniform grid over boundary
//! segments that finds the facing pieces of two boundaries.
//!
//! Place in the flow: `model` calls it while building an interface whose nodes do not pair
//! up, and while finding interfaces from the drawing (`[contact]`). Everything here is
//! plain geometry on body-local node indices; nothing reads the scene or the mesh.
//!
//! # The rows
//!
//! Side A (the first body) has hats ψ_j on its interface elements, side B hats ψ_k. Each
//! element of A is parametrised by ξ ∈ [0, 1]; a facing element of B is projected onto A's
//! element along A's element normal, which maps it onto an interval of ξ linearly. On that
//! overlap
//!
//! ```text
//!   M_jk = ∫ φ_j ψ_k ds,      D_j = Σ_k M_jk,      C_jk = M_jk / D_j
//!   g_j  = Σ_k C_jk u^B_k·n_j − u^A_j·n_j          (the row of A's node j)
//! ```
//!
//! with φ_j the *dual* basis of A on an element that B covers whole (`φ_p = 2 − 3ξ`,
//! `φ_q = 3ξ − 1`: `∫φ_j ψ_i = δ_ij ∫ψ_j`, Wohlmuth's biorthogonal basis) and the hat itself
//! on an element that B covers only in part (and on the elements next to those, so that
//! both ends of every element use the same kind). Then
//!
//! * `Σ_k C_jk = 1`: a rigid translation closes every row;
//! * on dual elements `Σ_k C_jk x_k = x_j` for every linear field: a uniform strain across
//!   the interface closes every row (the patch test, also for tied tangential rows);
//! * `D_j = ∫ψ_j` over the covered part, and B receives `Σ_j C_jk λ_j`: for a uniform
//!   pressure p, `λ_j = p D_j` is A's consistent nodal force and B's load is
//!   `p Σ_j M_jk = p ∫ψ_k` (the hats of each element sum to one), B's consistent nodal
//!   force. The pressure of a patch test is reproduced on both sides.
//!
//! Where the two meshes coincide, `M` is diagonal and `C` the identity: the rows are the
//! node-to-node rows.
//!
//! The geometric gap of a row is the same operator applied to the positions,
//! `h_j = Σ_k C_jk (x_k − x_j)·n_j`, with n_j A's nodal normal (negative: interference).

use std::collections::{BTreeMap, HashMap};

use crate::vec2::{dot, norm, sub};

/// One side of an interface: body-local node positions and its segments (body-local node
/// indices, oriented with the body on the left, so the outward normal is `(τ_y, −τ_x)`).
#[derive(Debug, Clone, Copy)]
pub struct Side<'a> {
    pub x: &'a [[f64; 2]],
    pub segments: &'a [[usize; 2]],
}

/// The row of one node of side A.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct MortarRow {
    /// Nodes of side B and their coefficients `C_jk` (they sum to one), in node order.
    pub coefs: Vec<(usize, f64)>,
    /// `D_j`: the integral of A's hat over the part of its support that faces B (the
    /// tributary length of the row).
    pub weight: f64,
    /// The geometric normal gap `Σ_k C_jk (x_k − x_j)·n_j`.
    pub gap: f64,
    /// The segment of B (index into `Side::segments`) facing the node.
    pub segment: usize,
}

/// How far the pieces of side B may lie from side A to be paired, along A's normal.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Reach {
    /// Largest gap (B ahead of A).
    pub ahead: f64,
    /// Largest interference (B behind A's surface).
    pub behind: f64,
}

/// Cosine above which a segment of B no longer faces a segment of A: their outward normals
/// must be within 60° of opposite.
const FACING_COS: f64 = -0.5;

/// Sine of the angle between two segments above which, where they come within the search
/// distance of each other near one point only, they touch at that point and do not face
/// each other: a stone's corner on the foundation, or two stones' faces that meet at a
/// vertex with a third stone in the wedge between them. No node of one lies within reach
/// of the other there, so such a pair has no row; kept, it made an interface of no rows (an
/// error) or lent a wedge's face to a joint's rows (a false overlap). The facing segments
/// of a curved body and a flat, a few degrees apart, still pair.
const POINT_TOUCH_SIN: f64 = 0.5;

fn lerp(a: [f64; 2], b: [f64; 2], t: f64) -> [f64; 2] {
    [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
}

/// Unit tangent, length and outward normal of a segment.
fn frame(p: [f64; 2], q: [f64; 2]) -> ([f64; 2], f64, [f64; 2]) {
    let d = sub(q, p);
    let l = norm(d);
    let t = if l > 0.0 {
        [d[0] / l, d[1] / l]
    } else {
        [0.0, 0.0]
    };
    (t, l, [t[1], -t[0]])
}

/// One facing piece: segment f of B over [lo, hi] of A's element, B's parameter
/// `η = (ξ − xr)/(xs − xr)`, and the normal distance at the middle of the piece.
#[derive(Debug, Clone, Copy)]
struct Piece {
    f: usize,
    lo: f64,
    hi: f64,
    xr: f64,
    xs: f64,
    dist: f64,
}

/// Segment `[r, s]` projected on `[p, q]` (whose frame is `(τ, l, ν)`): the parameters ξ of
/// r and s along it, their overlap `[lo, hi]` within [0, 1], and the distance from `[p, q]` to
/// `[r, s]` along ν at the middle of the overlap. None where `[r, s]` is perpendicular to it
/// or overlaps it by rounding only.
fn mid_overlap(
    p: [f64; 2],
    q: [f64; 2],
    (tau, l, nu): ([f64; 2], f64, [f64; 2]),
    r: [f64; 2],
    s: [f64; 2],
) -> Option<(f64, f64, f64, f64, f64)> {
    let xr = dot(sub(r, p), tau) / l;
    let xs = dot(sub(s, p), tau) / l;
    if (xs - xr).abs() <= 1e-12 {
        return None;
    }
    let lo = xr.min(xs).max(0.0);
    let hi = xr.max(xs).min(1.0);
    if hi - lo <= 1e-12 {
        return None;
    }
    let xm = 0.5 * (lo + hi);
    let eta = (xm - xr) / (xs - xr);
    // Both points relative to p (exact differences), not as positions: far from the origin
    // the positions would round.
    let dist = dot(
        sub(
            lerp(sub(r, p), sub(s, p), eta),
            lerp([0.0; 2], sub(q, p), xm),
        ),
        nu,
    );
    Some((xr, xs, lo, hi, dist))
}

/// The pieces of B that face element `[p, q]` of A, nearest layer only.
fn pieces(p: [f64; 2], q: [f64; 2], b: &Side, cands: &[usize], reach: Reach) -> Vec<Piece> {
    let (tau, l, nu) = frame(p, q);
    if l <= 0.0 {
        return Vec::new();
    }
    let mut out: Vec<Piece> = Vec::new();
    for &f in cands {
        let [r, s] = b.segments[f];
        let (xr_pt, xs_pt) = (b.x[r], b.x[s]);
        let (_, lf, nf) = frame(xr_pt, xs_pt);
        if lf <= 0.0 || dot(nu, nf) > FACING_COS {
            continue;
        }
        let Some((xr, xs, lo, hi, dist)) = mid_overlap(p, q, (tau, l, nu), xr_pt, xs_pt) else {
            continue;
        };
        if dist > reach.ahead || dist < -reach.behind {
            continue;
        }
        out.push(Piece {
            f,
            lo,
            hi,
            xr,
            xs,
            dist,
        });
    }
    // The nearest layer: a piece farther than the nearest one by more than the elements'
    // size lies behind it (the far side of a thin body, the other wall of a slot).
    if let Some(dmin) = out.iter().map(|c| c.dist).min_by(f64::total_cmp) {
        out.retain(|c| {
            let [r, s] = b.segments[c.f];
            c.dist <= dmin + l.max(norm(sub(b.x[s], b.x[r])))
        });
    }
    out
}

/// Measure of the union of intervals.
fn union_length(mut iv: Vec<(f64, f64)>) -> f64 {
    iv.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut total = 0.0;
    let mut cur: Option<(f64, f64)> = None;
    for (lo, hi) in iv {
        match cur {
            Some((a, b)) if lo <= b => cur = Some((a, b.max(hi))),
            Some((a, b)) => {
                total += b - a;
                cur = Some((lo, hi));
            }
            None => cur = Some((lo, hi)),
        }
    }
    if let Some((a, b)) = cur {
        total += b - a;
    }
    total
}

/// One element of side A with the pieces of B that face it.
struct Elem {
    ends: [usize; 2],
    length: f64,
    /// True when B covers the element whole.
    full: bool,
    pieces: Vec<Piece>,
}

/// What one node of A gathers: `M_jk` by B node, the covered integral of its hat, and the
/// segment of B facing it (the nearest piece that holds the node's parameter, else the one
/// with the largest share).
struct Acc {
    m: BTreeMap<usize, f64>,
    weight: f64,
    at_node: Option<(f64, usize)>,
    largest: (f64, usize),
}

impl Default for Acc {
    fn default() -> Acc {
        Acc {
            m: BTreeMap::new(),
            weight: 0.0,
            at_node: None,
            largest: (0.0, usize::MAX),
        }
    }
}

impl Acc {
    /// Adds the integrals of piece `c` of B over element `e` of A for the node at `end` of
    /// e, with the dual basis or the hat (`dual`).
    fn add(&mut self, e: &Elem, end: usize, dual: bool, c: &Piece, b: &Side) {
        // Gauss–Legendre, 2 points on [0, 1]: exact for the quadratic products of two hats.
        const G: [(f64, f64); 2] = [
            (0.211_324_865_405_187_1, 0.5),
            (0.788_675_134_594_812_9, 0.5),
        ];
        let [r, s] = b.segments[c.f];
        let span = (c.hi - c.lo) * e.length;
        let mut share = 0.0;
        for (g, wg) in G {
            let xi = c.lo + g * (c.hi - c.lo);
            let hat = if end == 0 { 1.0 - xi } else { xi };
            let basis = match (dual, end) {
                (false, _) => hat,
                (true, 0) => 2.0 - 3.0 * xi,
                (true, _) => 3.0 * xi - 1.0,
            };
            let eta = (xi - c.xr) / (c.xs - c.xr);
            let w = wg * span;
            *self.m.entry(r).or_default() += w * basis * (1.0 - eta);
            *self.m.entry(s).or_default() += w * basis * eta;
            self.weight += w * hat;
            share += w * hat;
        }
        if share > self.largest.0 {
            self.largest = (share, c.f);
        }
        let xi_node = end as f64;
        let holds = c.lo <= xi_node + 1e-9 && c.hi >= xi_node - 1e-9;
        if holds && self.at_node.is_none_or(|(d, _)| c.dist.abs() < d) {
            self.at_node = Some((c.dist.abs(), c.f));
        }
    }

    /// The row of node n (None where B faces too little of its hat, `full_hat` long).
    fn row(
        self,
        n: usize,
        full_hat: f64,
        a: &Side,
        normal: [f64; 2],
        b: &Side,
    ) -> Option<MortarRow> {
        // Shares at rounding level (a segment of B that meets A's hat at one end only) are
        // left out.
        let total: f64 = self.m.values().sum();
        let kept: Vec<(usize, f64)> = self
            .m
            .iter()
            .filter(|(_, &v)| v.abs() > 1e-12 * total.abs())
            .map(|(&k, &v)| (k, v))
            .collect();
        let d: f64 = kept.iter().map(|c| c.1).sum();
        if self.weight <= 1e-9 * full_hat || d <= 1e-9 * full_hat {
            return None;
        }
        let coefs: Vec<(usize, f64)> = kept.into_iter().map(|(k, v)| (k, v / d)).collect();
        let xj = a.x[n];
        let gap = coefs
            .iter()
            .map(|&(k, c)| c * dot(sub(b.x[k], xj), normal))
            .sum();
        Some(MortarRow {
            coefs,
            weight: self.weight,
            gap,
            segment: self.at_node.map_or(self.largest.1, |(_, f)| f),
        })
    }
}

/// The rows of A's interface nodes over B (see the module documentation). `normals[n]` is
/// A's unit normal at node n (only A's interface nodes are read); `cands(p, q)` lists the
/// segments of B that may face A's segment `[p, q]` (all of them, or those a
/// [`SegmentGrid`] finds near it). A node that no piece of B faces has no row.
pub(crate) fn mortar_rows(
    a: &Side,
    normals: &[[f64; 2]],
    b: &Side,
    reach: Reach,
    cands: &dyn Fn([f64; 2], [f64; 2]) -> Vec<usize>,
) -> BTreeMap<usize, MortarRow> {
    let elems: Vec<Elem> = a
        .segments
        .iter()
        .map(|&[i, j]| {
            let (p, q) = (a.x[i], a.x[j]);
            let ps = pieces(p, q, b, &cands(p, q), reach);
            let covered = union_length(ps.iter().map(|c| (c.lo, c.hi)).collect());
            Elem {
                ends: [i, j],
                length: norm(sub(q, p)),
                full: covered >= 1.0 - 1e-9,
                pieces: ps,
            }
        })
        .collect();
    // A node is "whole" when every element of A at it is covered whole; an element uses the
    // dual basis when both its ends are whole.
    let mut whole: HashMap<usize, bool> = HashMap::new();
    let mut full_hat: HashMap<usize, f64> = HashMap::new();
    for e in &elems {
        for n in e.ends {
            *whole.entry(n).or_insert(true) &= e.full;
            *full_hat.entry(n).or_default() += 0.5 * e.length;
        }
    }
    let mut acc: BTreeMap<usize, Acc> = BTreeMap::new();
    for e in &elems {
        let dual = e.ends.iter().all(|n| whole[n]);
        for (end, &n) in e.ends.iter().enumerate() {
            let at = acc.entry(n).or_default();
            for c in &e.pieces {
                at.add(e, end, dual, c, b);
            }
        }
    }
    acc.into_iter()
        .filter_map(|(n, at)| Some((n, at.row(n, full_hat[&n], a, normals[n], b)?)))
        .collect()
}

/// A uniform grid over segments: each cell lists the segments that pass through it.
#[derive(Debug, Clone)]
pub(crate) struct SegmentGrid {
    origin: [f64; 2],
    h: f64,
    cells: HashMap<(i64, i64), Vec<usize>>,
}

impl SegmentGrid {
    /// The grid of `segments` with cells of side `h` (about the mean segment length).
    pub fn new(segments: &[([f64; 2], [f64; 2])], h: f64) -> SegmentGrid {
        let origin = segments.iter().fold([f64::INFINITY; 2], |o, (a, b)| {
            [o[0].min(a[0]).min(b[0]), o[1].min(a[1]).min(b[1])]
        });
        let origin = if origin[0].is_finite() {
            origin
        } else {
            [0.0, 0.0]
        };
        let h = if h > 0.0 && h.is_finite() { h } else { 1.0 };
        let mut grid = SegmentGrid {
            origin,
            h,
            cells: HashMap::new(),
        };
        for (i, &(a, b)) in segments.iter().enumerate() {
            for c in grid.cells_along(a, b, 0.0) {
                grid.cells.entry(c).or_default().push(i);
            }
        }
        grid
    }

    fn cell(&self, p: [f64; 2]) -> (i64, i64) {
        (
            ((p[0] - self.origin[0]) / self.h).floor() as i64,
            ((p[1] - self.origin[1]) / self.h).floor() as i64,
        )
    }

    /// The cells within `r` of the segment `[a, b]` (a superset: whole cells).
    fn cells_along(&self, a: [f64; 2], b: [f64; 2], r: f64) -> Vec<(i64, i64)> {
        let lo = self.cell([a[0].min(b[0]) - r, a[1].min(b[1]) - r]);
        let hi = self.cell([a[0].max(b[0]) + r, a[1].max(b[1]) + r]);
        let count = (hi.0 - lo.0 + 1).saturating_mul(hi.1 - lo.1 + 1);
        if count <= 64 {
            let mut out = Vec::with_capacity(count as usize);
            for x in lo.0..=hi.0 {
                for y in lo.1..=hi.1 {
                    out.push((x, y));
                }
            }
            return out;
        }
        // A long or slanted segment: the cells along it, widened by r and one cell.
        let pad = (r / self.h).ceil() as i64 + 1;
        let steps = ((4.0 * norm(sub(b, a)) / self.h).ceil() as usize).max(1);
        let mut out = Vec::new();
        for k in 0..=steps {
            let c = self.cell(lerp(a, b, k as f64 / steps as f64));
            for dx in -pad..=pad {
                for dy in -pad..=pad {
                    out.push((c.0 + dx, c.1 + dy));
                }
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }

    /// The segments that may lie within `r` of the segment `[a, b]`, sorted, each once.
    pub fn near(&self, a: [f64; 2], b: [f64; 2], r: f64) -> Vec<usize> {
        let mut out: Vec<usize> = self
            .cells_along(a, b, r)
            .into_iter()
            .filter_map(|c| self.cells.get(&c))
            .flatten()
            .copied()
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }
}

/// A boundary segment of a body, for [`facing_pairs`].
#[derive(Debug, Clone, Copy)]
pub struct BodySegment {
    pub body: usize,
    pub a: [f64; 2],
    pub b: [f64; 2],
    /// Unit outward normal.
    pub normal: [f64; 2],
}

/// The pairs (i, j) of segments of different bodies (`body` of i below that of j) that face
/// each other within `search`: outward normals within 60° of opposite, at most `search`
/// apart, and each overlapping the other in projection (pieces that meet at a corner only
/// do not pair, nor pieces more than 30° apart that come within `search` near one point
/// only: `touch_at_a_point`, nor pieces farther apart than `search` at the middle of their
/// overlap: `apart_mid_overlap`). A uniform grid of cells about one segment or `search` wide, whichever is
/// larger, keeps the search near linear in the number of segments.
pub fn facing_pairs(segs: &[BodySegment], search: f64) -> Vec<(usize, usize)> {
    let lines: Vec<([f64; 2], [f64; 2])> = segs.iter().map(|s| (s.a, s.b)).collect();
    let mean =
        lines.iter().map(|(p, q)| norm(sub(*q, *p))).sum::<f64>() / lines.len().max(1) as f64;
    let grid = SegmentGrid::new(&lines, mean.max(search));
    let mut out = Vec::new();
    for (i, s) in segs.iter().enumerate() {
        for j in grid.near(s.a, s.b, search) {
            let t = &segs[j];
            if t.body <= s.body
                || dot(s.normal, t.normal) > FACING_COS
                || segment_distance(s.a, s.b, t.a, t.b) > search
                || !overlaps(s.a, s.b, t.a, t.b)
                || touch_at_a_point(s, t, search)
                || apart_mid_overlap(s, t, search)
            {
                continue;
            }
            out.push((i, j));
        }
    }
    out
}

/// True when t lies farther than `search` ahead of s at the middle of their overlap (t
/// projected on s), measured along s's normal as the rows measure it ([`pieces`]): faces that
/// meet at a corner and diverge at a small angle are within `search` near that corner only,
/// and such a pair would have no rows.
fn apart_mid_overlap(s: &BodySegment, t: &BodySegment, search: f64) -> bool {
    let f = frame(s.a, s.b);
    f.1 > 0.0 && mid_overlap(s.a, s.b, f, t.a, t.b).is_some_and(|m| m.4 > search)
}

/// True when segments s and t cross at more than 30° (`POINT_TOUCH_SIN`) and are not wholly
/// within `search` of each other: diverging lines, within reach near one point only.
fn touch_at_a_point(s: &BodySegment, t: &BodySegment, search: f64) -> bool {
    let (ds, dt) = (sub(s.b, s.a), sub(t.b, t.a));
    let cross = ds[0] * dt[1] - ds[1] * dt[0];
    if cross.abs() <= POINT_TOUCH_SIN * norm(ds) * norm(dt) {
        return false;
    }
    let near = |p: [f64; 2], a: [f64; 2], b: [f64; 2]| segment_distance(p, p, a, b) <= search;
    !(near(s.a, t.a, t.b) && near(s.b, t.a, t.b) && near(t.a, s.a, s.b) && near(t.b, s.a, s.b))
}

/// True when segment [r, s] projected on the line of [p, q] overlaps it by more than
/// rounding, and the other way round.
fn overlaps(p: [f64; 2], q: [f64; 2], r: [f64; 2], s: [f64; 2]) -> bool {
    let along = |p: [f64; 2], q: [f64; 2], r: [f64; 2], s: [f64; 2]| -> bool {
        let d = sub(q, p);
        let l2 = dot(d, d);
        if l2 <= 0.0 {
            return false;
        }
        let (a, b) = (dot(sub(r, p), d) / l2, dot(sub(s, p), d) / l2);
        a.max(b).min(1.0) - a.min(b).max(0.0) > 1e-9
    };
    along(p, q, r, s) && along(r, s, p, q)
}

/// Distance between two segments (zero where they touch or cross).
pub(crate) fn segment_distance(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> f64 {
    let point_seg = |p: [f64; 2], s0: [f64; 2], s1: [f64; 2]| -> f64 {
        let (v, w) = (sub(s1, s0), sub(p, s0));
        let l2 = dot(v, v);
        let t = if l2 > 0.0 {
            (dot(w, v) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        norm([w[0] - t * v[0], w[1] - t * v[1]])
    };
    let cross = |u: [f64; 2], v: [f64; 2]| u[0] * v[1] - u[1] * v[0];
    let (o1, o2) = (cross(sub(b, a), sub(c, a)), cross(sub(b, a), sub(d, a)));
    let (o3, o4) = (cross(sub(d, c), sub(a, c)), cross(sub(d, c), sub(b, c)));
    if o1 * o2 < 0.0 && o3 * o4 < 0.0 {
        return 0.0;
    }
    point_seg(a, c, d)
        .min(point_seg(b, c, d))
        .min(point_seg(c, a, b))
        .min(point_seg(d, a, b))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A straight side along y = y0 from x0 to x1 with n elements, the body below (normal
    /// +y, drawn right to left along the body's loop) or above (normal −y, left to right).
    fn line(x0: f64, x1: f64, y0: f64, n: usize, below: bool) -> (Vec<[f64; 2]>, Vec<[usize; 2]>) {
        let x: Vec<[f64; 2]> = (0..=n)
            .map(|i| [x0 + (x1 - x0) * i as f64 / n as f64, y0])
            .collect();
        let segs = (0..n)
            .map(|i| if below { [i + 1, i] } else { [i, i + 1] })
            .collect();
        (x, segs)
    }

    /// The rows of side A (normal +y at every node) over every segment of B.
    fn pair_up(
        xa: &[[f64; 2]],
        sa: &[[usize; 2]],
        xb: &[[f64; 2]],
        sb: &[[usize; 2]],
        reach: Reach,
    ) -> BTreeMap<usize, MortarRow> {
        let normals = vec![[0.0, 1.0]; xa.len()];
        let n = sb.len();
        mortar_rows(
            &Side {
                x: xa,
                segments: sa,
            },
            &normals,
            &Side {
                x: xb,
                segments: sb,
            },
            reach,
            &move |_, _| (0..n).collect(),
        )
    }

    const FAR: Reach = Reach {
        ahead: f64::INFINITY,
        behind: 1.0,
    };

    #[test]
    fn matching_meshes_give_node_to_node_rows() {
        let (xa, sa) = line(0.0, 2.0, 1.0, 4, true);
        let (xb, sb) = line(0.0, 2.0, 1.0, 4, false);
        let rows = pair_up(&xa, &sa, &xb, &sb, FAR);
        assert_eq!(rows.len(), 5);
        for (&j, r) in &rows {
            assert_eq!(r.coefs.len(), 1, "node {j}: {:?}", r.coefs);
            assert_eq!(r.coefs[0].0, j);
            assert!((r.coefs[0].1 - 1.0).abs() < 1e-14);
            let w = if j == 0 || j == 4 { 0.25 } else { 0.5 };
            assert!(
                (r.weight - w).abs() < 1e-14,
                "node {j}: weight {}",
                r.weight
            );
            assert!(r.gap.abs() < 1e-15);
        }
    }

    /// The three properties of the module documentation on non-matching meshes 10 / 7.
    #[test]
    fn non_matching_rows_reproduce_linear_fields_and_consistent_loads() {
        let (xa, sa) = line(0.0, 2.0, 1.0, 10, true);
        let (xb, sb) = line(0.0, 2.0, 1.0, 7, false);
        let rows = pair_up(&xa, &sa, &xb, &sb, FAR);
        assert_eq!(rows.len(), 11);
        let mut load_b = vec![0.0; xb.len()];
        for (&j, r) in &rows {
            let sum: f64 = r.coefs.iter().map(|c| c.1).sum();
            assert!((sum - 1.0).abs() < 1e-14, "node {j}: sum {sum}");
            // Linear field u = 3 + 2x: Σ C u(x_k) = u(x_j).
            let u = |p: [f64; 2]| 3.0 + 2.0 * p[0];
            let got: f64 = r.coefs.iter().map(|&(k, c)| c * u(xb[k])).sum();
            assert!(
                (got - u(xa[j])).abs() < 1e-13,
                "node {j}: {got} vs {}",
                u(xa[j])
            );
            let hat = if j == 0 || j == 10 { 0.1 } else { 0.2 };
            assert!((r.weight - hat).abs() < 1e-14);
            for &(k, c) in &r.coefs {
                load_b[k] += c * r.weight; // unit pressure: λ_j = D_j
            }
        }
        // B's consistent nodal load under a unit pressure: ∫ψ_k = half of each element.
        let h = 2.0 / 7.0;
        for (k, l) in load_b.iter().enumerate() {
            let want = if k == 0 || k == 7 { 0.5 * h } else { h };
            assert!((l - want).abs() < 1e-14, "B node {k}: {l} vs {want}");
        }
    }

    #[test]
    fn gap_is_measured_along_the_normal_and_partial_cover_keeps_loads_consistent() {
        // A: y = 0 on [0, 2], 8 elements; B: y = 0.01 on [0.3, 1.25], 5 elements (covers
        // A's nodes partly).
        let (xa, sa) = line(0.0, 2.0, 0.0, 8, true);
        let (xb, sb) = line(0.3, 1.25, 0.01, 5, false);
        let rows = pair_up(&xa, &sa, &xb, &sb, FAR);
        // Nodes at 0.25 .. 1.25 have a share of B; 0 and 1.5 .. 2 none.
        let with_rows: Vec<usize> = rows.keys().copied().collect();
        assert_eq!(with_rows, vec![1, 2, 3, 4, 5]);
        let mut load_b = vec![0.0; xb.len()];
        let mut total = 0.0;
        for r in rows.values() {
            assert!((r.gap - 0.01).abs() < 1e-15, "gap {}", r.gap);
            for &(k, c) in &r.coefs {
                load_b[k] += c * r.weight;
            }
            total += r.weight;
        }
        assert!((total - 0.95).abs() < 1e-14, "covered length {total}");
        let h = 0.95 / 5.0;
        for (k, l) in load_b.iter().enumerate() {
            let want = if k == 0 || k == 5 { 0.5 * h } else { h };
            assert!((l - want).abs() < 1e-14, "B node {k}: {l} vs {want}");
        }
    }

    #[test]
    fn far_side_and_wrong_facing_segments_are_left_out() {
        // B is a thin strip above A: its bottom (facing A) at y = 0.1, its top (facing up)
        // at y = 0.2; only the bottom pairs.
        let (xa, sa) = line(0.0, 1.0, 0.0, 2, true);
        let mut xb = vec![[0.0, 0.1], [1.0, 0.1], [1.0, 0.2], [0.0, 0.2]];
        xb.push([0.5, 0.1]);
        let sb = vec![[0, 4], [4, 1], [1, 2], [2, 3], [3, 0]];
        let rows = pair_up(&xa, &sa, &xb, &sb, FAR);
        assert_eq!(rows.len(), 3);
        for r in rows.values() {
            assert!((r.gap - 0.1).abs() < 1e-15);
            assert!(r.coefs.iter().all(|&(k, _)| [0, 1, 4].contains(&k)));
        }
        // Beyond the reach: nothing.
        let near = Reach {
            ahead: 0.05,
            behind: 0.05,
        };
        let rows = pair_up(&xa, &sa, &xb, &sb, near);
        assert!(rows.is_empty());
    }

    #[test]
    fn grid_finds_every_segment_within_reach() {
        // Segments on a jittered lattice; compare with brute force.
        let mut segs = Vec::new();
        for i in 0..30 {
            for j in 0..30 {
                let x = i as f64 * 0.37 + ((i * j) % 7) as f64 * 0.01;
                let y = j as f64 * 0.29;
                segs.push(([x, y], [x + 0.3 + (j % 3) as f64 * 0.5, y + 0.05]));
            }
        }
        let grid = SegmentGrid::new(&segs, 0.3);
        for (q, &(a, b)) in segs.iter().enumerate().step_by(17) {
            for r in [0.0, 0.05, 0.4] {
                let found = grid.near(a, b, r);
                for (i, &(c, d)) in segs.iter().enumerate() {
                    if segment_distance(a, b, c, d) <= r {
                        assert!(found.contains(&i), "query {q} r {r}: misses {i}");
                    }
                }
            }
        }
    }

    #[test]
    fn facing_pieces_overlap_but_corners_do_not() {
        // Two stacked blocks' faces: overlap; diagonal neighbours meeting at a corner: not.
        assert!(overlaps([0.0, 0.0], [1.0, 0.0], [1.5, 0.0], [0.5, 0.0]));
        assert!(!overlaps([0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [1.0, 0.0]));
        // A steep piece overlaps the line of a long one, not the other way round.
        assert!(!overlaps([0.0, 0.0], [1.0, 0.0], [0.5, 0.0], [0.5, 1.0]));
    }

    #[test]
    fn facing_pairs_of_two_stacked_squares() {
        // Square 0 [0,1]², square 1 [0.5,1.5] x [1,2] (counter-clockwise): only the top of
        // 0 and the bottom of 1 face each other; the corner (1, 1) where 0's right side
        // meets 1's bottom does not pair.
        let square = |body: usize, x0: f64, y0: f64| {
            let p = [
                [x0, y0],
                [x0 + 1.0, y0],
                [x0 + 1.0, y0 + 1.0],
                [x0, y0 + 1.0],
            ];
            (0..4)
                .map(|k| {
                    let (a, b) = (p[k], p[(k + 1) % 4]);
                    let l = norm(sub(b, a));
                    BodySegment {
                        body,
                        a,
                        b,
                        normal: [(b[1] - a[1]) / l, -(b[0] - a[0]) / l],
                    }
                })
                .collect::<Vec<_>>()
        };
        let mut segs = square(0, 0.0, 0.0);
        segs.extend(square(1, 0.5, 1.0));
        assert_eq!(facing_pairs(&segs, 1e-6), vec![(2, 4)]);
        // Apart by 0.01: found with search 0.02, not with 0.005.
        let mut segs = square(0, 0.0, 0.0);
        segs.extend(square(1, 0.5, 1.01));
        assert_eq!(facing_pairs(&segs, 0.02), vec![(2, 4)]);
        assert!(facing_pairs(&segs, 0.005).is_empty());
    }

    #[test]
    fn faces_that_touch_at_one_point_at_an_angle_do_not_pair() {
        let seg = |body: usize, a: [f64; 2], b: [f64; 2], n: [f64; 2]| {
            let l = norm(n);
            BodySegment {
                body,
                a,
                b,
                normal: [n[0] / l, n[1] / l],
            }
        };
        // Two stones' faces meeting at the vertex (0, 0), 58° apart, a third stone in the
        // wedge below: normals within 60° of opposite and overlapping in projection, so
        // only the point rule keeps them apart.
        let s = seg(0, [-1.0, -1.3], [0.0, 0.0], [1.3, -1.0]);
        let t = seg(1, [0.0, 0.0], [0.4, -1.0], [-1.0, -0.4]);
        assert!(dot(s.normal, t.normal) <= FACING_COS);
        assert!(overlaps(s.a, s.b, t.a, t.b));
        assert!(facing_pairs(&[s, t], 1e-6).is_empty());
        // A stone's corner on the foundation's top, its face rising at 45°.
        let top = seg(0, [1.0, 0.0], [-1.0, 0.0], [0.0, 1.0]);
        let face = seg(1, [0.0, 0.0], [-0.5, 0.5], [-1.0, -1.0]);
        assert!(facing_pairs(&[top, face], 1e-6).is_empty());
        // A curved body's segment touching a flat 5.7° apart pairs where the search reaches
        // the middle of their overlap (0.025 apart there: the rows measure the gap there),
        // not where it touches at the point only; the 45° pieces pair where the search
        // reaches over both whole (segments shorter than it).
        let curve = seg(1, [0.0, 0.0], [0.5, 0.05], [0.05, -0.5]);
        assert_eq!(facing_pairs(&[top, curve], 0.03), vec![(0, 1)]);
        assert!(facing_pairs(&[top, curve], 0.02).is_empty());
        assert!(facing_pairs(&[top, curve], 1e-6).is_empty());
        assert_eq!(facing_pairs(&[top, face], 1.0), vec![(0, 1)]);
    }

    #[test]
    fn segment_distance_cases() {
        let d = segment_distance([0.0, 0.0], [1.0, 0.0], [0.5, -1.0], [0.5, 1.0]);
        assert_eq!(d, 0.0);
        let d = segment_distance([0.0, 0.0], [1.0, 0.0], [2.0, 1.0], [3.0, 1.0]);
        assert!((d - 2f64.sqrt()).abs() < 1e-15);
        let d = segment_distance([0.0, 0.0], [1.0, 0.0], [0.2, 0.3], [0.8, 0.3]);
        assert!((d - 0.3).abs() < 1e-15);
    }
}
