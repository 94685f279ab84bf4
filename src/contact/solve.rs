//! The INTERNODES active-set loop: a primal-dual active set method (a semismooth Newton method
//! on the nodal complementarity conditions; Hüeber and Wohlmuth 2005) over interface operators
//! built once ([`super::interface`]), with its answer certified by independent checks
//! ([`super::certificate`]).
//!
//! ```text
//! A <- primary candidates that touch or penetrate in the reference configuration, e <- 0
//! repeat
//!   1. coupling of A: rows of R12, columns of M2 R21, lumped M1, gaps d + e   (fixed operators)
//!   2. solve the coupled system for u1, u2, lambda
//!   3. gaps of every candidate: geometric g (closest point, deformed) and linearized g_lin
//!   4. A' <- {i in A : p_i >= -tol_t p_max}  +  {i not in A : g_i < -tol_p h_i};  e <- g - g_lin
//! until A' = A and every active node lies on the other surface (|g_i| <= 0.01 tol_p h_i)
//! certify: geometric penetration, tension and force balance, measured independently
//! ```
//!
//! Step 4 is the primal-dual active set update for the nodal complementarity function
//! `C_i = p_i - max(0, p_i - c g_i)`, `c = E*/h`: a node is active next when `p_i - c g_i > 0`.
//! At an active node the constraint holds `g_i = 0`, at an inactive one `p_i = 0`, so the test
//! reads `p_i > 0` on A and `g_i < 0` off it, and `c` drops out; the tolerances make the two
//! tests robust to round-off. Removal and addition happen in one update, as in the seed's
//! Algorithm 3 (its improvement over Algorithm 3's one-at-a-time variants). What differs from
//! the seed's loop: the operators do not change with A (the seed rebuilds them, with Algorithm
//! 2, for every active set, so that the discrete problem itself moves from one iteration to the
//! next), the pressure `p_i = -lambda_i . n_i` tested is the unknown of the system (lumped
//! interface mass, [`super::surface`]), and the gap is the geometric one.
//!
//! An update that would return to an active set seen before first keeps active (pins, for the
//! rest of the solve) the nodes it removes for tension that had been removed before and came
//! back for penetration, and leaves their tension to the certificate: at the rim of a contact
//! zone a node can be in tension while active and penetrate while inactive (seen with tied
//! contact between dissimilar materials: 2% of the peak pressure, then 4e-3 h), and no active
//! set satisfies both tests. If the set still repeats, it takes a single switch instead:
//! only the node with the largest violation (penetration over `h`, tension over `p_max`)
//! changes; if that set was seen too the loop stops as [`ContactStatus::Cycling`]. It never
//! declares convergence. Running out of iterations is [`ContactStatus::IterationLimit`]; an
//! active node held a spacing or more off the other surface is [`ContactStatus::Unstable`].

use std::collections::{BTreeSet, HashSet};
use std::time::Instant;

use super::certificate::certify;
use super::coupled_solver::{self, BodyFactors, CoupledSolver};
use super::interface::{InterfaceOperators, geometric_gaps};
use super::solution::{ContactSolution, ContactStatus, IterationRecord, PhaseSeconds};
use super::system::CoupledSystem;
use super::{ContactError, ContactProblem, post};
use crate::elastic::{AssembledBody, SolveStats, SolverSettings, assemble};

/// Solves a two-body contact problem at its full load.
pub fn solve_contact(
    problem: &ContactProblem,
    solver: &SolverSettings,
) -> Result<ContactSolution, ContactError> {
    ContactSolver::new(problem, solver)?.solve(1.0, None)
}

/// An active node this many spacings off the other surface after a solve means the constraint
/// no longer controls the geometry ([`ContactStatus::Unstable`]). On converging cases the
/// active nodes stay within a few hundredths of a spacing of the other surface at every
/// iteration (the gap correction is an interpolation error, a small fraction of `h`).
const UNSTABLE_GAP_OVER_H: f64 = 1.0;

/// The active nodes count as lying on the other surface when their geometric gaps are within
/// this fraction of the penetration tolerance. The gap corrections contract by about ten per
/// iteration, so settling to well inside the tolerance costs a solve or two with an unchanged
/// active set, and makes the answer independent of the path (load steps or one solve) to that
/// precision.
const SETTLED: f64 = 0.01;

/// Where an active-set loop starts: the active primary candidates (surface indices) and the
/// gap corrections `e` (one per primary candidate; [`super::interface`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ActiveSet {
    pub nodes: BTreeSet<usize>,
    pub corrections: Vec<f64>,
}

/// A contact problem set up once: both bodies assembled (and, on the Schur path, factored) and
/// the interface operators built. Every load step reuses all of it: loads and prescribed
/// displacements enter the system linearly, `f_c(s) = s f_c(1)`, while `K`, its factors and the
/// interface geometry do not change.
pub struct ContactSolver<'a> {
    pub(super) problem: &'a ContactProblem<'a>,
    solver: SolverSettings,
    pub(super) body1: AssembledBody,
    pub(super) body2: AssembledBody,
    pub(super) stats1: SolveStats,
    pub(super) stats2: SolveStats,
    factors: Option<BodyFactors>,
    operators: InterfaceOperators,
}

impl<'a> ContactSolver<'a> {
    pub fn new(
        problem: &'a ContactProblem<'a>,
        solver: &SolverSettings,
    ) -> Result<Self, ContactError> {
        problem.settings.validate()?;
        let (s1, s2) = (&problem.primary_surface, &problem.secondary_surface);
        let (mut stats1, mut stats2) = (SolveStats::default(), SolveStats::default());
        let body1 = assemble(&problem.primary, &mut stats1, false)?;
        let body2 = assemble(&problem.secondary, &mut stats2, false)?;
        let factors = match problem.settings.solver {
            CoupledSolver::Schur => {
                let start = Instant::now();
                let factors = BodyFactors::new(&body1, &body2, s1, s2, solver.ordering)?;
                if solver.verbose {
                    eprintln!(
                        "  Cholesky of both bodies: {:.3} s",
                        start.elapsed().as_secs_f64()
                    );
                }
                Some(factors)
            }
            CoupledSolver::MonolithicLu => None,
        };
        let operators = InterfaceOperators::new(
            s1,
            s2,
            problem.settings.rbf_radius,
            problem.normal_weights(),
        )?;
        Ok(Self {
            problem,
            solver: *solver,
            body1,
            body2,
            stats1,
            stats2,
            factors,
            operators,
        })
    }

    /// The primary candidates that touch or penetrate in the reference configuration, with no
    /// gap correction.
    pub fn initial_active_set(&self) -> ActiveSet {
        let (s1, s2) = (
            &self.problem.primary_surface,
            &self.problem.secondary_surface,
        );
        let tol = self.problem.settings.penetration_tolerance;
        let gaps = geometric_gaps(s1, s2, None, None);
        ActiveSet {
            nodes: (0..s1.len())
                .filter(|&i| self.operators.facing[i] && gaps[i] < tol * s1.spacing[i])
                .collect(),
            corrections: vec![0.0; s1.len()],
        }
    }

    /// Runs the active-set loop with the loads and prescribed displacements scaled by
    /// `load_factor`, from `start` (default: [`Self::initial_active_set`]).
    pub fn solve(
        &mut self,
        load_factor: f64,
        start: Option<&ActiveSet>,
    ) -> Result<ContactSolution, ContactError> {
        let problem = self.problem;
        let settings = &problem.settings;
        let (s1, s2) = (&problem.primary_surface, &problem.secondary_surface);
        let start = start.cloned().unwrap_or_else(|| self.initial_active_set());
        let (mut active, mut corrections) = (start.nodes, start.corrections);
        let mut seen: HashSet<BTreeSet<usize>> = HashSet::new();
        // Nodes removed for tension, those of them added back for penetration, and those kept
        // active against a repeat (module doc).
        let (mut released, mut readded, mut pinned) =
            (HashSet::new(), HashSet::new(), HashSet::new());
        let mut history = Vec::new();
        let mut status = ContactStatus::IterationLimit;
        let mut last = None;

        for iteration in 1..=settings.max_iterations {
            let mut seconds = PhaseSeconds::default();
            // 1. The coupling of the active set: rows and columns of the fixed operators.
            let clock = Instant::now();
            let nodes: Vec<usize> = active.iter().copied().collect();
            let coupling =
                self.operators
                    .coupling(s1, s2, settings.formulation, &nodes, &corrections);
            seconds.operators = clock.elapsed().as_secs_f64();

            // 2. The coupled solve, checked by its residual.
            let clock = Instant::now();
            let dim = s1.dim;
            let system =
                CoupledSystem::assemble(&self.body1, &self.body2, &coupling, dim, load_factor)?;
            let x =
                coupled_solver::solve(&system, &self.body1, &self.body2, self.factors.as_mut())?;
            let residual = system.relative_residual(&self.body1, &self.body2, &x);
            if residual.is_nan() || residual > self.solver.residual_tolerance {
                return Err(ContactError::Inaccurate {
                    residual,
                    tolerance: self.solver.residual_tolerance,
                });
            }
            let solution = system.solution(&x, &coupling, dim, residual);
            seconds.solve = clock.elapsed().as_secs_f64();

            // 3. Gaps of every primary candidate: geometric (the search) and linearized.
            let clock = Instant::now();
            let gaps = geometric_gaps(s1, s2, Some(&solution.u1), Some(&solution.u2));
            let linear = self
                .operators
                .linearized_gaps(s1, s2, &solution.u1, &solution.u2);
            seconds.search = clock.elapsed().as_secs_f64();

            // 4. The primal-dual active set update, and the gap corrections.
            let clock = Instant::now();
            let update = Update::new(
                problem,
                &nodes,
                &solution.traction,
                &coupling.normals,
                &gaps,
                &self.operators.facing,
                &pinned,
            );
            readded.extend(
                update
                    .penetrating
                    .iter()
                    .map(|&(i, _)| i)
                    .filter(|i| released.contains(i)),
            );
            released.extend(update.tension.iter().map(|&(i, _)| i));
            corrections = gaps.iter().zip(&linear).map(|(g, l)| g - l).collect();
            seconds.checks = clock.elapsed().as_secs_f64();
            let record = update.record(iteration, residual, seconds);
            if self.solver.verbose {
                eprintln!("{}", record.line());
            }
            history.push(record);
            last = Some((coupling, solution));

            if update.max_gap_error_over_h > UNSTABLE_GAP_OVER_H {
                status = ContactStatus::Unstable;
                break;
            }
            if update.next == active {
                if update.settled {
                    status = ContactStatus::Converged;
                    break;
                }
                continue; // same set, corrected gaps: solve again
            }
            seen.insert(active.clone());
            let mut next = update.next.clone();
            if seen.contains(&next) {
                // A repeat. First keep active the nodes in tension that came back after an
                // earlier removal (a rim node alternating between the two tests).
                let alternating: Vec<usize> = update
                    .tension
                    .iter()
                    .map(|&(i, _)| i)
                    .filter(|i| readded.contains(i))
                    .collect();
                pinned.extend(alternating.iter().copied());
                next.extend(alternating);
                if next == active {
                    continue;
                }
            }
            if seen.contains(&next) {
                match update.single_switch(&active) {
                    Some(switched) if !seen.contains(&switched) => next = switched,
                    _ => {
                        status = ContactStatus::Cycling;
                        break;
                    }
                }
            }
            active = next;
        }

        let (coupling, solution) = last.expect("max_iterations >= 1 is validated");
        let certificate = certify(problem, &solution);
        let status = match status {
            ContactStatus::Converged if !certificate.passed => ContactStatus::NotCertified,
            ContactStatus::Converged if active.is_empty() => ContactStatus::NoContact,
            other => other,
        };
        let next_start = ActiveSet {
            nodes: active,
            corrections,
        };
        post::finish(
            self,
            load_factor,
            status,
            history,
            certificate,
            &coupling,
            solution,
            next_start,
        )
    }
}

/// The active-set update of one iteration (step 4 of the module doc), in surface indices.
struct Update {
    next: BTreeSet<usize>,
    /// Active nodes (not pinned) with `p_i < -tol_t p_max`, with their tension over `p_max`.
    tension: Vec<(usize, f64)>,
    /// Inactive nodes facing the other surface with `g_i < -tol_p h_i`, with their penetration
    /// over `h_i` (a penetrating node that does not face the other candidate surface is left
    /// to the certificate, which names it).
    penetrating: Vec<(usize, f64)>,
    /// Every active node lies on the other surface: `|g_i| <= SETTLED tol_p h_i`.
    settled: bool,
    active: usize,
    max_gap_error_over_h: f64,
}

impl Update {
    fn new(
        problem: &ContactProblem,
        active: &[usize],
        traction: &[[f64; 3]],
        normals: &[[f64; 3]],
        gaps: &[f64],
        facing: &[bool],
        pinned: &HashSet<usize>,
    ) -> Self {
        let settings = &problem.settings;
        let s1 = &problem.primary_surface;
        let pressure: Vec<f64> = traction
            .iter()
            .zip(normals)
            .map(|(t, n)| -(t[0] * n[0] + t[1] * n[1] + t[2] * n[2]))
            .collect();
        let p_max = pressure.iter().copied().fold(0.0, f64::max);
        let tension: Vec<(usize, f64)> = active
            .iter()
            .zip(&pressure)
            .filter(|&(i, &p)| p < -settings.tension_tolerance * p_max && !pinned.contains(i))
            .map(|(&i, &p)| (i, -p / p_max.max(f64::MIN_POSITIVE)))
            .collect();
        let is_active: HashSet<usize> = active.iter().copied().collect();
        let penetrating: Vec<(usize, f64)> = (0..s1.len())
            .filter(|&i| facing[i] && !is_active.contains(&i))
            .map(|i| (i, -gaps[i] / s1.spacing[i]))
            .filter(|&(_, over_h)| over_h > settings.penetration_tolerance)
            .collect();
        let max_gap_error_over_h = active
            .iter()
            .map(|&i| gaps[i].abs() / s1.spacing[i])
            .fold(0.0, f64::max);
        let mut next: BTreeSet<usize> = active.iter().copied().collect();
        for (i, _) in &tension {
            next.remove(i);
        }
        next.extend(penetrating.iter().map(|&(i, _)| i));
        Self {
            next,
            settled: max_gap_error_over_h <= SETTLED * settings.penetration_tolerance,
            tension,
            penetrating,
            active: active.len(),
            max_gap_error_over_h,
        }
    }

    /// The active set with only the worst violation switched, if any.
    fn single_switch(&self, active: &BTreeSet<usize>) -> Option<BTreeSet<usize>> {
        let worst = |v: &[(usize, f64)]| v.iter().copied().max_by(|a, b| a.1.total_cmp(&b.1));
        let mut next = active.clone();
        match (worst(&self.tension), worst(&self.penetrating)) {
            (Some(t), Some(p)) if p.1 >= t.1 => next.insert(p.0),
            (Some(t), _) => next.remove(&t.0),
            (None, Some(p)) => next.insert(p.0),
            (None, None) => return None,
        };
        Some(next)
    }

    fn record(&self, iteration: usize, residual: f64, seconds: PhaseSeconds) -> IterationRecord {
        let max = |v: &[(usize, f64)]| v.iter().map(|x| x.1).fold(0.0, f64::max);
        IterationRecord {
            iteration,
            active: self.active,
            added: self.penetrating.len(),
            removed: self.tension.len(),
            max_penetration_over_h: max(&self.penetrating),
            max_tension_over_p: max(&self.tension),
            max_gap_error_over_h: self.max_gap_error_over_h,
            relative_residual: residual,
            seconds,
        }
    }
}
