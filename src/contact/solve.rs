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
//! checks measure (`super::gap`): steps 1-3 are Newton's method on `g_A(u) = 0`,
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

use std::collections::{BTreeSet, HashMap};
use std::time::Instant;

use super::active_set::{ActiveSet, Update};
use super::checks::{certify, contact_status};
use super::coupled_krylov::Tightness;
use super::coupled_solver::{self, BodyFactors};
use super::gap::{GapRow, gap_rows, geometric_gaps};
use super::half_space::{compliance_factor, force_controlled_set, predicted_set};
use super::interface::{Constraint, InterfaceOperators};
use super::post::{self, LastIterate};
use super::safeguard::{Safeguard, Step};
use super::settings::CoupledSolver;
use super::solution::{
    ContactSolution, ContactStatus, IterationRecord, LinearSolvers, PhaseSeconds,
};
use super::system::{CoupledSolution, CoupledSystem, Coupling, Pair};
use super::{ContactError, ContactProblem, ContactSurface, Formulation, Transfer};
use crate::elastic::{AssembledBody, SolveStats, SolverSettings, assemble};
use crate::fem::rigid_modes::RigidModes;
use crate::linalg::BodySolverKind;

/// [`ContactSolver::check_held`]: a free motion is held when the Gram matrix's eigenvalue along
/// it, per row, exceeds this. Measured (2026-11-28): a block resting flat, its rotation 0.15; a
/// half-disc turning about its centre, with the disc's own normals 0 (2D) and a hemisphere's
/// 3e-8 to 6e-8 (3D: P1 vertex normals are radial to about 2e-4); along the flat block's
/// normals the hemisphere's turn still reads 3e-6 to 3e-4, which is why the body's own normals
/// are tested too. A rotation held by a zone 2% of the body's size across reads about 3e-5.
const HELD_PER_ROW: f64 = 1e-6;

/// The rigid motions (combinations of [`RigidModes`], one per column) that `body`'s supports
/// leave free: those that vanish on its prescribed dofs and move each force-controlled group
/// uniformly along its component (the group is one plate); its rigid-mode pins hold nothing.
/// They are the null space of the Gram matrix of those conditions' rows.
fn motions_left_free(coords: &[[f64; 3]], body: &AssembledBody) -> nalgebra::DMatrix<f64> {
    let dim = body.dim;
    let modes = RigidModes::new(coords, dim);
    let count = modes.count();
    let value = |dof: usize| -> Vec<f64> {
        let at = modes.at(&coords[dof / dim]);
        at.iter().map(|m| m[dof % dim]).collect()
    };
    let mut gram = nalgebra::DMatrix::<f64>::zeros(count, count);
    let mut add = |row: Vec<f64>| {
        let row = nalgebra::DVector::from_vec(row);
        gram += &row * row.transpose();
    };
    let rigid: HashMap<usize, usize> = (body.rigid.iter().enumerate())
        .flat_map(|(r, rigid)| rigid.dofs.iter().map(move |&dof| (dof, r)))
        .collect();
    for dof in (0..body.f_c.len()).filter(|&d| body.constraints.is_fixed(d)) {
        if !rigid.contains_key(&dof) {
            add(value(dof));
        }
    }
    for group in body.rigid.iter().filter(|rigid| !rigid.pin) {
        let first = value(group.dofs[0]);
        for &dof in &group.dofs[1..] {
            add(value(dof).iter().zip(&first).map(|(a, b)| a - b).collect());
        }
    }
    let eigen = nalgebra::SymmetricEigen::new(gram);
    let largest = eigen.eigenvalues.iter().cloned().fold(0.0, f64::max);
    let free: Vec<usize> = (0..count)
        .filter(|&i| eigen.eigenvalues[i] <= 1e-10 * largest || largest == 0.0)
        .collect();
    nalgebra::DMatrix::from_fn(count, free.len(), |r, c| eigen.eigenvectors[(r, free[c])])
}

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
    /// The force-controlled components `(body, index into its rigid columns)` that nothing but
    /// the contact holds (body 0 the primary): with no node in contact the system is singular.
    held_by_contact: Vec<(usize, usize)>,
    /// The body (0 the primary) that only the contact holds along some rigid motions, with
    /// those motions (combinations of `crate::fem::rigid_modes::RigidModes`, one per column):
    /// the motions its Dirichlet supports leave free.
    free_motions: Option<(usize, nalgebra::DMatrix<f64>)>,
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

/// The nodes of a body whose displacements the constraint rows read: its candidate surface's,
/// and the nodes a force-controlled group's row reads (its column `k`).
fn read_nodes(surface: &ContactSurface, body: &AssembledBody) -> Vec<usize> {
    let mut nodes = surface.nodes.clone();
    for rigid in &body.rigid {
        nodes.extend(rigid.column.iter().map(|&(dof, _)| dof / body.dim));
    }
    nodes.sort_unstable();
    nodes.dedup();
    nodes
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
        let kind = solver.body.resolve(s1.dim, dofs);
        let factors = match problem.settings.solver {
            CoupledSolver::MonolithicLu => None,
            _ => {
                let start = Instant::now();
                let materials = [&problem.primary.material, &problem.secondary.material];
                let factors = BodyFactors::new(
                    &[&body1, &body2],
                    vec![read_nodes(s1, &body1), read_nodes(s2, &body2)],
                    vec![compliance_factor(materials, s1.dim)],
                    solver,
                    kind,
                    &problem.settings,
                )?;
                if solver.verbose {
                    let what = match kind {
                        BodySolverKind::CgAmg => "CG + AMG set-up",
                        _ => "Cholesky",
                    };
                    let seconds = start.elapsed().as_secs_f64();
                    log::info!("  {what} of both bodies: {seconds:.3} s");
                }
                Some(factors)
            }
        };
        let operators = pair(problem, [0.0; 3])?;
        let held_by_contact = coupled_solver::held_by_contacts_only(
            &[&body1, &body2],
            factors.as_ref(),
            solver.ordering,
        )?
        .into_iter()
        .enumerate()
        .flat_map(|(k, held)| held.into_iter().map(move |r| (k, r)))
        .collect::<Vec<_>>();
        if held_by_contact.iter().any(|h| h.0 == 0) && held_by_contact.iter().any(|h| h.0 == 1) {
            return Err(ContactError::NothingHolds {
                first: problem.primary.body.name.clone(),
                second: problem.secondary.body.name.clone(),
            });
        }
        let free_motions = held_by_contact.first().map(|&(k, _)| {
            let (elastic, body) = match k {
                0 => (&problem.primary, &body1),
                _ => (&problem.secondary, &body2),
            };
            (k, motions_left_free(&elastic.body.coords, body))
        });
        Ok(Self {
            problem,
            solver: solver.clone(),
            body1,
            body2,
            stats1,
            stats2,
            factors,
            held_by_contact,
            free_motions,
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
                body_applications: None,
            },
            Some(factors) => LinearSolvers {
                body: factors.body_kind().name(),
                interface: match factors.is_krylov() {
                    true => CoupledSolver::Krylov.name(),
                    false => CoupledSolver::Schur.name(),
                },
                krylov_failure: factors.fell_back.clone(),
                body_applications: factors.body_applications(),
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
        if start.is_none() && self.operators.slid != [0.0; 3] {
            self.pair_again([0.0; 3])?;
        }
        let cold = start.is_none();
        let start = start.cloned().unwrap_or_else(|| self.initial_active_set());
        let mut state = LoopState {
            solved: start.nodes.clone(),
            active: start.nodes,
            rows: start.rows,
            corrections: start.corrections,
            safeguard: Safeguard::default(),
            history: Vec::new(),
            last: None,
            cold,
            first_contact: false,
        };
        let mut status = ContactStatus::IterationLimit;
        for iteration in 1..=self.problem.settings.max_iterations {
            self.solver.cancel.check()?;
            if let Some(end) = self.iteration(&mut state, iteration, load_factor)? {
                status = end;
                break;
            }
        }

        let (coupling, solution) = state.last.expect("max_iterations >= 1 is validated");
        let next_start = ActiveSet {
            nodes: state.active,
            rows: state.rows,
            corrections: state.corrections,
        };
        self.finish(
            load_factor,
            status,
            state.history,
            &coupling,
            solution,
            next_start,
        )
    }
}

/// The active-set loop between two iterations.
struct LoopState {
    /// The active set the next iteration solves on.
    active: BTreeSet<usize>,
    rows: Vec<GapRow>,
    corrections: Vec<f64>,
    safeguard: Safeguard,
    history: Vec<IterationRecord>,
    /// The last iterate: its coupling and solution.
    last: Option<(Coupling, CoupledSolution)>,
    /// The active set `last` was solved on (`active` moves on to the next one).
    solved: BTreeSet<usize>,
    /// Whether the solve started without an active set from an earlier one.
    cold: bool,
    /// Whether the loop has chosen where a body that only its contacts hold touches first
    /// ([`ContactSolver::first_contact`]).
    first_contact: bool,
}

impl LoopState {
    /// Keeps an iteration's `record` and `last` iterate, and moves on to its `step`: the status
    /// the loop ends with, or `None` to go on with the next active set.
    fn advance(
        &mut self,
        record: IterationRecord,
        last: (Coupling, CoupledSolution),
        step: Step,
    ) -> Option<ContactStatus> {
        self.history.push(record);
        self.last = Some(last);
        self.solved = self.active.clone();
        match step {
            Step::Solve(next) => {
                self.active = next;
                None
            }
            Step::Stop(end) => Some(end),
        }
    }
}

impl ContactSolver<'_> {
    /// One iteration of the loop on `state.active`, recorded in `state`: the status the loop
    /// ends with, or `None` to go on with the next active set.
    fn iteration(
        &mut self,
        state: &mut LoopState,
        iteration: usize,
        load_factor: f64,
    ) -> Result<Option<ContactStatus>, ContactError> {
        let problem = self.problem;
        let mut seconds = PhaseSeconds::default();
        if state.active.is_empty() || (iteration == 1 && state.cold) {
            self.first_contact(state, load_factor)?;
        }
        // 1. The coupling of the active set: rows and columns of the fixed operators.
        let nodes: Vec<usize> = state.active.iter().copied().collect();
        let coupling = timed(&mut seconds.operators, || {
            self.coupling(&nodes, &state.rows, &state.corrections)
        });
        self.check_held(&coupling, &nodes)?;
        // 2-4. The coupled solve, the gaps at the iterate, the active set update.
        let iterate = self.iterate(
            &coupling,
            &state.active,
            load_factor,
            &state.safeguard,
            &mut state.rows,
            &mut seconds,
        );
        let Iterate {
            solution,
            gaps,
            linear,
            slid,
            update,
            krylov_iterations,
        } = match iterate {
            // After a solve that left active nodes a spacing off the surface, an interface
            // system that cannot be solved accurately is the same diagnosis as `Unstable`:
            // the constraint does not control the geometry. The last iterate is the
            // answer, its certificate says what fails.
            Err(ContactError::Inaccurate { .. })
                if state.safeguard.off_surface.is_some() && state.last.is_some() =>
            {
                state.active = std::mem::take(&mut state.solved);
                return Ok(Some(ContactStatus::Unstable));
            }
            iterate => iterate?,
        };
        let drift = pairing_drift(
            &self.operators.slid,
            &slid,
            &problem.primary_surface,
            &nodes,
        );
        if problem.settings.formulation == Formulation::Tied {
            state.corrections = gaps.iter().zip(&linear).map(|(g, l)| g - l).collect();
        }
        // 5. Stop, or go on with the next set (safeguarded against repeats); a set that
        //    settled on a pairing the surfaces have slid away from is paired again where
        //    they touch, and solved again.
        let step = match state.safeguard.next(&state.active, &update) {
            Step::Stop(ContactStatus::Converged) if drift > REPAIR_DRIFT_OVER_H => {
                timed(&mut seconds.operators, || self.pair_again(slid))?;
                state.corrections = self.corrections(&solution, &gaps);
                state.safeguard = Safeguard::default();
                Step::Solve(state.active.clone())
            }
            // The first iteration of a solve goes on with the set the half-space model
            // predicts, rather than with every penetrating node.
            Step::Solve(next)
                if iteration == 1
                    && !update.penetrating.is_empty()
                    && problem.settings.formulation == Formulation::Frictionless =>
            {
                Step::Solve(self.predicted(&next, &update, &nodes, &solution, &coupling, &gaps))
            }
            step => step,
        };
        let residual = solution.relative_residual;
        let record = record(
            &update,
            iteration,
            residual,
            drift,
            krylov_iterations,
            seconds,
        );
        if self.solver.verbose {
            log::info!("{}", record.line());
        }
        Ok(state.advance(record, (coupling, solution), step))
    }

    /// Where a body that nothing but the contact holds along a force-controlled component
    /// touches first, when the loop starts cold or has no node in contact: with no node in
    /// contact its system is singular (the force would move it without bound), and from the
    /// nodes that merely touch (a sphere's pole) the first iterate would carry the whole force
    /// on them. The active set becomes the half-space model's zone for the force
    /// (`super::half_space::force_controlled_set`), or the closest node if the model finds
    /// none. If the loop lets go of every contact after that, the force pulls the body off: an
    /// error that names it.
    fn first_contact(&self, state: &mut LoopState, load_factor: f64) -> Result<(), ContactError> {
        let Some(&(body, index)) = self.held_by_contact.first() else {
            return Ok(());
        };
        let (name, assembled) = match body {
            0 => (&self.problem.primary.body.name, &self.body1),
            _ => (&self.problem.secondary.body.name, &self.body2),
        };
        let rigid = &assembled.rigid[index];
        let component = ["x", "y", "z"][rigid.component];
        if state.first_contact {
            if state.active.is_empty() {
                return Err(match rigid.pin {
                    true => ContactError::FloatsAway { body: name.clone() },
                    false => ContactError::PulledAway {
                        body: name.clone(),
                        group: rigid.group.clone(),
                        component,
                    },
                });
            }
            return Ok(());
        }
        let problem = self.problem;
        let (s1, s2) = (&problem.primary_surface, &problem.secondary_surface);
        let gaps = match state.last.as_ref().map(|(_, solution)| &solution.u) {
            Some(u) => geometric_gaps(s1, s2, Some(&u[0]), Some(&u[1])),
            None => geometric_gaps(s1, s2, None, None),
        };
        // The force the contact carries, at most: the resultant of the body's loads and of the
        // forces on its force-controlled groups (its supports may carry part of it; the zone
        // then errs on the large side, which the loop corrects).
        let dim = assembled.dim;
        let force = (0..dim)
            .map(|c| {
                let on_groups: f64 = (assembled.rigid.iter())
                    .filter(|rigid| !rigid.pin && rigid.component == c)
                    .map(|rigid| rigid.force)
                    .sum();
                let loads: f64 = assembled.f.iter().skip(c).step_by(dim).sum();
                (load_factor * (on_groups + loads)).powi(2)
            })
            .sum::<f64>()
            .sqrt();
        let materials = [&problem.primary.material, &problem.secondary.material];
        let c0 = compliance_factor(materials, s1.dim);
        let mut zone: BTreeSet<usize> = force_controlled_set(s1, &gaps, force, c0)
            .into_iter()
            .collect();
        if zone.is_empty() {
            let closest = (0..s1.len()).min_by(|&a, &b| gaps[a].total_cmp(&gaps[b]));
            zone.extend(closest);
        }
        if self.solver.verbose {
            log::info!(
                "  '{name}' is held along {component} only by the contact: it starts on the {} \
                 nodes where two half-spaces would carry its force {force:.6e}",
                zone.len()
            );
        }
        state.active = zone;
        state.first_contact = true;
        Ok(())
    }

    /// An error unless the contact of the active `nodes` (with their `coupling`) holds the
    /// body that only the contact holds along the motions its supports leave free: each
    /// motion must move some active node along a direction its constraint holds (the normal;
    /// every direction for tied contact). Without it the coupled system is singular along that
    /// motion, and a Krylov solve may still return one of its infinitely many answers.
    ///
    /// The test: with `h_i = [d . r_j(x_i)]_j` for each held direction `d` at each active node
    /// `x_i` and the free motions `V`, the Gram matrix `sum (h_i V)^T (h_i V)` must have no
    /// eigenvalue below [`HELD_PER_ROW`] times the number of rows (each `h_i` has a unit
    /// translation part, and the rotations are scaled by the body's size).
    fn check_held(&self, coupling: &Coupling, nodes: &[usize]) -> Result<(), ContactError> {
        let Some((body, motions)) = &self.free_motions else {
            return Ok(());
        };
        let free = motions.ncols();
        if free == 0 || nodes.is_empty() {
            return Ok(());
        }
        let problem = self.problem;
        let elastic = match body {
            0 => &problem.primary,
            _ => &problem.secondary,
        };
        let dim = elastic.body.dim;
        let modes = RigidModes::new(&elastic.body.coords, dim);
        let s1 = &problem.primary_surface;
        // The directions each active node holds. Frictionless: its normal, taken once as the
        // secondary facet's (the constraint's) and once as the primary surface's own: a round
        // body turning about its centre moves its nodes along the other body's normal but
        // maps its surface onto itself, so only its own normals show that nothing holds it.
        let own: Vec<[f64; 3]> = match body {
            0 => nodes.iter().map(|&i| s1.normals[i]).collect(),
            // The secondary's own normal where each active node touches it: its nodes'
            // normals weighted as the constraint row weighs them.
            _ => {
                let s2 = &problem.secondary_surface;
                let surface_index: HashMap<usize, usize> =
                    s2.nodes.iter().enumerate().map(|(s, &n)| (n, s)).collect();
                (coupling.r12.iter())
                    .map(|row| {
                        let mut n = [0.0; 3];
                        for &(node, w) in row {
                            if let Some(&s) = surface_index.get(&node) {
                                (0..3).for_each(|c| n[c] += w * s2.normals[s][c]);
                            }
                        }
                        let length = (0..3).map(|c| n[c] * n[c]).sum::<f64>().sqrt();
                        n.map(|v| if length > 0.0 { v / length } else { 0.0 })
                    })
                    .collect()
            }
        };
        let direction_sets: Vec<Vec<Vec<[f64; 3]>>> = match problem.settings.formulation {
            Formulation::Frictionless => vec![
                (0..nodes.len())
                    .map(|k| vec![coupling.normals[k]])
                    .collect(),
                own.into_iter().map(|n| vec![n]).collect(),
            ],
            Formulation::Tied => vec![
                (0..nodes.len())
                    .map(|_| {
                        (0..dim)
                            .map(|c| std::array::from_fn(|j| f64::from(u8::from(j == c))))
                            .collect()
                    })
                    .collect(),
            ],
        };
        let mut unheld = 0;
        for directions in direction_sets {
            let mut gram = nalgebra::DMatrix::<f64>::zeros(free, free);
            let mut rows = 0.0;
            for (&i, at_node) in nodes.iter().zip(directions) {
                let at = modes.at(&s1.coords[i]);
                for d in at_node {
                    let h = nalgebra::DVector::from_iterator(
                        at.len(),
                        at.iter().map(|r| (0..3).map(|c| d[c] * r[c]).sum::<f64>()),
                    );
                    let hv = motions.transpose() * h;
                    gram += &hv * hv.transpose();
                    rows += 1.0;
                }
            }
            let eigenvalues = nalgebra::SymmetricEigen::new(gram).eigenvalues;
            let held = |e: &&f64| **e > HELD_PER_ROW * rows;
            unheld = unheld.max(eigenvalues.iter().filter(|e| !held(e)).count());
        }
        if unheld > 0 {
            return Err(ContactError::NotHeld {
                body: elastic.body.name.clone(),
                free: unheld,
                active: nodes.len(),
            });
        }
        Ok(())
    }

    /// The active set the half-space model predicts (`super::half_space::predicted_set`) from
    /// the iterate `solution` on the active `nodes` with its `coupling`, over the nodes the
    /// update keeps or adds (`next`) and those it removes; `next` itself if the model predicts
    /// no contact.
    fn predicted(
        &self,
        next: &BTreeSet<usize>,
        update: &Update,
        nodes: &[usize],
        solution: &CoupledSolution,
        coupling: &Coupling,
        gaps: &[f64],
    ) -> BTreeSet<usize> {
        let problem = self.problem;
        let s1 = &problem.primary_surface;
        let mut pressure = vec![0.0; s1.len()];
        for ((&i, t), n) in nodes
            .iter()
            .zip(&solution.traction[0])
            .zip(&coupling.normals)
        {
            pressure[i] = -(t[0] * n[0] + t[1] * n[1] + t[2] * n[2]);
        }
        let mut candidates: BTreeSet<usize> = next.clone();
        candidates.extend(update.tension.iter().map(|&(i, _)| i));
        let candidates: Vec<usize> = candidates.into_iter().collect();
        let materials = [&problem.primary.material, &problem.secondary.material];
        let c0 = compliance_factor(materials, s1.dim);
        let predicted: BTreeSet<usize> = predicted_set(s1, &candidates, gaps, &pressure, c0)
            .into_iter()
            .collect();
        if self.solver.verbose {
            log::info!(
                "  half-space prediction: {} nodes active next (the update's {})",
                predicted.len(),
                next.len()
            );
        }
        if predicted.is_empty() {
            next.clone()
        } else {
            predicted
        }
    }

    /// The tied corrections of the current operators at `solution`, whose geometric gaps are
    /// `gaps`: each gap less its linearization.
    fn corrections(&self, solution: &CoupledSolution, gaps: &[f64]) -> Vec<f64> {
        let (s1, s2) = (
            &self.problem.primary_surface,
            &self.problem.secondary_surface,
        );
        let jumps = (self.operators).jumps(s1, s2, &solution.u[0], &solution.u[1]);
        let linear = self.operators.linearized_gaps(&jumps);
        gaps.iter().zip(&linear).map(|(g, l)| g - l).collect()
    }
}

impl ContactSolver<'_> {
    /// The coupling of the active primary nodes `nodes` (surface indices): rows and columns of
    /// the fixed operators, the constraint linearized by `rows` (frictionless) or corrected by
    /// `corrections` (tied).
    fn coupling(&mut self, nodes: &[usize], rows: &[GapRow], corrections: &[f64]) -> Coupling {
        let problem = self.problem;
        let formulation = problem.settings.formulation;
        let constraint = match formulation {
            Formulation::Frictionless => Constraint::Geometric { rows },
            Formulation::Tied => Constraint::Interpolated { corrections },
        };
        let (s1, s2) = (&problem.primary_surface, &problem.secondary_surface);
        (self.operators).coupling(s1, s2, formulation, nodes, constraint)
    }

    /// Steps 2-4 of the loop on the active set `active` with its `coupling`: the coupled
    /// solve; the gaps of every primary candidate, geometric (the search) and linearized at
    /// the iterate (into `rows`), and how far the active nodes' pairing has slid; the
    /// primal-dual active set update. On the Krylov path the solve is first loose
    /// ([`Tightness::Loose`]) and solved again tightly when its update would keep the active
    /// set or return to one seen before: no answer, status or check rests on a loose solve. The time of each phase is added to `seconds`.
    #[allow(clippy::too_many_arguments)]
    fn iterate(
        &mut self,
        coupling: &Coupling,
        active: &BTreeSet<usize>,
        load_factor: f64,
        safeguard: &Safeguard,
        rows: &mut Vec<GapRow>,
        seconds: &mut PhaseSeconds,
    ) -> Result<Iterate, ContactError> {
        let problem = self.problem;
        let settings = &problem.settings;
        let (s1, s2) = (&problem.primary_surface, &problem.secondary_surface);
        let nodes: Vec<usize> = active.iter().copied().collect();
        let mut loose = self.factors.as_ref().is_some_and(BodyFactors::is_krylov);
        let mut krylov_iterations = None;
        loop {
            let solution = timed(&mut seconds.solve, || {
                let tightness = if loose {
                    Tightness::Loose
                } else {
                    Tightness::Tight
                };
                self.coupled_solve(coupling, load_factor, tightness)
            })?;
            if let Some(stats) = self.factors.as_ref().and_then(|f| f.last_krylov) {
                *krylov_iterations.get_or_insert(0) += stats.iterations;
            }
            let (u1, u2) = (&solution.u[0][..], &solution.u[1][..]);
            let (gaps, linear, slid) = timed(&mut seconds.search, || {
                let gaps = geometric_gaps(s1, s2, Some(u1), Some(u2));
                *rows = gap_rows(s1, s2, Some(u1), Some(u2));
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
                let (traction, normals) = (&solution.traction[0], &coupling.normals);
                let pinned = &safeguard.pinned;
                Update::new(problem, &nodes, traction, normals, [&gaps, &held], pinned)
            });
            if loose && (update.next == *active || safeguard.seen.contains(&update.next)) {
                loose = false;
                continue;
            }
            return Ok(Iterate {
                solution,
                gaps,
                linear,
                slid,
                update,
                krylov_iterations,
            });
        }
    }

    /// The answer of a loop that ended `loop_end` with `solution` on the active set of
    /// `next_start`: certified without the loop's operators (`super::checks`), which decides
    /// the status, with the fields and forces of `super::post`.
    fn finish(
        &self,
        load_factor: f64,
        loop_end: ContactStatus,
        history: Vec<IterationRecord>,
        coupling: &Coupling,
        solution: CoupledSolution,
        next_start: ActiveSet,
    ) -> Result<ContactSolution, ContactError> {
        let nodes: Vec<usize> = next_start.nodes.iter().copied().collect();
        let (certificate, gaps) = certify(self.problem, &solution, &nodes);
        let status = contact_status(loop_end, &certificate, nodes.is_empty());
        post::finish(LastIterate {
            problem: self.problem,
            bodies: [(&self.body1, &self.stats1), (&self.body2, &self.stats2)],
            linear_solvers: self.linear_solvers(),
            load_factor,
            status,
            history,
            certificate,
            gaps,
            coupling,
            solution,
            active_set: next_start,
        })
    }

    /// Builds the interface operators again, paired with the primary surface slid by `slid`;
    /// the bodies' responses computed with the old ones are forgotten.
    fn pair_again(&mut self, slid: [f64; 3]) -> Result<(), ContactError> {
        self.operators = pair(self.problem, slid)?;
        if let Some(factors) = self.factors.as_mut() {
            factors.forget_responses();
        }
        Ok(())
    }

    /// The coupled system of `coupling`, solved and checked by its relative residual; or, a
    /// [`Tightness::Loose`] solve on the Krylov path, its residual only recorded.
    fn coupled_solve(
        &mut self,
        coupling: &Coupling,
        load_factor: f64,
        tightness: Tightness,
    ) -> Result<CoupledSolution, ContactError> {
        let dim = self.problem.primary_surface.dim;
        let bodies = [&self.body1, &self.body2];
        let pairs = [Pair {
            primary: 0,
            secondary: 1,
            coupling,
        }];
        let system = CoupledSystem::assemble(&bodies, &pairs, dim, load_factor)?;
        let x = match self.factors.as_mut() {
            None => coupled_solver::solve_monolithic(&system, &bodies)?,
            Some(factors) => factors.solve(&system, &pairs, &bodies, tightness)?,
        };
        let loose = tightness == Tightness::Loose
            && self.factors.as_ref().is_some_and(BodyFactors::is_krylov);
        let residual = system.relative_residual(&bodies, &x);
        if residual.is_nan() || (!loose && residual > self.solver.residual_tolerance) {
            return Err(ContactError::Inaccurate {
                residual,
                tolerance: self.solver.residual_tolerance,
            });
        }
        Ok(system.solution(&x, &bodies, &pairs, dim, residual))
    }
}

/// What steps 2-4 of one iteration found.
struct Iterate {
    solution: CoupledSolution,
    /// The geometric gap of every primary candidate at the iterate.
    gaps: Vec<f64>,
    /// Their gaps through the interpolation operators (tied contact's corrections).
    linear: Vec<f64>,
    /// The slide of the active nodes' pairing ([`InterfaceOperators::slide`]).
    slid: [f64; 3],
    update: Update,
    /// GMRES iterations of the solves (Krylov path).
    krylov_iterations: Option<usize>,
}

/// Runs `f`, adding its wall-clock seconds to `slot`.
fn timed<T>(slot: &mut f64, f: impl FnOnce() -> T) -> T {
    let clock = Instant::now();
    let value = f();
    *slot += clock.elapsed().as_secs_f64();
    value
}

/// The iteration's record of `update`; `pairing_drift_over_h` as [`pairing_drift`].
fn record(
    update: &Update,
    iteration: usize,
    residual: f64,
    pairing_drift_over_h: f64,
    krylov_iterations: Option<usize>,
    seconds: PhaseSeconds,
) -> IterationRecord {
    let max = |v: &[(usize, f64)]| v.iter().map(|x| x.1).fold(0.0, f64::max);
    IterationRecord {
        iteration,
        active: update.active,
        added: update.penetrating.len(),
        removed: update.tension.len(),
        max_penetration_over_h: max(&update.penetrating),
        max_tension_over_p: max(&update.tension),
        max_gap_error_over_h: update.max_gap_error_over_h,
        pairing_drift_over_h,
        relative_residual: residual,
        krylov_iterations,
        seconds,
    }
}
