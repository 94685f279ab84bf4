//! `internodes solve CASE`: from a case file to the result files, one step after another.
//!
//! The case is solved in memory ([`solve_case_on`]) and its result files written
//! ([`write_results`]) into the staging folder of a [`ResultFolder`], which moves them into place
//! when all are written. Progress messages go through the `log` crate (level info), warnings at
//! level warn: the command line prints them on stderr, the Python module hands them to Python's
//! `logging`.

mod solve;
mod write;

pub use solve::{CaseSolution, PairSurface, SolvedBody, SolvedContact, Timings, solve_case_on};
pub use write::write_results;

use std::path::{Path, PathBuf};
use std::time::Instant;

use thiserror::Error;

use crate::case::{Case, CaseError};
use crate::contact::ContactError;
use crate::elastic::SolveError;
use crate::mesh::{Mesh, MeshError, mesh_geo, read_msh, read_msh_bytes};
use crate::output::{CaseSummary, GENERATED_MESH, OutputError, ResultFolder, mark_failed_folder};

/// Command-line overrides of the case file.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    pub output: Option<PathBuf>,
    pub export_matrices: bool,
    pub quiet: bool,
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
}

impl RunError {
    /// Whether the run stopped because its [`crate::cancel::Cancel`] token was cancelled.
    pub fn is_cancelled(&self) -> bool {
        matches!(
            self,
            RunError::Contact {
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
    let results = ResultFolder::create(
        output,
        origin,
        &[&case.path, &case.mesh],
        case.generates_mesh(),
    )?;
    let outcome = solve_into(case, options, &results).and_then(|run| {
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

/// The run itself: every result file is written into the staging folder of `results`; returns
/// the summary, the mesh and the solution.
fn solve_into(
    mut case: Case,
    options: &RunOptions,
    results: &ResultFolder,
) -> Result<(CaseSummary, Mesh, CaseSolution), RunError> {
    let mut timings = Timings::start();
    case.export_matrices |= options.export_matrices;
    // The live progress line of long interface solves, on a terminal.
    case.solver.verbose = !options.quiet;

    // 1. The mesh, generated by gmsh when the case names a .geo.
    let phase = Instant::now();
    let mesh = if case.generates_mesh() {
        log::info!("meshing {} with gmsh", case.mesh.display());
        let mesh = generate_mesh(&case, results)?;
        timings.record("gmsh", phase);
        mesh
    } else {
        read_msh(&case.mesh).map_err(|source| CaseError::Mesh {
            path: case.path.clone(),
            source,
        })?
    };
    let seconds = timings.record("read mesh", phase);
    log::info!(
        "read {} ({}D, {} bodies) in {seconds:.3} s",
        mesh.path.display(),
        mesh.dim,
        mesh.bodies.len(),
    );

    // 2. Every body solved: the two in contact together, the others alone.
    let solution = solve_case_on(&case, &mesh, timings)?;

    // 3. The result files, into the staging folder.
    let summary = write_results(&solution, &case, &mesh, results.staging())?;
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
