//! How the coupled system of an iteration is solved, behind one interface.
//!
//! - [`CoupledSolver::Krylov`]: each body's constrained stiffness is factored once
//!   (sparse Cholesky; or CG + AMG set up once, with `[solver] body = "cg-amg"`: see
//!   `crate::linalg::BodySolver`) for the whole contact solve, and every iteration solves
//!   only the interface problem by block elimination:
//!   `z = K^-1 f`, `(D - C K^-1 B) lambda = g - C z`, `u = z - K^-1 (B lambda)`,
//!   the middle equation by preconditioned GMRES ([`super::interface_krylov`]): one solve per
//!   body per product, nothing per multiplier, warm-started from the last iteration's
//!   tractions.
//! - [`CoupledSolver::Schur`]: the same elimination with `C K^-1 B = s C Y` formed densely
//!   from each body's responses `Y_k` to the multipliers ([`super::compliance`]), computed
//!   once per multiplier (`dim` solves per primary node) and reused by every later iteration
//!   and load step; the Schur complement is factored by dense LU with partial pivoting
//!   (interfaces have hundreds to a few thousand multipliers). Each iteration then costs two
//!   single-column solves per body, plus `dim` solves per body for each node that becomes
//!   active for the first time. With CG + AMG body solves each of those columns is a full CG
//!   solve: `schur` then runs the Krylov path.
//! - [`CoupledSolver::Auto`]: Krylov, and Schur after a GMRES failure (below).
//! - [`CoupledSolver::MonolithicLu`]: a sparse LU of the whole unsymmetric matrix, refactored
//!   every iteration; the reference the Schur path is tested against.
//!
//! # Which one: `auto`
//!
//! `auto` (the default) runs the Krylov path and moves to the dense Schur complement for the
//! rest of the solve at the first GMRES failure. The Krylov path is faster wherever it was
//! measured; the dense path is exact whatever the conditioning of the interface problem,
//! which GMRES needs: with a stiff body named primary on a compliant one (E ratio 1e4, 2D
//! R/600 and 3D R/45 foreign meshes), the half-space preconditioner does not tame the
//! interface problem, and GMRES stagnated or reached its cap in 16 of 180 such runs (with
//! `krylov` an error that names it; with `auto` the dense path then solves them, as `schur`
//! does). A failed GMRES solve costs at most its iteration cap in products, which is why the
//! fallback is for the rest of the solve and not retried per iteration.
//!
//! Measured 2026-11-26 on this project's 2-core machine (shared, so within 2x), the contact
//! benchmark's hemisphere on block in one step: wall seconds of the whole process and peak
//! memory; every run converged after the same 8 (99k) and 9 (217k) active-set iterations,
//! with the same active nodes and contact force to the 7 digits printed:
//!
//! | DOFs | schur + Cholesky | krylov + Cholesky | krylov + CG + AMG |
//! |---|---|---|---|
//! | 98,700 | 27 s, 1.7 GB | 19.6 s, 1.3 GB | 52 s, 0.6 GB |
//! | 216,537 | 133 s, 4.4 GB | 42 s, 3.2 GB | 207 s, 1.2 GB |
//!
//! (schur from `validation/CONTACT_BENCHMARK.md` of the same day; the Krylov runs with the
//! loose solves of `super::solve`, which cut GMRES iterations per active-set iteration from
//! 15-25 to 2-10.) CG + AMG loses on time at these sizes: a product costs two CG solves, run
//! one after the other because PETSc calls are serialized, where a factor costs two pairs of
//! triangular solves. It wins on memory, which is what bounds the direct path: the factors
//! grow like `n^(4/3)` (3.2 GB at 217k, 15 GB for one body of 677k DOFs), so `auto` bodies
//! become CG + AMG from [`crate::linalg::AUTO_CG_AMG_MIN_DOFS_CONTACT`] dofs in the larger
//! body (`BodySolverKind::resolve_for_contact`).

use std::io::IsTerminal;

use faer::prelude::*;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use nalgebra::{DMatrix, DVector};

use super::compliance::SurfaceResponse;
use super::interface_krylov::{
    self, Bodies, KRYLOV_RTOL, KRYLOV_RTOL_OVER_BODY_RTOL, KrylovState, KrylovStats, Target,
};
use super::settings::{ContactSettings, CoupledSolver};
use super::system::{CoupledSystem, Coupling};
use super::{ContactError, ContactSurface};
use crate::elastic::AssembledBody;
use crate::elastic::SolverSettings;
use crate::linalg::{BodySolver, BodySolverKind, Cholesky, CholeskySymbolic};

/// The solvers (Cholesky factors, or CG + AMG) of both bodies' constrained stiffness matrices,
/// and what the interface solve keeps between iterations: the bodies' responses to the
/// multipliers computed so far (dense Schur), or the warm start (Krylov).
pub struct BodyFactors {
    factor1: BodySolver,
    factor2: BodySolver,
    /// CG's relative residual (`None` for factors).
    body_rtol: Option<f64>,
    interface: Interface,
    /// The candidate nodes of each body, for the dense Schur path `auto` falls back to.
    fallback: Option<[Vec<usize>; 2]>,
    /// Why the interface solve left GMRES for the dense Schur complement, if it did.
    pub fell_back: Option<String>,
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
        /// GMRES' relative residual target ([`KRYLOV_RTOL`], or
        /// [`KRYLOV_RTOL_OVER_BODY_RTOL`] times CG's `rtol`).
        tolerance: f64,
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
    /// for the interface solve `contact.solver`; the response caches cover the candidate
    /// surfaces.
    pub fn new(
        body1: &AssembledBody,
        body2: &AssembledBody,
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
            _ => CholeskySymbolic::new(&body.pattern, settings.ordering)
                .and_then(|symbolic| Cholesky::factorize(symbolic, &body.k_c))
                .map(BodySolver::Cholesky)
                .map_err(|e| ContactError::Linalg(format!("Cholesky of a body's stiffness: {e}"))),
        };
        // The two set-ups are independent: side by side.
        let (factor1, factor2) = rayon::join(|| factor(body1), || factor(body2));
        let cg = kind == BodySolverKind::CgAmg;
        let krylov = cg || matches!(method, CoupledSolver::Krylov | CoupledSolver::Auto);
        let sizes = [body1.f_c.len(), body2.f_c.len()];
        let interface = if krylov {
            let tolerance = match cg {
                true => KRYLOV_RTOL.max(KRYLOV_RTOL_OVER_BODY_RTOL * settings.rtol),
                false => KRYLOV_RTOL,
            };
            Interface::Krylov {
                state: {
                    let mut state = KrylovState::new(
                        settings.verbose
                            && settings.progress_line
                            && std::io::stderr().is_terminal(),
                    );
                    state.cancel = settings.cancel.clone();
                    state
                },
                tolerance,
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
            body_rtol: cg.then_some(settings.rtol),
            interface,
            fallback,
            fell_back: None,
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

    /// Whether the interface problem is solved by GMRES (whose solves can stop short of
    /// round-off on request: [`Self::solve`]).
    pub fn is_krylov(&self) -> bool {
        matches!(self.interface, Interface::Krylov { .. })
    }

    /// Solves the coupled system of `coupling`; returns `x = [u1; u2; lambda / s]`.
    ///
    /// `gap_tolerance` (a length), on the Krylov path only: GMRES may stop once every active
    /// node's constraint holds its gap to within it, instead of at round-off; the caller
    /// then owns the residual check. A GMRES failure under `auto` moves this and every later
    /// iteration to the dense Schur complement ([`Self::fell_back`] says why).
    pub fn solve(
        &mut self,
        system: &CoupledSystem,
        coupling: &Coupling,
        coordinates1: &[f64],
        gap_tolerance: Option<f64>,
    ) -> Result<Vec<f64>, ContactError> {
        self.last_krylov = None;
        let (state, tolerance, max_iterations) = match &mut self.interface {
            Interface::Dense {
                response1,
                response2,
            } => return solve_schur(system, &self.factor1, &self.factor2, response1, response2),
            Interface::Krylov {
                state,
                tolerance,
                max_iterations,
            } => (state, *tolerance, *max_iterations),
        };
        let bodies = Bodies {
            solver1: &self.factor1,
            solver2: &self.factor2,
            rtol: self.body_rtol,
        };
        let target = Target {
            relative: tolerance,
            absolute: gap_tolerance.map_or(0.0, |gap| system.t * gap),
            max_iterations,
        };
        let dim = self.dim;
        let solved =
            interface_krylov::solve(system, coupling, coordinates1, dim, &bodies, state, target);
        let stats = state.last;
        self.last_krylov = Some(stats);
        if self.verbose {
            // Over a progress line, if one was shown.
            let clear = if state.progress { "\r\x1b[2K" } else { "" };
            log::info!(
                "{clear}    interface GMRES: {} iterations (+{} residuals), relative residual {:.1e} \
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
                if self.verbose {
                    log::info!("    {failure}: the dense Schur complement from here on");
                }
                let sizes = [system.n1, system.n2];
                self.interface = Interface::dense([&nodes1, &nodes2], dim, sizes);
                self.fell_back = Some(failure.to_string());
                self.solve(system, coupling, coordinates1, gap_tolerance)
            }
            (solved, fallback) => {
                self.fallback = fallback;
                solved
            }
        }
    }
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
