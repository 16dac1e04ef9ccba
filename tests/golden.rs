//! Regression of every example's headline figures against golden JSON (`tests/golden/`):
//! each scene is meshed from its .geo and run through the command line; detached and closed
//! lengths, open pairs, the normal resultant and the peak compression of every interface must
//! match the golden values to 1e-6 relative (lengths, counts: exactly one element either way
//! is a failure). To refresh after a deliberate change, run the scene and copy the figures.

mod support;

use support::*;

const REL: f64 = 1e-6;

fn run_golden(scene: &str, geo: &str) {
    run_golden_with(scene, scene, geo, &[]);
}

/// `golden` names tests/golden/<golden>.json; `scene` pipelines/<scene>.toml, run with the
/// `--set` overrides `sets`.
fn run_golden_with(golden_name: &str, scene: &str, geo: &str, sets: &[&str]) {
    let golden: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(root().join(format!("tests/golden/{golden_name}.json"))).unwrap(),
    )
    .unwrap();
    let dir = tmpdir(&format!("golden-{golden_name}"));
    let msh = gmsh(
        &root().join(format!("geo/{geo}.geo")),
        &dir,
        "m.msh",
        false,
        &[],
    );
    let out = dir.join("out");
    let (code, _, err) = sgbem(
        &[
            "run",
            root()
                .join(format!("pipelines/{scene}.toml"))
                .to_str()
                .unwrap(),
            "--mesh",
            msh.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ]
        .into_iter()
        .chain(sets.iter().flat_map(|s| ["--set", *s]))
        .collect::<Vec<_>>(),
    );
    let scene = golden_name;
    assert_eq!(code, 0, "{scene}: {err}");
    let got: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(got["status"], golden["status"], "{scene}");
    let gi = golden["interfaces"].as_object().unwrap();
    for (name, fig) in gi {
        for (key, want) in fig.as_object().unwrap() {
            let (w, g) = (
                want.as_f64().unwrap(),
                got["interfaces"][name][key].as_f64().unwrap(),
            );
            let tol = REL * w.abs().max(1e-9);
            assert!(
                (w - g).abs() <= tol,
                "{scene}: {name}.{key} = {g}, golden {w}"
            );
        }
    }
}

#[test]
fn example_1_stick() {
    run_golden("beam_on_blocks", "beam_on_blocks");
}

#[test]
fn example_1_slide() {
    run_golden("beam_on_blocks_slide", "beam_on_blocks");
}

#[test]
fn example_2() {
    run_golden("clamped_beam_joint", "clamped_beam_joint");
}

#[test]
fn example_3_without_and_with_cohesion() {
    run_golden("vault_c0", "vault");
    run_golden_with(
        "vault_c0.4",
        "vault_c0",
        "vault",
        &["interface.*.cohesion=4.0"],
    );
}

#[test]
fn hertz_contact_patch_and_two_blocks() {
    run_golden("hertz_contact", "hertz_contact");
    run_golden("contact_patch", "contact_patch");
    run_golden("two_blocks", "two_blocks");
}
