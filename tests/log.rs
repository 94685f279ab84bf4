//! The log of `internodes solve` at each level (docs/output.md, "The log"): the demo's default
//! log fits a screen with no line over 120 characters, `-v` adds the active-set iterations
//! and the checks, `-vv` the coupled GMRES solves, `--quiet` prints nothing on success.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::contact::half_disc_on_block;

const BINARY: &str = env!("CARGO_BIN_EXE_internodes");

/// `internodes solve CASE --output OUT` with `flags`: the exit status must be 0; its stderr.
fn solve(case: &Path, output: &Path, flags: &[&str]) -> String {
    let run = Command::new(BINARY)
        .args(["solve", case.to_str().unwrap(), "--output"])
        .arg(output)
        .args(flags)
        .output()
        .unwrap();
    let stderr = String::from_utf8(run.stderr).unwrap();
    assert!(run.status.success(), "{flags:?}: {stderr}");
    assert!(run.stdout.is_empty(), "{flags:?}: the log goes to stderr");
    stderr
}

fn count(log: &str, pattern: &str) -> usize {
    log.lines().filter(|l| l.contains(pattern)).count()
}

/// `line` with each run of digits as one `#`: the lines of two runs, whatever their times.
fn shape(line: &str) -> String {
    let mut shape = String::new();
    for c in line.chars() {
        match c.is_ascii_digit() {
            true if shape.ends_with('#') => {}
            true => shape.push('#'),
            false => shape.push(c),
        }
    }
    shape
}

#[test]
fn the_demo_log_fits_a_screen() {
    // `make demo`'s case: five load steps of the hemisphere, meshed by gmsh.
    let case = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("geo/hemisphere_on_block.toml");
    let dir = tempfile::tempdir().unwrap();
    let log = solve(&case, &dir.path().join("out"), &[]);
    let lines: Vec<&str> = log.lines().collect();
    assert!(lines.len() <= 25, "{} lines:\n{log}", lines.len());
    for line in &lines {
        assert!(
            line.chars().count() <= 120,
            "{} characters: {line}",
            line.len()
        );
    }
    // No carriage return: a pipe gets plain lines.
    assert!(!log.contains('\r'), "{log:?}");
    // One line per load step, with its status, force, contact size, iterations and time.
    for k in 1..=5 {
        let step = (lines.iter())
            .find(|l| l.starts_with(&format!("load step {k}/5 (factor ")))
            .unwrap_or_else(|| panic!("no line of step {k}:\n{log}"));
        for word in [
            "converged in ",
            " iterations; force ",
            " contact nodes; ",
            " s",
        ] {
            assert!(step.contains(word), "{word:?} not in {step}");
        }
    }
    // The accuracy report in one line; nothing of the -v detail.
    assert_eq!(count(&log, "accuracy report"), 1, "{log}");
    assert!(
        log.contains("accuracy report: passed; not estimated: "),
        "{log}"
    );
    for detail in ["iteration ", "checks", "coupled GMRES", "Hertz fit"] {
        assert_eq!(
            count(&log, detail),
            0,
            "{detail:?} at the default level:\n{log}"
        );
    }
}

#[test]
fn each_level_adds_its_detail_and_quiet_prints_nothing() {
    let (dir, path) = half_disc_on_block().load_steps(&[0.5, 1.0]).write();
    let out = dir.path().join("out");
    let default = solve(&path, &out, &[]);
    let verbose = solve(&path, &out, &["-v"]);
    let very = solve(&path, &out, &["--verbose", "--verbose"]);
    assert_eq!(solve(&path, &out, &["--quiet"]), "");

    // The default: a line per step, no iteration, check or Krylov line.
    assert_eq!(count(&default, "load step "), 2, "{default}");
    assert_eq!(count(&default, "iteration "), 0, "{default}");
    assert_eq!(count(&default, "coupled GMRES"), 0, "{default}");
    // -v: the default's lines, each step's header, iterations and checks; no Krylov line.
    let verbose_lines: Vec<String> = verbose.lines().map(shape).collect();
    for line in default.lines() {
        assert!(
            verbose_lines.contains(&shape(line)),
            "{line:?} not in the -v log:\n{verbose}"
        );
    }
    assert_eq!(count(&verbose, "load step 2/2: factor 1"), 1, "{verbose}");
    let iterations = count(&verbose, "  iteration ");
    assert!(iterations >= 2, "{verbose}");
    assert_eq!(count(&verbose, "  checks:"), 2, "{verbose}");
    assert!(verbose.contains("    penetration "), "{verbose}");
    assert!(verbose.contains(" not estimated: "), "{verbose}");
    assert_eq!(count(&verbose, "coupled GMRES"), 0, "{verbose}");
    assert!(!verbose.contains("(operators "), "{verbose}");
    // -vv: the same iterations, with their phases, and the coupled GMRES solves.
    assert_eq!(count(&very, "  iteration "), iterations, "{very}");
    assert_eq!(count(&very, "(operators "), iterations, "{very}");
    assert!(count(&very, "coupled GMRES: ") >= iterations, "{very}");
}

#[test]
fn quiet_and_verbose_do_not_go_together() {
    let (dir, path) = half_disc_on_block().write();
    let run = Command::new(BINARY)
        .args(["solve", path.to_str().unwrap(), "-q", "-v", "--output"])
        .arg(dir.path().join("out"))
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&run.stderr).starts_with("error:"));
}
