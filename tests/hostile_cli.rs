//! The command line under hostile conditions: closed pipes, an error with causes, output that
//! must stay valid JSON.

mod common;

use std::process::Command;

use common::case_builder::Dirichlet;
use common::fixture;
use common::hostile::{BINARY, run_quiet, square_case, two_blocks_case};

#[test]
fn info_into_a_closed_pipe_does_not_panic() {
    // `internodes info m.msh | head -1`: the reader stops early.
    let mut child = Command::new(BINARY)
        .args(["info", fixture("two_blocks_3d.msh").to_str().unwrap()])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let output = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn solve_into_a_closed_stderr_pipe_does_not_panic() {
    // `internodes solve case 2>&1 | head -1`: the progress lines meet a closed pipe. A panic
    // exits with status 101; the process must end by SIGPIPE (or finish) instead.
    let (_dir, case) = common::half_disc_on_block("half_disc_on_block.msh").write();
    let mut child = Command::new(BINARY)
        .args(["solve", case.to_str().unwrap()])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stderr.take());
    let status = child.wait().unwrap();
    assert_ne!(status.code(), Some(101), "{status:?}");
}

#[test]
fn exporting_matrices_with_a_dirichlet_point_group_does_not_panic() {
    let (dir, path) = two_blocks_case(&fixture("two_blocks_2d.msh"), "upper")
        .export_matrices()
        .with_support("upper", "upper_top", |_| Dirichlet::on("upper_top").uy(0.0))
        .support("upper", Dirichlet::on("upper_corner").ux(0.0))
        .write();
    run_quiet(&path).unwrap();
    let matrices = dir.path().join("out/matrices");
    assert!(matrices.join("upper__upper_top_mass.mtx").exists());
    assert!(!matrices.join("upper__upper_corner_mass.mtx").exists());
}

#[test]
fn an_error_and_its_causes_are_printed_once() {
    // The case error quotes the mesh error, which quotes the I/O error: each once on stderr and
    // in the failure mark (every cause used to be printed again under its own message).
    let mut square = square_case("square_sorted.msh", &[1.0, 0.0]);
    square.mesh = "missing.msh".into();
    let (dir, case) = square.write();
    std::fs::create_dir(dir.path().join("out")).unwrap();
    let output = Command::new(BINARY)
        .args(["solve", case.to_str().unwrap(), "--quiet"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    let mark = std::fs::read_to_string(dir.path().join("out/FAILED.txt")).unwrap();
    for text in [stderr.as_ref(), mark.as_str()] {
        assert_eq!(text.matches("cannot read mesh file").count(), 1, "{text}");
        assert_eq!(
            text.matches("No such file or directory").count(),
            1,
            "{text}"
        );
        assert!(!text.contains("caused by"), "{text}");
    }
}

#[test]
fn bodies_pulled_apart_leave_no_null_in_the_iteration_history() {
    // The upper block is lifted off the lower one: the first iteration finds every active node
    // in tension and none compressed, and its tension over the largest pressure was
    // p / f64::MIN_POSITIVE = inf, written as `null` into summary.json.
    let case = two_blocks_case(&fixture("two_blocks_2d.msh"), "upper")
        .contact(["upper", "lower"], ["upper_contact", "lower_contact"])
        .with_support("upper", "upper_top", |d| d.uy(0.01));
    let text = case.to_toml();
    assert!(text.contains("uy = 0.01"), "{text}");
    let (dir, case) = case.write();
    run_quiet(&case).unwrap();
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("out/summary.json")).unwrap(),
    )
    .unwrap();
    let contact = &summary["contact"];
    assert_eq!(contact["status"], "no-contact");
    let iterations = contact["iterations"].as_array().unwrap();
    assert!(!iterations.is_empty());
    // The first iteration starts with every facing node active (all of them then in tension).
    assert!(
        iterations[0]["removed"].as_u64().unwrap() > 0,
        "{iterations:?}"
    );
    for record in iterations {
        for (key, value) in record.as_object().unwrap() {
            assert!(!value.is_null(), "{key} is null in {record}");
        }
        let tension = record["max_tension_over_p"].as_f64().unwrap();
        assert!((0.0..=1.0).contains(&tension), "{record}");
    }
}
