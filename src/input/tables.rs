//! Tables for many bodies: glob tables (`[body."brick*"]`, `[interface."joint*"]`) and
//! defaults (`[defaults.body]`, `[defaults.interface]`), resolved against the mesh's groups.
//!
//! Place in the flow: `scene` reads the tables (each validated like a named one); `model`
//! calls [`resolve_bodies`] before it reads the Physical Surfaces and [`resolve_interfaces`]
//! once it knows which Physical Curves two bodies share. Both return the scene with one
//! concrete table per group, so nothing after them sees a pattern.
//!
//! Which table applies to a group (a Physical Surface for `body`, a Physical Curve for
//! `interface`), first rule that gives one:
//!
//! 1. the table named exactly after the group (`[body.brick_1]`; for a Physical Curve an
//!    exact `[boundary.NAME]` counts too, and then no interface table applies to it);
//! 2. the most specific glob table that matches the whole name (`*` any run of characters,
//!    `?` one character); specificity is the number of literal characters, so `brick_1*` (7)
//!    beats `brick*` (5), which beats `*` (0). Two matching globs of equal specificity whose
//!    tables differ are an input error naming both; identical tables are not a conflict;
//! 3. `[defaults.body]` for a Physical Surface; `[defaults.interface]` for a Physical Curve
//!    that two bodies share.
//!
//! A table applies whole: keys are never merged across tables. A glob table that matches no
//! group is an input error (as an exact table naming a missing group is); an interface glob
//! that matches a Physical Curve no two bodies share is one too.

use std::collections::BTreeSet;
use std::path::Path;

use crate::error::{Error, Result};
use crate::input::mesh::Mesh;
use crate::input::scene::{BodySpec, InterfaceSpec, Scene};

/// A glob over group names: `*` matches any run of characters, `?` exactly one.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Glob {
    pattern: String,
}

impl Glob {
    /// True when a table name is a pattern rather than a group name.
    pub(crate) fn is_pattern(name: &str) -> bool {
        name.contains(['*', '?'])
    }

    pub fn new(pattern: &str) -> Glob {
        Glob {
            pattern: pattern.to_string(),
        }
    }

    pub fn as_str(&self) -> &str {
        &self.pattern
    }

    /// Literal (non-wildcard) characters: the rank of the pattern among matching ones.
    pub(crate) fn specificity(&self) -> usize {
        self.pattern
            .chars()
            .filter(|c| !matches!(c, '*' | '?'))
            .count()
    }

    /// Whole-name match, by backtracking on the last `*` (linear in practice).
    pub fn matches(&self, name: &str) -> bool {
        let p: Vec<char> = self.pattern.chars().collect();
        let s: Vec<char> = name.chars().collect();
        let (mut i, mut j) = (0usize, 0usize);
        let mut star: Option<(usize, usize)> = None;
        while j < s.len() {
            if i < p.len() && (p[i] == '?' || p[i] == s[j]) {
                i += 1;
                j += 1;
            } else if i < p.len() && p[i] == '*' {
                star = Some((i, j));
                i += 1;
            } else if let Some((si, sj)) = star {
                i = si + 1;
                j = sj + 1;
                star = Some((si, sj + 1));
            } else {
                return false;
            }
        }
        p[i..].iter().all(|&c| c == '*')
    }
}

/// One glob table: its pattern, its validated contents and its TOML text (to compare two
/// tables for a conflict).
#[derive(Debug, Clone)]
pub struct Pattern<T> {
    pub glob: Glob,
    pub spec: T,
    pub raw: toml::Value,
}

/// The glob and default tables of a scene.
#[derive(Debug, Clone, Default)]
pub struct Tables {
    pub bodies: Vec<Pattern<BodySpec>>,
    pub interfaces: Vec<Pattern<InterfaceSpec>>,
    pub default_body: Option<BodySpec>,
    pub default_interface: Option<InterfaceSpec>,
}

impl Tables {
    pub fn is_empty(&self) -> bool {
        self.bodies.is_empty()
            && self.interfaces.is_empty()
            && self.default_body.is_none()
            && self.default_interface.is_none()
    }
}

/// Which table gave a group its contents, for `sgbem check`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Resolved {
    /// The table as written in the scene: `[body.A]`, `[body."brick*"]`, `[defaults.body]`.
    pub table: String,
    /// The group it applies to.
    pub group: String,
}

/// Where a group's table came from.
enum Source<'a, T> {
    Glob(&'a Pattern<T>),
    Default(&'a T),
}

/// The table for `name` among globs and the default (the exact table already failed), or an
/// error for two equally specific, different globs.
fn pick<'a, T>(
    kind: &str,
    what: &str,
    name: &str,
    globs: &'a [Pattern<T>],
    default: Option<&'a T>,
    sfile: &Path,
) -> Result<Option<Source<'a, T>>> {
    let matching: Vec<&Pattern<T>> = globs.iter().filter(|g| g.glob.matches(name)).collect();
    let Some(best) = matching.iter().map(|g| g.glob.specificity()).max() else {
        return Ok(default.map(Source::Default));
    };
    let top: Vec<&&Pattern<T>> = matching
        .iter()
        .filter(|g| g.glob.specificity() == best)
        .collect();
    if let Some(other) = top.iter().skip(1).find(|g| g.raw != top[0].raw) {
        return Err(Error::input(
            sfile,
            format!(
                "{what} \"{name}\" matches [{kind}.\"{}\"] and [{kind}.\"{}\"], equally specific \
                 ({best} literal characters each) but with different values: add an exact \
                 [{kind}.{name}] table, or make one pattern more specific",
                top[0].glob.as_str(),
                other.glob.as_str()
            ),
        ));
    }
    Ok(Some(Source::Glob(top[0])))
}

fn table_name(kind: &str, source: &Source<'_, impl Sized>) -> String {
    match source {
        Source::Glob(g) => format!("[{kind}.\"{}\"]", g.glob.as_str()),
        Source::Default(_) => format!("[defaults.{kind}]"),
    }
}

/// Every glob must match at least one group.
fn check_used<T>(
    kind: &str,
    what: &str,
    globs: &[Pattern<T>],
    groups: &[&str],
    sfile: &Path,
) -> Result<()> {
    for g in globs {
        if !groups.iter().any(|n| g.glob.matches(n)) {
            let list = if groups.is_empty() {
                "none".to_string()
            } else {
                groups.join(", ")
            };
            return Err(Error::input(
                sfile,
                format!(
                    "[{kind}.\"{}\"] matches no {what} of the mesh ({list}): correct the pattern \
                     (`*` stands for any run of characters, `?` for one) or remove the table",
                    g.glob.as_str()
                ),
            ));
        }
    }
    Ok(())
}

/// The mesh's group names of one dimension, in its order.
fn group_names(mesh: &Mesh, dim: i32) -> Vec<&str> {
    mesh.physical_names
        .iter()
        .filter(|p| p.dim == dim)
        .map(|p| p.name.as_str())
        .collect()
}

/// One kind of table resolved over the groups: for each group without an exact table (in
/// the groups' order), the winning glob (`accept` may refuse it for that group) or the
/// default (`default_for`), renamed after the group by `named`.
#[allow(clippy::too_many_arguments)]
fn resolve_kind<'a, T>(
    (kind, what): (&str, &str),
    groups: &[&str],
    has_exact: impl Fn(&str) -> bool,
    globs: &'a [Pattern<T>],
    default_for: impl Fn(&str) -> Option<&'a T>,
    accept: impl Fn(&Pattern<T>, &str) -> Result<()>,
    named: impl Fn(&T, &str) -> T,
    sfile: &Path,
) -> Result<Vec<(T, Resolved)>> {
    check_used(kind, what, globs, groups, sfile)?;
    let mut out = Vec::new();
    let mut seen: BTreeSet<&str> = BTreeSet::new();
    for &name in groups {
        if has_exact(name) || !seen.insert(name) {
            continue;
        }
        let Some(source) = pick(kind, what, name, globs, default_for(name), sfile)? else {
            continue;
        };
        let spec = match &source {
            Source::Glob(g) => {
                accept(g, name)?;
                &g.spec
            }
            Source::Default(d) => *d,
        };
        let table = table_name(kind, &source);
        out.push((
            named(spec, name),
            Resolved {
                table,
                group: name.to_string(),
            },
        ));
    }
    Ok(out)
}

/// The scene with a concrete `[body]` table for every Physical Surface that has none but
/// matches a glob or takes `[defaults.body]`: exact tables first in file order, then the
/// others in the mesh's order. Also says which table applies to each body.
pub fn resolve_bodies(scene: &Scene, mesh: &Mesh) -> Result<(Scene, Vec<Resolved>)> {
    let found = resolve_kind(
        ("body", "Physical Surface"),
        &group_names(mesh, 2),
        |name| scene.body(name).is_some(),
        &scene.tables.bodies,
        |_| scene.tables.default_body.as_ref(),
        |_, _| Ok(()),
        |spec, name| BodySpec {
            name: name.to_string(),
            ..spec.clone()
        },
        &scene.path,
    )?;
    let mut out = scene.clone();
    let mut resolved: Vec<Resolved> = scene
        .bodies
        .iter()
        .map(|b| Resolved {
            table: format!("[body.{}]", b.name),
            group: b.name.clone(),
        })
        .collect();
    for (spec, r) in found {
        out.bodies.push(spec);
        resolved.push(r);
    }
    Ok((out, resolved))
}

/// The scene with a concrete `[interface]` table for every Physical Curve that has no exact
/// `[boundary]` or `[interface]` table but matches an interface glob or, when two bodies
/// share one of its curves (`shared`), takes `[defaults.interface]`.
pub fn resolve_interfaces(
    scene: &Scene,
    mesh: &Mesh,
    shared: &BTreeSet<&str>,
) -> Result<(Scene, Vec<Resolved>)> {
    let sfile = scene.path.as_path();
    let found = resolve_kind(
        ("interface", "Physical Curve"),
        &group_names(mesh, 1),
        |name| scene.interface(name).is_some() || scene.boundary(name).is_some(),
        &scene.tables.interfaces,
        |name| {
            scene
                .tables
                .default_interface
                .as_ref()
                .filter(|_| shared.contains(name))
        },
        |g, name| {
            if shared.contains(name) {
                return Ok(());
            }
            Err(Error::input(
                sfile,
                format!(
                    "[interface.\"{}\"] matches Physical Curve \"{name}\", which no two bodies \
                     share: an interface joins two bodies; make the pattern narrower, or give \
                     \"{name}\" its own [boundary.{name}] table",
                    g.glob.as_str()
                ),
            ))
        },
        |spec, name| InterfaceSpec {
            name: name.to_string(),
            ..spec.clone()
        },
        sfile,
    )?;
    let mut out = scene.clone();
    let mut resolved: Vec<Resolved> = scene
        .interfaces
        .iter()
        .map(|i| Resolved {
            table: format!("[interface.{}]", i.name),
            group: i.name.clone(),
        })
        .collect();
    for (spec, r) in found {
        out.interfaces.push(spec);
        resolved.push(r);
    }
    Ok((out, resolved))
}

/// A hint for a `--set body.NAME.KEY=V` or `--set interface.NAME.KEY=V` that failed because it
/// made a new, incomplete `[body.NAME]` (`[interface.NAME]`) table while the scene's bodies
/// (interfaces) take `[defaults.body]` (`[defaults.interface]`): such a table applies whole
/// (keys are never merged across tables), so the key belongs in the defaults. `doc` is the
/// scene's document before the overrides.
pub(crate) fn defaults_hint(doc: &toml::Table, set: &str) -> Option<String> {
    let (path, value) = set.split_once('=')?;
    let parts: Vec<&str> = path.trim().split('.').collect();
    let [kind @ ("body" | "interface"), name, key] = parts[..] else {
        return None;
    };
    let declared = doc
        .get(kind)
        .and_then(|t| t.as_table())
        .is_some_and(|t| t.contains_key(name));
    let defaults = doc
        .get("defaults")
        .and_then(|d| d.get(kind))
        .is_some_and(toml::Value::is_table);
    if declared || !defaults || name == "*" {
        return None;
    }
    let value = value.trim();
    let needs = if kind == "body" {
        "`young` and `poisson`"
    } else {
        "`model` first"
    };
    Some(format!(
        "the scene has no [{kind}.{name}] table: its {kind} \"{name}\" takes [defaults.{kind}], \
         and a table applies whole (a new [{kind}.{name}] would need every key of its own, \
         {needs}). Set the default instead: --set defaults.{kind}.{key}={value} (every {kind} \
         that takes the defaults), or declare [{kind}.{name}] in the scene with all its keys"
    ))
}

#[cfg(test)]
mod tests {
    use super::Glob;

    #[test]
    fn globs_match_whole_names() {
        let g = Glob::new("brick*");
        assert!(g.matches("brick") && g.matches("brick_12") && !g.matches("abrick"));
        assert!(Glob::new("*").matches("") && Glob::new("*").matches("anything"));
        assert!(
            Glob::new("b?ick_*2").matches("brick_12") && !Glob::new("b?ick_*2").matches("brick_13")
        );
        assert!(Glob::new("*a*b*").matches("xxaxxbxx") && !Glob::new("*a*b*").matches("xxbxxaxx"));
        assert!(!Glob::new("v?").matches("v") && Glob::new("v?").matches("v1"));
        assert_eq!(Glob::new("brick_1*").specificity(), 7);
        assert_eq!(Glob::new("*").specificity(), 0);
        assert!(Glob::is_pattern("a*") && Glob::is_pattern("a?") && !Glob::is_pattern("a_1"));
    }
}
