//! `make bench` (third part): whole runs with default outputs of the arch pipeline
//! (`pipelines/arch.toml` on `geo/arch.geo`, 6 elements per joint) for 6 … 100 voussoirs and
//! of the running-bond wall (`pipelines/wall_running_bond.toml` on `geo/wall.geo`, 6
//! elements per course height) for 7 … 410 bricks with the full history (the default) and
//! 798, 2 048 and 4 128 bricks with the final state, and of the same walls drawn brick by
//! brick (`pipelines/wall_drawn.toml` on `geo/wall_drawn.geo`, `[contact]`) for 105 … 2 047
//! bricks; the solver (evolutive path or sparse) and its iterations: seconds per stage (from
//! the run's `timings.json`), peak memory of the run, fitted exponents against the number of
//! bodies (all walls, and those of 200 bodies on). Writes out/bench/masonry.csv and prints a
//! table.
//! `SGBEM_BENCH_VOUSSOIRS=6,12`, `SGBEM_BENCH_WALLS=2x3,10x10,20x20:final` and
//! `SGBEM_BENCH_DRAWN=4x3,28x28:final` (courses x bricks, optionally `:final` for history =
//! "final") select sizes.

#[path = "../tests/support/mod.rs"]
mod support;

use std::path::Path;

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

const STAGES: [&str; 10] = [
    "read",
    "assemble",
    "condense",
    "interface_system",
    "contact_lcp",
    "contact_active_set",
    "contact_sparse",
    "contact_record",
    "write",
    "total",
];

/// One whole run of a masonry series, as a process of its own (`sgbem run` under
/// `/usr/bin/time`, whose maximum resident set is the run's peak memory: measured in this
/// process, the memory an earlier run left with the allocator would count); prints a line
/// and returns the CSV row, the number of bodies, the total seconds and the peak memory.
fn one(
    label: &str,
    size: &str,
    scene: &Path,
    args: &[String],
    out: &Path,
) -> (String, f64, f64, f64) {
    let mut cmd = std::process::Command::new("/usr/bin/time");
    cmd.arg("-f")
        .arg("%M")
        .arg(env!("CARGO_BIN_EXE_sgbem"))
        .arg("run")
        .arg(scene)
        .arg("--quiet")
        .arg("--out")
        .arg(out)
        .args(args);
    let (status, peak) = match cmd.output() {
        Ok(o) => {
            let err = String::from_utf8_lossy(&o.stderr);
            let peak = err
                .lines()
                .last()
                .and_then(|l| l.trim().parse::<f64>().ok())
                .map_or(f64::NAN, |kb| kb / 1024.0);
            let status = match o.status.code() {
                Some(0) | Some(3) => String::new(),
                _ => format!(
                    "failed: {}",
                    err.lines().find(|l| l.starts_with("sgbem")).unwrap_or("?")
                ),
            };
            (status, peak)
        }
        Err(e) => (format!("failed: /usr/bin/time: {e}"), f64::NAN),
    };
    let summary: serde_json::Value = std::fs::read_to_string(out.join("summary.json"))
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .unwrap_or_default();
    let status = if status.is_empty() {
        summary["status"].as_str().unwrap_or("?").to_string()
    } else {
        status
    };
    let timings: serde_json::Value = std::fs::read_to_string(out.join("timings.json"))
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .unwrap_or_default();
    let counts = &summary["counts"];
    let (bodies, elems, pairs) = (
        counts["bodies"].as_u64().unwrap_or(0),
        counts["boundary_elements"].as_u64().unwrap_or(0),
        counts["interface_pairs"].as_u64().unwrap_or(0),
    );
    let t: Vec<f64> = STAGES
        .iter()
        .map(|s| timings["stages"][*s].as_f64().unwrap_or(f64::NAN))
        .collect();
    let solver = summary["contact"]["solver"]
        .as_str()
        .unwrap_or("-")
        .to_string();
    let iterations = summary["contact"]["iterations"].as_u64().unwrap_or(0);
    let mut line = format!("{label:>5} {size:>12} {bodies:>6} {elems:>6} {pairs:>6}");
    for v in &t {
        line += &format!(" {v:>10.3}");
    }
    println!("{line} {peak:>8.0} {solver:>7} {iterations:>6} {status}");
    let row = format!(
        "{label},{size},{bodies},{elems},{pairs},{},{peak:.1},{solver},{iterations},{status}\n",
        t.iter()
            .map(|v| v.to_string())
            .collect::<Vec<_>>()
            .join(",")
    );
    (row, bodies as f64, t[STAGES.len() - 1], peak)
}

fn sizes(var: &str, default: &[&str]) -> Vec<String> {
    std::env::var(var)
        .ok()
        .map(|v| v.split(',').map(|x| x.trim().to_string()).collect())
        .unwrap_or_else(|| default.iter().map(|s| s.to_string()).collect())
}

fn exponents(label: &str, xs: &[f64], totals: &[f64], peaks: &[f64]) {
    let ok: Vec<usize> = (0..xs.len())
        .filter(|&i| totals[i].is_finite() && xs[i] > 0.0)
        .collect();
    if ok.len() >= 2 {
        let pick = |v: &[f64]| ok.iter().map(|&i| v[i]).collect::<Vec<_>>();
        println!(
            "{label}: fitted exponents against the number of bodies: total time p = {:.2}, \
             peak memory p = {:.2}",
            fit(&pick(xs), &pick(totals)),
            fit(&pick(xs), &pick(peaks))
        );
    }
}

/// One series of walls, `(label, scene, variable)`: the scene run at each size of `variable`
/// (or `default`), `COURSESxBRICKS` optionally with `:final` (history = "final"), with the
/// `--set` values `sets` besides; prints the fitted exponents and returns the CSV rows.
fn walls(
    (label, scene, var): (&str, &str, &str),
    default: &[&str],
    sets: &[&str],
    dir: &Path,
) -> String {
    let scene = root().join(scene);
    let (mut csv, mut xs, mut totals, mut peaks) = (String::new(), vec![], vec![], vec![]);
    for size in sizes(var, default) {
        let (dims, history) = size.split_once(':').unwrap_or((&size, "full"));
        let (c, b) = dims.split_once('x').unwrap_or((dims, "1"));
        let out = dir.join(format!("{label}{dims}{history}"));
        let mut all = vec![format!("mesh.courses={c}"), format!("mesh.bricks={b}")];
        all.extend(sets.iter().map(|x| x.to_string()));
        if history != "full" {
            all.push(format!("output.history=\"{history}\""));
        }
        let args: Vec<String> = all
            .into_iter()
            .flat_map(|x| ["--set".to_string(), x])
            .collect();
        let (row, n, t, p) = one(label, &size, &scene, &args, &out);
        csv += &row;
        xs.push(n);
        totals.push(t);
        peaks.push(p);
    }
    exponents(label, &xs, &totals, &peaks);
    // The sparse solver's range alone (over 3000 unilateral pairs: 14 x 14 on).
    let big: Vec<usize> = (0..xs.len()).filter(|&i| xs[i] >= 200.0).collect();
    let pick = |v: &[f64]| big.iter().map(|&i| v[i]).collect::<Vec<_>>();
    exponents(
        &format!("{label}, 200 bodies and more"),
        &pick(&xs),
        &pick(&totals),
        &pick(&peaks),
    );
    csv
}

fn main() {
    let dir = tmpdir("bench-masonry");
    println!(
        "sgbem whole runs with default outputs, {} threads; seconds per stage, peak memory in \
         MB",
        rayon::current_num_threads()
    );
    let mut header = format!(
        "{:>5} {:>12} {:>6} {:>6} {:>6}",
        "", "size", "bodies", "elems", "pairs"
    );
    for s in STAGES {
        header += &format!(" {s:>10}");
    }
    println!(
        "{header} {:>8} {:>7} {:>6} status",
        "peak", "solver", "iters"
    );
    let mut csv = format!(
        "series,size,bodies,elements,pairs,{},peak_mb,solver,iterations,status\n",
        STAGES.map(|s| format!("{s}_s")).join(",")
    );

    // Arches: pipelines/arch.toml on geo/arch.geo (t/R = 0.12, 6 elements per joint,
    // self-weight, stick), nv voussoirs and two abutments.
    let scene = root().join("pipelines/arch.toml");
    let (mut xs, mut totals, mut peaks) = (Vec::new(), Vec::new(), Vec::new());
    for nv in sizes("SGBEM_BENCH_VOUSSOIRS", &["6", "12", "25", "50", "100"]) {
        let msh = gmsh(
            &root().join("geo/arch.geo"),
            &dir,
            &format!("arch{nv}.msh"),
            false,
            &["-setnumber", "nv", &nv],
        );
        let out = dir.join(format!("arch{nv}"));
        let args = vec!["--mesh".to_string(), msh.display().to_string()];
        let (row, b, t, p) = one("arch", &nv, &scene, &args, &out);
        csv += &row;
        xs.push(b);
        totals.push(t);
        peaks.push(p);
    }
    exponents("arch", &xs, &totals, &peaks);

    // Running-bond walls: pipelines/wall_running_bond.toml (geo/wall.geo, 6 elements per
    // course height, self-weight and wind, friction 0.7), COURSESxBRICKS. Walls of over 3000
    // unilateral pairs (14 x 14 on) are solved by the sparse solver, the smaller ones by the
    // full rows (their joints meet at T-junctions), as a scene without `method` is; 28 x 28 (798 bodies), 45 x 45 (2 048) and 64 x 64 (4 128: about 85 s and
    // 7.7 GB) with the final state only.
    csv += &walls(
        (
            "wall",
            "pipelines/wall_running_bond.toml",
            "SGBEM_BENCH_WALLS",
        ),
        &[
            "2x3",
            "4x5",
            "6x8",
            "10x10",
            "14x14",
            "20x20",
            "28x28:final",
            "45x45:final",
            "64x64:final",
        ],
        &[],
        &dir,
    );
    // The same walls drawn brick by brick (pipelines/wall_drawn.toml: geo/wall_drawn.geo on
    // its foundation, [contact] finds the joints), 6 elements per course height, without
    // VTK files (45 x 45: about 4 min and 6.6 GB on a busy machine).
    csv += &walls(
        ("drawn", "pipelines/wall_drawn.toml", "SGBEM_BENCH_DRAWN"),
        &["10x10", "20x20:final", "28x28:final", "45x45:final"],
        &["mesh.nj=6", "output.vtk=false"],
        &dir,
    );

    let out = std::path::Path::new("out/bench");
    std::fs::create_dir_all(out).expect("out/bench");
    std::fs::write(out.join("masonry.csv"), csv).expect("write masonry.csv");
}
