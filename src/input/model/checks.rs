//! Checks on the built model: prescribed values are finite at every node, and every group of
//! bodies linked by interfaces is held against rigid motion.

use std::collections::BTreeMap;
use std::path::Path;

use crate::error::{Error, Result};
use crate::input::scene::{Condition, Frame};

use super::{fmt_num, fmt_point, sub, Body, DofClass, Interface, Part, Role};

/// Prescribed values must be finite at every node of their part.
pub(super) fn check_values(bodies: &[Body], parts: &[Part], sfile: &Path, t: f64) -> Result<()> {
    for body in bodies {
        for e in &body.elements {
            let Role::Boundary(pi) = e.role else { continue };
            let spec = &parts[pi].spec;
            for (c, cond) in spec.components.iter().enumerate() {
                let (Condition::Displacement(v) | Condition::Traction(v)) = cond;
                if v.as_const().is_some() {
                    continue;
                }
                for n in e.nodes {
                    let x = body.nodes[n];
                    let val = v.eval(x, t);
                    if !val.is_finite() {
                        let comp = match (spec.frame, c, cond.is_displacement()) {
                            (Frame::Global, 0, true) => "ux",
                            (Frame::Global, _, true) => "uy",
                            (Frame::Local, 0, true) => "ut",
                            (Frame::Local, _, true) => "un",
                            (Frame::Global, 0, false) => "tx",
                            (Frame::Global, _, false) => "ty",
                            (Frame::Local, 0, false) => "tt",
                            (Frame::Local, _, false) => "tn",
                        };
                        return Err(Error::input(
                            sfile,
                            format!(
                                "`boundary.{}.{comp}` = {v} is {val} at {} (body \"{}\", element \
                                 {}, t = {}): the expression must be defined on the whole curve \
                                 at every step",
                                spec.name,
                                fmt_point(x),
                                body.name,
                                e.tag,
                                fmt_num(t)
                            ),
                        ));
                    }
                }
            }
        }
    }
    Ok(())
}

/// Every group of bodies linked by interfaces must be held against all rigid motions by its
/// displacement conditions.
pub(super) fn check_held(
    bodies: &[Body],
    interfaces: &[Interface],
    sfile: &Path,
    scale: f64,
) -> Result<()> {
    // Connected components through interfaces (union–find).
    let mut parent: Vec<usize> = (0..bodies.len()).collect();
    fn find(p: &mut [usize], i: usize) -> usize {
        let mut r = i;
        while p[r] != r {
            r = p[r];
        }
        p[i] = r;
        r
    }
    for it in interfaces {
        let (ra, rb) = (find(&mut parent, it.body_a), find(&mut parent, it.body_b));
        parent[ra] = rb;
    }
    let mut groups: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for b in 0..bodies.len() {
        let r = find(&mut parent, b);
        groups.entry(r).or_default().push(b);
    }
    for members in groups.values() {
        // Rows [d_x, d_y, d · (−(y − yc), x − xc) / scale] of every known direction, with
        // x − xc taken as (x − o) − (xc − o), o the first node: exact far from the origin.
        let (o, centre) = {
            let pts: Vec<[f64; 2]> = members
                .iter()
                .flat_map(|&b| bodies[b].nodes.iter().copied())
                .collect();
            let o = pts.first().copied().unwrap_or([0.0; 2]);
            let n = pts.len().max(1) as f64;
            (
                o,
                [
                    pts.iter().map(|p| p[0] - o[0]).sum::<f64>() / n,
                    pts.iter().map(|p| p[1] - o[1]).sum::<f64>() / n,
                ],
            )
        };
        let mut basis: Vec<[f64; 3]> = Vec::new();
        'outer: for &b in members {
            let body = &bodies[b];
            for (n, d) in body.dofs.iter().enumerate() {
                for k in 0..2 {
                    if d.class[k] != DofClass::Known {
                        continue;
                    }
                    let dir = d.frame[k];
                    let r = sub(sub(body.nodes[n], o), centre);
                    let mut row = [dir[0], dir[1], (-r[1] * dir[0] + r[0] * dir[1]) / scale];
                    for q in &basis {
                        let p = row[0] * q[0] + row[1] * q[1] + row[2] * q[2];
                        for i in 0..3 {
                            row[i] -= p * q[i];
                        }
                    }
                    let len = (row[0] * row[0] + row[1] * row[1] + row[2] * row[2]).sqrt();
                    if len > 1e-6 {
                        basis.push([row[0] / len, row[1] / len, row[2] / len]);
                        if basis.len() == 3 {
                            break 'outer;
                        }
                    }
                }
            }
        }
        if basis.len() == 3 {
            continue;
        }
        let names: Vec<String> = members
            .iter()
            .map(|&b| format!("\"{}\"", bodies[b].name))
            .collect();
        let one = members.len() == 1;
        let who = if one {
            format!("body {} is", names[0])
        } else if names.len() <= 6 {
            format!("bodies {} (joined by interfaces) are", names.join(", "))
        } else {
            format!(
                "bodies {} and {} more (joined by interfaces) are",
                names[..5].join(", "),
                names.len() - 5
            )
        };
        let free = free_mode(&basis);
        let (it, its) = if one {
            ("it has", "its")
        } else {
            ("they have", "their")
        };
        let what = if basis.is_empty() {
            format!("{it} no displacement condition")
        } else {
            format!("{its} displacement conditions leave {free} free")
        };
        let no_iface = members.len() == 1
            && !interfaces
                .iter()
                .any(|i| i.body_a == members[0] || i.body_b == members[0]);
        let extra = if no_iface { " and no interface" } else { "" };
        return Err(Error::input(
            sfile,
            format!(
                "{who} not held: {what}{extra}; prescribe displacements on a boundary \
                 (e.g. [boundary.NAME] ux = 0, uy = 0) or join {} to a held body with an \
                 interface",
                if one { "it" } else { "them" }
            ),
        ));
    }
    Ok(())
}

/// Describes a rigid mode orthogonal to the given rows (fewer than 3 orthonormal rows).
fn free_mode(basis: &[[f64; 3]]) -> String {
    let candidates = [
        ([1.0, 0.0, 0.0], "a translation along x"),
        ([0.0, 1.0, 0.0], "a translation along y"),
        ([0.0, 0.0, 1.0], "a rotation"),
    ];
    // The candidate with the largest component outside the span of the basis.
    let mut best = ("a rigid motion", 0.0);
    for (v, name) in candidates {
        let mut r = v;
        for q in basis {
            let p = r[0] * q[0] + r[1] * q[1] + r[2] * q[2];
            for i in 0..3 {
                r[i] -= p * q[i];
            }
        }
        let len = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
        if len > best.1 + 1e-9 {
            best = (name, len);
        }
    }
    best.0.to_string()
}
