//! The result of one elastic solve.

use std::time::Instant;

use serde::Serialize;

use crate::linalg::BodySolverKind;
use crate::progress::Heartbeat;

/// Displacement, reactions and solver statistics of one body. Its strain and stress are
/// computed from the displacement where they are read (`crate::fem::stress`): the output
/// writes them a chunk of cells at a time, so that no process holds them whole.
#[derive(Debug, Clone)]
pub struct ElasticSolution {
    /// Nodal displacement, interleaved (`dim` per node): every node's on one process; on a
    /// rank of a distributed run only at the nodes whose coordinates the body's mesh keeps
    /// (its own, its cells', the boundary's and the groups'), in their order, so that no rank
    /// holds a whole body's vector: `crate::mesh::NodeCoords::position` finds a node's
    /// values, and the output gathers the nodes' values from their owners.
    pub displacement: Vec<f64>,
    /// Reaction force of each Dirichlet group: `sum (K u - f)` over its prescribed dofs, with
    /// `K`, `f` unconstrained (a node in two groups counts in both).
    pub reactions: Vec<(String, Vec<f64>)>,
    pub stats: SolveStats,
}

/// Sizes, accuracy and timings of one solve, as written to the JSON summary.
#[derive(Debug, Clone, Default, Serialize)]
pub struct SolveStats {
    pub num_dofs: usize,
    pub num_prescribed_dofs: usize,
    pub stiffness_nnz: usize,
    /// Entries of the Cholesky factor (0 when solved by CG + AMG).
    pub factor_nnz: usize,
    /// The body solver that ran (absent where the body was not solved alone, as in contact
    /// runs).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub body_solver: Option<BodySolverKind>,
    /// CG iterations of the solve (CG + AMG only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cg_iterations: Option<usize>,
    /// Each MPI rank's number of the body's dofs, in rank order (`[num_dofs]` on one process;
    /// absent where the body was not solved).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub rank_dofs: Vec<usize>,
    /// `||K_c u - f_c|| / ||f_c||` of the constrained system.
    pub relative_residual: f64,
    /// Seconds per phase, in order.
    pub timings: Vec<(String, f64)>,
}

/// Runs `f`, records its duration under `name`, and when verbose reports it (in the `-v` log:
/// one line per body solve is enough by default) and its progress if it runs long.
pub(crate) fn timed<T>(
    stats: &mut SolveStats,
    verbose: bool,
    name: &str,
    f: impl FnOnce() -> T,
) -> T {
    let start = Instant::now();
    let beat = Heartbeat::start(verbose, format!("    {name}"));
    let value = f();
    drop(beat);
    let seconds = start.elapsed().as_secs_f64();
    if verbose {
        log::debug!("    {name:<28} {seconds:>8.3} s");
    }
    stats.timings.push((name.to_string(), seconds));
    value
}
