//! The `sgbem` command line: a thin front over the pipeline.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{CommandFactory, Parser, Subcommand, ValueEnum};

use sgbem::error::Error;
use sgbem::input::scene::Method;
use sgbem::{pipeline, report};

mod guard;
use guard::{allocation_failed, LARGE};

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
    Sparse,
    Exact,
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
        /// Mesh a `.geo` even if it runs programs (gmsh's SystemCall, OnelabRun): only
        /// for a .geo you have read and trust.
        #[arg(long)]
        allow_geo_shell: bool,
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
        /// Contact solver, as `run --method`: the plan and cost of that run.
        #[arg(long, value_enum)]
        method: Option<MethodArg>,
        /// Print the report as JSON (bodies, boundary parts, interfaces, plan, cost) instead
        /// of text.
        #[arg(long)]
        json: bool,
        /// Mesh a `.geo` even if it runs programs (gmsh's SystemCall, OnelabRun): only
        /// for a .geo you have read and trust.
        #[arg(long)]
        allow_geo_shell: bool,
    },
    /// Run a scene for every combination of values and tabulate the headline results.
    Sweep {
        /// The scene file (TOML); not with `--file`, whose `scene` it is.
        #[arg(required_unless_present = "file", conflicts_with = "file")]
        scene: Option<PathBuf>,
        /// A sweep file (TOML: `scene`, `set`, and optionally `out`, `columns`, `parts`,
        /// `allow_geo_shell`; paths relative to the file). The options given with it
        /// override the file's: `--out` and `--columns` replace its own, a `--set` replaces
        /// the file's entry for the same key (or adds a key), `--parts` and
        /// `--allow-geo-shell` turn on.
        #[arg(long, value_name = "FILE")]
        file: Option<PathBuf>,
        /// A swept key and its values, e.g. `--set interface.joint.cohesion=0,1,2`
        /// (repeatable: every combination runs; `*` matches every key of a table, e.g.
        /// `interface.*.cohesion`; a single value is a plain override).
        #[arg(
            long = "set",
            value_name = "KEY=V1,V2,...",
            required_unless_present = "file"
        )]
        set: Vec<String>,
        /// Runs at a time.
        #[arg(long, default_value_t = 1)]
        jobs: usize,
        /// Folder for the runs (one sub-folder per point, named from key=value) and
        /// sweep.csv / sweep.md (with `--file`: the file's `out`, else out/<file name>).
        #[arg(long, required_unless_present = "file")]
        out: Option<PathBuf>,
        /// Mesh a `.geo` even if it runs programs (gmsh's SystemCall, OnelabRun): only
        /// for a .geo you have read and trust.
        #[arg(long)]
        allow_geo_shell: bool,
        /// Print the points (number from 1, run folder, `--set` arguments; tab separated)
        /// and run nothing.
        #[arg(long, conflicts_with_all = ["point", "table"])]
        list: bool,
        /// Run point K (from 1) alone, e.g. `--point $SLURM_ARRAY_TASK_ID` in a job array;
        /// no table (see `--table`).
        #[arg(long, value_name = "K", conflicts_with = "table")]
        point: Option<usize>,
        /// Tabulate the point folders already written (after a job array) into sweep.csv and
        /// sweep.md, running nothing; exit_code is 0 for a converged run, 3 otherwise.
        #[arg(long)]
        table: bool,
        /// The figures tabulated per interface, e.g. `--columns
        /// detached_length,slip_length,tangential_resultant` (default
        /// detached_length,normal_resultant): any key of an interface in summary.json.
        #[arg(long, value_name = "K1,K2,...")]
        columns: Option<String>,
        /// Tabulate each part of a Physical Curve split per pair of bodies, not the curve's
        /// totals.
        #[arg(long)]
        parts: bool,
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
    /// Print a shell completion script, e.g. `sgbem completions bash >
    /// ~/.local/share/bash-completion/completions/sgbem`.
    Completions {
        /// The shell.
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
    /// Print the manual page (roff), e.g. `sgbem man > sgbem.1; man -l sgbem.1` (`make man`
    /// writes target/sgbem.1).
    Man,
    /// Print the JSON Schema of a scene file, for editors that check TOML against one, e.g.
    /// `sgbem schema > sgbem-scene.schema.json` and `#:schema ./sgbem-scene.schema.json` as
    /// the scene's first line (Taplo, Even Better TOML).
    Schema,
}

/// Environment variable that marks the child process reading an archive.
const ARCHIVE_WORKER: &str = "SGBEM_ARCHIVE_WORKER";

/// Writes to stdout. A closed pipe (`| head -1`) ends the output quietly; any other failure
/// (a full device) is an I/O error.
fn out(text: &str) -> Result<(), Error> {
    let mut o = std::io::stdout().lock();
    match o.write_all(text.as_bytes()).and_then(|()| o.flush()) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        Err(e) => Err(Error::io("standard output", format!("cannot write: {e}"))),
    }
}

/// Writes a line to stderr; a stderr that cannot be written is ignored (nothing else can
/// be told).
fn err_line(text: &str) {
    let _ = writeln!(std::io::stderr().lock(), "{text}");
}

/// Seconds the reader of an archive of `bytes` may take: 10 s and 0.1 s per MB (whole
/// archives are read at about 300 MB/s: `export` of a 24 MB archive takes 0.08 s), at most
/// 300 s.
fn archive_time_bound(bytes: u64) -> f64 {
    (10.0 + 0.1 * bytes as f64 / 1e6).min(300.0)
}

/// Runs `inspect` or `export` in a child process bounded in time (in proportion to the
/// archive's size, or `SGBEM_ARCHIVE_TIMEOUT`), so that a damaged archive that crashes or
/// hangs the HDF5 library ends in a message, not a crash.
fn archive_in_child(archive: &std::path::Path) -> Result<u8, Error> {
    let exe = std::env::current_exe().map_err(|e| Error::io("sgbem", e))?;
    let size = std::fs::metadata(archive).map_or(0, |m| m.len());
    let limit = std::env::var("SGBEM_ARCHIVE_TIMEOUT")
        .ok()
        .and_then(|v| v.trim().parse::<f64>().ok())
        .filter(|v| v.is_finite() && *v > 0.0)
        .unwrap_or_else(|| archive_time_bound(size));
    let mut child = std::process::Command::new(exe)
        .args(std::env::args_os().skip(1))
        .env(ARCHIVE_WORKER, "1")
        .spawn()
        .map_err(|e| Error::io(archive, format!("cannot start the reader: {e}")))?;
    let start = std::time::Instant::now();
    let damaged = |why: &str| {
        Error::io(
            archive,
            format!(
                "the archive is damaged ({why}): it is not a whole archive written by \
                 `sgbem run`; run the scene again to write it anew"
            ),
        )
    };
    loop {
        match child.try_wait() {
            Ok(Some(status)) => {
                return match status.code() {
                    Some(c) => Ok(u8::try_from(c).unwrap_or(1)),
                    None => Err(damaged("reading it crashed the HDF5 library")),
                };
            }
            Ok(None) => {}
            Err(e) => {
                return Err(Error::io(
                    archive,
                    format!("cannot wait for the reader: {e}"),
                ))
            }
        }
        if start.elapsed().as_secs_f64() > limit {
            let _ = child.kill();
            let _ = child.wait();
            return Err(damaged(&format!("reading it did not end within {limit} s")));
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

/// A panic that says the system refused a resource (a failed allocation reported by a
/// library, a thread that could not start) is the same out-of-memory end: a message and
/// exit 1. Any other panic keeps the default report.
fn install_resource_hook() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let text = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        let words = [
            "AllocError",
            "failed to spawn",
            "os error 12",
            "Cannot allocate memory",
        ];
        if words.iter().any(|w| text.contains(w)) {
            allocation_failed(LARGE);
        }
        default(info);
    }));
}

fn main() -> ExitCode {
    install_resource_hook();
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            // Help and version go to stdout; a closed or full stream must not panic.
            let code = if e.use_stderr() { 2 } else { 0 };
            let text = e.render().to_string();
            if e.use_stderr() {
                err_line(text.trim_end());
            } else if let Err(e) = out(&text) {
                err_line(&format!("sgbem: {e}"));
                return ExitCode::from(1);
            }
            return ExitCode::from(code);
        }
    };
    if std::env::var_os(ARCHIVE_WORKER).is_none() {
        if let Command::Inspect { archive } | Command::Export { archive, .. } = &cli.command {
            return match archive_in_child(archive) {
                Ok(code) => ExitCode::from(code),
                Err(e) => fail(&e),
            };
        }
    }
    // A sweep ended by a signal: exit 130 after its table is written.
    let mut interrupted = false;
    let result = match cli.command {
        Command::Completions { shell } => {
            let mut script = Vec::new();
            clap_complete::generate(shell, &mut Cli::command(), "sgbem", &mut script);
            out(&String::from_utf8_lossy(&script))
        }
        Command::Man => out(&man_page(Cli::command())),
        Command::Schema => out(&format!("{:#}\n", sgbem::input::scene::schema::schema())),
        Command::Check {
            scene,
            mesh,
            set,
            method,
            json,
            allow_geo_shell,
        } => check_command(
            &scene,
            (mesh, set, method.map(method_of)),
            json,
            allow_geo_shell,
        ),
        Command::Run {
            scene,
            mesh,
            out: out_dir,
            method,
            quiet,
            set,
            allow_geo_shell,
        } => {
            sgbem::input::gmsh::allow_shell_commands(allow_geo_shell);
            let opts = pipeline::RunOptions {
                mesh,
                out: out_dir,
                method: method.map(method_of),
                quiet,
                sets: set,
            };
            pipeline::run(&scene, &opts).and_then(|r| {
                for n in &r.notes {
                    err_line(&format!("sgbem: note: {n}"));
                }
                if quiet {
                    Ok(())
                } else {
                    out(&format!("results in {}\n", r.out_dir.display()))
                }
            })
        }
        Command::Sweep {
            scene,
            file,
            set,
            jobs,
            out,
            allow_geo_shell,
            list,
            point,
            table,
            columns,
            parts,
        } => {
            let mode = match (list, point, table) {
                (true, _, _) => sgbem::sweep::Mode::List,
                (_, Some(k), _) => sgbem::sweep::Mode::Point(k),
                (_, _, true) => sgbem::sweep::Mode::Table,
                _ => sgbem::sweep::Mode::All,
            };
            let given = sgbem::sweep::file::Given {
                scene,
                sets: set,
                out,
                columns,
                parts,
                allow_geo_shell,
            };
            sweep_command(file.as_deref(), given, jobs, mode, &mut interrupted)
        }
        Command::Inspect { archive } => {
            sgbem::output::archive::inspect(&archive).and_then(|text| out(&text))
        }
        Command::Export { archive, vtk } => {
            sgbem::output::vtk::export(&archive, &vtk).and_then(|files| {
                out(&format!(
                    "{} VTK files written to {}\n",
                    files.len(),
                    vtk.display()
                ))
            })
        }
    };
    match result {
        Ok(()) if interrupted => ExitCode::from(130),
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => fail(&e),
    }
}

/// Reports an error on stderr; its kind decides the exit status.
fn fail(e: &Error) -> ExitCode {
    err_line(&format!("sgbem: {e}"));
    ExitCode::from(e.exit_code() as u8)
}

/// The scene's contact method of a `--method` argument.
fn method_of(m: MethodArg) -> Method {
    match m {
        MethodArg::Lcp => Method::Lcp,
        MethodArg::Qp => Method::Qp,
        MethodArg::Both => Method::Both,
        MethodArg::Sparse => Method::Sparse,
        MethodArg::Exact => Method::Exact,
    }
}

/// `sgbem check`: reads and validates the scene as `run` would (with `--method` applied as
/// `run` applies it), prints the report (`json`: as JSON), and refuses what `run` would
/// refuse for memory or disk space (after the report, which shows the estimates), in the
/// same words; nothing computed.
fn check_command(
    scene: &std::path::Path,
    (mesh, sets, method): (Option<PathBuf>, Vec<String>, Option<Method>),
    json: bool,
    allow_geo_shell: bool,
) -> sgbem::error::Result<()> {
    sgbem::input::gmsh::allow_shell_commands(allow_geo_shell);
    // A .geo mesh is meshed into a temporary folder, removed afterwards.
    let tmp = sgbem::input::gmsh::Scratch::new("check");
    let loaded = pipeline::load_with(
        scene,
        &pipeline::LoadOptions {
            mesh,
            sets,
            mesh_dir: Some(tmp.path().to_path_buf()),
            method,
        },
    );
    // The report reads the mesh file's size (the outputs' estimate): the folder goes after
    // it.
    let printed = loaded.and_then(|mut l| {
        let on = l.scene.output.directory.clone();
        let fits = pipeline::check_resources(&mut l, scene, &on);
        out(&if json {
            let v = report::check_json(&l.scene, &l.model, &l.plan, l.mesh.binary);
            format!("{}\n", serde_json::to_string_pretty(&v).unwrap_or_default())
        } else {
            report::check_report(&l.scene, &l.model, &l.plan, l.mesh.binary)
        })?;
        fits
    });
    drop(tmp);
    printed
}

/// `sgbem sweep` of `given` (the command line, merged into the sweep file `file` if given)
/// in `mode`: the runs, the table, and the exit status of the sweep (130 when a signal ended
/// it, through `interrupted`).
fn sweep_command(
    file: Option<&std::path::Path>,
    given: sgbem::sweep::file::Given,
    jobs: usize,
    mode: sgbem::sweep::Mode,
    interrupted: &mut bool,
) -> sgbem::error::Result<()> {
    let given = match file {
        Some(f) => sgbem::sweep::file::read(f, given)?,
        None => given,
    };
    // The command line makes both present (clap's required_unless_present), a file both.
    let (Some(scene), Some(out)) = (&given.scene, &given.out) else {
        return Err(Error::input(
            "sgbem sweep",
            "give a SCENE with --set and --out, or a sweep file with --file",
        ));
    };
    let columns = sgbem::sweep::Columns::parse(given.columns.as_deref(), given.parts)
        .map_err(|m| Error::input(scene, m))?;
    let w = sgbem::sweep::sweep(
        scene,
        &given.sets,
        jobs,
        out,
        given.allow_geo_shell,
        mode,
        &columns,
    )?;
    match mode {
        sgbem::sweep::Mode::List => return Ok(()),
        sgbem::sweep::Mode::Point(k) => {
            println!("results in {}", w.table.display());
            if w.failed > 0 {
                return Err(sgbem::error::Error::numerical(format!(
                    "point {k} of the sweep did not converge or failed: see {}",
                    w.table.display()
                )));
            }
            return Ok(());
        }
        _ => {}
    }
    println!("sweep table in {}", w.table.display());
    if w.interrupted {
        err_line(&format!(
            "sgbem: interrupted: the sweep ended its runs; {} lists the points that finished",
            w.table.display()
        ));
        *interrupted = true;
        return Ok(());
    }
    if w.failed > 0 {
        Err(sgbem::error::Error::numerical(format!(
            "{} point(s) of the sweep failed: see the exit_code and status columns of {}",
            w.failed,
            w.table.display()
        )))
    } else {
        Ok(())
    }
}

/// Text for roff: backslashes and hyphens escaped, a leading `.` or `'` made literal.
fn roff(text: &str) -> String {
    let t = text.replace('\\', "\\e").replace('-', "\\-");
    t.lines()
        .map(|l| {
            if l.starts_with('.') || l.starts_with('\'') {
                format!("\\&{l}")
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The manual page of `cmd` (the command line's own help, as roff for `man`).
fn man_page(mut cmd: clap::Command) -> String {
    // Built, so that every argument knows how many values it takes.
    cmd.build();
    let about = |c: &clap::Command| {
        c.get_long_about()
            .or(c.get_about())
            .map(|a| roff(&a.to_string()))
            .unwrap_or_default()
    };
    let mut m = format!(
        ".TH SGBEM 1 \"\" \"sgbem {}\" \"User Commands\"\n.SH NAME\nsgbem \\- {}\n\
         .SH SYNOPSIS\n.B sgbem\n\\fICOMMAND\\fR [\\fIOPTIONS\\fR]\n.SH DESCRIPTION\n{}\n\
         .SH COMMANDS\n",
        env!("CARGO_PKG_VERSION"),
        roff(&cmd.get_about().map(|a| a.to_string()).unwrap_or_default()),
        about(&cmd)
    );
    for sub in cmd.get_subcommands().filter(|c| c.get_name() != "help") {
        m += &format!(".SS \"sgbem {}\"\n{}\n", sub.get_name(), about(sub));
        for arg in sub.get_arguments() {
            let id = arg.get_id().as_str();
            if id == "help" || id == "version" {
                continue;
            }
            let value = arg
                .get_value_names()
                .map(|v| {
                    v.iter()
                        .map(|n| n.to_string())
                        .collect::<Vec<_>>()
                        .join(" ")
                })
                .unwrap_or_else(|| id.to_uppercase());
            let head = match (arg.get_long(), arg.is_positional()) {
                (_, true) => format!("\\fI{}\\fR", roff(&value)),
                (Some(l), false) if arg.get_num_args().is_some_and(|n| n.takes_values()) => {
                    format!("\\fB\\-\\-{}\\fR \\fI{}\\fR", roff(l), roff(&value))
                }
                (Some(l), false) => format!("\\fB\\-\\-{}\\fR", roff(l)),
                (None, false) => continue,
            };
            let help = arg
                .get_long_help()
                .or(arg.get_help())
                .map(|h| roff(&h.to_string()))
                .unwrap_or_default();
            m += &format!(".TP\n{head}\n{help}\n");
        }
    }
    m += ".SH EXIT STATUS\n0 success; 2 invalid input (the message names the file, key, group or \
          element and the fix); 3 numerical failure (no equilibrium, not converged: every output \
          is written); 130 interrupted; 1 anything else (I/O).\n\
          .SH SEE ALSO\nThe README and docs/scene.md (every key of a scene) in the sources; \
          \\fBsgbem schema\\fR for editors.\n";
    m
}
