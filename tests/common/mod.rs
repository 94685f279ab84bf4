//! Shared helpers of the integration tests.
#![allow(dead_code)]

pub mod case_builder;
pub mod contact;
pub mod hostile;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use case_builder::{Body, CaseFile, Dirichlet, Load};
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

/// `text` (an ASCII MSH 4.1 file) with the physical tags of every entity of dimension `dim`
/// removed from `$Entities`: its elements then belong to no physical group.
pub fn without_physical_tags(text: &str, dim: usize) -> String {
    let start = text.find("$Entities").expect("an $Entities section");
    let end = text.find("$EndEntities").expect("an $EndEntities line");
    let mut lines: Vec<String> = text[start..end].lines().map(str::to_string).collect();
    let counts: Vec<usize> = lines[1]
        .split_whitespace()
        .map(|c| c.parse().unwrap())
        .collect();
    // Points, curves, surfaces, volumes, one line each, after the section name and the counts.
    let first = 2 + counts[..dim].iter().sum::<usize>();
    for line in &mut lines[first..first + counts[dim]] {
        let mut parts: Vec<&str> = line.split_whitespace().collect();
        // tag, 6 bounding box values (3 for points), number of physical tags, the tags, ...
        let at = if dim == 0 { 4 } else { 7 };
        let n: usize = parts[at].parse().unwrap();
        parts.drain(at + 1..at + 1 + n);
        parts[at] = "0";
        *line = parts.join(" ");
    }
    format!("{}{}\n{}", &text[..start], lines.join("\n"), &text[end..])
}

/// Edits of a case's text that must apply: a replacement that matches nothing would leave the
/// case as it was, and the test would check something else than it says.
pub trait Edit {
    /// The text with every `from` replaced by `to`; panics when `from` does not occur.
    fn edit(&self, from: &str, to: &str) -> String;
}

impl Edit for str {
    fn edit(&self, from: &str, to: &str) -> String {
        assert!(
            self.contains(from),
            "the case has no {from:?} to replace:\n{self}"
        );
        self.replace(from, to)
    }
}

/// A case file with `text`, written to a fresh temporary folder (kept alive by the returned
/// guard; relative output paths land inside it).
pub fn write_case(text: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().expect("temporary folder");
    let path = dir.path().join("case.toml");
    std::fs::write(&path, text).expect("write the case file");
    (dir, path)
}

/// Runs `case` through the CLI, which must succeed: its folder (kept alive by the guard; the
/// case writes into `out/` there) and its `summary.json`.
pub fn run_to_summary(case: &case_builder::CaseFile) -> (tempfile::TempDir, serde_json::Value) {
    let (dir, path) = case.write();
    let output = run_solve(&path);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    let text = std::fs::read_to_string(dir.path().join("out/summary.json")).unwrap();
    (dir, serde_json::from_str(&text).unwrap())
}

/// Runs `internodes solve CASE --quiet`.
pub fn run_solve(case: &Path) -> Output {
    run_solve_with(case, &[])
}

/// Runs `internodes solve CASE --quiet` with extra environment variables.
pub fn run_solve_with(case: &Path, env: &[(&str, &str)]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_internodes"))
        .args(["solve", case.to_str().expect("UTF-8 path"), "--quiet"])
        .envs(env.iter().copied())
        .output()
        .expect("run the internodes binary")
}

/// A valid 3D case on the `block_3d` fixture: the block clamped at its base under a Hertzian
/// pressure on its top.
pub fn block_3d_case() -> CaseFile {
    CaseFile::on_fixture("block_3d.msh").body(
        Body::new("block", 1000.0, 0.3)
            .dirichlet(Dirichlet::clamped("block_base", 3))
            .load(Load::hertz("block_top", 10.0, 0.5, &[0.0, 0.0, 0.0])),
    )
}

/// The contact case of `geo/half_disc_on_block.toml` on the fixture `mesh`: the half-disc
/// (R = 1) pressed by 0.02 onto the block, both E = 1000, nu = 0.3, the disc primary.
pub fn half_disc_on_block(mesh: &str) -> CaseFile {
    CaseFile::on_fixture(mesh)
        .contact(["disc", "block"], ["disc_contact", "block_contact"])
        .primary("disc")
        .body(Body::new("disc", 1000.0, 0.3).dirichlet(Dirichlet::on("disc_top").ux(0.0).uy(-0.02)))
        .body(Body::new("block", 1000.0, 0.3).dirichlet(Dirichlet::clamped("block_base", 2)))
}
