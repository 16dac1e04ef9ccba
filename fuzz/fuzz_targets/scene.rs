//! Any text given to the scene reader gives `Ok` or `Err`, never a panic; an `Ok` scene
//! holds only valid values.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(s) = sgbem::input::scene::parse_scene(text, Path::new("fuzz/scene.toml")) {
        assert!(!s.bodies.is_empty());
        for b in &s.bodies {
            assert!(b.young > 0.0 && b.poisson > -1.0 && b.poisson <= 0.5);
        }
        assert!(s.thickness > 0.0);
        assert!(!s.solve.load_factors.is_empty());
        for sec in &s.output.sections {
            assert!(sec.points >= 2);
        }
        // Expressions evaluate to a number or NaN, never panic.
        for b in &s.boundaries {
            for c in &b.components {
                let (sgbem::input::scene::Condition::Displacement(v)
                | sgbem::input::scene::Condition::Traction(v)) = c;
                let _ = v.eval([0.3, -1.7]);
            }
        }
    }
});
