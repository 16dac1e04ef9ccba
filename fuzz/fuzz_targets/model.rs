//! Any MSH bytes, read with a fixed scene for the fixture `tests/fixtures/two_squares.geo`,
//! give a model or an input error, never a panic; a model's interface pairs refer to nodes
//! of their bodies.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

const SCENE: &str = r#"
plane = "strain"
[body.left]
young = 1.0
poisson = 0.3
[body.right]
young = 2.0
poisson = 0.25
[boundary.clamp]
ux = 0.0
uy = "0.01*y"
[boundary.free]
tn = "-x"
[interface.interface]
model = "unilateral"
"#;

fuzz_target!(|data: &[u8]| {
    let Ok(scene) = sgbem::input::scene::parse_scene(SCENE, Path::new("fuzz/scene.toml")) else {
        return;
    };
    let Ok(mesh) = sgbem::input::mesh::parse_msh(data, Path::new("fuzz.msh")) else {
        return;
    };
    if let Ok(model) = sgbem::input::model::build(&scene, &mesh, Path::new("fuzz.msh")) {
        for it in &model.interfaces {
            let (a, b) = (&model.bodies[it.body_a], &model.bodies[it.body_b]);
            for p in &it.pairs {
                assert!(p.node_a < a.nodes.len() && p.node_b < b.nodes.len());
                assert!(p.normal[0].is_finite() && p.normal[1].is_finite());
            }
        }
        for b in &model.bodies {
            assert!(b.area > 0.0);
            assert_eq!(b.dofs.len(), b.nodes.len());
        }
        let _ = sgbem::plan::plan(&scene, &model);
    }
});
