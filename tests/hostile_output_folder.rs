//! The output folder holds one run's complete results, or a failure mark: failed and
//! concurrent runs, inputs inside the folder, the commit lock.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::case_builder::{Body, Dirichlet};
use common::hostile::{
    BINARY, assert_failed_without_results, case_failure, displacement_by_tag, exists, run_error,
    run_quiet, square_case, two_blocks_case,
};
use common::{Edit, fixture};
use internodes::run::{RunOptions, solve_case};

/// A folder holding `two_blocks_2d.msh` as `mesh` and the case `case` reading it, with the output
/// folder set to the folder itself (`output = "."`).
fn case_beside_its_outputs(mesh: &str, case: &str) -> (tempfile::TempDir, PathBuf, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let mesh_path = dir.path().join(mesh);
    std::fs::copy(fixture("two_blocks_2d.msh"), &mesh_path).unwrap();
    let case_path = dir.path().join(case);
    two_blocks_case(Path::new(mesh), "upper")
        .output(".")
        .write_to(&case_path);
    (dir, mesh_path, case_path)
}

/// Runs `internodes solve CASE --quiet` as a child process and kills it if it has not ended
/// within `limit` (`None` then): a run that waits forever fails the test instead of hanging it.
fn solve_within(case: &Path, limit: std::time::Duration) -> Option<std::process::Output> {
    let mut child = Command::new(BINARY)
        .args(["solve", case.to_str().unwrap(), "--quiet"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > limit {
            child.kill().unwrap();
            child.wait().unwrap();
            return None;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    Some(child.wait_with_output().unwrap())
}

#[test]
fn a_failed_run_removes_earlier_results_and_marks_the_folder() {
    let case = two_blocks_case(&fixture("two_blocks_2d.msh"), "upper");
    let (dir, good) = case.write();
    let out = dir.path().join("out");
    run_quiet(&good).unwrap();
    assert!(exists(&out, "solution.h5") && exists(&out, "summary.json"));

    // The same case, now failing in the solve of its second body.
    let bad = dir.path().join("bad.toml");
    case.residual_tolerance(1e-300).write_to(&bad);
    let e = run_error(&bad, "the tolerance cannot be met");
    assert_failed_without_results(&out, &e.to_string());

    // The next successful run removes the mark.
    run_quiet(&good).unwrap();
    assert!(exists(&out, "summary.json") && !exists(&out, "FAILED.txt"));
}

#[test]
fn runs_remove_only_their_own_files_from_the_output_folder() {
    // An output folder the user keeps other files in, also inside matrices/.
    let case = two_blocks_case(&fixture("two_blocks_2d.msh"), "upper").export_matrices();
    let (dir, good) = case.write();
    let out = dir.path().join("out");
    std::fs::create_dir_all(out.join("matrices")).unwrap();
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    std::fs::write(out.join("matrices/notes.txt"), "mine").unwrap();
    run_quiet(&good).unwrap();
    assert!(exists(&out, "matrices/lower_stiffness.mtx"));
    case.with_body("upper", |b| Body {
        name: "nowhere".to_string(),
        ..b
    })
    .write_to(&good);
    run_error(&good, "no body 'nowhere'");
    assert!(!exists(&out, "matrices/lower_stiffness.mtx"));
    assert!(exists(&out, "notes.txt") && exists(&out, "matrices/notes.txt"));
}

#[test]
fn a_case_file_that_does_not_parse_marks_the_folder_it_names() {
    let (dir, good) = two_blocks_case(&fixture("two_blocks_2d.msh"), "upper").write();
    run_quiet(&good).unwrap();
    // A misspelled key is no case the builder can describe: its text is edited.
    let text = std::fs::read_to_string(&good).unwrap();
    std::fs::write(&good, text.edit("poisson_ratio", "poison_ratio")).unwrap();
    let e = run_error(&good, "misspelled key");
    assert_failed_without_results(&dir.path().join("out"), "poison_ratio");
    assert!(e.to_string().contains("poison_ratio"));
}

#[test]
fn a_run_failing_after_writing_the_solution_leaves_no_result() {
    // The first run succeeds; the second writes solution.h5 and then fails exporting the
    // matrices of a body whose name is too long for a file name (250 bytes and
    // `_stiffness.mtx` exceed the 255 of Linux file systems).
    let (dir, good) = two_blocks_case(&fixture("two_blocks_2d.msh"), "upper").write();
    run_quiet(&good).unwrap();
    let long = "u".repeat(250);
    let mesh = dir.path().join("long.msh");
    let text = std::fs::read_to_string(fixture("two_blocks_2d.msh")).unwrap();
    std::fs::write(&mesh, text.replacen("\"upper\"", &format!("\"{long}\""), 1)).unwrap();
    let bad = dir.path().join("bad.toml");
    two_blocks_case(&mesh, &long)
        .export_matrices()
        .write_to(&bad);
    let e = run_error(&bad, "the file name is too long");
    assert!(e.to_string().contains("_stiffness.mtx"), "{e}");
    assert_failed_without_results(&dir.path().join("out"), &e.to_string());
}

#[test]
fn concurrent_runs_into_one_folder_leave_one_runs_complete_results() {
    // Two cases that differ in Young's modulus, run together into one folder, ten times.
    let dir = tempfile::tempdir().unwrap();
    let cases: Vec<PathBuf> = [100.0, 400.0]
        .iter()
        .map(|&e| {
            let path = dir.path().join(format!("e{e:?}.toml"));
            square_case("square_sorted.msh", &[1.0, 0.0])
                .with_body("square", |b| Body {
                    youngs_modulus: e,
                    ..b
                })
                .output("shared")
                .write_to(&path);
            path
        })
        .collect();
    let out = dir.path().join("shared");
    for _ in 0..10 {
        std::thread::scope(|s| {
            for case in &cases {
                s.spawn(move || run_quiet(case).unwrap());
            }
        });
        // The displacement scales with 1 / E: the HDF5 file and the summary are one run's.
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        let e = summary["bodies"][0]["youngs_modulus"].as_f64().unwrap();
        let u = displacement_by_tag(&out);
        let largest = u.values().map(|v| v[0].abs()).fold(0.0, f64::max);
        // E = 100 gives a largest ux of about 1e-2, E = 400 a quarter of it.
        assert!(
            (largest * e - 1.0).abs() < 0.5,
            "E = {e}, largest ux {largest}"
        );
        assert!(!exists(&out, "FAILED.txt"));
    }
}

#[test]
fn an_input_mesh_named_mesh_msh_in_the_output_folder_is_never_removed() {
    let original = std::fs::read(fixture("two_blocks_2d.msh")).unwrap();
    let (dir, mesh, case) = case_beside_its_outputs("mesh.msh", "case.toml");
    run_quiet(&case).unwrap();
    assert_eq!(
        std::fs::read(&mesh).unwrap(),
        original,
        "the input mesh was changed"
    );
    assert!(exists(dir.path(), "summary.json"));

    // --output naming the mesh's folder, and a second run over the first one's results.
    solve_case(
        &case,
        &RunOptions {
            output: Some(dir.path().to_owned()),
            quiet: true,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(
        std::fs::read(&mesh).unwrap(),
        original,
        "--output removed the input mesh"
    );

    // A case file that does not parse marks the folder, and the mesh stays.
    let text = std::fs::read_to_string(&case).unwrap();
    std::fs::write(&case, text.edit("youngs_modulus", "young_modulus")).unwrap();
    run_error(&case, "misspelled key");
    assert_failed_without_results(dir.path(), "young_modulus");
    assert_eq!(
        std::fs::read(&mesh).unwrap(),
        original,
        "a failed run removed the input mesh"
    );
}

#[test]
fn an_output_folder_holding_an_input_under_a_result_name_is_refused() {
    // The mesh saved as summary.json beside the case, output = ".": the run would replace it.
    let original = std::fs::read(fixture("two_blocks_2d.msh")).unwrap();
    let (dir, mesh, case) = case_beside_its_outputs("summary.json", "case.toml");
    let message = run_error(&case, "the mesh has a result's name").to_string();
    assert!(
        message.contains("summary.json")
            && message.contains("`output` key")
            && message.contains("case.toml"),
        "{message}"
    );
    assert_eq!(
        std::fs::read(&mesh).unwrap(),
        original,
        "the input mesh was changed"
    );
    assert!(!exists(dir.path(), "FAILED.txt") && !exists(dir.path(), "solution.h5"));

    // --output is named as such.
    let with_option = solve_case(
        &case,
        &RunOptions {
            output: Some(dir.path().to_owned()),
            quiet: true,
            ..Default::default()
        },
    );
    let Err(e) = with_option.map(|_| ()) else {
        panic!("--output holds the mesh under a result name");
    };
    let e = e.to_string();
    assert!(e.contains("--output") && e.contains("summary.json"), "{e}");

    // A case file named like the failure mark, that does not parse, is not overwritten by it.
    let (dir, _, case) = case_beside_its_outputs("lower.msh", "FAILED.txt");
    let broken = std::fs::read_to_string(&case)
        .unwrap()
        .edit("youngs_modulus", "young_modulus");
    std::fs::write(&case, &broken).unwrap();
    run_error(&case, "misspelled key");
    assert_eq!(
        std::fs::read_to_string(&case).unwrap(),
        broken,
        "the case file was overwritten"
    );
    assert!(exists(dir.path(), "lower.msh"));
}

#[test]
fn a_folder_named_as_the_commit_lock_is_an_error_naming_it() {
    // The run used to wait for it forever without a word.
    let (dir, case) = two_blocks_case(&fixture("two_blocks_2d.msh"), "upper").write();
    let lock = dir.path().join("out/.internodes-commit.lock");
    std::fs::create_dir_all(&lock).unwrap();
    let output = solve_within(&case, std::time::Duration::from_secs(20))
        .expect("the run must end at once, not wait for a folder to go away");
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains(&format!("the commit lock {} is a folder", lock.display()))
            && stderr.contains("rm -r"),
        "{stderr}"
    );
    assert!(lock.is_dir(), "the user's folder stays");
}

#[test]
fn a_commit_lock_dated_in_the_future_is_not_fresh_forever() {
    // A lock file left with a modification time a year ahead (a clock set back, a folder copied
    // from another machine) used to make every run wait for it forever.
    let (dir, case) = two_blocks_case(&fixture("two_blocks_2d.msh"), "upper").write();
    let out = dir.path().join("out");
    std::fs::create_dir_all(&out).unwrap();
    let lock = out.join(".internodes-commit.lock");
    let file = std::fs::File::create(&lock).unwrap();
    let year = std::time::Duration::from_secs(365 * 86_400);
    file.set_modified(std::time::SystemTime::now() + year)
        .unwrap();
    drop(file);
    let output = solve_within(&case, std::time::Duration::from_secs(20))
        .expect("the run must not wait for a lock dated in the future");
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(exists(&out, "summary.json") && !lock.exists());
}

#[test]
fn names_with_a_slash_are_refused_before_solving_when_matrices_are_exported() {
    // Body and group names go into matrices/<body>_stiffness.mtx and
    // matrices/<body>__<group>_mass.mtx: 'up/per' once failed after the solve, and a group
    // '../../base' would write outside the output folder.
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(fixture("two_blocks_2d.msh")).unwrap();
    let body_mesh = dir.path().join("body.msh");
    std::fs::write(&body_mesh, text.replacen("\"upper\"", "\"up/per\"", 1)).unwrap();
    let message = case_failure(&two_blocks_case(&body_mesh, "up/per").export_matrices());
    assert!(
        message.contains("body 'up/per', export_matrices")
            && message.contains("matrices/up/per_stiffness.mtx")
            && message.contains("rename"),
        "{message}"
    );

    let group_mesh = dir.path().join("group.msh");
    std::fs::write(
        &group_mesh,
        text.replacen("\"lower_base\"", "\"../../base\"", 1),
    )
    .unwrap();
    let with_group =
        two_blocks_case(&group_mesh, "upper").with_support("lower", "lower_base", |d| Dirichlet {
            group: "../../base".to_string(),
            ..d
        });
    let message = case_failure(&with_group.clone().export_matrices());
    assert!(
        message.contains("group '../../base'") && message.contains("lower__../../base_mass.mtx"),
        "{message}"
    );
    // Without the export the names are fine: the solution files do not use them as paths.
    let (_dir, path) = with_group.write();
    run_quiet(&path).unwrap();
}
