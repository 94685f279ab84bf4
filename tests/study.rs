//! `internodes study`: a refinement study of a small 2D contact case writes its files and
//! estimates, and a parameter the `.geo` does not use is refused before anything is solved.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use common::case_builder::{Body, CaseFile, Dirichlet};

const BINARY: &str = env!("CARGO_BIN_EXE_internodes");

/// `geo/half_disc_on_block.geo` coarsened (h_c = R/20 at level 0), the disc pressed by 0.02
/// onto the block: a few hundred nodes per body at level 0.
fn coarse_half_disc() -> CaseFile {
    let geo = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("geo/half_disc_on_block.geo");
    CaseFile::new(geo)
        .geo_parameter("h_c", 0.05)
        .geo_parameter("r_c", 0.25)
        .contact(["disc", "block"], ["disc_contact", "block_contact"])
        .primary("disc")
        .body(Body::new("disc", 1000.0, 0.3).dirichlet(Dirichlet::on("disc_top").ux(0.0).uy(-0.02)))
        .body(Body::new("block", 1000.0, 0.3).dirichlet(Dirichlet::clamped("block_base", 2)))
}

fn study(case: &Path, parameter: &str, output: &Path) -> Output {
    Command::new(BINARY)
        .args([
            "study",
            case.to_str().unwrap(),
            "--parameter",
            parameter,
            "--output",
        ])
        .arg(output)
        .output()
        .unwrap()
}

fn read_json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn a_three_level_study_writes_its_files_and_estimates() {
    let (dir, case) = coarse_half_disc().write();
    let out = dir.path().join("study");
    let run = study(&case, "level=0,1,2", &out);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    for name in ["study.json", "study.csv", "study.md", "study.png"] {
        assert!(out.join(name).is_file(), "{name} missing; {stderr}");
    }
    for level in 0..3 {
        assert!(out.join(format!("level_{level}/summary.json")).is_file());
    }
    let json = read_json(&out.join("study.json"));
    assert_eq!(json["parameter"], "level");
    let levels = json["levels"].as_array().unwrap();
    let h: Vec<f64> = (levels.iter())
        .map(|l| l["spacing"]["h"].as_f64().unwrap())
        .collect();
    // Measured, not assumed: each level about halves the contact-zone spacing.
    for pair in h.windows(2) {
        let ratio = pair[0] / pair[1];
        assert!((1.6..2.4).contains(&ratio), "{h:?}");
    }
    assert!(levels.iter().all(|l| l["spacing"]["contact_zone"] == true));
    let estimates = json["estimates"].as_array().unwrap();
    let keys: Vec<&str> = estimates
        .iter()
        .map(|e| e["key"].as_str().unwrap())
        .collect();
    assert_eq!(keys, ["force", "a", "p0", "max_pressure"]);
    let force = &estimates[0]["estimate"];
    let p = force["order"]
        .as_f64()
        .expect("an observed order of the force");
    assert!(
        p > 0.0 && force["gci_fine"].as_f64().unwrap() > 0.0,
        "{force}"
    );
    let csv = std::fs::read_to_string(out.join("study.csv")).unwrap();
    assert_eq!(csv.lines().count(), 4, "{csv}");
    assert!(csv.starts_with("level,h,"), "{csv}");
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        stdout.contains("| contact force |"),
        "the tables are printed: {stdout}"
    );
}

#[test]
fn two_levels_give_the_difference_and_say_there_is_no_order() {
    let (dir, case) = coarse_half_disc().write();
    let out = dir.path().join("two");
    let run = study(&case, "level=-1,0", &out);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let json = read_json(&out.join("study.json"));
    let force = &json["estimates"][0]["estimate"];
    assert!(force["difference"].as_f64().unwrap() != 0.0);
    assert!(
        force["order"].is_null() && force["gci_fine"].is_null(),
        "{force}"
    );
    assert_eq!(force["flags"], serde_json::json!(["two-levels"]));
    let md = std::fs::read_to_string(out.join("study.md")).unwrap();
    assert!(
        md.contains("Two levels only") && md.contains("no order"),
        "{md}"
    );
}

#[test]
fn a_study_over_an_earlier_one_removes_its_levels_and_nothing_of_the_users() {
    let (dir, case) = coarse_half_disc().write();
    let out = dir.path().join("study");
    // An earlier study's level this one does not solve, killed while it wrote its results.
    let stale = out.join("level_3");
    std::fs::create_dir_all(stale.join(".internodes-partial-1-0")).unwrap();
    for name in ["summary.json", "solution.h5", "mesh.msh"] {
        std::fs::write(stale.join(name), "earlier").unwrap();
    }
    // A level folder holding a file of the user's, and a folder of the user's.
    let annotated = out.join("level_4");
    std::fs::create_dir_all(&annotated).unwrap();
    std::fs::write(annotated.join("summary.json"), "earlier").unwrap();
    std::fs::write(annotated.join("notes.txt"), "mine").unwrap();
    std::fs::create_dir_all(out.join("notes")).unwrap();
    std::fs::write(out.join("notes/level_5.txt"), "mine").unwrap();
    std::fs::write(out.join("study.json"), "earlier").unwrap();

    let run = study(&case, "level=-1,0", &out);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(!stale.exists(), "{stderr}");
    assert!(
        stderr.contains(&format!("removed {}", stale.display())),
        "{stderr}"
    );
    assert!(annotated.join("notes.txt").is_file() && annotated.join("summary.json").is_file());
    assert!(out.join("notes/level_5.txt").is_file());
    let json = read_json(&out.join("study.json"));
    let folders: Vec<&str> = (json["levels"].as_array().unwrap().iter())
        .map(|l| l["folder"].as_str().unwrap())
        .collect();
    assert_eq!(folders, ["level_-1", "level_0"]);
}

#[test]
fn a_parameter_the_geo_does_not_use_is_refused_with_its_parameters() {
    let (dir, case) = coarse_half_disc().write();
    let out = dir.path().join("typo");
    let run = study(&case, "levle=0,1,2", &out);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("geo_parameters.levle") && stderr.contains("does not use a parameter"),
        "{stderr}"
    );
    assert!(
        stderr.contains("level, R, gap"),
        "the script's parameters are listed: {stderr}"
    );
    assert!(!out.exists(), "nothing is solved before the check");
}

#[test]
fn bad_values_and_meshes_that_are_not_geo_are_refused() {
    let (dir, case) = coarse_half_disc().write();
    for (parameter, why) in [
        ("level=0", "at least two values"),
        ("level=0,0", "given twice"),
        ("level", "expected NAME=V1,V2"),
        ("level=0,x", "'x'"),
    ] {
        let run = study(&case, parameter, &dir.path().join("bad"));
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(
            !run.status.success() && stderr.contains(why),
            "{parameter}: {stderr}"
        );
    }
    let (dir, msh_case) = common::half_disc_on_block("half_disc_on_block_hertz.msh").write();
    let run = study(&msh_case, "level=0,1", &dir.path().join("msh"));
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("not a .geo"), "{stderr}");
}

#[test]
fn the_default_log_is_one_line_per_level_and_v_adds_each_solve_log() {
    let (dir, case) = coarse_half_disc().write();
    let log_of = |flags: &[&str]| {
        let run = Command::new(BINARY)
            .args(["study", case.to_str().unwrap(), "--parameter", "level=-1,0"])
            .arg("--output")
            .arg(dir.path().join("log"))
            .args(flags)
            .output()
            .unwrap();
        let stderr = String::from_utf8(run.stderr).unwrap();
        assert!(run.status.success(), "{flags:?}: {stderr}");
        stderr
    };
    let default = log_of(&[]);
    let lines: Vec<&str> = default.lines().collect();
    assert_eq!(lines.len(), 2, "one line per level: {default}");
    for (line, value) in lines.iter().zip(["-1", "0"]) {
        assert!(
            line.starts_with(&format!("study: level = {value}: converged (exit 0); h "))
                && line.contains(" DOFs, force "),
            "{line}"
        );
        assert!(line.chars().count() <= 120, "{line}");
    }
    // -v: each level's solve log as `solve -v` prints it (its iterations among them).
    let verbose = log_of(&["-v"]);
    let count = |start: &str| verbose.lines().filter(|l| l.starts_with(start)).count();
    assert_eq!(count("contact status: converged"), 2, "{verbose}");
    assert!(count("  iteration ") >= 2, "{verbose}");
    assert_eq!(
        count("study: level = "),
        4,
        "each level's start and end: {verbose}"
    );
}
