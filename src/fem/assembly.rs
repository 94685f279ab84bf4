//! The numeric phase of assembly: element kernels scattered into a [`SparsityPattern`].

use faer::sparse::SparseColMat;
use rayon::prelude::*;

use super::kernels::{
    facet_mass, facet_measure_and_normal, tetrahedron_stiffness, triangle_stiffness,
};
use super::{Material, NodeGraph, SparsityPattern};
use crate::mesh::{BodyMesh, CellNodes, FacetGroup};

/// Coordinates of the `N` nodes of a cell or facet.
pub fn node_coords<const N: usize, C>(coords: &C, nodes: &[usize]) -> [[f64; 3]; N]
where
    C: std::ops::Index<usize, Output = [f64; 3]> + ?Sized,
{
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

/// The stiffness matrix of one cell (its node indices `cell`) into `element`: column-major,
/// `dim * nodes` square, unknowns interleaved per node.
pub fn element_stiffness(
    body: &BodyMesh,
    material: &Material,
    cell: &[usize],
    element: &mut [f64],
) {
    if body.dim == 2 {
        let ke = triangle_stiffness(&node_coords(&body.coords, cell), material);
        element.copy_from_slice(ke.as_slice());
    } else {
        let ke = tetrahedron_stiffness(&node_coords(&body.coords, cell), material);
        element.copy_from_slice(ke.as_slice());
    }
}

/// The node graph of a body's stiffness (`dim` unknowns per node): all a distributed run
/// builds of the pattern of the whole matrix (`super::NodeColumns` holds its rank's part).
pub fn stiffness_graph(body: &BodyMesh) -> NodeGraph {
    NodeGraph::new(
        body.num_nodes(),
        &body.cells,
        body.nodes_per_cell(),
        body.dim,
    )
}

/// Cells per batch of [`assemble_stiffness`]: many per synchronisation, and the element
/// matrices of two batches (2 x 9 MB in 3D) stay small next to `K`.
const CELL_BATCH: usize = 8192;

/// The (unconstrained) stiffness matrix `K` of a body, on `pattern` (from [`stiffness_pattern`]).
///
/// By batches of cells: while one batch's element matrices are scattered into `K`, one cell
/// after another, the next batch's are computed in parallel. The scatter is the plain
/// sequential sum in cell order, so `K` is the same, bit for bit, for any number of threads.
///
/// Measured on 189,489 tetrahedra (100,530 dofs; fastest runs, otherwise idle 2-core machine):
/// element matrices 0.16 s on 1 thread, 0.09 s on 2; the scatter 0.31 s. The whole takes 0.46 s
/// on 1 thread and 0.37 s on 2 (1.24x; 1.35x at 20k dofs): the sequential scatter bounds it.
/// Scattering in parallel by ranges of columns, each range taking every cell in order (same
/// bits), gained no more: 0.42 s to 0.34 s, as every range streams all element matrices.
/// Assembly is about 5% of a single-body solve (`benches/threads.rs` prints these phases).
pub fn assemble_stiffness(
    body: &BodyMesh,
    material: &Material,
    pattern: &SparsityPattern,
) -> SparseColMat<usize, f64> {
    let nodes_per_cell = body.nodes_per_cell();
    let size = (body.dim * nodes_per_cell).pow(2);
    let batches: Vec<&[u32]> = body.cells.chunks(CELL_BATCH * nodes_per_cell).collect();
    let element_matrices = |cells: &[u32], out: &mut [f64]| {
        out[..cells.len() / nodes_per_cell * size]
            .par_chunks_exact_mut(size)
            .zip(cells.par_chunks_exact(nodes_per_cell))
            .for_each(|(element, cell)| {
                element_stiffness(body, material, &CellNodes::of(cell), element)
            });
    };
    let mut values = vec![0.0; pattern.nnz()];
    let batch_len = CELL_BATCH.min(body.num_cells()) * size;
    let (mut current, mut next) = (vec![0.0; batch_len], vec![0.0; batch_len]);
    if let Some(first) = batches.first() {
        element_matrices(first, &mut current);
    }
    for (k, cells) in batches.iter().enumerate() {
        // This batch into K, in cell order, while the next batch's matrices are computed.
        rayon::join(
            || {
                for (cell, element) in cells
                    .chunks_exact(nodes_per_cell)
                    .zip(current.chunks_exact(size))
                {
                    pattern.add_element(&CellNodes::of(cell), element, &mut values);
                }
            },
            || {
                if let Some(following) = batches.get(k + 1) {
                    element_matrices(following, &mut next);
                }
            },
        );
        std::mem::swap(&mut current, &mut next);
    }
    pattern.matrix(values)
}

/// The scalar surface mass matrix `M[a, b] = int_G phi_a phi_b ds` of a boundary group `G`,
/// `num_nodes x num_nodes` (rows and columns of nodes off the group are empty).
///
/// This is the consistent interface mass matrix of the INTERNODES system (`docs/method.md`,
/// section 2.1): a surface integral without density, not the volume mass matrix restricted to
/// the interface. The contact solver uses its row sums (the lumped mass).
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
