//! The curves of the mesh sorted by their use (docs/scene.md): the named groups, each body's
//! surfaces and boundary curves, which curves bodies share, which Physical Curves are
//! interfaces (declared, `between = [A, B]`) and which are boundary parts.
//!
//! Place in the flow: `model::build` → **`curves`** → `body`, `interface`.

use super::*;
/// The mesh's physical groups, looked up by dimension and name, with the files that input
/// errors name.
pub(super) struct Groups<'a> {
    pub(super) mesh: &'a Mesh,
    pub(super) mfile: &'a Path,
    pub(super) sfile: &'a Path,
}

impl<'a> Groups<'a> {
    /// The names of the physical groups of dimension `dim`.
    pub(super) fn named(&self, dim: i32) -> Vec<&'a str> {
        self.mesh
            .physical_names
            .iter()
            .filter(|p| p.dim == dim)
            .map(|p| p.name.as_str())
            .collect()
    }

    /// The tag of the physical group `name` of dimension `dim`.
    pub(super) fn tag(&self, dim: i32, name: &str) -> Option<i32> {
        self.mesh
            .physical_names
            .iter()
            .find(|p| p.dim == dim && p.name == name)
            .map(|p| p.tag)
    }

    /// The error for a scene table `[key.name]` whose group is not a physical group of
    /// dimension `want`: one of another kind, or none of that name.
    pub(super) fn wrong_kind(&self, key: &str, name: &str, want: i32) -> Error {
        let (sfile, mfile) = (self.sfile, self.mfile);
        let kinds = [
            "Physical Point",
            "Physical Curve",
            "Physical Surface",
            "Physical Volume",
        ];
        let found = self
            .mesh
            .physical_names
            .iter()
            .find(|p| p.name == name)
            .map(|p| kinds.get(p.dim as usize).copied().unwrap_or("group"));
        let want_s = kinds[want as usize];
        match found {
            Some(kind) => Error::input(
                sfile,
                format!(
                    "[{key}.{name}] names a {kind} of {}, but a {key} must be a {want_s}",
                    mfile.display()
                ),
            ),
            None => Error::input(
                sfile,
                format!(
                    "[{key}.{name}]: {} has no {want_s} named \"{name}\"{}; its {want_s}s are: {}",
                    mfile.display(),
                    did_you_mean(name, self.named(want).into_iter()),
                    list_or_none(&self.named(want))
                ),
            ),
        }
    }
}

/// Bodies: the surface entities of each body's Physical Surface, in scene order. Every
/// Physical Surface must be a body of the scene, and no surface may belong to two bodies.
pub(super) fn body_surfaces(scene: &Scene, groups: &Groups) -> Result<Vec<Vec<i32>>> {
    let (mesh, mfile, sfile) = (groups.mesh, groups.mfile, groups.sfile);
    let mut surface_owner: HashMap<i32, usize> = HashMap::new();
    let mut body_surfaces: Vec<Vec<i32>> = Vec::new();
    for (bi, spec) in scene.bodies.iter().enumerate() {
        let tag = groups
            .tag(2, &spec.name)
            .ok_or_else(|| groups.wrong_kind("body", &spec.name, 2))?;
        let surfaces: Vec<i32> = mesh
            .surfaces
            .values()
            .filter(|s| s.physical_tags.contains(&tag))
            .map(|s| s.tag)
            .collect();
        if surfaces.is_empty() {
            return Err(Error::input(
                mfile,
                format!(
                    "Physical Surface \"{}\" holds no surface entity: mesh the .geo again",
                    spec.name
                ),
            ));
        }
        for &s in &surfaces {
            if let Some(&other) = surface_owner.get(&s) {
                return Err(Error::input(
                    mfile,
                    format!(
                        "surface {s} belongs to both Physical Surfaces \"{}\" and \"{}\": bodies \
                         overlap; put each surface in one body only",
                        scene.bodies[other].name, spec.name
                    ),
                ));
            }
            surface_owner.insert(s, bi);
        }
        body_surfaces.push(surfaces);
    }
    for p in mesh.physical_names.iter().filter(|p| p.dim == 2) {
        if scene.body(&p.name).is_none() {
            return Err(Error::input(
                sfile,
                format!(
                    "{} has a Physical Surface \"{}\" but the scene has no [body.{}]: add it with \
                     its young and poisson (or a [body.\"PATTERN*\"] or [defaults.body] table \
                     that applies to it){}",
                    mfile.display(),
                    p.name,
                    p.name,
                    did_you_mean(&p.name, scene.bodies.iter().map(|b| b.name.as_str()))
                        .replace("did you mean", "or rename")
                ),
            ));
        }
    }
    Ok(body_surfaces)
}

/// The boundary curves of each body: the bounding curves of its surfaces, less those that
/// bound two surfaces of the same body (internal to it).
pub(super) fn boundary_curves(
    scene: &Scene,
    mesh: &Mesh,
    body_surfaces: &[Vec<i32>],
    mfile: &Path,
) -> Result<Vec<BTreeSet<i32>>> {
    let mut body_curves: Vec<BTreeSet<i32>> = Vec::new();
    for (bi, surfaces) in body_surfaces.iter().enumerate() {
        let mut count: BTreeMap<i32, usize> = BTreeMap::new();
        for s in surfaces {
            let ent = &mesh.surfaces[s];
            if ent.bounding.is_empty() {
                return Err(Error::input(
                    mfile,
                    format!(
                        "surface {s} of body \"{}\" has no bounding curves in $Entities",
                        scene.bodies[bi].name
                    ),
                ));
            }
            for c in &ent.bounding {
                let tag = c.checked_abs().filter(|t| *t > 0).ok_or_else(|| {
                    Error::input(
                        mfile,
                        format!("surface {s} lists an invalid bounding curve tag {c} in $Entities"),
                    )
                })?;
                *count.entry(tag).or_default() += 1;
            }
        }
        // A curve bounding two surfaces of the same body is internal to it.
        body_curves.push(
            count
                .into_iter()
                .filter(|(_, n)| n % 2 == 1)
                .map(|(c, _)| c)
                .collect(),
        );
    }
    Ok(body_curves)
}

/// The bodies each boundary curve bounds (two for a shared curve), in body order.
pub(super) fn curve_bodies(body_curves: &[BTreeSet<i32>]) -> BTreeMap<i32, Vec<usize>> {
    let mut curve_bodies: BTreeMap<i32, Vec<usize>> = BTreeMap::new();
    for (bi, curves) in body_curves.iter().enumerate() {
        for &c in curves {
            curve_bodies.entry(c).or_default().push(bi);
        }
    }
    curve_bodies
}

/// The Physical Curves that hold a curve shared by two or more bodies: the groups that
/// interface tables from globs and defaults may apply to.
pub(super) fn shared_groups<'m>(
    mesh: &'m Mesh,
    curve_bodies: &BTreeMap<i32, Vec<usize>>,
) -> BTreeSet<&'m str> {
    mesh.physical_names
        .iter()
        .filter(|p| p.dim == 1)
        .filter(|p| {
            mesh.curves.values().any(|c| {
                c.physical_tags.contains(&p.tag)
                    && curve_bodies.get(&c.tag).is_some_and(|b| b.len() >= 2)
            })
        })
        .map(|p| p.name.as_str())
        .collect()
}

/// What the scene makes of the mesh's Physical Curves.
pub(super) struct CurveUses {
    /// The boundary parts: the listed ones and the traction-free rest.
    pub(super) parts: Vec<Part>,
    /// Each interface's table (named after its pair of bodies when the curve is split), the
    /// Physical Curve it comes from, and its curves.
    pub(super) interfaces: Vec<(InterfaceSpec, String, BTreeSet<i32>)>,
    /// Group tag → use.
    pub(super) uses: HashMap<i32, CurveUse>,
    /// The Physical Curves that lie on no body boundary.
    pub(super) unused: Vec<String>,
}

/// Checks that every `[interface]` names a Physical Curve, or with `between = [A, B]` two
/// of them (and is not one itself); adds the `between` interfaces to `found` (their curves:
/// those of A and B) and returns each side's group name → its interface.
pub(super) fn between_interfaces<'s>(
    scene: &'s Scene,
    groups: &Groups,
    found: &mut Vec<(InterfaceSpec, String, BTreeSet<i32>)>,
) -> Result<HashMap<&'s str, usize>> {
    let (mesh, mfile, sfile) = (groups.mesh, groups.mfile, groups.sfile);
    let mut between_of = HashMap::new();
    for i in &scene.interfaces {
        let Some(sides) = &i.between else {
            if groups.tag(1, &i.name).is_none() {
                return Err(groups.wrong_kind("interface", &i.name, 1));
            }
            continue;
        };
        if groups.tag(1, &i.name).is_some() {
            return Err(Error::input(
                sfile,
                format!(
                    "[interface.{0}] gives `between`, but {1} also has a Physical Curve named \
                     \"{0}\": an interface is a Physical Curve or the two curves of `between`; \
                     rename one",
                    i.name,
                    mfile.display()
                ),
            ));
        }
        let mut curves = BTreeSet::new();
        for g in sides {
            let tag = groups.tag(1, g).ok_or_else(|| {
                Error::input(
                    sfile,
                    format!(
                        "`interface.{}.between` names \"{g}\", but {} has no Physical Curve \
                         named so{}; its Physical Curves are: {}",
                        i.name,
                        mfile.display(),
                        did_you_mean(g, groups.named(1).into_iter()),
                        list_or_none(&groups.named(1))
                    ),
                )
            })?;
            curves.extend(
                mesh.curves
                    .values()
                    .filter(|c| c.physical_tags.contains(&tag))
                    .map(|c| c.tag),
            );
            between_of.insert(g.as_str(), found.len());
        }
        found.push((i.clone(), i.name.clone(), curves));
    }
    Ok(between_of)
}

/// What each physical curve is: a boundary part (listed, or traction-free), an interface, or
/// one interface per pair of bodies it joins. A curve shared by two bodies must be an
/// interface of the scene.
pub(super) fn classify_curves(
    scene: &Scene,
    groups: &Groups,
    curve_bodies: &BTreeMap<i32, Vec<usize>>,
) -> Result<CurveUses> {
    let (mesh, mfile, sfile) = (groups.mesh, groups.mfile, groups.sfile);
    for b in &scene.boundaries {
        if groups.tag(1, &b.name).is_none() {
            return Err(groups.wrong_kind("boundary", &b.name, 1));
        }
    }
    let mut parts: Vec<Part> = Vec::new();
    let mut interfaces_found: Vec<(InterfaceSpec, String, BTreeSet<i32>)> = Vec::new();
    let between_of = between_interfaces(scene, groups, &mut interfaces_found)?;
    let mut uses: HashMap<i32, CurveUse> = HashMap::new();
    let mut unused_curves = Vec::new();
    for p in mesh.physical_names.iter().filter(|p| p.dim == 1) {
        let curves: Vec<i32> = mesh
            .curves
            .values()
            .filter(|c| c.physical_tags.contains(&p.tag))
            .map(|c| c.tag)
            .collect();
        let on_bodies: BTreeSet<usize> = curves
            .iter()
            .filter_map(|c| curve_bodies.get(c))
            .flatten()
            .copied()
            .collect();
        let between = between_of.get(p.name.as_str()).copied();
        if on_bodies.is_empty() {
            if scene.boundary(&p.name).is_some()
                || scene.interface(&p.name).is_some()
                || between.is_some()
            {
                return Err(Error::input(
                    sfile,
                    format!(
                        "Physical Curve \"{}\" lies on no body boundary in {}: check the curves \
                         it holds",
                        p.name,
                        mfile.display()
                    ),
                ));
            }
            unused_curves.push(p.name.clone());
            continue;
        }
        if let Some(k) = between {
            uses.insert(p.tag, CurveUse::Interface(k));
            continue;
        }
        let shared: Vec<i32> = curves
            .iter()
            .copied()
            .filter(|c| curve_bodies.get(c).is_some_and(|b| b.len() >= 2))
            .collect();
        if let Some(spec) = scene.interface(&p.name) {
            let by_pair = pairs_of_bodies(&p.name, &curves, curve_bodies, scene, sfile)?;
            if by_pair.len() <= 1 {
                uses.insert(p.tag, CurveUse::Interface(interfaces_found.len()));
                interfaces_found.push((
                    spec.clone(),
                    p.name.clone(),
                    curves.iter().copied().collect(),
                ));
            } else {
                let mut split = BTreeMap::new();
                for ((a, b), set) in by_pair {
                    split.insert((a, b), interfaces_found.len());
                    let name = split_name(&p.name, &scene.bodies[a].name, &scene.bodies[b].name);
                    interfaces_found.push((
                        InterfaceSpec {
                            name,
                            ..spec.clone()
                        },
                        p.name.clone(),
                        set,
                    ));
                }
                uses.insert(p.tag, CurveUse::Split(split));
            }
        } else {
            if let Some(&c) = shared.first() {
                let names: Vec<&str> = curve_bodies[&c]
                    .iter()
                    .map(|&b| scene.bodies[b].name.as_str())
                    .collect();
                let how = if scene.boundary(&p.name).is_some() {
                    format!("[boundary.{}] cannot apply to it", p.name)
                } else {
                    "the scene does not list it".to_string()
                };
                return Err(Error::input(
                    sfile,
                    format!(
                        "Physical Curve \"{}\" is shared by bodies {} (curve {c}) and {how}: \
                         declare [interface.{}] with model = \"bonded\" or \"unilateral\" (or \
                         an [interface.\"PATTERN*\"] or [defaults.interface] table)",
                        p.name,
                        names.join(" and "),
                        p.name
                    ),
                ));
            }
            let (spec, listed) = match scene.boundary(&p.name) {
                Some(s) => (s.clone(), true),
                None => (BoundarySpec::traction_free(&p.name), false),
            };
            uses.insert(p.tag, CurveUse::Boundary(parts.len()));
            parts.push(Part {
                spec,
                listed,
                elements: BTreeMap::new(),
                length: 0.0,
            });
        }
    }
    Ok(CurveUses {
        parts,
        interfaces: interfaces_found,
        uses,
        unused: unused_curves,
    })
}

/// The role of each boundary curve (through its physical group). Groups the scene uses win
/// over unlisted (traction-free) ones; a curve in no named group, or in two groups the scene
/// uses, is an input error.
pub(super) fn curve_roles(
    scene: &Scene,
    groups: &Groups,
    body_curves: &[BTreeSet<i32>],
    curve_bodies: &BTreeMap<i32, Vec<usize>>,
    found: &CurveUses,
) -> Result<HashMap<i32, Role>> {
    let (mesh, mfile, sfile) = (groups.mesh, groups.mfile, groups.sfile);
    let (parts, uses) = (&found.parts, &found.uses);
    let mut curve_role: HashMap<i32, Role> = HashMap::new();
    for (bi, curves) in body_curves.iter().enumerate() {
        for &c in curves {
            let ent = match mesh.curves.get(&c) {
                Some(e) => e,
                None => {
                    return Err(Error::input(
                        mfile,
                        format!(
                            "surface of body \"{}\" is bounded by curve {c}, which $Entities does \
                             not define",
                            scene.bodies[bi].name
                        ),
                    ))
                }
            };
            let roles: Vec<(Role, String)> = ent
                .physical_tags
                .iter()
                .filter_map(|t| {
                    let name = mesh.physical_name(1, *t)?.to_string();
                    match uses.get(t)? {
                        CurveUse::Boundary(pi) => Some((Role::Boundary(*pi), name)),
                        CurveUse::Interface(k) => Some((Role::Interface(*k), name)),
                        CurveUse::Split(by_pair) => {
                            let on = curve_bodies.get(&c)?;
                            let k = by_pair.get(&(on[0].min(on[1]), on[0].max(on[1])))?;
                            Some((Role::Interface(*k), name))
                        }
                    }
                })
                .collect();
            // Groups the scene uses win over unlisted (traction-free) ones.
            let used: Vec<&(Role, String)> = roles
                .iter()
                .filter(|(r, _)| match r {
                    Role::Boundary(pi) => parts[*pi].listed,
                    Role::Interface(_) => true,
                })
                .collect();
            let listed: Vec<&(Role, String)> = if used.is_empty() {
                roles.iter().take(1).collect()
            } else {
                used
            };
            match listed.as_slice() {
                [] => {
                    return Err(Error::input(
                        mfile,
                        format!(
                            "curve {c} bounds body \"{}\" but belongs to no named Physical \
                             Curve: {OPEN_LOOP_HINT}",
                            scene.bodies[bi].name
                        ),
                    ))
                }
                [(role, _)] => {
                    curve_role.insert(c, *role);
                }
                many => {
                    let names: Vec<&str> = many.iter().map(|(_, n)| n.as_str()).collect();
                    return Err(Error::input(
                        sfile,
                        format!(
                            "curve {c} belongs to Physical Curves {} which the scene all uses: \
                             a curve may carry one condition; split the groups",
                            names.join(", ")
                        ),
                    ));
                }
            }
        }
    }
    Ok(curve_role)
}
