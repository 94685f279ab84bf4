//! How one body's unknowns are shared among the ranks of a distributed run, and the rows a
//! rank hands to PETSc.
//!
//! The body's nodes are split into one part per rank by METIS (`METIS_PartGraphKway` on the
//! node graph of the stiffness: parts of nearly equal size with few edges between them, so
//! that a matrix-vector product or a V-cycle exchanges little; and, for a body with many
//! contact-surface nodes, a nearly equal share of those: [`node_owners`]), each part given to
//! the rank that keeps the ranks' totals over the bodies even ([`spread_parts`]). PETSc owns its
//! rows by contiguous ranges, so PETSc's numbering puts the nodes of rank 0 first, then those
//! of rank 1, and so on, each rank's along a Z curve through their coordinates (locality for the
//! products of GAMG's set-up and V-cycles: `super::node_order`), each node's `dim` unknowns
//! together (the block structure GAMG aggregates by). Rank 0 partitions the body
//! (`crate::run`'s partition); each rank orders its own nodes along the curve ([`own_order`]),
//! and a rank keeps the PETSc number of the nodes it reads only (its own, its cells', its
//! boundary's), asked of their owners ([`Distribution::from_parts`]: no rank gathers the whole
//! order). It assembles the columns of its
//! own nodes only ([`crate::fem::NodeColumns`]: its rows, `K` being symmetric; in our order)
//! and hands them to PETSc, in PETSc's order, as [`RankRows`].
//!
//! Vectors cross between the two numberings here: [`Distribution::local_part`] takes this
//! rank's rows out of a whole vector in our numbering, [`Distribution::gather`] puts every
//! rank's rows back into one whole vector on every rank (`MPI_Allgatherv`, with the rows'
//! nodes), [`NodeGather`] some nodes' values.

use super::LinalgError;
use super::node_order::{z_curve_key, z_curve_keys};
use super::ordering::partition;
use crate::fem::{NodeColumns, NodeGraph};
use crate::mesh::NodeCoords;
use crate::parallel::ranks::Ranks;

#[derive(Debug)]
pub struct Distribution {
    /// This rank's nodes in PETSc's order: PETSc's rows `block (first + i) .. block (first +
    /// i + 1)` are our node `own[i]`'s unknowns.
    own: Vec<u32>,
    /// PETSc's node of each node this rank reads, by our node, increasing: of every node on
    /// one process, on a rank of a distributed run of those whose coordinates it keeps (its
    /// own, its cells', its body's boundary's and groups': `crate::mesh::NodeCoords`), so that
    /// no rank keeps a map of the whole body. 32 bits each, as the mesh's cells hold a node.
    known: Vec<(u32, u32)>,
    /// This rank's nodes, increasing, each with its place among this rank's nodes in PETSc's
    /// order.
    own_sorted: Vec<(u32, u32)>,
    /// The rows of each rank (unknowns), in rank order.
    counts: Vec<usize>,
    /// PETSc's first node of this rank (`block` rows each).
    first: usize,
    /// This rank's number of nodes (`block` rows each).
    local: usize,
    /// Unknowns per node.
    block: usize,
}

/// Contact-surface nodes per rank from which a partition shares them out evenly
/// ([`node_owners`]). The contact loop's rows cost about 23 kB a contact-surface node (the
/// coupling blocks, the interpolation's rows and columns and the interface coupling: 491 MB
/// over 4 ranks for the 21,470 of the hemisphere on a block at 1M DOFs), so below a thousand
/// a rank they weigh tens of MB at most, while a second constraint on a few hundred nodes
/// costs METIS the balance of the sizes (a 2D body of 51 nodes split 28 / 23, 10% over an
/// even half).
pub const BALANCED_INTERFACE_PER_RANK: usize = 1_000;

/// The rank that owns each node of a body whose stiffness has the node graph `graph`: a METIS
/// partition into `ranks.size` parts, the same on every rank (METIS is deterministic for a
/// given graph). Where `interface` marks the body's contact-surface nodes and they number at
/// least [`BALANCED_INTERFACE_PER_RANK`] a rank, each rank also gets a nearly equal share of
/// them (`super::ordering::partition`); `interface` may be empty.
pub fn node_owners(
    graph: &NodeGraph,
    ranks: Ranks,
    interface: &[bool],
) -> Result<Vec<u32>, LinalgError> {
    let num_nodes = graph.num_nodes();
    let neighbours: Vec<Vec<usize>> = (0..num_nodes)
        .map(|a| {
            graph
                .neighbours(a)
                .iter()
                .copied()
                .filter(|&b| b != a)
                .collect()
        })
        .collect();
    let marked = interface.iter().filter(|&&m| m).count();
    let balanced = match marked >= BALANCED_INTERFACE_PER_RANK * ranks.size {
        true => interface,
        false => &[],
    };
    let part = partition(&neighbours, ranks.size, balanced)?;
    drop(neighbours);
    // The mesh refuses bodies of 2^32 nodes or more (`crate::mesh::MeshError`).
    if u32::try_from(num_nodes).is_err() {
        return Err(LinalgError::Sizes(format!(
            "{num_nodes} nodes: more than a partition numbers (2^32 - 1)"
        )));
    }
    Ok(part.into_iter().map(|rank| rank as u32).collect())
}

/// Gives the parts of one more body to the ranks so that the ranks' totals stay even: `owner`
/// is the body's partition ([`node_owners`]: part `p` on rank `p`), `nodes_on_rank` the nodes
/// each rank owns of the bodies placed before it, to which this body's are added.
///
/// METIS keeps each body's parts within a few percent of an even share, but which part gets
/// which label is arbitrary, so several bodies' larger parts can fall on one rank: the 3M-DOF
/// hemisphere on a block on 2 ranks gave rank 1 both bodies' larger parts, 4.2% more unknowns
/// than rank 0 and the larger GAMG hierarchy. The parts are given largest first, each to the
/// rank with the fewest nodes so far (the longest-processing-time rule; ties to the lower
/// part and the lower rank), and the body keeps METIS's labels unless that lowers the largest
/// total. Only labels change: the cut, each part and its share of the contact surface stay.
/// Returns the rank given each part.
pub fn spread_parts(owner: &mut [u32], nodes_on_rank: &mut [usize]) -> Vec<usize> {
    let ranks = nodes_on_rank.len();
    let mut size = vec![0usize; ranks];
    for &part in owner.iter() {
        size[part as usize] += 1;
    }
    let mut by_size: Vec<usize> = (0..ranks).collect();
    by_size.sort_by_key(|&part| std::cmp::Reverse(size[part]));
    let mut spread = vec![0; ranks];
    let mut total = nodes_on_rank.to_vec();
    for part in by_size {
        let rank = (0..ranks)
            .min_by_key(|&r| (total[r], r))
            .expect("at least one rank");
        spread[part] = rank;
        total[rank] += size[part];
    }
    let with_metis_labels = (0..ranks).map(|r| nodes_on_rank[r] + size[r]).max();
    let rank_of_part: Vec<usize> = match total.into_iter().max() < with_metis_labels {
        true => spread,
        false => (0..ranks).collect(),
    };
    for part in owner.iter_mut() {
        *part = rank_of_part[*part as usize] as u32;
    }
    for (part, &rank) in rank_of_part.iter().enumerate() {
        nodes_on_rank[rank] += size[part];
    }
    rank_of_part
}

/// This rank's place in PETSc's numbering of a body's nodes (the order
/// [`Distribution::with_owners`] gives them): its nodes `own` (increasing) sorted along the Z
/// curve through their coordinates `coords` (`dim` values per node, in the order of `own`)
/// within the whole body's bounding box `low`..`high`, ties by node. A rank that keeps only its
/// part of a body's coordinates orders its own nodes this way, and the ranks' orders gathered
/// one after the other are the whole body's ([`Distribution::from_order`]).
pub fn own_order(own: &[u32], coords: &[f64], low: &[f64], high: &[f64]) -> Vec<u32> {
    let dim = low.len();
    let key = z_curve_key(low, high);
    let mut keyed: Vec<(u64, u32)> = (own.iter().enumerate())
        .map(|(i, &a)| (key(&coords[dim * i..dim * (i + 1)]), a))
        .collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, a)| a).collect()
}

impl Distribution {
    /// The distribution over `ranks` of the unknowns of the body whose stiffness has the node
    /// graph `graph` and whose nodes are at `coords` (one value per unknown: `block` per node).
    pub fn new(graph: &NodeGraph, coords: &[f64], ranks: Ranks) -> Result<Self, LinalgError> {
        Self::with_owners(
            &node_owners(graph, ranks, &[])?,
            coords,
            graph.block(),
            ranks,
        )
    }

    /// The distribution over `ranks` of the unknowns of a body whose nodes `owner` assigns to
    /// the ranks ([`node_owners`]) and are at `coords` (`block` values per node, its unknowns).
    pub fn with_owners(
        owner: &[u32],
        coords: &[f64],
        block: usize,
        ranks: Ranks,
    ) -> Result<Self, LinalgError> {
        let num_nodes = owner.len();
        if coords.len() != num_nodes * block {
            return Err(LinalgError::Sizes(format!(
                "{} coordinates for {num_nodes} nodes of {block} unknowns",
                coords.len()
            )));
        }
        let keys = z_curve_keys(coords, block);
        let mut nodes = Vec::with_capacity(num_nodes);
        let mut nodes_per_rank = vec![0; ranks.size];
        for (rank, count) in nodes_per_rank.iter_mut().enumerate() {
            let first = nodes.len();
            nodes.extend(
                (0..num_nodes)
                    .filter(|&a| owner[a] as usize == rank)
                    .map(|a| a as u32),
            );
            nodes[first..].sort_by_key(|&a| (keys[a as usize], a));
            *count = nodes.len() - first;
        }
        drop(keys);
        Ok(Self::from_order(
            &nodes,
            &nodes_per_rank,
            block,
            ranks,
            None,
        ))
    }

    /// The distribution whose PETSc numbering holds our nodes `nodes` (those of rank 0 along
    /// their Z curve, then those of rank 1, ...: [`own_order`] on each rank, gathered), of which
    /// `nodes_per_rank[r]` are rank r's; this rank reads the nodes `known` (increasing), every
    /// node where `None`.
    pub fn from_order(
        nodes: &[u32],
        nodes_per_rank: &[usize],
        block: usize,
        ranks: Ranks,
        known: Option<&[u32]>,
    ) -> Self {
        debug_assert_eq!(nodes.len(), nodes_per_rank.iter().sum::<usize>());
        let first: usize = nodes_per_rank[..ranks.rank].iter().sum();
        let own = nodes[first..first + nodes_per_rank[ranks.rank]].to_vec();
        let mut all: Vec<(u32, u32)> = (nodes.iter().zip(0..)).map(|(&a, p)| (a, p)).collect();
        all.sort_unstable();
        let known = match known {
            None => all,
            Some(known) => {
                let mut at = 0;
                (known.iter())
                    .filter_map(|&a| {
                        at += all[at..].partition_point(|&(b, _)| b < a);
                        all.get(at).filter(|&&(b, _)| b == a).copied()
                    })
                    .collect()
            }
        };
        Self::from_parts(own, nodes_per_rank, block, ranks, known)
    }

    /// The distribution in which this rank's nodes are `own` (in PETSc's order), rank `r` has
    /// `nodes_per_rank[r]`, and this rank reads the nodes of `known` (each with its PETSc
    /// node, increasing by our node): what [`Self::from_order`] makes from the whole order,
    /// without it.
    pub fn from_parts(
        own: Vec<u32>,
        nodes_per_rank: &[usize],
        block: usize,
        ranks: Ranks,
        known: Vec<(u32, u32)>,
    ) -> Self {
        debug_assert_eq!(own.len(), nodes_per_rank[ranks.rank]);
        debug_assert!(
            known.windows(2).all(|w| w[0].0 < w[1].0),
            "known increasing"
        );
        let counts: Vec<usize> = nodes_per_rank.iter().map(|&n| n * block).collect();
        let first = counts[..ranks.rank].iter().sum::<usize>() / block;
        let local = counts[ranks.rank] / block;
        let mut own_sorted: Vec<(u32, u32)> = (own.iter().zip(0..))
            .map(|(&node, place)| (node, place))
            .collect();
        own_sorted.sort_unstable();
        Self {
            own,
            known,
            own_sorted,
            counts,
            first,
            local,
            block,
        }
    }

    /// Each rank's number of unknowns, in rank order.
    pub fn counts(&self) -> &[usize] {
        &self.counts
    }

    /// This rank's number of unknowns.
    pub fn local(&self) -> usize {
        self.local * self.block
    }

    /// This rank's nodes in PETSc's order.
    pub fn own_nodes(&self) -> &[u32] {
        &self.own
    }

    /// This rank's nodes, increasing, each with its place in [`Self::own_nodes`].
    pub fn own_places(&self) -> &[(u32, u32)] {
        &self.own_sorted
    }

    /// Unknowns per node.
    pub fn block(&self) -> usize {
        self.block
    }

    /// This rank's nodes, increasing: the columns ([`NodeColumns`]) it assembles.
    pub fn nodes(&self) -> Vec<usize> {
        self.own_sorted
            .iter()
            .map(|&(node, _)| node as usize)
            .collect()
    }

    /// This rank's rows for PETSc: `columns` (of this rank's [`Self::nodes`], constrained)
    /// read as rows, with global column indices in PETSc's numbering, sorted in each row, and
    /// the coordinates of this rank's nodes (`block` values a node, from `coords`).
    pub fn rows(self, columns: &NodeColumns, coords: &NodeCoords) -> RankRows {
        let block = self.block;
        let rows: Vec<usize> = self.own().collect();
        debug_assert_eq!(columns.num_columns(), rows.len());
        // The column of `columns` (its nodes increasing) at each of this rank's places.
        let mut column_of_place = vec![0; self.local];
        for (q, &(_, place)) in self.own_sorted.iter().enumerate() {
            column_of_place[place as usize] = q;
        }
        // PETSc's node of each of our nodes that this rank reads (its columns' rows are its
        // cells' nodes), for as long as the rows are made.
        let mut petsc_node = vec![u32::MAX; coords.len()];
        for &(ours, p) in &self.known {
            petsc_node[ours as usize] = p;
        }
        let petsc_of = |ours: usize| {
            let p = petsc_node[ours / block];
            assert!(
                p != u32::MAX,
                "node {} of a column is not known here",
                ours / block
            );
            p as usize * block + ours % block
        };
        let mut row_ptr = Vec::with_capacity(rows.len() + 1);
        let mut petsc_columns = Vec::with_capacity(columns.nnz());
        let mut values = Vec::with_capacity(columns.nnz());
        let mut row: Vec<(i64, f64)> = Vec::new();
        row_ptr.push(0i64);
        for (r, &ours) in rows.iter().enumerate() {
            let q = column_of_place[r / block] * block + r % block;
            debug_assert_eq!(columns.dof(q), ours);
            let (entries, entry_values) = columns.column(q);
            row.clear();
            row.extend(
                (entries.iter().zip(entry_values))
                    .map(|(&column, &value)| (petsc_of(column) as i64, value)),
            );
            row.sort_unstable_by_key(|&(column, _)| column);
            petsc_columns.extend(row.iter().map(|&(column, _)| column));
            values.extend(row.iter().map(|&(_, value)| value));
            row_ptr.push(petsc_columns.len() as i64);
        }
        let coords = (rows.iter())
            .map(|&ours| coords[ours / block][ours % block])
            .collect();
        RankRows {
            distribution: self,
            row_ptr,
            columns: petsc_columns,
            values,
            coords,
        }
    }

    /// This rank's rows of `whole` (our numbering), in PETSc's order.
    pub fn local_part(&self, whole: &[f64]) -> Vec<f64> {
        self.own().map(|ours| whole[ours]).collect()
    }

    /// Our unknown at each of this rank's rows, in PETSc's order.
    pub fn own(&self) -> impl Iterator<Item = usize> + '_ {
        let block = self.block;
        (self.own.iter()).flat_map(move |&a| (0..block).map(move |c| a as usize * block + c))
    }

    /// The row among this rank's rows (PETSc's order) of our unknown `dof`, if this rank owns
    /// its node.
    pub fn own_row(&self, dof: usize) -> Option<usize> {
        let node = u32::try_from(dof / self.block).ok()?;
        let at = (self.own_sorted)
            .binary_search_by_key(&node, |&(n, _)| n)
            .ok()?;
        Some(self.own_sorted[at].1 as usize * self.block + dof % self.block)
    }

    /// The rank that owns each of `nodes` (our numbering, increasing, nodes this rank reads).
    pub fn owner_ranks(&self, nodes: &[u32]) -> Result<Vec<u32>, LinalgError> {
        let mut owner = vec![0; nodes.len()];
        for (rank, _, place) in self.places_of(nodes)? {
            owner[place as usize] = rank as u32;
        }
        Ok(owner)
    }

    /// How every rank receives the values of `nodes` (our numbering, increasing, nodes this
    /// rank reads) from their owners ([`NodeGather`]).
    pub fn node_gather(&self, nodes: Vec<u32>) -> Result<NodeGather, LinalgError> {
        let mut counts = vec![0; self.counts.len()];
        let (mut arrival, mut sends) = (Vec::with_capacity(nodes.len()), Vec::new());
        for (rank, p, place) in self.places_of(&nodes)? {
            counts[rank] += self.block;
            arrival.push(place);
            if (self.first..self.first + self.local).contains(&p) {
                sends.push(((p - self.first) as u32, place));
            }
        }
        Ok(NodeGather {
            arrival,
            nodes,
            counts,
            sends,
            block: self.block,
        })
    }

    /// Each of `nodes` (our numbering, increasing) as `(its owner, its PETSc node, its place in
    /// `nodes`)`, in PETSc's order (rank after rank); an error names a node this rank does not
    /// read (whose PETSc node it does not know).
    fn places_of(&self, nodes: &[u32]) -> Result<Vec<(usize, usize, u32)>, LinalgError> {
        debug_assert!(nodes.windows(2).all(|w| w[0] < w[1]), "nodes increasing");
        let starts = self.rank_ends();
        let mut places = Vec::with_capacity(nodes.len());
        let mut at = 0;
        for (place, &a) in nodes.iter().enumerate() {
            at += self.known[at..].partition_point(|&(b, _)| b < a);
            match self.known.get(at) {
                Some(&(b, p)) if b == a => {
                    let p = p as usize;
                    let rank = starts.partition_point(|&start| start <= p);
                    places.push((rank, p, place as u32));
                }
                _ => {
                    return Err(LinalgError::Sizes(format!(
                        "node {a} is not one this rank reads (its own, its cells', the boundary's)"
                    )));
                }
            }
        }
        places.sort_unstable_by_key(|&(_, p, _)| p);
        Ok(places)
    }

    /// The PETSc node after each rank's last, in rank order: the owner of PETSc node `p` is
    /// the number of them at or below `p`.
    fn rank_ends(&self) -> Vec<usize> {
        (self.counts.iter())
            .scan(0, |start, &count| {
                *start += count / self.block;
                Some(*start)
            })
            .collect()
    }

    /// The values of the body's vector at every node this rank reads (`block` each, the nodes
    /// increasing: on a rank of a distributed run those whose coordinates its mesh keeps,
    /// `crate::mesh::NodeCoords`, so the values are laid out like its kept coordinates), from
    /// `rows`, this rank's rows of it in PETSc's order (collective). Its own nodes' values are
    /// its rows'; the others' it asks of their owners, and each rank answers what the others
    /// read of its nodes (two `MPI_Alltoallv`): no rank receives more than it reads, and the
    /// values are the owners' to the bit.
    pub fn at_read_nodes(&self, rows: &[f64]) -> Result<Vec<f64>, LinalgError> {
        let b = self.block;
        let mpi = |e: crate::parallel::ParallelError| LinalgError::Mpi(e.to_string());
        let own = self.first..self.first + self.local;
        let ends = self.rank_ends();
        let mut values = vec![0.0; b * self.known.len()];
        // What this rank asks each rank for (PETSc nodes), and where each answer goes.
        let mut asked = vec![Vec::new(); ends.len()];
        let mut places = vec![Vec::new(); ends.len()];
        for (place, &(_, p)) in self.known.iter().enumerate() {
            let p = p as usize;
            if own.contains(&p) {
                let row = p - self.first;
                values[b * place..b * (place + 1)].copy_from_slice(&rows[b * row..b * (row + 1)]);
            } else {
                let rank = ends.partition_point(|&end| end <= p);
                asked[rank].push(p as f64);
                places[rank].push(place);
            }
        }
        let asks = crate::parallel::exchange(asked).map_err(mpi)?;
        let mut answers = Vec::with_capacity(asks.len());
        for nodes in &asks {
            let mut answer = Vec::with_capacity(b * nodes.len());
            for &p in nodes {
                let p = p as usize;
                if !own.contains(&p) {
                    return Err(LinalgError::Sizes(format!(
                        "a rank asked for PETSc node {p}, which this rank does not own"
                    )));
                }
                let row = p - self.first;
                answer.extend_from_slice(&rows[b * row..b * (row + 1)]);
            }
            answers.push(answer);
        }
        let answered = crate::parallel::exchange(answers).map_err(mpi)?;
        for (places, answer) in places.iter().zip(&answered) {
            if answer.len() != b * places.len() {
                return Err(LinalgError::Sizes(format!(
                    "{} values answered for {} nodes asked",
                    answer.len(),
                    places.len()
                )));
            }
            for (&place, value) in places.iter().zip(answer.chunks_exact(b)) {
                values[b * place..b * (place + 1)].copy_from_slice(value);
            }
        }
        Ok(values)
    }

    /// The nonzero entries `(unknown, value)` (our numbering) of a vector whose values each
    /// rank holds at its own unknowns, `own` this rank's (at its unknowns only), gathered onto
    /// every rank by increasing unknown (`MPI_Allgatherv` of the entries): a vector nonzero at
    /// few unknowns crosses the ranks without a vector of the body's size (collective).
    pub fn gather_nonzero(
        &self,
        own: impl Iterator<Item = (usize, f64)>,
    ) -> Result<Vec<(usize, f64)>, LinalgError> {
        let mpi = |e: crate::parallel::ParallelError| LinalgError::Mpi(e.to_string());
        // `[unknown, value]` pairs: an unknown is exact in an f64.
        let sent: Vec<f64> = (own.filter(|&(_, value)| value != 0.0))
            .flat_map(|(unknown, value)| [unknown as f64, value])
            .collect();
        let counts = crate::parallel::gather(sent.len() as f64).map_err(mpi)?;
        let counts: Vec<usize> = counts.iter().map(|&c| c as usize).collect();
        let every = crate::parallel::all_gather(&sent, &counts).map_err(mpi)?;
        let mut entries: Vec<(usize, f64)> = (every.chunks_exact(2))
            .map(|pair| (pair[0] as usize, pair[1]))
            .collect();
        entries.sort_unstable_by_key(|&(unknown, _)| unknown);
        Ok(entries)
    }

    /// Every rank's `local` rows (PETSc's order) into `whole` (our numbering), on every rank:
    /// each rank's values and its nodes (`MPI_Allgatherv` each), so that no rank needs a map of
    /// every node.
    pub fn gather(&self, local: &[f64], whole: &mut [f64]) -> Result<(), LinalgError> {
        let mpi = |e: crate::parallel::ParallelError| LinalgError::Mpi(e.to_string());
        let values = crate::parallel::all_gather(local, &self.counts).map_err(mpi)?;
        let nodes_per_rank: Vec<usize> = self.counts.iter().map(|c| c / self.block).collect();
        let own: Vec<f64> = self.own.iter().map(|&a| f64::from(a)).collect();
        let nodes = crate::parallel::all_gather(&own, &nodes_per_rank).map_err(mpi)?;
        let block = self.block;
        for (&a, values) in nodes.iter().zip(values.chunks_exact(block)) {
            let d = a as usize * block;
            whole[d..d + block].copy_from_slice(values);
        }
        Ok(())
    }
}

/// Some nodes' values gathered from the ranks that own them, onto every rank: what the contact
/// loop reads of a body (its displacement on the boundary, its contact forces) without a
/// vector of the body's size on any rank ([`Distribution::node_gather`]). Each rank sends its
/// own nodes' values among them, in PETSc's order, and every rank receives every rank's
/// (`MPI_Allgatherv`): the values are the owners' to the bit.
#[derive(Debug)]
pub struct NodeGather {
    /// The nodes (our numbering), increasing.
    nodes: Vec<u32>,
    /// The place in `nodes` of each node in the order the values arrive (rank after rank,
    /// each rank's in PETSc's order).
    arrival: Vec<u32>,
    /// The values each rank sends (`block` per node), in rank order.
    counts: Vec<usize>,
    /// This rank's nodes among `nodes`, in the order it sends them: each one's row among this
    /// rank's rows (PETSc's order, `block` values each) and its place in `nodes`.
    sends: Vec<(u32, u32)>,
    block: usize,
}

impl NodeGather {
    /// The nodes gathered, increasing.
    pub fn nodes(&self) -> &[u32] {
        &self.nodes
    }

    /// The place of `node` among [`Self::nodes`], if it is one of them.
    pub fn place(&self, node: usize) -> Option<usize> {
        u32::try_from(node)
            .ok()
            .and_then(|node| self.nodes.binary_search(&node).ok())
    }

    /// Every node's values (`block` each, in the order of [`Self::nodes`]) from `rows`, this
    /// rank's rows of the body's vector in PETSc's order (collective).
    pub fn from_rows(&self, rows: &[f64]) -> Result<Vec<f64>, LinalgError> {
        self.exchange(&self.sent(rows, |(row, _)| row))
    }

    /// Every node's values (`block` each, in the order of [`Self::nodes`]) as the rank that
    /// owns it has them in `at_nodes` (the same layout; this rank's values at the other ranks'
    /// nodes are not read) (collective).
    pub fn from_owners(&self, at_nodes: &[f64]) -> Result<Vec<f64>, LinalgError> {
        self.exchange(&self.sent(at_nodes, |(_, place)| place))
    }

    /// The values this rank sends: `block` of `from` at the position `at` picks of each of its
    /// nodes (its row, or its place among the nodes).
    fn sent(&self, from: &[f64], at: impl Fn((u32, u32)) -> u32) -> Vec<f64> {
        let b = self.block;
        (self.sends.iter())
            .flat_map(|&send| {
                let k = at(send) as usize;
                from[k * b..(k + 1) * b].iter().copied()
            })
            .collect()
    }

    fn exchange(&self, sent: &[f64]) -> Result<Vec<f64>, LinalgError> {
        let arrived = crate::parallel::all_gather(sent, &self.counts)
            .map_err(|e| LinalgError::Mpi(e.to_string()))?;
        Ok(self.placed(&arrived))
    }

    /// What every rank sent, in rank order, put in the order of [`Self::nodes`].
    fn placed(&self, arrived: &[f64]) -> Vec<f64> {
        let b = self.block;
        let mut values = vec![0.0; b * self.nodes.len()];
        for (&place, value) in self.arrival.iter().zip(arrived.chunks_exact(b)) {
            values[place as usize * b..(place as usize + 1) * b].copy_from_slice(value);
        }
        values
    }
}

/// One rank's rows of a body's constrained stiffness, as PETSc takes them: compressed rows
/// (pointers from 0, global columns in PETSc's numbering, values), with the coordinates of the
/// rank's nodes (the near-null space), and how the body is distributed.
#[derive(Debug)]
pub struct RankRows {
    pub distribution: Distribution,
    pub row_ptr: Vec<i64>,
    pub columns: Vec<i64>,
    pub values: Vec<f64>,
    pub coords: Vec<f64>,
}

impl RankRows {
    /// The number of this rank's rows.
    pub fn num_rows(&self) -> usize {
        self.row_ptr.len() - 1
    }

    /// The body's number of unknowns (every rank's rows).
    pub fn num_dofs(&self) -> usize {
        self.distribution.counts().iter().sum()
    }

    /// The block size (unknowns per node).
    pub fn block(&self) -> usize {
        self.distribution.block
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A body's partition with parts of the given sizes (part `p`'s nodes labelled `p`).
    fn parts(sizes: &[usize]) -> Vec<u32> {
        (sizes.iter().enumerate())
            .flat_map(|(p, &n)| std::iter::repeat_n(p as u32, n))
            .collect()
    }

    #[test]
    fn a_second_body_s_larger_part_goes_to_the_rank_with_fewer_nodes() {
        let mut nodes_on_rank = vec![0, 0];
        let mut first = parts(&[100, 104]);
        spread_parts(&mut first, &mut nodes_on_rank);
        // Nothing placed yet: any labels are as good, so METIS's stay.
        assert_eq!(first, parts(&[100, 104]));
        assert_eq!(nodes_on_rank, [100, 104]);

        let mut second = parts(&[50, 53]);
        spread_parts(&mut second, &mut nodes_on_rank);
        assert_eq!(&second[..50], &[1; 50]);
        assert_eq!(&second[50..], &[0; 53]);
        assert_eq!(nodes_on_rank, [153, 154]);

        // A body that evens the totals with METIS's labels keeps them.
        let mut third = parts(&[11, 10]);
        spread_parts(&mut third, &mut nodes_on_rank);
        assert_eq!(third, parts(&[11, 10]));
        assert_eq!(nodes_on_rank, [164, 164]);
    }

    #[test]
    fn each_rank_orders_its_own_nodes_as_the_whole_body_s_coordinates_do() {
        // 40 nodes scattered over a box, owned by ranks 0, 1, 2 in turn.
        let (num_nodes, block) = (40, 2);
        let owner: Vec<u32> = (0..num_nodes).map(|a| (a % 3) as u32).collect();
        let coords: Vec<f64> = (0..num_nodes)
            .flat_map(|a| [(1.7 * a as f64).sin() * 3.0, (0.9 * a as f64).cos() - 2.0])
            .collect();
        let low: Vec<f64> = (0..block)
            .map(|c| {
                coords
                    .iter()
                    .skip(c)
                    .step_by(block)
                    .copied()
                    .fold(f64::INFINITY, f64::min)
            })
            .collect();
        let high: Vec<f64> = (0..block)
            .map(|c| {
                (coords.iter().skip(c).step_by(block).copied()).fold(f64::NEG_INFINITY, f64::max)
            })
            .collect();
        for rank in 0..3 {
            let whole = Distribution::with_owners(&owner, &coords, block, Ranks { rank, size: 3 });
            let own: Vec<u32> = (0..num_nodes as u32)
                .filter(|&a| owner[a as usize] == rank as u32)
                .collect();
            let own_coords: Vec<f64> = (own.iter())
                .flat_map(|&a| coords[block * a as usize..block * (a as usize + 1)].to_vec())
                .collect();
            assert_eq!(
                own_order(&own, &own_coords, &low, &high),
                whole.unwrap().own_nodes()
            );
        }
    }

    #[test]
    fn some_nodes_gathered_from_three_ranks_are_the_whole_vector_s_entries() {
        // 12 nodes of 2 unknowns on a line, owned by ranks 0, 1, 2 in turn; the whole vector's
        // entry at unknown `d` is `d`.
        let (num_nodes, block) = (12, 2);
        let owner: Vec<u32> = (0..num_nodes).map(|a| (a % 3) as u32).collect();
        let coords: Vec<f64> = (0..num_nodes).flat_map(|a| [a as f64, 0.0]).collect();
        let whole: Vec<f64> = (0..num_nodes * block).map(|d| d as f64).collect();
        let nodes: Vec<u32> = vec![0, 2, 3, 7, 8, 11];
        let ranks = |rank| Ranks { rank, size: 3 };
        let distributions: Vec<Distribution> = (0..3)
            .map(|r| Distribution::with_owners(&owner, &coords, block, ranks(r)).unwrap())
            .collect();
        let plans: Vec<NodeGather> = (distributions.iter())
            .map(|d| d.node_gather(nodes.clone()).unwrap())
            .collect();
        let expected: Vec<f64> = (nodes.iter())
            .flat_map(|&a| whole[block * a as usize..block * (a as usize + 1)].to_vec())
            .collect();
        // From each rank's rows: what every rank sends, in rank order, is what each receives.
        let arrived: Vec<f64> = (plans.iter().zip(&distributions))
            .flat_map(|(plan, d)| plan.sent(&d.local_part(&whole), |(row, _)| row))
            .collect();
        for plan in &plans {
            assert_eq!(plan.placed(&arrived), expected);
        }
        // From values at the nodes, each node's owner's (the others' are not read).
        let arrived: Vec<f64> = (plans.iter().enumerate())
            .flat_map(|(r, plan)| {
                let mine: Vec<f64> = (nodes.iter())
                    .flat_map(|&a| {
                        let d = block * a as usize;
                        match owner[a as usize] as usize == r {
                            true => whole[d..d + block].to_vec(),
                            false => vec![f64::NAN; block],
                        }
                    })
                    .collect();
                plan.sent(&mine, |(_, place)| place)
            })
            .collect();
        for plan in &plans {
            assert_eq!(plan.placed(&arrived), expected);
        }
        assert_eq!(plans[1].place(7), Some(3));
        assert_eq!(plans[1].place(5), None);
        let owners: Vec<u32> = nodes.iter().map(|&a| owner[a as usize]).collect();
        for d in &distributions {
            assert_eq!(d.owner_ranks(&nodes).unwrap(), owners);
        }
    }

    #[test]
    fn parts_on_four_ranks_fill_the_emptiest_ranks_largest_first() {
        let mut nodes_on_rank = vec![30, 0, 20, 10];
        let mut owner = parts(&[40, 5, 25, 31]);
        spread_parts(&mut owner, &mut nodes_on_rank);
        // With METIS's labels the totals would be 70 / 5 / 45 / 41. Largest first: 40 to rank
        // 1 (0 nodes so far), 31 to rank 3 (10), 25 to rank 2 (20), 5 to rank 0 (30).
        assert_eq!(nodes_on_rank, [35, 40, 45, 41]);
        assert_eq!(
            owner,
            [vec![1; 40], vec![0; 5], vec![2; 25], vec![3; 31]].concat()
        );
    }
}
