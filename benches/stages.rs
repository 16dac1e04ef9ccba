//! `make bench`: time of each solver stage against the number of boundary elements per body,
//! with fitted exponents. Two bonded square blocks, N elements per body (N/4 per side).
//! Writes out/bench/stages.csv and prints a table.

#[path = "../tests/support/mod.rs"]
mod support;

use std::time::Instant;

use sgbem::bem::prepare;
use sgbem::bem::quadrature::QuadratureSettings;
use sgbem::contact::solve_all_closed;
use sgbem::pipeline::load;
use support::*;

const SCENE: &str = "plane = \"strain\"\n[body.lower]\nyoung = 10.0\npoisson = 0.3\n\
[body.upper]\nyoung = 1.0\npoisson = 0.3\n[boundary.base]\nux = 0.0\nuy = 0.0\n\
[boundary.top]\nty = \"-1 - x\"\n[interface.joint]\nmodel = \"bonded\"\n";

fn fit(xs: &[f64], ys: &[f64]) -> f64 {
    let n = xs.len() as f64;
    let (lx, ly): (Vec<f64>, Vec<f64>) = xs.iter().zip(ys).map(|(x, y)| (x.ln(), y.ln())).unzip();
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let sxy: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = lx.iter().map(|x| (x - mx) * (x - mx)).sum();
    sxy / sxx
}

fn main() {
    let sizes: Vec<usize> = std::env::var("SGBEM_BENCH_SIZES")
        .ok()
        .map(|s| s.split(',').filter_map(|v| v.trim().parse().ok()).collect())
        // 4000 elements per body (22 002 dofs, dense: 5.8 GB at the peak) only when asked,
        // SGBEM_BENCH_SIZES=4000: `make bench` stays within 4 GB.
        .unwrap_or_else(|| vec![250, 500, 1000, 2000]);
    let quad = std::env::var("SGBEM_BENCH_QUADRATURE").unwrap_or_else(|_| "standard".into());
    let q = QuadratureSettings::from_name(&quad).expect("quadrature preset");
    let dir = tmpdir("bench");
    let threads = rayon::current_num_threads();
    println!("sgbem stage timings: two bonded blocks, {quad} quadrature, {threads} threads");
    println!(
        "{:>8} {:>8} {:>10} {:>10} {:>10} {:>10}",
        "N/body", "dofs", "assemble", "condense", "solve", "total"
    );
    let mut csv = String::from("elements_per_body,dofs,assemble_s,condense_s,solve_s\n");
    let (mut ns, mut ta, mut tc) = (Vec::new(), Vec::new(), Vec::new());
    for &n in &sizes {
        let per_side = (n / 4).max(1);
        let msh = stacked_blocks(per_side).save(&dir, "m.msh");
        let sc = write(&dir, "s.toml", SCENE);
        let l = load(&sc, Some(&msh)).expect("bench scene loads");
        let t0 = Instant::now();
        let prep = prepare(&l.model, l.scene.plane, &q, 1.0, &sc, &|_| {}).expect("prepare");
        let t1 = Instant::now();
        let sol = solve_all_closed(&l.model, &prep).expect("solve");
        let ts = t1.elapsed().as_secs_f64();
        let _ = t0;
        let dofs: usize = prep.systems.iter().map(|s| s.n()).sum();
        let ne = 4 * per_side;
        println!(
            "{:>8} {:>8} {:>10.3} {:>10.3} {:>10.4} {:>10.3}",
            ne,
            dofs,
            prep.assemble_seconds,
            prep.condense_seconds,
            ts,
            prep.assemble_seconds + prep.condense_seconds + ts
        );
        csv += &format!(
            "{ne},{dofs},{},{},{ts}\n",
            prep.assemble_seconds, prep.condense_seconds
        );
        ns.push(ne as f64);
        ta.push(prep.assemble_seconds);
        tc.push(prep.condense_seconds);
        drop(sol);
    }
    if ns.len() >= 2 {
        println!(
            "fitted exponents (time ∝ N^p): assemble p = {:.2}, condense p = {:.2}",
            fit(&ns, &ta),
            fit(&ns, &tc)
        );
    }
    let out = std::path::Path::new("out/bench");
    std::fs::create_dir_all(out).expect("out/bench");
    std::fs::write(out.join("stages.csv"), csv).expect("write stages.csv");
}
