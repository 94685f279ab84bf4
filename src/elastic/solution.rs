//! The result of one elastic solve.

use std::time::Instant;

use serde::Serialize;

use crate::fem::Material;
use crate::fem::stress::{CellFields, cell_fields};
use crate::linalg::BodySolverKind;
use crate::mesh::BodyMesh;
use crate::progress::Heartbeat;

/// Displacement, cell fields, reactions and solver statistics of one body.
#[derive(Debug, Clone)]
pub struct ElasticSolution {
    /// Nodal displacement, interleaved (`dim` per node).
    pub displacement: Vec<f64>,
    /// Empty on the ranks of a distributed run that write nothing ([`written_cell_fields`]).
    pub cell_fields: CellFields,
    /// Reaction force of each Dirichlet group: `sum (K u - f)` over its prescribed dofs, with
    /// `K`, `f` unconstrained (a node in two groups counts in both).
    pub reactions: Vec<(String, Vec<f64>)>,
    pub stats: SolveStats,
}

/// The strain and stress of `u` on every cell of `body`, where they are written: on one
/// process, and on rank 0 of a distributed run, which writes the output. The other ranks read
/// them nowhere and leave them empty: at 1M DOFs they would hold 290 MB each.
pub fn written_cell_fields(body: &BodyMesh, material: &Material, u: &[f64]) -> CellFields {
    if crate::parallel::is_root() {
        cell_fields(body, material, u)
    } else {
        CellFields::default()
    }
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
