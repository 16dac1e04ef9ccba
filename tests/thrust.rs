//! The thrust line (`thrust.csv`, summary.json `thrust`, the VTK block `thrust`;
//! post/thrust.rs) against statics: a block on a base under its weight, a pressure on its top
//! and a lateral force there. The joint's resultant must balance the loads of the upper
//! block, N = W + P, T = Q, and its point of application lies at e = M / N from the joint's
//! mid-point (M the loads' moment about it), whether the joint is closed or partly open; a
//! fully open joint has no point. And the shipped arch stands: every joint compressed, every
//! point within its joint.

mod support;

use std::collections::BTreeMap;

use serde_json::Value;
use support::*;

/// The block on a base of geo/two_blocks.geo (upper [0,1] × [0.5,1] on lower
/// [0,1] × [0,0.5], joint at y = 0.5), elastic, the joint unilateral and sticking.
fn block_scene(top: &str) -> String {
    format!(
        r#"
mesh = "tb.msh"
plane = "strain"
units = {{ length = "m", force = "kN" }}
[body.lower]
young = 1000.0
poisson = 0.25
[body.upper]
young = 1000.0
poisson = 0.25
body_force = [0.0, -2.0]
[boundary.base]
ux = 0.0
uy = 0.0
[boundary.top]
{top}
[interface.joint]
model = "unilateral"
initial = "closed"
tangential = "stick"
[output]
directory = "out"
field = false
history = "final"
"#
    )
}

/// Runs the block with the top condition `top`; returns its run folder and summary.
fn run_block(name: &str, top: &str) -> (std::path::PathBuf, Value) {
    let dir = two_blocks_mesh(name);
    let scene = write(&dir, "block.toml", &block_scene(top));
    let out = dir.join("out");
    let summary = run(&scene, &out);
    (out, summary)
}

/// `sgbem run SCENE --out OUT`, which must succeed; returns the summary.
fn run(scene: &std::path::Path, out: &std::path::Path) -> Value {
    let s = |p: &std::path::Path| p.to_str().unwrap_or_default().to_string();
    let (code, _, err) = sgbem(&["run", &s(scene), "--out", &s(out), "--quiet"]);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(out.join("summary.json")).expect("summary.json");
    serde_json::from_str(&text).expect("JSON")
}

/// The rows of `thrust.csv` as (header, fields).
fn thrust_csv(out: &std::path::Path) -> (String, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(out.join("thrust.csv")).expect("thrust.csv");
    let mut lines = text.lines();
    let header = lines.next().unwrap_or_default().to_string();
    let rows = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    (header, rows)
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// Checks the joint of the block against statics for the top traction (Q, −P); returns its
/// summary figures.
fn check_statics(name: &str, q: f64, p: f64) -> Value {
    let (out, s) = run_block(name, &format!("tx = {q}\nty = {}", -p));
    assert_eq!(s["status"], "converged");
    let t = &s["thrust"]["joint"];
    // Weight 2 × 0.5; the loads' moment about the joint's centre (0.5, 0.5): Q at 0.5 above
    // it (the pressure and the weight act on the centre line).
    let (n, m) = (2.0 * 0.5 + p, q * 0.5);
    let f = |k: &str| t[k].as_f64().unwrap_or(f64::NAN);
    assert!(
        rel(f("normal_force"), n) < 1e-6,
        "N {} against {n}",
        f("normal_force")
    );
    // The force on the first body (lower) along the pairs' tangent (−n_y, n_x) = (−1, 0).
    assert!(
        rel(-f("tangential_force"), q) < 1e-6,
        "T {}",
        f("tangential_force")
    );
    let x = 0.5 + m / n;
    assert!(rel(f("x"), x) < 1e-6, "x {} against {x}", f("x"));
    assert!((f("y") - 0.5).abs() < 1e-12);
    assert!(
        rel(f("e").abs(), m / n) < 1e-6,
        "e {} against {}",
        f("e"),
        m / n
    );
    assert!(rel(f("e_over_half_length").abs(), m / n / 0.5) < 1e-6);
    assert_eq!(
        (&t["inside"], &t["in_closed_part"]),
        (&Value::Bool(true), &Value::Bool(true))
    );
    // The CSV holds the same numbers, with the units in its header.
    let (header, rows) = thrust_csv(&out);
    assert_eq!(
        header,
        "joint,body_a,body_b,N [kN],T [kN],x [m],y [m],s [m],e [m],e_over_half_length,inside,\
         in_closed_part"
    );
    assert_eq!(rows.len(), 1);
    assert_eq!(&rows[0][..3], ["joint", "lower", "upper"]);
    assert_eq!(rows[0][3].parse::<f64>().ok(), Some(f("normal_force")));
    assert_eq!(rows[0][5].parse::<f64>().ok(), Some(f("x")));
    assert_eq!(&rows[0][10..], ["true", "true"]);
    s
}

/// Closed joint (e = 0.05 within the middle third): the BEM tractions reproduce statics.
#[test]
fn closed_joint_reproduces_statics() {
    let s = check_statics("thrust-closed", 0.2, 1.0);
    assert_eq!(s["interfaces"]["joint"]["open_pairs"], 0);
}

/// Partly open joint (e = 0.3, 0.6 of the half length): still e = M / N, the point within
/// the closed part.
#[test]
fn partly_open_joint_keeps_e_equal_m_over_n() {
    let s = check_statics("thrust-open", 1.2, 1.0);
    let open = s["interfaces"]["joint"]["open_pairs"].as_u64().unwrap_or(0);
    assert!(
        open > 0,
        "the windward end should open: {}",
        s["interfaces"]["joint"]
    );
}

/// Fully open joint (the upper block lifted): N = 0, no point (null in the summary, empty
/// fields in the CSV, no point in the VTK block).
#[test]
fn fully_open_joint_has_no_point() {
    let (out, s) = run_block("thrust-lifted", "ux = 0.0\nuy = 0.01");
    let t = &s["thrust"]["joint"];
    assert_eq!(t["normal_force"].as_f64(), Some(0.0), "{t}");
    for k in [
        "x",
        "y",
        "s",
        "e",
        "e_over_half_length",
        "inside",
        "in_closed_part",
    ] {
        assert!(t[k].is_null(), "{k}: {t}");
    }
    let (_, rows) = thrust_csv(&out);
    assert!(rows[0][5..].iter().all(String::is_empty), "{:?}", rows[0]);
    let vtu = std::fs::read_to_string(out.join("vtk/thrust_0000.vtu")).expect("thrust_0000.vtu");
    assert!(
        vtu.contains("NumberOfPoints=\"0\" NumberOfCells=\"0\""),
        "{vtu}"
    );
}

/// The shipped arch (20 voussoirs, t/R = 0.12) stands: every joint compressed, its point
/// within the joint; the crown joint is a hinge (the point at its edge), the thrust line is
/// symmetric, and the VTK block joins the 21 points by 20 segments.
#[test]
fn arch_thrust_line_stays_in_the_ring() {
    let out = tmpdir("thrust-arch").join("out");
    let summary = run(&root().join("pipelines/arch.toml"), &out);
    let thrust = summary["thrust"].as_object().expect("thrust block");
    assert_eq!(thrust.len(), 21);
    for (name, t) in thrust {
        let n = t["normal_force"].as_f64().unwrap_or(f64::NAN);
        let r = t["e_over_half_length"].as_f64().unwrap_or(f64::NAN);
        assert!(n > 0.0, "{name}: N = {n}");
        assert!(r.abs() <= 1.0 + 1e-9 && t["inside"] == true, "{name}: {t}");
    }
    let crown = &thrust["joints[voussoir_10|voussoir_11]"];
    let r = crown["e_over_half_length"].as_f64().unwrap_or(0.0);
    assert!((r.abs() - 1.0).abs() < 1e-9, "crown: {crown}");
    // Mirror images: the springings, the haunches.
    for (a, b) in [
        ("voussoir_1|abutment_L", "voussoir_20|abutment_R"),
        ("voussoir_4|voussoir_5", "voussoir_16|voussoir_17"),
    ] {
        for key in ["normal_force", "e_over_half_length"] {
            let v = |k: &str| thrust[&format!("joints[{k}]")][key].as_f64().unwrap_or(0.0);
            assert!(rel(v(a), v(b)) < 1e-9, "{key}: {a} {} {b} {}", v(a), v(b));
        }
    }
    let vtm = std::fs::read_to_string(out.join("vtk/state_0000.vtm")).unwrap();
    assert!(
        vtm.contains("name=\"thrust\" file=\"thrust_0000.vtu\""),
        "{vtm}"
    );
    let vtu = std::fs::read_to_string(out.join("vtk/thrust_0000.vtu")).unwrap();
    assert!(vtu.contains("NumberOfPoints=\"21\" NumberOfCells=\"41\""));
    let marker = std::fs::read_to_string(out.join(".sgbem-run.json")).unwrap();
    assert!(marker.contains("\"thrust.csv\"") && marker.contains("\"vtk/thrust_0000.vtu\""));
}

/// A running-bond wall (geo/wall.geo: 3 courses of 2 bricks, 0.4 × 0.2 m, the middle
/// course a half, a whole and a half brick) on a clamped base under its weight, the joints
/// unilateral and sticking: `mesh` the .geo, `body_force` the weight's vector, `extra` more
/// tables.
fn bond_scene(mesh: &std::path::Path, body_force: &str, extra: &str) -> String {
    format!(
        r#"
plane = "strain"
units = {{ length = "m", force = "kN" }}
[mesh]
file = "{}"
courses = 3
bricks = 2
nj = 4
[defaults.body]
young = 5.0e6
poisson = 0.2
body_force = {body_force}
[defaults.interface]
model = "unilateral"
tangential = "stick"
[boundary.base]
ux = 0.0
uy = 0.0
[output]
directory = "out"
field = false
history = "final"
{extra}
"#,
        mesh.display()
    )
}

/// The bricks of the bond wall by name: [x0, x1, y0, y1] (numbered course by course, left
/// to right, as geo/wall.geo does).
fn bond_brick(name: &str) -> [f64; 4] {
    let k: usize = name.trim_start_matches("brick_").parse().unwrap_or(0);
    let xs: [&[f64]; 3] = [&[0.0, 0.4, 0.8], &[0.0, 0.2, 0.6, 0.8], &[0.0, 0.4, 0.8]];
    let (mut first, mut course) = (1, 0);
    while k >= first + xs[course].len() - 1 {
        first += xs[course].len() - 1;
        course += 1;
    }
    let i = k - first;
    let y = 0.2 * course as f64;
    [xs[course][i], xs[course][i + 1], y, y + 0.2]
}

/// The outward normal of brick `a` on its joint with brick `b`.
fn outward(a: [f64; 4], b: [f64; 4]) -> [f64; 2] {
    let near = |u: f64, v: f64| (u - v).abs() < 1e-9;
    if near(a[2], b[3]) {
        [0.0, -1.0]
    } else if near(a[3], b[2]) {
        [0.0, 1.0]
    } else if near(a[1], b[0]) {
        [1.0, 0.0]
    } else {
        [-1.0, 0.0]
    }
}

fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// The thrust block of a VTK file: points, cells (connectivity by cell) and `joint`.
fn thrust_block(vtu: &str) -> (Vec<[f64; 2]>, Vec<Vec<usize>>, Vec<i32>) {
    let arrays = binary_arrays(vtu, false);
    let get = |n: &str| &arrays.iter().find(|(k, _)| k == n).expect(n).1;
    let f64s: Vec<f64> = get("Points")
        .chunks(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap_or_default()))
        .collect();
    let points = f64s.chunks(3).map(|p| [p[0], p[1]]).collect();
    let u64s = |n: &str| -> Vec<usize> {
        get(n)
            .chunks(4)
            .map(|c| i32::from_le_bytes(c.try_into().unwrap_or_default()) as usize)
            .collect()
    };
    let (conn, offsets) = (u64s("connectivity"), u64s("offsets"));
    let mut cells = Vec::new();
    let mut at = 0;
    for o in offsets {
        cells.push(conn[at..o].to_vec());
        at = o;
    }
    let joint = get("joint")
        .chunks(4)
        .map(|c| i32::from_le_bytes(c.try_into().unwrap_or_default()))
        .collect();
    (points, cells, joint)
}

/// `thrust_hubs.csv` as body -> (x, y, R, group, joints).
#[allow(clippy::type_complexity)]
fn hub_csv(out: &std::path::Path) -> BTreeMap<String, ([f64; 2], [f64; 2], String, usize)> {
    let text = std::fs::read_to_string(out.join("thrust_hubs.csv")).expect("thrust_hubs.csv");
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("body,x [m],y [m],R_x [kN],R_y [kN],group,joints")
    );
    let num = |c: &str| c.parse::<f64>().expect("a number");
    lines
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            let joints = c[6].parse().expect("a count");
            let v = (
                [num(c[1]), num(c[2])],
                [num(c[3]), num(c[4])],
                c[5].to_string(),
                joints,
            );
            (c[0].to_string(), v)
        })
        .collect()
}

/// The hubs of the bond wall run into `out` (summary `s`), checked: each brick with more
/// than two loaded joints gets a hub (a point with `joint` −1) and a line from each of its
/// joints' points of application to it; the line ends are the joints' points (summary.json)
/// to 1e-12; `thrust_hubs.csv` has the same hubs, bit for bit; the hub lies on the line of
/// action of the resultant of the brick's bed joints below (above for the first course),
/// whose moment about it vanishes and which is the CSV's resultant, and the brick balances
/// about it: its joints' forces (N, T at their points) and its weight at its centroid, to
/// 1e-10 of the moments' scale. `back` takes the run's coordinates to the upright wall's
/// (where the weight points to −y), in which the checks are made. Returns each brick's hub
/// in the upright wall.
fn check_hubs(
    out: &std::path::Path,
    s: &Value,
    back: &dyn Fn([f64; 2]) -> [f64; 2],
) -> BTreeMap<String, [f64; 2]> {
    let (_, rows) = thrust_csv(out);
    let f = |t: &Value, k: &str| t[k].as_f64().unwrap_or(f64::NAN);
    // Per joint: bodies, point (upright), N, T (None without a point).
    let joints: Vec<_> = rows
        .iter()
        .map(|r| {
            let t = &s["thrust"][&r[0]];
            let p = t["x"].as_f64().map(|x| back([x, f(t, "y")]));
            (
                r[1].clone(),
                r[2].clone(),
                p,
                f(t, "normal_force"),
                f(t, "tangential_force"),
            )
        })
        .collect();
    let mut loaded: BTreeMap<String, Vec<usize>> = Default::default();
    for (k, j) in joints.iter().enumerate() {
        if j.2.is_some() {
            loaded.entry(j.0.clone()).or_default().push(k);
            loaded.entry(j.1.clone()).or_default().push(k);
        }
    }
    let many: Vec<&String> = loaded
        .iter()
        .filter(|(_, l)| l.len() > 2)
        .map(|(b, _)| b)
        .collect();
    // Every brick: with every pair's own rows (the full rows, this scene's default: its
    // joints meet at T-junctions) the top course's head joint stays closed. (The evolutive
    // path, `method = "lcp"`, whose implied components at the junctions carry no friction
    // force, opens it: the first two courses only.)
    assert_eq!(
        many,
        ["brick_1", "brick_2", "brick_3", "brick_4", "brick_5", "brick_6", "brick_7"]
    );
    let vtu = std::fs::read_to_string(out.join("vtk/thrust_0000.vtu")).expect("thrust_0000.vtu");
    let (points, cells, joint) = thrust_block(&vtu);
    let hubs: Vec<usize> = (0..points.len()).filter(|&i| joint[i] == -1).collect();
    assert_eq!(hubs.len(), many.len());
    let csv = hub_csv(out);
    assert_eq!(csv.len(), hubs.len(), "{csv:?}");
    let mut found = BTreeMap::new();
    let mut worst = (0.0f64, 0.0f64, 0.0f64);
    for &h in &hubs {
        // The lines ending at the hub: their other ends are the brick's joints' points.
        let ends: Vec<usize> = cells
            .iter()
            .filter(|c| c.len() == 2 && c[1] == h)
            .map(|c| c[0])
            .collect();
        let js: Vec<usize> = ends.iter().map(|&e| joint[e] as usize).collect();
        let body = many
            .iter()
            .find(|b| {
                js.iter()
                    .all(|&k| joints[k].0 == ***b || joints[k].1 == ***b)
            })
            .expect("the hub's brick");
        assert_eq!(&js, &loaded[*body], "{body}");
        let (cx, resultant, group, count) = &csv[*body];
        assert_eq!(
            (*cx, *count),
            (points[h], js.len()),
            "{body}: CSV against VTK"
        );
        for (&e, &k) in ends.iter().zip(&js) {
            let p = joints[k].2.unwrap_or_default();
            let q = back(points[e]);
            worst.0 = worst.0.max((q[0] - p[0]).abs().max((q[1] - p[1]).abs()));
        }
        // Forces on the brick: −N n + T τ with n its outward normal, τ = (−n_y, n_x) of the
        // first body's normal.
        let rect = bond_brick(body);
        let x = back(points[h]);
        let (mut below, mut rest, mut scale) = (0.0, 0.0, 0.0);
        let mut r_below = [0.0; 2];
        let has_below = js.iter().any(|&k| {
            let other = if joints[k].0 == **body {
                &joints[k].1
            } else {
                &joints[k].0
            };
            outward(rect, bond_brick(other))[1] < 0.0
        });
        assert_eq!(group, if has_below { "below" } else { "above" }, "{body}");
        for &k in &js {
            let (a, b, p, n, t) = &joints[k];
            let na = outward(bond_brick(a), bond_brick(b));
            let fa = [-n * na[0] - t * na[1], -n * na[1] + t * na[0]];
            let sign = if a == *body { 1.0 } else { -1.0 };
            let fb = [sign * fa[0], sign * fa[1]];
            let r = [
                p.unwrap_or_default()[0] - x[0],
                p.unwrap_or_default()[1] - x[1],
            ];
            let m = cross(r, fb);
            let ny = sign * na[1];
            if (has_below && ny < 0.0) || (!has_below && ny > 0.0) {
                below += m;
                r_below = [r_below[0] + fb[0], r_below[1] + fb[1]];
            } else {
                rest += m;
            }
            scale += r[0].hypot(r[1]) * fb[0].hypot(fb[1]);
        }
        // The CSV's resultant is the group's (in the run's coordinates).
        let rr = back(*resultant);
        let size = r_below[0].hypot(r_below[1]);
        assert!(
            (rr[0] - r_below[0]).hypot(rr[1] - r_below[1]) < 1e-9 * size,
            "{body}: R {rr:?} against {r_below:?}"
        );
        // The weight at the centroid.
        let w = [0.0, -20.0 * (rect[1] - rect[0]) * (rect[3] - rect[2])];
        let g = [
            0.5 * (rect[0] + rect[1]) - x[0],
            0.5 * (rect[2] + rect[3]) - x[1],
        ];
        rest += cross(g, w);
        scale += g[0].hypot(g[1]) * w[1].abs();
        worst.1 = worst.1.max(below.abs() / scale);
        // The first course also rests on the clamped base, whose reaction is not a joint's.
        if rect[2] > 0.0 {
            worst.2 = worst.2.max((below + rest).abs() / scale);
        }
        // On a straight bed the hub lies on it.
        assert!(
            rect[2..].iter().any(|y| (x[1] - y).abs() < 1e-12),
            "{body}: {x:?}"
        );
        found.insert(body.to_string(), x);
    }
    println!(
        "ends {:.1e}, group moment {:.1e}, balance {:.1e}",
        worst.0, worst.1, worst.2
    );
    assert!(
        worst.0 < 1e-12 && worst.1 < 1e-10 && worst.2 < 1e-10,
        "{worst:?}"
    );
    found
}

/// Runs the bond wall meshed from `mesh` under `body_force` (and `extra` tables) in a folder
/// named `name`; returns its run folder and summary.
fn run_bond(
    name: &str,
    mesh: &std::path::Path,
    body_force: &str,
    extra: &str,
) -> (std::path::PathBuf, Value) {
    let dir = tmpdir(name);
    let scene = write(&dir, "bond.toml", &bond_scene(mesh, body_force, extra));
    let out = dir.join("out");
    let s = run(&scene, &out);
    assert_eq!(s["status"], "converged");
    (out, s)
}

/// A running-bond wall: every brick with more than two loaded joints gets a hub and a line
/// from each of its joints' points to it, the same hubs in thrust_hubs.csv, and the brick
/// balances about its hub ([`check_hubs`]).
#[test]
fn running_bond_bricks_get_their_force_paths() {
    let wall = root().join("geo/wall.geo");
    let (out, s) = run_bond("thrust-bond", &wall, "[0.0, -20.0]", "");
    check_hubs(&out, &s, &|p| p);
}

/// The same wall turned a quarter turn (counter-clockwise: its base on the right, x = 0)
/// under its weight along +x, a sideways body force: its bed joints are vertical, so "below"
/// must come from the body force (a −y rule would take the head joints). The hubs are the
/// upright wall's turned (to 1e-9 of the wall's size) and the bricks balance about them as
/// there. The weight grows in pseudo-time (`20 t`, t = 0.5 then 1), so the final state's
/// body force is not the one the model records (t = 0.5): the archive keeps the state's, and
/// `sgbem export` draws the same thrust block.
#[test]
fn sideways_body_force_turns_the_hubs() {
    let dir = tmpdir("thrust-bond-turned");
    let turned = write(
        &dir,
        "turned.geo",
        &format!(
            "Include \"{}\";\nRotate {{{{0, 0, 1}}, {{0, 0, 0}}, Pi/2}} {{ Surface{{:}}; }}\n",
            root().join("geo/wall.geo").display()
        ),
    );
    let time = "[solve]\ntime = [0.5, 1.0]";
    let (out, s) = run_bond("thrust-bond-sideways", &turned, "[\"20*t\", 0.0]", time);
    // (x, y) of the turned wall is (−y, x) of the upright one.
    let turned_hubs = check_hubs(&out, &s, &|p| [p[1], -p[0]]);
    let vtk = dir.join("exported");
    let a = out.join("archive.h5");
    let (code, _, err) = sgbem(&[
        "export",
        a.to_str().unwrap(),
        "--vtk",
        vtk.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let file = "thrust_0000.vtu";
    let ran = std::fs::read(out.join("vtk").join(file)).unwrap();
    assert!(
        ran == std::fs::read(vtk.join(file)).unwrap(),
        "export draws another block"
    );
    let wall = root().join("geo/wall.geo");
    let (out, s) = run_bond("thrust-bond-upright", &wall, "[0.0, -20.0]", "");
    let upright = check_hubs(&out, &s, &|p| p);
    let mut worst = 0.0f64;
    for (body, x) in &upright {
        let y = turned_hubs[body];
        worst = worst.max((x[0] - y[0]).abs().max((x[1] - y[1]).abs()));
    }
    println!("turned against upright hubs: {worst:.1e} m");
    assert!(worst < 1e-9 * 0.8, "{worst}");
}

/// The VTK block `contact` (`vtk/contact_NNNN.vtu`): one point per contact row, whose
/// statuses and tractions are the interface tables' row by row, and whose normal and
/// tangential forces add up to each joint's N and T of the thrust line (3 × 3 running-bond wall, friction 0.3:
/// 23 of its rows slip).
#[test]
fn contact_block_holds_every_row_of_the_interface_tables() {
    let out = tmpdir("thrust-contact-block").join("out");
    let scene = root().join("pipelines/wall_running_bond.toml");
    let s = |p: &std::path::Path| p.to_str().unwrap_or_default().to_string();
    let (code, _, err) = sgbem(&[
        "run",
        &s(&scene),
        "--out",
        &s(&out),
        "--set",
        "mesh.courses=3",
        "--set",
        "mesh.bricks=3",
        "--set",
        "defaults.interface.friction=0.3",
        "--set",
        "output.history=\"final\"",
        "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let vtm = std::fs::read_to_string(out.join("vtk/state_0000.vtm")).unwrap();
    assert!(
        vtm.contains("name=\"contact\" file=\"contact_0000.vtu\""),
        "{vtm}"
    );
    let vtu = std::fs::read_to_string(out.join("vtk/contact_0000.vtu")).unwrap();
    let arrays = binary_arrays(&vtu, false);
    let get = |n: &str| &arrays.iter().find(|(k, _)| k == n).expect(n).1;
    let f64s = |n: &str| -> Vec<f64> {
        get(n)
            .chunks(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap_or_default()))
            .collect()
    };
    let i32s = |n: &str| -> Vec<i32> {
        get(n)
            .chunks(4)
            .map(|c| i32::from_le_bytes(c.try_into().unwrap_or_default()))
            .collect()
    };
    let (iface, pair, status, tstatus) = (
        i32s("interface"),
        i32s("pair"),
        i32s("contact_status"),
        i32s("tangential_status"),
    );
    let (tn, tt, force, shear) = (
        f64s("normal_traction"),
        f64s("tangential_traction"),
        f64s("normal_force"),
        f64s("tangential_force"),
    );
    // The interface names: UTF-8 bytes in an ascii UInt8 array, one name per line.
    let names_text = vtu
        .split("Name=\"interface_names\"")
        .nth(1)
        .and_then(|t| t.split('>').nth(1))
        .and_then(|t| t.split('<').next())
        .expect("interface_names");
    let bytes: Vec<u8> = names_text
        .split_whitespace()
        .map(|b| b.parse().expect("a byte"))
        .collect();
    let names: Vec<String> = String::from_utf8(bytes)
        .expect("UTF-8")
        .lines()
        .map(str::to_string)
        .collect();
    let thrust = summary["thrust"].as_object().expect("thrust block");
    assert_eq!(names.len(), thrust.len());
    let mut rows_seen = 0;
    let mut slipping = 0;
    for (i, name) in names.iter().enumerate() {
        let table = read_interface_csv(&out.join("interfaces").join(format!("{name}.csv")));
        let at: Vec<usize> = (0..iface.len()).filter(|&p| iface[p] == i as i32).collect();
        assert_eq!(at.len(), table.len(), "{name}");
        let (mut sum, mut sum_t) = (0.0, 0.0);
        for (j, (&p, row)) in at.iter().zip(&table).enumerate() {
            assert_eq!(pair[p], j as i32, "{name}");
            assert_eq!(status[p] == 1, row.closed, "{name} pair {j}");
            assert_eq!((tn[p], tt[p]), (row.tn, row.tt), "{name} pair {j}");
            let want = match row.tangential_status.as_deref() {
                Some("stick") => 1,
                Some("slip") => 2,
                Some("open") => 0,
                _ => -1,
            };
            assert_eq!(tstatus[p], want, "{name} pair {j}");
            slipping += usize::from(want == 2);
            sum += force[p];
            sum_t += shear[p];
        }
        // N is compression positive; the rows' normal forces are tension positive.
        let n = thrust[name]["normal_force"].as_f64().expect("N");
        assert!(
            (sum + n).abs() <= 1e-12 * n.abs().max(1e-300),
            "{name}: {sum} vs {n}"
        );
        let t = thrust[name]["tangential_force"].as_f64().expect("T");
        assert!(
            (sum_t - t).abs() <= 1e-12 * n.abs().max(1e-300),
            "{name}: {sum_t} vs T {t}"
        );
        rows_seen += at.len();
    }
    assert_eq!(rows_seen, iface.len());
    assert!(
        slipping > 0,
        "no row slips: the test would not see the friction statuses"
    );
}
