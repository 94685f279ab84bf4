//! Any bytes given to the mesh reader give a mesh or an error, never a panic, an abort or a
//! runaway allocation. See `fuzz/README.md`.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|bytes: &[u8]| {
    // Only the outcome's kind matters; the messages are formatted so that their code runs too.
    match internodes::mesh::read_msh_bytes(Path::new("fuzz.msh"), bytes) {
        Ok(mesh) => {
            let _ = internodes::mesh::MeshSummary(&mesh).to_string();
        }
        Err(e) => {
            let _ = e.to_string();
        }
    }
});
