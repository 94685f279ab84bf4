//! Sparse Cholesky factorization `P K P^T = L L^T` (faer, supernodal), with the symbolic
//! analysis (ordering and elimination structure) and the numeric factorization as separate
//! types, so that one analysis serves every matrix with the same pattern.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::perm::PermRef;
use faer::sparse::SparseColMat;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::{Conj, MatMut, Par, Side};
use serde::{Deserialize, Serialize};

use super::LinalgError;
use super::ordering::nested_dissection;
use crate::fem::SparsityPattern;

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

/// The symbolic phase: ordering and structure of `L` for one sparsity pattern.
pub struct CholeskySymbolic {
    inner: SymbolicCholesky<usize>,
}

impl CholeskySymbolic {
    pub fn new(pattern: &SparsityPattern, ordering: Ordering) -> Result<Self, LinalgError> {
        let params = CholeskySymbolicParams::default();
        let inner = match ordering {
            Ordering::Amd => factorize_symbolic_cholesky(
                pattern.symbolic(),
                Side::Lower,
                SymmetricOrdering::Amd,
                params,
            ),
            Ordering::NestedDissection => {
                let (forward, inverse) = nested_dissection(pattern)?;
                let n = forward.len();
                let perm = PermRef::new_checked(&forward, &inverse, n);
                factorize_symbolic_cholesky(
                    pattern.symbolic(),
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
        let par = Par::rayon(0);
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

    /// Overwrites the columns of `rhs` (n x k, column-major) with the solutions of `K x = rhs`.
    pub fn solve_in_place(&self, rhs: &mut [f64], num_rhs: usize) {
        let n = self.symbolic.inner.nrows();
        let par = Par::rayon(0);
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
