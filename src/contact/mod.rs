//! Elastic bodies in contact, coupled by INTERNODES: one or several pairs, decided together.
//!
//! In each pair, body 1 (primary) carries the multiplier `lambda`, the contact traction on it;
//! body 2 (secondary) receives `-R21 lambda`. The parts of a solve, folders and files, in the
//! order of one solve; each folder's `mod.rs` lists its files in order, and each file imports
//! only files listed before it (`tests/architecture.rs` checks that the imports have no cycle):
//! - `geometry/`: the contact surfaces and the interpolation between them, with no method and
//!   no law: closest points on a P1 surface, a body's closed boundary, the rescaled Wendland C2
//!   interpolation, a candidate surface (nodes, facets, spacings, lumped interface mass), the
//!   geometric gap and the gap linearized at an iterate;
//! - `settings.rs` (every setting, its default and range) and `problem.rs` (the two bodies,
//!   their surfaces, which one is primary, which transfer);
//! - the contact law, `law/` (frictionless, tied, Coulomb): each active node's multipliers
//!   (column and row), the tangential state of a Coulomb node (stick, slip) and its update, and
//!   the loop's per-node state; the only place that tells the laws apart;
//! - `method.rs`: how the law is enforced, INTERNODES or the penalty method (a row's own term,
//!   and where the secondary receives the force); the only place that tells them apart;
//! - `coupled/`: the linear algebra of an iteration, for any number of bodies and pairs: the
//!   bodies' responses to unit tractions, the coupled system of an active set, the INTERNODES
//!   interface operators (built once over all candidates: the interpolation evaluated at each
//!   node's closest point on the other surface, the contact normal), the half-space
//!   approximation of the interface Schur complement, and the system's solvers (one
//!   preconditioned GMRES on the whole system, or the dense Schur complement) behind one call;
//! - what a solve returns: `certificate.rs` (the checks of an answer), `active_set.rs` (where
//!   the loop starts, and its primal-dual update: a solution carries the active set the next
//!   load step starts from, so it comes before the loop), `solution.rs`;
//! - `verify/`: the last iterate measured without the loop's operators (the residuals that
//!   decide the status, the accuracy report), a Hertz fit, and the fields and forces of the
//!   last iterate;
//! - `iteration/`: the active-set loop over every pair, and when it stops;
//! - `driver.rs`: [`solve_contact`], the solve a caller asks for: the load steps, and for a
//!   single pair a second solve with the other body as primary, or auto's transfer, when a
//!   choice made may be the wrong one.
//!
//! Method, signs and the reasons behind each rule: `docs/method.md`.

mod active_set;
mod certificate;
mod coupled;
mod driver;
mod geometry;
mod iteration;
pub mod law;
mod method;
mod problem;
mod settings;
mod solution;
mod verify;

pub use active_set::ActiveSet;
pub use certificate::{Certificate, CertificateCheck, CheckKind, ErrorCoverage};
pub use coupled::coupled_krylov::{KrylovError, KrylovFailure};
pub use coupled::system;
pub use driver::{ContactRun, StepFriction, StepRecord, solve_contact, solve_contact_steps};
pub use geometry::surface::{ContactSurface, SurfaceError};
pub use geometry::{projection, rbf};
pub use iteration::solve::ContactSolver;
pub use problem::{
    ContactProblem, ContactSide, OtherPrimary, PrimaryChoice, PrimaryReport, TransferReport,
};
pub use settings::{
    ContactSettings, CoupledSolver, DEFAULT_PENALTY, Formulation, Method, SettingsError, Transfer,
};
pub use solution::{
    ContactSolution, ContactStatus, ForcedDisplacement, FrictionFields, FrictionState, HertzFit,
    IterationRecord, LinearSolvers, PhaseSeconds, SurfaceFields,
};

use thiserror::Error;

use crate::elastic::{ProblemError, SolveError};

/// Why a contact solve could not be carried out (how the active-set loop ended is a
/// [`ContactStatus`], not an error).
#[derive(Debug, Error)]
pub enum ContactError {
    #[error("load factors: expected a non-empty list of finite numbers, got {0:?}")]
    LoadFactors(Vec<f64>),
    #[error("load path: {0}")]
    LoadPath(String),
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
    #[error(
        "body '{body}' is held along {component} by nothing but its contacts (its group \
         '{group}' is force-controlled along {component}), and the force pulls it off the \
         other body: nothing balances it. Check the force's sign, or hold the body along \
         {component} elsewhere"
    )]
    PulledAway {
        body: String,
        group: String,
        component: &'static str,
    },
    #[error(
        "body '{body}' is held by its contact alone (its supports leave it free to move), and \
         its loads pull it off the other body: nothing balances them. Check the loads' signs, \
         or support the body"
    )]
    FloatsAway { body: String },
    #[error(
        "body '{body}' is held by its contact alone along {free} of its rigid motions, and the \
         contact at this iteration's {active} active nodes does not hold it there \
         (frictionless contact cannot hold a sliding along a flat contact surface or the \
         rotation of a round body, nor can friction once every node slips: a tangential load \
         beyond what friction holds; nothing else does): support the body along them"
    )]
    NotHeld {
        body: String,
        free: usize,
        active: usize,
    },
    #[error(
        "bodies {bodies} are held only by their contacts (along a force-controlled component, \
         or the rigid motions their supports leave free): together they are held by nothing. \
         Hold one of them (a displacement)"
    )]
    NothingHolds { bodies: String },
    #[error("contact pairs: {0}")]
    PairSettings(String),
    #[error("{0}")]
    Linalg(String),
    #[error(
        "the coupled solve is inaccurate: relative residual {residual:.2e} > [solver] \
         residual_tolerance {tolerance:.0e}"
    )]
    Inaccurate { residual: f64, tolerance: f64 },
    #[error(transparent)]
    Krylov(#[from] coupled::coupled_krylov::KrylovError),
    /// The solve's [`crate::cancel::Cancel`] token was cancelled.
    #[error(transparent)]
    Cancelled(#[from] crate::cancel::Cancelled),
}

/// A body's assembly failing inside a contact solve: a problem error as it is, anything else
/// (a partition or an MPI call of a distributed run) as a linear-algebra failure.
impl From<SolveError> for ContactError {
    fn from(e: SolveError) -> Self {
        match e {
            SolveError::Problem(problem) => Self::Problem(problem),
            other => Self::Linalg(other.to_string()),
        }
    }
}
