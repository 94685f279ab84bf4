//! A 2D square's 90 degree corner pressed into a block (`geo/tilted_square_2d.geo`, meshed at
//! test time, coarse: 0.004 at the corner, the block 1.4 times coarser). Against a stiff block the
//! corner is solved and certified. Against a block of the same material it digs a crater, whose
//! bottom is a concave vertex of the block's surface: the corner's node is held against both
//! walls (`internodes::contact::walls`), the pairing follows its slide at every iteration, and
//! `auto` takes the square as primary with the conservative transfer; the answer is within 1% of
//! the same-mesh two-body reference where the zone spans more than a spacing, and named by the
//! resolution indicator where it does not (`docs/method.md` 4.1).

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

/// The corner pressed into a block of either modulus, `primary = "auto"`: solved, the square
/// carrying the multiplier, the force within 1% of the same-mesh reference at 2% and 4% of the
/// side. The equal block's zones span one to three spacings of this coarse mesh, which the
/// resolution indicator names (at 1% the force is 1.7% off); the stiff block's at 4% is the
/// control, certified.
#[test]
fn a_corner_pressed_into_a_block_of_its_own_material_agrees_with_the_same_mesh_reference() {
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
        assert_eq!(solution.status, ContactStatus::Converged, "{label}");
        let on_square = (solution.primary.reactions.iter()).any(|(group, _)| group == "square_top");
        assert!(on_square, "{label}: the square is auto's primary");
        if block > 1000.0 {
            assert!(failed.is_empty(), "{label}: {failed:?}");
        } else {
            // This coarse mesh resolves no zone: every run's accuracy report names it.
            assert_eq!(failed, [CheckKind::Resolution], "{label}");
        }
        if delta > 0.004 {
            assert!(error.abs() <= 0.01, "{label}: force {error:+.4}");
        }
    }
}

/// Refined eight times (the corner at 0.0005), the same corner pressed by 2% of its side into an
/// equal block, the block named primary: the square's corner cuts into the block between the
/// block's nodes, and the block's surface slides along the crater's two walls, in opposite
/// directions, by more spacings than the pairing follows before any set settles (the pairing
/// follows at every iteration only a corner of the primary). The run ends refused, and its
/// explanation names the slide, not a stiff primary (both bodies are of one material).
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
