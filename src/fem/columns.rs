//! The columns of a body's stiffness matrix at some of its nodes, assembled without the rest:
//! what one rank of a distributed run holds of `K` (its nodes' rows: `K` is symmetric, so a
//! node's rows are its columns), and the rows at the prescribed dofs that every rank needs for
//! the reactions.
//!
//! The layout is that of [`super::SparsityPattern`] restricted to the chosen nodes: the
//! column of unknown `c` of node `a` holds, for every neighbour `b` of `a` (sorted, `a`
//! included), the `block` rows of `b`. Each column receives the element matrices of the cells
//! around its node in cell order, the order [`super::assembly::assemble_stiffness`] adds them
//! in: its entries are those of the whole matrix, bit for bit.

use super::assembly::element_stiffness;
use super::{Material, NodeGraph};
use crate::mesh::BodyMesh;

/// Some nodes' columns of a stiffness matrix (all rows of each).
#[derive(Debug, Clone)]
pub struct NodeColumns {
    block: usize,
    /// The nodes whose columns are held, increasing.
    nodes: Vec<usize>,
    /// Where each held column starts in `rows` and `values` (`block` columns per node, in the
    /// order of `nodes`), and where the last ends.
    col_ptr: Vec<usize>,
    /// The row (an unknown of the whole body) of each entry, increasing within a column.
    rows: Vec<usize>,
    values: Vec<f64>,
}

impl NodeColumns {
    /// The columns of `K` at `nodes` (increasing) of `body`, whose node graph is `graph`.
    ///
    /// One pass over the cells: a cell with none of `nodes` is skipped before its element
    /// matrix is computed, so the work is that of the cells around `nodes`.
    pub fn assemble(
        body: &BodyMesh,
        material: &Material,
        graph: &NodeGraph,
        nodes: Vec<usize>,
    ) -> Self {
        debug_assert!(
            nodes.windows(2).all(|w| w[0] < w[1]),
            "nodes are increasing"
        );
        let block = graph.block();
        let mut position = vec![usize::MAX; graph.num_nodes()];
        let mut col_ptr = Vec::with_capacity(block * nodes.len() + 1);
        col_ptr.push(0);
        let mut rows = Vec::new();
        for (q, &a) in nodes.iter().enumerate() {
            position[a] = q;
            let adjacent = graph.neighbours(a);
            for _ in 0..block {
                for &b in adjacent {
                    rows.extend((0..block).map(|r| block * b + r));
                }
                col_ptr.push(rows.len());
            }
        }
        let mut values = vec![0.0; rows.len()];
        let nodes_per_cell = body.nodes_per_cell();
        let n = block * nodes_per_cell;
        let mut element = vec![0.0; n * n];
        for cell in body.cells() {
            if cell.iter().all(|&a| position[a] == usize::MAX) {
                continue;
            }
            element_stiffness(body, material, &cell, &mut element);
            for (ja, &a) in cell.iter().enumerate() {
                let q = position[a];
                if q != usize::MAX {
                    graph.add_node_columns(&cell, ja, &element, &col_ptr[block * q..], &mut values);
                }
            }
        }
        Self {
            block,
            nodes,
            col_ptr,
            rows,
            values,
        }
    }

    /// The nodes whose columns are held, increasing.
    pub fn nodes(&self) -> &[usize] {
        &self.nodes
    }

    /// The number of held columns (`block` per node).
    pub fn num_columns(&self) -> usize {
        self.col_ptr.len() - 1
    }

    /// The unknown of the whole body that held column `q` is.
    pub fn dof(&self, q: usize) -> usize {
        self.block * self.nodes[q / self.block] + q % self.block
    }

    /// Held column `q`: its rows and values.
    pub fn column(&self, q: usize) -> (&[usize], &[f64]) {
        let range = self.col_ptr[q]..self.col_ptr[q + 1];
        (&self.rows[range.clone()], &self.values[range])
    }

    /// Held column `q`: its rows, and its values to change.
    pub fn column_mut(&mut self, q: usize) -> (&[usize], &mut [f64]) {
        let range = self.col_ptr[q]..self.col_ptr[q + 1];
        (&self.rows[range.clone()], &mut self.values[range])
    }

    /// The number of stored entries.
    pub fn nnz(&self) -> usize {
        self.rows.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::assembly::{assemble_stiffness, stiffness_graph, stiffness_pattern};
    use crate::mesh::BodyMesh;

    /// Two triangles and a third sharing a node: every node's columns, alone or with others,
    /// are the whole matrix's, bit for bit.
    #[test]
    fn columns_are_those_of_the_whole_matrix() {
        let coords = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.1, 0.0],
            [0.2, 1.0, 0.0],
            [1.3, 1.1, 0.0],
            [2.0, 0.4, 0.0],
        ];
        let body = BodyMesh {
            name: "plate".into(),
            physical_tag: 1,
            dim: 2,
            node_tags: (1..=5).collect(),
            coords: coords.into(),
            cells: vec![0, 1, 2, 1, 3, 2, 1, 4, 3],
            cell_tags: vec![1, 2, 3].into(),
            boundary_groups: Default::default(),
            point_groups: Default::default(),
            part: None,
        };
        let material = Material::new(1000.0, 0.3).unwrap();
        let whole = assemble_stiffness(&body, &material, &stiffness_pattern(&body)).to_dense();
        let graph = stiffness_graph(&body);
        for nodes in [vec![0], vec![1, 3], vec![0, 1, 2, 3, 4], vec![4]] {
            let columns = NodeColumns::assemble(&body, &material, &graph, nodes.clone());
            assert_eq!(columns.num_columns(), 2 * nodes.len());
            for q in 0..columns.num_columns() {
                let j = columns.dof(q);
                let (rows, values) = columns.column(q);
                for i in 0..whole.nrows() {
                    let held = rows.iter().position(|&r| r == i).map_or(0.0, |p| values[p]);
                    assert_eq!(held.to_bits(), whole[(i, j)].to_bits(), "entry ({i}, {j})");
                }
            }
        }
    }
}
