//! The JSON Schema of a scene file (`sgbem schema`), for editors that check TOML against a
//! schema (Taplo, Even Better TOML, IntelliJ): key names, types, allowed words and a short
//! description of every key, from docs/scene.md, and the combinations of keys the reader
//! refuses (draft-07 `dependencies`, `if`/`then`/`else`, `not`: `rules`). Ranges that
//! depend on other keys' values (a collapse tolerance below its max), expressions, names of
//! mesh groups and files, and names shared across tables are `sgbem check`'s.
//!
//! Place in the flow: nothing reads it; the test below keeps its keys those of `raw`.

use serde_json::{json, Map, Value};

use super::raw::BOUNDARY_KEYS;

/// A table with exactly the keys `props` (name, schema), of which `required` must be given.
fn table(description: &str, props: &[(&str, Value)], required: &[&str]) -> Value {
    let properties: Map<String, Value> = props
        .iter()
        .map(|(k, v)| (k.to_string(), v.clone()))
        .collect();
    json!({
        "type": "object",
        "description": description,
        "properties": properties,
        "required": required,
        "additionalProperties": false,
    })
}

fn typed(ty: &str, description: &str) -> Value {
    json!({ "type": ty, "description": description })
}

fn choice(words: &[&str], description: &str) -> Value {
    json!({ "type": "string", "enum": words, "description": description })
}

/// A number, or an expression in x, y (and t) as a string.
fn scalar(description: &str) -> Value {
    json!({ "type": ["number", "string"], "description": description })
}

fn point(description: &str) -> Value {
    json!({
        "type": "array", "items": { "type": "number" }, "minItems": 2, "maxItems": 2,
        "description": description,
    })
}

fn numbers(description: &str) -> Value {
    json!({ "type": "array", "items": { "type": "number" }, "description": description })
}

/// `key` is given and is `word`.
fn is(key: &str, word: &str) -> Value {
    json!({ "required": [key], "properties": { key: { "const": word } } })
}

/// Any of `keys` is given.
fn any_of(keys: &[&str]) -> Value {
    let each: Vec<Value> = keys.iter().map(|k| json!({ "required": [k] })).collect();
    json!({ "anyOf": each })
}

/// `table` with the combinations of keys the reader refuses, `rules` (each a schema the
/// table must also satisfy), and `dependencies` (key: the schema the table satisfies where
/// the key is given).
fn rules(mut table: Value, rules: Vec<Value>, dependencies: Value) -> Value {
    if !rules.is_empty() {
        table["allOf"] = Value::Array(rules);
    }
    if dependencies.as_object().is_some_and(|d| !d.is_empty()) {
        table["dependencies"] = dependencies;
    }
    table
}

/// Tables keyed by a group name or pattern, each of the schema `of`.
fn named(description: &str, of: Value) -> Value {
    json!({ "type": "object", "description": description, "additionalProperties": of })
}

fn body() -> Value {
    table(
        "an elastic body (a Physical Surface)",
        &[
            ("young", typed("number", "Young's modulus E (F/L²), > 0")),
            (
                "poisson",
                typed("number", "Poisson's ratio ν, -1 < ν < 0.5"),
            ),
            (
                "body_force",
                json!({
                    "type": "array", "items": { "type": ["number", "string"] },
                    "minItems": 2, "maxItems": 2,
                    "description": "body force [bx, by] (F/L³): numbers or expressions in t (uniform in the body)",
                }),
            ),
        ],
        &["young", "poisson"],
    )
}

fn boundary() -> Value {
    let d = |k: &str| match k {
        "ux" | "uy" => "displacement held (L): number or expression",
        "un" | "ut" => "normal / tangential displacement held (L): number or expression",
        "tx" | "ty" => "traction (F/L²): number or expression",
        _ => "normal / tangential traction (F/L²): number or expression",
    };
    let props: Vec<(&str, Value)> = BOUNDARY_KEYS.iter().map(|&k| (k, scalar(d(k)))).collect();
    // Per direction a displacement or a traction, not both; one frame per boundary.
    let both: Vec<Value> = [["ux", "tx"], ["uy", "ty"], ["un", "tn"], ["ut", "tt"]]
        .iter()
        .map(|pair| json!({ "required": pair }))
        .collect();
    rules(
        table("conditions on a Physical Curve", &props, &[]),
        vec![
            json!({ "not": { "anyOf": both } }),
            json!({
                "if": any_of(&["ux", "uy", "tx", "ty"]),
                "then": { "not": any_of(&["un", "ut", "tn", "tt"]) },
            }),
        ],
        json!({}),
    )
}

/// An interface table; `between` only in a named one (the reader refuses it in a pattern
/// or default table).
fn interface(named: bool) -> Value {
    let mut props = vec![
        (
            "model",
            choice(&["bonded", "unilateral"], "bonded, or unilateral contact"),
        ),
        (
            "initial",
            choice(&["closed", "open"], "the status at the start"),
        ),
        (
            "cohesion",
            scalar("tensile strength (F/L²), lost where the joint opens"),
        ),
        (
            "gap",
            scalar("initial normal gap (L), added to the drawn one"),
        ),
        (
            "tangential",
            choice(
                &["stick", "slide", "friction"],
                "tangential law of a unilateral interface",
            ),
        ),
        (
            "friction",
            scalar("Coulomb coefficient μ, with tangential = \"friction\""),
        ),
    ];
    if named {
        props.push((
            "between",
            json!({
                "type": "array", "items": { "type": "string" }, "minItems": 2, "maxItems": 2,
                "description": "two Physical Curves, one on each body, drawn on their own",
            }),
        ));
    }
    let zero = json!({ "const": 0 });
    rules(
        table("an interface between two bodies", &props, &["model"]),
        vec![
            // tangential = "friction" needs its coefficient.
            json!({ "if": is("tangential", "friction"), "then": { "required": ["friction"] } }),
            // A bonded interface starts closed, with no cohesion, gap or sliding.
            json!({
                "if": is("model", "bonded"),
                "then": { "properties": {
                    "initial": { "const": "closed" }, "cohesion": zero, "gap": zero,
                    "tangential": { "const": "stick" },
                } },
            }),
            // A gap applies to zones that start open, a cohesion to zones that start closed.
            json!({
                "if": is("initial", "open"),
                "then": { "properties": { "cohesion": zero } },
                "else": { "properties": { "gap": zero } },
            }),
        ],
        // The coefficient applies with tangential = "friction" only.
        json!({ "friction": is("tangential", "friction") }),
    )
}

fn solve() -> Value {
    let solve = table(
        "the contact solver and the load path",
        &[
            (
                "method",
                choice(
                    &["lcp", "qp", "both", "sparse", "exact"],
                    "the contact solver",
                ),
            ),
            (
                "tolerance",
                typed("number", "relative tolerance of the contact conditions"),
            ),
            (
                "max_iterations",
                typed("integer", "contact iterations per load step"),
            ),
            ("load_factors", numbers("load factors of the steps")),
            ("time", numbers("pseudo-times t of the steps")),
            (
                "collapse",
                table(
                    "search the largest multiplier t that stands",
                    &[
                        ("max", typed("number", "the largest t tried")),
                        ("tolerance", typed("number", "bracket width of the answer")),
                    ],
                    &["max"],
                ),
            ),
            (
                "quadrature",
                choice(&["fast", "standard", "accurate"], "Galerkin quadrature"),
            ),
            (
                "junctions",
                choice(
                    &["auto", "joints", "tangential"],
                    "where cycles of pairs at junction points are cut",
                ),
            ),
        ],
        &[],
    );
    // Load factors or pseudo-time, not both; a collapse search with neither.
    rules(
        solve,
        vec![json!({ "not": { "required": ["time", "load_factors"] } })],
        json!({ "collapse": { "not": any_of(&["time", "load_factors"]) } }),
    )
}

fn output() -> Value {
    let section = table(
        "a section: displacements and stresses along a segment",
        &[
            ("name", typed("string", "file name of the section")),
            ("from", point("first end [x, y] (L)")),
            ("to", point("last end [x, y] (L)")),
            (
                "points",
                typed("integer", "equally spaced points, 2 … 1 000 000"),
            ),
        ],
        &["name", "from", "to", "points"],
    );
    let output = table(
        "what the run writes",
        &[
            ("directory", typed("string", "the run folder")),
            (
                "history",
                choice(
                    &["full", "steps", "final"],
                    "which contact iterations are kept: all, the end of each load step, the last",
                ),
            ),
            (
                "every",
                json!({
                    "type": "integer", "minimum": 1,
                    "description": "with history = \"full\": keep every n-th iteration and the last",
                }),
            ),
            (
                "operators",
                typed("boolean", "archive the bodies' Galerkin blocks"),
            ),
            (
                "compress",
                typed("boolean", "deflate the archive's large datasets"),
            ),
            (
                "vtk",
                json!({
                    "oneOf": [{ "type": "boolean" }, { "enum": ["compressed"] }],
                    "description": "write the VTK files (\"compressed\": zlib-compressed arrays)",
                }),
            ),
            (
                "vtk_fields",
                json!({
                    "type": "array", "minItems": 1, "uniqueItems": true,
                    "items": { "enum": crate::output::vtk::POINT_ARRAYS },
                    "description": "the VTK point arrays to write (default: all)",
                }),
            ),
            (
                "field",
                typed(
                    "boolean",
                    "interior displacement and stress at the mesh nodes",
                ),
            ),
            (
                "section",
                json!({ "type": "array", "items": section, "description": "sections" }),
            ),
        ],
        &[],
    );
    // `every` thins a full history (the default).
    rules(
        output,
        Vec::new(),
        json!({ "every": { "properties": { "history": { "const": "full" } } } }),
    )
}

/// A `.geo` file name (the extension in any case, as the reader takes it).
const GEO: &str = "\\.[gG][eE][oO]$";

/// The schema of a scene file.
pub fn schema() -> Value {
    let mesh = json!({
        "description": "the .msh or .geo file, or a table with `file` and gmsh -setnumber parameters",
        "oneOf": [
            { "type": "string" },
            {
                "type": "object",
                "properties": { "file": { "type": "string" } },
                "required": ["file"],
                "additionalProperties": { "type": "number" },
                // gmsh parameters apply to a .geo only.
                "if": { "minProperties": 2 },
                "then": { "properties": { "file": { "pattern": GEO } } },
            },
        ],
    });
    let props = [
        ("title", typed("string", "the scene's title")),
        ("mesh", mesh),
        (
            "plane",
            choice(&["strain", "stress"], "plane strain or stress"),
        ),
        (
            "thickness",
            typed("number", "out-of-plane thickness (L), > 0"),
        ),
        (
            "units",
            table(
                "unit names, for labels",
                &[
                    ("length", typed("string", "length unit")),
                    ("force", typed("string", "force unit")),
                ],
                &[],
            ),
        ),
        (
            "body",
            named("bodies by Physical Surface name or pattern", body()),
        ),
        (
            "boundary",
            named("conditions by Physical Curve name or pattern", boundary()),
        ),
        (
            "interface",
            json!({
                "type": "object",
                "description": "interfaces by Physical Curve name or pattern (* and ?)",
                "patternProperties": { "[*?]": interface(false) },
                "additionalProperties": interface(true),
            }),
        ),
        (
            "defaults",
            table(
                "what bodies and interfaces without a table of their own take",
                &[("body", body()), ("interface", interface(false))],
                &[],
            ),
        ),
        (
            "contact",
            table(
                "contact found from the geometry",
                &[
                    ("bodies", typed("string", "the bodies searched, a pattern")),
                    (
                        "search",
                        typed("number", "largest distance of facing sides (L)"),
                    ),
                ],
                &["search"],
            ),
        ),
        ("solve", solve()),
        ("output", output()),
    ];
    // The mesh may come from the command line (--mesh) instead. A body table, a pattern
    // or [defaults.body]: at least one.
    let bodies = json!({ "anyOf": [
        { "required": ["body"], "properties": { "body": { "minProperties": 1 } } },
        { "required": ["defaults"], "properties": { "defaults": { "required": ["body"] } } },
    ] });
    let mut s = rules(
        table("an sgbem scene (docs/scene.md)", &props, &["plane"]),
        vec![bodies],
        json!({}),
    );
    s["$schema"] = json!("http://json-schema.org/draft-07/schema#");
    s["title"] = json!("sgbem scene");
    s
}

#[cfg(test)]
mod tests {
    use super::super::raw::{
        BODY_KEYS, CONTACT_KEYS, DEFAULTS_KEYS, INTERFACE_KEYS, OUTPUT_KEYS, SECTION_KEYS,
        SOLVE_KEYS, TOP_KEYS, UNITS_KEYS,
    };
    use super::*;

    fn keys(v: &Value) -> Vec<String> {
        let mut k: Vec<String> = v["properties"]
            .as_object()
            .expect("a table")
            .keys()
            .cloned()
            .collect();
        k.sort();
        k
    }

    fn sorted(k: &[&str]) -> Vec<String> {
        let mut k: Vec<String> = k.iter().map(|s| s.to_string()).collect();
        k.sort();
        k
    }

    /// Every table of the schema has exactly the keys the reader accepts.
    #[test]
    fn schema_keys_are_the_readers() {
        let s = schema();
        let p = &s["properties"];
        assert_eq!(keys(&s), sorted(&TOP_KEYS));
        assert_eq!(keys(&p["body"]["additionalProperties"]), sorted(&BODY_KEYS));
        assert_eq!(
            keys(&p["defaults"]["properties"]["body"]),
            sorted(&BODY_KEYS)
        );
        let b = &p["boundary"]["additionalProperties"];
        assert_eq!(keys(b), sorted(&BOUNDARY_KEYS));
        let i = &p["interface"]["additionalProperties"];
        assert_eq!(keys(i), sorted(&INTERFACE_KEYS));
        // `between` only in a named interface table.
        let unnamed: Vec<&str> = INTERFACE_KEYS
            .into_iter()
            .filter(|&k| k != "between")
            .collect();
        let pattern = &p["interface"]["patternProperties"]["[*?]"];
        assert_eq!(keys(pattern), sorted(&unnamed));
        let d = &p["defaults"]["properties"]["interface"];
        assert_eq!(keys(d), sorted(&unnamed));
        assert_eq!(keys(&p["defaults"]), sorted(&DEFAULTS_KEYS));
        assert_eq!(keys(&p["units"]), sorted(&UNITS_KEYS));
        assert_eq!(keys(&p["contact"]), sorted(&CONTACT_KEYS));
        assert_eq!(keys(&p["solve"]), sorted(&SOLVE_KEYS));
        assert_eq!(keys(&p["output"]), sorted(&OUTPUT_KEYS));
        let sec = &p["output"]["properties"]["section"]["items"];
        assert_eq!(keys(sec), sorted(&SECTION_KEYS));
    }
}
