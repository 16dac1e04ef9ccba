//! Post-processing of one solved state: boundary stresses, interior fields, sections and
//! stress invariants.
//!
//! Place in the flow: `solution` (the boundary fields `u`, `t` of each body) →
//! **`postprocess`** → output writers. Inputs are plain: a [`Body`], its [`Material`], its
//! [`BodyField`], its body force (already multiplied by the load factor) and the
//! [`QuadratureSettings`]. Outputs are plain arrays in global components.
//!
//! * **Boundary stress** (docs/formulation.md §2.4, "Interior points"): at an element end the
//!   traction gives `σ_nn = t_n`, `σ_ns = t_s`, and the tangential strain of the P1 displacement
//!   gives `σ_ss = E'ε_ss + ν'σ_nn`, `ε_ss = du_s/ds`. With the effective Poisson ratio ν of
//!   [`Material`] (ν̄ = ν/(1+ν) in plane stress) both planes read `E' = 2μ/(1−ν)`,
//!   `ν' = ν/(1−ν)`: the plane-strain `E/(1−ν²)`, `ν/(1−ν)` and the plane-stress `E`, `ν` of
//!   the formulation. [`boundary_stress`] uses the element's own (one-sided, first-order)
//!   strain; [`smoothed_boundary_stress`] and [`nodal_boundary_stress`] use the centred strain
//!   at smooth nodes and a traction fit at corners (second order).
//! * **Interior points**: the Somigliana identities [paper eqs. 1a,b] (docs/formulation.md §2.1),
//!   `u_i(x) = ∫ U_ik t_k − ∫ T_ik u_k + u^b_i` and `σ_ij(x) = ∫ Σ_ijk t_k − ∫ S_kij u_k + σ^b_ij`,
//!   with the P1 boundary data and the exact body-force terms `u^b`, `σ^b` of docs/formulation.md
//!   §4.1. [`somigliana`] evaluates them as they are.
//! * **Near the boundary** (docs/formulation.md §8.5) the identities with P1 data are only first
//!   order within about half an element of the boundary, and their error grows like `log(L/d)`
//!   towards nodes and corners, where the data have kinks (measured in tests/postprocess.rs).
//!   [`interior`] therefore interpolates across a layer of [`BOUNDARY_LAYER`] element lengths,
//!   along the ray from the nearest boundary point (or corner) through x, between the boundary
//!   value and the identities at the far end of the ray, and keeps second order up to the
//!   boundary.
//! * **Points in a model**: which body contains a point (winding number), then [`interior`],
//!   in parallel: [`evaluate_points`], [`field_at_nodes`], [`section_points`].
//! * **Invariants**: [`out_of_plane_stress`], [`von_mises`], [`principal_stresses`].
//!
//! **Scaled coordinates.** The boundary operators of a body are integrated in the scaled
//! coordinates `x' = ((x − o) − c)/L` of [`crate::bem::assembly::scaling`] (docs/formulation.md
//! §8.4), which amounts to the single-layer kernel `U + const·I`. The interior identities use the
//! same coordinates, so that interior values belong to the same discrete solution as the
//! boundary values. Points are taken relative to the body's node o as they come in (exact for
//! points near the body), and everything after (rays of the boundary layer, nearest elements,
//! winding numbers) works in those relative coordinates: a model far from the origin keeps its
//! digits. Back in physical units the single-layer displacement integrals carry a factor L,
//! the double layer 1, the stress single layer 1, the stress double layer 1/L, and the
//! body-force terms `u^b` and `σ^b` the factors L² and L. For data in equilibrium
//! (`∮t ds + b|Ω| = 0`) the constants of the single layer and of `u^b` cancel and the result
//! is the physical identity.

// Index loops mirror the component formulas (δ_ik, r̂_i r̂_k, …) and read better than iterators.
#![allow(clippy::needless_range_loop)]

pub mod equilibrium;
pub mod plausibility;
pub mod thrust;

use std::collections::HashMap;

use rayon::prelude::*;

use crate::bem::assembly::{scaling, Scaling};
use crate::bem::galerkin::{
    point_integrals_on, ElementFrame, PointDisplacement, PointStress, Segment,
};
use crate::bem::kernels::{body_force_fields, boundary_area, Mat2, Material, Vec2};
use crate::bem::quadrature::QuadratureSettings;
use crate::input::model::Body;
use crate::input::scene::Plane;
use crate::solution::BodyField;
use crate::vec2::dot;

/// Thickness of the boundary layer of [`interior`], as a fraction of the nearest element's
/// length: 0.5.
///
/// Measured on the Kelvin field of tests/postprocess.rs (8 to 64 elements per side), the raw
/// identities are still second order at half an element from the boundary and lose it
/// closer in; layers of 0.5 and 1.0 element lengths gave the same worst errors within 30%,
/// and the thinner one the smaller at coarse meshes.
pub const BOUNDARY_LAYER: f64 = 0.5;

/// Fallback only: where no ray of the boundary layer stays clear of the boundary (thin parts,
/// points outside within [`ON_BOUNDARY_TOLERANCE`]), points closer to the boundary than this
/// fraction of the nearest element's length take the boundary values instead of the raw
/// identities.
///
/// Why 1e-3: with exact P1 data of a linear field the raw identities lose about `ε·(L/d)²`
/// to rounding, measured 4e-13 at d = 1e-2·L, 3e-11 at 1e-3·L, 5e-10 at 1e-4·L and 1e-5 at
/// 1e-6·L (relative to the stress). Down to 1e-3·L the rounding stays far below any
/// discretisation error.
pub const NEAR_BOUNDARY_FRACTION: f64 = 1e-3;

/// A point within this fraction of the body's scaling length ([`scaling`]: twice the largest
/// distance of a boundary node from their centroid) of the boundary is on the boundary: it
/// belongs to the body when points are located ([`evaluate_points`], [`PointSampler`]).
pub const ON_BOUNDARY_TOLERANCE: f64 = 1e-9;

/// Turning angle at a node above which the nodal stress is fitted to the tractions of both
/// elements instead of averaging the recovered element-end stresses
/// ([`nodal_boundary_stress`]): 30°.
pub const CORNER_ANGLE: f64 = std::f64::consts::PI / 6.0;

// ---------------------------------------------------------------------------------------
// Small 2-vector helpers.

#[inline]
fn lerp2(a: Vec2, b: Vec2, xi: f64) -> Vec2 {
    [a[0] + xi * (b[0] - a[0]), a[1] + xi * (b[1] - a[1])]
}

#[inline]
fn lerp_mat(a: &Mat2, b: &Mat2, xi: f64) -> Mat2 {
    let mut out = [[0.0; 2]; 2];
    for i in 0..2 {
        for j in 0..2 {
            out[i][j] = a[i][j] + xi * (b[i][j] - a[i][j]);
        }
    }
    out
}

/// Nearest point of segment `seg` to `x`: (distance, parameter ξ ∈ \[0,1\]).
fn project(seg: &Segment, x: Vec2) -> (f64, f64) {
    let c = seg.chord();
    let w = [x[0] - seg.p[0], x[1] - seg.p[1]];
    let cc = dot(c, c);
    let xi = if cc > 0.0 {
        (dot(w, c) / cc).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (
        crate::bem::kernels::norm2(w[0] - xi * c[0], w[1] - xi * c[1]),
        xi,
    )
}

// ---------------------------------------------------------------------------------------
// Boundary stress recovery.

/// `E' = 2μ/(1−ν)` and `ν' = ν/(1−ν)` with the effective ν of the material: plane strain
/// `E/(1−ν²)`, `ν/(1−ν)`; plane stress (ν̄ = ν/(1+ν)) `E`, `ν` (docs/formulation.md §2.4).
fn recovery_moduli(m: &Material) -> (f64, f64) {
    (2.0 * m.mu / (1.0 - m.nu), m.nu / (1.0 - m.nu))
}

/// Stress tensor (global xx, xy, yy) from its components in the element frame (s = tangent,
/// n = outward normal).
fn from_local(s: Vec2, n: Vec2, ss: f64, nn: f64, ns: f64) -> Mat2 {
    let mut out = [[0.0; 2]; 2];
    for i in 0..2 {
        for j in 0..2 {
            out[i][j] = ss * s[i] * s[j] + nn * n[i] * n[j] + ns * (n[i] * s[j] + s[i] * n[j]);
        }
    }
    out
}

/// The stress tensor at both ends of every element, indexed `[element][end][i][j]` in global
/// components, by the recovery formula (docs/formulation.md §2.4): `σ_nn = t_n`, `σ_ns = t_s`,
/// `σ_ss = E'ε_ss + ν'σ_nn` with `ε_ss = (u_Q − u_P)·τ/L` of the element's P1 displacement.
/// Exact for a linear displacement field with its constant stress.
pub fn boundary_stress(body: &Body, material: &Material, field: &BodyField) -> Vec<[Mat2; 2]> {
    assert_eq!(
        field.u.len(),
        body.nodes.len(),
        "boundary field of body \"{}\" has {} displacements for {} nodes",
        body.name,
        field.u.len(),
        body.nodes.len()
    );
    assert_eq!(
        field.t.len(),
        body.elements.len(),
        "boundary field of body \"{}\" has {} traction pairs for {} elements",
        body.name,
        field.t.len(),
        body.elements.len()
    );
    let (e_mod, nu_mod) = recovery_moduli(material);
    body.elements
        .iter()
        .enumerate()
        .map(|(ei, e)| {
            let (s, n) = (e.tangent, e.normal);
            let du = [
                field.u[e.nodes[1]][0] - field.u[e.nodes[0]][0],
                field.u[e.nodes[1]][1] - field.u[e.nodes[0]][1],
            ];
            let eps_ss = dot(du, s) / e.length;
            let end = |a: usize| {
                let t = field.t[ei][a];
                let (nn, ns) = (dot(t, n), dot(t, s));
                from_local(s, n, e_mod * eps_ss + nu_mod * nn, nn, ns)
            };
            [end(0), end(1)]
        })
        .collect()
}

/// How the boundary turns at a node: the element ends meeting there and, for two ends, whether
/// they form a corner ([`CORNER_ANGLE`]).
enum NodeKind {
    /// Two ends on a smooth stretch: (element, end) of the arriving and leaving elements.
    Smooth([(usize, usize); 2]),
    /// Two ends at a corner.
    Corner([(usize, usize); 2]),
    /// Any other number of ends (loops touching at a point).
    Other(Vec<(usize, usize)>),
}

fn node_kinds(body: &Body) -> Vec<NodeKind> {
    let mut meeting: Vec<Vec<(usize, usize)>> = vec![Vec::new(); body.nodes.len()];
    for (ei, e) in body.elements.iter().enumerate() {
        meeting[e.nodes[1]].push((ei, 1));
        meeting[e.nodes[0]].push((ei, 0));
    }
    let cos_corner = CORNER_ANGLE.cos();
    meeting
        .into_iter()
        .map(|list| {
            if list.len() == 2 {
                let pair = [list[0], list[1]];
                let (e1, e2) = (&body.elements[pair[0].0], &body.elements[pair[1].0]);
                if dot(e1.normal, e2.normal) < cos_corner {
                    NodeKind::Corner(pair)
                } else {
                    NodeKind::Smooth(pair)
                }
            } else {
                NodeKind::Other(list)
            }
        })
        .collect()
}

/// Tangential strain `ε_ss = (u_Q − u_P)·τ/L` of each element's P1 displacement.
fn element_strains(body: &Body, field: &BodyField) -> Vec<f64> {
    body.elements
        .iter()
        .map(|e| {
            let (p, q) = (field.u[e.nodes[0]], field.u[e.nodes[1]]);
            dot([q[0] - p[0], q[1] - p[1]], e.tangent) / e.length
        })
        .collect()
}

/// The stress at both ends of every element, like [`boundary_stress`] but with a better
/// tangential component at the nodes: `σ_nn = t_n` and `σ_ns = t_s` from the end's own
/// traction (so traction jumps are kept), and
///
/// * at a smooth node, `σ_ss = E'ε̄_ss + ν'σ_nn` with `ε̄_ss = (L₂ε₁ + L₁ε₂)/(L₁ + L₂)`, the
///   derivative at the node of the quadratic through the three nodal displacements: second
///   order where the one-sided `ε_ss` of one element is first order;
/// * at a corner, `σ_ss = s·σ̂·s` with σ̂ the traction fit of [`nodal_boundary_stress`]: the
///   tangential stress of one side is the normal stress of the other.
///
/// These are the boundary values [`interior`] interpolates along an element.
pub fn smoothed_boundary_stress(
    body: &Body,
    material: &Material,
    field: &BodyField,
) -> Vec<[Mat2; 2]> {
    let mut ends = boundary_stress(body, material, field);
    let strains = element_strains(body, field);
    let (e_mod, nu_mod) = recovery_moduli(material);
    for kind in node_kinds(body) {
        match kind {
            NodeKind::Smooth(pair) => {
                let (l1, l2) = (
                    body.elements[pair[0].0].length,
                    body.elements[pair[1].0].length,
                );
                let eps = (l2 * strains[pair[0].0] + l1 * strains[pair[1].0]) / (l1 + l2);
                for (ei, a) in pair {
                    let e = &body.elements[ei];
                    let t = field.t[ei][a];
                    let (nn, ns) = (dot(t, e.normal), dot(t, e.tangent));
                    ends[ei][a] =
                        from_local(e.tangent, e.normal, e_mod * eps + nu_mod * nn, nn, ns);
                }
            }
            NodeKind::Corner(pair) => {
                let fit = corner_fit(body, field, pair);
                for (ei, a) in pair {
                    let e = &body.elements[ei];
                    let t = field.t[ei][a];
                    let s = e.tangent;
                    let ss = dot(s, [dot(fit[0], s), dot(fit[1], s)]);
                    ends[ei][a] = from_local(s, e.normal, ss, dot(t, e.normal), dot(t, s));
                }
            }
            NodeKind::Other(_) => {}
        }
    }
    ends
}

fn corner_fit(body: &Body, field: &BodyField, pair: [(usize, usize); 2]) -> Mat2 {
    let data = pair.map(|(ei, a)| (body.elements[ei].normal, field.t[ei][a]));
    traction_fit(&data)
}

/// The stress at each boundary node (body-local numbering).
///
/// * Where the boundary turns by less than [`CORNER_ANGLE`]: the average of the two
///   element-end stresses of [`smoothed_boundary_stress`], which share the second-order
///   tangential strain; with continuous traction this is the recovery formula with that strain.
/// * At a corner (turning angle of at least [`CORNER_ANGLE`]): the two tractions `σn₁ = t₁`
///   and `σn₂ = t₂` determine the whole symmetric tensor, which is their least-squares fit
///   (four equations, three unknowns). It uses only nodal traction values, no one-sided
///   strain, and is exact whenever the tractions are. At a traction-free convex corner it
///   gives σ = 0, as it must; where the stress is singular (re-entrant corners, ends of a
///   clamp) no nodal value is meaningful and the fit is a compromise between the two sides.
/// * Elsewhere (loops touching at a node): the average of the plain recovered stresses.
pub fn nodal_boundary_stress(body: &Body, material: &Material, field: &BodyField) -> Vec<Mat2> {
    let ends = smoothed_boundary_stress(body, material, field);
    node_kinds(body)
        .into_iter()
        .map(|kind| match kind {
            NodeKind::Corner(pair) => corner_fit(body, field, pair),
            NodeKind::Smooth(pair) => {
                let [(e1, a1), (e2, a2)] = pair;
                lerp_mat(&ends[e1][a1], &ends[e2][a2], 0.5)
            }
            NodeKind::Other(list) => {
                let mut avg = [[0.0; 2]; 2];
                let w = 1.0 / list.len().max(1) as f64;
                for &(ei, a) in &list {
                    for i in 0..2 {
                        for j in 0..2 {
                            avg[i][j] += w * ends[ei][a][i][j];
                        }
                    }
                }
                avg
            }
        })
        .collect()
}

/// Least-squares symmetric stress with `σ n_k ≈ t_k` for the given (normal, traction) pairs.
fn traction_fit(data: &[(Vec2, Vec2)]) -> Mat2 {
    // Unknowns (σxx, σyy, σxy); rows σxx n_x + σxy n_y = t_x and σxy n_x + σyy n_y = t_y.
    let mut a = [[0.0; 3]; 3];
    let mut r = [0.0; 3];
    for &(n, t) in data {
        for (row, rhs) in [([n[0], 0.0, n[1]], t[0]), ([0.0, n[1], n[0]], t[1])] {
            for i in 0..3 {
                r[i] += row[i] * rhs;
                for j in 0..3 {
                    a[i][j] += row[i] * row[j];
                }
            }
        }
    }
    let s = solve3(a, r);
    [[s[0], s[2]], [s[2], s[1]]]
}

/// Solves a 3×3 system by Cramer's rule (the normal equations of [`traction_fit`], well
/// conditioned at corners of at least [`CORNER_ANGLE`]).
fn solve3(a: [[f64; 3]; 3], r: [f64; 3]) -> [f64; 3] {
    let det = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(a);
    let mut out = [0.0; 3];
    for k in 0..3 {
        let mut m = a;
        for i in 0..3 {
            m[i][k] = r[i];
        }
        out[k] = det(m) / d;
    }
    out
}

// ---------------------------------------------------------------------------------------
// Interior points.

/// One body prepared for point evaluation, apart from any boundary solution: scaled
/// geometry, computed once and shared by all points and all states.
///
/// Points are taken relative to the body's [`Scaling`] origin, one of its nodes, as soon as
/// they come in (an exact difference for a point near the body): the boundary layer's rays,
/// the nearest element and the winding number are then as accurate far from the origin as
/// near it.
struct Geometry<'a> {
    body: &'a Body,
    material: Material,
    scaling: Scaling,
    /// The boundary nodes relative to the origin.
    nodes: Vec<Vec2>,
    /// Segments relative to the origin (for distances) and scaled segments (for the
    /// integrals, with their normals and lengths).
    segments: Vec<Segment>,
    scaled: Vec<Segment>,
    frames: Vec<ElementFrame>,
    scaled_area: f64,
    /// For corner nodes, the shorter length of the two elements meeting there.
    corner_layer: Vec<Option<f64>>,
}

/// The boundary solution of one state on a [`Geometry`]: the field, the body force (times
/// the load factor) and the recovered boundary stresses.
struct Values<'a> {
    field: &'a BodyField,
    body_force: Option<Vec2>,
    /// [`smoothed_boundary_stress`] and [`nodal_boundary_stress`].
    ends: Vec<[Mat2; 2]>,
    nodal: Vec<Mat2>,
}

/// A geometry with the values of one state.
struct Prepared<'a> {
    geometry: Geometry<'a>,
    values: Values<'a>,
}

/// Where a boundary-layer ray starts ([`interior`]).
#[derive(Debug, Clone, Copy)]
enum RayBase {
    /// The point at parameter ξ of an element.
    Element(usize, f64),
    /// A corner node.
    Node(usize),
}

/// How [`interior`] obtains the value at a point: decided by the geometry alone, so that
/// one plan serves every state of a run. Points relative to the body's origin.
#[derive(Debug, Clone, Copy)]
enum PointPlan {
    /// The boundary value at parameter ξ of an element.
    Boundary(usize, f64),
    /// The Somigliana identities at the point.
    Identities(Vec2),
    /// Linear interpolation with weight `w` between the boundary value at `base` and the
    /// identities at `far`.
    Ray { base: RayBase, w: f64, far: Vec2 },
}

/// The kernel integrals of the identities at one point (scaled coordinates `xs`), per
/// element: they depend on the geometry alone.
struct Integrals {
    xs: Vec2,
    per_element: Vec<(PointDisplacement, PointStress)>,
}

impl<'a> Geometry<'a> {
    fn new(body: &'a Body, material: &Material, scaling: Scaling) -> Self {
        assert!(
            scaling.length > 0.0,
            "body \"{}\" has a degenerate scaling length {}",
            body.name,
            scaling.length
        );
        let nodes: Vec<Vec2> = body.nodes.iter().map(|&p| scaling.relative(p)).collect();
        let segments: Vec<Segment> = body
            .elements
            .iter()
            .map(|e| Segment::new(nodes[e.nodes[0]], nodes[e.nodes[1]]))
            .collect();
        let scaled: Vec<Segment> = segments
            .iter()
            .map(|s| Segment::new(scaling.scaled_relative(s.p), scaling.scaled_relative(s.q)))
            .collect();
        let scaled_area = boundary_area(&scaled);
        Geometry {
            body,
            material: *material,
            scaling,
            nodes,
            segments,
            frames: scaled.iter().map(|s| ElementFrame::new(*s)).collect(),
            scaled,
            scaled_area,
            corner_layer: node_kinds(body)
                .into_iter()
                .map(|k| match k {
                    NodeKind::Corner([(e1, _), (e2, _)]) => {
                        Some(body.elements[e1].length.min(body.elements[e2].length))
                    }
                    _ => None,
                })
                .collect(),
        }
    }

    /// The values of a boundary solution on this geometry.
    fn values<'f>(&self, field: &'f BodyField, body_force: Option<Vec2>) -> Values<'f> {
        let (body, material) = (self.body, &self.material);
        Values {
            field,
            body_force: body_force.filter(|b| *b != [0.0, 0.0]),
            ends: smoothed_boundary_stress(body, material, field),
            nodal: nodal_boundary_stress(body, material, field),
        }
    }

    /// A point relative to the origin: exact for a point near the body.
    fn relative(&self, x: Vec2) -> Vec2 {
        self.scaling.relative(x)
    }

    /// The point `base + offset` relative to the origin, as `(base − o) + offset`: the sum
    /// `base + offset` itself would round far from the origin.
    fn relative_offset(&self, (base, offset): (Vec2, Vec2)) -> Vec2 {
        let r = self.scaling.relative(base);
        [r[0] + offset[0], r[1] + offset[1]]
    }

    /// The kernel integrals of every element at x (relative; see [`Integrals`]).
    fn integrals(&self, settings: &QuadratureSettings, x: Vec2) -> Integrals {
        let xs = self.scaling.scaled_relative(x);
        Integrals {
            xs,
            per_element: self
                .frames
                .iter()
                .map(|f| point_integrals_on(&self.material, xs, f, settings))
                .collect(),
        }
    }

    /// The Somigliana identities at the scaled point `xs` from the kernel integrals of the
    /// elements in order, with the boundary data of `v` (no near-boundary switch).
    fn identities(
        &self,
        v: &Values,
        xs: Vec2,
        integrals: impl Iterator<Item = (PointDisplacement, PointStress)>,
    ) -> (Vec2, Mat2) {
        let m = &self.material;
        let l = self.scaling.length;
        let (mut u_single, mut u_double) = ([0.0; 2], [0.0; 2]);
        let (mut s_single, mut s_double) = ([[0.0; 2]; 2], [[0.0; 2]; 2]);
        for (ei, (pd, ps)) in integrals.enumerate() {
            let nodes = self.body.elements[ei].nodes;
            for b in 0..2 {
                let ub = v.field.u[nodes[b]];
                let tb = v.field.t[ei][b];
                for i in 0..2 {
                    for k in 0..2 {
                        u_single[i] += pd.single[b][i][k] * tb[k];
                        u_double[i] += pd.double[b][i][k] * ub[k];
                        for j in 0..2 {
                            s_single[i][j] += ps.single[b][i][j][k] * tb[k];
                            s_double[i][j] += ps.double[b][k][i][j] * ub[k];
                        }
                    }
                }
            }
        }
        let mut u = [0.0; 2];
        let mut s = [[0.0; 2]; 2];
        for i in 0..2 {
            u[i] = l * u_single[i] - u_double[i];
            for j in 0..2 {
                s[i][j] = s_single[i][j] - s_double[i][j] / l;
            }
        }
        if let Some(b) = v.body_force {
            let (ub, g) = body_force_fields(m, xs, &self.scaled, b, self.scaled_area);
            let sb = m.stress_from_gradient(g);
            for i in 0..2 {
                u[i] += l * l * ub[i];
                for j in 0..2 {
                    s[i][j] += l * sb[i][j];
                }
            }
        }
        (u, s)
    }

    /// The Somigliana identities at x (relative), integrating as it goes.
    fn somigliana(&self, v: &Values, settings: &QuadratureSettings, x: Vec2) -> (Vec2, Mat2) {
        let xs = self.scaling.scaled_relative(x);
        let m = &self.material;
        let integrals = self
            .frames
            .iter()
            .map(|f| point_integrals_on(m, xs, f, settings));
        self.identities(v, xs, integrals)
    }

    /// Nearest element to x (relative): (element, distance, parameter ξ). Elements within
    /// 1e-12·L of the nearest distance are as near, and the first of them is taken: at a
    /// point of symmetry (on the diagonal of a square corner) the last bits of the
    /// coordinates would choose otherwise.
    fn nearest(&self, x: Vec2) -> (usize, f64, f64) {
        let mut best = (0, f64::INFINITY, 0.0);
        let tie = 1e-12 * self.scaling.length;
        for (ei, seg) in self.segments.iter().enumerate() {
            let (d, xi) = project(seg, x);
            if d < best.1 - tie {
                best = (ei, d, xi);
            }
        }
        best
    }

    /// Boundary values at parameter ξ of element `ei`: linear displacement, smoothed
    /// recovered stress interpolated between the element ends.
    fn boundary_value(&self, v: &Values, ei: usize, xi: f64) -> (Vec2, Mat2) {
        let nodes = self.body.elements[ei].nodes;
        let u = lerp2(v.field.u[nodes[0]], v.field.u[nodes[1]], xi);
        // At a node the two elements meeting there are equally near: take the node's own
        // value, so that the result does not depend on which element was found first.
        let s = if xi <= 1e-12 {
            v.nodal[nodes[0]]
        } else if xi >= 1.0 - 1e-12 {
            v.nodal[nodes[1]]
        } else {
            lerp_mat(&v.ends[ei][0], &v.ends[ei][1], xi)
        };
        (u, s)
    }

    /// How [`interior`] evaluates x (relative; see there).
    fn plan(&self, x: Vec2) -> PointPlan {
        let (ei, d, xi) = self.nearest(x);
        let le = self.body.elements[ei].length;
        let layer = BOUNDARY_LAYER;
        let rho = layer * le;
        if d >= rho {
            return PointPlan::Identities(x);
        }
        if d == 0.0 {
            return PointPlan::Boundary(ei, xi);
        }
        // Rays from the boundary through x: (base, distance r of x from it, layer
        // thickness ρ, base point). The far point of a ray is at distance ρ.
        let foot = self.segments[ei].point(xi);
        let mut rays = vec![(RayBase::Element(ei, xi), d, rho, foot)];
        for a in 0..2 {
            let node = self.body.elements[ei].nodes[a];
            if let Some(rho_v) = self.corner_layer[node] {
                let v = self.nodes[node];
                let r = crate::bem::kernels::norm2(x[0] - v[0], x[1] - v[1]);
                if r < layer * rho_v && r > 0.0 {
                    rays.push((RayBase::Node(node), r, layer * rho_v, v));
                }
            }
        }
        let mut best: Option<(f64, usize, Vec2)> = None;
        for (k, &(_, r, rho_k, base)) in rays.iter().enumerate() {
            let x1 = [
                base[0] + (x[0] - base[0]) * rho_k / r,
                base[1] + (x[1] - base[1]) * rho_k / r,
            ];
            let c = self.clearance(x1);
            if best.is_none_or(|(cb, _, _)| c > cb) {
                best = Some((c, k, x1));
            }
        }
        if let Some((c, k, x1)) = best {
            if c > d {
                let (base, r, rho_k, _) = rays[k];
                return PointPlan::Ray {
                    base,
                    w: r / rho_k,
                    far: x1,
                };
            }
        }
        let snap = (NEAR_BOUNDARY_FRACTION * le).max(ON_BOUNDARY_TOLERANCE * self.scaling.length);
        if d < snap {
            PointPlan::Boundary(ei, xi)
        } else {
            PointPlan::Identities(x)
        }
    }

    /// The value of a plan for the state `v`; `identities` evaluates the Somigliana
    /// identities at a point of the plan.
    fn value(
        &self,
        v: &Values,
        plan: PointPlan,
        identities: impl FnOnce(Vec2) -> (Vec2, Mat2),
    ) -> (Vec2, Mat2) {
        match plan {
            PointPlan::Boundary(ei, xi) => self.boundary_value(v, ei, xi),
            PointPlan::Identities(x) => identities(x),
            PointPlan::Ray { base, w, far } => {
                let (u0, s0) = match base {
                    RayBase::Element(ei, xi) => self.boundary_value(v, ei, xi),
                    RayBase::Node(node) => (v.field.u[node], v.nodal[node]),
                };
                let (u1, s1) = identities(far);
                (lerp2(u0, u1, w), lerp_mat(&s0, &s1, w))
            }
        }
    }

    /// Winding number of the boundary around x (relative): see [`winding_number`].
    fn winding(&self, x: Vec2) -> i32 {
        crate::input::model::winding(x, self.segments.iter().map(|s| (s.p, s.q)))
    }

    /// True when x (relative) is inside the body or within [`ON_BOUNDARY_TOLERANCE`]·L of
    /// its boundary, L the scaling length.
    fn contains(&self, x: Vec2) -> bool {
        let (c, l) = (self.scaling.centre, self.scaling.length);
        let tol = ON_BOUNDARY_TOLERANCE * l;
        // Every boundary node lies within L/2 of the centroid, hence so does the body.
        if (x[0] - c[0]).hypot(x[1] - c[1]) > 0.5 * l + tol {
            return false;
        }
        self.winding(x) != 0
            || self
                .segments
                .iter()
                .map(|seg| project(seg, x).0)
                .fold(f64::INFINITY, f64::min)
                <= tol
    }

    /// Distance from x (relative) to the boundary if x is inside the body, else 0.
    fn clearance(&self, x: Vec2) -> f64 {
        if self.winding(x) == 0 {
            return 0.0;
        }
        self.segments
            .iter()
            .map(|seg| seg.distance_to_point(x))
            .fold(f64::INFINITY, f64::min)
    }
}

impl<'a> Prepared<'a> {
    fn new(
        body: &'a Body,
        material: &Material,
        field: &'a BodyField,
        scaling: Scaling,
        body_force: Option<Vec2>,
    ) -> Self {
        let geometry = Geometry::new(body, material, scaling);
        let values = geometry.values(field, body_force);
        Prepared { geometry, values }
    }

    /// The Somigliana identities at x (no near-boundary switch).
    fn somigliana(&self, settings: &QuadratureSettings, x: Vec2) -> (Vec2, Mat2) {
        let g = &self.geometry;
        g.somigliana(&self.values, settings, g.relative(x))
    }

    /// See [`interior`].
    fn interior(&self, settings: &QuadratureSettings, x: Vec2) -> (Vec2, Mat2) {
        let (g, v) = (&self.geometry, &self.values);
        g.value(v, g.plan(g.relative(x)), |y| g.somigliana(v, settings, y))
    }
}

/// Displacement and stress at x by the Somigliana identities [paper eqs. 1a,b] alone, without
/// the boundary layer of [`interior`]. `scaling` is [`crate::bem::assembly::scaling`] of the
/// body (or `(c, L)`), `body_force` the body force already multiplied by the load factor. The
/// point must lie inside the body and off its boundary; the stress loses about `ε·(L/d)²` to
/// rounding at a distance d from an element of length L.
pub fn somigliana(
    body: &Body,
    material: &Material,
    field: &BodyField,
    scaling: impl Into<Scaling>,
    body_force: Option<Vec2>,
    settings: &QuadratureSettings,
    x: Vec2,
) -> (Vec2, Mat2) {
    Prepared::new(body, material, field, scaling.into(), body_force).somigliana(settings, x)
}

/// Displacement and stress at a point x of the body (inside it or on its boundary).
///
/// * At least [`BOUNDARY_LAYER`]·L_e from the boundary (L_e the length of the nearest
///   element): the Somigliana identities ([`somigliana`]).
/// * On the boundary: the boundary values at x, i.e. the linear displacement and the
///   [`smoothed_boundary_stress`] interpolated along the element.
/// * In between (docs/formulation.md §8.5): linear interpolation along a ray from the boundary
///   through x, between the boundary value at its base (the nearest boundary point, or a
///   corner node within the layer, with the [`nodal_boundary_stress`] there) and the
///   identities at distance ρ = [`BOUNDARY_LAYER`]·L_e along the ray. Of these rays the one
///   whose far point is clearest of the boundary is used. Exact for linear fields; second
///   order up to the boundary for smooth fields (the raw identities are first order there,
///   with a `log(L_e/d)` growth next to nodes).
/// * If no ray's far point is farther from the boundary than x itself (thin parts, points
///   just outside): the raw identities, or the boundary values closer than
///   [`NEAR_BOUNDARY_FRACTION`]·L_e.
///
/// `scaling` is [`crate::bem::assembly::scaling`] of the body, `body_force` the body force already
/// multiplied by the load factor. For a point outside the body the result is meaningless;
/// [`evaluate_points`] locates points first.
pub fn interior(
    body: &Body,
    material: &Material,
    field: &BodyField,
    scaling: impl Into<Scaling>,
    body_force: Option<Vec2>,
    settings: &QuadratureSettings,
    x: Vec2,
) -> (Vec2, Mat2) {
    Prepared::new(body, material, field, scaling.into(), body_force).interior(settings, x)
}

// ---------------------------------------------------------------------------------------
// Points in a model.

/// What [`evaluate_points`] and [`field_at_nodes`] need of one body.
#[derive(Debug, Clone, Copy)]
pub struct BodyInput<'a> {
    pub body: &'a Body,
    /// `assembly::material(body, plane)`.
    pub material: Material,
    pub field: &'a BodyField,
    /// The body force already multiplied by the load factor.
    pub body_force: Option<Vec2>,
}

impl<'a> BodyInput<'a> {
    fn prepare(&self) -> Prepared<'a> {
        Prepared::new(
            self.body,
            &self.material,
            self.field,
            scaling(self.body),
            self.body_force,
        )
    }
}

/// The field at a located point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointValue {
    /// Index of the body containing the point (in the slice passed in).
    pub body: usize,
    pub u: Vec2,
    pub sigma: Mat2,
}

/// Winding number of the boundary loops of `body` around x: 1 inside the material (outer
/// loops counter-clockwise, holes clockwise), 0 outside and in holes.
pub fn winding_number(body: &Body, x: Vec2) -> i32 {
    body.winding_number(x)
}

/// Displacement and stress at each point, with the index of the first body that contains it
/// (inside by [`winding_number`], or on its boundary within [`ON_BOUNDARY_TOLERANCE`] of the
/// body size: the first body wins on an interface), or `None` for a point in no body.
/// Values by [`interior`]; points are evaluated in parallel (rayon).
pub fn evaluate_points(
    bodies: &[BodyInput],
    settings: &QuadratureSettings,
    points: &[Vec2],
) -> Vec<Option<PointValue>> {
    let prepared: Vec<Prepared> = bodies.iter().map(|b| b.prepare()).collect();
    points
        .par_iter()
        .map(|&x| {
            let bi = prepared
                .iter()
                .position(|p| p.geometry.contains(p.geometry.relative(x)))?;
            let (u, sigma) = prepared[bi].interior(settings, x);
            Some(PointValue { body: bi, u, sigma })
        })
        .collect()
}

/// Memory that the cached kernel integrals of one [`PointSampler`] may take: 256 MB (about
/// 700 000 point–element pairs). Points beyond it are integrated again for every state:
/// the same values, in more time.
pub(crate) const SAMPLER_CACHE_BYTES: usize = 256 << 20;

/// Fixed points evaluated for many states of the same bodies, e.g. a section at every
/// contact iteration.
///
/// Which body holds a point, how [`interior`] obtains its value (boundary value, identities,
/// or a ray between them) and the kernel integrals of its identities depend on the geometry
/// alone: they are computed once, here, and each state then costs one pass over the cached
/// integrals with its boundary data. The values are those of [`evaluate_points`] bit for
/// bit (the same products summed in the same order).
pub struct PointSampler<'a> {
    geometries: Vec<Geometry<'a>>,
    settings: QuadratureSettings,
    /// Per point: the body holding it, its plan and the slot of its cached integrals
    /// (`None`: over [`SAMPLER_CACHE_BYTES`], or no identities needed); `None` outside.
    points: Vec<Option<(usize, PointPlan, Option<usize>)>>,
    cached: Vec<Integrals>,
}

impl<'a> PointSampler<'a> {
    /// Locates and plans `points` in the bodies of `bodies` (their fields are not used) and
    /// integrates the kernels at each identities point, in parallel.
    pub fn new(bodies: &[BodyInput<'a>], settings: &QuadratureSettings, points: &[Vec2]) -> Self {
        let at: Vec<(Vec2, Vec2)> = points.iter().map(|&x| (x, [0.0; 2])).collect();
        Self::at(bodies, settings, &at)
    }

    /// [`PointSampler::new`] for the points `base + offsets[k]`, each taken relative to the
    /// body holding it as `(base − o) + offset` (o the body's [`Scaling`] origin): the
    /// points of a section, `from + t (to − from)`, are then the same far from the origin,
    /// where their sum would round, as near it ([`section_offsets`]).
    pub(crate) fn with_offsets(
        bodies: &[BodyInput<'a>],
        settings: &QuadratureSettings,
        base: Vec2,
        offsets: &[Vec2],
    ) -> Self {
        let at: Vec<(Vec2, Vec2)> = offsets.iter().map(|&d| (base, d)).collect();
        Self::at(bodies, settings, &at)
    }

    /// The sampler of the points `base + offset`.
    fn at(bodies: &[BodyInput<'a>], settings: &QuadratureSettings, at: &[(Vec2, Vec2)]) -> Self {
        let geometries: Vec<Geometry> = bodies
            .iter()
            .map(|b| Geometry::new(b.body, &b.material, scaling(b.body)))
            .collect();
        let located: Vec<Option<(usize, PointPlan)>> = at
            .par_iter()
            .map(|&p| {
                let bi = geometries
                    .iter()
                    .position(|g| g.contains(g.relative_offset(p)))?;
                let g = &geometries[bi];
                Some((bi, g.plan(g.relative_offset(p))))
            })
            .collect();
        let pair = std::mem::size_of::<(PointDisplacement, PointStress)>();
        let mut budget = SAMPLER_CACHE_BYTES;
        let mut todo: Vec<(usize, Vec2)> = Vec::new();
        let points = located
            .into_iter()
            .map(|p| {
                p.map(|(bi, plan)| {
                    let y = match plan {
                        PointPlan::Identities(x) => Some(x),
                        PointPlan::Ray { far, .. } => Some(far),
                        PointPlan::Boundary(..) => None,
                    };
                    let bytes = geometries[bi].frames.len() * pair;
                    let slot = y.filter(|_| bytes <= budget).map(|y| {
                        budget -= bytes;
                        todo.push((bi, y));
                        todo.len() - 1
                    });
                    (bi, plan, slot)
                })
            })
            .collect();
        let cached = todo
            .par_iter()
            .map(|&(bi, y)| geometries[bi].integrals(settings, y))
            .collect();
        PointSampler {
            geometries,
            settings: settings.clone(),
            points,
            cached,
        }
    }

    /// The value at every point for the boundary solution of `bodies` (the same bodies, in
    /// the same order, as [`PointSampler::new`] was given), in parallel.
    pub fn evaluate(&self, bodies: &[BodyInput]) -> Vec<Option<PointValue>> {
        assert_eq!(
            bodies.len(),
            self.geometries.len(),
            "a point sampler evaluates the bodies it was built for"
        );
        let values: Vec<Values> = self
            .geometries
            .iter()
            .zip(bodies)
            .map(|(g, b)| {
                assert!(
                    std::ptr::eq(g.body, b.body) && g.material == b.material,
                    "a point sampler evaluates the bodies it was built for"
                );
                g.values(b.field, b.body_force)
            })
            .collect();
        self.points
            .par_iter()
            .map(|p| {
                let (bi, plan, slot) = (*p)?;
                let (g, v) = (&self.geometries[bi], &values[bi]);
                let (u, sigma) = g.value(v, plan, |y| match slot {
                    Some(k) => {
                        let c = &self.cached[k];
                        g.identities(v, c.xs, c.per_element.iter().copied())
                    }
                    None => g.somigliana(v, &self.settings, y),
                });
                Some(PointValue { body: bi, u, sigma })
            })
            .collect()
    }
}

/// The field at one node of the body's triangle mesh.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodeValue {
    /// Index into the mesh node list.
    pub mesh_node: usize,
    pub u: Vec2,
    pub sigma: Mat2,
}

/// The field at every node of the body's triangles (`body.triangles`), one entry per distinct
/// mesh node in increasing order of mesh index. `mesh_nodes` are the coordinates of all mesh
/// nodes. Nodes that are boundary nodes of the body (`body.mesh_nodes`) take the boundary
/// values exactly: `field.u` and [`nodal_boundary_stress`]; the others [`interior`], in
/// parallel.
pub fn field_at_nodes(
    input: &BodyInput,
    settings: &QuadratureSettings,
    mesh_nodes: &[Vec2],
) -> Vec<NodeValue> {
    field_at_nodes_with(input, settings, mesh_nodes, &|_| {})
}

/// The number of nodes [`field_at_nodes`] evaluates for a body (its triangles' nodes).
pub(crate) fn field_node_count(body: &crate::input::model::Body) -> usize {
    let mut ids: Vec<usize> = body.triangles.iter().flatten().copied().collect();
    ids.sort_unstable();
    ids.dedup();
    ids.len()
}

/// [`field_at_nodes`] calling `done(1)` after each node (from the worker threads), for a
/// progress bar.
pub(crate) fn field_at_nodes_with(
    input: &BodyInput,
    settings: &QuadratureSettings,
    mesh_nodes: &[Vec2],
    done: &(dyn Fn(u64) + Sync),
) -> Vec<NodeValue> {
    let prepared = input.prepare();
    let nodal = &prepared.values.nodal;
    let mut on_boundary: HashMap<usize, usize> = HashMap::new();
    for (n, &mn) in input.body.mesh_nodes.iter().enumerate() {
        on_boundary.entry(mn).or_insert(n);
    }
    let mut ids: Vec<usize> = input.body.triangles.iter().flatten().copied().collect();
    ids.sort_unstable();
    ids.dedup();
    ids.par_iter()
        .map(|&mn| {
            let (u, sigma) = match on_boundary.get(&mn) {
                Some(&n) => (input.field.u[n], nodal[n]),
                None => prepared.interior(settings, mesh_nodes[mn]),
            };
            done(1);
            NodeValue {
                mesh_node: mn,
                u,
                sigma,
            }
        })
        .collect()
}

/// `count` equally spaced points from `from` to `to`, both included (a section line).
pub fn section_points(from: Vec2, to: Vec2, count: usize) -> Vec<Vec2> {
    assert!(count >= 2, "a section needs at least 2 points, got {count}");
    (0..count)
        .map(|k| lerp2(from, to, k as f64 / (count - 1) as f64))
        .collect()
}

/// The offsets `t (to − from)` from `from` of the [`section_points`], for
/// [`PointSampler::with_offsets`].
pub(crate) fn section_offsets(from: Vec2, to: Vec2, count: usize) -> Vec<Vec2> {
    assert!(count >= 2, "a section needs at least 2 points, got {count}");
    let d = [to[0] - from[0], to[1] - from[1]];
    (0..count)
        .map(|k| {
            let t = k as f64 / (count - 1) as f64;
            [t * d[0], t * d[1]]
        })
        .collect()
}

// ---------------------------------------------------------------------------------------
// Stress invariants.

/// Out-of-plane stress σ_zz: `ν(σxx + σyy)` in plane strain, with the *real* Poisson ratio
/// ν of the body (not the effective one of [`Material`]); 0 in plane stress.
pub fn out_of_plane_stress(sigma: &Mat2, plane: Plane, poisson: f64) -> f64 {
    match plane {
        Plane::Strain => poisson * (sigma[0][0] + sigma[1][1]),
        Plane::Stress => 0.0,
    }
}

/// Von Mises equivalent stress of the in-plane tensor with out-of-plane stress `sigma_zz`
/// ([`out_of_plane_stress`]):
/// `√(½[(σxx−σyy)² + (σyy−σzz)² + (σzz−σxx)²] + 3σxy²)`.
pub fn von_mises(sigma: &Mat2, sigma_zz: f64) -> f64 {
    let (xx, yy, xy) = (sigma[0][0], sigma[1][1], 0.5 * (sigma[0][1] + sigma[1][0]));
    let zz = sigma_zz;
    (0.5 * ((xx - yy).powi(2) + (yy - zz).powi(2) + (zz - xx).powi(2)) + 3.0 * xy * xy).sqrt()
}

/// In-plane principal stresses `[σ1, σ2]` with σ1 ≥ σ2, and the angle (radians, from the
/// x axis, in (−π/2, π/2\]) of the direction of σ1.
pub fn principal_stresses(sigma: &Mat2) -> ([f64; 2], f64) {
    let (xx, yy, xy) = (sigma[0][0], sigma[1][1], 0.5 * (sigma[0][1] + sigma[1][0]));
    let mean = 0.5 * (xx + yy);
    let radius = (0.5 * (xx - yy)).hypot(xy);
    let angle = 0.5 * (2.0 * xy).atan2(xx - yy);
    ([mean + radius, mean - radius], angle)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn principal_and_von_mises() {
        // Pure shear τ: principal ±τ at 45°, von Mises √3 τ.
        let s = [[0.0, 2.0], [2.0, 0.0]];
        let (p, a) = principal_stresses(&s);
        assert!((p[0] - 2.0).abs() < 1e-15 && (p[1] + 2.0).abs() < 1e-15);
        assert!((a - std::f64::consts::FRAC_PI_4).abs() < 1e-15);
        assert!((von_mises(&s, 0.0) - 2.0 * 3f64.sqrt()).abs() < 1e-14);
        // Uniaxial σ along y: σ1 = σ along 90°, von Mises σ in plane stress.
        let s = [[0.0, 0.0], [0.0, 5.0]];
        let (p, a) = principal_stresses(&s);
        assert!((p[0] - 5.0).abs() < 1e-15 && p[1].abs() < 1e-15);
        assert!((a.abs() - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        let zz = out_of_plane_stress(&s, Plane::Stress, 0.3);
        assert_eq!(zz, 0.0);
        assert!((von_mises(&s, zz) - 5.0).abs() < 1e-14);
        // Plane strain, hydrostatic in-plane p: σ_zz = 2νp, von Mises |p − 2νp|.
        let s = [[-1.0, 0.0], [0.0, -1.0]];
        let zz = out_of_plane_stress(&s, Plane::Strain, 0.3);
        assert!((zz + 0.6).abs() < 1e-15);
        assert!((von_mises(&s, zz) - 0.4).abs() < 1e-14);
    }

    #[test]
    fn sections_include_both_ends() {
        let p = section_points([1.0, 2.0], [3.0, -2.0], 5);
        assert_eq!(p.len(), 5);
        assert_eq!(p[0], [1.0, 2.0]);
        assert_eq!(p[4], [3.0, -2.0]);
        assert!((p[2][0] - 2.0).abs() < 1e-15 && p[2][1].abs() < 1e-15);
    }

    #[test]
    fn traction_fit_recovers_a_tensor_at_a_corner() {
        let s = [[0.3, -0.7], [-0.7, 1.9]];
        let normals = [[0.0, -1.0], [0.6, 0.8]];
        let data: Vec<(Vec2, Vec2)> = normals
            .iter()
            .map(|&n| {
                (
                    n,
                    [
                        s[0][0] * n[0] + s[0][1] * n[1],
                        s[1][0] * n[0] + s[1][1] * n[1],
                    ],
                )
            })
            .collect();
        let f = traction_fit(&data);
        for i in 0..2 {
            for j in 0..2 {
                assert!((f[i][j] - s[i][j]).abs() < 1e-14, "{f:?}");
            }
        }
    }
}
