//! The order in which a body's nodes are handed to PETSc: along a Z-order (Morton) curve
//! through their coordinates (on one process the whole body's, in a distributed run each
//! rank's nodes: `Distribution`).
//!
//! Our nodes come in the mesh file's tag order, which for a gmsh 3D mesh is close to random: in
//! the 217k-DOF hemisphere on block two nodes of one tetrahedron lie a median 10,000 places
//! apart. Every sparse product of GAMG's set-up and of each V-cycle then reads its vectors at
//! random places, out of the caches. Sorted along a Z curve, nodes close in space are close in
//! memory, so a row's columns and a coarse aggregate's nodes mostly share cache lines (dolfinx
//! reorders its dofs for the same reason). Measured on the 1M-DOF hemisphere (docs/decisions.md):
//! the two bodies' GAMG set-up takes about a third less time, the contact step about a seventh.
//!
//! The Z curve needs nothing but the coordinates: the key of a node interleaves the bits of its
//! coordinates, each scaled to `63 / dim` bits over the body's bounding box, and the nodes are
//! sorted by key (ties by their index, so the order is a function of the mesh alone). A graph
//! ordering (reverse Cuthill-McKee, nested dissection) would need the matrix's nodal graph;
//! the curve is as good for locality and costs a sort. Hand-written: it is a dozen lines of bit
//! interleaving, and none of our dependencies orders points along a curve.
//!
//! On one process only PETSc sees this order ([`NodeOrder`]): its matrix and vectors are
//! permuted on the way in and out, so every caller keeps our numbering. In a distributed run
//! PETSc's numbering is the distribution's anyway, and each rank's nodes take their place in
//! it along the curve.

/// The Z-curve key of each node at `coords` (`dim` values per node, interleaved): the bits of
/// its coordinates, each scaled to `63 / dim` bits over the nodes' bounding box, interleaved.
pub(crate) fn z_curve_keys(coords: &[f64], dim: usize) -> Vec<u64> {
    let num_nodes = coords.len() / dim;
    let (mut low, mut high) = (vec![f64::INFINITY; dim], vec![f64::NEG_INFINITY; dim]);
    for x in coords.chunks_exact(dim) {
        for (c, &x) in x.iter().enumerate() {
            low[c] = low[c].min(x);
            high[c] = high[c].max(x);
        }
    }
    let key = z_curve_key(&low, &high);
    (0..num_nodes)
        .map(|k| key(&coords[k * dim..(k + 1) * dim]))
        .collect()
}

/// The Z-curve key of a point (its `dim` coordinates) within the box from `low` to `high`: on
/// a rank that keeps some of a body's nodes, the body's box makes each node's key the one the
/// whole body's nodes give it ([`z_curve_keys`]).
pub(crate) fn z_curve_key(low: &[f64], high: &[f64]) -> impl Fn(&[f64]) -> u64 {
    let dim = low.len();
    let (low, high) = (low.to_vec(), high.to_vec());
    let bits = 63 / dim as u32;
    let cells = ((1u64 << bits) - 1) as f64;
    move |node: &[f64]| -> u64 {
        let mut key = 0u64;
        for (c, &x) in node.iter().enumerate() {
            let extent = high[c] - low[c];
            let scaled = match extent > 0.0 {
                true => ((x - low[c]) / extent * cells).clamp(0.0, cells) as u64,
                false => 0,
            };
            for bit in 0..bits {
                key |= ((scaled >> bit) & 1) << (bit as usize * dim + c);
            }
        }
        key
    }
}

/// A permutation of a body's nodes (`dim` dofs each, interleaved) and of their dofs.
#[cfg(feature = "petsc")]
#[derive(Debug, Clone)]
pub(crate) struct NodeOrder {
    dim: usize,
    /// `petsc_node[k]`: where our node `k` stands in PETSc's order.
    petsc_node: Vec<usize>,
    /// `our_node[p]`: which of our nodes stands at place `p` of PETSc's order.
    our_node: Vec<usize>,
}

#[cfg(feature = "petsc")]
impl NodeOrder {
    /// The nodes at `coords` (`dim` values per node, interleaved) sorted along a Z curve.
    pub(crate) fn along_z_curve(coords: &[f64], dim: usize) -> Self {
        let keys = z_curve_keys(coords, dim);
        let num_nodes = keys.len();
        let mut keyed: Vec<(u64, usize)> = keys.into_iter().zip(0..).collect();
        keyed.sort_unstable();
        let our_node: Vec<usize> = keyed.into_iter().map(|(_, k)| k).collect();
        let mut petsc_node = vec![0; num_nodes];
        for (p, &k) in our_node.iter().enumerate() {
            petsc_node[k] = p;
        }
        Self {
            dim,
            petsc_node,
            our_node,
        }
    }

    /// Where each of our nodes stands in PETSc's order, as the shim reads it.
    pub(crate) fn petsc_nodes(&self) -> Vec<i64> {
        self.petsc_node.iter().map(|&p| p as i64).collect()
    }

    /// Our dof `i`'s place in PETSc's order.
    pub(crate) fn petsc_dof(&self, i: usize) -> usize {
        self.petsc_node[i / self.dim] * self.dim + i % self.dim
    }

    /// `ours` (one value per dof, or per coordinate) in PETSc's order.
    pub(crate) fn to_petsc(&self, ours: &[f64]) -> Vec<f64> {
        let dim = self.dim;
        let mut petsc = Vec::with_capacity(ours.len());
        for &k in &self.our_node {
            petsc.extend_from_slice(&ours[k * dim..(k + 1) * dim]);
        }
        petsc
    }

    /// `petsc` (in PETSc's order) into `ours`.
    pub(crate) fn to_ours(&self, petsc: &[f64], ours: &mut [f64]) {
        let dim = self.dim;
        for (p, &k) in self.our_node.iter().enumerate() {
            ours[k * dim..(k + 1) * dim].copy_from_slice(&petsc[p * dim..(p + 1) * dim]);
        }
    }

    /// Which of our dofs stands at place `p` of PETSc's order.
    pub(crate) fn our_dof(&self, p: usize) -> usize {
        self.our_node[p / self.dim] * self.dim + p % self.dim
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_z_curve_visits_a_grid_quadrant_by_quadrant() {
        // A 4 x 4 grid of nodes listed row by row: the curve visits each 2 x 2 quadrant
        // whole before the next, in the order (0,0), (1,0), (0,1), (1,1) within each.
        let coords: Vec<f64> = (0..16)
            .flat_map(|k| [(k % 4) as f64, (k / 4) as f64])
            .collect();
        let keys = z_curve_keys(&coords, 2);
        let mut order: Vec<usize> = (0..16).collect();
        order.sort_by_key(|&k| keys[k]);
        assert_eq!(
            order,
            [0, 1, 4, 5, 2, 3, 6, 7, 8, 9, 12, 13, 10, 11, 14, 15]
        );
    }

    #[test]
    #[cfg(feature = "petsc")]
    fn values_go_to_petsc_and_back_unchanged() {
        let coords = [0.3, 0.1, 0.9, 0.0, 0.5, 0.5, 0.1, 0.8, 0.2, 0.7, 0.4, 0.6];
        let order = NodeOrder::along_z_curve(&coords, 3);
        let petsc = order.to_petsc(&coords);
        assert_ne!(petsc, coords);
        let mut back = vec![0.0; coords.len()];
        order.to_ours(&petsc, &mut back);
        assert_eq!(back, coords);
        for i in 0..coords.len() {
            assert_eq!(petsc[order.petsc_dof(i)], coords[i]);
            assert_eq!(order.our_dof(order.petsc_dof(i)), i);
        }
    }
}
