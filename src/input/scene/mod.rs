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
//!
//! Files: this one holds the scene's types, reading and [`parse_scene`]'s walk over the
//! tables; `raw.rs` the TOML shapes and the valid keys, `spec.rs` each table's validation,
//! `set.rs` the `--set` overrides.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::input::expr::Scalar;
use crate::input::tables::{Glob, Pattern, Tables};

mod raw;
pub mod schema;
mod set;
mod spec;

use raw::{
    check_keys, choice_error, sub_tables, typed, RawBoundary, RawInterface, RawOutput, RawSolve,
    RawUnits,
};
use set::apply_set;
pub(crate) use set::shown_set;
use spec::{
    body_spec, boundary_spec, contact_spec, interface_spec, mesh_spec, no_between, output_spec,
    solve_spec,
};

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
    pub(crate) fn is_displacement(&self) -> bool {
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
    pub(crate) fn traction_free(name: &str) -> BoundarySpec {
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
    pub(crate) fn describe(&self) -> String {
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
    /// Every pair component its own row (junctions exact), one convex programme per set of
    /// slip bounds (interior point).
    Exact,
}

impl Method {
    pub fn name(self) -> &'static str {
        match self {
            Method::Lcp => "lcp",
            Method::Qp => "qp",
            Method::Both => "both",
            Method::Sparse => "sparse",
            Method::Exact => "exact",
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
    /// Why the scene is solved by `method`: given (in the scene or by `--method`), or chosen
    /// for the model by [`SolveSpec::choose_method`].
    pub method_choice: MethodChoice,
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
    /// `[solve] junctions`: where the cycles of pairs at junction points are cut.
    pub junctions: JunctionCuts,
}

/// `[solve] junctions`: how a junction's cycle of pairs is cut (which pair components get
/// no row of their own; docs/scene.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JunctionCuts {
    /// `"joints"` for the sparse solver up to 90 000 pairs (collapse searches included),
    /// `"tangential"` otherwise.
    Auto,
    /// At whole joints, moved where an implied component breaks its law to a component of
    /// its cycle that carries no force, and the load path solved again (exact wherever the
    /// cycle has such a component).
    Joints,
    /// Bonded rows first, then normal, then tangential (the paper's solvers): implied
    /// components that slip are reported (`implied_slipping`).
    Tangential,
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

/// Why a scene without `method` is solved by the method it gets ([`SolveSpec::choose_method`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MethodChoice {
    /// The scene or the command line gave the method.
    Given,
    /// No junction of unilateral joints, up to [`SPARSE_FROM_PAIRS`] pairs: the paper's path.
    Paper,
    /// Unilateral joints meet at junctions, up to [`SPARSE_FROM_PAIRS`] pairs: the full rows,
    /// so that every pair there obeys its own law.
    Junctions,
    /// Over [`SPARSE_FROM_PAIRS`] unilateral pairs: the sparse solver.
    Size,
}

impl SolveSpec {
    /// The method of a scene without `method`: the sparse solver above
    /// [`SPARSE_FROM_PAIRS`] unilateral pairs; below it the full rows (`exact`) where
    /// unilateral joints meet at junctions (the evolutive path and the sparse solver leave a
    /// dependent component there without a row, and a closed pair may slide at that node
    /// without a friction force of its own), the evolutive path (`lcp`, the paper's, every
    /// switch recorded) elsewhere.
    pub fn choose_method(&mut self, unilateral_pairs: usize, unilateral_junction: bool) {
        if self.method_choice == MethodChoice::Given {
            return;
        }
        (self.method, self.method_choice) = if unilateral_pairs > SPARSE_FROM_PAIRS {
            (Method::Sparse, MethodChoice::Size)
        } else if unilateral_junction {
            (Method::Exact, MethodChoice::Junctions)
        } else {
            (self.method, MethodChoice::Paper)
        };
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

/// Which solved states a run keeps (`output.history`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HistoryLevel {
    /// Every contact iteration (every `output.every`-th, and the last of each load step).
    Full,
    /// The state at the end of each load step.
    Steps,
    /// The final state only.
    Final,
}

impl HistoryLevel {
    /// The name written in the scene.
    pub fn name(self) -> &'static str {
        match self {
            HistoryLevel::Full => "full",
            HistoryLevel::Steps => "steps",
            HistoryLevel::Final => "final",
        }
    }
}

/// How the VTK files are written (`output.vtk`, `output.vtk_fields`).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct VtkStyle {
    /// zlib-compressed binary arrays (`vtk = "compressed"`).
    pub compressed: bool,
    /// The point arrays written, by name; None: every array.
    pub fields: Option<Vec<String>>,
}

impl VtkStyle {
    /// Whether the point array `name` is written.
    pub fn writes(&self, name: &str) -> bool {
        self.fields
            .as_ref()
            .is_none_or(|f| f.iter().any(|x| x == name))
    }
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
    pub history: HistoryLevel,
    /// Whether `output.history` was given (else the run may choose "steps" for a large
    /// scene).
    pub history_given: bool,
    /// With history "full": keep every n-th iteration of a load step (and always its last).
    pub every: usize,
    pub operators: bool,
    /// Deflate the archive's large datasets (shuffle + deflate): about a third smaller, for
    /// about 0.2 s of CPU per 10 MB of operators; off by default.
    pub compress: bool,
    pub vtk: bool,
    pub vtk_style: VtkStyle,
    pub field: bool,
    pub sections: Vec<SectionSpec>,
}

/// The scene's units, as written in it (empty when not given); serialised as `summary.json`'s
/// and the archive's `units`, its fields in alphabetical order as every record there.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct Units {
    pub force: String,
    pub length: String,
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
pub(crate) fn read_scene_with(path: &Path, sets: &[String]) -> Result<Scene> {
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

/// [`parse_scene`] with `--set KEY=VALUE` overrides applied to the document first. An error
/// that only the overrides cause names the first `--set` that causes it.
pub(crate) fn parse_scene_with(text: &str, path: &Path, sets: &[String]) -> Result<Scene> {
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
pub(crate) fn file_name_problem(name: &str) -> Option<String> {
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
pub(crate) const YOUNG_RANGE: (f64, f64) = (1e-100, 1e100);

/// Parses and validates scene text; `path` locates relative paths and names the file in
/// messages.
pub fn parse_scene(text: &str, path: &Path) -> Result<Scene> {
    validate(&parse_doc(text, path)?, text, path)
}

fn parse_doc(text: &str, path: &Path) -> Result<toml::Table> {
    text.parse()
        .map_err(|e: toml::de::Error| Error::input(path, toml_error(&e, text)))
}

/// A TOML parse error of `text`: where (line and column), what, and the line around that
/// column (at most 60 characters either side). Nesting deeper than the parser follows is
/// said so.
pub(crate) fn toml_error(e: &toml::de::Error, text: &str) -> String {
    let what = e.message().trim_end();
    let what = if what.contains("recursion limit") {
        "tables or arrays nested deeper than sgbem reads (a scene's values nest a few levels)"
    } else {
        what
    };
    let Some(at) = e.span().map(|s| s.start.min(text.len())) else {
        return format!("not valid TOML: {what}");
    };
    let at = (0..=at)
        .rev()
        .find(|&i| text.is_char_boundary(i))
        .unwrap_or(0);
    let line_start = text[..at].rfind('\n').map_or(0, |i| i + 1);
    let line_end = text[at..].find('\n').map_or(text.len(), |i| at + i);
    let line_no = text[..at].matches('\n').count() + 1;
    let before: Vec<char> = text[line_start..at].chars().collect();
    let column = before.len() + 1;
    let from = before.len().saturating_sub(60);
    let start: String = before[from..].iter().collect();
    let rest: String = text[at..line_end].chars().take(60).collect();
    let cut_start = if from > 0 { "…" } else { "" };
    let cut_end = if text[at..line_end].chars().count() > 60 {
        "…"
    } else {
        ""
    };
    format!(
        "not valid TOML at line {line_no}, column {column}: {what}\n  {line_no} | \
         {cut_start}{start}{rest}{cut_end}"
    )
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
    let plane = plane(&doc, path)?;
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

    let mut tables = Tables::default();
    let bodies = body_tables(&doc, plane, &mut tables, path)?;

    let mut boundaries = Vec::new();
    for (name, v) in sub_tables(&doc, "boundary", path)? {
        let key = format!("boundary.{name}");
        let raw: RawBoundary = typed(v, &key, path)?;
        boundaries.push(boundary_spec(name, raw, &key, path)?);
    }

    let interfaces = interface_tables(&doc, &mut tables, path)?;
    for b in &boundaries {
        if interfaces.iter().any(|i| i.name == b.name) {
            return Err(err(format!(
                "`{}` is both a [boundary] and an [interface]: a Physical Curve is one or the other",
                b.name
            )));
        }
    }

    check_between(&interfaces, &boundaries, path)?;
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

/// The two Physical Curves of a `between` are neither boundaries nor interfaces of their own.
fn check_between(
    interfaces: &[InterfaceSpec],
    boundaries: &[BoundarySpec],
    path: &Path,
) -> Result<()> {
    for i in interfaces {
        for g in i.between.iter().flatten() {
            if boundaries.iter().any(|b| &b.name == g) {
                return Err(Error::input(
                    path,
                    format!(
                        "`interface.{}.between` names \"{g}\", which has a [boundary.{g}] \
                         table: a Physical Curve is a boundary or a side of an interface; \
                         remove one",
                        i.name
                    ),
                ));
            }
            if let Some(o) = interfaces.iter().find(|o| o.name == *g) {
                return Err(Error::input(
                    path,
                    format!(
                        "`interface.{}.between` names \"{g}\", which is [interface.{}] \
                         itself: a Physical Curve is a side of one interface only",
                        i.name, o.name
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// `plane`: "strain" or "stress", required.
fn plane(doc: &toml::Table, path: &Path) -> Result<Plane> {
    let err = |msg: String| Error::input(path, msg);
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
    Ok(plane)
}

/// The `[body.NAME]` tables, with the glob tables and `[defaults.body]` into `tables`; a
/// scene needs at least one of them.
fn body_tables(
    doc: &toml::Table,
    plane: Plane,
    tables: &mut Tables,
    path: &Path,
) -> Result<Vec<BodySpec>> {
    let err = |msg: String| Error::input(path, msg);
    let mut bodies = Vec::new();
    for (name, v) in sub_tables(doc, "body", path)? {
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
    if let Some(v) = defaults_table(doc, "body", path)? {
        tables.default_body = Some(body_spec("", v, "defaults.body", plane, path)?);
    }
    if bodies.is_empty() && tables.bodies.is_empty() && tables.default_body.is_none() {
        return Err(err(
            "no bodies: add a [body.NAME] table (young, poisson) for each Physical Surface, \
             or [body.\"PATTERN*\"] / [defaults.body] tables for many"
                .into(),
        ));
    }
    Ok(bodies)
}

/// The `[interface.NAME]` tables, with the glob tables and `[defaults.interface]` into
/// `tables`.
fn interface_tables(
    doc: &toml::Table,
    tables: &mut Tables,
    path: &Path,
) -> Result<Vec<InterfaceSpec>> {
    let err = |msg: String| Error::input(path, msg);
    let mut interfaces = Vec::new();
    for (name, v) in sub_tables(doc, "interface", path)? {
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
    if let Some(v) = defaults_table(doc, "interface", path)? {
        let raw: RawInterface = typed(v, "defaults.interface", path)?;
        no_between(&raw, "defaults.interface", path)?;
        tables.default_interface = Some(interface_spec("", raw, "defaults.interface", path)?);
    }
    Ok(interfaces)
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
