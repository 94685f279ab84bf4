//! How the coupled system of an iteration is solved, behind one interface, for any number of
//! bodies and pairs.
//!
//! Each body's solver is set up once for the whole contact solve (a sparse Cholesky factor, or
//! PETSc's AMG: `crate::linalg::BodySolver`); then, per iteration:
//!
//! - [`CoupledSolver::Krylov`]: one restarted GMRES on the whole system, block-preconditioned
//!   by one application of each body's solver and a half-space approximation of the interface
//!   Schur complement ([`crate::contact::coupled::coupled_krylov`]), warm-started from the last
//!   solve.
//! - [`CoupledSolver::Schur`]: the exact reference by elimination, `z = K^-1 f`,
//!   `(D - C K^-1 B) lambda = g - C z`, `u = z - K^-1 (B lambda)`, with `C K^-1 B = s C Y`
//!   formed densely from each body's responses `Y_k` to the multipliers
//!   ([`crate::contact::coupled::compliance`]), computed once per multiplier (`dim` solves per
//!   primary node) and reused by every later iteration and load step; the Schur complement is
//!   factored by dense LU with partial pivoting (interfaces have hundreds to a few thousand
//!   multipliers). With CG + AMG bodies each of those columns would be a whole CG solve: `schur`
//!   then runs the Krylov path.
//! - [`CoupledSolver::Auto`]: Krylov, and Schur after a GMRES failure (below).
//! - [`CoupledSolver::MonolithicLu`]: a sparse LU of the whole unsymmetric matrix, refactored
//!   every iteration; the reference the Schur path is tested against.
//!
//! # Which one: `auto`
//!
//! `auto` (the default) runs the Krylov path and moves to the dense Schur complement for the
//! rest of the solve at the first GMRES failure. The Krylov path costs per iteration about what
//! one elastic solve of each body costs; the dense path is exact whatever the conditioning of
//! the interface problem: with a stiff body named primary on a compliant one (E ratio 1e4), the
//! half-space approximation may not tame it and GMRES may stagnate or reach its cap (with
//! `krylov` an error that names it; with `auto` the dense path then solves it, as `schur`
//! does). A failed GMRES solve costs at most its iteration cap, which is why the fallback is
//! for the rest of the solve and not retried per iteration.

use faer::prelude::*;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

use crate::contact::ContactError;
use crate::contact::coupled::compliance::SurfaceResponse;
use crate::contact::coupled::coupled_krylov::{self, KrylovState, KrylovStats, Tightness};
use crate::contact::coupled::row_ownership::{self, RowOwnership, shared_bodies};
use crate::contact::coupled::system::{CoupledSystem, Pair, Unknowns, assembled};
use crate::contact::settings::{ContactSettings, CoupledSolver};
use crate::elastic::AssembledBody;
use crate::elastic::SolverSettings;
use crate::fem::LoadVector;
use crate::linalg::{
    BodyRows, BodySolver, BodySolverKind, Cholesky, CholeskySymbolic, Distribution, LinalgError,
    Ordering,
};

/// The solvers (Cholesky factors, or CG + AMG) of every body's constrained stiffness matrix,
/// and what the interface solve keeps between iterations: the bodies' responses to the
/// multipliers computed so far (dense Schur), or the warm start (Krylov).
pub struct BodyFactors {
    solvers: Vec<BodySolver>,
    /// Where this rank's rows of the bodies are, in a distributed run: its coupled systems
    /// hold only its entries of `B` and `C` (`CoupledSystem::assemble_on`).
    ownership: Option<RowOwnership>,
    /// The half-space compliance factor of each pair's two materials
    /// (`crate::contact::coupled::half_space`).
    compliance: Vec<f64>,
    interface: Interface,
    /// The candidate nodes of each body, for the dense Schur path `auto` falls back to.
    fallback: Option<Vec<Vec<usize>>>,
    /// Why the interface solve left GMRES for the dense Schur complement, if it did.
    pub fell_back: Option<String>,
    /// The fill-reducing ordering of Cholesky factors (also those of the fallback).
    ordering: Ordering,
    /// The last Krylov solve's figures (`None` when the last solve was not a Krylov one).
    pub last_krylov: Option<KrylovStats>,
    dim: usize,
    verbose: bool,
}

/// How the interface problem is solved, with what it keeps between iterations.
enum Interface {
    /// Each body's responses to the unit tractions, on its candidate surfaces.
    Dense { responses: Vec<SurfaceResponse> },
    Krylov {
        state: KrylovState,
        /// GMRES' iteration cap per solve (`ContactSettings::krylov_max_iterations`).
        max_iterations: usize,
    },
}

impl Interface {
    fn dense(candidates: &[Vec<usize>], bodies: &[&AssembledBody]) -> Self {
        let responses = (candidates.iter().zip(bodies))
            .map(|(nodes, body)| SurfaceResponse::new(nodes, body.dim, body.f_c.len()))
            .collect();
        Self::Dense { responses }
    }
}

impl BodyFactors {
    /// Sets up every body's solver (`kind`: Cholesky or CG + AMG, resolved by the caller) for
    /// the coupled solve `contact.solver`. `candidates` are each body's candidate nodes (over
    /// all its pairs), which the response caches of the dense path cover; `compliance` each
    /// pair's half-space compliance factor
    /// (`crate::contact::coupled::half_space::compliance_factor`), for the Krylov path's
    /// preconditioner.
    ///
    /// `ready`: solvers already set up for the bodies (those of
    /// [`petsc_solvers`]); otherwise they are set up here.
    pub fn new(
        bodies: &[&AssembledBody],
        candidates: Vec<Vec<usize>>,
        compliance: Vec<f64>,
        settings: &SolverSettings,
        kind: BodySolverKind,
        contact: &ContactSettings,
        ready: Option<Vec<BodySolver>>,
    ) -> Result<Self, ContactError> {
        let method = contact.solver;
        let dim = bodies.first().map_or(3, |body| body.dim);
        let factor = |body: &&AssembledBody| match kind {
            BodySolverKind::CgAmg => {
                let coordinates = body.stiffness.coordinates().unwrap_or_default();
                BodySolver::cg_amg(assembled(body)?, body.dim, coordinates, settings.rtol)
                    .map_err(cg_amg_error)
            }
            _ => cholesky(body, None, settings.ordering),
        };
        // The set-ups are independent: side by side.
        let solvers = match ready {
            Some(solvers) => solvers,
            None => bodies
                .par_iter()
                .map(factor)
                .collect::<Result<Vec<_>, _>>()?,
        };
        let ownership = RowOwnership::of(&solvers)?;
        let cg = kind == BodySolverKind::CgAmg;
        let krylov = cg || matches!(method, CoupledSolver::Krylov | CoupledSolver::Auto);
        let interface = if krylov {
            Interface::Krylov {
                state: KrylovState::new(settings.cancel.clone()),
                max_iterations: contact.krylov_max_iterations,
            }
        } else {
            Interface::dense(&candidates, bodies)
        };
        // A distributed run has no factors to fall back on (`crate::parallel`).
        let fallback = (method == CoupledSolver::Auto && !crate::parallel::distributed())
            .then_some(candidates);
        Ok(Self {
            solvers,
            ownership,
            compliance,
            interface,
            fallback,
            fell_back: None,
            ordering: settings.ordering,
            last_krylov: None,
            dim,
            verbose: settings.verbose,
        })
    }

    /// Forgets the bodies' responses to the multipliers: the interface operators changed.
    /// (The Krylov warm start is kept: tractions mapped by node stay a good first guess.)
    pub fn forget_responses(&mut self) {
        if let Interface::Dense { responses } = &mut self.interface {
            responses.iter_mut().for_each(SurfaceResponse::clear);
        }
    }

    /// Whether the coupled system is solved by GMRES (whose solves can stop short of
    /// round-off on request: [`Self::solve`]).
    pub fn is_krylov(&self) -> bool {
        matches!(self.interface, Interface::Krylov { .. })
    }

    /// Where this rank's rows of the bodies are, in a distributed run (`None` on one process).
    pub fn ownership(&self) -> Option<&RowOwnership> {
        self.ownership.as_ref()
    }

    /// Which ranks keep the interface transfers' entries at `nodes`, the secondary candidates
    /// of a pair on body `k` of `bodies`, in a distributed run ([`row_ownership::Keepers`]);
    /// `None` on one process, which keeps them all.
    pub fn keepers(
        &self,
        bodies: &[&AssembledBody],
        k: usize,
        nodes: &[usize],
    ) -> Result<Option<row_ownership::Keepers>, ContactError> {
        (shared_bodies(&self.solvers)?)
            .map(|shared| row_ownership::Keepers::new(shared[k], bodies[k], nodes))
            .transpose()
    }

    /// The forces on the bodies numbered `which`, made on this rank from the entries it keeps,
    /// completed from the ranks that own them ([`row_ownership::complete_forces`]); nothing
    /// to do on one process (collective).
    pub fn complete_forces(
        &self,
        which: &[usize],
        forces: &mut [&mut LoadVector],
    ) -> Result<(), ContactError> {
        match shared_bodies(&self.solvers)? {
            None => Ok(()),
            Some(shared) => {
                let bodies: Vec<&Distribution> = which.iter().map(|&k| shared[k]).collect();
                row_ownership::complete_forces(&bodies, forces)
            }
        }
    }

    /// How each body's unknowns are shared among the ranks, in a distributed run; `None` on
    /// one process.
    pub fn distributions(&self) -> Result<Option<Vec<&Distribution>>, ContactError> {
        shared_bodies(&self.solvers)
    }

    /// Each body's displacements at the nodes this rank reads (those whose coordinates its
    /// mesh keeps, in their order: `Distribution::at_read_nodes`) from every rank's rows of
    /// them (this rank's, PETSc's order, in `u`: a distributed run's solve answers so;
    /// collective, the owners' values to the bit); unchanged on one process, where they are
    /// whole.
    pub fn at_read_nodes(&self, u: &mut [Vec<f64>]) -> Result<(), ContactError> {
        if let Some(shared) = shared_bodies(&self.solvers)? {
            for (distribution, u) in shared.iter().zip(u.iter_mut()) {
                *u = (distribution.at_read_nodes(u)).map_err(|e| {
                    ContactError::Linalg(format!("a body's displacement at its nodes: {e}"))
                })?;
            }
        }
        Ok(())
    }

    /// `|[f; g] - A x| / |[f; g]|` of the answer `x` of [`Self::solve`]: by the system's blocks,
    /// or on several ranks, whose systems hold only their entries, by the coupled GMRES's
    /// product (collective).
    pub fn relative_residual(
        &self,
        system: &CoupledSystem,
        pairs: &[Pair],
        bodies: &[&AssembledBody],
        x: &[f64],
    ) -> Result<f64, ContactError> {
        match system.unknowns {
            Unknowns::Whole => system.relative_residual(bodies, Some(&self.solvers), x),
            Unknowns::RankRows => {
                let problem = coupled_krylov::KrylovProblem {
                    system,
                    pairs,
                    bodies,
                    solvers: &self.solvers,
                    compliance: &self.compliance,
                    dim: self.dim,
                };
                coupled_krylov::relative_residual(&problem, x.to_vec())
            }
        }
    }

    /// Each body's share of its unknowns among the MPI ranks (`BodySolver::rank_dofs`).
    pub fn rank_dofs(&self) -> Vec<Vec<usize>> {
        self.solvers.iter().map(BodySolver::rank_dofs).collect()
    }

    /// The bodies' solver (Cholesky after a fallback from CG + AMG).
    pub fn body_kind(&self) -> BodySolverKind {
        self.solvers
            .first()
            .map_or(BodySolverKind::Cholesky, BodySolver::kind)
    }

    /// Applications of each body's block of the Krylov preconditioner so far (`None` off the
    /// Krylov path).
    pub fn body_applications(&self) -> Option<Vec<usize>> {
        match &self.interface {
            Interface::Krylov { state, .. } => Some(state.body_applications.clone()),
            Interface::Dense { .. } => None,
        }
    }

    /// Solves the coupled system of `pairs` on `bodies`; returns `x = [u_1; ...; u_N; lambda
    /// / s]`, in a distributed run this rank's rows of each body (PETSc's order) then every
    /// multiplier (`crate::contact::coupled::krylov_layout`).
    ///
    /// On the Krylov path a loose solve ([`Tightness`]) stops at a relative residual the
    /// caller's active-set decision needs, not at round-off; the caller then owns the residual
    /// check. A GMRES failure under `auto` moves this and every later iteration to the dense
    /// Schur complement ([`Self::fell_back`] says why).
    pub fn solve(
        &mut self,
        system: &CoupledSystem,
        pairs: &[Pair],
        bodies: &[&AssembledBody],
        tightness: Tightness,
    ) -> Result<Vec<f64>, ContactError> {
        self.last_krylov = None;
        let (state, max_iterations) = match &mut self.interface {
            Interface::Dense { responses } => {
                return solve_schur(system, &self.solvers, responses, bodies);
            }
            Interface::Krylov {
                state,
                max_iterations,
            } => (state, *max_iterations),
        };
        let problem = coupled_krylov::KrylovProblem {
            system,
            pairs,
            bodies,
            solvers: &self.solvers,
            compliance: &self.compliance,
            dim: self.dim,
        };
        let solved = coupled_krylov::solve(&problem, state, tightness, max_iterations);
        let stats = state.last;
        self.last_krylov = Some(stats);
        if self.verbose {
            log::trace!(
                "    coupled GMRES: {} iterations (+{} residuals), relative residual {:.1e} \
                 (start {:.1e}, target {:.1e})",
                stats.iterations,
                stats.residual_products,
                stats.relative_residual,
                stats.initial_residual,
                stats.tolerance,
            );
        }
        match (solved, self.fallback.take()) {
            (Err(ContactError::Krylov(failure)), Some(candidates)) => {
                // The dense Schur complement solves `dim` systems per body for each active
                // node: with CG + AMG bodies each would be a whole CG solve, so the bodies are
                // factored instead (a factor that does not fit in memory is an error naming it).
                let factored = !matches!(
                    self.solvers.first().map(BodySolver::kind),
                    Some(BodySolverKind::Cholesky)
                );
                if self.verbose {
                    let how = if factored {
                        "Cholesky factors of the bodies and "
                    } else {
                        ""
                    };
                    log::info!("    {failure}: {how}the dense Schur complement from here on");
                }
                if factored {
                    let ordering = self.ordering;
                    self.solvers = (bodies.par_iter().zip(&self.solvers))
                        .map(|(body, solver)| cholesky(body, Some(solver), ordering))
                        .collect::<Result<Vec<_>, _>>()?;
                }
                self.interface = Interface::dense(&candidates, bodies);
                self.fell_back = Some(failure.to_string());
                self.solve(system, pairs, bodies, tightness)
            }
            (solved, fallback) => {
                self.fallback = fallback;
                solved
            }
        }
    }
}

/// The force-controlled components (indices into `body.rigid`) of each body that nothing but
/// its contacts holds (`crate::elastic::unheld_components`): the body's own stiffness along
/// them needs `K_c^-1 k` of each, solved by the body's solver in `factors`, or by a Cholesky
/// factor made for the purpose (the monolithic path has no body solvers).
pub fn held_by_contacts_only(
    bodies: &[&AssembledBody],
    factors: Option<&BodyFactors>,
    ordering: Ordering,
) -> Result<Vec<Vec<usize>>, ContactError> {
    let mut held = Vec::with_capacity(bodies.len());
    for (k, body) in bodies.iter().enumerate() {
        if body.rigid.is_empty() {
            held.push(Vec::new());
            continue;
        }
        let own;
        let solver = match factors {
            Some(factors) => &factors.solvers[k],
            None => {
                own = cholesky(body, None, ordering)?;
                &own
            }
        };
        // `W` held as the solver holds a body's vectors: this rank's rows on a rank.
        let rows = BodyRows::new(solver.distribution(), body.f_c.len());
        let mut w = Vec::with_capacity(rows.len() * body.rigid.len());
        for rigid in &body.rigid {
            w.extend(rows.of_entries(&rigid.column));
        }
        solver
            .solve_rows_in_place(&mut w, body.rigid.len())
            .map_err(body_solve_error)?;
        let stiffness = crate::elastic::rigid_stiffness(body, &rows, &w)
            .map_err(|e| ContactError::Linalg(format!("a body's own stiffness: {e}")))?;
        held.push(crate::elastic::unheld_components(body, &stiffness));
    }
    Ok(held)
}

/// The Cholesky factor of a body's constrained stiffness: ours, or where we released it
/// ([`petsc_solvers`]) a copy of the one `solver` holds.
fn cholesky(
    body: &AssembledBody,
    solver: Option<&BodySolver>,
    ordering: Ordering,
) -> Result<BodySolver, ContactError> {
    let copy = match body.stiffness.whole() {
        Some(_) => None,
        None => solver.and_then(BodySolver::matrix),
    };
    let k_c = match &copy {
        Some(matrix) => matrix,
        None => assembled(body)?,
    };
    let graph = (body.graph.as_ref())
        .ok_or_else(|| ContactError::Linalg("a body's whole K_c has no node graph".into()))?;
    let factor = CholeskySymbolic::new(graph, k_c.symbolic(), ordering)
        .and_then(|symbolic| Cholesky::factorize(symbolic, k_c))
        .map_err(|e| ContactError::Linalg(format!("Cholesky of a body's stiffness: {e}")))?;
    Ok(match copy {
        Some(matrix) => BodySolver::CholeskyOfCopy { factor, matrix },
        None => BodySolver::Cholesky(factor),
    })
}

fn cg_amg_error(e: LinalgError) -> ContactError {
    ContactError::Linalg(format!("CG + AMG of a body: {e}"))
}

/// The bodies' CG + AMG solvers, each holding the only copy of its body's `K_c`
/// (`AssembledBody::stiffness` is left `Released`: products and, on one process, the matrix
/// for a Cholesky fallback come from the solver): every body's matrix (a distributed run: this
/// rank's rows of it) goes to PETSc and ours is freed, then the multigrid hierarchies are
/// built, so that a process never holds its matrices beside a hierarchy being set up. On one
/// process this is `K_c` once instead of twice (at 1M DOFs about 0.9 GB less).
pub fn petsc_solvers(
    bodies: &mut [AssembledBody],
    settings: &SolverSettings,
) -> Result<Vec<BodySolver>, ContactError> {
    let mut pending = Vec::with_capacity(bodies.len());
    for body in bodies.iter_mut() {
        let matrix = match body.stiffness.take_rows() {
            Some(rows) => BodySolver::cg_amg_rows(rows, settings.rtol),
            None => {
                let (k_c, coordinates) = body.stiffness.take_whole().ok_or_else(|| {
                    ContactError::Linalg("a body's stiffness was released twice".to_string())
                })?;
                BodySolver::cg_amg_matrix(&k_c, body.dim, &coordinates, settings.rtol)
            }
        };
        pending.push(matrix.map_err(cg_amg_error)?);
    }
    (pending.into_iter())
        .map(|matrix| matrix.set_up().map_err(cg_amg_error))
        .collect()
}

/// The coupled system solved by one sparse LU of its whole matrix.
pub fn solve_monolithic(
    system: &CoupledSystem,
    bodies: &[&AssembledBody],
) -> Result<Vec<f64>, ContactError> {
    let matrix = system.matrix(bodies)?;
    let lu_error =
        |e: String| ContactError::Linalg(format!("sparse LU of the coupled system: {e}"));
    let symbolic =
        SymbolicLu::try_new(matrix.symbolic()).map_err(|e| lu_error(format!("{e:?}")))?;
    let lu = Lu::try_new_with_symbolic(symbolic, matrix.as_ref())
        .map_err(|e| lu_error(format!("{e:?}")))?;
    let mut x = system.rhs();
    let n = x.len();
    lu.solve_in_place(faer::MatMut::from_column_major_slice_mut(&mut x, n, 1));
    Ok(x)
}

fn body_solve_error(e: crate::linalg::LinalgError) -> ContactError {
    ContactError::Linalg(format!("a body's solve: {e}"))
}

/// The exact elimination (module doc), then one step of iterative refinement: the whole
/// system's residual `[f; g] - A x` is eliminated again and the correction added. The dense LU
/// of an ill-conditioned Schur complement (a stiff body named primary on a fine, compliant one)
/// loses digits that the elimination of `u` then amplifies: a 2D stiff block on an R/600 disc
/// left a relative residual of 1.8e-8, above `residual_tolerance`, which one step of
/// refinement (Wilkinson's, in working precision, with the exact residual) removes.
fn solve_schur(
    system: &CoupledSystem,
    solvers: &[BodySolver],
    responses: &mut [SurfaceResponse],
    bodies: &[&AssembledBody],
) -> Result<Vec<f64>, ContactError> {
    extend_responses(system, solvers, responses)?;
    let schur = schur_complement(system, responses).lu();
    let mut x = eliminate(system, solvers, &schur, &system.f, &system.g)?;
    let residual = system.residual(bodies, Some(solvers), &x)?;
    let (r_u, r_l) = residual.split_at(system.num_displacements());
    let correction = eliminate(system, solvers, &schur, r_u, r_l)?;
    x.iter_mut().zip(&correction).for_each(|(x, dx)| *x += dx);
    Ok(x)
}

/// `x = A^-1 [f; g]` by elimination with the LU of the Schur complement `S = D - C K^-1 B`:
/// `z = K^-1 f`, `S lambda = g - C z`, `u = z - K^-1 (B lambda)`.
fn eliminate(
    system: &CoupledSystem,
    solvers: &[BodySolver],
    schur: &nalgebra::linalg::LU<f64, nalgebra::Dyn, nalgebra::Dyn>,
    f: &[f64],
    g: &[f64],
) -> Result<Vec<f64>, ContactError> {
    let (n, m) = (system.num_displacements(), system.m);
    let mut z = f.to_vec();
    solve_bodies(system, solvers, &mut z)?;
    let mut r = DVector::from_column_slice(g);
    for (k, col, value) in system.c_entries() {
        r[k] -= value * z[col];
    }
    let lambda = if m > 0 {
        schur.solve(&r).ok_or_else(|| {
            ContactError::Linalg("the interface Schur complement is singular".into())
        })?
    } else {
        DVector::zeros(0)
    };
    let mut w = vec![0.0; n];
    system.add_b_product(lambda.as_slice(), 1.0, &mut w);
    solve_bodies(system, solvers, &mut w)?;
    let mut x: Vec<f64> = z.iter().zip(&w).map(|(z, w)| z - w).collect();
    x.extend(lambda.iter());
    Ok(x)
}

/// `K_k^-1 w_k` in place on each body's part of `w`; the bodies are independent, so side by
/// side.
fn solve_bodies(
    system: &CoupledSystem,
    solvers: &[BodySolver],
    w: &mut [f64],
) -> Result<(), ContactError> {
    system
        .body_parts(w)
        .into_par_iter()
        .zip(solvers)
        .try_for_each(|(part, solver)| solver.solve_in_place(part, 1).map(|_| ()))
        .map_err(body_solve_error)
}

/// Each body's responses to the unit forces of `system` not seen before with the same load
/// (`crate::contact::coupled::compliance`).
fn extend_responses(
    system: &CoupledSystem,
    solvers: &[BodySolver],
    responses: &mut [SurfaceResponse],
) -> Result<(), ContactError> {
    let on_body = |body: usize| {
        let dofs = system.body_dofs(body);
        (system.unit_loads.iter())
            .map(|unit| {
                let on_body: Vec<(usize, f64)> = (unit.load.iter())
                    .filter(|(row, _)| dofs.contains(row))
                    .map(|&(row, value)| (row - dofs.start, value))
                    .collect();
                (unit.key, on_body)
            })
            .collect::<Vec<_>>()
    };
    let loads: Vec<_> = (0..responses.len()).map(on_body).collect();
    (responses.par_iter_mut())
        .zip(solvers)
        .zip(&loads)
        .try_for_each(|((response, solver), loads)| response.extend(solver, loads))
}

/// The interface Schur complement `S = D - s C Y`, with `C` and each body's responses `Y` as
/// dense blocks on the dofs `C` reads.
fn schur_complement(system: &CoupledSystem, responses: &[SurfaceResponse]) -> DMatrix<f64> {
    let (m, s) = (system.m, system.s);
    let mut schur = DMatrix::<f64>::from_diagonal(&DVector::from_column_slice(&system.d));
    for &(k, l, value) in &system.d_coupled {
        schur[(k, l)] += value;
    }
    for (body, response) in responses.iter().enumerate() {
        let dofs = system.body_dofs(body);
        let mut read: Vec<usize> = (system.c_entries())
            .filter(|e| dofs.contains(&e.1))
            .map(|e| e.1 - dofs.start)
            .collect();
        read.sort_unstable();
        read.dedup();
        if read.is_empty() || m == 0 {
            continue;
        }
        let position = |dof: usize| read.binary_search(&dof).expect("listed dof");
        let mut c = DMatrix::<f64>::zeros(m, read.len());
        for (k, col, value) in system.c_entries() {
            if dofs.contains(&col) {
                c[(k, position(col - dofs.start))] += value;
            }
        }
        // One hash lookup per multiplier, not per entry: this runs every iteration.
        let rows = response.rows(&read);
        let mut y = DMatrix::<f64>::zeros(read.len(), m);
        let mut part = vec![0.0; read.len()];
        for (k, column) in system.columns.iter().enumerate() {
            for (key, weight) in column {
                if !response.contains(key) {
                    // A unit force that does not reach this body: no response.
                    continue;
                }
                response.gather(key, &rows, &mut part);
                let mut y_k = y.column_mut(k);
                for (value, p) in y_k.iter_mut().zip(&part) {
                    *value += weight * p;
                }
            }
        }
        schur -= (c * y) * s;
    }
    schur
}

#[cfg(test)]
mod tests {
    //! The coupled system of several bodies and pairs against an exact reference: blocks
    //! side by side, tied where they touch on matching nodes, are one block. Three unit squares
    //! in a row (bodies 0, 1, 2; pairs 0-1 and 2-1, body 1 the secondary of both), clamped at
    //! the base and pressed down at the top, give the displacements of the 3 x 1 block meshed
    //! alike; a fourth body in no pair gives its own elastic solution.

    use std::collections::BTreeMap;

    use super::*;
    use crate::contact::coupled::half_space::compliance_factor;
    use crate::contact::coupled::system::Coupling;
    use crate::contact::law::{ContactLaw, Reads, Restates, Tangential};
    use crate::elastic::{
        DirichletCondition, ElasticProblem, SolveStats, StepFactors, assemble, solve,
    };
    use crate::fem::Material;
    use crate::fem::assembly::stiffness_graph;
    use crate::linalg::Distribution;
    use crate::mesh::{BodyMesh, FacetGroup};

    const NX: usize = 4;
    const NY: usize = 6;

    /// `nx` x `NY` squares of side `1/NX` (P1 triangles) from `x0`, height 1, with the groups
    /// `base`, `top`, `left` and `right` (facets, outward right-hand normals).
    fn grid(name: &str, x0: f64, nx: usize) -> BodyMesh {
        let node = |i: usize, j: usize| i + j * (nx + 1);
        let h = 1.0 / NX as f64;
        let mut coords = Vec::new();
        for j in 0..=NY {
            for i in 0..=nx {
                coords.push([x0 + i as f64 * h, j as f64 / NY as f64, 0.0]);
            }
        }
        let mut cells = Vec::new();
        for j in 0..NY {
            for i in 0..nx {
                let [a, b, c, d] = [
                    node(i, j),
                    node(i + 1, j),
                    node(i + 1, j + 1),
                    node(i, j + 1),
                ];
                cells.extend([a, b, c, a, c, d].map(|n| n as u32));
            }
        }
        let cell = |i: usize, j: usize, t: usize| 2 * (i + j * nx) + t;
        let group = |tag: i32, facets: Vec<[usize; 2]>, facet_cells: Vec<usize>| FacetGroup {
            physical_tag: tag,
            facets: facets.concat(),
            facet_cells,
            interior_facets: Vec::new(),
        };
        let mut groups = BTreeMap::new();
        let along = 0..nx;
        let up = 0..NY;
        groups.insert(
            "base".into(),
            group(
                1,
                along
                    .clone()
                    .map(|i| [node(i, 0), node(i + 1, 0)])
                    .collect(),
                along.clone().map(|i| cell(i, 0, 0)).collect(),
            ),
        );
        groups.insert(
            "top".into(),
            group(
                2,
                along
                    .clone()
                    .map(|i| [node(i + 1, NY), node(i, NY)])
                    .collect(),
                along.map(|i| cell(i, NY - 1, 1)).collect(),
            ),
        );
        groups.insert(
            "right".into(),
            group(
                3,
                up.clone().map(|j| [node(nx, j), node(nx, j + 1)]).collect(),
                up.clone().map(|j| cell(nx - 1, j, 0)).collect(),
            ),
        );
        groups.insert(
            "left".into(),
            group(
                4,
                up.clone().map(|j| [node(0, j + 1), node(0, j)]).collect(),
                up.map(|j| cell(0, j, 1)).collect(),
            ),
        );
        BodyMesh {
            name: name.into(),
            physical_tag: 0,
            dim: 2,
            node_tags: (1..=coords.len() as u64).collect(),
            cell_tags: (1..=(cells.len() / 3) as u64).collect(),
            coords: coords.into(),
            cells,
            boundary_groups: groups,
            point_groups: BTreeMap::new(),
            part: None,
        }
    }

    /// Clamped base, top pushed down by `push`.
    fn problem(mesh: &BodyMesh, push: f64) -> ElasticProblem<'_> {
        let material = Material::new(1000.0, 0.3).unwrap();
        let held = |group: &str, components| DirichletCondition {
            group: group.into(),
            components,
            path: None,
        };
        let dirichlet = vec![
            held("base", [Some(0.0), Some(0.0), None]),
            held("top", [None, Some(-push), None]),
        ];
        ElasticProblem::new(mesh, material, dirichlet, Vec::new(), None).unwrap()
    }

    /// Tied coupling of the column `i1` of `primary` (nx1 squares wide) with the column `i2` of
    /// the secondary, on matching nodes.
    fn tied(
        primary: &BodyMesh,
        nx1: usize,
        i1: usize,
        nx2: usize,
        i2: usize,
        normal: f64,
    ) -> Coupling {
        let h = 1.0 / NY as f64;
        let area = |j: usize| if j == 0 || j == NY { h / 2.0 } else { h };
        let primary_nodes: Vec<usize> = (0..=NY).map(|j| i1 + j * (nx1 + 1)).collect();
        let secondary: Vec<usize> = (0..=NY).map(|j| i2 + j * (nx2 + 1)).collect();
        Coupling {
            normals: vec![[normal, 0.0, 0.0]; NY + 1],
            areas1: (0..=NY).map(area).collect(),
            multipliers: vec![
                ContactLaw::Tied.multipliers(
                    [normal, 0.0, 0.0],
                    Tangential::Stick,
                    2,
                    0.0
                );
                NY + 1
            ],
            geometric: vec![Vec::new(); NY + 1],
            interpolated: secondary.iter().map(|&n| vec![(n, 1.0)]).collect(),
            walls: vec![Vec::new(); NY + 1],
            loads2: (0..=NY).map(|j| vec![(secondary[j], area(j))]).collect(),
            gaps: vec![[0.0; 3]; NY + 1],
            points: primary_nodes.iter().map(|&n| primary.coords[n]).collect(),
            primary_nodes,
        }
    }

    /// `coupling` with two multipliers per node along a basis turned by 30 degrees: each reads
    /// both components of the jump and loads both components of the node (shared), and the
    /// second has its own term `compliance` in its row.
    fn turned(mut coupling: Coupling, compliance: f64) -> Coupling {
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        for multipliers in &mut coupling.multipliers {
            for (j, (multiplier, direction)) in
                (multipliers.iter_mut().zip([[c, s, 0.0], [-s, c, 0.0]])).enumerate()
            {
                multiplier.force = direction;
                multiplier.row = direction;
                multiplier.reads = Reads::Interpolated;
                multiplier.restates = Restates::Node;
                multiplier.compliance = if j == 1 { compliance } else { 0.0 };
            }
        }
        coupling
    }

    /// The bodies of `meshes`, each with its top pushed down by its `push`, assembled.
    fn assembled(meshes: &[BodyMesh], pushes: &[f64]) -> Vec<AssembledBody> {
        let mut stats = SolveStats::default();
        (meshes.iter().zip(pushes))
            .map(|(mesh, &push)| assemble(&problem(mesh, push), &mut stats, false).unwrap())
            .collect()
    }

    /// The bodies' factors (Cholesky) for the interface `solver`, on the primary `candidates`,
    /// with `pairs` pairs of one material.
    fn factors(
        bodies: &[&AssembledBody],
        candidates: Vec<Vec<usize>>,
        pairs: usize,
        solver: CoupledSolver,
    ) -> BodyFactors {
        let settings = SolverSettings {
            verbose: false,
            ..SolverSettings::default()
        };
        let material = Material::new(1000.0, 0.3).unwrap();
        let contact = ContactSettings {
            solver,
            ..ContactSettings::default()
        };
        let compliance = vec![compliance_factor([&material, &material], 2); pairs];
        let kind = BodySolverKind::Cholesky;
        BodyFactors::new(
            bodies, candidates, compliance, &settings, kind, &contact, None,
        )
        .unwrap()
    }

    #[test]
    fn bodies_tied_side_by_side_are_one_body_on_every_path() {
        let meshes = [
            grid("left", 0.0, NX),
            grid("middle", 1.0, NX),
            grid("right", 2.0, NX),
            grid("alone", 5.0, NX),
        ];
        let bodies = assembled(&meshes, &[0.01, 0.01, 0.01, 0.02]);
        let bodies: Vec<&AssembledBody> = bodies.iter().collect();
        let couplings = [
            tied(&meshes[0], NX, NX, NX, 0, 1.0),
            tied(&meshes[2], NX, 0, NX, NX, -1.0),
        ];
        let pairs = [
            Pair {
                primary: 0,
                secondary: 1,
                coupling: &couplings[0],
            },
            Pair {
                primary: 2,
                secondary: 1,
                coupling: &couplings[1],
            },
        ];
        let system =
            CoupledSystem::assemble(&bodies, &pairs, 2, &StepFactors::uniform(1.0)).unwrap();

        // The references: the 3 x 1 block, and the fourth body alone.
        let settings = SolverSettings {
            verbose: false,
            ..SolverSettings::default()
        };
        let whole_mesh = grid("whole", 0.0, 3 * NX);
        let whole = solve(&problem(&whole_mesh, 0.01), &settings)
            .unwrap()
            .displacement;
        let alone = solve(&problem(&meshes[3], 0.02), &settings)
            .unwrap()
            .displacement;
        let scale = whole.iter().map(|u| u.abs()).fold(0.0, f64::max);
        let check = |path: &str, x: &[f64]| {
            let solution = system.solution(x, &bodies, &pairs, 2, 0.0);
            for (k, u) in solution.u[..3].iter().enumerate() {
                for j in 0..=NY {
                    for i in 0..=NX {
                        for c in 0..2 {
                            let ours = u[2 * (i + j * (NX + 1)) + c];
                            let exact = whole[2 * (NX * k + i + j * (3 * NX + 1)) + c];
                            assert!(
                                (ours - exact).abs() <= 1e-9 * scale,
                                "{path}: body {k} node ({i}, {j}) component {c}: {ours} vs {exact}"
                            );
                        }
                    }
                }
            }
            let off = (solution.u[3].iter().zip(&alone)).map(|(a, b)| (a - b).abs());
            assert!(
                off.fold(0.0, f64::max) <= 1e-9 * scale,
                "{path}: the body in no pair"
            );
            // Each pair's tractions balance between its bodies: no force is lost.
            let forces = solution.total_forces(2);
            let sum: f64 = forces.iter().map(|f| f[0].abs() + f[1].abs()).sum();
            for c in 0..2 {
                let net: f64 = forces.iter().map(|f| f[c]).sum();
                assert!(net.abs() <= 1e-9 * sum.max(1.0), "{path}: net force {net}");
            }
        };

        check(
            "monolithic LU",
            &solve_monolithic(&system, &bodies).unwrap(),
        );
        let candidates = vec![
            (0..=NY).map(|j| NX + j * (NX + 1)).collect::<Vec<_>>(),
            (0..=NY)
                .flat_map(|j| [j * (NX + 1), NX + j * (NX + 1)])
                .collect(),
            (0..=NY).map(|j| j * (NX + 1)).collect(),
            Vec::new(),
        ];
        for solver in [CoupledSolver::Schur, CoupledSolver::Krylov] {
            let mut factors = factors(&bodies, candidates.clone(), 2, solver);
            let x = factors
                .solve(&system, &pairs, &bodies, Tightness::Tight)
                .unwrap();
            check(solver.name(), &x);
        }
    }

    /// The products the Krylov and Schur paths take without the entries (a unit load shared by
    /// a node's multipliers, a jump read once by its rows: `CoupledSystem::add_b_product`,
    /// `add_c_product`) and a multiplier's own term in its row (`D`, a slipping node's
    /// direction row) give the answer of the monolithic LU, which assembles the entries one
    /// by one; and the answer holds that row, `r . (u1 - u2) + compliance lambda = 0`.
    #[test]
    fn shared_loads_and_reads_and_a_multipliers_own_term_give_the_entries_answer() {
        let meshes = [grid("left", 0.0, NX), grid("right", 1.0, NX)];
        let bodies = assembled(&meshes, &[0.01, 0.02]);
        let bodies: Vec<&AssembledBody> = bodies.iter().collect();
        let compliance = 1e-4;
        let coupling = turned(tied(&meshes[0], NX, NX, NX, 0, 1.0), compliance);
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let pairs = [Pair {
            primary: 0,
            secondary: 1,
            coupling: &coupling,
        }];
        let system =
            CoupledSystem::assemble(&bodies, &pairs, 2, &StepFactors::uniform(1.0)).unwrap();
        // Every node but the clamped one (its multipliers restate its Dirichlet condition).
        assert_eq!(system.shared_jumps.len(), coupling.primary_nodes.len() - 1);
        assert!(
            system
                .unit_loads
                .iter()
                .all(|unit| unit.multipliers.len() == 2)
        );
        let reference = solve_monolithic(&system, &bodies).unwrap();
        let scale = reference.iter().map(|v| v.abs()).fold(0.0, f64::max);
        let candidates = vec![
            (0..=NY).map(|j| NX + j * (NX + 1)).collect::<Vec<_>>(),
            (0..=NY).map(|j| j * (NX + 1)).collect(),
        ];
        for solver in [CoupledSolver::Schur, CoupledSolver::Krylov] {
            let mut factors = factors(&bodies, candidates.clone(), 1, solver);
            let x = (factors.solve(&system, &pairs, &bodies, Tightness::Tight)).unwrap();
            let off = (x.iter().zip(&reference)).map(|(a, b)| (a - b).abs());
            assert!(
                off.fold(0.0, f64::max) <= 1e-8 * scale,
                "{}: off the monolithic answer",
                solver.name()
            );
        }
        let solution = system.solution(&reference, &bodies, &pairs, 2, 0.0);
        let u_scale = (solution.u.iter().flatten()).fold(0.0_f64, |m, u| m.max(u.abs()));
        let mut largest = 0.0_f64;
        for (k, &node) in coupling.primary_nodes.iter().enumerate() {
            let (node2, _) = coupling.interpolated[k][0];
            let jump: Vec<f64> = (0..2)
                .map(|c| solution.u[0][2 * node + c] - solution.u[1][2 * node2 + c])
                .collect();
            let lambda = solution.traction[0][k];
            let along = |d: [f64; 2], v: &[f64]| d[0] * v[0] + d[1] * v[1];
            let held = along([-s, c], &jump) + compliance * along([-s, c], &lambda[..2]);
            assert!(held.abs() <= 1e-9 * u_scale, "node {k}: {held}");
            largest = largest.max(along([-s, c], &lambda[..2]).abs());
        }
        // The own term is not idle: the multiplier carries a traction.
        assert!(largest * compliance > 1e-3 * u_scale, "{largest}");
    }

    /// A distributed run's coupled system holds on each rank the entries of `B` on its rows
    /// and of `C` on its columns, numbered by their place in its Krylov vectors: over the
    /// ranks of 2- and 3-way partitions they make the whole system's products, each row of
    /// `B y` on one rank alone (the same terms in the same order: the same bits) and `C x` as
    /// the sum of the ranks' parts; the multiplier blocks are every rank's.
    #[test]
    fn each_ranks_share_of_the_coupling_blocks_adds_up_to_the_whole() {
        let meshes = [grid("left", 0.0, NX), grid("right", 1.0, NX)];
        let bodies = assembled(&meshes, &[0.01, 0.02]);
        let bodies: Vec<&AssembledBody> = bodies.iter().collect();
        let factors = StepFactors::uniform(1.0);
        for coupling in [
            tied(&meshes[0], NX, NX, NX, 0, 1.0),
            turned(tied(&meshes[0], NX, NX, NX, 0, 1.0), 1e-4),
        ] {
            let pairs = [Pair {
                primary: 0,
                secondary: 1,
                coupling: &coupling,
            }];
            let whole = CoupledSystem::assemble(&bodies, &pairs, 2, &factors).unwrap();
            let (n, m) = (whole.num_displacements(), whole.m);
            let x: Vec<f64> = (0..n).map(|i| (0.37 * i as f64).sin()).collect();
            let y: Vec<f64> = (0..m).map(|k| (0.71 * k as f64).cos()).collect();
            let mut c_whole = vec![0.0; m];
            whole.add_c_product(&x, &mut c_whole);
            let mut b_whole = vec![0.0; n];
            whole.add_b_product(&y, 1.0, &mut b_whole);
            for size in [2, 3] {
                let mut c_sum = vec![0.0; m];
                let mut b_rows = vec![None; n];
                for rank in 0..size {
                    let ranks = crate::parallel::Ranks { rank, size };
                    let distributions: Vec<Distribution> = (meshes.iter())
                        .map(|mesh| {
                            let coords = mesh.coords.flat(mesh.dim);
                            Distribution::new(&stiffness_graph(mesh), &coords, ranks).unwrap()
                        })
                        .collect();
                    let shared: Vec<&Distribution> = distributions.iter().collect();
                    let ownership = RowOwnership::from_distributions(&shared);
                    let system =
                        CoupledSystem::assemble_on(&bodies, &pairs, 2, &factors, Some(&ownership))
                            .unwrap();
                    assert_eq!(system.unknowns, Unknowns::RankRows);
                    assert_eq!(
                        (system.d.clone(), system.g.clone()),
                        (whole.d.clone(), whole.g.clone())
                    );
                    assert!(system.residual(&bodies, None, &x).is_err());
                    // This rank's rows, in the order of its Krylov vectors.
                    let own: Vec<usize> = (distributions.iter().zip(&whole.offsets))
                        .flat_map(|(d, &offset)| d.own().map(move |dof| offset + dof))
                        .collect();
                    // Every unknown placed at its row among this rank's, or nowhere; the
                    // right-hand side held at those rows alone.
                    let mut places = vec![None; n];
                    own.iter()
                        .enumerate()
                        .for_each(|(k, &row)| places[row] = Some(k));
                    let placed: Vec<Option<usize>> = (0..n).map(|i| ownership.place(i)).collect();
                    assert_eq!(placed, places);
                    assert_eq!(ownership.num_local(), own.len());
                    let f_rank: Vec<f64> = own.iter().map(|&row| whole.f[row]).collect();
                    assert_eq!(system.f, f_rank);
                    let x_rank: Vec<f64> = own.iter().map(|&row| x[row]).collect();
                    let mut c_rank = vec![0.0; m];
                    system.add_c_product(&x_rank, &mut c_rank);
                    c_sum
                        .iter_mut()
                        .zip(&c_rank)
                        .for_each(|(sum, part)| *sum += part);
                    let mut b_rank = vec![0.0; own.len()];
                    system.add_b_product(&y, 1.0, &mut b_rank);
                    for (&row, value) in own.iter().zip(b_rank) {
                        assert!(b_rows[row].is_none(), "row {row} on two ranks");
                        b_rows[row] = Some(value);
                    }
                }
                let b_rows: Vec<f64> = b_rows.into_iter().map(Option::unwrap).collect();
                assert_eq!(b_rows, b_whole, "B y on {size} ranks");
                let scale = c_whole.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
                assert!(scale > 0.0);
                let off =
                    (c_sum.iter().zip(&c_whole)).fold(0.0_f64, |a, (s, w)| a.max((s - w).abs()));
                assert!(
                    off <= 1e-14 * scale,
                    "C x on {size} ranks: off by {off:.1e}"
                );
            }
        }
    }

    /// A Krylov solve of the system just solved starts from its answer and needs no iteration,
    /// also where a node's traction is the sum of several multipliers along directions other
    /// than the axes (a sticking Coulomb node's normal and tangent): the start maps the
    /// tractions kept per node and component back onto each multiplier, so each component must
    /// keep the sum of the node's multipliers, not the last one's share.
    #[test]
    fn a_solve_restarted_from_its_own_answer_takes_no_iteration() {
        let meshes = [grid("left", 0.0, NX), grid("right", 1.0, NX)];
        let bodies = assembled(&meshes, &[0.01, 0.01]);
        let bodies: Vec<&AssembledBody> = bodies.iter().collect();
        // The tied coupling of the two columns that meet, between their clamped and pushed
        // ends (where a turned multiplier would restate a prescribed component), its two
        // multipliers per node along a basis turned by 30 degrees.
        let whole = tied(&meshes[0], NX, NX, NX, 0, 1.0);
        let inner = 1..NY;
        let mut coupling = Coupling {
            primary_nodes: whole.primary_nodes[inner.clone()].to_vec(),
            points: whole.points[inner.clone()].to_vec(),
            normals: whole.normals[inner.clone()].to_vec(),
            areas1: whole.areas1[inner.clone()].to_vec(),
            multipliers: whole.multipliers[inner.clone()].to_vec(),
            geometric: whole.geometric[inner.clone()].to_vec(),
            interpolated: whole.interpolated[inner.clone()].to_vec(),
            walls: whole.walls[inner.clone()].to_vec(),
            loads2: whole.loads2[inner.clone()].to_vec(),
            gaps: whole.gaps[inner].to_vec(),
        };
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        for multipliers in &mut coupling.multipliers {
            for (multiplier, direction) in multipliers.iter_mut().zip([[c, s, 0.0], [-s, c, 0.0]]) {
                multiplier.force = direction;
                multiplier.row = direction;
                multiplier.restates = Restates::Node;
            }
        }
        let pairs = [Pair {
            primary: 0,
            secondary: 1,
            coupling: &coupling,
        }];
        let system =
            CoupledSystem::assemble(&bodies, &pairs, 2, &StepFactors::uniform(1.0)).unwrap();
        let candidates = vec![
            (0..=NY).map(|j| NX + j * (NX + 1)).collect::<Vec<_>>(),
            (0..=NY).map(|j| j * (NX + 1)).collect(),
        ];
        let mut factors = factors(&bodies, candidates, 1, CoupledSolver::Krylov);
        let first = (factors.solve(&system, &pairs, &bodies, Tightness::Tight)).unwrap();
        let cold = factors.last_krylov.unwrap();
        assert!(cold.iterations > 0, "{cold:?}");
        let again = (factors.solve(&system, &pairs, &bodies, Tightness::Tight)).unwrap();
        let warm = factors.last_krylov.unwrap();
        assert_eq!(
            warm.iterations, 0,
            "restarted: {warm:?}, first solve: {cold:?}"
        );
        let change = (first.iter().zip(&again)).map(|(a, b)| (a - b).abs());
        let scale = first.iter().map(|v| v.abs()).fold(0.0, f64::max);
        assert!(change.fold(0.0, f64::max) <= 1e-12 * scale);
    }
}
