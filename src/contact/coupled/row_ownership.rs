//! Which of the bodies' unknowns a rank of a distributed run owns, and where each sits in its
//! Krylov vectors (`crate::contact::coupled::krylov_layout`): this rank's rows of each body in
//! PETSc's order, one body after another. The coupled system numbers the entries of `B` and
//! `C` it keeps by it (`crate::contact::coupled::system::CoupledSystem::assemble_on`), and the
//! interface transfers keep their entries at this rank's nodes only ([`kept_nodes`]); the
//! forces they make are completed from the ranks that own them ([`complete_forces`]).

use crate::contact::ContactError;
use crate::elastic::AssembledBody;
use crate::linalg::{BodySolver, Distribution};

/// Where each of the bodies' unknowns sits in this rank's Krylov vectors, in a distributed run:
/// what `CoupledSystem::assemble_on` numbers the coupling blocks' entries by.
pub struct RowOwnership {
    /// For each unknown of the bodies (the system's numbering), its place among this rank's
    /// rows, or [`Self::ELSEWHERE`]: four bytes an unknown on every rank (the partition itself,
    /// `Distribution`, takes four bytes a node).
    place: Vec<u32>,
}

impl RowOwnership {
    const ELSEWHERE: u32 = u32::MAX;

    /// The ownership of the bodies whose `solvers` are shared among the ranks; `None` where
    /// they are whole on this process.
    pub fn of(solvers: &[BodySolver]) -> Result<Option<Self>, ContactError> {
        shared_bodies(solvers)?
            .map(|shared| Self::from_distributions(&shared))
            .transpose()
    }

    /// The ownership of the bodies shared as `bodies` say, one after another.
    pub fn from_distributions(bodies: &[&Distribution]) -> Result<Self, ContactError> {
        let total: usize = bodies
            .iter()
            .map(|d| d.counts().iter().sum::<usize>())
            .sum();
        if total >= Self::ELSEWHERE as usize {
            return Err(ContactError::Linalg(format!(
                "{total} unknowns: more than a rank's coupled GMRES numbers (2^32 - 1)"
            )));
        }
        let mut place = vec![Self::ELSEWHERE; total];
        let (mut first, mut local) = (0, 0);
        for body in bodies {
            for ours in body.own() {
                place[first + ours] = local as u32;
                local += 1;
            }
            first += body.counts().iter().sum::<usize>();
        }
        Ok(Self { place })
    }

    /// The place of unknown `global` among this rank's rows, if it is this rank's.
    pub fn place(&self, global: usize) -> Option<usize> {
        match self.place[global] {
            Self::ELSEWHERE => None,
            local => Some(local as usize),
        }
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
    for node in distribution.nodes() {
        kept[node] = true;
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
/// whole transfers, bit for bit).
pub fn complete_forces(
    bodies: &[&Distribution],
    forces: &mut [&mut Vec<f64>],
) -> Result<(), ContactError> {
    for (distribution, force) in bodies.iter().zip(forces.iter_mut()) {
        let own = distribution.local_part(force);
        (distribution.gather(&own, force)).map_err(|e| ContactError::Linalg(e.to_string()))?;
    }
    Ok(())
}
