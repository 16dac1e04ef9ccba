//! `make bench` (fourth part): `[contact]`'s search for facing boundaries
//! (`pairing::facing_pairs`, the uniform grid over boundary segments) on running-bond walls
//! of bricks drawn each on its own (0.4 x 0.2, 4 elements on the bottom, 5 on the top and 2
//! on each side, so that no joint has matching nodes) up to 4 000 bricks, the target being
//! under a second. Prints the segments, the facing element pairs, the pairs of bricks found
//! and the seconds (best of three). `SGBEM_BENCH_BRICKS=1000,4000` selects sizes.

use std::time::Instant;

use sgbem::input::pairing::{facing_pairs, BodySegment};

/// The segments of a wall of `courses` x `per` bricks, every other course shifted by half a
/// brick; each brick counter-clockwise, outward normals.
fn wall(courses: usize, per: usize) -> Vec<BodySegment> {
    let (w, h) = (0.4, 0.2);
    let mut segs = Vec::new();
    let mut body = 0;
    for c in 0..courses {
        let shift = if c % 2 == 1 { 0.5 * w } else { 0.0 };
        for i in 0..per {
            let (x0, y0) = (i as f64 * w + shift, c as f64 * h);
            let corners = [[x0, y0], [x0 + w, y0], [x0 + w, y0 + h], [x0, y0 + h]];
            for (k, n) in [4, 2, 5, 2].into_iter().enumerate() {
                let (a, b) = (corners[k], corners[(k + 1) % 4]);
                let l = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
                let normal = [(b[1] - a[1]) / l, -(b[0] - a[0]) / l];
                for e in 0..n {
                    let t = |s: f64| [a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1])];
                    segs.push(BodySegment {
                        body,
                        a: t(e as f64 / n as f64),
                        b: t((e + 1) as f64 / n as f64),
                        normal,
                    });
                }
            }
            body += 1;
        }
    }
    segs
}

fn main() {
    let sizes: Vec<usize> = std::env::var("SGBEM_BENCH_BRICKS")
        .ok()
        .map(|v| v.split(',').filter_map(|s| s.trim().parse().ok()).collect())
        .unwrap_or_else(|| vec![250, 1000, 4000]);
    println!("| bricks | segments | facing element pairs | brick pairs | seconds (best of 3) |");
    println!("|---|---|---|---|---|");
    for n in sizes {
        let per = ((n as f64).sqrt().round() as usize).max(1);
        let courses = n.div_ceil(per);
        let segs = wall(courses, per);
        let mut best = f64::INFINITY;
        let mut found = Vec::new();
        for _ in 0..3 {
            let t = Instant::now();
            found = facing_pairs(&segs, 1e-6);
            best = best.min(t.elapsed().as_secs_f64());
        }
        let mut bricks: Vec<(usize, usize)> = found
            .iter()
            .map(|&(i, j)| (segs[i].body, segs[j].body))
            .collect();
        bricks.sort_unstable();
        bricks.dedup();
        println!(
            "| {} | {} | {} | {} | {best:.3} |",
            courses * per,
            segs.len(),
            found.len(),
            bricks.len()
        );
    }
}
