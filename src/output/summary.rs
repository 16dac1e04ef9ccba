//! `summary.json`: the headline results of a run (README "Outputs"), as typed records.
//!
//! This module alone knows the file's shape: the pipeline fills a [`Summary`] and writes it
//! with `serde_json::to_string_pretty`. Key order: serde_json keeps the keys of an object
//! value sorted, and `summary.json` has always been written so; a struct is written in the
//! order of its fields, so every record here declares its fields in alphabetical order (the
//! test `keys_are_sorted` holds them to it). A figure that is not finite is written as
//! `null`. The contact stage's blocks (`contact`, `qp.info`) are records of
//! `crate::solution`, which the contact stage fills.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::contact::driver::QpCheck;
use crate::input::model::wrench::Wrench;
use crate::input::model::Interface;
use crate::input::scene::Units;
use crate::post::equilibrium::BodyBalance;
use crate::post::thrust::Thrust;
use crate::solution::{
    ContactSummary, InterfaceResult, MechanismBody, PairStatus, RunStatus, SolverInfo,
};

/// The whole of `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// The contact stage's own block (solver, iterations, cross-checks, ...).
    pub contact: ContactSummary,
    pub counts: Counts,
    pub diagnostics: Diagnostics,
    pub effects: Vec<&'static str>,
    /// Per body: its loads and imbalance.
    pub equilibrium: BTreeMap<String, BodyEquilibrium>,
    /// Where the run did not converge: why, as the message on stderr says it (the
    /// mechanism, with the bodies and the motion, where no equilibrium exists).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
    /// Per Physical Curve split into one interface per pair of bodies, when there is one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub interface_curves: Option<BTreeMap<String, CurveFigures>>,
    pub interfaces: BTreeMap<String, InterfaceFigures>,
    pub load_factor: f64,
    /// With `[solve] time`: every step's pseudo-time and what depends on it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub load_path: Option<LoadPath>,
    /// Where the run found no equilibrium and the motion of the mechanism: each moving
    /// body's rigid motion, as the message says it and the VTK block "mechanism" draws it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mechanism: Option<Vec<MechanismBody>>,
    /// "linear" without a unilateral interface, else the scene's method.
    pub method: &'static str,
    pub notes: Vec<String>,
    /// The `--set KEY=VALUE` applied to the scene.
    pub overrides: Vec<String>,
    pub plane: &'static str,
    pub problem: String,
    /// The QP's figures at the last load step, when the QP ran as a cross-check.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub qp: Option<QpSummary>,
    pub quadrature: &'static str,
    pub status: RunStatus,
    pub thickness: f64,
    /// Per interface (joint) of the final state: its resultant and point of application
    /// (post/thrust.rs); left out without interfaces.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub thrust: Option<BTreeMap<String, ThrustFigures>>,
    /// With `[solve] time`: the pseudo-time of the final state.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time: Option<f64>,
    pub title: String,
    pub units: Units,
}

/// The problem's sizes.
#[derive(Debug, Clone, Serialize)]
pub struct Counts {
    pub bodies: usize,
    pub boundary_elements: usize,
    /// Cuts that `[contact]` made where the body a line element faces changes (the
    /// archive's mesh has as many line elements more).
    pub contact_cuts: usize,
    /// The unknowns of all bodies' systems.
    pub dofs: usize,
    /// The mesh nodes where the interior field was evaluated.
    pub field_nodes: usize,
    pub interface_pairs: usize,
}

/// Figures of the operators' quality.
#[derive(Debug, Clone, Serialize)]
pub struct Diagnostics {
    /// The largest relative asymmetry of a condensed operator D00.
    pub d00_asymmetry: f64,
    /// The smallest pivot ratio of the condensations.
    pub min_pivot_ratio: f64,
}

/// The load path of `[solve] time`.
#[derive(Debug, Clone, Serialize)]
pub struct LoadPath {
    /// The prescribed values that depend on the pseudo-time.
    pub depends_on_t: Vec<String>,
    /// Every step's pseudo-time.
    pub time: Vec<f64>,
}

/// Per-interface figures: detached and closed lengths, open pairs, resultants, extreme
/// normal tractions (tension positive; resultants times the thickness); with friction the
/// stick and slip lengths and the largest accumulated slip.
#[derive(Debug, Clone, Serialize)]
pub struct InterfaceFigures {
    pub closed_length: f64,
    pub detached_length: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_accumulated_slip: Option<f64>,
    pub max_normal_traction: f64,
    pub min_normal_traction: f64,
    pub normal_resultant: f64,
    pub open_pairs: usize,
    pub pairs: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub slip_length: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stick_length: Option<f64>,
    pub tangential_resultant: f64,
}

impl InterfaceFigures {
    /// The floating-point figures by key, in key order (`None` where one is not written).
    fn floats(&self) -> [(&'static str, Option<f64>); 9] {
        [
            ("closed_length", Some(self.closed_length)),
            ("detached_length", Some(self.detached_length)),
            ("max_accumulated_slip", self.max_accumulated_slip),
            ("max_normal_traction", Some(self.max_normal_traction)),
            ("min_normal_traction", Some(self.min_normal_traction)),
            ("normal_resultant", Some(self.normal_resultant)),
            ("slip_length", self.slip_length),
            ("stick_length", self.stick_length),
            ("tangential_resultant", Some(self.tangential_resultant)),
        ]
    }
}

/// A Physical Curve joining several pairs of bodies: its parts (interfaces `CURVE[A|B]`)
/// and their figures combined. A figure is `None` (written `null`) where a sum was not
/// finite; the next part's sum starts again from 0 there.
#[derive(Debug, Clone, Serialize)]
pub struct CurveFigures {
    pub closed_length: Option<f64>,
    pub detached_length: Option<f64>,
    /// With friction: the largest accumulated slip of the parts, and the sums of their
    /// stick and slip lengths (absent without friction).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_accumulated_slip: Option<f64>,
    pub max_normal_traction: Option<f64>,
    pub min_normal_traction: Option<f64>,
    pub normal_resultant: Option<f64>,
    pub open_pairs: u64,
    pub pairs: u64,
    pub parts: Vec<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub slip_length: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stick_length: Option<f64>,
    pub tangential_resultant: Option<f64>,
}

/// One joint's resultant in the `thrust` block (post/thrust.rs): the normal force, compression
/// positive, and the tangential force times the thickness; the point of application, its
/// eccentricity and where it lies: `null` where the joint is fully open (no normal force).
#[derive(Debug, Clone, Serialize)]
pub struct ThrustFigures {
    pub e: Option<f64>,
    pub e_over_half_length: Option<f64>,
    pub in_closed_part: Option<bool>,
    pub inside: Option<bool>,
    pub normal_force: f64,
    pub s: Option<f64>,
    pub tangential_force: f64,
    pub x: Option<f64>,
    pub y: Option<f64>,
}

impl From<&Thrust> for ThrustFigures {
    fn from(t: &Thrust) -> ThrustFigures {
        let p = t.point.as_ref();
        ThrustFigures {
            e: p.map(|p| p.e),
            e_over_half_length: p.map(|p| p.e_over_half_length),
            in_closed_part: p.map(|p| p.in_closed_part),
            inside: p.map(|p| p.inside),
            normal_force: t.normal,
            s: p.map(|p| p.s),
            tangential_force: t.tangential,
            x: p.map(|p| p.x[0]),
            y: p.map(|p| p.x[1]),
        }
    }
}

/// The `thrust` block: each interface's resultant by name; `None` without interfaces.
pub fn thrust(its: &[Interface], thrusts: &[Thrust]) -> Option<BTreeMap<String, ThrustFigures>> {
    let m: BTreeMap<String, ThrustFigures> = its
        .iter()
        .zip(thrusts)
        .map(|(it, t)| (it.spec.name.clone(), ThrustFigures::from(t)))
        .collect();
    (!m.is_empty()).then_some(m)
}

/// The summary's `qp` block.
#[derive(Debug, Clone, Serialize)]
pub struct QpSummary {
    pub converged: bool,
    /// Pairs whose status differs from the main solver's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub differing_pairs_from_lcp: Option<usize>,
    pub form: &'static str,
    /// The solver's figures (iterations, status).
    pub info: SolverInfo,
    pub interfaces: BTreeMap<String, InterfaceFigures>,
}

/// One body's balance in the `equilibrium` block.
#[derive(Debug, Clone, Serialize)]
pub struct BodyEquilibrium {
    pub imbalance: WrenchFigures,
    /// Each load by name (`body_force`, `boundary NAME`, `interface NAME`).
    pub loads: BTreeMap<String, WrenchFigures>,
    /// The point moments are taken about: the centroid.
    pub moments_about: [f64; 2],
    pub relative_imbalance: f64,
}

/// Force (x, y) and moment of one load.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct WrenchFigures {
    pub fx: f64,
    pub fy: f64,
    pub m: f64,
}

impl From<&Wrench> for WrenchFigures {
    fn from(w: &Wrench) -> WrenchFigures {
        WrenchFigures {
            fx: w.fx,
            fy: w.fy,
            m: w.m,
        }
    }
}

/// Per-interface figures: detached and closed lengths, open pairs, resultants, extreme
/// normal tractions (tension positive; resultants times the thickness).
pub fn interface_figures(it: &Interface, r: &InterfaceResult, thickness: f64) -> InterfaceFigures {
    let mut detached = 0.0;
    let mut closed = 0.0;
    let mut normal = 0.0;
    let mut tangential = 0.0;
    for (ie, e) in it.elements.iter().enumerate() {
        let _ = ie;
        let [j, k] = e.pairs;
        let l = (0..2)
            .map(|c| it.pairs[k].x[c] - it.pairs[j].x[c])
            .map(|d| d * d)
            .sum::<f64>()
            .sqrt();
        let (sj, sk) = (r.pairs[j].status, r.pairs[k].status);
        if sj == PairStatus::Open && sk == PairStatus::Open {
            detached += l;
        }
        if sj == PairStatus::Closed && sk == PairStatus::Closed {
            closed += l;
        }
        normal += 0.5 * l * (r.pairs[j].traction[1] + r.pairs[k].traction[1]);
        tangential += 0.5 * l * (r.pairs[j].traction[0] + r.pairs[k].traction[0]);
    }
    if it.independent() {
        // Sides meshed on their own: the pairs' tributary lengths are the parts of A's
        // elements that face B, so the resultants are the sums of the row forces.
        let w = it.weights();
        normal = r.pairs.iter().zip(&w).map(|(p, w)| p.traction[1] * w).sum();
        tangential = r.pairs.iter().zip(&w).map(|(p, w)| p.traction[0] * w).sum();
    }
    let tn: Vec<f64> = r.pairs.iter().map(|p| p.traction[1]).collect();
    let open = r
        .pairs
        .iter()
        .filter(|p| p.status == PairStatus::Open)
        .count();
    let mut out = InterfaceFigures {
        closed_length: closed,
        detached_length: detached,
        max_accumulated_slip: None,
        max_normal_traction: tn.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        min_normal_traction: tn.iter().copied().fold(f64::INFINITY, f64::min),
        normal_resultant: normal * thickness,
        open_pairs: open,
        pairs: it.pairs.len(),
        slip_length: None,
        stick_length: None,
        tangential_resultant: tangential * thickness,
    };
    if r.pairs.iter().any(|p| p.slipping.is_some()) {
        // Lengths of elements whose two ends stick / slip (an element with one end of each
        // counts half to both).
        let (mut stick, mut slip) = (0.0, 0.0);
        for e in &it.elements {
            let [j, k] = e.pairs;
            let l =
                (it.pairs[k].x[0] - it.pairs[j].x[0]).hypot(it.pairs[k].x[1] - it.pairs[j].x[1]);
            for p in [j, k] {
                match r.pairs[p].tangential_status() {
                    Some("stick") => stick += 0.5 * l,
                    Some("slip") => slip += 0.5 * l,
                    _ => {}
                }
            }
        }
        let max_slip = r.pairs.iter().map(|p| p.slip).fold(0.0, f64::max);
        out.stick_length = Some(stick);
        out.slip_length = Some(slip);
        out.max_accumulated_slip = Some(max_slip);
    }
    out
}

/// The `interfaces` block: each interface's figures by name.
pub fn interfaces(
    its: &[Interface],
    results: &[InterfaceResult],
    thickness: f64,
) -> BTreeMap<String, InterfaceFigures> {
    let mut m = BTreeMap::new();
    for (it, r) in its.iter().zip(results) {
        m.insert(it.spec.name.clone(), interface_figures(it, r, thickness));
    }
    m
}

/// The summary's `qp` block: the QP's figures at the last load step.
pub fn qp(its: &[Interface], q: &QpCheck, thickness: f64) -> QpSummary {
    QpSummary {
        converged: q.converged,
        differing_pairs_from_lcp: q.differing_pairs,
        form: "primal (openings, symmetric Steklov-Poincare stiffness)",
        info: q.info.clone(),
        interfaces: interfaces(its, &q.interfaces, thickness),
    }
}

/// The first interface figure (interfaces by name, figures by key) that is not finite and
/// so is written as `null`, as `interface "NAME": KEY`: a resultant of finite tractions can
/// overflow.
pub(crate) fn non_finite_figure(interfaces: &BTreeMap<String, InterfaceFigures>) -> Option<String> {
    interfaces.iter().find_map(|(name, fig)| {
        fig.floats()
            .into_iter()
            .find(|(_, v)| v.is_some_and(|v| !v.is_finite()))
            .map(|(k, _)| format!("interface \"{name}\": {k}"))
    })
}

/// A figure as `summary.json` holds it: `None` (null) where it is not finite.
fn written(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

/// Per Physical Curve that joins several pairs of bodies (split into interfaces
/// `CURVE[A|B]`): its parts and their figures combined (lengths, pairs and resultants
/// summed, extreme tractions over all parts), each figure taken as written. `None` when no
/// curve is split.
pub fn interface_curves(
    its: &[Interface],
    figures: &BTreeMap<String, InterfaceFigures>,
) -> Option<BTreeMap<String, CurveFigures>> {
    let mut m: BTreeMap<String, CurveFigures> = BTreeMap::new();
    for it in its.iter().filter(|it| it.spec.name != it.group) {
        let fig = figures.get(it.spec.name.as_str());
        // A part's figure as written (NaN where it is null or missing).
        let get =
            |f: fn(&InterfaceFigures) -> f64| fig.and_then(|g| written(f(g))).unwrap_or(f64::NAN);
        let entry = m.entry(it.group.clone()).or_insert_with(|| CurveFigures {
            closed_length: Some(0.0),
            detached_length: Some(0.0),
            max_accumulated_slip: None,
            max_normal_traction: None,
            min_normal_traction: None,
            normal_resultant: Some(0.0),
            open_pairs: 0,
            pairs: 0,
            parts: Vec::new(),
            slip_length: None,
            stick_length: None,
            tangential_resultant: Some(0.0),
        });
        if let Some(g) = fig {
            let add = |a: Option<f64>, b: Option<f64>| b.map(|b| a.unwrap_or(0.0) + b).or(a);
            entry.stick_length = add(entry.stick_length, g.stick_length);
            entry.slip_length = add(entry.slip_length, g.slip_length);
            entry.max_accumulated_slip = g
                .max_accumulated_slip
                .map(|b| entry.max_accumulated_slip.unwrap_or(0.0).max(b))
                .or(entry.max_accumulated_slip);
        }
        entry.parts.push(it.spec.name.clone());
        for (sum, part) in [
            (&mut entry.detached_length, get(|g| g.detached_length)),
            (&mut entry.closed_length, get(|g| g.closed_length)),
            (&mut entry.normal_resultant, get(|g| g.normal_resultant)),
            (
                &mut entry.tangential_resultant,
                get(|g| g.tangential_resultant),
            ),
        ] {
            *sum = written(sum.unwrap_or(0.0) + part);
        }
        entry.open_pairs += fig.map_or(0, |g| g.open_pairs as u64);
        entry.pairs += fig.map_or(0, |g| g.pairs as u64);
        let hi = get(|g| g.max_normal_traction);
        let lo = get(|g| g.min_normal_traction);
        entry.max_normal_traction = written(entry.max_normal_traction.unwrap_or(hi).max(hi));
        entry.min_normal_traction = written(entry.min_normal_traction.unwrap_or(lo).min(lo));
    }
    if m.is_empty() {
        None
    } else {
        Some(m)
    }
}

/// The `equilibrium` block: per body the point, each load's `fx fy m`, the imbalance and
/// its relative size.
pub fn equilibrium(balances: &[BodyBalance]) -> BTreeMap<String, BodyEquilibrium> {
    let mut m = BTreeMap::new();
    for b in balances {
        let loads: BTreeMap<String, WrenchFigures> = b
            .loads
            .iter()
            .map(|(n, w)| (n.clone(), WrenchFigures::from(w)))
            .collect();
        m.insert(
            b.body.clone(),
            BodyEquilibrium {
                imbalance: WrenchFigures::from(&b.imbalance),
                loads,
                moments_about: b.point,
                relative_imbalance: b.relative,
            },
        );
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solution::{
        CollapseSummary, CollapseTrial, ContactSolveSummary, CrossCheck, ImpliedComponent,
        ImpliedSlipping, Junctions, LinearSummary, SlippingPair,
    };
    use serde_json::Value;

    /// Whether every object in `v`, at every depth, is written with its keys sorted.
    fn sorted_everywhere(text: &str) -> bool {
        let ordered = |v: &Value| serde_json::to_string_pretty(v).unwrap_or_default();
        let v: Value = serde_json::from_str(text).unwrap_or(Value::Null);
        text == ordered(&v)
    }

    /// Every figure a solver's `info` can hold.
    fn full_info() -> SolverInfo {
        SolverInfo {
            constraints: Some(4),
            friction_finishing_pivots: Some(1),
            friction_outer_changes: Some(vec![0.5, 0.0]),
            iterations: Some(9),
            objective: Some(-1.5),
            pivots: Some(3),
            qp_rescues: Some(1),
            solver_status: Some("Solved".into()),
            stick_tie_resolves: Some(1),
            variables: Some(4),
        }
    }

    /// A `junctions` block with every key, `implied_slipping` where `slipping`.
    fn junctions(slipping: bool) -> Junctions {
        Junctions {
            implied: BTreeMap::from([(
                "bed".to_string(),
                vec![ImpliedComponent {
                    component: "tangential",
                    x: [1.0, 0.0],
                }],
            )]),
            implied_components: 1,
            implied_slipping: slipping.then(|| ImpliedSlipping {
                at: vec![SlippingPair {
                    interface: "bed".into(),
                    slip: 1e-6,
                    x: [1.0, 0.0],
                }],
                count: 1,
                largest_slip: 1e-6,
                meaning: "slips",
            }),
            most_bodies_at_a_point: 3,
            points: 1,
            rule: "kept rows",
        }
    }

    /// A mechanism of a rotating and a sliding body (every key of a body's record).
    fn mechanism() -> Vec<MechanismBody> {
        vec![
            MechanismBody {
                body: "upper".into(),
                centre: Some([1.0, 0.5]),
                direction: None,
                kind: "rotation",
                magnitude: 1.0,
                sense: Some("clockwise"),
            },
            MechanismBody {
                body: "lower".into(),
                centre: None,
                direction: Some([1.0, 0.0]),
                kind: "translation",
                magnitude: 0.5,
                sense: None,
            },
        ]
    }

    /// A contact block with every key (collapse search, cross-checks, junctions).
    fn contact_block() -> ContactSummary {
        ContactSummary::Contact(Box::new(ContactSolveSummary {
            collapse: Some(CollapseSummary {
                collapses_at: Some(0.75),
                max: 1.0,
                mechanism: Some("a mechanism".into()),
                motion: Some(mechanism()),
                multiplier: 0.5,
                state: "largest",
                tolerance: 0.25,
                trials: vec![CollapseTrial {
                    undecided: false,
                    by_statics: false,
                    stands: true,
                    t: 0.0,
                    steps: 1,
                }],
                upper_bound: Some(0.8),
                upper_bound_meaning: "a bound".into(),
            }),
            complementarity_residual: 0.0,
            converged: true,
            cross_checks: vec![CrossCheck {
                converged: true,
                degenerate_pairs: 0,
                differing_pairs: 0,
                failure: Some("why".into()),
                info: full_info(),
                iterations: 2,
                load_step: 0,
                outer_iterations: 1,
                solver: "qp",
            }],
            interface_system_size: 12,
            iterations: 3,
            junctions: Some(junctions(true)),
            load_steps: 1,
            opening_stiffness_columns: 4,
            problem: "nodal contact forces",
            solver: "lcp",
        }))
    }

    /// The contact block's records are written with sorted keys, with every optional key
    /// and without them (an empty `info` as `{}`), and a linear run's block too.
    #[test]
    fn contact_block_keys_are_sorted() {
        let linear = ContactSummary::Linear(LinearSummary {
            junctions: Some(junctions(false)),
            solver: "linear (no unilateral interface)",
        });
        let bare = ContactSummary::Linear(LinearSummary {
            junctions: None,
            solver: "linear (no unilateral interface)",
        });
        for block in [contact_block(), linear, bare] {
            let text = serde_json::to_string_pretty(&block).unwrap_or_default();
            assert!(sorted_everywhere(&text), "{text}");
        }
        let empty = serde_json::to_string_pretty(&SolverInfo::default()).unwrap_or_default();
        assert_eq!(empty, "{}");
        let bare = ContactSummary::Linear(LinearSummary {
            junctions: None,
            solver: "linear",
        });
        let text = serde_json::to_string(&bare).unwrap_or_default();
        assert_eq!(text, r#"{"solver":"linear"}"#);
    }

    fn figures(friction: bool) -> InterfaceFigures {
        InterfaceFigures {
            closed_length: 1.0,
            detached_length: 2.0,
            max_accumulated_slip: friction.then_some(0.5),
            max_normal_traction: 3.0,
            min_normal_traction: -4.0,
            normal_resultant: 5.0,
            open_pairs: 6,
            pairs: 7,
            slip_length: friction.then_some(0.25),
            stick_length: friction.then_some(0.75),
            tangential_resultant: 8.0,
        }
    }

    /// Every record is written with its keys in the sorted order that `summary.json` has
    /// always had (a struct is written in its fields' order).
    #[test]
    fn keys_are_sorted() {
        let wrench = WrenchFigures {
            fx: 1.0,
            fy: 2.0,
            m: 3.0,
        };
        let summary = Summary {
            contact: contact_block(),
            counts: Counts {
                bodies: 2,
                boundary_elements: 10,
                contact_cuts: 0,
                dofs: 40,
                field_nodes: 0,
                interface_pairs: 3,
            },
            diagnostics: Diagnostics {
                d00_asymmetry: 1e-15,
                min_pivot_ratio: 0.5,
            },
            effects: vec!["elastic", "detachment"],
            equilibrium: BTreeMap::from([(
                "A".to_string(),
                BodyEquilibrium {
                    imbalance: wrench,
                    loads: BTreeMap::from([("body_force".to_string(), wrench)]),
                    moments_about: [0.0, 1.0],
                    relative_imbalance: 1e-12,
                },
            )]),
            failure: Some("no equilibrium exists".to_string()),
            interface_curves: Some(BTreeMap::from([(
                "joint".to_string(),
                CurveFigures {
                    closed_length: Some(1.0),
                    detached_length: None,
                    max_accumulated_slip: Some(0.5),
                    max_normal_traction: Some(2.0),
                    min_normal_traction: Some(-2.0),
                    normal_resultant: Some(3.0),
                    open_pairs: 1,
                    pairs: 2,
                    parts: vec!["joint[A|B]".into()],
                    slip_length: Some(0.25),
                    stick_length: Some(0.75),
                    tangential_resultant: Some(0.0),
                },
            )])),
            interfaces: BTreeMap::from([
                ("a".to_string(), figures(true)),
                ("b".to_string(), figures(false)),
            ]),
            load_factor: 1.0,
            load_path: Some(LoadPath {
                depends_on_t: vec!["boundary.top.ty".into()],
                time: vec![0.5, 1.0],
            }),
            mechanism: Some(mechanism()),
            method: "lcp",
            notes: vec!["a note".into()],
            overrides: vec![],
            plane: "strain",
            problem: "detachment".into(),
            qp: Some(QpSummary {
                converged: true,
                differing_pairs_from_lcp: Some(0),
                form: "primal",
                info: full_info(),
                interfaces: BTreeMap::from([("a".to_string(), figures(false))]),
            }),
            quadrature: "standard",
            status: RunStatus::Converged,
            thickness: 1.0,
            thrust: Some(BTreeMap::from([
                (
                    "a".to_string(),
                    ThrustFigures {
                        e: Some(0.1),
                        e_over_half_length: Some(0.2),
                        in_closed_part: Some(true),
                        inside: Some(true),
                        normal_force: 3.0,
                        s: Some(0.6),
                        tangential_force: 0.5,
                        x: Some(0.6),
                        y: Some(0.0),
                    },
                ),
                (
                    "b".to_string(),
                    ThrustFigures::from(&crate::post::thrust::thrust(
                        &crate::post::thrust::Joint {
                            x: vec![[0.0, 0.0], [1.0, 0.0]],
                            s: vec![0.0, 1.0],
                            weights: vec![0.5, 0.5],
                            normal: vec![[0.0, 1.0]; 2],
                        },
                        &InterfaceResult { pairs: vec![] },
                        1.0,
                    )),
                ),
            ])),
            time: Some(1.0),
            title: "t".into(),
            units: Units {
                force: "N".into(),
                length: "m".into(),
            },
        };
        let text = serde_json::to_string_pretty(&summary).unwrap_or_default();
        assert!(sorted_everywhere(&text), "{text}");
    }

    /// A figure that is not finite is written as null and named.
    #[test]
    fn a_non_finite_figure_is_null_and_named() {
        let mut fig = figures(false);
        fig.normal_resultant = f64::INFINITY;
        let text = serde_json::to_string(&fig).unwrap_or_default();
        assert!(text.contains("\"normal_resultant\":null"), "{text}");
        let interfaces = BTreeMap::from([("b".to_string(), fig), ("a".to_string(), figures(true))]);
        let floats: Vec<&str> = figures(true).floats().iter().map(|f| f.0).collect();
        let mut keys = floats.clone();
        keys.sort_unstable();
        assert_eq!(floats, keys);
        assert_eq!(
            non_finite_figure(&interfaces).as_deref(),
            Some("interface \"b\": normal_resultant")
        );
    }
}
