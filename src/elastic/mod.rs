//! Linear elasticity on one body: the problem, how it is solved, and the solution.

mod assemble;
mod error;
mod factors;
mod problem;
mod solution;
mod solve;

pub use assemble::{AssembledBody, RhsPart, RigidColumn, Stiffness, assemble};
pub use error::SolveError;
pub use factors::StepFactors;
pub(crate) use problem::constraints as prescribed_dofs;
pub use problem::{
    DirichletCondition, ElasticProblem, ForceCondition, LoadCondition, ProblemError,
};
pub use solution::{ElasticSolution, SolveStats};
pub use solve::{SolverSettings, reactions, rigid_stiffness, solve, unheld_components};
