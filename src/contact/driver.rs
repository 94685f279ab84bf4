//! The contact solve a caller asks for: from a problem and its load factors to a certified
//! answer, whichever primary carries it.
//!
//! ```text
//! 1. every load step with the chosen primary (one set-up, one active-set loop per step)
//! 2. if "auto" chose between bodies of similar stiffness and the answer is not trusted
//!    (not solved, or its accuracy report failed):
//!      every load step with the other primary; keep its answer if that one is, and agrees
//!      with the first one where that one settled with a passing accuracy report
//! 3. if the primary was named and is much stiffer than the other body, or the case asks
//!    (check_other_primary):
//!      every load step with the other primary; check that the two contact forces agree
//! 4. if a transfer was named that auto would not choose:
//!      every load step with auto's transfer; check that the two contact forces agree
//! ```
//!
//! Step 2 answers the sag of a curved secondary between the nodes of a coarse flat primary
//! ([`OtherPrimary::RetryIfUntrusted`]); step 3 the stiff primary that passes every check of
//! the loop's certificate with a wrong force ([`OtherPrimary::CheckAgreement`]). Both live here,
//! not in the command line, so that every caller of [`solve_contact`] gets the same answer.

use std::time::Instant;

use serde::Serialize;

use super::certificate::CheckKind;
use super::checks::agreement;
use super::{
    ActiveSet, CertificateCheck, ContactError, ContactProblem, ContactSolution, ContactSolver,
    ContactStatus, ForcedDisplacement, OtherPrimary, Transfer,
};
use crate::elastic::SolverSettings;

/// How one load step ended.
#[derive(Debug, Clone, Serialize)]
pub struct StepRecord {
    pub step: usize,
    pub load_factor: f64,
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
    /// Seconds of each set-up and load step, named in order (the checking solves prefixed).
    pub timings: Vec<(String, f64)>,
}

/// Solves the contact `problems` (one or several pairs, decided together) at each of
/// `load_factors` in turn (each step starting from the previous active set). A single pair
/// gets the retry and the agreement checks of the module doc; several pairs are solved once,
/// and a case that would need those checks is refused ([`refuse_unchecked`]). Progress goes
/// to the `log` crate (level info) when `solver.verbose`.
pub fn solve_contact<'m>(
    problems: Vec<ContactProblem<'m>>,
    solver: &SolverSettings,
    load_factors: &[f64],
) -> Result<ContactRun<'m>, ContactError> {
    if load_factors.is_empty() || !load_factors.iter().all(|f| f.is_finite()) {
        return Err(ContactError::LoadFactors(load_factors.to_vec()));
    }
    let mut log = Log {
        verbose: solver.verbose,
        timings: Vec::new(),
    };
    let problems = match <[ContactProblem; 1]>::try_from(problems) {
        Ok([problem]) => {
            let (problem, solution, steps) = solve_pair(problem, solver, load_factors, &mut log)?;
            return Ok(ContactRun {
                problems: vec![problem],
                solutions: vec![solution],
                steps: vec![steps],
                timings: log.timings,
            });
        }
        Err(problems) => problems,
    };
    refuse_unchecked(&problems)?;
    let (solutions, steps) = solve_load_steps(&problems, solver, load_factors, "", &mut log)?;
    for solution in &solutions {
        report_coverage(solution, &log);
    }
    Ok(ContactRun {
        problems,
        solutions,
        steps,
        timings: log.timings,
    })
}

/// Several pairs are solved once: the retry with the other primary and the agreement checks
/// (module doc) compare whole solves of one pair, and are not made for several. A pair whose
/// answer one of them would have to confirm (a named primary that auto would not choose
/// between bodies of different stiffness, `check_other_primary`, a named transfer auto would
/// not choose) is refused rather than certified unchecked. (An untrusted answer between
/// bodies of similar stiffness is reported as such, without the retry.)
fn refuse_unchecked(problems: &[ContactProblem]) -> Result<(), ContactError> {
    for (p, problem) in problems.iter().enumerate() {
        let names = format!(
            "'{}' and '{}'",
            problem.primary.body.name, problem.secondary.body.name
        );
        let why = if problem.primary_report.other_primary == OtherPrimary::CheckAgreement {
            "names a primary that \"auto\" would not choose (the stiffer body), whose answer \
             must be checked against the other primary's"
        } else if problem.settings.check_other_primary {
            "asks for check_other_primary"
        } else if problem.transfer_differs_from_auto() {
            "names a transfer that \"auto\" would not choose, whose answer must be checked \
             against auto's"
        } else {
            continue;
        };
        return Err(ContactError::PairSettings(format!(
            "pair {} ({names}) {why}; that check is made for a case with one contact pair \
             only: use primary = \"auto\" and transfer = \"auto\" with several pairs",
            p + 1
        )));
    }
    Ok(())
}

/// One pair, with the retry and the agreement checks of the module doc.
fn solve_pair<'m>(
    problem: ContactProblem<'m>,
    solver: &SolverSettings,
    load_factors: &[f64],
    log: &mut Log,
) -> Result<(ContactProblem<'m>, ContactSolution, Vec<StepRecord>), ContactError> {
    // 1. The chosen primary.
    let (solution, steps) = solve_pair_steps(&problem, solver, load_factors, "", log)?;
    // 2. The other primary, when auto's choice between similar bodies did not settle.
    let other_primary = problem.primary_report.other_primary;
    let retry = other_primary == OtherPrimary::RetryIfUntrusted && !solution.is_trusted();
    let (problem, mut solution, mut steps) = if retry {
        retry_with_other_primary(problem, solution, steps, solver, load_factors, log)
    } else {
        (problem, solution, steps)
    };
    // The retry and the checks go on after an error of their own: a cancelled one ends here.
    solver.cancel.check()?;
    // 3. The other primary's forces, when a stiff primary was named or the case asks for
    //    them (a retry has compared the two already); 4. auto's transfer's, when another
    //    transfer was named.
    if steps.iter().any(|s| s.status.is_solution()) {
        for alternative in [Alternative::OtherPrimary, Alternative::AutoTransfer] {
            let due = match alternative {
                Alternative::OtherPrimary => {
                    other_primary == OtherPrimary::CheckAgreement
                        || (problem.settings.check_other_primary && !retry)
                }
                Alternative::AutoTransfer => problem.transfer_differs_from_auto(),
            };
            if due {
                // The other discretization is the better one when it is auto's choice.
                let reference_is_better = match alternative {
                    Alternative::OtherPrimary => other_primary == OtherPrimary::CheckAgreement,
                    Alternative::AutoTransfer => true,
                };
                solution = check_against(
                    &problem,
                    (alternative, reference_is_better),
                    solution,
                    &mut steps,
                    solver,
                    load_factors,
                    log,
                );
                solver.cancel.check()?;
            }
        }
    }
    report_coverage(&solution, log);
    // The last step's record is the answer's, checks made after the loop included.
    if let Some(last) = steps.last_mut() {
        last.status = solution.status;
        last.accurate = solution.certificate.accurate();
        last.failed_checks = solution.certificate.failed();
    }
    Ok((problem, solution, steps))
}

/// Says which errors the accuracy report of `solution` could not estimate, and why.
fn report_coverage(solution: &ContactSolution, log: &Log) {
    for error in solution.certificate.coverage() {
        if let Some(how) = error.not_estimated {
            log.say(format!(
                "accuracy report: {} not estimated: {how}",
                error.error
            ));
        }
    }
}

/// Every load step again with the other body as primary. Its answer is kept if it is a
/// solution; otherwise the first one is, and the reason says what both ended with.
fn retry_with_other_primary<'m>(
    problem: ContactProblem<'m>,
    solution: ContactSolution,
    steps: Vec<StepRecord>,
    solver: &SolverSettings,
    load_factors: &[f64],
    log: &mut Log,
) -> (ContactProblem<'m>, ContactSolution, Vec<StepRecord>) {
    let (first, first_ended) = (problem.primary.body.name.clone(), solution.ending());
    let other = problem.clone().with_other_primary();
    let other_name = other.primary.body.name.clone();
    log.say(format!(
        "primary = \"auto\": with '{first}' as primary the solve ended {first_ended}; solving \
         again with '{other_name}' as primary"
    ));
    let retried = solve_pair_steps(&other, solver, load_factors, "other primary: ", log);
    let tolerance = problem.settings.accuracy_tolerance;
    let retried =
        retried.map(|(second, steps)| (agrees_with_first(&solution, second, tolerance), steps));
    match retried {
        Ok((second, second_steps)) if second.is_trusted() => (
            other.with_reason_appended(&format!(
                "'{other_name}' carries the multiplier because '{first}' as primary ended \
                 {first_ended}"
            )),
            second,
            second_steps,
        ),
        retry => {
            let second_ended = match retry {
                Ok((second, _)) => second.ending(),
                Err(e) => format!("with an error ({e})"),
            };
            let problem = problem.with_reason_appended(&format!(
                "kept although it ended {first_ended}: '{other_name}' as primary ended \
                 {second_ended}"
            ));
            (problem, solution, steps)
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

/// Every load step again with the `alternative` discretization, and an agreement check of each
/// step's force against it (`primary agreement` or `transfer agreement`): in the last step's
/// accuracy report, and in every step's record (the force-displacement curve is an answer
/// too). The answer kept is the named choice's. When the alternative is the better
/// discretization (`reference_is_better`: auto's primary or transfer, the named one not), the
/// distance to it may be at most the accuracy tolerance over
/// [`ERROR_PER_DISTANCE_TO_BETTER`]; otherwise the tolerance itself (the answer checked is
/// the better one, its error at most the distance).
fn check_against(
    problem: &ContactProblem,
    (alternative, reference_is_better): (Alternative, bool),
    mut solution: ContactSolution,
    steps: &mut [StepRecord],
    solver: &SolverSettings,
    load_factors: &[f64],
    log: &mut Log,
) -> ContactSolution {
    let per_distance = match reference_is_better {
        true => ERROR_PER_DISTANCE_TO_BETTER,
        false => 1.0,
    };
    let (tolerance, formulation) = (
        problem.settings.accuracy_tolerance / per_distance,
        problem.settings.formulation,
    );
    let other = OtherSolve::new(problem, alternative);
    let with = &other.with;
    log.say(format!("checking the answer: solving again with {with}"));
    let label = format!("check with {with}: ");
    let solved = solve_pair_steps(&other.problem, solver, load_factors, &label, log);
    let (reference, other_steps) = match solved {
        Ok((check, other_steps))
            if check.status == ContactStatus::Converged && check.is_trusted() =>
        {
            (
                Ok(other.on_these_bodies(check.force_primary, check.force_secondary)),
                other_steps,
            )
        }
        Ok((check, other_steps)) => (Err(check.ending()), other_steps),
        Err(e) => (Err(format!("with an error ({e})")), Vec::new()),
    };
    other.certify_earlier_steps(steps, &other_steps, tolerance);
    let forces = [solution.force_primary, solution.force_secondary];
    let check = agreement(other.kind, forces, reference, with, tolerance);
    log.say(format!("check with {with}: {}", check.describe()));
    solution.certify_further(check);
    log.say(format!(
        "contact status: {}",
        solution.describe(formulation)
    ));
    solution
}

/// The solve of an [`Alternative`] that an answer is checked against.
struct OtherSolve<'m> {
    problem: ContactProblem<'m>,
    kind: CheckKind,
    /// Whether its primary is this solve's secondary.
    swapped: bool,
    /// What the messages call it: "'block' as primary", "the interpolation transfer".
    with: String,
}

impl<'m> OtherSolve<'m> {
    fn new(problem: &ContactProblem<'m>, alternative: Alternative) -> Self {
        let (other, kind, swapped) = match alternative {
            Alternative::OtherPrimary => (
                problem.clone().with_other_primary(),
                CheckKind::PrimaryAgreement,
                true,
            ),
            Alternative::AutoTransfer => (
                problem.clone().with_transfer(Transfer::Auto),
                CheckKind::TransferAgreement,
                false,
            ),
        };
        let with = match alternative {
            Alternative::OtherPrimary => format!("'{}' as primary", other.primary.body.name),
            Alternative::AutoTransfer => format!(
                "the {} transfer",
                serde_json::to_value(other.transfer().transfer).expect("a unit enum serializes")
            )
            .replace('"', ""),
        };
        OtherSolve {
            problem: other,
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

    /// The agreement check of the steps before the last, each against `other_steps`' step at
    /// the same load factor.
    fn certify_earlier_steps(
        &self,
        steps: &mut [StepRecord],
        other_steps: &[StepRecord],
        tolerance: f64,
    ) {
        let trusted = |o: &StepRecord| o.status == ContactStatus::Converged && o.is_trusted();
        let earlier = steps.len().saturating_sub(1);
        for (k, step) in steps[..earlier].iter_mut().enumerate() {
            let other_step = match other_steps.get(k) {
                Some(o) if trusted(o) => {
                    Ok(self.on_these_bodies(vector(&o.force_primary), vector(&o.force_secondary)))
                }
                Some(o) => Err(o.ending()),
                None => Err("before this load step (its load steps stopped)".to_string()),
            };
            let forces = [vector(&step.force_primary), vector(&step.force_secondary)];
            let check = agreement(self.kind, forces, other_step, &self.with, tolerance);
            step.certify_further(&check);
        }
    }
}

/// [`solve_load_steps`] of one pair.
fn solve_pair_steps(
    problem: &ContactProblem,
    solver: &SolverSettings,
    load_factors: &[f64],
    label: &str,
    log: &mut Log,
) -> Result<(ContactSolution, Vec<StepRecord>), ContactError> {
    let (solutions, steps) = solve_load_steps(
        std::slice::from_ref(problem),
        solver,
        load_factors,
        label,
        log,
    )?;
    let solution = solutions.into_iter().next().expect("one pair");
    Ok((solution, steps.into_iter().next().expect("one pair")))
}

/// The set-up (assembly, factorizations, interpolation) once, then one active-set loop per
/// load step, each starting from the previous active sets; stops at the first step whose loop
/// does not settle (`not-solved` steps go on). `label` prefixes the timing names. Each pair's
/// answer at the last step, and its records.
#[allow(clippy::type_complexity)]
fn solve_load_steps(
    problems: &[ContactProblem],
    solver: &SolverSettings,
    load_factors: &[f64],
    label: &str,
    log: &mut Log,
) -> Result<(Vec<ContactSolution>, Vec<Vec<StepRecord>>), ContactError> {
    let dim = problems[0].primary_surface.dim;
    let phase = Instant::now();
    let mut contact_solver = ContactSolver::new(problems, solver)?;
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
    for (k, &factor) in load_factors.iter().enumerate() {
        solver.cancel.check()?;
        if load_factors.len() > 1 {
            log.say(format!(
                "load step {}/{}: factor {factor}",
                k + 1,
                load_factors.len()
            ));
        }
        let phase = Instant::now();
        let start: Option<Vec<ActiveSet>> = (last.as_ref())
            .map(|solutions| solutions.iter().map(|s| s.active_set.clone()).collect());
        let solutions = contact_solver.solve(factor, start.as_deref())?;
        let seconds = log.time(format!("{label}contact step {}", k + 1), phase);
        for ((problem, solution), steps) in problems.iter().zip(&solutions).zip(&mut steps) {
            let pair = match problems.len() {
                1 => String::new(),
                _ => format!(
                    "'{}' on '{}': ",
                    problem.primary.body.name, problem.secondary.body.name
                ),
            };
            log.say(format!(
                "{pair}contact status: {}",
                solution.describe(problem.settings.formulation)
            ));
            steps.push(StepRecord {
                step: k + 1,
                load_factor: factor,
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
            });
        }
        // A step whose active set settled is a valid start for the next one, whatever its
        // checks say (each step is checked on its own: a narrow zone at a small load factor can
        // fail the sag check on a mesh that resolves the final zone); a loop that did not settle
        // is not.
        let stop = (solutions.iter())
            .any(|s| !s.status.is_solution() && s.status != ContactStatus::NotSolved);
        last = Some(solutions);
        if stop {
            log.say("stopping the load steps: this step's active set did not settle");
            break;
        }
    }
    Ok((last.expect("solve_contact checks the load factors"), steps))
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
    fn say(&self, message: impl AsRef<str>) {
        if self.verbose {
            log::info!("{}", message.as_ref());
        }
    }

    /// Records the seconds since `start` under `name`, and returns them.
    fn time(&mut self, name: String, start: Instant) -> f64 {
        let seconds = start.elapsed().as_secs_f64();
        self.timings.push((name, seconds));
        seconds
    }
}
