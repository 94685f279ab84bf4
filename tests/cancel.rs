//! A contact solve whose `Cancel` token is cancelled stops with `ContactError::Cancelled`, from
//! the library's own API (the Python module's Ctrl-C and `Cancel` rest on it); a run cancelled
//! so, or the command line stopped by Ctrl-C, leaves a failure mark and no staging folder.

mod common;

use std::time::{Duration, Instant};

use common::contact::half_disc_on_block;
use internodes::cancel::Cancel;
use internodes::case::Case;
use internodes::contact::{ContactError, solve_contact};
use internodes::elastic::SolverSettings;
use internodes::mesh::{Mesh, read_msh};

/// The half-disc on the block, its mesh, and quiet solver settings with a fresh token.
fn half_disc_with_a_token() -> (Case, Mesh, SolverSettings) {
    let (_dir, path) = half_disc_on_block().write();
    let case = Case::load(&path).unwrap();
    let mesh = read_msh(&case.mesh).unwrap();
    let settings = SolverSettings {
        verbose: false,
        cancel: Cancel::new(),
        ..case.solver.clone()
    };
    (case, mesh, settings)
}

#[test]
fn a_cancelled_token_stops_the_contact_solve() {
    let (case, mesh, settings) = half_disc_with_a_token();
    let steps = [0.25, 0.5, 0.75, 1.0];
    // Not cancelled: solved.
    let problem = case.contact_problems(&mesh).unwrap().remove(0);
    assert!(solve_contact(vec![problem], &settings, &steps).is_ok());
    // Cancelled, here before the solve starts: the first safe point stops it.
    settings.cancel.cancel();
    let problem = case.contact_problems(&mesh).unwrap().remove(0);
    let error = solve_contact(vec![problem], &settings, &steps)
        .err()
        .unwrap();
    assert!(matches!(error, ContactError::Cancelled(_)), "{error}");
    assert_eq!(error.to_string(), "the solve was cancelled");
}

#[test]
fn a_token_cancelled_from_another_thread_stops_a_running_solve() {
    let (case, mesh, settings) = half_disc_with_a_token();
    // Many load steps, so that the solve outlasts the wait below by far.
    let steps: Vec<f64> = (1..=2000).map(|k| f64::from(k) / 2000.0).collect();
    let token = settings.cancel.clone();
    let problem = case.contact_problems(&mesh).unwrap().remove(0);
    let cancelled_at = std::thread::scope(|scope| {
        let solve = scope.spawn(|| solve_contact(vec![problem], &settings, &steps));
        std::thread::sleep(Duration::from_millis(300));
        let at = Instant::now();
        token.cancel();
        let error = solve.join().unwrap().err().expect("the solve was stopped");
        assert!(matches!(error, ContactError::Cancelled(_)), "{error}");
        at.elapsed()
    });
    assert!(cancelled_at < Duration::from_secs(2), "{cancelled_at:?}");
}

/// The entries of `dir` whose names start with `.internodes-partial-`: staging folders.
fn staging_folders(dir: &std::path::Path) -> Vec<String> {
    (std::fs::read_dir(dir).unwrap())
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".internodes-partial-"))
        .collect()
}

#[test]
fn a_cancelled_run_leaves_a_failure_mark_and_no_staging_folder() {
    let (dir, path) = half_disc_on_block().write();
    let cancel = Cancel::new();
    cancel.cancel();
    let options = internodes::run::RunOptions {
        quiet: true,
        cancel,
        ..Default::default()
    };
    let error = internodes::run::solve_case(&path, &options).err().unwrap();
    assert!(error.is_cancelled(), "{error}");
    let out = dir.path().join("out");
    assert!(staging_folders(&out).is_empty());
    assert!(!out.join("summary.json").exists());
    let mark = std::fs::read_to_string(out.join("FAILED.txt")).unwrap();
    assert!(mark.contains("cancelled"), "{mark}");
}

/// The 3D stack of three blocks pushed in 400 load steps: several seconds of solving, with a
/// safe point at each step.
fn a_long_run() -> String {
    let steps: Vec<String> = (1..=400)
        .map(|k| (f64::from(k) / 400.0).to_string())
        .collect();
    let mut text = format!(
        "mesh = {:?}\noutput = \"out\"\nload_steps = [{}]\n\n\
         [[contact]]\nbodies = [\"upper\", \"middle\"]\n\
         surfaces = [\"upper_contact\", \"middle_top\"]\n\n\
         [[contact]]\nbodies = [\"middle\", \"lower\"]\n\
         surfaces = [\"middle_bottom\", \"lower_contact\"]\n\n",
        common::fixture("three_blocks_3d.msh"),
        steps.join(", ")
    );
    for (name, support) in [
        ("lower", "{ group = \"lower_base\", uz = 0.0 }, "),
        ("middle", ""),
        ("upper", "{ group = \"upper_top\", uz = -0.01 }, "),
    ] {
        text += &format!(
            "[[body]]\nname = \"{name}\"\nyoungs_modulus = 1000.0\npoisson_ratio = 0.3\n\
             dirichlet = [{support}{{ group = \"{name}_sides\", ux = 0.0, uy = 0.0 }}]\n\n"
        );
    }
    text
}

#[test]
#[cfg(unix)]
fn ctrl_c_stops_the_command_line_and_leaves_no_staging_folder() {
    let (dir, path) = common::write_case(&a_long_run());
    let out = dir.path().join("out");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_internodes"))
        .args(["solve", path.to_str().unwrap(), "--quiet"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Once the staging folder exists the run is meshing or solving.
    let start = Instant::now();
    while !out.is_dir() || staging_folders(&out).is_empty() {
        assert!(child.try_wait().unwrap().is_none(), "the run ended first");
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "no staging folder"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    std::thread::sleep(Duration::from_millis(300));
    let pid = libc::pid_t::try_from(child.id()).unwrap();
    // SAFETY: a signal to our own child process.
    assert_eq!(unsafe { libc::kill(pid, libc::SIGINT) }, 0);
    let output = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(130), "{stderr}");
    assert!(stderr.contains("cancelled"), "{stderr}");
    assert!(staging_folders(&out).is_empty());
    assert!(!out.join("summary.json").exists());
    assert!(out.join("FAILED.txt").is_file());
}
