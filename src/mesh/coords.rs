//! The coordinates of a body's nodes: every node's, or on a rank of a distributed run only
//! those of the nodes it reads.
//!
//! After the partition (`crate::run`'s), a rank reads the coordinates of the nodes of its
//! cells (its own nodes and the layer around them, for its columns of `K` and its cells'
//! strain and stress) and of the body's boundary (the contact geometry, the loads, the
//! Dirichlet groups); nothing else reads a node's position. Every node's coordinates on
//! every rank would be 24 bytes a node, the largest array of the body's size a rank kept (800
//! MB a rank at 100M DOFs). So a rank keeps those nodes' coordinates only, with the sorted
//! list of which they are (4 bytes a kept node), and a node's are found by a binary search.
//! What reads every node (the output's geometry, the Z curve and the rigid-body frame of the
//! whole body) reads them on rank 0 before the partition or gathers them.

use std::ops::{Index, Range};

use serde::{Deserialize, Serialize};

/// A body's node coordinates (`z = 0` in 2D), indexed by the body's node.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NodeCoords {
    /// The body's number of nodes.
    count: usize,
    /// The nodes whose coordinates are kept, increasing; `None`: every node's, in order.
    kept: Option<Vec<u32>>,
    /// The kept nodes' coordinates, in the order of `kept`.
    values: Vec<[f64; 3]>,
}

impl From<Vec<[f64; 3]>> for NodeCoords {
    fn from(values: Vec<[f64; 3]>) -> Self {
        Self {
            count: values.len(),
            kept: None,
            values,
        }
    }
}

impl NodeCoords {
    /// The coordinates of `nodes` (increasing) of a body of `count` nodes.
    pub fn of_nodes(count: usize, nodes: Vec<u32>, values: Vec<[f64; 3]>) -> Self {
        debug_assert_eq!(nodes.len(), values.len());
        debug_assert!(nodes.windows(2).all(|w| w[0] < w[1]));
        debug_assert!(nodes.last().is_none_or(|&n| (n as usize) < count));
        Self {
            count,
            kept: Some(nodes),
            values,
        }
    }

    /// The body's number of nodes (whether or not their coordinates are kept).
    pub fn len(&self) -> usize {
        self.count
    }

    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Every node's coordinates, if they are all kept.
    pub fn as_whole(&self) -> Option<&[[f64; 3]]> {
        match self.kept {
            None => Some(&self.values),
            Some(_) => None,
        }
    }

    /// Whether every node's coordinates are kept.
    pub fn is_whole(&self) -> bool {
        self.kept.is_none()
    }

    /// The coordinates of `node`, if they are kept.
    pub fn get(&self, node: usize) -> Option<&[f64; 3]> {
        self.position(node).map(|i| &self.values[i])
    }

    /// Where `node` is among the kept nodes, if it is kept.
    pub fn position(&self, node: usize) -> Option<usize> {
        match &self.kept {
            None => (node < self.count).then_some(node),
            Some(kept) => kept.binary_search(&u32::try_from(node).ok()?).ok(),
        }
    }

    /// `whole`'s values (`dim` a node, every node's) at the kept nodes, in their order: the
    /// layout of a field held at the kept nodes, in which [`Self::position`] finds a node's
    /// values (`whole` itself where every node is kept).
    pub fn kept_values(&self, whole: Vec<f64>, dim: usize) -> Vec<f64> {
        match &self.kept {
            None => whole,
            Some(kept) => (kept.iter())
                .flat_map(|&a| &whole[dim * a as usize..dim * (a as usize + 1)])
                .copied()
                .collect(),
        }
    }

    /// The kept nodes' first `dim` coordinates, one node after the other in increasing node
    /// order (every node's where all are kept): the layout a solver's rigid-body near-null
    /// space and the Z curve read.
    pub fn flat(&self, dim: usize) -> Vec<f64> {
        (self.values.iter())
            .flat_map(|x| x[..dim].iter().copied())
            .collect()
    }

    /// The kept nodes and their coordinates, in increasing node order (every node, where all
    /// are kept).
    pub fn kept(&self) -> impl ExactSizeIterator<Item = (usize, &[f64; 3])> + '_ {
        (0..self.values.len()).map(move |i| self.kept_at(i))
    }

    /// The kept node at `position` among them (`0..` in increasing node order) and its
    /// coordinates.
    pub fn kept_at(&self, position: usize) -> (usize, &[f64; 3]) {
        let node = (self.kept.as_ref()).map_or(position, |kept| kept[position] as usize);
        (node, &self.values[position])
    }

    /// The positions among the kept nodes of those in `nodes` (a binary search each end).
    pub fn positions_within(&self, nodes: Range<usize>) -> Range<usize> {
        match &self.kept {
            None => nodes.start.min(self.count)..nodes.end.min(self.count),
            Some(kept) => {
                let first = kept.partition_point(|&n| (n as usize) < nodes.start);
                first..first + kept[first..].partition_point(|&n| (n as usize) < nodes.end)
            }
        }
    }
}

impl Index<usize> for NodeCoords {
    type Output = [f64; 3];

    /// The coordinates of `node`. A node whose coordinates this rank does not keep is a
    /// program error (the partition keeps every node a rank reads).
    fn index(&self, node: usize) -> &[f64; 3] {
        self.get(node).unwrap_or_else(|| {
            panic!(
                "node {node}'s coordinates are not kept on this rank ({} of {} are)",
                self.values.len(),
                self.count
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_subset_finds_its_nodes_and_only_those() {
        let whole = NodeCoords::from(
            (0..10)
                .map(|i| [i as f64, 2.0 * i as f64, 0.0])
                .collect::<Vec<_>>(),
        );
        assert!(whole.is_whole());
        let nodes = vec![1, 4, 9];
        let part = NodeCoords::of_nodes(
            10,
            nodes.clone(),
            nodes.iter().map(|&n| whole[n as usize]).collect(),
        );
        assert_eq!(part.len(), 10);
        assert!(!part.is_whole() && part.as_whole().is_none());
        assert_eq!(part[4], [4.0, 8.0, 0.0]);
        assert_eq!(part.get(9), Some(&[9.0, 18.0, 0.0]));
        assert_eq!(part.get(5), None);
        assert_eq!(part.get(10), None);
        let kept: Vec<usize> = part.kept().map(|(n, _)| n).collect();
        assert_eq!(kept, [1, 4, 9]);
        assert_eq!(part.positions_within(2..9), 1..2);
        assert_eq!(part.positions_within(0..10), 0..3);
        assert_eq!(part.positions_within(5..9), 2..2);
        assert_eq!(part.kept_at(2), (9, &[9.0, 18.0, 0.0]));
        assert_eq!(whole.positions_within(8..12), 8..10);
        assert!(whole.kept().all(|(n, x)| x[0] == n as f64));
    }
}
