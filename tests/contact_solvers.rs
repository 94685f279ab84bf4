//! The linear solvers of a contact iteration give the same answer: the dense Schur
//! complement, sparse LU of the whole system, GMRES on the interface, CG + AMG bodies.

mod common;

use common::contact::{
    half_disc_on_block, hemisphere_on_block, narrow_blocks, solve, two_blocks_on_rollers,
};
use internodes::contact::ContactSolution;

/// The largest `|a - b|` over the largest `|b|`.
fn relative_difference(a: &[f64], b: &[f64]) -> f64 {
    let max = |v: &mut dyn Iterator<Item = f64>| v.fold(0.0f64, |m, x| m.max(x.abs()));
    let diff = max(&mut a.iter().zip(b).map(|(x, y)| x - y));
    let scale = max(&mut b.iter().copied());
    if scale > 0.0 { diff / scale } else { diff }
}

/// `a` (a solve through the interface GMRES) against `b` (the dense Schur path): the same
/// active-set history and status, and displacements, pressures and forces within `tolerance`.
fn assert_same_contact(a: &ContactSolution, b: &ContactSolution, tolerance: f64, label: &str) {
    assert_eq!(a.status, b.status, "{label}: status");
    assert_eq!(a.history.len(), b.history.len(), "{label}: iterations");
    for (x, y) in a.history.iter().zip(&b.history) {
        assert_eq!(
            (x.active, x.added, x.removed),
            (y.active, y.added, y.removed),
            "{label}: active sets"
        );
    }
    let pairs = [
        (
            "primary displacement",
            &a.primary.displacement,
            &b.primary.displacement,
        ),
        (
            "secondary displacement",
            &a.secondary.displacement,
            &b.secondary.displacement,
        ),
        (
            "pressure",
            &a.primary_fields.pressure,
            &b.primary_fields.pressure,
        ),
    ];
    for (name, x, y) in pairs {
        let difference = relative_difference(x, y);
        eprintln!("{label}: {name} differs by {difference:.1e} relative");
        assert!(
            difference <= tolerance,
            "{label}: {name} differs by {difference:.2e}"
        );
    }
    let force = relative_difference(&a.force_primary, &b.force_primary);
    eprintln!("{label}: force differs by {force:.1e} relative");
    assert!(force <= tolerance, "{label}: force differs by {force:.2e}");
}

#[test]
fn schur_and_monolithic_solves_agree() {
    // The factor-once Schur path against the sparse LU of the whole system, on a case with a
    // partial active set (2D Hertz) and on the 3D patch test, both formulations.
    let cases = [
        half_disc_on_block(),
        half_disc_on_block().contact_setting("formulation", "tied"),
        two_blocks_on_rollers(3, "frictionless"),
        two_blocks_on_rollers(3, "tied"),
    ];
    for case in cases {
        let schur = solve(&case.clone().contact_setting("solver", "schur")).unwrap();
        let lu = solve(&case.contact_setting("solver", "monolithic-lu")).unwrap();
        assert_eq!(schur.history.len(), lu.history.len());
        let max = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for (a, b) in [
            (&schur.primary, &lu.primary),
            (&schur.secondary, &lu.secondary),
        ] {
            let diff: Vec<f64> = a
                .displacement
                .iter()
                .zip(&b.displacement)
                .map(|(x, y)| x - y)
                .collect();
            assert!(
                max(&diff) <= 1e-8 * max(&b.displacement),
                "displacement differs by {:.2e}",
                max(&diff)
            );
        }
        let (pa, pb) = (&schur.primary_fields.pressure, &lu.primary_fields.pressure);
        let diff: Vec<f64> = pa.iter().zip(pb).map(|(x, y)| x - y).collect();
        assert!(
            max(&diff) <= 1e-8 * max(pb),
            "pressure differs by {:.2e}",
            max(&diff)
        );
        assert!(schur.history.iter().all(|h| h.relative_residual < 1e-10));
    }
}

#[test]
fn krylov_and_schur_solves_agree() {
    // The coupled GMRES against the dense Schur complement, both on Cholesky factors: 2D
    // Hertz (a partial active set, both formulations), the 3D patch test (both formulations),
    // the 3D Hertz hemisphere (a partial set reached after several iterations), the
    // conservative transfer, two load steps (the second from the first's set, warm start and
    // `K^-1 f`) and a slide (the operators paired again).
    //
    // GMRES stops early on the iterations that change the active set (`LOOSE_RTOL` in
    // src/contact/coupled/coupled_krylov.rs), so the next iteration's gaps are linearized at a slightly
    // different point. Where the active set is right from the first solve (the patch tests,
    // the 2D cases here) the two paths solve the same systems and agree to round-off. On the
    // 3D hemisphere they reach the same active sets and each final iterate holds its active
    // gaps within the settled tolerance (`SETTLED` = 0.01 of the penetration tolerance 1e-3
    // h, 1e-5 h), so the answers may differ by that much: 1e-5 h / delta = 1.5e-5 relative
    // for h = R/67, delta = 0.01 R. 1e-6 asks for fifteen times less.
    let cases = [
        ("2D frictionless", half_disc_on_block(), 1e-8),
        (
            "2D tied",
            half_disc_on_block().contact_setting("formulation", "tied"),
            1e-8,
        ),
        (
            "3D patch frictionless",
            two_blocks_on_rollers(3, "frictionless"),
            1e-8,
        ),
        ("3D patch tied", two_blocks_on_rollers(3, "tied"), 1e-8),
        (
            "3D Hertz",
            hemisphere_on_block("hemisphere_on_block_hertz.msh", 0.01, 1000.0, 1000.0),
            1e-6,
        ),
        (
            "2D conservative transfer",
            narrow_blocks()
                .primary("upper")
                .contact_setting("transfer", "conservative"),
            1e-8,
        ),
        (
            "2D load steps",
            half_disc_on_block().load_steps(&[0.5, 1.0]),
            1e-8,
        ),
        (
            "2D slid",
            common::half_disc_on_block("half_disc_on_block.msh").with_support(
                "disc",
                "disc_top",
                |d| d.ux(0.1),
            ),
            1e-8,
        ),
    ];
    for (label, case, tolerance) in cases {
        let with = |solver: &str| case.clone().contact_setting("solver", solver);
        let krylov = solve(&with("krylov")).unwrap();
        let schur = solve(&with("schur")).unwrap();
        assert_same_contact(&krylov, &schur, tolerance, label);
        // Iterations that change the active set may stop GMRES early (a loose solve); the
        // answer is the last iteration's, solved to round-off.
        let last = krylov.history.last().unwrap();
        assert!(last.relative_residual < 1e-10, "{label}: {last:?}");
        assert_eq!(krylov.linear_solvers.interface, "krylov");
        assert_eq!(schur.linear_solvers.interface, "schur");
    }
}

#[test]
fn a_gmres_failure_under_auto_moves_to_the_schur_complement_with_the_same_answer() {
    // GMRES capped at one iteration cannot solve an interface problem started cold: under
    // `auto` the failing solve and every later one go to the dense Schur complement, the
    // answer is the Schur path's to round-off (every solve that counts is a Schur solve), and
    // `linear_solvers` says why. Under `krylov` the same failure ends the run with an error
    // naming it, never an answer.
    let cases = [
        (
            "2D Hertz",
            half_disc_on_block().contact_setting("krylov_max_iterations", 1),
        ),
        (
            "3D Hertz",
            hemisphere_on_block("hemisphere_on_block_hertz.msh", 0.01, 1000.0, 1000.0)
                .contact_setting("krylov_max_iterations", 1),
        ),
    ];
    for (label, case) in cases {
        let with = |solver: &str| case.clone().contact_setting("solver", solver);
        let auto = solve(&with("auto")).unwrap();
        let schur = solve(&with("schur")).unwrap();
        assert_same_contact(&auto, &schur, 1e-10, label);
        assert_eq!(auto.linear_solvers.interface, "schur", "{label}");
        let failure = auto.linear_solvers.krylov_failure.as_deref();
        assert!(
            failure.is_some_and(|why| why.contains("iteration limit")),
            "{label}: {failure:?}"
        );
        assert_eq!(schur.linear_solvers.krylov_failure, None, "{label}");
        let message = solve(&with("krylov"))
            .err()
            .expect("an error, not an answer");
        assert!(
            message.contains("coupled GMRES did not converge (iteration limit reached"),
            "{label}: {message}"
        );
        // The message names the setting and the way out.
        assert!(
            message.contains("krylov_max_iterations") && message.contains("solver = \"auto\""),
            "{label}: {message}"
        );
    }
}

#[test]
fn a_gmres_failure_with_cg_amg_bodies_factors_the_matrices_petsc_holds() {
    // With CG + AMG bodies a contact solve keeps each K_c only as PETSc's copy; the fallback of
    // `auto` after a GMRES failure factors a copy of it, and the answer is the Schur path's on
    // Cholesky bodies.
    let case = hemisphere_on_block("hemisphere_on_block_hertz.msh", 0.01, 1000.0, 1000.0);
    let auto = solve(
        &(case.clone())
            .body_solver("cg-amg")
            .contact_setting("krylov_max_iterations", 1),
    )
    .unwrap();
    let schur = solve(&(case.body_solver("cholesky")).contact_setting("solver", "schur")).unwrap();
    assert_eq!(auto.linear_solvers.body, "cholesky");
    assert_eq!(auto.linear_solvers.interface, "schur");
    assert!(auto.linear_solvers.krylov_failure.is_some());
    assert_same_contact(&auto, &schur, 1e-10, "CG + AMG bodies, then Cholesky");
}

#[test]
fn cg_amg_bodies_take_the_krylov_path_and_agree_with_cholesky() {
    // With CG + AMG bodies, `schur` runs the coupled GMRES (one V-cycle per body and
    // iteration, no per-node CG solves), to the same relative residual as on Cholesky factors.
    let case = hemisphere_on_block("hemisphere_on_block_hertz.msh", 0.01, 1000.0, 1000.0);
    let cholesky = solve(&case.clone().body_solver("cholesky")).unwrap();
    let cg = solve(&case.body_solver("cg-amg")).unwrap();
    assert_same_contact(&cg, &cholesky, 1e-6, "CG + AMG");
}
