//! `force_displacement.png`: the contact force and the contact radius of each load step
//! against the imposed approach, one curve per contact pair, the picture of
//! `force_displacement.csv`.
//!
//! plotters draws text with a font it is given at run time (its pure-Rust `ab_glyph` backend,
//! so no fontconfig or freetype): DejaVu Sans from Debian's `fonts-dejavu-core`, or the file
//! named by `INTERNODES_PLOT_FONT`. Without a readable font no PNG can be drawn; the caller
//! reports that as a warning, since the CSV already holds the same numbers.

use std::path::{Path, PathBuf};
use std::sync::{Mutex, PoisonError};

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::FontStyle;
use thiserror::Error;

use crate::contact::StepRecord;

/// The font used when `INTERNODES_PLOT_FONT` is not set (Debian package `fonts-dejavu-core`).
const DEFAULT_PLOT_FONT: &str = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";

/// The font family name the chart asks plotters for; [`register_font`] binds it to the file.
pub(crate) const FAMILY: &str = "sans-serif";

#[derive(Debug, Error)]
pub enum PlotError {
    #[error(
        "cannot read the plot font {path}: {source} (install Debian's fonts-dejavu-core, or set \
         INTERNODES_PLOT_FONT to a TrueType font file)"
    )]
    FontUnreadable {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("the plot font {path} is not a TrueType/OpenType font")]
    FontInvalid { path: PathBuf },
    #[error("cannot draw {path}: {message}")]
    Draw { path: PathBuf, message: String },
}

/// Width and height of the picture in pixels: two panels side by side.
pub const PLOT_SIZE: (u32, u32) = (1200, 540);

/// Draws the load steps of each pair of `curves` (its name and its steps) into the PNG file
/// `path`, two panels against the imposed approach, axes from 0, a dot per step and a line
/// between successive steps (none from the origin): the magnitude of the contact force on the
/// primary body, and the contact radius (half-width in 2D) of each step's Hertz fit; one curve
/// per pair, with a legend of the pairs' names when there are several. `approach` is the
/// imposed approach at load factor 1 (the largest difference between two bodies' prescribed
/// displacements); where no displacement is imposed (0: the bodies are loaded by forces) the x
/// axis is the load factor. In a force-controlled run (`[[body.force]]`) the x axis is the
/// displacement the first force-controlled group moved by, an output of each step. Along a
/// load path (`[load_path]`: the loads do not scale together) it is the step's number.
pub fn write_force_displacement_png(
    path: &Path,
    title: &str,
    curves: &[(&str, &[StepRecord])],
    approach: f64,
) -> Result<(), PlotError> {
    register_font()?;
    let draw_error = |e: &dyn std::fmt::Display| draw_error(path, e);
    let along_path =
        (curves.iter()).any(|(_, steps)| steps.iter().any(|s| !s.path_factors.is_empty()));
    let (scale, x_desc) = if along_path {
        (1.0, "load step (the case has a [load_path])".to_string())
    } else if approach > 0.0 {
        (
            approach,
            format!("imposed approach (load factor x {approach})"),
        )
    } else {
        (1.0, "load factor (no displacement imposed)".to_string())
    };
    // The first force-controlled group of any pair, and its displacement at each step.
    let forced = (curves.iter()).find_map(|(_, steps)| steps.first()?.forced.first());
    let x_desc = match forced {
        Some(f) => format!(
            "displacement |u{}| of '{}' on '{}' (force-controlled)",
            f.component, f.group, f.body
        ),
        None => x_desc,
    };
    let x = |k: usize, s: &StepRecord| {
        let moved = forced.and_then(|f| {
            (curves.iter())
                .filter_map(|(_, steps)| steps.get(k))
                .flat_map(|step| &step.forced)
                .find(|g| g.body == f.body && g.group == f.group && g.component == f.component)
        });
        match moved {
            Some(g) => g.displacement.abs(),
            None if along_path => s.step as f64,
            None => scale * s.load_factor,
        }
    };
    let norm = |f: &[f64]| f.iter().map(|c| c * c).sum::<f64>().sqrt();
    // Only solved points: a line from the origin to a single step would read as a linear law.
    let series = |value: &dyn Fn(&StepRecord) -> Option<f64>| -> Vec<Series> {
        (curves.iter())
            .map(|(name, steps)| {
                let points = (steps.iter().enumerate())
                    .filter_map(|(k, s)| value(s).map(|v| (x(k, s), v)))
                    .collect();
                (name.to_string(), points)
            })
            .collect()
    };
    let force = series(&|s| Some(norm(&s.force_primary)));
    let radius = series(&|s| s.hertz_a);

    let root = BitMapBackend::new(path, PLOT_SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(|e| draw_error(&e))?;
    let root = root
        .titled(title, (FAMILY, 22))
        .map_err(|e| draw_error(&e))?;
    let (left, right) = root.split_horizontally(PLOT_SIZE.0 / 2);
    let panels = [
        (&left, &force, "contact force |F| on the primary body", 0),
        (
            &right,
            &radius,
            "contact radius a (Hertz fit of the pressure)",
            1,
        ),
    ];
    for (area, series, y_desc, colour) in panels {
        draw_panel(path, area, series, (&x_desc, y_desc), colour)?;
    }
    root.present().map_err(|e| draw_error(&e))
}

/// A curve of a panel: its name (the pair's) and points.
type Series = (String, Vec<(f64, f64)>);

/// One panel: each of `series` as a line with a dot at each point (one point: the dot
/// alone), on axes from 0 described by `desc` (x, y), in colours of plotters' palette from
/// number `colour` on; several series get a legend of their names.
fn draw_panel(
    path: &Path,
    area: &DrawingArea<BitMapBackend, Shift>,
    series: &[Series],
    (x_desc, y_desc): (&str, &str),
    colour: usize,
) -> Result<(), PlotError> {
    let draw_error = |e: &dyn std::fmt::Display| draw_error(path, e);
    let points = || series.iter().flat_map(|(_, points)| points.iter());
    let x_range = padded_range(points().map(|p| p.0));
    let y_range = padded_range(points().map(|p| p.1));
    let mut chart = ChartBuilder::on(area)
        .margin(20)
        .x_label_area_size(50)
        .y_label_area_size(90)
        .build_cartesian_2d(x_range, y_range)
        .map_err(|e| draw_error(&e))?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .axis_desc_style((FAMILY, 16))
        .label_style((FAMILY, 14))
        .x_labels(6)
        .y_labels(8)
        .x_label_formatter(&|v| tick_label(*v))
        .y_label_formatter(&|v| tick_label(*v))
        .draw()
        .map_err(|e| draw_error(&e))?;
    for (k, (name, points)) in series.iter().enumerate() {
        let color = Palette99::pick(colour + 2 * k).to_rgba();
        chart
            .draw_series(LineSeries::new(
                points.iter().copied(),
                color.stroke_width(2),
            ))
            .map_err(|e| draw_error(&e))?
            .label(name.as_str())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
            });
        chart
            .draw_series(points.iter().map(|&p| Circle::new(p, 4, color.filled())))
            .map_err(|e| draw_error(&e))?;
    }
    if series.len() > 1 {
        chart
            .configure_series_labels()
            .label_font((FAMILY, 14))
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(|e| draw_error(&e))?;
    }
    Ok(())
}

fn draw_error(path: &Path, e: &dyn std::fmt::Display) -> PlotError {
    PlotError::Draw {
        path: path.to_owned(),
        message: e.to_string(),
    }
}

/// Plain decimals for moderate magnitudes, scientific notation otherwise (forces range from
/// micro-newtons to mega-newtons depending on the model's units).
pub(crate) fn tick_label(v: f64) -> String {
    if v == 0.0 || (1e-2..1e4).contains(&v.abs()) {
        format!("{v:.3}")
    } else {
        format!("{v:.2e}")
    }
}

/// `min(0, values) .. max(0, values)` widened by 5 % (and to a unit interval when all values
/// are 0), so the origin, where a force-displacement curve starts, is always in view.
fn padded_range(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) = values.fold((0.0f64, 0.0f64), |(lo, hi), v| (lo.min(v), hi.max(v)));
    let pad = if hi > lo { 0.05 * (hi - lo) } else { 1.0 };
    (lo - pad)..(hi + pad)
}

/// Binds [`FAMILY`] to the font file, once per process: plotters keeps the font for the rest of
/// the process and wants `'static` bytes, so the file's bytes are leaked (once, when valid).
pub(crate) fn register_font() -> Result<(), PlotError> {
    static REGISTERED: Mutex<bool> = Mutex::new(false);
    let mut registered = REGISTERED.lock().unwrap_or_else(PoisonError::into_inner);
    if *registered {
        return Ok(());
    }
    let path = std::env::var_os("INTERNODES_PLOT_FONT")
        .map_or_else(|| PathBuf::from(DEFAULT_PLOT_FONT), PathBuf::from);
    let bytes = std::fs::read(&path).map_err(|source| PlotError::FontUnreadable {
        path: path.clone(),
        source,
    })?;
    let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
    plotters::style::register_font(FAMILY, FontStyle::Normal, bytes)
        .map_err(|_| PlotError::FontInvalid { path })?;
    *registered = true;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_contain_the_origin_and_every_value() {
        let r = padded_range([0.5, 1.0].into_iter());
        assert!(r.start < 0.0 && r.end > 1.0);
        let r = padded_range([-3.0, -1.0].into_iter());
        assert!(r.start < -3.0 && r.end > 0.0);
        let r = padded_range(std::iter::empty());
        assert!(r.start < 0.0 && r.end > 0.0);
    }
}
