//! Shared helpers for integration tests: temporary folders, gmsh meshing, a small MSH 4.1
//! writer for hand-made (also deliberately broken) meshes, and the command line.
#![allow(dead_code)]

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

/// A fresh temporary folder for one test.
pub fn tmpdir(name: &str) -> PathBuf {
    // Unique per call: tests of one binary run in parallel and may share a name.
    static COUNT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let k = COUNT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let d = std::env::temp_dir()
        .join("sgbem-tests")
        .join(format!("{name}-{}-{k}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("create temp dir");
    d
}

/// Repository root.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Meshes a .geo file with gmsh (MSH 4.1, ASCII or binary) into `dir`.
pub fn gmsh(geo: &Path, dir: &Path, out_name: &str, binary: bool, opts: &[&str]) -> PathBuf {
    let out = dir.join(out_name);
    let mut cmd = Command::new("gmsh");
    cmd.arg("-2").arg("-format").arg("msh41");
    if binary {
        cmd.arg("-bin");
    }
    cmd.args(opts).arg(geo).arg("-o").arg(&out);
    let o = cmd.output().expect("gmsh must be installed (make setup)");
    assert!(
        o.status.success(),
        "gmsh failed on {}: {}",
        geo.display(),
        String::from_utf8_lossy(&o.stderr)
    );
    out
}

/// Writes a text file and returns its path.
pub fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).expect("write file");
    p
}

/// Runs the sgbem binary; returns (exit code, stdout, stderr).
pub fn sgbem(args: &[&str]) -> (i32, String, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_sgbem"))
        .args(args)
        .output()
        .expect("run sgbem");
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// A hand-made 2D mesh written as MSH 4.1 ASCII: polyline curves, surfaces bounded by
/// signed curves, physical groups.
#[derive(Default)]
pub struct Msh {
    pub nodes: Vec<[f64; 2]>,
    /// (tag, node indices along the curve, physical tags)
    pub curves: Vec<(i32, Vec<usize>, Vec<i32>)>,
    /// (tag, signed bounding curves, physical tags)
    pub surfaces: Vec<(i32, Vec<i32>, Vec<i32>)>,
    /// (dim, tag, name)
    pub names: Vec<(i32, i32, String)>,
}

impl Msh {
    /// Index of a node at p (reused if one exists there).
    pub fn node(&mut self, p: [f64; 2]) -> usize {
        if let Some(i) = self.nodes.iter().position(|q| *q == p) {
            return i;
        }
        self.nodes.push(p);
        self.nodes.len() - 1
    }

    /// A new node at p even if one exists there.
    pub fn new_node(&mut self, p: [f64; 2]) -> usize {
        self.nodes.push(p);
        self.nodes.len() - 1
    }

    /// A straight curve from a to b with n elements; end nodes shared by position.
    pub fn line(&mut self, tag: i32, a: [f64; 2], b: [f64; 2], n: usize, phys: &[i32]) {
        let mut ids = Vec::new();
        for k in 0..=n {
            let t = k as f64 / n as f64;
            let p = if k == n {
                b
            } else {
                [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
            };
            ids.push(if k == 0 || k == n {
                self.node(p)
            } else {
                self.new_node(p)
            });
        }
        self.curves.push((tag, ids, phys.to_vec()));
    }

    pub fn surface(&mut self, tag: i32, bounding: &[i32], phys: &[i32]) {
        self.surfaces.push((tag, bounding.to_vec(), phys.to_vec()));
    }

    pub fn name(&mut self, dim: i32, tag: i32, name: &str) {
        self.names.push((dim, tag, name.to_string()));
    }

    pub fn to_text(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "$MeshFormat\n4.1 0 8\n$EndMeshFormat");
        let _ = writeln!(s, "$PhysicalNames\n{}", self.names.len());
        for (d, t, n) in &self.names {
            let _ = writeln!(s, "{d} {t} \"{n}\"");
        }
        let _ = writeln!(s, "$EndPhysicalNames");
        let _ = writeln!(
            s,
            "$Entities\n0 {} {} 0",
            self.curves.len(),
            self.surfaces.len()
        );
        for (tag, ids, phys) in &self.curves {
            let (lo, hi) = if ids.is_empty() {
                ([0.0; 2], [0.0; 2])
            } else {
                bbox(ids.iter().map(|&i| self.nodes[i]))
            };
            let _ = write!(
                s,
                "{tag} {} {} 0 {} {} 0 {}",
                lo[0],
                lo[1],
                hi[0],
                hi[1],
                phys.len()
            );
            for p in phys {
                let _ = write!(s, " {p}");
            }
            let _ = writeln!(s, " 0");
        }
        for (tag, bnd, phys) in &self.surfaces {
            let _ = write!(s, "{tag} 0 0 0 1 1 0 {}", phys.len());
            for p in phys {
                let _ = write!(s, " {p}");
            }
            let _ = write!(s, " {}", bnd.len());
            for b in bnd {
                let _ = write!(s, " {b}");
            }
            let _ = writeln!(s);
        }
        let _ = writeln!(s, "$EndEntities");
        let n = self.nodes.len();
        let surf = self.surfaces.first().map(|x| x.0).unwrap_or(1);
        let _ = writeln!(s, "$Nodes\n1 {n} 1 {n}\n2 {surf} 0 {n}");
        for i in 0..n {
            let _ = writeln!(s, "{}", i + 1);
        }
        for p in &self.nodes {
            let _ = writeln!(s, "{} {} 0", p[0], p[1]);
        }
        let _ = writeln!(s, "$EndNodes");
        // A curve with no nodes has no elements: what gmsh writes for an untagged curve.
        let meshed: Vec<_> = self.curves.iter().filter(|c| c.1.len() >= 2).collect();
        let total: usize = meshed.iter().map(|c| c.1.len() - 1).sum();
        let _ = writeln!(s, "$Elements\n{} {total} 1 {total}", meshed.len());
        let mut tag = 1;
        for (ctag, ids, _) in meshed {
            let _ = writeln!(s, "1 {ctag} 1 {}", ids.len() - 1);
            for w in ids.windows(2) {
                let _ = writeln!(s, "{tag} {} {}", w[0] + 1, w[1] + 1);
                tag += 1;
            }
        }
        let _ = writeln!(s, "$EndElements");
        s
    }

    pub fn save(&self, dir: &Path, name: &str) -> PathBuf {
        write(dir, name, &self.to_text())
    }
}

fn bbox(points: impl Iterator<Item = [f64; 2]>) -> ([f64; 2], [f64; 2]) {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in points {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

/// Two unit-wide blocks stacked along y: lower [0,1]x[0,1] (surface 1), upper [0,1]x[1,2]
/// (surface 2), joint y = 1 (curve 3), n elements per side. Physical tags: curves base 1,
/// sides 2, joint 3, top 4; surfaces lower 1, upper 2.
pub fn stacked_blocks(n: usize) -> Msh {
    let mut m = Msh::default();
    m.line(1, [0.0, 0.0], [1.0, 0.0], n, &[1]);
    m.line(2, [1.0, 0.0], [1.0, 1.0], n, &[2]);
    m.line(3, [1.0, 1.0], [0.0, 1.0], n, &[3]);
    m.line(4, [0.0, 1.0], [0.0, 0.0], n, &[2]);
    m.line(5, [1.0, 1.0], [1.0, 2.0], n, &[2]);
    m.line(6, [1.0, 2.0], [0.0, 2.0], n, &[4]);
    m.line(7, [0.0, 2.0], [0.0, 1.0], n, &[2]);
    m.surface(1, &[1, 2, 3, 4], &[1]);
    m.surface(2, &[-3, 5, 6, 7], &[2]);
    m.name(1, 1, "base");
    m.name(1, 2, "sides");
    m.name(1, 3, "joint");
    m.name(1, 4, "top");
    m.name(2, 1, "lower");
    m.name(2, 2, "upper");
    m
}

/// A scene for [`stacked_blocks`].
pub const STACKED_SCENE: &str = r#"
plane = "strain"
[body.lower]
young = 1.0
poisson = 0.3
[body.upper]
young = 1.0
poisson = 0.3
[boundary.base]
ux = 0.0
uy = 0.0
[boundary.top]
ty = -1.0
[interface.joint]
model = "unilateral"
"#;

/// One row of an `interfaces/<name>.csv` table.
#[derive(Debug, Clone)]
pub struct InterfaceRow {
    pub x: f64,
    pub y: f64,
    pub s: f64,
    pub closed: bool,
    pub tn: f64,
    pub tt: f64,
    pub opening: f64,
    pub slip: f64,
    pub gap: f64,
    /// Friction interfaces: `stick`, `slip` or `open`, and the accumulated slip path.
    pub tangential_status: Option<String>,
    pub slip_path: f64,
}

/// Reads an interface table written by `sgbem run`, checking its header.
pub fn read_interface_csv(path: &Path) -> Vec<InterfaceRow> {
    let text = std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    let mut lines = text.lines();
    let header = lines.next().unwrap_or("");
    let base =
        "x,y,s,status,normal_traction,tangential_traction,normal_opening,tangential_slip,gap";
    // Sides meshed on their own add the columns side and segment.
    let header = header.strip_suffix(",side,segment").unwrap_or(header);
    assert!(
        header == base || header == format!("{base},tangential_status,slip"),
        "{}: header {header}",
        path.display()
    );
    lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            let num = |i: usize| -> f64 { f[i].parse().expect("a number in the interface CSV") };
            InterfaceRow {
                x: num(0),
                y: num(1),
                s: num(2),
                closed: match f[3] {
                    "closed" => true,
                    "open" => false,
                    other => panic!("unknown status {other}"),
                },
                tn: num(4),
                tt: num(5),
                opening: num(6),
                slip: num(7),
                gap: num(8),
                tangential_status: f.get(9).map(|v| v.to_string()),
                slip_path: f.get(10).map_or(0.0, |v| v.parse().expect("a number")),
            }
        })
        .collect()
}

/// Peak resident memory (kB) of this process since the last [`reset_peak`] (benches).
pub fn peak_kb() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|v| v.parse().ok())
        })
        .unwrap_or(0)
}

/// Resets the peak resident memory counter of this process.
pub fn reset_peak() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// A fresh folder `name` with `geo/two_blocks.geo` meshed (16 elements per unit length) as
/// `tb.msh`: "upper" (1 × 0.5) on "lower" (clamped at its bottom, `base`), joined along
/// `joint`.
pub fn two_blocks_mesh(name: &str) -> PathBuf {
    let dir = tmpdir(name);
    gmsh(
        &root().join("geo/two_blocks.geo"),
        &dir,
        "tb.msh",
        false,
        &["-setnumber", "n", "16"],
    );
    dir
}

/// The scene of [`two_blocks_mesh`]: both blocks E = 1000, ν = 0.3, the upper one under
/// the body force `body_force` (a TOML value), Coulomb friction μ on the joint (closed at
/// the start), then the TOML tables `solve`; output to `out` without the interior field,
/// and without VTK files unless `vtk`.
pub fn two_blocks_scene(body_force: &str, mu: f64, solve: &str, vtk: bool) -> String {
    format!(
        r#"
mesh = "tb.msh"
plane = "strain"
[body.lower]
young = 1000.0
poisson = 0.3
[body.upper]
young = 1000.0
poisson = 0.3
body_force = {body_force}
[boundary.base]
ux = 0.0
uy = 0.0
[interface.joint]
model = "unilateral"
initial = "closed"
tangential = "friction"
friction = {mu}
{solve}
[output]
directory = "out"
field = false
vtk = {vtk}
"#
    )
}

/// A unit body force tilted by θ from the vertical, tan θ = `tan` (a TOML array).
pub fn tilted(tan: f64) -> String {
    let th = tan.atan();
    format!("[{}, {}]", th.sin(), -th.cos())
}

/// `sgbem run SCENE --out OUT --quiet`: the exit code and stderr.
pub fn run_scene(scene: &Path, out: &Path) -> (i32, String) {
    let s = |p: &Path| p.to_str().expect("utf-8 path").to_string();
    let (code, _, err) = sgbem(&["run", &s(scene), "--out", &s(out), "--quiet"]);
    (code, err)
}

/// `sgbem run SCENE --mesh MESH --out OUT --quiet`.
pub fn run_quiet(scene: &Path, mesh: &Path, out: &Path) -> (i32, String, String) {
    let s = |p: &Path| p.to_str().expect("utf-8 path").to_string();
    let (scene, mesh, out) = (s(scene), s(mesh), s(out));
    sgbem(&["run", &scene, "--mesh", &mesh, "--out", &out, "--quiet"])
}

/// `sgbem run SCENE --mesh MESH --out OUT --method METHOD --quiet`; returns the exit code,
/// stderr and the summary (where written: a failed contact solve writes it too).
pub fn run_method(
    scene: &Path,
    mesh: &Path,
    out: &Path,
    method: &str,
) -> (i32, String, Option<serde_json::Value>) {
    let s = |p: &Path| p.to_str().expect("utf-8 path").to_string();
    let (scene, mesh, out_s) = (s(scene), s(mesh), s(out));
    let (code, _, err) = sgbem(&[
        "run", &scene, "--mesh", &mesh, "--out", &out_s, "--method", method, "--quiet",
    ]);
    let summary = std::fs::read_to_string(out.join("summary.json"))
        .ok()
        .map(|t| serde_json::from_str(&t).expect("summary.json is JSON"));
    (code, err, summary)
}

/// Asserts an exit status, no panic, and (on failure) a message on stderr that starts
/// with `sgbem: ` and names every word.
pub fn expect_exit(out: &(i32, String, String), code: i32, words: &[&str]) {
    let (c, _, err) = out;
    assert_eq!(*c, code, "exit status; stderr: {err}");
    assert!(!err.contains("panicked"), "{err}");
    if code != 0 {
        assert!(err.starts_with("sgbem: "), "{err}");
    }
    for w in words {
        assert!(err.contains(w), "message should say {w:?}: {err}");
    }
}

/// Decodes base64 (RFC 4648, with padding).
pub fn b64_decode(text: &str) -> Vec<u8> {
    let val = |c: u8| -> u32 {
        match c {
            b'A'..=b'Z' => u32::from(c - b'A'),
            b'a'..=b'z' => u32::from(c - b'a') + 26,
            b'0'..=b'9' => u32::from(c - b'0') + 52,
            b'+' => 62,
            b'/' => 63,
            _ => panic!("not base64: {c}"),
        }
    };
    let mut out = Vec::new();
    for chunk in text.as_bytes().chunks(4) {
        let pad = chunk.iter().filter(|&&c| c == b'=').count();
        let mut n = 0u32;
        for (i, &c) in chunk.iter().enumerate() {
            n |= if c == b'=' { 0 } else { val(c) } << (18 - 6 * i);
        }
        out.extend_from_slice(&n.to_be_bytes()[1..4 - pad]);
    }
    out
}

/// The values of every binary array of a VTK file by name (Points, connectivity, … too):
/// plain (UInt64 size, then the bytes) or zlib-compressed (header in its own base64, then the
/// blocks).
pub fn binary_arrays(xml: &str, compressed: bool) -> Vec<(String, Vec<u8>)> {
    use std::io::Read as _;
    let mut out = Vec::new();
    for piece in xml.split("<DataArray").skip(1) {
        if !piece.contains("format=\"binary\"") {
            continue;
        }
        let name = piece
            .split("Name=\"")
            .nth(1)
            .unwrap()
            .split('"')
            .next()
            .unwrap();
        let text = piece.split('>').nth(1).unwrap().split('<').next().unwrap();
        let bytes = if compressed {
            // The header: 3 + blocks UInt64, 4/3 of it in base64 rounded up to 4 chars.
            let first = b64_decode(&text[..12]);
            let blocks = u64::from_le_bytes(first[..8].try_into().unwrap()) as usize;
            let header_chars = (8 * (3 + blocks)).div_ceil(3) * 4;
            let header = b64_decode(&text[..header_chars]);
            let h: Vec<usize> = header
                .chunks(8)
                .take(3 + blocks)
                .map(|c| u64::from_le_bytes(c.try_into().unwrap()) as usize)
                .collect();
            let data = b64_decode(&text[header_chars..]);
            let (mut at, mut v) = (0, Vec::new());
            for &size in &h[3..] {
                let mut z = flate2::read::ZlibDecoder::new(&data[at..at + size]);
                z.read_to_end(&mut v).unwrap();
                at += size;
            }
            let expected = if h[2] == 0 {
                h[0] * h[1]
            } else {
                (h[0] - 1) * h[1] + h[2]
            };
            assert_eq!(v.len(), expected, "{name}: block sizes");
            v
        } else {
            let v = b64_decode(text);
            let n = u64::from_le_bytes(v[..8].try_into().unwrap()) as usize;
            v[8..8 + n].to_vec()
        };
        out.push((name.to_string(), bytes));
    }
    out
}

/// One boundary node of the VTK block "mechanism": its body, position and
/// `mechanism_velocity`.
#[derive(Debug, Clone, Copy)]
pub struct MechanismNode {
    pub body: i32,
    pub x: [f64; 2],
    pub v: [f64; 3],
}

/// The VTK block "mechanism" of a run folder `out`: where the last state's multiblock
/// (`vtk/state_NNNN.vtm`) names it, its nodes; none where it has no such block. Asserts that
/// no other state's multiblock names one and that the file is the only `mechanism_*.vtu`.
pub fn mechanism_block(out: &Path) -> Option<Vec<MechanismNode>> {
    let vtk = out.join("vtk");
    let mut states: Vec<String> = std::fs::read_dir(&vtk)
        .expect("vtk folder")
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.starts_with("state_") && n.ends_with(".vtm"))
        .collect();
    states.sort();
    let last = states.pop().expect("a state multiblock");
    for s in &states {
        let text = std::fs::read_to_string(vtk.join(s)).unwrap();
        assert!(
            !text.contains("\"mechanism\""),
            "{s} names a mechanism block"
        );
    }
    let vtm = std::fs::read_to_string(vtk.join(&last)).unwrap();
    let file = vtm
        .split("name=\"mechanism\" file=\"")
        .nth(1)?
        .split('"')
        .next()
        .unwrap();
    assert_eq!(
        file,
        last.replace("state_", "mechanism_").replace(".vtm", ".vtu")
    );
    let files = std::fs::read_dir(&vtk).unwrap().filter(|e| {
        let n = e.as_ref().unwrap().file_name();
        n.to_string_lossy().starts_with("mechanism_")
    });
    assert_eq!(files.count(), 1, "one mechanism file");
    let xml = std::fs::read_to_string(vtk.join(file)).unwrap();
    let arrays = binary_arrays(&xml, xml.contains("vtkZLibDataCompressor"));
    let get = |n: &str| &arrays.iter().find(|(k, _)| k == n).expect(n).1;
    let f64s = |n: &str| -> Vec<f64> {
        get(n)
            .chunks(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
            .collect()
    };
    let (points, velocity) = (f64s("Points"), f64s("mechanism_velocity"));
    let body: Vec<i32> = get("body")
        .chunks(4)
        .map(|c| i32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert_eq!(points.len(), 3 * body.len());
    assert_eq!(velocity.len(), 3 * body.len());
    Some(
        (0..body.len())
            .map(|i| MechanismNode {
                body: body[i],
                x: [points[3 * i], points[3 * i + 1]],
                v: [velocity[3 * i], velocity[3 * i + 1], velocity[3 * i + 2]],
            })
            .collect(),
    )
}

/// `sgbem run pipelines/NAME.toml --out OUT --quiet` (a shipped scene): the exit code and
/// stderr.
pub fn run_shipped(name: &str, out: &Path) -> (i32, String) {
    let scene = root().join("pipelines").join(format!("{name}.toml"));
    let (scene, out) = (scene.to_str().unwrap(), out.to_str().unwrap());
    let (code, _, err) = sgbem(&["run", scene, "--out", out, "--quiet"]);
    (code, err)
}

/// A run folder's summary.json.
pub fn read_summary(out: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(out.join("summary.json")).expect("summary.json");
    serde_json::from_str(&text).expect("summary.json is JSON")
}
