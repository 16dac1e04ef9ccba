//! `archive.h5`: everything needed to re-examine a run (SPEC.md "Outputs"), written from
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
//!                        concatenated
//! /solution/             the final state per body and interface: attributes as a state;
//!                        bodies/<name>/{u (n×2), t (m×2×2)}, interfaces/<name>/{status,
//!                        traction, jump, normal_opening[, tangential_status, slip]},
//!                        interior/<name>/{mesh_nodes, x, u, sigma (k×3)}
//! /timings/              attribute created (UTC date of the run); one scalar dataset per
//!                        stage (seconds). The date and the timings are the only parts
//!                        that differ between two runs of the same scene and mesh.
//! ```
//!
//! Groups that list named children (`/bodies`, `/interfaces`, `/contact/operators`,
//! `/timings`, `/history/interfaces`) carry an `order` attribute with the child names in
//! record order; a child's real name is its `name` attribute (group names have `/` replaced).
//! Every dataset carries `description` and `units` attributes. With `output.compress = true`
//! datasets of 4096 values or more (but the states' floats) are chunked and compressed
//! (shuffle + deflate, level `DEFLATE_LEVEL`) when the HDF5 library has deflate. It is off
//! by default: example 2's archive is 16 MB instead of 11 MB, and its run 0.38–0.40 s instead
//! of 0.47 s (deflating its 13 MB of dense operators costs 0.19 s of CPU).
//!
//! The file is written in the HDF5 1.10 format (libver bounds v110..latest): its metadata
//! (superblock, object headers, B-trees, heaps of links) carries checksums. Attribute
//! strings are still variable-length (the global heap has none).
//!
//! The file is written under a temporary name in the same folder (synced, unless it is in a
//! run's staging folder, which is synced when committed) and renamed when complete: an interrupted run never leaves a file named `archive.h5` that looks finished.
//! HDF5 file locking is off for both writing and reading: the temporary name is private to
//! the writer, and the library opens files without close-on-exec, so a child process
//! started meanwhile (by another thread) would otherwise keep the lock after the rename.

use std::path::Path;

use h5::types::VarLenUnicode;
use h5::{Group, H5Type, Location};
use hdf5_metno as h5;
use ndarray::{ArrayViewD, IxDyn};

use super::record::{
    plane_name, Array, BodyOperators, BodyRecord, InterfaceRecord, InteriorRecord, MeshRecord,
    PairingRecord, RunRecord, StateRecord, FORMAT_VERSION,
};
use crate::error::{Error, Result};
use crate::input::scene::{Plane, Units};
use crate::solution::{BodyField, History, HistoryRow, InterfaceResult, PairResult, PairStatus};

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
    write_archive_with(path, rec, true)
}

/// [`write_archive`] into a run's staging folder: not synced (the folder's commit syncs it).
pub fn write_archive_staged(path: &Path, rec: &RunRecord) -> Result<()> {
    write_archive_with(path, rec, false)
}

fn write_archive_with(path: &Path, rec: &RunRecord, durable: bool) -> Result<()> {
    rec.validate().map_err(|m| {
        Error::io(
            path,
            format!("cannot write the archive: the run record is inconsistent: {m}"),
        )
    })?;
    write_file(path, durable, rec.compress, |file| write_all(file, rec))
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
        states: Vec<StateRecord>,
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
            } => {
                rec.contact_operators = contact_operators;
                rec.history = history;
                rec.states = states;
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
        return Err(Error::io(
            path,
            "no such archive: give the archive.h5 of a run (sgbem run writes it to the output folder)",
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

// ---------------------------------------------------------------------------------------
// Writing.

/// Unit strings of the datasets.
struct U {
    l: String,
    f: String,
}

impl U {
    fn new(units: &Units) -> U {
        let or = |s: &str, d: &str| {
            if s.is_empty() {
                d.to_string()
            } else {
                s.to_string()
            }
        };
        U {
            l: or(&units.length, "length"),
            f: or(&units.force, "force"),
        }
    }
    fn len(&self) -> &str {
        &self.l
    }
    fn stress(&self) -> String {
        format!("{}/{}^2", self.f, self.l)
    }
    fn body_force(&self) -> String {
        format!("{}/{}^3", self.f, self.l)
    }
}

/// Group name of a record name: HDF5 paths cannot hold `/`, nor be `.`.
fn group_name(name: &str) -> String {
    let s = name.replace('/', "_");
    if s.is_empty() || s == "." {
        "_".into()
    } else {
        s
    }
}

fn ctx<T>(r: h5::Result<T>, what: impl FnOnce() -> String) -> R<T> {
    r.map_err(|e| format!("{}: {e}", what()))
}

fn vlu(s: &str) -> R<VarLenUnicode> {
    s.replace('\0', "")
        .parse::<VarLenUnicode>()
        .map_err(|e| format!("text {s:?}: {e}"))
}

fn put_attr_str(loc: &Location, name: &str, value: &str) -> R<()> {
    let v = vlu(value)?;
    let a = ctx(
        loc.new_attr::<VarLenUnicode>().shape(()).create(name),
        || format!("attribute {name}"),
    )?;
    ctx(a.write_scalar(&v), || format!("attribute {name}"))
}

fn put_attr<T: H5Type>(loc: &Location, name: &str, value: T) -> R<()> {
    let a = ctx(loc.new_attr::<T>().shape(()).create(name), || {
        format!("attribute {name}")
    })?;
    ctx(a.write_scalar(&value), || format!("attribute {name}"))
}

fn put_attr_list(loc: &Location, name: &str, values: &[String]) -> R<()> {
    let v = values.iter().map(|s| vlu(s)).collect::<R<Vec<_>>>()?;
    ctx(
        loc.new_attr_builder()
            .with_data(&ndarray::Array1::from(v))
            .create(name),
        || format!("attribute {name}"),
    )
    .map(|_| ())
}

/// Writes dataset `name` of the given shape with its `description` and `units`; chunked and
/// compressed when large and `compress`.
fn put_with<T: H5Type>(
    g: &Group,
    name: &str,
    shape: &[usize],
    data: &[T],
    description: &str,
    units: &str,
    compress: bool,
) -> R<()> {
    let where_ = || format!("{}/{name}", g.name().trim_end_matches('/'));
    let view =
        ArrayViewD::from_shape(IxDyn(shape), data).map_err(|e| format!("{}: {e}", where_()))?;
    let n = data.len();
    let builder = g.new_dataset_builder().with_data(view);
    let ds = if compress
        && COMPRESS.with(|c| c.get())
        && n >= COMPRESS_FROM
        && h5::filters::deflate_available()
    {
        let mut chunk = shape.to_vec();
        let rest: usize = shape[1..].iter().product::<usize>().max(1);
        chunk[0] = (CHUNK_VALUES / rest).clamp(1, shape[0]);
        builder
            .chunk(chunk)
            .shuffle()
            .deflate(DEFLATE_LEVEL)
            .create(name)
    } else {
        builder.create(name)
    };
    let ds = ctx(ds, where_)?;
    put_attr_str(&ds, "description", description)?;
    put_attr_str(&ds, "units", units)
}

fn put<T: H5Type>(g: &Group, name: &str, shape: &[usize], data: &[T], d: &str, u: &str) -> R<()> {
    put_with(g, name, shape, data, d, u, true)
}

fn put_f64(g: &Group, name: &str, shape: &[usize], data: &[f64], d: &str, u: &str) -> R<()> {
    put(g, name, shape, data, d, u)
}

fn put_vec2(g: &Group, name: &str, data: &[[f64; 2]], d: &str, u: &str) -> R<()> {
    put(g, name, &[data.len(), 2], data.as_flattened(), d, u)
}

fn put_idx(g: &Group, name: &str, data: &[usize], d: &str) -> R<()> {
    let v: Vec<i64> = data.iter().map(|&i| i as i64).collect();
    put(g, name, &[v.len()], &v, d, "1")
}

fn put_idx_n<const K: usize>(g: &Group, name: &str, data: &[[usize; K]], d: &str) -> R<()> {
    let v: Vec<i64> = data.iter().flatten().map(|&i| i as i64).collect();
    put(g, name, &[data.len(), K], &v, d, "1")
}

fn put_opt_idx(g: &Group, name: &str, data: &[Option<usize>], d: &str) -> R<()> {
    let v: Vec<i64> = data.iter().map(|i| i.map_or(-1, |i| i as i64)).collect();
    put(g, name, &[v.len()], &v, d, "1")
}

fn put_strs(g: &Group, name: &str, data: &[String], d: &str) -> R<()> {
    let v = data.iter().map(|s| vlu(s)).collect::<R<Vec<_>>>()?;
    put(g, name, &[v.len()], &v, d, "")
}

fn put_array(g: &Group, name: &str, a: &Array, d: &str, u: &str) -> R<()> {
    put(g, name, &a.shape, &a.data, d, u)
}

fn group(parent: &Group, name: &str) -> R<Group> {
    ctx(parent.create_group(name), || {
        format!("group {}/{name}", parent.name().trim_end_matches('/'))
    })
}

fn status_code(s: PairStatus) -> i8 {
    match s {
        PairStatus::Closed => 1,
        PairStatus::Open => 0,
    }
}

fn write_all(file: &h5::File, rec: &RunRecord) -> R<()> {
    write_model(file, rec)?;
    write_solved(file, rec)?;
    write_finished(file, rec)
}

/// The root attributes known before solving, the mesh, the bodies (with their operators) and
/// the interfaces.
fn write_model(file: &h5::File, rec: &RunRecord) -> R<()> {
    let u = U::new(&rec.units);
    let root: &Group = file;
    put_attr_str(root, "format", FORMAT)?;
    put_attr(root, "format_version", FORMAT_VERSION)?;
    put_attr_str(root, "tool_version", &rec.tool_version)?;
    put_attr_str(root, "scene", &rec.scene_text)?;
    let overrides = serde_json::Value::from(rec.overrides.clone());
    put_attr_str(root, "overrides", &overrides.to_string())?;
    put_attr_str(root, "mesh_sha256", &rec.mesh_sha256)?;
    let units = serde_json::json!({"length": rec.units.length, "force": rec.units.force});
    put_attr_str(root, "units", &units.to_string())?;
    put_attr_str(root, "title", &rec.title)?;
    put_attr_str(root, "plane", plane_name(rec.plane))?;
    put_attr(root, "thickness", rec.thickness)?;

    write_mesh(&group(root, "mesh")?, &rec.mesh, &u)?;

    let bodies = group(root, "bodies")?;
    let names: Vec<String> = rec.bodies.iter().map(|b| group_name(&b.name)).collect();
    put_attr_list(&bodies, "order", &names)?;
    for (i, (b, gname)) in rec.bodies.iter().zip(&names).enumerate() {
        write_body(&group(&bodies, gname)?, i, b, &u)?;
    }

    let ifaces = group(root, "interfaces")?;
    let inames: Vec<String> = rec.interfaces.iter().map(|i| group_name(&i.name)).collect();
    put_attr_list(&ifaces, "order", &inames)?;
    for (i, (it, gname)) in rec.interfaces.iter().zip(&inames).enumerate() {
        write_interface(&group(&ifaces, gname)?, i, it, rec, &u)?;
    }
    Ok(())
}

/// The contact operators, the history and every state but the last.
fn write_solved(file: &h5::File, rec: &RunRecord) -> R<()> {
    let u = U::new(&rec.units);
    let root: &Group = file;
    if let Some(ops) = &rec.contact_operators {
        let g = group(&group(root, "contact")?, "operators")?;
        let names: Vec<String> = ops.iter().map(|(n, _)| group_name(n)).collect();
        put_attr_list(&g, "order", &names)?;
        for ((name, a), gname) in ops.iter().zip(&names) {
            put_array(
                &g,
                gname,
                a,
                &format!("interface operator {name} of the final status (formulation §5)"),
                "mixed: stiffness and load blocks in the units of their unknowns",
            )?;
        }
    }

    write_history(&group(root, "history")?, &rec.history, rec, &u)?;

    let states = group(root, "states")?;
    put_attr(&states, "count", rec.states.len() as i64)?;
    let (nodes, elements, pairs) = offsets(rec);
    put_idx(
        &states,
        "node_offset",
        &nodes,
        "first row of each body (in /bodies order) in the states' u; last: the total",
    )?;
    put_idx(
        &states,
        "element_offset",
        &elements,
        "first row of each body (in /bodies order) in the states' t; last: the total",
    )?;
    put_idx(
        &states,
        "pair_offset",
        &pairs,
        "first row of each interface (in /interfaces order) in the states' pair datasets; \
         last: the total",
    )?;
    let before_last = rec.states.len().saturating_sub(1);
    for (k, st) in rec.states[..before_last].iter().enumerate() {
        write_state_compact(&group(&states, &format!("{k:04}"))?, st, rec, &u)?;
    }
    Ok(())
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

/// One state of `/states`: every body's and every interface's values in one dataset per
/// quantity, concatenated in `/bodies` and `/interfaces` order (see `node_offset`,
/// `element_offset`, `pair_offset`): a few datasets per state whatever the number of
/// bodies, so that the full history of a wall of hundreds of bricks stays small and quick.
fn write_state_compact(g: &Group, st: &StateRecord, rec: &RunRecord, u: &U) -> R<()> {
    put_attr(g, "iteration", st.iteration as i64)?;
    put_attr(g, "load_step", st.load_step as i64)?;
    put_attr(g, "load_factor", st.load_factor)?;
    // The states' fields are most of a long history and compress poorly (to about two
    // thirds, at two and a half times the cost of writing them: 410-brick wall, 1195 states,
    // 34 s against 13 s): they are stored unfiltered.
    let uu: Vec<f64> = st
        .fields
        .iter()
        .flat_map(|f| f.u.iter().flatten().copied())
        .collect();
    put_with(
        g,
        "u",
        &[uu.len() / 2, 2],
        &uu,
        "displacement of each boundary node (x, y), bodies concatenated",
        u.len(),
        false,
    )?;
    let t: Vec<f64> = st
        .fields
        .iter()
        .flat_map(|f| f.t.iter().flatten().flatten().copied())
        .collect();
    put_with(
        g,
        "t",
        &[t.len() / 4, 2, 2],
        &t,
        "traction t = sigma n at the start and end of each element (x, y), bodies \
         concatenated",
        &u.stress(),
        false,
    )?;
    let pairs: Vec<PairResult> = st.interfaces.iter().flat_map(|r| r.pairs.clone()).collect();
    let opening: Vec<f64> = rec
        .interfaces
        .iter()
        .zip(st.interfaces.iter())
        .flat_map(|(it, r)| (0..r.pairs.len()).map(move |j| it.opening(r, j)))
        .collect();
    write_pairs(g, &pairs, &opening, u)
}

/// The pair values of one interface, or of all interfaces concatenated (the floats
/// unfiltered, as the states' fields).
/// The pair values of one interface, or of all interfaces concatenated.
fn write_pairs(g: &Group, pairs: &[PairResult], opening: &[f64], u: &U) -> R<()> {
    let np = pairs.len();
    let status: Vec<i8> = pairs.iter().map(|p| status_code(p.status)).collect();
    put(
        g,
        "status",
        &[np],
        &status,
        "pair status: 1 closed, 0 open",
        "1",
    )?;
    let tr: Vec<f64> = pairs.iter().flat_map(|p| p.traction).collect();
    put_with(
        g,
        "traction",
        &[np, 2],
        &tr,
        "traction on body A in the pair frame: tangential, normal (tension positive)",
        &u.stress(),
        false,
    )?;
    let jump: Vec<f64> = pairs.iter().flat_map(|p| p.jump).collect();
    put_with(
        g,
        "jump",
        &[np, 2],
        &jump,
        "relative displacement u_B - u_A in the pair frame: slip, normal",
        u.len(),
        false,
    )?;
    put_with(
        g,
        "normal_opening",
        &[np],
        opening,
        "normal opening: gap + normal jump where open, 0 where closed",
        u.len(),
        false,
    )?;
    if pairs.iter().any(|p| p.slipping.is_some()) {
        let ts: Vec<i8> = pairs
            .iter()
            .map(|p| match p.slipping {
                None => -1,
                Some(false) => 1,
                Some(true) => 2,
            })
            .collect();
        put(
            g,
            "tangential_status",
            &[np],
            &ts,
            "friction: 1 stick, 2 slip (of a closed pair), -1 no friction or open",
            "1",
        )?;
        let slip: Vec<f64> = pairs.iter().map(|p| p.slip).collect();
        put_with(
            g,
            "slip",
            &[np],
            &slip,
            "friction: accumulated slip path sum |ds| over the load steps while closed",
            u.len(),
            false,
        )?;
    }
    Ok(())
}

/// The last state (with its interior field) and its link `/solution`, the timings, and the
/// root attributes known at the end (status, summary).
fn write_finished(file: &h5::File, rec: &RunRecord) -> R<()> {
    let u = U::new(&rec.units);
    let root: &Group = file;
    put_attr_str(root, "status", &rec.status)?;
    put_attr_str(root, "summary", &rec.summary_json)?;
    if let Some(st) = rec.states.last() {
        let states = ctx(root.group("states"), || "group /states".into())?;
        let name = format!("{:04}", rec.states.len() - 1);
        write_state_compact(&group(&states, &name)?, st, rec, &u)?;
        write_state(&group(root, "solution")?, st, rec, &u)?;
    }

    // The only parts that differ between identical runs: the date and the timings.
    let timings = group(root, "timings")?;
    put_attr_str(&timings, "created", &rec.created)?;
    let tnames: Vec<String> = rec.timings.iter().map(|(s, _)| group_name(s)).collect();
    put_attr_list(&timings, "order", &tnames)?;
    for ((stage, t), gname) in rec.timings.iter().zip(&tnames) {
        put_f64(
            &timings,
            gname,
            &[],
            &[*t],
            &format!("seconds spent in stage {stage}"),
            "s",
        )?;
    }
    Ok(())
}

fn write_mesh(g: &Group, m: &MeshRecord, u: &U) -> R<()> {
    put_vec2(g, "nodes", &m.nodes, "mesh node coordinates x, y", u.len())?;
    put_idx(g, "node_tags", &m.node_tags, "gmsh tag of each mesh node")?;
    put_idx_n(
        g,
        "lines",
        &m.lines,
        "2-node line elements (0-based mesh node indices)",
    )?;
    put_opt_idx(
        g,
        "line_group",
        &m.line_group,
        "physical group of each line (index into group_names; -1: none)",
    )?;
    put_idx_n(
        g,
        "triangles",
        &m.triangles,
        "3-node triangles (0-based mesh node indices)",
    )?;
    put_opt_idx(
        g,
        "triangle_group",
        &m.triangle_group,
        "physical group of each triangle (index into group_names; -1: none)",
    )?;
    put_strs(
        g,
        "group_names",
        &m.group_names,
        "names of the physical groups",
    )?;
    let dims: Vec<i64> = m.group_dims.iter().map(|&d| i64::from(d)).collect();
    put(
        g,
        "group_dims",
        &[dims.len()],
        &dims,
        "dimension of each physical group (1 curve, 2 surface)",
        "1",
    )
}

fn write_body(g: &Group, index: usize, b: &BodyRecord, u: &U) -> R<()> {
    put_attr_str(g, "name", &b.name)?;
    put_attr(g, "index", index as i64)?;
    put_attr(g, "young", b.young)?;
    put_attr(g, "poisson", b.poisson)?;
    put_attr_str(g, "young_units", &u.stress())?;
    if let Some(f) = b.body_force {
        ctx(
            g.new_attr_builder()
                .with_data(&ndarray::arr1(&f))
                .create("body_force"),
            || "attribute body_force".into(),
        )?;
        put_attr_str(g, "body_force_units", &u.body_force())?;
    }
    put_vec2(
        g,
        "nodes",
        &b.nodes,
        "boundary node coordinates (body-local numbering)",
        u.len(),
    )?;
    put_idx(
        g,
        "mesh_nodes",
        &b.mesh_nodes,
        "mesh node of each boundary node",
    )?;
    put_idx_n(
        g,
        "elements",
        &b.elements,
        "boundary elements, start and end node (body on the left: outer loop counter-clockwise)",
    )?;
    put_idx_n(
        g,
        "triangles",
        &b.triangles,
        "mesh triangles of the body (mesh node indices)",
    )?;
    if let Some(op) = &b.operators {
        write_operators(g, op)?;
    }
    Ok(())
}

fn write_operators(g: &Group, op: &BodyOperators) -> R<()> {
    put_attr(g, "n_x", op.n_x as i64)?;
    put_strs(
        g,
        "unknowns",
        &op.unknowns,
        "unknowns: X = [F1; -U2] (the first n_x), then X0 = [F0; -U0] in the pair frames",
    )?;
    let mixed = "mixed: each block in the units of its rows and columns (see unknowns)";
    put_array(
        g,
        "A",
        &op.a,
        "Galerkin block A (rows and columns X)",
        mixed,
    )?;
    put_array(
        g,
        "A0",
        &op.a0,
        "Galerkin block A0 (rows X, columns X0)",
        mixed,
    )?;
    put_array(
        g,
        "A00",
        &op.a00,
        "Galerkin block A00 (rows and columns X0)",
        mixed,
    )?;
    put_f64(
        g,
        "load",
        &[op.load.len()],
        &op.load,
        "load [L; L0] of the Galerkin system (known data and body forces)",
        mixed,
    )?;
    put_array(
        g,
        "D00",
        &op.d00,
        "condensed operator D00 = A00 - A0^T A^-1 A0 (symmetrised)",
        mixed,
    )?;
    put_f64(
        g,
        "Z0",
        &[op.z0.len()],
        &op.z0,
        "condensed load Z0 = L0 - A0^T A^-1 L",
        mixed,
    )
}

fn write_interface(g: &Group, index: usize, it: &InterfaceRecord, rec: &RunRecord, u: &U) -> R<()> {
    put_attr_str(g, "name", &it.name)?;
    put_attr(g, "index", index as i64)?;
    put_attr_str(g, "body_a", &rec.bodies[it.body_a].name)?;
    put_attr_str(g, "body_b", &rec.bodies[it.body_b].name)?;
    put_attr(g, "body_a_index", it.body_a as i64)?;
    put_attr(g, "body_b_index", it.body_b as i64)?;
    put_attr_str(g, "model", &it.model)?;
    put_attr_str(g, "initial", &it.initial)?;
    put_attr_str(g, "tangential", &it.tangential)?;
    put_attr(g, "length", it.length())?;
    put_idx(
        g,
        "node_a",
        &it.node_a,
        "node of each pair in body A (body-local)",
    )?;
    put_idx(
        g,
        "node_b",
        &it.node_b,
        "node of each pair in body B (body-local)",
    )?;
    put_vec2(g, "x", &it.x, "pair coordinates", u.len())?;
    put_vec2(
        g,
        "normal",
        &it.normal,
        "outward unit normal of body A at each pair",
        "1",
    )?;
    put_vec2(
        g,
        "tangent",
        &it.tangent,
        "unit tangent (-n_y, n_x) at each pair",
        "1",
    )?;
    put_f64(
        g,
        "s",
        &[it.s.len()],
        &it.s,
        "arc length from the curve's first node",
        u.len(),
    )?;
    put_f64(
        g,
        "gap",
        &[it.gap.len()],
        &it.gap,
        "initial normal gap of open zones",
        u.len(),
    )?;
    put_f64(
        g,
        "cohesion",
        &[it.cohesion.len()],
        &it.cohesion,
        "tensile strength of closed zones",
        &u.stress(),
    )?;
    put_idx_n(
        g,
        "elements",
        &it.elements,
        "interface elements as (start pair, end pair) along body A",
    )?;
    match &it.pairing {
        Some(pr) => write_pairing(&group(g, "pairing")?, pr, u),
        None => Ok(()),
    }
}

/// `/interfaces/<name>/pairing/`: the rows of an interface whose sides were meshed on their
/// own (docs/formulation.md §5.6).
fn write_pairing(g: &Group, pr: &PairingRecord, u: &U) -> R<()> {
    put_idx(
        g,
        "offset",
        &pr.offset,
        "where each pair's partners start in node and coef (pairs + 1)",
    )?;
    put_idx(
        g,
        "node",
        &pr.node,
        "partner nodes of the pairs' rows in body B (body-local)",
    )?;
    put_f64(
        g,
        "coef",
        &[pr.coef.len()],
        &pr.coef,
        "coefficients of the partners: u_B = sum coef u_B[node] (they sum to one per pair)",
        "1",
    )?;
    put_f64(
        g,
        "weight",
        &[pr.weight.len()],
        &pr.weight,
        "tributary length of each pair's rows (the part of body A facing body B)",
        u.len(),
    )?;
    put_f64(
        g,
        "gap_geometry",
        &[pr.gap_geometry.len()],
        &pr.gap_geometry,
        "normal gap of each pair measured from the geometry",
        u.len(),
    )?;
    put_opt_idx(
        g,
        "segment",
        &pr.segment,
        "element of body B facing each pair (body-local; -1: none)",
    )?;
    put_idx(
        g,
        "b_nodes",
        &pr.b_nodes,
        "interface nodes of body B (body-local)",
    )
}

fn write_history(g: &Group, h: &History, rec: &RunRecord, u: &U) -> R<()> {
    let rows = &h.rows;
    let nr = rows.len();
    let ni = rec.interfaces.len();
    let col = |f: &dyn Fn(&HistoryRow) -> i64| rows.iter().map(f).collect::<Vec<i64>>();
    put(
        g,
        "load_step",
        &[nr],
        &col(&|r| r.load_step as i64),
        "load step of each row",
        "1",
    )?;
    put(
        g,
        "iteration",
        &[nr],
        &col(&|r| r.iteration as i64),
        "iteration within the load step (0: initial status)",
        "1",
    )?;
    let lf: Vec<f64> = rows.iter().map(|r| r.load_factor).collect();
    put_f64(g, "load_factor", &[nr], &lf, "load factor of each row", "1")?;
    let solvers: Vec<String> = rows.iter().map(|r| r.solver.to_string()).collect();
    put_strs(g, "solver", &solvers, "solver that produced each row")?;
    let dl: Vec<f64> = rows
        .iter()
        .flat_map(|r| r.detached_length.iter().copied())
        .collect();
    put_f64(
        g,
        "detached_length",
        &[nr, ni],
        &dl,
        "detached length per row and interface (elements with both ends open)",
        u.len(),
    )?;
    let gi = group(g, "interfaces")?;
    let names: Vec<String> = rec.interfaces.iter().map(|i| group_name(&i.name)).collect();
    put_attr_list(&gi, "order", &names)?;
    for (i, (it, gname)) in rec.interfaces.iter().zip(&names).enumerate() {
        let gg = group(&gi, gname)?;
        put_attr_str(&gg, "name", &it.name)?;
        let np = it.node_a.len();
        let st: Vec<i8> = rows
            .iter()
            .flat_map(|r| r.status[i].iter().map(|&s| status_code(s)))
            .collect();
        put(
            &gg,
            "status",
            &[nr, np],
            &st,
            "pair status per row: 1 closed, 0 open",
            "1",
        )?;
        let tn: Vec<f64> = rows
            .iter()
            .flat_map(|r| r.normal_traction[i].iter().copied())
            .collect();
        put_f64(
            &gg,
            "normal_traction",
            &[nr, np],
            &tn,
            "normal traction on body A per row and pair (tension positive)",
            &u.stress(),
        )?;
        let op: Vec<f64> = rows
            .iter()
            .flat_map(|r| r.normal_opening[i].iter().copied())
            .collect();
        put_f64(
            &gg,
            "normal_opening",
            &[nr, np],
            &op,
            "normal opening per row and pair (current normal distance, 0 where closed)",
            u.len(),
        )?;
    }
    Ok(())
}

fn write_state(g: &Group, st: &StateRecord, rec: &RunRecord, u: &U) -> R<()> {
    put_attr(g, "iteration", st.iteration as i64)?;
    put_attr(g, "load_step", st.load_step as i64)?;
    put_attr(g, "load_factor", st.load_factor)?;
    let gb = group(g, "bodies")?;
    for (b, f) in rec.bodies.iter().zip(st.fields.iter()) {
        let gg = group(&gb, &group_name(&b.name))?;
        put_attr_str(&gg, "name", &b.name)?;
        put_vec2(
            &gg,
            "u",
            &f.u,
            "displacement of each boundary node (x, y)",
            u.len(),
        )?;
        let t: Vec<f64> = f.t.iter().flatten().flatten().copied().collect();
        put_f64(
            &gg,
            "t",
            &[f.t.len(), 2, 2],
            &t,
            "traction t = sigma n at the start and end of each element (x, y)",
            &u.stress(),
        )?;
    }
    let gi = group(g, "interfaces")?;
    for (it, r) in rec.interfaces.iter().zip(st.interfaces.iter()) {
        let gg = group(&gi, &group_name(&it.name))?;
        put_attr_str(&gg, "name", &it.name)?;
        let opening: Vec<f64> = (0..r.pairs.len()).map(|j| it.opening(r, j)).collect();
        write_pairs(&gg, &r.pairs, &opening, u)?;
    }
    if !st.interior.is_empty() {
        let gf = group(g, "interior")?;
        for (b, f) in rec.bodies.iter().zip(&st.interior) {
            let gg = group(&gf, &group_name(&b.name))?;
            put_attr_str(&gg, "name", &b.name)?;
            put_idx(
                &gg,
                "mesh_nodes",
                &f.mesh_nodes,
                "mesh node of each interior point",
            )?;
            let x: Vec<[f64; 2]> = f.mesh_nodes.iter().map(|&n| rec.mesh.nodes[n]).collect();
            put_vec2(&gg, "x", &x, "coordinates of each point", u.len())?;
            put_vec2(&gg, "u", &f.u, "displacement (x, y)", u.len())?;
            put_f64(
                &gg,
                "sigma",
                &[f.sigma.len(), 3],
                f.sigma.as_flattened(),
                "stress components xx, yy, xy",
                &u.stress(),
            )?;
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------
// Reading.

fn open_group(parent: &Group, name: &str) -> R<Group> {
    ctx(parent.group(name), || {
        format!(
            "missing group {}/{name}",
            parent.name().trim_end_matches('/')
        )
    })
}

fn attr_str(loc: &Location, name: &str) -> R<String> {
    let a = ctx(loc.attr(name), || {
        format!("{}: missing attribute {name}", loc.name())
    })?;
    let v: VarLenUnicode = ctx(a.read_scalar(), || {
        format!("{}: attribute {name}", loc.name())
    })?;
    Ok(v.as_str().to_string())
}

fn attr_f64(loc: &Location, name: &str) -> R<f64> {
    let a = ctx(loc.attr(name), || {
        format!("{}: missing attribute {name}", loc.name())
    })?;
    ctx(a.read_scalar(), || {
        format!("{}: attribute {name}", loc.name())
    })
}

fn attr_i64(loc: &Location, name: &str) -> R<i64> {
    let a = ctx(loc.attr(name), || {
        format!("{}: missing attribute {name}", loc.name())
    })?;
    ctx(a.read_scalar(), || {
        format!("{}: attribute {name}", loc.name())
    })
}

fn attr_usize(loc: &Location, name: &str) -> R<usize> {
    let v = attr_i64(loc, name)?;
    usize::try_from(v).map_err(|_| format!("{}: attribute {name} = {v} is negative", loc.name()))
}

fn attr_list(loc: &Location, name: &str) -> R<Vec<String>> {
    let a = ctx(loc.attr(name), || {
        format!("{}: missing attribute {name}", loc.name())
    })?;
    let v: Vec<VarLenUnicode> = ctx(a.read_raw(), || format!("{}: attribute {name}", loc.name()))?;
    Ok(v.iter().map(|s| s.as_str().to_string()).collect())
}

/// Reads dataset `name` and checks its shape against `shape` (`None`: any extent).
fn get<T: H5Type>(g: &Group, name: &str, shape: &[Option<usize>]) -> R<(Vec<usize>, Vec<T>)> {
    let where_ = || format!("{}/{name}", g.name().trim_end_matches('/'));
    let ds = ctx(g.dataset(name), || format!("missing dataset {}", where_()))?;
    let s = ds.shape();
    let ok = s.len() == shape.len() && s.iter().zip(shape).all(|(a, b)| b.is_none_or(|b| *a == b));
    if !ok {
        let want: Vec<String> = shape
            .iter()
            .map(|d| d.map_or("any".into(), |d| d.to_string()))
            .collect();
        return Err(format!(
            "{} has shape {s:?}, expected [{}]",
            where_(),
            want.join(", ")
        ));
    }
    let data: Vec<T> = ctx(ds.read_raw(), where_)?;
    if data.len() != s.iter().product::<usize>() {
        return Err(format!("{}: size does not match its shape", where_()));
    }
    Ok((s, data))
}

fn get_f64(g: &Group, name: &str, len: Option<usize>) -> R<Vec<f64>> {
    Ok(get::<f64>(g, name, &[len])?.1)
}

fn get_vec2(g: &Group, name: &str, len: Option<usize>) -> R<Vec<[f64; 2]>> {
    let (_, d) = get::<f64>(g, name, &[len, Some(2)])?;
    Ok(d.chunks_exact(2).map(|c| [c[0], c[1]]).collect())
}

fn to_index(v: i64, g: &Group, name: &str) -> R<usize> {
    usize::try_from(v).map_err(|_| {
        format!(
            "{}/{name} holds the negative index {v}",
            g.name().trim_end_matches('/')
        )
    })
}

fn get_idx(g: &Group, name: &str, len: Option<usize>) -> R<Vec<usize>> {
    let (_, d) = get::<i64>(g, name, &[len])?;
    d.into_iter().map(|v| to_index(v, g, name)).collect()
}

fn get_idx_n<const K: usize>(g: &Group, name: &str) -> R<Vec<[usize; K]>> {
    let (_, d) = get::<i64>(g, name, &[None, Some(K)])?;
    let flat = d
        .into_iter()
        .map(|v| to_index(v, g, name))
        .collect::<R<Vec<usize>>>()?;
    Ok(flat
        .chunks_exact(K)
        .map(|c| std::array::from_fn(|i| c[i]))
        .collect())
}

fn get_opt_idx(g: &Group, name: &str, len: usize) -> R<Vec<Option<usize>>> {
    let (_, d) = get::<i64>(g, name, &[Some(len)])?;
    Ok(d.into_iter().map(|v| usize::try_from(v).ok()).collect())
}

fn get_strs(g: &Group, name: &str, len: Option<usize>) -> R<Vec<String>> {
    let (_, d) = get::<VarLenUnicode>(g, name, &[len])?;
    Ok(d.iter().map(|s| s.as_str().to_string()).collect())
}

fn get_array(g: &Group, name: &str, rank: usize) -> R<Array> {
    let (shape, data) = get::<f64>(g, name, &vec![None; rank])?;
    Ok(Array { shape, data })
}

fn status_of(v: i8) -> PairStatus {
    if v != 0 {
        PairStatus::Closed
    } else {
        PairStatus::Open
    }
}

/// The solver names a history row may carry (rows hold `&'static str`).
fn solver_name(s: &str) -> &'static str {
    const KNOWN: [&str; 6] = ["lcp", "active-set", "lemke", "qp", "bonded", "linear"];
    KNOWN.iter().find(|k| **k == s).copied().unwrap_or("other")
}

fn read_all(file: &h5::File) -> R<RunRecord> {
    let root: &Group = file;
    let plane = match attr_str(root, "plane")?.as_str() {
        "strain" => Plane::Strain,
        "stress" => Plane::Stress,
        p => {
            return Err(format!(
                "root attribute plane = {p:?} is neither strain nor stress"
            ))
        }
    };
    let mut rec = RunRecord::empty(&attr_str(root, "title")?, plane);
    rec.scene_text = attr_str(root, "scene")?;
    rec.mesh_sha256 = attr_str(root, "mesh_sha256")?;
    rec.tool_version = attr_str(root, "tool_version")?;
    // Archives written before the date moved to /timings hold it at the root.
    rec.created = match open_group(root, "timings").and_then(|t| attr_str(&t, "created")) {
        Ok(c) => c,
        Err(_) => attr_str(root, "created")?,
    };
    if let Ok(text) = attr_str(root, "overrides") {
        rec.overrides = serde_json::from_str(&text)
            .map_err(|e| format!("root attribute overrides is not a JSON list: {e}"))?;
    }
    let units: serde_json::Value = serde_json::from_str(&attr_str(root, "units")?)
        .map_err(|e| format!("root attribute units is not JSON: {e}"))?;
    let unit = |k: &str| {
        units
            .get(k)
            .and_then(|v| v.as_str())
            .unwrap_or("")
            .to_string()
    };
    rec.units = Units {
        length: unit("length"),
        force: unit("force"),
    };
    rec.thickness = attr_f64(root, "thickness")?;
    rec.status = attr_str(root, "status")?;
    rec.summary_json = attr_str(root, "summary")?;

    rec.mesh = read_mesh(&open_group(root, "mesh")?)?;

    let bodies = open_group(root, "bodies")?;
    for name in attr_list(&bodies, "order")? {
        rec.bodies.push(read_body(&open_group(&bodies, &name)?)?);
    }
    let ifaces = open_group(root, "interfaces")?;
    for name in attr_list(&ifaces, "order")? {
        rec.interfaces
            .push(read_interface(&open_group(&ifaces, &name)?)?);
    }
    if root.link_exists("contact") {
        let g = open_group(&open_group(root, "contact")?, "operators")?;
        let mut ops = Vec::new();
        for name in attr_list(&g, "order")? {
            let ds = ctx(g.dataset(&name), || {
                format!("missing dataset /contact/operators/{name}")
            })?;
            let rank = ds.ndim();
            ops.push((name.clone(), get_array(&g, &name, rank)?));
        }
        rec.contact_operators = Some(ops);
    }
    rec.history = read_history(&open_group(root, "history")?, &rec)?;
    let states = open_group(root, "states")?;
    let count = attr_usize(&states, "count")?;
    if attr_i64(root, "format_version")? >= 2 {
        let (nodes, elements, pairs) = offsets(&rec);
        for (name, want) in [
            ("node_offset", &nodes),
            ("element_offset", &elements),
            ("pair_offset", &pairs),
        ] {
            if get_idx(&states, name, Some(want.len()))? != *want {
                return Err(format!(
                    "/states/{name} does not match the bodies and interfaces of the archive"
                ));
            }
        }
        for k in 0..count {
            let g = open_group(&states, &format!("{k:04}"))?;
            rec.states
                .push(read_state_compact(&g, &rec, (&nodes, &elements, &pairs))?);
        }
        // The final state's interior field is in /solution only.
        if count > 0 {
            let last = read_state(&open_group(root, "solution")?, &rec)?;
            if let Some(st) = rec.states.last_mut() {
                st.interior = last.interior;
            }
        }
    } else {
        for k in 0..count {
            let st = read_state(&open_group(&states, &format!("{k:04}"))?, &rec)?;
            rec.states.push(st);
        }
    }
    let timings = open_group(root, "timings")?;
    for name in attr_list(&timings, "order")? {
        let (_, v) = get::<f64>(&timings, &name, &[])?;
        rec.timings.push((name, v[0]));
    }
    Ok(rec)
}

fn read_mesh(g: &Group) -> R<MeshRecord> {
    let nodes = get_vec2(g, "nodes", None)?;
    let node_tags = get_idx(g, "node_tags", Some(nodes.len()))?;
    let lines = get_idx_n::<2>(g, "lines")?;
    let line_group = get_opt_idx(g, "line_group", lines.len())?;
    let triangles = get_idx_n::<3>(g, "triangles")?;
    let triangle_group = get_opt_idx(g, "triangle_group", triangles.len())?;
    let group_names = get_strs(g, "group_names", None)?;
    let (_, dims) = get::<i64>(g, "group_dims", &[Some(group_names.len())])?;
    Ok(MeshRecord {
        nodes,
        node_tags,
        lines,
        line_group,
        triangles,
        triangle_group,
        group_names,
        group_dims: dims.into_iter().map(|d| d as i32).collect(),
    })
}

fn read_body(g: &Group) -> R<BodyRecord> {
    let body_force = if g.attr("body_force").is_ok() {
        let a = ctx(g.attr("body_force"), || "attribute body_force".into())?;
        let v: Vec<f64> = ctx(a.read_raw(), || "attribute body_force".into())?;
        if v.len() != 2 {
            return Err(format!(
                "{}: body_force has {} components",
                g.name(),
                v.len()
            ));
        }
        Some([v[0], v[1]])
    } else {
        None
    };
    let nodes = get_vec2(g, "nodes", None)?;
    let operators = if g.link_exists("D00") {
        Some(BodyOperators {
            unknowns: get_strs(g, "unknowns", None)?,
            n_x: attr_usize(g, "n_x")?,
            a: get_array(g, "A", 2)?,
            a0: get_array(g, "A0", 2)?,
            a00: get_array(g, "A00", 2)?,
            load: get_f64(g, "load", None)?,
            d00: get_array(g, "D00", 2)?,
            z0: get_f64(g, "Z0", None)?,
        })
    } else {
        None
    };
    Ok(BodyRecord {
        name: attr_str(g, "name")?,
        young: attr_f64(g, "young")?,
        poisson: attr_f64(g, "poisson")?,
        body_force,
        mesh_nodes: get_idx(g, "mesh_nodes", Some(nodes.len()))?,
        nodes,
        elements: get_idx_n::<2>(g, "elements")?,
        triangles: get_idx_n::<3>(g, "triangles")?,
        operators,
    })
}

fn read_interface(g: &Group) -> R<InterfaceRecord> {
    let node_a = get_idx(g, "node_a", None)?;
    let n_pairs = node_a.len();
    let np = Some(n_pairs);
    Ok(InterfaceRecord {
        name: attr_str(g, "name")?,
        body_a: attr_usize(g, "body_a_index")?,
        body_b: attr_usize(g, "body_b_index")?,
        model: attr_str(g, "model")?,
        initial: attr_str(g, "initial")?,
        tangential: attr_str(g, "tangential")?,
        node_b: get_idx(g, "node_b", np)?,
        node_a,
        x: get_vec2(g, "x", np)?,
        normal: get_vec2(g, "normal", np)?,
        tangent: get_vec2(g, "tangent", np)?,
        s: get_f64(g, "s", np)?,
        gap: get_f64(g, "gap", np)?,
        cohesion: get_f64(g, "cohesion", np)?,
        elements: get_idx_n::<2>(g, "elements")?,
        pairing: if g.link_exists("pairing") {
            let pg = ctx(g.group("pairing"), || "group pairing".into())?;
            let offset = get_idx(&pg, "offset", np.map(|n| n + 1))?;
            let node = get_idx(&pg, "node", None)?;
            Some(PairingRecord {
                coef: get_f64(&pg, "coef", Some(node.len()))?,
                weight: get_f64(&pg, "weight", np)?,
                gap_geometry: get_f64(&pg, "gap_geometry", np)?,
                segment: get_opt_idx(&pg, "segment", n_pairs)?,
                b_nodes: get_idx(&pg, "b_nodes", None)?,
                offset,
                node,
            })
        } else {
            None
        },
    })
}

fn read_history(g: &Group, rec: &RunRecord) -> R<History> {
    let load_step = get_idx(g, "load_step", None)?;
    let nr = Some(load_step.len());
    let iteration = get_idx(g, "iteration", nr)?;
    let load_factor = get_f64(g, "load_factor", nr)?;
    let solver = get_strs(g, "solver", nr)?;
    let ni = rec.interfaces.len();
    let (_, dl) = get::<f64>(g, "detached_length", &[nr, Some(ni)])?;
    let gi = open_group(g, "interfaces")?;
    let names = attr_list(&gi, "order")?;
    if names.len() != ni {
        return Err(format!(
            "/history/interfaces lists {} interfaces, the archive has {ni}",
            names.len()
        ));
    }
    // Per interface: status, normal traction, normal opening (rows × pairs), pairs.
    type Columns = (Vec<i8>, Vec<f64>, Vec<f64>, usize);
    let mut per: Vec<Columns> = Vec::new();
    for (name, it) in names.iter().zip(&rec.interfaces) {
        let gg = open_group(&gi, name)?;
        let np = Some(it.node_a.len());
        let (_, st) = get::<i8>(&gg, "status", &[nr, np])?;
        let (_, tn) = get::<f64>(&gg, "normal_traction", &[nr, np])?;
        let (_, op) = get::<f64>(&gg, "normal_opening", &[nr, np])?;
        per.push((st, tn, op, it.node_a.len()));
    }
    let rows = (0..load_step.len())
        .map(|r| HistoryRow {
            load_step: load_step[r],
            load_factor: load_factor[r],
            iteration: iteration[r],
            solver: solver_name(&solver[r]),
            status: per
                .iter()
                .map(|(st, _, _, np)| {
                    st[r * np..(r + 1) * np]
                        .iter()
                        .map(|&v| status_of(v))
                        .collect()
                })
                .collect(),
            normal_traction: per
                .iter()
                .map(|(_, tn, _, np)| tn[r * np..(r + 1) * np].to_vec())
                .collect(),
            normal_opening: per
                .iter()
                .map(|(_, _, op, np)| op[r * np..(r + 1) * np].to_vec())
                .collect(),
            detached_length: dl[r * ni..(r + 1) * ni].to_vec(),
        })
        .collect();
    Ok(History { rows })
}

/// A state of the compact layout (format_version 2; see [`write_state_compact`]).
fn read_state_compact(
    g: &Group,
    rec: &RunRecord,
    (nodes, elements, pairs): (&[usize], &[usize], &[usize]),
) -> R<StateRecord> {
    let (mut fields, mut interfaces) = (Vec::new(), Vec::new());
    let (nn, ne, np) = (
        nodes[nodes.len() - 1],
        elements[elements.len() - 1],
        pairs[pairs.len() - 1],
    );
    let u = get_vec2(g, "u", Some(nn))?;
    let (_, t) = get::<f64>(g, "t", &[Some(ne), Some(2), Some(2)])?;
    for b in 0..rec.bodies.len() {
        fields.push(BodyField {
            u: u[nodes[b]..nodes[b + 1]].to_vec(),
            t: t[4 * elements[b]..4 * elements[b + 1]]
                .chunks_exact(4)
                .map(|c| [[c[0], c[1]], [c[2], c[3]]])
                .collect(),
            reaction: Vec::new(),
        });
    }
    let (_, status) = get::<i8>(g, "status", &[Some(np)])?;
    let tr = get_vec2(g, "traction", Some(np))?;
    let jump = get_vec2(g, "jump", Some(np))?;
    let friction = if g.link_exists("tangential_status") {
        let (_, ts) = get::<i8>(g, "tangential_status", &[Some(np)])?;
        let (_, slip) = get::<f64>(g, "slip", &[Some(np)])?;
        Some((ts, slip))
    } else {
        None
    };
    for k in 0..rec.interfaces.len() {
        let pairs = (pairs[k]..pairs[k + 1])
            .map(|j| PairResult {
                status: status_of(status[j]),
                traction: tr[j],
                jump: jump[j],
                slipping: match friction.as_ref().map(|f| f.0[j]) {
                    Some(1) => Some(false),
                    Some(2) => Some(true),
                    _ => None,
                },
                slip: friction.as_ref().map_or(0.0, |f| f.1[j]),
            })
            .collect();
        interfaces.push(InterfaceResult { pairs });
    }
    Ok(StateRecord::new(
        attr_usize(g, "iteration")?,
        attr_usize(g, "load_step")?,
        attr_f64(g, "load_factor")?,
        fields,
        interfaces,
    ))
}

fn read_state(g: &Group, rec: &RunRecord) -> R<StateRecord> {
    let (mut fields, mut interfaces) = (Vec::new(), Vec::new());
    let gb = open_group(g, "bodies")?;
    for b in &rec.bodies {
        let gg = open_group(&gb, &group_name(&b.name))?;
        let u = get_vec2(&gg, "u", Some(b.nodes.len()))?;
        let (_, t) = get::<f64>(&gg, "t", &[Some(b.elements.len()), Some(2), Some(2)])?;
        let t = t
            .chunks_exact(4)
            .map(|c| [[c[0], c[1]], [c[2], c[3]]])
            .collect();
        fields.push(BodyField {
            u,
            t,
            reaction: Vec::new(),
        });
    }
    let gi = open_group(g, "interfaces")?;
    for it in &rec.interfaces {
        let gg = open_group(&gi, &group_name(&it.name))?;
        let np = Some(it.node_a.len());
        let (_, status) = get::<i8>(&gg, "status", &[np])?;
        let tr = get_vec2(&gg, "traction", np)?;
        let jump = get_vec2(&gg, "jump", np)?;
        let mut pairs: Vec<PairResult> = status
            .iter()
            .zip(tr.iter().zip(&jump))
            .map(|(&s, (&traction, &jump))| PairResult {
                status: status_of(s),
                traction,
                jump,
                slipping: None,
                slip: 0.0,
            })
            .collect();
        if gg.link_exists("tangential_status") {
            let (_, ts) = get::<i8>(&gg, "tangential_status", &[np])?;
            let (_, slip) = get::<f64>(&gg, "slip", &[np])?;
            for ((p, &t), &sl) in pairs.iter_mut().zip(&ts).zip(&slip) {
                p.slipping = match t {
                    1 => Some(false),
                    2 => Some(true),
                    _ => None,
                };
                p.slip = sl;
            }
        }
        interfaces.push(InterfaceResult { pairs });
    }
    let mut st = StateRecord::new(
        attr_usize(g, "iteration")?,
        attr_usize(g, "load_step")?,
        attr_f64(g, "load_factor")?,
        fields,
        interfaces,
    );
    if g.link_exists("interior") {
        let gf = open_group(g, "interior")?;
        for b in &rec.bodies {
            let gg = open_group(&gf, &group_name(&b.name))?;
            let mesh_nodes = get_idx(&gg, "mesh_nodes", None)?;
            let n = Some(mesh_nodes.len());
            let u = get_vec2(&gg, "u", n)?;
            let (_, s) = get::<f64>(&gg, "sigma", &[n, Some(3)])?;
            st.interior.push(InteriorRecord {
                mesh_nodes,
                u,
                sigma: s.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
            });
        }
    }
    Ok(st)
}
