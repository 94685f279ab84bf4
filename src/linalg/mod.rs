//! Sparse linear algebra: fill-reducing orderings and the Cholesky factorization of a body's
//! stiffness, the iterative alternative (PETSc CG + AMG, cargo feature `petsc`), the choice
//! between them, restarted GMRES for the coupled contact system, a bound-constrained quadratic
//! program solver for the half-space model of the contact zone, plus the residual check every
//! solve reports.

mod body_rows;
mod body_solver;
pub mod bound_qp;
mod cholesky;
mod distribution;
pub mod gmres;
mod node_order;
mod ordering;
#[cfg(feature = "petsc")]
pub mod petsc;

pub use body_rows::BodyRows;
pub use body_solver::{
    AUTO_CG_AMG_MIN_DOFS_3D, BodySolver, BodySolverKind, CG_AMG_AVAILABLE, PendingCgAmg,
};
pub use cholesky::{Cholesky, CholeskySymbolic, Ordering};
pub use distribution::{
    BALANCED_INTERFACE_PER_RANK, Distribution, NodeGather, RankRows, node_owners, own_order,
    spread_parts,
};
pub(crate) use node_order::z_curve_keys;

use faer::sparse::SparseColMat;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum LinalgError {
    #[error("the matrix is not positive definite (pivot {pivot} of the permuted matrix)")]
    NotPositiveDefinite { pivot: usize },
    #[error("fill-reducing ordering failed: {0}")]
    Ordering(String),
    #[error("MPI: {0}")]
    Mpi(String),
    #[error("partitioning a body among the MPI ranks failed: {0}")]
    Partition(String),
    #[error("sparse factorization failed: {0}")]
    Faer(String),
    #[error(
        "out of memory: the Cholesky factor needs {bytes} bytes; use a coarser mesh or a larger machine"
    )]
    OutOfMemory { bytes: usize },
    #[error(
        "the body solver \"cg-amg\" needs PETSc, and this binary was built without it \
         (rebuild with `cargo build --release --features petsc`, or use body = \"cholesky\")"
    )]
    PetscUnavailable,
    #[error("inconsistent sizes: {0}")]
    Sizes(String),
    #[error("PETSc error {code} ({message}) in {step}")]
    Petsc {
        step: String,
        code: i32,
        message: String,
    },
    #[error(
        "CG + AMG did not converge: {reason} after {iterations} iterations \
         (relative residual {relative_residual:.2e})"
    )]
    NotConverged {
        reason: String,
        iterations: usize,
        relative_residual: f64,
    },
}

/// `y = A x` for a compressed-column matrix.
pub fn mat_vec(a: &SparseColMat<usize, f64>, x: &[f64]) -> Vec<f64> {
    let (symbolic, values) = a.parts();
    let mut y = vec![0.0; symbolic.nrows()];
    let col_ptr = symbolic.col_ptr();
    let row_idx = symbolic.row_idx();
    for (j, &xj) in x.iter().enumerate() {
        for p in col_ptr[j]..col_ptr[j + 1] {
            y[row_idx[p]] += values[p] * xj;
        }
    }
    y
}

/// `||A x - b|| / ||b||` (0 when `b = 0` and `x = 0`).
pub fn relative_residual(a: &SparseColMat<usize, f64>, x: &[f64], b: &[f64]) -> f64 {
    relative_difference(&mat_vec(a, x), b)
}

/// `||ax - b|| / ||b||` (`||ax||` when `b = 0`): a relative residual from the product `A x`.
pub fn relative_difference(ax: &[f64], b: &[f64]) -> f64 {
    let r: f64 = ax
        .iter()
        .zip(b)
        .map(|(p, q)| (p - q).powi(2))
        .sum::<f64>()
        .sqrt();
    let nb: f64 = b.iter().map(|v| v * v).sum::<f64>().sqrt();
    if nb > 0.0 { r / nb } else { r }
}
