//! What can go wrong solving one body.

use thiserror::Error;

use super::problem::ProblemError;
use crate::linalg::LinalgError;

#[derive(Debug, Error)]
pub enum SolveError {
    #[error(transparent)]
    Problem(#[from] ProblemError),
    #[error("body '{body}': {source}")]
    Linalg { body: String, source: LinalgError },
    #[error(
        "body '{body}': the linear solve is inaccurate (relative residual {residual:.2e} > [solver] \
         residual_tolerance {tolerance:.0e}); the mesh may be badly graded or the material nearly \
         incompressible"
    )]
    Inaccurate {
        body: String,
        residual: f64,
        tolerance: f64,
    },
    #[error(
        "body '{body}' is held along {component} by nothing but the force-controlled group \
         '{group}': alone, nothing balances that force; prescribe a displacement along \
         {component} somewhere, or put the body in contact"
    )]
    Unheld {
        body: String,
        group: String,
        component: &'static str,
    },
}
