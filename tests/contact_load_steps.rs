//! Load steps (one set-up, each step from the last active set) and bodies sliding over each
//! other.

mod common;

use common::contact::{half_disc_on_block, solve, stiff_block};
use common::{fixture, run_solve};
use internodes::case::Case;
use internodes::contact::{ContactSolver, ContactStatus};
use internodes::elastic::{SolverSettings, StepFactors};
use internodes::mesh::read_msh;

#[test]
fn load_steps_reuse_the_set_up_and_match_independent_solves() {
    // Stepping 0.5 -> 1 from the previous active set (one set-up, one factorization) must give,
    // at each step, what an independent solve at that load factor gives.
    let case_file = half_disc_on_block();
    let (dir, path) = case_file.write();
    let case = Case::load(&path).unwrap();
    let mesh = read_msh(&case.mesh).unwrap();
    let problem = case.contact_problems(&mesh).unwrap().remove(0);
    let settings = SolverSettings {
        verbose: false,
        ..case.solver
    };
    let mut solver = ContactSolver::new(std::slice::from_ref(&problem), &settings).unwrap();
    let half = solver
        .solve(&StepFactors::uniform(0.5), None)
        .unwrap()
        .remove(0);
    let start = [half.active_set.clone()];
    let full = solver
        .solve(&StepFactors::uniform(1.0), Some(&start))
        .unwrap()
        .remove(0);
    let max = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    // Both paths end when every active node lies within 0.01 tol_p h of the other surface
    // (the loop's stopping rule, tol_p = 1e-3): their displacements agree to that order.
    let h_min = problem
        .primary_surface
        .spacing
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    let settled = 1e-2 * 1e-3 * h_min;
    for (factor, stepped) in [(0.5, &half), (1.0, &full)] {
        let alone = solver
            .solve(&StepFactors::uniform(factor), None)
            .unwrap()
            .remove(0);
        assert_eq!(stepped.status, ContactStatus::Converged);
        assert_eq!(
            stepped.primary_fields.active, alone.primary_fields.active,
            "factor {factor}: same active set"
        );
        let diff: Vec<f64> = stepped
            .primary
            .displacement
            .iter()
            .zip(&alone.primary.displacement)
            .map(|(a, b)| a - b)
            .collect();
        assert!(
            max(&diff) <= settled,
            "factor {factor}: differs by {:.2e} (bound {settled:.2e})",
            max(&diff)
        );
    }
    assert!(full.force_primary[1].abs() > half.force_primary[1].abs());

    // From the command line: one CSV row per step.
    case_file.load_steps(&[0.5, 1.0]).write_to(&path);
    let output = run_solve(&path);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let csv = std::fs::read_to_string(dir.path().join("out/force_displacement.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().collect();
    assert_eq!(rows.len(), 3, "{csv}");
    assert!(
        rows[0].starts_with("step,load_factor,status,iterations,contact_force_x,contact_force_y")
    );
    assert!(rows[2].starts_with("2,1,converged,"), "{csv}");
}

#[test]
fn a_not_certified_load_step_does_not_stop_the_later_ones_and_sets_the_exit_status() {
    // The stiff block primary on its twice coarser surface (R/80 disc), pressed by 0.02 in two
    // steps: at 5% of the load the zone spans about two block spacings and the disc's sag fails
    // the certificate; the full load resolves the zone and is certified. Both steps run, each
    // with its own status; the run's status is the last one's, and its exit status the worst
    // step's: 3, naming the first step (its point of the force-displacement curve is not
    // trusted).
    let case = stiff_block("half_disc_on_block_coarse_block.msh", "block").load_steps(&[0.05, 1.0]);
    let text = case.to_toml();
    assert!(text.contains("load_steps = [0.05, 1.0]"), "{text}");
    let (dir, path) = case.write();
    let output = run_solve(&path);
    let code = output.status.code();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("accuracy report of an earlier one failed: step 1 (load factor 0.05)"),
        "{stderr}"
    );
    let summary = std::fs::read_to_string(dir.path().join("out/summary.json")).unwrap();
    let summary: serde_json::Value = serde_json::from_str(&summary).unwrap();
    let contact = &summary["contact"];
    let steps = contact["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 2, "{contact}");
    assert_eq!(steps[0]["status"], "converged", "{contact}");
    assert_eq!(steps[0]["accurate"], false, "{contact}");
    assert_eq!(steps[1]["status"], "converged", "{contact}");
    assert_eq!(steps[1]["accurate"], true, "{contact}");
    assert_eq!(contact["status"], "converged");
    assert_eq!(code, Some(3));
}

#[test]
fn a_body_slid_sideways_is_paired_where_it_touches() {
    // Frictionless contact between equally stiff bodies: the half-disc pressed by 0.02 and
    // pushed sideways by 0.1 (four spacings) onto the flat block must carry the force it carries
    // pressed straight down: sliding over a flat changes where the block is loaded, not how
    // much. Paired where the contact began, the block received its reaction four spacings from
    // where the disc touched it and the run was certified 3.1% high.
    let straight = common::half_disc_on_block("half_disc_on_block.msh");
    let slid = straight
        .clone()
        .with_support("disc", "disc_top", |d| d.ux(0.1));
    let slid_text = slid.to_toml();
    assert!(slid_text.contains("ux = 0.1"), "{slid_text}");
    let (straight, slid) = (solve(&straight).unwrap(), solve(&slid).unwrap());
    assert_eq!(straight.status, ContactStatus::Converged);
    assert_eq!(slid.status, ContactStatus::Converged);
    let ratio = slid.force_primary[1] / straight.force_primary[1];
    assert!((ratio - 1.0).abs() < 0.005, "force ratio {ratio}");
    let seen = (slid.history.iter()).fold(0.0f64, |m, r| m.max(r.pairing_drift_over_h));
    assert!(seen > 1.0, "the slide was not seen: {seen} h");

    // Where each body is loaded, from the output fields: the pressure-weighted centre of the
    // disc's displaced nodes and of the block's nodes.
    let mesh = read_msh(&fixture("half_disc_on_block.msh")).unwrap();
    let centre = |fields: &internodes::contact::SurfaceFields, body: &str, u: &[f64]| {
        let coords = &mesh.body(body).unwrap().coords;
        let (mut sum, mut weight) = (0.0, 0.0);
        for (s, &node) in fields.nodes.iter().enumerate() {
            let p = fields.mean_pressure[s].max(0.0);
            sum += p * (coords[node][0] + u[2 * node]);
            weight += p;
        }
        sum / weight
    };
    let disc = centre(&slid.primary_fields, "disc", &slid.primary.displacement);
    let block = centre(
        &slid.secondary_fields,
        "block",
        &slid.secondary.displacement,
    );
    eprintln!("slid by 0.1: force ratio {ratio:.5}, centres: disc {disc:.4}, block {block:.4}");
    assert!((disc - 0.1).abs() < 0.025, "disc loaded about x = {disc}");
    assert!(
        (block - disc).abs() < 0.005,
        "block loaded about x = {block}, disc {disc}"
    );
}
