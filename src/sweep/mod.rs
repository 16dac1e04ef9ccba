//! `sgbem sweep`: one run per point of a parameter grid, in child processes, and a table
//! of headline results (`sweep.csv`, `sweep.md`).
//!
//! Place in the flow: above the pipeline; each point is `sgbem run SCENE --set ... --out
//! DIR/<point> --quiet`, so that a point that fails (exit 3) leaves the others alone.
//!
//! Point folders have unique names (values that clean to the same text get `~2`, `~3`), of
//! at most 160 characters (each value's first 40).
//! A lock (`.DIR.lock`, flock) refuses a second sweep into the same folder. The children
//! run in process groups of their own and end with the sweep: SIGINT or SIGTERM to the
//! sweep ends them (SIGTERM to each group), writes the table of the points that finished
//! and exits 130; SIGKILL to the sweep ends them through the kernel (parent-death signal).
//! `DIR/.sgbem-sweep.json` lists the points a sweep wrote: a re-sweep removes the points of
//! the previous one that its grid no longer has (only the files their runs listed).
//!
//! Files: this one runs and tabulates; `file.rs` reads sweep files (`--file`).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicBool, Ordering};

use serde::Serialize;

use crate::error::{Error, Result};
use crate::input::scene;

pub mod file;

/// One swept key and its values (the text after `=`, split at top-level commas).
#[derive(Debug, Clone)]
pub struct Axis {
    pub key: String,
    pub values: Vec<String>,
}

/// Splits `KEY=V1,V2,...` at the commas outside brackets, braces and quotes.
pub fn parse_axis(set: &str) -> std::result::Result<Axis, String> {
    let whole = set;
    let set = &crate::input::scene::shown_set(set);
    let Some((key, values)) = whole.split_once('=') else {
        return Err(format!(
            "--set {set}: expected KEY=V1,V2,..., e.g. --set interface.joint.cohesion=0,1,2"
        ));
    };
    let mut out = Vec::new();
    let (mut depth, mut quote, mut cur) = (0i32, None::<char>, String::new());
    for ch in values.chars() {
        match (quote, ch) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), _) => {}
            (None, '"' | '\'') => quote = Some(ch),
            (None, '[' | '{') => depth += 1,
            (None, ']' | '}') => depth -= 1,
            (None, ',') if depth == 0 => {
                out.push(std::mem::take(&mut cur).trim().to_string());
                continue;
            }
            _ => {}
        }
        cur.push(ch);
    }
    out.push(cur.trim().to_string());
    if out.iter().any(String::is_empty) {
        return Err(format!("--set {set}: an empty value in the list"));
    }
    Ok(Axis {
        key: key.trim().to_string(),
        values: out,
    })
}

/// A point of the grid: its folder name (`label=value` joined by `_`) and its `--set
/// KEY=VALUE` list.
#[derive(Debug, Clone)]
pub struct Point {
    pub name: String,
    pub sets: Vec<String>,
    pub values: Vec<String>,
}

/// The folder-name label of a key: its last segment, or the whole key when two swept
/// keys share the last segment.
fn labels(axes: &[Axis]) -> Vec<String> {
    let last = |k: &str| k.rsplit('.').next().unwrap_or(k).to_string();
    axes.iter()
        .map(|a| {
            let l = last(&a.key);
            if axes.iter().filter(|b| last(&b.key) == l).count() > 1 {
                a.key.replace('*', "all")
            } else {
                l
            }
        })
        .collect()
}

/// The longest cleaned value in a point's folder name, and the longest name: a file name
/// has at most 255 bytes, and the run writes `.NAME.staging-PID` beside its folder.
const VALUE_CHARS: usize = 40;
const NAME_CHARS: usize = 160;

fn clean(v: &str) -> String {
    v.chars()
        .take(VALUE_CHARS)
        .map(|c| {
            if c.is_ascii_alphanumeric() || "._+-".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// The grid: every combination of the axes' values, the first axis varying slowest.
pub fn points(axes: &[Axis]) -> Vec<Point> {
    let labels = labels(axes);
    let mut pts = vec![Point {
        name: String::new(),
        sets: Vec::new(),
        values: Vec::new(),
    }];
    for (a, label) in axes.iter().zip(&labels) {
        let mut next = Vec::new();
        for p in &pts {
            for v in &a.values {
                let mut q = p.clone();
                if !q.name.is_empty() {
                    q.name.push('_');
                }
                q.name += &format!("{label}={}", clean(v));
                q.sets.push(format!("{}={v}", a.key));
                q.values.push(v.clone());
                next.push(q);
            }
        }
        pts = next;
    }
    // Distinct values may clean to the same text (`α`, `β` → `_`, long values cut to their
    // start): number the repeats (`~` is never in a cleaned value, so the names stay
    // distinct).
    let mut seen = std::collections::HashMap::new();
    for p in &mut pts {
        if p.name.len() > NAME_CHARS {
            // Cleaned names are ASCII: any byte is a character boundary.
            p.name.truncate(NAME_CHARS);
        }
        let n = seen.entry(p.name.clone()).or_insert(0usize);
        *n += 1;
        if *n > 1 {
            p.name = format!("{}~{n}", p.name);
        }
    }
    pts
}

/// What a sweep did: the table's path, the points that failed, and whether a signal
/// ended it before every point ran.
pub struct Swept {
    pub table: PathBuf,
    pub failed: usize,
    pub interrupted: bool,
}

/// Set by SIGINT or SIGTERM: the sweep ends its children and writes what finished.
static STOP: AtomicBool = AtomicBool::new(false);

unsafe extern "C" {
    fn kill(pid: i32, sig: i32) -> i32;
    fn prctl(option: i32, ...) -> i32;
}

const SIGTERM: i32 = 15;
const PR_SET_PDEATHSIG: i32 = 1;

/// What `sgbem sweep` does with its points.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Run every point `jobs` at a time and tabulate them.
    All,
    /// Print the points (number, folder, `--set` arguments) and run nothing.
    List,
    /// Run point K (from 1) alone, e.g. one task of a SLURM job array; no table.
    Point(usize),
    /// Tabulate the point folders already written (after a job array), run nothing.
    Table,
}

/// Runs the sweep: validates every point's scene first (exit 2 before any run), then runs
/// the points `jobs` at a time and writes `out/sweep.csv` and `out/sweep.md` (`Mode::All`),
/// or one point, the list or the table alone (`mode`).
pub fn sweep(
    scene_path: &Path,
    sets: &[String],
    jobs: usize,
    out: &Path,
    allow_geo_shell: bool,
    mode: Mode,
    columns: &Columns,
) -> Result<Swept> {
    if !scene_path.is_file() {
        return Err(Error::input(
            scene_path,
            "no such scene file: give the path of a .toml scene",
        ));
    }
    let axes: Vec<Axis> = sets
        .iter()
        .map(|s| parse_axis(s).map_err(|m| Error::input(scene_path, m)))
        .collect::<Result<_>>()?;
    if axes.is_empty() {
        return Err(Error::input(
            scene_path,
            "nothing to sweep: give at least one --set KEY=V1,V2,...",
        ));
    }
    let pts = points(&axes);
    crate::input::gmsh::allow_shell_commands(allow_geo_shell);
    for p in &pts {
        let sc = scene::read_scene_with(scene_path, &p.sets)?;
        if let Some(mesh) = sc.mesh.as_deref().filter(|m| crate::input::gmsh::is_geo(m)) {
            crate::input::gmsh::check_commands(mesh)?;
        }
    }
    // The table is written after every finished point, so that whatever ends the sweep
    // (even SIGKILL) leaves the results of the points that finished.
    let write = |codes: &[Option<i32>]| -> Result<(PathBuf, usize)> {
        let (csv, md, failed) = table(&axes, &pts, codes, out, columns);
        super::output::write_atomic(&out.join("sweep.md"), md.as_bytes())?;
        let path = out.join("sweep.csv");
        super::output::write_atomic(&path, csv.as_bytes())?;
        Ok((path, failed))
    };
    match mode {
        Mode::List => return Ok(list(&pts, out)),
        Mode::Point(k) => return one_point(scene_path, &pts, k, out, allow_geo_shell),
        Mode::Table => {
            if !out.is_dir() {
                return Err(Error::input(
                    out,
                    "no sweep folder here to tabulate: run its points first (--point K)",
                ));
            }
            let (table, failed) = write(&finished(&pts, out))?;
            return Ok(Swept {
                table,
                failed,
                interrupted: false,
            });
        }
        Mode::All => {}
    }
    // The lock beside the folder first: a refused sweep creates nothing.
    if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent)
            .map_err(|e| Error::io(parent, format!("cannot create the folder: {e}")))?;
    }
    let lock_path = crate::output::folder::beside(out, "lock");
    let _lock = crate::output::folder::Lock::take(&lock_path, out)?;
    if out.join(crate::output::owned::MARKER).exists() {
        return Err(Error::input(
            out,
            format!(
                "this is the folder of a run or an export (it holds {}): a sweep writes its \
                 points into a folder of its own, and the run's next rerun would refuse the \
                 folder then; give --out another folder",
                crate::output::owned::MARKER
            ),
        ));
    }
    std::fs::create_dir_all(out)
        .map_err(|e| Error::io(out, format!("cannot create the sweep folder: {e}")))?;
    let _ = ctrlc::set_handler(|| STOP.store(true, Ordering::SeqCst));
    remove_stale_points(out, &pts);
    let marker = SweepMarker {
        points: pts.iter().map(|p| p.name.as_str()).collect(),
        tool: "sgbem sweep",
    };
    let text = serde_json::to_string_pretty(&marker).unwrap_or_default();
    super::output::write_atomic(&out.join(SWEEP_MARKER), format!("{text}\n").as_bytes())?;
    let exe = std::env::current_exe()
        .map_err(|e| Error::io(scene_path, format!("cannot find the sgbem program: {e}")))?;
    let codes = run_points(&exe, scene_path, &pts, jobs, out, allow_geo_shell, &write)?;
    let (table, failed) = write(&codes)?;
    Ok(Swept {
        table,
        failed,
        interrupted: codes.iter().any(Option::is_none),
    })
}

/// `--list`: one line per point, its number (from 1), folder and `--set` arguments, tab
/// separated, on stdout.
fn list(pts: &[Point], out: &Path) -> Swept {
    for (k, p) in pts.iter().enumerate() {
        let sets: Vec<String> = p.sets.iter().map(|s| format!("--set '{s}'")).collect();
        println!(
            "{}\t{}\t{}",
            k + 1,
            out.join(&p.name).display(),
            sets.join(" ")
        );
    }
    Swept {
        table: PathBuf::new(),
        failed: 0,
        interrupted: false,
    }
}

/// `--point K`: runs point K (from 1) into its folder of the sweep, as `Mode::All` would,
/// without the sweep's lock or table (each run locks its own folder, so the tasks of a job
/// array run side by side); its exit code is the result's.
fn one_point(
    scene_path: &Path,
    pts: &[Point],
    k: usize,
    out: &Path,
    allow_geo_shell: bool,
) -> Result<Swept> {
    let Some(p) = k.checked_sub(1).and_then(|i| pts.get(i)) else {
        return Err(Error::input(
            scene_path,
            format!(
                "--point {k}: the sweep has points 1 to {}; `sgbem sweep ... --list` lists them",
                pts.len()
            ),
        ));
    };
    std::fs::create_dir_all(out)
        .map_err(|e| Error::io(out, format!("cannot create the sweep folder: {e}")))?;
    let exe = std::env::current_exe()
        .map_err(|e| Error::io(scene_path, format!("cannot find the sgbem program: {e}")))?;
    let mut cmd = run_command(&exe, scene_path, p, out, allow_geo_shell);
    eprintln!("sweep: point {k} of {}: {}", pts.len(), p.name);
    let status = cmd
        .status()
        .map_err(|e| Error::io(scene_path, format!("cannot start the run: {e}")))?;
    let code = status.code().unwrap_or(-1);
    Ok(Swept {
        table: out.join(&p.name),
        failed: usize::from(code != 0),
        interrupted: false,
    })
}

/// The `sgbem run` of point `p` into its folder of the sweep `out`.
fn run_command(
    exe: &Path,
    scene_path: &Path,
    p: &Point,
    out: &Path,
    allow_geo_shell: bool,
) -> Command {
    let mut cmd = Command::new(exe);
    cmd.arg("run").arg(scene_path);
    for s in &p.sets {
        cmd.arg("--set").arg(s);
    }
    cmd.arg("--out").arg(out.join(&p.name)).arg("--quiet");
    if allow_geo_shell {
        cmd.arg("--allow-geo-shell");
    }
    cmd
}

/// `--table`: the exit code of each point from the summary its run left (0 converged, 3
/// not converged), None where there is none (not run, or refused with exit 2).
fn finished(pts: &[Point], out: &Path) -> Vec<Option<i32>> {
    pts.iter()
        .map(|p| {
            let text = std::fs::read_to_string(out.join(&p.name).join("summary.json")).ok()?;
            let v: serde_json::Value = serde_json::from_str(&text).ok()?;
            Some(if v["status"] == "converged" { 0 } else { 3 })
        })
        .collect()
}

/// The list of the points a sweep wrote, in its folder.
const SWEEP_MARKER: &str = ".sgbem-sweep.json";

/// The sweep folder's marker [`SWEEP_MARKER`]: its points' folders, in point order; fields
/// in alphabetical order, the order of its keys as it has always been written.
#[derive(Serialize)]
struct SweepMarker<'a> {
    points: Vec<&'a str>,
    tool: &'static str,
}

/// Removes the point folders of the previous sweep into `out` that `pts` does not have:
/// only the entries their run's marker lists (a folder holding anything else keeps it).
fn remove_stale_points(out: &Path, pts: &[Point]) {
    let Ok(text) = std::fs::read_to_string(out.join(SWEEP_MARKER)) else {
        return;
    };
    let Ok(v) = serde_json::from_str::<serde_json::Value>(&text) else {
        return;
    };
    let old = v["points"].as_array().cloned().unwrap_or_default();
    for name in old.iter().filter_map(|n| n.as_str()) {
        // Only a plain folder name of this sweep folder.
        if name.is_empty() || name.contains('/') || name.starts_with('.') {
            continue;
        }
        if pts.iter().any(|p| p.name == name) {
            continue;
        }
        let dir = out.join(name);
        if let Ok(Some(o)) = crate::output::owned::owner(&dir) {
            if o.prefix.is_empty() {
                crate::output::owned::remove_listed(&dir, &o.entries);
            }
        }
    }
}

/// Runs the points `jobs` at a time; each point's exit code, None for a point that did not
/// finish (a signal ended the sweep).
#[allow(clippy::type_complexity)]
fn run_points(
    exe: &Path,
    scene_path: &Path,
    pts: &[Point],
    jobs: usize,
    out: &Path,
    allow_geo_shell: bool,
    write: &dyn Fn(&[Option<i32>]) -> Result<(PathBuf, usize)>,
) -> Result<Vec<Option<i32>>> {
    use std::os::unix::process::CommandExt;
    let jobs = jobs.max(1);
    // Each child gets its share of the cores, unless the caller chose.
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let threads = (cores / jobs).max(1).to_string();
    let parent = std::process::id();
    let mut codes = vec![None; pts.len()];
    let mut next = 0;
    let mut running: Vec<(usize, std::process::Child)> = Vec::new();
    while (next < pts.len() && !STOP.load(Ordering::SeqCst)) || !running.is_empty() {
        while running.len() < jobs && next < pts.len() && !STOP.load(Ordering::SeqCst) {
            let p = &pts[next];
            let mut cmd = run_command(exe, scene_path, p, out, allow_geo_shell);
            if std::env::var_os("RAYON_NUM_THREADS").is_none() {
                cmd.env("RAYON_NUM_THREADS", &threads);
            }
            // A process group of its own (the run and its gmsh end together), and SIGTERM
            // when the sweep dies, even by SIGKILL.
            cmd.process_group(0);
            // SAFETY: prctl and getppid are async-signal-safe; nothing is allocated.
            unsafe {
                cmd.pre_exec(move || {
                    prctl(PR_SET_PDEATHSIG, SIGTERM as std::ffi::c_ulong);
                    if std::os::unix::process::parent_id() != parent {
                        return Err(std::io::Error::other("the sweep ended"));
                    }
                    Ok(())
                });
            }
            eprintln!("sweep: {} of {}: {}", next + 1, pts.len(), p.name);
            let child = cmd
                .spawn()
                .map_err(|e| Error::io(exe, format!("cannot start a run: {e}")))?;
            running.push((next, child));
            next += 1;
        }
        if STOP.load(Ordering::SeqCst) {
            for (_, child) in &running {
                let pgid = i32::try_from(child.id()).unwrap_or(0);
                if pgid > 0 {
                    // SAFETY: a plain system call on the child's own process group.
                    unsafe { kill(-pgid, SIGTERM) };
                }
            }
            for (_, child) in &mut running {
                let _ = child.wait();
            }
            running.clear();
            eprintln!("sweep: interrupted: the points that finished are tabulated");
            break;
        }
        let mut finished = None;
        for (i, (k, child)) in running.iter_mut().enumerate() {
            if let Ok(Some(status)) = child.try_wait() {
                codes[*k] = Some(status.code().unwrap_or(-1));
                finished = Some(i);
                break;
            }
        }
        match finished {
            Some(i) => {
                running.remove(i);
                write(&codes)?;
            }
            None => std::thread::sleep(std::time::Duration::from_millis(50)),
        }
    }
    Ok(codes)
}

/// The figures of an interface that `--columns` can tabulate (its keys in summary.json).
pub(crate) const COLUMN_KEYS: [&str; 11] = [
    "closed_length",
    "detached_length",
    "max_accumulated_slip",
    "max_normal_traction",
    "min_normal_traction",
    "normal_resultant",
    "open_pairs",
    "pairs",
    "slip_length",
    "stick_length",
    "tangential_resultant",
];

/// What the table shows per interface: the figures `keys`, and for a Physical Curve split
/// per pair of bodies its parts (`parts`) or its totals (`interface_curves`, the default).
#[derive(Debug, Clone)]
pub struct Columns {
    pub keys: Vec<String>,
    pub parts: bool,
}

impl Columns {
    /// From `--columns K1,K2,...` (default the detached length and normal resultant).
    pub fn parse(list: Option<&str>, parts: bool) -> std::result::Result<Columns, String> {
        let keys: Vec<String> = match list {
            None => vec!["detached_length".into(), "normal_resultant".into()],
            Some(l) => l.split(',').map(|k| k.trim().to_string()).collect(),
        };
        for k in &keys {
            if !COLUMN_KEYS.contains(&k.as_str()) {
                return Err(format!(
                    "--columns: \"{k}\" is not a figure of an interface{}; valid: {}",
                    crate::error::did_you_mean(k, COLUMN_KEYS.iter().copied()),
                    COLUMN_KEYS.join(", ")
                ));
            }
        }
        Ok(Columns { keys, parts })
    }

    /// The unit of a figure from the summary's `units` (lengths L, resultants F, tractions
    /// F/L²), empty for counts or where the scene names no units.
    fn unit(key: &str, units: &serde_json::Value) -> String {
        let (l, f) = (units["length"].as_str(), units["force"].as_str());
        match (key, l, f) {
            ("open_pairs" | "pairs", _, _) => String::new(),
            (k, _, Some(f)) if k.ends_with("_resultant") => format!(" ({f})"),
            (k, Some(l), Some(f)) if k.ends_with("_traction") => format!(" ({f}/{l}²)"),
            (k, Some(l), _) if k.ends_with("_length") || k.ends_with("_slip") => {
                format!(" ({l})")
            }
            _ => String::new(),
        }
    }
}

/// The interfaces of the table, in the order of `s` (the first summary that has them):
/// each with the summary block it is read from. A split curve is one entry
/// (`interface_curves`) unless `parts`.
fn tabulated(s: &serde_json::Value, parts: bool) -> Vec<(String, &'static str)> {
    let mut names: Vec<(String, &'static str)> = Vec::new();
    let mut in_curve = std::collections::HashSet::new();
    if let (false, Some(curves)) = (parts, s["interface_curves"].as_object()) {
        for (curve, c) in curves {
            names.push((curve.clone(), "interface_curves"));
            for p in c["parts"].as_array().into_iter().flatten() {
                in_curve.insert(p.as_str().unwrap_or("").to_string());
            }
        }
    }
    if let Some(m) = s["interfaces"].as_object() {
        names.extend(
            m.keys()
                .filter(|n| !in_curve.contains(*n))
                .map(|n| (n.clone(), "interfaces")),
        );
    }
    names
}

/// The headline table: per point the swept values, exit code, status, contact iterations
/// and per interface (or split curve) the figures `columns` (from its summary.json); the
/// Markdown table's headers carry the units.
fn table(
    axes: &[Axis],
    pts: &[Point],
    codes: &[Option<i32>],
    out: &Path,
    columns: &Columns,
) -> (String, String, usize) {
    let summaries: Vec<Option<serde_json::Value>> = pts
        .iter()
        .zip(codes)
        .map(|(p, code)| {
            code.as_ref()?;
            std::fs::read_to_string(out.join(&p.name).join("summary.json"))
                .ok()
                .and_then(|t| serde_json::from_str(&t).ok())
        })
        .collect();
    let first = summaries.iter().flatten().next();
    let names = first.map_or_else(Vec::new, |s| tabulated(s, columns.parts));
    let units = first.map_or(serde_json::Value::Null, |s| s["units"].clone());
    let mut head: Vec<String> = vec!["point".into()];
    head.extend(axes.iter().map(|a| a.key.clone()));
    head.extend(["exit_code", "status", "contact_iterations"].map(String::from));
    let fixed = head.len();
    for (n, _) in &names {
        head.extend(columns.keys.iter().map(|k| format!("{n}.{k}")));
    }
    let width = columns.keys.len() * names.len();
    let mut rows = Vec::new();
    let mut failed = 0;
    for ((p, code), s) in pts.iter().zip(codes).zip(&summaries) {
        let mut row = vec![p.name.clone()];
        row.extend(p.values.iter().cloned());
        let Some(code) = *code else {
            // Not run yet, or ended with the sweep: no result of it is credited.
            row.push(String::new());
            row.push("not finished".into());
            row.extend(std::iter::repeat_n(String::new(), 1 + width));
            rows.push(row);
            continue;
        };
        if code != 0 {
            failed += 1;
        }
        row.push(code.to_string());
        let num = |v: &serde_json::Value| v.as_f64().map(|x| format!("{x}")).unwrap_or_default();
        match s {
            Some(s) => {
                row.push(s["status"].as_str().unwrap_or("").to_string());
                row.push(num(&s["contact"]["iterations"]));
                for (n, block) in &names {
                    row.extend(columns.keys.iter().map(|k| num(&s[*block][n][k])));
                }
            }
            None => {
                row.push("no summary".into());
                row.extend(std::iter::repeat_n(String::new(), 1 + width));
            }
        }
        rows.push(row);
    }
    // The Markdown headers with units.
    let mut md_head = head.clone();
    for (i, h) in md_head.iter_mut().enumerate().skip(fixed) {
        let key = &columns.keys[(i - fixed) % columns.keys.len()];
        h.push_str(&Columns::unit(key, &units));
    }
    let quote = |c: &String| {
        if c.contains([',', '"', '\n']) {
            format!("\"{}\"", c.replace('"', "\"\""))
        } else {
            c.clone()
        }
    };
    let mut csv = String::new();
    for r in std::iter::once(&head).chain(&rows) {
        let _ = writeln!(csv, "{}", r.iter().map(quote).collect::<Vec<_>>().join(","));
    }
    let mut md = String::new();
    let cell = |c: &String| c.replace('|', "\\|");
    let _ = writeln!(
        md,
        "| {} |",
        md_head.iter().map(cell).collect::<Vec<_>>().join(" | ")
    );
    let _ = writeln!(md, "|{}", "---|".repeat(head.len()));
    for r in &rows {
        let _ = writeln!(
            md,
            "| {} |",
            r.iter().map(cell).collect::<Vec<_>>().join(" | ")
        );
    }
    (csv, md, failed)
}
