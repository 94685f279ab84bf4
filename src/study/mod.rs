//! `internodes study CASE --parameter NAME=V1,V2,...`: a mesh refinement study of a contact case
//! whose mesh is a gmsh `.geo`. The case is solved once per value of the gmsh parameter `NAME`
//! (each solve as `internodes solve` runs it, into its own folder), the contact quantities of
//! every level are read from its summary (`quantities`), the spacing of every level is measured
//! on its mesh (`measure`), and each quantity's discretization error is estimated from the
//! levels by the grid convergence index of Celik et al. (2008), on every triplet of consecutive
//! levels ([`gci`]). The results go into `study.json`, `study.csv`, `study.md` and `study.png`
//! ([`files`], `plot`); `docs/study.md` is the user's page.

pub mod files;
pub mod gci;
mod measure;
mod plot;
mod quantities;

pub use files::write_study_files;
pub use measure::{Spacing, contact_zone_spacing};
pub use quantities::{QUANTITIES, Quantity};

use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::time::Instant;

use serde::Serialize;
use thiserror::Error;

use crate::case::{Case, CaseError};
use crate::run::{RunError, RunOptions, solve_loaded_case};

use gci::{Estimate, estimate};

/// The gmsh parameter a study varies and its values, as `--parameter level=0,1,2` gives them.
#[derive(Debug, Clone, PartialEq)]
pub struct StudySpec {
    pub parameter: String,
    pub values: Vec<f64>,
}

impl FromStr for StudySpec {
    type Err = String;

    /// `NAME=V1,V2,...`: at least two distinct finite values.
    fn from_str(text: &str) -> Result<Self, String> {
        let (name, values) = text
            .split_once('=')
            .ok_or_else(|| format!("expected NAME=V1,V2,... (e.g. level=0,1,2), got '{text}'"))?;
        let values = (values.split(','))
            .map(|v| v.trim().parse::<f64>().map_err(|e| format!("'{v}': {e}")))
            .collect::<Result<Vec<f64>, String>>()?;
        let spec = StudySpec {
            parameter: name.trim().to_string(),
            values,
        };
        spec.check()?;
        Ok(spec)
    }
}

impl StudySpec {
    /// A name, and at least two distinct finite values.
    pub fn check(&self) -> Result<(), String> {
        if self.parameter.is_empty() {
            return Err("the parameter has no name".to_string());
        }
        if self.values.len() < 2 {
            return Err(format!(
                "a study needs at least two values of '{}', got {}",
                self.parameter,
                self.values.len()
            ));
        }
        if let Some(v) = self.values.iter().find(|v| !v.is_finite()) {
            return Err(format!("the value {v} is not finite"));
        }
        for (k, v) in self.values.iter().enumerate() {
            if self.values[..k].contains(v) {
                return Err(format!("the value {v} is given twice"));
            }
        }
        Ok(())
    }

    /// The folder of the level with `value` inside the study's folder: `level_2`, `h_c_0.01`.
    pub fn folder_name(&self, value: f64) -> String {
        format!("{}_{value}", self.parameter)
    }
}

/// Command-line settings of a study.
#[derive(Debug, Clone, Default)]
pub struct StudyOptions {
    /// The study's folder; default `<the case's output>/study`.
    pub output: Option<PathBuf>,
    /// Progress messages off (errors and warnings only).
    pub quiet: bool,
    /// Stops the level being solved, and with it the study ([`RunOptions::cancel`]).
    pub cancel: crate::cancel::Cancel,
}

#[derive(Debug, Error)]
pub enum StudyError {
    #[error(transparent)]
    Case(#[from] CaseError),
    #[error("case file {path}: {message}")]
    Invalid { path: PathBuf, message: String },
    #[error("study level {parameter} = {value}: {source}")]
    Level {
        parameter: String,
        value: f64,
        source: Box<RunError>,
    },
    #[error("cannot write {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// One level of a study: its mesh, its solve, and the quantities read from its summary.
#[derive(Debug, Clone, Serialize)]
pub struct Level {
    /// The parameter's value.
    pub value: f64,
    /// Its result folder, relative to the study's.
    pub folder: String,
    /// The measured spacing ([`contact_zone_spacing`]).
    pub spacing: Spacing,
    /// Degrees of freedom of all bodies.
    pub num_dofs: usize,
    /// The body that carried the multiplier.
    pub primary: String,
    /// The contact status, and `internodes solve`'s exit status for this level.
    pub status: String,
    pub exit_status: u8,
    /// Wall-clock seconds of the level (meshing, solving, writing).
    pub seconds: f64,
    /// Each of [`QUANTITIES`] by key (`None` where the summary has none, e.g. no Hertz fit).
    pub quantities: Vec<(String, Option<f64>)>,
}

/// One quantity's estimate, or why there is none.
#[derive(Debug, Clone, Serialize)]
pub struct QuantityEstimate {
    pub key: String,
    pub name: String,
    /// Where in `summary.json` its value is read.
    pub source: String,
    pub estimate: Option<Estimate>,
    pub error: Option<String>,
}

/// A finished study: what `study.json` holds.
#[derive(Debug, Clone, Serialize)]
pub struct Study {
    pub case: String,
    pub parameter: String,
    /// What `h` is.
    pub spacing: String,
    /// In the order given.
    pub levels: Vec<Level>,
    pub estimates: Vec<QuantityEstimate>,
    /// The worst level's exit status: 2 if a level was not solved, else 3 if one failed its
    /// accuracy report, else 0. The flags of the estimates do not change it.
    pub exit_status: u8,
    /// Total wall-clock seconds.
    pub seconds: f64,
    /// The study's folder (not in `study.json`, which may be copied elsewhere).
    #[serde(skip)]
    pub folder: PathBuf,
}

/// Solves `case` at every value of `spec` into `<output>/<parameter>_<value>/`, estimates each
/// quantity's discretization error and writes the study's files into the output folder.
/// Every value's case is checked before anything is solved, and what an earlier study left in
/// the folder removed ([`files::remove_earlier_study`]).
pub fn run_study(
    case: &Case,
    spec: &StudySpec,
    options: &StudyOptions,
) -> Result<Study, StudyError> {
    let started = Instant::now();
    let invalid = |message: String| StudyError::Invalid {
        path: case.path.clone(),
        message,
    };
    spec.check()
        .map_err(|m| invalid(format!("study parameter: {m}")))?;
    if case.contacts.len() != 1 {
        return Err(invalid(match case.contacts.len() {
            0 => "a refinement study measures contact quantities, and the case has no [contact] \
                  table"
                .to_string(),
            n => format!(
                "a refinement study measures the quantities of one contact pair, and the case \
                 has {n}: study a case with one [contact] table"
            ),
        }));
    }
    let cases = (spec.values.iter())
        .map(|&v| case.with_geo_parameter(&spec.parameter, v))
        .collect::<Result<Vec<Case>, CaseError>>()?;
    let folder = (options.output.clone())
        .or_else(|| case.output.as_ref().map(|o| o.join("study")))
        .ok_or_else(|| {
            invalid(
                "no output folder: give the `output` key in the case file, or the --output flag \
                 of `internodes study` (output= in Python)"
                    .to_string(),
            )
        })?;
    for removed in files::remove_earlier_study(&folder)? {
        log::info!(
            "study: removed {}, a level of an earlier study (only results of a run in it)",
            removed.display()
        );
    }
    let mut levels = Vec::new();
    for (level_case, &value) in cases.into_iter().zip(&spec.values) {
        levels.push(solve_level(level_case, spec, value, &folder, options)?);
    }
    let study = finish(case, spec, levels, folder, started.elapsed().as_secs_f64());
    write_study_files(&study)?;
    Ok(study)
}

/// One level: solved into its folder, measured, its quantities read.
fn solve_level(
    case: Case,
    spec: &StudySpec,
    value: f64,
    folder: &Path,
    options: &StudyOptions,
) -> Result<Level, StudyError> {
    let started = Instant::now();
    let name = spec.folder_name(value);
    log::debug!(
        "study: {} = {value} into {}",
        spec.parameter,
        folder.join(&name).display()
    );
    let run_options = RunOptions {
        output: Some(folder.join(&name)),
        export_matrices: false,
        quiet: options.quiet,
        cancel: options.cancel.clone(),
    };
    let command = format!(
        "internodes study {} ({} = {value})",
        case.path.display(),
        spec.parameter
    );
    let contact = case.contacts.first().cloned();
    let run =
        solve_loaded_case(case, &run_options, "internodes study", &command).map_err(|source| {
            StudyError::Level {
                parameter: spec.parameter.clone(),
                value,
                source: Box::new(source),
            }
        })?;
    let summary = &run.report.summary;
    let contact_summary = summary.contact.as_ref();
    let primary = contact_summary.map_or_else(String::new, |c| c.primary.clone());
    let surfaces = contact.map(|c| (c.bodies, c.surfaces));
    let spacing = contact_zone_spacing(&run.mesh, &run.solution, &primary, surfaces.as_ref());
    let verdict = summary.verdict();
    let level = Level {
        value,
        folder: name,
        spacing,
        num_dofs: summary.bodies.iter().map(|b| b.num_dofs).sum(),
        primary,
        status: contact_summary
            .map_or("solved", |c| c.status.name())
            .to_string(),
        exit_status: verdict.exit_status(),
        seconds: started.elapsed().as_secs_f64(),
        quantities: (QUANTITIES.iter())
            .map(|q| (q.key.to_string(), (q.read)(summary)))
            .collect(),
    };
    log::info!(target: LOG_TARGET, "{}", level.line(&spec.parameter));
    Ok(level)
}

/// The log target of the study's own lines: `internodes study` shows only these (and
/// warnings and progress lines) at its default level, each level's solve log with `-v`.
pub const LOG_TARGET: &str = "internodes::study";

impl Level {
    /// The level's line of the log: status, exit status, size, force and time.
    fn line(&self, parameter: &str) -> String {
        let force = (self.quantities.iter())
            .find(|(key, _)| key == "force")
            .and_then(|(_, value)| *value)
            .map_or_else(|| "no force".to_string(), |f| format!("force {f:.4e}"));
        format!(
            "study: {parameter} = {}: {} (exit {}); h {:.3e}, {} DOFs, {force}; {:.1} s",
            self.value, self.status, self.exit_status, self.spacing.h, self.num_dofs, self.seconds
        )
    }
}

/// The estimates of every quantity and the study's exit status.
fn finish(
    case: &Case,
    spec: &StudySpec,
    levels: Vec<Level>,
    folder: PathBuf,
    seconds: f64,
) -> Study {
    let estimates = (QUANTITIES.iter().enumerate())
        .map(|(k, q)| {
            let pairs: Option<Vec<(f64, f64)>> = (levels.iter())
                .map(|l| l.quantities[k].1.map(|v| (l.spacing.h, v)))
                .collect();
            let result = match pairs {
                Some(pairs) => estimate(&pairs).map_err(|e| e.to_string()),
                None => Err("a level has no value (see study.csv)".to_string()),
            };
            QuantityEstimate {
                key: q.key.to_string(),
                name: q.name.to_string(),
                source: q.source.to_string(),
                error: result.as_ref().err().cloned(),
                estimate: result.ok(),
            }
        })
        .collect();
    // Not solved (2) outranks inaccurate (3).
    let statuses: Vec<u8> = levels.iter().map(|l| l.exit_status).collect();
    let exit_status = [2, 3]
        .into_iter()
        .find(|code| statuses.contains(code))
        .unwrap_or(0);
    Study {
        case: case.path.display().to_string(),
        parameter: spec.parameter.clone(),
        spacing: measure::SPACING_DEFINITION.to_string(),
        levels,
        estimates,
        exit_status,
        seconds,
        folder,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parameters_parse_and_name_their_folders() {
        let spec: StudySpec = "h_c = 0.03, 0.015,0.0075".parse().unwrap();
        assert_eq!(spec.parameter, "h_c");
        assert_eq!(spec.values, vec![0.03, 0.015, 0.0075]);
        assert_eq!(spec.folder_name(0.015), "h_c_0.015");
        let level: StudySpec = "level=-1,0".parse().unwrap();
        assert_eq!(level.folder_name(-1.0), "level_-1");
        for bad in [
            "level",
            "=0,1",
            "level=0",
            "level=1,1",
            "level=0,inf",
            "level=0,a",
        ] {
            assert!(bad.parse::<StudySpec>().is_err(), "{bad}");
        }
    }
}
