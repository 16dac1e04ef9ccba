//! The TOML side of the scene: the raw tables as serde reads them, the valid keys of each
//! table, and the checked reading of values and sub-tables.

use std::path::Path;

use serde::Deserialize;

use crate::error::{did_you_mean, Error, Result};
use crate::input::expr::{Expr, Scalar};

// ---------------------------------------------------------------------------------------
// Raw TOML shapes (serde). Unknown keys are caught first by `check_keys` for a friendly
// message; `deny_unknown_fields` stays as a second guard.

#[derive(Deserialize)]
#[serde(untagged)]
pub(super) enum RawScalar {
    Number(f64),
    Text(String),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawBody {
    pub(super) young: f64,
    pub(super) poisson: f64,
    pub(super) body_force: Option<[RawScalar; 2]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawBoundary {
    pub(super) ux: Option<RawScalar>,
    pub(super) uy: Option<RawScalar>,
    pub(super) un: Option<RawScalar>,
    pub(super) ut: Option<RawScalar>,
    pub(super) tx: Option<RawScalar>,
    pub(super) ty: Option<RawScalar>,
    pub(super) tn: Option<RawScalar>,
    pub(super) tt: Option<RawScalar>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawInterface {
    pub(super) model: String,
    pub(super) initial: Option<String>,
    pub(super) cohesion: Option<RawScalar>,
    pub(super) gap: Option<RawScalar>,
    pub(super) tangential: Option<String>,
    pub(super) friction: Option<RawScalar>,
    pub(super) between: Option<Vec<String>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawContact {
    pub(super) bodies: Option<String>,
    pub(super) search: f64,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSolve {
    pub(super) method: Option<String>,
    pub(super) tolerance: Option<f64>,
    pub(super) max_iterations: Option<i64>,
    pub(super) load_factors: Option<Vec<f64>>,
    pub(super) time: Option<Vec<f64>>,
    pub(super) collapse: Option<RawCollapse>,
    pub(super) quadrature: Option<String>,
    pub(super) junctions: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawCollapse {
    pub(super) max: f64,
    pub(super) tolerance: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSection {
    pub(super) name: String,
    pub(super) from: [f64; 2],
    pub(super) to: [f64; 2],
    pub(super) points: i64,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RawOutput {
    pub(super) directory: Option<String>,
    pub(super) history: Option<String>,
    pub(super) every: Option<i64>,
    pub(super) operators: Option<bool>,
    pub(super) compress: Option<bool>,
    pub(super) vtk: Option<RawVtk>,
    pub(super) vtk_fields: Option<Vec<String>>,
    pub(super) field: Option<bool>,
    #[serde(default)]
    pub(super) section: Vec<RawSection>,
}

/// `output.vtk`: `true`, `false` or `"compressed"`.
#[derive(Deserialize)]
#[serde(untagged)]
pub(super) enum RawVtk {
    Flag(bool),
    Mode(String),
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RawUnits {
    pub(super) length: Option<String>,
    pub(super) force: Option<String>,
}

pub(super) const TOP_KEYS: [&str; 12] = [
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
pub(super) const CONTACT_KEYS: [&str; 2] = ["bodies", "search"];
pub(super) const DEFAULTS_KEYS: [&str; 2] = ["body", "interface"];
pub(super) const UNITS_KEYS: [&str; 2] = ["length", "force"];
pub(super) const BODY_KEYS: [&str; 3] = ["young", "poisson", "body_force"];
pub(super) const BOUNDARY_KEYS: [&str; 8] = ["ux", "uy", "un", "ut", "tx", "ty", "tn", "tt"];
pub(super) const INTERFACE_KEYS: [&str; 7] = [
    "model",
    "initial",
    "cohesion",
    "gap",
    "tangential",
    "friction",
    "between",
];
pub(super) const SOLVE_KEYS: [&str; 8] = [
    "method",
    "tolerance",
    "max_iterations",
    "load_factors",
    "time",
    "collapse",
    "quadrature",
    "junctions",
];
pub(super) const OUTPUT_KEYS: [&str; 9] = [
    "directory",
    "history",
    "every",
    "operators",
    "compress",
    "vtk",
    "vtk_fields",
    "field",
    "section",
];
pub(super) const SECTION_KEYS: [&str; 4] = ["name", "from", "to", "points"];

/// Rejects unknown keys anywhere in the document, suggesting the nearest valid one.
pub(super) fn check_keys(doc: &toml::Table, path: &Path) -> Result<()> {
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
pub(super) fn typed<'de, T: Deserialize<'de>>(
    v: &toml::Value,
    key: &str,
    path: &Path,
) -> Result<T> {
    T::deserialize(v.clone()).map_err(|e| {
        Error::input(
            path,
            format!("`{key}`: {}", e.to_string().trim_end().replace('\n', " ")),
        )
    })
}

/// The named sub-tables of `[group.NAME]`, in file order.
pub(super) fn sub_tables<'a>(
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

pub(super) fn choice_error(key: &str, got: &str, valid: &[&str]) -> String {
    let quoted: Vec<String> = valid.iter().map(|v| format!("\"{v}\"")).collect();
    format!(
        "`{key}` = \"{got}\" is not one of {}{}",
        quoted.join(", "),
        did_you_mean(got, valid.iter().copied())
    )
}

pub(super) fn scalar(raw: RawScalar, key: &str, path: &Path) -> Result<Scalar> {
    match raw {
        RawScalar::Number(v) if v.is_finite() => Ok(Scalar::Const(v)),
        RawScalar::Number(v) => Err(Error::input(path, format!("`{key}` = {v} is not finite"))),
        RawScalar::Text(t) => match Expr::parse(&t) {
            Ok(e) => Ok(Scalar::Expr(e)),
            Err(why) => Err(Error::input(path, format!("`{key}` = \"{t}\": {why}"))),
        },
    }
}
