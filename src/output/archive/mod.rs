//! `archive.h5`: everything needed to re-examine a run (README "Outputs"), written from
//! a [`RunRecord`] and read back into one.
//!
//! Place in the flow: pipeline → [`RunRecord`] → **`archive`**; `sgbem inspect` and
//! `sgbem export` read it with [`read_archive`]. Layout (format_version 2; version 1, read
//! too, held every state in the layout of `/solution`):
//!
//! ```text
//! /                      attributes format = "sgbem-archive", format_version, tool_version,
//!                        scene (the scene file's text), overrides (JSON list of the
//!                        `--set KEY=VALUE` applied to it), mesh_sha256, units (JSON
//!                        {"length": .., "force": ..}), title, plane, thickness, status,
//!                        summary (the text of summary.json)
//! /mesh/                 nodes (N×2), node_tags (N), lines (L×2), line_group (L, -1: none),
//!                        triangles (T×3), triangle_group (T), group_names (G), group_dims (G)
//! /bodies/<name>/        attributes name, index, young, poisson[, body_force];
//!                        nodes (n×2), mesh_nodes (n), elements (m×2), triangles (t×3);
//!                        with operators: unknowns (strings), A, A0, A00, load, D00, Z0
//!                        and the attribute n_x
//! /interfaces/<name>/    attributes name, index, body_a, body_b (names and *_index), model,
//!                        initial, tangential, length; node_a, node_b, x, normal, tangent
//!                        (p×2), s, gap, cohesion (p), elements (e×2 pair indices); where
//!                        the sides were meshed on their own, pairing/{offset (p+1), node,
//!                        coef (the pairs' rows over B's nodes), weight, gap_geometry,
//!                        segment (p), b_nodes}
//! /contact/operators/    one dataset per interface operator of the final status
//! /history/              load_step, load_factor, iteration, solver (R),
//!                        detached_length (R×interfaces);
//!                        interfaces/<name>/{status (R×p, 1 closed 0 open),
//!                        normal_traction, normal_opening (R×p)}
//! /states/               attribute count; node_offset (B+1), element_offset (B+1),
//!                        pair_offset (I+1): where each body (interface) starts in the
//!                        concatenated datasets of a state
//! /states/NNNN/          every archived state, attributes iteration, load_step,
//!                        load_factor: u (N×2, the bodies' nodes concatenated), t (M×2×2),
//!                        status, traction (P×2: s, n), jump (P×2), normal_opening (P), with
//!                        friction tangential_status and slip (P): the interfaces' pairs
//!                        concatenated; body_force (B×2, NaN: none) where the state's body
//!                        forces differ from the bodies' (pseudo-time, collapse search)
//! /solution/             the final state per body and interface: attributes (and
//!                        body_force) as a state; bodies/<name>/{u (n×2), t (m×2×2)},
//!                        interfaces/<name>/{status, traction, jump,
//!                        normal_opening[, tangential_status, slip]},
//!                        interior/<name>/{mesh_nodes, x, u, sigma (k×3)}
//! /mechanism/            where the run failed at a mechanism, or its collapse search found
//!                        one: the moving bodies' rigid motions drawn with the last state
//!                        (the VTK block "mechanism"), body (k, index in /bodies order),
//!                        centroid (k×2), translation (k×2, the centroid's velocity),
//!                        rotation (k, anticlockwise), the fastest boundary node at 1
//! /timings/              attribute created (UTC date of the run); one scalar dataset per
//!                        stage (seconds). The date and the timings are the only parts
//!                        that differ between two runs of the same scene and mesh.
//! ```
//!
//! Groups that list named children (`/bodies`, `/interfaces`, `/contact/operators`,
//! `/timings`, `/history/interfaces`) carry an `order` attribute with the child names in
//! record order; a child's real name is its `name` attribute (group names have `/` replaced).
//! Every dataset carries `description` and `units` attributes. Every dataset but the scalar
//! timings (and empty ones) is chunked (whole rows, at most `CHUNK_VALUES` values a chunk,
//! the chunks equal) with the Fletcher-32 checksum of each chunk, which the library checks on
//! every read: a damaged chunk is an error naming the dataset. With `output.compress = true`
//! datasets of 4096 values or more (but the states' floats) are also compressed
//! (shuffle + deflate, level `DEFLATE_LEVEL`) when the HDF5 library has deflate. It is off
//! by default: example 2's archive is 16 MB instead of 11 MB, and its run 0.38–0.40 s instead
//! of 0.47 s (deflating its 13 MB of dense operators costs 0.19 s of CPU).
//!
//! The file is written in the HDF5 1.10 format (libver bounds v110..latest): its metadata
//! (superblock, object headers, B-trees, heaps of links) carries checksums. Strings
//! (attributes and datasets) are fixed-length UTF-8, null-padded to the longest one: stored in
//! their object, none in the global heap (which has no checksum). The reader reads both
//! these and the variable-length strings of earlier archives.
//!
//! The file is written under a temporary name in the same folder (synced, unless it is in a
//! run's staging folder, which is synced when committed) and renamed when complete: an interrupted run never leaves a file named `archive.h5` that looks finished.
//! HDF5 file locking is off for both writing and reading: the temporary name is private to
//! the writer, and the library opens files without close-on-exec, so a child process
//! started meanwhile (by another thread) would otherwise keep the lock after the rename.
//!
//! Files: this one holds the entry points and the writer thread; `write.rs` writes each group,
//! `read.rs` reads them back.

use std::path::Path;

use hdf5_metno as h5;

use super::record::{Array, InteriorRecord, IterateRecord, RunRecord, FORMAT_VERSION};
use crate::error::{Error, Result};
use crate::solution::{BodyMotion, History};

mod read;
mod write;

use read::{attr_i64, attr_str, read_all};
use write::{write_all, write_finished, write_model, write_solved};

/// The value of the root attribute `format`.
pub const FORMAT: &str = "sgbem-archive";

/// Datasets with at least this many values are chunked and compressed.
const COMPRESS_FROM: usize = 4096;
/// The deflate level: 1. Compressing the archived operators is the largest single piece of
/// a run's CPU (example 2: 13 MB of dense matrices); level 1 costs about 9 % less CPU per run
/// than level 4 for 0.7 % more archive (11.64 MB against 11.56 MB).
const DEFLATE_LEVEL: u8 = 1;
thread_local! {
    /// Whether the archive this thread writes deflates its large datasets
    /// (`output.compress`; set by [`write_file`] for the whole file).
    static COMPRESS: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Values per chunk, at most.
const CHUNK_VALUES: usize = 65_536;

type R<T> = std::result::Result<T, String>;

/// Writes the archive of `rec` to `path` atomically and durably (synced before the rename).
pub fn write_archive(path: &Path, rec: &RunRecord) -> Result<()> {
    rec.validate().map_err(|m| {
        Error::io(
            path,
            format!("cannot write the archive: the run record is inconsistent: {m}"),
        )
    })?;
    write_file(path, true, rec.compress, |file| write_all(file, rec))
}

/// Creates the archive under a temporary name beside `path`, lets `write` fill it, closes it,
/// syncs it when `durable`, and renames it into place; on failure removes it.
fn write_file(
    path: &Path,
    durable: bool,
    compress: bool,
    write: impl FnOnce(&h5::File) -> R<()>,
) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    std::fs::create_dir_all(&dir)
        .map_err(|e| Error::io(&dir, format!("cannot create the folder: {e}")))?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "archive.h5".into());
    let tmp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    COMPRESS.with(|c| c.set(compress));
    let written = (|| -> R<()> {
        // The 1.10 file format: superblock, object headers and B-trees carry checksums,
        // so a damaged file is detected when read instead of sending the library astray.
        let file = h5::File::with_options()
            .with_fapl(|p| p.file_locking(false).libver_v110())
            .create(&tmp)
            .map_err(|e| e.to_string())?;
        write(&file)?;
        file.close().map_err(|e| e.to_string())?;
        // Make the content durable before the rename makes it visible.
        if durable {
            std::fs::File::open(&tmp)
                .and_then(|f| f.sync_all())
                .map_err(|e| e.to_string())?;
        }
        std::fs::rename(&tmp, path).map_err(|e| e.to_string())
    })();
    written.map_err(|m| {
        let _ = std::fs::remove_file(&tmp);
        Error::io(
            path,
            format!("cannot write the archive: {m}; check that the folder is writable and the disk not full"),
        )
    })
}

/// What an [`ArchiveWriter`] is handed after the model: the contact results, then the end.
pub enum ArchivePart {
    /// The results of the contact stage: the interface operators of the final status, the
    /// history and every state, the last one without its interior field.
    Solved {
        contact_operators: Option<Vec<(String, Array)>>,
        history: History,
        states: Vec<IterateRecord>,
        /// The mechanism drawn with the last state (empty: none).
        mechanism: Vec<BodyMotion>,
    },
    /// The end of the run: the interior field of the final state, the status, the timings
    /// and the text of summary.json.
    Finished {
        interior: Vec<InteriorRecord>,
        status: String,
        timings: Vec<(String, f64)>,
        summary_json: String,
    },
}

impl ArchivePart {
    /// Puts the part into the record.
    fn apply(self, rec: &mut RunRecord) {
        match self {
            ArchivePart::Solved {
                contact_operators,
                history,
                states,
                mechanism,
            } => {
                rec.contact_operators = contact_operators;
                rec.history = history;
                rec.states = states;
                rec.mechanism = mechanism;
            }
            ArchivePart::Finished {
                interior,
                status,
                timings,
                summary_json,
            } => {
                if let Some(last) = rec.states.last_mut() {
                    last.interior = interior;
                }
                rec.status = status;
                rec.timings = timings;
                rec.summary_json = summary_json;
            }
        }
    }
}

/// An archive written part by part on a thread of its own while the run goes on (the
/// HDF5 library is serial, and compressing the operators is the largest single piece of
/// writing): the model and the body operators during the contact stage, the contact results
/// during post-processing, the final state beside the VTK files. The file is the one
/// [`write_archive`] writes for the whole record; it is renamed into place (not synced: a
/// run's staging folder is synced when committed) only when [`ArchiveWriter::finish`] has
/// been handed both parts. Dropped before, the writer removes its temporary file.
pub struct ArchiveWriter {
    parts: Option<std::sync::mpsc::Sender<ArchivePart>>,
    worker: Option<std::thread::JoinHandle<Result<()>>>,
}

impl ArchiveWriter {
    /// Starts writing `model` (root attributes, mesh, bodies with their operators,
    /// interfaces; its states, history and contact operators are ignored) into `path`.
    pub fn start(path: &Path, model: RunRecord) -> ArchiveWriter {
        let (tx, rx) = std::sync::mpsc::channel::<ArchivePart>();
        let path = path.to_path_buf();
        let worker = std::thread::spawn(move || {
            let mut rec = model;
            let compress = rec.compress;
            write_file(&path, false, compress, |file| {
                let inconsistent = |m: String| format!("the run record is inconsistent: {m}");
                rec.validate().map_err(inconsistent)?;
                write_model(file, &rec)?;
                let parts: [fn(&h5::File, &RunRecord) -> R<()>; 2] = [write_solved, write_finished];
                for write in parts {
                    let part = rx
                        .recv()
                        .map_err(|_| "the run ended before its results".to_string())?;
                    part.apply(&mut rec);
                    rec.validate().map_err(inconsistent)?;
                    write(file, &rec)?;
                }
                Ok(())
            })
        });
        ArchiveWriter {
            parts: Some(tx),
            worker: Some(worker),
        }
    }

    /// Hands over the next part (a writer that has already failed ignores it; its error
    /// comes from [`ArchiveWriter::finish`]).
    pub fn send(&self, part: ArchivePart) {
        if let Some(tx) = &self.parts {
            let _ = tx.send(part);
        }
    }

    /// Waits until the archive is complete and in place.
    pub fn finish(mut self) -> Result<()> {
        self.parts = None;
        match self.worker.take().map(|w| w.join()) {
            Some(Ok(result)) => result,
            Some(Err(panic)) => std::panic::resume_unwind(panic),
            None => Ok(()),
        }
    }
}

impl Drop for ArchiveWriter {
    fn drop(&mut self) {
        self.parts = None;
        if let Some(w) = self.worker.take() {
            let _ = w.join();
        }
    }
}

/// Reads an archive written by [`write_archive`].
pub fn read_archive(path: &Path) -> Result<RunRecord> {
    if !path.is_file() {
        let what = match std::fs::metadata(path) {
            Err(_) => "no such archive",
            Ok(m) if m.is_dir() => "this is a folder, not an archive",
            Ok(_) => "this is a special file (a pipe or a device), not an archive",
        };
        return Err(Error::io(
            path,
            format!(
                "{what}: give the archive.h5 of a run (sgbem run writes it to the output folder)"
            ),
        ));
    }
    let file = h5::File::with_options()
        .with_fapl(|p| p.file_locking(false))
        .open(path)
        .map_err(|e| {
            Error::io(
                path,
                format!("cannot open the archive: not an HDF5 file, or truncated or damaged ({e})"),
            )
        })?;
    let damaged = |m: String| {
        Error::io(
            path,
            format!("the archive is damaged or incomplete: {m}; run the scene again to rewrite it"),
        )
    };
    let format = attr_str(&file, "format").map_err(|_| {
        Error::io(
            path,
            format!("not an sgbem archive (no root attribute format = \"{FORMAT}\")"),
        )
    })?;
    if format != FORMAT {
        return Err(Error::io(
            path,
            format!("not an sgbem archive: its format is \"{format}\", not \"{FORMAT}\""),
        ));
    }
    let version = attr_i64(&file, "format_version").map_err(damaged)?;
    if version > FORMAT_VERSION {
        return Err(Error::io(
            path,
            format!(
                "archive format version {version} is newer than this sgbem reads \
                 ({FORMAT_VERSION}): use a newer sgbem"
            ),
        ));
    }
    let rec = read_all(&file).map_err(damaged)?;
    rec.validate().map_err(damaged)?;
    Ok(rec)
}

/// What `sgbem inspect` prints for an archive.
pub fn inspect(path: &Path) -> Result<String> {
    let rec = read_archive(path)?;
    Ok(format!(
        "archive     {}\n{}",
        path.display(),
        rec.describe()
    ))
}

// Shared by the writer and the reader.

/// Group name of a record name: HDF5 paths cannot hold `/`, nor be `.`.
fn group_name(name: &str) -> String {
    let s = name.replace('/', "_");
    if s.is_empty() || s == "." {
        "_".into()
    } else {
        s
    }
}

/// An HDF5 result, its error prefixed with what was being done.
fn ctx<T>(r: h5::Result<T>, what: impl FnOnce() -> String) -> R<T> {
    r.map_err(|e| format!("{}: {e}", what()))
}

/// Where each body's nodes and elements and each interface's pairs start in the
/// concatenated datasets of a state (one more entry: the totals).
fn offsets(rec: &RunRecord) -> (Vec<usize>, Vec<usize>, Vec<usize>) {
    let acc = |lens: Vec<usize>| {
        let mut out = Vec::with_capacity(lens.len() + 1);
        let mut k = 0;
        out.push(0);
        for l in lens {
            k += l;
            out.push(k);
        }
        out
    };
    (
        acc(rec.bodies.iter().map(|b| b.nodes.len()).collect()),
        acc(rec.bodies.iter().map(|b| b.elements.len()).collect()),
        acc(rec.interfaces.iter().map(|i| i.node_a.len()).collect()),
    )
}
