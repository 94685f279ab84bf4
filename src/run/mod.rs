//! `internodes solve CASE`: from a case file to the result files, one step after another.
//!
//! The case is solved in memory ([`solve_case_on`]) and its result files written
//! ([`write_results`]) into the staging folder of a [`ResultFolder`], which moves them into place
//! when all are written. Progress messages go through the `log` crate (info, debug and trace:
//! the default log, `-v` and `-vv` of docs/output.md, "The log"), warnings at level warn: the
//! command line prints them on stderr, the Python module hands them to Python's `logging`.

mod gathered_rows;
mod partition;
mod solve;
mod write;

pub use solve::{CaseSolution, PairSurface, SolvedBody, SolvedContact, Timings, solve_case_on};
pub use write::write_results;

use std::path::{Path, PathBuf};
use std::time::Instant;

use thiserror::Error;

use crate::cancel::{Cancel, Cancelled};
use crate::case::{Case, CaseError};
use crate::contact::ContactError;
use crate::contact::CoupledSolver;
use crate::elastic::SolveError;
use crate::linalg::BodySolverKind;
use crate::mesh::{Mesh, MeshError, mesh_geo, read_msh, read_msh_bytes};
use crate::output::{
    CaseSummary, GENERATED_MESH, OutputError, ResultFolder, mark_failed_folder, peak_memory_mb,
};
use crate::parallel::{self, ParallelError};
use crate::progress::Heartbeat;

/// Command-line overrides of the case file, and the run's cancellation token.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    pub output: Option<PathBuf>,
    pub export_matrices: bool,
    pub quiet: bool,
    /// Stops the run (the command line cancels it on Ctrl-C): the solve at its next safe
    /// point, and the run before it moves its results into place. The run then fails like any
    /// other, its staging folder removed and the output folder marked.
    pub cancel: Cancel,
}

#[derive(Debug, Error)]
pub enum RunError {
    #[error(transparent)]
    Case(#[from] CaseError),
    #[error("case file {path}: {source}")]
    Solve { path: PathBuf, source: SolveError },
    #[error("case file {path}: contact: {source}")]
    Contact { path: PathBuf, source: ContactError },
    #[error(transparent)]
    Output(#[from] OutputError),
    #[error(transparent)]
    Parallel(ParallelError),
    /// Cancelled between the solve and the commit (a solve cancelled in its contact loop is a
    /// [`RunError::Contact`]).
    #[error(transparent)]
    Cancelled(#[from] Cancelled),
}

impl RunError {
    /// Whether the run stopped because its [`crate::cancel::Cancel`] token was cancelled.
    pub fn is_cancelled(&self) -> bool {
        matches!(
            self,
            RunError::Cancelled(_)
                | RunError::Contact {
                    source: ContactError::Cancelled(_),
                    ..
                }
        )
    }
}

/// What a run wrote.
pub struct RunReport {
    pub output_dir: PathBuf,
    pub summary: CaseSummary,
}

/// Solves every body of a case and writes `solution.h5`, `solution.xdmf`, `summary.json`,
/// `force_displacement.csv` and `.png` (contact runs), and `matrices/` when asked, into the
/// output folder.
///
/// The folder then holds this run's complete results and nothing else of ours; a run that
/// fails leaves no result in it, only [`FAILURE_MARK`](crate::output::FAILURE_MARK) with the
/// error (and the mesh gmsh made, if it got that far). See [`ResultFolder`].
pub fn solve_case(case_path: &Path, options: &RunOptions) -> Result<RunReport, RunError> {
    let command = format!("internodes solve {}", case_path.display());
    // Where the output folder was set, for an error that refuses it.
    let origin = match options.output {
        Some(_) => "--output".to_string(),
        None => format!("the `output` key of {}", case_path.display()),
    };
    let case = match Case::load(case_path) {
        Ok(case) => case,
        Err(e) => {
            let folder = options
                .output
                .clone()
                .or_else(|| Case::output_folder_of(case_path));
            if let Some(dir) = folder {
                mark_failed_folder(&dir, &origin, case_path, &command, &e);
            }
            return Err(e.into());
        }
    };
    solve_loaded_case(case, options, &origin, &command).map(|run| run.report)
}

/// A run's report with the mesh it solved on and the solution it wrote, for callers that
/// measure them (the refinement study, `internodes study`).
pub struct SolvedRun {
    pub report: RunReport,
    pub mesh: Mesh,
    pub solution: CaseSolution,
}

/// [`solve_case`] of a case already loaded (and perhaps changed, as the refinement study sets a
/// gmsh parameter): `origin` says where the output folder was set and `command` what ran, for
/// the messages of a failed run.
pub fn solve_loaded_case(
    case: Case,
    options: &RunOptions,
    origin: &str,
    command: &str,
) -> Result<SolvedRun, RunError> {
    let Some(output) = options.output.as_ref().or(case.output.as_ref()) else {
        return Err(CaseError::Invalid {
            path: case.path.clone(),
            context: "output".to_string(),
            message: "no output folder: give the `output` key in the case file (e.g. output = \
                      \"out\") or the --output flag of `internodes solve`"
                .to_string(),
        }
        .into());
    };
    if parallel::distributed() {
        check_distributable(&case)?;
        if !parallel::is_root() {
            let output = output.clone();
            return solve_beside_root(case, &output);
        }
    }
    let results = ResultFolder::create(
        output,
        origin,
        &[&case.path, &case.mesh],
        case.generates_mesh(),
    )?;
    let outcome = solve_into(case, options, &results).and_then(|run| {
        // Results written after a Ctrl-C are not the ones asked for any more.
        options.cancel.check()?;
        results.commit()?;
        Ok(run)
    });
    match outcome {
        Ok((summary, mesh, solution)) => Ok(SolvedRun {
            report: RunReport {
                output_dir: results.dir().to_owned(),
                summary,
            },
            mesh,
            solution,
        }),
        Err(e) => {
            results.fail(command, &e);
            Err(e)
        }
    }
}

/// What a distributed run cannot do: factor a body (`body = "cholesky"`; `auto` is CG + AMG
/// there) or solve the coupled system by one sparse LU (`solver = "monolithic-lu"`).
fn check_distributable(case: &Case) -> Result<(), CaseError> {
    let ranks = parallel::ranks().size;
    let refuse = |context: &str, what: &str| CaseError::Invalid {
        path: case.path.clone(),
        context: context.to_string(),
        message: format!(
            "{what} runs on one process, and this run has {ranks} MPI ranks: a distributed run \
             solves each body by CG + AMG (body = \"cg-amg\" or \"auto\") and the coupled \
             system by GMRES (solver = \"auto\", \"krylov\" or \"schur\")"
        ),
    };
    if case.solver.body == BodySolverKind::Cholesky {
        return Err(refuse(
            "[solver] body",
            "the Cholesky factor (body = \"cholesky\")",
        ));
    }
    if case
        .contacts
        .iter()
        .any(|c| c.settings.solver == CoupledSolver::MonolithicLu)
    {
        return Err(refuse(
            "[contact] solver",
            "the sparse LU of solver = \"monolithic-lu\"",
        ));
    }
    Ok(())
}

/// A rank other than 0 of a distributed run: the same solve, in step with rank 0 (which reads
/// or meshes the mesh and sends this rank its part), writing nothing but sending rank 0 the
/// output's rows of the cells it writes.
fn solve_beside_root(mut case: Case, output: &Path) -> Result<SolvedRun, RunError> {
    let timings = Timings::start();
    case.solver.verbose = false;
    let mesh = partition::scatter_mesh(None, &case)?;
    let mut solution = solve_case_on(&case, &mesh, timings)?;
    solution.rank_peak_memory_mb = gather_peak_memory()?;
    let summary = solution.summary_with(&case, &mesh, &solution.timings);
    let fields = write::body_fields(&solution, &mesh);
    gathered_rows::send_output_rows(&fields).map_err(RunError::Parallel)?;
    Ok(SolvedRun {
        report: RunReport {
            output_dir: output.to_owned(),
            summary,
        },
        mesh,
        solution,
    })
}

/// Every rank's peak memory in MB, in rank order, in a distributed run (empty otherwise).
fn gather_peak_memory() -> Result<Vec<f64>, RunError> {
    if !parallel::distributed() {
        return Ok(Vec::new());
    }
    parallel::gather(peak_memory_mb().unwrap_or(f64::NAN)).map_err(RunError::Parallel)
}

fn read_case_mesh(case: &Case) -> Result<Mesh, CaseError> {
    read_msh(&case.mesh).map_err(|source| CaseError::Mesh {
        path: case.path.clone(),
        source,
    })
}

/// The run itself: every result file is written into the staging folder of `results`; returns
/// the summary, the mesh and the solution.
fn solve_into(
    mut case: Case,
    options: &RunOptions,
    results: &ResultFolder,
) -> Result<(CaseSummary, Mesh, CaseSolution), RunError> {
    let mut timings = Timings::start();
    case.export_matrices |= options.export_matrices;
    case.solver.cancel = options.cancel.clone();
    case.solver.verbose = !options.quiet;
    let verbose = case.solver.verbose;

    // 1. The mesh, generated by gmsh when the case names a .geo.
    let phase = Instant::now();
    let mesh = if case.generates_mesh() {
        log::info!("meshing {} with gmsh", case.mesh.display());
        let beat = Heartbeat::start(verbose, "  gmsh");
        let mesh = generate_mesh(&case, results)?;
        drop(beat);
        timings.record("gmsh", phase);
        mesh
    } else {
        let _beat = Heartbeat::start(verbose, "  reading the mesh");
        read_case_mesh(&case)?
    };
    let seconds = timings.record("read mesh", phase);
    log::info!(
        "read {} ({}D, {} bodies) in {seconds:.3} s",
        mesh.path.display(),
        mesh.dim,
        mesh.bodies.len(),
    );

    // 2. Every body solved: the two in contact together, the others alone. Rank 0 of a
    //    distributed run sends each rank the mesh with only the cells it assembles.
    let mesh = match parallel::distributed() {
        true => {
            let phase = Instant::now();
            let mesh = partition::scatter_mesh(Some(mesh), &case)?;
            timings.record("partition the mesh", phase);
            mesh
        }
        false => mesh,
    };
    let mut solution = solve_case_on(&case, &mesh, timings)?;
    solution.rank_peak_memory_mb = gather_peak_memory()?;

    // 3. The result files, into the staging folder (the other ranks of a distributed run send
    //    the rows of the cells rank 0 does not hold).
    let beat = Heartbeat::start(verbose, "  writing the results");
    let summary = write_results(&solution, &case, &mesh, results.staging())?;
    drop(beat);
    log::info!(
        "wrote {} (solution.xdmf, solution.h5, summary.json) in {:.3} s total",
        results.dir().display(),
        solution.timings.elapsed()
    );
    Ok((summary, mesh, solution))
}

/// Meshes the case's `.geo` with its `geo_parameters` into the staging folder, moves the mesh to
/// `<output>/mesh.msh` (kept if the run fails, for inspection) and reads it. The bytes are read
/// before the move, so a concurrent run into the same folder cannot swap the file in between.
fn generate_mesh(case: &Case, results: &ResultFolder) -> Result<Mesh, RunError> {
    let staged = results.staging().join(GENERATED_MESH);
    let parameters: Vec<(String, f64)> = case
        .geo_parameters
        .iter()
        .map(|(k, v)| (k.clone(), *v))
        .collect();
    mesh_geo(&case.mesh, &staged, &parameters).map_err(|message| CaseError::Gmsh {
        path: case.path.clone(),
        geo: case.mesh.clone(),
        message,
    })?;
    let mesh_error = |source| CaseError::Mesh {
        path: case.path.clone(),
        source,
    };
    let bytes = std::fs::read(&staged).map_err(|source| {
        mesh_error(MeshError::Io {
            path: staged.clone(),
            source,
        })
    })?;
    let msh = results.publish(GENERATED_MESH)?;
    Ok(read_msh_bytes(&msh, &bytes).map_err(mesh_error)?)
}
