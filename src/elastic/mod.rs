//! Linear elasticity on one body: the problem, how it is solved, and the solution.

mod problem;
mod solution;
mod solve;

pub use problem::{
    DirichletCondition, ElasticProblem, ForceCondition, LoadCondition, ProblemError,
};
pub use solution::{ElasticSolution, SolveStats};
pub use solve::{
    AssembledBody, RigidColumn, SolveError, SolverSettings, assemble, reactions, rigid_stiffness,
    solve, unheld_components,
};
