//! The command line and the case file, end to end: a solve writes readable results, and every
//! kind of bad case gets an error that names the file and the key, group or body at fault.

mod common;

use std::path::Path;
use std::process::Command;

use common::case_builder::{Body, CaseFile, Dirichlet, Load};
use common::{Edit, block_3d_case, fixture, write_case};
use internodes::case::CaseError;
use internodes::elastic::{ProblemError, SolveError};
use internodes::fem::MaterialError;
use internodes::run::{RunError, RunOptions, solve_case};

const BINARY: &str = env!("CARGO_BIN_EXE_internodes");

fn run_quiet(case: &Path) -> Result<internodes::run::RunReport, RunError> {
    solve_case(
        case,
        &RunOptions {
            quiet: true,
            ..Default::default()
        },
    )
}

/// The `block_3d` case with `change` applied to its body.
fn block_with(change: impl FnOnce(Body) -> Body) -> CaseFile {
    block_3d_case().with_body("block", change)
}

/// Runs a case that must fail and returns the error and its message.
fn failure(case: &CaseFile) -> (RunError, String) {
    text_failure(&case.to_toml())
}

/// [`failure`] of a case file given as text.
fn text_failure(text: &str) -> (RunError, String) {
    let (_dir, path) = write_case(text);
    let e = match run_quiet(&path) {
        Ok(_) => panic!("the case should fail:\n{text}"),
        Err(e) => e,
    };
    let message = e.to_string();
    assert!(
        message.contains("case.toml"),
        "the error names the case file: {message}"
    );
    (e, message)
}

#[test]
fn solve_writes_xdmf_hdf5_and_summary() {
    let (dir, path) = block_3d_case().write();
    let output = Command::new(BINARY)
        .args(["solve", path.to_str().unwrap(), "--export-matrices", "-v"])
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("body 'block': ") && stderr.contains("numeric factorization"),
        "the body and, with -v, the phases of its solve are reported: {stderr}"
    );

    let out = dir.path().join("out");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let body = &summary["bodies"][0];
    assert_eq!(body["name"], "block");
    let num_nodes = body["num_nodes"].as_u64().unwrap() as usize;
    let reaction_z = body["reactions"]["block_base"][2].as_f64().unwrap();
    assert!(
        reaction_z > 0.0,
        "the base pushes up against a downward load"
    );

    let file = hdf5::File::open(out.join("solution.h5")).unwrap();
    let u = file.dataset("fields/displacement").unwrap();
    assert_eq!(u.shape(), vec![num_nodes, 3]);
    assert_eq!(file.dataset("mesh/topology").unwrap().shape()[1], 4);
    assert_eq!(file.dataset("fields/stress").unwrap().shape()[1], 9);
    let tags: Vec<i64> = file.dataset("mesh/node_tag").unwrap().read_raw().unwrap();
    assert_eq!(tags.len(), num_nodes);

    let xdmf = std::fs::read_to_string(out.join("solution.xdmf")).unwrap();
    assert!(
        xdmf.contains("TopologyType=\"Tetrahedron\"")
            && xdmf.contains("solution.h5:/fields/displacement")
    );
    for matrix in [
        "block_stiffness.mtx",
        "block__block_base_mass.mtx",
        "block__block_top_mass.mtx",
    ] {
        let text = std::fs::read_to_string(out.join("matrices").join(matrix)).unwrap();
        assert!(text.starts_with("%%MatrixMarket matrix coordinate real general"));
    }
}

#[test]
fn info_prints_groups_and_counts() {
    let output = Command::new(BINARY)
        .args(["info", fixture("two_blocks_2d.msh").to_str().unwrap()])
        .output()
        .unwrap();
    assert!(output.status.success());
    let text = String::from_utf8_lossy(&output.stdout);
    assert!(
        text.contains("body 'lower': 58 nodes, 90 triangles"),
        "{text}"
    );
    assert!(
        text.contains("boundary 'upper_contact'") && text.contains("bounding box"),
        "{text}"
    );
}

#[test]
fn cli_reports_errors_with_a_failure_status() {
    // A misspelled key is no case the builder can describe: its text is edited.
    let (_dir, path) = write_case(
        &block_3d_case()
            .to_toml()
            .edit("youngs_modulus", "youngs_modulu"),
    );
    let output = Command::new(BINARY)
        .args(["solve", path.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.starts_with("error: case file") && stderr.contains("youngs_modulu"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"));
}

#[test]
fn misspelled_key_names_the_key_and_line() {
    let (e, message) = text_failure(
        &block_3d_case()
            .to_toml()
            .edit("poisson_ratio", "poison_ratio"),
    );
    assert!(matches!(e, RunError::Case(CaseError::Syntax { .. })));
    assert!(
        message.contains("poison_ratio") && message.contains("line 7"),
        "{message}"
    );
}

#[test]
fn missing_key_is_named() {
    let (e, message) = text_failure(&block_3d_case().to_toml().edit("poisson_ratio = 0.3\n", ""));
    assert!(matches!(e, RunError::Case(CaseError::Syntax { .. })));
    assert!(message.contains("poisson_ratio"), "{message}");
}

#[test]
fn non_physical_materials_are_rejected() {
    let (e, message) = failure(&block_with(|b| Body {
        youngs_modulus: 0.0,
        ..b
    }));
    assert!(
        matches!(
            e,
            RunError::Case(CaseError::Material {
                source: MaterialError::YoungsModulus(_),
                ..
            })
        ),
        "{message}"
    );
    assert!(message.contains("body 'block'"));
    let (e, message) = failure(&block_with(|b| Body {
        poisson_ratio: 0.5,
        ..b
    }));
    assert!(
        matches!(
            e,
            RunError::Case(CaseError::Material {
                source: MaterialError::PoissonRatio(_),
                ..
            })
        ),
        "{message}"
    );
    let (e, _) = failure(&block_with(|b| Body {
        poisson_ratio: -1.2,
        ..b
    }));
    assert!(matches!(e, RunError::Case(CaseError::Material { .. })));
}

#[test]
fn unknown_group_lists_the_groups_of_the_body() {
    let (e, message) = failure(&block_with(|b| Body {
        loads: vec![Load::hertz("block_tpo", 10.0, 0.5, &[0.0, 0.0, 0.0])],
        ..b
    }));
    assert!(matches!(
        e,
        RunError::Case(CaseError::Problem {
            source: ProblemError::UnknownGroup { .. },
            ..
        })
    ));
    assert!(
        message.contains("block_tpo") && message.contains("block_base, block_sides, block_top"),
        "{message}"
    );
}

#[test]
fn unknown_body_lists_the_bodies_of_the_mesh() {
    let (e, message) = failure(&block_with(|b| Body {
        name: "sphere".to_string(),
        ..b
    }));
    assert!(matches!(e, RunError::Case(CaseError::UnknownBody { .. })));
    assert!(
        message.contains("'sphere'") && message.contains("its bodies: block"),
        "{message}"
    );
}

#[test]
fn a_body_without_dirichlet_condition_is_singular() {
    let (e, message) = failure(&block_with(|b| Body {
        dirichlet: Vec::new(),
        ..b
    }));
    assert!(
        matches!(
            e,
            RunError::Case(CaseError::Problem {
                source: ProblemError::NoDirichlet { .. },
                ..
            })
        ),
        "{message}"
    );
    assert!(message.contains("singular"));
}

#[test]
fn dirichlet_conditions_that_leave_rigid_motions_free_are_singular() {
    // Only uz = 0 on the flat base: translations in x, y and the rotation about z are free.
    let (e, message) = failure(&block_3d_case().with_support("block", "block_base", |_| {
        Dirichlet::on("block_base").uz(0.0)
    }));
    assert!(
        matches!(
            e,
            RunError::Case(CaseError::Problem {
                source: ProblemError::FreeRigidModes { count: 3, .. },
                ..
            })
        ),
        "{message}"
    );
}

#[test]
fn a_load_must_have_exactly_one_kind() {
    let mut case = block_3d_case();
    case.bodies[0].loads[0].pressure = Some(1.0);
    let (e, message) = failure(&case);
    assert!(matches!(e, RunError::Case(CaseError::Invalid { .. })));
    assert!(
        message.contains("exactly one of") && message.contains("load on 'block_top'"),
        "{message}"
    );
}

#[test]
fn vectors_must_match_the_mesh_dimension() {
    let (e, message) = failure(&block_with(|b| Body {
        loads: vec![Load::hertz("block_top", 10.0, 0.5, &[0.0, 0.0])],
        ..b
    }));
    assert!(matches!(e, RunError::Case(CaseError::Invalid { .. })));
    assert!(message.contains("expected 3 components"), "{message}");
}

#[test]
fn a_bad_mesh_is_reported_through_the_case() {
    let mut case = block_3d_case();
    case.mesh = fixture("no_such.msh");
    let (e, message) = failure(&case);
    assert!(matches!(e, RunError::Case(CaseError::Mesh { .. })));
    assert!(message.contains("no_such.msh"), "{message}");
}

#[test]
fn inaccurate_solves_are_errors_not_results() {
    // A residual tolerance below round-off cannot be met: the solve must say so.
    let (e, message) = failure(&block_3d_case().residual_tolerance(1e-30));
    assert!(
        matches!(
            e,
            RunError::Solve {
                source: SolveError::Inaccurate { .. },
                ..
            }
        ),
        "{message}"
    );
}

#[test]
fn the_output_folder_may_come_from_the_flag_alone() {
    // `output` used to be required in the case file even with --output.
    let (dir, path) = block_3d_case().without_output().write();
    let out = dir.path().join("elsewhere");
    let output = Command::new(BINARY)
        .args(["solve", path.to_str().unwrap(), "--quiet", "--output"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(out.join("summary.json").exists() && out.join("solution.h5").exists());
}

#[test]
fn without_the_output_key_or_flag_the_error_names_both() {
    let (e, message) = failure(&block_3d_case().without_output());
    assert!(
        matches!(e, RunError::Case(CaseError::Invalid { .. })),
        "{message}"
    );
    assert!(
        message.contains("`output` key") && message.contains("--output"),
        "{message}"
    );
}

#[test]
fn usage_errors_exit_1_with_the_message_of_the_command_line_parser_and_help_exits_0() {
    // Exit 2 says "contact not solved"; a command line the parser refuses is an error (1).
    for args in [
        &["solve", "--bogus", "case.toml"][..],
        &["solve"][..],
        &["study", "case.toml", "--parameter", "level"][..],
        &["frobnicate"][..],
    ] {
        let output = Command::new(BINARY).args(args).output().unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(stderr.starts_with("error:"), "{args:?}: {stderr}");
    }
    let help = Command::new(BINARY).arg("--help").output().unwrap();
    assert_eq!(help.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&help.stdout).contains("solve"));
}
