//! A body's mesh as one rank of a distributed run keeps it: the cells it assembles, and what
//! the rest of the run needs of the cells it dropped.
//!
//! Once a body's nodes are partitioned among the ranks, a rank assembles the columns of its
//! own nodes and of the prescribed ones (`crate::elastic`), and after the assembly only the
//! output reads a cell: the contact loop works on surfaces. So a rank holds only the cells
//! around those nodes (every cell that holds one: their columns are then complete, bit for
//! bit), each with its index in the whole body (the output's row of the cell, which the rank
//! that writes it sends to rank 0: `crate::run`'s output), and the facts of the whole body the
//! run still needs: the body's boundary ([`BodyMesh::boundary_facets`]) and the extent of its
//! nodes ([`super::BodyExtent`]). Of the nodes it keeps the coordinates and owners of those it
//! reads only: its own and its cells' nodes and those of the body's boundary and groups
//! ([`BodyMesh::divide_nodes`]; 24 bytes a node of coordinates on every rank before, the
//! largest array of a body's size a rank kept). Rank 0, which reads the mesh, divides the
//! cells ([`BodyMesh::cells_by_rank`]) and the nodes and sends each rank its own
//! (`crate::run`'s partition); the others never hold the whole body. The node tags stay whole,
//! kept as runs ([`super::GmshTags`]).

use std::ops::Range;

use rayon::slice::ParallelSliceMut;
use serde::{Deserialize, Serialize};

use super::{BodyExtent, BodyMesh, GmshTags, NodeCoords};

/// What a rank keeps of a body's mesh beside the cells ([`BodyMesh::part`]).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RankPart {
    /// The rank that owns each node whose coordinates the rank keeps, in the order of
    /// [`BodyMesh::coords`]' kept nodes ([`BodyMesh::owner`]): the partition of the whole
    /// body's node graph that the distribution of its unknowns follows
    /// (`crate::linalg::Distribution`). Every node's on rank 0 until it divides the nodes.
    pub owner: Vec<u32>,
    /// The number of cells of the whole body.
    pub total_cells: usize,
    /// [`BodyMesh::boundary_facets`] of the whole body.
    pub boundary_facets: Vec<usize>,
    /// The extent of the whole body's nodes ([`BodyMesh::extent`]), of which the rank keeps
    /// the coordinates of the nodes it reads only ([`BodyMesh::divide_nodes`]).
    pub extent: BodyExtent,
    /// The whole body's index of each cell this rank keeps, increasing ([`BodyMesh::cells`]
    /// holds them in this order): the row the output writes it in.
    pub cell_indices: Vec<u32>,
    /// The whole body's element tags on rank 0, which writes the output (gmsh numbers a
    /// body's elements in a few runs of consecutive tags: [`GmshTags`]); `None` on the
    /// other ranks. Never sent between ranks.
    #[serde(skip)]
    pub whole_cell_tags: Option<GmshTags>,
}

/// The nodes each rank keeps the coordinates of, one rank after the other: what rank 0 of a
/// distributed run sends the ranks ([`BodyMesh::divide_nodes`]).
#[derive(Debug, Clone, Default)]
pub struct NodesByRank {
    /// The nodes of rank 0, increasing, then those of rank 1, ...
    pub nodes: Vec<u32>,
    /// [`NODE_WORDS`] words a node: its coordinates, each one's 64 bits as two 32-bit words,
    /// low first (so that they travel as the cells' words do, and arrive exact), then its owner.
    pub words: Vec<u32>,
    /// The number of nodes of each rank.
    pub counts: Vec<usize>,
}

/// The 32-bit words of a node ([`NodesByRank::words`]).
pub const NODE_WORDS: usize = 7;

fn coordinate_words(x: &[f64; 3]) -> [u32; 6] {
    let bits = x.map(f64::to_bits);
    std::array::from_fn(|w| (bits[w / 2] >> (32 * (w % 2))) as u32)
}

/// Every rank's cells of a body, one rank after the other, each rank's in the body's order:
/// what rank 0 of a distributed run sends the ranks ([`BodyMesh::cells_by_rank`]).
#[derive(Debug, Clone, Default)]
pub struct CellsByRank {
    /// The cells of rank 0, then of rank 1, ..., flat (`dim + 1` nodes a cell).
    pub cells: Vec<u32>,
    /// The whole body's index of each of those cells ([`RankPart::cell_indices`]).
    pub indices: Vec<u32>,
    /// The number of cells of each rank.
    pub counts: Vec<usize>,
}

impl BodyMesh {
    /// The cells each of `ranks` ranks assembles: a cell goes to every rank that owns one of
    /// its nodes (`owner`), and to every rank where one of its nodes is `everywhere` (a node
    /// whose columns every rank assembles). One pass counts, one places: no cell is held
    /// twice for a rank.
    pub fn cells_by_rank(
        &self,
        owner: &[u32],
        ranks: usize,
        everywhere: impl Fn(usize) -> bool,
    ) -> CellsByRank {
        // The ranks of one cell, in increasing order, into `into` (cleared first).
        let ranks_of = |cell: &[u32], into: &mut Vec<usize>| {
            into.clear();
            if cell.iter().any(|&a| everywhere(a as usize)) {
                into.extend(0..ranks);
            } else {
                into.extend(cell.iter().map(|&a| owner[a as usize] as usize));
                into.sort_unstable();
                into.dedup();
            }
        };
        let n = self.nodes_per_cell();
        let mut counts = vec![0; ranks];
        let mut of_cell = Vec::with_capacity(ranks.max(n));
        for cell in self.cells.chunks_exact(n) {
            ranks_of(cell, &mut of_cell);
            for &r in &of_cell {
                counts[r] += 1;
            }
        }
        let mut next: Vec<usize> = (counts.iter())
            .scan(0, |at, &count| {
                let start = *at;
                *at += count;
                Some(n * start)
            })
            .collect();
        let total = counts.iter().sum::<usize>();
        let (mut cells, mut indices) = (vec![0; n * total], vec![0; total]);
        for (c, cell) in self.cells.chunks_exact(n).enumerate() {
            ranks_of(cell, &mut of_cell);
            for &r in &of_cell {
                cells[next[r]..next[r] + n].copy_from_slice(cell);
                // Bodies of 2^32 cells or more are refused before they are divided.
                indices[next[r] / n] = c as u32;
                next[r] += n;
            }
        }
        CellsByRank {
            cells,
            indices,
            counts,
        }
    }

    /// Makes the body what every rank keeps of it before its own cells come
    /// ([`Self::receive_cells`]): no cells and no tags (only the output reads them, on rank
    /// 0: kept for a rank's cells, which break gmsh's runs of consecutive tags, they would
    /// take 8 bytes a cell beside the cell's 16), the partition `owner`, and what the whole
    /// body's cells gave ([`RankPart`]). Returns the tags, which rank 0 keeps
    /// ([`RankPart::whole_cell_tags`]).
    pub fn drop_cells(&mut self, owner: Vec<u32>) -> GmshTags {
        debug_assert!(self.part.is_none(), "the cells of a whole body");
        let boundary_facets = self.boundary_facets();
        let total_cells = self.num_cells();
        let extent = self.extent();
        self.cells = Vec::new();
        self.part = Some(RankPart {
            owner,
            total_cells,
            boundary_facets,
            extent,
            cell_indices: Vec::new(),
            whole_cell_tags: None,
        });
        std::mem::replace(&mut self.cell_tags, GmshTags::from(Vec::new()))
    }

    /// This rank's cells of a body whose cells were dropped ([`Self::drop_cells`]), in the
    /// whole body's order, with their indices in the whole body.
    pub fn receive_cells(&mut self, cells: Vec<u32>, indices: Vec<u32>) {
        debug_assert!(self.cells.is_empty());
        debug_assert_eq!(cells.len(), self.nodes_per_cell() * indices.len());
        let part = self.part.as_mut().expect("a body whose cells were dropped");
        self.cells = cells;
        part.cell_indices = indices;
    }

    /// The nodes whose coordinates and owners each rank keeps, of a body whose cells were
    /// divided into `cells` ([`Self::cells_by_rank`], then [`Self::drop_cells`]): the rank's
    /// own nodes, the nodes of its cells, of the body's boundary facets and of the cell
    /// vertices opposite them (which orient them), and of its boundary and point groups.
    /// Nothing else reads a node's position once the mesh is divided: the assembly and the
    /// cell fields read their cells' nodes, the loads, supports and pins their groups and the
    /// boundary, the contact geometry the boundary. The body then keeps no coordinates until
    /// its own arrive ([`Self::receive_nodes`]).
    pub fn divide_nodes(&mut self, cells: &CellsByRank) -> NodesByRank {
        let part = self.part.as_mut().expect("a body whose cells were dropped");
        let owner = std::mem::take(&mut part.owner);
        let mut everywhere: Vec<u32> = (part.boundary_facets.iter())
            .chain(self.boundary_groups.values().flat_map(|g| &g.facets))
            .chain(self.point_groups.values().flatten())
            .map(|&a| a as u32)
            .collect();
        everywhere.sort_unstable();
        everywhere.dedup();
        let width = self.nodes_per_cell();
        let mut owned: Vec<Vec<u32>> = vec![Vec::new(); cells.counts.len()];
        for (a, &rank) in owner.iter().enumerate() {
            owned[rank as usize].push(a as u32);
        }
        let mut by_rank = NodesByRank::default();
        let mut first = 0;
        for (&count, owned) in cells.counts.iter().zip(owned) {
            let mut nodes: Vec<u32> = cells.cells[width * first..width * (first + count)].to_vec();
            first += count;
            nodes.extend(owned);
            nodes.extend_from_slice(&everywhere);
            nodes.par_sort_unstable();
            nodes.dedup();
            by_rank.counts.push(nodes.len());
            for &a in &nodes {
                by_rank
                    .words
                    .extend(coordinate_words(&self.coords[a as usize]));
                by_rank.words.push(owner[a as usize]);
            }
            by_rank.nodes.extend(nodes);
        }
        self.coords = NodeCoords::of_nodes(self.num_nodes(), Vec::new(), Vec::new());
        by_rank
    }

    /// This rank's nodes of a body whose nodes were divided ([`Self::divide_nodes`]), with
    /// their words ([`NodesByRank::words`]).
    pub fn receive_nodes(&mut self, nodes: Vec<u32>, words: &[u32]) {
        debug_assert_eq!(words.len(), NODE_WORDS * nodes.len());
        let (values, owner) = (words.chunks_exact(NODE_WORDS))
            .map(|words| {
                let x = std::array::from_fn(|k| {
                    f64::from_bits(u64::from(words[2 * k]) | (u64::from(words[2 * k + 1]) << 32))
                });
                (x, words[NODE_WORDS - 1])
            })
            .unzip();
        self.coords = NodeCoords::of_nodes(self.num_nodes(), nodes, values);
        self.part
            .as_mut()
            .expect("a body whose nodes were divided")
            .owner = owner;
    }

    /// The rank that owns `node`, of a body divided among the ranks ([`RankPart::owner`]);
    /// `None` where its coordinates are not kept here or the body is whole.
    pub fn owner(&self, node: usize) -> Option<u32> {
        let part = self.part.as_ref()?;
        let i = match self.coords.is_whole() {
            true => node,
            false => self.coords.position(node)?,
        };
        part.owner.get(i).copied()
    }

    /// The nodes `rank` owns among those whose coordinates are kept here, with their
    /// coordinates, increasing (none for a whole body).
    pub fn owned_by(&self, rank: usize) -> impl Iterator<Item = (usize, &[f64; 3])> + '_ {
        self.owned_within(rank, 0..self.num_nodes())
    }

    /// [`Self::owned_by`] among `nodes` only (found by a binary search, not a scan of the kept
    /// nodes: the output asks for its nodes a chunk at a time).
    pub fn owned_within(
        &self,
        rank: usize,
        nodes: Range<usize>,
    ) -> impl Iterator<Item = (usize, &[f64; 3])> + '_ {
        let owner = self.part.as_ref().map_or(&[][..], |part| &part.owner[..]);
        (self.coords.positions_within(nodes))
            .filter(move |&i| owner.get(i).is_some_and(|&o| o as usize == rank))
            .map(|i| self.coords.kept_at(i))
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
        // Each facet of each cell, keyed by its sorted nodes (padded for a 2D edge), with its
        // cell and the cell's node opposite it; sorted by key, a boundary facet is a key that
        // appears once. A sort of fixed-size keys rather than a hash map of their vectors: 0.3
        // s against 4.9 s a body at 1M DOFs (2.9M tetrahedra; one run each).
        let n = self.nodes_per_cell();
        let mut facets: Vec<([u32; 3], usize, u8)> = Vec::with_capacity(n * self.num_cells());
        for (c, cell) in self.cells.chunks_exact(n).enumerate() {
            for opposite in 0..n {
                let mut key = [u32::MAX; 3];
                let others = (0..n).filter(|&k| k != opposite).map(|k| cell[k]);
                for (slot, node) in key.iter_mut().zip(others) {
                    *slot = node;
                }
                key[..n - 1].sort_unstable();
                facets.push((key, c, opposite as u8));
            }
        }
        facets.par_sort_unstable_by_key(|&(key, ..)| key);
        let mut boundary: Vec<(Vec<usize>, usize)> = Vec::new();
        for run in facets.chunk_by(|a, b| a.0 == b.0) {
            if let [(_, c, opposite)] = run {
                let cell = self.cell(*c);
                let opposite = *opposite as usize;
                let facet = (0..n).filter(|&k| k != opposite).map(|k| cell[k]).collect();
                boundary.push((facet, cell[opposite]));
            }
        }
        // A deterministic order, whatever the sort left among equal keys.
        boundary.sort_unstable();
        (boundary.into_iter())
            .flat_map(|(facet, opposite)| facet.into_iter().chain([opposite]))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::NODE_WORDS;
    use crate::mesh::read_msh;

    #[test]
    fn a_rank_keeps_the_cells_around_its_nodes_and_the_whole_boundary() {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/block_3d.msh");
        let whole = read_msh(&path).unwrap().bodies.remove(0);
        // Three ranks: nodes dealt round the ranks, every rank assembling the columns of the
        // nodes that are multiples of 7.
        let owner: Vec<u32> = (0..whole.num_nodes()).map(|a| (a % 3) as u32).collect();
        let everywhere = |node: usize| node.is_multiple_of(7);
        let split = whole.cells_by_rank(&owner, 3, everywhere);
        assert_eq!(split.counts.len(), 3);

        let mut at = 0;
        for (rank, &count) in split.counts.iter().enumerate() {
            let held =
                |cell: &[usize]| (cell.iter()).any(|&a| owner[a] as usize == rank || everywhere(a));
            let expected: Vec<u32> = (whole.cells())
                .filter(|cell| held(cell))
                .flat_map(|cell| cell.iter().map(|&a| a as u32).collect::<Vec<_>>())
                .collect();
            let expected_indices: Vec<u32> = (whole.cells().enumerate())
                .filter(|(_, cell)| held(cell))
                .map(|(c, _)| c as u32)
                .collect();
            let kept = split.cells[at..at + 4 * count].to_vec();
            let indices = split.indices[at / 4..at / 4 + count].to_vec();
            at += 4 * count;
            assert_eq!(kept, expected, "rank {rank}");
            assert_eq!(indices, expected_indices, "rank {rank}");
            assert!(count < whole.num_cells());

            let mut part = whole.clone();
            let tags = part.drop_cells(owner.clone());
            assert_eq!(tags, whole.cell_tags);
            part.receive_cells(kept, indices.clone());
            assert_eq!(part.num_cells(), count);
            assert!(part.cell_tags.is_empty());
            assert_eq!(part.part.as_ref().unwrap().cell_indices, indices);
            assert_eq!(part.total_cells(), whole.num_cells());
            assert_eq!(part.boundary_facets(), whole.boundary_facets());
            assert_eq!(part.part.as_ref().unwrap().owner, owner);
        }
        assert_eq!(at, split.cells.len());
    }

    #[test]
    fn a_rank_keeps_the_coordinates_and_owners_of_the_nodes_it_reads_exactly() {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/block_3d.msh");
        let whole = read_msh(&path).unwrap().bodies.remove(0);
        // Three ranks, each a slab of the block along x.
        let (low, high) = whole.bounding_box();
        let owner: Vec<u32> = (whole.coords.kept())
            .map(|(_, x)| ((3.0 * (x[0] - low[0]) / (high[0] - low[0])) as u32).min(2))
            .collect();
        let split = whole.cells_by_rank(&owner, 3, |_| false);
        let mut rank0 = whole.clone();
        rank0.drop_cells(owner.clone());
        let divided = rank0.divide_nodes(&split);
        assert_eq!(rank0.coords.kept().count(), 0, "rank 0 sent them all");
        assert_eq!(divided.counts.len(), 3);

        let (boundary, groups) = (whole.boundary_facets(), whole.group_names());
        let (mut at, mut cells_at, mut kept) = (0, 0, Vec::new());
        for (rank, &count) in divided.counts.iter().enumerate() {
            let nodes = divided.nodes[at..at + count].to_vec();
            let words = &divided.words[NODE_WORDS * at..NODE_WORDS * (at + count)];
            at += count;
            let mut part = whole.clone();
            part.drop_cells(owner.clone());
            let cells = split.counts[rank];
            part.receive_cells(
                split.cells[4 * cells_at..4 * (cells_at + cells)].to_vec(),
                split.indices[cells_at..cells_at + cells].to_vec(),
            );
            cells_at += cells;
            part.receive_nodes(nodes, words);
            assert!(!part.coords.is_whole());
            kept.push(part.coords.kept().count());
            // Every node it reads: its own, its cells', the boundary's (with the opposite
            // nodes), the groups'; each exactly as read, with its owner.
            let read = (0..whole.num_nodes())
                .filter(|&a| owner[a] as usize == rank)
                .chain(part.cells.iter().map(|&a| a as usize))
                .chain(boundary.iter().copied())
                .chain(groups.iter().flat_map(|g| whole.group_nodes(g).unwrap()));
            for a in read {
                assert_eq!(part.coords[a], whole.coords[a], "rank {rank} node {a}");
                assert_eq!(part.owner(a), Some(owner[a]), "rank {rank} node {a}");
            }
            assert_eq!(part.extent(), whole.extent());
        }
        assert_eq!(at, divided.nodes.len());
        // The slab at an end reaches the middle one's first layer only.
        assert!(
            kept[0] < whole.num_nodes(),
            "{kept:?} of {}",
            whole.num_nodes()
        );
    }

    #[test]
    fn a_mesh_sent_between_ranks_arrives_whole_even_from_a_folder_whose_name_is_not_utf8() {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/block_3d.msh");
        let mut mesh = read_msh(&path).unwrap();
        #[cfg(unix)]
        {
            use std::os::unix::ffi::OsStrExt;
            let folder = std::ffi::OsStr::from_bytes(b"/tmp/bad\xffdir");
            mesh.path = std::path::Path::new(folder).join("mesh.msh");
        }
        let owner = vec![0; mesh.bodies[0].num_nodes()];
        mesh.bodies[0].drop_cells(owner);

        let bytes = postcard::to_allocvec(&mesh).unwrap();
        let sent: crate::mesh::Mesh = postcard::from_bytes(&bytes).unwrap();
        assert_eq!(sent.path, mesh.path);
        assert_eq!(sent.dim, mesh.dim);
        assert_eq!(sent.physical_groups, mesh.physical_groups);
        let (body, arrived) = (&mesh.bodies[0], &sent.bodies[0]);
        assert_eq!(arrived.coords, body.coords);
        assert_eq!(arrived.node_tags, body.node_tags);
        assert_eq!(arrived.total_cells(), body.total_cells());
        assert_eq!(arrived.boundary_facets(), body.boundary_facets());
        assert_eq!(
            arrived.part.as_ref().unwrap().owner,
            body.part.as_ref().unwrap().owner
        );
        assert_eq!(arrived.point_groups, body.point_groups);
        let names: Vec<_> = arrived.boundary_groups.keys().collect();
        assert_eq!(names, body.boundary_groups.keys().collect::<Vec<_>>());
        for (name, group) in &body.boundary_groups {
            assert_eq!(arrived.boundary_groups[name].facets, group.facets, "{name}");
            assert_eq!(arrived.boundary_groups[name].facet_cells, group.facet_cells);
        }
    }

    #[test]
    fn the_boundary_is_every_facet_that_no_other_cell_shares_in_a_fixed_order() {
        for name in ["block_3d.msh", "block_2d.msh"] {
            let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("tests/fixtures")
                .join(name);
            let body = read_msh(&path).unwrap().bodies.remove(0);
            // The oracle: each facet counted by its node set in a hash map.
            let mut count = std::collections::HashMap::new();
            for cell in body.cells() {
                for opposite in 0..cell.len() {
                    let facet: Vec<usize> = (0..cell.len())
                        .filter(|&k| k != opposite)
                        .map(|k| cell[k])
                        .collect();
                    let mut key = facet.clone();
                    key.sort_unstable();
                    let entry = count.entry(key).or_insert((0, facet, cell[opposite]));
                    entry.0 += 1;
                }
            }
            let mut expected: Vec<(Vec<usize>, usize)> = (count.into_values())
                .filter(|(n, ..)| *n == 1)
                .map(|(_, facet, opposite)| (facet, opposite))
                .collect();
            expected.sort_unstable();
            let expected: Vec<usize> = (expected.into_iter())
                .flat_map(|(facet, opposite)| facet.into_iter().chain([opposite]))
                .collect();
            assert!(!expected.is_empty());
            assert_eq!(body.boundary_facets(), expected, "{name}");
        }
    }
}
