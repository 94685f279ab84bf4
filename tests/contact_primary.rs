//! Which body carries the multiplier and how the force reaches the other: the automatic
//! choices, a primary or transfer named by hand, and the checks against the other choice.

mod common;

use common::case_builder::{Body, CaseFile, Dirichlet};
use common::contact::{
    failed_checks, failed_in_summary, flat_punch, footprint_force, narrow_blocks, solve, solve_cli,
    stiff_block,
};
use common::run_solve;
use internodes::case::Case;
use internodes::contact::{ContactStatus, solve_contact};
use internodes::elastic::SolverSettings;
use internodes::mesh::read_msh;

/// The hemisphere of `foreign_hemisphere_on_fine_block.msh` (R/25, E = 1000) pressed by 0.004
/// onto the block 1e4 times stiffer and twice finer, the block primary by hand.
fn foreign_stiff_block_primary() -> CaseFile {
    CaseFile::on_fixture("foreign_hemisphere_on_fine_block.msh")
        .contact(["sphere", "block"], ["sphere_contact", "block_contact"])
        .primary("block")
        .body(
            Body::new("sphere", 1000.0, 0.3)
                .dirichlet(Dirichlet::on("sphere_top").lateral(3, 0.0).uz(-0.004)),
        )
        .body(Body::new("block", 1.0e7, 0.3).dirichlet(Dirichlet::clamped("block_base", 3)))
}

/// How the written case spells the stiff block's Young's modulus, 1e7.
const STIFF_MODULUS: &str = "youngs_modulus = 10000000.0";

/// The hemisphere of `tests/fixtures/foreign_hemisphere_on_fine_block.msh` pressed by 0.004
/// onto a rigid flat: contact force computed by dolfinx (PETSc VI solver, exact node-to-plane
/// constraint) on the same hemisphere mesh, by `validation/foreign_meshes.py`.
const FOREIGN_RIGID_FLAT_FORCE_3D: f64 = 0.4213517106868755;

/// The same at the approaches 0.001, 0.002, 0.003 (`run_reference(..., delta=0.004)`, its
/// default fractions 0.25, 0.5, 0.75).
const FOREIGN_RIGID_FLAT_FORCES_3D: [f64; 3] = [
    0.043539357158780406,
    0.16472739076094023,
    0.2930395507239048,
];

/// The half-disc of `tests/fixtures/half_disc_on_block_coarse_block.msh` pressed by 0.02 onto
/// a rigid flat: contact force per unit length computed by dolfinx (PETSc VI solver, exact
/// node-to-plane constraint) on the same disc mesh, by `validation/rigid_flat.py`.
const RIGID_FLAT_REFERENCE_FORCE_2D: f64 = 12.200145815310922;

/// `half_disc_on_block_coarse_block.msh`'s half-disc pressed by 0.004 onto a rigid flat, by
/// dolfinx (`validation/contact_reference.py`, `run_reference(..., delta=0.004)`).
const COARSE_BLOCK_RIGID_FLAT_FORCE_2D_AT_0_004: f64 = 1.829546778705095;

#[test]
fn auto_primary_is_the_more_compliant_body() {
    let case = stiff_block("half_disc_on_block.msh", "auto");
    let text = case.to_toml();
    assert!(
        text.contains(STIFF_MODULUS) && text.contains("\"auto\""),
        "{text}"
    );
    let (code, summary) = solve_cli(&case);
    let contact = &summary["contact"];
    assert_eq!(code, Some(0), "{contact}");
    assert_eq!(contact["primary"], "disc", "{contact}");
    assert_eq!(contact["primary_choice"]["mode"], "auto");
    let reason = contact["primary_choice"]["reason"].as_str().unwrap();
    assert!(reason.contains("more compliant"), "{reason}");
    assert_eq!(contact["status"], "converged");
}

#[test]
fn a_stiff_primary_as_fine_as_the_other_is_right_or_says_why() {
    // The block made primary by hand, its contact surface as fine as the disc's (R/80): the
    // answer must be the dolfinx rigid-flat force (same disc mesh as the coarse-block fixture)
    // or a status that is not "converged", with an exit status of 1.
    let (code, summary) = solve_cli(&stiff_block("half_disc_on_block_hertz.msh", "block"));
    let contact = &summary["contact"];
    assert_eq!(contact["primary"], "block");
    assert_eq!(contact["primary_choice"]["mode"], "explicit");
    if contact["status"] == "converged" {
        assert_eq!(code, Some(0));
        let force = contact["force_secondary"][1].as_f64().unwrap();
        let error = (force - RIGID_FLAT_REFERENCE_FORCE_2D) / RIGID_FLAT_REFERENCE_FORCE_2D;
        assert!(
            error.abs() <= 0.01,
            "force on the disc {force}: {error:+.4}"
        );
        eprintln!("stiff block primary as fine as the disc (R/80): force {error:+.4}");
    } else {
        assert_eq!(code, Some(1), "{contact}");
    }
}

#[test]
fn an_explicit_stiff_primary_is_right_or_named() {
    // A mesh made without `geo/`: a hemisphere (R/25) on a block 1e4 times stiffer meshed twice
    // finer, pressed by 0.004, the block primary by hand. With the constraint rows of the RBF
    // interpolation, the loop certified a force 3% below dolfinx's rigid flat on the same
    // hemisphere mesh, and only the comparison with the hemisphere as primary named it. With
    // the gap's own linearization the loop ends `unstable` (a fine stiff multiplier surface
    // on a coarse compliant one: the inf-sup condition). Either way the answer must be right
    // or named, for a library caller and on the command line.
    let case = foreign_stiff_block_primary();
    let library = solve(&case).unwrap();
    let error = library.force_secondary[2] / FOREIGN_RIGID_FLAT_FORCE_3D - 1.0;
    if library.is_trusted() {
        assert!(error.abs() <= 0.01, "trusted, but {error:+.4} off dolfinx");
    }
    eprintln!(
        "stiff block primary by hand: {} ({error:+.4})",
        library.ending()
    );

    let (code, summary) = solve_cli(&case);
    let contact = &summary["contact"];
    assert_eq!(contact["primary"], "block", "{contact}");
    let reason = contact["primary_choice"]["reason"].as_str().unwrap();
    assert!(reason.contains("would choose 'sphere'"), "{reason}");
    assert_eq!(contact["status"], library.status.name(), "{contact}");
    if library.is_trusted() {
        assert_eq!(code, Some(0), "{contact}");
    } else if library.status.is_solution() {
        assert_eq!(code, Some(3), "{contact}");
        assert!(!failed_in_summary(contact).is_empty(), "{contact}");
    } else {
        assert_eq!(code, Some(2), "{contact}");
    }
}

#[test]
fn every_load_step_of_an_explicit_stiff_primary_is_right_or_named() {
    // The force-displacement curve is an answer too: stepped to 0.004 in four steps, the stiff
    // block primary's loop with the RBF constraint rows certified steps whose force was more
    // than 1% off dolfinx. Every step's record must be right or say why it is not trusted.
    let factors = [0.25, 0.5, 0.75, 1.0];
    let (_dir, path) = foreign_stiff_block_primary().write();
    let case = Case::load(&path).unwrap();
    let mesh = read_msh(&case.mesh).unwrap();
    let settings = SolverSettings {
        verbose: false,
        ..case.solver.clone()
    };
    let references: Vec<f64> = FOREIGN_RIGID_FLAT_FORCES_3D
        .into_iter()
        .chain([FOREIGN_RIGID_FLAT_FORCE_3D])
        .collect();
    let error = |force_on_sphere: f64, k: usize| force_on_sphere / references[k] - 1.0;

    let problem = case.contact_problems(&mesh).unwrap().remove(0);
    let run = solve_contact(vec![problem], &settings, &factors).unwrap();
    let steps = &run.steps[0];
    assert!(!steps.is_empty());
    for (k, step) in steps.iter().enumerate() {
        let e = error(step.force_secondary[2], k);
        let trusted = step.status.is_solution() && step.accurate;
        assert!(
            !trusted || e.abs() <= 0.01,
            "step {k}: trusted, {e:+.4} off dolfinx"
        );
        assert_eq!(
            trusted,
            step.failed_checks.is_empty() && step.status.is_solution()
        );
    }
}

#[test]
fn a_stiff_primary_on_a_coarser_surface_matches_the_rigid_flat_reference() {
    // The block 1e4 times stiffer than the disc and the primary body, its contact surface meshed
    // twice coarser: the loop converges, without the warning, to the dolfinx rigid-flat force.
    let case = common::half_disc_on_block("half_disc_on_block_coarse_block.msh")
        .primary("block")
        .with_body("block", |b| Body {
            youngs_modulus: 1.0e7,
            ..b
        });
    let text = case.to_toml();
    assert!(
        text.contains(STIFF_MODULUS) && text.contains("primary = \"block\""),
        "{text}"
    );
    let (dir, path) = case.write();
    let output = run_solve(&path);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(!stderr.contains("warning"), "{stderr}");
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("out/summary.json")).unwrap(),
    )
    .unwrap();
    let contact = &summary["contact"];
    assert_eq!(contact["status"], "converged", "{contact}");
    let force_on_disc = contact["force_secondary"][1].as_f64().unwrap();
    let error = (force_on_disc - RIGID_FLAT_REFERENCE_FORCE_2D) / RIGID_FLAT_REFERENCE_FORCE_2D;
    assert!(
        error.abs() <= 0.01,
        "force on the disc {force_on_disc}: {error:+.4}"
    );
    let imbalance = contact["force_imbalance"].as_f64().unwrap();
    assert!(imbalance <= 0.01, "imbalance {imbalance}");
    // "auto" would make the disc primary: the answer was compared with that one.
    let checks = contact["accuracy"]["indicators"].as_array().unwrap();
    let agreement = (checks.iter())
        .find(|c| c["name"] == "primary agreement")
        .unwrap_or_else(|| panic!("no primary agreement check: {contact}"));
    assert_eq!(agreement["passed"], true, "{agreement}");
    assert!(
        agreement["note"]
            .as_str()
            .unwrap()
            .contains("'disc' as primary"),
        "{agreement}"
    );
    eprintln!(
        "stiff block primary, 2D: force {error:+.4} against dolfinx, imbalance {imbalance:.2e}, \
         {:.2e} from the disc primary's force",
        agreement["value"].as_f64().unwrap()
    );
}

#[test]
fn a_coarser_secondary_receives_the_conservative_transfer() {
    // The disc (R/80) primary on a block 1e4 times stiffer meshed twice coarser, pressed by
    // 0.004 (7 disc nodes in contact). Interpolating the traction at the coarse block's nodes
    // (INTERNODES' R21) under-samples it: the block receives several percent less force than
    // the disc, and the answer is not certified. The auto transfer sends the disc's nodal forces
    // through R12^T instead: certified, and the disc force is dolfinx's rigid flat on the same
    // disc mesh to 1%.
    let case = stiff_block("half_disc_on_block_coarse_block.msh", "disc").with_support(
        "disc",
        "disc_top",
        |d| d.uy(-0.004),
    );
    let text = case.to_toml();
    assert!(text.contains("uy = -0.004"), "{text}");
    let interpolated = solve(&case.clone().contact_setting("transfer", "interpolation")).unwrap();
    assert_eq!(interpolated.status, ContactStatus::NotSolved);
    assert_eq!(failed_checks(&interpolated), ["equilibrium"]);

    let (code, summary) = solve_cli(&case);
    let contact = &summary["contact"];
    assert_eq!(code, Some(0), "{contact}");
    assert_eq!(contact["status"], "converged", "{contact}");
    assert_eq!(contact["transfer"]["transfer"], "conservative", "{contact}");
    // The block is both coarser and nearly rigid; the second reason is tested first.
    let reason = contact["transfer"]["reason"].as_str().unwrap();
    assert!(reason.contains("nearly rigid"), "{reason}");
    let force = contact["force_primary"][1].as_f64().unwrap();
    let error = force / COARSE_BLOCK_RIGID_FLAT_FORCE_2D_AT_0_004 - 1.0;
    assert!(
        error.abs() <= 0.01,
        "force on the disc {force}: {error:+.4}"
    );
}

#[test]
fn auto_tries_the_other_primary_when_its_first_choice_is_not_certified() {
    // Equal materials, the block's surface twice coarser than the disc's (R/80), pressed by
    // 0.004: auto picks the coarser block, whose answer fails the certificate on the disc's
    // sag (its force is 2% below the disc primary's); the disc as primary is certified, and
    // that answer is the one kept, with the reason.
    let case = common::half_disc_on_block("half_disc_on_block_coarse_block.msh").with_support(
        "disc",
        "disc_top",
        |d| d.uy(-0.004),
    );
    let text = case.to_toml();
    assert!(text.contains("uy = -0.004"), "{text}");
    let block_first = solve(&case.clone().primary("block")).unwrap();
    assert!(!block_first.is_trusted());

    let (code, summary) = solve_cli(&case.primary("auto"));
    let contact = &summary["contact"];
    assert_eq!(code, Some(0), "{contact}");
    assert_eq!(contact["status"], "converged", "{contact}");
    assert_eq!(contact["primary"], "disc", "{contact}");
    assert_eq!(contact["primary_choice"]["mode"], "auto");
    let reason = contact["primary_choice"]["reason"].as_str().unwrap();
    assert!(
        reason
            .contains("'block' as primary ended converged, accuracy report failed (secondary sag"),
        "{reason}"
    );
}

#[test]
fn a_stiff_punch_made_primary_by_hand_is_right_or_named() {
    // The punch as primary: its nodes are held on the block's surface, the block's between
    // them only through the transfer. In 2D that is the rigid punch's answer to 0.1%; in 3D
    // the fine stiff multiplier surface on the compliant block is unstable (the inf-sup
    // condition that `primary = "auto"` avoids). Either way: right, or named.
    for dim in [2, 3] {
        for delta in [0.002, 0.02] {
            let label = format!("{dim}D punch primary pressed by {delta}");
            let (code, summary) = solve_cli(&flat_punch(dim, delta, "punch"));
            let contact = &summary["contact"];
            let force = contact["force_primary"][dim - 1].as_f64().unwrap().abs();
            let error = force / footprint_force(dim, delta) - 1.0;
            if code == Some(0) {
                assert!(error.abs() <= 0.01, "{label}: trusted, {error:+.4} off");
            } else {
                assert!(matches!(code, Some(2 | 3)), "{label}: {code:?}");
                assert!(!failed_in_summary(contact).is_empty(), "{label}: {contact}");
            }
            eprintln!(
                "{label}: exit {code:?}, status {}, force {error:+.4}",
                contact["status"]
            );
        }
    }
}

#[test]
fn a_named_transfer_is_checked_against_the_automatic_one() {
    // The defaults: converged and accurate. Naming the conservative transfer with the coarser
    // upper block primary loads the finer lower block unevenly between the projections of the
    // primary's nodes: 2.3% softer, and every residual and the sag pass. The answer is then
    // compared with auto's transfer (interpolation here, which does not balance the forces on
    // this pair: nothing trusted to compare with), and the accuracy report names it.
    let (code, summary) = solve_cli(&narrow_blocks());
    let contact = &summary["contact"];
    assert_eq!(code, Some(0), "{contact}");
    let trusted = contact["force_primary"][1].as_f64().unwrap().abs();

    let case = narrow_blocks()
        .primary("upper")
        .contact_setting("transfer", "conservative");
    let solution = solve(&case).unwrap();
    let error = solution.force_primary[1].abs() / trusted - 1.0;
    assert!(
        error < -0.01,
        "the premise: {error:+.4} from the default answer"
    );
    assert_eq!(solution.status, ContactStatus::Converged);
    assert_eq!(failed_checks(&solution), ["transfer agreement"]);
    let (code, summary) = solve_cli(&case);
    assert_eq!(code, Some(3), "{}", summary["contact"]);
}

#[test]
fn a_retry_is_checked_against_the_first_answer_where_that_one_settled() {
    // Two equal flat blocks, the upper narrower and coarser: auto's first choice (the coarser
    // upper block) ends not-solved on its force balance alone (the interpolation transfer),
    // with a passing accuracy report; the lower block as primary is solved. Its answer is kept
    // only after its force is compared with the first one's, within accuracy_tolerance plus
    // the first answer's imbalance.
    let (code, summary) = solve_cli(&narrow_blocks());
    let contact = &summary["contact"];
    assert_eq!(code, Some(0), "{contact}");
    assert_eq!(contact["primary"], "lower");
    let reason = contact["primary_choice"]["reason"].as_str().unwrap();
    assert!(
        reason.contains("'upper' as primary ended not-solved (equilibrium"),
        "{reason}"
    );
    let indicators = contact["accuracy"]["indicators"].as_array().unwrap();
    let check = (indicators.iter())
        .find(|c| c["name"] == "primary agreement")
        .expect("the retry is compared with the first answer");
    let note = check["note"].as_str().unwrap();
    assert!(note.contains("with the first choice of primary"), "{note}");
    let value = check["value"].as_f64().unwrap();
    let tolerance = check["tolerance"].as_f64().unwrap();
    assert!(value > 0.01 && value < tolerance, "{check}");
    assert!(
        tolerance > 0.01,
        "the first answer's imbalance widens the bound: {check}"
    );
}

#[test]
fn a_named_primary_says_whether_auto_would_choose_it() {
    // Two bodies of one material: auto takes the coarser surface, and either primary is
    // stable. The reason of each named primary must tell the truth about auto's choice.
    let problems = |primary: &str| {
        let (_dir, path) = common::half_disc_on_block("half_disc_on_block.msh")
            .primary(primary)
            .write();
        let case = Case::load(&path).unwrap();
        let mesh = read_msh(&case.mesh).unwrap();
        let problems = case.contact_problems(&mesh).unwrap();
        let primary = problems[0].primary.body.name.clone();
        (primary, problems[0].primary_report.reason.clone())
    };
    let (auto, _) = problems("auto");
    for named in ["disc", "block"] {
        let (primary, reason) = problems(named);
        assert_eq!(primary, named);
        if named == auto {
            assert!(reason.contains("as \"auto\" would"), "{named}: {reason}");
        } else {
            assert!(!reason.contains("as \"auto\" would"), "{named}: {reason}");
            assert!(
                reason.contains(&format!("would choose '{auto}'")),
                "{named}: {reason}"
            );
        }
    }
}
