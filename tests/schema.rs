//! `sgbem schema` against the scene reader, both ways:
//!
//! * every shipped scene (`pipelines/*.toml`) fits the schema: each key it uses is one the
//!   schema lists, with a value of the schema's type and words (a small validator of the
//!   JSON Schema keywords the schema uses; any other keyword fails the test), and the reader
//!   accepts the scene;
//! * every property the schema lists for the top level, `[mesh]`, `[units]`,
//!   `[defaults.body]`, `[defaults.interface]`, `[body.NAME]`, `[boundary.NAME]`,
//!   `[interface.NAME]` (named and pattern), `[contact]`, `[solve]` (and `collapse`),
//!   `[output]` (and `section`) is accepted by the reader: sample values of every type the
//!   schema allows (a number both as an integer and as a float) and every word of its
//!   `enum`, each one valid against the schema, are set into a scene the reader accepts,
//!   which must still be accepted;
//! * a key the schema marks required is one without which the reader refuses the table, and
//!   the reverse.
//!
//! The reader is `sgbem::input::scene::parse_scene`: everything `sgbem check` judges without
//! the mesh (the mesh file is not opened).

use std::path::PathBuf;

use serde_json::Value as Json;
use sgbem::input::scene::{parse_scene, schema::schema};
use toml::Value;

/// The JSON Schema keywords the validator below implements (draft-07; the combinations of
/// keys the reader refuses: `const`, `not`, `allOf`, `anyOf`, `if`/`then`/`else`,
/// `dependencies`, `minProperties`, and `pattern` in the one form the schema uses).
const KEYWORDS: [&str; 25] = [
    "$schema",
    "title",
    "description",
    "type",
    "enum",
    "oneOf",
    "properties",
    "patternProperties",
    "additionalProperties",
    "required",
    "items",
    "minItems",
    "maxItems",
    "uniqueItems",
    "minimum",
    "const",
    "not",
    "allOf",
    "anyOf",
    "if",
    "then",
    "else",
    "dependencies",
    "minProperties",
    "pattern",
];

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Whether TOML value `v` is of JSON Schema type `ty` (a TOML integer is a number too).
fn has_type(v: &Value, ty: &str) -> bool {
    match ty {
        "string" => v.is_str(),
        "integer" => v.is_integer(),
        "number" => v.is_integer() || v.is_float(),
        "boolean" => v.is_bool(),
        "array" => v.is_array(),
        "object" => v.is_table(),
        _ => false,
    }
}

/// TOML value `v` as JSON, for `enum` and `uniqueItems`.
fn json_of(v: &Value) -> Json {
    serde_json::to_value(v).unwrap_or(Json::Null)
}

/// The types a schema names in `type` (one or a list).
fn types(s: &Json) -> Vec<String> {
    match &s["type"] {
        Json::String(t) => vec![t.clone()],
        Json::Array(a) => a
            .iter()
            .filter_map(|t| t.as_str().map(String::from))
            .collect(),
        _ => Vec::new(),
    }
}

/// The schemas of `patternProperties` whose pattern matches `key`. The patterns the schema
/// uses are character classes (`[*?]`: the key holds one of these characters).
fn pattern_schemas<'a>(s: &'a Json, key: &str) -> Vec<&'a Json> {
    let Some(p) = s["patternProperties"].as_object() else {
        return Vec::new();
    };
    p.iter()
        .filter(|(pat, _)| {
            let class = pat
                .strip_prefix('[')
                .and_then(|r| r.strip_suffix(']'))
                .unwrap_or_else(|| panic!("pattern {pat:?}: only [chars] classes are checked"));
            key.chars().any(|c| class.contains(c))
        })
        .map(|(_, v)| v)
        .collect()
}

/// The schema of key `key` of a table of schema `s`: its property, else the patterns it
/// matches, else `additionalProperties` (`None`: not allowed).
fn property<'a>(s: &'a Json, key: &str) -> Option<&'a Json> {
    if let Some(p) = s["properties"].get(key) {
        return Some(p);
    }
    if let Some(p) = pattern_schemas(s, key).first() {
        return Some(p);
    }
    match &s["additionalProperties"] {
        Json::Bool(false) => None,
        Json::Object(_) => Some(&s["additionalProperties"]),
        _ => Some(&Json::Null),
    }
}

/// Whether TOML value `v` equals JSON value `c` (numbers by value: 0 is 0.0).
fn same(v: &Value, c: &Json) -> bool {
    match (
        v.as_float().or(v.as_integer().map(|i| i as f64)),
        c.as_f64(),
    ) {
        (Some(a), Some(b)) => a == b,
        _ => json_of(v) == *c,
    }
}

/// Whether `text` matches `pattern`, of the one form the schema uses: literal characters
/// (`\.` a dot) and classes `[..]`, anchored at the end (`$`).
fn matches(text: &str, pattern: &str) -> bool {
    let body = pattern
        .strip_suffix('$')
        .unwrap_or_else(|| panic!("pattern {pattern:?}: only a suffix ending in $ is checked"));
    let mut tokens: Vec<Vec<char>> = Vec::new();
    let mut chars = body.chars();
    while let Some(c) = chars.next() {
        tokens.push(match c {
            '\\' => vec![chars.next().expect("an escaped character")],
            '[' => chars.by_ref().take_while(|&c| c != ']').collect(),
            c if c.is_alphanumeric() || c == '_' => vec![c],
            c => panic!("pattern {pattern:?}: `{c}` is not checked"),
        });
    }
    let text: Vec<char> = text.chars().collect();
    text.len() >= tokens.len()
        && text[text.len() - tokens.len()..]
            .iter()
            .zip(&tokens)
            .all(|(c, class)| class.contains(c))
}

/// The combinations of keys: `const`, `allOf`, `anyOf`, `not`, `if`/`then`/`else`,
/// `dependencies`, `minProperties`, `pattern`.
fn check_combinations(v: &Value, s: &Json, at: &str, errors: &mut Vec<String>, seen: &mut usize) {
    let fits = |b: &Json| {
        let mut e = Vec::new();
        check(v, b, at, &mut e, &mut 0);
        e.is_empty()
    };
    if let Some(c) = s.get("const") {
        if !same(v, c) {
            errors.push(format!("{at} = {v}: not {c} (const)"));
        }
    }
    for b in s["allOf"].as_array().into_iter().flatten() {
        check(v, b, at, errors, seen);
    }
    if let Some(bs) = s["anyOf"].as_array() {
        if !bs.iter().any(fits) {
            errors.push(format!("{at}: fits none of the anyOf branches"));
        }
    }
    if let Some(n) = s.get("not") {
        if fits(n) {
            errors.push(format!("{at}: fits {n}, which `not` forbids"));
        }
    }
    if let Some(cond) = s.get("if") {
        let branch = if fits(cond) { "then" } else { "else" };
        if let Some(b) = s.get(branch) {
            check(v, b, &format!("{at} ({branch})"), errors, seen);
        }
    }
    if let Value::Table(t) = v {
        for (k, d) in s["dependencies"].as_object().into_iter().flatten() {
            if !t.contains_key(k) {
                continue;
            }
            match d {
                Json::Array(keys) => {
                    for r in keys.iter().filter_map(Json::as_str) {
                        if !t.contains_key(r) {
                            errors.push(format!("{at}: `{k}` needs `{r}`"));
                        }
                    }
                }
                d => check(v, d, &format!("{at} (with `{k}`)"), errors, seen),
            }
        }
        if s["minProperties"]
            .as_u64()
            .is_some_and(|m| (t.len() as u64) < m)
        {
            errors.push(format!("{at}: fewer keys than minProperties"));
        }
    }
    if let (Some(p), Some(text)) = (s["pattern"].as_str(), v.as_str()) {
        if !matches(text, p) {
            errors.push(format!("{at} = {text:?}: does not match {p}"));
        }
    }
}

/// Checks `v` (at key path `at`) against schema `s`, pushing a line per violation; counts
/// the values checked in `seen`.
fn check(v: &Value, s: &Json, at: &str, errors: &mut Vec<String>, seen: &mut usize) {
    *seen += 1;
    let Some(obj) = s.as_object() else {
        return; // true, or no schema: anything goes
    };
    for k in obj.keys() {
        if !KEYWORDS.contains(&k.as_str()) {
            errors.push(format!(
                "{at}: the schema uses `{k}`, which this test does not check"
            ));
        }
    }
    if let Some(branches) = s["oneOf"].as_array() {
        let fits = branches
            .iter()
            .filter(|b| {
                let mut e = Vec::new();
                check(v, b, at, &mut e, &mut 0);
                e.is_empty()
            })
            .count();
        if fits != 1 {
            errors.push(format!(
                "{at} = {v}: fits {fits} of the oneOf branches, not 1"
            ));
        }
    }
    let ts = types(s);
    if !ts.is_empty() && !ts.iter().any(|t| has_type(v, t)) {
        errors.push(format!("{at} = {v}: not of type {ts:?}"));
        return;
    }
    check_combinations(v, s, at, errors, seen);
    if let Some(words) = s["enum"].as_array() {
        if !words.contains(&json_of(v)) {
            errors.push(format!("{at} = {v}: not one of {words:?}"));
        }
    }
    if let (Some(min), Some(x)) = (s["minimum"].as_f64(), v.as_integer()) {
        if (x as f64) < min {
            errors.push(format!("{at} = {x}: below the minimum {min}"));
        }
    }
    if let Value::Table(t) = v {
        for (k, x) in t {
            let path = if at.is_empty() {
                k.clone()
            } else {
                format!("{at}.{k}")
            };
            match property(s, k) {
                Some(p) => check(x, p, &path, errors, seen),
                None => errors.push(format!("{path}: a key the schema does not list")),
            }
        }
        for r in s["required"].as_array().into_iter().flatten() {
            if let Some(r) = r.as_str() {
                if !t.contains_key(r) {
                    errors.push(format!("{at}: misses the required key `{r}`"));
                }
            }
        }
    }
    if let Value::Array(a) = v {
        let n = a.len() as u64;
        if s["minItems"].as_u64().is_some_and(|m| n < m) {
            errors.push(format!("{at}: {n} items, fewer than minItems"));
        }
        if s["maxItems"].as_u64().is_some_and(|m| n > m) {
            errors.push(format!("{at}: {n} items, more than maxItems"));
        }
        if s["uniqueItems"].as_bool() == Some(true) {
            let j: Vec<Json> = a.iter().map(json_of).collect();
            if (1..j.len()).any(|i| j[..i].contains(&j[i])) {
                errors.push(format!("{at}: an item twice (uniqueItems)"));
            }
        }
        for (i, x) in a.iter().enumerate() {
            check(x, &s["items"], &format!("{at}[{i}]"), errors, seen);
        }
    }
}

fn violations(v: &Value, s: &Json) -> (Vec<String>, usize) {
    let (mut errors, mut seen) = (Vec::new(), 0);
    check(v, s, "", &mut errors, &mut seen);
    (errors, seen)
}

fn toml_text(t: &toml::Table) -> String {
    toml::to_string(t).expect("a TOML table serialises")
}

/// `KEY = VALUE` text's value.
fn value(text: &str) -> Value {
    let t: toml::Table = format!("v = {text}")
        .parse()
        .unwrap_or_else(|e| panic!("sample {text:?}: {e}"));
    t["v"].clone()
}

/// The reader's verdict on a document: `Err(message)` where it refuses it.
fn read(doc: &toml::Table) -> Result<(), String> {
    let path = root().join("pipelines").join("schema_probe.toml");
    parse_scene(&toml_text(doc), &path)
        .map(|_| ())
        .map_err(|e| e.message().to_string())
}

#[test]
fn every_shipped_scene_fits_the_schema_and_is_read() {
    let s = schema();
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(root().join("pipelines"))
        .expect("pipelines/")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    scenes.sort();
    assert!(scenes.len() >= 20, "{} scenes", scenes.len());
    let (mut errors, mut seen) = (Vec::new(), 0);
    for p in &scenes {
        let text = std::fs::read_to_string(p).expect("a scene");
        let doc: Value = Value::Table(text.parse().expect("TOML"));
        let (e, n) = violations(&doc, &s);
        errors.extend(e.into_iter().map(|e| format!("{}: {e}", p.display())));
        seen += n;
        if let Err(e) = parse_scene(&text, p) {
            errors.push(format!(
                "{}: the reader refuses it: {}",
                p.display(),
                e.message()
            ));
        }
    }
    assert!(errors.is_empty(), "{}", errors.join("\n"));
    // Every value of every scene was walked (the scenes hold some hundreds).
    assert!(seen > 20 * scenes.len(), "{seen} values checked");

    // The validator is not blind: each of these mistakes in a shipped scene is reported.
    let good: toml::Table = std::fs::read_to_string(root().join("pipelines/wall_collapse.toml"))
        .expect("wall_collapse.toml")
        .parse()
        .expect("TOML");
    let mistakes: [(&str, &str); 9] = [
        ("defaults.interface.frition", "0.8"),
        ("defaults.interface.tangential", "\"coulomb\""),
        ("defaults.body.young", "\"stiff\""),
        ("solve.max_iterations", "10.5"),
        ("solve.collapse.step", "1.0"),
        ("output.vtk", "\"zip\""),
        ("output.every", "0"),
        ("output.vtk_fields", "[\"displacement\", \"displacement\"]"),
        ("mesh.h", "\"fine\""),
    ];
    for (key, v) in mistakes {
        let mut doc = good.clone();
        set(&mut doc, key, value(v));
        let (e, _) = violations(&Value::Table(doc), &s);
        assert!(!e.is_empty(), "{key} = {v} passes the validator");
    }
}

/// Sets `v` at the dotted key path `key` (`"NAME"` segments quoted, a number indexes an
/// array), making tables on the way.
fn set(doc: &mut toml::Table, key: &str, v: Value) {
    let parts = split(key);
    let (last, head) = parts.split_last().expect("a key");
    if let Some(t) = walk(doc, head) {
        t.insert(last.clone(), v);
    }
}

/// Removes the key `key`; whether it was there.
fn remove(doc: &mut toml::Table, key: &str) -> bool {
    let parts = split(key);
    let (last, head) = parts.split_last().expect("a key");
    walk(doc, head).is_some_and(|t| t.remove(last).is_some())
}

/// The table at path `parts` below `t`, made where missing (`None`: a value on the way is
/// not a table or an array).
fn walk<'a>(t: &'a mut toml::Table, parts: &[String]) -> Option<&'a mut toml::Table> {
    let Some((first, rest)) = parts.split_first() else {
        return Some(t);
    };
    let next = t
        .entry(first.clone())
        .or_insert_with(|| Value::Table(Default::default()));
    walk_value(next, rest)
}

fn walk_value<'a>(v: &'a mut Value, parts: &[String]) -> Option<&'a mut toml::Table> {
    match v {
        Value::Table(t) => walk(t, parts),
        Value::Array(a) => {
            let (i, rest) = parts.split_first()?;
            walk_value(a.get_mut(i.parse::<usize>().ok()?)?, rest)
        }
        _ => None,
    }
}

fn split(key: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut quoted = false;
    for c in key.chars() {
        match c {
            '"' => quoted = !quoted,
            '.' if !quoted => out.push(std::mem::take(&mut cur)),
            _ => cur.push(c),
        }
    }
    out.push(cur);
    out
}

/// A scene the reader accepts: the base every probe starts from.
const BASE: &str = r#"
plane = "strain"
[mesh]
file = "probe.geo"
[body.A]
young = 1000.0
poisson = 0.25
"#;

/// The tables probed: key path (as `set` reads it), where its schema is (JSON pointer) and
/// the least table the reader accepts there (set before each probe of one of its keys).
const TABLES: [(&str, &str, &str); 15] = [
    ("", "", "{}"),
    (
        "mesh",
        "/properties/mesh/oneOf/1",
        r#"{ file = "probe.geo" }"#,
    ),
    ("units", "/properties/units", "{}"),
    (
        "defaults.body",
        "/properties/defaults/properties/body",
        "{ young = 1000.0, poisson = 0.25 }",
    ),
    (
        "defaults.interface",
        "/properties/defaults/properties/interface",
        r#"{ model = "unilateral" }"#,
    ),
    (
        "body.A",
        "/properties/body/additionalProperties",
        "{ young = 1000.0, poisson = 0.25 }",
    ),
    (
        "boundary.B",
        "/properties/boundary/additionalProperties",
        "{}",
    ),
    (
        "interface.J",
        "/properties/interface/additionalProperties",
        r#"{ model = "unilateral" }"#,
    ),
    (r#"interface."j*""#, "", r#"{ model = "unilateral" }"#),
    ("contact", "/properties/contact", "{ search = 0.01 }"),
    ("solve", "/properties/solve", "{}"),
    (
        "solve.collapse",
        "/properties/solve/properties/collapse",
        "{ max = 2.0 }",
    ),
    ("output", "/properties/output", "{}"),
    (
        "output.section.0",
        "/properties/output/properties/section/items",
        r#"{ name = "s", from = [0.0, 0.0], to = [1.0, 0.0], points = 3 }"#,
    ),
    ("defaults", "/properties/defaults", "{}"),
];

/// Sample values (TOML text) of each property: at least one of every type the schema allows
/// (a number as an integer and as a float, but for [`NO_INTEGER`]); the words of an `enum`
/// are added by the test. `mesh.h` stands for any gmsh parameter.
const SAMPLES: &[(&str, &[&str])] = &[
    ("title", &[r#""probe""#]),
    (
        "mesh",
        &[r#""probe.msh""#, r#"{ file = "probe.geo", h = 2 }"#],
    ),
    ("plane", &[]),
    ("thickness", &["2", "0.5"]),
    ("units", &[r#"{ length = "m", force = "kN" }"#]),
    ("body", &["{ A = { young = 1, poisson = 0.2 } }"]),
    ("boundary", &["{ B = { ux = 0 } }"]),
    ("interface", &[r#"{ J = { model = "bonded" } }"#]),
    ("defaults", &[r#"{ body = { young = 1.0, poisson = 0 } }"#]),
    ("defaults.body", &["{ young = 1.0, poisson = 0 }"]),
    ("defaults.interface", &[r#"{ model = "bonded" }"#]),
    ("contact", &["{ search = 0.01 }"]),
    ("solve", &[r#"{ method = "qp" }"#]),
    ("output", &[r#"{ history = "final" }"#]),
    ("mesh.file", &[r#""other.geo""#]),
    ("mesh.h", &["2", "0.5"]),
    ("units.length", &[r#""m""#]),
    ("units.force", &[r#""kN""#]),
    ("young", &["2000", "2.5e3"]),
    ("poisson", &["0", "0.3"]),
    ("body_force", &["[0, -20]", r#"["20*t", -20.0]"#]),
    ("ux", &["0", "0.5", r#""0.001*x*t""#]),
    ("uy", &["0", "-0.5", r#""0.001*y""#]),
    ("un", &["0", "0.5", r#""0.001*t""#]),
    ("ut", &["0", "0.5", r#""0.001*t""#]),
    ("tx", &["1", "1.5", r#""x*t""#]),
    ("ty", &["-1", "-1.5", r#""-10*t""#]),
    ("tn", &["-1", "-1.5", r#""-10*t""#]),
    ("tt", &["1", "0.5", r#""2*t""#]),
    ("model", &[]),
    ("initial", &[]),
    ("cohesion", &["2", "0.5", r#""0.1*x""#]),
    ("gap", &["0", "0.001", r#""0.001*x""#]),
    ("tangential", &[]),
    ("friction", &["1", "0.6", r#""0.5 + 0.1*t""#]),
    ("between", &[r#"["J_a", "J_b"]"#]),
    ("contact.bodies", &[r#""brick_*""#]),
    ("contact.search", &["1", "0.5"]),
    ("solve.method", &[]),
    ("solve.tolerance", &["1e-8"]),
    ("solve.max_iterations", &["50"]),
    ("solve.load_factors", &["[0.5, 1]", "[2]"]),
    ("solve.time", &["[0.5, 1]", "[2]"]),
    (
        "solve.collapse",
        &["{ max = 2 }", "{ max = 2.0, tolerance = 0.01 }"],
    ),
    ("solve.quadrature", &[]),
    ("solve.junctions", &[]),
    ("collapse.max", &["3", "2.5"]),
    ("collapse.tolerance", &["1", "0.01"]),
    ("output.directory", &[r#""probe_out""#]),
    ("output.history", &[]),
    ("output.every", &["2"]),
    ("output.operators", &["true", "false"]),
    ("output.compress", &["true", "false"]),
    ("output.vtk", &["true", "false"]),
    ("output.vtk_fields", &[r#"["displacement", "von_mises"]"#]),
    ("output.field", &["true", "false"]),
    (
        "output.section",
        &[r#"[{ name = "s", from = [0, 0], to = [1, 0], points = 3 }]"#],
    ),
    ("section.name", &[r#""along""#]),
    ("section.from", &["[0.5, 0.5]", "[0, 1]"]),
    ("section.to", &["[2.5, 0.0]", "[2, 1]"]),
    ("section.points", &["100"]),
];

/// Numbers without a valid integer value: `solve.tolerance` lies in (0, 1).
const NO_INTEGER: [&str; 1] = ["solve.tolerance"];

/// The samples of key `key` of table `table`: by the full path, else the table's last name
/// and the key (`collapse.max`), else the key alone (a body's, boundary's or interface's).
fn samples(table: &str, key: &str) -> Option<&'static [&'static str]> {
    let full = if table.is_empty() {
        key.to_string()
    } else {
        format!("{table}.{key}")
    };
    let last = split(table)
        .iter()
        .rev()
        .find(|p| p.parse::<usize>().is_err())
        .map(|p| format!("{p}.{key}"))
        .unwrap_or_default();
    [full.as_str(), last.as_str(), key]
        .iter()
        .find_map(|k| SAMPLES.iter().find(|(s, _)| s == k).map(|(_, v)| *v))
}

/// What a probe of `key` = `v` in an interface table needs besides (the reader ties some keys
/// to others: friction to tangential = "friction", a gap to initial = "open").
fn context(table: &str, key: &str, v: &Value) -> Vec<(String, Value)> {
    let at = |k: &str, v: &str| (format!("{table}.{k}"), value(v));
    match (key, v.as_str()) {
        ("tangential", Some("friction")) => vec![at("friction", "0.6")],
        ("friction", _) => vec![at("tangential", r#""friction""#)],
        ("gap", _) => vec![at("initial", r#""open""#)],
        _ => Vec::new(),
    }
}

/// Every type a sample must show for a property of schema `p`: its `type`s (a number as an
/// integer and as a float), those of its `oneOf` branches, a string for an `enum`.
fn wanted(p: &Json) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for t in types(p) {
        if t == "number" {
            out.extend(["integer".into(), "float".into()]);
        } else {
            out.push(t);
        }
    }
    for b in p["oneOf"].as_array().into_iter().flatten() {
        out.extend(wanted(b));
    }
    if out.is_empty() && p["enum"].is_array() {
        out.push("string".into());
    }
    out.sort();
    out.dedup();
    out
}

fn toml_type(v: &Value) -> &'static str {
    match v {
        Value::String(_) => "string",
        Value::Integer(_) => "integer",
        Value::Float(_) => "float",
        Value::Boolean(_) => "boolean",
        Value::Array(_) => "array",
        Value::Table(_) => "object",
        Value::Datetime(_) => "datetime",
    }
}

/// The words of an `enum` of `p` or of its `oneOf` branches.
fn words(p: &Json) -> Vec<Value> {
    let mut out: Vec<Value> = Vec::new();
    for w in p["enum"].as_array().into_iter().flatten() {
        match w {
            Json::String(s) => out.push(Value::String(s.clone())),
            Json::Bool(b) => out.push(Value::Boolean(*b)),
            other => panic!("an enum word {other}: strings and booleans only here"),
        }
    }
    for b in p["oneOf"].as_array().into_iter().flatten() {
        out.extend(words(b));
    }
    if let Some(items) = p["items"].as_object() {
        // An array of words (vtk_fields): each word alone.
        for w in words(&Json::Object(items.clone())) {
            out.push(Value::Array(vec![w]));
        }
    }
    out
}

/// Sets table `table` of [`TABLES`] to `least`: `NAME.0` is the array `NAME` of it.
fn place(doc: &mut toml::Table, table: &str, least: &str) {
    match table.strip_suffix(".0") {
        Some(array) => set(doc, array, Value::Array(vec![value(least)])),
        None if table.is_empty() => {}
        None => set(doc, table, value(least)),
    }
}

/// The schema of table `table` of [`TABLES`]: at `pointer`, the whole for the top level, the
/// pattern's for the pattern table (`pointer` empty).
fn table_schema<'a>(s: &'a Json, table: &str, pointer: &str) -> &'a Json {
    if table.is_empty() {
        s
    } else if pointer.is_empty() {
        property(&s["properties"]["interface"], "j*").expect("interface patterns")
    } else {
        s.pointer(pointer)
            .unwrap_or_else(|| panic!("{pointer}: not in the schema"))
    }
}

#[test]
fn every_schema_property_is_read() {
    let s = schema();
    let base: toml::Table = BASE.parse().expect("BASE");
    read(&base).expect("the base scene is read");
    let mut drift = Vec::new();
    let mut probes = 0;
    for (table, pointer, least) in TABLES {
        let node = table_schema(&s, table, pointer);
        let mut start = base.clone();
        place(&mut start, table, least);
        if let Err(e) = read(&start) {
            panic!("[{table}] = {least}: the reader refuses the least table: {e}");
        }
        let mut keys: Vec<String> = node["properties"]
            .as_object()
            .map(|p| p.keys().cloned().collect())
            .unwrap_or_default();
        if node["additionalProperties"].is_object() {
            keys.push("h".into()); // [mesh]: gmsh parameters, any name
        }
        for key in keys {
            let p = property(node, &key).expect("listed");
            let Some(given) = samples(table, &key) else {
                drift.push(format!("{table}.{key}: no sample in SAMPLES"));
                continue;
            };
            let mut vs: Vec<Value> = given.iter().map(|t| value(t)).collect();
            vs.extend(words(p));
            let shown: Vec<&str> = vs.iter().map(toml_type).collect();
            for w in wanted(p) {
                let full = format!("{table}.{key}");
                if w == "integer" && NO_INTEGER.contains(&full.as_str()) {
                    continue;
                }
                if !shown.contains(&w.as_str()) {
                    drift.push(format!(
                        "{table}.{key}: no {w} sample (the schema allows it)"
                    ));
                }
            }
            for v in vs {
                let (e, _) = violations(&v, p);
                assert!(
                    e.is_empty(),
                    "{table}.{key} = {v}: the sample is not valid: {e:?}"
                );
                let mut doc = start.clone();
                let full = if table.is_empty() {
                    key.clone()
                } else {
                    format!("{table}.{key}")
                };
                for (k, x) in context(table, &key, &v) {
                    set(&mut doc, &k, x);
                }
                set(&mut doc, &full, v.clone());
                let (e, _) = violations(&Value::Table(doc.clone()), &s);
                assert!(e.is_empty(), "{full} = {v}: the probe is not valid: {e:?}");
                probes += 1;
                if let Err(m) = read(&doc) {
                    drift.push(format!(
                        "{full} = {v}: the schema allows it, the reader says: {m}"
                    ));
                }
            }
        }
    }
    assert!(drift.is_empty(), "{}", drift.join("\n"));
    assert!(probes > 100, "{probes} probes");
}

/// A key the schema requires is one without which the reader refuses the table, and each
/// key of a table's least form that the reader cannot do without is required by the schema
/// (a scene's bodies excepted: `[body.NAME]`, a pattern or `[defaults.body]` will do).
#[test]
fn required_keys_are_the_readers() {
    let s = schema();
    let base: toml::Table = BASE.parse().expect("BASE");
    let mut drift = Vec::new();
    for (table, pointer, least) in TABLES {
        let node = table_schema(&s, table, pointer);
        let mut start = base.clone();
        let keys: Vec<String> = if table.is_empty() {
            vec!["plane".into(), "mesh".into()]
        } else {
            place(&mut start, table, least);
            value(least)
                .as_table()
                .expect("a table")
                .keys()
                .cloned()
                .collect()
        };
        let required: Vec<&str> = node["required"]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(Json::as_str)
            .collect();
        for r in &required {
            if !keys.iter().any(|k| k == r) {
                drift.push(format!(
                    "[{table}]: `{r}` is required but not in the test's table"
                ));
            }
        }
        for k in keys {
            let mut doc = start.clone();
            let full = if table.is_empty() {
                k.clone()
            } else {
                format!("{table}.{k}")
            };
            assert!(remove(&mut doc, &full), "{full}");
            let reader = read(&doc).is_err();
            let schema_says = required.contains(&k.as_str());
            if reader != schema_says {
                drift.push(format!(
                    "{full}: the reader {} it, the schema {}",
                    if reader {
                        "requires"
                    } else {
                        "does not require"
                    },
                    if schema_says {
                        "requires it"
                    } else {
                        "does not"
                    }
                ));
            }
        }
    }
    assert!(drift.is_empty(), "{}", drift.join("\n"));
}

/// The combinations of keys the reader refuses (each names the other key in its message),
/// planted alone into [`BASE`], a scene it reads, and beside each the nearest combination it
/// accepts: the keys set (`PATH=VALUE`, `; ` between them) and whether the reader reads it.
const PLANTED: &[(&str, bool)] = &[
    // tangential = "friction" needs its coefficient; the coefficient needs that law.
    (
        r#"interface.J.model="unilateral"; interface.J.tangential="friction""#,
        false,
    ),
    (
        r#"interface.J.model="unilateral"; interface.J.friction=0.5"#,
        false,
    ),
    (
        r#"interface.J.model="unilateral"; interface.J.friction=0.5; interface.J.tangential="slide""#,
        false,
    ),
    (
        r#"interface.J.model="unilateral"; interface.J.friction=0.5; interface.J.tangential="friction""#,
        true,
    ),
    // A bonded interface: closed, no cohesion, gap or sliding (in a named, pattern or
    // default table alike).
    (
        r#"defaults.interface.model="bonded"; defaults.interface.initial="open""#,
        false,
    ),
    (
        r#"interface."j*".model="bonded"; interface."j*".cohesion=1.5"#,
        false,
    ),
    (
        r#"interface.J.model="bonded"; interface.J.cohesion="0""#,
        false,
    ),
    (
        r#"interface.J.model="bonded"; interface.J.tangential="slide""#,
        false,
    ),
    (
        r#"interface.J.model="bonded"; interface.J.cohesion=0; interface.J.gap=0.0; interface.J.initial="closed"; interface.J.tangential="stick""#,
        true,
    ),
    // A gap for zones that start open, a cohesion for zones that start closed.
    (
        r#"interface.J.model="unilateral"; interface.J.gap=0.01"#,
        false,
    ),
    (
        r#"interface.J.model="unilateral"; interface.J.initial="closed"; interface.J.gap="0.01*x""#,
        false,
    ),
    (
        r#"interface.J.model="unilateral"; interface.J.initial="open"; interface.J.cohesion=1"#,
        false,
    ),
    (
        r#"interface.J.model="unilateral"; interface.J.initial="open"; interface.J.gap="0.01*x"; interface.J.cohesion=0"#,
        true,
    ),
    (
        r#"interface.J.model="unilateral"; interface.J.cohesion=2; interface.J.gap=0"#,
        true,
    ),
    // Per direction a displacement or a traction; one frame per boundary.
    ("boundary.B.ux=0; boundary.B.tx=1", false),
    (r#"boundary.B.un=0; boundary.B.tn="-t""#, false),
    ("boundary.B.ux=0; boundary.B.tn=1", false),
    ("boundary.B.ty=-1; boundary.B.ut=0", false),
    ("boundary.B.ux=0; boundary.B.ty=-1", true),
    ("boundary.B.un=0; boundary.B.tt=1", true),
    // Load factors or pseudo-time; a collapse search with neither.
    ("solve.time=[1.0]; solve.load_factors=[1.0]", false),
    ("solve.collapse.max=2.0; solve.time=[0.5, 1.0]", false),
    ("solve.collapse.max=2.0; solve.load_factors=[1]", false),
    (r#"solve.collapse.max=2.0; solve.method="sparse""#, true),
    ("solve.time=[0.5, 1.0]", true),
    // `every` thins a full history.
    (r#"output.every=2; output.history="steps""#, false),
    (r#"output.every=3; output.history="final""#, false),
    (r#"output.every=2; output.history="full""#, true),
    // gmsh parameters with a .geo only.
    (r#"mesh.file="probe.msh"; mesh.h=2"#, false),
    (r#"mesh.file="probe.GEO"; mesh.h=2"#, true),
    // At least one body table, pattern or [defaults.body].
    ("body={}", false),
    (
        "body={}; defaults.body={ young = 1.0, poisson = 0.3 }",
        true,
    ),
    (
        r#"body={ "brick_*" = { young = 1.0, poisson = 0.3 } }"#,
        true,
    ),
];

/// The combinations of keys the reader refuses are marked by the schema (draft-07
/// `dependencies`, `if`/`then`/`else`, `not`, `anyOf`, `const`, `pattern`, read by the
/// validator above), planted one at a time into a scene the reader reads; the nearest
/// combinations it accepts pass the schema (it is not stricter than the reader).
#[test]
fn combinations_the_reader_refuses_are_marked_by_the_schema() {
    let s = schema();
    let base: toml::Table = BASE.parse().expect("BASE");
    let mut drift = Vec::new();
    for (keys, reads) in PLANTED {
        let mut doc = base.clone();
        for kv in keys.split("; ") {
            let (k, v) = kv.split_once('=').expect("PATH=VALUE");
            set(&mut doc, k, value(v));
        }
        let reader = read(&doc);
        let (errors, _) = violations(&Value::Table(doc), &s);
        if reader.is_ok() != *reads {
            drift.push(format!(
                "{keys:?}: the reader says {reader:?}, expected {reads}"
            ));
        }
        if errors.is_empty() != *reads {
            drift.push(format!(
                "{keys:?}: the schema {}",
                if errors.is_empty() {
                    "passes it".to_string()
                } else {
                    format!("marks it: {errors:?}")
                }
            ));
        }
    }
    assert!(drift.is_empty(), "{}", drift.join("\n"));
    let refused = PLANTED.iter().filter(|(_, r)| !r).count();
    assert!(refused >= 20, "{refused} planted mistakes");
}
