//! Two elastic bodies in contact, coupled by INTERNODES.
//!
//! Body 1 (primary) carries the multiplier `lambda`, the contact traction on it; body 2
//! (secondary) receives `-R21 lambda`. One solve, in the order of the files:
//! - `problem.rs`: the two bodies, their candidate surfaces (`surface.rs`) and the settings;
//! - `interface.rs`: the interface operators, built once over all candidates: rescaled Wendland
//!   C2 interpolation (`rbf.rs`) evaluated at each node's closest point on the other surface
//!   (`projection.rs`), the lumped interface mass, the contact normal and the gaps;
//! - `solve.rs`: the active-set loop (primal-dual active set), each iteration assembling the
//!   coupled system (`system.rs`) with the frictionless constraint linearized at the last
//!   iterate (`linearization.rs`) and solving it (`coupled_solver.rs`, `compliance.rs`);
//! - `checks.rs`: the active-set update of each iteration, and the checks of the answer,
//!   measured independently of the loop's operators: the residuals that decide the status and
//!   the accuracy report; `post.rs`: fields, forces, Hertz fit;
//! - `driver.rs`: [`solve_contact`], the solve a caller asks for: the load steps, and a second
//!   solve with the other body as primary, or auto's transfer, when a choice made may be the
//!   wrong one.
//!
//! Method, signs and the reasons behind each rule: `docs/method.md`.

mod boundary;
mod checks;
mod compliance;
mod coupled_solver;
mod driver;
mod hertz;
mod interface;
mod interface_krylov;
mod linearization;
mod post;
mod problem;
pub mod projection;
pub mod rbf;
mod solution;
mod solve;
mod surface;
pub mod system;

pub use checks::{Certificate, CertificateCheck, CheckKind};
pub use coupled_solver::CoupledSolver;
pub use driver::{ContactRun, StepRecord, solve_contact};
pub use interface_krylov::{KrylovError, KrylovFailure};
pub use problem::{
    ContactProblem, ContactSettings, ContactSide, Formulation, PrimaryChoice, PrimaryReport,
    SettingsError, Transfer, TransferReport,
};
pub use solution::{
    ContactSolution, ContactStatus, HertzFit, IterationRecord, LinearSolvers, PhaseSeconds,
    SurfaceFields,
};
pub use solve::{ActiveSet, ContactSolver};
pub use surface::{ContactSurface, SurfaceError};

use thiserror::Error;

use crate::elastic::ProblemError;

/// Why a contact solve could not be carried out (how the active-set loop ended is a
/// [`ContactStatus`], not an error).
#[derive(Debug, Error)]
pub enum ContactError {
    #[error("load factors: expected a non-empty list of finite numbers, got {0:?}")]
    LoadFactors(Vec<f64>),
    #[error("contact settings: {0}")]
    Settings(#[from] SettingsError),
    #[error(transparent)]
    Problem(#[from] ProblemError),
    #[error("interpolation between the contact surfaces: {0}")]
    Interpolation(#[from] rbf::RbfError),
    #[error("contact surface '{group}' of body '{body}' has no facets to project onto")]
    NoFacets { body: String, group: String },
    #[error(
        "node {tag} of body '{body}' (and {} more) is not covered by the interpolation from \
         body '{other}': its closest point on that surface lies outside every RBF support \
         (a surface whose spacing varies by more than the support radius between neighbours?)",
        .count - 1
    )]
    Uncovered {
        body: String,
        tag: u64,
        other: String,
        count: usize,
    },
    #[error("the active primary facets have no area: the interface mass matrix is zero")]
    EmptyInterfaceMass,
    #[error("{0}")]
    Linalg(String),
    #[error("the coupled solve is inaccurate (relative residual {residual:.2e} > {tolerance:.0e})")]
    Inaccurate { residual: f64, tolerance: f64 },
    #[error(transparent)]
    Krylov(#[from] interface_krylov::KrylovError),
}
