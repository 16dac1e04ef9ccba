//! Equilibrium of every body (`summary.json` `equilibrium`): the shipped arch and pier
//! pipelines, run end to end.
//!
//! Every body balances to round-off (asserted ≤ 1e-8): the interface loads are the contact
//! problem's nodal forces, and the reactions of displacement conditions are the nodal forces
//! of the held nodes' hypersingular rows (`BodySystem::held_rows`), which the discrete problem
//! balances against the body force and the prescribed tractions as exactly. (Integrated from
//! the element tractions of the held edges instead, the reactions balanced only to the
//! discretisation error: 0.86 / 0.34 / 0.17 / 0.09 % for the arch's abutments at 3 / 6 / 12 /
//! 24 elements per joint.)

mod support;

use serde_json::Value;
use support::*;

fn run(name: &str, scene: &str, sets: &[&str]) -> Value {
    let (code, s) = run_code(name, scene, sets);
    assert_eq!(code, 0, "{}", s["status"]);
    s
}

/// Runs a pipeline; returns the exit code and the summary (written on exit 3 too).
fn run_code(name: &str, scene: &str, sets: &[&str]) -> (i32, Value) {
    let dir = tmpdir(name);
    let out = dir.join("out");
    let scene = root().join(scene);
    let mut args = vec![
        "run",
        scene.to_str().unwrap_or_default(),
        "--quiet",
        "--out",
    ];
    args.push(out.to_str().unwrap_or_default());
    let sets: Vec<String> = sets.iter().map(|s| format!("--set={s}")).collect();
    args.extend(sets.iter().map(String::as_str));
    let (code, _, err) = sgbem(&args);
    assert!(code == 0 || code == 3, "{err}");
    let text = std::fs::read_to_string(out.join("summary.json")).expect("summary.json");
    (
        code,
        serde_json::from_str(&text).expect("summary.json is JSON"),
    )
}

fn relative(s: &Value, body: &str) -> f64 {
    s["equilibrium"][body]["relative_imbalance"]
        .as_f64()
        .unwrap_or_else(|| panic!("no equilibrium for {body}"))
}

fn load(s: &Value, body: &str, what: &str) -> [f64; 3] {
    let w = &s["equilibrium"][body]["loads"][what];
    let c = |k: &str| {
        w[k].as_f64()
            .unwrap_or_else(|| panic!("{body}: no {what}.{k}"))
    };
    [c("fx"), c("fy"), c("m")]
}

#[test]
fn arch_voussoirs_balance_to_round_off_and_abutments_converge() {
    let mut abutment = Vec::new();
    for nj in [3, 6, 12] {
        let s = run(
            "eq-arch",
            "pipelines/arch.toml",
            &["mesh.nv=10", &format!("mesh.nj={nj}")],
        );
        assert_eq!(s["status"], "converged");
        for v in 1..=10 {
            let b = format!("voussoir_{v}");
            let r = relative(&s, &b);
            assert!(r <= 1e-8, "{b} at nj = {nj}: relative imbalance {r:e}");
            // Self-weight: 20 kN/m³ over the voussoir's (polygonal) area, about its centroid.
            let w = load(&s, &b, "body_force");
            assert!(w[0] == 0.0 && w[2] == 0.0, "{w:?}");
            assert!(w[1] < 0.0 && (w[1] / -20.0 - 0.94).abs() < 0.01, "{w:?}");
        }
        // The joint between voussoirs 5 and 6 acts equally and oppositely on both.
        let on5 = load(&s, "voussoir_5", "interface joints[voussoir_5|voussoir_6]");
        let on6 = load(&s, "voussoir_6", "interface joints[voussoir_5|voussoir_6]");
        assert!(
            (on5[0] + on6[0]).abs() < 1e-9 * on5[0].abs() && (on5[1] + on6[1]).abs() < 1e-9,
            "{on5:?} {on6:?}"
        );
        // The crown joint of a symmetric arch carries a horizontal thrust only.
        assert!(on5[0].abs() > 1e3 * on5[1].abs(), "{on5:?}");
        abutment.push(relative(&s, "abutment_L").max(relative(&s, "abutment_R")));
        // The "joints" curve, split into 11 interfaces: its combined figures are the sums
        // (and extremes) of its parts'.
        let curve = &s["interface_curves"]["joints"];
        let parts = curve["parts"].as_array().expect("parts");
        assert_eq!(parts.len(), 11);
        let part = |p: &Value, k: &str| s["interfaces"][p.as_str().unwrap_or_default()][k].clone();
        let sum = |k: &str| {
            parts
                .iter()
                .map(|p| part(p, k).as_f64().unwrap_or(f64::NAN))
                .sum::<f64>()
        };
        assert_eq!(curve["pairs"].as_u64(), Some(11 * (nj as u64 + 1)));
        for k in ["detached_length", "normal_resultant"] {
            let (got, want) = (curve[k].as_f64().unwrap_or(f64::NAN), sum(k));
            assert!(
                (got - want).abs() <= 1e-12 * want.abs().max(1.0),
                "{k}: {got} {want}"
            );
        }
        let lowest = parts
            .iter()
            .map(|p| part(p, "min_normal_traction").as_f64().unwrap_or(f64::NAN))
            .fold(f64::INFINITY, f64::min);
        assert_eq!(curve["min_normal_traction"].as_f64(), Some(lowest));
    }
    // The abutments' reactions are the hypersingular rows of their held nodes, nodal forces
    // that the discrete problem balances exactly (with the element tractions integrated
    // instead, they balanced only to 0.86 / 0.34 / 0.17 % at 3 / 6 / 12 elements per joint).
    for (k, r) in abutment.iter().enumerate() {
        assert!(*r <= 1e-8, "abutment at nj = {}: {r:e}", [3, 6, 12][k]);
    }
}

#[test]
fn pier_blocks_balance_under_self_weight_and_wind() {
    let s = run("eq-pier", "pipelines/wall.toml", &[]);
    assert_eq!(s["status"], "converged");
    for k in 2..=8 {
        let b = format!("brick_{k}");
        let r = relative(&s, &b);
        assert!(r <= 1e-8, "{b}: relative imbalance {r:e}");
        // Wind 1.5 kN/m² on the 0.2 m left face: 0.3 kN/m to the right.
        let wind = load(&s, &b, "boundary left");
        assert!(
            (wind[0] - 0.3).abs() < 1e-9 && wind[1].abs() < 1e-12,
            "{wind:?}"
        );
    }
    // Joint k carries the weight of the 8 - k blocks above it (1.6 kN/m each) and their
    // wind (0.3 kN/m each): the nodal forces give both (to the solver tolerance, 1e-9).
    for k in 1..=7 {
        let on_top = load(
            &s,
            &format!("brick_{}", k + 1),
            &format!("interface joints[brick_{k}|brick_{}]", k + 1),
        );
        let above = (8 - k) as f64;
        assert!(
            (on_top[1] - 1.6 * above).abs() < 1e-7,
            "joint {k}: {on_top:?}"
        );
        assert!(
            (on_top[0] + 0.3 * above).abs() < 1e-7,
            "joint {k}: {on_top:?}"
        );
    }
    // The clamped block too: its reactions are the nodal forces of its held nodes.
    let r = relative(&s, "brick_1");
    assert!(r <= 1e-8, "brick_1: {r:e}");
}

#[test]
fn a_contact_solution_that_is_no_equilibrium_is_noted() {
    // Past overturning (wind 4 kN/m²: the resultant at the lowest joint falls 0.35 m from
    // the centre of a 0.4 m block) no equilibrium exists; whatever the contact stage
    // reports, the blocks above the clamped one cannot balance, and the run says so.
    let (code, s) = run_code(
        "eq-pier-over",
        "pipelines/wall.toml",
        &["boundary.left.tx=4.0"],
    );
    if code == 3 {
        // A contact stage that detects the mechanism itself fails the run instead.
        assert_ne!(s["status"], "converged");
        return;
    }
    let worst = (2..=8)
        .map(|k| relative(&s, &format!("brick_{k}")))
        .fold(0.0, f64::max);
    assert!(worst > 1e-3, "{worst}");
    let notes: Vec<&str> = s["notes"]
        .as_array()
        .map(|a| a.iter().filter_map(Value::as_str).collect())
        .unwrap_or_default();
    assert!(
        notes
            .iter()
            .any(|n| n.starts_with("equilibrium: 7 bodies") && n.contains("brick_2")),
        "{notes:?}"
    );
    // The balanced pier has no such note.
    let ok = run("eq-pier-ok", "pipelines/wall.toml", &[]);
    assert!(
        !ok["notes"].to_string().contains("equilibrium"),
        "{}",
        ok["notes"]
    );
}
