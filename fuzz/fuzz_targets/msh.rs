//! Any bytes given to the MSH reader give `Ok` or `Err`, never a panic, and an `Ok` mesh
//! only refers to nodes it holds.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(mesh) = sgbem::input::mesh::parse_msh(data, Path::new("fuzz.msh")) {
        let n = mesh.nodes.len();
        assert_eq!(mesh.node_tags.len(), n);
        assert!(mesh.nodes.iter().flatten().all(|c| c.is_finite()));
        assert!(mesh.lines.iter().flat_map(|l| l.nodes).all(|i| i < n));
        assert!(mesh.triangles.iter().flat_map(|t| t.nodes).all(|i| i < n));
        assert!(mesh
            .lines
            .iter()
            .all(|l| mesh.curves.contains_key(&l.curve)));
        assert!(mesh
            .triangles
            .iter()
            .all(|t| mesh.surfaces.contains_key(&t.surface)));
    }
});
