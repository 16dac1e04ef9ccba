//! What in a folder the tool wrote: the marker `.sgbem-run.json` that every run (and
//! export) folder holds lists, relative to its folder, each file (`a/b.csv`) and folder
//! (`a/`) the tool wrote there. A folder is replaced only when everything in it is listed
//! by its own marker, or by the marker of its parent folder (an export into the `vtk/`
//! folder of a run); when it is replaced, only the listed entries are removed.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::error::{Error, Result};

/// The name of the marker file.
pub(crate) const MARKER: &str = ".sgbem-run.json";

/// The marker that lists the entries of a folder.
pub struct Owner {
    /// The marker file.
    pub marker: PathBuf,
    /// The folder's path relative to the marker's folder (`vtk/`), empty for its own.
    pub prefix: String,
    /// Every entry the marker lists (relative to the marker's folder).
    pub entries: BTreeSet<String>,
}

impl Owner {
    /// The entries under the folder, relative to the folder itself.
    pub fn inside(&self) -> BTreeSet<String> {
        self.entries
            .iter()
            .filter_map(|e| e.strip_prefix(&self.prefix))
            .filter(|e| !e.is_empty())
            .map(str::to_string)
            .collect()
    }
}

/// Reads a marker: None when there is none; an error when it is not one.
fn read_marker(marker: &Path) -> Result<Option<BTreeSet<String>>> {
    let Ok(meta) = std::fs::symlink_metadata(marker) else {
        return Ok(None);
    };
    let damaged = || {
        Error::input(
            marker,
            "this is not a marker written by sgbem (a JSON object with the list `files`): \
             the tool cannot tell which files of the folder it wrote; move the folder away \
             or give another --out",
        )
    };
    if !meta.is_file() || meta.len() > 64 << 20 {
        return Err(damaged());
    }
    let text = std::fs::read_to_string(marker).map_err(|_| damaged())?;
    let value: serde_json::Value = serde_json::from_str(&text).map_err(|_| damaged())?;
    let files = value
        .get("files")
        .and_then(|f| f.as_array())
        .ok_or_else(damaged)?;
    let mut set = BTreeSet::new();
    for f in files {
        let name = f.as_str().ok_or_else(damaged)?;
        // No entry may lead out of the folder.
        if name.is_empty()
            || name.starts_with('/')
            || name.split('/').any(|p| p == ".." || p == ".")
        {
            return Err(damaged());
        }
        set.insert(name.to_string());
    }
    Ok(Some(set))
}

/// The marker that owns `folder`: its own, else its parent's when that lists the folder.
pub(crate) fn owner(folder: &Path) -> Result<Option<Owner>> {
    let own = folder.join(MARKER);
    if let Some(entries) = read_marker(&own)? {
        return Ok(Some(Owner {
            marker: own,
            prefix: String::new(),
            entries,
        }));
    }
    let (Some(parent), Some(name)) = (folder.parent(), folder.file_name()) else {
        return Ok(None);
    };
    let parent = if parent.as_os_str().is_empty() {
        Path::new(".")
    } else {
        parent
    };
    let marker = parent.join(MARKER);
    let prefix = format!("{}/", name.to_string_lossy());
    Ok(read_marker(&marker)?
        .filter(|entries| entries.contains(&prefix))
        .map(|entries| Owner {
            marker,
            prefix,
            entries,
        }))
}

/// Every entry under `dir`, relative to it (folders with a trailing `/`), sorted; symbolic
/// links and other special files as `Err(name)` (never the tool's).
fn walk(dir: &Path) -> Vec<std::result::Result<String, String>> {
    let mut out = Vec::new();
    let mut stack = vec![(dir.to_path_buf(), String::new())];
    while let Some((d, rel)) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in entries.flatten() {
            let name = format!("{rel}{}", e.file_name().to_string_lossy());
            match e.file_type() {
                Ok(t) if t.is_dir() => {
                    out.push(Ok(format!("{name}/")));
                    stack.push((e.path(), format!("{name}/")));
                }
                Ok(t) if t.is_file() => out.push(Ok(name)),
                _ => out.push(Err(name)),
            }
        }
    }
    out.sort_by(|a, b| {
        let key = |r: &std::result::Result<String, String>| match r {
            Ok(n) | Err(n) => n.clone(),
        };
        key(a).cmp(&key(b))
    });
    out
}

/// The entries of `folder` that its owner does not list (all of them without an owner);
/// the marker of the folder itself is its owner's.
pub fn foreign(folder: &Path, owner: Option<&Owner>) -> Vec<String> {
    let listed = owner.map(Owner::inside).unwrap_or_default();
    let own_marker = owner.is_some_and(|o| o.prefix.is_empty());
    walk(folder)
        .into_iter()
        .filter_map(|e| match e {
            Ok(n) if listed.contains(&n) || (own_marker && n == MARKER) => None,
            // A folder the owner does not list: name it, not everything inside it.
            Ok(n) => Some(n),
            Err(n) => Some(n),
        })
        .fold(Vec::<String>::new(), |mut v, n| {
            if !v
                .iter()
                .any(|p| p.ends_with('/') && n.starts_with(p.as_str()))
            {
                v.push(n);
            }
            v
        })
}

/// The refusal for `folder` holding `strangers`.
pub(crate) fn refusal(folder: &Path, strangers: &[String], owned: bool) -> Error {
    let shown: Vec<String> = strangers.iter().take(5).map(|s| format!("`{s}`")).collect();
    let more = if strangers.len() > 5 {
        format!(" and {} more", strangers.len() - 5)
    } else {
        String::new()
    };
    let them = if strangers.len() == 1 { "it" } else { "them" };
    let why = if owned {
        format!(
            "which the sgbem run that wrote it did not write (its {MARKER} does not list {them})"
        )
    } else {
        format!(
            "and sgbem did not write this folder (it has no {MARKER}; a folder of an sgbem \
             older than 0.1 has none either)"
        )
    };
    Error::input(
        folder,
        format!(
            "the output folder exists and holds {}{more}, {why}: sgbem replaces only what it \
             wrote, so move {} away, or give --out (or output.directory, or --vtk) a new \
             folder",
            shown.join(", "),
            if strangers.len() == 1 {
                "it"
            } else {
                "these files"
            }
        ),
    )
}

/// The marker `.sgbem-run.json`; fields in alphabetical order, the order of its keys as
/// it has always been written.
#[derive(Serialize)]
struct Marker<'a> {
    about: &'static str,
    files: &'a BTreeSet<String>,
    tool: &'static str,
    tool_version: &'static str,
}

/// The marker text listing `entries`.
pub(crate) fn marker_text(entries: &BTreeSet<String>) -> String {
    let marker = Marker {
        about: "the files and folders sgbem wrote here: a later run or export replaces \
                only these, and refuses a folder holding anything else",
        files: entries,
        tool: "sgbem",
        tool_version: env!("CARGO_PKG_VERSION"),
    };
    let text = serde_json::to_string_pretty(&marker).unwrap_or_default();
    format!("{text}\n")
}

/// Every entry under `dir` (relative; folders with a trailing `/`), the marker excepted.
pub fn listing(dir: &Path) -> BTreeSet<String> {
    walk(dir)
        .into_iter()
        .filter_map(|e| e.ok())
        .filter(|n| n != MARKER)
        .collect()
}

/// Removes from `dir` the listed `entries` (files, then the folders they leave empty), its
/// marker, and `dir` itself if nothing else is left; anything not listed stays.
pub(crate) fn remove_listed(dir: &Path, entries: &BTreeSet<String>) {
    for f in entries.iter().filter(|e| !e.ends_with('/')) {
        if std::fs::symlink_metadata(dir.join(f)).is_ok_and(|m| m.is_file()) {
            let _ = std::fs::remove_file(dir.join(f));
        }
    }
    let _ = std::fs::remove_file(dir.join(MARKER));
    // Deepest folders first; remove_dir refuses a folder that is not empty.
    let mut dirs: Vec<&String> = entries.iter().filter(|e| e.ends_with('/')).collect();
    dirs.sort_by_key(|d| std::cmp::Reverse(d.matches('/').count()));
    for d in dirs {
        let _ = std::fs::remove_dir(dir.join(d));
    }
    let _ = std::fs::remove_dir(dir);
}
