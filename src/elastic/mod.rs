//! Linear elasticity on one body: the problem, how it is solved, and the solution.

mod assemble;
mod problem;
mod solution;
mod solve;

pub use assemble::{AssembledBody, RigidColumn, Stiffness, assemble};
pub use problem::{
    DirichletCondition, ElasticProblem, ForceCondition, LoadCondition, ProblemError,
};
pub use solution::{ElasticSolution, SolveStats};
pub use solve::{SolveError, SolverSettings, reactions, rigid_stiffness, solve, unheld_components};
