//! Floating bodies: a body in contact whose supports leave it free to move is held by its
//! contact. Its free rigid motions are pinned by zero-force unknowns, which leave it exactly as
//! free as without them; the independent measures are equilibrium (the contact carries the
//! load, computed from the geometry) and the same body held by a support at the displacement
//! the floating solve found there (the same field, and no reaction). A contact that cannot hold
//! a free motion is an error that names the body.

mod common;

use common::case_builder::{Body, CaseFile, Dirichlet, Load};
use common::contact::stacked_blocks;
use common::hostile::displacement_by_tag;
use common::{read_fixture, run_solve, run_to_summary};

const PRESSURE: f64 = 10.0;

/// The stacked 2D blocks, the lower one held at its base and corner, the upper one held only
/// by `upper` (its Dirichlet conditions) and pressed down by a uniform pressure on its top.
fn floating_upper(upper: Vec<Dirichlet>) -> CaseFile {
    stacked_blocks(2)
        .support("lower", Dirichlet::on("lower_corner").ux(0.0))
        .with_body("upper", |body| {
            Body {
                dirichlet: upper,
                ..body
            }
            .load(Load::pressure("upper_top", PRESSURE))
        })
}

/// The width of the upper block's top, from the mesh: the pressure's resultant over it.
fn top_width() -> f64 {
    let mesh = read_fixture("two_blocks_2d.msh");
    let upper = mesh.bodies.iter().find(|b| b.name == "upper").unwrap();
    let xs: Vec<f64> = (upper.group_nodes("upper_top").unwrap().iter())
        .map(|&n| upper.coords[n][0])
        .collect();
    xs.iter().cloned().fold(f64::MIN, f64::max) - xs.iter().cloned().fold(f64::MAX, f64::min)
}

/// The gmsh tag of the upper block's corner point.
fn corner_tag() -> i64 {
    let mesh = read_fixture("two_blocks_2d.msh");
    let upper = mesh.bodies.iter().find(|b| b.name == "upper").unwrap();
    let nodes = upper.group_nodes("upper_corner").unwrap();
    upper.node_tags.get(nodes[0]) as i64
}

#[test]
fn a_block_held_only_sideways_rests_on_its_contact() {
    // Held at one corner sideways: its vertical motion and rotation are free, and its flat
    // contact holds both.
    let (dir, summary) =
        run_to_summary(&floating_upper(vec![Dirichlet::on("upper_corner").ux(0.0)]));
    let contact = &summary["contact"];
    assert_eq!(contact["status"], "converged", "{contact}");
    let load = PRESSURE * top_width();
    let carried = contact["force_primary"][1].as_f64().unwrap();
    assert!(
        (carried - load).abs() <= 1e-8 * load,
        "the contact carries {carried}, the pressure's resultant is {load}"
    );
    // No pin shows as a force-controlled group.
    assert_eq!(contact["steps"][0]["forced"], serde_json::json!([]));

    // The same block held at its corner vertically too, at the displacement the floating
    // solve found there: the same field, and the support carries nothing.
    let floating = displacement_by_tag(&dir.path().join("out"));
    let corner = &floating[&corner_tag()];
    let (held_dir, held) = run_to_summary(&floating_upper(vec![
        Dirichlet::on("upper_corner").ux(0.0).uy(corner[1]),
    ]));
    assert_eq!(held["contact"]["status"], "converged");
    let reaction = held["bodies"]
        .as_array()
        .unwrap()
        .iter()
        .find(|b| b["name"] == "upper")
        .unwrap()["reactions"]["upper_corner"][1]
        .as_f64()
        .unwrap();
    assert!(reaction.abs() <= 1e-8 * load, "corner reaction {reaction}");
    let held = displacement_by_tag(&held_dir.path().join("out"));
    let largest = (floating.values().flatten()).fold(0.0_f64, |m, v| m.max(v.abs()));
    let worst = (floating.iter())
        .flat_map(|(tag, u)| u.iter().zip(&held[tag]).map(|(a, b)| (a - b).abs()))
        .fold(0.0_f64, f64::max);
    assert!(worst <= 1e-8 * largest, "{worst} of {largest}");
}

#[test]
fn a_free_block_is_held_by_tied_contact() {
    let (_dir, summary) =
        run_to_summary(&floating_upper(Vec::new()).contact_setting("formulation", "tied"));
    let contact = &summary["contact"];
    assert_eq!(contact["status"], "converged", "{contact}");
    let load = PRESSURE * top_width();
    let force = &contact["force_primary"];
    assert!(
        (force[1].as_f64().unwrap() - load).abs() <= 1e-8 * load,
        "{force}"
    );
    assert!(force[0].as_f64().unwrap().abs() <= 1e-8 * load, "{force}");
}

#[test]
fn a_free_block_on_frictionless_contact_is_refused_by_name() {
    // Nothing holds it sideways: frictionless contact on a flat surface lets it slide.
    let (_dir, path) = floating_upper(Vec::new()).write();
    let output = run_solve(&path);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success(), "{stderr}");
    for word in ["body 'upper'", "does not hold it", "1 of its rigid motions"] {
        assert!(stderr.contains(word), "no {word:?} in {stderr}");
    }
}

#[test]
fn a_block_held_only_sideways_rests_on_its_contact_3d() {
    // Pinned sideways at two corners: its vertical motion and the two tilts are free, and the
    // flat contact holds all three.
    let case = stacked_blocks(3)
        .support("lower", Dirichlet::on("lower_corner_a").ux(0.0).uy(0.0))
        .support("lower", Dirichlet::on("lower_corner_b").uy(0.0))
        .with_body("upper", |body| {
            Body {
                dirichlet: vec![
                    Dirichlet::on("upper_corner_a").ux(0.0).uy(0.0),
                    Dirichlet::on("upper_corner_b").uy(0.0),
                ],
                ..body
            }
            .load(Load::pressure("upper_top", PRESSURE))
        });
    let (_dir, summary) = run_to_summary(&case);
    let contact = &summary["contact"];
    assert_eq!(contact["status"], "converged", "{contact}");
    let mesh = read_fixture("two_blocks_3d.msh");
    let upper = mesh.bodies.iter().find(|b| b.name == "upper").unwrap();
    let top = upper.group_nodes("upper_top").unwrap();
    let extent = |c: usize| {
        let v: Vec<f64> = top.iter().map(|&n| upper.coords[n][c]).collect();
        v.iter().cloned().fold(f64::MIN, f64::max) - v.iter().cloned().fold(f64::MAX, f64::min)
    };
    let load = PRESSURE * extent(0) * extent(1);
    let carried = contact["force_primary"][2].as_f64().unwrap();
    assert!(
        (carried - load).abs() <= 1e-8 * load,
        "{carried} against {load}"
    );
}

#[test]
fn a_half_disc_free_to_turn_about_its_centre_is_refused() {
    // Held sideways along its flat top only: it may turn about the top's midpoint, its centre,
    // and a frictionless contact on its round surface cannot hold that.
    let case = common::half_disc_on_block("half_disc_on_block.msh").with_body("disc", |body| {
        Body {
            dirichlet: vec![Dirichlet::on("disc_top").ux(0.0)],
            ..body
        }
        .load(Load::pressure("disc_top", 2.5))
    });
    let (_dir, path) = case.write();
    let output = run_solve(&path);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success(), "{stderr}");
    for word in [
        "body 'disc'",
        "does not hold it",
        "1 of its rigid motions",
        "round body",
    ] {
        assert!(stderr.contains(word), "no {word:?} in {stderr}");
    }
}
