//! Any bytes given as an archive to `inspect` and to the VTK export give `Ok` or `Err`,
//! never a panic. (A crash or a hang inside libhdf5 is what the command line contains in
//! its child process; this target finds them.)
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let dir = std::env::temp_dir().join(format!("sgbem-fuzz-archive-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let file = dir.join("archive.h5");
    if std::fs::write(&file, data).is_err() {
        return;
    }
    if let Ok(text) = sgbem::output::archive::inspect(&file) {
        assert!(!text.is_empty());
    }
    let _ = sgbem::output::vtk::export(&file, &dir.join("vtk"));
});
