//! A body's discrete system: `K` and `f` assembled, the Dirichlet conditions applied
//! (`K_c u = f_c`), and the force-controlled components' borders ([`RigidColumn`]).
//!
//! One process assembles the whole `K_c`. A rank of a distributed run (`crate::parallel`)
//! assembles only the rows of its own nodes (`crate::linalg::Distribution`: a METIS partition
//! of the body's nodes), which go to PETSc; what every rank needs whole is small or a vector:
//! `f_c` (each rank computes its rows, then their nonzero entries are gathered: a load vector
//! kept sparse where few dofs carry one, `crate::fem::LoadVector`), the rows of `K` at the
//! prescribed dofs (every rank assembles those columns: the cells along the Dirichlet groups)
//! and the largest diagonal entry (the largest of the ranks'). `f` is summed at the nodes the
//! process keeps (`crate::fem::loads::LoadSum`), never over the whole body on a rank; a body
//! force, which loads most dofs and which a rank knows only around its own and the prescribed
//! nodes, stays the rank's part there (`LoadVector::Part`), and so does `f_c` at its rows.

use std::collections::HashMap;

use faer::sparse::SparseColMat;

use super::StepFactors;
use super::error::SolveError;
use super::problem::{
    ElasticProblem, ForcedComponent, LoadCondition, constraints, forced_components,
};
use super::solution::{SolveStats, timed};
use crate::fem::assembly::{assemble_stiffness, stiffness_graph, stiffness_pattern};
use crate::fem::loads::{LoadSum, add_body_force, add_surface_load};
use crate::fem::{Constraints, LoadVector, NodeColumns, NodeGraph};
use crate::linalg::{BodyRows, Distribution, LinalgError, RankRows, own_order};
use crate::mesh::BodyMesh;
use crate::parallel::ranks::Ranks;

/// A body's assembled system: `f` as assembled, the Dirichlet-constrained `K_c` (on the
/// pattern of `K`) and `f_c`, and what the reactions need of `K`.
pub struct AssembledBody {
    /// Dofs per node.
    pub dim: usize,
    /// The node graph of `K_c`'s pattern, for a Cholesky factor's fill-reducing ordering, with
    /// the whole `K_c`; `None` with a rank's rows, which only the partition needed it for (at
    /// 1M DOFs 60 MB on every rank).
    pub graph: Option<NodeGraph>,
    /// The rows of the unconstrained `K` at the prescribed dofs, `(dof, [(column, value)])`:
    /// all the reactions need of it. The whole `K` is not kept: at a million DOFs it is a
    /// gigabyte beside `K_c` and the solver's own copies.
    pub prescribed_rows: Vec<(usize, Vec<(usize, f64)>)>,
    /// The loads as assembled (on a rank with a body force, its part:
    /// [`LoadVector::Part`]).
    pub f: LoadVector,
    /// The sum of each component of `f` over the whole body (the resultant's).
    pub load_sums: Vec<f64>,
    pub constraints: Constraints,
    /// The constrained stiffness `K_c`: whole, or this rank's rows of it.
    pub stiffness: Stiffness,
    /// The largest diagonal entry of `K_c` (the contact system's scale).
    pub k_scale: f64,
    /// The constrained right-hand side.
    pub f_c: LoadVector,
    /// The force-controlled components of the body, in the order of
    /// `forced_components`: their dofs are held at 0 in `K_c` and move by unknowns of the
    /// contact solve.
    pub rigid: Vec<RigidColumn>,
    /// `f` and `f_c` split by load path, the default one first, then the named ones by name,
    /// when a load or prescribed displacement of the body follows a named path (`[load_path]`);
    /// empty otherwise, when everything follows the default path and `f`, `f_c` scale as they
    /// are. The parts sum to `f` and `f_c` (up to round-off). See [`Self::rhs`].
    pub parts: Vec<RhsPart>,
}

/// The part of a body's right-hand side that follows one load path
/// ([`AssembledBody::parts`]).
#[derive(Debug, Clone)]
pub struct RhsPart {
    /// The path: `None` the default one.
    pub path: Option<String>,
    /// The loads that follow it (with the body force on the default path), assembled.
    pub f: LoadVector,
    /// The sum of each component of `f` over the whole body.
    pub load_sums: Vec<f64>,
    /// Its constrained right-hand side: at a free dof its loads less the pull of the values it
    /// prescribes (`-K_FD g_D`), at a prescribed dof `K_dd g_d` of its own value (0 at the
    /// dofs other paths prescribe), so that `sum_p s_p f_c(p)` is `f_c` of the loads and
    /// values of step factors `s_p`.
    pub f_c: LoadVector,
}

impl AssembledBody {
    /// The constrained right-hand side at a load step of `factors`: `s f_c` without named
    /// paths (`s` the default factor, the exact operations of one factor for all), else the
    /// sum of each part's `f_c` times its path's factor.
    pub fn rhs(&self, factors: &StepFactors) -> Vec<f64> {
        if self.parts.is_empty() {
            return self.f_c.scaled(factors.default);
        }
        let mut rhs = vec![0.0; self.f_c.len()];
        for part in &self.parts {
            part.f_c
                .add_scaled_to(factors.of(part.path.as_deref()), &mut rhs);
        }
        rhs
    }

    /// [`Self::rhs`] at `dof` alone, the same bits (the same products, added in the same
    /// order): what a rank of a distributed run reads at its rows.
    pub fn rhs_at(&self, dof: usize, factors: &StepFactors) -> f64 {
        if self.parts.is_empty() {
            return factors.default * self.f_c.get(dof);
        }
        let mut rhs = 0.0;
        for part in &self.parts {
            if let Some(value) = part.f_c.kept_entry(dof) {
                rhs += factors.of(part.path.as_deref()) * value;
            }
        }
        rhs
    }

    /// The load (the step's `f`) at `dof` at a step of `factors`.
    pub fn load(&self, dof: usize, factors: &StepFactors) -> f64 {
        match self.parts.is_empty() {
            true => factors.default * self.f.get(dof),
            false => (self.parts.iter())
                .map(|part| factors.of(part.path.as_deref()) * part.f.get(dof))
                .sum(),
        }
    }

    /// The right-hand side of the `r`-th force-controlled component at a step of `factors`,
    /// `s (force + applied)` with each part scaled by its path's factor (`RigidColumn`).
    pub fn rigid_rhs(&self, r: usize, factors: &StepFactors) -> f64 {
        let rigid = &self.rigid[r];
        if self.parts.is_empty() && rigid.path.is_none() {
            return factors.default * (rigid.force + rigid.applied);
        }
        let force = self.rigid_force(r, factors);
        match self.parts.is_empty() {
            true => force + factors.default * rigid.applied,
            false => (self.parts.iter().zip(&rigid.applied_parts)).fold(force, |g, (part, a)| {
                g + factors.of(part.path.as_deref()) * a
            }),
        }
    }

    /// The force on the `r`-th force-controlled component at a step of `factors`.
    pub fn rigid_force(&self, r: usize, factors: &StepFactors) -> f64 {
        let rigid = &self.rigid[r];
        factors.of(rigid.path.as_deref()) * rigid.force
    }

    /// The magnitude of the resultant of the body's loads and of the forces on its
    /// force-controlled groups at a step of `factors`.
    pub fn resultant(&self, factors: &StepFactors) -> f64 {
        let dim = self.dim;
        let magnitude = |force: &dyn Fn(&RigidColumn) -> f64, loads: &dyn Fn(usize) -> f64| {
            (0..dim)
                .map(|c| {
                    let on_groups: f64 = (self.rigid.iter())
                        .filter(|rigid| !rigid.pin && rigid.component == c)
                        .map(force)
                        .sum();
                    (on_groups + loads(c)).powi(2)
                })
                .sum::<f64>()
                .sqrt()
        };
        if self.parts.is_empty() && self.rigid.iter().all(|r| r.path.is_none()) {
            // At factor 1, then scaled: the operations of one factor for all.
            return factors.default * magnitude(&|rigid| rigid.force, &|c| self.load_sums[c]);
        }
        let force = |rigid: &RigidColumn| factors.of(rigid.path.as_deref()) * rigid.force;
        let loads = |c: usize| match self.parts.is_empty() {
            true => factors.default * self.load_sums[c],
            false => (self.parts.iter())
                .map(|part| factors.of(part.path.as_deref()) * part.load_sums[c])
                .sum(),
        };
        magnitude(&force, &loads)
    }
}

/// A body's constrained stiffness `K_c` as this process holds it.
pub enum Stiffness {
    /// All of it (one process), with the node coordinates (`dim` per node) from which a
    /// CG + AMG solver builds the rigid-body modes of its multigrid (the near-null space): they
    /// go with the matrix to that solver, as a rank's go with its rows ([`RankRows`]), and
    /// no copy of a body's size stays behind once it is taken.
    Whole {
        k_c: SparseColMat<usize, f64>,
        coordinates: Vec<f64>,
    },
    /// This rank's rows (a distributed run), until its solver takes them.
    Rows(RankRows),
    /// Taken by its CG + AMG solver (PETSc), which makes the products.
    Released,
}

impl Stiffness {
    /// The whole matrix, if this process holds it.
    pub fn whole(&self) -> Option<&SparseColMat<usize, f64>> {
        match self {
            Self::Whole { k_c, .. } => Some(k_c),
            _ => None,
        }
    }

    /// The node coordinates that go with the whole matrix, if this process holds it.
    pub fn coordinates(&self) -> Option<&[f64]> {
        match self {
            Self::Whole { coordinates, .. } => Some(coordinates),
            _ => None,
        }
    }

    /// The whole matrix, taken for a solver that keeps its own copy (`Released` is left);
    /// `None`, and nothing changed, if this process does not hold it whole.
    pub fn take_whole(&mut self) -> Option<(SparseColMat<usize, f64>, Vec<f64>)> {
        match std::mem::replace(self, Self::Released) {
            Self::Whole { k_c, coordinates } => Some((k_c, coordinates)),
            other => {
                *self = other;
                None
            }
        }
    }

    /// This rank's rows, taken for its distributed solver (`Released` is left); `None`, and
    /// nothing changed, if this process holds no rows.
    pub fn take_rows(&mut self) -> Option<RankRows> {
        match std::mem::replace(self, Self::Released) {
            Self::Rows(rows) => Some(rows),
            other => {
                *self = other;
                None
            }
        }
    }
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
    /// The load path the force follows (`None`: the default one); `applied` follows the paths
    /// of the loads and values it comes from.
    pub path: Option<String>,
    /// `applied` split as [`AssembledBody::parts`] (empty without parts).
    pub applied_parts: Vec<f64>,
}

/// The [`RigidColumn`]s of `forced`, read from the rows of the unconstrained `K` at the
/// prescribed dofs and from `f` (and each of `parts`, for `applied_parts`).
fn rigid_columns(
    forced: Vec<ForcedComponent>,
    prescribed_rows: &[(usize, Vec<(usize, f64)>)],
    constraints: &Constraints,
    f: &LoadVector,
    parts: &[PathLoads<LoadVector>],
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
            let mut applied_parts = vec![0.0; parts.len()];
            for &d in &component.dofs {
                applied += f.get(d);
                for (a, part) in applied_parts.iter_mut().zip(parts) {
                    *a += part.f.get(d);
                }
                for &(j, value) in row(d) {
                    match (constraints.value(j), owner.get(&j)) {
                        (None, _) => *column.entry(j).or_default() += value,
                        (Some(_), Some(&b)) if b == r => diagonal += value,
                        (Some(_), Some(&b)) => *coupled.entry(b).or_default() += value,
                        (Some(g), None) => {
                            applied -= value * g;
                            for (a, part) in applied_parts.iter_mut().zip(parts) {
                                *a -= value * part.value(j);
                            }
                        }
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
                path: component.path,
                applied_parts,
            }
        })
        .collect()
}

/// Assembles `f` and `K`, and applies the Dirichlet conditions, timing each phase into
/// `stats`: the whole `K_c` on one process, this rank's rows of it in a distributed run.
pub fn assemble(
    problem: &ElasticProblem,
    stats: &mut SolveStats,
    verbose: bool,
) -> Result<AssembledBody, SolveError> {
    let body = problem.body;
    let dim = body.dim;
    stats.num_dofs = body.num_dofs();
    let constraints = constraints(problem)?;
    stats.num_prescribed_dofs = constraints.num_fixed();

    // 1. Load vector f: surface loads and body force, summed at the nodes this process keeps.
    let f = timed(stats, verbose, "assemble loads", || {
        load_sum(problem, |_| true, true)
    });

    // With named load paths, f split by path (its parts' constrained `f_c` follow below).
    let path_loads = path_loads(problem);

    // 2. K_c and f_c, and the rows of K at the prescribed dofs.
    let ranks = crate::parallel::ranks();
    let linalg = |source| SolveError::Linalg {
        body: body.name.clone(),
        source,
    };
    let constrained = match ranks.size {
        1 => whole_stiffness(
            problem,
            &constraints,
            &f,
            body.coords.flat(dim),
            stats,
            verbose,
        ),
        _ => rank_stiffness(problem, &constraints, &f, ranks, stats, verbose).map_err(linalg)?,
    };

    // 3. f as this process keeps it: whole (or sparse) where it knows every entry; with a
    //    body force on a rank that keeps only the cells around its own and the prescribed
    //    nodes, the rank's part: its own dofs and the prescribed ones, all it reads.
    let own = match (&constrained.stiffness, body_force_in_part(problem)) {
        (Stiffness::Rows(rows), true) => Some(&rows.distribution),
        _ => None,
    };
    let kept = |sum: LoadSum| match own {
        None => sum.into_whole(),
        Some(distribution) => {
            sum.into_part(|dof| distribution.own_row(dof).is_some() || constraints.is_fixed(dof))
        }
    };
    let f = kept(f);
    let path_loads: Vec<PathLoads<LoadVector>> = (path_loads.into_iter())
        .map(|part| part.map(kept))
        .collect();

    // 4. The force-controlled components, and with named load paths f_c split by path.
    let rigid = rigid_columns(
        forced_components(problem),
        &constrained.prescribed_rows,
        &constraints,
        &f,
        &path_loads,
    );
    let parts = (path_loads.into_iter())
        .map(|part| part.constrained(dim, &constraints, &constrained.prescribed_rows, own))
        .collect::<Result<_, _>>()
        .map_err(linalg)?;
    let load_sums = load_sums(&f, dim, own).map_err(linalg)?;
    Ok(AssembledBody {
        dim,
        graph: constrained.graph,
        prescribed_rows: constrained.prescribed_rows,
        f,
        load_sums,
        constraints,
        stiffness: constrained.stiffness,
        k_scale: constrained.k_scale,
        f_c: constrained.f_c,
        rigid,
        parts,
    })
}

/// Whether the body has a body force and this rank keeps only its part of the cells: its
/// load vector is then known at its own and the prescribed nodes only.
fn body_force_in_part(problem: &ElasticProblem) -> bool {
    problem.body_force.is_some() && problem.body.part.is_some()
}

/// The loads of `problem` that `follows` selects (in the case's order), then its body force
/// with `body_force`, summed at the nodes this process keeps ([`LoadSum`]).
fn load_sum<'m>(
    problem: &ElasticProblem<'m>,
    follows: impl Fn(&LoadCondition) -> bool,
    body_force: bool,
) -> LoadSum<'m> {
    let body = problem.body;
    let mut sum = LoadSum::new(body);
    let mut add = |dof, value| sum.add(dof, value);
    for load in problem.loads.iter().filter(|load| follows(load)) {
        let group = body
            .boundary_group(&load.group)
            .expect("groups are checked first");
        add_surface_load(body, group, &load.load, &mut add);
    }
    if let (true, Some(b)) = (body_force, &problem.body_force) {
        add_body_force(body, b, &mut add);
    }
    sum
}

/// The sum of each component of `f`, for the resultant: over every entry in dof order (a
/// whole vector's sum, to the bit), or, where this rank keeps its part of `f` (`own`), over
/// its own dofs, added to the other ranks' sums in rank order (collective).
fn load_sums(
    f: &LoadVector,
    dim: usize,
    own: Option<&Distribution>,
) -> Result<Vec<f64>, LinalgError> {
    let Some(distribution) = own else {
        return Ok((0..dim).map(|c| f.component_sum(c, dim)).collect());
    };
    let mut sums = vec![0.0; dim];
    for (dof, value) in f.nonzero_entries() {
        if distribution.own_row(dof).is_some() {
            sums[dof % dim] += value;
        }
    }
    BodyRows::new(Some(distribution), f.len()).sum_over_ranks(sums)
}

/// The loads and prescribed values of one load path ([`path_loads`]): `f` being summed
/// ([`LoadSum`]), then as this process keeps it ([`LoadVector`]).
struct PathLoads<F> {
    path: Option<String>,
    f: F,
    /// Its nonzero prescribed values, by dof.
    values: HashMap<usize, f64>,
}

impl<F> PathLoads<F> {
    /// The same path with `f` kept as `kept` makes it.
    fn map<G>(self, kept: impl Fn(F) -> G) -> PathLoads<G> {
        PathLoads {
            path: self.path,
            f: kept(self.f),
            values: self.values,
        }
    }
}

impl PathLoads<LoadVector> {
    /// The value this path prescribes at the prescribed dof `dof` (0 where another path
    /// prescribes it).
    fn value(&self, dof: usize) -> f64 {
        self.values.get(&dof).copied().unwrap_or(0.0)
    }

    /// This path's part of the right-hand side: `f_c` of its loads and values, the rows of `K`
    /// at the prescribed dofs giving the pull of the values on the free dofs
    /// ([`Constraints::apply_to_load`]), and the sums of its loads. From the rows every rank
    /// holds whole, so a distributed run computes it as one process does; where the rank keeps
    /// its part of `f` (`own`), it keeps `f_c` at its own dofs, the rows it reads (collective
    /// then, for the sums).
    fn constrained(
        self,
        dim: usize,
        constraints: &Constraints,
        prescribed_rows: &[(usize, Vec<(usize, f64)>)],
        own: Option<&Distribution>,
    ) -> Result<RhsPart, LinalgError> {
        let f_c = constraints.apply_to_load(&self.f, prescribed_rows, |j| self.value(j));
        let f_c = match own {
            None => f_c,
            Some(distribution) => {
                let entries = f_c.nonzero_entries();
                let own_entries = entries.filter(|&(d, _)| distribution.own_row(d).is_some());
                LoadVector::part(f_c.len(), own_entries.collect())
            }
        };
        Ok(RhsPart {
            path: self.path,
            load_sums: load_sums(&self.f, dim, own)?,
            f: self.f,
            f_c,
        })
    }
}

/// The loads and prescribed values of `problem` by load path, the default path first, then
/// the named ones by name: empty unless a load or Dirichlet condition follows a named path
/// (the forces' paths are their `RigidColumn`s'). The body force follows the default path.
fn path_loads<'m>(problem: &ElasticProblem<'m>) -> Vec<PathLoads<LoadSum<'m>>> {
    let named: std::collections::BTreeSet<&str> = (problem.loads.iter())
        .map(|l| l.path.as_deref())
        .chain(problem.dirichlet.iter().map(|d| d.path.as_deref()))
        .flatten()
        .collect();
    if named.is_empty() {
        return Vec::new();
    }
    let body = problem.body;
    let dim = body.dim;
    let paths = std::iter::once(None).chain(named.into_iter().map(Some));
    paths
        .map(|path| {
            let f = load_sum(problem, |l| l.path.as_deref() == path, path.is_none());
            let mut values = HashMap::new();
            for condition in (problem.dirichlet.iter()).filter(|d| d.path.as_deref() == path) {
                let nodes = body
                    .group_nodes(&condition.group)
                    .expect("groups are checked first");
                for node in nodes {
                    for (c, value) in condition.components.iter().enumerate().take(dim) {
                        if let Some(value) = value.filter(|&v| v != 0.0) {
                            values.insert(dim * node + c, value);
                        }
                    }
                }
            }
            PathLoads {
                path: path.map(str::to_string),
                f,
                values,
            }
        })
        .collect()
}

/// `K_c` as this process holds it, with what the rest of the system needs of `K`.
struct ConstrainedStiffness {
    graph: Option<NodeGraph>,
    stiffness: Stiffness,
    f_c: LoadVector,
    prescribed_rows: Vec<(usize, Vec<(usize, f64)>)>,
    k_scale: f64,
}

/// The whole `K_c`: `K` on its pattern, then the Dirichlet conditions eliminated symmetrically
/// in `K`'s storage; the rows of `K` at the prescribed dofs are kept first, for the reactions
/// (`K` is symmetric: the row of a dof is its column).
fn whole_stiffness(
    problem: &ElasticProblem,
    constraints: &Constraints,
    f: &LoadSum,
    coordinates: Vec<f64>,
    stats: &mut SolveStats,
    verbose: bool,
) -> ConstrainedStiffness {
    let body = problem.body;
    let pattern = timed(stats, verbose, "sparsity pattern", || {
        stiffness_pattern(body)
    });
    let k = timed(stats, verbose, "assemble stiffness", || {
        assemble_stiffness(body, &problem.material, &pattern)
    });
    stats.stiffness_nnz = pattern.nnz();
    // K holds the pattern now; the solvers need only its node graph besides.
    let graph = pattern.into_graph();
    let prescribed_rows = {
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
        constraints.apply(k, f.as_whole().expect("one process keeps every node"))
    });
    ConstrainedStiffness {
        graph: Some(graph),
        k_scale: largest_diagonal(&k_c),
        stiffness: Stiffness::Whole { k_c, coordinates },
        f_c: LoadVector::new(f_c),
        prescribed_rows,
    }
}

/// This rank's rows of `K_c` in a distributed run: the body's nodes are partitioned (as the
/// mesh's [`crate::mesh::RankPart`] says, where the run kept only this rank's cells), the
/// columns of this rank's nodes assembled and constrained (its rows: `K` is symmetric), and
/// its rows of `f_c` computed and their nonzero entries gathered on every rank. Every rank
/// assembles the columns at the prescribed dofs too (the cells along the Dirichlet groups),
/// for the reactions. Where the rank kept only its cells, a body force in `f` is right at its
/// own and the prescribed nodes only: the rank keeps its rows of `f_c` then, not gathered.
/// Collective: every rank calls it for every body, in the same order.
fn rank_stiffness(
    problem: &ElasticProblem,
    constraints: &Constraints,
    f: &LoadSum,
    ranks: Ranks,
    stats: &mut SolveStats,
    verbose: bool,
) -> Result<ConstrainedStiffness, LinalgError> {
    let body = problem.body;
    let dim = body.dim;
    // The symbolic phase of a rank: the node graph, and which nodes are whose.
    let (graph, distribution) = timed(stats, verbose, "sparsity pattern", || {
        let graph = stiffness_graph(body);
        let distribution = match &body.part {
            Some(_) => partitioned_distribution(body, ranks),
            None => Distribution::new(&graph, &body.coords.flat(dim), ranks),
        };
        distribution.map(|distribution| (graph, distribution))
    })?;
    let mut columns = timed(stats, verbose, "assemble stiffness", || {
        NodeColumns::assemble(body, &problem.material, &graph, distribution.nodes())
    });
    let nnz = crate::parallel::gather(columns.nnz() as f64).map_err(mpi)?;
    stats.stiffness_nnz = nnz.iter().sum::<f64>() as usize;

    let prescribed_nodes = (0..body.num_nodes())
        .filter(|&a| (0..dim).any(|c| constraints.is_fixed(dim * a + c)))
        .collect();
    let prescribed = NodeColumns::assemble(body, &problem.material, &graph, prescribed_nodes);
    let prescribed_rows = (0..prescribed.num_columns())
        .filter(|&q| constraints.is_fixed(prescribed.dof(q)))
        .map(|q| {
            let (rows, values) = prescribed.column(q);
            let row = rows.iter().copied().zip(values.iter().copied());
            (prescribed.dof(q), row.collect())
        })
        .collect();
    drop(prescribed);

    let (f_c, local_largest) = timed(stats, verbose, "apply Dirichlet conditions", || {
        let local_f_c = constraints.apply_to_columns(&mut columns, |dof| f.get(dof));
        let own = (local_f_c.iter().enumerate()).map(|(q, &value)| (columns.dof(q), value));
        let len = body.num_dofs();
        let f_c = match body_force_in_part(problem) {
            true => {
                let mut entries: Vec<(usize, f64)> = own.filter(|&(_, v)| v != 0.0).collect();
                entries.sort_unstable_by_key(|&(dof, _)| dof);
                LoadVector::part(len, entries)
            }
            false => LoadVector::from_entries(len, distribution.gather_nonzero(own)?),
        };
        let largest = (0..columns.num_columns())
            .flat_map(|q| {
                let dof = columns.dof(q);
                let (rows, values) = columns.column(q);
                rows.iter().zip(values).filter(move |(i, _)| **i == dof)
            })
            .map(|(_, value)| value.abs())
            .fold(0.0, f64::max);
        Ok::<_, LinalgError>((f_c, largest))
    })?;
    let k_scale = (crate::parallel::gather(local_largest).map_err(mpi)?)
        .into_iter()
        .fold(0.0, f64::max);
    let rows = distribution.rows(&columns, &body.coords);
    drop(graph);
    Ok(ConstrainedStiffness {
        graph: None,
        stiffness: Stiffness::Rows(rows),
        f_c,
        prescribed_rows,
        k_scale,
    })
}

/// The distribution of a body whose nodes rank 0 divided among the ranks (`crate::run`'s
/// partition): each rank orders its own nodes along the Z curve within the whole body's box
/// ([`own_order`]), PETSc numbering rank 0's first, then rank 1's, and so on; each rank learns
/// the PETSc node of every node it reads that another rank owns from that rank (one
/// `MPI_Alltoallv` of the questions, one of the answers), so that no rank holds the whole
/// body's order (collective).
fn partitioned_distribution(body: &BodyMesh, ranks: Ranks) -> Result<Distribution, LinalgError> {
    let dim = body.dim;
    let (mut own, mut coords) = (Vec::new(), Vec::new());
    for (a, x) in body.owned_by(ranks.rank) {
        own.push(a as u32);
        coords.extend_from_slice(&x[..dim]);
    }
    let extent = body.extent();
    let order = own_order(&own, &coords, &extent.low[..dim], &extent.high[..dim]);
    drop((own, coords));
    let nodes_per_rank: Vec<usize> = (crate::parallel::gather(order.len() as f64).map_err(mpi)?)
        .into_iter()
        .map(|count| count as usize)
        .collect();
    // The PETSc node of each of this rank's nodes, by our node.
    let first = nodes_per_rank[..ranks.rank].iter().sum::<usize>() as u32;
    let mut own_petsc: Vec<(u32, u32)> =
        (order.iter().zip(first..)).map(|(&a, p)| (a, p)).collect();
    own_petsc.sort_unstable();
    let petsc_of_own = |a: u32| {
        (own_petsc.binary_search_by_key(&a, |&(b, _)| b))
            .map(|at| own_petsc[at].1)
            .map_err(|_| LinalgError::Sizes(format!("node {a} is not this rank's own")))
    };
    // This rank reads the nodes whose coordinates it keeps, and knows their PETSc nodes only:
    // its own from its order, the others' asked of their owners.
    let mut known = Vec::with_capacity(body.coords.kept().len());
    let (mut asked, mut waiting) = (vec![Vec::new(); ranks.size], vec![Vec::new(); ranks.size]);
    for (a, _) in body.coords.kept() {
        let owner = (body.owner(a))
            .ok_or_else(|| LinalgError::Partition(format!("node {a} kept without its owner")))?;
        if owner as usize == ranks.rank {
            known.push((a as u32, petsc_of_own(a as u32)?));
        } else {
            asked[owner as usize].push(a as f64);
            waiting[owner as usize].push(known.len());
            known.push((a as u32, u32::MAX));
        }
    }
    let questions = crate::parallel::exchange(asked).map_err(mpi)?;
    let answers = (questions.iter())
        .map(|nodes| {
            (nodes.iter())
                .map(|&a| petsc_of_own(a as u32).map(f64::from))
                .collect::<Result<Vec<f64>, _>>()
        })
        .collect::<Result<Vec<_>, _>>()?;
    let answered = crate::parallel::exchange(answers).map_err(mpi)?;
    for (places, answer) in waiting.iter().zip(&answered) {
        if answer.len() != places.len() {
            return Err(LinalgError::Sizes(format!(
                "{} PETSc nodes answered for {} nodes asked",
                answer.len(),
                places.len()
            )));
        }
        for (&k, &p) in places.iter().zip(answer) {
            known[k].1 = p as u32;
        }
    }
    Ok(Distribution::from_parts(
        order,
        &nodes_per_rank,
        dim,
        ranks,
        known,
    ))
}

fn mpi(e: crate::parallel::ParallelError) -> LinalgError {
    LinalgError::Mpi(e.to_string())
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
