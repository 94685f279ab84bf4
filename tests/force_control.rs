//! Force control (`[[body.force]]`): a group loaded by a prescribed total force moves rigidly,
//! by a displacement that is an unknown of the solve. The independent measure is the
//! displacement-controlled run: a body pressed by an imposed displacement, then by the force
//! that displacement gave (its group's reaction), must come back to that displacement, with
//! the same contact. Also: load steps ramp the force, a single body, and the errors of a body
//! that nothing holds or that the force pulls off.

mod common;

use common::case_builder::{Body, CaseFile, Dirichlet, Force};
use common::contact::{hemisphere_on_block, solve};
use common::{half_disc_on_block, run_solve, run_to_summary};
use internodes::contact::{ContactSolution, ContactStatus};

/// The loop holds every active gap to `penetration_tolerance` (1e-3) of a spacing; the finest
/// contact spacing of these fixtures is at least R/80 (R = 1). Two runs of the same discrete
/// problem, one held by its displacement and one by the force it gave, end within that of each
/// other.
const SETTLED: f64 = 1e-3 / 80.0;

/// The reaction of `group` (its components) in `solution`'s primary body.
fn reaction(solution: &ContactSolution, group: &str) -> Vec<f64> {
    let reactions = &solution.primary.reactions;
    let (_, force) = (reactions.iter().find(|(g, _)| g == group))
        .unwrap_or_else(|| panic!("no reaction of '{group}': {reactions:?}"));
    force.clone()
}

/// The run of `displaced` (its primary's `group` held at `-delta` along the vertical axis of a
/// `dim`-dimensional mesh) against the run of `forced` with that group loaded by the reaction
/// the first run gave: the force-controlled displacement, the contact force and the active set.
fn assert_force_gives_back_the_displacement(
    displaced: CaseFile,
    forced: impl FnOnce(f64) -> CaseFile,
    group: &str,
    dim: usize,
    delta: f64,
) {
    let reference = solve(&displaced).expect("the displacement-controlled run");
    assert_eq!(reference.status, ContactStatus::Converged);
    let force = reaction(&reference, group)[dim - 1];
    assert!(force < 0.0, "the group pushes the body down: {force}");

    let run = solve(&forced(force)).expect("the force-controlled run");
    assert_eq!(run.status, ContactStatus::Converged);
    assert_eq!(run.forced.len(), 1, "{:?}", run.forced);
    let moved = &run.forced[0];
    assert_eq!(moved.group, group);
    assert_eq!(moved.force, force);
    assert!(
        (moved.displacement + delta).abs() <= SETTLED,
        "the force {force} moved '{group}' by {}, the displacement that gave it was {}",
        moved.displacement,
        -delta
    );
    // Nothing but the contact holds the body along the force: the contact carries it all
    // (the group's reaction, read from K u, is the force).
    let carried = run.force_primary[dim - 1];
    assert!(
        (carried + force).abs() <= 1e-8 * force.abs(),
        "contact force {carried} against the force {force}"
    );
    assert!((reaction(&run, group)[dim - 1] - force).abs() <= 1e-8 * force.abs());
    assert_eq!(
        run.active_set.nodes, reference.active_set.nodes,
        "the same contact zone"
    );
}

/// The half-disc pressed onto the block: `disc_top` held laterally and loaded by `force`.
fn half_disc_pressed_by(force: f64) -> CaseFile {
    half_disc_on_block("half_disc_on_block.msh").with_body("disc", |body| {
        Body {
            dirichlet: vec![Dirichlet::on("disc_top").ux(0.0)],
            ..body
        }
        .force(Force::vertical("disc_top", 2, force))
    })
}

#[test]
fn a_force_gives_back_the_displacement_that_gave_it_on_every_solver_2d() {
    for solver in ["krylov", "schur", "monolithic-lu"] {
        let with = |case: CaseFile| case.contact_setting("solver", solver);
        assert_force_gives_back_the_displacement(
            with(half_disc_on_block("half_disc_on_block.msh")),
            |force| with(half_disc_pressed_by(force)),
            "disc_top",
            2,
            0.02,
        );
    }
}

#[test]
fn a_force_on_the_secondary_gives_back_its_displacement_2d() {
    // The block primary: the force-controlled disc is the body that receives the transfer.
    let block_primary = |case: CaseFile| case.primary("block");
    let reference = solve(&block_primary(half_disc_on_block("half_disc_on_block.msh"))).unwrap();
    let force = reference.secondary.reactions[0].1[1];
    let run = solve(&block_primary(half_disc_pressed_by(force))).unwrap();
    assert_eq!(run.status, ContactStatus::Converged);
    assert!(
        (run.forced[0].displacement + 0.02).abs() <= SETTLED,
        "{:?}",
        run.forced
    );
    assert_eq!(run.active_set.nodes, reference.active_set.nodes);
}

#[test]
fn a_force_gives_back_the_displacement_that_gave_it_3d() {
    // The sphere touches the block at its pole only: a force-controlled start would carry the
    // whole force on that node and sink the sphere several times its approach.
    let delta = 0.01;
    let mesh = "hemisphere_on_block_hertz.msh";
    assert_force_gives_back_the_displacement(
        hemisphere_on_block(mesh, delta, 1000.0, 1000.0),
        |force| {
            hemisphere_on_block(mesh, delta, 1000.0, 1000.0).with_body("sphere", |body| {
                Body {
                    dirichlet: vec![Dirichlet::on("sphere_top").lateral(3, 0.0)],
                    ..body
                }
                .force(Force::vertical("sphere_top", 3, force))
            })
        },
        "sphere_top",
        3,
        delta,
    );
}

#[test]
fn load_steps_ramp_the_force() {
    let one_step = solve(&half_disc_pressed_by(-5.0)).unwrap();
    let stepped = solve(&half_disc_pressed_by(-5.0).load_steps(&[0.5, 1.0])).unwrap();
    let (a, b) = (
        one_step.forced[0].displacement,
        stepped.forced[0].displacement,
    );
    assert!((a - b).abs() <= SETTLED, "one step {a}, two steps {b}");
    assert_eq!(stepped.forced[0].force, -5.0);
    assert_eq!(stepped.active_set.nodes, one_step.active_set.nodes);
}

/// The block of the `block_2d` fixture clamped at its base, its top held laterally and pushed
/// down by `top` (a displacement or a force), solved alone.
fn block_pushed(top: impl FnOnce(Body) -> Body) -> CaseFile {
    CaseFile::on_fixture("block_2d.msh").body(top(
        Body::new("block", 1000.0, 0.3).dirichlet(Dirichlet::clamped("block_base", 2))
    ))
}

/// The `block_top` reaction along y in a summary.
fn top_reaction(summary: &serde_json::Value) -> f64 {
    summary["bodies"][0]["reactions"]["block_top"][1]
        .as_f64()
        .unwrap()
}

#[test]
fn a_single_body_moves_by_the_displacement_whose_force_it_is_given() {
    // The top also shifted sideways: the prescribed dofs next to the force-controlled ones
    // pull on them (`applied` of `RigidColumn`).
    let (displaced_dir, displaced) = run_to_summary(&block_pushed(|body| {
        body.dirichlet(Dirichlet::on("block_top").ux(0.003).uy(-0.01))
    }));
    let force = top_reaction(&displaced);
    let (forced_dir, forced) = run_to_summary(&block_pushed(|body| {
        body.dirichlet(Dirichlet::on("block_top").ux(0.003))
            .force(Force::vertical("block_top", 2, force))
    }));
    let reaction = top_reaction(&forced);
    assert!(
        (reaction - force).abs() <= 1e-9 * force.abs(),
        "{reaction} against {force}"
    );
    // A linear problem: the same displacement field, to the solver's accuracy.
    let (a, b) = (
        common::hostile::displacement_by_tag(&displaced_dir.path().join("out")),
        common::hostile::displacement_by_tag(&forced_dir.path().join("out")),
    );
    assert_eq!(a.len(), b.len());
    let largest = (a.values().flatten()).fold(0.0_f64, |m, v| m.max(v.abs()));
    let worst = (a.iter())
        .flat_map(|(tag, u)| u.iter().zip(&b[tag]).map(|(x, y)| (x - y).abs()))
        .fold(0.0_f64, f64::max);
    assert!(worst <= 1e-9 * largest, "{worst} of {largest}");
    assert!(largest >= 0.01, "the top moved by 0.01: {largest}");
}

/// Runs `case` through the CLI, which must fail with a message holding every one of `words`.
fn assert_refused(case: &CaseFile, words: &[&str]) {
    let (_dir, path) = case.write();
    let output = run_solve(&path);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success(), "accepted: {stderr}");
    for word in words {
        assert!(stderr.contains(word), "no {word:?} in: {stderr}");
    }
}

#[test]
fn a_single_body_that_only_its_force_holds_is_refused() {
    // The base on rollers (x held): along y only the force-controlled top holds the block.
    assert_refused(
        &CaseFile::on_fixture("block_2d.msh").body(
            Body::new("block", 1000.0, 0.3)
                .dirichlet(Dirichlet::on("block_base").ux(0.0))
                .dirichlet(Dirichlet::on("block_top").ux(0.0))
                .force(Force::vertical("block_top", 2, -1.0)),
        ),
        &["body 'block'", "along y", "'block_top'"],
    );
}

#[test]
fn a_force_that_pulls_the_body_off_its_contact_is_an_error() {
    assert_refused(
        &half_disc_pressed_by(5.0),
        &["body 'disc'", "along y", "'disc_top'", "pulls it off"],
    );
}

#[test]
fn a_component_both_prescribed_and_force_controlled_is_refused() {
    let case = half_disc_on_block("half_disc_on_block.msh").with_body("disc", |body| {
        body.force(Force::vertical("disc_top", 2, -1.0))
    });
    assert_refused(
        &case,
        &[
            "body 'disc'",
            "'s uy is force-controlled (fy) by group 'disc_top'",
            "by the Dirichlet condition on group 'disc_top'",
        ],
    );
}

#[test]
fn malformed_forces_are_refused() {
    let with_force = |force: Force| {
        half_disc_pressed_by(-1.0).with_body("disc", |body| Body {
            forces: vec![force],
            ..body
        })
    };
    let force = |group: &str| Force {
        group: group.to_string(),
        fx: None,
        fy: None,
        fz: None,
    };
    assert_refused(
        &with_force(force("disc_top")),
        &["'disc_top'", "no component"],
    );
    assert_refused(
        &with_force(Force {
            fz: Some(-1.0),
            ..force("disc_top")
        }),
        &["'disc_top'", "fz", "2D"],
    );
    assert_refused(
        &with_force(Force {
            fy: Some(-1.0),
            ..force("no_such_group")
        }),
        &["'no_such_group'"],
    );
    assert_refused(
        &with_force(Force {
            fy: Some(f64::INFINITY),
            ..force("disc_top")
        }),
        &["'disc_top'", "fy"],
    );
}

#[test]
fn two_bodies_held_only_by_their_contact_are_refused() {
    let case = half_disc_pressed_by(-1.0).with_body("block", |body| {
        Body {
            dirichlet: vec![Dirichlet::on("block_base").ux(0.0)],
            ..body
        }
        .force(Force::vertical("block_base", 2, 1.0))
    });
    assert_refused(&case, &["'disc'", "'block'", "held by nothing"]);
}

#[test]
fn the_example_case_file_reads() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("geo/hemisphere_pressed_by_force.toml");
    let case = internodes::case::Case::load(&path).expect("the example case");
    let sphere = &case.bodies[0];
    assert_eq!(sphere.forces.len(), 1);
    assert_eq!(
        (sphere.forces[0].group.as_str(), sphere.forces[0].fz),
        ("sphere_top", Some(-0.8))
    );
}

#[test]
fn a_force_on_the_contact_face_itself_gives_back_its_displacement() {
    // The upper block's contact face is the loading plate: every active node of the primary
    // moves with the plate, so each constraint row reads the plate's displacement and each
    // multiplier's force enters the plate's reaction (the entries of D between them).
    use common::contact::{pinned_at_corners, stacked_blocks};
    let upper_face = |condition: Dirichlet| {
        pinned_at_corners(stacked_blocks(2), 2).with_body("upper", |body| Body {
            dirichlet: (body.dirichlet.into_iter())
                .filter(|d| d.group != "upper_top")
                .chain([condition])
                .collect(),
            ..body
        })
    };
    let reference = solve(&upper_face(Dirichlet::on("upper_contact").uy(-0.01))).unwrap();
    assert_eq!(reference.status, ContactStatus::Converged);
    let force = reaction(&reference, "upper_contact")[1];
    assert!(force < 0.0, "{force}");
    let run = solve(
        &upper_face(Dirichlet::on("upper_corner").ux(0.0)).with_body("upper", |body| {
            body.force(Force::vertical("upper_contact", 2, force))
        }),
    )
    .unwrap();
    assert_eq!(run.status, ContactStatus::Converged);
    assert!(
        (run.forced[0].displacement + 0.01).abs() <= SETTLED,
        "{:?}",
        run.forced
    );
    assert!((reaction(&run, "upper_contact")[1] - force).abs() <= 1e-8 * force.abs());
    assert_eq!(run.active_set.nodes, reference.active_set.nodes);
}
