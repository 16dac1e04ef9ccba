//! VTK files for ParaView, pyvista and meshio (SPEC.md "Outputs"): per archived state
//! `boundary_NNNN.vtu` (the boundary lines of every body) and, where interior values exist,
//! `field_NNNN.vtu` (the triangles of every body), and `history.pvd`, which gives each file
//! its iteration number as its time.
//!
//! Place in the flow: [`RunRecord`] → **`vtk`**. Everything is computed from the record
//! alone, so that `sgbem export` rebuilds the same bytes from the archive. Files are XML
//! unstructured grids (binary, base64, little-endian, UInt64 headers) written by vtkio, each
//! written atomically.
//!
//! Points sit at their reference positions; `displacement` has three components (z = 0) so
//! that ParaView's Warp By Vector shows the strained shape. Nodes are per body: an interface
//! node appears once for each of its two bodies, so that opening shows as a gap.
//!
//! Boundary point data: `displacement`, `traction` (average of the element-end values at
//! the node), `normal` (unit, average of the adjacent element normals), `contact_status`
//! (1 closed, 0 open, −1 not an interface node), `normal_traction` (interface nodes: the
//! pair's normal traction, tension positive; elsewhere the average of t·n over the adjacent
//! element ends), `normal_opening` (interface nodes: gap + normal jump where open, 0 where
//! closed; elsewhere 0), `body` (index). Field point data: `displacement`, `stress` (xx, yy,
//! xy), `von_mises`, `principal_stress` (σ1 ≥ σ2 in plane, then σzz), `principal_direction`
//! (unit vector of σ1), `body`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use vtkio::model::{
    Attribute, Attributes, ByteOrder, CellType, Cells, DataSet, UnstructuredGridPiece, Version,
    VertexNumbers, Vtk,
};

use super::record::RunRecord;
use super::write_atomic;
use crate::error::{Error, Result};
use crate::post::{out_of_plane_stress, principal_stresses, von_mises};
use crate::solution::PairStatus;

/// File name of the boundary file of state `k`.
pub fn boundary_name(k: usize) -> String {
    format!("boundary_{k:04}.vtu")
}

/// File name of the field file of state `k`.
pub fn field_name(k: usize) -> String {
    format!("field_{k:04}.vtu")
}

/// Writes every VTK file of `rec` into `dir` (created if needed); returns the paths written,
/// `history.pvd` last.
pub fn write_vtk(dir: &Path, rec: &RunRecord) -> Result<Vec<PathBuf>> {
    rec.validate().map_err(|m| {
        Error::io(
            dir,
            format!("cannot write the VTK files: the run record is inconsistent: {m}"),
        )
    })?;
    let mut written = Vec::new();
    let mut pvd = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" \
         byte_order=\"LittleEndian\">\n  <Collection>\n",
    );
    for (k, st) in rec.states.iter().enumerate() {
        let name = boundary_name(k);
        let path = dir.join(&name);
        write_atomic(&path, &to_xml(boundary_grid(rec, k), &path)?)?;
        written.push(path);
        let _ = writeln!(
            pvd,
            "    <DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{name}\"/>",
            st.iteration
        );
        if !st.interior.is_empty() {
            let name = field_name(k);
            let path = dir.join(&name);
            write_atomic(&path, &to_xml(field_grid(rec, k), &path)?)?;
            written.push(path);
            let _ = writeln!(
                pvd,
                "    <DataSet timestep=\"{}\" group=\"\" part=\"1\" file=\"{name}\"/>",
                st.iteration
            );
        }
    }
    pvd.push_str("  </Collection>\n</VTKFile>\n");
    let path = dir.join("history.pvd");
    write_atomic(&path, pvd.as_bytes())?;
    written.push(path);
    Ok(written)
}

/// `sgbem export`: reads an archive and writes its VTK files into `dir`.
pub fn export(archive: &Path, dir: &Path) -> Result<Vec<PathBuf>> {
    let rec = super::archive::read_archive(archive)?;
    write_vtk(dir, &rec)
}

fn to_xml(piece: UnstructuredGridPiece, path: &Path) -> Result<Vec<u8>> {
    let vtk = Vtk {
        version: Version::new_xml(1, 0),
        byte_order: ByteOrder::LittleEndian,
        title: String::new(),
        file_path: None,
        data: DataSet::inline(piece),
    };
    let mut bytes = Vec::new();
    vtk.write_xml(&mut bytes)
        .map_err(|e| Error::io(path, format!("cannot encode the VTK file: {e}")))?;
    bytes.push(b'\n');
    Ok(bytes)
}

fn cells(conn: Vec<u64>, per_cell: usize, kind: CellType) -> Cells {
    let n = conn.len().checked_div(per_cell).unwrap_or(0);
    Cells {
        cell_verts: VertexNumbers::XML {
            offsets: (1..=n).map(|i| (i * per_cell) as u64).collect(),
            connectivity: conn,
        },
        types: vec![kind; n],
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
fn boundary_grid(rec: &RunRecord, k: usize) -> UnstructuredGridPiece {
    let st = &rec.states[k];
    let (mut pts, mut disp, mut trac, mut normal) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut status, mut tn, mut opening, mut body) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut conn = Vec::new();
    let mut offset = 0usize;
    for (bi, (b, f)) in rec.bodies.iter().zip(&st.fields).enumerate() {
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
        for (it, r) in rec.interfaces.iter().zip(&st.interfaces) {
            let side = if it.body_a == bi {
                &it.node_a
            } else if it.body_b == bi {
                &it.node_b
            } else {
                continue;
            };
            for (j, &node) in side.iter().enumerate() {
                st_code[node] = match r.pairs[j].status {
                    PairStatus::Closed => 1,
                    PairStatus::Open => 0,
                };
                node_tn[node] = r.pairs[j].traction[1];
                node_open[node] = it.opening(r, j);
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
        body.extend(std::iter::repeat_n(bi as i32, n));
        offset += n;
    }
    UnstructuredGridPiece {
        points: pts.into(),
        cells: cells(conn, 2, CellType::Line),
        data: Attributes {
            point: vec![
                Attribute::vectors("displacement").with_data(disp),
                Attribute::vectors("traction").with_data(trac),
                Attribute::normals("normal").with_data(normal),
                Attribute::scalars("contact_status", 1).with_data(status),
                Attribute::scalars("normal_traction", 1).with_data(tn),
                Attribute::scalars("normal_opening", 1).with_data(opening),
                Attribute::scalars("body", 1).with_data(body),
            ],
            cell: Vec::new(),
        },
    }
}

/// The triangles of every body in state `k`, with the interior values at their nodes.
fn field_grid(rec: &RunRecord, k: usize) -> UnstructuredGridPiece {
    let st = &rec.states[k];
    let (mut pts, mut disp, mut stress, mut vm) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut principal, mut direction, mut body) = (Vec::new(), Vec::new(), Vec::new());
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
            stress.extend([xx, yy, xy]);
            let s = [[xx, xy], [xy, yy]];
            let zz = out_of_plane_stress(&s, rec.plane, b.poisson);
            vm.push(von_mises(&s, zz));
            let (p, angle) = principal_stresses(&s);
            principal.extend([p[0], p[1], zz]);
            direction.extend([angle.cos(), angle.sin(), 0.0]);
            body.push(bi as i32);
        }
        offset += f.mesh_nodes.len();
    }
    UnstructuredGridPiece {
        points: pts.into(),
        cells: cells(conn, 3, CellType::Triangle),
        data: Attributes {
            point: vec![
                Attribute::vectors("displacement").with_data(disp),
                Attribute::generic("stress", 3).with_data(stress),
                Attribute::scalars("von_mises", 1).with_data(vm),
                Attribute::generic("principal_stress", 3).with_data(principal),
                Attribute::generic("principal_direction", 3).with_data(direction),
                Attribute::scalars("body", 1).with_data(body),
            ],
            cell: Vec::new(),
        },
    }
}
