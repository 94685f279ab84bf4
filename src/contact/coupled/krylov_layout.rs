//! How this process holds the vectors of the coupled GMRES
//! (`crate::contact::coupled::coupled_krylov`).
//!
//! On one process a vector of the coupled system is whole: `[u_1; ...; u_N; lambda / s]`, each
//! body's unknowns in our numbering. In a distributed run each body's unknowns are shared among
//! the ranks (`crate::linalg::Distribution`), and so are the multipliers (and force-controlled
//! displacements): a Krylov vector holds only this rank's rows of each body, in PETSc's order,
//! followed by this rank's block of the multipliers:
//!
//! ```text
//! local = [u_1 (this rank's rows); ...; u_N (this rank's rows); lambda / s (this rank's block)]
//! ```
//!
//! The GMRES basis, up to 50 vectors, then takes `(n + m) / P` values per vector on each of `P`
//! ranks instead of `n + m`. The multipliers are split into `P` consecutive blocks of equal
//! size (to one), rank after rank, rather than given to the ranks that own the primary's contact
//! nodes: a product and a preconditioner application read every multiplier (`B`'s columns on a
//! rank's rows reach multipliers of nodes other ranks own, through the RBF transfer, and the
//! half-space block `S~^-1` is dense over a pair's multipliers), so each gathers them whole for
//! the time of the operation (`MPI_Allgatherv` of `m` values, two vectors of `m` a rank), and
//! ownership only decides who stores them between operations: equal blocks store the fewest.
//!
//! Inner products: each rank sums over its rows and its multipliers; every rank receives every
//! rank's sum (`MPI_Allgatherv` of one value each) and adds them in rank order. The result is
//! the same bits on every rank and from one run to the next (`MPI_Allreduce` would leave the
//! order of the sum to the library).
//!
//! The coupling blocks follow the vectors (`crate::contact::coupled::row_ownership`): a rank's
//! coupled system holds the entries of `B` on its rows and those of `C` on its columns,
//! numbered by their place in this rank's Krylov vectors
//! (`crate::contact::coupled::system::CoupledSystem::assemble_on`).
//! So `B lambda` is computed on this rank's rows alone, and `C u` is every rank's part over its
//! columns, sent to the ranks that hold each multiplier and added there in rank order
//! (`MPI_Alltoallv`: a rank receives `m / P` values from each rank): no rank holds or gathers a
//! whole displacement vector during the solve.

use std::ops::Range;

use crate::contact::ContactError;
use crate::contact::coupled::row_ownership::shared_bodies;
use crate::contact::coupled::system::{CoupledSystem, Unknowns};
use crate::linalg::{BodySolver, gmres};

/// Where the values of a Krylov vector are held (module doc).
pub enum KrylovLayout {
    /// The whole vector on this process.
    Whole,
    /// This rank's rows of each body, then its block of the multipliers.
    Shared(SharedLayout),
}

/// The layout of a distributed run's Krylov vectors.
pub struct SharedLayout {
    /// Body `k`'s rows of this rank are `local[k]..local[k + 1]` of a Krylov vector.
    local: Vec<usize>,
    /// Rank `r` holds the multipliers `blocks[r]..blocks[r + 1]` (of `0..m`).
    blocks: Vec<usize>,
    /// This rank.
    rank: usize,
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
        let ranks = crate::parallel::ranks();
        Ok(Self::Shared(SharedLayout {
            local,
            blocks: multiplier_blocks(system.m, ranks.size),
            rank: ranks.rank,
        }))
    }

    /// The displacement rows of a vector: where its multipliers start.
    pub fn num_rows(&self, system: &CoupledSystem) -> usize {
        match self {
            Self::Whole => system.num_displacements(),
            Self::Shared(layout) => layout.num_local(),
        }
    }

    /// A vector of this layout from `x`, the displacement rows it holds followed by every
    /// multiplier (what the solve takes and returns).
    pub fn own_part(&self, mut x: Vec<f64>) -> Vec<f64> {
        match self {
            Self::Whole => x,
            Self::Shared(layout) => {
                let rows = layout.num_local();
                let own = layout.own_multipliers();
                x.copy_within(rows + own.start..rows + own.end, rows);
                x.truncate(rows + own.len());
                x.shrink_to_fit();
                x
            }
        }
    }

    /// `x` (of this layout) with every multiplier: the displacement rows it holds followed by
    /// every rank's block of the multipliers (collective when shared).
    pub fn with_every_multiplier(
        &self,
        x: Vec<f64>,
        system: &CoupledSystem,
    ) -> Result<Vec<f64>, ContactError> {
        match self {
            Self::Whole => Ok(x),
            Self::Shared(layout) => {
                let rows = layout.num_local();
                let mut all = Vec::with_capacity(rows + system.m);
                all.extend_from_slice(&x[..rows]);
                all.resize(rows + system.m, 0.0);
                layout.gather_multipliers(&x[rows..], &mut all[rows..])?;
                Ok(all)
            }
        }
    }

    /// `a . b` of two vectors of this layout (collective when shared).
    pub fn dot(&self, a: &[f64], b: &[f64]) -> Result<f64, ContactError> {
        match self {
            Self::Whole => Ok(gmres::dot(a, b)),
            Self::Shared(_) => {
                let partials = crate::parallel::gather(gmres::dot(a, b)).map_err(mpi_error)?;
                Ok(partials.iter().sum())
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

    /// The multipliers this rank holds (of `0..m`).
    pub fn own_multipliers(&self) -> Range<usize> {
        self.blocks[self.rank]..self.blocks[self.rank + 1]
    }

    /// Every multiplier into `all` (`m` values) from every rank's block of them, `own` this
    /// rank's (collective).
    pub fn gather_multipliers(&self, own: &[f64], all: &mut [f64]) -> Result<(), ContactError> {
        let counts: Vec<usize> = self.blocks.windows(2).map(|b| b[1] - b[0]).collect();
        let gathered = crate::parallel::all_gather(own, &counts).map_err(mpi_error)?;
        all.copy_from_slice(&gathered);
        Ok(())
    }

    /// `own += ` the sum over the ranks of every rank's `partial` (`m` values on every rank) on
    /// this rank's block of the multipliers, added in rank order: each rank sends each other
    /// its part of that rank's block (collective).
    pub fn add_to_owners(&self, partial: &[f64], own: &mut [f64]) -> Result<(), ContactError> {
        let sends = (self.blocks.windows(2))
            .map(|b| partial[b[0]..b[1]].to_vec())
            .collect();
        let received = crate::parallel::exchange(sends).map_err(mpi_error)?;
        for (k, value) in own.iter_mut().enumerate() {
            let sum: f64 = received.iter().map(|from| from[k]).sum();
            *value += sum;
        }
        Ok(())
    }
}

/// Where each of `ranks` ranks' block of `m` multipliers starts, and `m`: consecutive blocks
/// whose sizes differ by one at most.
fn multiplier_blocks(m: usize, ranks: usize) -> Vec<usize> {
    (0..=ranks).map(|r| m * r / ranks).collect()
}

fn mpi_error(e: crate::parallel::ParallelError) -> ContactError {
    ContactError::Linalg(format!("a sum over the ranks in the coupled GMRES: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_multipliers_are_split_in_blocks_of_nearly_equal_size() {
        assert_eq!(multiplier_blocks(7, 3), [0, 2, 4, 7]);
        assert_eq!(multiplier_blocks(2, 4), [0, 0, 1, 1, 2]);
        for (m, ranks) in [(0, 2), (1, 3), (2_779, 4), (60_000, 256)] {
            let blocks = multiplier_blocks(m, ranks);
            let sizes: Vec<usize> = blocks.windows(2).map(|b| b[1] - b[0]).collect();
            assert_eq!((blocks[0], blocks[ranks]), (0, m));
            let (low, high) = (sizes.iter().min().unwrap(), sizes.iter().max().unwrap());
            assert!(high - low <= 1, "{m} on {ranks}: {sizes:?}");
        }
    }

    #[test]
    fn a_rank_keeps_its_rows_and_its_block_of_the_multipliers() {
        // Rank 1 of 2 with 3 rows and 5 multipliers: it holds multipliers 2, 3 and 4.
        let layout = KrylovLayout::Shared(SharedLayout {
            local: vec![0, 1, 3],
            blocks: multiplier_blocks(5, 2),
            rank: 1,
        });
        let x = vec![10.0, 11.0, 12.0, 0.0, 1.0, 2.0, 3.0, 4.0];
        assert_eq!(layout.own_part(x), [10.0, 11.0, 12.0, 2.0, 3.0, 4.0]);
        let KrylovLayout::Shared(shared) = &layout else {
            unreachable!()
        };
        assert_eq!(shared.own_multipliers(), 2..5);
        assert_eq!(shared.local_range(1), 1..3);
    }
}
