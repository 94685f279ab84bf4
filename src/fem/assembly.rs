//! The numeric phase of assembly: element kernels scattered into a [`SparsityPattern`].

use faer::sparse::SparseColMat;

use super::kernels::{
    facet_mass, facet_measure_and_normal, tetrahedron_stiffness, triangle_stiffness,
};
use super::{Material, SparsityPattern};
use crate::mesh::{BodyMesh, FacetGroup};

/// Coordinates of the `N` nodes of a cell or facet.
pub(crate) fn node_coords<const N: usize>(coords: &[[f64; 3]], nodes: &[usize]) -> [[f64; 3]; N] {
    std::array::from_fn(|k| coords[nodes[k]])
}

/// The stiffness pattern of a body: `dim` unknowns per node, coupled through the cells.
pub fn stiffness_pattern(body: &BodyMesh) -> SparsityPattern {
    SparsityPattern::new(
        body.num_nodes(),
        &body.cells,
        body.nodes_per_cell(),
        body.dim,
    )
}

/// The (unconstrained) stiffness matrix `K` of a body, on `pattern` (from [`stiffness_pattern`]).
pub fn assemble_stiffness(
    body: &BodyMesh,
    material: &Material,
    pattern: &SparsityPattern,
) -> SparseColMat<usize, f64> {
    let mut values = vec![0.0; pattern.nnz()];
    for c in 0..body.num_cells() {
        let cell = body.cell(c);
        if body.dim == 2 {
            let ke = triangle_stiffness(&node_coords(&body.coords, cell), material);
            pattern.add_element(cell, ke.as_slice(), &mut values);
        } else {
            let ke = tetrahedron_stiffness(&node_coords(&body.coords, cell), material);
            pattern.add_element(cell, ke.as_slice(), &mut values);
        }
    }
    pattern.matrix(values)
}

/// The scalar surface mass matrix `M[a, b] = int_G phi_a phi_b ds` of a boundary group `G`,
/// `num_nodes x num_nodes` (rows and columns of nodes off the group are empty).
///
/// This is the interface mass matrix of the INTERNODES system (method.md section 2): a surface
/// integral without density, not the volume mass matrix restricted to the interface.
pub fn assemble_surface_mass(body: &BodyMesh, group: &FacetGroup) -> SparseColMat<usize, f64> {
    let dim = body.dim;
    let pattern = SparsityPattern::new(body.num_nodes(), &group.facets, dim, 1);
    let mut values = vec![0.0; pattern.nnz()];
    let mut element = vec![0.0; dim * dim];
    for f in 0..group.num_facets(dim) {
        let facet = group.facet(f, dim);
        let x: Vec<[f64; 3]> = facet.iter().map(|&n| body.coords[n]).collect();
        let (measure, _) = facet_measure_and_normal(&x, dim);
        let m = facet_mass(measure, dim);
        for a in 0..dim {
            for b in 0..dim {
                element[a + dim * b] = m[a][b];
            }
        }
        pattern.add_element(facet, &element, &mut values);
    }
    pattern.matrix(values)
}
