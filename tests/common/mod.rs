//! Shared helpers of the integration tests.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

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

/// A case file with `text`, written to a fresh temporary folder (kept alive by the returned
/// guard; relative output paths land inside it).
pub fn write_case(text: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().expect("temporary folder");
    let path = dir.path().join("case.toml");
    std::fs::write(&path, text).expect("write the case file");
    (dir, path)
}

/// Runs `internodes solve CASE --quiet`.
pub fn run_solve(case: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_internodes"))
        .args(["solve", case.to_str().expect("UTF-8 path"), "--quiet"])
        .output()
        .expect("run the internodes binary")
}
