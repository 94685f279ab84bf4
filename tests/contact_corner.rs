//! A 2D square's 90 degree corner pressed into a block (`geo/tilted_square_2d.geo`, meshed at
//! test time, coarse: 0.004 at the corner, the block 1.4 times coarser). Against a stiff block the
//! corner is solved and certified; against a block of the same material the loop does not settle
//! in the crater the corner digs, and the answers it stops on are wrong. Where the tension bound
//! alone refuses such an answer, by 2% to 7% of the bound, the force is 15% to 54% off the
//! same-mesh two-body reference; where the equilibrium bound alone refuses one (0.026 against
//! 0.01), 1.7% off. The bounds are the scales of what they measure, not numbers to loosen for
//! corners (`docs/method.md` 4.1).

mod common;

use std::path::{Path, PathBuf};

use common::case_builder::{Body, CaseFile, Dirichlet};
use common::contact::solve_with;
use internodes::contact::{CheckKind, ContactSolution, ContactStatus};
use internodes::mesh::mesh_geo;

/// `geo/tilted_square_2d.geo` meshed by gmsh into `folder`: the square's corner at 0.004, the
/// block's top at 0.0056 there.
fn mesh(folder: &Path) -> PathBuf {
    mesh_at(folder, 0.004)
}

/// `geo/tilted_square_2d.geo` meshed by gmsh into `folder`: the square's corner at `h`, the
/// block's top at `1.4 h` there.
fn mesh_at(folder: &Path, h: f64) -> PathBuf {
    let geo = Path::new(env!("CARGO_MANIFEST_DIR")).join("geo/tilted_square_2d.geo");
    let msh = folder.join("tilted_square_2d.msh");
    let parameters = [("h_c".to_string(), h), ("h_b".to_string(), 1.4 * h)];
    mesh_geo(&geo, &msh, &parameters).expect("gmsh meshes");
    msh
}

/// The square (E = 1000) pressed by `delta` (its two upper sides moved down, held sideways)
/// into the block of modulus `block`, clamped at its base; `primary = "auto"`.
fn corner_on_block(msh: &Path, delta: f64, block: f64) -> CaseFile {
    CaseFile::new(msh)
        .contact(["square", "block"], ["square_contact", "block_contact"])
        .body(
            Body::new("square", 1000.0, 0.3).dirichlet(
                Dirichlet::on("square_top")
                    .lateral(2, 0.0)
                    .vertical(2, -delta),
            ),
        )
        .body(Body::new("block", block, 0.3).dirichlet(Dirichlet::clamped("block_base", 2)))
}

/// The vertical contact force on the square.
fn force_on_square(solution: &ContactSolution) -> f64 {
    let on_square = (solution.primary.reactions.iter()).any(|(group, _)| group == "square_top");
    let force = match on_square {
        true => solution.force_primary,
        false => solution.force_secondary,
    };
    force[1]
}

/// The same-mesh two-body reference, `validation/edge_reference.py` `two_body_solve` on this
/// mesh (dolfinx's stiffness matrices, node to segment from the square onto the block on the
/// deformed surfaces, solved to convergence): `(delta, E_block, force)`.
const REFERENCE: [(f64, f64, f64); 4] = [
    (0.004, 1000.0, 0.475055),
    (0.008, 1000.0, 0.984694),
    (0.016, 1000.0, 2.224485),
    (0.016, 1.0e6, 3.930092),
];

#[test]
fn a_corner_on_an_equal_block_refused_by_a_residual_bound_alone_is_wrong() {
    let folder = tempfile::tempdir().unwrap();
    let msh = mesh(folder.path());
    for (delta, block, reference) in REFERENCE {
        let label = format!("corner pressed by {delta} into a block of E = {block}");
        let solution = solve_with(&corner_on_block(&msh, delta, block), false).unwrap();
        let error = force_on_square(&solution) / reference - 1.0;
        let failed = solution.certificate.failed();
        eprintln!(
            "{label}: {}, force {error:+.4} from the reference, failed {failed:?}",
            solution.status.name()
        );
        if block > 1000.0 {
            // The control: a corner on a stiff block is solved, certified and right (at 4% of
            // the side: at 1% and 2% the zone is one or two nodes across, which the resolution
            // indicator names).
            assert_eq!(solution.status, ContactStatus::Converged, "{label}");
            assert!(solution.certificate.accurate(), "{label}: {failed:?}");
            assert!(error.abs() <= 0.01, "{label}: force {error:+.4}");
            continue;
        }
        // Not solved, not merely inaccurate: the answer is far off, and where only the tension
        // bound refuses it (by 2% to 7% of the bound) that bound is all that keeps it from being
        // called solved (exit 3, with its accuracy report failed) or, were the indicators to
        // pass, certified.
        assert!(
            !solution.status.is_solution(),
            "{label}: {} with the force {error:+.4} off",
            solution.status.name()
        );
        let residuals: Vec<CheckKind> = (failed.iter().copied())
            .filter(|kind| kind.is_residual())
            .collect();
        if residuals == [CheckKind::Tension] {
            let tension = (solution.certificate.residuals())
                .find(|check| check.name == CheckKind::Tension)
                .unwrap();
            assert!(
                tension.value <= 1.1 * tension.tolerance,
                "{label}: refused by tension {} against {}: not the margin this test is about",
                tension.value,
                tension.tolerance
            );
            assert!(
                error.abs() > 0.1,
                "{label}: refused by its tension bound alone with a force {error:+.4} off"
            );
        }
    }
}

/// Refined eight times (the corner at 0.0005), the same corner pressed by 2% of its side into an
/// equal block, the block primary: the block's surface slides along the crater's two walls, in
/// opposite directions, by more spacings than the pairing follows before any set settles. The
/// run ends refused, and its explanation names the slide, not a stiff primary (both bodies
/// are of one material).
#[test]
fn a_corner_whose_surfaces_slide_off_their_pairing_is_refused_and_says_so() {
    let folder = tempfile::tempdir().unwrap();
    let msh = mesh_at(folder.path(), 0.0005);
    let case = corner_on_block(&msh, 0.008, 1000.0).primary("block");
    let solution = solve_with(&case, false).unwrap();
    assert!(!solution.status.is_solution(), "{}", solution.status.name());
    let slid = solution.history.last().unwrap().pairing_drift_over_h;
    assert!(slid >= 1.0, "slid {slid} spacings");
    let summary = solution.summary();
    assert!(
        summary.contains(&format!("had slid {slid:.1} spacings")),
        "{summary}"
    );
    assert!(!summary.contains("stiffer"), "{summary}");
}
