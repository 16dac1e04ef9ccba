//! The minimum thickness of a semicircular masonry arch under its own weight: the arch
//! pipeline (`pipelines/arch.toml`, `geo/arch.geo` with radial joints, centre-line radius
//! R = 5) with 40 voussoirs and friction μ = 1 on every joint (no joint slides), bisected on
//! t/R between a ring that stands (exit 0) and one that collapses (exit 3, the hinge
//! mechanism). Milankovitch: t/R = 0.1075 for a continuous semicircular arch.
//! (`pipelines/arch_min_thickness.py` is the same search as a pipeline.)

mod support;

const R: f64 = 5.0;
const MILANKOVITCH: f64 = 0.1075;

/// Runs the arch at t/R; returns (exit code, stderr).
fn arch(dir: &std::path::Path, t_over_r: f64) -> (i32, String) {
    let scene = support::root().join("pipelines/arch.toml");
    let out = dir.join(format!("t{t_over_r:.5}"));
    let (code, _, stderr) = support::sgbem(&[
        "run",
        scene.to_str().unwrap(),
        "--set",
        "mesh.nv=40",
        "--set",
        &format!("mesh.t={:.6}", t_over_r * R),
        "--set",
        "defaults.interface.tangential=friction",
        "--set",
        "defaults.interface.friction=1.0",
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(
        code == 0 || code == 3,
        "t/R = {t_over_r}: exit {code}: {stderr}"
    );
    (code, stderr)
}

#[test]
fn semicircular_arch_minimum_thickness_is_milankovitch_s() {
    let dir = support::tmpdir("arch_limit");
    // A ring at t/R = 0.12 stands; one at 0.10 ends with the hinge mechanism.
    let (code, stderr) = arch(&dir, 0.12);
    assert_eq!(code, 0, "t/R = 0.12 must stand: {stderr}");
    let (code, stderr) = arch(&dir, 0.10);
    assert_eq!(code, 3, "t/R = 0.10 must collapse");
    assert!(
        stderr.contains("no equilibrium exists") && stderr.contains("voussoir_"),
        "{stderr}"
    );
    // Bisection to 0.001 in t/R.
    let (mut lo, mut hi) = (0.10, 0.12);
    while hi - lo > 1e-3 {
        let mid = 0.5 * (lo + hi);
        if arch(&dir, mid).0 == 0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let found = 0.5 * (lo + hi);
    eprintln!(
        "minimum t/R = {found:.4} (between {lo:.4} and {hi:.4}); Milankovitch {MILANKOVITCH}: \
         {:+.1} %",
        100.0 * (found / MILANKOVITCH - 1.0)
    );
    assert!(
        (found / MILANKOVITCH - 1.0).abs() < 0.03,
        "t/R = {found} vs {MILANKOVITCH}"
    );
}

/// Runs `sgbem run SCENE ARGS --out DIR/out --quiet`, which must succeed; its summary.
fn run_summary(dir: &std::path::Path, scene: &std::path::Path, args: &[&str]) -> serde_json::Value {
    let out = dir.join("out");
    let mut all = vec!["run", scene.to_str().unwrap()];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--out", out.to_str().unwrap(), "--quiet"]);
    let (code, _, stderr) = support::sgbem(&all);
    assert_eq!(code, 0, "{stderr}");
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

/// `[solve] collapse`: the multiplier t of a lateral body force at which a block on a base
/// (b × h = 1 × 0.5, friction 10: it cannot slide) tips, against the rigid-block limit
/// analysis value b/h = 2 (overturning about the toe: t·W·h/2 = W·b/2).
#[test]
fn collapse_multiplier_of_a_tilting_block_is_the_rigid_block_limit() {
    let dir = support::two_blocks_mesh("collapse_block");
    let scene = support::two_blocks_scene(
        "[\"t\", -1.0]",
        10.0,
        "[solve]\ncollapse = { max = 5.0, tolerance = 0.001 }",
        true,
    );
    let scene = support::write(&dir, "col.toml", &scene);
    let s = run_summary(&dir, &scene, &[]);
    let c = &s["contact"]["collapse"];
    let (lo, hi) = (
        c["multiplier"].as_f64().unwrap(),
        c["collapses_at"].as_f64().unwrap(),
    );
    let rigid = 1.0 / 0.5;
    eprintln!("tilting block: collapse multiplier {lo:.4} .. {hi:.4}, rigid block {rigid}");
    assert!(hi - lo <= 0.001 + 1e-12, "bisection to the tolerance");
    assert!((lo / rigid - 1.0).abs() < 0.01, "{lo} vs {rigid}");
    // The rigid-block statics (tipping at b/h before sliding at μ = 10) is the closed form,
    // and confirms the mechanism found above it.
    let bound = c["upper_bound"].as_f64().expect("upper_bound");
    eprintln!(
        "tilting block: rigid-block statics upper bound {bound:.9} ({:+.1e})",
        bound - rigid
    );
    assert!((bound - rigid).abs() < 1e-6, "{bound} vs {rigid}");
    let mech = c["mechanism"].as_str().unwrap();
    assert!(
        mech.contains("body \"upper\"") && mech.contains("tipping"),
        "{mech}"
    );
    assert!(mech.contains("the rigid-block check confirms it"), "{mech}");
    // The reported state is the standing one at the multiplier.
    assert_eq!(s["status"], "converged");
    // The mechanism as data: the block turns clockwise about its toe (1, 0.5), its corner
    // farthest from the toe, (0, 1) at √1.25, the fastest node; the VTK block "mechanism" of
    // the reported state draws that rigid velocity to 1e-6, the base at rest.
    let motion = c["motion"].as_array().expect("collapse.motion");
    assert_eq!(motion.len(), 1, "{motion:?}");
    let b = &motion[0];
    assert_eq!(
        (&b["body"], &b["kind"], &b["sense"]),
        (&"upper".into(), &"rotation".into(), &"clockwise".into())
    );
    let centre = [
        b["centre"][0].as_f64().unwrap(),
        b["centre"][1].as_f64().unwrap(),
    ];
    assert!(
        (centre[0] - 1.0).hypot(centre[1] - 0.5) <= 1e-6,
        "{centre:?}"
    );
    assert!(
        (b["magnitude"].as_f64().unwrap() - 1.0).abs() <= 1e-12,
        "{b}"
    );
    let w = -1.0 / 1.25f64.sqrt();
    let nodes = support::mechanism_block(&dir.join("out")).expect("a mechanism block");
    let upper = nodes.iter().find(|n| n.x[1] > 0.75).unwrap().body;
    for n in nodes {
        let want = if n.body == upper {
            [-w * (n.x[1] - 0.5), w * (n.x[0] - 1.0)]
        } else {
            [0.0, 0.0]
        };
        let off = (n.v[0] - want[0]).hypot(n.v[1] - want[1]);
        assert!(off <= 1e-6, "at {:?}: {:?} against {want:?}", n.x, n.v);
    }
}

/// The same for a pier of two blocks on a clamped one (`pipelines/wall.toml`, 3 courses of
/// 0.4 × 0.2 blocks): the two upper blocks tip together about the toe of the first joint at
/// the rigid-block limit t = b / (2h) = 1 (a lateral acceleration t·g); the top joint alone
/// would need b/h = 2.
#[test]
fn collapse_multiplier_of_a_two_block_pier_is_the_rigid_block_limit() {
    let dir = support::tmpdir("collapse_pier");
    let scene = support::root().join("pipelines/wall.toml");
    let s = run_summary(
        &dir,
        &scene,
        &[
            "--set",
            "mesh.courses=3",
            "--set",
            "body.brick_*.body_force=[\"20*t\", -20.0]",
            "--set",
            "boundary.left.tx=0.0",
            "--set",
            "solve.collapse={ max = 5.0, tolerance = 0.001 }",
        ],
    );
    let c = &s["contact"]["collapse"];
    let lo = c["multiplier"].as_f64().unwrap();
    let rigid = 0.4 / (2.0 * 0.2);
    let bound = c["upper_bound"].as_f64().expect("upper_bound");
    eprintln!(
        "two-block pier: collapse multiplier {lo:.4}, rigid blocks {rigid}, rigid-block \
         statics {bound:.9} ({:+.1e})",
        bound - rigid
    );
    assert!((lo / rigid - 1.0).abs() < 0.01, "{lo} vs {rigid}");
    // Stick joints: no sliding, so the statics' bound is the rocking limit itself.
    assert!((bound - rigid).abs() < 1e-6, "{bound} vs {rigid}");
    let mech = c["mechanism"].as_str().unwrap();
    assert!(mech.contains("joints[brick_1|brick_2]"), "{mech}");
}

/// An axis-aligned rigid block `[x0, x1] × [y0, y1]`.
#[derive(Clone, Copy)]
struct Rect {
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
}

/// The running-bond blocks of `courses` courses of `bricks` bricks `w × h` (odd courses
/// shifted by half a brick, with half bricks at the ends).
fn running_bond(courses: usize, bricks: usize, w: f64, h: f64) -> Vec<Rect> {
    let mut out = Vec::new();
    for c in 0..courses {
        let (y0, y1) = (c as f64 * h, (c + 1) as f64 * h);
        let mut xs: Vec<f64> = (0..=bricks).map(|i| i as f64 * w).collect();
        if c % 2 == 1 {
            xs = std::iter::once(0.0)
                .chain((0..bricks).map(|i| (i as f64 + 0.5) * w))
                .chain(std::iter::once(bricks as f64 * w))
                .collect();
        }
        for p in xs.windows(2) {
            out.push(Rect {
                x0: p[0],
                x1: p[1],
                y0,
                y1,
            });
        }
    }
    out
}

/// A gmsh model of the blocks: Physical Surfaces `b1`, `b2`, …; Physical Curves `base`
/// (y = 0), `bed` (horizontal joints), `head` (vertical joints) and `free` (the rest), each
/// block edge cut at every corner of a neighbour on it, `n` elements per length `h`.
fn blocks_geo(blocks: &[Rect], h: f64, n: usize) -> String {
    let eq = |a: f64, b: f64| (a - b).abs() < 1e-9;
    let mut pts: Vec<[f64; 2]> = Vec::new();
    let pid = |p: [f64; 2], pts: &mut Vec<[f64; 2]>| -> usize {
        match pts.iter().position(|q| eq(q[0], p[0]) && eq(q[1], p[1])) {
            Some(i) => i + 1,
            None => {
                pts.push(p);
                pts.len()
            }
        }
    };
    let corners: Vec<[f64; 2]> = blocks
        .iter()
        .flat_map(|r| [[r.x0, r.y0], [r.x1, r.y0], [r.x1, r.y1], [r.x0, r.y1]])
        .collect();
    // Lines as (start point, end point), each once; loops reference them with a sign.
    let mut lines: Vec<(usize, usize, &'static str)> = Vec::new();
    let mut loops = Vec::new();
    for r in blocks {
        let ring = [[r.x0, r.y0], [r.x1, r.y0], [r.x1, r.y1], [r.x0, r.y1]];
        let mut refs = Vec::new();
        for k in 0..4 {
            let (a, b) = (ring[k], ring[(k + 1) % 4]);
            // Corners of any block on the segment a–b, in order from a.
            let mut on: Vec<[f64; 2]> = corners
                .iter()
                .copied()
                .filter(|p| {
                    let cr = (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
                    let t = ((p[0] - a[0]) * (b[0] - a[0]) + (p[1] - a[1]) * (b[1] - a[1]))
                        / ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2));
                    cr.abs() < 1e-12 && t > -1e-9 && t < 1.0 + 1e-9
                })
                .collect();
            let d = |p: &[f64; 2]| (p[0] - a[0]).abs() + (p[1] - a[1]).abs();
            on.sort_by(|p, q| d(p).total_cmp(&d(q)));
            on.dedup_by(|p, q| eq(p[0], q[0]) && eq(p[1], q[1]));
            for seg in on.windows(2) {
                let (i, j) = (pid(seg[0], &mut pts), pid(seg[1], &mut pts));
                let horizontal = eq(seg[0][1], seg[1][1]);
                let inside = blocks.iter().filter(|o| {
                    let (mx, my) = ((seg[0][0] + seg[1][0]) / 2.0, (seg[0][1] + seg[1][1]) / 2.0);
                    mx >= o.x0 - 1e-9 && mx <= o.x1 + 1e-9 && my >= o.y0 - 1e-9 && my <= o.y1 + 1e-9
                });
                let shared = inside.count() == 2;
                let kind = match (shared, horizontal) {
                    (true, true) => "bed",
                    (true, false) => "head",
                    (false, true) if eq(seg[0][1], 0.0) => "base",
                    _ => "free",
                };
                match lines
                    .iter()
                    .position(|&(p, q, _)| (p, q) == (j, i) || (p, q) == (i, j))
                {
                    Some(l) if lines[l].0 == i => refs.push(l as i64 + 1),
                    Some(l) => refs.push(-(l as i64 + 1)),
                    None => {
                        lines.push((i, j, kind));
                        refs.push(lines.len() as i64);
                    }
                }
            }
        }
        loops.push(refs);
    }
    let mut g = String::new();
    for (k, p) in pts.iter().enumerate() {
        g += &format!("Point({}) = {{{}, {}, 0}};\n", k + 1, p[0], p[1]);
    }
    for (k, &(a, b, _)) in lines.iter().enumerate() {
        let len = (pts[b - 1][0] - pts[a - 1][0]).abs() + (pts[b - 1][1] - pts[a - 1][1]).abs();
        let m = ((len / h) * n as f64).round().max(1.0) as usize;
        g += &format!(
            "Line({}) = {{{a}, {b}}};\nTransfinite Curve{{{}}} = {};\n",
            k + 1,
            k + 1,
            m + 1
        );
    }
    for (k, refs) in loops.iter().enumerate() {
        let list: Vec<String> = refs.iter().map(|r| r.to_string()).collect();
        g += &format!(
            "Curve Loop({}) = {{{}}};\nPlane Surface({}) = {{{}}};\nPhysical Surface(\"b{}\") = {{{}}};\n",
            k + 1,
            list.join(", "),
            k + 1,
            k + 1,
            k + 1,
            k + 1
        );
    }
    for kind in ["base", "bed", "head", "free"] {
        let ids: Vec<String> = lines
            .iter()
            .enumerate()
            .filter(|(_, l)| l.2 == kind)
            .map(|(k, _)| (k + 1).to_string())
            .collect();
        if !ids.is_empty() {
            g += &format!("Physical Curve(\"{kind}\") = {{{}}};\n", ids.join(", "));
        }
    }
    g
}

/// The rigid-block limit multiplier λ of a lateral load λ·W (at each block's centroid, W
/// its weight) on no-tension blocks, by the static theorem: maximise λ over the forces
/// N ≥ 0, |T| ≤ μN at the two ends of every contact (bed joints μ = `mu_bed`, head joints
/// frictionless) that balance every block; the blocks standing on y = 0 are held there
/// (clamped: any force). An LP solved by Clarabel (Livesley's formulation). With
/// frictionless head joints and beds that do not slide, the only mechanisms are rocking
/// ones, for which the static theorem holds for real (non-associative) blocks too.
fn rigid_block_limit(blocks: &[Rect], mu_bed: f64) -> f64 {
    use clarabel::algebra::CscMatrix;
    use clarabel::solver::{
        DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus, ZeroConeT,
    };
    let eq = |a: f64, b: f64| (a - b).abs() < 1e-9;
    // (block A or None for the ground, block B, point, normal from A into B, μ).
    type Vertex = (Option<usize>, usize, [f64; 2], [f64; 2], f64);
    let mut vertices: Vec<Vertex> = Vec::new();
    for (j, b) in blocks.iter().enumerate() {
        if eq(b.y0, 0.0) {
            for x in [b.x0, b.x1] {
                vertices.push((None, j, [x, 0.0], [0.0, 1.0], f64::INFINITY));
            }
        }
        for (i, a) in blocks.iter().enumerate() {
            let (lo, hi) = (a.x0.max(b.x0), a.x1.min(b.x1));
            if eq(a.y1, b.y0) && hi - lo > 1e-9 {
                for x in [lo, hi] {
                    vertices.push((Some(i), j, [x, b.y0], [0.0, 1.0], mu_bed));
                }
            }
            let (lo, hi) = (a.y0.max(b.y0), a.y1.min(b.y1));
            if eq(a.x1, b.x0) && hi - lo > 1e-9 {
                for y in [lo, hi] {
                    vertices.push((Some(i), j, [b.x0, y], [1.0, 0.0], 0.0));
                }
            }
        }
    }
    let (nb, nv) = (blocks.len(), vertices.len());
    let n = 1 + 2 * nv; // λ, then (N, T) per vertex
    let mut a: Vec<Vec<f64>> = vec![vec![0.0; n]; 3 * nb];
    let mut b = vec![0.0; 3 * nb];
    for (k, r) in blocks.iter().enumerate() {
        let w = (r.x1 - r.x0) * (r.y1 - r.y0);
        // Σ F + (λW, −W) = 0 and Σ (p − c) × F = 0 (the loads act at the centroid).
        a[3 * k][0] = w;
        b[3 * k + 1] = w;
    }
    let mut ineq: Vec<(Vec<(usize, f64)>, f64)> = vec![(vec![(0, 1.0)], 100.0)]; // λ ≤ 100
    for (v, &(blk_a, blk_b, p, nrm, mu)) in vertices.iter().enumerate() {
        let t = [-nrm[1], nrm[0]];
        for (k, sign) in [(Some(blk_b), 1.0), (blk_a, -1.0)] {
            let Some(k) = k else { continue };
            let r = blocks[k];
            let rr = [p[0] - (r.x0 + r.x1) / 2.0, p[1] - (r.y0 + r.y1) / 2.0];
            for (col, d) in [(1 + 2 * v, nrm), (2 + 2 * v, t)] {
                a[3 * k][col] += sign * d[0];
                a[3 * k + 1][col] += sign * d[1];
                a[3 * k + 2][col] += sign * (rr[0] * d[1] - rr[1] * d[0]);
            }
        }
        if mu.is_finite() {
            // −N ≤ 0, T − μN ≤ 0, −T − μN ≤ 0.
            let (cn, ct) = (1 + 2 * v, 2 + 2 * v);
            ineq.push((vec![(cn, -1.0)], 0.0));
            ineq.push((vec![(cn, -mu), (ct, 1.0)], 0.0));
            ineq.push((vec![(cn, -mu), (ct, -1.0)], 0.0));
        }
    }
    let m = a.len() + ineq.len();
    for (row, rhs) in &ineq {
        let mut dense = vec![0.0; n];
        for &(c, x) in row {
            dense[c] = x;
        }
        a.push(dense);
        b.push(*rhs);
    }
    let (mut colptr, mut rowval, mut nzval) = (vec![0], Vec::new(), Vec::new());
    for j in 0..n {
        for (i, row) in a.iter().enumerate() {
            if row[j] != 0.0 {
                rowval.push(i);
                nzval.push(row[j]);
            }
        }
        colptr.push(rowval.len());
    }
    let am = CscMatrix::new(m, n, colptr, rowval, nzval);
    let pm = CscMatrix::new(n, n, vec![0; n + 1], Vec::new(), Vec::new());
    let mut q = vec![0.0; n];
    q[0] = -1.0;
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .build()
        .expect("settings");
    let cones = [ZeroConeT(3 * nb), NonnegativeConeT(ineq.len())];
    let mut solver = DefaultSolver::new(&pm, &q, &am, &b, &cones, settings).expect("LP");
    solver.solve();
    assert_eq!(solver.solution.status, SolverStatus::Solved);
    solver.solution.x[0]
}

/// The multiplier of the rigid mechanism in which `blocks` rotate together about `pivot`
/// under a lateral load λ·W and their weight W: λ = Σ W (x_p − x_c) / Σ W (y_c − y_p)
/// (kinematic theorem: an upper bound of the collapse multiplier).
fn rocking_multiplier(blocks: &[Rect], pivot: [f64; 2]) -> f64 {
    let (mut restoring, mut overturning) = (0.0, 0.0);
    for r in blocks {
        let w = (r.x1 - r.x0) * (r.y1 - r.y0);
        restoring += w * (pivot[0] - (r.x0 + r.x1) / 2.0);
        overturning += w * ((r.y0 + r.y1) / 2.0 - pivot[1]);
    }
    restoring / overturning
}

/// The scene of the running-bond `blocks` (courses `h` high, meshed into `dir`): E = 5 GPa,
/// bed joints μ = 5, head joints frictionless, the first course clamped, under the body
/// force `body_force` (TOML), with `extra` (TOML tables) after.
fn running_bond_scene(
    dir: &std::path::Path,
    blocks: &[Rect],
    body_force: &str,
    extra: &str,
) -> String {
    let h = blocks[0].y1 - blocks[0].y0;
    let geo = support::write(dir, "wall.geo", &blocks_geo(blocks, h, 4));
    let msh = support::gmsh(&geo, dir, "wall.msh", false, &[]);
    format!(
        r#"plane = "strain"
[mesh]
file = "{}"
[defaults.body]
young = 5.0e6
poisson = 0.2
body_force = {body_force}
[interface.bed]
model = "unilateral"
tangential = "friction"
friction = 5.0
[interface.head]
model = "unilateral"
tangential = "slide"
[boundary.base]
ux = 0.0
uy = 0.0
{extra}
[output]
history = "final"
vtk = false
"#,
        msh.display()
    )
}

/// Running-bond walls on a clamped first course, under a lateral acceleration t·g: the
/// collapse multiplier of the elastic blocks (E = 5 GPa: nearly rigid; bed joints μ = 5,
/// head joints frictionless) against rigid-block limit analysis. The courses above the
/// first meet at T-junctions.
///
/// * 2 courses (5 blocks, 3 T-junctions): the static LP gives 1 (the half brick at the
///   leeward end tips alone; no joint slides in that mechanism, so the LP's associative
///   friction is exact).
/// * 3 courses (7 blocks, 6 T-junctions): the leeward half brick tips together with the
///   brick above it, which lifts off its other support while sliding over it (0.714 by the
///   kinematic theorem). That relative sliding of a separating joint is free for real
///   friction but not for the LP's associative friction, whose static bound (1.08) is only
///   an upper bound here: the elastic blocks collapse at the mechanism's multiplier.
#[test]
fn collapse_multiplier_of_running_bond_walls_is_the_rigid_block_limit() {
    let (w, h) = (0.4, 0.2);
    for courses in [2, 3] {
        let blocks = running_bond(courses, 2, w, h);
        let lp = rigid_block_limit(&blocks, 5.0);
        let dir = support::tmpdir("collapse_wall");
        let scene = running_bond_scene(
            &dir,
            &blocks,
            "[\"20*t\", -20.0]",
            "[solve]\ncollapse = { max = 5.0, tolerance = 0.001 }",
        );
        let path = support::write(&dir, "wall.toml", &scene);
        let s = run_summary(&dir, &path, &[]);
        let c = &s["contact"]["collapse"];
        let t = c["multiplier"].as_f64().unwrap();
        let bound = c["upper_bound"].as_f64().expect("upper_bound");
        let junctions = s["contact"]["junctions"]["points"].as_u64().unwrap_or(0);
        // The leeward half brick (b5), with the brick above it (b7) in 3 courses, tipping
        // about its toe.
        let toe = [2.0 * w, h];
        let moving: Vec<Rect> = if courses == 2 {
            vec![blocks[4]]
        } else {
            vec![blocks[4], blocks[6]]
        };
        let kinematic = rocking_multiplier(&moving, toe);
        eprintln!(
            "running-bond wall of {courses} courses ({} blocks, {junctions} junctions): \
             collapse multiplier {t:.4}; rigid blocks: mechanism {kinematic:.4}, static LP \
             {lp:.6}, the run's rigid-block statics {bound:.6} ({:+.1e})",
            blocks.len(),
            bound - lp
        );
        // sgbem's statics over every pair of the mesh is this test's LP over the joints'
        // ends (a joint's cone is spanned by its ends').
        assert!((bound - lp).abs() < 1e-6, "{bound} vs {lp}");
        assert_eq!(junctions, 3 * (courses as u64 - 1));
        assert!((t / kinematic - 1.0).abs() < 0.01, "{t} vs {kinematic}");
        assert!(t <= lp * 1.001, "{t} above the LP bound {lp}");
        if courses == 2 {
            assert!((lp - kinematic).abs() < 1e-6, "{lp} vs {kinematic}");
        }
        let mech = c["mechanism"].as_str().unwrap();
        assert!(mech.contains("b5"), "{mech}");
    }
}

/// The 3-course running-bond wall above at 0.9 g sideways, between its collapse multiplier
/// (0.714: the leeward half brick tips with the brick above it, which slides over its other
/// support as it lifts off) and the rigid-block statics' bound (1.085: associative friction,
/// that sliding not free): the solver ends at that mechanism, but forces within the friction
/// cones that balance every block exist, so the run's verdict is undecided: exit 3, a
/// message that no longer says "no equilibrium exists", no mechanism in the summary, no
/// substeps.
#[test]
fn a_mechanism_that_the_statics_cannot_confirm_is_undecided() {
    let dir = support::tmpdir("undecided_wall");
    // The default (the full rows: the joints meet at junctions) and the evolutive path, whose
    // message also suggests the full rows.
    for (name, extra) in [("lcp", "[solve]\nmethod = \"lcp\""), ("default", "")] {
        let scene = running_bond_scene(&dir, &running_bond(3, 2, 0.4, 0.2), "[18.0, -20.0]", extra);
        let path = support::write(&dir, &format!("wall_{name}.toml"), &scene);
        let out = dir.join(format!("out_{name}"));
        let t0 = std::time::Instant::now();
        let (code, stderr) = support::run_scene(&path, &out);
        eprintln!(
            "0.9 g, {name}: exit {code} in {:.1} s: {}",
            t0.elapsed().as_secs_f64(),
            stderr.trim()
        );
        assert_eq!(code, 3, "{stderr}");
        assert!(
            stderr.contains("undecided: the solver found no equilibrium, but interface forces")
                && stderr.contains("method = \"exact\"") == (name == "lcp")
                && !stderr.contains("no equilibrium exists"),
            "{stderr}"
        );
        check_undecided_summary(&out);
    }
}

/// The summary of an undecided run: not converged, no mechanism, no substeps.
fn check_undecided_summary(out: &std::path::Path) {
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["status"], "not converged");
    assert!(s.get("mechanism").is_none(), "{}", s["mechanism"]);
    // Like a mechanism, not solved again in substeps.
    let notes = s["notes"].to_string();
    assert!(!notes.contains("substeps"), "{notes}");
}
