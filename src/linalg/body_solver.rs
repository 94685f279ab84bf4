//! The solver of one body's constrained system `K_c u = f_c`: sparse Cholesky, or (cargo
//! feature `petsc`) conjugate gradients preconditioned by smoothed-aggregation AMG.
//!
//! Both are set up once per matrix and then solve any number of right-hand sides: the
//! single-body solve needs one, the contact solve one per unit interface load.
//!
//! # Which one
//!
//! `[solver] body` in the case file ([`BodySolverKind`]): `"cholesky"`, `"cg-amg"` or
//! `"auto"` (the default). `auto` takes CG + AMG for a 3D body of at least
//! [`AUTO_CG_AMG_MIN_DOFS_3D`] dofs when the binary is built with PETSc, and Cholesky
//! otherwise; see that constant for the measurement. In 2D the Cholesky factor stays cheap
//! (nested dissection fill grows like `n log n`): on block_2d meshes Cholesky's factorization +
//! solve took 1.68 s against CG + AMG's 2.37 s at 219,916 dofs, and 8.84 s against 8.27 s at
//! 875,562 dofs (2026-11-26, fastest of 2 runs, same machine and load as below), so `auto`
//! keeps Cholesky in 2D.
//!
//! A contact solve resolves `auto` the same way on its larger body: its coupled Krylov solve
//! applies each body's solver once per iteration, as one CG iteration does (a V-cycle, or the
//! factor's two triangular solves), so the single-body crossover holds. Measured 2026-11-28 on
//! the hemisphere on block, one step, 8 active-set iterations (whole process, a machine loaded
//! by other work): 6.8 s against Cholesky's 5.9 s at 31k DOFs, 15.6 s and 0.62 GB against
//! 18.0 s and 1.27 GB at 99k.

use faer::sparse::SparseColMat;
use serde::{Deserialize, Serialize};

use super::{Cholesky, Distribution, LinalgError, RankRows};

#[cfg(feature = "petsc")]
use super::petsc::{CgAmg, CgAmgMatrix};

/// The body solver a case asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum BodySolverKind {
    /// Cholesky, or CG + AMG for large 3D bodies when built with PETSc.
    #[default]
    Auto,
    /// Sparse Cholesky (faer, supernodal).
    Cholesky,
    /// PETSc CG + GAMG (cargo feature `petsc`).
    CgAmg,
}

/// From this many dofs on, `auto` solves a 3D body by CG + AMG (when built with PETSc).
///
/// Measured 2026-11-26 on this project's 2-core machine (shared: load average about 5 during
/// the runs), block_3d meshes (`geo/block_3d.geo`, P1 tetrahedra, E = 1000, nu = 0.3, clamped
/// base, Hertzian pressure), rtol 1e-10; seconds of factorization + solve against CG + AMG
/// setup + solve (`internodes solve`'s own timings, fastest of 3 runs), and the wall time of
/// the whole process:
///
/// | dofs | Cholesky | CG + AMG (iterations) | wall, Cholesky / CG + AMG |
/// |---|---|---|---|
/// | 6,132 | 0.068 | 0.512 (21) | 0.18 / 0.65 |
/// | 10,542 | 0.256 | 0.550 (22) | 0.45 / 0.71 |
/// | 16,692 | 0.560 | 0.707 (23) | 0.80 / 0.94 |
/// | 22,182 | 0.868 | 0.979 (25) | 1.19 / 1.28 |
/// | 29,469 | 1.318 | 1.179 (24) | 1.70 / 1.71 |
/// | 47,757 | 3.091 | 1.949 (24) | 3.77 / 2.66 |
/// | 100,530 | 10.38 | 4.888 (25) | 11.98 / 7.00 |
///
/// The setup includes PETSc's (and MPI's) initialization, 0.3 to 0.45 s once per process,
/// which is most of CG + AMG's time below 10k dofs. The two cross near 30k dofs; above, the
/// factor's `n^2` work and `n^(4/3)` memory lose to CG + AMG's `O(n)`.
pub const AUTO_CG_AMG_MIN_DOFS_3D: usize = 30_000;

/// Whether this binary can solve by CG + AMG.
pub const CG_AMG_AVAILABLE: bool = cfg!(feature = "petsc");

impl BodySolverKind {
    /// The solver `auto` stands for on a single body of `num_dofs` dofs in dimension `dim`
    /// (other kinds stand for themselves).
    /// In a distributed run ([`crate::parallel`]) `auto` stands for CG + AMG whatever the size:
    /// a factor is not distributed.
    pub fn resolve(self, dim: usize, num_dofs: usize) -> Self {
        match self {
            Self::Auto if crate::parallel::distributed() => Self::CgAmg,
            Self::Auto if CG_AMG_AVAILABLE && dim == 3 && num_dofs >= AUTO_CG_AMG_MIN_DOFS_3D => {
                Self::CgAmg
            }
            Self::Auto => Self::Cholesky,
            kind => kind,
        }
    }

    /// The name used in case files and summaries.
    pub fn name(self) -> &'static str {
        match self {
            Self::Auto => "auto",
            Self::Cholesky => "cholesky",
            Self::CgAmg => "cg-amg",
        }
    }
}

/// A body's solver, set up for one matrix.
// The Cholesky variant is larger, but there is one value per body, never a collection.
#[allow(clippy::large_enum_variant)]
pub enum BodySolver {
    Cholesky(Cholesky),
    /// The factor of a matrix its body no longer holds, with the copy it was made from, which
    /// makes the products: what a contact solve falls back to from CG + AMG, whose solver held
    /// the only copy (`crate::contact::coupled::coupled_solver::petsc_solvers`).
    CholeskyOfCopy {
        factor: Cholesky,
        matrix: SparseColMat<usize, f64>,
    },
    #[cfg(feature = "petsc")]
    CgAmg(CgAmg),
}

impl BodySolver {
    /// CG + AMG on `matrix` (symmetric positive definite, `dim` dofs per node, interleaved,
    /// nodes at `coords`, `dim` values each), solving to the relative residual `rtol`. Without
    /// the feature `petsc`: [`LinalgError::PetscUnavailable`].
    pub fn cg_amg(
        matrix: &SparseColMat<usize, f64>,
        dim: usize,
        coords: &[f64],
        rtol: f64,
    ) -> Result<Self, LinalgError> {
        Self::cg_amg_matrix(matrix, dim, coords, rtol)?.set_up()
    }

    /// Each rank's number of the body's unknowns, in rank order (`[n]` on one process; a
    /// factor is never distributed).
    pub fn rank_dofs(&self) -> Vec<usize> {
        match self {
            Self::Cholesky(factor) | Self::CholeskyOfCopy { factor, .. } => vec![factor.size()],
            #[cfg(feature = "petsc")]
            Self::CgAmg(cg) => cg.rank_dofs(),
        }
    }

    /// [`Self::cg_amg`] in two steps: PETSc's copy of `matrix` now, its multigrid hierarchy
    /// by [`PendingCgAmg::set_up`], so that the caller can free `matrix` in between. The
    /// matrix is whole on this process; a distributed run's bodies go by
    /// [`Self::cg_amg_rows`].
    #[cfg_attr(not(feature = "petsc"), allow(unused_variables))]
    pub fn cg_amg_matrix(
        matrix: &SparseColMat<usize, f64>,
        dim: usize,
        coords: &[f64],
        rtol: f64,
    ) -> Result<PendingCgAmg, LinalgError> {
        #[cfg(feature = "petsc")]
        {
            CgAmgMatrix::new(matrix, dim, coords, rtol).map(|matrix| PendingCgAmg { matrix })
        }
        #[cfg(not(feature = "petsc"))]
        {
            Err(LinalgError::PetscUnavailable)
        }
    }

    /// CG + AMG on a body shared among the ranks of a distributed run, from this rank's `rows`
    /// (collective), its hierarchy by [`PendingCgAmg::set_up`].
    #[cfg_attr(not(feature = "petsc"), allow(unused_variables))]
    pub fn cg_amg_rows(rows: RankRows, rtol: f64) -> Result<PendingCgAmg, LinalgError> {
        #[cfg(feature = "petsc")]
        {
            CgAmgMatrix::distributed(rows, rtol).map(|matrix| PendingCgAmg { matrix })
        }
        #[cfg(not(feature = "petsc"))]
        {
            Err(LinalgError::PetscUnavailable)
        }
    }

    /// `y = K x` by the solver's own copy of the matrix: CG + AMG's (on several ranks, each
    /// computes its rows), or the copy a factor was made from. A factor alone keeps no matrix:
    /// [`LinalgError::Sizes`].
    #[cfg_attr(not(feature = "petsc"), allow(unused_variables))]
    pub fn multiply(&self, x: &[f64], y: &mut [f64]) -> Result<(), LinalgError> {
        match self {
            Self::Cholesky(_) => Err(LinalgError::Sizes(
                "a product by a Cholesky factor, which keeps no matrix".to_string(),
            )),
            Self::CholeskyOfCopy { matrix, .. } => {
                if x.len() != matrix.ncols() || y.len() != matrix.nrows() {
                    return Err(LinalgError::Sizes(format!(
                        "a product of a {} x {} matrix with {} values into {}",
                        matrix.nrows(),
                        matrix.ncols(),
                        x.len(),
                        y.len()
                    )));
                }
                y.copy_from_slice(&super::mat_vec(matrix, x));
                Ok(())
            }
            #[cfg(feature = "petsc")]
            Self::CgAmg(cg) => cg.multiply(x, y),
        }
    }

    /// How the body's unknowns are shared among the ranks of a distributed run (`None` on one
    /// process, whose vectors are whole in our numbering).
    pub fn distribution(&self) -> Option<&Distribution> {
        match self {
            Self::Cholesky(_) | Self::CholeskyOfCopy { .. } => None,
            #[cfg(feature = "petsc")]
            Self::CgAmg(cg) => cg.distribution(),
        }
    }

    /// [`Self::multiply`] on this rank's rows alone ([`Self::distribution`]: `x` and `y` in
    /// PETSc's order; collective); on one process, the whole vectors.
    pub fn multiply_rows(&self, x: &[f64], y: &mut [f64]) -> Result<(), LinalgError> {
        match self {
            #[cfg(feature = "petsc")]
            Self::CgAmg(cg) => cg.multiply_rows(x, y),
            _ => self.multiply(x, y),
        }
    }

    /// [`Self::precondition`] on this rank's rows alone, as [`Self::multiply_rows`].
    pub fn precondition_rows(&self, r: &[f64], x: &mut [f64]) -> Result<(), LinalgError> {
        match self {
            #[cfg(feature = "petsc")]
            Self::CgAmg(cg) => cg.precondition_rows(r, x),
            _ => self.precondition(r, x),
        }
    }

    /// A copy of the matrix the solver holds, where it is whole on this process: CG + AMG's
    /// (so that a process that freed its own can still factor it); `None` for a factor, which
    /// keeps no matrix, and on several ranks.
    pub fn matrix(&self) -> Option<SparseColMat<usize, f64>> {
        match self {
            Self::Cholesky(_) => None,
            Self::CholeskyOfCopy { matrix, .. } => Some(matrix.clone()),
            #[cfg(feature = "petsc")]
            Self::CgAmg(cg) => cg.matrix(),
        }
    }

    pub fn kind(&self) -> BodySolverKind {
        match self {
            Self::Cholesky(_) | Self::CholeskyOfCopy { .. } => BodySolverKind::Cholesky,
            #[cfg(feature = "petsc")]
            Self::CgAmg(_) => BodySolverKind::CgAmg,
        }
    }

    /// Overwrites the columns of `rhs` (n x `num_rhs`, column-major) with the solutions of
    /// `K x = rhs`; returns the most CG iterations a column took (0 for Cholesky).
    ///
    /// Cholesky solves the columns in parallel blocks ([`Cholesky::solve_in_place`]); CG one
    /// after the other (each CG solve holds PETSc exclusively), to the relative residual it was
    /// set up with.
    pub fn solve_in_place(&self, rhs: &mut [f64], num_rhs: usize) -> Result<usize, LinalgError> {
        self.solve_in_place_within(rhs, num_rhs, None)
    }

    /// [`Self::solve_in_place`], CG stopping at the relative residual `rtol` when given (a
    /// factor solves exactly whatever `rtol` says).
    #[cfg_attr(not(feature = "petsc"), allow(unused_variables))]
    pub fn solve_in_place_within(
        &self,
        rhs: &mut [f64],
        num_rhs: usize,
        rtol: Option<f64>,
    ) -> Result<usize, LinalgError> {
        match self {
            Self::Cholesky(factor) | Self::CholeskyOfCopy { factor, .. } => {
                factor.solve_in_place(rhs, num_rhs);
                Ok(0)
            }
            #[cfg(feature = "petsc")]
            Self::CgAmg(cg) => each_column(rhs, num_rhs, |column| match rtol {
                Some(rtol) => cg.solve_within(column, rtol),
                None => cg.solve(column),
            }),
        }
    }

    /// [`Self::solve_in_place`] on this rank's rows alone ([`Self::distribution`]: each
    /// column holds this rank's rows in PETSc's order; collective), so that no rank holds a
    /// whole vector; on one process, the whole vectors.
    pub fn solve_rows_in_place(
        &self,
        rhs: &mut [f64],
        num_rhs: usize,
    ) -> Result<usize, LinalgError> {
        match self {
            #[cfg(feature = "petsc")]
            Self::CgAmg(cg) => each_column(rhs, num_rhs, |column| cg.solve_rows(column)),
            _ => self.solve_in_place(rhs, num_rhs),
        }
    }

    /// `x = P^-1 r` for the body's preconditioner in a coupled Krylov solve: the factor's exact
    /// solve, or one AMG V-cycle. Called from several threads, V-cycles of different bodies
    /// run at the same time (the one PETSc call that does not wait for all others:
    /// `linalg::petsc`'s "PETSc in a Rust process"); those of one body take turns.
    pub fn precondition(&self, r: &[f64], x: &mut [f64]) -> Result<(), LinalgError> {
        match self {
            Self::Cholesky(factor) | Self::CholeskyOfCopy { factor, .. } => {
                x.copy_from_slice(r);
                factor.solve_in_place(x, 1);
                Ok(())
            }
            #[cfg(feature = "petsc")]
            Self::CgAmg(cg) => cg.precondition(r, x),
        }
    }
}

/// Overwrites each of the `num_rhs` columns of `rhs` (one after the other) with its CG
/// answer by `solve`, one column at a time (each CG solve holds PETSc exclusively); returns
/// the most iterations a column took.
#[cfg(feature = "petsc")]
fn each_column(
    rhs: &mut [f64],
    num_rhs: usize,
    solve: impl Fn(&[f64]) -> Result<(Vec<f64>, super::petsc::CgStats), LinalgError>,
) -> Result<usize, LinalgError> {
    if num_rhs == 0 || rhs.is_empty() {
        return Ok(0);
    }
    let mut most = 0;
    for column in rhs.chunks_mut(rhs.len() / num_rhs) {
        let (x, stats) = solve(column)?;
        column.copy_from_slice(&x);
        most = most.max(stats.iterations);
    }
    Ok(most)
}

/// A CG + AMG solver whose matrix PETSc holds, its multigrid hierarchy not yet built
/// ([`BodySolver::cg_amg_matrix`]).
pub struct PendingCgAmg {
    #[cfg(feature = "petsc")]
    matrix: CgAmgMatrix,
}

impl PendingCgAmg {
    /// Builds the hierarchy: the body's solver.
    pub fn set_up(self) -> Result<BodySolver, LinalgError> {
        #[cfg(feature = "petsc")]
        {
            self.matrix.set_up().map(BodySolver::CgAmg)
        }
        #[cfg(not(feature = "petsc"))]
        {
            Err(LinalgError::PetscUnavailable)
        }
    }
}
