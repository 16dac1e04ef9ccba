//! `summary.json`: the headline results of a run (SPEC.md "Outputs").

use serde_json::{json, Map, Value};

use crate::contact::driver::QpCheck;
use crate::input::model::Interface;
use crate::solution::{InterfaceResult, PairStatus};

/// Per-interface figures: detached and closed lengths, open pairs, resultants, extreme
/// normal tractions (tension positive; resultants times the thickness).
pub fn interface_figures(it: &Interface, r: &InterfaceResult, thickness: f64) -> Value {
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
    let mut out = json!({
        "detached_length": detached,
        "closed_length": closed,
        "open_pairs": open,
        "pairs": it.pairs.len(),
        "normal_resultant": normal * thickness,
        "tangential_resultant": tangential * thickness,
        "max_normal_traction": tn.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        "min_normal_traction": tn.iter().copied().fold(f64::INFINITY, f64::min),
    });
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
        out["stick_length"] = json!(stick);
        out["slip_length"] = json!(slip);
        out["max_accumulated_slip"] = json!(max_slip);
    }
    out
}

/// Builds the `interfaces` object.
pub fn interfaces(its: &[Interface], results: &[InterfaceResult], thickness: f64) -> Value {
    let mut m = Map::new();
    for (it, r) in its.iter().zip(results) {
        m.insert(it.spec.name.clone(), interface_figures(it, r, thickness));
    }
    Value::Object(m)
}

/// The summary's `qp` block: the QP's figures at the last load step.
pub fn qp(its: &[Interface], q: &QpCheck, thickness: f64) -> Value {
    let mut block = json!({
        "form": "primal (openings, symmetric Steklov-Poincare stiffness)",
        "interfaces": interfaces(its, &q.interfaces, thickness),
        "converged": q.converged,
        "info": q.info,
    });
    if let Some(d) = q.differing_pairs {
        block["differing_pairs_from_lcp"] = json!(d);
    }
    block
}

/// Per Physical Curve that joins several pairs of bodies (split into interfaces
/// `CURVE[A|B]`): its parts and their figures combined (lengths, pairs and resultants
/// summed, extreme tractions over all parts). `None` when no curve is split.
pub fn interface_curves(its: &[Interface], figures: &Value) -> Option<Value> {
    let mut m = Map::new();
    for it in its.iter().filter(|it| it.spec.name != it.group) {
        let fig = &figures[it.spec.name.as_str()];
        let entry = m.entry(it.group.clone()).or_insert_with(|| {
            json!({
                "parts": [], "detached_length": 0.0, "closed_length": 0.0, "open_pairs": 0,
                "pairs": 0, "normal_resultant": 0.0, "tangential_resultant": 0.0,
                "max_normal_traction": null, "min_normal_traction": null,
            })
        });
        if let Some(parts) = entry["parts"].as_array_mut() {
            parts.push(json!(it.spec.name));
        }
        for key in [
            "detached_length",
            "closed_length",
            "normal_resultant",
            "tangential_resultant",
        ] {
            let sum = entry[key].as_f64().unwrap_or(0.0) + fig[key].as_f64().unwrap_or(f64::NAN);
            entry[key] = json!(sum);
        }
        for key in ["open_pairs", "pairs"] {
            let sum = entry[key].as_u64().unwrap_or(0) + fig[key].as_u64().unwrap_or(0);
            entry[key] = json!(sum);
        }
        let hi = fig["max_normal_traction"].as_f64().unwrap_or(f64::NAN);
        let lo = fig["min_normal_traction"].as_f64().unwrap_or(f64::NAN);
        entry["max_normal_traction"] =
            json!(entry["max_normal_traction"].as_f64().unwrap_or(hi).max(hi));
        entry["min_normal_traction"] =
            json!(entry["min_normal_traction"].as_f64().unwrap_or(lo).min(lo));
    }
    if m.is_empty() {
        None
    } else {
        Some(Value::Object(m))
    }
}
