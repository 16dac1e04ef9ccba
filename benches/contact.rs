//! `make bench` (second part): the contact stage of every solver on the paper's examples 1
//! (stick, frictionless, Coulomb friction μ = 0.6), 3 (stick, friction) and 2 with its joint
//! refined (104 / 208 / 416 / 832 elements), with the peak memory of each case and the outer
//! iterations (brittle cohesion, stick ties, the Tresca fixed point of friction). Writes out/bench/contact.csv and prints a table.
//!
//! Each solver runs on the same prepared bodies and the same problem (columns of the opening
//! stiffness computed once per run and shared, as in `sgbem run`): `lcp` is the evolutive
//! path with every state recorded (compact; expanding the states into body fields is timed
//! apart as `record`), then the active set, Lemke and the QP from the scene's start.

#[path = "../tests/support/mod.rs"]
mod support;

use std::time::Instant;

use sgbem::bem::prepare;
use sgbem::bem::quadrature::QuadratureSettings;
use sgbem::contact::{Session, Solver};
use sgbem::pipeline::load;
use support::*;

fn main() {
    let mut cases: Vec<(String, &str, &str, Vec<String>)> = vec![
        (
            "example 1 (stick)".into(),
            "geo/beam_on_blocks.geo",
            "pipelines/beam_on_blocks.toml",
            vec![],
        ),
        (
            "example 1 (slide)".into(),
            "geo/beam_on_blocks.geo",
            "pipelines/beam_on_blocks_slide.toml",
            vec![],
        ),
        (
            "example 1 (friction 0.6)".into(),
            "geo/beam_on_blocks.geo",
            "pipelines/beam_on_blocks_friction.toml",
            vec![],
        ),
        (
            "example 3 (stick)".into(),
            "geo/vault.geo",
            "pipelines/vault_c0.toml",
            vec![],
        ),
        (
            "example 3 (friction 0.6)".into(),
            "geo/vault.geo",
            "pipelines/vault_friction.toml",
            vec![],
        ),
    ];
    let sizes: Vec<usize> = std::env::var("SGBEM_BENCH_JOINTS")
        .ok()
        .map(|v| v.split(',').filter_map(|x| x.trim().parse().ok()).collect())
        .unwrap_or_else(|| vec![104, 208, 416, 832]);
    for n in sizes {
        cases.push((
            format!("example 2, {n} joint el."),
            "geo/clamped_beam_joint.geo",
            "pipelines/clamped_beam_joint.toml",
            vec!["-setnumber".into(), "n_joint".into(), n.to_string()],
        ));
    }
    let dir = tmpdir("bench-contact");
    let q = QuadratureSettings::standard();
    println!(
        "sgbem contact solvers ({} threads), seconds; peak memory of the case in MB",
        rayon::current_num_threads()
    );
    println!(
        "{:<26} {:>5} {:>8} {:>8} {:>7} {:>5} {:>7} {:>7} {:>7} {:>7} {:>7} {:>6} {:>9} {:>7}",
        "case",
        "pairs",
        "prepare",
        "system",
        "lcp",
        "outer",
        "record",
        "act.set",
        "lemke",
        "qp",
        "switch",
        "differ",
        "detached",
        "peak"
    );
    let mut csv = String::from(
        "case,pairs,prepare_s,interface_system_s,lcp_s,outer_iterations,record_s,active_set_s,lemke_s,qp_s,lcp_switches,differing_pairs,detached_length,peak_mb\n",
    );
    for (name, geo, scene, opts) in cases {
        let o: Vec<&str> = opts.iter().map(|s| s.as_str()).collect();
        let msh = gmsh(&root().join(geo), &dir, "m.msh", false, &o);
        let l = load(&root().join(scene), Some(&msh)).expect("scene loads");
        reset_peak();
        let t = Instant::now();
        let prep =
            prepare(&l.model, l.scene.plane, &q, 1.0, &l.scene.path, &|_| {}).expect("prepare");
        let t_prep = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let mut s = Session::new(&l.model, &prep).expect("interface system");
        let t_sys = t.elapsed().as_secs_f64();
        let start = s.initial();
        let f = *l.scene.solve.load_factors.last().expect("a load factor");
        let t = Instant::now();
        let mut e = s.solve_step(&start, Solver::Evolutive, 1e-10, 100000, 0, f, true);
        let t_lcp = t.elapsed().as_secs_f64();
        let t = Instant::now();
        s.expand(&mut e);
        let t_rec = t.elapsed().as_secs_f64();
        let mut times = Vec::new();
        let mut differ = 0;
        for m in [Solver::ActiveSet, Solver::Lemke, Solver::Qp] {
            let t = Instant::now();
            let r = s.solve_step(&start, m, 1e-10, 100000, 0, f, false);
            times.push(t.elapsed().as_secs_f64());
            differ += sgbem::contact::differing_pairs(&r.interfaces, &e.interfaces);
            assert!(
                r.converged,
                "{name} {m:?}: {:?}",
                r.failure.as_ref().map(|x| x.message())
            );
        }
        let det: f64 = (0..l.model.interfaces.len())
            .map(|k| sgbem::contact::detached_length(&l.model, k, &e.interfaces[k]))
            .sum();
        let peak = peak_kb() as f64 / 1024.0;
        println!(
            "{:<26} {:>5} {:>8.3} {:>8.3} {:>7.3} {:>5} {:>7.3} {:>7.3} {:>7.3} {:>7.3} {:>7} {:>6} {:>9.4} {:>7.0}",
            name,
            l.model.pair_count(),
            t_prep,
            t_sys,
            t_lcp,
            e.outer_iterations,
            t_rec,
            times[0],
            times[1],
            times[2],
            e.iterations,
            differ,
            det,
            peak
        );
        csv += &format!(
            "{name},{},{t_prep},{t_sys},{t_lcp},{},{t_rec},{},{},{},{},{differ},{det},{peak}\n",
            l.model.pair_count(),
            e.outer_iterations,
            times[0],
            times[1],
            times[2],
            e.iterations
        );
    }
    println!("paper (Karnak.sGbem + MATLAB): example 1 LCP 237.7 s, QP 4.3 s; example 2 LCP 984.4 s, QP 16.2 s");
    let out = std::path::Path::new("out/bench");
    std::fs::create_dir_all(out).expect("out/bench");
    std::fs::write(out.join("contact.csv"), csv).expect("write contact.csv");
}
