//! The symbolic phase of assembly: the compressed-column pattern of a matrix with `block`
//! unknowns per node, built once from the node graph of the elements.
//!
//! Every node `a` owns columns `block * a .. block * (a + 1)`; each of those columns holds the
//! rows of all nodes adjacent to `a` (including `a`), `block` rows per neighbour, sorted. The
//! position of the coupling between nodes `a` and `b` is therefore found by one binary search
//! in `a`'s neighbour list, whatever `block` is.

use faer::sparse::{SparseColMat, SymbolicSparseColMat, SymbolicSparseColMatRef};

use crate::mesh::NodeIndex;

/// The node graph of a pattern: which nodes the elements couple, and the unknowns per node.
/// All a fill-reducing ordering needs (`crate::linalg::ordering`), `block^2` times smaller
/// than the pattern itself.
#[derive(Debug, Clone)]
pub struct NodeGraph {
    block: usize,
    /// Neighbours of each node, including itself, sorted (CSR layout).
    neighbour_ptr: Vec<usize>,
    neighbours: Vec<usize>,
}

impl NodeGraph {
    /// The graph of `num_nodes` nodes coupled through `elements` (`nodes_per_element` node
    /// indices each, flat), with `block` unknowns per node.
    pub fn new<I: NodeIndex>(
        num_nodes: usize,
        elements: &[I],
        nodes_per_element: usize,
        block: usize,
    ) -> Self {
        // node -> elements, then node -> distinct nodes of those elements.
        let mut element_ptr = vec![0usize; num_nodes + 1];
        for n in elements {
            element_ptr[n.index() + 1] += 1;
        }
        for i in 0..num_nodes {
            element_ptr[i + 1] += element_ptr[i];
        }
        let mut next = element_ptr.clone();
        let mut node_elements = vec![0usize; elements.len()];
        for (k, n) in elements.iter().enumerate() {
            node_elements[next[n.index()]] = k / nodes_per_element;
            next[n.index()] += 1;
        }

        let mut neighbour_ptr = Vec::with_capacity(num_nodes + 1);
        neighbour_ptr.push(0);
        let mut neighbours = Vec::new();
        let mut scratch = Vec::new();
        for a in 0..num_nodes {
            scratch.clear();
            scratch.push(a);
            for &e in &node_elements[element_ptr[a]..element_ptr[a + 1]] {
                let element = &elements[e * nodes_per_element..(e + 1) * nodes_per_element];
                scratch.extend(element.iter().map(|n| n.index()));
            }
            scratch.sort_unstable();
            scratch.dedup();
            neighbours.extend_from_slice(&scratch);
            neighbour_ptr.push(neighbours.len());
        }
        Self {
            block,
            neighbour_ptr,
            neighbours,
        }
    }

    pub fn num_nodes(&self) -> usize {
        self.neighbour_ptr.len() - 1
    }

    pub fn block(&self) -> usize {
        self.block
    }

    /// Neighbours of node `a`, including `a`, sorted.
    pub fn neighbours(&self, a: usize) -> &[usize] {
        &self.neighbours[self.neighbour_ptr[a]..self.neighbour_ptr[a + 1]]
    }

    /// Adds the `block` columns of element node `ja` (node `nodes[ja]`) of a dense element
    /// matrix (column-major, `block * nodes.len()` square, unknowns interleaved per node) into
    /// `values`, where that node's columns start at `starts[0..block]` and hold, like every
    /// column of a pattern built on this graph, `block` rows per neighbour in neighbour order.
    pub(super) fn add_node_columns(
        &self,
        nodes: &[usize],
        ja: usize,
        element: &[f64],
        starts: &[usize],
        values: &mut [f64],
    ) {
        let block = self.block;
        let n = block * nodes.len();
        let adjacent = self.neighbours(nodes[ja]);
        for (ib, b) in nodes.iter().enumerate() {
            let k = adjacent
                .binary_search(b)
                .expect("element nodes are neighbours in the graph built from the elements");
            for c in 0..block {
                let base = starts[c] + block * k;
                let column = &element[n * (block * ja + c) + block * ib..];
                for r in 0..block {
                    values[base + r] += column[r];
                }
            }
        }
    }
}

/// Compressed-column pattern of a finite element matrix, with the node graph it came from.
#[derive(Debug, Clone)]
pub struct SparsityPattern {
    graph: NodeGraph,
    symbolic: SymbolicSparseColMat<usize>,
}

impl SparsityPattern {
    /// The pattern of `num_nodes` nodes coupled through `elements` (`nodes_per_element` node
    /// indices each, flat), with `block` unknowns per node.
    pub fn new<I: NodeIndex>(
        num_nodes: usize,
        elements: &[I],
        nodes_per_element: usize,
        block: usize,
    ) -> Self {
        let graph = NodeGraph::new(num_nodes, elements, nodes_per_element, block);
        let n = block * num_nodes;
        let mut col_ptr = Vec::with_capacity(n + 1);
        col_ptr.push(0usize);
        let mut row_idx = Vec::with_capacity(block * block * graph.neighbours.len());
        for a in 0..num_nodes {
            let adjacent = graph.neighbours(a);
            for _ in 0..block {
                for &b in adjacent {
                    row_idx.extend((0..block).map(|r| block * b + r));
                }
                col_ptr.push(row_idx.len());
            }
        }
        let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        Self { graph, symbolic }
    }

    /// The node graph alone, for a matrix that has taken a copy of the pattern: the
    /// dof-level pattern is the bulk of the memory (8 bytes per stored entry).
    pub fn into_graph(self) -> NodeGraph {
        self.graph
    }

    pub fn graph(&self) -> &NodeGraph {
        &self.graph
    }

    pub fn symbolic(&self) -> SymbolicSparseColMatRef<'_, usize> {
        self.symbolic.as_ref()
    }

    pub fn nnz(&self) -> usize {
        self.symbolic.row_idx().len()
    }

    pub fn num_nodes(&self) -> usize {
        self.graph.num_nodes()
    }

    pub fn block(&self) -> usize {
        self.graph.block
    }

    /// Neighbours of node `a`, including `a`, sorted.
    pub fn neighbours(&self, a: usize) -> &[usize] {
        self.graph.neighbours(a)
    }

    /// Adds a dense element matrix (column-major, `block * nodes.len()` square, unknowns
    /// interleaved per node) into `values`, the value array of this pattern.
    pub fn add_element(&self, nodes: &[usize], element: &[f64], values: &mut [f64]) {
        let block = self.graph.block;
        debug_assert_eq!(element.len(), (block * nodes.len()).pow(2));
        let col_ptr = self.symbolic.col_ptr();
        for (ja, &a) in nodes.iter().enumerate() {
            self.graph
                .add_node_columns(nodes, ja, element, &col_ptr[block * a..], values);
        }
    }

    /// A matrix with this pattern and the given values.
    pub fn matrix(&self, values: Vec<f64>) -> SparseColMat<usize, f64> {
        SparseColMat::new(self.symbolic.clone(), values)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pattern_of_two_triangles_with_two_unknowns_per_node() {
        // Triangles (0, 1, 2) and (1, 3, 2): nodes 0 and 3 are not coupled.
        let p = SparsityPattern::new(4, &[0usize, 1, 2, 1, 3, 2], 3, 2);
        assert_eq!(p.neighbours(0), &[0, 1, 2]);
        assert_eq!(p.neighbours(1), &[0, 1, 2, 3]);
        assert_eq!(p.nnz(), 4 * (3 + 4 + 4 + 3));
        let mut values = vec![0.0; p.nnz()];
        let element: Vec<f64> = (0..36).map(|k| k as f64).collect();
        p.add_element(&[0, 1, 2], &element, &mut values);
        let m = p.matrix(values).to_dense();
        // Entry (row 3 = node 1 y, col 4 = node 2 x) is element entry (3, 4) = 3 + 6 * 4.
        assert_eq!(m[(3, 4)], 27.0);
        assert_eq!(m[(6, 0)], 0.0);
    }
}
