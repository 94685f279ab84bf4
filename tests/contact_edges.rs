//! Contact at the edges of a surface: a stiff flat punch with sharp edges whose footprint does
//! not fall on the block's mesh lines, in 2D and 3D. A block node beside the punch faces no
//! facet of the punch's face; measured against the plane of the face's last facet it read as
//! penetrating wherever the block bulged up beside the punch, and the answer carried the force
//! of nodes the punch does not touch (3D: +5% against the rigid punch, certified accurate).

mod common;

use common::case_builder::{Body, CaseFile, Dirichlet};
use common::contact::solve_with;
use common::fixture;
use internodes::case::Case;
use internodes::contact::ContactStatus;
use internodes::elastic::SolverSettings;
use internodes::mesh::{BodyMesh, mesh_geo, read_msh};

/// The punch's half-width and shift off the origin in `offset_punch_{dim}d.geo`. In 2D the
/// shift puts a block node 0.05 spacings beyond the punch's right corner, where the plane of
/// the punch's face reached.
fn footprint(dim: usize) -> (f64, [f64; 2]) {
    match dim {
        2 => (0.25, [0.0336, 0.0]),
        _ => (0.2, [0.0137, 0.0071]),
    }
}

/// How far outside the footprint a point of the block's top is (negative inside), in the
/// footprint's plane.
fn outside_footprint(dim: usize, x: &[f64; 3]) -> f64 {
    let (w, shift) = footprint(dim);
    (0..dim - 1)
        .map(|k| (x[k] - shift[k]).abs() - w)
        .fold(f64::NEG_INFINITY, f64::max)
}

/// The `offset_punch_{dim}d.geo` fixture meshed by gmsh into `folder`.
fn mesh(dim: usize, folder: &std::path::Path) -> std::path::PathBuf {
    let msh = folder.join(format!("offset_punch_{dim}d.msh"));
    mesh_geo(&fixture(&format!("offset_punch_{dim}d.geo")), &msh, &[]).expect("gmsh meshes");
    msh
}

/// The punch (E = 1e6) pressed by `delta` onto the block (E = 1000), which is clamped at its
/// base.
fn punch_on_block(msh: &std::path::Path, dim: usize, delta: f64) -> CaseFile {
    CaseFile::new(msh)
        .contact(["punch", "block"], ["punch_face", "block_top"])
        .body(
            Body::new("punch", 1.0e6, 0.3).dirichlet(
                Dirichlet::on("punch_top")
                    .lateral(dim, 0.0)
                    .vertical(dim, -delta),
            ),
        )
        .body(Body::new("block", 1000.0, 0.3).dirichlet(Dirichlet::clamped("block_base", dim)))
}

/// The rigid frictionless punch on the same block mesh: the block alone, its base clamped and
/// its top nodes inside the footprint pushed down by `delta`, free to slide. Every one of them
/// is in compression under a flat punch, and a node outside the footprint cannot reach the
/// punch's face, so this is the discrete Signorini problem's answer. Returns the vertical
/// force.
fn rigid_punch_force(msh: &std::path::Path, dim: usize, delta: f64) -> f64 {
    let mut mesh = read_msh(msh).unwrap();
    let block: &mut BodyMesh = mesh.bodies.iter_mut().find(|b| b.name == "block").unwrap();
    let top = block.boundary_group("block_top").unwrap().nodes();
    let under: Vec<usize> = (top.into_iter())
        .filter(|&n| outside_footprint(dim, &block.coords[n]) < 0.0)
        .collect();
    block.point_groups.insert("footprint".to_string(), under);
    let alone = Body::new("block", 1000.0, 0.3)
        .dirichlet(Dirichlet::clamped("block_base", dim))
        .dirichlet(Dirichlet::on("footprint").vertical(dim, -delta));
    let (_dir, path) = CaseFile::new(msh).body(alone.clone()).write();
    let case = Case::load(&path).unwrap();
    let block = mesh.body("block").unwrap();
    let problem = case.elastic_problem(block, &case.bodies[0]).unwrap();
    let settings = SolverSettings {
        verbose: false,
        ..SolverSettings::default()
    };
    let solution = internodes::elastic::solve(&problem, &settings).unwrap();
    let reaction = (solution.reactions.iter()).find(|(name, _)| name == "footprint");
    reaction.unwrap().1[dim - 1].abs()
}

#[test]
fn a_punch_whose_footprint_is_off_the_mesh_lines_loads_only_the_nodes_under_it() {
    let folder = tempfile::tempdir().unwrap();
    for dim in [2, 3] {
        let msh = mesh(dim, folder.path());
        // The premise: no block node of the top is on the footprint's edge, to within 1e-3 of
        // a spacing (the geo script's shift).
        let mesh = read_msh(&msh).unwrap();
        let block = mesh.body("block").unwrap();
        let top = block.boundary_group("block_top").unwrap().nodes();
        let closest = (top.iter())
            .map(|&n| outside_footprint(dim, &block.coords[n]).abs())
            .fold(f64::INFINITY, f64::min);
        assert!(
            closest > 1e-4,
            "{dim}D: a block node on the footprint's edge"
        );
        for delta in [0.002, 0.004] {
            let label = format!("{dim}D punch pressed by {delta}");
            let solution = solve_with(&punch_on_block(&msh, dim, delta), false).unwrap();
            assert_eq!(solution.status, ContactStatus::Converged, "{label}");
            // The automatic choice: the compliant block carries the multiplier.
            let primary_is_block =
                (solution.primary.reactions.iter()).any(|(group, _)| group == "block_base");
            assert!(primary_is_block, "{label}: the punch was made primary");
            // Geometry: no active block node lies outside the footprint.
            let fields = &solution.primary_fields;
            let beside = (fields.nodes.iter().zip(&fields.active))
                .filter(|&(&n, &active)| active && outside_footprint(dim, &block.coords[n]) > 0.0)
                .count();
            let force = solution.force_primary[dim - 1].abs();
            let reference = rigid_punch_force(&msh, dim, delta);
            let error = force / reference - 1.0;
            eprintln!("{label}: force {error:+.5} from the rigid punch's, {beside} active beside");
            assert_eq!(beside, 0, "{label}: active block nodes beside the punch");
            assert!(
                error.abs() <= 0.005,
                "{label}: force {force} against the rigid punch's {reference}: {error:+.4}"
            );
        }
    }
}

/// `geo/tilted_cube_3d.geo` meshed by gmsh into `folder` at the edge sweep's spacings: the
/// cube 0.01 and the block 0.014 within 0.04 of the cube's lowest edge.
fn tilted_cube(folder: &std::path::Path) -> std::path::PathBuf {
    let geo = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("geo/tilted_cube_3d.geo");
    let msh = folder.join("tilted_cube_3d.msh");
    let parameters = [("h_c".to_string(), 0.01), ("h_b".to_string(), 0.014)];
    mesh_geo(&geo, &msh, &parameters).expect("gmsh meshes");
    msh
}

#[test]
fn an_edge_pressed_into_a_body_of_its_own_material_is_one_node_across_and_not_certified() {
    // The tilted cube's lowest edge pressed by 1% of its side into a block: with the cube as
    // primary the loop converges on the edge's line of nodes, one node across however long the
    // line. On a block of the cube's own material the load across the line is what the transfer
    // spreads: the answer was certified 1.9% off a same-mesh node-to-triangle reference (the
    // edge sweep's `cube-edge-equal`) while the zone's largest extent, the edge's length,
    // passed the resolution check. Against a nearly rigid block the same line is held on the
    // block's plane whatever spreads the load (the edge sweep's `cube-edge`: 0.04% off the
    // rigid plane), and the check stays as it was.
    let folder = tempfile::tempdir().unwrap();
    let msh = tilted_cube(folder.path());
    for (block_modulus, named) in [(1000.0, true), (1.0e6, false)] {
        let case = CaseFile::new(&msh)
            .contact(["cube", "block"], ["cube_contact", "block_contact"])
            .primary("cube")
            .body(
                Body::new("cube", 1000.0, 0.3).dirichlet(
                    Dirichlet::on("cube_top")
                        .lateral(3, 0.0)
                        .vertical(3, -0.004),
                ),
            )
            .body(
                Body::new("block", block_modulus, 0.3)
                    .dirichlet(Dirichlet::clamped("block_base", 3)),
            );
        let solution = solve_with(&case, false).unwrap();
        let label = format!("block E = {block_modulus}");
        assert_eq!(solution.status, ContactStatus::Converged, "{label}");
        let resolution = (solution.certificate.checks.iter())
            .find(|c| c.name == internodes::contact::CheckKind::Resolution)
            .expect("a resolution check");
        eprintln!(
            "{label}: resolution {:.3e} at {:?}",
            resolution.value, resolution.body
        );
        assert_eq!(!resolution.passed, named, "{label}: {resolution:?}");
        if named {
            // One node across: the figure is the cap of a zone without width.
            assert!(resolution.value > 100.0, "{label}: {resolution:?}");
        }
    }
}
