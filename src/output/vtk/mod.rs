//! VTK files for ParaView, pyvista and meshio (SPEC.md "Outputs"): per archived state
//! `boundary_NNNN.vtu` (the boundary lines of every body) and, where interior values exist,
//! `field_NNNN.vtu` (the triangles of every body), and `history.pvd`, the time series.
//!
//! Place in the flow: [`RunRecord`] → **`vtk`**. Everything is computed from the record
//! alone, so that `sgbem export` rebuilds the same bytes from the archive. Files are XML
//! unstructured grids (binary, base64, little-endian, UInt64 headers, Int32 point indices
//! where they fit), each written atomically; the bytes depend on the record alone (no
//! dates, no timings).
//!
//! `states.pvd` lists one multiblock per time, `state_NNNN.vtm`, with named blocks:
//! `boundary` (the boundary file of the state) and `field` only in the states that have their
//! interior field (the final one): the series to open in ParaView. Where the run failed at a
//! mechanism, or its collapse search found one, the last state's multiblock ends with the
//! block `mechanism` (`mechanism_NNNN.vtu`): the boundary lines of every body with the point
//! array `mechanism_velocity`, each moving body's rigid velocity `t + ω k × (x − c)` (zero
//! on the bodies at rest, the fastest node at 1), for Warp By Vector.
//!
//! `history.pvd` lists two parts at every time: part 0 the boundary file of the state,
//! part 1 the field file of the latest state at or before that time that has one (the
//! first one before it exists). ParaView's PVD reader reads a part only when it is listed at
//! every time, so the field is repeated rather than left out; each file's field data
//! (`iteration`, `load_step`, `load_factor`) says which state it holds. Times: the states of
//! load step s (counted from 1) with n recorded states lie at s − 1 + j/n, j = 1..n, so
//! the last state of step s is at time s (see [`state_times`]).
//!
//! Points sit at their reference positions; `displacement` has three components (z = 0) so
//! that ParaView's Warp By Vector shows the strained shape. Nodes are per body: an interface
//! node appears once for each of its two bodies, so that opening shows as a gap.
//!
//! Field data of every file: `title`, `length_unit`, `force_unit`, `stress_unit` (text as
//! UTF-8 bytes in UInt8 arrays, since meshio reads no string arrays; left out when empty),
//! `iteration`, `load_step` (from 0), `load_factor`, `time` (the state's time in
//! `history.pvd`). The same texts as text for ParaView, where meshio does not look: string
//! arrays `run title`, `length unit`, `force unit`, `stress unit` in the field data of each
//! `state_NNNN.vtm` (ParaView's Information panel shows them as words).
//!
//! Boundary point data: `displacement`, `traction` (average of the element-end values at
//! the node), `normal` (unit, average of the adjacent element normals), `contact_status`
//! (1 closed, 0 open, −1 not an interface node), with friction `tangential_status` (1 stick,
//! 2 slip, 0 open, −1 not a friction node) and `slip` (accumulated slip path),
//! `normal_traction` (interface nodes: the
//! pair's normal traction, tension positive; elsewhere the average of t·n over the adjacent
//! element ends), `normal_opening` (interface nodes: gap + normal jump where open, 0 where
//! closed; elsewhere 0), `body` (index). Field point data: `displacement`, `stress` (the
//! symmetric tensor as ParaView orders it: xx, yy, zz, xy, yz, xz, with component names;
//! zz is the out-of-plane stress, yz = xz = 0), `sxx`, `syy`, `szz`, `sxy`, `von_mises`,
//! `principal_stress` (σ1 ≥ σ2 in plane, then σzz), `principal_direction` (unit vector of
//! σ1), `body`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::record::{InterfaceRecord, RunRecord};
use super::write_files;
use crate::error::{Error, Result};
use crate::input::scene::VtkStyle;
use crate::post::{out_of_plane_stress, principal_stresses, von_mises};
use crate::solution::PairStatus;

/// The names of the point arrays that the boundary and field files can hold, the choices of
/// `output.vtk_fields` in alphabetical order (a name both files use selects it in both).
pub const POINT_ARRAYS: [&str; 17] = [
    "body",
    "contact_status",
    "displacement",
    "normal",
    "normal_opening",
    "normal_traction",
    "principal_direction",
    "principal_stress",
    "slip",
    "stress",
    "sxx",
    "sxy",
    "syy",
    "szz",
    "tangential_status",
    "traction",
    "von_mises",
];

/// File name of the boundary file of state `k`.
pub(crate) fn boundary_name(k: usize) -> String {
    format!("boundary_{k:04}.vtu")
}

/// File name of the field file of state `k`.
pub(crate) fn field_name(k: usize) -> String {
    format!("field_{k:04}.vtu")
}

/// File name of the thrust line of state `k`.
pub(crate) fn thrust_name(k: usize) -> String {
    format!("thrust_{k:04}.vtu")
}

/// File name of the contact rows of state `k`.
pub(crate) fn contact_name(k: usize) -> String {
    format!("contact_{k:04}.vtu")
}

/// File name of the mechanism drawn with state `k` (the last one).
pub(crate) fn mechanism_name(k: usize) -> String {
    format!("mechanism_{k:04}.vtu")
}

/// File name of the multiblock of state `k` (`states.pvd`'s entry).
pub(crate) fn state_name(k: usize) -> String {
    format!("state_{k:04}.vtm")
}

/// The time of every state in `history.pvd`: the states of load step s (from 1) with n
/// recorded states at s − 1 + j/n, j = 1..n (the last state of step s at time s).
pub fn state_times(rec: &RunRecord) -> Vec<f64> {
    let mut times = Vec::with_capacity(rec.states.len());
    let mut i = 0;
    while i < rec.states.len() {
        let step = rec.states[i].load_step;
        let n = rec.states[i..]
            .iter()
            .take_while(|s| s.load_step == step)
            .count();
        for j in 1..=n {
            times.push(step as f64 + j as f64 / n as f64);
        }
        i += n;
    }
    times
}

/// Writes every VTK file of `rec` into `dir` (created if needed), synced before they are
/// renamed into place; returns the paths written, `history.pvd` last.
pub fn write_vtk(dir: &Path, rec: &RunRecord) -> Result<Vec<PathBuf>> {
    write_vtk_with(dir, rec, true)
}

/// [`write_vtk`] into a run's staging folder: not synced (the folder's commit syncs it).
pub(crate) fn write_vtk_staged(dir: &Path, rec: &RunRecord) -> Result<Vec<PathBuf>> {
    write_vtk_with(dir, rec, false)
}

/// One file of [`write_vtk`].
#[derive(Clone, Copy)]
enum File {
    Boundary(usize),
    Field(usize),
    Thrust(usize),
    Contact(usize),
    Mechanism(usize),
    /// The multiblock of a state: its boundary file, where it has one its field file,
    /// where the run has interfaces its thrust line and its contact rows, and where it is
    /// drawn with the state the mechanism.
    State(usize, bool, bool, bool),
    StatesPvd,
    Pvd,
}

fn write_vtk_with(dir: &Path, rec: &RunRecord, durable: bool) -> Result<Vec<PathBuf>> {
    rec.validate().map_err(|m| {
        Error::io(
            dir,
            format!("cannot write the VTK files: the run record is inconsistent: {m}"),
        )
    })?;
    let times = state_times(rec);
    let mut files = Vec::new();
    let mut field_of = Vec::with_capacity(rec.states.len());
    let thrust = !rec.interfaces.is_empty();
    for (k, st) in rec.states.iter().enumerate() {
        files.push(File::Boundary(k));
        let field = !st.interior.is_empty();
        if field {
            files.push(File::Field(k));
        }
        if thrust {
            files.push(File::Thrust(k));
            files.push(File::Contact(k));
        }
        // The mechanism is drawn with the last state.
        let mechanism = !rec.mechanism.is_empty() && k + 1 == rec.states.len();
        if mechanism {
            files.push(File::Mechanism(k));
        }
        files.push(File::State(k, field, thrust, mechanism));
        field_of.push(field.then_some(k));
    }
    files.push(File::StatesPvd);
    files.push(File::Pvd);
    let paths: Vec<PathBuf> = files
        .iter()
        .map(|f| match *f {
            File::Boundary(k) => dir.join(boundary_name(k)),
            File::Field(k) => dir.join(field_name(k)),
            File::Thrust(k) => dir.join(thrust_name(k)),
            File::Contact(k) => dir.join(contact_name(k)),
            File::Mechanism(k) => dir.join(mechanism_name(k)),
            File::State(k, ..) => dir.join(state_name(k)),
            File::StatesPvd => dir.join("states.pvd"),
            File::Pvd => dir.join("history.pvd"),
        })
        .collect();
    // The files are made and written in parallel; history.pvd is renamed into place last.
    write_files(&paths, durable, |i| {
        Ok(match files[i] {
            File::Boundary(k) => grid_xml(
                boundary_grid(rec, k),
                &state_meta(rec, k, times[k]),
                &rec.vtk,
            ),
            File::Field(k) => grid_xml(field_grid(rec, k), &state_meta(rec, k, times[k]), &rec.vtk),
            File::Thrust(k) => {
                let (grid, names) = thrust_grid(rec, k);
                let mut meta = state_meta(rec, k, times[k]);
                meta.push(("joint_names", FieldValue::Text(names)));
                // Every array of the thrust line: `vtk_fields` selects the others' arrays.
                let style = VtkStyle {
                    compressed: rec.vtk.compressed,
                    fields: None,
                };
                grid_xml(grid, &meta, &style)
            }
            File::Contact(k) => {
                let mut meta = state_meta(rec, k, times[k]);
                let names: Vec<&str> = rec.interfaces.iter().map(|i| i.name.as_str()).collect();
                meta.push(("interface_names", FieldValue::Text(names.join("\n"))));
                // Every array of the contact rows, as for the thrust line.
                let style = VtkStyle {
                    compressed: rec.vtk.compressed,
                    fields: None,
                };
                grid_xml(contact_grid(rec, k), &meta, &style)
            }
            File::Mechanism(k) => {
                // Every array, as for the thrust line.
                let style = VtkStyle {
                    compressed: rec.vtk.compressed,
                    fields: None,
                };
                grid_xml(mechanism_grid(rec), &state_meta(rec, k, times[k]), &style)
            }
            File::State(k, field, thrust, mechanism) => {
                state_vtm(k, field, thrust, mechanism, &state_meta(rec, k, times[k])).into_bytes()
            }
            File::StatesPvd => states_pvd(&times).into_bytes(),
            File::Pvd => pvd(&times, &field_of).into_bytes(),
        })
    })?;
    Ok(paths)
}

/// `state_NNNN.vtm`: the state as one multiblock with named blocks, `boundary`, where the
/// state has its interior field `field` (nowhere else), where the run has interfaces
/// `thrust` and `contact`, and where the mechanism is drawn with it `mechanism`; the
/// multiblock's own field data holds the text of `meta` as text (see [`text_field_data`]).
fn state_vtm(
    k: usize,
    field: bool,
    thrust: bool,
    mechanism: bool,
    meta: &[(&'static str, FieldValue)],
) -> String {
    let mut o = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"vtkMultiBlockDataSet\" version=\"1.0\" \
         byte_order=\"LittleEndian\">\n  <vtkMultiBlockDataSet>\n",
    );
    let _ = writeln!(
        o,
        "    <DataSet index=\"0\" name=\"boundary\" file=\"{}\"/>",
        boundary_name(k)
    );
    if field {
        let _ = writeln!(
            o,
            "    <DataSet index=\"1\" name=\"field\" file=\"{}\"/>",
            field_name(k)
        );
    }
    if thrust {
        let _ = writeln!(
            o,
            "    <DataSet index=\"{}\" name=\"thrust\" file=\"{}\"/>",
            1 + usize::from(field),
            thrust_name(k)
        );
        let _ = writeln!(
            o,
            "    <DataSet index=\"{}\" name=\"contact\" file=\"{}\"/>",
            2 + usize::from(field),
            contact_name(k)
        );
    }
    if mechanism {
        let _ = writeln!(
            o,
            "    <DataSet index=\"{}\" name=\"mechanism\" file=\"{}\"/>",
            1 + usize::from(field) + 2 * usize::from(thrust),
            mechanism_name(k)
        );
    }
    o.push_str("  </vtkMultiBlockDataSet>\n");
    text_field_data(&mut o, meta);
    o.push_str("</VTKFile>\n");
    o
}

/// The multiblock's field data: every non-empty text of `meta` as a VTK string array named
/// with a space for the underscore (`title` → `run title`, `stress_unit` → `stress unit`),
/// so that ParaView's Information panel shows "stress unit  daN/cm^2" rather than the
/// codes of the blocks' UInt8 arrays (which keep their names: meshio refuses a .vtu with a
/// string array, and reads no .vtm). A distinct name, since ParaView merges the field data
/// of the blocks and the root by name, and the blocks' UInt8 array would hide the text.
/// A string array's ASCII payload is each string's UTF-8 bytes followed by a 0.
fn text_field_data(o: &mut String, meta: &[(&'static str, FieldValue)]) {
    let texts: Vec<(String, &str)> = meta
        .iter()
        .filter_map(|(name, v)| match v {
            FieldValue::Text(s) if !s.is_empty() => {
                let shown = if *name == "title" {
                    "run title".to_string()
                } else {
                    name.replace('_', " ")
                };
                Some((shown, s.as_str()))
            }
            _ => None,
        })
        .collect();
    if texts.is_empty() {
        return;
    }
    o.push_str("  <FieldData>\n");
    for (name, s) in texts {
        let mut codes: Vec<String> = s.bytes().map(|b| b.to_string()).collect();
        codes.push("0".into());
        let _ = writeln!(
            o,
            "    <Array type=\"String\" Name=\"{}\" NumberOfTuples=\"1\" \
             format=\"ascii\">{}</Array>",
            name,
            codes.join(" ")
        );
    }
    o.push_str("  </FieldData>\n");
}

/// `states.pvd`: one multiblock (`state_NNNN.vtm`) per time, the series to open in ParaView.
fn states_pvd(times: &[f64]) -> String {
    collection(
        times
            .iter()
            .enumerate()
            .map(|(k, &t)| (t, 0, state_name(k))),
    )
}

/// `history.pvd`: at each time the boundary file of the state and the latest field at or
/// before it, else the first one.
fn pvd(times: &[f64], field_of: &[Option<usize>]) -> String {
    let mut latest = field_of.iter().flatten().next().copied();
    let mut entries = Vec::with_capacity(2 * times.len());
    for (k, &t) in times.iter().enumerate() {
        if field_of[k].is_some() {
            latest = field_of[k];
        }
        entries.push((t, 0, boundary_name(k)));
        if let Some(f) = latest {
            entries.push((t, 1, field_name(f)));
        }
    }
    collection(entries.into_iter())
}

/// A PVD collection of (time, part, file) entries.
fn collection(entries: impl Iterator<Item = (f64, usize, String)>) -> String {
    let mut pvd = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" \
         byte_order=\"LittleEndian\">\n  <Collection>\n",
    );
    for (t, part, file) in entries {
        let _ = writeln!(
            pvd,
            "    <DataSet timestep=\"{t}\" group=\"\" part=\"{part}\" file=\"{file}\"/>"
        );
    }
    pvd.push_str("  </Collection>\n</VTKFile>\n");
    pvd
}

/// `sgbem export`: reads an archive and writes its VTK files into `dir`.
pub fn export(archive: &Path, dir: &Path) -> Result<Vec<PathBuf>> {
    let mut rec = super::archive::read_archive(archive)?;
    // The VTK files as the run wrote them: `output.vtk` and `output.vtk_fields` of the
    // archived scene with its overrides (every array, uncompressed, if it no longer reads).
    rec.vtk = crate::input::scene::parse_scene_with(&rec.scene_text, archive, &rec.overrides)
        .map(|s| s.output.vtk_style)
        .unwrap_or_default();
    // The folder is written whole, as a run folder is: no file of a longer earlier export
    // is left, and nothing the tool did not write is replaced (output/folder.rs).
    let folder = super::folder::RunFolder::acquire(dir, &[archive])?;
    let files = write_vtk_staged(folder.staging(), &rec)?;
    let files = files
        .iter()
        .filter_map(|f| f.file_name())
        .map(|n| folder.target().join(n))
        .collect();
    folder.commit()?;
    Ok(files)
}

// ---------------------------------------------------------------------------------------
// The XML writer: an unstructured grid with inline base64 binary arrays.

enum Values {
    F64(Vec<f64>),
    I32(Vec<i32>),
    U64(Vec<u64>),
    U8(Vec<u8>),
}

impl Values {
    fn type_name(&self) -> &'static str {
        match self {
            Values::F64(_) => "Float64",
            Values::I32(_) => "Int32",
            Values::U64(_) => "UInt64",
            Values::U8(_) => "UInt8",
        }
    }
    /// The size of the values in bytes.
    fn size(&self) -> usize {
        match self {
            Values::F64(v) => 8 * v.len(),
            Values::I32(v) => 4 * v.len(),
            Values::U64(v) => 8 * v.len(),
            Values::U8(v) => v.len(),
        }
    }
    /// The binary payload of the array: with `header`, its size in bytes (UInt64) first;
    /// then the values, little-endian.
    fn payload(&self, header: bool) -> Vec<u8> {
        fn bytes<const K: usize>(
            n: usize,
            header: bool,
            values: impl Iterator<Item = [u8; K]>,
        ) -> Vec<u8> {
            let mut p = Vec::with_capacity(8 + n * K);
            if header {
                p.extend_from_slice(&((n * K) as u64).to_le_bytes());
            }
            for b in values {
                p.extend_from_slice(&b);
            }
            p
        }
        match self {
            Values::F64(v) => bytes(v.len(), header, v.iter().map(|x| x.to_le_bytes())),
            Values::I32(v) => bytes(v.len(), header, v.iter().map(|x| x.to_le_bytes())),
            Values::U64(v) => bytes(v.len(), header, v.iter().map(|x| x.to_le_bytes())),
            Values::U8(v) => bytes(v.len(), header, v.iter().map(|&x| [x])),
        }
    }
    fn as_f64(&self) -> Vec<f64> {
        match self {
            Values::F64(v) => v.clone(),
            Values::I32(v) => v.iter().map(|&x| f64::from(x)).collect(),
            Values::U64(v) => v.iter().map(|&x| x as f64).collect(),
            Values::U8(v) => v.iter().map(|&x| f64::from(x)).collect(),
        }
    }
}

/// One named point-data (or grid) array.
struct DataArray {
    name: &'static str,
    components: usize,
    component_names: &'static [&'static str],
    values: Values,
}

fn array(name: &'static str, components: usize, values: Values) -> DataArray {
    DataArray {
        name,
        components,
        component_names: &[],
        values,
    }
}

/// Field data: strings and numbers describing the whole file.
enum FieldValue {
    Text(String),
    Number(f64),
}

struct Grid {
    points: Vec<f64>,
    connectivity: Vec<u64>,
    /// The VTK type of every cell, in order; a cell's points follow the previous cell's in
    /// `connectivity` ([`cell_size`]).
    cell_types: Vec<u8>,
    point_data: Vec<DataArray>,
    /// Attribute names for `<PointData>`: scalars, vectors, tensors.
    active: [&'static str; 3],
}

fn state_meta(rec: &RunRecord, k: usize, time: f64) -> Vec<(&'static str, FieldValue)> {
    let st = &rec.states[k];
    let (l, f) = (&rec.units.length, &rec.units.force);
    let stress_unit = if l.is_empty() && f.is_empty() {
        String::new()
    } else {
        format!("{f}/{l}^2")
    };
    vec![
        ("title", FieldValue::Text(rec.title.clone())),
        ("length_unit", FieldValue::Text(l.clone())),
        ("force_unit", FieldValue::Text(f.clone())),
        ("stress_unit", FieldValue::Text(stress_unit)),
        ("iteration", FieldValue::Number(st.iteration as f64)),
        ("load_step", FieldValue::Number(st.load_step as f64)),
        ("load_factor", FieldValue::Number(st.load_factor)),
        ("time", FieldValue::Number(time)),
    ]
}

const B64: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

/// Appends the base64 encoding of `bytes` (standard alphabet, `=` padding) to `o`.
fn base64_into(o: &mut String, bytes: &[u8]) {
    let mut out = Vec::with_capacity(bytes.len().div_ceil(3) * 4);
    let mut chunks = bytes.chunks_exact(3);
    for c in &mut chunks {
        let n = (u32::from(c[0]) << 16) | (u32::from(c[1]) << 8) | u32::from(c[2]);
        out.extend_from_slice(&[
            B64[(n >> 18) as usize & 63],
            B64[(n >> 12) as usize & 63],
            B64[(n >> 6) as usize & 63],
            B64[n as usize & 63],
        ]);
    }
    let rest = chunks.remainder();
    if !rest.is_empty() {
        let b1 = rest.get(1).copied().unwrap_or(0);
        let n = (u32::from(rest[0]) << 16) | (u32::from(b1) << 8);
        out.extend_from_slice(&[
            B64[(n >> 18) as usize & 63],
            B64[(n >> 12) as usize & 63],
            if rest.len() == 2 {
                B64[(n >> 6) as usize & 63]
            } else {
                b'='
            },
            b'=',
        ]);
    }
    // Every byte comes from the ASCII alphabet above: always valid UTF-8.
    o.push_str(std::str::from_utf8(&out).unwrap_or_default());
}

/// The uncompressed size of a block of compressed data (VTK's default).
const BLOCK_SIZE: usize = 1 << 15;

/// Appends `bytes` as VTK's zlib-compressed inline binary data: the header (UInt64: the
/// number of blocks, the block size, the size of the last block if partial (else 0), the
/// compressed size of each block) in base64, then the blocks, each a zlib stream, in
/// base64 of their own.
fn compressed_into(o: &mut String, bytes: &[u8]) {
    use flate2::{write::ZlibEncoder, Compression};
    use std::io::Write as _;
    let blocks: Vec<Vec<u8>> = bytes
        .chunks(BLOCK_SIZE)
        .map(|block| {
            let mut z = ZlibEncoder::new(Vec::new(), Compression::default());
            // Writing into a Vec cannot fail.
            let _ = z.write_all(block);
            z.finish().unwrap_or_default()
        })
        .collect();
    let mut header: Vec<u64> = vec![
        blocks.len() as u64,
        BLOCK_SIZE as u64,
        (bytes.len() % BLOCK_SIZE) as u64,
    ];
    header.extend(blocks.iter().map(|b| b.len() as u64));
    let header: Vec<u8> = header.iter().flat_map(|h| h.to_le_bytes()).collect();
    base64_into(o, &header);
    base64_into(o, &blocks.concat());
}

fn write_data_array(o: &mut String, a: &DataArray, compressed: bool) {
    let _ = write!(
        o,
        "<DataArray type=\"{}\" Name=\"{}\"",
        a.values.type_name(),
        a.name
    );
    if a.components != 1 {
        let _ = write!(o, " NumberOfComponents=\"{}\"", a.components);
    }
    for (i, c) in a.component_names.iter().enumerate() {
        let _ = write!(o, " ComponentName{i}=\"{c}\"");
    }
    o.push_str(" format=\"binary\"");
    if a.components == 1 {
        let v = a.values.as_f64();
        if !v.is_empty() {
            let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            if lo.is_finite() && hi.is_finite() {
                let _ = write!(o, " RangeMin=\"{lo}\" RangeMax=\"{hi}\"");
            }
        }
    }
    o.push('>');
    if compressed {
        compressed_into(o, &a.values.payload(false));
    } else {
        base64_into(o, &a.values.payload(true));
    }
    o.push_str("</DataArray>\n");
}

/// An unstructured grid's XML file: the arrays `style` selects, compressed if it says so.
fn grid_xml(mut g: Grid, meta: &[(&'static str, FieldValue)], style: &VtkStyle) -> Vec<u8> {
    g.point_data.retain(|a| style.writes(a.name));
    for name in &mut g.active {
        if !style.writes(name) {
            *name = "";
        }
    }
    let z = style.compressed;
    let n_points = g.points.len() / 3;
    let n_cells = g.cell_types.len();
    // The file's size, at most: its base64 payloads and some text (one allocation).
    let payload: usize = g.point_data.iter().map(|a| a.values.size()).sum::<usize>()
        + 8 * (g.points.len() + 2 * g.connectivity.len())
        + n_cells;
    let mut o = String::with_capacity(payload / 3 * 4 + 4096);
    o.push_str(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" \
         byte_order=\"LittleEndian\" header_type=\"UInt64\"",
    );
    if z {
        o.push_str(" compressor=\"vtkZLibDataCompressor\"");
    }
    o.push_str(">\n<UnstructuredGrid>\n<FieldData>\n");
    for (name, v) in meta {
        match v {
            FieldValue::Text(s) => {
                // UTF-8 bytes in a UInt8 array: meshio reads no string arrays.
                if s.is_empty() {
                    continue;
                }
                let codes: Vec<String> = s.bytes().map(|b| b.to_string()).collect();
                let _ = writeln!(
                    o,
                    "<DataArray type=\"UInt8\" Name=\"{name}\" NumberOfTuples=\"{}\" \
                     format=\"ascii\">{}</DataArray>",
                    codes.len(),
                    codes.join(" ")
                );
            }
            FieldValue::Number(x) => {
                let _ = writeln!(
                    o,
                    "<DataArray type=\"Float64\" Name=\"{name}\" NumberOfTuples=\"1\" \
                     format=\"ascii\">{x:?}</DataArray>"
                );
            }
        }
    }
    o.push_str("</FieldData>\n");
    let _ = writeln!(
        o,
        "<Piece NumberOfPoints=\"{n_points}\" NumberOfCells=\"{n_cells}\">"
    );
    let [s, v, t] = g.active;
    let mut attrs = String::new();
    for (key, name) in [("Scalars", s), ("Vectors", v), ("Tensors", t)] {
        if !name.is_empty() {
            let _ = write!(attrs, " {key}=\"{name}\"");
        }
    }
    let _ = writeln!(o, "<PointData{attrs}>");
    for a in &g.point_data {
        write_data_array(&mut o, a, z);
    }
    o.push_str("</PointData>\n<Points>\n");
    write_data_array(&mut o, &array("Points", 3, Values::F64(g.points)), z);
    o.push_str("</Points>\n<Cells>\n");
    // Point indices as Int32 where they fit (a third of a boundary file's bytes otherwise).
    let ends: Vec<usize> = g
        .cell_types
        .iter()
        .scan(0, |end, &c| {
            *end += cell_size(c);
            Some(*end)
        })
        .collect();
    let last_offset = ends.last().copied().unwrap_or(0);
    let (connectivity, offsets) = match (
        g.connectivity
            .iter()
            .map(|&c| i32::try_from(c))
            .collect::<std::result::Result<Vec<i32>, _>>(),
        i32::try_from(last_offset),
    ) {
        (Ok(c), Ok(_)) => (
            Values::I32(c),
            Values::I32(ends.iter().map(|&e| e as i32).collect()),
        ),
        _ => (
            Values::U64(g.connectivity),
            Values::U64(ends.iter().map(|&e| e as u64).collect()),
        ),
    };
    write_data_array(&mut o, &array("connectivity", 1, connectivity), z);
    write_data_array(&mut o, &array("offsets", 1, offsets), z);
    write_data_array(&mut o, &array("types", 1, Values::U8(g.cell_types)), z);
    o.push_str("</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    o.into_bytes()
}

const VTK_VERTEX: u8 = 1;
const VTK_LINE: u8 = 3;
const VTK_TRIANGLE: u8 = 5;

/// The number of points of a cell of VTK type `c` (of those written here).
fn cell_size(c: u8) -> usize {
    match c {
        VTK_VERTEX => 1,
        VTK_LINE => 2,
        _ => 3,
    }
}

fn vec3(v: &[[f64; 2]]) -> Vec<f64> {
    v.iter().flat_map(|a| [a[0], a[1], 0.0]).collect()
}

fn unit(v: [f64; 2]) -> [f64; 2] {
    let n = v[0].hypot(v[1]);
    if n > 0.0 {
        [v[0] / n, v[1] / n]
    } else {
        v
    }
}

/// The boundary lines of every body in state `k`.
fn boundary_grid(rec: &RunRecord, k: usize) -> Grid {
    let st = &rec.states[k];
    let (mut pts, mut disp, mut trac, mut normal) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut status, mut tn, mut opening, mut body) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let friction = st
        .interfaces
        .iter()
        .any(|r| r.pairs.iter().any(|p| p.slipping.is_some()));
    let (mut tstatus, mut slip) = (Vec::new(), Vec::new());
    let mut conn = Vec::new();
    let mut offset = 0usize;
    for (bi, (b, f)) in rec.bodies.iter().zip(st.fields.iter()).enumerate() {
        let n = b.nodes.len();
        // Per node: sums of end tractions, of element normals, of t·n, and the count.
        let mut t_sum = vec![[0.0; 2]; n];
        let mut n_sum = vec![[0.0; 2]; n];
        let mut tn_sum = vec![0.0; n];
        let mut count = vec![0usize; n];
        for (e, nodes) in b.elements.iter().enumerate() {
            let (p, q) = (b.nodes[nodes[0]], b.nodes[nodes[1]]);
            let tau = unit([q[0] - p[0], q[1] - p[1]]);
            let ne = [tau[1], -tau[0]];
            for (&i, t) in nodes.iter().zip(f.t[e]) {
                t_sum[i][0] += t[0];
                t_sum[i][1] += t[1];
                n_sum[i][0] += ne[0];
                n_sum[i][1] += ne[1];
                tn_sum[i] += t[0] * ne[0] + t[1] * ne[1];
                count[i] += 1;
            }
            conn.push((offset + nodes[0]) as u64);
            conn.push((offset + nodes[1]) as u64);
        }
        let mut st_code = vec![-1i32; n];
        let mut node_tn: Vec<f64> = (0..n).map(|i| tn_sum[i] / count[i].max(1) as f64).collect();
        let mut node_open = vec![0.0; n];
        let mut node_ts = vec![-1i32; n];
        let mut node_slip = vec![0.0; n];
        for (it, r) in rec.interfaces.iter().zip(st.interfaces.iter()) {
            let side: Vec<(usize, usize)> = if it.body_a == bi {
                it.node_a.iter().copied().enumerate().collect()
            } else if it.body_b == bi {
                b_side_pairs(it)
            } else {
                continue;
            };
            for (j, node) in side {
                st_code[node] = match r.pairs[j].status {
                    PairStatus::Closed => 1,
                    PairStatus::Open => 0,
                };
                node_tn[node] = r.pairs[j].traction[1];
                node_open[node] = it.opening(r, j);
                let p = &r.pairs[j];
                if p.slipping.is_some() {
                    node_ts[node] = match p.tangential_status() {
                        Some("stick") => 1,
                        Some("slip") => 2,
                        _ => 0,
                    };
                    node_slip[node] = p.slip;
                }
            }
        }
        pts.extend(vec3(&b.nodes));
        disp.extend(vec3(&f.u));
        for i in 0..n {
            let c = count[i].max(1) as f64;
            trac.extend([t_sum[i][0] / c, t_sum[i][1] / c, 0.0]);
            let nn = unit(n_sum[i]);
            normal.extend([nn[0], nn[1], 0.0]);
        }
        status.extend(st_code);
        tn.extend(node_tn);
        opening.extend(node_open);
        tstatus.extend(node_ts);
        slip.extend(node_slip);
        body.extend(std::iter::repeat_n(bi as i32, n));
        offset += n;
    }
    let mut point_data = vec![
        array("displacement", 3, Values::F64(disp)),
        array("traction", 3, Values::F64(trac)),
        array("normal", 3, Values::F64(normal)),
        array("contact_status", 1, Values::I32(status)),
        array("normal_traction", 1, Values::F64(tn)),
        array("normal_opening", 1, Values::F64(opening)),
        array("body", 1, Values::I32(body)),
    ];
    if friction {
        point_data.push(array("tangential_status", 1, Values::I32(tstatus)));
        point_data.push(array("slip", 1, Values::F64(slip)));
    }
    Grid {
        points: pts,
        cell_types: vec![VTK_LINE; conn.len() / 2],
        connectivity: conn,
        point_data,
        active: ["contact_status", "displacement", ""],
    }
}

/// The boundary lines of every body with the rigid velocity of the mechanism at their
/// nodes (`mechanism_velocity`: zero on the bodies at rest) and `body`.
fn mechanism_grid(rec: &RunRecord) -> Grid {
    let (mut pts, mut velocity, mut body, mut conn) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut motion = vec![None; rec.bodies.len()];
    for m in &rec.mechanism {
        if let Some(slot) = motion.get_mut(m.body) {
            *slot = Some(m);
        }
    }
    let mut offset = 0u64;
    for (bi, (b, motion)) in rec.bodies.iter().zip(motion).enumerate() {
        pts.extend(vec3(&b.nodes));
        for &x in &b.nodes {
            let v = motion.map_or([0.0; 2], |m| m.velocity(x));
            velocity.extend([v[0], v[1], 0.0]);
        }
        body.extend(std::iter::repeat_n(bi as i32, b.nodes.len()));
        conn.extend(
            b.elements
                .iter()
                .flat_map(|e| [offset + e[0] as u64, offset + e[1] as u64]),
        );
        offset += b.nodes.len() as u64;
    }
    Grid {
        points: pts,
        cell_types: vec![VTK_LINE; conn.len() / 2],
        connectivity: conn,
        point_data: vec![
            array("mechanism_velocity", 3, Values::F64(velocity)),
            array("body", 1, Values::I32(body)),
        ],
        active: ["body", "mechanism_velocity", ""],
    }
}

/// The triangles of every body in state `k`, with the interior values at their nodes.
fn field_grid(rec: &RunRecord, k: usize) -> Grid {
    let st = &rec.states[k];
    let (mut pts, mut disp, mut stress, mut vm) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut principal, mut direction, mut body) = (Vec::new(), Vec::new(), Vec::new());
    let (mut sxx, mut syy, mut szz, mut sxy) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut conn = Vec::new();
    let mut offset = 0usize;
    for (bi, (b, f)) in rec.bodies.iter().zip(&st.interior).enumerate() {
        let local: std::collections::HashMap<usize, usize> = f
            .mesh_nodes
            .iter()
            .enumerate()
            .map(|(i, &m)| (m, i))
            .collect();
        for t in &b.triangles {
            for m in t {
                // validate() guarantees every triangle node has a value.
                conn.push((offset + local.get(m).copied().unwrap_or(0)) as u64);
            }
        }
        for (i, &m) in f.mesh_nodes.iter().enumerate() {
            let x = rec.mesh.nodes[m];
            pts.extend([x[0], x[1], 0.0]);
            disp.extend([f.u[i][0], f.u[i][1], 0.0]);
            let [xx, yy, xy] = f.sigma[i];
            let s = [[xx, xy], [xy, yy]];
            let zz = out_of_plane_stress(&s, rec.plane, b.poisson);
            stress.extend([xx, yy, zz, xy, 0.0, 0.0]);
            sxx.push(xx);
            syy.push(yy);
            szz.push(zz);
            sxy.push(xy);
            vm.push(von_mises(&s, zz));
            let (p, angle) = principal_stresses(&s);
            principal.extend([p[0], p[1], zz]);
            direction.extend([angle.cos(), angle.sin(), 0.0]);
            body.push(bi as i32);
        }
        offset += f.mesh_nodes.len();
    }
    Grid {
        points: pts,
        cell_types: vec![VTK_TRIANGLE; conn.len() / 3],
        connectivity: conn,
        point_data: vec![
            array("displacement", 3, Values::F64(disp)),
            DataArray {
                name: "stress",
                components: 6,
                component_names: &["XX", "YY", "ZZ", "XY", "YZ", "XZ"],
                values: Values::F64(stress),
            },
            array("sxx", 1, Values::F64(sxx)),
            array("syy", 1, Values::F64(syy)),
            array("szz", 1, Values::F64(szz)),
            array("sxy", 1, Values::F64(sxy)),
            array("von_mises", 1, Values::F64(vm)),
            DataArray {
                name: "principal_stress",
                components: 3,
                component_names: &["1", "2", "zz"],
                values: Values::F64(principal),
            },
            array("principal_direction", 3, Values::F64(direction)),
            array("body", 1, Values::I32(body)),
        ],
        active: ["von_mises", "displacement", "stress"],
    }
}

/// The thrust line of state `k` (post/thrust.rs): a point per joint that carries a normal
/// force, at its point of application, a vertex each, a line through every body between
/// its two joints, and for a body with more joints a point at its hub and a line from each
/// of its joints' points to it (docs/thrust.md); point data `N`, `T`, `e`,
/// `e_over_half_length`, `inside` and `in_closed_part` (1 yes, 0 no), `joint` (the
/// interface's index in the run) and `displacement` (the first body's, weighted as the point
/// is). At a hub `joint` is −1, `N`, `T`, `e`, `e_over_half_length` NaN, `inside` and
/// `in_closed_part` −1, `displacement` the mean of its joints' points'. Also the joints'
/// names, one a line, for the field data `joint_names`.
fn thrust_grid(rec: &RunRecord, k: usize) -> (Grid, String) {
    use crate::post::thrust::{down, hubs, segments, thrust};
    let st = &rec.states[k];
    let mut g = ThrustColumns::default();
    let mut point_of = vec![None; rec.interfaces.len()];
    let mut all = Vec::with_capacity(rec.interfaces.len());
    for (j, (it, r)) in rec.interfaces.iter().zip(st.interfaces.iter()).enumerate() {
        let th = thrust(&it.joint(), r, rec.thickness);
        if let Some(p) = th.point {
            let u: Vec<[f64; 2]> = it
                .node_a
                .iter()
                .map(|&a| st.fields[it.body_a].u[a])
                .collect();
            let ua = th.at_point(&u).unwrap_or_default();
            point_of[j] = Some(g.joint.len() as u64);
            g.push(
                p.x,
                ua,
                j as i32,
                [th.normal, th.tangential, p.e, p.e_over_half_length],
            );
            g.inside.push(i32::from(p.inside));
            g.closed.push(i32::from(p.in_closed_part));
        }
        all.push(th);
    }
    let mut conn: Vec<u64> = (0..g.joint.len() as u64).collect();
    let mut cell_types = vec![VTK_VERTEX; g.joint.len()];
    let bodies: Vec<(usize, usize)> = rec
        .interfaces
        .iter()
        .map(|i| (i.body_a, i.body_b))
        .collect();
    let has_point: Vec<bool> = point_of.iter().map(Option::is_some).collect();
    for [a, b] in segments(&bodies, &has_point, rec.bodies.len()) {
        if let (Some(pa), Some(pb)) = (point_of[a], point_of[b]) {
            conn.extend([pa, pb]);
            cell_types.push(VTK_LINE);
        }
    }
    let down = down(&st.body_forces(&rec.bodies));
    for h in hubs(&bodies, &all, &down) {
        let ends: Vec<u64> = h.joints.iter().filter_map(|&j| point_of[j]).collect();
        let mut u = [0.0; 2];
        for &e in &ends {
            let at = 3 * e as usize;
            u = [u[0] + g.disp[at], u[1] + g.disp[at + 1]];
        }
        let m = ends.len().max(1) as f64;
        let hub = g.joint.len() as u64;
        g.push(h.x, [u[0] / m, u[1] / m], -1, [f64::NAN; 4]);
        g.inside.push(-1);
        g.closed.push(-1);
        conn.push(hub);
        cell_types.push(VTK_VERTEX);
        for e in ends {
            conn.extend([e, hub]);
            cell_types.push(VTK_LINE);
        }
    }
    let names: Vec<&str> = rec.interfaces.iter().map(|i| i.name.as_str()).collect();
    let grid = Grid {
        points: g.pts,
        connectivity: conn,
        cell_types,
        point_data: vec![
            array("N", 1, Values::F64(g.n)),
            array("T", 1, Values::F64(g.t)),
            array("e", 1, Values::F64(g.e)),
            array("e_over_half_length", 1, Values::F64(g.ratio)),
            array("inside", 1, Values::I32(g.inside)),
            array("in_closed_part", 1, Values::I32(g.closed)),
            array("joint", 1, Values::I32(g.joint)),
            array("displacement", 3, Values::F64(g.disp)),
        ],
        active: ["N", "displacement", ""],
    };
    (grid, names.join("\n"))
}

/// The contact rows of state `k` as points (one vertex per pair, at the pair's point on the
/// first body): `interface` and `pair` (indices; the file's field data `interface_names`
/// names the interfaces), `contact_status` (1 closed, 0 open), `tangential_status` (1 stick,
/// 2 slip, 0 open, −1 not a friction pair), `gap` (the initial normal gap),
/// `normal_opening` (gap + normal jump where open, 0 where closed), `normal_traction`
/// (tension positive) and `tangential_traction` on the first body, `normal_force` and
/// `tangential_force` (the tractions times the pair's tributary length and the thickness),
/// `slip` (the accumulated slip path), `displacement` (the first body's, for Warp By Vector).
fn contact_grid(rec: &RunRecord, k: usize) -> Grid {
    let st = &rec.states[k];
    let mut c = ContactColumns::default();
    for (i, (it, r)) in rec.interfaces.iter().zip(st.interfaces.iter()).enumerate() {
        let w = it.weights();
        for (j, p) in r.pairs.iter().enumerate() {
            let x = it.x[j];
            let u = st.fields[it.body_a].u[it.node_a[j]];
            let w = w.get(j).copied().unwrap_or(0.0) * rec.thickness;
            c.pts.extend([x[0], x[1], 0.0]);
            c.disp.extend([u[0], u[1], 0.0]);
            c.interface.push(i as i32);
            c.pair.push(j as i32);
            c.status.push(match p.status {
                PairStatus::Closed => 1,
                PairStatus::Open => 0,
            });
            c.tangential.push(match p.tangential_status() {
                Some("stick") => 1,
                Some("slip") => 2,
                Some(_) => 0,
                None => -1,
            });
            c.gap.push(it.gap[j]);
            c.opening.push(it.opening(r, j));
            c.tn.push(p.traction[1]);
            c.tt.push(p.traction[0]);
            c.fn_.push(p.traction[1] * w);
            c.ft.push(p.traction[0] * w);
            c.slip.push(p.slip);
        }
    }
    let n = c.status.len();
    Grid {
        points: c.pts,
        connectivity: (0..n as u64).collect(),
        cell_types: vec![VTK_VERTEX; n],
        point_data: vec![
            array("interface", 1, Values::I32(c.interface)),
            array("pair", 1, Values::I32(c.pair)),
            array("contact_status", 1, Values::I32(c.status)),
            array("tangential_status", 1, Values::I32(c.tangential)),
            array("gap", 1, Values::F64(c.gap)),
            array("normal_opening", 1, Values::F64(c.opening)),
            array("normal_traction", 1, Values::F64(c.tn)),
            array("tangential_traction", 1, Values::F64(c.tt)),
            array("normal_force", 1, Values::F64(c.fn_)),
            array("tangential_force", 1, Values::F64(c.ft)),
            array("slip", 1, Values::F64(c.slip)),
            array("displacement", 3, Values::F64(c.disp)),
        ],
        active: ["contact_status", "displacement", ""],
    }
}

/// The point arrays of the contact block.
#[derive(Default)]
struct ContactColumns {
    pts: Vec<f64>,
    disp: Vec<f64>,
    interface: Vec<i32>,
    pair: Vec<i32>,
    status: Vec<i32>,
    tangential: Vec<i32>,
    gap: Vec<f64>,
    opening: Vec<f64>,
    tn: Vec<f64>,
    tt: Vec<f64>,
    fn_: Vec<f64>,
    ft: Vec<f64>,
    slip: Vec<f64>,
}

/// The point arrays of the thrust block, filled point by point.
#[derive(Default)]
struct ThrustColumns {
    pts: Vec<f64>,
    disp: Vec<f64>,
    joint: Vec<i32>,
    n: Vec<f64>,
    t: Vec<f64>,
    e: Vec<f64>,
    ratio: Vec<f64>,
    inside: Vec<i32>,
    closed: Vec<i32>,
}

impl ThrustColumns {
    /// A point at `x` with displacement `u`, joint index and `[N, T, e, e/(L/2)]`.
    fn push(&mut self, x: [f64; 2], u: [f64; 2], joint: i32, v: [f64; 4]) {
        self.pts.extend([x[0], x[1], 0.0]);
        self.disp.extend([u[0], u[1], 0.0]);
        self.joint.push(joint);
        self.n.push(v[0]);
        self.t.push(v[1]);
        self.e.push(v[2]);
        self.ratio.push(v[3]);
    }
}

/// The pair that each of body B's interface nodes shows (pair index, node): its pair's node
/// where nodes pair up; where the sides were meshed on their own, every interface node of B
/// shows the pair whose row gives it the largest coefficient.
fn b_side_pairs(it: &InterfaceRecord) -> Vec<(usize, usize)> {
    let Some(pr) = &it.pairing else {
        return it.node_b.iter().copied().enumerate().collect();
    };
    let mut best: std::collections::BTreeMap<usize, (f64, usize)> = Default::default();
    for j in 0..pr.offset.len().saturating_sub(1) {
        for m in pr.offset[j]..pr.offset[j + 1] {
            let e = best.entry(pr.node[m]).or_insert((f64::NEG_INFINITY, j));
            if pr.coef[m] > e.0 {
                *e = (pr.coef[m], j);
            }
        }
    }
    best.into_iter().map(|(node, (_, j))| (j, node)).collect()
}

#[cfg(test)]
mod tests {
    use super::base64_into;

    #[test]
    fn base64_matches_rfc_4648_vectors() {
        // RFC 4648 §10, appended to text already in the buffer.
        for (input, expected) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            let mut o = String::from(">");
            base64_into(&mut o, input.as_bytes());
            assert_eq!(o, format!(">{expected}"), "{input:?}");
        }
        // Every byte value, through all three positions of a block.
        let bytes: Vec<u8> = (0..=255u8).collect();
        let mut o = String::new();
        base64_into(&mut o, &bytes);
        assert_eq!(o.len(), 344);
        assert!(
            o.starts_with("AAECAwQFBgcICQoLDA0ODxAREhMUFRYXGBkaGxwdHh8g"),
            "{o}"
        );
        assert!(o.ends_with("+/w=="), "{o}");
    }
}
