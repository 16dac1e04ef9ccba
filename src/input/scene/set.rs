//! `--set KEY=VALUE` overrides: reading one, applying it to the scene's TOML document, and
//! showing it in messages.

/// One `--set KEY=VALUE`: the dotted key path and the value. The value is read as a TOML
/// value (number, string, boolean, array, inline table); anything that is not one is taken
/// as a bare string, so `--set solve.method=qp` works without quotes.
fn parse_set(set: &str) -> std::result::Result<(Vec<String>, toml::Value), String> {
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
pub(super) fn apply_set(doc: &mut toml::Table, set: &str) -> std::result::Result<(), String> {
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
pub(crate) fn shown_set(set: &str) -> String {
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
