//! One body, `K u = f`, solved by sparse Cholesky or by CG + AMG (`crate::linalg::BodySolver`).

use std::collections::HashMap;
use std::time::Instant;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::{ElasticProblem, ElasticSolution, ProblemError, SolveStats};
use crate::cancel::Cancel;
use crate::fem::assembly::{assemble_stiffness, stiffness_pattern};
use crate::fem::loads::{add_body_force, add_surface_load};
use crate::fem::stress::cell_fields;
use crate::fem::{Constraints, NodeGraph};
use crate::linalg::{
    BodySolver, BodySolverKind, Cholesky, CholeskySymbolic, LinalgError, Ordering,
    relative_residual,
};
use faer::sparse::SparseColMat;

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
    /// Report each phase and its time as `log` messages at level info (default: true; the
    /// CLI's `--quiet` clears it).
    #[serde(skip)]
    pub verbose: bool,
    /// With `verbose`, rewrite a live progress line of long interface solves on stderr when it
    /// is a terminal (default: true; the Python module clears it: its messages go to Python's
    /// `logging`, never to the terminal).
    #[serde(skip)]
    pub progress_line: bool,
    /// Stops a contact solve at its next load step, active-set iteration or coupled GMRES
    /// iteration once cancelled, with `ContactError::Cancelled` (default: a token nobody
    /// cancels; the Python module sets it on Ctrl-C).
    #[serde(skip)]
    pub cancel: Cancel,
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
            progress_line: true,
            cancel: Cancel::default(),
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
        "body '{body}': the linear solve is inaccurate (relative residual {residual:.2e} > [solver] \
         residual_tolerance {tolerance:.0e}); the mesh may be badly graded or the material nearly \
         incompressible"
    )]
    Inaccurate {
        body: String,
        residual: f64,
        tolerance: f64,
    },
    #[error(
        "body '{body}' is held along {component} by nothing but the force-controlled group \
         '{group}': alone, nothing balances that force; prescribe a displacement along \
         {component} somewhere, or put the body in contact"
    )]
    Unheld {
        body: String,
        group: String,
        component: &'static str,
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
    // A force-controlled dof is held at 0 in `K_c`: its displacement is the group's unknown,
    // which enters through its column (`RigidColumn`).
    let mut forced_by: HashMap<usize, String> = HashMap::new();
    for forced in forced_components(problem) {
        for &dof in &forced.dofs {
            if let Some(value) = constraints.value(dof) {
                let other = match forced_by.get(&dof) {
                    Some(group) => format!("by group '{group}'"),
                    None => format!("prescribed {value} by a Dirichlet condition"),
                };
                return Err(ProblemError::ForcedTwice {
                    body: body.name.clone(),
                    group: forced.group.clone(),
                    node_tag: body.node_tags[dof / dim],
                    component: forced.component,
                    other,
                });
            }
            constraints
                .prescribe(dof, 0.0)
                .expect("the dof was free: checked above");
            forced_by.insert(dof, forced.group.clone());
        }
    }
    Ok(constraints)
}

/// One force-controlled component of a group: its dofs (one per node of the group) and force;
/// or a rigid-mode pin (`ElasticProblem::pins`), one dof with no force.
pub(crate) struct ForcedComponent {
    pub group: String,
    pub component: usize,
    pub force: f64,
    pub dofs: Vec<usize>,
    pub pin: bool,
}

/// The force-controlled components of `problem`, group after group, component after component.
pub(crate) fn forced_components(problem: &ElasticProblem) -> Vec<ForcedComponent> {
    let body = problem.body;
    let dim = body.dim;
    let mut out = Vec::new();
    for condition in &problem.forces {
        let nodes = body
            .group_nodes(&condition.group)
            .expect("groups are checked first");
        for (component, force) in condition.components.iter().enumerate().take(dim) {
            if let Some(force) = *force {
                out.push(ForcedComponent {
                    group: condition.group.clone(),
                    component,
                    force,
                    dofs: nodes.iter().map(|&node| dim * node + component).collect(),
                    pin: false,
                });
            }
        }
    }
    for &(node, component) in &problem.pins {
        out.push(ForcedComponent {
            group: format!("rigid-mode pin at node {}", body.node_tags[node]),
            component,
            force: 0.0,
            dofs: vec![dim * node + component],
            pin: true,
        });
    }
    out
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
        log::info!("    {name:<28} {seconds:>8.3} s");
    }
    stats.timings.push((name.to_string(), seconds));
    value
}

/// A body's assembled system: `K` and `f` as assembled, and the Dirichlet-constrained
/// `K_c`, `f_c` on the same pattern.
pub struct AssembledBody {
    /// Dofs per node.
    pub dim: usize,
    /// Node coordinates, `dim` per node: the rigid-body modes an iterative solver's
    /// multigrid needs (its near-null space).
    pub coordinates: Vec<f64>,
    /// The node graph of `k_c`'s pattern (for a fill-reducing ordering).
    pub graph: NodeGraph,
    /// The rows of the unconstrained `K` at the prescribed dofs, `(dof, [(column, value)])`:
    /// all the reactions need of it. The whole `K` is not kept: at a million DOFs it is a
    /// gigabyte beside `k_c` and the solver's own copies.
    pub prescribed_rows: Vec<(usize, Vec<(usize, f64)>)>,
    pub f: Vec<f64>,
    pub constraints: Constraints,
    /// The constrained stiffness `K_c`; `None` once released to a distributed solver (a contact
    /// solve on several MPI ranks: PETSc holds each rank's rows, and products go through it).
    pub k_c: Option<SparseColMat<usize, f64>>,
    /// The largest diagonal entry of `K_c` (the contact system's scale).
    pub k_scale: f64,
    pub f_c: Vec<f64>,
    /// The force-controlled components of the body, in the order of
    /// [`forced_components`]: their dofs are held at 0 in `k_c` and move by unknowns of the
    /// contact solve.
    pub rigid: Vec<RigidColumn>,
}

/// A force-controlled component of a group (`super::ForceCondition`) in the constrained
/// system. Its dofs `G` move together by one unknown `a` and are held at 0 in `K_c`; with `e`
/// the indicator of `G` and `s` the load factor (loads, prescribed values and forces scale
/// alike), the body's equations are
///
/// ```text
/// K_c u + k a               = s f_c(1)       k = K_FG e (free rows F)
/// k^T u + d a + sum_b c_b b = s (force + applied)
/// ```
///
/// with `d = e^T K_GG e`, `c_b = e^T K_GH e_H` for the body's other force-controlled components
/// `b` (dofs `H`), and `applied = e^T f_G - e^T K_GD g_D` (the loads on `G` and the pull of the
/// prescribed dofs `D`). The second equation is the group's reaction `e^T (K u - f)_G` set to
/// the force. `K` is symmetric, so `k` is both the column of `a` and its row.
#[derive(Debug, Clone)]
pub struct RigidColumn {
    pub group: String,
    pub component: usize,
    pub force: f64,
    pub dofs: Vec<usize>,
    /// `k`: `(free dof, value)`, by dof.
    pub column: Vec<(usize, f64)>,
    pub diagonal: f64,
    /// `(b, c_b)`: the couplings to the body's other force-controlled components.
    pub coupled: Vec<(usize, f64)>,
    pub applied: f64,
    /// A rigid-mode pin of a floating body (`ElasticProblem::pins`), not a group of the case.
    pub pin: bool,
}

/// The [`RigidColumn`]s of `forced`, read from the rows of the unconstrained `K` at the
/// prescribed dofs and from `f`.
fn rigid_columns(
    forced: Vec<ForcedComponent>,
    prescribed_rows: &[(usize, Vec<(usize, f64)>)],
    constraints: &Constraints,
    f: &[f64],
) -> Vec<RigidColumn> {
    let mut owner: HashMap<usize, usize> = HashMap::new();
    for (r, component) in forced.iter().enumerate() {
        owner.extend(component.dofs.iter().map(|&dof| (dof, r)));
    }
    let row = |dof: usize| {
        let at = prescribed_rows
            .binary_search_by_key(&dof, |(d, _)| *d)
            .expect("a forced dof is prescribed");
        &prescribed_rows[at].1
    };
    (forced.into_iter().enumerate())
        .map(|(r, component)| {
            let mut column: HashMap<usize, f64> = HashMap::new();
            let mut coupled: HashMap<usize, f64> = HashMap::new();
            let (mut diagonal, mut applied) = (0.0, 0.0);
            for &d in &component.dofs {
                applied += f[d];
                for &(j, value) in row(d) {
                    match (constraints.value(j), owner.get(&j)) {
                        (None, _) => *column.entry(j).or_default() += value,
                        (Some(_), Some(&b)) if b == r => diagonal += value,
                        (Some(_), Some(&b)) => *coupled.entry(b).or_default() += value,
                        (Some(g), None) => applied -= value * g,
                    }
                }
            }
            let mut column: Vec<(usize, f64)> = column.into_iter().collect();
            column.sort_unstable_by_key(|e| e.0);
            let mut coupled: Vec<(usize, f64)> = coupled.into_iter().collect();
            coupled.sort_unstable_by_key(|e| e.0);
            RigidColumn {
                group: component.group,
                component: component.component,
                force: component.force,
                dofs: component.dofs,
                column,
                diagonal,
                coupled,
                applied,
                pin: component.pin,
            }
        })
        .collect()
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
    // K holds the pattern now; the solvers need only its node graph besides.
    let graph = pattern.into_graph();

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

    // 3. Dirichlet conditions, eliminated symmetrically on the same pattern, in K's storage;
    //    the rows of K at the prescribed dofs are kept first, for the reactions (K is
    //    symmetric: the row of a dof is its column).
    let constraints = constraints(problem)?;
    stats.num_prescribed_dofs = constraints.num_fixed();
    let prescribed_rows: Vec<(usize, Vec<(usize, f64)>)> = {
        let (symbolic, values) = k.parts();
        let (col_ptr, row_idx) = (symbolic.col_ptr(), symbolic.row_idx());
        (0..symbolic.ncols())
            .filter(|&d| constraints.is_fixed(d))
            .map(|d| {
                let row = (col_ptr[d]..col_ptr[d + 1]).map(|p| (row_idx[p], values[p]));
                (d, row.collect())
            })
            .collect()
    };
    let (k_c, f_c) = timed(stats, verbose, "apply Dirichlet conditions", || {
        constraints.apply(k, &f)
    });
    let rigid = rigid_columns(
        forced_components(problem),
        &prescribed_rows,
        &constraints,
        &f,
    );
    let dim = body.dim;
    Ok(AssembledBody {
        dim,
        coordinates: body.coords.iter().flat_map(|x| x[..dim].to_vec()).collect(),
        graph,
        prescribed_rows,
        f,
        constraints,
        k_scale: largest_diagonal(&k_c),
        k_c: Some(k_c),
        f_c,
        rigid,
    })
}

/// The largest absolute diagonal entry of `k`.
fn largest_diagonal(k: &SparseColMat<usize, f64>) -> f64 {
    let (symbolic, values) = k.parts();
    let (col_ptr, row_idx) = (symbolic.col_ptr(), symbolic.row_idx());
    (0..symbolic.ncols())
        .flat_map(|j| (col_ptr[j]..col_ptr[j + 1]).filter(move |&p| row_idx[p] == j))
        .map(|p| values[p].abs())
        .fold(0.0, f64::max)
}

/// Reaction of each Dirichlet and force-controlled group: `sum (K u - s f - f_other)` over its
/// prescribed and force-controlled dofs, with `s` the load factor and `f_other` forces not in
/// `f` (contact forces; empty for a single body). A group named by both kinds of condition has
/// one entry.
pub fn reactions(
    problem: &ElasticProblem,
    system: &AssembledBody,
    u: &[f64],
    load_factor: f64,
    f_other: &[f64],
) -> Vec<(String, Vec<f64>)> {
    let body = problem.body;
    let dim = body.dim;
    let mut r = vec![0.0; u.len()];
    for (dof, row) in &system.prescribed_rows {
        r[*dof] = row.iter().map(|&(j, value)| value * u[j]).sum();
    }
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
                        r[d] - load_factor * system.f[d] - f_other.get(d).copied().unwrap_or(0.0);
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
/// .. k_r]` (the columns one after another).
pub fn rigid_stiffness(system: &AssembledBody, w: &[f64]) -> nalgebra::DMatrix<f64> {
    let r = system.rigid.len();
    let n = system.f_c.len();
    let mut s = nalgebra::DMatrix::<f64>::zeros(r, r);
    for (i, rigid) in system.rigid.iter().enumerate() {
        s[(i, i)] += rigid.diagonal;
        for &(j, c) in &rigid.coupled {
            s[(i, j)] += c;
        }
        for j in 0..r {
            let w = &w[j * n..(j + 1) * n];
            s[(i, j)] -= rigid.column.iter().map(|&(dof, k)| k * w[dof]).sum::<f64>();
        }
    }
    s
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
/// [`solve`]): `u0` is `K_c^-1 f_c`, `w` the columns `K_c^-1 k_j` one after another.
fn rigid_displacements(
    problem: &ElasticProblem,
    system: &AssembledBody,
    u0: &[f64],
    w: &[f64],
) -> Result<Vec<f64>, SolveError> {
    let s = rigid_stiffness(system, w);
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
    let b = nalgebra::DVector::from_iterator(
        system.rigid.len(),
        (system.rigid.iter()).map(|rigid| {
            let pull = rigid
                .column
                .iter()
                .map(|&(dof, k)| k * u0[dof])
                .sum::<f64>();
            rigid.force + rigid.applied - pull
        }),
    );
    let a = s.lu().solve(&b).ok_or_else(|| unheld(0))?;
    Ok(a.iter().copied().collect())
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
    let (graph, f_c) = (&system.graph, &system.f_c);
    // A body solved alone keeps its `K_c` (only a distributed contact solve releases it).
    let k_c = system.k_c.as_ref().ok_or_else(|| {
        linalg(LinalgError::Sizes(
            "the stiffness was released to a distributed solver".into(),
        ))
    })?;

    // 4. The body solver: Cholesky (symbolic, then numeric) or CG + AMG (matrix and multigrid
    //    hierarchy). Both take K_c as it is: Dirichlet rows and columns zeroed with K_dd kept on
    //    the diagonal (`crate::fem::Constraints::apply`). That keeps every node's dim x dim
    //    blocks, which the multigrid aggregates by (block size dim) and whose rigid-body modes
    //    are its near-null space; removing the fixed dofs instead would break the blocks of
    //    partly fixed nodes. dolfinx does the same, with 1 on the diagonal.
    let kind = settings.body_solver(body.dim, body.num_dofs());
    let solver = match kind {
        BodySolverKind::CgAmg => timed(&mut stats, verbose, "CG + AMG setup", || {
            BodySolver::cg_amg(k_c, system.dim, &system.coordinates, settings.rtol)
        })
        .map_err(linalg)?,
        _ => {
            let symbolic = timed(&mut stats, verbose, "ordering + symbolic", || {
                CholeskySymbolic::new(graph, k_c.symbolic(), settings.ordering)
            })
            .map_err(linalg)?;
            stats.factor_nnz = symbolic.factor_nnz();
            BodySolver::Cholesky(
                timed(&mut stats, verbose, "numeric factorization", || {
                    Cholesky::factorize(symbolic, k_c)
                })
                .map_err(linalg)?,
            )
        }
    };
    stats.body_solver = Some(solver.kind());
    stats.rank_dofs = solver.rank_dofs();

    // 5. Solve and check the residual of the constrained system. Force-controlled components
    //    (`RigidColumn`) border it: with `W = K_c^-1 [k_1 .. k_r]` and `u0 = K_c^-1 f_c`, their
    //    displacements solve `(D_aa - k^T W) a = (force + applied) - k^T u0`, and `u = u0 - W a`.
    let r = system.rigid.len();
    let n = f_c.len();
    let mut columns = f_c.clone();
    for rigid in &system.rigid {
        let mut k = vec![0.0; n];
        rigid.column.iter().for_each(|&(dof, v)| k[dof] = v);
        columns.extend(k);
    }
    let phase = match solver.kind() {
        BodySolverKind::CgAmg => "CG + AMG solve",
        _ => "triangular solves",
    };
    let iterations = timed(&mut stats, verbose, phase, || {
        solver.solve_in_place(&mut columns, 1 + r)
    })
    .map_err(linalg)?;
    if solver.kind() == BodySolverKind::CgAmg {
        stats.cg_iterations = Some(iterations);
    }
    // The factor or multigrid hierarchy can be the largest object of the run: freed before
    // the cell fields.
    drop(solver);
    let (mut u, w) = (columns[..n].to_vec(), &columns[n..]);
    let a = match r {
        0 => Vec::new(),
        _ => rigid_displacements(problem, &system, &u, w)?,
    };
    let mut rhs = f_c.clone();
    for (j, (rigid, a)) in system.rigid.iter().zip(&a).enumerate() {
        u.iter_mut().zip(&w[j * n..]).for_each(|(u, w)| *u -= w * a);
        rigid.column.iter().for_each(|&(dof, v)| rhs[dof] -= v * a);
    }
    stats.relative_residual = relative_residual(k_c, &u, &rhs);
    if stats.relative_residual.is_nan() || stats.relative_residual > settings.residual_tolerance {
        return Err(SolveError::Inaccurate {
            body: body.name.clone(),
            residual: stats.relative_residual,
            tolerance: settings.residual_tolerance,
        });
    }
    for (rigid, a) in system.rigid.iter().zip(&a) {
        rigid.dofs.iter().for_each(|&dof| u[dof] = *a);
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
