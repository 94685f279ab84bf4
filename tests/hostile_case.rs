//! Case files that are wrong but were once accepted, or rejected with a vague message: every
//! error names the file, the key or group, and what was expected.

mod common;

use std::path::PathBuf;

use common::case_builder::{Body, CaseFile, Dirichlet, Load};
use common::hostile::{
    assert_failed_without_results, case_failure, run_error, run_quiet, square_case, two_blocks_case,
};
use common::{fixture, half_disc_on_block};

// The faults here are values a case file may hold (a NaN, a group of the wrong kind), built
// with the typed case builder; misspelled keys and TOML syntax are tested in `cli.rs` and
// `hostile_output_folder.rs` on the builder's text.

/// A case on `geo/{geo}` with the one `geo_parameters` entry `parameter = value`.
fn geo_case(geo: &str, parameter: &str, value: impl Into<toml::Value>) -> CaseFile {
    let geo = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("geo")
        .join(geo);
    CaseFile::new(geo)
        .geo_parameter(parameter, value)
        .body(Body::new("block", 1000.0, 0.3).dirichlet(Dirichlet::clamped("block_base", 2)))
}

/// A case on `glued_blocks_{dim}d.msh` (`lower` below `upper`, their union, the `interface`
/// between them): `body` clamped on `lower_base`, `load` on `interface`.
fn glued_case(dim: usize, body: &str, load: Load) -> CaseFile {
    CaseFile::on_fixture(&format!("glued_blocks_{dim}d.msh")).body(
        Body::new(body, 1000.0, 0.3)
            .dirichlet(Dirichlet::clamped("lower_base", dim))
            .load(load),
    )
}

/// The force in the direction `dim - 1` on `lower_base` of the run of `case`.
fn base_reaction(case: &CaseFile, dim: usize) -> f64 {
    let (_dir, path) = case.write();
    let report = run_quiet(&path).unwrap_or_else(|e| panic!("{e}\n{}", case.to_toml()));
    report.summary.bodies[0].reactions["lower_base"][dim - 1]
}

#[test]
fn a_contact_case_with_a_bad_extra_body_fails_before_solving() {
    // The contact bodies are fine, a third [[body]] is not in the mesh: nothing may be solved
    // or written (the old run solved the contact and left force_displacement.csv).
    let (dir, path) = half_disc_on_block("half_disc_on_block.msh")
        .body(Body::new("third", 1.0, 0.3))
        .write();
    let e = run_error(&path, "no body 'third'");
    assert!(e.to_string().contains("'third'"), "{e}");
    assert_failed_without_results(&dir.path().join("out"), "'third'");
}

#[test]
fn a_body_in_two_body_tables_is_an_error() {
    let message = case_failure(&two_blocks_case(&fixture("two_blocks_2d.msh"), "lower"));
    assert!(
        message.contains("body 'lower' has two [[body]] tables"),
        "{message}"
    );
}

#[test]
fn geo_parameters_the_script_does_not_use_are_errors() {
    let message = case_failure(&geo_case("block_2d.geo", "levle", 1));
    assert!(
        message.contains("geo_parameters.levle") && message.contains("level"),
        "{message}"
    );
}

#[test]
fn non_finite_geo_parameters_are_errors() {
    let message = case_failure(&geo_case("block_2d.geo", "level", f64::NAN));
    assert!(
        message.contains("geo_parameters.level") && message.contains("finite"),
        "{message}"
    );
}

#[test]
fn geo_parameters_beside_a_msh_are_errors() {
    let message =
        case_failure(&square_case("square_sorted.msh", &[1.0, 0.0]).geo_parameter("level", 1));
    assert!(
        message.contains("geo_parameters") && message.contains("not a .geo"),
        "{message}"
    );
}

#[test]
fn load_steps_beyond_the_bound_are_errors() {
    let steps = vec![1.0; internodes::case::MAX_LOAD_STEPS + 1];
    let message = case_failure(&half_disc_on_block("half_disc_on_block.msh").load_steps(&steps));
    assert!(
        message.contains("load_steps") && message.contains("at most 1000"),
        "{message}"
    );
}

#[test]
fn non_finite_loads_are_errors_naming_the_load() {
    for load in [
        Load::traction("right", &[f64::NAN, 0.0]),
        Load::pressure("right", f64::NAN),
        Load::pressure("right", f64::INFINITY),
        Load::hertz("right", f64::NAN, 0.5, &[0.0, 0.0]),
    ] {
        let case = square_case("square_sorted.msh", &[1.0, 0.0]).with_body("square", |b| Body {
            loads: vec![load.clone()],
            ..b
        });
        let message = case_failure(&case);
        assert!(
            message.contains("body 'square', load on 'right'") && message.contains("finite"),
            "{load:?}: {message}"
        );
    }
    let case = square_case("square_sorted.msh", &[1.0, 0.0])
        .with_body("square", |b| b.body_force(&[0.0, f64::NAN]));
    let message = case_failure(&case);
    assert!(
        message.contains("body_force") && message.contains("finite"),
        "{message}"
    );
}

#[test]
fn finite_values_that_overflow_downstream_are_rejected_naming_the_key_and_range() {
    // Each was accepted and failed in the solve with an unmet residual or a singular matrix
    // that named neither the key nor the value.
    let square = |change: &dyn Fn(Body) -> Body| {
        square_case("square_sorted.msh", &[1.0, 0.0]).with_body("square", change)
    };
    let load = |load: Load| {
        square(&|b| Body {
            loads: vec![load.clone()],
            ..b
        })
    };
    let modulus = |e: f64| {
        square(&|b| Body {
            youngs_modulus: e,
            ..b
        })
    };
    let half_disc = || half_disc_on_block("half_disc_on_block.msh");
    let range = "of magnitude at most 1e40";
    for (case, key, expected) in [
        (
            load(Load::traction("right", &[1e308, 0.0])),
            "load on 'right'",
            range,
        ),
        (
            load(Load::pressure("right", 1e308)),
            "load on 'right', pressure",
            range,
        ),
        (
            load(Load::hertz("right", 1e308, 0.5, &[0.0, 0.0])),
            "hertz_pressure.p0",
            range,
        ),
        (
            square(&|b| b.body_force(&[1e308, 0.0])),
            "body_force",
            range,
        ),
        (
            square_case("square_sorted.msh", &[1.0, 0.0])
                .with_support("square", "left", |d| d.ux(1e308)),
            "Dirichlet condition on 'left', ux",
            range,
        ),
        (modulus(1e308), "youngs_modulus", "from 1e-40 to 1e40"),
        (modulus(1e-300), "youngs_modulus", "from 1e-40 to 1e40"),
        (half_disc().load_steps(&[1e300]), "load_steps", range),
        (
            half_disc().contact_setting("rbf_radius", 1e300),
            "rbf_radius",
            "<= 10",
        ),
        (
            half_disc().contact_setting("rbf_radius", 1e9),
            "rbf_radius",
            "<= 10",
        ),
        (
            half_disc().contact_setting("krylov_max_iterations", 0),
            "krylov_max_iterations",
            "between 1 and 10000",
        ),
    ] {
        let message = case_failure(&case);
        assert!(
            message.contains("case.toml") && message.contains(key) && message.contains(expected),
            "{key}: {message}"
        );
    }
}

#[test]
fn a_load_on_a_point_group_says_a_boundary_group_is_needed() {
    let case =
        two_blocks_case(&fixture("two_blocks_2d.msh"), "upper").with_body("lower", |b| Body {
            loads: vec![Load::traction("lower_corner", &[0.0, -1.0])],
            ..b
        });
    let message = case_failure(&case);
    assert!(
        message.contains("load on 'lower_corner'")
            && message.contains("group of points")
            && message.contains("physical curve"),
        "{message}"
    );
}

#[test]
fn a_pressure_on_a_group_inside_the_body_is_an_error_in_2d_and_3d() {
    // The interface of the two blocks lies inside their union: its facets are shared by two
    // cells, and the run once succeeded with zero reaction.
    for dim in [2, 3] {
        let center: &[f64] = if dim == 2 {
            &[0.5, 0.0]
        } else {
            &[0.5, 0.5, 0.0]
        };
        for load in [
            Load::pressure("interface", 1.0),
            Load::hertz("interface", 1.0, 0.5, center),
        ] {
            let message = case_failure(&glued_case(dim, "union", load.clone()));
            assert!(
                message.contains("load on 'interface'")
                    && message.contains("inside the body")
                    && message.contains("two cells of 'union'")
                    && message.contains("a pressure needs a boundary group"),
                "{dim}D, {load:?}: {message}"
            );
        }
    }
}

#[test]
fn a_pressure_on_the_interface_of_two_bodies_loads_each_as_a_boundary() {
    // The same interface is a boundary of `lower` alone (one cell per facet): a unit pressure on
    // its unit length (2D) or area (3D) is balanced by the clamped base, to round-off.
    for dim in [2, 3] {
        let reaction = base_reaction(
            &glued_case(dim, "lower", Load::pressure("interface", 1.0)),
            dim,
        );
        assert!((reaction - 1.0).abs() < 1e-10, "{dim}D: {reaction}");
    }
}

#[test]
fn a_traction_on_a_group_inside_the_body_is_a_line_or_surface_force() {
    // A traction vector does not depend on the side: inside the union it is a force of 2 per
    // unit length (area) over the unit interface, balanced by the base.
    for dim in [2, 3] {
        let traction: &[f64] = if dim == 2 {
            &[0.0, 2.0]
        } else {
            &[0.0, 0.0, 2.0]
        };
        let case = glued_case(dim, "union", Load::traction("interface", traction));
        let reaction = base_reaction(&case, dim);
        assert!((reaction + 2.0).abs() < 1e-10, "{dim}D: {reaction}");
    }
}

#[test]
fn a_curve_of_a_3d_body_named_as_a_boundary_group_is_an_error_saying_so() {
    // The reader keeps no edges of a 3D mesh, so 'base_edge' was reported as missing from the
    // body, though `info` lists it.
    let clamped = |group: &str| {
        CaseFile::on_fixture("cube_edge_group.msh").body(
            Body::new("block", 1000.0, 0.3)
                .dirichlet(Dirichlet::clamped(group, 3))
                .load(Load::pressure("block_top", 1.0)),
        )
    };
    let message = case_failure(&clamped("base_edge"));
    assert!(
        message.contains("group 'base_edge'")
            && message.contains("is a physical curve of")
            && message.contains("a curve of a 3D body, which is not a boundary group")
            && message.contains("physical surfaces"),
        "{message}"
    );
    let message = case_failure(&clamped("block"));
    assert!(
        message.contains("'block' is a physical volume") && message.contains("a body"),
        "{message}"
    );
    // The base itself is a boundary group: a unit pressure on the unit top is carried by it.
    let (_dir, path) = clamped("block_base").write();
    let report = run_quiet(&path).unwrap();
    let reaction = report.summary.bodies[0].reactions["block_base"][2];
    assert!((reaction - 1.0).abs() < 1e-10, "{reaction}");
}
