//! Reading the archive back into a [`RunRecord`], every shape checked against the file.

use h5::types::{TypeDescriptor, VarLenUnicode};
use h5::{Group, H5Type, Location};
use hdf5_metno as h5;
use hdf5_metno_sys as h5sys;

use crate::input::scene::{Plane, Units};
use crate::output::record::{
    Array, BodyOperators, BodyRecord, InterfaceRecord, InteriorRecord, IterateRecord, MeshRecord,
    PairingRecord, RunRecord,
};
use crate::solution::{
    BodyField, BodyMotion, History, HistoryRow, InterfaceResult, PairResult, PairStatus,
};

use super::{ctx, group_name, offsets, R};

fn open_group(parent: &Group, name: &str) -> R<Group> {
    ctx(parent.group(name), || {
        format!(
            "missing group {}/{name}",
            parent.name().trim_end_matches('/')
        )
    })
}

pub(super) fn attr_str(loc: &Location, name: &str) -> R<String> {
    let what = || format!("{}: attribute {name}", loc.name());
    let mut v = attr_texts(loc, name)?;
    match v.len() {
        1 => Ok(v.remove(0)),
        k => Err(format!("{}: {k} strings, expected one", what())),
    }
}

/// The strings of attribute `name`: fixed-length (archives since format 1.10 checksums of
/// the data) or variable-length (earlier archives).
fn attr_texts(loc: &Location, name: &str) -> R<Vec<String>> {
    let what = || format!("{}: attribute {name}", loc.name());
    let a = ctx(loc.attr(name), || {
        format!("{}: missing attribute {name}", loc.name())
    })?;
    let t = ctx(a.dtype(), what)?;
    let Some(n) = fixed_len(&t, what)? else {
        let v: Vec<VarLenUnicode> = ctx(a.read_raw(), what)?;
        return Ok(v.iter().map(|s| s.as_str().to_string()).collect());
    };
    let mut bytes = text_buffer(loc, n, a.size(), what)?;
    // SAFETY: `bytes` has room for all the attribute's values in its own (fixed-length
    // string) type, and both handles are open; the library's lock is held as the crate
    // holds it.
    let rc = h5::sync::sync(|| unsafe {
        h5sys::h5a::H5Aread(a.id(), t.id(), bytes.as_mut_ptr().cast())
    });
    if rc < 0 {
        return Err(format!("{}: the library could not read it", what()));
    }
    split_text(&bytes, n, what)
}

/// The length of a fixed-length string type (`None`: a variable-length one).
fn fixed_len(t: &h5::Datatype, what: impl Fn() -> String) -> R<Option<usize>> {
    match ctx(t.to_descriptor(), &what)? {
        TypeDescriptor::FixedUnicode(n) | TypeDescriptor::FixedAscii(n) => Ok(Some(n)),
        TypeDescriptor::VarLenUnicode | TypeDescriptor::VarLenAscii => Ok(None),
        d => Err(format!("{}: holds {d}, not text", what())),
    }
}

/// A buffer for `count` strings of `n` bytes, refused when larger than the file (the
/// lengths of a damaged file).
fn text_buffer(loc: &Location, n: usize, count: usize, what: impl Fn() -> String) -> R<Vec<u8>> {
    let file_size = loc.file().map(|f| f.size()).unwrap_or(0);
    match n.checked_mul(count) {
        Some(b) if b as u64 <= file_size.max(1 << 20) => Ok(vec![0u8; b]),
        _ => Err(format!(
            "{}: {count} strings of {n} bytes, more than the file holds",
            what()
        )),
    }
}

/// Fixed-length strings of `n` bytes each, cut at their first NUL.
fn split_text(bytes: &[u8], n: usize, what: impl Fn() -> String) -> R<Vec<String>> {
    bytes
        .chunks_exact(n.max(1))
        .map(|c| {
            let end = c.iter().position(|&b| b == 0).unwrap_or(c.len());
            String::from_utf8(c[..end].to_vec()).map_err(|_| format!("{}: not UTF-8", what()))
        })
        .collect()
}

fn attr_f64(loc: &Location, name: &str) -> R<f64> {
    let a = ctx(loc.attr(name), || {
        format!("{}: missing attribute {name}", loc.name())
    })?;
    ctx(a.read_scalar(), || {
        format!("{}: attribute {name}", loc.name())
    })
}

pub(super) fn attr_i64(loc: &Location, name: &str) -> R<i64> {
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
    attr_texts(loc, name)
}

/// Reads dataset `name` and checks its shape against `shape` (`None`: any extent).
fn get<T: H5Type>(g: &Group, name: &str, shape: &[Option<usize>]) -> R<(Vec<usize>, Vec<T>)> {
    let where_ = || format!("{}/{name}", g.name().trim_end_matches('/'));
    let ds = ctx(g.dataset(name), || format!("missing dataset {}", where_()))?;
    let s = check_shape(&ds, shape, where_)?;
    let data: Vec<T> = ctx(ds.read_raw(), where_)?;
    if data.len() != s.iter().product::<usize>() {
        return Err(format!("{}: size does not match its shape", where_()));
    }
    Ok((s, data))
}

/// The shape of `ds`, checked against `shape` (`None`: any extent).
fn check_shape(
    ds: &h5::Dataset,
    shape: &[Option<usize>],
    where_: impl Fn() -> String,
) -> R<Vec<usize>> {
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
    Ok(s)
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

/// A dataset of strings: fixed-length (archives since the data's checksums) or
/// variable-length (earlier archives).
fn get_strs(g: &Group, name: &str, len: Option<usize>) -> R<Vec<String>> {
    let where_ = || format!("{}/{name}", g.name().trim_end_matches('/'));
    let ds = ctx(g.dataset(name), || format!("missing dataset {}", where_()))?;
    let t = ctx(ds.dtype(), where_)?;
    let Some(n) = fixed_len(&t, where_)? else {
        let (_, d) = get::<VarLenUnicode>(g, name, &[len])?;
        return Ok(d.iter().map(|s| s.as_str().to_string()).collect());
    };
    let s = check_shape(&ds, &[len], where_)?;
    let mut bytes = text_buffer(g, n, s[0], where_)?;
    if bytes.is_empty() {
        return Ok(Vec::new());
    }
    // SAFETY: `bytes` has room for all the dataset's values in its own (fixed-length
    // string) type, and both handles are open; the library's lock is held as the crate
    // holds it.
    let rc = h5::sync::sync(|| unsafe {
        h5sys::h5d::H5Dread(
            ds.id(),
            t.id(),
            h5sys::h5s::H5S_ALL,
            h5sys::h5s::H5S_ALL,
            h5sys::h5p::H5P_DEFAULT,
            bytes.as_mut_ptr().cast(),
        )
    });
    if rc < 0 {
        return Err(format!(
            "{}: the library could not read it (a checksum that does not match, or damage)",
            where_()
        ));
    }
    split_text(&bytes, n, where_)
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

pub(super) fn read_all(file: &h5::File) -> R<RunRecord> {
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
    if root.link_exists("mechanism") {
        rec.mechanism = read_mechanism(&open_group(root, "mechanism")?)?;
    }
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

/// The mechanism drawn with the last state (`/mechanism`).
fn read_mechanism(g: &Group) -> R<Vec<BodyMotion>> {
    let body = get_idx(g, "body", None)?;
    let k = Some(body.len());
    let centroid = get_vec2(g, "centroid", k)?;
    let translation = get_vec2(g, "translation", k)?;
    let rotation = get_f64(g, "rotation", k)?;
    Ok((0..body.len())
        .map(|i| BodyMotion {
            body: body[i],
            centroid: centroid[i],
            translation: translation[i],
            rotation: rotation[i],
        })
        .collect())
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
) -> R<IterateRecord> {
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
    let mut st = IterateRecord::new(
        attr_usize(g, "iteration")?,
        attr_usize(g, "load_step")?,
        attr_f64(g, "load_factor")?,
        fields,
        interfaces,
    );
    st.body_force = state_body_force(g, rec)?;
    Ok(st)
}

/// A state's `body_force` (where the writer kept it: it differs from the bodies'), empty
/// where there is none; a row of NaN is a body without one.
fn state_body_force(g: &Group, rec: &RunRecord) -> R<Vec<Option<[f64; 2]>>> {
    if !g.link_exists("body_force") {
        return Ok(Vec::new());
    }
    let f = get_vec2(g, "body_force", Some(rec.bodies.len()))?;
    Ok(f.into_iter()
        .map(|v| v.iter().all(|c| c.is_finite()).then_some(v))
        .collect())
}

fn read_state(g: &Group, rec: &RunRecord) -> R<IterateRecord> {
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
    let mut st = IterateRecord::new(
        attr_usize(g, "iteration")?,
        attr_usize(g, "load_step")?,
        attr_f64(g, "load_factor")?,
        fields,
        interfaces,
    );
    st.body_force = state_body_force(g, rec)?;
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
