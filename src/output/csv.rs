//! CSV tables: one row per interface pair (final state), one row per section point, one row
//! per joint (`thrust.csv`, final state) and the hubs of the bodies with more joints
//! (`thrust_hubs.csv`).

use std::fmt::Write;

use crate::input::model::{Body, Interface};
use crate::post::thrust::{Hub, Thrust};
use crate::solution::{InterfaceResult, PairStatus};

/// `x,y,s,status,normal_traction,tangential_traction,normal_opening,tangential_slip,gap`:
/// tractions on the first body (tension positive); the opening is the current normal
/// distance `gap + n·(u_B − u_A)`; the slip `s·(u_B − u_A)`.
///
/// Friction interfaces add `tangential_status` (`stick`, `slip`, `open`) and `slip`, the
/// accumulated slip path Σ|Δs| over the load steps while the pair is closed. Where the two
/// sides were meshed on their own (rows of A's nodes over B's segments), `side` (the body
/// whose node the row is at) and `segment` (the gmsh element of the other body that the node
/// faces; empty where none) follow.
pub fn interface_table(it: &Interface, r: &InterfaceResult, bodies: &[Body]) -> String {
    let friction = r.pairs.iter().any(|p| p.slipping.is_some());
    let mut o = String::from(
        "x,y,s,status,normal_traction,tangential_traction,normal_opening,tangential_slip,gap",
    );
    if friction {
        o.push_str(",tangential_status,slip");
    }
    if it.independent() {
        o.push_str(",side,segment");
    }
    o.push('\n');
    for (p, q) in it.pairs.iter().zip(&r.pairs) {
        let status = match q.status {
            PairStatus::Closed => "closed",
            PairStatus::Open => "open",
        };
        let opening = match q.status {
            PairStatus::Closed => 0.0,
            PairStatus::Open => p.gap + q.jump[1],
        };
        let slip = q.jump[0];
        let _ = write!(
            o,
            "{:e},{:e},{:e},{status},{:e},{:e},{:e},{:e},{:e}",
            p.x[0], p.x[1], p.s, q.traction[1], q.traction[0], opening, slip, p.gap
        );
        if friction {
            let _ = write!(
                o,
                ",{},{:e}",
                q.tangential_status().unwrap_or("none"),
                q.slip
            );
        }
        if it.independent() {
            let segment = p
                .segment
                .map(|e| bodies[it.body_b].elements[e].tag.to_string())
                .unwrap_or_default();
            let _ = write!(o, ",{},{segment}", bodies[it.body_a].name);
        }
        o.push('\n');
    }
    o
}

/// One sampled point: position, displacement, stress (xx, yy, xy); `None` outside the bodies.
pub(crate) type SectionRow = ([f64; 2], Option<([f64; 2], [f64; 3])>);

/// `x,y,ux,uy,sxx,syy,sxy`; points outside every body get `nan`.
pub(crate) fn section_table(rows: &[SectionRow]) -> String {
    let mut o = String::from("x,y,ux,uy,sxx,syy,sxy\n");
    for (x, v) in rows {
        match v {
            Some((u, s)) => {
                let _ = writeln!(
                    o,
                    "{:e},{:e},{:e},{:e},{:e},{:e},{:e}",
                    x[0], x[1], u[0], u[1], s[0], s[1], s[2]
                );
            }
            None => {
                let _ = writeln!(o, "{:e},{:e},nan,nan,nan,nan,nan", x[0], x[1]);
            }
        }
    }
    o
}

/// One joint of `thrust.csv`: its name, the names of its two bodies and its resultant.
pub type ThrustRow<'a> = (&'a str, &'a str, &'a str, &'a Thrust);

/// `thrust.csv`: per joint `joint,body_a,body_b,N,T,x,y,s,e,e_over_half_length,inside,
/// in_closed_part` (post/thrust.rs), the units of the scene in brackets (`force` and
/// `length` where it gives none); N compression positive. A fully open joint has N = 0 and
/// empty fields from `x` on (it has no point of application).
pub fn thrust_table(rows: &[ThrustRow], force: &str, length: &str) -> String {
    let f = if force.is_empty() { "force" } else { force };
    let l = if length.is_empty() { "length" } else { length };
    let mut o = format!(
        "joint,body_a,body_b,N [{f}],T [{f}],x [{l}],y [{l}],s [{l}],e [{l}],\
         e_over_half_length,inside,in_closed_part\n"
    );
    for (name, a, b, t) in rows {
        let _ = write!(
            o,
            "{},{},{},{:e},{:e}",
            quoted(name),
            quoted(a),
            quoted(b),
            t.normal + 0.0,
            t.tangential + 0.0
        );
        match &t.point {
            Some(p) => {
                let _ = writeln!(
                    o,
                    ",{:e},{:e},{:e},{:e},{:e},{},{}",
                    p.x[0] + 0.0,
                    p.x[1] + 0.0,
                    p.s + 0.0,
                    p.e + 0.0,
                    p.e_over_half_length + 0.0,
                    p.inside,
                    p.in_closed_part
                );
            }
            None => o.push_str(",,,,,,,\n"),
        }
    }
    o
}

/// `thrust_hubs.csv`: per body with a hub (post/thrust.rs `hubs`, final state), in body order,
/// `body,x,y,R_x,R_y,group,joints`: the body's name, its hub, the resultant on the body of
/// its group of joints (`below`: its bed joints below, along its body force; `above`: those
/// above, where none is below) and how many loaded joints the hub joins; the scene's units in
/// brackets as in `thrust.csv`. Only the header where no body has a hub.
pub fn hub_table(rows: &[(&str, &Hub)], force: &str, length: &str) -> String {
    let f = if force.is_empty() { "force" } else { force };
    let l = if length.is_empty() { "length" } else { length };
    let mut o = format!("body,x [{l}],y [{l}],R_x [{f}],R_y [{f}],group,joints\n");
    for (name, h) in rows {
        let _ = writeln!(
            o,
            "{},{:e},{:e},{:e},{:e},{},{}",
            quoted(name),
            h.x[0] + 0.0,
            h.x[1] + 0.0,
            h.resultant[0] + 0.0,
            h.resultant[1] + 0.0,
            if h.below { "below" } else { "above" },
            h.joints.len()
        );
    }
    o
}

/// A CSV field, quoted where it holds a comma, a quote or a line break.
fn quoted(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}
