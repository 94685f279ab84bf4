//! A mesh handed over in memory (`mesh_from_model`, what the Python module's `Mesh.from_gmsh`
//! builds): split into bodies as a file is, and refused with a message when its parts do not fit
//! together. (The Python tests check that a gmsh model and the same model written to a file give
//! the same mesh and answer.)

use std::path::Path;

use internodes::mesh::{GmshModel, MeshError, ModelElements, ModelGroup, mesh_from_model};

/// The unit square as two triangles (body "square"), its bottom edge a boundary group.
fn square() -> GmshModel {
    GmshModel {
        physical_groups: vec![
            ModelGroup {
                dim: 2,
                tag: 1,
                name: "square".into(),
                entities: vec![1],
            },
            ModelGroup {
                dim: 1,
                tag: 2,
                name: "bottom".into(),
                entities: vec![1],
            },
        ],
        num_volumes: 0,
        node_tags: vec![10, 20, 30, 40],
        coords: vec![0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0.],
        element_blocks: vec![
            ModelElements {
                entity_dim: 2,
                entity_tag: 1,
                element_type: 2,
                element_tags: vec![1, 2],
                node_tags: vec![10, 20, 30, 10, 30, 40],
            },
            ModelElements {
                entity_dim: 1,
                entity_tag: 1,
                element_type: 1,
                element_tags: vec![3],
                node_tags: vec![10, 20],
            },
        ],
    }
}

fn refusal(model: GmshModel) -> String {
    match mesh_from_model(Path::new("gmsh model 'm'"), model) {
        Err(e @ MeshError::Model { .. }) => e.to_string(),
        other => panic!("expected a model error, got {other:?}"),
    }
}

#[test]
fn a_model_is_split_into_bodies_and_groups_as_a_file_is() {
    let mesh = mesh_from_model(Path::new("gmsh model 'm'"), square()).unwrap();
    assert_eq!(mesh.dim, 2);
    let body = mesh.body("square").unwrap();
    assert_eq!(body.node_tags.to_vec(), vec![10, 20, 30, 40]);
    assert_eq!(body.cell_tags.to_vec(), vec![1, 2]);
    let bottom = body.boundary_group("bottom").unwrap();
    // The bottom edge, oriented so that its right-hand normal points out of the square (-y).
    assert_eq!(bottom.facets, vec![0, 1]);
}

#[test]
fn coordinates_that_do_not_match_the_nodes_are_refused() {
    let mut model = square();
    model.coords.pop();
    assert_eq!(
        refusal(model),
        "gmsh model 'm': 4 node tags but 11 coordinates: expected three per node"
    );
}

#[test]
fn a_node_tag_given_twice_is_refused() {
    let mut model = square();
    model.node_tags[3] = 10;
    assert_eq!(refusal(model), "gmsh model 'm': node tag 10 appears twice");
}

#[test]
fn a_coordinate_that_is_not_finite_is_refused() {
    let mut model = square();
    model.coords[4] = f64::NAN;
    assert_eq!(
        refusal(model),
        "gmsh model 'm': node 20 has a coordinate that is not finite"
    );
}

#[test]
fn elements_with_the_wrong_number_of_nodes_are_refused() {
    let mut model = square();
    model.element_blocks[0].node_tags.pop();
    assert_eq!(
        refusal(model),
        "gmsh model 'm': the 2 Tri3 elements of entity 1 (dimension 2) have 5 node tags in all: \
         expected 3 per element"
    );
    let mut model = square();
    model.element_blocks[0].element_type = 99;
    assert!(refusal(model).contains("elements of type 99, which gmsh does not define"));
}

#[test]
fn an_undefined_node_is_named_as_in_a_file() {
    let mut model = square();
    model.element_blocks[0].node_tags[2] = 50;
    let error = mesh_from_model(Path::new("gmsh model 'm'"), model).unwrap_err();
    assert!(
        matches!(
            error,
            MeshError::UndefinedNode {
                element_tag: 1,
                node_tag: 50,
                ..
            }
        ),
        "{error}"
    );
}
