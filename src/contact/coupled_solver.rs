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
//! - [`CoupledSolver::MonolithicLu`]: a sparse LU of the whole unsymmetric matrix, refactored
//!   every iteration; the reference the Schur path is tested against.
//!
//! # Which one, and what `[solver] body = "auto"` means here
//!
//! Measured 2026-11-26 on this project's 2-core machine, shared (load average about 6 during
//! the runs, so the schur figures are 1.5 to 2.7 times the quiet machine's of
//! `validation/CONTACT_BENCHMARK.md`; the runs of one size were back to back), the contact
//! benchmark's hemisphere on block in one step (`validation/interface_solver_timing.py`):
//! wall seconds of the whole process, and the GMRES iterations of each active-set iteration
//! (the first, on the one node touching at the start, takes one):
//!
//! | DOFs | schur + Cholesky | krylov + Cholesky (GMRES its) | krylov + CG + AMG (GMRES its) |
//! |---|---|---|---|
//! | 31,113 | 9.06 | 7.39 (1, 20, 19, 18, 18, 16, 14) | 12.82 (1, 15, 14, 14, 13, 11, 9) |
//! | 98,700 | 75.9 | 44.3 (1, 23, 21, 21, 20, 19, 17, 14) | 119.8 (1, 17, 15, 15, 14, 13, 12, 8) |
//! | 216,537 | 234.8 | 126.2 (1, 25, 22, 21, 21, 20, 19, 17, 14) | not run |
//!
//! Every run ends converged after the same 7, 8 and 9 active-set iterations per size with
//! the same active nodes (240, 558, 966) and contact force (to the 7 digits printed). The
//! Krylov path on Cholesky factors wins, and more so as the interface grows (1.2, 1.7, 1.9
//! times faster: the dense path pays `dim` solves per new active node, about 3 x 1048 at 99k
//! DOFs, where the first contact iteration makes the whole overlap active). It is not the
//! default yet: with a stiff body named primary on a compliant one (E ratio 1e4, 2D R/600 and
//! 3D R/45 foreign meshes), the half-space preconditioner does not tame the interface
//! problem, and GMRES stagnated or reached its 600 iterations in 16 of 180 such runs (an
//! error that names it, never an answer), where the dense path solves every one; `schur`
//! stays the default until the Krylov path is robust there. CG + AMG loses to Cholesky at these sizes even without per-node solves: a
//! product costs two CG solves (20 to 25 CG iterations each, `crate::linalg::body_solver`)
//! where the factor costs two pairs of triangular solves. So `auto` stays Cholesky for a
//! contact solve (`BodySolverKind::resolve_for_contact`), whichever coupled solver runs.

use faer::prelude::*;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use super::compliance::SurfaceResponse;
use super::interface_krylov::{self, Bodies, KRYLOV_RTOL, KRYLOV_RTOL_OVER_BODY_RTOL, KrylovState};
use super::system::{CoupledSystem, Coupling};
use super::{ContactError, ContactSurface};
use crate::elastic::AssembledBody;
use crate::elastic::SolverSettings;
use crate::linalg::{BodySolver, BodySolverKind, Cholesky, CholeskySymbolic};

#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CoupledSolver {
    /// Cholesky of each body once, dense Schur complement on the multipliers per iteration.
    /// The default: exact whatever the conditioning of the interface problem (below).
    #[default]
    Schur,
    /// Sparse LU of the whole saddle-point matrix per iteration (reference).
    MonolithicLu,
    /// Each body's solver set up once, the interface problem solved matrix-free by
    /// preconditioned GMRES per iteration (also what `schur` runs with CG + AMG bodies).
    /// Faster than `schur` at the contact benchmark's sizes, but not yet the default (module
    /// doc).
    Krylov,
}

/// The solvers (Cholesky factors, or CG + AMG) of both bodies' constrained stiffness matrices,
/// and what the interface solve keeps between iterations: the bodies' responses to the
/// multipliers computed so far (dense Schur), or the warm start (Krylov).
pub struct BodyFactors {
    factor1: BodySolver,
    factor2: BodySolver,
    interface: Interface,
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
    },
}

impl BodyFactors {
    /// Factors both bodies (or sets up CG + AMG: `settings.body`, `auto` being Cholesky
    /// here) for the interface solve `method` (`Schur` or `Krylov`; `Schur` on CG + AMG is
    /// `Krylov`, see the module doc); the response caches cover their candidate surfaces.
    pub fn new(
        body1: &AssembledBody,
        body2: &AssembledBody,
        surface1: &ContactSurface,
        surface2: &ContactSurface,
        settings: &SolverSettings,
        method: CoupledSolver,
    ) -> Result<Self, ContactError> {
        let dim = surface1.dim;
        let kind = settings.body.resolve_for_contact();
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
        // The two factorizations are independent: side by side.
        let (factor1, factor2) = rayon::join(|| factor(body1), || factor(body2));
        let interface = if method == CoupledSolver::Krylov || kind == BodySolverKind::CgAmg {
            let tolerance = match kind {
                BodySolverKind::CgAmg => {
                    KRYLOV_RTOL.max(KRYLOV_RTOL_OVER_BODY_RTOL * settings.rtol)
                }
                _ => KRYLOV_RTOL,
            };
            Interface::Krylov {
                state: KrylovState::default(),
                tolerance,
            }
        } else {
            Interface::Dense {
                response1: SurfaceResponse::new(&surface1.nodes, dim, body1.f_c.len()),
                response2: SurfaceResponse::new(&surface2.nodes, dim, body2.f_c.len()),
            }
        };
        Ok(Self {
            factor1: factor1?,
            factor2: factor2?,
            interface,
            verbose: settings.verbose,
        })
    }
}

impl BodyFactors {
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
}

/// Solves the coupled system of `coupling` (on bodies of dimension `dim`); returns
/// `x = [u1; u2; lambda / s]`.
pub fn solve(
    system: &CoupledSystem,
    coupling: &Coupling,
    dim: usize,
    body1: &AssembledBody,
    body2: &AssembledBody,
    factors: Option<&mut BodyFactors>,
) -> Result<Vec<f64>, ContactError> {
    let Some(factors) = factors else {
        return solve_monolithic(system, body1, body2);
    };
    let BodyFactors {
        factor1,
        factor2,
        interface,
        verbose,
    } = factors;
    match interface {
        Interface::Dense {
            response1,
            response2,
        } => solve_schur(system, factor1, factor2, response1, response2),
        Interface::Krylov { state, tolerance } => {
            let bodies = Bodies {
                solver1: factor1,
                solver2: factor2,
            };
            let x = interface_krylov::solve(
                system,
                coupling,
                &body1.coordinates,
                dim,
                &bodies,
                state,
                *tolerance,
            )?;
            if *verbose {
                let stats = state.last;
                eprintln!(
                    "    interface GMRES: {} iterations (+{} residuals), relative residual \
                     {:.1e} (start {:.1e})",
                    stats.iterations,
                    stats.residual_products,
                    stats.relative_residual,
                    stats.initial_residual
                );
            }
            Ok(x)
        }
    }
}

fn solve_monolithic(
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
    let (n1, n2, m, s) = (system.n1, system.n2, system.m, system.s);

    // z = K^-1 f. The bodies are independent: solved side by side.
    let mut z1 = system.f[..n1].to_vec();
    let mut z2 = system.f[n1..].to_vec();
    let (done1, done2) = rayon::join(
        || factor1.solve_in_place(&mut z1, 1),
        || factor2.solve_in_place(&mut z2, 1),
    );
    done1.and(done2).map_err(body_solve_error)?;

    // The responses to the unit forces not seen before (`super::compliance`).
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
        || response1.extend(factor1, &new1),
        || response2.extend(factor2, &new2),
    );
    done1.and(done2)?;

    // S = D - s C Y, and r = g - C z; C and Y as dense blocks on the dofs C reads.
    let mut schur = DMatrix::<f64>::from_diagonal(&DVector::from_column_slice(&system.d));
    for (response, dofs) in [(&*response1, 0..n1), (&*response2, n1..n1 + n2)] {
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
    let (done1, done2) = rayon::join(
        || factor1.solve_in_place(&mut w1, 1),
        || factor2.solve_in_place(&mut w2, 1),
    );
    done1.and(done2).map_err(body_solve_error)?;
    let mut x: Vec<f64> = z1.iter().zip(&w1).map(|(z, w)| z - w).collect();
    x.extend(z2.iter().zip(&w2).map(|(z, w)| z - w));
    x.extend(lambda.iter());
    Ok(x)
}
