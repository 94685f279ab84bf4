//! The INTERNODES active-set loop: a primal-dual active set method (a semismooth Newton method
//! on the nodal complementarity conditions; Hüeber and Wohlmuth 2005) over interface operators
//! built once (`super::interface`), with its answer checked by independent measures
//! ([`super::checks`]).
//!
//! ```text
//! A <- primary candidates that touch or penetrate in the reference configuration
//! L <- the gap of every primary candidate linearized at u = 0            (frictionless)
//! repeat
//!   1. coupling of A: constraint rows from L (frictionless: node to segment on the secondary
//!      facet each node projects onto; tied: rows of R12 with the correction e), traction
//!      columns through the transfer (R21 or R12^T), lumped M1
//!   2. solve the coupled system for u1, u2, lambda
//!   3. gaps of every candidate: geometric g (closest point, deformed); L <- linearized at u
//!      (tied: e <- g - g_lin); the slide s of the surfaces over each other
//!   4. A' <- {i in A : p_i >= -tol_t p_max}  +  {i not in A : g_i < -tol_p h_i}
//!   5. if A' = A, settled, and s moved more than 0.05 h from the operators' pairing:
//!      pair the operators again for s (each node moved by s), A' <- A
//! until A' = A and every active node lies on the other surface (|g_i| <= 0.01 tol_p h_i),
//!   or A' = A and |g_i| stopped shrinking (by half, twice): converged within tol_p h_i,
//!   stalled beyond
//! check: the residuals of the discrete problem (penetration of both bodies, tension,
//!   complementarity, equilibrium) decide the status; the accuracy indicators are reported
//! ```
//!
//! **Why it converges.** On a fixed active set, step 3 linearizes the very gap step 4 and the
//! checks measure (`super::linearization`): steps 1-3 are Newton's method on `g_A(u) = 0`,
//! exact in one step where the secondary surface is flat and quadratic where it is smooth; on
//! a P1 surface the gap is piecewise linear, and a node on an edge can hold the error at the
//! size of the kink, which the stall test accepts within the tolerance. Over active sets,
//! step 4 is the semismooth Newton step of the complementarity function (below). The former
//! constraint, the rows of `R12` with the gap correction `e = g - g_lin` of the last iterate,
//! is a fixed-point iteration on `e` that contracts only where `R12` reproduces the P1
//! surface; it diverged at the ends of two blocks pressed together, and tied contact, which
//! keeps it, is judged by the same stall test.
//!
//! Step 5 is what lets the bodies slide: the operators pair each node with the point of the
//! other surface it faces, and a body pushed sideways touches the other elsewhere than where it
//! started. The operators change only when the active set has settled, so each pairing is a
//! fixed complementarity problem for the update of step 4.
//!
//! Step 4 is the primal-dual active set update for the nodal complementarity function
//! `C_i = p_i - max(0, p_i - c g_i)`, `c = E*/h`: a node is active next when `p_i - c g_i > 0`.
//! At an active node the constraint holds `g_i = 0`, at an inactive one `p_i = 0`, so the test
//! reads `p_i > 0` on A and `g_i < 0` off it, and `c` drops out; the tolerances make the two
//! tests robust to round-off. Removal and addition happen in one update (`docs/method.md` 3.3).
//! What differs from earlier INTERNODES contact loops: the operators do not change with A
//! (rebuilding them for every active set moves the discrete problem from one iteration to the
//! next), the pressure `p_i = -lambda_i . n_i` tested is the unknown of the system (lumped
//! interface mass, `super::surface`), and the gap is the geometric one, for the loop and the
//! checks alike.
//!
//! An update that would return to an active set seen before first keeps active (pins, for the
//! rest of the solve) the nodes it removes for tension that had been removed before and came
//! back for penetration, and leaves their tension to the certificate: at the rim of a contact
//! zone a node can be in tension while active and penetrate while inactive (seen with tied
//! contact between dissimilar materials: 2% of the peak pressure, then 4e-3 h), and no active
//! set satisfies both tests. If the set still repeats, it takes a single switch instead:
//! only the node with the largest violation (penetration over `h`, tension over `p_max`)
//! changes; if that set was seen too the loop stops as [`ContactStatus::Cycling`]. It never
//! declares convergence. A gap error that stops contracting on one active set beyond the
//! tolerance is [`ContactStatus::Stalled`]; running out of iterations is
//! [`ContactStatus::IterationLimit`]; active nodes held a spacing or more off the other
//! surface on two solves in a row, the second not contracting (or followed by an interface
//! system that cannot be solved accurately), is [`ContactStatus::Unstable`].

use std::collections::{BTreeSet, HashSet};
use std::time::Instant;

use super::checks::{Update, certify, contact_status};
use super::coupled_solver::{self, BodyFactors, CoupledSolver};
use super::interface::{Constraint, InterfaceOperators, geometric_gaps};
use super::linearization::{GapRow, gap_rows};
use super::solution::{ContactSolution, ContactStatus, LinearSolvers, PhaseSeconds};
use super::system::{CoupledSolution, CoupledSystem, Coupling};
use super::{ContactError, ContactProblem, ContactSurface, Formulation, Transfer, post};
use crate::elastic::{AssembledBody, SolveStats, SolverSettings, assemble};
use crate::linalg::BodySolverKind;

/// An active node this many spacings off the other surface after two solves in a row, the second
/// not closer by [`CONTRACTION`], means the constraint no longer controls the geometry
/// ([`ContactStatus::Unstable`]): the stiff half-disc primary at R/500 was 1.3 to 1.8 h off at
/// its second solve, and further off at every solve after. One solve that far off is Newton's
/// method linearizing the gap far from the answer, which the next solve contracts: after the
/// unconstrained first iteration the gap is linearized where the bodies overlap by the whole
/// approach, and the error of that linearization grows with the overlap over the spacing (0.36 h
/// after an overlap of 1.8 h on the 3D R/159 hemisphere; 1.4 h after 3.2 h at R/270, the
/// contact benchmark's 1M DOFs).
const UNSTABLE_GAP_OVER_H: f64 = 1.0;

/// When the surfaces have slid ([`InterfaceOperators::slide`]) this many spacings of the
/// active nodes away from the pairing of the operators, they are paired again once the active
/// set settles.
const REPAIR_DRIFT_OVER_H: f64 = 0.05;

/// How far the slide `now` is from the operators' `slid`, over the smallest spacing of the
/// `active` primary nodes.
fn pairing_drift(
    slid: &[f64; 3],
    now: &[f64; 3],
    primary: &ContactSurface,
    active: &[usize],
) -> f64 {
    let h = (active.iter().map(|&i| primary.spacing[i])).fold(f64::INFINITY, f64::min);
    let distance = (0..3)
        .map(|k| (now[k] - slid[k]).powi(2))
        .sum::<f64>()
        .sqrt();
    if h.is_finite() { distance / h } else { 0.0 }
}

/// The active nodes count as lying on the other surface when their geometric gaps are within
/// this fraction of the penetration tolerance. The gap corrections contract by about ten per
/// iteration, so settling to well inside the tolerance costs a solve or two with an unchanged
/// active set, and makes the answer independent of the path (load steps or one solve) to that
/// precision.
pub(super) const SETTLED: f64 = 0.01;

/// Where an active-set loop starts: the active primary candidates (surface indices) and the
/// linearization point of their constraints: the gap rows of every primary candidate
/// (frictionless, `super::linearization`) or the gap corrections `e` (tied,
/// `super::interface`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ActiveSet {
    pub nodes: BTreeSet<usize>,
    pub rows: Vec<GapRow>,
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
    /// The body solver `factors` holds (`auto` resolved).
    body_solver: BodySolverKind,
    /// Paired for the slide of the last solve; a solve without a start pairs them again
    /// unslid, so that it does not depend on earlier solves.
    operators: InterfaceOperators,
}

/// The interface operators of `problem`, paired with the primary surface slid by `slid` over
/// the secondary ([`InterfaceOperators::slide`]).
fn pair(problem: &ContactProblem, slid: [f64; 3]) -> Result<InterfaceOperators, ContactError> {
    InterfaceOperators::new(
        &problem.primary_surface,
        &problem.secondary_surface,
        problem.settings.rbf_radius,
        problem.normal_weights(),
        problem.transfer().transfer == Transfer::Conservative,
        slid,
    )
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
        let dofs = body1.f_c.len().max(body2.f_c.len());
        let kind = solver.body.resolve_for_contact(s1.dim, dofs);
        let factors = match problem.settings.solver {
            CoupledSolver::MonolithicLu => None,
            _ => {
                let start = Instant::now();
                let factors =
                    BodyFactors::new(&body1, &body2, s1, s2, solver, kind, &problem.settings)?;
                if solver.verbose {
                    let what = match kind {
                        BodySolverKind::CgAmg => "CG + AMG set-up",
                        _ => "Cholesky",
                    };
                    let seconds = start.elapsed().as_secs_f64();
                    eprintln!("  {what} of both bodies: {seconds:.3} s");
                }
                Some(factors)
            }
        };
        let operators = pair(problem, [0.0; 3])?;
        Ok(Self {
            problem,
            solver: *solver,
            body1,
            body2,
            stats1,
            stats2,
            factors,
            body_solver: kind,
            operators,
        })
    }

    /// The body and interface solvers that ran.
    pub fn linear_solvers(&self) -> LinearSolvers {
        match &self.factors {
            None => LinearSolvers {
                body: CoupledSolver::MonolithicLu.name(),
                interface: CoupledSolver::MonolithicLu.name(),
                krylov_failure: None,
            },
            Some(factors) => LinearSolvers {
                body: self.body_solver.name(),
                interface: match factors.is_krylov() {
                    true => CoupledSolver::Krylov.name(),
                    false => CoupledSolver::Schur.name(),
                },
                krylov_failure: factors.fell_back.clone(),
            },
        }
    }

    /// The primary candidates that touch or penetrate in the reference configuration, with
    /// their constraints linearized there.
    pub fn initial_active_set(&self) -> ActiveSet {
        let (s1, s2) = (
            &self.problem.primary_surface,
            &self.problem.secondary_surface,
        );
        let tol = self.problem.settings.penetration_tolerance;
        let gaps = geometric_gaps(s1, s2, None, None);
        ActiveSet {
            nodes: (0..s1.len())
                .filter(|&i| gaps[i] < tol * s1.spacing[i])
                .collect(),
            rows: gap_rows(s1, s2, None, None),
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
        if start.is_none() && self.operators.slid != [0.0; 3] {
            self.pair_again([0.0; 3])?;
        }
        let start = start.cloned().unwrap_or_else(|| self.initial_active_set());
        let (mut active, mut rows, mut corrections) = (start.nodes, start.rows, start.corrections);
        let mut safeguard = Safeguard::default();
        let mut history = Vec::new();
        let mut status = ContactStatus::IterationLimit;
        let mut last = None;
        // The active set `last` was solved on (`active` moves on to the next one).
        let mut solved = active.clone();

        'iterations: for iteration in 1..=settings.max_iterations {
            let mut seconds = PhaseSeconds::default();
            // 1. The coupling of the active set: rows and columns of the fixed operators.
            let nodes: Vec<usize> = active.iter().copied().collect();
            let coupling = timed(&mut seconds.operators, || {
                let formulation = settings.formulation;
                let constraint = match formulation {
                    Formulation::Frictionless => Constraint::Geometric { rows: &rows },
                    Formulation::Tied => Constraint::Interpolated {
                        corrections: &corrections,
                    },
                };
                (self.operators).coupling(s1, s2, formulation, &nodes, constraint)
            });
            // 2-4. The coupled solve; the gaps of every primary candidate, geometric (the
            //    search) and linearized at this iterate, and how far the active nodes' pairing
            //    has slid; the primal-dual active set update. On the Krylov path the solve is
            //    first loose (`LOOSE_GAP`) and solved again exactly when its update would keep
            //    the active set or return to one seen before.
            let mut loose = self.factors.as_ref().is_some_and(BodyFactors::is_krylov);
            let h = (nodes.iter().map(|&i| s1.spacing[i])).fold(f64::INFINITY, f64::min);
            let loose_gap = LOOSE_GAP * settings.penetration_tolerance * h;
            let mut krylov_iterations = None;
            let (solution, gaps, slid, update, linear) = loop {
                let solved_now = timed(&mut seconds.solve, || {
                    let gap_tolerance = (loose && loose_gap.is_finite()).then_some(loose_gap);
                    self.coupled_solve(&coupling, load_factor, gap_tolerance)
                });
                let solution = match solved_now {
                    // After a solve that left active nodes a spacing off the surface, an
                    // interface system that cannot be solved accurately is the same diagnosis
                    // as `Unstable`: the constraint does not control the geometry. The last
                    // iterate is the answer, its certificate says what fails.
                    Err(ContactError::Inaccurate { .. })
                        if safeguard.off_surface.is_some() && last.is_some() =>
                    {
                        status = ContactStatus::Unstable;
                        active = solved;
                        break 'iterations;
                    }
                    solved_now => solved_now?,
                };
                if let Some(stats) = self.factors.as_ref().and_then(|f| f.last_krylov) {
                    *krylov_iterations.get_or_insert(0) += stats.iterations;
                }
                let (u1, u2) = (&solution.u1[..], &solution.u2[..]);
                let (gaps, linear, slid) = timed(&mut seconds.search, || {
                    let gaps = geometric_gaps(s1, s2, Some(u1), Some(u2));
                    rows = gap_rows(s1, s2, Some(u1), Some(u2));
                    let jumps = self.operators.jumps(s1, s2, u1, u2);
                    let slid = self.operators.slide(s1, &jumps, &nodes);
                    (gaps, self.operators.linearized_gaps(&jumps), slid)
                });
                // The gap each active node's constraint holds: the gap of its linearization.
                let held: Vec<f64> = match settings.formulation {
                    Formulation::Frictionless => rows.iter().map(|r| r.gap).collect(),
                    Formulation::Tied => gaps.clone(),
                };
                let update = timed(&mut seconds.checks, || {
                    let (traction, normals) = (&solution.traction, &coupling.normals);
                    Update::new(
                        problem,
                        &nodes,
                        traction,
                        normals,
                        [&gaps, &held],
                        &safeguard.pinned,
                    )
                });
                if loose && (update.next == active || safeguard.seen.contains(&update.next)) {
                    loose = false;
                    continue;
                }
                break (solution, gaps, slid, update, linear);
            };
            let drift = pairing_drift(&self.operators.slid, &slid, s1, &nodes);
            if settings.formulation == Formulation::Tied {
                corrections = gaps.iter().zip(&linear).map(|(g, l)| g - l).collect();
            }
            // 5. Stop, or go on with the next set (safeguarded against repeats); a set that
            //    settled on a pairing the surfaces have slid away from is paired again where
            //    they touch, and solved again.
            let step = match safeguard.next(&active, &update) {
                Step::Stop(ContactStatus::Converged) if drift > REPAIR_DRIFT_OVER_H => {
                    timed(&mut seconds.operators, || self.pair_again(slid))?;
                    let jumps = (self.operators).jumps(s1, s2, &solution.u1, &solution.u2);
                    let linear = self.operators.linearized_gaps(&jumps);
                    corrections = gaps.iter().zip(&linear).map(|(g, l)| g - l).collect();
                    safeguard = Safeguard::default();
                    Step::Solve(active.clone())
                }
                step => step,
            };
            let residual = solution.relative_residual;
            let mut record = update.record(iteration, residual, drift, seconds);
            record.krylov_iterations = krylov_iterations;
            if self.solver.verbose {
                eprintln!("{}", record.line());
            }
            history.push(record);
            last = Some((coupling, solution));
            solved = active.clone();
            match step {
                Step::Solve(next) => active = next,
                Step::Stop(end) => {
                    status = end;
                    break;
                }
            }
        }

        let (coupling, solution) = last.expect("max_iterations >= 1 is validated");
        let nodes: Vec<usize> = active.iter().copied().collect();
        let (certificate, gaps) = certify(problem, &solution, &nodes);
        let status = contact_status(status, &certificate, active.is_empty());
        let next_start = ActiveSet {
            nodes: active,
            rows,
            corrections,
        };
        post::finish(
            self,
            load_factor,
            status,
            history,
            certificate,
            gaps,
            &coupling,
            solution,
            next_start,
        )
    }
}

impl ContactSolver<'_> {
    /// Builds the interface operators again, paired with the primary surface slid by `slid`;
    /// the bodies' responses computed with the old ones are forgotten.
    fn pair_again(&mut self, slid: [f64; 3]) -> Result<(), ContactError> {
        self.operators = pair(self.problem, slid)?;
        if let Some(factors) = self.factors.as_mut() {
            factors.forget_responses();
        }
        Ok(())
    }

    /// The coupled system of `coupling`, solved and checked by its relative residual; or,
    /// with a `gap_tolerance` (a length; Krylov path), solved until every active node's gap
    /// is held to it, its residual only recorded.
    fn coupled_solve(
        &mut self,
        coupling: &Coupling,
        load_factor: f64,
        gap_tolerance: Option<f64>,
    ) -> Result<CoupledSolution, ContactError> {
        let dim = self.problem.primary_surface.dim;
        let system = CoupledSystem::assemble(&self.body1, &self.body2, coupling, dim, load_factor)?;
        let x = match self.factors.as_mut() {
            None => coupled_solver::solve_monolithic(&system, &self.body1, &self.body2)?,
            Some(factors) => {
                factors.solve(&system, coupling, &self.body1.coordinates, gap_tolerance)?
            }
        };
        let loose =
            gap_tolerance.is_some() && self.factors.as_ref().is_some_and(BodyFactors::is_krylov);
        let residual = system.relative_residual(&self.body1, &self.body2, &x);
        if residual.is_nan() || (!loose && residual > self.solver.residual_tolerance) {
            return Err(ContactError::Inaccurate {
                residual,
                tolerance: self.solver.residual_tolerance,
            });
        }
        Ok(system.solution(&x, coupling, dim, residual))
    }
}

/// A loose interface solve holds every active node's gap to this fraction of the penetration
/// tolerance `tol_p h` (the smallest spacing of the active nodes). The update only reads gaps
/// against `tol_p h` (a node penetrating beyond it joins the active set) and the signs of the
/// pressures, so an iterate that is about to change the active set needs no more: its exact
/// solve would be thrown away with the set. The iteration that keeps the set, and so may
/// end the loop, is solved again to round-off (from the loose answer) before it is judged:
/// no answer, status or check rests on a loose solve.
const LOOSE_GAP: f64 = 0.1;

/// What the loop does after an iteration.
enum Step {
    /// Solve again with this active set (possibly the same, with corrected gaps).
    Solve(BTreeSet<usize>),
    Stop(ContactStatus),
}

/// The loop's memory against repeats (module doc): the sets seen, the nodes removed for
/// tension, those of them added back for penetration, and those kept active for good.
#[derive(Default)]
struct Safeguard {
    seen: HashSet<BTreeSet<usize>>,
    released: HashSet<usize>,
    readded: HashSet<usize>,
    pinned: HashSet<usize>,
    /// The smallest active nodes' gap error of the iterations on the current active set.
    best_error: Option<f64>,
    /// The active nodes' gap error (over h) of the last iteration, when beyond
    /// [`UNSTABLE_GAP_OVER_H`].
    off_surface: Option<f64>,
    /// How many iterations in a row on one active set failed to contract the gap error.
    slow: usize,
    /// The smallest violation of the contact conditions so far ([`violation`]), and how many
    /// iterations have passed without going below it.
    best_violation: Option<f64>,
    since_best: usize,
}

/// The largest violation of the nodal contact conditions an update found: penetration of an
/// inactive node (over `h`), tension of an active one (over `p_max`), and the active nodes'
/// distance to the other surface (over `h`).
fn violation(update: &Update) -> f64 {
    let max = |v: &[(usize, f64)]| v.iter().map(|x| x.1).fold(0.0, f64::max);
    max(&update.penetrating) + max(&update.tension) + update.max_gap_error_over_h
}

/// The primal-dual active set method converges superlinearly once near the solution: on the
/// sweep the set settles in 3 to 9 iterations. An iteration that does not reduce the smallest
/// violation found so far makes no progress; this many in a row end the loop as
/// [`ContactStatus::Stalled`] (the active set wandering through new sets, as a stiff primary
/// named by hand did for 50 iterations on a 3D foreign mesh), instead of running to the cap.
const NO_PROGRESS_AFTER: usize = 10;

/// On an unchanged active set the linearized constraint must shrink the active nodes' gap
/// error (`Update::max_gap_error_over_h`) to at most this factor of the smallest error seen on
/// that set (not of the last one: an error alternating between two values, 9.6e-5 h and
/// 2.9e-5 h on a 3D block held by a narrower one, halves every other iteration): Newton's
/// method on the gap ([`super::linearization`]) does far better (quadratic, exact in one step
/// on a flat), the tied fixed-point correction by about ten. An iteration that does not is
/// outside the regime where the iteration converges for a reason: [`STALLED_AFTER`] such
/// iterations in a row end the loop, converged if the error is within the penetration
/// tolerance (the complementarity residual the certificate checks), as
/// [`ContactStatus::Stalled`] otherwise, instead of running to the iteration cap. (A node on
/// an edge of the other P1 surface can hold the error at 1e-5 h, its closest facet changing
/// every iteration: seen on the half-disc, whose block surface bends at each node.)
const CONTRACTION: f64 = 0.5;

/// See [`CONTRACTION`].
const STALLED_AFTER: usize = 2;

impl Safeguard {
    fn next(&mut self, active: &BTreeSet<usize>, update: &Update) -> Step {
        let nodes = |v: &[(usize, f64)]| v.iter().map(|&(i, _)| i).collect::<Vec<_>>();
        let added_back = nodes(&update.penetrating);
        let released = &self.released;
        self.readded
            .extend(added_back.into_iter().filter(|i| released.contains(i)));
        self.released.extend(nodes(&update.tension));
        let off = update.max_gap_error_over_h;
        if off > UNSTABLE_GAP_OVER_H {
            if self
                .off_surface
                .is_some_and(|last| off > CONTRACTION * last)
            {
                return Step::Stop(ContactStatus::Unstable);
            }
            self.off_surface = Some(off);
        } else {
            self.off_surface = None;
        }
        let v = violation(update);
        if self.best_violation.is_none_or(|best| v < best) {
            (self.best_violation, self.since_best) = (Some(v), 0);
        } else {
            self.since_best += 1;
            if self.since_best >= NO_PROGRESS_AFTER && !update.settled {
                return Step::Stop(ContactStatus::Stalled);
            }
        }
        if update.next == *active {
            if update.settled {
                return Step::Stop(ContactStatus::Converged);
            }
            let error = update.max_gap_error_over_h;
            let contracted = (self.best_error).is_none_or(|best| error <= CONTRACTION * best);
            self.slow = if contracted { 0 } else { self.slow + 1 };
            self.best_error = Some(self.best_error.map_or(error, |best| best.min(error)));
            return if self.slow >= STALLED_AFTER {
                // Newton's method on a piecewise linear gap stops contracting where a node sits
                // on an edge of the other surface, its closest facet changing from one
                // iteration to the next; within the complementarity tolerance that is an
                // answer, beyond it a failure.
                Step::Stop(if update.within_tolerance {
                    ContactStatus::Converged
                } else {
                    ContactStatus::Stalled
                })
            } else {
                Step::Solve(active.clone())
            };
        }
        (self.best_error, self.slow) = (None, 0);
        self.seen.insert(active.clone());
        let mut next = update.next.clone();
        if self.seen.contains(&next) {
            // First keep active the nodes in tension that came back after an earlier removal.
            let readded = &self.readded;
            let alternating: Vec<usize> = nodes(&update.tension)
                .into_iter()
                .filter(|i| readded.contains(i))
                .collect();
            self.pinned.extend(alternating.iter().copied());
            next.extend(alternating);
            if next == *active {
                return Step::Solve(next);
            }
        }
        if self.seen.contains(&next) {
            match update.single_switch(active) {
                Some(switched) if !self.seen.contains(&switched) => next = switched,
                _ => return Step::Stop(ContactStatus::Cycling),
            }
        }
        Step::Solve(next)
    }
}

/// Runs `f`, adding its wall-clock seconds to `slot`.
fn timed<T>(slot: &mut f64, f: impl FnOnce() -> T) -> T {
    let clock = Instant::now();
    let value = f();
    *slot += clock.elapsed().as_secs_f64();
    value
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An update that keeps `active` as it is, with the active nodes' gap error `error` (over
    /// h), settled or not.
    fn unchanged(active: &BTreeSet<usize>, error: f64, settled: bool) -> Update {
        Update {
            next: active.clone(),
            tension: Vec::new(),
            penetrating: Vec::new(),
            settled,
            within_tolerance: error <= 1e-3,
            active: active.len(),
            max_gap_error_over_h: error,
        }
    }

    fn status(step: Step) -> Option<ContactStatus> {
        match step {
            Step::Stop(status) => Some(status),
            Step::Solve(_) => None,
        }
    }

    #[test]
    fn a_gap_error_that_stops_contracting_ends_stalled() {
        let active: BTreeSet<usize> = [1, 2, 3].into();
        let mut safeguard = Safeguard::default();
        // The first solve of a set has nothing to compare with; then 0.9 and 0.95 of the last.
        assert_eq!(
            status(safeguard.next(&active, &unchanged(&active, 1e-2, false))),
            None
        );
        assert_eq!(
            status(safeguard.next(&active, &unchanged(&active, 9e-3, false))),
            None
        );
        assert_eq!(
            status(safeguard.next(&active, &unchanged(&active, 8.5e-3, false))),
            Some(ContactStatus::Stalled)
        );
    }

    #[test]
    fn an_alternating_gap_error_ends_the_loop() {
        let active: BTreeSet<usize> = [1, 2].into();
        let mut safeguard = Safeguard::default();
        let errors = [4.6e-4, 9.6e-5, 2.9e-5, 9.6e-5, 2.9e-5];
        for error in &errors[..4] {
            assert_eq!(
                status(safeguard.next(&active, &unchanged(&active, *error, false))),
                None
            );
        }
        assert_eq!(
            status(safeguard.next(&active, &unchanged(&active, errors[4], false))),
            Some(ContactStatus::Converged)
        );
    }

    #[test]
    fn active_nodes_off_the_surface_twice_without_contracting_end_unstable() {
        let active: BTreeSet<usize> = [1, 2].into();
        // Once far off, then contracting by Newton's method: goes on.
        let mut safeguard = Safeguard::default();
        assert_eq!(
            status(safeguard.next(&active, &unchanged(&active, 1.4, false))),
            None
        );
        assert_eq!(
            status(safeguard.next(&active, &unchanged(&active, 0.2, false))),
            None
        );
        // Far off twice, the second no closer: the constraint does not hold the geometry.
        let mut safeguard = Safeguard::default();
        assert_eq!(
            status(safeguard.next(&active, &unchanged(&active, 1.3, false))),
            None
        );
        assert_eq!(
            status(safeguard.next(&active, &unchanged(&active, 1.8, false))),
            Some(ContactStatus::Unstable)
        );
    }

    #[test]
    fn an_active_set_that_wanders_without_progress_ends_stalled() {
        let mut safeguard = Safeguard::default();
        for k in 0..NO_PROGRESS_AFTER + 1 {
            let active: BTreeSet<usize> = [k].into();
            let mut update = unchanged(&active, 1e-4, false);
            update.next = [k + 1].into();
            update.penetrating = vec![(k + 1, 0.02)];
            let expected = (k == NO_PROGRESS_AFTER).then_some(ContactStatus::Stalled);
            assert_eq!(
                status(safeguard.next(&active, &update)),
                expected,
                "iteration {k}"
            );
        }
    }

    #[test]
    fn a_stalled_gap_error_within_the_tolerance_is_converged() {
        let active: BTreeSet<usize> = [4].into();
        let mut safeguard = Safeguard::default();
        for error in [1.2e-5, 1.1e-5] {
            assert_eq!(
                status(safeguard.next(&active, &unchanged(&active, error, false))),
                None
            );
        }
        assert_eq!(
            status(safeguard.next(&active, &unchanged(&active, 1.2e-5, false))),
            Some(ContactStatus::Converged)
        );
    }

    #[test]
    fn a_contracting_gap_error_goes_on_until_it_settles() {
        let active: BTreeSet<usize> = [1, 2].into();
        let mut safeguard = Safeguard::default();
        for error in [1e-1, 4e-2, 1e-3, 1e-6] {
            assert_eq!(
                status(safeguard.next(&active, &unchanged(&active, error, false))),
                None
            );
        }
        assert_eq!(
            status(safeguard.next(&active, &unchanged(&active, 1e-9, true))),
            Some(ContactStatus::Converged)
        );
    }

    #[test]
    fn a_slow_iteration_on_a_new_active_set_starts_the_count_again() {
        let (first, second): (BTreeSet<usize>, BTreeSet<usize>) = ([1, 2].into(), [1, 2, 3].into());
        let mut safeguard = Safeguard::default();
        assert_eq!(
            status(safeguard.next(&first, &unchanged(&first, 1e-2, false))),
            None
        );
        assert_eq!(
            status(safeguard.next(&first, &unchanged(&first, 9e-3, false))),
            None
        );
        let mut grow = unchanged(&first, 9e-3, false);
        grow.next = second.clone();
        assert_eq!(status(safeguard.next(&first, &grow)), None);
        assert_eq!(
            status(safeguard.next(&second, &unchanged(&second, 8e-3, false))),
            None
        );
        assert_eq!(
            status(safeguard.next(&second, &unchanged(&second, 7.9e-3, false))),
            None
        );
        assert_eq!(
            status(safeguard.next(&second, &unchanged(&second, 7.8e-3, false))),
            Some(ContactStatus::Stalled)
        );
    }
}
