//! How the coupled system of an iteration is solved, behind one interface.
//!
//! Each body's solver is set up once for the whole contact solve (a sparse Cholesky factor, or
//! PETSc's AMG: `crate::linalg::BodySolver`); then, per iteration:
//!
//! - [`CoupledSolver::Krylov`]: one restarted GMRES on the whole system, block-preconditioned
//!   by one application of each body's solver and a half-space approximation of the interface
//!   Schur complement ([`super::coupled_krylov`]), warm-started from the last solve.
//! - [`CoupledSolver::Schur`]: the exact reference by elimination, `z = K^-1 f`,
//!   `(D - C K^-1 B) lambda = g - C z`, `u = z - K^-1 (B lambda)`, with `C K^-1 B = s C Y`
//!   formed densely from each body's responses `Y_k` to the multipliers
//!   ([`super::compliance`]), computed once per multiplier (`dim` solves per primary node) and
//!   reused by every later iteration and load step; the Schur complement is factored by dense
//!   LU with partial pivoting (interfaces have hundreds to a few thousand multipliers). With
//!   CG + AMG bodies each of those columns would be a whole CG solve: `schur` then runs the
//!   Krylov path.
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

use std::io::IsTerminal;

use faer::prelude::*;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use nalgebra::{DMatrix, DVector};

use super::compliance::SurfaceResponse;
use super::coupled_krylov::{self, KrylovState, KrylovStats, Tightness};
use super::half_space::compliance_factor;
use super::settings::{ContactSettings, CoupledSolver};
use super::system::{CoupledSystem, Coupling};
use super::{ContactError, ContactSurface};
use crate::elastic::AssembledBody;
use crate::elastic::SolverSettings;
use crate::fem::Material;
use crate::linalg::{BodySolver, BodySolverKind, Cholesky, CholeskySymbolic, Ordering};

/// The solvers (Cholesky factors, or CG + AMG) of both bodies' constrained stiffness matrices,
/// and what the interface solve keeps between iterations: the bodies' responses to the
/// multipliers computed so far (dense Schur), or the warm start (Krylov).
pub struct BodyFactors {
    factor1: BodySolver,
    factor2: BodySolver,
    /// The half-space compliance factor of the two materials (`super::half_space`).
    compliance: f64,
    interface: Interface,
    /// The candidate nodes of each body, for the dense Schur path `auto` falls back to.
    fallback: Option<[Vec<usize>; 2]>,
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
    Dense {
        response1: SurfaceResponse,
        response2: SurfaceResponse,
    },
    Krylov {
        state: KrylovState,
        /// GMRES' iteration cap per solve (`ContactSettings::krylov_max_iterations`).
        max_iterations: usize,
    },
}

impl Interface {
    fn dense(nodes: [&[usize]; 2], dim: usize, sizes: [usize; 2]) -> Self {
        Self::Dense {
            response1: SurfaceResponse::new(nodes[0], dim, sizes[0]),
            response2: SurfaceResponse::new(nodes[1], dim, sizes[1]),
        }
    }
}

impl BodyFactors {
    /// Sets up both bodies' solvers (`kind`: Cholesky or CG + AMG, resolved by the caller)
    /// for the coupled solve `contact.solver`; the response caches cover the candidate
    /// surfaces. `materials` are the two bodies', for the half-space preconditioner.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        body1: &AssembledBody,
        body2: &AssembledBody,
        materials: [&Material; 2],
        surface1: &ContactSurface,
        surface2: &ContactSurface,
        settings: &SolverSettings,
        kind: BodySolverKind,
        contact: &ContactSettings,
    ) -> Result<Self, ContactError> {
        let method = contact.solver;
        let dim = surface1.dim;
        let factor = |body: &AssembledBody| match kind {
            BodySolverKind::CgAmg => {
                BodySolver::cg_amg(&body.k_c, body.dim, &body.coordinates, settings.rtol)
                    .map_err(|e| ContactError::Linalg(format!("CG + AMG of a body: {e}")))
            }
            _ => cholesky(body, settings.ordering),
        };
        // The two set-ups are independent: side by side.
        let (factor1, factor2) = rayon::join(|| factor(body1), || factor(body2));
        let cg = kind == BodySolverKind::CgAmg;
        let krylov = cg || matches!(method, CoupledSolver::Krylov | CoupledSolver::Auto);
        let sizes = [body1.f_c.len(), body2.f_c.len()];
        let interface = if krylov {
            let progress =
                settings.verbose && settings.progress_line && std::io::stderr().is_terminal();
            Interface::Krylov {
                state: KrylovState::new(progress, settings.cancel.clone()),
                max_iterations: contact.krylov_max_iterations,
            }
        } else {
            Interface::dense([&surface1.nodes, &surface2.nodes], dim, sizes)
        };
        let fallback = (method == CoupledSolver::Auto)
            .then(|| [surface1.nodes.clone(), surface2.nodes.clone()]);
        Ok(Self {
            factor1: factor1?,
            factor2: factor2?,
            compliance: compliance_factor(materials, dim),
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
        if let Interface::Dense {
            response1,
            response2,
        } = &mut self.interface
        {
            response1.clear();
            response2.clear();
        }
    }

    /// Whether the coupled system is solved by GMRES (whose solves can stop short of
    /// round-off on request: [`Self::solve`]).
    pub fn is_krylov(&self) -> bool {
        matches!(self.interface, Interface::Krylov { .. })
    }

    /// The bodies' solver (Cholesky after a fallback from CG + AMG).
    pub fn body_kind(&self) -> BodySolverKind {
        self.factor1.kind()
    }

    /// Applications of each body's block of the Krylov preconditioner so far (`None` off the
    /// Krylov path).
    pub fn body_applications(&self) -> Option<[usize; 2]> {
        match &self.interface {
            Interface::Krylov { state, .. } => Some(state.body_applications),
            Interface::Dense { .. } => None,
        }
    }

    /// Solves the coupled system of `coupling`; returns `x = [u1; u2; lambda / s]`.
    ///
    /// On the Krylov path a [`Tightness::Loose`] solve stops at a relative residual the
    /// caller's active-set decision needs, not at round-off; the caller then owns the residual
    /// check. A GMRES failure under `auto` moves this and every later iteration to the dense
    /// Schur complement ([`Self::fell_back`] says why).
    pub fn solve(
        &mut self,
        system: &CoupledSystem,
        coupling: &Coupling,
        bodies: [&AssembledBody; 2],
        tightness: Tightness,
    ) -> Result<Vec<f64>, ContactError> {
        self.last_krylov = None;
        let (state, max_iterations) = match &mut self.interface {
            Interface::Dense {
                response1,
                response2,
            } => return solve_schur(system, &self.factor1, &self.factor2, response1, response2),
            Interface::Krylov {
                state,
                max_iterations,
            } => (state, *max_iterations),
        };
        let dim = self.dim;
        let solved = coupled_krylov::solve(
            system,
            coupling,
            &bodies[0].coordinates,
            dim,
            self.compliance,
            [&self.factor1, &self.factor2],
            [&bodies[0].k_c, &bodies[1].k_c],
            state,
            tightness,
            max_iterations,
        );
        let stats = state.last;
        self.last_krylov = Some(stats);
        if self.verbose {
            // Over a progress line, if one was shown.
            let clear = if state.progress { "\r\x1b[2K" } else { "" };
            log::info!(
                "{clear}    coupled GMRES: {} iterations (+{} residuals), relative residual {:.1e} \
                 (start {:.1e}, target {:.1e})",
                stats.iterations,
                stats.residual_products,
                stats.relative_residual,
                stats.initial_residual,
                stats.tolerance,
            );
        }
        match (solved, self.fallback.take()) {
            (Err(ContactError::Krylov(failure)), Some([nodes1, nodes2])) => {
                // The dense Schur complement solves `dim` systems per body for each active
                // node: with CG + AMG bodies each would be a whole CG solve, so the bodies are
                // factored instead (a factor that does not fit in memory is an error naming it).
                let factored = !matches!(self.factor1, BodySolver::Cholesky(_));
                if self.verbose {
                    let how = if factored {
                        "Cholesky factors of both bodies and "
                    } else {
                        ""
                    };
                    log::info!("    {failure}: {how}the dense Schur complement from here on");
                }
                if factored {
                    let (factor1, factor2) = rayon::join(
                        || cholesky(bodies[0], self.ordering),
                        || cholesky(bodies[1], self.ordering),
                    );
                    (self.factor1, self.factor2) = (factor1?, factor2?);
                }
                let sizes = [system.n1, system.n2];
                self.interface = Interface::dense([&nodes1, &nodes2], dim, sizes);
                self.fell_back = Some(failure.to_string());
                self.solve(system, coupling, bodies, tightness)
            }
            (solved, fallback) => {
                self.fallback = fallback;
                solved
            }
        }
    }
}

/// The Cholesky factor of a body's constrained stiffness.
fn cholesky(body: &AssembledBody, ordering: Ordering) -> Result<BodySolver, ContactError> {
    CholeskySymbolic::new(&body.pattern, ordering)
        .and_then(|symbolic| Cholesky::factorize(symbolic, &body.k_c))
        .map(BodySolver::Cholesky)
        .map_err(|e| ContactError::Linalg(format!("Cholesky of a body's stiffness: {e}")))
}

/// The coupled system solved by one sparse LU of its whole matrix.
pub fn solve_monolithic(
    system: &CoupledSystem,
    body1: &AssembledBody,
    body2: &AssembledBody,
) -> Result<Vec<f64>, ContactError> {
    let matrix = system.matrix(body1, body2)?;
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

fn solve_schur(
    system: &CoupledSystem,
    factor1: &BodySolver,
    factor2: &BodySolver,
    response1: &mut SurfaceResponse,
    response2: &mut SurfaceResponse,
) -> Result<Vec<f64>, ContactError> {
    let (n1, n2, m) = (system.n1, system.n2, system.m);

    // z = K^-1 f.
    let mut z1 = system.f[..n1].to_vec();
    let mut z2 = system.f[n1..].to_vec();
    solve_both([factor1, factor2], [&mut z1, &mut z2])?;

    // S = D - s C Y from the responses Y (the new ones computed first), and r = g - C z.
    extend_responses(
        system,
        [factor1, factor2],
        [&mut *response1, &mut *response2],
    )?;
    let schur = schur_complement(system, [&*response1, &*response2]);
    let mut r = DVector::from_column_slice(&system.g);
    for &(k, col, value) in &system.c {
        r[k] -= value * if col < n1 { z1[col] } else { z2[col - n1] };
    }
    let lambda = if m > 0 {
        schur.lu().solve(&r).ok_or_else(|| {
            ContactError::Linalg("the interface Schur complement is singular".into())
        })?
    } else {
        DVector::zeros(0)
    };

    // u = z - K^-1 (B lambda).
    let mut w1 = vec![0.0; n1];
    let mut w2 = vec![0.0; n2];
    for &(row, k, value) in &system.b {
        if row < n1 {
            w1[row] += value * lambda[k];
        } else {
            w2[row - n1] += value * lambda[k];
        }
    }
    solve_both([factor1, factor2], [&mut w1, &mut w2])?;
    let mut x: Vec<f64> = z1.iter().zip(&w1).map(|(z, w)| z - w).collect();
    x.extend(z2.iter().zip(&w2).map(|(z, w)| z - w));
    x.extend(lambda.iter());
    Ok(x)
}

/// `K1^-1 w1` and `K2^-1 w2` in place; the bodies are independent, so side by side.
fn solve_both(factors: [&BodySolver; 2], [w1, w2]: [&mut Vec<f64>; 2]) -> Result<(), ContactError> {
    let (done1, done2) = rayon::join(
        || factors[0].solve_in_place(w1, 1),
        || factors[1].solve_in_place(w2, 1),
    );
    done1.and(done2).map(|_| ()).map_err(body_solve_error)
}

/// Each body's responses to the unit forces of `system` not seen before (`super::compliance`).
fn extend_responses(
    system: &CoupledSystem,
    factors: [&BodySolver; 2],
    [response1, response2]: [&mut SurfaceResponse; 2],
) -> Result<(), ContactError> {
    let n1 = system.n1;
    let new = |response: &SurfaceResponse, body: usize| {
        (system.unit_loads.iter())
            .filter(|(key, _)| !response.contains(key))
            .map(|(key, load)| {
                let on_body = load.iter().filter_map(|&(row, value)| match body {
                    0 if row < n1 => Some((row, value)),
                    1 if row >= n1 => Some((row - n1, value)),
                    _ => None,
                });
                (*key, on_body.collect())
            })
            .collect::<Vec<_>>()
    };
    let (new1, new2) = (new(response1, 0), new(response2, 1));
    let (done1, done2) = rayon::join(
        || response1.extend(factors[0], &new1),
        || response2.extend(factors[1], &new2),
    );
    done1.and(done2)
}

/// The interface Schur complement `S = D - s C Y`, with `C` and each body's responses `Y` as
/// dense blocks on the dofs `C` reads.
fn schur_complement(system: &CoupledSystem, responses: [&SurfaceResponse; 2]) -> DMatrix<f64> {
    let (n1, n2, m, s) = (system.n1, system.n2, system.m, system.s);
    let mut schur = DMatrix::<f64>::from_diagonal(&DVector::from_column_slice(&system.d));
    for (response, dofs) in responses.into_iter().zip([0..n1, n1..n1 + n2]) {
        let mut read: Vec<usize> = (system.c.iter())
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
        for &(k, col, value) in &system.c {
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
