//! The `sgbem` command line: a thin front over the pipeline.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand, ValueEnum};

use sgbem::input::scene::Method;
use sgbem::{pipeline, report};

#[derive(Parser)]
#[command(
    name = "sgbem",
    version,
    about = "Contact and detachment of 2D elastic bodies by the symmetric Galerkin BEM",
    long_about = "Contact and detachment of 2D elastic bodies by the symmetric Galerkin boundary \
                  element method.\n\nExit status: 0 success; 2 invalid input; 3 numerical \
                  failure; 1 anything else (I/O)."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Clone, Copy, ValueEnum)]
enum MethodArg {
    Lcp,
    Qp,
    Both,
}

#[derive(Subcommand)]
enum Command {
    /// Read, validate, solve and write all outputs.
    Run {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Mesh file (MSH 4.1); overrides the scene's `mesh`.
        #[arg(long)]
        mesh: Option<PathBuf>,
        /// Output directory; overrides the scene's `output.directory`.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Contact solver; overrides the scene's `solve.method`.
        #[arg(long, value_enum)]
        method: Option<MethodArg>,
        /// No progress bars.
        #[arg(long)]
        quiet: bool,
        /// Override a scene key: a dotted TOML path and a TOML value, e.g.
        /// `--set interface.joint.cohesion=2.0 --set solve.method=qp` (repeatable; validated
        /// like the file).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// Read and validate only; print the model and the plan.
    Check {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Mesh file (MSH 4.1); overrides the scene's `mesh`.
        #[arg(long)]
        mesh: Option<PathBuf>,
        /// Override a scene key: a dotted TOML path and a TOML value, e.g.
        /// `--set interface.joint.cohesion=2.0 --set solve.method=qp` (repeatable; validated
        /// like the file).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// Run a scene for every combination of values and tabulate the headline results.
    Sweep {
        /// The scene file (TOML).
        scene: PathBuf,
        /// A swept key and its values, e.g. `--set interface.joint.cohesion=0,1,2`
        /// (repeatable: every combination runs; `*` matches every key of a table, e.g.
        /// `interface.*.cohesion`; a single value is a plain override).
        #[arg(long = "set", value_name = "KEY=V1,V2,...", required = true)]
        set: Vec<String>,
        /// Runs at a time.
        #[arg(long, default_value_t = 1)]
        jobs: usize,
        /// Folder for the runs (one sub-folder per point, named from key=value) and
        /// sweep.csv / sweep.md.
        #[arg(long)]
        out: PathBuf,
    },
    /// Print what an archive holds.
    Inspect {
        /// An archive.h5 written by `sgbem run`.
        archive: PathBuf,
    },
    /// Write the VTK files again from an archive, without solving.
    Export {
        /// An archive.h5 written by `sgbem run`.
        archive: PathBuf,
        /// Directory for the VTK files.
        #[arg(long)]
        vtk: PathBuf,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Check { scene, mesh, set } => {
            // A .geo mesh is meshed into a temporary folder, removed afterwards.
            let tmp = std::env::temp_dir().join(format!("sgbem-check-{}", std::process::id()));
            let loaded = pipeline::load_with(
                &scene,
                &pipeline::LoadOptions {
                    mesh,
                    sets: set,
                    mesh_dir: Some(tmp.clone()),
                },
            );
            let _ = std::fs::remove_dir_all(&tmp);
            loaded.map(|l| {
                print!(
                    "{}",
                    report::check_report(&l.scene, &l.model, &l.plan, l.mesh.binary)
                );
            })
        }
        Command::Run {
            scene,
            mesh,
            out,
            method,
            quiet,
            set,
        } => {
            let opts = pipeline::RunOptions {
                mesh,
                out,
                method: method.map(|m| match m {
                    MethodArg::Lcp => Method::Lcp,
                    MethodArg::Qp => Method::Qp,
                    MethodArg::Both => Method::Both,
                }),
                quiet,
                sets: set,
            };
            pipeline::run(&scene, &opts).map(|r| {
                for n in &r.notes {
                    eprintln!("sgbem: note: {n}");
                }
                if !quiet {
                    println!("results in {}", r.out_dir.display());
                }
            })
        }
        Command::Sweep {
            scene,
            set,
            jobs,
            out,
        } => sgbem::sweep::sweep(&scene, &set, jobs, &out).and_then(|(table, failed)| {
            println!("sweep table in {}", table.display());
            if failed > 0 {
                Err(sgbem::error::Error::numerical(format!(
                    "{failed} point(s) of the sweep failed: see the exit_code and status \
                     columns of {}",
                    table.display()
                )))
            } else {
                Ok(())
            }
        }),
        Command::Inspect { archive } => {
            sgbem::output::archive::inspect(&archive).map(|text| print!("{text}"))
        }
        Command::Export { archive, vtk } => {
            sgbem::output::vtk::export(&archive, &vtk).map(|files| {
                println!("{} VTK files written to {}", files.len(), vtk.display());
            })
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("sgbem: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}
