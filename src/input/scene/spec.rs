//! One table at a time: a body, the mesh, a boundary part, an interface, the solver and the
//! output settings read from their raw TOML and validated, each message naming its key.

use std::path::{Path, PathBuf};

use crate::error::{did_you_mean, Error, Result};
use crate::input::expr::Scalar;

use super::raw::{
    choice_error, scalar, typed, RawBody, RawBoundary, RawContact, RawInterface, RawOutput,
    RawSolve, RawVtk,
};
use super::{
    file_name_problem, BodySpec, BoundarySpec, Collapse, Condition, ContactSpec, Frame,
    HistoryLevel, InitialState, InterfaceModel, InterfaceSpec, Method, OutputSpec, Plane,
    Quadrature, SectionSpec, SolveSpec, Tangential, VtkStyle, YOUNG_RANGE,
};

/// A body table (exact, glob or default) validated: `key` names it in messages.
pub(super) fn body_spec(
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
pub(super) type MeshSpec = (Option<PathBuf>, Vec<(String, f64)>);

/// `mesh = "FILE"`, or a `[mesh]` table: `file` and gmsh parameters (numbers) for a `.geo`.
pub(super) fn mesh_spec(v: Option<&toml::Value>, dir: &Path, path: &Path) -> Result<MeshSpec> {
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

pub(super) fn boundary_spec(
    name: &str,
    raw: RawBoundary,
    key: &str,
    path: &Path,
) -> Result<BoundarySpec> {
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

pub(super) fn interface_spec(
    name: &str,
    raw: RawInterface,
    key: &str,
    path: &Path,
) -> Result<InterfaceSpec> {
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
    let between = between(raw.between, key, path)?;
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

/// `between`: two different, non-empty Physical Curve names.
fn between(v: Option<Vec<String>>, key: &str, path: &Path) -> Result<Option<[String; 2]>> {
    let Some(v) = v else { return Ok(None) };
    match v.as_slice() {
        [a, b] if a != b && !a.is_empty() && !b.is_empty() => Ok(Some([a.clone(), b.clone()])),
        _ => Err(Error::input(
            path,
            format!(
                "`{key}.between` = {v:?} must name two different Physical Curves, one on each \
                 body: between = [\"A_FACE\", \"B_FACE\"]"
            ),
        )),
    }
}

/// `between` names two Physical Curves of one interface: not in a glob or default table.
pub(super) fn no_between(raw: &RawInterface, key: &str, path: &Path) -> Result<()> {
    if raw.between.is_some() {
        return Err(Error::input(
            path,
            format!(
                "`{key}.between` names the two Physical Curves of one interface: give it in a \
                 named [interface.NAME] table, not in a pattern or default table"
            ),
        ));
    }
    Ok(())
}

/// `[contact]`: `search` a positive length, `bodies` a glob (all by default).
pub(super) fn contact_spec(raw: RawContact, path: &Path) -> Result<ContactSpec> {
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

/// The value of the choice `got` of `key` among `options` (name, value), `default` where it
/// is not given; the message of [`choice_error`] where it is none of them.
fn one_of<T: Copy>(
    got: Option<&str>,
    key: &str,
    default: T,
    options: &[(&str, T)],
) -> std::result::Result<T, String> {
    let Some(got) = got else {
        return Ok(default);
    };
    options
        .iter()
        .find(|o| o.0 == got)
        .map(|o| o.1)
        .ok_or_else(|| {
            let names: Vec<&str> = options.iter().map(|o| o.0).collect();
            choice_error(key, got, &names)
        })
}

pub(super) fn solve_spec(raw: RawSolve, path: &Path) -> Result<SolveSpec> {
    let err = |msg: String| Error::input(path, msg);
    let method = one_of(
        raw.method.as_deref(),
        "solve.method",
        Method::Lcp,
        &[
            ("lcp", Method::Lcp),
            ("qp", Method::Qp),
            ("both", Method::Both),
            ("sparse", Method::Sparse),
            ("exact", Method::Exact),
        ],
    )
    .map_err(err)?;
    let junctions = one_of(
        raw.junctions.as_deref(),
        "solve.junctions",
        super::JunctionCuts::Auto,
        &[
            ("auto", super::JunctionCuts::Auto),
            ("joints", super::JunctionCuts::Joints),
            ("tangential", super::JunctionCuts::Tangential),
        ],
    )
    .map_err(err)?;
    let quadrature = one_of(
        raw.quadrature.as_deref(),
        "solve.quadrature",
        Quadrature::Standard,
        &[
            ("fast", Quadrature::Fast),
            ("standard", Quadrature::Standard),
            ("accurate", Quadrature::Accurate),
        ],
    )
    .map_err(err)?;
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
        method_choice: if raw.method.is_some() {
            super::MethodChoice::Given
        } else {
            super::MethodChoice::Paper
        },
        tolerance,
        max_iterations: max_iterations.map(|m| m as usize),
        load_factors,
        time,
        collapse,
        quadrature,
        junctions,
    })
}

pub(super) fn output_spec(
    raw: RawOutput,
    dir: &Path,
    stem: &str,
    path: &Path,
) -> Result<OutputSpec> {
    let err = |msg: String| Error::input(path, msg);
    let history = match raw.history.as_deref() {
        None | Some("full") => HistoryLevel::Full,
        Some("steps") => HistoryLevel::Steps,
        Some("final") => HistoryLevel::Final,
        Some(other) => {
            return Err(err(choice_error(
                "output.history",
                other,
                &["full", "steps", "final"],
            )))
        }
    };
    let every = match raw.every {
        None => 1,
        Some(n) if n < 1 => {
            return Err(err(format!(
                "`output.every` = {n} must be an integer of at least 1 (1 keeps every iteration)"
            )))
        }
        Some(n) if history != HistoryLevel::Full => {
            return Err(err(format!(
                "`output.every` = {n} thins a full history, but `output.history` is \"{}\": \
                 set history = \"full\" or remove `every`",
                history.name()
            )))
        }
        Some(n) => usize::try_from(n).unwrap_or(usize::MAX),
    };
    let (vtk, vtk_style) = vtk_choice(raw.vtk, raw.vtk_fields).map_err(err)?;
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
        history_given: raw.history.is_some(),
        every,
        operators: raw.operators.unwrap_or(true),
        compress: raw.compress.unwrap_or(false),
        vtk,
        vtk_style,
        field: raw.field.unwrap_or(false),
        sections,
    })
}

/// `output.vtk` (`true`, `false` or `"compressed"`) and `output.vtk_fields` (names of the
/// VTK point arrays, each known, none twice).
fn vtk_choice(
    vtk: Option<RawVtk>,
    fields: Option<Vec<String>>,
) -> std::result::Result<(bool, VtkStyle), String> {
    let (on, compressed) = match vtk {
        None | Some(RawVtk::Flag(true)) => (true, false),
        Some(RawVtk::Flag(false)) => (false, false),
        Some(RawVtk::Mode(m)) if m == "compressed" => (true, true),
        Some(RawVtk::Mode(m)) => {
            return Err(format!(
                "`output.vtk` = \"{m}\" is not a choice: write true, false or \"compressed\" \
                 (zlib-compressed arrays){}",
                did_you_mean(&m, ["compressed"].into_iter())
            ))
        }
    };
    if let Some(names) = &fields {
        let valid = crate::output::vtk::POINT_ARRAYS;
        if names.is_empty() {
            return Err(format!(
                "`output.vtk_fields` is empty: list the point arrays to write, from {}; \
                 or remove the key to write every one",
                valid.join(", ")
            ));
        }
        for (i, n) in names.iter().enumerate() {
            if !valid.contains(&n.as_str()) {
                return Err(format!(
                    "`output.vtk_fields`: \"{n}\" is not a VTK point array{}; valid names: {}",
                    did_you_mean(n, valid.iter().copied()),
                    valid.join(", ")
                ));
            }
            if names[..i].contains(n) {
                return Err(format!(
                    "`output.vtk_fields` lists \"{n}\" twice: name each array once"
                ));
            }
        }
    }
    Ok((on, VtkStyle { compressed, fields }))
}
