//! A body's displacement as the contact geometry reads it: whole (one process), or at the nodes
//! of the body's boundary alone (each iterate of a distributed run's contact loop, and its
//! answer's checks).
//!
//! The geometry of a contact reads a body's displacement only on its boundary: a contact
//! surface's nodes ([`crate::contact::geometry::surface`]) and, to tell inside from outside,
//! the body's closed boundary ([`crate::contact::geometry::boundary`]). Those are about
//! `n^(2/3)` of a body's `n` nodes, so a rank of a distributed run that receives each iterate's
//! displacement there, and not whole, holds nothing of the body's size through the loop.

/// A body's displacement at some of its nodes (`dim` values each), sorted by node: what every
/// rank receives of an iterate ([`BodyDisplacement::OnNodes`]).
#[derive(Debug, Clone, PartialEq)]
pub struct NodeValues {
    /// The nodes, increasing.
    nodes: Vec<u32>,
    /// `dim` values per node, in the order of `nodes`.
    values: Vec<f64>,
    dim: usize,
}

impl NodeValues {
    /// The values `values` (`dim` per node) at `nodes` (increasing).
    ///
    /// # Panics
    /// If `nodes` is not increasing or `values` does not hold `dim` values per node (a bug of
    /// the caller, which builds both from one list).
    pub fn new(nodes: Vec<u32>, values: Vec<f64>, dim: usize) -> Self {
        assert!(nodes.windows(2).all(|w| w[0] < w[1]), "nodes increasing");
        assert_eq!(values.len(), dim * nodes.len(), "{dim} values per node");
        Self { nodes, values, dim }
    }

    /// The nodes the values are at, increasing.
    pub fn nodes(&self) -> &[u32] {
        &self.nodes
    }
}

/// A body's displacement, `dim` values per node ([module doc](self)).
#[derive(Debug, Clone, Copy)]
pub enum BodyDisplacement<'a> {
    /// Every node's, as body dofs (`u[dim * node + k]`).
    Whole(&'a [f64]),
    /// At the nodes the contact geometry reads alone.
    OnNodes(&'a NodeValues),
}

impl<'a> From<&'a [f64]> for BodyDisplacement<'a> {
    fn from(u: &'a [f64]) -> Self {
        Self::Whole(u)
    }
}

impl<'a> From<&'a Vec<f64>> for BodyDisplacement<'a> {
    fn from(u: &'a Vec<f64>) -> Self {
        Self::Whole(u)
    }
}

impl BodyDisplacement<'_> {
    /// The displacement of `node`, three components (the third `0` in 2D: `dim` 2).
    ///
    /// # Panics
    /// If the displacement is held at some nodes and `node` is not one of them: the nodes are
    /// those of every contact surface and the closed boundary of the body
    /// (`crate::contact::iteration`), which is all the geometry reads, so this is a bug.
    pub fn at(&self, dim: usize, node: usize) -> [f64; 3] {
        let values = match self {
            Self::Whole(u) => &u[dim * node..dim * (node + 1)],
            Self::OnNodes(held) => {
                debug_assert_eq!(held.dim, dim);
                let place = (held.nodes.binary_search(&(node as u32)))
                    .expect("the contact geometry reads a body's displacement on its boundary");
                &held.values[dim * place..dim * (place + 1)]
            }
        };
        std::array::from_fn(|k| if k < dim { values[k] } else { 0.0 })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_displacement_held_at_some_nodes_reads_as_the_whole_one_there() {
        // 2D, four nodes; nodes 1 and 3 held.
        let whole = [0.1, 0.2, 1.1, 1.2, 2.1, 2.2, 3.1, 3.2];
        let held = NodeValues::new(vec![1, 3], vec![1.1, 1.2, 3.1, 3.2], 2);
        for node in [1, 3] {
            assert_eq!(
                BodyDisplacement::OnNodes(&held).at(2, node),
                BodyDisplacement::Whole(&whole).at(2, node)
            );
        }
        assert_eq!(BodyDisplacement::Whole(&whole).at(2, 2), [2.1, 2.2, 0.0]);
    }
}
