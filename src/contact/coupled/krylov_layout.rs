//! How this process holds the vectors of the coupled GMRES
//! (`crate::contact::coupled::coupled_krylov`).
//!
//! On one process a vector of the coupled system is whole: `[u_1; ...; u_N; lambda / s]`, each
//! body's unknowns in our numbering. In a distributed run each body's unknowns are shared among
//! the ranks (`crate::linalg::Distribution`), and a Krylov vector holds only this rank's rows of
//! each body, in PETSc's order, followed by every multiplier (and force-controlled
//! displacement):
//!
//! ```text
//! local = [u_1 (this rank's rows); ...; u_N (this rank's rows); lambda / s (all of them)]
//! ```
//!
//! The multipliers are of the interface's size, and every rank holds all of them: every rank
//! computes them from the same numbers, so they are the same bits on every rank. The GMRES
//! basis, up to 50 vectors, then takes `n / P + m` values per vector on each of `P` ranks
//! instead of `n + m`.
//!
//! Inner products: each rank sums over its rows; every rank receives every rank's sum
//! (`MPI_Allgatherv` of one value each) and adds them in rank order, then adds the multipliers'
//! part, which it computes itself. The result is the same bits on every rank and from one run to
//! the next (`MPI_Allreduce` would leave the order of the sum to the library).
//!
//! The coupling blocks follow the vectors (`crate::contact::coupled::row_ownership`): a rank's
//! coupled system holds the entries of `B` on its rows and those of `C` on its columns,
//! numbered by their place in this rank's Krylov vectors
//! (`crate::contact::coupled::system::CoupledSystem::assemble_on`).
//! So `B lambda` is computed on this rank's rows alone, and `C u` is every rank's part over its
//! columns, added in rank order as the inner products are (one `MPI_Allgatherv` of the `m`
//! values each): no rank holds or gathers a whole displacement vector during the solve.

use std::ops::Range;

use crate::contact::ContactError;
use crate::contact::coupled::row_ownership::shared_bodies;
use crate::contact::coupled::system::{CoupledSystem, Unknowns};
use crate::linalg::{BodySolver, gmres};

/// Where the values of a Krylov vector are held (module doc).
pub enum KrylovLayout {
    /// The whole vector on this process.
    Whole,
    /// This rank's rows of each body, then every multiplier.
    Shared(SharedLayout),
}

/// The layout of a distributed run's Krylov vectors.
pub struct SharedLayout {
    /// Body `k`'s rows of this rank are `local[k]..local[k + 1]` of a Krylov vector.
    local: Vec<usize>,
}

impl KrylovLayout {
    /// The layout of `system`'s vectors given the bodies' `solvers`: shared when they are
    /// shared among ranks, which in a distributed run every body's is (CG + AMG on its rows);
    /// then `system` must hold this rank's entries ([`Unknowns::RankRows`]).
    pub fn new(system: &CoupledSystem, solvers: &[BodySolver]) -> Result<Self, ContactError> {
        let shared = match (shared_bodies(solvers)?, system.unknowns) {
            (None, Unknowns::Whole) => return Ok(Self::Whole),
            (Some(shared), Unknowns::RankRows) => shared,
            (shared, unknowns) => {
                return Err(ContactError::Linalg(format!(
                    "the bodies are {} and the coupled system holds {unknowns:?}: the coupled \
                     GMRES needs both shared among the ranks, or neither",
                    if shared.is_some() {
                        "shared among the ranks"
                    } else {
                        "whole"
                    },
                )));
            }
        };
        let mut local = vec![0];
        for body in &shared {
            local.push(local.last().unwrap() + body.local());
        }
        Ok(Self::Shared(SharedLayout { local }))
    }

    /// The displacement rows of a vector: where its multipliers start.
    pub fn num_rows(&self, system: &CoupledSystem) -> usize {
        match self {
            Self::Whole => system.num_displacements(),
            Self::Shared(layout) => layout.num_local(),
        }
    }

    /// `a . b` of two vectors of this layout (collective when shared).
    pub fn dot(&self, a: &[f64], b: &[f64]) -> Result<f64, ContactError> {
        match self {
            Self::Whole => Ok(gmres::dot(a, b)),
            Self::Shared(layout) => {
                let rows = layout.num_local();
                let partial = gmres::dot(&a[..rows], &b[..rows]);
                let partials = crate::parallel::gather(partial).map_err(mpi_error)?;
                let bodies: f64 = partials.iter().sum();
                Ok(bodies + gmres::dot(&a[rows..], &b[rows..]))
            }
        }
    }
}

impl SharedLayout {
    /// This rank's rows of every body: where the multipliers start in a Krylov vector.
    pub fn num_local(&self) -> usize {
        *self.local.last().expect("offsets start with 0")
    }

    /// Body `k`'s rows of this rank, within a Krylov vector.
    pub fn local_range(&self, k: usize) -> Range<usize> {
        self.local[k]..self.local[k + 1]
    }

    /// `out += ` the sum over the ranks of every rank's `partial` (of one length on every
    /// rank), added in rank order (collective).
    pub fn add_rank_sums(&self, partial: &[f64], out: &mut [f64]) -> Result<(), ContactError> {
        let ranks = crate::parallel::ranks().size;
        let all =
            crate::parallel::all_gather(partial, &vec![partial.len(); ranks]).map_err(mpi_error)?;
        for (k, value) in out.iter_mut().enumerate() {
            let sum: f64 = (0..ranks).map(|r| all[r * partial.len() + k]).sum();
            *value += sum;
        }
        Ok(())
    }
}

fn mpi_error(e: crate::parallel::ParallelError) -> ContactError {
    ContactError::Linalg(format!("a sum over the ranks in the coupled GMRES: {e}"))
}
