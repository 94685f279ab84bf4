//! A body's mesh as one rank of a distributed run keeps it: the cells it assembles, and what
//! the rest of the run needs of the cells it dropped.
//!
//! Once a body's nodes are partitioned among the ranks, a rank assembles the columns of its
//! own nodes and of the prescribed ones (`crate::elastic`), and nothing after the assembly
//! reads a cell: the contact loop works on surfaces, and the output is written by rank 0 from
//! the mesh file read again. So a rank keeps only the cells around those nodes (every cell
//! that holds one: their columns are then complete, bit for bit), and the two facts of the
//! whole body the run still needs, the partition and the body's boundary
//! ([`BodyMesh::boundary_facets`]). Every node stays: the coordinates are 24 bytes a node
//! against the cells' 16 bytes a cell and about 5.5 cells a node in 3D.

use super::{BodyMesh, ElementTags};

/// What a rank keeps of a body's mesh beside the cells ([`BodyMesh::part`]).
#[derive(Debug, Clone)]
pub struct RankPart {
    /// The rank that owns each node: the partition of the whole body's node graph that the
    /// distribution of its unknowns follows (`crate::linalg::Distribution`).
    pub owner: Vec<u32>,
    /// The number of cells of the whole body.
    pub total_cells: usize,
    /// [`BodyMesh::boundary_facets`] of the whole body.
    pub boundary_facets: Vec<usize>,
}

impl BodyMesh {
    /// Keeps the cells of the whole body that hold a node `keep` accepts (in their order), and
    /// none of their tags (only the output reads them, on the whole mesh read again: kept for
    /// a rank's cells, which break gmsh's runs of consecutive tags, they took 8 bytes a cell
    /// beside the cell's 16), and records `owner` and what the whole body's cells gave
    /// ([`RankPart`]).
    pub fn keep_cells(&mut self, owner: Vec<u32>, keep: impl Fn(usize) -> bool) {
        debug_assert!(self.part.is_none(), "the cells of a whole body");
        let boundary_facets = self.boundary_facets();
        let total_cells = self.num_cells();
        let kept: Vec<usize> = (0..total_cells)
            .filter(|&c| self.cell(c).iter().any(|&a| keep(a)))
            .collect();
        let n = self.nodes_per_cell();
        let mut cells = Vec::with_capacity(n * kept.len());
        for &c in &kept {
            cells.extend_from_slice(&self.cells[n * c..n * (c + 1)]);
        }
        self.cells = cells;
        self.cell_tags = ElementTags::from(Vec::new());
        self.part = Some(RankPart {
            owner,
            total_cells,
            boundary_facets,
        });
    }

    /// The number of cells of the whole body (of which a rank's part keeps some).
    pub fn total_cells(&self) -> usize {
        self.part
            .as_ref()
            .map_or(self.num_cells(), |p| p.total_cells)
    }

    /// The facets of the body's cells that no other cell shares (its boundary, closed), each as
    /// its `dim` nodes then the node of its cell opposite it (which tells its outward side),
    /// flat, in a deterministic order. Of the whole body, also where a rank keeps only
    /// part of the cells.
    pub fn boundary_facets(&self) -> Vec<usize> {
        if let Some(part) = &self.part {
            return part.boundary_facets.clone();
        }
        // Each facet of each cell, keyed by its sorted nodes; a boundary facet appears once.
        let mut count: std::collections::HashMap<Vec<usize>, (usize, Vec<usize>, usize)> =
            std::collections::HashMap::new();
        for cell in self.cells() {
            for opposite in 0..cell.len() {
                let facet: Vec<usize> = (0..cell.len())
                    .filter(|&k| k != opposite)
                    .map(|k| cell[k])
                    .collect();
                let mut key = facet.clone();
                key.sort_unstable();
                count
                    .entry(key)
                    .and_modify(|e| e.0 += 1)
                    .or_insert((1, facet, cell[opposite]));
            }
        }
        let mut boundary: Vec<(Vec<usize>, usize)> = count
            .into_values()
            .filter(|(n, ..)| *n == 1)
            .map(|(_, facet, opposite)| (facet, opposite))
            .collect();
        // A deterministic order (the hash map's is not).
        boundary.sort_unstable();
        (boundary.into_iter())
            .flat_map(|(facet, opposite)| facet.into_iter().chain([opposite]))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use crate::mesh::read_msh;

    #[test]
    fn a_rank_keeps_the_cells_around_its_nodes_and_the_whole_boundary() {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/block_3d.msh");
        let whole = read_msh(&path).unwrap().bodies.remove(0);
        let keep = |node: usize| node.is_multiple_of(7);
        let mut part = whole.clone();
        part.keep_cells(vec![1; whole.num_nodes()], keep);

        let expected: Vec<Vec<usize>> = (whole.cells())
            .filter(|cell| cell.iter().any(|&a| keep(a)))
            .map(|cell| cell.to_vec())
            .collect();
        let kept: Vec<Vec<usize>> = part.cells().map(|cell| cell.to_vec()).collect();
        assert_eq!(kept, expected);
        assert!(kept.len() < whole.num_cells());
        assert!(part.cell_tags.is_empty());
        assert_eq!(part.total_cells(), whole.num_cells());
        assert_eq!(part.boundary_facets(), whole.boundary_facets());
        assert_eq!(
            part.part.as_ref().unwrap().owner,
            vec![1; whole.num_nodes()]
        );
    }
}
