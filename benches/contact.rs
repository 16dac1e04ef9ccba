//! `make bench` (second part): each contact solver's time on the paper's examples 1 and 2
//! and on example 2 refined four times, beside the paper's CPU times (LCP 237.7 s and
//! 984.4 s; QP 4.3 s and 16.2 s). Writes out/bench/contact.csv and prints a table.

#[path = "../tests/support/mod.rs"]
mod support;

use sgbem::bem::quadrature::QuadratureSettings;
use sgbem::pipeline::{load, solve_loaded, Timings};
use support::*;

fn main() {
    let cases: [(&str, &str, &str, &[&str]); 4] = [
        (
            "example 1 (stick)",
            "geo/beam_on_blocks.geo",
            "pipelines/beam_on_blocks.toml",
            &[],
        ),
        (
            "example 1 (slide)",
            "geo/beam_on_blocks.geo",
            "pipelines/beam_on_blocks_slide.toml",
            &[],
        ),
        (
            "example 2",
            "geo/clamped_beam_joint.geo",
            "pipelines/clamped_beam_joint.toml",
            &[],
        ),
        (
            "example 2, 4x refined",
            "geo/clamped_beam_joint.geo",
            "pipelines/clamped_beam_joint.toml",
            &["-setnumber", "h", "1", "-setnumber", "n_joint", "416"],
        ),
    ];
    let dir = tmpdir("bench-contact");
    let q = QuadratureSettings::standard();
    println!(
        "sgbem contact solvers ({} threads), seconds",
        rayon::current_num_threads()
    );
    println!(
        "{:<24} {:>6} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>10}",
        "case", "pairs", "assemble", "condense", "lcp", "act.set", "qp", "total", "detached"
    );
    let mut csv = String::from(
        "case,elements,pairs,assemble_s,condense_s,contact_lcp_s,contact_active_set_s,contact_qp_s,total_s,lcp_iterations,detached_length\n",
    );
    for (name, geo, scene, opts) in cases {
        let msh = gmsh(&root().join(geo), &dir, "m.msh", false, opts);
        let mut l = load(&root().join(scene), Some(&msh)).expect("scene loads");
        l.scene.solve.method = sgbem::input::scene::Method::Both;
        let mut t = Timings::default();
        let (_, r) = solve_loaded(&l, &q, &mut t).expect("solve");
        let get = |k: &str| {
            t.0.iter()
                .find(|(s, _)| *s == k)
                .map(|p| p.1)
                .unwrap_or(0.0)
        };
        let total: f64 = t.0.iter().map(|p| p.1).sum();
        let det: f64 = l
            .model
            .interfaces
            .iter()
            .zip(&r.interfaces)
            .map(|(it, ir)| {
                sgbem::output::summary::interface_figures(it, ir, 1.0)["detached_length"]
                    .as_f64()
                    .unwrap_or(0.0)
            })
            .sum();
        println!(
            "{:<24} {:>6} {:>9.3} {:>9.3} {:>9.3} {:>9.3} {:>9.3} {:>9.3} {:>10.4}",
            name,
            l.model.pair_count(),
            get("assemble"),
            get("condense"),
            get("contact_lcp"),
            get("contact_active_set"),
            get("contact_qp"),
            total,
            det
        );
        csv += &format!(
            "{name},{},{},{},{},{},{},{},{total},{},{det}\n",
            l.model.element_count(),
            l.model.pair_count(),
            get("assemble"),
            get("condense"),
            get("contact_lcp"),
            get("contact_active_set"),
            get("contact_qp"),
            r.contact["iterations"]
        );
    }
    println!("paper (Karnak.sGbem + MATLAB): example 1 LCP 237.7 s, QP 4.3 s; example 2 LCP 984.4 s, QP 16.2 s");
    let out = std::path::Path::new("out/bench");
    std::fs::create_dir_all(out).expect("out/bench");
    std::fs::write(out.join("contact.csv"), csv).expect("write contact.csv");
}
