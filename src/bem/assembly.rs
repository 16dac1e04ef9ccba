//! Per-body Galerkin system of the SGBEM in residual-W form ([paper eq. 10],
//! docs/formulation.md §3).
//!
//! Place in the flow: `model` + `galerkin` → **`assembly`** → `condensation`. For one body it
//! numbers the unknowns
//!
//! ```text
//!   X  = [F1; −U2]   traction on Γ1 (per element end and constrained direction),
//!                    displacement of free nodes (per unknown direction)
//!   X0 = [F0; −U0]   interface traction hats and interface displacements, in the local
//!                    pair frame (s_j, n_j) of docs/formulation.md §5.4
//! ```
//!
//! and assembles the symmetric matrix `G = [[A, A0], [A0ᵀ, A00]]` and the load `[L̂; L̂0]` of
//!
//! ```text
//!   0  = A X + A0 X0 + L̂        (W rows on Γ1, P rows of free nodes)
//!   Z0 = A0ᵀ X + A00 X0 + L̂0    (Z0 = [W0; P0], the interface outputs)
//! ```
//!
//! Blocks (docs/formulation.md §3.1–§3.2): (W, F) = V; (W, −U) = K + ½M on every W row (the
//! residual form, which keeps every condensed operator symmetric); (P, −U) = −D;
//! (P, F) = (W, −U)ᵀ. Known data go to the load: `V t̄ − (K + ½M) ū` on W rows,
//! `(Kᵀ − ½Mᵀ) t̄ + D ū` on P rows, plus the body-force terms W^b, P^b (docs/formulation.md §4).
//!
//! Degenerate scale (docs/formulation.md §8.4): each body is integrated in the coordinates of
//! its [`Scaling`], taken relative to one of its nodes (exact far from the origin), centred on
//! the centroid of its nodes and divided by twice their largest distance from it, so that it
//! fits in a disk of radius ½, and the blocks are brought back to physical units (V·L², K·L,
//! D·1). This uses the single-layer kernel up to an additive constant, an equivalent
//! formulation that is uniquely solvable.
//!
//! Assembly runs in parallel over test elements (rayon): each element yields the partial
//! rows of the unknowns supported on it, which are then added in order.

// Index loops mirror the block formulas and read better than iterators here.
#![allow(clippy::needless_range_loop)]
use faer::Mat;
use rayon::prelude::*;

use crate::bem::galerkin::{
    body_force_loads, element_mass, pair_blocks, ElementRef, PairBlocks, Segment,
};
use crate::bem::kernels::{boundary_area, Material};
use crate::bem::quadrature::QuadratureSettings;
use crate::error::{Error, Result};
use crate::input::model::{Body, DofClass, Model, Role};
use crate::input::scene::{Condition, Frame, Plane};
use crate::vec2::dot;

/// What one unknown of a body is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Unknown {
    /// Traction component on a Γ1 element end (direction `dir`, global unit vector).
    Traction1 {
        elem: usize,
        end: usize,
        dir: [f64; 2],
    },
    /// Interface traction hat of pair `pair` of interface `iface`, local component `comp`
    /// (0 = s, 1 = n).
    Traction0 {
        iface: usize,
        pair: usize,
        comp: usize,
        dir: [f64; 2],
    },
    /// Amplitude of a traction distributed as a rigid motion over a whole loop (one mode
    /// `[a, b, ω]`: `(a − ω(y−y_c)/L, b + ω(x−x_c)/L)`, with `(x_c, L)` the loop's
    /// [`Scaling`], which keeps `x − x_c` exact far from the origin). Added where a loop's
    /// rigid motions are not fixed by known or interface displacements (a hole with tractions
    /// only): the hypersingular rows cannot see such a motion, so the displacement equation
    /// tested with the mode is added with it. Its amplitude vanishes with the discretisation
    /// error.
    LoopMode {
        loop_index: usize,
        mode: [f64; 3],
        about: Scaling,
    },
    /// Displacement component of node `node` along `dir`; on an interface, its pair and
    /// local component.
    Displacement {
        node: usize,
        dir: [f64; 2],
        on: Option<(usize, usize, usize)>,
    },
}

impl Unknown {
    pub fn is_traction(&self) -> bool {
        !matches!(self, Unknown::Displacement { .. })
    }

    /// The value at x of a [`Unknown::LoopMode`] distribution ([0, 0] for other unknowns).
    pub(crate) fn loop_mode_value(&self, x: [f64; 2]) -> [f64; 2] {
        match *self {
            Unknown::LoopMode { mode, about, .. } => {
                let r = about.centred(x);
                [
                    mode[0] - mode[2] * r[1] / about.length,
                    mode[1] + mode[2] * r[0] / about.length,
                ]
            }
            _ => [0.0, 0.0],
        }
    }
}

/// The rigid modes of each loop that its known and interface displacements leave free.
fn loop_modes(body: &Body) -> Vec<Unknown> {
    let mut out = Vec::new();
    for (li, l) in body.loops.iter().enumerate() {
        let nodes: Vec<usize> = l
            .elements
            .iter()
            .map(|&e| body.elements[e].nodes[0])
            .collect();
        let points: Vec<[f64; 2]> = nodes.iter().map(|&k| body.nodes[k]).collect();
        let about = Scaling::of(&points);
        let mut basis: Vec<[f64; 3]> = Vec::new();
        let add = |v: [f64; 3], basis: &mut Vec<[f64; 3]>| -> Option<[f64; 3]> {
            let mut r = v;
            for q in basis.iter() {
                let p = r[0] * q[0] + r[1] * q[1] + r[2] * q[2];
                for i in 0..3 {
                    r[i] -= p * q[i];
                }
            }
            let len = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
            if len > 1e-6 {
                let u = [r[0] / len, r[1] / len, r[2] / len];
                basis.push(u);
                Some(u)
            } else {
                None
            }
        };
        for &k in &nodes {
            let d = body.dofs[k];
            let r = about.centred(body.nodes[k]);
            for c in 0..2 {
                if d.class[c] == DofClass::Free {
                    continue;
                }
                let dir = d.frame[c];
                let row = [
                    dir[0],
                    dir[1],
                    (-r[1] * dir[0] + r[0] * dir[1]) / about.length,
                ];
                add(row, &mut basis);
            }
        }
        for e in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] {
            if basis.len() == 3 {
                break;
            }
            if let Some(mode) = add(e, &mut basis) {
                out.push(Unknown::LoopMode {
                    loop_index: li,
                    mode,
                    about,
                });
            }
        }
    }
    out
}

/// One unknown's shape function on one element: the end whose shape function it uses and
/// its direction.
#[derive(Debug, Clone, Copy)]
struct Entry {
    index: usize,
    end: usize,
    dir: [f64; 2],
    traction: bool,
}

/// The assembled system of one body.
pub struct BodySystem {
    /// Unknowns: X (first `n_x`) then X0.
    pub unknowns: Vec<Unknown>,
    pub n_x: usize,
    /// `[[A, A0], [A0ᵀ, A00]]`.
    pub g: Mat<f64>,
    /// `[L̂; L̂0]`.
    pub load: Vec<f64>,
    /// Known displacement of each node (the known components only, global x, y).
    pub known_u: Vec<[f64; 2]>,
    /// Known traction at each element end (global x, y).
    pub known_t: Vec<[[f64; 2]; 2]>,
    /// Largest relative asymmetry of G (diagnostic; zero up to roundoff in the usual case).
    pub asymmetry: f64,
    pub material: Material,
    /// The scaled coordinates used for integration.
    pub scaling: Scaling,
    /// The known displacement components (node, global direction): the nodes held by
    /// displacement conditions.
    pub held: Vec<(usize, [f64; 2])>,
    /// Their hypersingular rows, the equations their displacement unknowns would have:
    /// `R = held_rows · [X; X0] + factor · held_load` is the Galerkin-weighted reaction
    /// `∫ψ_n t·d` of each held component, the nodal force that the discrete problem balances
    /// as exactly as the interfaces' nodal forces (`post::equilibrium`).
    pub held_rows: Mat<f64>,
    pub held_load: Vec<f64>,
}

impl BodySystem {
    pub fn n(&self) -> usize {
        self.unknowns.len()
    }
    pub fn n_x0(&self) -> usize {
        self.unknowns.len() - self.n_x
    }
}

fn quad(d: [f64; 2], m: &[[f64; 2]; 2], e: [f64; 2]) -> f64 {
    d[0] * (m[0][0] * e[0] + m[0][1] * e[1]) + d[1] * (m[1][0] * e[0] + m[1][1] * e[1])
}

/// The material of a body in the scene's plane.
pub fn material(body: &Body, plane: Plane) -> Material {
    Material::new(body.young, body.poisson, plane == Plane::Stress)
}

/// Numbers the unknowns of body `bi`, evaluates its known data, and assembles its system.
pub fn assemble_body(
    model: &Model,
    bi: usize,
    plane: Plane,
    settings: &QuadratureSettings,
    load_factor: f64,
    scene_file: &std::path::Path,
) -> Result<BodySystem> {
    let s = scaling(&model.bodies[bi]);
    assemble_body_scaled(model, bi, plane, settings, load_factor, scene_file, s)
}

/// [`assemble_body`] with the integration coordinates given (a [`Scaling`], or `(c, L)` for
/// `(x − c)/L`); the degenerate-scale test uses it to integrate a body at its physical size.
pub fn assemble_body_scaled(
    model: &Model,
    bi: usize,
    plane: Plane,
    settings: &QuadratureSettings,
    load_factor: f64,
    scene_file: &std::path::Path,
    scaling: impl Into<Scaling>,
) -> Result<BodySystem> {
    let scaling: Scaling = scaling.into();
    let length = scaling.length;
    let body = &model.bodies[bi];
    let mat = material(body, plane);
    let ne = body.elements.len();

    let node_pairs = node_pairs(model, bi);
    let KnownData {
        traction: known_t,
        constraints,
        mut unknowns,
    } = known_data(model, body, load_factor);
    let known_u = known_displacements(body, &constraints, scene_file)?;
    let n_x = number_unknowns(model, bi, &node_pairs, &mut unknowns, scene_file)?;
    let node_elems = node_elements(body);
    let mut entries = element_entries(model, bi, &unknowns, &node_elems);
    let n_sys = unknowns.len();
    let held = held_components(body, n_sys, &mut entries, &node_elems);

    // --- Scaled geometry ----------------------------------------------------------------------
    let scaled = |p: [f64; 2]| scaling.scaled(p);
    let elems: Vec<ElementRef> = body
        .elements
        .iter()
        .map(|e| {
            ElementRef::new(
                Segment::new(
                    scaled(body.nodes[e.nodes[0]]),
                    scaled(body.nodes[e.nodes[1]]),
                ),
                e.nodes,
            )
        })
        .collect();
    let boundary: Vec<Segment> = elems.iter().map(|e| e.seg).collect();
    let area = boundary_area(&boundary);
    let body_force = body
        .body_force
        .filter(|b| *b != [0.0, 0.0])
        .map(|b| [load_factor * b[0], load_factor * b[1]]);

    // --- Pair loop ------------------------------------------------------------------------------
    let n = n_sys + held.len();
    let pair_loop = PairLoop {
        body,
        mat: &mat,
        settings,
        elems: &elems,
        boundary: &boundary,
        area,
        entries: &entries,
        known_t: &known_t,
        known_u: &known_u,
        body_force,
        length,
        n,
    };
    let (mut g, mut load) = pair_loop.assemble(ne);
    // (P, F) = (W, −U)ᵀ, the held rows included.
    let is_t: Vec<bool> = unknowns
        .iter()
        .map(|u| u.is_traction())
        .chain(std::iter::repeat_n(false, held.len()))
        .collect();
    for p in 0..n {
        if is_t[p] {
            continue;
        }
        for f in 0..n {
            if is_t[f] {
                g[(p, f)] = g[(f, p)];
            }
        }
    }
    // The held rows apart; the known displacements are in the loads of every row already,
    // so their columns are dropped.
    let nh = held.len();
    let held_rows = g.as_ref().submatrix(n_sys, 0, nh, n_sys).to_owned();
    let held_load = load[n_sys..].to_vec();
    let g = g.as_ref().submatrix(0, 0, n_sys, n_sys).to_owned();
    load.truncate(n_sys);
    let asymmetry = relative_asymmetry(&g);

    Ok(BodySystem {
        unknowns,
        n_x,
        g,
        load,
        known_u,
        known_t,
        asymmetry,
        material: mat,
        scaling,
        held,
        held_rows,
        held_load,
    })
}

/// Interface membership of the nodes of body `bi`: (iface, pair), several at a junction.
///
/// A node where this body meets two or more other bodies (a junction: the corner of a brick
/// at a T-junction of head and bed joints) belongs to a pair of each interface. Its
/// displacement is one unknown vector (in the frame of its first pair); its traction has one
/// set of hats per interface, on that interface's elements.
fn node_pairs(model: &Model, bi: usize) -> Vec<Vec<(usize, usize)>> {
    let nn = model.bodies[bi].nodes.len();
    let mut node_pairs: Vec<Vec<(usize, usize)>> = vec![Vec::new(); nn];
    for (k, it) in model.interfaces.iter().enumerate() {
        let side_a = it.body_a == bi;
        if !side_a && it.body_b != bi {
            continue;
        }
        for j in 0..it.point_count(side_a) {
            node_pairs[it.point(side_a, j).0].push((k, j));
        }
    }
    node_pairs
}

/// The known data of a body's boundary parts.
struct KnownData {
    /// Known traction at each element end (global x, y).
    traction: Vec<[[f64; 2]; 2]>,
    /// The displacement constraints (direction, value) at each node.
    constraints: Vec<Vec<([f64; 2], f64)>>,
    /// The traction unknowns (F1) on the elements of displacement conditions.
    unknowns: Vec<Unknown>,
}

/// Known data: tractions per element end, displacement constraints per node, and the
/// traction unknowns where a displacement is prescribed.
fn known_data(model: &Model, body: &Body, load_factor: f64) -> KnownData {
    let ne = body.elements.len();
    let nn = body.nodes.len();
    let mut known_t = vec![[[0.0; 2]; 2]; ne];
    let mut constraints: Vec<Vec<([f64; 2], f64)>> = vec![Vec::new(); nn];
    let mut unknowns: Vec<Unknown> = Vec::new();
    for (ei, e) in body.elements.iter().enumerate() {
        let Role::Boundary(pi) = e.role else { continue };
        let spec = &model.parts[pi].spec;
        for (c, cond) in spec.components.iter().enumerate() {
            let dir = match (spec.frame, c) {
                (Frame::Global, 0) => [1.0, 0.0],
                (Frame::Global, _) => [0.0, 1.0],
                (Frame::Local, 0) => e.tangent,
                (Frame::Local, _) => e.normal,
            };
            match cond {
                Condition::Traction(v) => {
                    for a in 0..2 {
                        let val = load_factor * v.eval(body.nodes[e.nodes[a]], model.time);
                        known_t[ei][a][0] += val * dir[0];
                        known_t[ei][a][1] += val * dir[1];
                    }
                }
                Condition::Displacement(v) => {
                    for a in 0..2 {
                        unknowns.push(Unknown::Traction1 {
                            elem: ei,
                            end: a,
                            dir,
                        });
                        let n = e.nodes[a];
                        constraints[n].push((dir, load_factor * v.eval(body.nodes[n], model.time)));
                    }
                }
            }
        }
    }
    KnownData {
        traction: known_t,
        constraints,
        unknowns,
    }
}

/// Appends the displacement unknowns to the F1 unknowns: U2 in X, then the loop modes; then
/// X0, the interface traction hats F0 and the interface displacements U0 (pair frame).
/// Returns the size of X.
fn number_unknowns(
    model: &Model,
    bi: usize,
    node_pairs: &[Vec<(usize, usize)>],
    unknowns: &mut Vec<Unknown>,
    scene_file: &std::path::Path,
) -> Result<usize> {
    let body = &model.bodies[bi];
    let mut u0: Vec<Unknown> = Vec::new();
    for (n, d) in body.dofs.iter().enumerate() {
        for k in 0..2 {
            match d.class[k] {
                DofClass::Known => {}
                DofClass::Free => unknowns.push(Unknown::Displacement {
                    node: n,
                    dir: d.frame[k],
                    on: None,
                }),
                DofClass::Interface => {
                    u0.push(interface_unknown(model, bi, node_pairs, n, k, scene_file)?);
                }
            }
        }
    }
    unknowns.extend(loop_modes(body));
    let n_x = unknowns.len();
    // F0: interface traction hats, both local components at every pair node of this body.
    let mut pairs_here: Vec<(usize, usize, usize)> = node_pairs
        .iter()
        .enumerate()
        .flat_map(|(n, list)| list.iter().map(move |&(k, j)| (k, j, n)))
        .collect();
    pairs_here.sort_unstable();
    for &(k, j, _) in &pairs_here {
        let it = &model.interfaces[k];
        for (comp, dir) in it.point(it.body_a == bi, j).1.into_iter().enumerate() {
            unknowns.push(Unknown::Traction0 {
                iface: k,
                pair: j,
                comp,
                dir,
            });
        }
    }
    unknowns.extend(u0);
    Ok(n_x)
}

/// The interface displacement unknown (U0) of component `k` of node `n`, in the frame of
/// one of its pairs.
fn interface_unknown(
    model: &Model,
    bi: usize,
    node_pairs: &[Vec<(usize, usize)>],
    n: usize,
    k: usize,
    scene_file: &std::path::Path,
) -> Result<Unknown> {
    let body = &model.bodies[bi];
    let d = &body.dofs[n];
    let Some(&(iface, pair)) = node_pairs[n].first() else {
        return Err(Error::input(
            scene_file,
            format!(
                "node {} of body \"{}\" is marked as an interface node but belongs to no \
                 interface pair",
                fmt_point(body.nodes[n]),
                body.name
            ),
        ));
    };
    // The unknown direction must be one of a pair's local directions (at a junction, of any
    // of its pairs; the contact problem projects it onto the frames of the others).
    // The frame of point jj of interface kk on this body's side.
    let frame_of = |kk: usize, jj: usize| {
        let it = &model.interfaces[kk];
        it.point(it.body_a == bi, jj).1
    };
    let found = if d.class == [DofClass::Interface; 2] {
        Some((iface, pair, k, frame_of(iface, pair)[k]))
    } else {
        node_pairs[n].iter().find_map(|&(kk, jj)| {
            let frame = frame_of(kk, jj);
            (0..2)
                .find(|&c| dot(d.frame[k], frame[c]).abs() > 1.0 - 1e-9)
                .map(|c| (kk, jj, c, frame[c]))
        })
    };
    let Some((iface, pair, comp, dir)) = found else {
        return Err(Error::input(
            scene_file,
            format!(
                "interface \"{}\" at {}: a displacement condition there prescribes a direction \
                 oblique to the interface; prescribe it along the interface or its normal",
                model.interfaces[iface].spec.name,
                fmt_point(body.nodes[n])
            ),
        ));
    };
    Ok(Unknown::Displacement {
        node: n,
        dir,
        on: Some((iface, pair, comp)),
    })
}

/// The elements at each node of a body, as (element, end).
fn node_elements(body: &Body) -> Vec<Vec<(usize, usize)>> {
    let mut node_elems: Vec<Vec<(usize, usize)>> = vec![Vec::new(); body.nodes.len()];
    for (ei, e) in body.elements.iter().enumerate() {
        node_elems[e.nodes[0]].push((ei, 0));
        node_elems[e.nodes[1]].push((ei, 1));
    }
    node_elems
}

/// Entries per element: the unknowns whose shape functions live on each element of body
/// `bi`.
fn element_entries(
    model: &Model,
    bi: usize,
    unknowns: &[Unknown],
    node_elems: &[Vec<(usize, usize)>],
) -> Vec<Vec<Entry>> {
    let body = &model.bodies[bi];
    let mut entries: Vec<Vec<Entry>> = vec![Vec::new(); body.elements.len()];
    for (index, u) in unknowns.iter().enumerate() {
        match *u {
            Unknown::LoopMode { loop_index, .. } => {
                for &ei in &body.loops[loop_index].elements {
                    for end in 0..2 {
                        let dir = u.loop_mode_value(body.nodes[body.elements[ei].nodes[end]]);
                        entries[ei].push(Entry {
                            index,
                            end,
                            dir,
                            traction: true,
                        });
                    }
                }
            }
            Unknown::Traction1 { elem, end, dir } => entries[elem].push(Entry {
                index,
                end,
                dir,
                traction: true,
            }),
            Unknown::Displacement { node, dir, .. } => {
                for &(ei, end) in &node_elems[node] {
                    entries[ei].push(Entry {
                        index,
                        end,
                        dir,
                        traction: false,
                    });
                }
            }
            Unknown::Traction0 {
                iface, pair, dir, ..
            } => {
                let it = &model.interfaces[iface];
                let node = it.point(it.body_a == bi, pair).0;
                for &(ei, end) in &node_elems[node] {
                    if body.elements[ei].role == Role::Interface(iface) {
                        entries[ei].push(Entry {
                            index,
                            end,
                            dir,
                            traction: true,
                        });
                    }
                }
            }
        }
    }
    entries
}

/// Held components: rows only (index `n_sys + q`), never unknowns. Adds their entries and
/// returns them as (node, direction).
fn held_components(
    body: &Body,
    n_sys: usize,
    entries: &mut [Vec<Entry>],
    node_elems: &[Vec<(usize, usize)>],
) -> Vec<(usize, [f64; 2])> {
    let mut held: Vec<(usize, [f64; 2])> = Vec::new();
    for (node, d) in body.dofs.iter().enumerate() {
        for k in 0..2 {
            if d.class[k] == DofClass::Known {
                let q = n_sys + held.len();
                held.push((node, d.frame[k]));
                for &(ei, end) in &node_elems[node] {
                    entries[ei].push(Entry {
                        index: q,
                        end,
                        dir: d.frame[k],
                        traction: false,
                    });
                }
            }
        }
    }
    held
}

/// What the pair loop reads: the body's elements in scaled coordinates, the entries of the
/// unknowns on each, and the known data; `n` rows and columns, the held rows included.
struct PairLoop<'a> {
    body: &'a Body,
    mat: &'a Material,
    settings: &'a QuadratureSettings,
    elems: &'a [ElementRef],
    boundary: &'a [Segment],
    area: f64,
    entries: &'a [Vec<Entry>],
    known_t: &'a [[[f64; 2]; 2]],
    known_u: &'a [[f64; 2]],
    body_force: Option<[f64; 2]>,
    length: f64,
    n: usize,
}

impl PairLoop<'_> {
    /// G and the load over the `ne` test elements: their strips, computed in parallel by
    /// chunks and added in element order.
    fn assemble(&self, ne: usize) -> (Mat<f64>, Vec<f64>) {
        let n = self.n;
        let mut g = Mat::<f64>::zeros(n, n);
        let mut load = vec![0.0; n];
        let chunk = 32;
        for start in (0..ne).step_by(chunk) {
            let end = (start + chunk).min(ne);
            let strips: Vec<_> = (start..end)
                .into_par_iter()
                .map(|ei| self.strip(ei))
                .collect();
            for (rows, vals, ld) in strips {
                for (ri, &r) in rows.iter().enumerate() {
                    for c in 0..n {
                        g[(r, c)] += vals[ri * n + c];
                    }
                }
                for (l, x) in load.iter_mut().zip(ld) {
                    *l += x;
                }
            }
        }
        (g, load)
    }

    /// The strip of test element `ei`: the indices of the unknowns supported on it, their
    /// partial rows (row by row, `n` values each) and their partial load, integrated against
    /// every element.
    fn strip(&self, ei: usize) -> (Vec<usize>, Vec<f64>, Vec<f64>) {
        let (body, mat, settings) = (self.body, self.mat, self.settings);
        let (elems, entries, known_t, known_u) =
            (self.elems, self.entries, self.known_t, self.known_u);
        let (n, length) = (self.n, self.length);
        let l2 = length * length;
        let rows: Vec<&Entry> = entries[ei].iter().collect();
        let mut vals = vec![0.0; rows.len() * n];
        let mut ld = vec![0.0; n];
        let e = &elems[ei];
        let mass_e = element_mass(&body_segment(body, ei));
        let te = known_t[ei];
        let t_nonzero = te.iter().any(|t| t[0] != 0.0 || t[1] != 0.0);
        for (fi, f) in elems.iter().enumerate() {
            let raw: PairBlocks = pair_blocks(mat, e, f, settings);
            let (v, k, d) = (scale4(&raw.v, l2), scale4(&raw.k, length), raw.d);
            let same = ei == fi;
            let tf = known_t[fi];
            let uf = [
                known_u[body.elements[fi].nodes[0]],
                known_u[body.elements[fi].nodes[1]],
            ];
            for (ri, r) in rows.iter().enumerate() {
                let row = &mut vals[ri * n..(ri + 1) * n];
                let a = r.end;
                if r.traction {
                    for c in &entries[fi] {
                        let b = c.end;
                        row[c.index] += if c.traction {
                            quad(r.dir, &v[a][b], c.dir)
                        } else {
                            let mut x = quad(r.dir, &k[a][b], c.dir);
                            if same {
                                x += 0.5 * mass_e[a][b] * dot(r.dir, c.dir);
                            }
                            x
                        };
                    }
                    for b in 0..2 {
                        let mut x = quad(r.dir, &v[a][b], tf[b]) - quad(r.dir, &k[a][b], uf[b]);
                        if same {
                            x -= 0.5 * mass_e[a][b] * dot(r.dir, uf[b]);
                        }
                        ld[r.index] += x;
                    }
                } else {
                    for c in entries[fi].iter().filter(|c| !c.traction) {
                        row[c.index] -= quad(r.dir, &d[a][c.end], c.dir);
                    }
                    for b in 0..2 {
                        ld[r.index] += quad(r.dir, &d[a][b], uf[b]);
                    }
                }
            }
            // Known traction on e acting on the displacement unknowns of f: (Kᵀ − ½Mᵀ) t̄.
            if t_nonzero {
                for c in entries[fi].iter().filter(|c| !c.traction) {
                    for a in 0..2 {
                        let mut x = quad(te[a], &k[a][c.end], c.dir);
                        if same {
                            x -= 0.5 * mass_e[a][c.end] * dot(te[a], c.dir);
                        }
                        ld[c.index] += x;
                    }
                }
            }
        }
        if let Some(b) = self.body_force {
            let bl = body_force_loads(mat, &e.seg, self.boundary, b, self.area, settings);
            for r in &rows {
                let (w, p) = (bl.w[r.end], bl.p[r.end]);
                ld[r.index] += if r.traction {
                    length * l2 * dot(r.dir, w)
                } else {
                    l2 * dot(r.dir, p)
                };
            }
        }
        (rows.iter().map(|r| r.index).collect(), vals, ld)
    }
}

/// Degenerate-scale detector (docs/formulation.md §8.4, §7 item 15): the single-layer block V over
/// the traction unknowns must be positive definite. Returns the smallest pivot of its
/// Cholesky factor relative to the largest; an error when the factorisation fails.
pub fn check_single_layer(sys: &BodySystem, body: &str) -> Result<f64> {
    let idx: Vec<usize> = (0..sys.n())
        .filter(|&i| sys.unknowns[i].is_traction())
        .collect();
    if idx.is_empty() {
        return Ok(1.0);
    }
    let d: Vec<f64> = idx
        .iter()
        .map(|&i| sys.g[(i, i)].abs().sqrt().max(f64::MIN_POSITIVE))
        .collect();
    let v = Mat::<f64>::from_fn(idx.len(), idx.len(), |i, j| {
        sys.g[(idx[i], idx[j])] / (d[i] * d[j])
    });
    let fail = || {
        Error::numerical(format!(
            "the single-layer operator of body \"{body}\" is not positive definite: the body's \
             size meets a degenerate scale of the logarithmic kernel"
        ))
    };
    let llt = v.llt(faer::Side::Lower).map_err(|_| fail())?;
    let l = llt.L();
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for i in 0..idx.len() {
        lo = lo.min(l[(i, i)].abs());
        hi = hi.max(l[(i, i)].abs());
    }
    let ratio = lo / hi;
    if ratio.is_nan() || ratio < 1e-7 {
        return Err(fail());
    }
    Ok(ratio)
}

/// The physical segment of element `ei`.
pub(crate) fn body_segment(body: &Body, ei: usize) -> Segment {
    let e = &body.elements[ei];
    Segment::new(body.nodes[e.nodes[0]], body.nodes[e.nodes[1]])
}

/// The coordinates a body is integrated in (docs/formulation.md §8.4):
/// `x' = ((x − o) − c)/L`, with o one of its boundary nodes, c the centroid of its boundary
/// nodes relative to o and L twice their largest distance from c, so that the scaled body
/// lies in a disk of radius 1/2, below every degenerate scale. They follow rotations,
/// translations and rescalings of the body, so results do too. Far from the origin, the
/// difference `x − o` of two nearby floating-point numbers is exact (Sterbenz): a body
/// moved by 1e15 whose nodes are still the same numbers plus the shift is integrated in the
/// same coordinates, to the last bit, as near the origin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scaling {
    /// A boundary node of the body (the first), or the point given.
    pub origin: [f64; 2],
    /// The centroid of the boundary nodes, relative to `origin`.
    pub centre: [f64; 2],
    /// Twice the largest distance of a boundary node from the centroid.
    pub length: f64,
}

impl Scaling {
    /// The scaling of a set of points: about the first, their centroid and extent.
    pub fn of(points: &[[f64; 2]]) -> Scaling {
        let origin = points.first().copied().unwrap_or([0.0; 2]);
        let rel = |p: &[f64; 2]| [p[0] - origin[0], p[1] - origin[1]];
        let n = points.len().max(1) as f64;
        let centre = [
            points.iter().map(|p| rel(p)[0]).sum::<f64>() / n,
            points.iter().map(|p| rel(p)[1]).sum::<f64>() / n,
        ];
        let r = points
            .iter()
            .map(|p| {
                let d = rel(p);
                (d[0] - centre[0]).hypot(d[1] - centre[1])
            })
            .fold(0.0, f64::max);
        Scaling {
            origin,
            centre,
            length: 2.0 * r,
        }
    }

    /// `x − o`: exact for a point near the body.
    pub fn relative(&self, x: [f64; 2]) -> [f64; 2] {
        [x[0] - self.origin[0], x[1] - self.origin[1]]
    }

    /// The scaled coordinates of a point given relative to `origin`.
    pub(crate) fn scaled_relative(&self, r: [f64; 2]) -> [f64; 2] {
        [
            (r[0] - self.centre[0]) / self.length,
            (r[1] - self.centre[1]) / self.length,
        ]
    }

    /// `(x − o) − c`: a point relative to the centroid, unscaled.
    pub fn centred(&self, x: [f64; 2]) -> [f64; 2] {
        let r = self.relative(x);
        [r[0] - self.centre[0], r[1] - self.centre[1]]
    }

    /// The scaled coordinates `((x − o) − c)/L` of a point.
    pub fn scaled(&self, x: [f64; 2]) -> [f64; 2] {
        self.scaled_relative(self.relative(x))
    }
}

impl From<([f64; 2], f64)> for Scaling {
    /// The scaled coordinates `(x − c)/L` about a given point c.
    fn from((c, length): ([f64; 2], f64)) -> Scaling {
        Scaling {
            origin: c,
            centre: [0.0; 2],
            length,
        }
    }
}

/// The [`Scaling`] of a body: about its first boundary node, the centroid of its boundary
/// nodes and their extent.
pub fn scaling(body: &Body) -> Scaling {
    Scaling::of(&body.nodes)
}

fn scale4(b: &[[[[f64; 2]; 2]; 2]; 2], s: f64) -> [[[[f64; 2]; 2]; 2]; 2] {
    let mut out = *b;
    for row in out.iter_mut() {
        for m in row.iter_mut() {
            for r in m.iter_mut() {
                for x in r.iter_mut() {
                    *x *= s;
                }
            }
        }
    }
    out
}

fn relative_asymmetry(g: &Mat<f64>) -> f64 {
    let n = g.nrows();
    let mut max = 0.0f64;
    let mut diff = 0.0f64;
    for i in 0..n {
        for j in 0..n {
            max = max.max(g[(i, j)].abs());
            if j > i {
                diff = diff.max((g[(i, j)] - g[(j, i)]).abs());
            }
        }
    }
    if max > 0.0 {
        diff / max
    } else {
        0.0
    }
}

/// The known displacement of each node from the constraints of its adjacent elements
/// (least squares over the constrained directions); conflicting conditions are an error.
fn known_displacements(
    body: &Body,
    constraints: &[Vec<([f64; 2], f64)>],
    scene_file: &std::path::Path,
) -> Result<Vec<[f64; 2]>> {
    let mut out = vec![[0.0; 2]; body.nodes.len()];
    for (n, list) in constraints.iter().enumerate() {
        if list.is_empty() {
            continue;
        }
        let d = body.dofs[n];
        // Known directions of the node: both axes, or frame[1] only.
        let known: Vec<[f64; 2]> = (0..2)
            .filter(|&k| d.class[k] == DofClass::Known)
            .map(|k| d.frame[k])
            .collect();
        // Solve min Σ (d_i·u − v_i)² over u in the span of the known directions.
        let u = if known.len() == 2 {
            let (mut a, mut r) = ([[0.0; 2]; 2], [0.0; 2]);
            for (dir, v) in list {
                for i in 0..2 {
                    r[i] += dir[i] * v;
                    for j in 0..2 {
                        a[i][j] += dir[i] * dir[j];
                    }
                }
            }
            let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
            [
                (a[1][1] * r[0] - a[0][1] * r[1]) / det,
                (a[0][0] * r[1] - a[1][0] * r[0]) / det,
            ]
        } else if known.len() == 1 {
            let k = known[0];
            let (mut num, mut den) = (0.0, 0.0);
            for (dir, v) in list {
                let c = dot(*dir, k);
                num += c * v;
                den += c * c;
            }
            let s = num / den;
            [s * k[0], s * k[1]]
        } else {
            [0.0, 0.0]
        };
        let scale = list.iter().map(|(_, v)| v.abs()).fold(0.0, f64::max);
        let worst = list
            .iter()
            .map(|(dir, v)| (dot(*dir, u) - v).abs())
            .fold(0.0, f64::max);
        if !(u[0].is_finite() && u[1].is_finite()) || worst > 1e-9 * scale.max(1e-300) {
            return Err(Error::input(
                scene_file,
                format!(
                    "the displacement conditions meeting at {} (body \"{}\") disagree: the \
                     boundaries that share this node prescribe incompatible values",
                    fmt_point(body.nodes[n]),
                    body.name
                ),
            ));
        }
        out[n] = u;
    }
    Ok(out)
}

fn fmt_point(p: [f64; 2]) -> String {
    format!(
        "({}, {})",
        crate::input::model::fmt_num(p[0]),
        crate::input::model::fmt_num(p[1])
    )
}
