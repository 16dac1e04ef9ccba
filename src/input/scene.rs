//! The scene file (TOML): materials, conditions, interfaces, solver and output settings.
//!
//! Place in the flow: the first stage. `read_scene` turns the file into a validated
//! [`Scene`]; nothing after it sees TOML. Validation here covers everything that can be
//! judged without the mesh: unknown keys (with the nearest valid key suggested), types,
//! ranges (`young > 0`, `-1 < poisson < 0.5`, non-negative cohesion and friction; a negative
//! gap is an interference), conflicting
//! conditions (`ux` with `tx`), expressions that do not parse. Checks that need the mesh
//! (group names and kinds, loops, interfaces) are made by `model`.
//!
//! Every message names the scene file and the key path, e.g. `body.A.poisson`.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::error::{did_you_mean, Error, Result};
use crate::input::expr::{Expr, Scalar};
use crate::input::tables::{Glob, Pattern, Tables};

/// Plane strain or plane stress (docs/scene.md §2, `plane`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Plane {
    Strain,
    Stress,
}

/// A body: the material of a Physical Surface.
#[derive(Debug, Clone)]
pub struct BodySpec {
    pub name: String,
    pub young: f64,
    pub poisson: f64,
    /// Force per unit volume (uniform in the body; each component a number or an
    /// expression in the pseudo-time `t`); `None` when the scene gives none.
    pub body_force: Option<[Scalar; 2]>,
}

impl BodySpec {
    /// The body force at pseudo-time t.
    pub fn body_force_at(&self, t: f64) -> Option<[f64; 2]> {
        self.body_force
            .as_ref()
            .map(|b| [b[0].eval([0.0, 0.0], t), b[1].eval([0.0, 0.0], t)])
    }
}

/// The frame in which a boundary gives its components.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Frame {
    /// Components x, y.
    Global,
    /// Components t (tangential, along the loop with the body on the left), n (outward normal).
    Local,
}

/// The condition on one component of a boundary part.
#[derive(Debug, Clone)]
pub enum Condition {
    /// Prescribed displacement component (Γ1 in this direction).
    Displacement(Scalar),
    /// Prescribed traction component (Γ2 in this direction); absent components are 0.
    Traction(Scalar),
}

impl Condition {
    pub fn is_displacement(&self) -> bool {
        matches!(self, Condition::Displacement(_))
    }
}

/// Conditions on a Physical Curve that is not an interface.
#[derive(Debug, Clone)]
pub struct BoundarySpec {
    pub name: String,
    pub frame: Frame,
    /// Component 0 is x (or t), component 1 is y (or n).
    pub components: [Condition; 2],
}

impl BoundarySpec {
    /// The traction-free condition of a Physical Curve the scene does not list.
    pub fn traction_free(name: &str) -> BoundarySpec {
        BoundarySpec {
            name: name.to_string(),
            frame: Frame::Global,
            components: [
                Condition::Traction(Scalar::Const(0.0)),
                Condition::Traction(Scalar::Const(0.0)),
            ],
        }
    }

    /// Short description for reports: `ux=0 uy=0`, `ty=-10`, `traction-free`.
    pub fn describe(&self) -> String {
        let names = match self.frame {
            Frame::Global => ["x", "y"],
            Frame::Local => ["t", "n"],
        };
        let mut parts = Vec::new();
        for (c, n) in self.components.iter().zip(names) {
            match c {
                Condition::Displacement(v) => parts.push(format!("u{n}={v}")),
                Condition::Traction(v) if !v.is_zero() => parts.push(format!("t{n}={v}")),
                Condition::Traction(_) => {}
            }
        }
        if parts.is_empty() {
            "traction-free".into()
        } else {
            parts.join(" ")
        }
    }

    /// Constrained (all components displacement), free (all traction) or mixed.
    pub fn role(&self) -> &'static str {
        match (
            self.components[0].is_displacement(),
            self.components[1].is_displacement(),
        ) {
            (true, true) => "constrained",
            (false, false) => "free",
            _ => "mixed",
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InterfaceModel {
    Bonded,
    Unilateral,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InitialState {
    /// In contact (real).
    Closed,
    /// Detached (virtual).
    Open,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Tangential {
    /// Closed nodes bonded in both directions (the paper's "no friction and no sliding").
    Stick,
    /// Frictionless: the tangential component is always free.
    Slide,
    /// Coulomb friction with the coefficient `friction` of the interface.
    Friction,
}

impl Tangential {
    pub fn name(self) -> &'static str {
        match self {
            Tangential::Stick => "stick",
            Tangential::Slide => "slide",
            Tangential::Friction => "friction",
        }
    }
}

/// An interface: a Physical Curve shared by two bodies.
#[derive(Debug, Clone)]
pub struct InterfaceSpec {
    pub name: String,
    pub model: InterfaceModel,
    pub initial: InitialState,
    pub cohesion: Scalar,
    pub gap: Scalar,
    pub tangential: Tangential,
    /// Coulomb coefficient μ ≥ 0 (with `tangential = "friction"`; 0 otherwise).
    pub friction: Scalar,
    /// `between = [A, B]`: the interface joins Physical Curve A (on one body) and Physical
    /// Curve B (on another) instead of being a Physical Curve of its own.
    pub between: Option<[String; 2]>,
}

/// `[contact]`: interfaces found from the drawing (docs/scene.md).
#[derive(Debug, Clone)]
pub struct ContactSpec {
    /// The bodies (a glob over their names) whose boundaries may touch one another.
    pub bodies: crate::input::tables::Glob,
    /// The largest gap (length units) at which facing boundaries pair up.
    pub search: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    Lcp,
    Qp,
    Both,
    /// The active set iteration on the sparse system of displacements and openings (no
    /// dense column of the opening stiffness: for scenes of many bodies).
    Sparse,
}

impl Method {
    pub fn name(self) -> &'static str {
        match self {
            Method::Lcp => "lcp",
            Method::Qp => "qp",
            Method::Both => "both",
            Method::Sparse => "sparse",
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quadrature {
    Fast,
    Standard,
    Accurate,
}

impl Quadrature {
    pub fn name(self) -> &'static str {
        match self {
            Quadrature::Fast => "fast",
            Quadrature::Standard => "standard",
            Quadrature::Accurate => "accurate",
        }
    }
}

#[derive(Debug, Clone)]
pub struct SolveSpec {
    pub method: Method,
    /// `method` was given (in the scene or by `--method`); otherwise it follows the size of
    /// the model ([`SolveSpec::choose_method`]).
    pub method_given: bool,
    pub tolerance: f64,
    /// Contact iterations per load step; `None`: automatic, the larger of 1000 and four per
    /// pair component that can open (a wall of hundreds of bricks needs a switch per head
    /// joint pair that opens, and more with friction).
    pub max_iterations: Option<usize>,
    pub load_factors: Vec<f64>,
    /// Pseudo-time steps (`[solve] time`), increasing; `None` with load factors.
    pub time: Option<Vec<f64>>,
    /// `[solve] collapse`: find the largest pseudo-time t (the load multiplier) at which
    /// equilibrium exists, by bisection.
    pub collapse: Option<Collapse>,
    pub quadrature: Quadrature,
}

/// The collapse search: t in [0, max], bisected to `tolerance` (absolute, in t).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Collapse {
    pub max: f64,
    pub tolerance: f64,
}

/// Unilateral pairs above which a scene without `method` is solved by the sparse solver:
/// the evolutive path's dense columns cost more from there (measured on running-bond walls:
/// 105 bricks, 2 000 pairs, contact 0.3 s evolutive against 0.4 s sparse; 410 bricks,
/// 8 050 pairs, 15.7 s against 4.1 s).
pub const SPARSE_FROM_PAIRS: usize = 3000;

impl SolveSpec {
    /// The method of a scene without `method`: the evolutive path (`lcp`, the paper's, every
    /// switch recorded) up to [`SPARSE_FROM_PAIRS`] unilateral pairs, the sparse solver above.
    pub fn choose_method(&mut self, unilateral_pairs: usize) {
        if !self.method_given && unilateral_pairs > SPARSE_FROM_PAIRS {
            self.method = Method::Sparse;
        }
    }

    /// The load steps as (load factor, pseudo-time): `(f, 1)` for each load factor, or
    /// `(1, t)` for each pseudo-time value.
    pub fn steps(&self) -> Vec<(f64, f64)> {
        match &self.time {
            Some(ts) => ts.iter().map(|&t| (1.0, t)).collect(),
            None => self.load_factors.iter().map(|&f| (f, 1.0)).collect(),
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum History {
    Full,
    Final,
}

/// A segment along which displacements and stresses are sampled.
#[derive(Debug, Clone)]
pub struct SectionSpec {
    pub name: String,
    pub from: [f64; 2],
    pub to: [f64; 2],
    pub points: usize,
}

#[derive(Debug, Clone)]
pub struct OutputSpec {
    pub directory: PathBuf,
    pub history: History,
    pub operators: bool,
    /// Deflate the archive's large datasets (shuffle + deflate): about a third smaller, for
    /// about 0.2 s of CPU per 10 MB of operators; off by default.
    pub compress: bool,
    pub vtk: bool,
    pub field: bool,
    pub sections: Vec<SectionSpec>,
}

#[derive(Debug, Clone, Default)]
pub struct Units {
    pub length: String,
    pub force: String,
}

/// A validated scene. Paths are resolved against the scene file's folder.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The scene file, as given.
    pub path: PathBuf,
    /// Its text, kept for the archive.
    pub text: String,
    pub title: String,
    /// The mesh file, if the scene names one (`--mesh` overrides it): a `.msh`, or a
    /// `.geo` that the pipeline meshes with gmsh.
    pub mesh: Option<PathBuf>,
    /// gmsh `-setnumber NAME VALUE` parameters for a `.geo` mesh (the `[mesh]` table's keys
    /// other than `file`), in file order.
    pub mesh_parameters: Vec<(String, f64)>,
    /// The `--set KEY=VALUE` overrides applied to the file's text, in order.
    pub overrides: Vec<String>,
    pub plane: Plane,
    pub thickness: f64,
    pub units: Units,
    /// Bodies in scene order.
    pub bodies: Vec<BodySpec>,
    pub boundaries: Vec<BoundarySpec>,
    pub interfaces: Vec<InterfaceSpec>,
    /// `[contact]`: find interfaces between the bodies' boundaries from the drawing.
    pub contact: Option<ContactSpec>,
    /// Glob tables and `[defaults]`, resolved against the mesh by `model`.
    pub tables: Tables,
    pub solve: SolveSpec,
    pub output: OutputSpec,
}

impl Scene {
    pub fn body(&self, name: &str) -> Option<&BodySpec> {
        self.bodies.iter().find(|b| b.name == name)
    }
    pub fn boundary(&self, name: &str) -> Option<&BoundarySpec> {
        self.boundaries.iter().find(|b| b.name == name)
    }
    pub fn interface(&self, name: &str) -> Option<&InterfaceSpec> {
        self.interfaces.iter().find(|b| b.name == name)
    }
}

/// Reads and validates a scene file.
pub fn read_scene(path: &Path) -> Result<Scene> {
    read_scene_with(path, &[])
}

/// Reads a scene file, applies the `--set KEY=VALUE` overrides to its TOML document and
/// validates the result exactly like a file.
pub fn read_scene_with(path: &Path, sets: &[String]) -> Result<Scene> {
    let bytes = std::fs::read(path)
        .map_err(|e| Error::io(path, format!("cannot read the scene file: {e}")))?;
    if let Some(hint) = not_a_scene(path, &bytes) {
        return Err(Error::input(path, hint));
    }
    let text = match std::str::from_utf8(&bytes) {
        Ok(t) => t,
        Err(e) => {
            return Err(Error::input(
                path,
                format!(
                    "the scene is not UTF-8 text (invalid byte at offset {}): a scene is a TOML \
                     text file; save it as UTF-8",
                    e.valid_up_to()
                ),
            ))
        }
    };
    parse_scene_with(text, path, sets)
}

/// One `--set KEY=VALUE`: the dotted key path and the value. The value is read as a TOML
/// value (number, string, boolean, array, inline table); anything that is not one is taken
/// as a bare string, so `--set solve.method=qp` works without quotes.
pub fn parse_set(set: &str) -> std::result::Result<(Vec<String>, toml::Value), String> {
    let whole = set;
    let set = &shown_set(set);
    let Some((key, value)) = whole.split_once('=') else {
        return Err(format!(
            "--set {set}: expected KEY=VALUE, e.g. --set interface.joint.cohesion=2.0"
        ));
    };
    let key = key.trim();
    // Every key of a scene is at most four levels deep (defaults.interface.NAME.KEY);
    // bounding the path keeps a hostile key from exhausting the stack or memory.
    const MAX_PARTS: usize = 8;
    const MAX_KEY: usize = 512;
    if key.len() > MAX_KEY || key.split('.').count() > MAX_PARTS {
        return Err(format!(
            "--set {set}: the key has {} characters and {} dotted parts; a scene key has \
             at most {MAX_PARTS} parts and {MAX_KEY} characters (e.g. \
             interface.joint.cohesion=2.0)",
            key.len(),
            key.split('.').count()
        ));
    }
    let path: Vec<String> = key.split('.').map(|k| k.trim().to_string()).collect();
    if path.iter().any(|k| k.is_empty()) {
        return Err(format!(
            "--set {set}: `{key}` is not a dotted key path such as solve.method"
        ));
    }
    let value = value.trim();
    let parsed = format!("v = {value}")
        .parse::<toml::Table>()
        .ok()
        .and_then(|mut t| t.remove("v"));
    Ok((
        path,
        parsed.unwrap_or_else(|| toml::Value::String(value.to_string())),
    ))
}

/// Applies one override to a TOML document, creating the tables on its path (`*` matches
/// every key of a table). A top-level `mesh = "FILE"` becomes `[mesh] file = "FILE"` when a
/// mesh parameter is set.
fn apply_set(doc: &mut toml::Table, set: &str) -> std::result::Result<(), String> {
    let (path, value) = parse_set(set)?;
    if path.len() > 1 && path[0] == "mesh" {
        if let Some(toml::Value::String(file)) = doc.get("mesh") {
            let mut t = toml::Table::new();
            t.insert("file".into(), toml::Value::String(file.clone()));
            doc.insert("mesh".into(), toml::Value::Table(t));
        }
    }
    set_path(doc, &path, 0, &value, &shown_set(set))
}

/// A `--set` as messages show it: whole up to 100 characters, else its start and length.
pub fn shown_set(set: &str) -> String {
    if set.chars().count() <= 100 {
        return set.to_string();
    }
    let start: String = set.chars().take(80).collect();
    format!("{start}… ({} characters)", set.len())
}

/// Sets `path[i..]` below `table` (the keys before `i` already walked). A `*` segment stands
/// for every existing key of its table, e.g. `interface.*.cohesion`.
fn set_path(
    table: &mut toml::Table,
    path: &[String],
    i: usize,
    value: &toml::Value,
    set: &str,
) -> std::result::Result<(), String> {
    let k = &path[i];
    let last = i + 1 == path.len();
    if k == "*" {
        if last {
            return Err(format!(
                "--set {set}: `*` stands for a table's keys, not a value"
            ));
        }
        if table.is_empty() {
            return Err(format!(
                "--set {set}: `{}` has no entries for `*` to match{}",
                path[..i].join("."),
                if i == 1 && matches!(path[0].as_str(), "body" | "interface") {
                    format!(
                        " (a [defaults.{0}] table is set with --set defaults.{0}.KEY=VALUE)",
                        path[0]
                    )
                } else {
                    String::new()
                }
            ));
        }
        for (name, v) in table.iter_mut() {
            match v {
                toml::Value::Table(t) => set_path(t, path, i + 1, value, set)?,
                _ => {
                    return Err(format!(
                        "--set {set}: `{}.{name}` is not a table",
                        path[..i].join(".")
                    ))
                }
            }
        }
        return Ok(());
    }
    if last {
        table.insert(k.clone(), value.clone());
        return Ok(());
    }
    let entry = table
        .entry(k.clone())
        .or_insert_with(|| toml::Value::Table(toml::Table::new()));
    match entry {
        toml::Value::Table(t) => set_path(t, path, i + 1, value, set),
        _ => Err(format!(
            "--set {set}: `{}` is not a table, so it has no key `{}`",
            path[..=i].join("."),
            path[i + 1]
        )),
    }
}

/// [`parse_scene`] with `--set KEY=VALUE` overrides applied to the document first. An error
/// that only the overrides cause names the first `--set` that causes it.
pub fn parse_scene_with(text: &str, path: &Path, sets: &[String]) -> Result<Scene> {
    if sets.is_empty() {
        return parse_scene(text, path);
    }
    let doc = parse_doc(text, path)?;
    let with = |n: usize| -> Result<Scene> {
        let mut d = doc.clone();
        for set in &sets[..n] {
            apply_set(&mut d, set).map_err(|m| Error::input(path, m))?;
        }
        let mut scene = validate(&d, text, path)?;
        scene.overrides = sets[..n].to_vec();
        Ok(scene)
    };
    match with(sets.len()) {
        Ok(scene) => Ok(scene),
        Err(e) => {
            if validate(&doc, text, path).is_err() {
                return Err(e);
            }
            // The file alone is valid: name the first override that breaks it.
            for k in 1..=sets.len() {
                if let Err(e) = with(k) {
                    let m = e.message();
                    if let Some(hint) = crate::input::tables::defaults_hint(&doc, &sets[k - 1]) {
                        return Err(Error::input(path, format!("--set {}: {hint}", sets[k - 1])));
                    }
                    if m.starts_with("--set ") {
                        return Err(e);
                    }
                    return Err(Error::input(
                        path,
                        format!("--set {}: {m}", shown_set(&sets[k - 1])),
                    ));
                }
            }
            Err(e)
        }
    }
}

/// A hint when the file given as the scene is another kind of file sgbem knows.
fn not_a_scene(path: &Path, bytes: &[u8]) -> Option<String> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    let head = String::from_utf8_lossy(&bytes[..bytes.len().min(4096)]).into_owned();
    if bytes.starts_with(b"\x89HDF") || ext == "h5" {
        return Some(
            "this is an HDF5 archive, not a scene: give the .toml scene it came from, or read \
             it with `sgbem inspect FILE.h5`"
                .into(),
        );
    }
    if head.trim_start().starts_with("$MeshFormat") || ext == "msh" {
        return Some(
            "this is a gmsh mesh, not a scene: pass it with --mesh FILE.msh (or mesh = \
             \"FILE.msh\" in the scene) and give the .toml scene as the first argument"
                .into(),
        );
    }
    let geo_words = [
        "SetFactory",
        "Point(",
        "Line(",
        "Curve Loop(",
        "Plane Surface(",
    ];
    if ext == "geo" || geo_words.iter().any(|w| head.contains(w)) {
        return Some(
            "this is a gmsh geometry, not a scene: mesh it with gmsh -2 -format msh41 FILE.geo \
             -o FILE.msh, then pass a .toml scene that names the mesh"
                .into(),
        );
    }
    None
}

/// Err message when `name` cannot be used as a file or group name: it must be made of ASCII
/// letters, digits, `.`, `_` and `-`, not be empty and not start with `.`.
pub fn file_name_problem(name: &str) -> Option<String> {
    if name.is_empty() {
        return Some("the name is empty".into());
    }
    if name.starts_with('.') {
        return Some(format!(
            "the name \"{name}\" starts with `.` (a hidden file)"
        ));
    }
    if let Some(c) = name
        .chars()
        .find(|c| !(c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-')))
    {
        return Some(format!("the name \"{name}\" holds `{c}`"));
    }
    if name.len() > 100 {
        return Some(format!("the name \"{name}\" is longer than 100 characters"));
    }
    None
}

/// Young's moduli outside this range are refused as extreme values.
pub const YOUNG_RANGE: (f64, f64) = (1e-100, 1e100);

// ---------------------------------------------------------------------------------------
// Raw TOML shapes (serde). Unknown keys are caught first by `check_keys` for a friendly
// message; `deny_unknown_fields` stays as a second guard.

#[derive(Deserialize)]
#[serde(untagged)]
enum RawScalar {
    Number(f64),
    Text(String),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBody {
    young: f64,
    poisson: f64,
    body_force: Option<[RawScalar; 2]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBoundary {
    ux: Option<RawScalar>,
    uy: Option<RawScalar>,
    un: Option<RawScalar>,
    ut: Option<RawScalar>,
    tx: Option<RawScalar>,
    ty: Option<RawScalar>,
    tn: Option<RawScalar>,
    tt: Option<RawScalar>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawInterface {
    model: String,
    initial: Option<String>,
    cohesion: Option<RawScalar>,
    gap: Option<RawScalar>,
    tangential: Option<String>,
    friction: Option<RawScalar>,
    between: Option<Vec<String>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawContact {
    bodies: Option<String>,
    search: f64,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawSolve {
    method: Option<String>,
    tolerance: Option<f64>,
    max_iterations: Option<i64>,
    load_factors: Option<Vec<f64>>,
    time: Option<Vec<f64>>,
    collapse: Option<RawCollapse>,
    quadrature: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCollapse {
    max: f64,
    tolerance: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSection {
    name: String,
    from: [f64; 2],
    to: [f64; 2],
    points: i64,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawOutput {
    directory: Option<String>,
    history: Option<String>,
    operators: Option<bool>,
    compress: Option<bool>,
    vtk: Option<bool>,
    field: Option<bool>,
    #[serde(default)]
    section: Vec<RawSection>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawUnits {
    length: Option<String>,
    force: Option<String>,
}

const TOP_KEYS: [&str; 12] = [
    "title",
    "mesh",
    "plane",
    "thickness",
    "units",
    "body",
    "boundary",
    "interface",
    "defaults",
    "contact",
    "solve",
    "output",
];
const CONTACT_KEYS: [&str; 2] = ["bodies", "search"];
const DEFAULTS_KEYS: [&str; 2] = ["body", "interface"];
const UNITS_KEYS: [&str; 2] = ["length", "force"];
const BODY_KEYS: [&str; 3] = ["young", "poisson", "body_force"];
const BOUNDARY_KEYS: [&str; 8] = ["ux", "uy", "un", "ut", "tx", "ty", "tn", "tt"];
const INTERFACE_KEYS: [&str; 7] = [
    "model",
    "initial",
    "cohesion",
    "gap",
    "tangential",
    "friction",
    "between",
];
const SOLVE_KEYS: [&str; 7] = [
    "method",
    "tolerance",
    "max_iterations",
    "load_factors",
    "time",
    "collapse",
    "quadrature",
];
const OUTPUT_KEYS: [&str; 7] = [
    "directory",
    "history",
    "operators",
    "compress",
    "vtk",
    "field",
    "section",
];
const SECTION_KEYS: [&str; 4] = ["name", "from", "to", "points"];

/// Parses and validates scene text; `path` locates relative paths and names the file in
/// messages.
pub fn parse_scene(text: &str, path: &Path) -> Result<Scene> {
    validate(&parse_doc(text, path)?, text, path)
}

fn parse_doc(text: &str, path: &Path) -> Result<toml::Table> {
    text.parse().map_err(|e: toml::de::Error| {
        Error::input(
            path,
            format!(
                "not valid TOML: {}",
                e.to_string().trim_end().replace('\n', "\n  ")
            ),
        )
    })
}

/// Validates a TOML document (the file's, overrides applied); `text` is kept for the archive.
fn validate(doc: &toml::Table, text: &str, path: &Path) -> Result<Scene> {
    let err = |msg: String| Error::input(path, msg);
    check_keys(doc, path)?;
    let doc = doc.clone();
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());

    let title = match doc.get("title") {
        Some(v) => typed::<String>(v, "title", path)?,
        None => stem.clone(),
    };
    let (mesh, mesh_parameters) = mesh_spec(doc.get("mesh"), &dir, path)?;
    let plane = match doc.get("plane") {
        None => {
            return Err(err(
                "`plane` is missing: add plane = \"strain\" or plane = \"stress\"".into(),
            ))
        }
        Some(v) => match typed::<String>(v, "plane", path)?.as_str() {
            "strain" => Plane::Strain,
            "stress" => Plane::Stress,
            other => return Err(err(choice_error("plane", other, &["strain", "stress"]))),
        },
    };
    let thickness = match doc.get("thickness") {
        Some(v) => typed::<f64>(v, "thickness", path)?,
        None => 1.0,
    };
    if !(thickness.is_finite() && thickness > 0.0) {
        return Err(err(format!(
            "`thickness` = {thickness} must be a positive number"
        )));
    }
    let units = match doc.get("units") {
        Some(v) => {
            let raw: RawUnits = typed(v, "units", path)?;
            Units {
                length: raw.length.unwrap_or_default(),
                force: raw.force.unwrap_or_default(),
            }
        }
        None => Units::default(),
    };

    let mut bodies = Vec::new();
    let mut tables = Tables::default();
    for (name, v) in sub_tables(&doc, "body", path)? {
        if Glob::is_pattern(name) {
            let key = pattern_key("body", name, path)?;
            let spec = body_spec(name, v, &key, plane, path)?;
            tables.bodies.push(Pattern {
                glob: Glob::new(name),
                spec,
                raw: v.clone(),
            });
            continue;
        }
        let key = format!("body.{name}");
        if let Some(problem) = file_name_problem(name) {
            return Err(err(format!(
                "[{key}]: {problem}; a body's name becomes a group name in the archive: \
                 name the Physical Surface (and this table) with letters, digits, . _ - only"
            )));
        }
        bodies.push(body_spec(name, v, &key, plane, path)?);
    }
    if let Some(v) = defaults_table(&doc, "body", path)? {
        tables.default_body = Some(body_spec("", v, "defaults.body", plane, path)?);
    }
    if bodies.is_empty() && tables.bodies.is_empty() && tables.default_body.is_none() {
        return Err(err(
            "no bodies: add a [body.NAME] table (young, poisson) for each Physical Surface, \
             or [body.\"PATTERN*\"] / [defaults.body] tables for many"
                .into(),
        ));
    }

    let mut boundaries = Vec::new();
    for (name, v) in sub_tables(&doc, "boundary", path)? {
        let key = format!("boundary.{name}");
        let raw: RawBoundary = typed(v, &key, path)?;
        boundaries.push(boundary_spec(name, raw, &key, path)?);
    }

    let mut interfaces = Vec::new();
    for (name, v) in sub_tables(&doc, "interface", path)? {
        if Glob::is_pattern(name) {
            let key = pattern_key("interface", name, path)?;
            let raw: RawInterface = typed(v, &key, path)?;
            no_between(&raw, &key, path)?;
            tables.interfaces.push(Pattern {
                glob: Glob::new(name),
                spec: interface_spec(name, raw, &key, path)?,
                raw: v.clone(),
            });
            continue;
        }
        let key = format!("interface.{name}");
        if let Some(problem) = file_name_problem(name) {
            return Err(err(format!(
                "[{key}]: {problem}; an interface's name becomes a file name \
                 (interfaces/NAME.csv): name the Physical Curve (and this table) with letters, \
                 digits, . _ - only"
            )));
        }
        let raw: RawInterface = typed(v, &key, path)?;
        interfaces.push(interface_spec(name, raw, &key, path)?);
    }
    if let Some(v) = defaults_table(&doc, "interface", path)? {
        let raw: RawInterface = typed(v, "defaults.interface", path)?;
        no_between(&raw, "defaults.interface", path)?;
        tables.default_interface = Some(interface_spec("", raw, "defaults.interface", path)?);
    }
    for b in &boundaries {
        if interfaces.iter().any(|i| i.name == b.name) {
            return Err(err(format!(
                "`{}` is both a [boundary] and an [interface]: a Physical Curve is one or the other",
                b.name
            )));
        }
    }

    for i in &interfaces {
        for g in i.between.iter().flatten() {
            if boundaries.iter().any(|b| &b.name == g) {
                return Err(err(format!(
                    "`interface.{}.between` names \"{g}\", which has a [boundary.{g}] table:                      a Physical Curve is a boundary or a side of an interface; remove one",
                    i.name
                )));
            }
            if let Some(o) = interfaces.iter().find(|o| o.name == *g) {
                return Err(err(format!(
                    "`interface.{}.between` names \"{g}\", which is [interface.{}] itself:                      a Physical Curve is a side of one interface only",
                    i.name, o.name
                )));
            }
        }
    }
    let contact = match doc.get("contact") {
        Some(v) => Some(contact_spec(typed(v, "contact", path)?, path)?),
        None => None,
    };

    let raw_solve: RawSolve = match doc.get("solve") {
        Some(v) => typed(v, "solve", path)?,
        None => RawSolve::default(),
    };
    let solve = solve_spec(raw_solve, path)?;

    let raw_output: RawOutput = match doc.get("output") {
        Some(v) => typed(v, "output", path)?,
        None => RawOutput::default(),
    };
    let output = output_spec(raw_output, &dir, &stem, path)?;

    Ok(Scene {
        path: path.to_path_buf(),
        text: text.to_string(),
        title,
        mesh,
        mesh_parameters,
        overrides: Vec::new(),
        plane,
        thickness,
        units,
        bodies,
        boundaries,
        interfaces,
        contact,
        tables,
        solve,
        output,
    })
}

/// `between` names two Physical Curves of one interface: not in a glob or default table.
fn no_between(raw: &RawInterface, key: &str, path: &Path) -> Result<()> {
    if raw.between.is_some() {
        return Err(Error::input(
            path,
            format!(
                "`{key}.between` names the two Physical Curves of one interface: give it in a                  named [interface.NAME] table, not in a pattern or default table"
            ),
        ));
    }
    Ok(())
}

fn contact_spec(raw: RawContact, path: &Path) -> Result<ContactSpec> {
    if !(raw.search.is_finite() && raw.search > 0.0) {
        return Err(Error::input(
            path,
            format!(
                "`contact.search` = {} must be a positive length: the largest gap at which \
                 facing boundaries pair up (e.g. search = 1e-3)",
                raw.search
            ),
        ));
    }
    let bodies = raw.bodies.unwrap_or_else(|| "*".to_string());
    if bodies.is_empty() {
        return Err(Error::input(
            path,
            "`contact.bodies` is empty: give the bodies whose boundaries may touch, as a \
             glob over their names (\"*\" for all, \"brick_*\")",
        ));
    }
    Ok(ContactSpec {
        bodies: crate::input::tables::Glob::new(&bodies),
        search: raw.search,
    })
}

/// The key of a glob table in messages (`body."brick*"`), after checking that the pattern
/// is made of the characters of names and the wildcards `*` and `?`.
fn pattern_key(group: &str, name: &str, path: &Path) -> Result<String> {
    let key = format!("{group}.\"{name}\"");
    if let Some(c) = name
        .chars()
        .find(|c| !(c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-' | '*' | '?')))
    {
        return Err(Error::input(
            path,
            format!(
                "[{key}]: the pattern holds `{c}`: a pattern is made of the letters, digits, \
                 . _ - of group names and the wildcards * (any run of characters) and ? (one)"
            ),
        ));
    }
    Ok(key)
}

/// `[defaults.KIND]`, if given.
fn defaults_table<'a>(
    doc: &'a toml::Table,
    kind: &str,
    path: &Path,
) -> Result<Option<&'a toml::Value>> {
    let Some(d) = doc.get("defaults") else {
        return Ok(None);
    };
    let Some(t) = d.as_table() else {
        return Err(Error::input(
            path,
            "`defaults` must hold tables: write [defaults.body] or [defaults.interface]",
        ));
    };
    match t.get(kind) {
        None => Ok(None),
        Some(v) if v.is_table() => Ok(Some(v)),
        Some(_) => Err(Error::input(
            path,
            format!(
                "`defaults.{kind}` must be a table: write [defaults.{kind}] with its keys below"
            ),
        )),
    }
}

/// A body table (exact, glob or default) validated: `key` names it in messages.
fn body_spec(
    name: &str,
    v: &toml::Value,
    key: &str,
    plane: Plane,
    path: &Path,
) -> Result<BodySpec> {
    let err = |msg: String| Error::input(path, msg);
    let raw: RawBody = typed(v, key, path)?;
    if !(raw.young.is_finite() && raw.young > 0.0) {
        return Err(err(format!(
            "`{key}.young` = {} must be a positive number (Young's modulus)",
            raw.young
        )));
    }
    if !(YOUNG_RANGE.0..=YOUNG_RANGE.1).contains(&raw.young) {
        return Err(err(format!(
            "`{key}.young` = {:e} is an extreme value (outside {:e}..{:e}): products of it \
                 overflow or underflow double precision; choose units that keep the moduli \
                 moderate (e.g. MPa and mm, or GPa)",
            raw.young, YOUNG_RANGE.0, YOUNG_RANGE.1
        )));
    }
    if !(raw.poisson.is_finite() && raw.poisson > -1.0 && raw.poisson < 0.5) {
        let range = match plane {
            Plane::Strain => "-1 < poisson < 0.5 (0.5, incompressible, is invalid in plane strain)",
            // ν = 0.5 is physical in plane stress (ν̄ = ν/(1+ν) = 1/3), but the kernels
            // take the material's ν in (-1, 0.5).
            Plane::Stress => {
                "-1 < poisson < 0.5 (0.5 is not supported in plane stress either: use \
                     0.499 for a nearly incompressible sheet)"
            }
        };
        return Err(err(format!(
            "`{key}.poisson` = {} is outside {range}",
            raw.poisson
        )));
    }
    let body_force = match raw.body_force {
        Some([bx, by]) => {
            let b = [
                scalar(bx, &format!("{key}.body_force[0]"), path)?,
                scalar(by, &format!("{key}.body_force[1]"), path)?,
            ];
            if let Some((c, _)) = b.iter().enumerate().find(|(_, v)| v.uses_space()) {
                return Err(err(format!(
                    "`{key}.body_force[{c}]` depends on x or y: a body force is uniform in \
                     its body (it may depend on the pseudo-time t); split the body into parts \
                     with their own body forces"
                )));
            }
            Some(b)
        }
        None => None,
    };
    Ok(BodySpec {
        name: name.to_string(),
        young: raw.young,
        poisson: raw.poisson,
        body_force,
    })
}

/// The mesh file and its gmsh parameters.
type MeshSpec = (Option<PathBuf>, Vec<(String, f64)>);

/// `mesh = "FILE"`, or a `[mesh]` table: `file` and gmsh parameters (numbers) for a `.geo`.
fn mesh_spec(v: Option<&toml::Value>, dir: &Path, path: &Path) -> Result<MeshSpec> {
    let err = |msg: String| Error::input(path, msg);
    let t = match v {
        None => return Ok((None, Vec::new())),
        Some(toml::Value::String(f)) => return Ok((Some(dir.join(f)), Vec::new())),
        Some(toml::Value::Table(t)) => t,
        Some(_) => {
            return Err(err(
                "`mesh` must be a file name (mesh = \"beam.msh\") or a table \
                 ([mesh] with file = \"beam.geo\" and gmsh parameters such as h = 2.0)"
                    .into(),
            ))
        }
    };
    let file =
        match t.get("file") {
            Some(toml::Value::String(f)) => dir.join(f),
            Some(_) => return Err(err("`mesh.file` must be a file name".into())),
            None => return Err(err(
                "`mesh.file` is missing: the [mesh] table names the .geo with file = \"NAME.geo\""
                    .into(),
            )),
        };
    let mut params = Vec::new();
    for (k, v) in t {
        if k == "file" {
            continue;
        }
        let x = match v {
            toml::Value::Float(x) => *x,
            toml::Value::Integer(i) => *i as f64,
            _ => {
                return Err(err(format!(
                    "`mesh.{k}` must be a number (a gmsh -setnumber parameter of the .geo)"
                )))
            }
        };
        if !x.is_finite() {
            return Err(err(format!("`mesh.{k}` = {x} must be a finite number")));
        }
        params.push((k.clone(), x));
    }
    let is_geo = file
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("geo"));
    if !params.is_empty() && !is_geo {
        return Err(err(format!(
            "`mesh.{}`: mesh parameters apply to a .geo file only, and `mesh.file` is {}",
            params[0].0,
            file.display()
        )));
    }
    Ok((Some(file), params))
}

/// Rejects unknown keys anywhere in the document, suggesting the nearest valid one.
fn check_keys(doc: &toml::Table, path: &Path) -> Result<()> {
    let unknown = |key: &str, prefix: &str, valid: &[&str]| -> Error {
        let full = if prefix.is_empty() {
            key.to_string()
        } else {
            format!("{prefix}.{key}")
        };
        let hint = did_you_mean(key, valid.iter().copied());
        let list = if hint.is_empty() {
            format!("; valid keys here: {}", valid.join(", "))
        } else {
            String::new()
        };
        Error::input(path, format!("unknown key `{full}`{hint}{list}"))
    };
    let table_keys = |t: &toml::Table, prefix: &str, valid: &[&str]| -> Result<()> {
        for k in t.keys() {
            if !valid.contains(&k.as_str()) {
                return Err(unknown(k, prefix, valid));
            }
        }
        Ok(())
    };
    table_keys(doc, "", &TOP_KEYS)?;
    let named = [
        ("body", &BODY_KEYS[..]),
        ("boundary", &BOUNDARY_KEYS[..]),
        ("interface", &INTERFACE_KEYS[..]),
    ];
    for (group, valid) in named {
        if let Some(toml::Value::Table(t)) = doc.get(group) {
            for (name, v) in t {
                if let toml::Value::Table(inner) = v {
                    table_keys(inner, &format!("{group}.{name}"), valid)?;
                }
            }
        }
    }
    if let Some(toml::Value::Table(t)) = doc.get("defaults") {
        table_keys(t, "defaults", &DEFAULTS_KEYS)?;
        for (group, valid) in [("body", &BODY_KEYS[..]), ("interface", &INTERFACE_KEYS[..])] {
            if let Some(toml::Value::Table(inner)) = t.get(group) {
                table_keys(inner, &format!("defaults.{group}"), valid)?;
            }
        }
    }
    if let Some(toml::Value::Table(t)) = doc.get("units") {
        table_keys(t, "units", &UNITS_KEYS)?;
    }
    if let Some(toml::Value::Table(t)) = doc.get("solve") {
        table_keys(t, "solve", &SOLVE_KEYS)?;
    }
    if let Some(toml::Value::Table(t)) = doc.get("contact") {
        table_keys(t, "contact", &CONTACT_KEYS)?;
    }
    if let Some(toml::Value::Table(t)) = doc.get("output") {
        table_keys(t, "output", &OUTPUT_KEYS)?;
        if let Some(toml::Value::Array(a)) = t.get("section") {
            for (i, s) in a.iter().enumerate() {
                if let toml::Value::Table(st) = s {
                    table_keys(st, &format!("output.section[{}]", i + 1), &SECTION_KEYS)?;
                }
            }
        }
    }
    Ok(())
}

/// Deserialises one value with serde, naming the key on failure.
fn typed<'de, T: Deserialize<'de>>(v: &toml::Value, key: &str, path: &Path) -> Result<T> {
    T::deserialize(v.clone()).map_err(|e| {
        Error::input(
            path,
            format!("`{key}`: {}", e.to_string().trim_end().replace('\n', " ")),
        )
    })
}

/// The named sub-tables of `[group.NAME]`, in file order.
fn sub_tables<'a>(
    doc: &'a toml::Table,
    group: &str,
    path: &Path,
) -> Result<Vec<(&'a String, &'a toml::Value)>> {
    match doc.get(group) {
        None => Ok(Vec::new()),
        Some(toml::Value::Table(t)) => {
            let mut out = Vec::new();
            for (name, v) in t {
                if !v.is_table() {
                    return Err(Error::input(
                        path,
                        format!(
                            "`{group}.{name}` must be a table: write [{group}.{name}] with its keys below"
                        ),
                    ));
                }
                out.push((name, v));
            }
            Ok(out)
        }
        Some(_) => Err(Error::input(
            path,
            format!("`{group}` must hold tables: write [{group}.NAME] sections"),
        )),
    }
}

fn choice_error(key: &str, got: &str, valid: &[&str]) -> String {
    let quoted: Vec<String> = valid.iter().map(|v| format!("\"{v}\"")).collect();
    format!(
        "`{key}` = \"{got}\" is not one of {}{}",
        quoted.join(", "),
        did_you_mean(got, valid.iter().copied())
    )
}

fn scalar(raw: RawScalar, key: &str, path: &Path) -> Result<Scalar> {
    match raw {
        RawScalar::Number(v) if v.is_finite() => Ok(Scalar::Const(v)),
        RawScalar::Number(v) => Err(Error::input(path, format!("`{key}` = {v} is not finite"))),
        RawScalar::Text(t) => match Expr::parse(&t) {
            Ok(e) => Ok(Scalar::Expr(e)),
            Err(why) => Err(Error::input(path, format!("`{key}` = \"{t}\": {why}"))),
        },
    }
}

fn boundary_spec(name: &str, raw: RawBoundary, key: &str, path: &Path) -> Result<BoundarySpec> {
    let err = |msg: String| Error::input(path, msg);
    let global = [&raw.ux, &raw.uy, &raw.tx, &raw.ty]
        .iter()
        .any(|v| v.is_some());
    let local = [&raw.un, &raw.ut, &raw.tn, &raw.tt]
        .iter()
        .any(|v| v.is_some());
    if global && local {
        return Err(err(format!(
            "`{key}` mixes x/y components (ux uy tx ty) with normal/tangential ones (un ut tn tt): \
             give one frame per boundary, or split the curve into two Physical Curves"
        )));
    }
    let (frame, pairs, names) = if local {
        (
            Frame::Local,
            [(raw.ut, raw.tt), (raw.un, raw.tn)],
            [("ut", "tt"), ("un", "tn")],
        )
    } else {
        (
            Frame::Global,
            [(raw.ux, raw.tx), (raw.uy, raw.ty)],
            [("ux", "tx"), ("uy", "ty")],
        )
    };
    let mut components: Vec<Condition> = Vec::with_capacity(2);
    for ((u, t), (un, tn)) in pairs.into_iter().zip(names) {
        components.push(match (u, t) {
            (Some(_), Some(_)) => {
                return Err(err(format!(
                    "`{key}` gives both `{un}` and `{tn}`: per direction, prescribe either the \
                     displacement or the traction"
                )))
            }
            (Some(u), None) => Condition::Displacement(scalar(u, &format!("{key}.{un}"), path)?),
            (None, Some(t)) => Condition::Traction(scalar(t, &format!("{key}.{tn}"), path)?),
            (None, None) => Condition::Traction(Scalar::Const(0.0)),
        });
    }
    let [c0, c1]: [Condition; 2] = match components.try_into() {
        Ok(c) => c,
        Err(_) => return Err(err(format!("`{key}`: internal error building components"))),
    };
    Ok(BoundarySpec {
        name: name.to_string(),
        frame,
        components: [c0, c1],
    })
}

fn interface_spec(name: &str, raw: RawInterface, key: &str, path: &Path) -> Result<InterfaceSpec> {
    let err = |msg: String| Error::input(path, msg);
    let model = match raw.model.as_str() {
        "bonded" => InterfaceModel::Bonded,
        "unilateral" => InterfaceModel::Unilateral,
        other => {
            return Err(err(choice_error(
                &format!("{key}.model"),
                other,
                &["bonded", "unilateral"],
            )))
        }
    };
    let initial = match raw.initial.as_deref() {
        None | Some("closed") => InitialState::Closed,
        Some("open") => InitialState::Open,
        Some(other) => {
            return Err(err(choice_error(
                &format!("{key}.initial"),
                other,
                &["closed", "open"],
            )))
        }
    };
    let tangential = match raw.tangential.as_deref() {
        None | Some("stick") => Tangential::Stick,
        Some("slide") => Tangential::Slide,
        Some("friction") => Tangential::Friction,
        Some(other) => {
            return Err(err(choice_error(
                &format!("{key}.tangential"),
                other,
                &["stick", "slide", "friction"],
            )))
        }
    };
    let friction = match (raw.friction, tangential) {
        (Some(v), Tangential::Friction) => scalar(v, &format!("{key}.friction"), path)?,
        (None, Tangential::Friction) => {
            return Err(err(format!(
                "`{key}` has tangential = \"friction\" but no `friction`: give the Coulomb \
                 coefficient, e.g. friction = 0.6"
            )))
        }
        (Some(_), other) => {
            return Err(err(format!(
                "`{key}.friction` is given but tangential = \"{}\": the coefficient applies \
                 with tangential = \"friction\"; set it or remove `friction`",
                other.name()
            )))
        }
        (None, _) => Scalar::Const(0.0),
    };
    let cohesion = match raw.cohesion {
        Some(v) => scalar(v, &format!("{key}.cohesion"), path)?,
        None => Scalar::Const(0.0),
    };
    let gap = match raw.gap {
        Some(v) => scalar(v, &format!("{key}.gap"), path)?,
        None => Scalar::Const(0.0),
    };
    // A negative gap is an interference (a shrink fit): the pair starts overlapping.
    for (what, v) in [("cohesion", &cohesion), ("friction", &friction)] {
        if let Some(c) = v.as_const() {
            if c < 0.0 {
                return Err(err(format!("`{key}.{what}` = {c} must be >= 0")));
            }
        }
    }
    if model == InterfaceModel::Bonded {
        let contradiction = if initial == InitialState::Open {
            Some("initial = \"open\"")
        } else if !cohesion.is_zero() {
            Some("cohesion")
        } else if !gap.is_zero() {
            Some("gap")
        } else if tangential != Tangential::Stick {
            Some(if tangential == Tangential::Slide {
                "tangential = \"slide\""
            } else {
                "tangential = \"friction\""
            })
        } else {
            None
        };
        if let Some(what) = contradiction {
            return Err(err(format!(
                "`{key}` is bonded but sets {what}: that applies to unilateral interfaces; \
                 set model = \"unilateral\" or remove it"
            )));
        }
    }
    if initial == InitialState::Closed && !gap.is_zero() {
        return Err(err(format!(
            "`{key}` starts closed but sets a gap: a gap applies to zones that start open; \
             set initial = \"open\" or remove `gap`"
        )));
    }
    if initial == InitialState::Open && !cohesion.is_zero() {
        return Err(err(format!(
            "`{key}` starts open but sets a cohesion: cohesion applies to zones that start closed; \
             set initial = \"closed\" or remove `cohesion`"
        )));
    }
    let between = match raw.between {
        None => None,
        Some(v) => match v.as_slice() {
            [a, b] if a != b && !a.is_empty() && !b.is_empty() => Some([a.clone(), b.clone()]),
            _ => {
                return Err(err(format!(
                    "`{key}.between` = {v:?} must name two different Physical Curves, one on \
                     each body: between = [\"A_FACE\", \"B_FACE\"]"
                )))
            }
        },
    };
    Ok(InterfaceSpec {
        name: name.to_string(),
        model,
        initial,
        cohesion,
        gap,
        tangential,
        friction,
        between,
    })
}

fn solve_spec(raw: RawSolve, path: &Path) -> Result<SolveSpec> {
    let err = |msg: String| Error::input(path, msg);
    let method = match raw.method.as_deref() {
        None | Some("lcp") => Method::Lcp,
        Some("qp") => Method::Qp,
        Some("both") => Method::Both,
        Some("sparse") => Method::Sparse,
        Some(other) => {
            return Err(err(choice_error(
                "solve.method",
                other,
                &["lcp", "qp", "both", "sparse"],
            )))
        }
    };
    let quadrature = match raw.quadrature.as_deref() {
        None | Some("standard") => Quadrature::Standard,
        Some("fast") => Quadrature::Fast,
        Some("accurate") => Quadrature::Accurate,
        Some(other) => {
            return Err(err(choice_error(
                "solve.quadrature",
                other,
                &["fast", "standard", "accurate"],
            )))
        }
    };
    let tolerance = raw.tolerance.unwrap_or(1e-10);
    if !(tolerance.is_finite() && tolerance > 0.0 && tolerance < 1.0) {
        return Err(err(format!(
            "`solve.tolerance` = {tolerance} must be a number between 0 and 1 (e.g. 1e-10)"
        )));
    }
    if let Some(m) = raw.max_iterations.filter(|&m| m < 1) {
        return Err(err(format!(
            "`solve.max_iterations` = {m} must be at least 1"
        )));
    }
    let max_iterations = raw.max_iterations;
    let has_factors = raw.load_factors.is_some();
    let load_factors = raw.load_factors.unwrap_or_else(|| vec![1.0]);
    if load_factors.is_empty() {
        return Err(err(
            "`solve.load_factors` is empty: give at least one factor, e.g. [1.0]".into(),
        ));
    }
    if let Some(f) = load_factors.iter().find(|f| !f.is_finite()) {
        return Err(err(format!(
            "`solve.load_factors` holds {f}, which is not finite"
        )));
    }
    let time = match raw.time {
        None => None,
        Some(_) if has_factors => {
            return Err(err(
                "`solve.time` and `solve.load_factors` are both given: use load factors to \
                 scale every load, or pseudo-time steps with loads that are expressions in t, \
                 not both"
                    .into(),
            ))
        }
        Some(ts) => {
            if ts.is_empty() {
                return Err(err(
                    "`solve.time` is empty: give at least one pseudo-time, e.g. [1.0]".into(),
                ));
            }
            if let Some(t) = ts.iter().find(|t| !t.is_finite()) {
                return Err(err(format!("`solve.time` holds {t}, which is not finite")));
            }
            if let Some(w) = ts.windows(2).find(|w| w[1] <= w[0]) {
                return Err(err(format!(
                    "`solve.time` must increase: {} follows {}; list the pseudo-times in order",
                    w[1], w[0]
                )));
            }
            Some(ts)
        }
    };
    let collapse = match raw.collapse {
        None => None,
        Some(_) if has_factors || time.is_some() => {
            return Err(err(
                "`solve.collapse` searches the load multiplier t itself: remove \
                 `solve.load_factors` and `solve.time`"
                    .into(),
            ))
        }
        Some(c) => {
            if !(c.max.is_finite() && c.max > 0.0) {
                return Err(err(format!(
                    "`solve.collapse.max` = {} must be a positive number (the largest load \
                     multiplier t tried)",
                    c.max
                )));
            }
            let tol = c.tolerance.unwrap_or(1e-3 * c.max);
            if !(tol.is_finite() && tol > 0.0 && tol < c.max) {
                return Err(err(format!(
                    "`solve.collapse.tolerance` = {tol} must be positive and below max = {}",
                    c.max
                )));
            }
            // Bisection halves [lo, hi] within [0, max]; below a few units in the last place
            // of max, the midpoint is lo or hi again and the search would never end.
            let finest = 4.0 * f64::EPSILON * c.max;
            if tol < finest {
                return Err(err(format!(
                    "`solve.collapse.tolerance` = {} is finer than floating point can \
                     resolve a load multiplier up to max = {} (the bisection would never end): \
                     give a tolerance of at least {}",
                    crate::input::model::fmt_num(tol),
                    crate::input::model::fmt_num(c.max),
                    crate::input::model::fmt_num(finest * 1.001)
                )));
            }
            Some(Collapse {
                max: c.max,
                tolerance: tol,
            })
        }
    };
    Ok(SolveSpec {
        method,
        method_given: raw.method.is_some(),
        tolerance,
        max_iterations: max_iterations.map(|m| m as usize),
        load_factors,
        time,
        collapse,
        quadrature,
    })
}

fn output_spec(raw: RawOutput, dir: &Path, stem: &str, path: &Path) -> Result<OutputSpec> {
    let err = |msg: String| Error::input(path, msg);
    let history = match raw.history.as_deref() {
        None | Some("full") => History::Full,
        Some("final") => History::Final,
        Some(other) => {
            return Err(err(choice_error(
                "output.history",
                other,
                &["full", "final"],
            )))
        }
    };
    let directory = match raw.directory {
        Some(d) if d.trim().is_empty() => {
            return Err(err("`output.directory` is empty".into()));
        }
        Some(d) => dir.join(d),
        None => dir.join("out").join(stem),
    };
    let mut sections: Vec<SectionSpec> = Vec::new();
    for (i, s) in raw.section.into_iter().enumerate() {
        let key = format!("output.section[{}] (\"{}\")", i + 1, s.name);
        if let Some(problem) = file_name_problem(&s.name) {
            return Err(err(format!(
                "{key}: {problem}; the name becomes a file name; use letters, digits, - _ and . \
                 only"
            )));
        }
        if sections.iter().any(|o| o.name == s.name) {
            return Err(err(format!("{key}: two sections have this name")));
        }
        // sections/NAME.csv and sections/NAME_path.csv must not meet.
        if let Some(o) = sections
            .iter()
            .find(|o| o.name == format!("{}_path", s.name) || s.name == format!("{}_path", o.name))
        {
            return Err(err(format!(
                "{key}: the sections \"{}\" and \"{}\" would write the same file \
                 (sections/NAME_path.csv holds a section's contact path): rename one",
                o.name, s.name
            )));
        }
        if !s.from.iter().chain(s.to.iter()).all(|c| c.is_finite()) {
            return Err(err(format!("{key}: `from` and `to` must be finite points")));
        }
        if s.from == s.to {
            return Err(err(format!("{key}: `from` and `to` are the same point")));
        }
        if s.points < 2 || s.points > 1_000_000 {
            return Err(err(format!(
                "{key}: `points` = {} must be between 2 and 1000000",
                s.points
            )));
        }
        sections.push(SectionSpec {
            name: s.name,
            from: s.from,
            to: s.to,
            points: s.points as usize,
        });
    }
    Ok(OutputSpec {
        directory,
        history,
        operators: raw.operators.unwrap_or(true),
        compress: raw.compress.unwrap_or(false),
        vtk: raw.vtk.unwrap_or(true),
        field: raw.field.unwrap_or(false),
        sections,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"
title = "Clamped beam"
mesh = "beam.msh"
plane = "stress"
thickness = 1
units = { length = "cm", force = "daN" }
[body.A]
young = 5000
poisson = 0.2
body_force = [0.0, -0.0018]
[body.B]
young = 5000.0
poisson = 0.2
[boundary.clamp]
ux = 0
uy = 0.0
[boundary.top]
ty = "-10*x/400"
[boundary.symmetry]
un = 0.0
tt = 0.0
[interface.joint]
model = "unilateral"
initial = "closed"
cohesion = 0.0
tangential = "stick"
[solve]
method = "both"
load_factors = [0.5, 1.0]
[output]
directory = "../out/beam"
field = true
[[output.section]]
name = "a-a"
from = [100.0, 0.0]
to = [100.0, 40.0]
points = 41
"#;

    fn parse(text: &str) -> Result<Scene> {
        parse_scene(text, Path::new("pipelines/beam.toml"))
    }

    fn fails(text: &str) -> String {
        match parse(text) {
            Ok(_) => panic!("expected an error for:\n{text}"),
            Err(e) => {
                assert_eq!(e.exit_code(), 2);
                e.to_string()
            }
        }
    }

    #[test]
    fn full_scene_is_read() {
        let s = parse(GOOD).expect("valid scene");
        assert_eq!(s.title, "Clamped beam");
        assert_eq!(s.mesh.as_deref(), Some(Path::new("pipelines/beam.msh")));
        assert_eq!(s.plane, Plane::Stress);
        assert_eq!(s.bodies.len(), 2);
        assert_eq!(s.bodies[0].name, "A");
        assert_eq!(s.bodies[0].body_force_at(1.0), Some([0.0, -0.0018]));
        assert_eq!(s.bodies[1].body_force_at(1.0), None);
        let top = s.boundary("top").unwrap();
        assert_eq!(top.frame, Frame::Global);
        match &top.components[1] {
            Condition::Traction(v) => assert_eq!(v.eval([200.0, 40.0], 1.0), -5.0),
            _ => panic!("ty is a traction"),
        }
        assert!(matches!(top.components[0], Condition::Traction(Scalar::Const(z)) if z == 0.0));
        let sym = s.boundary("symmetry").unwrap();
        assert_eq!(sym.frame, Frame::Local);
        assert!(sym.components[1].is_displacement() && !sym.components[0].is_displacement());
        assert_eq!(s.boundary("clamp").unwrap().role(), "constrained");
        assert_eq!(s.solve.method, Method::Both);
        assert_eq!(s.solve.load_factors, vec![0.5, 1.0]);
        assert_eq!(s.output.directory, Path::new("pipelines/../out/beam"));
        assert!(s.output.field && s.output.vtk && s.output.operators);
        assert_eq!(s.output.sections[0].points, 41);
        assert_eq!(
            s.interface("joint").unwrap().model,
            InterfaceModel::Unilateral
        );
    }

    #[test]
    fn defaults_apply() {
        let s = parse("plane = \"strain\"\n[body.A]\nyoung = 1.0\npoisson = 0.3\n").unwrap();
        assert_eq!(s.title, "beam");
        assert_eq!(s.thickness, 1.0);
        assert_eq!(s.solve.tolerance, 1e-10);
        assert_eq!(s.solve.max_iterations, None);
        assert_eq!(s.solve.quadrature, Quadrature::Standard);
        assert_eq!(s.output.directory, Path::new("pipelines/out/beam"));
        assert!(!s.output.field);
    }

    #[test]
    fn unknown_keys_suggest_the_nearest() {
        let m = fails(&GOOD.replace("poisson = 0.2\nbody_force", "poison = 0.2\nbody_force"));
        assert!(
            m.contains("`body.A.poison`") && m.contains("did you mean `poisson`"),
            "{m}"
        );
        let m = fails(&GOOD.replace("[solve]\n", "[solve]\ntolerence = 1e-9\n"));
        assert!(
            m.contains("solve.tolerence") && m.contains("`tolerance`"),
            "{m}"
        );
        let m = fails(&GOOD.replace("points = 41", "points = 41\ncount = 3"));
        assert!(m.contains("output.section[1].count"), "{m}");
        let m = fails(&format!("colour = 1\n{GOOD}"));
        assert!(m.contains("`colour`") && m.contains("valid keys"), "{m}");
    }

    #[test]
    fn invalid_values_are_named() {
        let m = fails(&GOOD.replace("young = 5000\n", "young = -1\n"));
        assert!(m.contains("body.A.young"), "{m}");
        let m = fails(&GOOD.replace("poisson = 0.2\nbody_force", "poisson = 0.7\nbody_force"));
        assert!(m.contains("body.A.poisson"), "{m}");
        let strain = GOOD.replace("plane = \"stress\"", "plane = \"strain\"");
        let m = fails(&strain.replace("poisson = 0.2\nbody_force", "poisson = 0.5\nbody_force"));
        assert!(m.contains("invalid in plane strain"), "{m}");
        let m = fails(&GOOD.replace("ux = 0\n", "ux = 0\ntx = 1\n"));
        assert!(
            m.contains("boundary.clamp") && m.contains("`ux`") && m.contains("`tx`"),
            "{m}"
        );
        let m = fails(&GOOD.replace("cohesion = 0.0", "cohesion = -1.0"));
        assert!(m.contains("interface.joint.cohesion"), "{m}");
        let m = fails(&GOOD.replace("ty = \"-10*x/400\"", "ty = \"-10*z\""));
        assert!(m.contains("boundary.top.ty") && m.contains("`z`"), "{m}");
        let m = fails(&GOOD.replace("ty = \"-10*x/400\"", "ty = \"-10*(x\""));
        assert!(
            m.contains("boundary.top.ty") && m.contains("does not parse"),
            "{m}"
        );
        let m = fails(&GOOD.replace("model = \"unilateral\"", "model = \"unilatreal\""));
        assert!(m.contains("did you mean `unilateral`"), "{m}");
        let m = fails(&GOOD.replace("young = 5000\n", "young = \"hard\"\n"));
        assert!(m.contains("body.A"), "{m}");
        let m = fails(&GOOD.replace("un = 0.0", "un = 0.0\nux = 0.0"));
        assert!(m.contains("mixes"), "{m}");
        let m = fails(&GOOD.replace("plane = \"stress\"\n", ""));
        assert!(m.contains("`plane` is missing"), "{m}");
        let m = fails(&GOOD.replace("cohesion = 0.0", "gap = 0.1"));
        assert!(m.contains("gap"), "{m}");
        let m = fails("plane = \"strain\"\n[body.A]\nyoung = 1.0\n");
        assert!(m.contains("poisson"), "{m}");
        let m = fails("plane = \"strain\"\n");
        assert!(m.contains("no bodies"), "{m}");
        let m = fails("plane = strain\n");
        assert!(m.contains("not valid TOML"), "{m}");
    }
}
