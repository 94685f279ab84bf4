//! Linear elasticity on one body: the problem, how it is solved, and the solution.

mod problem;
mod solution;
mod solve;

pub use problem::{DirichletCondition, ElasticProblem, LoadCondition, ProblemError};
pub use solution::{ElasticSolution, SolveStats};
pub use solve::{AssembledBody, SolveError, SolverSettings, assemble, reactions, solve};
