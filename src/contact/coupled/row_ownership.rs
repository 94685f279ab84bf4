//! Which of the bodies' unknowns a rank of a distributed run owns, and where each sits in its
//! Krylov vectors (`crate::contact::coupled::krylov_layout`): this rank's rows of each body in
//! PETSc's order, one body after another. The coupled system numbers the entries of `B` and
//! `C` it keeps by it (`crate::contact::coupled::system::CoupledSystem::assemble_on`), and the
//! interface transfers keep their entries at this rank's nodes only ([`kept_nodes`]); the
//! forces they make are completed from the ranks that own them ([`complete_forces`]).

use crate::contact::ContactError;
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

/// The nodes of a shared `body` at which this rank keeps the entries of the interface
/// transfers (`crate::contact::coupled::interface::InterfaceOperators::coupling`): its own
/// nodes, whose entries are the rows of `B` and the columns of `C` it holds, and every node
/// with a force-controlled unknown, whose entries go to the rigid block `D` that every rank
/// holds whole. An entry elsewhere would be dropped by `CoupledSystem::assemble_on` anyway;
/// kept, the transfers' rows and columns (the largest part of the interface at 1M DOFs) would
/// be whole on every rank.
pub fn kept_nodes(distribution: &Distribution, body: &AssembledBody) -> Vec<bool> {
    let mut kept = vec![false; body.f.len() / body.dim];
    for &node in distribution.own_nodes() {
        kept[node as usize] = true;
    }
    for dof in body.rigid.iter().flat_map(|rigid| &rigid.dofs) {
        kept[dof / body.dim] = true;
    }
    kept
}

/// The forces `forces` on the shared bodies whose distributions are `bodies`, each made on
/// this rank from the entries it keeps ([`kept_nodes`]), completed from their owners: every
/// unknown's terms are all on the rank that owns it, so its value there is whole, and each
/// rank's own values are gathered onto every rank (the same sums in the same order as from
/// whole transfers, bit for bit). Each force is whole only while it is gathered, and kept as
/// its nonzero entries after (`LoadVector::new`).
pub fn complete_forces(
    bodies: &[&Distribution],
    forces: &mut [&mut LoadVector],
) -> Result<(), ContactError> {
    for (distribution, force) in bodies.iter().zip(forces.iter_mut()) {
        let mut whole = force.to_vec();
        let own = distribution.local_part(&whole);
        (distribution.gather(&own, &mut whole)).map_err(|e| ContactError::Linalg(e.to_string()))?;
        **force = LoadVector::new(whole);
    }
    Ok(())
}
