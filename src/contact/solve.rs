//! The INTERNODES active-set loop (seed Algorithm 3, with removal and addition in one pass).
//!
//! ```text
//! I^C, J^C <- candidate nodes that touch or penetrate in the reference configuration
//! repeat
//!   1. I, J <- interface nodes among I^C, J^C                 (seed Algorithm 2, on the
//!      configuration of the last iterate)
//!   2. R12, R21, M1, M2, d on the reference geometry           (method.md section 2);
//!      R12 takes its sources from J and the ring of secondary nodes around it, R21 from I and
//!      the ring of inactive primary nodes around it (where lambda = 0): no extrapolation at
//!      the rim of the contact zone
//!   3. solve the coupled system for u1, u2, lambda
//!   4. tension:     active nodes whose mean pressure p_s < -tol_t p_max
//!      penetration: candidate nodes with gap . n < -tol_p h    (deformed configuration;
//!                   n the contact normal, below)
//!   5. I^C <- I - tension + penetrating, same for J^C
//! until nothing is in tension or penetrating (converged), an active set repeats (cycling),
//! or the iteration cap is reached
//! ```
//!
//! Tension is judged on the mean pressure of a node, `p_s = int p phi_s ds / int phi_s ds`, i.e.
//! on the normal contact force the interface exerts at that node (`M1 lambda` on body 1,
//! `-M2 R21 lambda` on body 2) divided by the node's area: the discrete counterpart of
//! `int p v ds >= 0` for every non-negative `v`. The nodal value `-lambda . n` itself is the
//! consistent-mass (L2) representation of a pressure that falls to zero with infinite slope at
//! the rim, and undershoots there like any L2 projection of a kink: with the nodal value as
//! the test, the outermost node was dropped for a tension that no node force carries, its
//! neighbour then penetrated, and the 3D Hertz case at R/67 cycled between the two (a rim node
//! at 9% of p0 in nodal tension, then 1.8e-3 h of penetration). The nodal values are still
//! written (`contact_pressure`), beside the mean pressure (`contact_mean_pressure`).
//!
//! The contact normal at a node bisects its own outward normal and the other surface's, interpolated
//! there: `n = (n_own - R n_other) / |n_own - R n_other|`. The frictionless constraint and the
//! penetration check both measure the gap along it. With the primary's own normal, a curved
//! primary on a flat was held along a direction tilted by its slope, and the 2D half-disc on a
//! stiff block lost 1.15% of its force (R/67 hemisphere: 1.29%) against the dolfinx rigid-flat
//! reference; with the bisector, 0.53% and 0.47%. Between two equal bodies it is the symmetry
//! plane's normal.
//!
//! An empty interface is a valid iterate: the bodies are then solved apart, and penetration
//! adds the nodes that the loads push into the other body. Converging with an empty interface
//! means the bodies do not touch ([`ContactStatus::NoContact`]).

use std::collections::{BTreeSet, HashSet};
use std::time::Instant;

use super::coupled_solver::{self, BodyFactors, CoupledSolver};
use super::rbf::{Interpolation, interface_nodes, interpolation_radii};
use super::solution::{ContactSolution, ContactStatus, IterationRecord, SurfaceFields};
use super::system::{CoupledSolution, CoupledSystem, Coupling};
use super::{ContactError, ContactProblem, ContactSurface, hertz};
use crate::elastic::{
    AssembledBody, ElasticProblem, ElasticSolution, SolveStats, SolverSettings, assemble, reactions,
};
use crate::fem::stress::cell_fields;
use nalgebra::DMatrix;

/// Solves a two-body contact problem at its full load.
pub fn solve_contact(
    problem: &ContactProblem,
    solver: &SolverSettings,
) -> Result<ContactSolution, ContactError> {
    ContactSolver::new(problem, solver)?.solve(1.0, None)
}

/// The candidate sets an active-set loop starts from (surface indices).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Candidates {
    pub primary: BTreeSet<usize>,
    pub secondary: BTreeSet<usize>,
}

/// The other candidate surface as seen from one surface: the interpolation of its fields to this
/// surface's nodes, and the contact normal at each of them ([`bisector`]), built once.
struct Facing {
    interpolation: Interpolation,
    normals: Vec<[f64; 3]>,
}

impl Facing {
    fn new(
        own: &ContactSurface,
        other: &ContactSurface,
        radius: f64,
    ) -> Result<Self, ContactError> {
        let interpolation = Interpolation::new(
            &other.coords,
            &interpolation_radii(&other.coords, radius)?,
            &own.coords,
        )?;
        let other_normals: Vec<f64> = other.normals.iter().flatten().copied().collect();
        let at_own = interpolation.apply(&other_normals, 3);
        let normals = (0..own.len())
            .map(|i| bisector(&own.normals[i], &at_own[3 * i..3 * i + 3]))
            .collect();
        Ok(Self {
            interpolation,
            normals,
        })
    }
}

/// A contact problem set up once: both bodies assembled (and, on the Schur path, factored) and
/// the candidate-to-candidate interpolations built. Every load step reuses all of it: loads and
/// prescribed displacements enter the system linearly, `f_c(s) = s f_c(1)`, while `K`, its
/// factors and the interface geometry do not change.
pub struct ContactSolver<'a> {
    problem: &'a ContactProblem<'a>,
    solver: SolverSettings,
    body1: AssembledBody,
    body2: AssembledBody,
    stats1: SolveStats,
    stats2: SolveStats,
    factors: Option<BodyFactors>,
    to_primary: Facing,
    to_secondary: Facing,
}

impl<'a> ContactSolver<'a> {
    pub fn new(
        problem: &'a ContactProblem<'a>,
        solver: &SolverSettings,
    ) -> Result<Self, ContactError> {
        let (s1, s2) = (&problem.primary_surface, &problem.secondary_surface);
        // Each body's constrained system, assembled once.
        let (mut stats1, mut stats2) = (SolveStats::default(), SolveStats::default());
        let body1 = assemble(&problem.primary, &mut stats1, false)?;
        let body2 = assemble(&problem.secondary, &mut stats2, false)?;
        // With the Schur path, each body's stiffness is factored once.
        let factors = match problem.settings.solver {
            CoupledSolver::Schur => {
                let start = Instant::now();
                let factors = BodyFactors::new(
                    &body1,
                    &body2,
                    &s1.nodes,
                    &s2.nodes,
                    s1.dim,
                    solver.ordering,
                )?;
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
        // Interpolation between all candidates, for the contact checks of step 4.
        let radius = problem.settings.rbf_radius;
        let to_primary = Facing::new(s1, s2, radius)?;
        let to_secondary = Facing::new(s2, s1, radius)?;
        Ok(Self {
            problem,
            solver: *solver,
            body1,
            body2,
            stats1,
            stats2,
            factors,
            to_primary,
            to_secondary,
        })
    }

    /// The candidates that penetrate or touch in the reference configuration.
    pub fn initial_candidates(&self) -> Candidates {
        let (s1, s2) = (
            &self.problem.primary_surface,
            &self.problem.secondary_surface,
        );
        let (zero1, zero2) = (vec![0.0; self.body1.f.len()], vec![0.0; self.body2.f.len()]);
        let tol = self.problem.settings.penetration_tolerance;
        Candidates {
            primary: penetrating(
                s1,
                &normal_gaps(s1, s2, &self.to_primary, &zero1, &zero2),
                tol,
            )
            .into_iter()
            .collect(),
            secondary: penetrating(
                s2,
                &normal_gaps(s2, s1, &self.to_secondary, &zero2, &zero1),
                tol,
            )
            .into_iter()
            .collect(),
        }
    }

    /// Runs the active-set loop with the loads and prescribed displacements scaled by
    /// `load_factor`, from `start` (default: [`Self::initial_candidates`]).
    pub fn solve(
        &self,
        load_factor: f64,
        start: Option<&Candidates>,
    ) -> Result<ContactSolution, ContactError> {
        let problem = self.problem;
        let solver = &self.solver;
        let verbose = solver.verbose;
        let (s1, s2) = (&problem.primary_surface, &problem.secondary_surface);
        let settings = &problem.settings;
        let dim = s1.dim;
        let (body1, body2) = (&self.body1, &self.body2);
        let (to_primary, to_secondary) = (&self.to_primary, &self.to_secondary);
        let factors = self.factors.as_ref();
        let start_candidates = start.cloned().unwrap_or_else(|| self.initial_candidates());
        let mut candidates1 = start_candidates.primary;
        let mut candidates2 = start_candidates.secondary;
        let mut seen: HashSet<(Vec<usize>, Vec<usize>)> = HashSet::new();
        let mut history = Vec::new();
        let mut last: Option<(Coupling, CoupledSolution)> = None;
        let mut status = ContactStatus::IterationLimit;

        for iteration in 1..=settings.max_iterations {
            let start = Instant::now();
            // 1. Interface nodes among the candidates (Algorithm 2).
            let c1: Vec<usize> = candidates1.iter().copied().collect();
            let c2: Vec<usize> = candidates2.iter().copied().collect();
            let deformed = last
                .as_ref()
                .filter(|(c, _): &&(Coupling, CoupledSolution)| !c.primary_nodes.is_empty())
                .map(|(_, s)| (&s.u1[..], &s.u2[..]));
            let interface = find_interface(s1, s2, &c1, &c2, deformed)?.unwrap_or_default();

            // 2. Interface operators on the reference geometry.
            let coupling = coupling(problem, &interface)?;

            // 3. The coupled solve.
            let system = CoupledSystem::assemble(body1, body2, &coupling, dim, load_factor)?;
            let x = coupled_solver::solve(&system, body1, body2, factors)?;
            let residual = system.relative_residual(body1, body2, &x);
            let solution = system.solution(&x, &coupling, dim, residual);
            if solution.relative_residual.is_nan()
                || solution.relative_residual > solver.residual_tolerance
            {
                return Err(ContactError::Inaccurate {
                    residual: solution.relative_residual,
                    tolerance: solver.residual_tolerance,
                });
            }

            // 4. Contact checks on the deformed configuration.
            let checks = contact_checks(problem, &interface, &solution, to_primary, to_secondary);
            let (tension1, tension2) = (&checks.tension1, &checks.tension2);
            let (penetrating1, penetrating2) = (&checks.penetrating1, &checks.penetrating2);

            // 5. New candidate sets: drop tension, add penetration, both at once.
            let active1: BTreeSet<usize> = interface.primary.iter().copied().collect();
            let active2: BTreeSet<usize> = interface.secondary.iter().copied().collect();
            let next1 = update(&active1, tension1, penetrating1);
            let next2 = update(&active2, tension2, penetrating2);
            let added = next1.difference(&active1).count() + next2.difference(&active2).count();
            let removed = tension1.len() + tension2.len();
            let record = IterationRecord {
                iteration,
                active_primary: active1.len(),
                active_secondary: active2.len(),
                added,
                removed,
                max_penetration: checks.max_penetration,
                max_penetration_over_h: checks.max_penetration_over_h,
                max_tension: checks.max_tension,
                relative_residual: solution.relative_residual,
                seconds: start.elapsed().as_secs_f64(),
            };
            if verbose {
                eprintln!(
                    "  iteration {:>3}: active {:>5} + {:>5}, added {:>4}, removed {:>4}, penetration {:.2e} ({:.1e} h), tension {:.2e}, {:.3} s",
                    record.iteration,
                    record.active_primary,
                    record.active_secondary,
                    record.added,
                    record.removed,
                    record.max_penetration,
                    record.max_penetration_over_h,
                    record.max_tension,
                    record.seconds
                );
            }
            history.push(record);
            last = Some((coupling, solution));

            let converged = tension1.is_empty()
                && tension2.is_empty()
                && penetrating1.iter().all(|s| active1.contains(s))
                && penetrating2.iter().all(|s| active2.contains(s));
            if converged {
                status = if active1.is_empty() {
                    ContactStatus::NoContact
                } else {
                    ContactStatus::Converged
                };
                break;
            }
            // A repeated candidate set means the simultaneous update oscillates (typically at the
            // rim, where an outer node in tension holds the surfaces together and its inner
            // neighbours penetrate). Fall back to a one-sided step: remove the tension nodes only,
            // or if none, add the penetrating ones only; if that repeats a set too, the loop cycles.
            // Candidate sets (the input of an iteration) are compared, not the interfaces that
            // Algorithm 2 prunes from them.
            seen.insert(key(&candidates1, &candidates2));
            let (mut next1, mut next2) = (next1, next2);
            if seen.contains(&key(&next1, &next2)) {
                let one_sided = if removed > 0 {
                    (&[][..], &[][..])
                } else {
                    (&penetrating1[..], &penetrating2[..])
                };
                next1 = update(&active1, tension1, one_sided.0);
                next2 = update(&active2, tension2, one_sided.1);
                if seen.contains(&key(&next1, &next2)) {
                    status = ContactStatus::Cycling;
                    break;
                }
            }
            candidates1 = next1;
            candidates2 = next2;
        }

        let (coupling, solution) = last.expect("the loop runs at least once (max_iterations >= 1)");
        let candidates = Candidates {
            primary: candidates1,
            secondary: candidates2,
        };
        self.finish(
            load_factor,
            status,
            history,
            &coupling,
            solution,
            candidates,
        )
    }
}

/// What the contact checks of one iteration found (surface indices).
struct Checks {
    /// Active nodes in tension: mean pressure below `-tol_t p_max`.
    tension1: Vec<usize>,
    tension2: Vec<usize>,
    /// Candidate nodes whose deformed gap is below `-tol_p h`.
    penetrating1: Vec<usize>,
    penetrating2: Vec<usize>,
    max_tension: f64,
    /// Deepest penetration of an inactive candidate, absolute and relative to its h.
    max_penetration: f64,
    max_penetration_over_h: f64,
}

/// Tension of the active nodes and penetration of the candidates, deformed configuration.
fn contact_checks(
    problem: &ContactProblem,
    interface: &Interface,
    solution: &CoupledSolution,
    to_primary: &Facing,
    to_secondary: &Facing,
) -> Checks {
    let (s1, s2) = (&problem.primary_surface, &problem.secondary_surface);
    let settings = &problem.settings;
    let gaps1 = normal_gaps(s1, s2, to_primary, &solution.u1, &solution.u2);
    let gaps2 = normal_gaps(s2, s1, to_secondary, &solution.u2, &solution.u1);
    // Mean pressure of each active node of both surfaces (negative = tension).
    let mean1: Vec<(usize, f64)> = interface
        .primary
        .iter()
        .map(|&s| (s, s1.mean_pressure(&solution.contact_force1, s)))
        .collect();
    let mean2: Vec<(usize, f64)> = interface
        .secondary
        .iter()
        .map(|&s| (s, s2.mean_pressure(&solution.contact_force2, s)))
        .collect();
    let pressure_max = mean1.iter().map(|&(_, p)| p).fold(0.0, f64::max);
    let limit = -settings.tension_tolerance * pressure_max;
    let in_tension = |mean: &[(usize, f64)]| {
        mean.iter()
            .filter(|&&(_, p)| p < limit)
            .map(|&(s, _)| s)
            .collect()
    };
    let (max_penetration, max_penetration_over_h) =
        deepest(s1, &gaps1, &interface.primary).max_by(deepest(s2, &gaps2, &interface.secondary));
    Checks {
        tension1: in_tension(&mean1),
        tension2: in_tension(&mean2),
        penetrating1: penetrating(s1, &gaps1, settings.penetration_tolerance),
        penetrating2: penetrating(s2, &gaps2, settings.penetration_tolerance),
        max_tension: mean1
            .iter()
            .chain(&mean2)
            .map(|&(_, p)| -p)
            .fold(0.0, f64::max),
        max_penetration,
        max_penetration_over_h,
    }
}

/// Interface nodes (surface indices); empty when the candidate sets do not
/// face each other within interpolation range.
#[derive(Default)]
struct Interface {
    primary: Vec<usize>,
    secondary: Vec<usize>,
}

/// The search runs on the configuration of the last coupled iterate (`deformed`: its
/// displacements of both bodies), the reference one before any. An uncoupled iterate (empty
/// interface) is not used: there the bodies were solved apart, and overlap by the whole
/// approach (the tied two half-discs, pushed by five spacings in one step, then lost every
/// candidate). On the reference
/// geometry two curved surfaces are a gap `r^2 / R` apart at radius `r`, about one spacing at
/// the rim of the finest two-hemisphere mesh: candidates added there because they penetrated
/// were out of reach on the reference geometry, were dropped, and the loop repeated itself.
fn find_interface(
    s1: &ContactSurface,
    s2: &ContactSurface,
    c1: &[usize],
    c2: &[usize],
    deformed: Option<(&[f64], &[f64])>,
) -> Result<Option<Interface>, ContactError> {
    if c1.len() < 2 || c2.len() < 2 {
        return Ok(None);
    }
    let position = |s: &ContactSurface, u: Option<&[f64]>, i: usize| -> [f64; 3] {
        u.map_or(s.coords[i], |u| s.deformed(u, i))
    };
    let x1: Vec<[f64; 3]> = c1
        .iter()
        .map(|&s| position(s1, deformed.map(|d| d.0), s))
        .collect();
    let x2: Vec<[f64; 3]> = c2
        .iter()
        .map(|&s| position(s2, deformed.map(|d| d.1), s))
        .collect();
    match interface_nodes(&x1, &x2) {
        Ok(found) if found.primary.len() >= 2 && found.secondary.len() >= 2 => {
            Ok(Some(Interface {
                primary: found.primary.iter().map(|&k| c1[k]).collect(),
                secondary: found.secondary.iter().map(|&k| c2[k]).collect(),
            }))
        }
        Ok(_) | Err(super::rbf::RbfError::EmptyInterface { .. }) => Ok(None),
        Err(e) => Err(e.into()),
    }
}

/// `R12`, `R21`, `M1`, `M2` and the gaps `d = R12 x2 - x1` of an interface.
fn coupling(problem: &ContactProblem, interface: &Interface) -> Result<Coupling, ContactError> {
    let (s1, s2) = (&problem.primary_surface, &problem.secondary_surface);
    let x1: Vec<[f64; 3]> = interface.primary.iter().map(|&s| s1.coords[s]).collect();
    let x2: Vec<[f64; 3]> = interface.secondary.iter().map(|&s| s2.coords[s]).collect();
    let (m1_rows, m1) = s1.mass_matrix(&interface.primary);
    let (m2_rows, m2) = s2.mass_matrix(&interface.secondary);
    let mut coupling = Coupling {
        formulation: problem.settings.formulation,
        primary_nodes: interface.primary.iter().map(|&s| s1.nodes[s]).collect(),
        secondary_nodes: interface.secondary.iter().map(|&s| s2.nodes[s]).collect(),
        normals: interface.primary.iter().map(|&s| s1.normals[s]).collect(),
        r12: DMatrix::zeros(x1.len(), 0),
        r12_nodes: Vec::new(),
        r21: DMatrix::zeros(x2.len(), x1.len()),
        m1_rows: m1_rows.iter().map(|&s| s1.nodes[s]).collect(),
        m1,
        m2_rows: m2_rows.iter().map(|&s| s2.nodes[s]).collect(),
        m2_r21: DMatrix::zeros(m2.nrows(), x1.len()),
        gaps: Vec::new(),
    };
    if x1.is_empty() {
        return Ok(coupling);
    }
    // Likewise R12 interpolates the secondary displacement, which exists on the whole surface:
    // taking its sources from J and the ring around it avoids extrapolating at the rim of I.
    let ring2: Vec<[f64; 3]> = m2_rows.iter().map(|&s| s2.coords[s]).collect();
    let radius = problem.settings.rbf_radius;
    let r12 = Interpolation::new(&ring2, &interpolation_radii(&ring2, radius)?, &x1)?;
    // The interface was found on the last iterate's configuration; every active node must
    // still be within the other side's supports on the reference geometry, where R is built.
    if !r12.uncovered_targets().is_empty() {
        return Err(ContactError::UncoveredInterface {
            nodes: r12.uncovered_targets().len(),
        });
    }
    // R21 interpolates the multiplier field, a P1 field on the primary surface that vanishes at
    // inactive nodes: its sources are all nodes of the facets touching I (the zeros of the
    // inactive ring included), so that the traction passed to body 2 decays outside the contact
    // zone instead of carrying the rim value onto J nodes beyond it.
    let ring: Vec<[f64; 3]> = m1_rows.iter().map(|&s| s1.coords[s]).collect();
    let r21_ring = Interpolation::new(&ring, &interpolation_radii(&ring, radius)?, &x2)?.matrix();
    let r21 = DMatrix::from_fn(x2.len(), x1.len(), |j, a| {
        let column = m1_rows
            .binary_search(&interface.primary[a])
            .expect("active nodes are rows of M1");
        r21_ring[(j, column)]
    });
    let x2_flat: Vec<f64> = ring2.iter().flat_map(|x| x.iter().copied()).collect();
    let x2_at_1 = r12.apply(&x2_flat, 3);
    // The contact normal (module doc): with the primary's own normal, a node of a curved primary
    // that slides by u_t on a flat ends (x/R) u_t off it.
    let n2_flat: Vec<f64> = m2_rows.iter().flat_map(|&s| s2.normals[s]).collect();
    let n2_at_1 = r12.apply(&n2_flat, 3);
    coupling.normals = interface
        .primary
        .iter()
        .enumerate()
        .map(|(a, &s)| bisector(&s1.normals[s], &n2_at_1[3 * a..3 * a + 3]))
        .collect();
    // Only the normal part of R12 x2 - x1 is a gap: R reproduces constants but not the linear
    // coordinate field, so its tangential part is interpolation error, which the tied
    // constraint would otherwise impose as a spurious O(h) tangential jump.
    let gaps: Vec<[f64; 3]> = x1
        .iter()
        .zip(&coupling.normals)
        .enumerate()
        .map(|(a, (x, n))| {
            let normal_gap: f64 = (0..3).map(|k| n[k] * (x2_at_1[3 * a + k] - x[k])).sum();
            std::array::from_fn(|k| normal_gap * n[k])
        })
        .collect();
    coupling.gaps = gaps;
    coupling.m2_r21 = &m2 * &r21;
    coupling.r12 = r12.matrix();
    coupling.r12_nodes = m2_rows.iter().map(|&s| s2.nodes[s]).collect();
    coupling.r21 = r21;
    Ok(coupling)
}

/// Gap of each node of `own` to the deformed `other` surface along its contact normal:
/// `n . (R x_other(u) - x_own(u))`; NaN where `other` is out of interpolation range.
fn normal_gaps(
    own: &ContactSurface,
    other: &ContactSurface,
    to_own: &Facing,
    u_own: &[f64],
    u_other: &[f64],
) -> Vec<f64> {
    let other_flat: Vec<f64> = (0..other.len())
        .flat_map(|j| other.deformed(u_other, j))
        .collect();
    let other_at_own = to_own.interpolation.apply(&other_flat, 3);
    let uncovered: HashSet<usize> = to_own
        .interpolation
        .uncovered_targets()
        .iter()
        .copied()
        .collect();
    (0..own.len())
        .map(|i| {
            if uncovered.contains(&i) {
                return f64::NAN;
            }
            let n = to_own.normals[i];
            let x = own.deformed(u_own, i);
            (0..3)
                .map(|k| n[k] * (other_at_own[3 * i + k] - x[k]))
                .sum()
        })
        .collect()
}

/// The contact normal at a node: the bisector `(n_own - n_other) / |n_own - n_other|` of its
/// outward normal and the other surface's outward normal interpolated there (`n_own` if they
/// cancel, which facing surfaces cannot do). The constraint holds the gap along it and the
/// penetration check measures the gap along it, so that both judge the same distance.
fn bisector(own: &[f64; 3], other: &[f64]) -> [f64; 3] {
    let sum: [f64; 3] = std::array::from_fn(|k| own[k] - other[k]);
    let length = dot(&sum, &sum).sqrt();
    if length > 1e-12 {
        std::array::from_fn(|k| sum[k] / length)
    } else {
        *own
    }
}

fn penetrating(surface: &ContactSurface, gaps: &[f64], tolerance: f64) -> Vec<usize> {
    (0..surface.len())
        .filter(|&i| gaps[i] < -tolerance * surface.spacing[i])
        .collect()
}

/// Largest penetration `(absolute, relative to h)` (0 when none).
struct Deepest(f64, f64);

impl Deepest {
    fn max_by(self, other: Deepest) -> (f64, f64) {
        if other.1 > self.1 {
            (other.0, other.1)
        } else {
            (self.0, self.1)
        }
    }
}

/// The deepest penetration among the inactive candidates (the nodes the penetration criterion
/// applies to; active nodes are held by the interface constraint).
fn deepest(surface: &ContactSurface, gaps: &[f64], active: &[usize]) -> Deepest {
    let mut worst = Deepest(0.0, 0.0);
    for (i, &g) in gaps.iter().enumerate() {
        if -g / surface.spacing[i] > worst.1 && !active.contains(&i) {
            worst = Deepest(-g, -g / surface.spacing[i]);
        }
    }
    worst
}

fn key(a: &BTreeSet<usize>, b: &BTreeSet<usize>) -> (Vec<usize>, Vec<usize>) {
    (a.iter().copied().collect(), b.iter().copied().collect())
}

fn update(active: &BTreeSet<usize>, tension: &[usize], penetrating: &[usize]) -> BTreeSet<usize> {
    let mut next = active.clone();
    for s in tension {
        next.remove(s);
    }
    next.extend(penetrating.iter().copied());
    next
}

/// `lambda_2 = -R21 lambda` at the active secondary nodes.
fn secondary_tractions(
    coupling: &Coupling,
    solution: &CoupledSolution,
    dim: usize,
) -> Vec<[f64; 3]> {
    (0..coupling.secondary_nodes.len())
        .map(|j| {
            std::array::from_fn(|c| {
                if c >= dim {
                    return 0.0;
                }
                -(0..coupling.primary_nodes.len())
                    .map(|b| coupling.r21[(j, b)] * solution.traction[b][c])
                    .sum::<f64>()
            })
        })
        .collect()
}

fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[allow(clippy::too_many_arguments)]
impl ContactSolver<'_> {
    /// The solution of the last iterate, with surface fields, forces and the Hertz fit.
    fn finish(
        &self,
        load_factor: f64,
        status: ContactStatus,
        history: Vec<IterationRecord>,
        coupling: &Coupling,
        solution: CoupledSolution,
        candidates: Candidates,
    ) -> Result<ContactSolution, ContactError> {
        let problem = self.problem;
        let (body1, body2) = (&self.body1, &self.body2);
        let (to_primary, to_secondary) = (&self.to_primary, &self.to_secondary);
        let (mut stats1, mut stats2) = (self.stats1.clone(), self.stats2.clone());
        let (s1, s2) = (&problem.primary_surface, &problem.secondary_surface);
        let dim = s1.dim;
        stats1.relative_residual = solution.relative_residual;
        stats2.relative_residual = solution.relative_residual;
        let tractions2 = secondary_tractions(coupling, &solution, dim);
        let gaps1 = normal_gaps(s1, s2, to_primary, &solution.u1, &solution.u2);
        let gaps2 = normal_gaps(s2, s1, to_secondary, &solution.u2, &solution.u1);
        let primary_fields = surface_fields(
            s1,
            &coupling.primary_nodes,
            &solution.traction,
            &solution.contact_force1,
            gaps1,
        );
        let secondary_fields = surface_fields(
            s2,
            &coupling.secondary_nodes,
            &tractions2,
            &solution.contact_force2,
            gaps2,
        );
        let total = |force: &[f64]| -> [f64; 3] {
            std::array::from_fn(|c| {
                if c < dim {
                    force.iter().skip(c).step_by(dim).sum()
                } else {
                    0.0
                }
            })
        };
        let force_primary = total(&solution.contact_force1);
        let force_secondary = total(&solution.contact_force2);
        let norm = |f: &[f64; 3]| dot(f, f).sqrt();
        let sum: [f64; 3] = std::array::from_fn(|c| force_primary[c] + force_secondary[c]);
        let force_imbalance = if norm(&force_primary) > 0.0 {
            norm(&sum) / norm(&force_primary)
        } else {
            0.0
        };
        let hertz_primary = hertz::fit(s1, &primary_fields);
        // Tangential with respect to the contact normal the constraint used (the bisector of
        // the two surfaces' normals): zero for frictionless, the glue's shear for tied.
        let max_tangential_traction = solution
            .traction
            .iter()
            .zip(&coupling.normals)
            .map(|(t, n)| {
                let normal = dot(t, n);
                let tangential: [f64; 3] = std::array::from_fn(|k| t[k] - normal * n[k]);
                dot(&tangential, &tangential).sqrt()
            })
            .fold(0.0, f64::max);

        let body_solution = |p: &ElasticProblem,
                             body: &AssembledBody,
                             u: Vec<f64>,
                             force: &[f64],
                             stats: SolveStats| ElasticSolution {
            reactions: reactions(p, body, &u, load_factor, force),
            cell_fields: cell_fields(p.body, &p.material, &u),
            displacement: u,
            stats,
        };
        Ok(ContactSolution {
            status,
            history,
            primary: body_solution(
                &problem.primary,
                body1,
                solution.u1,
                &solution.contact_force1,
                stats1,
            ),
            secondary: body_solution(
                &problem.secondary,
                body2,
                solution.u2,
                &solution.contact_force2,
                stats2,
            ),
            primary_fields,
            secondary_fields,
            force_primary,
            force_secondary,
            force_imbalance,
            max_tangential_traction,
            hertz_primary,
            load_factor,
            candidates,
        })
    }
}

fn surface_fields(
    surface: &ContactSurface,
    active_nodes: &[usize],
    tractions: &[[f64; 3]],
    contact_force: &[f64],
    gaps: Vec<f64>,
) -> SurfaceFields {
    let mut fields = SurfaceFields {
        nodes: surface.nodes.clone(),
        traction: vec![[0.0; 3]; surface.len()],
        pressure: vec![0.0; surface.len()],
        mean_pressure: (0..surface.len())
            .map(|s| surface.mean_pressure(contact_force, s))
            .collect(),
        normal_gap: gaps,
        active: vec![false; surface.len()],
    };
    for (node, traction) in active_nodes.iter().zip(tractions) {
        let s = surface
            .nodes
            .binary_search(node)
            .expect("active nodes are surface nodes");
        fields.traction[s] = *traction;
        fields.pressure[s] = -dot(traction, &surface.normals[s]);
        fields.active[s] = true;
    }
    fields
}
