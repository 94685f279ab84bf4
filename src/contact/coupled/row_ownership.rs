//! Which of the bodies' unknowns a rank of a distributed run owns, and where each sits in its
//! Krylov vectors (`crate::contact::coupled::krylov_layout`): this rank's rows of each body in
//! PETSc's order, one body after another. The coupled system numbers the entries of `B` and
//! `C` it keeps by it (`crate::contact::coupled::system::CoupledSystem::assemble_on`), and the
//! interface transfers keep their entries at this rank's nodes only ([`Keepers`]); the
//! forces they make are completed from the ranks that own them ([`complete_forces`]).

use crate::contact::ContactError;
use crate::contact::geometry::rbf::Entries;
use crate::contact::geometry::rbf_patch::BlockShare;
use crate::elastic::AssembledBody;
use crate::fem::LoadVector;
use crate::linalg::{BodySolver, Distribution};

/// Where each of the bodies' unknowns sits in this rank's Krylov vectors, in a distributed run:
/// what `CoupledSystem::assemble_on` numbers the coupling blocks' entries by.
///
/// It keeps each body's own nodes and finds an unknown's node among them by bisection, so that
/// it holds four bytes per node of this rank's share, not of the whole bodies (a map of every
/// unknown to its place took four bytes per unknown of every body on every rank: 400 MB a rank
/// at 100M unknowns). A coupled system's assembly asks for one place per entry of `B` and `C`.
pub struct RowOwnership {
    /// Each body's rows of this rank, in the order of the bodies.
    bodies: Vec<OwnRows>,
    /// This rank's rows of every body.
    num_local: usize,
}

/// One body's rows of this rank.
struct OwnRows {
    /// The body's first unknown in the system's numbering.
    first: usize,
    /// Unknowns per node.
    block: usize,
    /// This rank's nodes of the body, increasing, each with its place among them in PETSc's
    /// order (`Distribution::own_places`): its rows are their unknowns, node by node, in
    /// PETSc's order.
    nodes: Vec<(u32, u32)>,
    /// Where the body's rows start among this rank's.
    local: usize,
}

impl RowOwnership {
    /// The ownership of the bodies whose `solvers` are shared among the ranks; `None` where
    /// they are whole on this process.
    pub fn of(solvers: &[BodySolver]) -> Result<Option<Self>, ContactError> {
        Ok(shared_bodies(solvers)?.map(|shared| Self::from_distributions(&shared)))
    }

    /// The ownership of the bodies shared as `bodies` say, one after another.
    pub fn from_distributions(bodies: &[&Distribution]) -> Self {
        let (mut first, mut local) = (0, 0);
        let mut own = Vec::with_capacity(bodies.len());
        for body in bodies {
            own.push(OwnRows {
                first,
                block: body.block(),
                nodes: body.own_places().to_vec(),
                local,
            });
            first += body.counts().iter().sum::<usize>();
            local += body.local();
        }
        Self {
            bodies: own,
            num_local: local,
        }
    }

    /// This rank's rows of every body: where the multipliers start in its Krylov vectors.
    pub fn num_local(&self) -> usize {
        self.num_local
    }

    /// Body `k`'s unknowns of this rank: each one's place among this rank's rows and the
    /// unknown (the body's numbering).
    pub fn own_rows(&self, k: usize) -> impl Iterator<Item = (usize, usize)> + '_ {
        let body = &self.bodies[k];
        let block = body.block;
        (body.nodes.iter()).flat_map(move |&(node, place)| {
            (0..block).map(move |c| {
                let row = body.local + place as usize * block + c;
                (row, node as usize * block + c)
            })
        })
    }

    /// The place of unknown `global` (the system's numbering) among this rank's rows, if it is
    /// this rank's.
    pub fn place(&self, global: usize) -> Option<usize> {
        let body = &self.bodies[self.bodies.partition_point(|b| b.first <= global) - 1];
        let ours = global - body.first;
        let node = u32::try_from(ours / body.block).ok()?;
        let k = body
            .nodes
            .binary_search_by_key(&node, |&(node, _)| node)
            .ok()?;
        Some(body.local + body.nodes[k].1 as usize * body.block + ours % body.block)
    }
}

/// How each body is shared among the ranks, from its solver: every body's distribution, or
/// `None` where every body is whole on this process (the coupled GMRES takes no mixture).
pub fn shared_bodies(solvers: &[BodySolver]) -> Result<Option<Vec<&Distribution>>, ContactError> {
    let shared: Vec<&Distribution> = solvers.iter().filter_map(|s| s.distribution()).collect();
    match shared.len() {
        0 => Ok(None),
        n if n == solvers.len() => Ok(Some(shared)),
        n => Err(ContactError::Linalg(format!(
            "{n} of {} bodies are shared among the ranks: the coupled GMRES needs all or none",
            solvers.len()
        ))),
    }
}

/// Which ranks keep the entries of the interface transfers
/// (`crate::contact::coupled::interface::InterfaceOperators::coupling`) at each secondary
/// candidate of a pair: the rank that owns its node, whose entries are the rows of `B` and
/// the columns of `C` that rank holds, and every rank at a node with a force-controlled
/// unknown, whose entries go to the rigid block `D` that every rank holds whole. An entry
/// elsewhere would be dropped by `CoupledSystem::assemble_on` anyway; kept, the transfers'
/// rows and columns (the largest part of the interface at 1M DOFs) would be whole on every
/// rank. Each rank computes a share of the rows and columns and sends each entry to the ranks
/// that keep it.
#[derive(Debug, Clone)]
pub struct Keepers {
    /// This rank, and the number of ranks.
    rank: u32,
    size: u32,
    /// The rank that owns each candidate's node.
    owner: Vec<u32>,
    /// Whether each candidate's node has a force-controlled unknown.
    everywhere: Vec<bool>,
}

impl Keepers {
    /// The keepers of the secondary candidates at `nodes` (increasing) of a shared `body`
    /// distributed as `distribution`.
    pub fn new(
        distribution: &Distribution,
        body: &AssembledBody,
        nodes: &[usize],
    ) -> Result<Self, ContactError> {
        let ranks = crate::parallel::ranks();
        let mut forced: Vec<usize> = (body.rigid.iter())
            .flat_map(|rigid| rigid.dofs.iter().map(|dof| dof / body.dim))
            .collect();
        forced.sort_unstable();
        let nodes32: Vec<u32> = nodes.iter().map(|&n| n as u32).collect();
        Ok(Self {
            rank: ranks.rank as u32,
            size: ranks.size as u32,
            owner: (distribution.owner_ranks(&nodes32))
                .map_err(|e| ContactError::Linalg(e.to_string()))?,
            everywhere: (nodes.iter())
                .map(|node| forced.binary_search(node).is_ok())
                .collect(),
        })
    }

    /// The ranks that keep the entries at candidate `j`, increasing.
    pub fn ranks_keeping(&self, j: usize) -> std::ops::Range<usize> {
        match self.everywhere[j] {
            true => 0..self.size as usize,
            false => self.owner[j] as usize..self.owner[j] as usize + 1,
        }
    }

    /// This rank's share of the blocks of rows and columns to compute.
    pub fn share(&self) -> BlockShare {
        BlockShare {
            rank: self.rank as usize,
            size: self.size as usize,
        }
    }
}

/// Rows (or columns) of a transfer that each rank computed a share of (`Some` where this rank
/// did), each entry `(j, w)` sent to the ranks `ranks_keeping(j)` names ([`Keepers`]): returns
/// every row with the entries this rank keeps, in the order they were computed in, so each row
/// is the one this rank would have computed and filtered itself, bit for bit (collective: one
/// `MPI_Alltoallv`).
pub fn send_to_keepers(
    computed: Vec<Option<Entries>>,
    ranks_keeping: impl Fn(usize) -> std::ops::Range<usize>,
) -> Result<Vec<Entries>, ContactError> {
    let size = crate::parallel::ranks().size;
    // Each entry as three values: its row, its column, its weight (the indices are exact in a
    // `f64` below 2^53).
    let mut sends = vec![Vec::new(); size];
    for (k, row) in computed.iter().enumerate() {
        for &(j, w) in row.iter().flatten() {
            for rank in ranks_keeping(j) {
                sends[rank].extend([k as f64, j as f64, w]);
            }
        }
    }
    let num_rows = computed.len();
    drop(computed);
    let received = crate::parallel::exchange(sends).map_err(|e| {
        ContactError::Linalg(format!("sending the interface transfers' entries: {e}"))
    })?;
    let mut rows = vec![Vec::new(); num_rows];
    for entry in received.iter().flat_map(|from| from.chunks_exact(3)) {
        rows[entry[0] as usize].push((entry[1] as usize, entry[2]));
    }
    Ok(rows)
}

/// The forces `forces` on the shared bodies whose distributions are `bodies`, each made on
/// this rank from the entries it keeps ([`Keepers`]), completed from their owners: every
/// unknown's terms are all on the rank that owns it, so its value there is whole, and each
/// rank's own nonzero values, with their unknowns, are gathered onto every rank (the same
/// values as from whole transfers, bit for bit). A force is nonzero at the interface's nodes
/// only, so no rank holds a vector of the body's size (`LoadVector::from_entries` keeps it as
/// `LoadVector::new` would keep the whole vector).
pub fn complete_forces(
    bodies: &[&Distribution],
    forces: &mut [&mut LoadVector],
) -> Result<(), ContactError> {
    for (distribution, force) in bodies.iter().zip(forces.iter_mut()) {
        let own = (force.nonzero_entries()).filter(|&(dof, _)| distribution.own_row(dof).is_some());
        let entries =
            (distribution.gather_nonzero(own)).map_err(|e| ContactError::Linalg(e.to_string()))?;
        **force = LoadVector::from_entries(force.len(), entries);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_sent_to_their_keepers_are_the_computed_rows_at_the_kept_entries() {
        // One rank, which keeps the entries at even columns: every computed row's entries
        // there, in their order, and an empty row where no rank computed one.
        let computed = vec![
            Some(vec![(0, 0.25), (3, -1.5), (4, 2.0)]),
            None,
            Some(vec![(1, 7.0), (2, 1e-12), (6, 3.0)]),
        ];
        let rows = send_to_keepers(computed, |j| 0..usize::from(j % 2 == 0)).unwrap();
        assert_eq!(
            rows,
            [
                vec![(0, 0.25), (4, 2.0)],
                vec![],
                vec![(2, 1e-12), (6, 3.0)]
            ]
        );
    }
}
