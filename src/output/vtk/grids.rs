//! The grids of the VTK files, each from the run record alone: the boundary lines, the
//! interior field, the mechanism, the thrust line and the contact rows of a state.

use super::xml::{array, DataArray, Grid, Values, VTK_LINE, VTK_TRIANGLE, VTK_VERTEX};
use crate::output::record::{InterfaceRecord, RunRecord};
use crate::post::{out_of_plane_stress, principal_stresses, von_mises};
use crate::solution::PairStatus;

fn vec3(v: &[[f64; 2]]) -> Vec<f64> {
    v.iter().flat_map(|a| [a[0], a[1], 0.0]).collect()
}

fn unit(v: [f64; 2]) -> [f64; 2] {
    let n = v[0].hypot(v[1]);
    if n > 0.0 {
        [v[0] / n, v[1] / n]
    } else {
        v
    }
}

/// The boundary lines of every body in state `k`.
pub(super) fn boundary_grid(rec: &RunRecord, k: usize) -> Grid {
    let st = &rec.states[k];
    let (mut pts, mut disp, mut trac, mut normal) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut status, mut tn, mut opening, mut body) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let friction = st
        .interfaces
        .iter()
        .any(|r| r.pairs.iter().any(|p| p.slipping.is_some()));
    let (mut tstatus, mut slip) = (Vec::new(), Vec::new());
    let mut conn = Vec::new();
    let mut offset = 0usize;
    for (bi, (b, f)) in rec.bodies.iter().zip(st.fields.iter()).enumerate() {
        let n = b.nodes.len();
        // Per node: sums of end tractions, of element normals, of t·n, and the count.
        let mut t_sum = vec![[0.0; 2]; n];
        let mut n_sum = vec![[0.0; 2]; n];
        let mut tn_sum = vec![0.0; n];
        let mut count = vec![0usize; n];
        for (e, nodes) in b.elements.iter().enumerate() {
            let (p, q) = (b.nodes[nodes[0]], b.nodes[nodes[1]]);
            let tau = unit([q[0] - p[0], q[1] - p[1]]);
            let ne = [tau[1], -tau[0]];
            for (&i, t) in nodes.iter().zip(f.t[e]) {
                t_sum[i][0] += t[0];
                t_sum[i][1] += t[1];
                n_sum[i][0] += ne[0];
                n_sum[i][1] += ne[1];
                tn_sum[i] += t[0] * ne[0] + t[1] * ne[1];
                count[i] += 1;
            }
            conn.push((offset + nodes[0]) as u64);
            conn.push((offset + nodes[1]) as u64);
        }
        let mut st_code = vec![-1i32; n];
        let mut node_tn: Vec<f64> = (0..n).map(|i| tn_sum[i] / count[i].max(1) as f64).collect();
        let mut node_open = vec![0.0; n];
        let mut node_ts = vec![-1i32; n];
        let mut node_slip = vec![0.0; n];
        for (it, r) in rec.interfaces.iter().zip(st.interfaces.iter()) {
            let side: Vec<(usize, usize)> = if it.body_a == bi {
                it.node_a.iter().copied().enumerate().collect()
            } else if it.body_b == bi {
                b_side_pairs(it)
            } else {
                continue;
            };
            for (j, node) in side {
                st_code[node] = match r.pairs[j].status {
                    PairStatus::Closed => 1,
                    PairStatus::Open => 0,
                };
                node_tn[node] = r.pairs[j].traction[1];
                node_open[node] = it.opening(r, j);
                let p = &r.pairs[j];
                if p.slipping.is_some() {
                    node_ts[node] = match p.tangential_status() {
                        Some("stick") => 1,
                        Some("slip") => 2,
                        _ => 0,
                    };
                    node_slip[node] = p.slip;
                }
            }
        }
        pts.extend(vec3(&b.nodes));
        disp.extend(vec3(&f.u));
        for i in 0..n {
            let c = count[i].max(1) as f64;
            trac.extend([t_sum[i][0] / c, t_sum[i][1] / c, 0.0]);
            let nn = unit(n_sum[i]);
            normal.extend([nn[0], nn[1], 0.0]);
        }
        status.extend(st_code);
        tn.extend(node_tn);
        opening.extend(node_open);
        tstatus.extend(node_ts);
        slip.extend(node_slip);
        body.extend(std::iter::repeat_n(bi as i32, n));
        offset += n;
    }
    let mut point_data = vec![
        array("displacement", 3, Values::F64(disp)),
        array("traction", 3, Values::F64(trac)),
        array("normal", 3, Values::F64(normal)),
        array("contact_status", 1, Values::I32(status)),
        array("normal_traction", 1, Values::F64(tn)),
        array("normal_opening", 1, Values::F64(opening)),
        array("body", 1, Values::I32(body)),
    ];
    if friction {
        point_data.push(array("tangential_status", 1, Values::I32(tstatus)));
        point_data.push(array("slip", 1, Values::F64(slip)));
    }
    Grid {
        points: pts,
        cell_types: vec![VTK_LINE; conn.len() / 2],
        connectivity: conn,
        point_data,
        active: ["contact_status", "displacement", ""],
    }
}

/// The boundary lines of every body with the rigid velocity of the mechanism at their
/// nodes (`mechanism_velocity`: zero on the bodies at rest) and `body`.
pub(super) fn mechanism_grid(rec: &RunRecord) -> Grid {
    let (mut pts, mut velocity, mut body, mut conn) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut motion = vec![None; rec.bodies.len()];
    for m in &rec.mechanism {
        if let Some(slot) = motion.get_mut(m.body) {
            *slot = Some(m);
        }
    }
    let mut offset = 0u64;
    for (bi, (b, motion)) in rec.bodies.iter().zip(motion).enumerate() {
        pts.extend(vec3(&b.nodes));
        for &x in &b.nodes {
            let v = motion.map_or([0.0; 2], |m| m.velocity(x));
            velocity.extend([v[0], v[1], 0.0]);
        }
        body.extend(std::iter::repeat_n(bi as i32, b.nodes.len()));
        conn.extend(
            b.elements
                .iter()
                .flat_map(|e| [offset + e[0] as u64, offset + e[1] as u64]),
        );
        offset += b.nodes.len() as u64;
    }
    Grid {
        points: pts,
        cell_types: vec![VTK_LINE; conn.len() / 2],
        connectivity: conn,
        point_data: vec![
            array("mechanism_velocity", 3, Values::F64(velocity)),
            array("body", 1, Values::I32(body)),
        ],
        active: ["body", "mechanism_velocity", ""],
    }
}

/// The triangles of every body in state `k`, with the interior values at their nodes.
pub(super) fn field_grid(rec: &RunRecord, k: usize) -> Grid {
    let st = &rec.states[k];
    let (mut pts, mut disp, mut stress, mut vm) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut principal, mut direction, mut body) = (Vec::new(), Vec::new(), Vec::new());
    let (mut sxx, mut syy, mut szz, mut sxy) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut conn = Vec::new();
    let mut offset = 0usize;
    for (bi, (b, f)) in rec.bodies.iter().zip(&st.interior).enumerate() {
        let local: std::collections::HashMap<usize, usize> = f
            .mesh_nodes
            .iter()
            .enumerate()
            .map(|(i, &m)| (m, i))
            .collect();
        for t in &b.triangles {
            for m in t {
                // validate() guarantees every triangle node has a value.
                conn.push((offset + local.get(m).copied().unwrap_or(0)) as u64);
            }
        }
        for (i, &m) in f.mesh_nodes.iter().enumerate() {
            let x = rec.mesh.nodes[m];
            pts.extend([x[0], x[1], 0.0]);
            disp.extend([f.u[i][0], f.u[i][1], 0.0]);
            let [xx, yy, xy] = f.sigma[i];
            let s = [[xx, xy], [xy, yy]];
            let zz = out_of_plane_stress(&s, rec.plane, b.poisson);
            stress.extend([xx, yy, zz, xy, 0.0, 0.0]);
            sxx.push(xx);
            syy.push(yy);
            szz.push(zz);
            sxy.push(xy);
            vm.push(von_mises(&s, zz));
            let (p, angle) = principal_stresses(&s);
            principal.extend([p[0], p[1], zz]);
            direction.extend([angle.cos(), angle.sin(), 0.0]);
            body.push(bi as i32);
        }
        offset += f.mesh_nodes.len();
    }
    Grid {
        points: pts,
        cell_types: vec![VTK_TRIANGLE; conn.len() / 3],
        connectivity: conn,
        point_data: vec![
            array("displacement", 3, Values::F64(disp)),
            DataArray {
                name: "stress",
                components: 6,
                component_names: &["XX", "YY", "ZZ", "XY", "YZ", "XZ"],
                values: Values::F64(stress),
            },
            array("sxx", 1, Values::F64(sxx)),
            array("syy", 1, Values::F64(syy)),
            array("szz", 1, Values::F64(szz)),
            array("sxy", 1, Values::F64(sxy)),
            array("von_mises", 1, Values::F64(vm)),
            DataArray {
                name: "principal_stress",
                components: 3,
                component_names: &["1", "2", "zz"],
                values: Values::F64(principal),
            },
            array("principal_direction", 3, Values::F64(direction)),
            array("body", 1, Values::I32(body)),
        ],
        active: ["von_mises", "displacement", "stress"],
    }
}

/// The thrust line of state `k` (post/thrust.rs): a point per joint that carries a normal
/// force, at its point of application, a vertex each, a line through every body between
/// its two joints, and for a body with more joints a point at its hub and a line from each
/// of its joints' points to it (docs/thrust.md); point data `N`, `T`, `e`,
/// `e_over_half_length`, `inside` and `in_closed_part` (1 yes, 0 no), `joint` (the
/// interface's index in the run) and `displacement` (the first body's, weighted as the point
/// is). At a hub `joint` is −1, `N`, `T`, `e`, `e_over_half_length` NaN, `inside` and
/// `in_closed_part` −1, `displacement` the mean of its joints' points'. Also the joints'
/// names, one a line, for the field data `joint_names`.
pub(super) fn thrust_grid(rec: &RunRecord, k: usize) -> (Grid, String) {
    use crate::post::thrust::{down, hubs, segments, thrust};
    let st = &rec.states[k];
    let mut g = ThrustColumns::default();
    let mut point_of = vec![None; rec.interfaces.len()];
    let mut all = Vec::with_capacity(rec.interfaces.len());
    for (j, (it, r)) in rec.interfaces.iter().zip(st.interfaces.iter()).enumerate() {
        let th = thrust(&it.joint(), r, rec.thickness);
        if let Some(p) = th.point {
            let u: Vec<[f64; 2]> = it
                .node_a
                .iter()
                .map(|&a| st.fields[it.body_a].u[a])
                .collect();
            let ua = th.at_point(&u).unwrap_or_default();
            point_of[j] = Some(g.joint.len() as u64);
            g.push(
                p.x,
                ua,
                j as i32,
                [th.normal, th.tangential, p.e, p.e_over_half_length],
            );
            g.inside.push(i32::from(p.inside));
            g.closed.push(i32::from(p.in_closed_part));
        }
        all.push(th);
    }
    let mut conn: Vec<u64> = (0..g.joint.len() as u64).collect();
    let mut cell_types = vec![VTK_VERTEX; g.joint.len()];
    let bodies: Vec<(usize, usize)> = rec
        .interfaces
        .iter()
        .map(|i| (i.body_a, i.body_b))
        .collect();
    let has_point: Vec<bool> = point_of.iter().map(Option::is_some).collect();
    for [a, b] in segments(&bodies, &has_point, rec.bodies.len()) {
        if let (Some(pa), Some(pb)) = (point_of[a], point_of[b]) {
            conn.extend([pa, pb]);
            cell_types.push(VTK_LINE);
        }
    }
    let down = down(&st.body_forces(&rec.bodies));
    for h in hubs(&bodies, &all, &down) {
        let ends: Vec<u64> = h.joints.iter().filter_map(|&j| point_of[j]).collect();
        let mut u = [0.0; 2];
        for &e in &ends {
            let at = 3 * e as usize;
            u = [u[0] + g.disp[at], u[1] + g.disp[at + 1]];
        }
        let m = ends.len().max(1) as f64;
        let hub = g.joint.len() as u64;
        g.push(h.x, [u[0] / m, u[1] / m], -1, [f64::NAN; 4]);
        g.inside.push(-1);
        g.closed.push(-1);
        conn.push(hub);
        cell_types.push(VTK_VERTEX);
        for e in ends {
            conn.extend([e, hub]);
            cell_types.push(VTK_LINE);
        }
    }
    let names: Vec<&str> = rec.interfaces.iter().map(|i| i.name.as_str()).collect();
    let grid = Grid {
        points: g.pts,
        connectivity: conn,
        cell_types,
        point_data: vec![
            array("N", 1, Values::F64(g.n)),
            array("T", 1, Values::F64(g.t)),
            array("e", 1, Values::F64(g.e)),
            array("e_over_half_length", 1, Values::F64(g.ratio)),
            array("inside", 1, Values::I32(g.inside)),
            array("in_closed_part", 1, Values::I32(g.closed)),
            array("joint", 1, Values::I32(g.joint)),
            array("displacement", 3, Values::F64(g.disp)),
        ],
        active: ["N", "displacement", ""],
    };
    (grid, names.join("\n"))
}

/// The contact rows of state `k` as points (one vertex per pair, at the pair's point on the
/// first body): `interface` and `pair` (indices; the file's field data `interface_names`
/// names the interfaces), `contact_status` (1 closed, 0 open), `tangential_status` (1 stick,
/// 2 slip, 0 open, −1 not a friction pair), `gap` (the initial normal gap),
/// `normal_opening` (gap + normal jump where open, 0 where closed), `normal_traction`
/// (tension positive) and `tangential_traction` on the first body, `normal_force` and
/// `tangential_force` (the tractions times the pair's tributary length and the thickness),
/// `slip` (the accumulated slip path), `displacement` (the first body's, for Warp By Vector).
pub(super) fn contact_grid(rec: &RunRecord, k: usize) -> Grid {
    let st = &rec.states[k];
    let mut c = ContactColumns::default();
    for (i, (it, r)) in rec.interfaces.iter().zip(st.interfaces.iter()).enumerate() {
        let w = it.weights();
        for (j, p) in r.pairs.iter().enumerate() {
            let x = it.x[j];
            let u = st.fields[it.body_a].u[it.node_a[j]];
            let w = w.get(j).copied().unwrap_or(0.0) * rec.thickness;
            c.pts.extend([x[0], x[1], 0.0]);
            c.disp.extend([u[0], u[1], 0.0]);
            c.interface.push(i as i32);
            c.pair.push(j as i32);
            c.status.push(match p.status {
                PairStatus::Closed => 1,
                PairStatus::Open => 0,
            });
            c.tangential.push(match p.tangential_status() {
                Some("stick") => 1,
                Some("slip") => 2,
                Some(_) => 0,
                None => -1,
            });
            c.gap.push(it.gap[j]);
            c.opening.push(it.opening(r, j));
            c.tn.push(p.traction[1]);
            c.tt.push(p.traction[0]);
            c.fn_.push(p.traction[1] * w);
            c.ft.push(p.traction[0] * w);
            c.slip.push(p.slip);
        }
    }
    let n = c.status.len();
    Grid {
        points: c.pts,
        connectivity: (0..n as u64).collect(),
        cell_types: vec![VTK_VERTEX; n],
        point_data: vec![
            array("interface", 1, Values::I32(c.interface)),
            array("pair", 1, Values::I32(c.pair)),
            array("contact_status", 1, Values::I32(c.status)),
            array("tangential_status", 1, Values::I32(c.tangential)),
            array("gap", 1, Values::F64(c.gap)),
            array("normal_opening", 1, Values::F64(c.opening)),
            array("normal_traction", 1, Values::F64(c.tn)),
            array("tangential_traction", 1, Values::F64(c.tt)),
            array("normal_force", 1, Values::F64(c.fn_)),
            array("tangential_force", 1, Values::F64(c.ft)),
            array("slip", 1, Values::F64(c.slip)),
            array("displacement", 3, Values::F64(c.disp)),
        ],
        active: ["contact_status", "displacement", ""],
    }
}

/// The point arrays of the contact block.
#[derive(Default)]
struct ContactColumns {
    pts: Vec<f64>,
    disp: Vec<f64>,
    interface: Vec<i32>,
    pair: Vec<i32>,
    status: Vec<i32>,
    tangential: Vec<i32>,
    gap: Vec<f64>,
    opening: Vec<f64>,
    tn: Vec<f64>,
    tt: Vec<f64>,
    fn_: Vec<f64>,
    ft: Vec<f64>,
    slip: Vec<f64>,
}

/// The point arrays of the thrust block, filled point by point.
#[derive(Default)]
struct ThrustColumns {
    pts: Vec<f64>,
    disp: Vec<f64>,
    joint: Vec<i32>,
    n: Vec<f64>,
    t: Vec<f64>,
    e: Vec<f64>,
    ratio: Vec<f64>,
    inside: Vec<i32>,
    closed: Vec<i32>,
}

impl ThrustColumns {
    /// A point at `x` with displacement `u`, joint index and `[N, T, e, e/(L/2)]`.
    fn push(&mut self, x: [f64; 2], u: [f64; 2], joint: i32, v: [f64; 4]) {
        self.pts.extend([x[0], x[1], 0.0]);
        self.disp.extend([u[0], u[1], 0.0]);
        self.joint.push(joint);
        self.n.push(v[0]);
        self.t.push(v[1]);
        self.e.push(v[2]);
        self.ratio.push(v[3]);
    }
}

/// The pair that each of body B's interface nodes shows (pair index, node): its pair's node
/// where nodes pair up; where the sides were meshed on their own, every interface node of B
/// shows the pair whose row gives it the largest coefficient.
fn b_side_pairs(it: &InterfaceRecord) -> Vec<(usize, usize)> {
    let Some(pr) = &it.pairing else {
        return it.node_b.iter().copied().enumerate().collect();
    };
    let mut best: std::collections::BTreeMap<usize, (f64, usize)> = Default::default();
    for j in 0..pr.offset.len().saturating_sub(1) {
        for m in pr.offset[j]..pr.offset[j + 1] {
            let e = best.entry(pr.node[m]).or_insert((f64::NEG_INFINITY, j));
            if pr.coef[m] > e.0 {
                *e = (pr.coef[m], j);
            }
        }
    }
    best.into_iter().map(|(node, (_, j))| (j, node)).collect()
}
