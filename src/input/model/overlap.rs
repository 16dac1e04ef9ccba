//! Overlap checks: elements of different bodies must not cross, and no body may lie inside
//! another.

use std::collections::HashMap;
use std::path::Path;

use crate::error::{Error, Result};

use super::{cross, fmt_num, fmt_point, norm, sub, winding, Body, Interface, Role};
use crate::input::pairing::segment_distance;

/// Elements of different bodies (or non-neighbouring elements of one body) must not cross,
/// and no body may lie inside another. The two sides of a declared interface whose sides
/// were meshed on their own may cross (an interference fit, drawn).
pub(super) fn check_overlaps(
    bodies: &[Body],
    declared: &[Interface],
    mfile: &Path,
    scale: f64,
) -> Result<()> {
    let segs = segments(bodies);
    let grid = segment_grid(&segs, scale);
    let interference = |s: &Seg, t: &Seg| -> bool {
        let (rs, rt) = (
            bodies[s.body].elements[s.elem].role,
            bodies[t.body].elements[t.elem].role,
        );
        match (rs, rt) {
            (Role::Interface(k), Role::Interface(l)) => {
                k == l && s.body != t.body && declared.get(k).is_some_and(|i| i.independent())
            }
            _ => false,
        }
    };
    if let Some((i, j)) = first_crossing(&segs, &grid, &interference) {
        {
            let (s, t) = (&segs[i], &segs[j]);
            {
                let (b1, b2) = (&bodies[s.body], &bodies[t.body]);
                let (e1, e2) = (&b1.elements[s.elem], &b2.elements[t.elem]);
                let what = if s.body == t.body {
                    format!("the boundary of body \"{}\" crosses itself", b1.name)
                } else {
                    format!(
                        "bodies \"{}\" and \"{}\" overlap by {}",
                        b1.name,
                        b2.name,
                        fmt_num(overlap_depth(b1, b2).max(overlap_depth(b2, b1)))
                    )
                };
                return Err(Error::input(
                    mfile,
                    format!(
                        "{what}: element {} (curve {}) crosses element {} (curve {}); fix the \
                         geometry so that bodies meet only along shared curves",
                        e1.tag, e1.curve, e2.tag, e2.curve
                    ),
                ));
            }
        }
    }
    for body in bodies {
        check_crossing_at_coincident_nodes(body, mfile, scale)?;
    }
    check_nesting(bodies, mfile)
}

/// A boundary element as a segment, for the crossing search.
struct Seg {
    body: usize,
    elem: usize,
    a: [f64; 2],
    b: [f64; 2],
    /// The mesh nodes of its ends.
    ma: usize,
    mb: usize,
    xmin: f64,
}

/// Every boundary element of every body as a segment, sorted by smallest x (the sweep order).
fn segments(bodies: &[Body]) -> Vec<Seg> {
    let mut segs: Vec<Seg> = Vec::new();
    for (bi, body) in bodies.iter().enumerate() {
        for (ei, e) in body.elements.iter().enumerate() {
            let a = body.nodes[e.nodes[0]];
            let b = body.nodes[e.nodes[1]];
            segs.push(Seg {
                body: bi,
                elem: ei,
                a,
                b,
                ma: body.mesh_nodes[e.nodes[0]],
                mb: body.mesh_nodes[e.nodes[1]],
                xmin: a[0].min(b[0]),
            });
        }
    }
    segs.sort_by(|p, q| p.xmin.total_cmp(&q.xmin));
    segs
}

/// Candidate pairs from a uniform grid of cells about one mean element long (a sweep along x
/// alone is quadratic for a column of vertical elements): cell → the segments that reach it.
fn segment_grid(segs: &[Seg], scale: f64) -> HashMap<(i64, i64), Vec<usize>> {
    let n = segs.len();
    let mean = segs.iter().map(|g| norm(sub(g.b, g.a))).sum::<f64>() / n.max(1) as f64;
    let h = mean.max(1e-12 * scale).max(f64::MIN_POSITIVE);
    let origin = segs.iter().fold([f64::INFINITY; 2], |o, g| {
        [o[0].min(g.xmin), o[1].min(g.a[1].min(g.b[1]))]
    });
    let cell = |p: [f64; 2]| -> (i64, i64) {
        (
            ((p[0] - origin[0]) / h).floor() as i64,
            ((p[1] - origin[1]) / h).floor() as i64,
        )
    };
    let mut grid: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
    for (i, g) in segs.iter().enumerate() {
        let (c0, c1) = (cell(g.a), cell(g.b));
        let mut cells: Vec<(i64, i64)> = Vec::new();
        let (lo, hi) = (
            (c0.0.min(c1.0), c0.1.min(c1.1)),
            (c0.0.max(c1.0), c0.1.max(c1.1)),
        );
        if (hi.0 - lo.0 + 1) * (hi.1 - lo.1 + 1) <= 64 {
            for x in lo.0..=hi.0 {
                for y in lo.1..=hi.1 {
                    cells.push((x, y));
                }
            }
        } else {
            // A long element: the cells along it (every point of it lies within h/4 of a
            // sample, so in a sample's cell or a neighbour).
            let steps = (4.0 * norm(sub(g.b, g.a)) / h).ceil() as usize;
            for k in 0..=steps {
                let t = k as f64 / steps as f64;
                let c = cell([
                    g.a[0] + t * (g.b[0] - g.a[0]),
                    g.a[1] + t * (g.b[1] - g.a[1]),
                ]);
                for dx in -1..=1 {
                    for dy in -1..=1 {
                        cells.push((c.0 + dx, c.1 + dy));
                    }
                }
            }
            cells.sort_unstable();
            cells.dedup();
        }
        for c in cells {
            grid.entry(c).or_default().push(i);
        }
    }
    grid
}

/// The first pair of crossing segments in sweep order that share no mesh node, if any, but
/// those `allowed` to cross.
fn first_crossing(
    segs: &[Seg],
    grid: &HashMap<(i64, i64), Vec<usize>>,
    allowed: &dyn Fn(&Seg, &Seg) -> bool,
) -> Option<(usize, usize)> {
    let mut first: Option<(usize, usize)> = None;
    for members in grid.values() {
        for (k, &i) in members.iter().enumerate() {
            for &j in &members[k + 1..] {
                let (i, j) = (i.min(j), i.max(j));
                if first.is_some_and(|f| f <= (i, j)) {
                    continue;
                }
                let (s, t) = (&segs[i], &segs[j]);
                if [t.ma, t.mb].contains(&s.ma) || [t.ma, t.mb].contains(&s.mb) {
                    continue;
                }
                if segments_cross(s.a, s.b, t.a, t.b) && !allowed(s, t) {
                    first = Some((i, j));
                }
            }
        }
    }
    first
}

/// How deep the boundary nodes of body `a` lie inside body `b`: the largest distance from
/// such a node to b's boundary (0 when none lies inside).
pub(super) fn overlap_depth(a: &Body, b: &Body) -> f64 {
    a.nodes
        .iter()
        .filter(|&&x| b.winding_number(x) != 0)
        .map(|&x| {
            b.elements
                .iter()
                .map(|e| segment_distance(x, x, b.nodes[e.nodes[0]], b.nodes[e.nodes[1]]))
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max)
}

/// A body entirely inside another: probe a point just inside each body. Only the bodies
/// whose bounding box holds the probe are asked for their winding number (4 000 bricks:
/// 16 million winding numbers otherwise).
fn check_nesting(bodies: &[Body], mfile: &Path) -> Result<()> {
    let boxes: Vec<[f64; 4]> = bodies
        .iter()
        .map(|b| {
            b.nodes.iter().fold(
                [
                    f64::INFINITY,
                    f64::INFINITY,
                    f64::NEG_INFINITY,
                    f64::NEG_INFINITY,
                ],
                |a, p| {
                    [
                        a[0].min(p[0]),
                        a[1].min(p[1]),
                        a[2].max(p[0]),
                        a[3].max(p[1]),
                    ]
                },
            )
        })
        .collect();
    // Whether the box holds the point at `offset` from `p` (differences of nodes: exact).
    let holds = |b: &[f64; 4], p: [f64; 2], offset: [f64; 2]| {
        offset[0] >= b[0] - p[0]
            && offset[0] <= b[2] - p[0]
            && offset[1] >= b[1] - p[1]
            && offset[1] <= b[3] - p[1]
    };
    for (bi, body) in bodies.iter().enumerate() {
        let outer = match body.loops.iter().find(|l| !l.is_hole) {
            Some(l) => l,
            None => continue,
        };
        // The probe, relative to the element's start node p: far from the origin the probe
        // itself may not be representable (it would round onto the boundary), its offset
        // from p is, and so are the offsets of the other body's nodes.
        let e = &body.elements[outer.elements[0]];
        let p = body.nodes[e.nodes[0]];
        let chord = sub(body.nodes[e.nodes[1]], p);
        let offset = [
            0.5 * chord[0] - 1e-3 * e.length * e.normal[0],
            0.5 * chord[1] - 1e-3 * e.length * e.normal[1],
        ];
        for (oi, other) in bodies.iter().enumerate() {
            if oi == bi || !holds(&boxes[oi], p, offset) {
                continue;
            }
            let w = winding(
                offset,
                other.elements.iter().map(|e| {
                    (
                        sub(other.nodes[e.nodes[0]], p),
                        sub(other.nodes[e.nodes[1]], p),
                    )
                }),
            );
            if w != 0 {
                return Err(Error::input(
                    mfile,
                    format!(
                        "body \"{}\" lies inside body \"{}\" (they overlap by {}, the depth of \
                         its deepest node): bodies must not overlap; cut a hole in \"{}\" \
                         bounded by the same curves",
                        body.name,
                        other.name,
                        fmt_num(overlap_depth(body, other)),
                        other.name
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Two distinct nodes of one body at the same point where the boundary passes twice: a
/// bow tie crosses itself there (the two passages interleave around the point), which the
/// segment test cannot see since the segments only touch. Passages that touch without
/// crossing (the two faces of a slit) are left alone.
fn check_crossing_at_coincident_nodes(body: &Body, mfile: &Path, scale: f64) -> Result<()> {
    let eps = 1e-10 * scale;
    // Cells relative to the first node: far from the origin, `x / eps` would saturate the
    // integer and put every node in one cell.
    let o = body.nodes.first().copied().unwrap_or([0.0; 2]);
    let key = |p: [f64; 2]| {
        (
            ((p[0] - o[0]) / eps).round() as i64,
            ((p[1] - o[1]) / eps).round() as i64,
        )
    };
    let mut neighbours: Vec<Vec<usize>> = vec![Vec::new(); body.nodes.len()];
    for e in &body.elements {
        neighbours[e.nodes[0]].push(e.nodes[1]);
        neighbours[e.nodes[1]].push(e.nodes[0]);
    }
    let mut cells: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
    for (n, &p) in body.nodes.iter().enumerate() {
        if neighbours[n].len() == 2 {
            cells.entry(key(p)).or_default().push(n);
        }
    }
    let angle = |from: [f64; 2], to: [f64; 2]| (to[1] - from[1]).atan2(to[0] - from[0]);
    let tau = std::f64::consts::TAU;
    for (&(kx, ky), here) in &cells {
        for &n in here {
            let p = body.nodes[n];
            for dx in -1..=1 {
                for dy in -1..=1 {
                    let Some(others) = cells.get(&(kx + dx, ky + dy)) else {
                        continue;
                    };
                    for &m in others.iter().filter(|&&m| m > n) {
                        let q = body.nodes[m];
                        if (p[0] - q[0]).abs() > eps || (p[1] - q[1]).abs() > eps {
                            continue;
                        }
                        // Sector swept counter-clockwise from n's first ray to its second.
                        let a0 = angle(p, body.nodes[neighbours[n][0]]);
                        let span = (angle(p, body.nodes[neighbours[n][1]]) - a0).rem_euclid(tau);
                        let side = |to: usize| {
                            let d = (angle(p, body.nodes[to]) - a0).rem_euclid(tau);
                            (
                                d > 1e-9 && d < span - 1e-9,
                                d > span + 1e-9 && d < tau - 1e-9,
                            )
                        };
                        let (s1, s2) = (side(neighbours[m][0]), side(neighbours[m][1]));
                        let crosses = (s1.0 && s2.1) || (s1.1 && s2.0);
                        if crosses {
                            return Err(Error::input(
                                mfile,
                                format!(
                                    "the boundary of body \"{}\" crosses itself at {}, where two \
                                     of its nodes coincide: a body's boundary must be simple \
                                     loops; split the bow tie into two surfaces (or fix the \
                                     curves there)",
                                    body.name,
                                    fmt_point(p)
                                ),
                            ));
                        }
                    }
                }
            }
        }
    }
    Ok(())
}

/// Proper crossing of two segments (touching end points and collinear overlap excluded).
fn segments_cross(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let scale = norm(sub(b, a)) * norm(sub(d, c));
    let tol = 1e-10 * scale;
    let o1 = cross(sub(b, a), sub(c, a));
    let o2 = cross(sub(b, a), sub(d, a));
    let o3 = cross(sub(d, c), sub(a, c));
    let o4 = cross(sub(d, c), sub(b, c));
    ((o1 > tol && o2 < -tol) || (o1 < -tol && o2 > tol))
        && ((o3 > tol && o4 < -tol) || (o3 < -tol && o4 > tol))
}
