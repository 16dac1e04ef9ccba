//! VTK files for ParaView, pyvista and meshio (README "Outputs"): per archived state
//! `boundary_NNNN.vtu` (the boundary lines of every body) and, where interior values exist,
//! `field_NNNN.vtu` (the triangles of every body), and `history.pvd`, the time series.
//!
//! Place in the flow: [`RunRecord`] → **`vtk`**. Everything is computed from the record
//! alone, so that `sgbem export` rebuilds the same bytes from the archive. Files are XML
//! unstructured grids (binary, base64, little-endian, UInt64 headers, Int32 point indices
//! where they fit), each written atomically; the bytes depend on the record alone (no
//! dates, no timings). `grids` builds each file's grid from the record, `xml` writes it.
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

mod grids;
mod xml;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use self::grids::{boundary_grid, contact_grid, field_grid, mechanism_grid, thrust_grid};
use self::xml::{grid_xml, FieldValue};
use super::record::RunRecord;
use super::write_files;
use crate::error::{Error, Result};
use crate::input::scene::VtkStyle;

/// The names of the point arrays that the boundary and field files can hold, the choices of
/// `output.vtk_fields` in alphabetical order (a name both files use selects it in both).
pub(crate) const POINT_ARRAYS: [&str; 17] = [
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

/// The field data of state `k`'s files: the run's texts and the state's numbers at `time`.
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
