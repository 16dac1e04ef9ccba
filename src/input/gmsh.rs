//! Meshing a `.geo` scene mesh with gmsh (`gmsh -2 -format msh41 [-setnumber P V ...]`).
//!
//! Place in the flow: before [`super::mesh::read_msh`], when the scene's `mesh` names a
//! `.geo`. The gmsh program is `$GMSH` or `gmsh` on the PATH.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicBool, Ordering};

use crate::error::{Error, Result};

/// Whether `path` names a gmsh geometry file (`.geo`).
pub(crate) fn is_geo(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("geo"))
}

/// Meshes `geo` into `dir/<stem>.msh` (MSH 4.1, 2D) with the given `-setnumber`
/// parameters (gmsh's log is not kept: it holds timings). Returns the mesh path. A missing
/// gmsh or a failing one is bad input (exit 2) with gmsh's message.
pub(crate) fn mesh_geo(geo: &Path, params: &[(String, f64)], dir: &Path) -> Result<PathBuf> {
    if !geo.is_file() {
        return Err(Error::input(
            geo,
            "no such .geo file: check the scene's `mesh`",
        ));
    }
    check_commands(geo)?;
    std::fs::create_dir_all(dir)
        .map_err(|e| Error::io(dir, format!("cannot create the mesh folder: {e}")))?;
    let stem = geo
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "mesh".into());
    let out = dir.join(format!("{stem}.msh"));
    let tmp = dir.join(format!(".{stem}.{}.tmp.msh", std::process::id()));
    let program = std::env::var_os("GMSH").unwrap_or_else(|| "gmsh".into());
    let mut cmd = Command::new(&program);
    cmd.arg("-2").arg("-format").arg("msh41");
    for (name, value) in params {
        cmd.arg("-setnumber").arg(name).arg(format!("{value}"));
    }
    cmd.arg(geo).arg("-o").arg(&tmp);
    let shown = format!(
        "{} -2 -format msh41{} {} -o {}",
        program.to_string_lossy(),
        params
            .iter()
            .map(|(n, v)| format!(" -setnumber {n} {v}"))
            .collect::<String>(),
        geo.display(),
        out.display()
    );
    let output = cmd.output().map_err(|e| {
        Error::input(
            geo,
            format!(
                "cannot run gmsh to mesh this .geo ({e}): install gmsh (apt-get install gmsh), \
                 set GMSH=/path/to/gmsh, or mesh it yourself and name the .msh in the scene"
            ),
        )
    })?;
    let log = [output.stdout.as_slice(), output.stderr.as_slice()].concat();
    // gmsh reports some errors with exit status 0: judge by its "Error" lines too.
    let text = String::from_utf8_lossy(&log);
    let mut errors: Vec<&str> = Vec::new();
    for l in text.lines().filter(|l| l.contains("Error")) {
        if !errors.contains(&l) && errors.len() < 5 {
            errors.push(l);
        }
    }
    if !output.status.success() || !errors.is_empty() || !tmp.is_file() {
        let _ = std::fs::remove_file(&tmp);
        let detail = if errors.is_empty() {
            text.lines().rev().take(5).collect::<Vec<_>>().join("\n  ")
        } else {
            errors.join("\n  ")
        };
        return Err(Error::input(
            geo,
            format!("gmsh failed to mesh this .geo ({shown}):\n  {detail}"),
        ));
    }
    std::fs::rename(&tmp, &out)
        .map_err(|e| Error::io(&out, format!("cannot write the mesh: {e}")))?;
    Ok(out)
}

/// A private folder under the system's temporary folder for meshing a `.geo` (so that a
/// mesh is never written into a folder before the tool knows it may write there), removed
/// with everything in it when dropped.
pub struct Scratch {
    path: PathBuf,
}

impl Scratch {
    /// `$TMPDIR/sgbem-WHAT-PID` (not created: gmsh meshing creates it).
    pub fn new(what: &str) -> Scratch {
        let path = std::env::temp_dir().join(format!("sgbem-{what}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&path);
        Scratch { path }
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.path);
    }
}

/// Whether a `.geo` may run commands (`--allow-geo-shell`).
static SHELL_ALLOWED: AtomicBool = AtomicBool::new(false);

/// Lets `.geo` files that run commands be meshed (the user allowed it explicitly).
pub fn allow_shell_commands(allowed: bool) {
    SHELL_ALLOWED.store(allowed, Ordering::Relaxed);
}

/// gmsh commands of a `.geo` that run other programs.
const COMMANDS: [&str; 2] = ["SystemCall", "OnelabRun"];

/// The text of a `.geo` without its comments (`// ...` and `/* ... */`), lines kept; with
/// `blank`, without the contents of its strings too.
fn without_comments(text: &str, blank: bool) -> String {
    let (mut out, mut chars) = (String::with_capacity(text.len()), text.chars().peekable());
    let (mut line, mut block, mut quoted) = (false, false, false);
    while let Some(c) = chars.next() {
        let next = chars.peek().copied();
        if line {
            if c == '\n' {
                line = false;
                out.push(c);
            }
        } else if block {
            if c == '*' && next == Some('/') {
                block = false;
                chars.next();
            } else if c == '\n' {
                out.push(c);
            }
        } else if !quoted && c == '/' && next == Some('/') {
            line = true;
        } else if !quoted && c == '/' && next == Some('*') {
            block = true;
            chars.next();
        } else {
            quoted ^= c == '"';
            if !(blank && quoted && c != '"') {
                out.push(c);
            }
        }
    }
    out
}

/// Refuses, unless allowed ([`allow_shell_commands`]), a `.geo` (or a file it includes)
/// that calls a command of `COMMANDS`: gmsh would run it as a shell command while meshing.
pub(crate) fn check_commands(geo: &Path) -> Result<()> {
    if SHELL_ALLOWED.load(Ordering::Relaxed) {
        return Ok(());
    }
    let mut files = vec![geo.to_path_buf()];
    let mut i = 0;
    // Includes, followed to a bounded number of files.
    while i < files.len() && i < 64 {
        let file = files[i].clone();
        i += 1;
        let Ok(text) = std::fs::read_to_string(&file) else {
            continue;
        };
        let (code, text) = (
            without_comments(&text, true),
            without_comments(&text, false),
        );
        for (n, (c, l)) in code.lines().zip(text.lines()).enumerate() {
            if let Some(cmd) = COMMANDS.iter().find(|k| c.contains(*k)) {
                let shown: String = l.trim().chars().take(120).collect();
                return Err(Error::input(
                    &file,
                    format!(
                        "line {}: `{shown}`: this .geo runs a program through gmsh's {cmd} \
                         (a shell command, run with your rights while meshing); sgbem refuses \
                         it unless you allow it: read the file, and if you trust it, give \
                         --allow-geo-shell (or mesh it yourself and name the .msh)",
                        n + 1
                    ),
                ));
            }
            if let Some(rest) = l.trim_start().strip_prefix("Include") {
                if let Some(name) = rest.split('"').nth(1) {
                    let dir = file.parent().unwrap_or(Path::new("."));
                    files.push(dir.join(name));
                }
            }
        }
    }
    Ok(())
}
