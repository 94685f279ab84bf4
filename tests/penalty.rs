//! The penalty method (`method = "penalty"`): the same cases as INTERNODES, the contact law
//! relaxed to `p = eps max(0, -g)`. Against an exact solution (two blocks in uniaxial
//! compression, where the penalty is a spring in series with the blocks), against INTERNODES as
//! the penalty grows (the force's error falls as `1 / eps`), and through the paths INTERNODES
//! has: tied contact, load steps, the other primary, the coupled solvers.

mod common;

use common::case_builder::CaseFile;
use common::contact::{
    half_disc_on_block, hemisphere_on_block, pinned_at_corners, solve, two_blocks,
};
use internodes::case::Case;
use internodes::contact::{CheckKind, ContactSolution, ContactStatus};
use internodes::mesh::read_msh;

/// `case` with the penalty method and the penalty factor `factor` (times `E* / h`).
fn penalized(case: CaseFile, factor: f64) -> CaseFile {
    case.contact_setting("method", "penalty")
        .contact_setting("penalty", factor)
}

/// The penalty `eps` the case's pair gets (`ContactProblem::penalty_stiffness`).
fn penalty_of(case: &CaseFile) -> f64 {
    let (_dir, path) = case.write();
    let case = Case::load(&path).unwrap();
    let mesh = read_msh(&case.mesh).unwrap();
    let problems = case.contact_problems(&mesh).unwrap();
    problems[0].penalty_stiffness().expect("a penalty pair")
}

/// The indicator `kind` of `solution`'s accuracy report.
fn indicator(solution: &ContactSolution, kind: CheckKind) -> f64 {
    let check = solution.certificate.checks.iter().find(|c| c.name == kind);
    check.unwrap_or_else(|| panic!("no {kind:?}")).value
}

#[test]
fn two_blocks_carry_the_uniaxial_stress_of_the_blocks_and_the_penalty_spring_in_series() {
    // Each block (height 1, E' = E in 3D, E / (1 - nu^2) in plane strain) is pinned at corners
    // alone and compressed uniaxially; the approach 0.01 is shared by the two blocks' strain and
    // the overlap `sigma / eps`: sigma = 0.01 / (2 / E' + 1 / eps). The largest penalty factor
    // is 1e9: the system stays well conditioned as eps grows (the pressure is its unknown).
    for dim in [2, 3] {
        let e_prime = if dim == 2 { 1000.0 / 0.91 } else { 1000.0 };
        for factor in [0.1, 1.0, 1e9] {
            let case = penalized(
                pinned_at_corners(two_blocks(dim, "frictionless"), dim),
                factor,
            );
            let eps = penalty_of(&case);
            let expected = 0.01 / (2.0 / e_prime + 1.0 / eps);
            let solution = solve(&case).unwrap();
            let label = format!("{dim}D, penalty {factor}");
            assert_eq!(solution.status, ContactStatus::Converged, "{label}");
            let fields = &solution.primary_fields;
            assert!(fields.active.iter().all(|&a| a), "{label}: all active");
            // The blocks' faces are unit squares (2D: unit lines); the contact pushes the
            // upper block up.
            let force = solution.force_primary[dim - 1];
            assert!(
                (force / expected - 1.0).abs() <= 1e-9,
                "{label}: mean stress {force} against {expected}"
            );
            for (p, g) in fields.pressure.iter().zip(&fields.normal_gap) {
                assert!(
                    (p / eps + g).abs() <= 1e-3 * 0.01,
                    "{label}: overlap {} against p / eps = {}",
                    -g,
                    p / eps
                );
            }
        }
    }
}

#[test]
fn the_penalty_answer_tends_to_internodes_as_the_penalty_grows() {
    // The half-disc on a block (2D Hertz, a / R about 0.1). Between penalty factors ten apart
    // the force's distance from the stiffest penalty's falls tenfold (an error of order
    // 1 / eps), and the stiffest penalty agrees with INTERNODES
    // (the same transfer): to 1e-6, the overlap of the stiffest penalty.
    let internodes = solve(&half_disc_on_block()).unwrap();
    let limit = solve(&penalized(half_disc_on_block(), 1e8)).unwrap();
    let force = |s: &ContactSolution| -s.force_primary[1];
    let difference = force(&limit) / force(&internodes) - 1.0;
    assert!(
        difference.abs() <= 1e-6,
        "1e8 against INTERNODES: {difference:+.2e}"
    );
    let mut errors = Vec::new();
    for factor in [3.0, 30.0, 300.0] {
        let solution = solve(&penalized(half_disc_on_block(), factor)).unwrap();
        assert_eq!(
            solution.status,
            ContactStatus::Converged,
            "penalty {factor}"
        );
        // The penalty only adds a positive diagonal: the loop takes the same steps.
        assert_eq!(
            solution.history.len(),
            internodes.history.len(),
            "penalty {factor}: iterations"
        );
        let error = 1.0 - force(&solution) / force(&limit);
        // The overlap indicator estimates the error from the overlap, and bounds it here.
        let estimate = indicator(&solution, CheckKind::PenaltyOverlap);
        assert!(
            error > 0.0 && estimate >= error && estimate <= 5.0 * error,
            "penalty {factor}: error {error:.3e}, estimate {estimate:.3e}"
        );
        errors.push(error);
    }
    for pair in errors.windows(2) {
        let ratio = pair[0] / pair[1];
        assert!(
            (8.0..12.0).contains(&ratio),
            "error ratio {ratio} ({errors:?})"
        );
    }
}

#[test]
fn a_tied_pair_under_the_penalty_method_is_glued_by_springs() {
    // Tied blocks on rollers: the glue's every component is a spring, and the uniaxial answer
    // is the frictionless one's, sigma = 0.01 / (2 / E' + 1 / eps), E' the constrained modulus
    // E (1 - nu) / ((1 + nu)(1 - 2 nu)) of a block on rollers.
    let e_c = 1000.0 * 0.7 / (1.3 * 0.4);
    for dim in [2, 3] {
        let case = penalized(common::contact::two_blocks_on_rollers(dim, "tied"), 1.0);
        let eps = penalty_of(&case);
        let solution = solve(&case).unwrap();
        assert_eq!(solution.status, ContactStatus::Converged, "{dim}D");
        let stress = solution.force_primary[dim - 1];
        let expected = 0.01 / (2.0 / e_c + 1.0 / eps);
        assert!(
            (stress / expected - 1.0).abs() <= 1e-9,
            "{dim}D: {stress} against {expected}"
        );
    }
}

#[test]
fn a_coulomb_pair_under_a_stiff_penalty_gives_the_internodes_answer_in_2d_and_3d() {
    // Pushed down and sideways in one step: a stick zone inside a slip annulus. The penalty
    // relaxes the normal rows only, and at 1e8 times `E* / h` the answer is INTERNODES': the
    // same nodes sticking and slipping, the force vector within 1e-6.
    let oblique = [
        half_disc_on_block().with_support("disc", "disc_top", |d| d.ux(0.002)),
        hemisphere_on_block("hemisphere_on_block.msh", 0.01, 1000.0, 1000.0).with_support(
            "sphere",
            "sphere_top",
            |d| d.ux(0.001),
        ),
    ];
    for case in oblique {
        let case = (case.contact_setting("formulation", "coulomb"))
            .contact_setting("friction_coefficient", 0.3);
        let exact = solve(&case).unwrap();
        let stiff = solve(&penalized(case, 1e8)).unwrap();
        for solution in [&exact, &stiff] {
            assert_eq!(solution.status, ContactStatus::Converged);
        }
        let states = |s: &ContactSolution| {
            let friction = s.primary_fields.friction.as_ref().expect("a Coulomb pair");
            (friction.stick_nodes, friction.slip_nodes)
        };
        assert_eq!(states(&exact), states(&stiff));
        assert!(
            states(&exact).0 > 0 && states(&exact).1 > 0,
            "{:?}",
            states(&exact)
        );
        let scale = exact
            .force_primary
            .iter()
            .map(|f| f.abs())
            .fold(0.0, f64::max);
        for (a, b) in exact.force_primary.iter().zip(&stiff.force_primary) {
            assert!((a - b).abs() <= 1e-6 * scale, "{a} against {b}");
        }
    }
}

#[test]
fn a_vanishing_penalty_ends_with_its_overlap_named() {
    // Pressures of 1e-298 once hung the Hertz fit (its SVD, on a normal of 0 / 0): the run now
    // ends, its accuracy report naming the overlap (the bodies pass through each other).
    let solution = solve(&penalized(half_disc_on_block(), 1e-300)).unwrap();
    assert!(solution.status.is_solution(), "{}", solution.status.name());
    let failed = solution.certificate.failed();
    assert!(failed.contains(&CheckKind::PenaltyOverlap), "{failed:?}");
}

/// The error a case that must be refused gets.
fn refused(case: &CaseFile) -> String {
    match solve(case) {
        Ok(solution) => panic!("solved: {}", solution.status.name()),
        Err(error) => error,
    }
}

#[test]
fn a_penalty_setting_without_the_penalty_method_is_refused_by_name() {
    let case = two_blocks(2, "frictionless").contact_setting("penalty", 10.0);
    let error = refused(&case);
    assert!(
        error.contains("penalty") && error.contains("method = \"penalty\""),
        "{error}"
    );
    for bad in [0.0, -1.0, 1e13] {
        let error = refused(&penalized(two_blocks(2, "frictionless"), bad));
        assert!(error.contains("penalty must be"), "{bad}: {error}");
    }
}
