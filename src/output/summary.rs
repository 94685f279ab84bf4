//! The JSON summary of a run: sizes, reactions, accuracy and timings.

use std::collections::BTreeMap;
use std::path::Path;

use serde::Serialize;

use super::OutputError;
use crate::contact::LinearSolvers;
use crate::contact::{
    Certificate, CertificateCheck, ContactSettings, ContactStatus, ErrorCoverage, HertzFit,
    IterationRecord, PrimaryReport, StepRecord, TransferReport,
};
use crate::elastic::SolveStats;

#[derive(Debug, Clone, Serialize)]
pub struct CaseSummary {
    pub case: String,
    pub mesh: String,
    pub dimension: usize,
    pub bodies: Vec<BodySummary>,
    /// Present in contact runs of one pair.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contact: Option<ContactSummary>,
    /// Each pair's, in the case file's order, in contact runs of several pairs.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub contacts: Vec<ContactSummary>,
    /// Seconds per phase of the whole run, in order.
    pub timings: Vec<(String, f64)>,
    /// The process's peak resident memory up to writing the summary, in MB (`VmHWM` of
    /// `/proc/self/status`; absent where the system does not report it).
    pub peak_memory_mb: Option<f64>,
    /// The number of MPI ranks that solved the case (1: one process).
    pub ranks: usize,
    /// Every rank's peak memory, in rank order, in a distributed run (rank 0's is
    /// `peak_memory_mb`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub rank_peak_memory_mb: Vec<f64>,
}

/// The process's peak resident set size in MB, where Linux reports it.
pub fn peak_memory_mb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

#[derive(Debug, Clone, Serialize)]
pub struct BodySummary {
    pub name: String,
    pub youngs_modulus: f64,
    pub poisson_ratio: f64,
    pub num_nodes: usize,
    pub num_cells: usize,
    pub num_dofs: usize,
    /// First row of this body in the `/mesh/geometry` and `/fields/displacement` datasets.
    pub node_offset: usize,
    /// First row of this body in the cell datasets.
    pub cell_offset: usize,
    /// Reaction force of each Dirichlet group.
    pub reactions: BTreeMap<String, Vec<f64>>,
    pub solve: SolveStats,
}

/// How the contact solve ended, its forces and the iteration history.
#[derive(Debug, Clone, Serialize)]
pub struct ContactSummary {
    /// The pair's name (`[contact] name`; default "BODY1-BODY2").
    pub name: String,
    pub status: ContactStatus,
    pub primary: String,
    pub secondary: String,
    /// Which body carries the multiplier, chosen how and why.
    pub primary_choice: PrimaryReport,
    /// How the secondary's contact force is computed, and why.
    pub transfer: TransferReport,
    /// Whether the last load step's discrete problem is solved: its residual checks.
    pub solved: SolvedChecks,
    /// Whether the last load step's answer can be trusted: its accuracy indicators.
    pub accuracy: AccuracyReport,
    pub settings: ContactSettings,
    /// The penalty `eps = penalty E* / h` of a penalty pair (a pressure per length of
    /// overlap); absent under INTERNODES.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub penalty_stiffness: Option<f64>,
    /// The body and interface solvers that ran (`auto` resolved).
    pub linear_solvers: LinearSolvers,
    /// Total contact force on each body, and `|F1 + F2| / |F1|`.
    pub force_primary: Vec<f64>,
    pub force_secondary: Vec<f64>,
    pub force_imbalance: f64,
    /// Active nodes at the end, on each surface.
    pub active_primary: usize,
    pub active_secondary: usize,
    /// Largest nodal contact pressure and tangential traction on the primary surface.
    pub max_pressure: f64,
    pub max_tangential_traction: f64,
    /// Hertz ellipse fitted to the primary pressure (contact radius / half-width and peak).
    pub hertz_fit: Option<HertzFit>,
    /// Iteration history of the last load step.
    pub iterations: Vec<IterationRecord>,
    /// One record per load step (also written as `force_displacement.csv`).
    pub steps: Vec<StepRecord>,
}

/// The residual checks of the discrete problem (`status` is `converged` only if all passed).
#[derive(Debug, Clone, Serialize)]
pub struct SolvedChecks {
    pub passed: bool,
    pub checks: Vec<CertificateCheck>,
}

/// The accuracy indicators of the answer (a failure leaves the status as it is, and makes the
/// run exit with status 3).
#[derive(Debug, Clone, Serialize)]
pub struct AccuracyReport {
    pub passed: bool,
    pub indicators: Vec<CertificateCheck>,
    /// Which errors of what a user reads the indicators estimate, and which they do not.
    pub coverage: Vec<ErrorCoverage>,
}

/// How a solved case ended, as the command line's exit status tells it.
#[derive(Debug, Clone, PartialEq)]
pub enum Verdict {
    /// Every body solved; a contact problem, if any, solved and its accuracy report passed
    /// (exit status 0).
    Solved,
    /// The contact problem was not solved (a status other than `converged` or `no-contact`;
    /// exit status 2): why, in one line.
    NotSolved(String),
    /// The contact problem was solved but its accuracy report failed (exit status 3): why.
    Inaccurate(String),
}

impl Verdict {
    /// The command line's exit status for this verdict.
    pub fn exit_status(&self) -> u8 {
        match self {
            Verdict::Solved => 0,
            Verdict::NotSolved(_) => 2,
            Verdict::Inaccurate(_) => 3,
        }
    }
}

impl CaseSummary {
    /// Whether the case was solved, and accurately: as its worst pair (a pair not solved
    /// before one whose accuracy report failed), named when there are several.
    pub fn verdict(&self) -> Verdict {
        let several = !self.contacts.is_empty();
        let verdicts = self.contact.iter().chain(&self.contacts).map(|contact| {
            let verdict = contact_verdict(contact);
            match (several, verdict) {
                (true, Verdict::NotSolved(why)) => {
                    Verdict::NotSolved(format!("pair '{}': {why}", contact.name))
                }
                (true, Verdict::Inaccurate(why)) => {
                    Verdict::Inaccurate(format!("pair '{}': {why}", contact.name))
                }
                (_, verdict) => verdict,
            }
        });
        let verdicts: Vec<Verdict> = verdicts.collect();
        (verdicts.iter())
            .find(|v| matches!(v, Verdict::NotSolved(_)))
            .or_else(|| {
                verdicts
                    .iter()
                    .find(|v| matches!(v, Verdict::Inaccurate(_)))
            })
            .cloned()
            .unwrap_or(Verdict::Solved)
    }
}

/// Whether one pair was solved, and accurately.
fn contact_verdict(contact: &ContactSummary) -> Verdict {
    if !contact.status.is_solution() {
        let failed = failures(&contact.solved.checks);
        return Verdict::NotSolved(format!(
            "the contact problem was not solved: status \"{}\"{}",
            contact.status.name(),
            if failed.is_empty() {
                String::new()
            } else {
                format!(", failed: {failed}")
            },
        ));
    }
    if !contact.accuracy.passed {
        return Verdict::Inaccurate(format!(
            "the contact problem was solved, but its accuracy report failed: {}",
            failures(&contact.accuracy.indicators)
        ));
    }
    earlier_steps_verdict(&contact.steps)
}

/// The verdict of the load steps before the last, whose answer was trusted: every step is an
/// answer a user reads (the force-displacement curve), so the run is only as good as its worst
/// step. A step that was not solved makes the run not solved, one whose accuracy report failed
/// makes it inaccurate; the message names the steps.
fn earlier_steps_verdict(steps: &[StepRecord]) -> Verdict {
    let describe = |step: &StepRecord| {
        let failed: Vec<&str> = step.failed_checks.iter().map(|c| c.name()).collect();
        format!(
            "step {} (load factor {}): {}{}",
            step.step,
            step.load_factor,
            step.status.name(),
            if failed.is_empty() {
                String::new()
            } else {
                format!(", failed: {}", failed.join(", "))
            }
        )
    };
    let list = |steps: Vec<&StepRecord>| -> String {
        steps
            .into_iter()
            .map(describe)
            .collect::<Vec<_>>()
            .join("; ")
    };
    let unsolved: Vec<&StepRecord> = steps.iter().filter(|s| !s.status.is_solution()).collect();
    if !unsolved.is_empty() {
        return Verdict::NotSolved(format!(
            "the last load step was solved, but an earlier one was not: {}",
            list(unsolved)
        ));
    }
    let inaccurate: Vec<&StepRecord> = steps.iter().filter(|s| !s.accurate).collect();
    if !inaccurate.is_empty() {
        return Verdict::Inaccurate(format!(
            "the last load step was solved and accurate, but the accuracy report of an earlier \
             one failed: {}",
            list(inaccurate)
        ));
    }
    Verdict::Solved
}

/// The failed checks among `checks`, in one line.
fn failures(checks: &[CertificateCheck]) -> String {
    (checks.iter().filter(|c| !c.passed))
        .map(|c| c.describe())
        .collect::<Vec<_>>()
        .join("; ")
}

impl ContactSummary {
    /// The two parts of a certificate.
    pub fn checks(certificate: &Certificate) -> (SolvedChecks, AccuracyReport) {
        (
            SolvedChecks {
                passed: certificate.solved(),
                checks: certificate.residuals().cloned().collect(),
            },
            AccuracyReport {
                passed: certificate.accurate(),
                indicators: certificate.indicators().cloned().collect(),
                coverage: certificate.coverage(),
            },
        )
    }
}

/// The load steps of each pair of `curves` (its name and its steps) as
/// `force_displacement.csv`: one header line, one row per step. One pair: the columns of
/// `pair_csv`. Several: the step and load factor (and each load path's factor), then each
/// pair's other columns, their names prefixed by the pair's (`upper-middle.contact_force_y`);
/// the pairs share the loop, so they have the same steps.
pub fn force_displacement_csv(curves: &[(&str, &[StepRecord])]) -> String {
    let tables: Vec<String> = curves.iter().map(|(_, steps)| pair_csv(steps)).collect();
    if let [table] = &tables[..] {
        return table.clone();
    }
    let paths = (curves.first())
        .and_then(|(_, steps)| steps.first())
        .map_or(0, |s| s.path_factors.len());
    let shared = 2 + paths;
    let split = |line: &str| -> Vec<String> { line.split(',').map(str::to_string).collect() };
    let lines: Vec<Vec<Vec<String>>> = (tables.iter())
        .map(|table| table.lines().map(split).collect())
        .collect();
    let rows = lines.iter().map(Vec::len).min().unwrap_or(0);
    let mut text = String::new();
    for row in 0..rows {
        let mut fields: Vec<String> = lines[0][row][..shared].to_vec();
        for ((name, _), table) in curves.iter().zip(&lines) {
            fields.extend(table[row][shared..].iter().map(|field| match row {
                0 => format!("{name}.{field}"),
                _ => field.clone(),
            }));
        }
        text += &fields.join(",");
        text += "\n";
    }
    text
}

/// One pair's load steps as CSV: one header line, one row per step. With a load path, each
/// path's factor follows the load factor (`path_<name>`).
fn pair_csv(steps: &[StepRecord]) -> String {
    let dim = steps.first().map_or(0, |s| s.force_primary.len());
    let axes = ["x", "y", "z"];
    let mut text = String::from("step,load_factor");
    for name in steps
        .first()
        .map(|s| s.path_factors.keys())
        .into_iter()
        .flatten()
    {
        text += &format!(",path_{name}");
    }
    text += ",status,iterations";
    for axis in &axes[..dim] {
        text += &format!(",contact_force_{axis}");
    }
    text += ",force_imbalance,hertz_a,hertz_p0";
    for forced in steps.first().map_or(&[][..], |s| &s.forced[..]) {
        text += &format!(
            ",{body}.{group}.f{c},{body}.{group}.u{c}",
            body = forced.body,
            group = forced.group,
            c = forced.component
        );
    }
    let friction = steps.iter().any(|s| s.friction.is_some());
    if friction {
        for axis in &axes[..dim] {
            text += &format!(",tangential_force_{axis}");
        }
        text += ",normal_force,stick_nodes,slip_nodes";
    }
    text += ",seconds,failed_checks\n";
    let optional = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:.10e}"));
    for s in steps {
        text += &format!("{},{}", s.step, s.load_factor);
        for factor in s.path_factors.values() {
            text += &format!(",{factor}");
        }
        text += &format!(",{},{}", s.status.name(), s.iterations);
        for f in &s.force_primary {
            text += &format!(",{f:.10e}");
        }
        text += &format!(
            ",{:.3e},{},{}",
            s.force_imbalance,
            optional(s.hertz_a),
            optional(s.hertz_p0),
        );
        for forced in &s.forced {
            text += &format!(",{:.10e},{:.10e}", forced.force, forced.displacement);
        }
        match (&s.friction, friction) {
            (Some(f), _) => {
                for t in &f.tangential_force {
                    text += &format!(",{t:.10e}");
                }
                text += &format!(
                    ",{:.10e},{},{}",
                    f.normal_force, f.stick_nodes, f.slip_nodes
                );
            }
            (None, true) => text += &",".repeat(dim + 3),
            (None, false) => {}
        }
        text += &format!(
            ",{:.3},{}\n",
            s.seconds,
            (s.failed_checks.iter().map(|c| c.name()))
                .collect::<Vec<_>>()
                .join(";")
        );
    }
    text
}

impl CaseSummary {
    pub fn write(&self, path: &Path) -> Result<(), OutputError> {
        let text = serde_json::to_string_pretty(self).map_err(|source| OutputError::Json {
            path: path.to_owned(),
            source,
        })?;
        std::fs::write(path, text + "\n").map_err(|source| OutputError::Io {
            path: path.to_owned(),
            source,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(step: usize, paths: &[(&str, f64)]) -> StepRecord {
        StepRecord {
            step,
            load_factor: 1.0,
            path_factors: paths.iter().map(|&(n, f)| (n.to_string(), f)).collect(),
            status: ContactStatus::Converged,
            iterations: 3,
            force_primary: vec![0.0, -1.0],
            force_secondary: vec![0.0, 1.0],
            force_imbalance: 0.0,
            hertz_a: None,
            hertz_p0: None,
            forced: Vec::new(),
            seconds: 0.5,
            accurate: true,
            failed_checks: Vec::new(),
            friction: None,
        }
    }

    #[test]
    fn each_load_path_has_a_column_after_the_load_factor() {
        let steps = [
            record(1, &[("press", 0.5), ("shear", 0.0)]),
            record(2, &[("press", 1.0), ("shear", 1.0)]),
        ];
        let one = force_displacement_csv(&[("pair", &steps)]);
        let rows: Vec<&str> = one.lines().collect();
        assert!(rows[0].starts_with("step,load_factor,path_press,path_shear,status,"));
        assert!(rows[1].starts_with("1,1,0.5,0,converged,3,"), "{}", rows[1]);
        // Several pairs share the step, the load factor and the paths' factors.
        let two = force_displacement_csv(&[("a", &steps), ("b", &steps)]);
        let rows: Vec<&str> = two.lines().collect();
        assert!(
            rows[0].starts_with("step,load_factor,path_press,path_shear,a.status,"),
            "{}",
            rows[0]
        );
        assert!(rows[0].contains(",b.status,"));
        assert!(!rows[0].contains("b.path_"));
        assert!(rows[2].starts_with("2,1,1,1,converged,"), "{}", rows[2]);
        // Without a load path, the columns are as they were.
        let plain = force_displacement_csv(&[("pair", &[record(1, &[])])]);
        assert!(plain.starts_with("step,load_factor,status,iterations,contact_force_x,"));
        let json = serde_json::to_string(&record(1, &[])).unwrap();
        assert!(!json.contains("path_factors"));
    }
}
