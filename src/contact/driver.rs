//! The contact solve a caller asks for: from the contact pairs and their load factors to a
//! certified answer for each pair, whichever primary carries it.
//!
//! ```text
//! 1. every load step with the chosen primaries (one set-up, one active-set loop per step,
//!    all pairs together)
//! 2. for each pair where "auto" chose between bodies of similar stiffness and the answer is
//!    not trusted (not solved, or its accuracy report failed):
//!      every load step with the other primary in those pairs; keep that answer if each of
//!      them is trusted there (and agrees with the first one where that one settled with a
//!      passing accuracy report) and no other pair lost its trust
//! 3. for each pair whose primary was named and is much stiffer than the other body, or
//!    that asks (check_other_primary):
//!      every load step with the other primary in those pairs; check that each one's two
//!      contact forces agree
//! 4. for each pair that names a transfer auto would not choose:
//!      every load step with auto's transfer in those pairs; check that the forces agree
//! ```
//!
//! Step 2 answers the sag of a curved secondary between the nodes of a coarse flat primary
//! ([`OtherPrimary::RetryIfUntrusted`]); step 3 the stiff primary that passes every check of
//! the loop's certificate with a wrong force ([`OtherPrimary::CheckAgreement`]). The pairs are
//! decided together, so each of steps 2 to 4 solves the whole case again with the
//! alternative in the pairs concerned, the others as they are. They live here, not in the
//! command line, so that every caller of [`solve_contact`] gets the same answer.

use std::collections::BTreeMap;
use std::time::Instant;

use serde::Serialize;

use crate::contact::ContactError;
use crate::contact::active_set::ActiveSet;
use crate::contact::certificate::{CertificateCheck, CheckKind};
use crate::contact::iteration::solve::ContactSolver;
use crate::contact::problem::{ContactProblem, OtherPrimary};
use crate::contact::settings::Transfer;
use crate::contact::solution::{ContactSolution, ContactStatus, ForcedDisplacement};
use crate::contact::verify::checks::agreement;
use crate::elastic::{SolverSettings, StepFactors};
use crate::progress::Heartbeat;

/// How one load step ended.
#[derive(Debug, Clone, Serialize)]
pub struct StepRecord {
    pub step: usize,
    /// The factor of the loads, forces and prescribed displacements without a load path
    /// (`load_steps`).
    pub load_factor: f64,
    /// The factor of each named load path (`[load_path]`; empty, and left out of
    /// `summary.json`, without one).
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub path_factors: BTreeMap<String, f64>,
    pub status: ContactStatus,
    pub iterations: usize,
    /// Total contact force on each body (the CSV has the primary's).
    pub force_primary: Vec<f64>,
    pub force_secondary: Vec<f64>,
    pub force_imbalance: f64,
    pub hertz_a: Option<f64>,
    pub hertz_p0: Option<f64>,
    /// The displacement of each force-controlled group (the approach a force gave).
    pub forced: Vec<ForcedDisplacement>,
    pub seconds: f64,
    /// Whether the step's accuracy report passed.
    pub accurate: bool,
    /// The checks this step failed: residuals (`not-solved`) and accuracy indicators.
    pub failed_checks: Vec<CheckKind>,
    /// A Coulomb pair's tangential answer at this step.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub friction: Option<StepFriction>,
}

/// A Coulomb pair's tangential answer at a load step ([`crate::contact::FrictionFields`]).
#[derive(Debug, Clone, Serialize)]
pub struct StepFriction {
    /// The tangential and the normal contact force on the primary (`dim` components).
    pub tangential_force: Vec<f64>,
    pub normal_force: f64,
    /// The primary's nodes in contact that stick and that slip.
    pub stick_nodes: usize,
    pub slip_nodes: usize,
}

impl StepRecord {
    /// Adds an accuracy indicator computed after the loop.
    fn certify_further(&mut self, check: &CertificateCheck) {
        if !check.passed {
            self.accurate = false;
            self.failed_checks.push(check.name);
        }
    }

    /// Whether the step's answer is one to rely on: solved, and accurate.
    fn is_trusted(&self) -> bool {
        self.status.is_solution() && self.accurate
    }

    /// How the step ended, in a few words: the status, and the failed checks.
    fn ending(&self) -> String {
        let failed: Vec<&str> = self.failed_checks.iter().map(|c| c.name()).collect();
        if failed.is_empty() {
            self.status.name().to_string()
        } else if self.status.is_solution() {
            format!(
                "{}, accuracy report failed ({})",
                self.status.name(),
                failed.join(", ")
            )
        } else {
            format!("{} ({})", self.status.name(), failed.join(", "))
        }
    }
}

/// A finished contact solve.
pub struct ContactRun<'m> {
    /// The pairs of the answer, in the order given: a single pair's primary is the body that
    /// carries the multiplier (the other one after a retry), and its report says why.
    pub problems: Vec<ContactProblem<'m>>,
    /// Each pair's answer at the last load step; its status and certificate include the
    /// checks made after the loop.
    pub solutions: Vec<ContactSolution>,
    /// Each pair's records, one per load step.
    pub steps: Vec<Vec<StepRecord>>,
    /// Each load step's answers before the last one (indexed by step, then pair), with
    /// `SolverSettings::keep_step_fields`; empty without it. Their status and certificate are
    /// the loop's: the checks made after the loop are in the step records only.
    pub earlier_solutions: Vec<Vec<ContactSolution>>,
    /// Seconds of each set-up and load step, named in order (the checking solves prefixed).
    pub timings: Vec<(String, f64)>,
}

/// Solves the contact `problems` (one or several pairs, decided together) at each of
/// `load_factors` in turn (each step starting from the previous active sets), with the retry
/// and the agreement checks of the module doc for each pair that needs them. Progress goes to
/// the `log` crate when `solver.verbose`, at the levels of docs/output.md ("The log": info a
/// line per phase and per load step, debug the iterations and checks, trace the Krylov
/// solves). Every load, force and prescribed
/// displacement is scaled by the step's factor: [`solve_contact_steps`] with no named load
/// path.
pub fn solve_contact<'m>(
    problems: Vec<ContactProblem<'m>>,
    solver: &SolverSettings,
    load_factors: &[f64],
) -> Result<ContactRun<'m>, ContactError> {
    if load_factors.is_empty() || !load_factors.iter().all(|f| f.is_finite()) {
        return Err(ContactError::LoadFactors(load_factors.to_vec()));
    }
    let steps: Vec<StepFactors> = (load_factors.iter())
        .map(|&f| StepFactors::uniform(f))
        .collect();
    solve_contact_steps(problems, solver, &steps)
}

/// [`solve_contact`] along a load path: at each step of `load_path` every load, force and
/// prescribed displacement is scaled by its path's factor (the default path's, or that of the
/// named path its condition follows). Every step must give every named path the problems use,
/// and the same ones; the factors must be finite.
pub fn solve_contact_steps<'m>(
    problems: Vec<ContactProblem<'m>>,
    solver: &SolverSettings,
    load_path: &[StepFactors],
) -> Result<ContactRun<'m>, ContactError> {
    if load_path.is_empty() || !load_path.iter().all(|f| f.default.is_finite()) {
        return Err(ContactError::LoadFactors(
            load_path.iter().map(|f| f.default).collect(),
        ));
    }
    for (k, factors) in load_path.iter().enumerate() {
        if let Some((name, f)) = factors.paths.iter().find(|(_, f)| !f.is_finite()) {
            return Err(ContactError::LoadPath(format!(
                "step {}: path '{name}' has the factor {f}, expected a finite number",
                k + 1
            )));
        }
        if !factors.paths.keys().eq(load_path[0].paths.keys()) {
            return Err(ContactError::LoadPath(format!(
                "step {} names the paths {:?}, step 1 {:?}: every step gives the same paths",
                k + 1,
                factors.paths.keys().collect::<Vec<_>>(),
                load_path[0].paths.keys().collect::<Vec<_>>()
            )));
        }
        (problems.iter()).try_for_each(|pair| pair.check_paths(factors))?;
    }
    let mut log = Log {
        verbose: solver.verbose,
        timings: Vec::new(),
    };
    // 1. The chosen primaries.
    let keep = solver.keep_step_fields;
    let (solutions, steps, earlier) =
        solve_load_steps(&problems, solver, load_path, keep, "", &mut log)?;
    let mut run = Answer {
        problems,
        solutions,
        steps,
        earlier,
    };
    // 2. The other primary of each pair where auto's choice between similar bodies did not
    //    settle.
    let retried: Vec<usize> = (0..run.problems.len())
        .filter(|&p| {
            run.problems[p].primary_report.other_primary == OtherPrimary::RetryIfUntrusted
                && run.solutions[p].wants_other_primary()
        })
        .collect();
    if !retried.is_empty() {
        run = retry_with_other_primary(run, &retried, solver, load_path, &mut log);
    }
    // The retry and the checks go on after an error of their own: a cancelled one ends here.
    solver.cancel.check()?;
    // 3. The other primary's forces, where a stiff primary was named or the case asks for
    //    them (a retry has compared the two already); 4. auto's transfer's, where another
    //    transfer was named. Only pairs with a solved step have an answer to check.
    for alternative in [Alternative::OtherPrimary, Alternative::AutoTransfer] {
        let due: Vec<usize> = (0..run.problems.len())
            .filter(|&p| {
                let problem = &run.problems[p];
                let solved = run.steps[p].iter().any(|s| s.status.is_solution());
                solved
                    && match alternative {
                        Alternative::OtherPrimary => {
                            problem.primary_report.other_primary == OtherPrimary::CheckAgreement
                                || (problem.settings.check_other_primary && !retried.contains(&p))
                        }
                        Alternative::AutoTransfer => problem.transfer_differs_from_auto(),
                    }
            })
            .collect();
        if !due.is_empty() {
            check_against(&mut run, alternative, &due, solver, load_path, &mut log);
            solver.cancel.check()?;
        }
    }
    for (p, (solution, steps)) in run.solutions.iter().zip(&mut run.steps).enumerate() {
        report_coverage(&pair_label(&run.problems, p), solution, &log);
        // The last step's record is the answer's, checks made after the loop included.
        if let Some(last) = steps.last_mut() {
            last.status = solution.status;
            last.accurate = solution.certificate.accurate();
            last.failed_checks = solution.certificate.failed();
        }
    }
    Ok(ContactRun {
        problems: run.problems,
        solutions: run.solutions,
        steps: run.steps,
        earlier_solutions: run.earlier,
        timings: log.timings,
    })
}

/// The pairs, their answers at the last load step and their step records, of one solve, and
/// the answers of the steps before the last when they are kept ([`ContactRun::earlier_solutions`]).
struct Answer<'m> {
    problems: Vec<ContactProblem<'m>>,
    solutions: Vec<ContactSolution>,
    steps: Vec<Vec<StepRecord>>,
    earlier: Vec<Vec<ContactSolution>>,
}

/// The accuracy report of `solution` (the last step's, after every check) in one line: its
/// verdict and the errors it could not estimate, by name; with -v, why each was not and how to
/// estimate it (a sentence each).
fn report_coverage(pair: &str, solution: &ContactSolution, log: &Log) {
    let coverage = solution.certificate.coverage();
    let missing: Vec<_> = (coverage.iter())
        .filter_map(|e| e.not_estimated.as_ref().map(|how| (e.error, how)))
        .collect();
    let verdict = match solution.certificate.accurate() {
        true => "passed".to_string(),
        false => format!("FAILED ({})", solution.certificate.failed_names()),
    };
    let not_estimated = match missing.is_empty() {
        true => String::new(),
        false => format!(
            "; not estimated: {} (-v says why)",
            (missing.iter().map(|(error, _)| *error))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    log.say(format!("{pair}accuracy report: {verdict}{not_estimated}"));
    for (error, how) in missing {
        log.detail(format!("  {error} not estimated: {how}"));
    }
}

/// Every load step again with the other body as primary in each of the `retried` pairs (the
/// pairs are decided together, so the whole case is solved again). The second answer is kept
/// if every retried pair is trusted there (and agrees with the first where that one settled:
/// [`agrees_with_first`]) and no pair trusted in the first answer lost it; otherwise the first
/// answer is, and each retried pair's reason says what both ended with.
fn retry_with_other_primary<'m>(
    first: Answer<'m>,
    retried: &[usize],
    solver: &SolverSettings,
    load_path: &[StepFactors],
    log: &mut Log,
) -> Answer<'m> {
    let mut others = first.problems.clone();
    for &p in retried {
        let other = others[p].clone().with_other_primary();
        log.say(format!(
            "primary = \"auto\": with '{}' as primary the solve ended {}; solving again with '{}' \
             as primary",
            first.problems[p].primary.body.name,
            first.solutions[p].ending(),
            other.primary.body.name
        ));
        others[p] = other;
    }
    let keep = solver.keep_step_fields;
    let retry = solve_load_steps(&others, solver, load_path, keep, "other primary: ", log);
    let retry = retry.map(|(solutions, steps, earlier)| {
        let solutions: Vec<ContactSolution> = (solutions.into_iter().enumerate())
            .map(|(p, second)| match retried.contains(&p) {
                true => {
                    let tolerance = first.problems[p].settings.accuracy_tolerance;
                    agrees_with_first(&first.solutions[p], second, tolerance)
                }
                false => second,
            })
            .collect();
        (solutions, steps, earlier)
    });
    let keep_second = retry.as_ref().is_ok_and(|(second, _, _)| {
        (0..second.len()).all(|p| match retried.contains(&p) {
            true => second[p].is_trusted(),
            false => !first.solutions[p].is_trusted() || second[p].is_trusted(),
        })
    });
    match retry {
        Ok((solutions, steps, earlier)) if keep_second => {
            for &p in retried {
                let (first_name, other_name) = (
                    &first.problems[p].primary.body.name,
                    &others[p].primary.body.name,
                );
                let reason = format!(
                    "'{other_name}' carries the multiplier because '{first_name}' as primary \
                     ended {}",
                    first.solutions[p].ending()
                );
                others[p] = others[p].clone().with_reason_appended(&reason);
            }
            Answer {
                problems: others,
                solutions,
                steps,
                earlier,
            }
        }
        retry => {
            let mut problems = first.problems.clone();
            for &p in retried {
                let second_ended = match &retry {
                    Ok((second, _, _)) => second[p].ending(),
                    Err(e) => format!("with an error ({e})"),
                };
                let reason = format!(
                    "kept although it ended {}: '{}' as primary ended {second_ended}",
                    first.solutions[p].ending(),
                    others[p].primary.body.name
                );
                problems[p] = problems[p].clone().with_reason_appended(&reason);
            }
            Answer { problems, ..first }
        }
    }
}

/// The retry's answer checked against the first one (`primary agreement`), when the first
/// settled (converged, or not solved by a residual) with a passing accuracy report: then it is
/// an answer of the other discretization, and a retry that contradicts it must not be
/// certified: two discretizations of one problem that disagree cannot both be right
/// (`docs/method.md` 4.2). The bound is `accuracy_tolerance` plus the
/// first answer's own imbalance, which is how well that answer knows its force.
fn agrees_with_first(
    first: &ContactSolution,
    mut second: ContactSolution,
    accuracy_tolerance: f64,
) -> ContactSolution {
    let settled = first.status.is_solution() || first.status == ContactStatus::NotSolved;
    if settled && first.certificate.accurate() {
        let tolerance = accuracy_tolerance + first.force_imbalance;
        let reference = [first.force_secondary, first.force_primary];
        let forces = [second.force_primary, second.force_secondary];
        let with = "the first choice of primary";
        let check = agreement(
            CheckKind::PrimaryAgreement,
            forces,
            Ok(reference),
            with,
            tolerance,
        );
        second.certify_further(check);
    }
    second
}

/// Another discretization of the same problem, to check an answer against.
#[derive(Clone, Copy, PartialEq)]
enum Alternative {
    /// The other body as primary (its force on this primary is the opposite of its own).
    OtherPrimary,
    /// The same primary, with the transfer `auto` would choose.
    AutoTransfer,
}

/// How far an answer may be from the truth for each unit of its distance to a better
/// discretization of the same problem. The distance `d` between the answer `F` and the better
/// one `R` estimates `F`'s error only up to `R`'s own: `|F - T| <= d + |R - T|`; with `R` at most
/// `theta` times as far from the truth as `F`, `|F - T| <= d / (1 - theta)`. `theta = 0.2`: on
/// the foreign meshes (`validation/foreign_meshes.py`), wherever a stiff block named primary
/// was more than 0.1% off the rigid-flat force, the compliant body's answer as primary was at
/// most 0.09 times as far off (41 pairs, 2026-11-28). Without the factor, a stiff block named
/// primary on a sphere (3D, R/25) passed its agreement check 0.999% from the sphere's answer with
/// a 1% tolerance while 1.01% off the reference.
const ERROR_PER_DISTANCE_TO_BETTER: f64 = 1.25;

/// Every load step again with the `alternative` discretization of the `due` pairs (the other
/// pairs as they are: the pairs are decided together), and an agreement check of each due
/// pair's force at each step against it (`primary agreement` or `transfer agreement`): in the
/// last step's accuracy report, and in every step's record (the force-displacement curve is an
/// answer too). The answers kept are the named choices'. When the alternative is the better
/// discretization (auto's primary or transfer, the named one not), the distance to it may be
/// at most the accuracy tolerance over [`ERROR_PER_DISTANCE_TO_BETTER`]; otherwise the
/// tolerance itself (the answer checked is the better one, its error at most the distance).
///
/// The alternative's answer is compared whenever it is trusted, `no-contact` included: that is
/// a right answer of a single run (bodies apart, a pair of a loop that stays open), so both
/// discretizations finding no contact agree (both forces zero: the figure 0), and one finding
/// contact where the other finds none disagree (the figure 1).
fn check_against(
    run: &mut Answer,
    alternative: Alternative,
    due: &[usize],
    solver: &SolverSettings,
    load_path: &[StepFactors],
    log: &mut Log,
) {
    let other = OtherSolve::new(&run.problems, alternative, due);
    for (&p, with) in due.iter().zip(&other.with) {
        let pair = pair_label(&run.problems, p);
        log.say(format!(
            "{pair}checking the answer: solving again with {with}"
        ));
    }
    let label = match &other.with[..] {
        [with] => format!("check with {with}: "),
        _ => "check with the other discretizations: ".to_string(),
    };
    // A check's answers are compared, not kept: its earlier steps' fields are not either.
    let solved = solve_load_steps(&other.problems, solver, load_path, false, &label, log);
    for (k, &p) in due.iter().enumerate() {
        let problem = &run.problems[p];
        let reference_is_better = match alternative {
            Alternative::OtherPrimary => {
                problem.primary_report.other_primary == OtherPrimary::CheckAgreement
            }
            Alternative::AutoTransfer => true,
        };
        let per_distance = match reference_is_better {
            true => ERROR_PER_DISTANCE_TO_BETTER,
            false => 1.0,
        };
        let tolerance = problem.settings.accuracy_tolerance / per_distance;
        let (reference, other_steps) = match &solved {
            Ok((checks, other_steps, _)) if checks[p].is_trusted() => {
                let check = &checks[p];
                (
                    Ok(other.on_these_bodies(check.force_primary, check.force_secondary)),
                    &other_steps[p][..],
                )
            }
            Ok((checks, other_steps, _)) => (Err(checks[p].ending()), &other_steps[p][..]),
            Err(e) => (Err(format!("with an error ({e})")), &[][..]),
        };
        let with = &other.with[k];
        other.certify_earlier_steps(&mut run.steps[p], other_steps, with, tolerance);
        let solution = &mut run.solutions[p];
        let forces = [solution.force_primary, solution.force_secondary];
        let check = agreement(other.kind, forces, reference, with, tolerance);
        let pair = pair_label(&run.problems, p);
        log.say(format!("{pair}check with {with}: {}", check.describe()));
        solution.certify_further(check);
        log.detail(format!(
            "{pair}contact status: {}\n{}",
            solution.summary(),
            solution.details(problem.settings.formulation)
        ));
    }
}

/// How messages name pair `p` of `problems`: nothing for a single pair.
fn pair_label(problems: &[ContactProblem], p: usize) -> String {
    match problems.len() {
        1 => String::new(),
        _ => format!(
            "'{}' on '{}': ",
            problems[p].primary.body.name, problems[p].secondary.body.name
        ),
    }
}

/// The solve of an [`Alternative`] that the answers of some pairs are checked against.
struct OtherSolve<'m> {
    /// Every pair: the checked ones with the alternative discretization.
    problems: Vec<ContactProblem<'m>>,
    kind: CheckKind,
    /// Whether a checked pair's primary is this solve's secondary.
    swapped: bool,
    /// What the messages call the alternative of each checked pair: "'block' as primary",
    /// "the interpolation transfer".
    with: Vec<String>,
}

impl<'m> OtherSolve<'m> {
    fn new(problems: &[ContactProblem<'m>], alternative: Alternative, checked: &[usize]) -> Self {
        let (kind, swapped) = match alternative {
            Alternative::OtherPrimary => (CheckKind::PrimaryAgreement, true),
            Alternative::AutoTransfer => (CheckKind::TransferAgreement, false),
        };
        let mut others = problems.to_vec();
        let mut with = Vec::with_capacity(checked.len());
        for &p in checked {
            let other = match alternative {
                Alternative::OtherPrimary => problems[p].clone().with_other_primary(),
                Alternative::AutoTransfer => problems[p].clone().with_transfer(Transfer::Auto),
            };
            with.push(match alternative {
                Alternative::OtherPrimary => format!("'{}' as primary", other.primary.body.name),
                Alternative::AutoTransfer => format!(
                    "the {} transfer",
                    serde_json::to_value(other.transfer().transfer)
                        .expect("a unit enum serializes")
                )
                .replace('"', ""),
            });
            others[p] = other;
        }
        OtherSolve {
            problems: others,
            kind,
            swapped,
            with,
        }
    }

    /// The other solve's forces on [this primary body, this secondary body]: its primary is
    /// this solve's secondary when the primaries are swapped.
    fn on_these_bodies(&self, primary: [f64; 3], secondary: [f64; 3]) -> [[f64; 3]; 2] {
        if self.swapped {
            [secondary, primary]
        } else {
            [primary, secondary]
        }
    }

    /// The agreement check of a pair's steps before the last, each against `other_steps`'
    /// step at the same load factor (the alternative called `with`).
    fn certify_earlier_steps(
        &self,
        steps: &mut [StepRecord],
        other_steps: &[StepRecord],
        with: &str,
        tolerance: f64,
    ) {
        let earlier = steps.len().saturating_sub(1);
        for (k, step) in steps[..earlier].iter_mut().enumerate() {
            let other_step = match other_steps.get(k) {
                Some(o) if o.is_trusted() => {
                    Ok(self.on_these_bodies(vector(&o.force_primary), vector(&o.force_secondary)))
                }
                Some(o) => Err(o.ending()),
                None => Err("before this load step (its load steps stopped)".to_string()),
            };
            let forces = [vector(&step.force_primary), vector(&step.force_secondary)];
            let check = agreement(self.kind, forces, other_step, with, tolerance);
            step.certify_further(&check);
        }
    }
}

/// The set-up (assembly, factorizations, interpolation) once, then one active-set loop per
/// load step, each starting from the previous active sets; stops at the first step whose loop
/// does not settle (`not-solved` steps go on). `label` prefixes the timing names. Each pair's
/// answer at the last step, and its records; with `keep`, the answers of the steps before the
/// last (by step, then pair), else nothing.
#[allow(clippy::type_complexity)]
fn solve_load_steps(
    problems: &[ContactProblem],
    solver: &SolverSettings,
    load_path: &[StepFactors],
    keep: bool,
    label: &str,
    log: &mut Log,
) -> Result<
    (
        Vec<ContactSolution>,
        Vec<Vec<StepRecord>>,
        Vec<Vec<ContactSolution>>,
    ),
    ContactError,
> {
    let dim = problems[0].primary_surface.dim;
    let phase = Instant::now();
    let set_up = Heartbeat::start(log.verbose, format!("  {label}contact set-up"));
    let mut contact_solver = ContactSolver::new(problems, solver)?;
    drop(set_up);
    log.time(format!("{label}contact set-up"), phase);
    for problem in problems {
        let transfer = problem.transfer();
        log.say(format!(
            "{label}force on '{}': {} transfer ({})",
            problem.secondary.body.name,
            serde_json::to_value(transfer.transfer).expect("a unit enum serializes"),
            transfer.reason
        ));
    }
    let mut steps = vec![Vec::new(); problems.len()];
    let mut last: Option<Vec<ContactSolution>> = None;
    let mut earlier = Vec::new();
    for (k, factors) in load_path.iter().enumerate() {
        solver.cancel.check()?;
        // "load step 2/5 (factor 0.55)" heads the step's outcome; with -v it also opens the
        // step's iterations, in the form validation/contact_benchmark.py parses.
        let step = match load_path.len() {
            1 => None,
            n => {
                let paths: String = (factors.paths.iter())
                    .map(|(name, f)| format!(", path '{name}' {f}"))
                    .collect();
                log.detail(format!(
                    "{label}load step {}/{n}: factor {}{paths}",
                    k + 1,
                    factors.default
                ));
                Some(format!(
                    "load step {}/{n} (factor {}{paths})",
                    k + 1,
                    factors.default
                ))
            }
        };
        let phase = Instant::now();
        let start: Option<Vec<ActiveSet>> = (last.as_ref())
            .map(|solutions| solutions.iter().map(|s| s.active_set.clone()).collect());
        // The paths the bodies follow: one that none does changes nothing, not even the
        // coupled solve's first guess (`StepFactors::scale_from`).
        let used = problems
            .iter()
            .flat_map(|p| [&p.primary, &p.secondary])
            .flat_map(|elastic| elastic.paths());
        let solutions = contact_solver.solve(&factors.only(used), start.as_deref())?;
        let seconds = log.time(format!("{label}contact step {}", k + 1), phase);
        for ((problem, solution), steps) in problems.iter().zip(&solutions).zip(&mut steps) {
            let pair = match problems.len() {
                1 => String::new(),
                _ => format!(
                    "'{}' on '{}': ",
                    problem.primary.body.name, problem.secondary.body.name
                ),
            };
            let head = step.as_deref().unwrap_or("contact status");
            log.say(format!(
                "{label}{head}: {pair}{}; {seconds:.2} s",
                solution.summary()
            ));
            log.detail(solution.details(problem.settings.formulation));
            steps.push(StepRecord {
                step: k + 1,
                load_factor: factors.default,
                path_factors: factors.paths.clone(),
                status: solution.status,
                iterations: solution.history.len(),
                force_primary: solution.force_primary[..dim].to_vec(),
                force_secondary: solution.force_secondary[..dim].to_vec(),
                force_imbalance: solution.force_imbalance,
                hertz_a: solution.hertz_primary.map(|h| h.a),
                hertz_p0: solution.hertz_primary.map(|h| h.p0),
                forced: solution.forced.clone(),
                seconds,
                accurate: solution.certificate.accurate(),
                failed_checks: solution.certificate.failed(),
                friction: (solution.primary_fields.friction.as_ref()).map(|f| StepFriction {
                    tangential_force: f.tangential_force[..dim].to_vec(),
                    normal_force: f.normal_force,
                    stick_nodes: f.stick_nodes,
                    slip_nodes: f.slip_nodes,
                }),
            });
        }
        // A step whose active set settled is a valid start for the next one, whatever its
        // checks say (each step is checked on its own: a narrow zone at a small load factor can
        // fail the sag check on a mesh that resolves the final zone); a loop that did not settle
        // is not.
        let stop = (solutions.iter())
            .any(|s| !s.status.is_solution() && s.status != ContactStatus::NotSolved);
        // The step before is moved, not copied: keeping it costs its memory only.
        if let Some(before) = last.replace(solutions)
            && keep
        {
            earlier.push(before);
        }
        if stop {
            log.say("stopping the load steps: this step's active set did not settle");
            break;
        }
    }
    let last = last.expect("solve_contact checks the load factors");
    Ok((last, steps, earlier))
}

/// A step record's force (`dim` components) as a 3-vector.
fn vector(force: &[f64]) -> [f64; 3] {
    std::array::from_fn(|c| *force.get(c).unwrap_or(&0.0))
}

/// Progress messages (when verbose) and phase timings of a solve.
struct Log {
    verbose: bool,
    timings: Vec<(String, f64)>,
}

impl Log {
    /// A line of the default log: a phase, a load step's outcome.
    fn say(&self, message: impl AsRef<str>) {
        if self.verbose {
            log::info!("{}", message.as_ref());
        }
    }

    /// A line of the `-v` log: what led to a phase's outcome.
    fn detail(&self, message: impl AsRef<str>) {
        if self.verbose {
            log::debug!("{}", message.as_ref());
        }
    }

    /// Records the seconds since `start` under `name`, and returns them.
    fn time(&mut self, name: String, start: Instant) -> f64 {
        let seconds = start.elapsed().as_secs_f64();
        self.timings.push((name, seconds));
        seconds
    }
}
