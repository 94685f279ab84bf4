//! Which of the bodies' unknowns a rank of a distributed run owns, and where each sits in its
//! Krylov vectors (`crate::contact::coupled::krylov_layout`): this rank's rows of each body in
//! PETSc's order, one body after another. The coupled system numbers the entries of `B` and
//! `C` it keeps by it (`crate::contact::coupled::system::CoupledSystem::assemble_on`).

use crate::contact::ContactError;
use crate::linalg::{BodySolver, Distribution};

/// Where each of the bodies' unknowns sits in this rank's Krylov vectors, in a distributed run:
/// what `CoupledSystem::assemble_on` numbers the coupling blocks' entries by.
pub struct RowOwnership {
    /// For each unknown of the bodies (the system's numbering), its place among this rank's
    /// rows, or [`Self::ELSEWHERE`]: four bytes an unknown, half of what the partition itself
    /// (`Distribution`) takes.
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
            for &ours in body.own() {
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
