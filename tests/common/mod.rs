//! Shared helpers of the integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

use internodes::mesh::{Mesh, read_msh};

/// A committed mesh from `tests/fixtures/` (generated from `geo/`; see its README).
pub fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

pub fn read_fixture(name: &str) -> Mesh {
    read_msh(&fixture(name)).unwrap_or_else(|e| panic!("fixture {name}: {e}"))
}

/// A fixture with `edit` applied to its text, written to a fresh temporary folder.
pub fn edited_fixture(
    name: &str,
    edit: impl FnOnce(String) -> String,
) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().expect("temporary folder");
    let text = std::fs::read_to_string(fixture(name)).expect("ASCII fixture");
    let path = dir.path().join(name);
    std::fs::write(&path, edit(text)).expect("write edited fixture");
    (dir, path)
}
