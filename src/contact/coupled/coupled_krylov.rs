//! The coupled system of an active-set iteration solved as a whole by one preconditioned Krylov
//! solve (`docs/method.md` 2.6):
//!
//! ```text
//! A = [ K  B ]   x = [u; lambda / s],   A x = [f; g]      (crate::contact::coupled::system)
//!     [ C  D ]
//! ```
//!
//! by restarted GMRES (`crate::linalg::gmres`; `A` is not symmetric: the constraint rows are node
//! to segment, the transfer is RBF-based), right-preconditioned by the block upper triangular
//!
//! ```text
//! P = [ K~  B  ]     P^-1 [r_u; r_l]:   y_l = S~^-1 r_l,   y_u = K~^-1 (r_u - B y_l)
//!     [ 0   S~ ]
//! ```
//!
//! with `K~^-1` one application of each body's solver (`BodySolver::precondition`: one AMG
//! V-cycle, or the exact solve of a Cholesky factor) and `S~` the half-space approximation of the
//! Schur complement `S = D - C K^-1 B` (`crate::contact::coupled::half_space`). With exact blocks,
//! `A P^-1 = [I 0; C K^-1  S S~^-1]`: its eigenvalues are 1 and those of `S S~^-1`, so GMRES needs
//! about as many iterations as on the interface problem alone; with V-cycles, about as many as CG
//! with the same V-cycle needs on one body, since the interface and the bulk are preconditioned
//! by blocks of their own scale. Nothing is solved exactly inside the iteration: a product is
//! one sparse matrix-vector product, and a preconditioner application one V-cycle per body, a
//! dense triangular solve on the multipliers and the coupling blocks.
//!
//! # Start and stop
//!
//! Every solve starts from the last one: its displacements (scaled by the ratio of the load
//! factors, since the loads enter linearly; as they are when the load paths' factors changed
//! in other proportions) and its tractions mapped by node and component,
//! projected on each multiplier's direction, `lambda_k = (e_k . t_node) / s` (a multiplier
//! that is new starts at 0). A solve stops when the true relative residual `|[f; g] - A x| /
//! |[f; g]|` is at most [`Tightness::relative`]: [`TIGHT_RTOL`] for an answer that may be
//! judged, [`LOOSE_RTOL`] for an iteration whose active set is about to change
//! (`crate::contact::iteration::solve` decides). A solve that does not get there ends in a
//! [`KrylovError`] naming why: the iteration cap, a restart cycle that did not reduce the true
//! residual, or a non-finite value.

use std::collections::HashMap;
use std::fmt;
use std::ops::Range;

use rayon::prelude::*;
use thiserror::Error;

use crate::cancel::Cancel;
use crate::contact::ContactError;
use crate::contact::coupled::compliance::MultiplierKey;
use crate::contact::coupled::half_space::HalfSpace;
use crate::contact::coupled::krylov_layout::KrylovLayout;
use crate::contact::coupled::system::{CoupledSystem, Pair, stiffness_product};
use crate::elastic::{AssembledBody, StepFactors};
use crate::linalg::BodySolver;
use crate::linalg::gmres::{self, GmresFailure, GmresSettings, GmresStats, Operators};

/// Relative residual of a solve whose answer may end the loop and be certified. Why 1e-12:
/// the answer then matches the dense Schur complement's to 1e-10 and better in forces,
/// displacements and pressures on the fixtures of `tests/contact_solvers.rs` (which ask for
/// 1e-8), and it is two orders above the round-off floor of the residual of a stiffness
/// system (`eps |A| |x| / |b|`, 1e-14 to 1e-13 on the benchmark's meshes).
pub const TIGHT_RTOL: f64 = 1e-12;

/// Relative residual of a solve whose active set is about to change: the update only reads
/// each gap against the penetration tolerance and each pressure's sign, so an iterate that is
/// to be thrown away with its set needs no more (the forcing term of an inexact Newton method,
/// held constant: the active-set loop is a semismooth Newton method, whose steps need only be
/// solved as accurately as their decisions). An iteration that keeps its set is solved again
/// to [`TIGHT_RTOL`] from the loose answer before it is judged: no answer rests on a loose
/// solve. Why 1e-6: six orders below the load, the gaps are held to about 1e-6 of the
/// displacement scale, far below the penetration tolerance (1e-3 to 1e-2 of the spacing), and
/// it saves half the iterations of a tight solve. 1e-4 saved another 30% of the V-cycles on the
/// hemisphere on block at 99k DOFs, with the same answer there, but changed decisions
/// elsewhere: the fixtures of `tests/contact_solvers.rs` then ended on other active sets (CG +
/// AMG against Cholesky bodies) and 1e-6 apart (3D Hertz, Krylov against Schur).
pub const LOOSE_RTOL: f64 = 1e-6;

/// Krylov vectors kept before a restart: 50 vectors of the whole system, 0.4 GB at a million
/// unknowns (divided among the ranks of a distributed run); a solve's iteration count stays
/// below it (a restart costs one product).
const RESTART: usize = 50;

/// How far below its starting residual a [`Tightness::Reduced`] solve goes at least: the
/// forcing term of an inexact Newton method (Eisenstat and Walker), constant. Why: the slip
/// directions of a Coulomb pair are iterated on by the loop on one set of nodes
/// (`crate::contact::law::coulomb`), and a direction's turn of 1e-2 changes the coupled system by
/// less than [`LOOSE_RTOL`] of its right-hand side (which the bodies' Dirichlet lift dominates).
/// A solve that starts from the last answer, as every solve does, then returned it unchanged
/// (zero GMRES iterations), and the directions stopped moving: five iterations at a turn of
/// 1.7e-2 on the friction cost's 99k-DOF sphere, then `cycling`. Why 1e-2: the direction
/// update reads the tractions, which a residual a hundred times below the start's brings within
/// a percent of the system's answer, the precision of a turn the loop is still making.
pub const REDUCTION: f64 = 1e-2;

/// How tightly one solve is asked to converge.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Tightness {
    /// To [`TIGHT_RTOL`].
    Tight,
    /// To [`LOOSE_RTOL`].
    Loose,
    /// To [`LOOSE_RTOL`] and at least [`REDUCTION`] times the starting residual: a solve of
    /// a loop that iterates on the slip directions (Coulomb pairs).
    Reduced,
}

impl Tightness {
    pub fn relative(self) -> f64 {
        match self {
            Self::Tight => TIGHT_RTOL,
            Self::Loose | Self::Reduced => LOOSE_RTOL,
        }
    }

    /// The fraction of the starting residual the solve must reach, if any.
    pub fn reduction(self) -> Option<f64> {
        (self == Self::Reduced).then_some(REDUCTION)
    }
}

/// Why the coupled Krylov solve stopped without converging.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KrylovFailure {
    /// `[contact] krylov_max_iterations` iterations were spent.
    IterationLimit,
    /// A restart cycle did not reduce the true residual.
    Stagnated,
    /// A product or the preconditioner produced a non-finite value.
    NotFinite,
}

impl From<GmresFailure> for KrylovFailure {
    fn from(failure: GmresFailure) -> Self {
        match failure {
            GmresFailure::IterationLimit => Self::IterationLimit,
            GmresFailure::Stagnated => Self::Stagnated,
            GmresFailure::NotFinite => Self::NotFinite,
        }
    }
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

/// The coupled Krylov solve failed.
#[derive(Debug, Error, Clone, PartialEq)]
#[error(
    "coupled GMRES did not converge ({reason}) after {iterations} iterations: relative \
     residual {residual:.2e} > {tolerance:.0e}"
)]
pub struct KrylovError {
    pub reason: KrylovFailure,
    pub iterations: usize,
    pub residual: f64,
    pub tolerance: f64,
}

/// What the last coupled Krylov solve did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct KrylovStats {
    /// GMRES iterations (one product with `A` and one application of `P^-1` each).
    pub iterations: usize,
    /// Products spent on true residuals (the starting one and one per restart cycle).
    pub residual_products: usize,
    /// `|[f; g] - A x| / |[f; g]|` at the end.
    pub relative_residual: f64,
    /// The relative residual of the starting guess.
    pub initial_residual: f64,
    /// The relative residual it was asked for.
    pub tolerance: f64,
}

/// What the Krylov path keeps between active-set iterations and load steps.
#[derive(Default)]
pub struct KrylovState {
    /// The bodies' displacements of the last solve (this rank's rows of them in a distributed
    /// run) and the load step's factors it was solved at.
    displacements: Option<(StepFactors, Vec<f64>)>,
    /// Traction of the last solve per (pair, primary node, component), unscaled.
    tractions: HashMap<MultiplierKey, f64>,
    /// The last solve's figures.
    pub last: KrylovStats,
    /// Applications of each body's block of the preconditioner so far (one V-cycle each with
    /// CG + AMG bodies).
    pub body_applications: Vec<usize>,
    /// Checked at each GMRES iteration.
    pub cancel: Cancel,
}

impl KrylovState {
    /// Nothing kept yet.
    pub fn new(cancel: Cancel) -> Self {
        Self {
            cancel,
            ..Self::default()
        }
    }
}

/// What one coupled Krylov solve works on.
pub struct KrylovProblem<'a> {
    pub system: &'a CoupledSystem,
    pub pairs: &'a [Pair<'a>],
    /// Each body's constrained stiffness (the operator's diagonal blocks).
    pub bodies: &'a [&'a AssembledBody],
    /// Each body's solver, applied once per iteration as its block of the preconditioner.
    pub solvers: &'a [BodySolver],
    /// Each pair's half-space compliance factor
    /// (`crate::contact::coupled::half_space::compliance_factor`).
    pub compliance: &'a [f64],
    pub dim: usize,
}

/// Solves the coupled system of `problem` to `tightness` from the last solve kept in `state`;
/// returns `x = [u_1; ...; u_N; lambda / s]` with the displacement rows this process holds
/// (`KrylovLayout`: every row, or this rank's rows of each body) and every multiplier.
pub fn solve(
    problem: &KrylovProblem,
    state: &mut KrylovState,
    tightness: Tightness,
    max_iterations: usize,
) -> Result<Vec<f64>, ContactError> {
    let system = problem.system;
    let tolerance = tightness.relative();
    let schur = (problem.pairs.iter().enumerate())
        .map(|(p, pair)| {
            let c0 = problem.compliance[p];
            HalfSpace::new(system, p, pair.coupling, problem.dim, c0)
        })
        .collect();
    let num_bodies = system.num_bodies();
    let product = CoupledProduct::new(problem)?;
    let layout = &product.layout;
    let rows = layout.num_rows(system);
    let rhs = layout.own_part(system.rhs());
    let rhs_norm = layout.dot(&rhs, &rhs)?.sqrt();
    let mut local_x = layout.own_part(starting_guess(system, state, rows));
    let local_scratch = vec![0.0; rows];
    // Every multiplier of the vectors `P^-1` is applied to, where they hold a block of them.
    let multipliers = || match layout {
        KrylovLayout::Whole => Vec::new(),
        KrylovLayout::Shared(_) => vec![0.0; system.m],
    };
    let (residual_multipliers, preconditioned_multipliers) = (multipliers(), multipliers());
    let mut operators = Blocks {
        product,
        schur,
        rigid: RigidBlock::new(system),
        applications: vec![0; num_bodies],
        tolerance,
        rhs_norm,
        cancel: &state.cancel,
        local_scratch,
        residual_multipliers,
        preconditioned_multipliers,
    };
    let settings = GmresSettings {
        tolerance: tolerance * rhs_norm,
        reduction: tightness.reduction(),
        max_iterations,
        restart: RESTART,
    };
    let outcome = gmres::solve(&mut operators, &rhs, &mut local_x, settings);
    state.body_applications.resize(num_bodies, 0);
    for (total, new) in state
        .body_applications
        .iter_mut()
        .zip(operators.applications)
    {
        *total += new;
    }
    let stats = outcome?;
    let relative = |r: f64| if rhs_norm > 0.0 { r / rhs_norm } else { r };
    state.last = KrylovStats {
        iterations: stats.iterations,
        residual_products: stats.residual_products,
        relative_residual: relative(stats.residual),
        initial_residual: relative(stats.initial_residual),
        tolerance,
    };
    if let Some(failure) = stats.failure {
        return Err(ContactError::from(KrylovError {
            reason: failure.into(),
            iterations: stats.iterations,
            residual: relative(stats.residual),
            tolerance,
        }));
    }
    let x = (operators.product.layout).with_every_multiplier(local_x, system)?;
    keep(
        system,
        &x,
        rows,
        &mut state.displacements,
        &mut state.tractions,
    );
    Ok(x)
}

/// The last solve's displacements (scaled to this load step's factors:
/// `StepFactors::scale_from`) and tractions, along each multiplier's direction; an uncoupled
/// multiplier's exact value. A vector of the solve's layout, whose displacement rows are the
/// first `rows` (`crate::contact::coupled::krylov_layout`).
fn starting_guess(system: &CoupledSystem, state: &KrylovState, rows: usize) -> Vec<f64> {
    let n = rows;
    // Allocated to its length (the multipliers appended to a vector of the displacements'
    // length would double its room): GMRES holds it through the solve.
    let mut x = Vec::with_capacity(n + system.m);
    match &state.displacements {
        Some((factors, u)) if u.len() == n => match system.factors.scale_from(factors) {
            Some(scale) => x.extend(u.iter().map(|u| scale * u)),
            None => x.resize(n, 0.0),
        },
        _ => x.resize(n, 0.0),
    };
    x.resize(n + system.m, 0.0);
    for (k, column) in system.columns.iter().enumerate() {
        if column.is_empty() && system.d[k] != 0.0 {
            x[n + k] = system.g[k] / system.d[k];
            continue;
        }
        let (mut along, mut weights) = (0.0, 0.0);
        for (key, weight) in column {
            along += weight * state.tractions.get(key).copied().unwrap_or(0.0);
            weights += weight * weight;
        }
        if weights > 0.0 {
            x[n + k] = along / (weights * system.s);
        }
    }
    x
}

/// Keeps the displacements and tractions of `x`, a vector of the solve's layout whose first
/// `rows` are displacements, for the next solve's start: in a distributed run this rank's rows
/// alone.
fn keep(
    system: &CoupledSystem,
    x: &[f64],
    rows: usize,
    displacements: &mut Option<(StepFactors, Vec<f64>)>,
    tractions: &mut HashMap<MultiplierKey, f64>,
) {
    let n = rows;
    *displacements = Some((system.factors.clone(), x[..n].to_vec()));
    tractions.clear();
    for (k, column) in system.columns.iter().enumerate() {
        for (key, weight) in column {
            *tractions.entry(*key).or_insert(0.0) += system.s * x[n + k] * weight;
        }
    }
}

/// `relative_residual = |[f; g] - A x| / |[f; g]|` of `x` (as [`solve`] returns it) by the coupled
/// GMRES's own product: on several ranks, where a rank's coupled system holds only its entries
/// of `B` and `C` (`crate::contact::coupled::system::Unknowns::RankRows`), the residual check
/// of a solve (collective); on one process the same sum as `CoupledSystem::relative_residual`
/// but for the order of its terms.
pub fn relative_residual(problem: &KrylovProblem, x: Vec<f64>) -> Result<f64, ContactError> {
    let mut product = CoupledProduct::new(problem)?;
    let rhs = product.layout.own_part(problem.system.rhs());
    let x = product.layout.own_part(x);
    let rhs_norm = product.layout.dot(&rhs, &rhs)?.sqrt();
    let mut residual = vec![0.0; x.len()];
    product.apply(&x, &mut residual)?;
    residual.iter_mut().zip(&rhs).for_each(|(r, b)| *r = b - *r);
    let norm = product.layout.dot(&residual, &residual)?.sqrt();
    Ok(if rhs_norm > 0.0 {
        norm / rhs_norm
    } else {
        norm
    })
}

/// The operator `A` of the module doc, on vectors held as `layout` says.
struct CoupledProduct<'a> {
    system: &'a CoupledSystem,
    /// Each body's constrained stiffness (symmetric), `k_c` (or its solver's copy).
    bodies: &'a [&'a AssembledBody],
    solvers: &'a [BodySolver],
    /// How the vectors are held: whole, or this rank's rows of each body and block of the
    /// multipliers.
    layout: KrylovLayout,
    /// A rank's part of `C u` over its columns, and every multiplier of the vector a product
    /// is applied to (empty on one process).
    partial: Vec<f64>,
    multipliers: Vec<f64>,
}

impl<'a> CoupledProduct<'a> {
    fn new(problem: &KrylovProblem<'a>) -> Result<Self, ContactError> {
        let layout = KrylovLayout::new(problem.system, problem.solvers)?;
        let scratch = || match &layout {
            KrylovLayout::Whole => Vec::new(),
            KrylovLayout::Shared(_) => vec![0.0; problem.system.m],
        };
        let (partial, multipliers) = (scratch(), scratch());
        Ok(Self {
            system: problem.system,
            bodies: problem.bodies,
            solvers: problem.solvers,
            layout,
            partial,
            multipliers,
        })
    }

    /// `out = A x`.
    fn apply(&mut self, x: &[f64], out: &mut [f64]) -> Result<(), ContactError> {
        let system = self.system;
        let KrylovLayout::Shared(layout) = &self.layout else {
            // Whole vectors: the bodies' products on their threads.
            let n = system.num_displacements();
            let (out_u, out_l) = out.split_at_mut(n);
            system
                .body_parts(out_u)
                .into_par_iter()
                .zip(self.bodies)
                .zip(self.solvers)
                .zip(system.offsets.par_windows(2))
                .try_for_each(|(((out, body), solver), range)| {
                    stiffness_product(body, Some(solver), &x[range[0]..range[1]], out)
                })?;
            multiplier_rows(system, &x[n..], 0..system.m, out_l);
            system.add_b_product(&x[n..], 1.0, out);
            system.add_c_product(&x[..n], &mut out[n..]);
            return Ok(());
        };
        // This rank's rows: `K u` by each body's rows, `B lambda` by this rank's entries (of
        // every multiplier, gathered), and on this rank's multipliers `D lambda` and `C u` as
        // every rank's part over its columns, summed.
        let rows = layout.num_local();
        layout.gather_multipliers(&x[rows..], &mut self.multipliers)?;
        let (out_u, out_l) = out.split_at_mut(rows);
        for (k, solver) in self.solvers.iter().enumerate() {
            let range = layout.local_range(k);
            solver
                .multiply_rows(&x[range.clone()], &mut out_u[range])
                .map_err(|e| ContactError::Linalg(format!("a body's stiffness product: {e}")))?;
        }
        multiplier_rows(system, &self.multipliers, layout.own_multipliers(), out_l);
        self.partial.fill(0.0);
        system.add_c_product(&x[..rows], &mut self.partial);
        layout.add_to_owners(&self.partial, out_l)?;
        system.add_b_product(&self.multipliers, 1.0, out_u);
        Ok(())
    }
}

/// The operator `A` and the block preconditioner `P^-1` of the module doc.
struct Blocks<'a> {
    product: CoupledProduct<'a>,
    /// `S~` of each pair, on its multipliers: the pairs' blocks of the preconditioner.
    schur: Vec<HalfSpace>,
    /// `S~` of the force-controlled displacements: their block of `D`.
    rigid: RigidBlock,
    /// Applications of each body's block.
    applications: Vec<usize>,
    tolerance: f64,
    rhs_norm: f64,
    cancel: &'a Cancel,
    /// `r_u - B y_l` of an application of `P^-1`, on the rows the vectors hold.
    local_scratch: Vec<f64>,
    /// Every multiplier of `r` and of `y_l` in an application of `P^-1` of a distributed run
    /// (whose vectors hold a block of them).
    residual_multipliers: Vec<f64>,
    preconditioned_multipliers: Vec<f64>,
}

impl Operators for Blocks<'_> {
    type Error = ContactError;

    fn apply(&mut self, x: &[f64], out: &mut [f64]) -> Result<(), ContactError> {
        self.product.apply(x, out)
    }

    fn precondition(&mut self, r: &[f64], out: &mut [f64]) -> Result<(), ContactError> {
        self.cancel.check()?;
        let system = self.product.system;
        let solvers = self.product.solvers;
        let rows = self.product.layout.num_rows(system);
        let (out_u, out_l) = out.split_at_mut(rows);
        // `y_l = S~^-1 r_l` over every multiplier: the half-space blocks are dense over a
        // pair's multipliers, so a distributed run gathers them and keeps its block of `y_l`.
        let (r_l, y_l) = match &self.product.layout {
            KrylovLayout::Whole => (&r[rows..], &mut out_l[..]),
            KrylovLayout::Shared(layout) => {
                layout.gather_multipliers(&r[rows..], &mut self.residual_multipliers)?;
                (
                    &self.residual_multipliers[..],
                    &mut self.preconditioned_multipliers[..],
                )
            }
        };
        for (p, schur) in self.schur.iter().enumerate() {
            let range = system.pair_multipliers(p);
            schur.apply(&r_l[range.clone()], &mut y_l[range]);
        }
        self.rigid.apply(r_l, y_l);
        self.local_scratch.copy_from_slice(&r[..rows]);
        system.add_b_product(y_l, -1.0, &mut self.local_scratch);
        if let KrylovLayout::Shared(layout) = &self.product.layout {
            out_l.copy_from_slice(&self.preconditioned_multipliers[layout.own_multipliers()]);
        }
        let scratch = &self.local_scratch;
        match &self.product.layout {
            // Whole vectors: the bodies' blocks on their threads.
            KrylovLayout::Whole => system
                .body_parts(out_u)
                .into_par_iter()
                .zip(solvers)
                .zip(system.offsets.par_windows(2))
                .try_for_each(|((out, solver), range)| {
                    solver.precondition(&scratch[range[0]..range[1]], out)
                }),
            // This rank's rows: each body's V-cycle on them (collective, in body order).
            KrylovLayout::Shared(layout) => {
                (solvers.iter().enumerate()).try_for_each(|(k, solver)| {
                    let range = layout.local_range(k);
                    solver.precondition_rows(&scratch[range.clone()], &mut out_u[range])
                })
            }
        }
        .map_err(|e| ContactError::Linalg(format!("a body's preconditioner: {e}")))?;
        self.applications.iter_mut().for_each(|a| *a += 1);
        Ok(())
    }

    fn dot(&mut self, a: &[f64], b: &[f64]) -> Result<f64, ContactError> {
        self.product.layout.dot(a, b)
    }

    /// How far the solve is, for the progress line of a long active-set iteration.
    fn progress(&mut self, stats: &GmresStats, estimate: f64) -> Result<(), ContactError> {
        crate::progress::note(|| {
            let estimate = if self.rhs_norm > 0.0 {
                estimate / self.rhs_norm
            } else {
                estimate
            };
            format!(
                "coupled GMRES: {} iterations, residual ~{estimate:.1e}, target {:.1e}",
                stats.iterations, self.tolerance
            )
        });
        Ok(())
    }
}

/// `out = D lambda` on the multiplier rows `rows` (`lambda` every multiplier of a vector, `out`
/// those rows' values).
fn multiplier_rows(system: &CoupledSystem, lambda: &[f64], rows: Range<usize>, out: &mut [f64]) {
    let first = rows.start;
    for ((o, d), l) in out
        .iter_mut()
        .zip(&system.d[rows.clone()])
        .zip(&lambda[rows.clone()])
    {
        *o = d * l;
    }
    for &(k, l, value) in &system.d_coupled {
        if rows.contains(&k) {
            out[k - first] += value * lambda[l];
        }
    }
}

/// The preconditioner's block of the force-controlled displacements `a`: their block `D_aa`
/// of `D` (`d` and the couplings of one body's components), solved densely.
///
/// Their Schur complement is `D_aa - k^T K^-1 k` less what the contacts add: for a body that
/// only its contacts hold along `a`, the body's part of it is zero and what is left is the
/// contact stiffness, which changes with the active set. `D_aa` leaves out the coupling
/// through `k` and the contacts, a perturbation of rank at most two per force-controlled
/// component of the preconditioned operator (`A P^-1` is the identity plus it where the other
/// blocks are exact), which GMRES resolves in that many more iterations.
struct RigidBlock {
    /// The first rigid unknown, within the multiplier block.
    first: usize,
    /// The LU of `D_aa` (`None` without force control).
    lu: Option<nalgebra::linalg::LU<f64, nalgebra::Dyn, nalgebra::Dyn>>,
}

impl RigidBlock {
    fn new(system: &CoupledSystem) -> Self {
        let first = system.rigid_offsets[0];
        let count = system.m - first;
        if count == 0 {
            return Self { first, lu: None };
        }
        let mut block = nalgebra::DMatrix::<f64>::zeros(count, count);
        for i in 0..count {
            block[(i, i)] = system.d[first + i];
        }
        for &(k, l, value) in &system.d_coupled {
            if k >= first && l >= first {
                block[(k - first, l - first)] += value;
            }
        }
        Self {
            first,
            lu: Some(block.lu()),
        }
    }

    /// `out[a] = D_aa^-1 r[a]` over the rigid unknowns of the multiplier block.
    fn apply(&self, r: &[f64], out: &mut [f64]) {
        let Some(lu) = &self.lu else {
            return;
        };
        let rhs = nalgebra::DVector::from_column_slice(&r[self.first..]);
        let y = lu.solve(&rhs).unwrap_or(rhs);
        out[self.first..].copy_from_slice(y.as_slice());
    }
}
