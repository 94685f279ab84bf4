//! The interface problem solved matrix-free: `S lambda = r`, `S = D - C K^-1 B`,
//! `r = g - C z`, `z = K^-1 f` (`docs/method.md` 2.6), by right-preconditioned restarted GMRES,
//! where each product `S v = D v - C K^-1 (B v)` costs one solve per body with whichever body
//! solver is set up (Cholesky factor, or CG + AMG). Nothing is computed per multiplier: an
//! active-set iteration costs `z`, the Krylov iterations and one product per restart cycle
//! (whose `K^-1 B lambda` gives `u = z - K^-1 B lambda` of the final cycle for free), one
//! solve per body each.
//!
//! # Why GMRES, written here
//!
//! `S` is not symmetric: the constraint rows `C` are node to segment, the transfer in `B` is
//! RBF-based (or the lumped mass). faer 0.24's matrix-free module (`faer::operator`) offers
//! BiCGSTAB but no GMRES, and its `LinOp::apply` is infallible and `Sync`: a CG body solve
//! can fail, and that failure must reach the caller as an error, not a panic. GMRES also
//! minimizes the residual over the Krylov space, so it needs the fewest products (the body
//! solves, all the cost; the `O(m k^2)` orthogonalization on `m` multipliers is nothing
//! beside them), where BiCGSTAB spends two per iteration and does not decrease monotonically.
//!
//! # Preconditioner: the half-space compliance of the active nodes
//!
//! `S` maps tractions to gaps: `(S lambda)_k ~ t s sum_l (e_k . e_l) w(x_k, x_l) A_l lambda_l`,
//! the displacement a traction `lambda_l e_l` on area `A_l` at `x_l` produces at `x_k` in
//! the direction `e_k` of multiplier `k` (the facet normal for frictionless contact, an axis
//! for tied), `t`, `s` the system's scalings. Its spectrum spans the ratio of the contact
//! zone to the spacing (the compliance operator is of order -1), so a diagonal preconditioner
//! leaves iteration counts growing under refinement. The preconditioner is the same operator
//! for two elastic half-spaces (Boussinesq; Johnson, *Contact Mechanics*, 1985, 3.2 and 2.2),
//! with every material constant dropped (a common factor does not change GMRES' iterates),
//! on the active nodes' reference positions:
//!
//! ```text
//! P_kl = (e_k . e_l) G_kl A_l,
//!   3D: G_kl = 1 / |x_k - x_l|,              G_kk = 2 / a_k,              a_k = (A_k / pi)^(1/2)
//!   2D: G_kl = -ln(|x_k - x_l| / L),          G_kk = 1 - ln(a_k / L),      a_k = A_k / 2
//! ```
//!
//! The self terms are the centre displacement under a uniform traction on a disc (3D) or a
//! segment (2D) of the node's area; `L` is twice the diagonal of the active nodes' bounding
//! box plus the largest `a_k` (the 2D half-plane displacement is defined up to a constant; a
//! length well above the zone's keeps the logarithmic kernel positive definite). The tangential
//! (Cerruti) compliance is taken equal to the normal one: within a factor `2(1 - nu)/(2 - nu)`
//! of it, which the Krylov iteration absorbs. `P` is dense and factored by LU once per
//! iteration (`m` is hundreds to a few thousand: `m^3 / 3` multiply-adds, 4e8 for the 1048
//! multipliers of the largest active set at the contact benchmark's 99k DOFs).
//!
//! Measured on the hemisphere on block (`validation/interface_solver_timing.py`, Cholesky
//! bodies, one step), the most GMRES iterations of an active-set iteration, with this
//! preconditioner and without any (identity):
//!
//! | DOFs | 7,821 | 19,485 | 31,113 | 98,700 | 216,537 |
//! |---|---|---|---|---|---|
//! | contact-zone spacing | R/47 | R/67 | R/79 | R/120 | R/159 |
//! | half-space | 20 | 21 | 20 | 23 | 25 |
//! | none | 42 | 47 | 50 | not run | not run |
//!
//! It halves the count, which is not flat either: it grows slowly, by 5 over a 3.4 times
//! finer spacing. Without it the count grows with the spacing (42 to 50 over 1.7 times,
//! where the preconditioned count stays at 20).
//! Multipliers that only restate a Dirichlet
//! condition (`D_kk != 0`, no coupling) are solved exactly by the starting guess,
//! `lambda_k = r_k / D_kk`, and stay out of the iteration.
//!
//! # Warm start and stopping
//!
//! The iteration starts from the previous active-set iteration's tractions mapped by node and
//! component (a multiplier that is new starts at 0), projected on the multiplier's direction:
//! `lambda_k = (e_k . t_node) / s`.
//! It stops when the true residual `|r - S lambda|` (recomputed at every restart, not the
//! Arnoldi estimate) is at most `max(tol |r|, absolute)` ([`Target`]): `tol` is round-off
//! ([`KRYLOV_RTOL`]), `absolute` is zero or, on a loose solve, `t` times the gap accuracy the
//! active-set update needs (`super::solve`). A solve that does not get there ends in a
//! [`KrylovError`] naming why: the iteration cap, a restart cycle that did not reduce the
//! true residual (inexact products, e.g. CG's, set a floor), or a non-finite value.

use std::collections::HashMap;
use std::fmt;

use faer::Mat;
use faer::prelude::*;
use thiserror::Error;

use super::ContactError;
use super::compliance::MultiplierKey;
use super::system::{CoupledSystem, Coupling};
use crate::cancel::Cancel;
use crate::linalg::BodySolver;

/// Relative residual `|r - S lambda| / |r|` the GMRES solve stops at with exact (Cholesky)
/// body solves. Why 1e-12: the answer then matches the dense Schur solve's to 1e-14 to 1e-12
/// (forces, displacements) and 1e-12 to 7e-11 (pressures) relative on the fixtures of
/// `tests/contact_solvers.rs`, two orders and more below the 1e-8 the tests ask; the error is about
/// `cond(S)` times the residual, so 1e-10 would leave pressures near that bound.
pub const KRYLOV_RTOL: f64 = 1e-12;

/// With CG + AMG body solves, each product is exact only to the body solver's `rtol`; GMRES'
/// true residual cannot go much below it, so the tolerance is this many times `rtol` (1e-9
/// at the default 1e-10, inside the coupled system's residual check of 1e-8).
pub const KRYLOV_RTOL_OVER_BODY_RTOL: f64 = 10.0;

/// Krylov vectors kept before a restart: `m x 150` values, and past iteration counts stay
/// well below it (a restart only costs one extra product, the true residual).
const RESTART: usize = 150;

/// A restart cycle must bring the true residual below this fraction of the one it started
/// from; otherwise the iteration has stagnated.
const STAGNATION: f64 = 0.9;

/// Why the interface Krylov solve stopped without converging.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KrylovFailure {
    /// [`Target::max_iterations`] products were spent.
    IterationLimit,
    /// A restart cycle did not reduce the true residual (inexact body solves set a floor).
    Stagnated,
    /// A product or the preconditioner produced a non-finite value.
    NotFinite,
}

impl fmt::Display for KrylovFailure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::IterationLimit => {
                "iteration limit reached: [contact] krylov_max_iterations; raise it, or let \
                 solver = \"auto\" move to the dense Schur complement"
            }
            Self::Stagnated => "stagnated: a restart cycle did not reduce the true residual",
            Self::NotFinite => "a non-finite value appeared",
        })
    }
}

/// The interface Krylov solve failed.
#[derive(Debug, Error, Clone, PartialEq)]
#[error(
    "interface GMRES did not converge ({reason}) after {iterations} iterations: relative \
     residual {residual:.2e} > {tolerance:.0e}"
)]
pub struct KrylovError {
    pub reason: KrylovFailure,
    pub iterations: usize,
    pub residual: f64,
    pub tolerance: f64,
}

/// What the last interface Krylov solve did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct KrylovStats {
    /// Krylov iterations (one product with `S`, one solve per body, each).
    pub iterations: usize,
    /// Products spent on true residuals (the starting one and one per restart cycle).
    pub residual_products: usize,
    /// `|r - S lambda| / |r|` at the end.
    pub relative_residual: f64,
    /// The relative residual of the starting guess (1 without a warm start).
    pub initial_residual: f64,
    /// The relative residual it was asked for ([`Target`] over `|r|`).
    pub tolerance: f64,
}

/// What the Krylov path keeps between active-set iterations and load steps.
#[derive(Default)]
pub struct KrylovState {
    /// `K^-1 f` and the load factor it was solved at: the loads and prescribed displacements
    /// enter `f` linearly, so every iteration and load step's `z` is a multiple of it, solved
    /// once per contact solve.
    load_response: Option<(f64, Vec<f64>)>,
    /// Traction of the last solve per (primary node, component), unscaled.
    tractions: HashMap<MultiplierKey, f64>,
    /// The last solve's figures.
    pub last: KrylovStats,
    /// Whether a solve over [`PROGRESS_AFTER`] rewrites a progress line on the terminal.
    pub progress: bool,
    /// Checked at each GMRES iteration.
    pub cancel: Cancel,
}

impl KrylovState {
    /// Nothing kept yet; `progress` as [`KrylovState::progress`].
    pub fn new(progress: bool) -> Self {
        Self {
            progress,
            ..Self::default()
        }
    }
}

/// A GMRES solve running longer than this (seconds) shows its progress (iterations, the
/// residual estimate, the time) on one line, when [`KrylovState::progress`] is set.
const PROGRESS_AFTER: f64 = 2.0;

/// The two bodies' solvers.
#[derive(Clone, Copy)]
pub struct Bodies<'a> {
    pub solver1: &'a BodySolver,
    pub solver2: &'a BodySolver,
    /// The relative residual of CG body solves (`None`: exact, or as they were set up).
    pub rtol: Option<f64>,
}

impl Bodies<'_> {
    /// `[K1^-1 w[..n1]; K2^-1 w[n1..]]`, in place, the bodies side by side.
    fn solve(&self, w: &mut [f64], n1: usize) -> Result<(), ContactError> {
        let (w1, w2) = w.split_at_mut(n1);
        let (done1, done2) = rayon::join(
            || self.solver1.solve_in_place_within(w1, 1, self.rtol),
            || self.solver2.solve_in_place_within(w2, 1, self.rtol),
        );
        done1
            .and(done2)
            .map(|_| ())
            .map_err(|e| ContactError::Linalg(format!("a body's solve: {e}")))
    }
}

/// `S v` and the body response `K^-1 B v` it was formed from.
fn product(
    system: &CoupledSystem,
    bodies: &Bodies,
    v: &[f64],
) -> Result<(Vec<f64>, Vec<f64>), ContactError> {
    let n = system.n1 + system.n2;
    let mut w = vec![0.0; n];
    for &(row, k, value) in &system.b {
        w[row] += value * v[k];
    }
    bodies.solve(&mut w, system.n1)?;
    let mut sv: Vec<f64> = system.d.iter().zip(v).map(|(d, x)| d * x).collect();
    for &(k, col, value) in &system.c {
        sv[k] -= value * w[col];
    }
    Ok((sv, w))
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The half-space preconditioner of the module doc on the coupled multipliers, LU-factored.
struct HalfSpace {
    /// The multipliers it acts on (`D_kk = 0`).
    coupled: Vec<usize>,
    lu: faer::linalg::solvers::PartialPivLu<f64>,
}

impl HalfSpace {
    fn new(system: &CoupledSystem, coupling: &Coupling, coordinates: &[f64], dim: usize) -> Self {
        let area: HashMap<usize, f64> = (coupling.primary_nodes.iter().copied())
            .zip(coupling.areas1.iter().copied())
            .collect();
        // Node, direction and area of each coupled multiplier (its column of B combines the
        // components of one node's traction).
        let mut coupled = Vec::new();
        let mut points = Vec::new();
        for (k, column) in system.columns.iter().enumerate() {
            let Some(((node, _), _)) = column.first() else {
                continue;
            };
            if system.d[k] != 0.0 {
                continue;
            }
            let mut e = [0.0; 3];
            for ((_, c), weight) in column {
                if let Some(c) = c {
                    e[*c] = *weight;
                }
            }
            let mut x = [0.0; 3];
            x[..dim].copy_from_slice(&coordinates[dim * node..dim * node + dim]);
            let a = area.get(node).copied().unwrap_or(0.0);
            coupled.push(k);
            points.push((x, e, a));
        }
        let radius = |a: f64| match dim {
            3 => (a / std::f64::consts::PI).sqrt(),
            _ => a / 2.0,
        };
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for (x, _, _) in &points {
            for c in 0..dim {
                lo[c] = lo[c].min(x[c]);
                hi[c] = hi[c].max(x[c]);
            }
        }
        let diagonal = (0..dim)
            .map(|c| (hi[c] - lo[c]).powi(2))
            .sum::<f64>()
            .sqrt();
        let largest = (points.iter().map(|p| radius(p.2))).fold(0.0, f64::max);
        let length = 2.0 * diagonal + largest;
        let kernel = |r: f64| {
            if dim == 3 {
                1.0 / r
            } else {
                -(r / length).ln()
            }
        };
        let self_term = |a: f64| {
            if dim == 3 {
                2.0 / a
            } else {
                1.0 - (a / length).ln()
            }
        };
        let p = Mat::<f64>::from_fn(points.len(), points.len(), |i, j| {
            let ((xi, ei, ai), (xj, ej, aj)) = (&points[i], &points[j]);
            let along: f64 = (0..3).map(|c| ei[c] * ej[c]).sum();
            if along == 0.0 {
                return 0.0;
            }
            let r = (0..3).map(|c| (xi[c] - xj[c]).powi(2)).sum::<f64>().sqrt();
            // Distinct nodes of a mesh never coincide; the same node's components have
            // orthogonal directions, so only the self term is left.
            let g = if i == j || r == 0.0 {
                self_term(radius(*ai))
            } else {
                kernel(r)
            };
            along * g * aj
        });
        Self {
            coupled,
            lu: p.partial_piv_lu(),
        }
    }

    /// `P^-1 v` on the coupled multipliers (the others are zero in every Krylov vector).
    fn apply(&self, v: &[f64]) -> Vec<f64> {
        let mut rhs = Mat::<f64>::from_fn(self.coupled.len(), 1, |i, _| v[self.coupled[i]]);
        self.lu.solve_in_place(rhs.as_mut());
        let mut out = vec![0.0; v.len()];
        for (i, &k) in self.coupled.iter().enumerate() {
            out[k] = rhs[(i, 0)];
        }
        out
    }
}

/// How far an interface solve goes: GMRES stops at `|r - S lambda| <= max(relative |r|,
/// absolute)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Target {
    pub relative: f64,
    /// In the units of the scaled constraint rows (`t` times a length).
    pub absolute: f64,
    /// The most products with `S` (Krylov iterations) the solve may take
    /// (`ContactSettings::krylov_max_iterations`).
    pub max_iterations: usize,
}

/// Solves the coupled system by elimination with the interface problem solved by GMRES to
/// `target`; returns `x = [u1; u2; lambda / s]` and updates the warm start in `state`.
///
/// CG body solves inside the iteration stop at the relative residual the target allows
/// (`KRYLOV_RTOL_OVER_BODY_RTOL` below it), never below `bodies.rtol`: an inexact product
/// perturbs the Krylov relation by about its relative error, so solves ten times more
/// accurate than the interface solve needs cost nothing in accuracy, and a loose target
/// (an active-set iteration whose decisions only need the gaps to a fraction of the
/// penetration tolerance) saves CG iterations as well as GMRES iterations.
#[allow(clippy::too_many_arguments)]
pub fn solve(
    system: &CoupledSystem,
    coupling: &Coupling,
    coordinates1: &[f64],
    dim: usize,
    bodies: &Bodies,
    state: &mut KrylovState,
    target: Target,
) -> Result<Vec<f64>, ContactError> {
    let (n1, n2, m) = (system.n1, system.n2, system.m);
    let z = load_response(system, bodies, state)?;
    let r = interface_rhs(system, &z);
    let r_norm = norm(&r);
    let tolerance = if r_norm > 0.0 {
        target.relative.max(target.absolute / r_norm)
    } else {
        target.relative
    };
    let inner = Bodies {
        rtol: (bodies.rtol).map(|rtol| rtol.max(tolerance / KRYLOV_RTOL_OVER_BODY_RTOL)),
        ..*bodies
    };
    let mut lambda = starting_guess(system, &r, state);

    let mut stats = KrylovStats {
        tolerance,
        ..KrylovStats::default()
    };
    let w = if m == 0 || r_norm == 0.0 {
        // r = 0: lambda = 0 exactly, and so is its response.
        lambda.fill(0.0);
        vec![0.0; n1 + n2]
    } else {
        let preconditioner = HalfSpace::new(system, coupling, coordinates1, dim);
        let monitor = Monitor {
            started: std::time::Instant::now(),
            progress: state.progress,
            tolerance,
            cancel: state.cancel.clone(),
        };
        gmres(
            system,
            &inner,
            &preconditioner,
            &r,
            &mut lambda,
            target.max_iterations,
            &mut stats,
            &monitor,
        )?
    };
    state.last = stats;
    keep_tractions(system, &lambda, state);

    // u = z - K^-1 (B lambda), the response of the last true residual.
    let mut x: Vec<f64> = z.iter().zip(&w).map(|(z, w)| z - w).collect();
    debug_assert_eq!(x.len(), n1 + n2);
    x.extend(&lambda);
    Ok(x)
}

/// `z = K^-1 f`: a multiple of the last load step's, solved once per contact solve.
fn load_response(
    system: &CoupledSystem,
    bodies: &Bodies,
    state: &mut KrylovState,
) -> Result<Vec<f64>, ContactError> {
    Ok(match &state.load_response {
        Some((factor, z)) if *factor != 0.0 => {
            let scale = system.load_factor / factor;
            z.iter().map(|z| scale * z).collect()
        }
        _ => {
            let mut z = system.f.clone();
            bodies.solve(&mut z, system.n1)?;
            state.load_response = Some((system.load_factor, z.clone()));
            z
        }
    })
}

/// The right-hand side of the interface problem, `r = g - C z`.
fn interface_rhs(system: &CoupledSystem, z: &[f64]) -> Vec<f64> {
    let mut r = system.g.clone();
    for &(k, col, value) in &system.c {
        r[k] -= value * z[col];
    }
    r
}

/// The starting guess: the last tractions along each multiplier's direction, and the
/// uncoupled multipliers' exact values.
fn starting_guess(system: &CoupledSystem, r: &[f64], state: &KrylovState) -> Vec<f64> {
    let mut lambda = vec![0.0; system.m];
    for (k, column) in system.columns.iter().enumerate() {
        if system.d[k] != 0.0 {
            lambda[k] = r[k] / system.d[k];
            continue;
        }
        let (mut along, mut weights) = (0.0, 0.0);
        for (key, weight) in column {
            along += weight * state.tractions.get(key).copied().unwrap_or(0.0);
            weights += weight * weight;
        }
        if weights > 0.0 {
            lambda[k] = along / (weights * system.s);
        }
    }
    lambda
}

/// Keeps the tractions of `lambda` for the next iteration's start.
fn keep_tractions(system: &CoupledSystem, lambda: &[f64], state: &mut KrylovState) {
    state.tractions.clear();
    for (k, column) in system.columns.iter().enumerate() {
        for (key, weight) in column {
            state.tractions.insert(*key, system.s * lambda[k] * weight);
        }
    }
}

/// What a GMRES solve reports as it goes: its progress line, and why it failed.
struct Monitor {
    started: std::time::Instant,
    /// [`KrylovState::progress`].
    progress: bool,
    /// The relative residual asked for.
    tolerance: f64,
    /// [`KrylovState::cancel`].
    cancel: Cancel,
}

impl Monitor {
    /// Rewrites the terminal line with the iterations and the residual `estimate`, once the
    /// solve has run [`PROGRESS_AFTER`]; the caller's summary line replaces it.
    fn show(&self, stats: &KrylovStats, estimate: f64) {
        let seconds = self.started.elapsed().as_secs_f64();
        if self.progress && seconds > PROGRESS_AFTER {
            eprint!(
                "\r\x1b[2K    interface GMRES: {} iterations, residual ~{estimate:.1e} (target \
                 {:.1e}), {seconds:.1} s",
                stats.iterations, self.tolerance
            );
        }
    }

    fn failure(&self, reason: KrylovFailure, stats: &KrylovStats, residual: f64) -> ContactError {
        ContactError::from(KrylovError {
            reason,
            iterations: stats.iterations,
            residual,
            tolerance: self.tolerance,
        })
    }
}

/// Restarted GMRES, right-preconditioned (so the residual it minimizes is the true one, not a
/// preconditioned one), modified Gram-Schmidt with Givens rotations. `lambda` holds the
/// starting guess and receives the solution; returns `K^-1 B lambda` of the solution.
#[allow(clippy::too_many_arguments)]
fn gmres(
    system: &CoupledSystem,
    bodies: &Bodies,
    preconditioner: &HalfSpace,
    r: &[f64],
    lambda: &mut [f64],
    max_iterations: usize,
    stats: &mut KrylovStats,
    monitor: &Monitor,
) -> Result<Vec<f64>, ContactError> {
    let m = r.len();
    let r_norm = norm(r);
    let target = monitor.tolerance * r_norm;
    let mut last_beta = f64::INFINITY;
    loop {
        // The true residual of the current iterate.
        let (s_lambda, w) = product(system, bodies, lambda)?;
        stats.residual_products += 1;
        let residual: Vec<f64> = r.iter().zip(&s_lambda).map(|(a, b)| a - b).collect();
        let beta = norm(&residual);
        stats.relative_residual = beta / r_norm;
        if stats.residual_products == 1 {
            stats.initial_residual = stats.relative_residual;
        }
        if !beta.is_finite() {
            return Err(monitor.failure(KrylovFailure::NotFinite, stats, beta / r_norm));
        }
        if beta <= target {
            return Ok(w);
        }
        if stats.iterations >= max_iterations {
            return Err(monitor.failure(KrylovFailure::IterationLimit, stats, beta / r_norm));
        }
        if beta > STAGNATION * last_beta {
            return Err(monitor.failure(KrylovFailure::Stagnated, stats, beta / r_norm));
        }
        last_beta = beta;

        let steps = RESTART.min(m).min(max_iterations - stats.iterations);
        let cycle = ArnoldiCycle {
            system,
            bodies,
            preconditioner,
            r_norm,
            target,
            monitor,
        };
        cycle.run(&residual, beta, steps, stats)?.add_to(lambda);
    }
}

/// One restart cycle of [`gmres`]: what it multiplies by, and where it stops.
struct ArnoldiCycle<'a> {
    system: &'a CoupledSystem,
    bodies: &'a Bodies<'a>,
    preconditioner: &'a HalfSpace,
    /// `|r|`, the scale of the relative residuals reported.
    r_norm: f64,
    /// The absolute residual the solve stops at.
    target: f64,
    monitor: &'a Monitor,
}

/// The least-squares problem a cycle leaves: `H y = g` (`H` upper triangular after the Givens
/// rotations) over the directions `Z = P^-1 V`.
struct CycleResult {
    directions: Vec<Vec<f64>>,
    h: Vec<Vec<f64>>,
    g: Vec<f64>,
    /// The columns of `H` filled.
    used: usize,
}

impl ArnoldiCycle<'_> {
    /// The Arnoldi basis `V` of `S P^-1` from `residual` (of norm `beta`), at most `steps`
    /// vectors, with `H` rotated as it grows so that `|g[j + 1]|` is the residual's estimate.
    fn run(
        &self,
        residual: &[f64],
        beta: f64,
        steps: usize,
        stats: &mut KrylovStats,
    ) -> Result<CycleResult, ContactError> {
        let mut basis: Vec<Vec<f64>> = vec![residual.iter().map(|x| x / beta).collect()];
        let mut directions: Vec<Vec<f64>> = Vec::new();
        let mut h = vec![vec![0.0; steps]; steps + 1];
        let (mut cs, mut sn) = (vec![0.0; steps], vec![0.0; steps]);
        let mut g = vec![0.0; steps + 1];
        g[0] = beta;
        let mut used = 0;
        for j in 0..steps {
            self.monitor.cancel.check()?;
            let zj = self.preconditioner.apply(&basis[j]);
            let (mut v, _) = product(self.system, self.bodies, &zj)?;
            stats.iterations += 1;
            directions.push(zj);
            orthogonalize(&mut v, &basis, &mut h, j);
            let next = norm(&v);
            h[j + 1][j] = next;
            apply_rotations(&mut h, &cs, &sn, j);
            let (a, b) = (h[j][j], h[j + 1][j]);
            let rho = a.hypot(b);
            if !rho.is_finite() {
                let residual = beta / self.r_norm;
                return Err(self
                    .monitor
                    .failure(KrylovFailure::NotFinite, stats, residual));
            }
            (cs[j], sn[j]) = if rho > 0.0 {
                (a / rho, b / rho)
            } else {
                (1.0, 0.0)
            };
            h[j][j] = rho;
            h[j + 1][j] = 0.0;
            g[j + 1] = -sn[j] * g[j];
            g[j] *= cs[j];
            used = j + 1;
            self.monitor.show(stats, g[j + 1].abs() / self.r_norm);
            // Half the target, so that the true residual, recomputed next, passes too.
            if g[j + 1].abs() <= 0.5 * self.target || next == 0.0 {
                break;
            }
            basis.push(v.iter().map(|x| x / next).collect());
        }
        Ok(CycleResult {
            directions,
            h,
            g,
            used,
        })
    }
}

/// Modified Gram-Schmidt of `v` against `basis`, twice: the basis stays orthogonal to
/// round-off however many vectors it holds. The coefficients accumulate in column `j` of `h`.
fn orthogonalize(v: &mut [f64], basis: &[Vec<f64>], h: &mut [Vec<f64>], j: usize) {
    for _ in 0..2 {
        for (i, q) in basis.iter().enumerate() {
            let c = dot(v, q);
            h[i][j] += c;
            for (vi, qi) in v.iter_mut().zip(q) {
                *vi -= c * qi;
            }
        }
    }
}

/// The earlier Givens rotations `(cs, sn)[..j]` applied to the new column `j` of `h`.
fn apply_rotations(h: &mut [Vec<f64>], cs: &[f64], sn: &[f64], j: usize) {
    for i in 0..j {
        let (a, b) = (h[i][j], h[i + 1][j]);
        h[i][j] = cs[i] * a + sn[i] * b;
        h[i + 1][j] = -sn[i] * a + cs[i] * b;
    }
}

impl CycleResult {
    /// `lambda += Z y`, `y = H^-1 g` by back substitution.
    fn add_to(&self, lambda: &mut [f64]) {
        let (h, g, used) = (&self.h, &self.g, self.used);
        let mut y = vec![0.0; used];
        for i in (0..used).rev() {
            let tail: f64 = (i + 1..used).map(|k| h[i][k] * y[k]).sum();
            y[i] = if h[i][i] != 0.0 {
                (g[i] - tail) / h[i][i]
            } else {
                0.0
            };
        }
        for (yi, zi) in y.iter().zip(&self.directions) {
            for (l, z) in lambda.iter_mut().zip(zi) {
                *l += yi * z;
            }
        }
    }
}
