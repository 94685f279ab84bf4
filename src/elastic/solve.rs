//! One body, `K u = f`, solved by sparse Cholesky.

use std::time::Instant;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::{ElasticProblem, ElasticSolution, ProblemError, SolveStats};
use crate::fem::assembly::{assemble_stiffness, stiffness_pattern};
use crate::fem::loads::{add_body_force, add_surface_load};
use crate::fem::stress::cell_fields;
use crate::fem::{Constraints, SparsityPattern};
use crate::linalg::{Cholesky, CholeskySymbolic, LinalgError, Ordering, relative_residual};
use faer::sparse::SparseColMat;

/// How to solve; every field has a documented default.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SolverSettings {
    /// Fill-reducing ordering of the Cholesky factorization (default: nested dissection).
    pub ordering: Ordering,
    /// A solve whose relative residual exceeds this is reported as failed (default 1e-8).
    pub residual_tolerance: f64,
    /// Print each phase and its time on stderr (default: true; the CLI's `--quiet` clears it).
    #[serde(skip)]
    pub verbose: bool,
}

impl Default for SolverSettings {
    fn default() -> Self {
        Self {
            ordering: Ordering::default(),
            residual_tolerance: 1e-8,
            verbose: true,
        }
    }
}

#[derive(Debug, Error)]
pub enum SolveError {
    #[error(transparent)]
    Problem(#[from] ProblemError),
    #[error("body '{body}': {source}")]
    Linalg { body: String, source: LinalgError },
    #[error(
        "body '{body}': the linear solve is inaccurate (relative residual {residual:.2e} > {tolerance:.0e}); \
         the mesh may be badly graded or the material nearly incompressible"
    )]
    Inaccurate {
        body: String,
        residual: f64,
        tolerance: f64,
    },
}

/// The prescribed dofs and values of a problem; conflicting values on shared nodes are errors.
pub(crate) fn constraints(problem: &ElasticProblem) -> Result<Constraints, ProblemError> {
    let body = problem.body;
    let dim = body.dim;
    let mut constraints = Constraints::new(body.num_dofs());
    for condition in &problem.dirichlet {
        let nodes = body
            .group_nodes(&condition.group)
            .expect("groups are checked first");
        for node in nodes {
            for (component, value) in condition.components.iter().enumerate().take(dim) {
                if let Some(value) = *value {
                    constraints
                        .prescribe(dim * node + component, value)
                        .map_err(|first| ProblemError::ConflictingDirichlet {
                            body: body.name.clone(),
                            group: condition.group.clone(),
                            node_tag: body.node_tags[node],
                            component,
                            first,
                            second: value,
                        })?;
                }
            }
        }
    }
    Ok(constraints)
}

/// Runs `f`, records its duration under `name`, and reports it when verbose.
pub(crate) fn timed<T>(
    stats: &mut SolveStats,
    verbose: bool,
    name: &str,
    f: impl FnOnce() -> T,
) -> T {
    let start = Instant::now();
    let value = f();
    let seconds = start.elapsed().as_secs_f64();
    if verbose {
        eprintln!("    {name:<28} {seconds:>8.3} s");
    }
    stats.timings.push((name.to_string(), seconds));
    value
}

/// A body's assembled system: `K` and `f` as assembled, and the Dirichlet-constrained
/// `K_c`, `f_c` on the same pattern.
pub struct AssembledBody {
    pub pattern: SparsityPattern,
    pub k: SparseColMat<usize, f64>,
    pub f: Vec<f64>,
    pub constraints: Constraints,
    pub k_c: SparseColMat<usize, f64>,
    pub f_c: Vec<f64>,
}

/// Assembles `K`, `f` and applies the Dirichlet conditions, timing each phase into `stats`.
pub fn assemble(
    problem: &ElasticProblem,
    stats: &mut SolveStats,
    verbose: bool,
) -> Result<AssembledBody, ProblemError> {
    let body = problem.body;
    stats.num_dofs = body.num_dofs();

    // 1. Sparsity pattern and stiffness K (unconstrained).
    let pattern = timed(stats, verbose, "sparsity pattern", || {
        stiffness_pattern(body)
    });
    let k = timed(stats, verbose, "assemble stiffness", || {
        assemble_stiffness(body, &problem.material, &pattern)
    });
    stats.stiffness_nnz = pattern.nnz();

    // 2. Load vector f: surface loads and body force.
    let f = timed(stats, verbose, "assemble loads", || {
        let mut f = vec![0.0; body.num_dofs()];
        for load in &problem.loads {
            let group = body
                .boundary_group(&load.group)
                .expect("groups are checked first");
            add_surface_load(body, group, &load.load, &mut f);
        }
        if let Some(b) = &problem.body_force {
            add_body_force(body, b, &mut f);
        }
        f
    });

    // 3. Dirichlet conditions, eliminated symmetrically on the same pattern.
    let constraints = constraints(problem)?;
    stats.num_prescribed_dofs = constraints.num_fixed();
    let (k_c, f_c) = timed(stats, verbose, "apply Dirichlet conditions", || {
        constraints.apply(&k, &f)
    });
    Ok(AssembledBody {
        pattern,
        k,
        f,
        constraints,
        k_c,
        f_c,
    })
}

/// Reaction of each Dirichlet group: `sum (K u - s f - f_other)` over its prescribed dofs, with
/// `s` the load factor and `f_other` forces not in `f` (contact forces; empty for a single body).
pub fn reactions(
    problem: &ElasticProblem,
    system: &AssembledBody,
    u: &[f64],
    load_factor: f64,
    f_other: &[f64],
) -> Vec<(String, Vec<f64>)> {
    let body = problem.body;
    let dim = body.dim;
    let r = crate::linalg::mat_vec(&system.k, u);
    problem
        .dirichlet
        .iter()
        .map(|condition| {
            let nodes = body
                .group_nodes(&condition.group)
                .expect("groups are checked first");
            let mut total = vec![0.0; dim];
            for node in nodes {
                for c in (0..dim).filter(|&c| condition.components[c].is_some()) {
                    let d = dim * node + c;
                    total[c] +=
                        r[d] - load_factor * system.f[d] - f_other.get(d).copied().unwrap_or(0.0);
                }
            }
            (condition.group.clone(), total)
        })
        .collect()
}

/// Solves the elastic problem of one body.
pub fn solve(
    problem: &ElasticProblem,
    settings: &SolverSettings,
) -> Result<ElasticSolution, SolveError> {
    let body = problem.body;
    let verbose = settings.verbose;
    let linalg = |source| SolveError::Linalg {
        body: body.name.clone(),
        source,
    };
    let mut stats = SolveStats::default();
    let system = assemble(problem, &mut stats, verbose)?;
    let (pattern, k_c, f_c) = (&system.pattern, &system.k_c, &system.f_c);

    // 4. Cholesky: symbolic (ordering) then numeric.
    let symbolic = timed(&mut stats, verbose, "ordering + symbolic", || {
        CholeskySymbolic::new(pattern, settings.ordering)
    })
    .map_err(linalg)?;
    stats.factor_nnz = symbolic.factor_nnz();
    let factor = timed(&mut stats, verbose, "numeric factorization", || {
        Cholesky::factorize(symbolic, k_c)
    })
    .map_err(linalg)?;

    // 5. Solve and check the residual of the constrained system.
    let mut u = f_c.clone();
    timed(&mut stats, verbose, "triangular solves", || {
        factor.solve_in_place(&mut u, 1)
    });
    stats.relative_residual = relative_residual(k_c, &u, f_c);
    if stats.relative_residual.is_nan() || stats.relative_residual > settings.residual_tolerance {
        return Err(SolveError::Inaccurate {
            body: body.name.clone(),
            residual: stats.relative_residual,
            tolerance: settings.residual_tolerance,
        });
    }

    // 6. Reactions and cell fields.
    let reactions = reactions(problem, &system, &u, 1.0, &[]);
    let cell_fields = timed(&mut stats, verbose, "strain and stress", || {
        cell_fields(body, &problem.material, &u)
    });
    Ok(ElasticSolution {
        displacement: u,
        cell_fields,
        reactions,
        stats,
    })
}
