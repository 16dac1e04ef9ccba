//! Writing the archive: attributes and datasets with their descriptions and units, one
//! group per part of the [`RunRecord`].

use h5::types::TypeDescriptor;
use h5::{Group, H5Type, Location};
use hdf5_metno as h5;
use hdf5_metno_sys as h5sys;
use ndarray::{ArrayViewD, IxDyn};

use crate::input::scene::Units;
use crate::output::record::{
    plane_name, Array, BodyOperators, BodyRecord, InterfaceRecord, IterateRecord, MeshRecord,
    PairingRecord, RunRecord, FORMAT_VERSION,
};
use crate::solution::{BodyMotion, History, HistoryRow, PairResult, PairStatus};

use super::{
    ctx, group_name, offsets, CHUNK_VALUES, COMPRESS, COMPRESS_FROM, DEFLATE_LEVEL, FORMAT, R,
};

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

/// Strings as fixed-length UTF-8, null-padded to `n` bytes each (the longest one's, at
/// least one byte), and their bytes one after another: stored in the attribute or dataset
/// itself, not in the global heap (which has no checksum), and written without the
/// library's allocations of variable-length strings. NUL characters are dropped (a reader
/// would cut the string there).
fn fixed_text(values: &[&str]) -> (TypeDescriptor, Vec<u8>) {
    let clean: Vec<String> = values.iter().map(|s| s.replace('\0', "")).collect();
    let n = clean.iter().map(String::len).max().unwrap_or(0).max(1);
    let mut bytes = vec![0u8; n * clean.len()];
    for (slot, s) in bytes.chunks_exact_mut(n).zip(&clean) {
        slot[..s.len()].copy_from_slice(s.as_bytes());
    }
    (TypeDescriptor::FixedUnicode(n), bytes)
}

/// Writes `bytes` (as from [`fixed_text`], as many strings as `a` holds) into attribute `a`.
fn write_attr_bytes(a: &h5::Attribute, bytes: &[u8], name: &str) -> R<()> {
    let t = ctx(a.dtype(), || format!("attribute {name}"))?;
    if bytes.len() != t.size() * a.size() {
        return Err(format!(
            "attribute {name}: {} bytes for its strings",
            bytes.len()
        ));
    }
    // SAFETY: `bytes` holds exactly the attribute's values in its own (fixed-length string)
    // type, and both handles are open; the library's lock is held as the crate holds it.
    let rc =
        h5::sync::sync(|| unsafe { h5sys::h5a::H5Awrite(a.id(), t.id(), bytes.as_ptr().cast()) });
    if rc < 0 {
        return Err(format!("attribute {name}: the library could not write it"));
    }
    Ok(())
}

fn put_attr_str(loc: &Location, name: &str, value: &str) -> R<()> {
    let (t, bytes) = fixed_text(&[value]);
    let a = ctx(
        loc.new_attr_builder().empty_as(t).shape(()).create(name),
        || format!("attribute {name}"),
    )?;
    write_attr_bytes(&a, &bytes, name)
}

fn put_attr<T: H5Type>(loc: &Location, name: &str, value: T) -> R<()> {
    let a = ctx(loc.new_attr::<T>().shape(()).create(name), || {
        format!("attribute {name}")
    })?;
    ctx(a.write_scalar(&value), || format!("attribute {name}"))
}

fn put_attr_list(loc: &Location, name: &str, values: &[String]) -> R<()> {
    let v: Vec<&str> = values.iter().map(String::as_str).collect();
    let (t, bytes) = fixed_text(&v);
    let a = ctx(
        loc.new_attr_builder()
            .empty_as(t)
            .shape(v.len())
            .create(name),
        || format!("attribute {name}"),
    )?;
    write_attr_bytes(&a, &bytes, name)
}

/// The chunk of a dataset of this shape: whole rows, at most `CHUNK_VALUES` values (`None`
/// for a scalar or an empty dataset, which cannot be chunked).
fn chunk_of(shape: &[usize]) -> Option<Vec<usize>> {
    if shape.is_empty() || shape.contains(&0) {
        return None;
    }
    let mut chunk = shape.to_vec();
    let rest: usize = shape[1..].iter().product::<usize>().max(1);
    // As many chunks as needed, equal in rows: the last one is stored whole (padding).
    let rows = (CHUNK_VALUES / rest).clamp(1, shape[0]);
    chunk[0] = shape[0].div_ceil(shape[0].div_ceil(rows));
    Some(chunk)
}

/// Writes dataset `name` of the given shape with its `description` and `units`; chunked
/// with the Fletcher-32 checksum of each chunk (all but scalars and empty datasets), and
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
    let mut builder = g.new_dataset_builder().with_data(view);
    if let Some(chunk) = chunk_of(shape) {
        builder = builder.chunk(chunk);
        if compress
            && COMPRESS.with(|c| c.get())
            && n >= COMPRESS_FROM
            && h5::filters::deflate_available()
        {
            builder = builder.shuffle().deflate(DEFLATE_LEVEL);
        }
        // Last: the checksum is of the bytes stored.
        builder = builder.fletcher32();
    }
    let ds = ctx(builder.create(name), where_)?;
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

/// A dataset of fixed-length strings (see [`fixed_text`]), chunked with Fletcher-32.
fn put_strs(g: &Group, name: &str, data: &[String], d: &str) -> R<()> {
    let where_ = || format!("{}/{name}", g.name().trim_end_matches('/'));
    let v: Vec<&str> = data.iter().map(String::as_str).collect();
    let (t, bytes) = fixed_text(&v);
    let mut builder = g.new_dataset_builder().empty_as(t).shape(v.len());
    if let Some(chunk) = chunk_of(&[v.len()]) {
        builder = builder.chunk(chunk).fletcher32();
    }
    let ds = ctx(builder.create(name), where_)?;
    if !v.is_empty() {
        let t = ctx(ds.dtype(), where_)?;
        // SAFETY: `bytes` holds exactly the dataset's values in its own (fixed-length
        // string) type, and both handles are open; the library's lock is held as the crate
        // holds it.
        let rc = h5::sync::sync(|| unsafe {
            h5sys::h5d::H5Dwrite(
                ds.id(),
                t.id(),
                h5sys::h5s::H5S_ALL,
                h5sys::h5s::H5S_ALL,
                h5sys::h5p::H5P_DEFAULT,
                bytes.as_ptr().cast(),
            )
        });
        if rc < 0 {
            return Err(format!("{}: the library could not write it", where_()));
        }
    }
    put_attr_str(&ds, "description", d)?;
    put_attr_str(&ds, "units", "")
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

pub(super) fn write_all(file: &h5::File, rec: &RunRecord) -> R<()> {
    write_model(file, rec)?;
    write_solved(file, rec)?;
    write_finished(file, rec)
}

/// The root attributes known before solving, the mesh, the bodies (with their operators) and
/// the interfaces.
pub(super) fn write_model(file: &h5::File, rec: &RunRecord) -> R<()> {
    let u = U::new(&rec.units);
    let root: &Group = file;
    put_attr_str(root, "format", FORMAT)?;
    put_attr(root, "format_version", FORMAT_VERSION)?;
    put_attr_str(root, "tool_version", &rec.tool_version)?;
    put_attr_str(root, "scene", &rec.scene_text)?;
    let overrides = serde_json::to_string(&rec.overrides).unwrap_or_default();
    put_attr_str(root, "overrides", &overrides)?;
    put_attr_str(root, "mesh_sha256", &rec.mesh_sha256)?;
    let units = serde_json::to_string(&rec.units).unwrap_or_default();
    put_attr_str(root, "units", &units)?;
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
pub(super) fn write_solved(file: &h5::File, rec: &RunRecord) -> R<()> {
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
    if !rec.mechanism.is_empty() {
        write_mechanism(&group(root, "mechanism")?, &rec.mechanism, &u)?;
    }

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

/// The mechanism drawn with the last state: one row per moving body.
fn write_mechanism(g: &Group, m: &[BodyMotion], u: &U) -> R<()> {
    let body: Vec<usize> = m.iter().map(|m| m.body).collect();
    let centroid: Vec<[f64; 2]> = m.iter().map(|m| m.centroid).collect();
    let translation: Vec<[f64; 2]> = m.iter().map(|m| m.translation).collect();
    let rotation: Vec<f64> = m.iter().map(|m| m.rotation).collect();
    put_idx(
        g,
        "body",
        &body,
        "each moving body (index in /bodies order)",
    )?;
    put_vec2(
        g,
        "centroid",
        &centroid,
        "the centroid of its nodes",
        u.len(),
    )?;
    put_vec2(
        g,
        "translation",
        &translation,
        "the velocity of its centroid, the fastest boundary node of the mechanism at 1",
        "1",
    )?;
    put_f64(
        g,
        "rotation",
        &[rotation.len()],
        &rotation,
        "its angular velocity, anticlockwise positive: v = translation + rotation k x \
         (x - centroid)",
        &format!("1/{}", u.len()),
    )
}

/// One state of `/states`: every body's and every interface's values in one dataset per
/// quantity, concatenated in `/bodies` and `/interfaces` order (see `node_offset`,
/// `element_offset`, `pair_offset`): a few datasets per state whatever the number of
/// bodies, so that the full history of a wall of hundreds of bricks stays small and quick.
fn write_state_compact(g: &Group, st: &IterateRecord, rec: &RunRecord, u: &U) -> R<()> {
    put_attr(g, "iteration", st.iteration as i64)?;
    put_attr(g, "load_step", st.load_step as i64)?;
    put_attr(g, "load_factor", st.load_factor)?;
    put_body_force(g, st, u)?;
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
pub(super) fn write_finished(file: &h5::File, rec: &RunRecord) -> R<()> {
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

/// A state's body forces (`body_force`, bodies × 2, NaN for a body without one), where they
/// differ from the bodies' own: a body force in pseudo-time, the collapse search's multiplier.
fn put_body_force(g: &Group, st: &IterateRecord, u: &U) -> R<()> {
    if st.body_force.is_empty() {
        return Ok(());
    }
    let f: Vec<[f64; 2]> = st
        .body_force
        .iter()
        .map(|f| f.unwrap_or([f64::NAN; 2]))
        .collect();
    put_vec2(
        g,
        "body_force",
        &f,
        "body force of each body in this state (x, y), before the load factor, where it \
         differs from the body's body_force attribute; NaN: none",
        &u.body_force(),
    )
}

fn write_state(g: &Group, st: &IterateRecord, rec: &RunRecord, u: &U) -> R<()> {
    put_attr(g, "iteration", st.iteration as i64)?;
    put_attr(g, "load_step", st.load_step as i64)?;
    put_attr(g, "load_factor", st.load_factor)?;
    put_body_force(g, st, u)?;
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
