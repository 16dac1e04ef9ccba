//! Sweep files: a sweep written down (`sgbem sweep --file FILE`, `pipelines/Snakefile`).
//!
//! Place in the flow: before [`super::sweep`]; reads the file, resolves its paths and merges
//! the command line into it, so that a sweep from a file is the sweep of the equivalent
//! command line (same points, folders and tables).
//!
//! The file (TOML, paths relative to its folder):
//!
//! ```toml
//! scene = "../wall_running_bond.toml"          # required: the scene swept
//! set = ["mesh.courses=2", "defaults.interface.friction=0.05,0.3,0.7"]  # required: --set
//! out = "../../out/wall_friction"              # optional: out/<file name> otherwise
//! columns = ["detached_length", "slip_length"] # optional: --columns
//! parts = false                                # optional: --parts
//! allow_geo_shell = false                      # optional: --allow-geo-shell
//! ```
//!
//! With the file, the command line: `--out` replaces the file's `out`; a `--set KEY=...`
//! replaces the file's entry for the same KEY (in its place, so that the points keep their
//! order and names) or, for a key the file does not sweep, is added after the file's;
//! `--columns` replaces the file's `columns`; `--parts` and `--allow-geo-shell` turn on what
//! the file leaves off. The scene comes from the file alone.

use std::path::{Component, Path, PathBuf};

use crate::error::{Error, Result};

/// The keys a sweep file may have.
pub(crate) const KEYS: [&str; 6] = ["scene", "set", "out", "columns", "parts", "allow_geo_shell"];

/// A sweep: what `sgbem sweep` runs, from the command line or a sweep file and it.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Given {
    pub scene: Option<PathBuf>,
    /// `KEY=V1,V2,...`, in order.
    pub sets: Vec<String>,
    pub out: Option<PathBuf>,
    /// `K1,K2,...` (`--columns`).
    pub columns: Option<String>,
    pub parts: bool,
    pub allow_geo_shell: bool,
}

/// The sweep of the file `path` with the command line `cli` merged into it (module
/// comment); the scene and the folder resolved (the folder `out/<file name>` where neither
/// gives one). Every problem of the file is an input error naming it.
pub fn read(path: &Path, cli: Given) -> Result<Given> {
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(Error::input(
                path,
                "no such sweep file: give the path of a sweep file (TOML with `scene` and \
                 `set`; README \"Sweeps\")",
            ))
        }
        Err(e) => return Err(Error::io(path, format!("cannot read the sweep file: {e}"))),
    };
    let err = |m: String| Error::input(path, format!("sweep file: {m}"));
    let text = std::str::from_utf8(&bytes)
        .map_err(|_| err("not UTF-8 text: a sweep file is TOML text".into()))?;
    let doc: toml::Table = text
        .parse()
        .map_err(|e: toml::de::Error| err(crate::input::scene::toml_error(&e, text)))?;
    for key in doc.keys() {
        if !KEYS.contains(&key.as_str()) {
            return Err(err(format!(
                "unknown key `{key}`{}; allowed keys: {}",
                crate::error::did_you_mean(key, KEYS.iter().copied()),
                KEYS.join(", ")
            )));
        }
    }
    let scene = match doc.get("scene") {
        Some(toml::Value::String(s)) => beside(path, s),
        Some(_) => return Err(err("`scene` must be a string, the scene's path".into())),
        None => {
            return Err(err(
                "`scene = \"SCENE.toml\"` is required (the scene swept, a path relative to \
                 the sweep file)"
                    .into(),
            ))
        }
    };
    if cli.scene.is_some() {
        return Err(err(
            "the scene comes from the sweep file's `scene`: give no SCENE with --file".into(),
        ));
    }
    if !scene.is_file() {
        return Err(err(format!(
            "scene = \"{}\": no such scene file {} (the path is relative to the sweep \
             file's folder)",
            doc["scene"].as_str().unwrap_or_default(),
            scene.display()
        )));
    }
    let sets = strings(&doc, "set", path)?.unwrap_or_default();
    if sets.is_empty() {
        return Err(err(
            "`set = [\"KEY=V1,V2,...\", ...]` is required, at least one key (sgbem sweep's \
             --set)"
                .into(),
        ));
    }
    let columns = strings(&doc, "columns", path)?;
    if let Some(cols) = &columns {
        super::Columns::parse(Some(&cols.join(",")), false)
            .map_err(|m| err(m.replacen("--columns", "`columns`", 1)))?;
    }
    let out = match doc.get("out") {
        None => None,
        Some(toml::Value::String(s)) => Some(beside(path, s)),
        Some(_) => return Err(err("`out` must be a string, the sweep's folder".into())),
    };
    let flag = |key: &str| match doc.get(key) {
        None => Ok(false),
        Some(toml::Value::Boolean(b)) => Ok(*b),
        Some(_) => Err(err(format!("`{key}` must be true or false"))),
    };
    let stem = path.file_stem().unwrap_or_default();
    Ok(Given {
        scene: Some(scene),
        sets: merged(sets, cli.sets),
        out: Some(
            cli.out
                .or(out)
                .unwrap_or_else(|| Path::new("out").join(stem)),
        ),
        columns: cli.columns.or(columns.map(|c| c.join(","))),
        parts: cli.parts || flag("parts")?,
        allow_geo_shell: cli.allow_geo_shell || flag("allow_geo_shell")?,
    })
}

/// The strings of `key`: a string or a list of strings (None where the key is absent).
fn strings(doc: &toml::Table, key: &str, path: &Path) -> Result<Option<Vec<String>>> {
    let bad = || {
        Error::input(
            path,
            format!("sweep file: `{key}` must be a list of strings, e.g. {key} = [\"...\"]"),
        )
    };
    match doc.get(key) {
        None => Ok(None),
        Some(toml::Value::String(s)) => Ok(Some(vec![s.clone()])),
        Some(toml::Value::Array(a)) => a
            .iter()
            .map(|v| v.as_str().map(str::to_string).ok_or_else(bad))
            .collect::<Result<Vec<_>>>()
            .map(Some),
        Some(_) => Err(bad()),
    }
}

/// The file's `--set` list with the command line's: an entry for a key the file has
/// replaces it in its place, the others follow in their order.
fn merged(mut file: Vec<String>, cli: Vec<String>) -> Vec<String> {
    let key = |s: &str| s.split_once('=').map_or(s, |(k, _)| k).trim().to_string();
    for s in cli {
        match file.iter().position(|f| key(f) == key(&s)) {
            Some(i) => file[i] = s,
            None => file.push(s),
        }
    }
    file
}

/// `rel` as written in the file `file`: relative to its folder (an absolute path as it
/// is), `.` and `..` taken out where they can be.
fn beside(file: &Path, rel: &str) -> PathBuf {
    let joined = file.parent().unwrap_or(Path::new("")).join(rel);
    let mut out = PathBuf::new();
    for c in joined.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir
                if matches!(out.components().next_back(), Some(Component::Normal(_))) =>
            {
                out.pop();
            }
            Component::ParentDir if out.has_root() => {}
            c => out.push(c),
        }
    }
    if out.as_os_str().is_empty() {
        out.push(".");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_are_relative_to_the_file() {
        let f = Path::new("pipelines/sweeps/w.toml");
        assert_eq!(
            beside(f, "../wall.toml"),
            PathBuf::from("pipelines/wall.toml")
        );
        assert_eq!(beside(f, "../../out/w"), PathBuf::from("out/w"));
        assert_eq!(beside(f, "../../../x"), PathBuf::from("../x"));
        assert_eq!(beside(f, "/abs/./s.toml"), PathBuf::from("/abs/s.toml"));
        assert_eq!(beside(Path::new("w.toml"), "."), PathBuf::from("."));
        assert_eq!(beside(Path::new("/w.toml"), "../a"), PathBuf::from("/a"));
    }

    #[test]
    fn command_line_sets_replace_or_follow() {
        let v = |a: &[&str]| a.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        assert_eq!(
            merged(v(&["a=1,2", "b.c=3"]), v(&["b.c = 4,5", "d=6"])),
            v(&["a=1,2", "b.c = 4,5", "d=6"])
        );
    }
}
