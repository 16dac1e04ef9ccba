//! `make bench` (third part): whole runs of the arch pipeline (`pipelines/arch.toml` on
//! `geo/arch.geo`, 6 elements per joint, default outputs) for 6 … 100 voussoirs: seconds per
//! stage (from the run's `timings.json`), peak memory of the run, fitted exponents against
//! the number of bodies. Writes out/bench/masonry.csv and prints a table.
//! `SGBEM_BENCH_VOUSSOIRS=6,12` selects sizes.

#[path = "../tests/support/mod.rs"]
mod support;

use sgbem::pipeline::{run, RunOptions};
use support::*;

fn fit(xs: &[f64], ys: &[f64]) -> f64 {
    let n = xs.len() as f64;
    let (lx, ly): (Vec<f64>, Vec<f64>) = xs
        .iter()
        .zip(ys)
        .map(|(x, y)| (x.ln(), y.max(1e-9).ln()))
        .unzip();
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let sxy: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = lx.iter().map(|x| (x - mx) * (x - mx)).sum();
    sxy / sxx
}

const STAGES: [&str; 7] = [
    "read",
    "assemble",
    "condense",
    "interface_system",
    "contact_lcp",
    "write",
    "total",
];

fn main() {
    let sizes: Vec<usize> = std::env::var("SGBEM_BENCH_VOUSSOIRS")
        .ok()
        .map(|v| v.split(',').filter_map(|x| x.trim().parse().ok()).collect())
        .unwrap_or_else(|| vec![6, 12, 25, 50, 100]);
    let dir = tmpdir("bench-masonry");
    let scene = root().join("pipelines/arch.toml");
    println!(
        "sgbem whole runs: semicircular arch (t/R = 0.12, 6 elements per joint, self-weight, \
         stick), {} threads; seconds per stage, peak memory in MB",
        rayon::current_num_threads()
    );
    let mut header = format!("{:>4} {:>6} {:>6}", "nv", "elems", "pairs");
    for s in STAGES {
        header += &format!(" {s:>10}");
    }
    println!("{header} {:>8} status", "peak");
    let mut csv = format!(
        "voussoirs,bodies,elements,pairs,{},peak_mb,status\n",
        STAGES.map(|s| format!("{s}_s")).join(",")
    );
    let (mut xs, mut totals, mut peaks) = (Vec::new(), Vec::new(), Vec::new());
    for nv in sizes {
        let nvs = nv.to_string();
        let msh = gmsh(
            &root().join("geo/arch.geo"),
            &dir,
            &format!("arch{nv}.msh"),
            false,
            &["-setnumber", "nv", &nvs],
        );
        let out = dir.join(format!("arch{nv}"));
        reset_peak();
        let report = run(
            &scene,
            &RunOptions {
                mesh: Some(msh),
                out: Some(out.clone()),
                quiet: true,
                ..RunOptions::default()
            },
        );
        let peak = peak_kb() as f64 / 1024.0;
        let status = match &report {
            Ok(r) => r.summary["status"].as_str().unwrap_or("?").to_string(),
            Err(e) => format!("failed: {e}"),
        };
        let summary: serde_json::Value = std::fs::read_to_string(out.join("summary.json"))
            .ok()
            .and_then(|t| serde_json::from_str(&t).ok())
            .unwrap_or_default();
        let timings: serde_json::Value = std::fs::read_to_string(out.join("timings.json"))
            .ok()
            .and_then(|t| serde_json::from_str(&t).ok())
            .unwrap_or_default();
        let counts = &summary["counts"];
        let (elems, pairs) = (
            counts["boundary_elements"].as_u64().unwrap_or(0),
            counts["interface_pairs"].as_u64().unwrap_or(0),
        );
        let t: Vec<f64> = STAGES
            .iter()
            .map(|s| timings["stages"][*s].as_f64().unwrap_or(f64::NAN))
            .collect();
        let mut line = format!("{nv:>4} {elems:>6} {pairs:>6}");
        for v in &t {
            line += &format!(" {v:>10.3}");
        }
        println!("{line} {peak:>8.0} {status}");
        csv += &format!(
            "{nv},{},{elems},{pairs},{},{peak:.1},{status}\n",
            nv + 2,
            t.iter()
                .map(|v| v.to_string())
                .collect::<Vec<_>>()
                .join(",")
        );
        xs.push((nv + 2) as f64);
        totals.push(t[STAGES.len() - 1]);
        peaks.push(peak);
    }
    if xs.len() >= 2 {
        println!(
            "fitted exponents against the number of bodies: total time p = {:.2}, peak memory \
             p = {:.2}",
            fit(&xs, &totals),
            fit(&xs, &peaks)
        );
    }
    let out = std::path::Path::new("out/bench");
    std::fs::create_dir_all(out).expect("out/bench");
    std::fs::write(out.join("masonry.csv"), csv).expect("write masonry.csv");
}
