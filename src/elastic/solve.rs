//! One body, `K u = f`, solved by sparse Cholesky or by CG + AMG (`crate::linalg::BodySolver`).

use serde::{Deserialize, Serialize};

use super::StepFactors;
use super::assemble::{AssembledBody, assemble};
use super::error::SolveError;
use super::problem::ElasticProblem;
use super::solution::{ElasticSolution, SolveStats, timed};
use crate::cancel::Cancel;
use crate::fem::LoadVector;
use crate::linalg::{
    BodyRows, BodySolver, BodySolverKind, Cholesky, CholeskySymbolic, LinalgError, Ordering,
    relative_residual,
};

/// How to solve; every field has a documented default.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SolverSettings {
    /// The body solver: `"auto"` (default), `"cholesky"` or `"cg-amg"` (PETSc; see
    /// `crate::linalg::BodySolverKind` for what `auto` picks).
    pub body: BodySolverKind,
    /// CG + AMG stops at this relative residual `||f_c - K_c u|| / ||f_c||` (default 1e-10).
    ///
    /// Why 1e-10: two orders below `residual_tolerance`, so that a converged CG passes that
    /// check with margin (the case file rejects an `rtol` above it with `body = "cg-amg"`, and
    /// `auto` then keeps Cholesky); the displacement then differs from Cholesky's by about 1e-12 relative, far
    /// below the 4 to 6 digits a user reads. Measured on the 100,530-dof block_3d mesh
    /// (2026-11-26; relative L2 difference to Cholesky): rtol 1e-8: 20 iterations, 2.4e-10,
    /// true residual 7.1e-9 (too close to 1e-8); 1e-10: 25 iterations, 1.4e-12; 1e-12: 29
    /// iterations, 2.3e-14. Each factor of 100 costs about 4 to 5 iterations, 20% of the
    /// solve and under 10% of setup + solve.
    pub rtol: f64,
    /// Fill-reducing ordering of the Cholesky factorization (default: nested dissection).
    pub ordering: Ordering,
    /// A solve whose relative residual exceeds this is reported as failed (default 1e-8).
    pub residual_tolerance: f64,
    /// Report the phases, their times and the progress of long ones as `log` messages, at the
    /// levels of docs/output.md, "The log" (default: true; the CLI's `--quiet` clears it).
    #[serde(skip)]
    pub verbose: bool,
    /// Stops a contact solve at its next load step, active-set iteration or coupled GMRES
    /// iteration once cancelled, with `ContactError::Cancelled` (default: a token nobody
    /// cancels; the Python module sets it on Ctrl-C).
    #[serde(skip)]
    pub cancel: Cancel,
    /// Keep every load step's answer, not only the last one's
    /// (`crate::contact::ContactRun::earlier_solutions`): each step's fields then cost the
    /// memory of the last step's (default: false; the command line writes the last step's
    /// fields only, the Python module keeps every step's).
    #[serde(skip)]
    pub keep_step_fields: bool,
}

impl SolverSettings {
    /// The solver of a single body of `num_dofs` dofs in dimension `dim`: `body`, with `auto`
    /// resolved by [`BodySolverKind::resolve`], except that `auto` keeps Cholesky when `rtol`
    /// is above `residual_tolerance` (CG stopped there would fail the residual check).
    pub fn body_solver(&self, dim: usize, num_dofs: usize) -> BodySolverKind {
        if self.body == BodySolverKind::Auto && self.rtol > self.residual_tolerance {
            BodySolverKind::Cholesky
        } else {
            self.body.resolve(dim, num_dofs)
        }
    }
}

impl Default for SolverSettings {
    fn default() -> Self {
        Self {
            body: BodySolverKind::default(),
            rtol: 1e-10,
            ordering: Ordering::default(),
            residual_tolerance: 1e-8,
            verbose: true,
            cancel: Cancel::default(),
            keep_step_fields: false,
        }
    }
}

/// Reaction of each Dirichlet and force-controlled group: `sum (K u - f_s - f_other)` over its
/// prescribed and force-controlled dofs, with `f_s` the loads at a step of `factors`
/// ([`AssembledBody::load`]) and `f_other` forces not in `f` (contact forces; empty for a
/// single body). A group named by both kinds of condition has one entry. `u` is laid out like
/// the body's kept coordinates (`crate::mesh::NodeCoords`: whole on one process, on a rank of
/// a distributed run the nodes it reads), which hold every node a prescribed row reaches (the
/// cells around the groups are every rank's).
pub fn reactions(
    problem: &ElasticProblem,
    system: &AssembledBody,
    u: &[f64],
    factors: &StepFactors,
    f_other: Option<&LoadVector>,
) -> Vec<(String, Vec<f64>)> {
    let body = problem.body;
    let dim = body.dim;
    let u_at = |dof: usize| {
        let at = (body.coords.position(dof / dim))
            .expect("a prescribed row reaches the nodes of the cells around its group, kept");
        u[dim * at + dof % dim]
    };
    // `(K u)_d` at a prescribed or force-controlled dof `d` (its row of `K`); no other is read.
    let k_u = |dof: usize| match (system.prescribed_rows).binary_search_by_key(&dof, |(d, _)| *d) {
        Ok(at) => (system.prescribed_rows[at].1.iter())
            .map(|&(j, value)| value * u_at(j))
            .sum(),
        Err(_) => 0.0,
    };
    let mut groups: Vec<(&String, [bool; 3])> = Vec::new();
    let conditions = (problem.dirichlet.iter().map(|d| (&d.group, d.components)))
        .chain(problem.forces.iter().map(|f| (&f.group, f.components)));
    for (group, components) in conditions {
        let held = components.map(|c| c.is_some());
        match groups.iter_mut().find(|(g, _)| *g == group) {
            Some((_, mask)) => (0..3).for_each(|c| mask[c] |= held[c]),
            None => groups.push((group, held)),
        }
    }
    groups
        .into_iter()
        .map(|(group, mask)| {
            let nodes = body.group_nodes(group).expect("groups are checked first");
            let mut total = vec![0.0; dim];
            for node in nodes {
                for c in (0..dim).filter(|&c| mask[c]) {
                    let d = dim * node + c;
                    total[c] +=
                        k_u(d) - system.load(d, factors) - f_other.map_or(0.0, |f| f.get(d));
                }
            }
            (group.clone(), total)
        })
        .collect()
}

/// A force-controlled component whose body offers less stiffness than this fraction of the
/// group's own (`S_ii` of [`rigid_stiffness`] against `d_i`) is held by nothing but the group:
/// the body is free to move along it. Round-off leaves `S_ii` at about `1e-16 d_i cond(K_c)`
/// where the body is free (at most `1e-10 d_i` for the conditionings seen), and a body held
/// by anything is many orders above it.
const UNHELD_STIFFNESS: f64 = 1e-8;

/// The body's own stiffness along its force-controlled components, `S = D_aa - k^T W` (the
/// Schur complement of `K_c` in the bordered matrix of `RigidColumn`), given `W = K_c^-1 [k_1
/// .. k_r]` (the columns one after another, each held as `rows` says; collective on a rank of
/// a distributed run, every rank receiving the same `S`).
pub fn rigid_stiffness(
    system: &AssembledBody,
    rows: &BodyRows,
    w: &[f64],
) -> Result<nalgebra::DMatrix<f64>, LinalgError> {
    let r = system.rigid.len();
    let n = rows.len();
    let mut k_w = Vec::with_capacity(r * r);
    for rigid in &system.rigid {
        k_w.extend((0..r).map(|j| rows.dot_entries(&rigid.column, &w[j * n..(j + 1) * n])));
    }
    let k_w = rows.sum_over_ranks(k_w)?;
    let mut s = nalgebra::DMatrix::<f64>::zeros(r, r);
    for (i, rigid) in system.rigid.iter().enumerate() {
        s[(i, i)] += rigid.diagonal;
        for &(j, c) in &rigid.coupled {
            s[(i, j)] += c;
        }
        for j in 0..r {
            s[(i, j)] -= k_w[i * r + j];
        }
    }
    Ok(s)
}

/// The force-controlled components (indices into `system.rigid`) that nothing but their group
/// holds, given their [`rigid_stiffness`] `s`.
pub fn unheld_components(system: &AssembledBody, s: &nalgebra::DMatrix<f64>) -> Vec<usize> {
    (system.rigid.iter().enumerate())
        // NaN-safe: a stiffness that is not clearly above the bound holds nothing.
        .filter(|(i, rigid)| {
            let held = s[(*i, *i)].partial_cmp(&(UNHELD_STIFFNESS * rigid.diagonal));
            held != Some(std::cmp::Ordering::Greater)
        })
        .map(|(i, _)| i)
        .collect()
}

/// The displacements `a` of a single body's force-controlled components (step 5 of
/// [`solve`]): `u0` is `K_c^-1 f_c`, `w` the columns `K_c^-1 k_j` one after another, each held
/// as `rows` says (collective).
fn rigid_displacements(
    problem: &ElasticProblem,
    system: &AssembledBody,
    rows: &BodyRows,
    u0: &[f64],
    w: &[f64],
) -> Result<Vec<f64>, SolveError> {
    let linalg = |source| SolveError::Linalg {
        body: problem.body.name.clone(),
        source,
    };
    let s = rigid_stiffness(system, rows, w).map_err(linalg)?;
    let unheld = |i: usize| {
        let rigid = &system.rigid[i];
        SolveError::Unheld {
            body: problem.body.name.clone(),
            group: rigid.group.clone(),
            component: ["x", "y", "z"][rigid.component],
        }
    };
    if let Some(&i) = unheld_components(system, &s).first() {
        return Err(unheld(i));
    }
    let pulls = (system.rigid.iter())
        .map(|rigid| rows.dot_entries(&rigid.column, u0))
        .collect();
    let pulls = rows.sum_over_ranks(pulls).map_err(linalg)?;
    let b = nalgebra::DVector::from_iterator(
        system.rigid.len(),
        (system.rigid.iter().zip(pulls)).map(|(rigid, pull)| rigid.force + rigid.applied - pull),
    );
    let a = s.lu().solve(&b).ok_or_else(|| unheld(0))?;
    Ok(a.iter().copied().collect())
}

/// Solves the elastic problem of one body, every load, force and prescribed displacement at
/// its full value (a load path's at factor 1: the load paths scale the steps of a contact solve).
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
    let mut system = assemble(problem, &mut stats, verbose)?;

    // 4. The body solver: Cholesky (symbolic, then numeric) or CG + AMG (matrix and multigrid
    //    hierarchy). Both take K_c as it is: Dirichlet rows and columns zeroed with K_dd kept on
    //    the diagonal (`crate::fem::Constraints::apply`). That keeps every node's dim x dim
    //    blocks, which the multigrid aggregates by (block size dim) and whose rigid-body modes
    //    are its near-null space; removing the fixed dofs instead would break the blocks of
    //    partly fixed nodes. dolfinx does the same, with 1 on the diagonal. A distributed run
    //    hands each rank's rows to PETSc (CG + AMG on every rank); one process hands it the
    //    whole K_c and frees ours before the hierarchy is built, so that K_c is held once.
    let kind = settings.body_solver(body.dim, body.num_dofs());
    let for_petsc = match kind {
        BodySolverKind::CgAmg => system.stiffness.take_whole(),
        _ => None,
    };
    let solver = match (
        system.stiffness.take_rows(),
        for_petsc,
        system.stiffness.whole(),
    ) {
        (Some(rows), _, _) => timed(&mut stats, verbose, "CG + AMG setup", || {
            BodySolver::cg_amg_rows(rows, settings.rtol)?.set_up()
        }),
        (None, Some((k_c, coordinates)), _) => timed(&mut stats, verbose, "CG + AMG setup", || {
            let matrix = BodySolver::cg_amg_matrix(&k_c, system.dim, &coordinates, settings.rtol)?;
            drop((k_c, coordinates));
            matrix.set_up()
        }),
        (None, None, Some(k_c)) => {
            let symbolic = timed(&mut stats, verbose, "ordering + symbolic", || {
                let graph = (system.graph.as_ref())
                    .ok_or_else(|| LinalgError::Sizes("the whole K_c has no node graph".into()))?;
                CholeskySymbolic::new(graph, k_c.symbolic(), settings.ordering)
            })
            .map_err(linalg)?;
            stats.factor_nnz = symbolic.factor_nnz();
            timed(&mut stats, verbose, "numeric factorization", || {
                Cholesky::factorize(symbolic, k_c)
            })
            .map(BodySolver::Cholesky)
        }
        (None, None, None) => Err(LinalgError::Sizes(
            "the stiffness was released to a PETSc solver".into(),
        )),
    }
    .map_err(linalg)?;
    stats.body_solver = Some(solver.kind());
    stats.rank_dofs = solver.rank_dofs();

    // 5. Solve and check the residual of the constrained system. Force-controlled components
    //    (`RigidColumn`) border it: with `W = K_c^-1 [k_1 .. k_r]` and `u0 = K_c^-1 f_c`, their
    //    displacements solve `(D_aa - k^T W) a = (force + applied) - k^T u0`, and `u = u0 - W a`.
    //    Each vector is whole on one process and this rank's rows on a rank of a distributed
    //    run (`BodyRows`), where the answer is then gathered at the nodes the rank keeps only.
    let rows = BodyRows::new(solver.distribution(), system.f_c.len());
    let r = system.rigid.len();
    let n = rows.len();
    let mut columns = rows.of_load(&system.f_c);
    for rigid in &system.rigid {
        columns.extend(rows.of_entries(&rigid.column));
    }
    let phase = match solver.kind() {
        BodySolverKind::CgAmg => "CG + AMG solve",
        _ => "triangular solves",
    };
    let iterations = timed(&mut stats, verbose, phase, || {
        solver.solve_rows_in_place(&mut columns, 1 + r)
    })
    .map_err(linalg)?;
    if solver.kind() == BodySolverKind::CgAmg {
        stats.cg_iterations = Some(iterations);
    }
    let (mut u, w) = (columns[..n].to_vec(), &columns[n..]);
    let a = match r {
        0 => Vec::new(),
        _ => rigid_displacements(problem, &system, &rows, &u, w)?,
    };
    let mut rhs = rows.of_load(&system.f_c);
    for (j, (rigid, a)) in system.rigid.iter().zip(&a).enumerate() {
        u.iter_mut().zip(&w[j * n..]).for_each(|(u, w)| *u -= w * a);
        (rigid.column.iter())
            .filter_map(|&(dof, v)| rows.row(dof).map(|row| (row, v)))
            .for_each(|(row, v)| rhs[row] -= v * a);
    }
    drop(columns);
    stats.relative_residual = match system.stiffness.whole() {
        Some(k_c) => relative_residual(k_c, &u, &rhs),
        None => {
            let mut ku = vec![0.0; n];
            solver.multiply_rows(&u, &mut ku).map_err(linalg)?;
            rows.relative_difference(&ku, &rhs).map_err(linalg)?
        }
    };
    drop(rhs);
    if stats.relative_residual.is_nan() || stats.relative_residual > settings.residual_tolerance {
        return Err(SolveError::Inaccurate {
            body: body.name.clone(),
            residual: stats.relative_residual,
            tolerance: settings.residual_tolerance,
        });
    }
    for (rigid, a) in system.rigid.iter().zip(&a) {
        (rigid.dofs.iter())
            .filter_map(|&dof| rows.row(dof))
            .for_each(|row| u[row] = *a);
    }
    // On a rank of a distributed run, the solution at the nodes it keeps (what the output and
    // the reactions read), as a contact solve's (collective: before the solver is freed,
    // which holds the distribution).
    let u = (rows.at_kept_nodes(u, &body.coords, body.dim)).map_err(linalg)?;
    // The factor or multigrid hierarchy can be the largest object of the run: freed before
    // the cell fields.
    drop(solver);

    // 6. Reactions.
    // Every load and prescribed value at its full value: every path at factor 1.
    let mut full = StepFactors::uniform(1.0);
    full.paths = (problem.paths().into_iter())
        .map(|path| (path.to_string(), 1.0))
        .collect();
    let reactions = reactions(problem, &system, &u, &full, None);
    Ok(ElasticSolution {
        displacement: u,
        reactions,
        stats,
    })
}
