//! Helpers of the hostile-input tests: running a case in process or as the binary, and the
//! small cases they break.

use std::collections::HashMap;
use std::path::Path;

use super::case_builder::{Body, CaseFile, Dirichlet, Load};
use internodes::run::{RunError, RunOptions, solve_case};

pub const BINARY: &str = env!("CARGO_BIN_EXE_internodes");

pub fn run_quiet(case: &Path) -> Result<internodes::run::RunReport, RunError> {
    solve_case(
        case,
        &RunOptions {
            quiet: true,
            ..Default::default()
        },
    )
}

/// The error of a case file that must fail; `why` says why it must.
pub fn run_error(case: &Path, why: &str) -> RunError {
    match run_quiet(case) {
        Ok(_) => panic!("{} should fail: {why}", case.display()),
        Err(e) => e,
    }
}

/// The message of a case that must fail.
pub fn case_failure(case: &CaseFile) -> String {
    let (_dir, path) = case.write();
    match run_quiet(&path) {
        Ok(_) => panic!("the case should fail:\n{}", case.to_toml()),
        Err(e) => e.to_string(),
    }
}

/// The two bodies of `two_blocks_2d.msh` (or an edit of it at `mesh`), each supported on its
/// own, the lower one loaded on its contact surface; the second is named `upper`.
pub fn two_blocks_case(mesh: &Path, upper: &str) -> CaseFile {
    CaseFile::new(mesh)
        .body(
            Body::new("lower", 1000.0, 0.3)
                .dirichlet(Dirichlet::clamped("lower_base", 2))
                .load(Load::traction("lower_contact", &[0.0, -1.0])),
        )
        .body(Body::new(upper, 1000.0, 0.3).dirichlet(Dirichlet::clamped("upper_top", 2)))
}

/// The unit square of `square_*.msh`: clamped on `left`, pulled by `traction` on `right`.
pub fn square_case(mesh: &str, traction: &[f64]) -> CaseFile {
    CaseFile::on_fixture(mesh).body(
        Body::new("square", 100.0, 0.25)
            .dirichlet(Dirichlet::clamped("left", 2))
            .load(Load::traction("right", traction)),
    )
}

/// Displacement of every node of `solution.h5` in `dir`, by gmsh node tag. Opened without HDF5's
/// file lock: the concurrent-runs test runs its solves as threads of this process, which share one
/// HDF5 library, and opening a file that a just-finished run of this process wrote failed once in
/// nine runs on the lock (EAGAIN); separate `internodes` processes do not meet this.
pub fn displacement_by_tag(dir: &Path) -> HashMap<i64, Vec<f64>> {
    let file = hdf5::File::with_options()
        .with_fapl(|p| p.file_locking(false))
        .open(dir.join("solution.h5"))
        .unwrap();
    let tags: Vec<i64> = file.dataset("mesh/node_tag").unwrap().read_raw().unwrap();
    let u: Vec<f64> = file
        .dataset("fields/displacement")
        .unwrap()
        .read_raw()
        .unwrap();
    let width = u.len() / tags.len();
    tags.into_iter()
        .zip(u.chunks(width).map(<[f64]>::to_vec))
        .collect()
}

pub fn exists(dir: &Path, name: &str) -> bool {
    dir.join(name).exists()
}

/// Asserts that `out` holds no result file and a failure mark naming `what`.
pub fn assert_failed_without_results(out: &Path, what: &str) {
    for name in internodes::output::RESULT_FILES {
        assert!(!exists(out, name), "{name} left in {}", out.display());
    }
    let mark = std::fs::read_to_string(out.join("FAILED.txt")).expect("FAILED.txt");
    assert!(mark.contains(what), "{mark}");
    let leftovers: Vec<_> = std::fs::read_dir(out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".internodes"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}
