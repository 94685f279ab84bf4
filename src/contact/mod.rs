//! Two elastic bodies in contact, coupled by INTERNODES.
//!
//! Body 1 (primary) carries the multiplier `lambda`, the contact traction on it; body 2
//! (secondary) receives `-R21 lambda`. The interface operators are built on the reference
//! geometry (small deformations): rescaled Wendland C2 interpolation [`rbf`] between the active
//! nodes, interface (surface) mass matrices and nodal gaps ([`system`]); the active set is
//! updated by the seed's Algorithm 3 ([`solve_contact`]). Method, signs and known traps:
//! `shared/notes/method.md`.

mod compliance;
mod coupled_solver;
mod hertz;
mod problem;
pub mod rbf;
mod solution;
mod solve;
mod surface;
pub mod system;

pub use coupled_solver::CoupledSolver;
pub use problem::{ContactProblem, ContactSettings, Formulation};
pub use solution::{ContactSolution, ContactStatus, HertzFit, IterationRecord, SurfaceFields};
pub use solve::{Candidates, ContactSolver, solve_contact};
pub use surface::{ContactSurface, SurfaceError};

use thiserror::Error;

use crate::elastic::ProblemError;

/// Why a contact solve could not be carried out (how the active-set loop ended is a
/// [`ContactStatus`], not an error).
#[derive(Debug, Error)]
pub enum ContactError {
    #[error(transparent)]
    Problem(#[from] ProblemError),
    #[error("interpolation between the contact surfaces: {0}")]
    Interpolation(#[from] rbf::RbfError),
    #[error(
        "{nodes} active primary node(s) lie outside the interpolation supports of the secondary \
         surface on the reference geometry, where the interface operators are built: the bodies \
         moved by more than a spacing relative to each other along the interface"
    )]
    UncoveredInterface { nodes: usize },
    #[error("the active primary facets have no area: the interface mass matrix is zero")]
    EmptyInterfaceMass,
    #[error("{0}")]
    Linalg(String),
    #[error("the coupled solve is inaccurate (relative residual {residual:.2e} > {tolerance:.0e})")]
    Inaccurate { residual: f64, tolerance: f64 },
}
