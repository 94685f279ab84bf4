//! Sparse Cholesky factorization `P K P^T = L L^T` (faer, supernodal), with the symbolic
//! analysis (ordering and elimination structure) and the numeric factorization as separate
//! types, so that one analysis serves every matrix with the same pattern.
//!
//! # Threads
//!
//! Results do not depend on the number of threads, bit for bit, and both cores are used where
//! it pays. faer's `Par::rayon(t)` cuts its dense kernels into `t` parts, so with `t` the pool
//! size (`Par::rayon(0)`) results depended on it: the dense matrix-vector product of a
//! one-column solve sums `t` partial products, and 1 and 2 threads gave displacements
//! differing by up to 9e-18 (of 1e-2) and contact pressures by 8e-13 (of 63) on 29k dofs.
//! Hence:
//! - **Factorization**: faer's parallel kernels, cut into a fixed [`FACTOR_PARTS`] = 2 parts
//!   whatever the number of threads that run them. In faer 0.24 the parts, hence the
//!   arithmetic, are fixed by that number and threads only pick them up; `tests/threads.rs`
//!   checks the outcome for 1, 2 and 3 threads.
//! - **Solves**: faer sequential (`Par::Seq`); many right-hand sides are cut into blocks of at
//!   most `RHS_BLOCK` columns, a partition fixed by their number, solved in parallel.
//!
//! Measured (`benches/threads.rs` and a faer-`Par` variant of it; block_3d and
//! hemisphere_on_block meshes; fastest of 3 to 10 runs on the shared 2-core machine, taken
//! while it was otherwise idle):
//!
//! | | 1 thread | 2 threads |
//! |---|---|---|
//! | ordering + factorization, 29,469 dofs: sequential / 2 parts | 0.727 / 0.770 s | 0.705 / **0.635 s** |
//! | ordering + factorization, 100,530 dofs: sequential / 2 parts | 7.48 / 7.92 s | 7.92 / **5.34 s** |
//! | 256 right-hand sides, 19,707 dofs, blocks of 64 | 0.350 s | **0.186 s** |
//! | 256 right-hand sides, 100,530 dofs, blocks of 64 | 3.41 s | **2.00 s** |
//! | 1 right-hand side, 100,530 dofs: sequential / `Par::rayon(2)` | 0.16 to 0.18 s | 0.15 to 0.19 s |
//!
//! The factorization gains 1.1x to 1.4x from its second part and loses 6% on one thread; a
//! one-column solve gains nothing measurable (those runs were on a loaded machine).
//! Many-column solves gain 1.7x to 2x. The block width: 256 columns on 19,707 dofs took, on one
//! thread, 0.87 s in blocks of 16, 0.49 to 0.61 s in blocks of 32, 0.38 to 0.53 s in blocks of
//! 64 and 0.49 to 0.65 s in one block (several runs). Blocks of 64 columns cost no more than one
//! wide block; blocks of 16 cost about 1.7x.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMat, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::LinalgError;
use super::ordering::nested_dissection;
use crate::fem::NodeGraph;

/// Fill-reducing ordering of the unknowns.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Ordering {
    /// METIS nested dissection on the node graph (the default: faster and leaner in 3D).
    #[default]
    NestedDissection,
    /// faer's approximate minimum degree.
    Amd,
}

/// How many parts faer cuts the dense kernels of the factorization into, whatever the number
/// of threads that then run them: the factor is the same for any thread count (see the module
/// doc). Two matches this project's machine; more parts would cost more on fewer cores.
const FACTOR_PARTS: usize = 2;

/// The most right-hand sides in one block of a multi-column solve: wide enough to cost no more
/// per column than one block of all columns (see the module doc).
const RHS_BLOCK: usize = 64;

/// The symbolic phase: ordering and structure of `L` for one sparsity pattern.
pub struct CholeskySymbolic {
    inner: SymbolicCholesky<usize>,
}

impl CholeskySymbolic {
    /// The analysis of the matrices with the compressed-column pattern `symbolic`, whose node
    /// graph is `graph` (nested dissection orders the graph).
    pub fn new(
        graph: &NodeGraph,
        symbolic: SymbolicSparseColMatRef<'_, usize>,
        ordering: Ordering,
    ) -> Result<Self, LinalgError> {
        let params = CholeskySymbolicParams::default();
        let inner = match ordering {
            Ordering::Amd => {
                factorize_symbolic_cholesky(symbolic, Side::Lower, SymmetricOrdering::Amd, params)
            }
            Ordering::NestedDissection => {
                let (forward, inverse) = nested_dissection(graph)?;
                let n = forward.len();
                let perm = PermRef::new_checked(&forward, &inverse, n);
                factorize_symbolic_cholesky(
                    symbolic,
                    Side::Lower,
                    SymmetricOrdering::Custom(perm),
                    params,
                )
            }
        }
        .map_err(|e| LinalgError::Faer(format!("{e:?}")))?;
        Ok(Self { inner })
    }

    /// Number of stored entries of `L`.
    pub fn factor_nnz(&self) -> usize {
        self.inner.len_val()
    }
}

/// The numeric phase: `L` for one matrix.
pub struct Cholesky {
    symbolic: CholeskySymbolic,
    values: Vec<f64>,
}

impl Cholesky {
    /// Factors the symmetric positive definite `matrix` (its lower triangle is read). Fails
    /// with [`LinalgError::NotPositiveDefinite`] when a pivot is not positive.
    pub fn factorize(
        symbolic: CholeskySymbolic,
        matrix: &SparseColMat<usize, f64>,
    ) -> Result<Self, LinalgError> {
        let par = Par::rayon(FACTOR_PARTS);
        let len = symbolic.inner.len_val();
        let mut values = Vec::new();
        values
            .try_reserve_exact(len)
            .map_err(|_| LinalgError::OutOfMemory { bytes: 8 * len })?;
        values.resize(len, 0.0);
        let scratch = symbolic
            .inner
            .factorize_numeric_llt_scratch::<f64>(par, Default::default());
        let mut mem = MemBuffer::try_new(scratch).map_err(|_| LinalgError::OutOfMemory {
            bytes: scratch.size_bytes(),
        })?;
        symbolic
            .inner
            .factorize_numeric_llt(
                &mut values,
                matrix.as_ref(),
                Side::Lower,
                LltRegularization::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| match e {
                faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index } => {
                    LinalgError::NotPositiveDefinite { pivot: index }
                }
            })?;
        Ok(Self { symbolic, values })
    }

    pub fn symbolic(&self) -> &CholeskySymbolic {
        &self.symbolic
    }

    /// The matrix's size.
    pub fn size(&self) -> usize {
        self.symbolic.inner.nrows()
    }

    /// Overwrites the columns of `rhs` (n x k, column-major) with the solutions of `K x = rhs`.
    ///
    /// The columns are cut into the fewest blocks of at most `RHS_BLOCK` columns, of equal
    /// width (the last one narrower), solved in parallel, each sequentially. The partition
    /// depends on `num_rhs` only, so every column gets the same arithmetic for any number of
    /// threads.
    pub fn solve_in_place(&self, rhs: &mut [f64], num_rhs: usize) {
        let n = self.symbolic.inner.nrows();
        debug_assert_eq!(rhs.len(), n * num_rhs);
        if n == 0 || num_rhs == 0 {
            return;
        }
        let width = num_rhs.div_ceil(num_rhs.div_ceil(RHS_BLOCK));
        rhs.par_chunks_mut(n * width)
            .for_each(|block| self.solve_block(block, block.len() / n));
    }

    /// One block of right-hand sides, solved sequentially.
    fn solve_block(&self, rhs: &mut [f64], num_rhs: usize) {
        let n = self.symbolic.inner.nrows();
        let par = Par::Seq;
        let llt = LltRef::new(&self.symbolic.inner, &self.values);
        let mut mem = MemBuffer::new(
            self.symbolic
                .inner
                .solve_in_place_scratch::<f64>(num_rhs, par),
        );
        llt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(rhs, n, num_rhs),
            par,
            MemStack::new(&mut mem),
        );
    }
}
