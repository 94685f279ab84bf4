//! A case solved in memory: the contact solve of the bodies in contact, and each other body
//! alone. Nothing is written here: the command line ([`super::solve_case`]) and the Python
//! module write the result files from a [`CaseSolution`] with [`super::write_results`].

use std::time::Instant;

use crate::case::{BodySpec, Case};
use crate::contact::{
    ContactProblem, ContactRun, ContactSolution, SurfaceFields, solve_contact_steps,
};
use crate::elastic::{DirichletCondition, ElasticSolution, solve};
use crate::fem::Material;
use crate::mesh::Mesh;
use crate::output::{BodySummary, CaseSummary, ContactSummary, peak_memory_mb};

use super::RunError;

/// Wall-clock seconds of each phase of a run, in order, from its start.
#[derive(Debug, Clone)]
pub struct Timings {
    started: Instant,
    phases: Vec<(String, f64)>,
}

impl Timings {
    /// A run that starts now.
    pub fn start() -> Self {
        Self {
            started: Instant::now(),
            phases: Vec::new(),
        }
    }

    /// Records the seconds since `since` under `name`, and returns them.
    pub fn record(&mut self, name: impl Into<String>, since: Instant) -> f64 {
        let seconds = since.elapsed().as_secs_f64();
        self.phases.push((name.into(), seconds));
        seconds
    }

    /// The phases so far, then `"total"`: the seconds since the run started.
    pub fn with_total(&self) -> Vec<(String, f64)> {
        let mut phases = self.phases.clone();
        phases.push(("total".to_string(), self.started.elapsed().as_secs_f64()));
        phases
    }

    /// The seconds since the run started.
    pub fn elapsed(&self) -> f64 {
        self.started.elapsed().as_secs_f64()
    }
}

/// Every body of a case, solved.
pub struct CaseSolution {
    /// In the case file's order of bodies.
    pub bodies: Vec<SolvedBody>,
    /// Each contact pair's outcome, in the case file's order (empty without contact).
    pub contacts: Vec<SolvedContact>,
    /// With `case.solver.keep_step_fields`, the bodies in contact at each load step before the
    /// last (`bodies` holds the last step's, and the bodies in no contact, which are solved
    /// once at their full load); empty without it.
    pub earlier_steps: Vec<Vec<SolvedBody>>,
    pub timings: Timings,
    /// Every rank's peak memory (MB) in a distributed run, in rank order (empty otherwise).
    pub rank_peak_memory_mb: Vec<f64>,
}

/// One body's solution and, in contact runs, its contact surfaces' fields (one per pair it is
/// in, in the case's order of pairs).
pub struct SolvedBody {
    pub name: String,
    /// Its material: its strain and stress are computed from the displacement where they are
    /// read (`crate::fem::stress`).
    pub material: Material,
    pub solution: ElasticSolution,
    pub surfaces: Vec<PairSurface>,
}

/// A body's contact surface in one pair.
pub struct PairSurface {
    /// The pair's name.
    pub pair: String,
    pub fields: SurfaceFields,
}

/// What a contact pair's solve leaves besides its bodies' fields.
pub struct SolvedContact {
    /// Status, certificate, accuracy report, forces and one record per load step: the
    /// `contact` part of `summary.json` (an entry of `contacts` with several pairs).
    pub summary: ContactSummary,
    /// The title of its force-displacement plot.
    pub plot_title: String,
    /// The approach the prescribed displacements impose at load factor 1 (the plot's x axis).
    pub imposed_approach: f64,
}

/// Solves every body of `case` on `mesh`: those in contact together, the others alone. Every
/// body's problem is built first, so that bad input is an error before anything is solved.
pub fn solve_case_on(
    case: &Case,
    mesh: &Mesh,
    mut timings: Timings,
) -> Result<CaseSolution, RunError> {
    case.check_bodies(mesh)?;
    if case.export_matrices {
        case.check_export_names(mesh)?;
    }
    let mut bodies = Vec::new();
    let mut contacts = Vec::new();
    let mut earlier_steps = Vec::new();
    // The pairs' surfaces (each with its body's whole boundary) before any contact phase.
    let phase = Instant::now();
    let problems = case.contact_problems(mesh)?;
    if !problems.is_empty() {
        timings.record("contact surfaces", phase);
        let (solved, in_contact, earlier) = solve_contact_pairs(case, problems, &mut timings)?;
        contacts = solved;
        bodies.extend(in_contact);
        earlier_steps = earlier;
    }
    for spec in &case.bodies {
        if !bodies.iter().any(|s| s.name == spec.name) {
            bodies.push(solve_alone(case, mesh, spec, &mut timings)?);
        }
    }
    bodies.sort_by_key(|s| case.bodies.iter().position(|b| b.name == s.name));
    Ok(CaseSolution {
        bodies,
        contacts,
        earlier_steps,
        timings,
        rank_peak_memory_mb: Vec::new(),
    })
}

/// The contact solve of the case's pairs ([`solve_contact_steps`]: its load steps, and for a single
/// pair the other primary's solve when the first choice may be wrong), the solution of each
/// body in contact, and with `keep_step_fields` those of the steps before the last.
#[allow(clippy::type_complexity)]
fn solve_contact_pairs(
    case: &Case,
    problems: Vec<ContactProblem>,
    timings: &mut Timings,
) -> Result<(Vec<SolvedContact>, Vec<SolvedBody>, Vec<Vec<SolvedBody>>), RunError> {
    for problem in &problems {
        let method = match problem.penalty_stiffness() {
            Some(eps) => format!(
                ", penalty {:.3e} ({} E*/h)",
                eps,
                problem.settings.penalty_factor().unwrap_or_default()
            ),
            None => String::new(),
        };
        log::info!(
            "contact: '{}' ({}, {} candidate nodes) on '{}' ({}, {} candidate nodes), {}{method}",
            problem.primary.body.name,
            problem.primary_surface.group,
            problem.primary_surface.len(),
            problem.secondary.body.name,
            problem.secondary_surface.group,
            problem.secondary_surface.len(),
            problem.settings.formulation.name(),
        );
        log::info!(
            "primary body '{}' ({}): {}",
            problem.primary.body.name,
            problem.primary_report.mode,
            problem.primary_report.reason
        );
    }
    let run =
        solve_contact_steps(problems, &case.solver, &case.step_factors()).map_err(|source| {
            RunError::Contact {
                path: case.path.clone(),
                source,
            }
        })?;
    let ContactRun {
        problems,
        solutions,
        steps,
        earlier_solutions,
        timings: contact_timings,
    } = run;
    timings.phases.extend(contact_timings);
    let mut contacts = Vec::new();
    for (p, ((problem, solution), steps)) in problems.iter().zip(&solutions).zip(steps).enumerate()
    {
        let name = case.contacts[p].name.clone();
        contacts.push(SolvedContact {
            summary: summarize_contact(name.clone(), problem, solution, steps),
            plot_title: format!(
                "{}: contact of '{}' (primary) and '{}'",
                case_name(case),
                problem.primary.body.name,
                problem.secondary.body.name,
            ),
            imposed_approach: imposed_approach(problem),
        });
    }
    let earlier = (earlier_solutions.into_iter())
        .map(|step| bodies_in_contact(case, &problems, step))
        .collect();
    Ok((
        contacts,
        bodies_in_contact(case, &problems, solutions),
        earlier,
    ))
}

/// Each body of the pairs `problems` with its solution in `solutions` (one per pair) and its
/// contact surface in each pair.
fn bodies_in_contact(
    case: &Case,
    problems: &[ContactProblem],
    solutions: Vec<ContactSolution>,
) -> Vec<SolvedBody> {
    let mut bodies: Vec<SolvedBody> = Vec::new();
    for (p, (problem, solution)) in problems.iter().zip(solutions).enumerate() {
        let name = &case.contacts[p].name;
        let sides = [
            (&problem.primary, solution.primary, solution.primary_fields),
            (
                &problem.secondary,
                solution.secondary,
                solution.secondary_fields,
            ),
        ];
        for (elastic, body_solution, fields) in sides {
            let fields = PairSurface {
                pair: name.clone(),
                fields,
            };
            match bodies.iter_mut().find(|b| b.name == elastic.body.name) {
                // A body in several pairs has one solution: the first pair's.
                Some(body) => body.surfaces.push(fields),
                None => bodies.push(SolvedBody {
                    name: elastic.body.name.clone(),
                    material: elastic.material,
                    solution: body_solution,
                    surfaces: vec![fields],
                }),
            }
        }
    }
    bodies
}

/// One body that is in no contact, solved alone.
fn solve_alone(
    case: &Case,
    mesh: &Mesh,
    spec: &BodySpec,
    timings: &mut Timings,
) -> Result<SolvedBody, RunError> {
    let body = case.body_mesh(mesh, spec)?;
    let problem = case.elastic_problem(body, spec)?;
    log::info!(
        "body '{}': {} nodes, {} cells, {} dofs",
        body.name,
        body.num_nodes(),
        body.total_cells(),
        body.num_dofs()
    );
    let phase = Instant::now();
    let solution = solve(&problem, &case.solver).map_err(|source| RunError::Solve {
        path: case.path.clone(),
        source,
    })?;
    timings.record(format!("solve {}", body.name), phase);
    Ok(SolvedBody {
        name: spec.name.clone(),
        material: problem.material,
        solution,
        surfaces: Vec::new(),
    })
}

impl CaseSolution {
    /// The contents of `summary.json`, with the timings recorded so far.
    pub fn summary(&self, case: &Case, mesh: &Mesh) -> CaseSummary {
        self.summary_with(case, mesh, &self.timings)
    }

    /// [`CaseSolution::summary`] with `timings` (this solve's, and more phases after it).
    pub(super) fn summary_with(&self, case: &Case, mesh: &Mesh, timings: &Timings) -> CaseSummary {
        let (mut node_offset, mut cell_offset) = (0, 0);
        let bodies = (self.bodies.iter())
            .map(|solved| {
                let spec = (case.bodies.iter())
                    .find(|b| b.name == solved.name)
                    .expect("solved bodies come from the case");
                let body = mesh
                    .body(&solved.name)
                    .expect("solved bodies are mesh bodies");
                let s = &solved.solution;
                let summary = BodySummary {
                    name: body.name.clone(),
                    youngs_modulus: spec.youngs_modulus,
                    poisson_ratio: spec.poisson_ratio,
                    num_nodes: body.num_nodes(),
                    num_cells: body.total_cells(),
                    num_dofs: body.num_dofs(),
                    node_offset,
                    cell_offset,
                    reactions: s.reactions.iter().cloned().collect(),
                    solve: s.stats.clone(),
                };
                node_offset += body.num_nodes();
                cell_offset += body.total_cells();
                summary
            })
            .collect();
        CaseSummary {
            case: case.path.display().to_string(),
            mesh: mesh.path.display().to_string(),
            dimension: mesh.dim,
            bodies,
            contact: match &self.contacts[..] {
                [single] => Some(single.summary.clone()),
                _ => None,
            },
            contacts: match self.contacts.len() {
                1 => Vec::new(),
                _ => self.contacts.iter().map(|c| c.summary.clone()).collect(),
            },
            timings: timings.with_total(),
            peak_memory_mb: peak_memory_mb(),
            ranks: crate::parallel::ranks().size,
            rank_peak_memory_mb: self.rank_peak_memory_mb.clone(),
        }
    }
}

fn summarize_contact(
    name: String,
    problem: &ContactProblem,
    solution: &ContactSolution,
    steps: Vec<crate::contact::StepRecord>,
) -> ContactSummary {
    let dim = problem.primary_surface.dim;
    let (solved, accuracy) = ContactSummary::checks(&solution.certificate);
    let active = |fields: &SurfaceFields| fields.active.iter().filter(|&&a| a).count();
    ContactSummary {
        name,
        status: solution.status,
        primary: problem.primary.body.name.clone(),
        secondary: problem.secondary.body.name.clone(),
        primary_choice: problem.primary_report.clone(),
        transfer: problem.transfer(),
        penalty_stiffness: problem.penalty_stiffness(),
        solved,
        accuracy,
        settings: problem.settings,
        linear_solvers: solution.linear_solvers.clone(),
        force_primary: solution.force_primary[..dim].to_vec(),
        force_secondary: solution.force_secondary[..dim].to_vec(),
        force_imbalance: solution.force_imbalance,
        active_primary: active(&solution.primary_fields),
        active_secondary: active(&solution.secondary_fields),
        max_pressure: (solution.primary_fields.pressure.iter().cloned()).fold(0.0, f64::max),
        max_tangential_traction: solution.max_tangential_traction,
        hertz_fit: solution.hertz_primary,
        iterations: solution.history.clone(),
        steps,
    }
}

/// The approach the two bodies' prescribed displacements impose at load factor 1: the largest
/// `|u1 - u2|` over a Dirichlet condition of each body (components not prescribed count as
/// 0). A hemisphere pushed down by 0.01 onto a clamped block: 0.01.
fn imposed_approach(problem: &ContactProblem) -> f64 {
    let vector = |c: &DirichletCondition| c.components.map(|u| u.unwrap_or(0.0));
    let mut largest = 0.0f64;
    for a in &problem.primary.dirichlet {
        for b in &problem.secondary.dirichlet {
            let (u1, u2) = (vector(a), vector(b));
            let d = (0..3).map(|k| (u1[k] - u2[k]).powi(2)).sum::<f64>().sqrt();
            largest = largest.max(d);
        }
    }
    largest
}

/// The case file's name without its extension (the plot title).
pub(super) fn case_name(case: &Case) -> String {
    case.path.file_stem().map_or_else(
        || case.path.display().to_string(),
        |s| s.to_string_lossy().into_owned(),
    )
}
