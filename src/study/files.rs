//! The study's files: `study.json` (everything), `study.csv` (one row per level), `study.md`
//! (the two tables a publication reports) and `study.png` (`super::plot`).

use std::path::{Path, PathBuf};

use super::gci::{Estimate, Flag, ORDER_AGREEMENT, SAFETY_FACTOR};
use super::{QUANTITIES, Study, StudyError};
use crate::output::holds_only_run_outputs;

/// The files a study writes into its folder, beside its levels' folders.
const STUDY_FILES: [&str; 4] = ["study.json", "study.csv", "study.md", "study.png"];

/// Removes what an earlier study left in `dir` before a new one starts, as `internodes solve`
/// removes the results of earlier runs from its output folder: the study's files, and every
/// level folder, a folder named `NAME_VALUE` (a level's name for any parameter, as an earlier
/// study may have varied another) that holds nothing but what a run writes. Without this a
/// study of fewer levels, or of another parameter, left the earlier levels beside its own, and
/// a study that failed left the earlier `study.json` describing them. A folder holding anything
/// else is the user's and stays. Returns the level folders removed, for the caller to say so.
pub fn remove_earlier_study(dir: &Path) -> Result<Vec<PathBuf>, StudyError> {
    let io = |path: &Path| {
        let path = path.to_owned();
        move |source| StudyError::Io { path, source }
    };
    if !dir.is_dir() {
        return Ok(Vec::new());
    }
    for name in STUDY_FILES {
        let path = dir.join(name);
        match std::fs::remove_file(&path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound && !path.is_dir() => {
                return Err(io(&path)(e));
            }
            _ => {}
        }
    }
    let mut removed = Vec::new();
    let entries = std::fs::read_dir(dir).map_err(io(dir))?;
    for entry in entries {
        let path = entry.map_err(io(dir))?.path();
        let name = path.file_name().unwrap_or_default().to_string_lossy();
        let level_name = name.rsplit_once('_').is_some_and(|(parameter, value)| {
            !parameter.is_empty() && value.parse::<f64>().is_ok()
        });
        let ours =
            level_name && path.is_dir() && holds_only_run_outputs(&path).map_err(io(&path))?;
        if ours {
            std::fs::remove_dir_all(&path).map_err(io(&path))?;
            removed.push(path);
        }
    }
    removed.sort();
    Ok(removed)
}

/// Writes the four files into the study's folder. The plot only pictures the tables: a plot
/// that cannot be drawn (no font) is a warning.
pub fn write_study_files(study: &Study) -> Result<(), StudyError> {
    let dir = &study.folder;
    let json = serde_json::to_string_pretty(study).expect("a study serializes");
    write(&dir.join("study.json"), &(json + "\n"))?;
    write(&dir.join("study.csv"), &csv(study))?;
    write(&dir.join("study.md"), &markdown(study))?;
    let png = dir.join("study.png");
    if let Err(e) = super::plot::write_study_png(&png, study) {
        log::warn!("{} not written: {e}", png.display());
    }
    Ok(())
}

fn write(path: &Path, text: &str) -> Result<(), StudyError> {
    std::fs::write(path, text).map_err(|source| StudyError::Io {
        path: path.to_owned(),
        source,
    })
}

/// One row per level, in the order given: the parameter's value, the spacing, the sizes, the
/// outcome and every quantity (empty where the level has none).
pub fn csv(study: &Study) -> String {
    let mut text = format!(
        "{},h,facets,contact_zone,dofs,primary,status,exit_status,seconds",
        study.parameter
    );
    for q in &QUANTITIES {
        text += &format!(",{}", q.key);
    }
    text += "\n";
    for l in &study.levels {
        text += &format!(
            "{},{:.10e},{},{},{},{},{},{},{:.3}",
            l.value,
            l.spacing.h,
            l.spacing.facets,
            l.spacing.contact_zone,
            l.num_dofs,
            l.primary,
            l.status,
            l.exit_status,
            l.seconds
        );
        for (_, value) in &l.quantities {
            text += &value.map_or(",".to_string(), |v| format!(",{v:.10e}"));
        }
        text += "\n";
    }
    text
}

/// The levels' table and the estimates' table, with what each column is.
pub fn markdown(study: &Study) -> String {
    let mut lines = vec![
        format!("# Refinement study of {}", study.case),
        String::new(),
        format!(
            "Parameter `{}`; h: {}. Total {:.1} s; exit status {}.",
            study.parameter, study.spacing, study.seconds, study.exit_status
        ),
        String::new(),
    ];
    let header: Vec<&str> = QUANTITIES.iter().map(|q| q.name).collect();
    lines.push(format!(
        "| {} | h | DOFs | primary | status | {} | seconds |",
        study.parameter,
        header.join(" | ")
    ));
    lines.push(format!("|{}", "---|".repeat(6 + QUANTITIES.len())));
    for l in &study.levels {
        let values: Vec<String> = (l.quantities.iter())
            .map(|(_, v)| v.map_or("-".to_string(), significant))
            .collect();
        lines.push(format!(
            "| {} | {} | {} | {} | {} | {} | {:.1} |",
            l.value,
            significant(l.spacing.h),
            l.num_dofs,
            l.primary,
            l.status,
            values.join(" | "),
            l.seconds
        ));
    }
    lines.push(String::new());
    lines.push(match study.levels.len() {
        2 => "Two levels only: their difference (e_a21 = |phi1 - phi2| / |phi1|); an observed \
              order, an extrapolation and a GCI need three levels."
            .to_string(),
        n => format!(
            "Estimates of the three finest levels (Celik et al. 2008; GCI_fine with Fs = \
             {SAFETY_FACTOR}, relative to phi1; band: phi1 +- GCI_fine |phi1|). Every triplet of \
             consecutive levels gives its order (finest first); a quantity is asymptotic only \
             when no triplet is flagged and their orders agree within a factor {:.2}.{}",
            ORDER_AGREEMENT,
            match n {
                3 =>
                    " One triplet: its order is observed, not confirmed; a fourth level would \
                      confirm it.",
                _ => "",
            }
        ),
    });
    lines.push(String::new());
    lines.push(
        "| quantity | phi1 (finest) | phi1 - phi2 | e_a21 | p | extrapolated | GCI_fine | band \
         | p of each triplet | flags |"
            .to_string(),
    );
    lines.push("|---|---|---|---|---|---|---|---|---|---|".to_string());
    for q in &study.estimates {
        lines.push(match (&q.estimate, &q.error) {
            (Some(e), _) => estimate_row(&q.name, e),
            (None, error) => format!(
                "| {} | - | - | - | - | - | - | - | - | {} |",
                q.name,
                error.as_deref().unwrap_or("")
            ),
        });
    }
    lines.push(String::new());
    if study.levels.len() > 3 {
        lines.extend(triplet_table(study));
    }
    lines.join("\n")
}

/// The table of every triplet of every quantity, each named by its levels' values.
fn triplet_table(study: &Study) -> Vec<String> {
    let value_at = |h: f64| {
        (study.levels.iter())
            .find(|l| l.spacing.h == h)
            .map_or("?".to_string(), |l| l.value.to_string())
    };
    let mut lines = vec![
        format!(
            "Each triplet of consecutive levels (`{}` values, finest first):",
            study.parameter
        ),
        String::new(),
        "| quantity | levels | p | extrapolated | GCI_fine | flags |".to_string(),
        "|---|---|---|---|---|---|".to_string(),
    ];
    for q in &study.estimates {
        for t in q.estimate.iter().flat_map(|e| &e.triplets) {
            let levels: Vec<String> = t.h.iter().map(|&h| value_at(h)).collect();
            lines.push(format!(
                "| {} | {} | {} | {} | {} | {} |",
                q.name,
                levels.join(", "),
                order(t.order),
                t.extrapolated.map_or("-".to_string(), significant),
                percent(t.gci_fine),
                flags(&t.flags, "none")
            ));
        }
    }
    lines.push(String::new());
    lines
}

/// One row of the estimates' table.
fn estimate_row(name: &str, e: &Estimate) -> String {
    let band = e.gci_fine.map_or("-".to_string(), |g| {
        let half = g * e.phi[0].abs();
        format!(
            "[{}, {}]",
            significant(e.phi[0] - half),
            significant(e.phi[0] + half)
        )
    });
    let orders: Vec<String> = e.triplets.iter().map(|t| order(t.order)).collect();
    format!(
        "| {name} | {} | {} | {} | {} | {} | {} | {band} | {} | {} |",
        significant(e.phi[0]),
        significant(e.difference),
        percent(Some(e.relative_difference)),
        order(e.order),
        e.extrapolated.map_or("-".to_string(), significant),
        percent(e.gci_fine),
        if orders.is_empty() {
            "-".to_string()
        } else {
            orders.join(", ")
        },
        flags(&e.flags, "none (asymptotic)")
    )
}

fn order(p: Option<f64>) -> String {
    p.map_or("-".to_string(), |p| format!("{p:.2}"))
}

fn percent(v: Option<f64>) -> String {
    v.map_or("-".to_string(), |v| format!("{:.3}%", 100.0 * v))
}

/// The flags' descriptions, or `none` when there are none.
fn flags(flags: &[Flag], none: &str) -> String {
    match flags {
        [] => none.to_string(),
        _ => (flags.iter().map(|f| f.describe()))
            .collect::<Vec<_>>()
            .join("; "),
    }
}

/// Five significant digits, scientific notation outside [1e-3, 1e5).
fn significant(v: f64) -> String {
    if !v.is_finite() {
        return format!("{v}");
    }
    if v == 0.0 {
        return "0".to_string();
    }
    if (1e-3..1e5).contains(&v.abs()) {
        let decimals = (4 - v.abs().log10().floor() as i32).max(0) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.4e}")
    }
}

#[cfg(test)]
mod tests {
    use super::significant;

    #[test]
    fn five_significant_digits() {
        assert_eq!(significant(5.29312), "5.2931");
        assert_eq!(significant(0.0123456), "0.012346");
        assert_eq!(significant(123456.0), "1.2346e5");
        assert_eq!(significant(-0.5), "-0.50000");
    }
}
