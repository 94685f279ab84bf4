//! `study.png`: each quantity against the spacing h, one panel per quantity, with the
//! Richardson extrapolation at h = 0 and the band `phi1 +- GCI_fine |phi1|` at the finest level.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::gci::Estimate;
use super::{QUANTITIES, Study};
use crate::output::PlotError;
use crate::output::plot::{FAMILY, register_font, tick_label};

/// Width and height in pixels: two by two panels.
const SIZE: (u32, u32) = (1000, 760);

/// Draws the study's quantities against h into the PNG file `path`.
pub fn write_study_png(path: &Path, study: &Study) -> Result<(), PlotError> {
    register_font()?;
    let draw_error = |e: &dyn std::fmt::Display| PlotError::Draw {
        path: path.to_owned(),
        message: e.to_string(),
    };
    let root = BitMapBackend::new(path, SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(|e| draw_error(&e))?;
    let title = format!("refinement study of {} ({})", study.case, study.parameter);
    let root = root
        .titled(&title, (FAMILY, 22))
        .map_err(|e| draw_error(&e))?;
    for (k, area) in root
        .split_evenly((2, 2))
        .iter()
        .enumerate()
        .take(QUANTITIES.len())
    {
        let mut points: Vec<(f64, f64)> = (study.levels.iter())
            .filter_map(|l| l.quantities[k].1.map(|v| (l.spacing.h, v)))
            .filter(|(h, v)| h.is_finite() && v.is_finite())
            .collect();
        points.sort_by(|a, b| a.0.total_cmp(&b.0));
        let estimate = study.estimates[k].estimate.as_ref();
        draw_panel(area, QUANTITIES[k].name, &points, estimate).map_err(|e| draw_error(&e))?;
    }
    root.present().map_err(|e| draw_error(&e))
}

/// A y tick label with enough decimals to tell apart ticks over a range `width` (a quantity
/// converging to 4 digits spans a tiny range).
fn y_tick(v: f64, width: f64) -> String {
    let magnitude = v.abs().max(width);
    if !(1e-3..1e5).contains(&magnitude) {
        return tick_label(v);
    }
    let decimals = (2 - width.log10().floor() as i32).clamp(0, 10) as usize;
    format!("{v:.decimals$}")
}

/// One panel: the levels as a line with dots, the extrapolated value at h = 0 as a cross and the
/// finest level's GCI band as a bar.
fn draw_panel(
    area: &DrawingArea<BitMapBackend, Shift>,
    name: &str,
    points: &[(f64, f64)],
    estimate: Option<&Estimate>,
) -> Result<(), Box<dyn std::error::Error>> {
    let extrapolated = estimate.and_then(|e| e.extrapolated.map(|x| (0.0, x)));
    let band = estimate.and_then(|e| {
        let half = e.gci_fine? * e.phi[0].abs();
        Some((e.h[0], e.phi[0] - half, e.phi[0] + half))
    });
    let ys = (points.iter().map(|p| p.1))
        .chain(extrapolated.map(|p| p.1))
        .chain(band.into_iter().flat_map(|(_, lo, hi)| [lo, hi]));
    let (lo, hi) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), y| {
        (lo.min(y), hi.max(y))
    });
    let pad = if hi > lo {
        0.08 * (hi - lo)
    } else {
        0.05 * lo.abs().max(1e-300)
    };
    let (lo, hi) = if lo.is_finite() {
        (lo - pad, hi + pad)
    } else {
        (0.0, 1.0)
    };
    let h_max = points
        .iter()
        .map(|p| p.0)
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let mut chart = ChartBuilder::on(area)
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(85)
        .caption(name, (FAMILY, 18))
        .build_cartesian_2d(0.0..1.08 * h_max, lo..hi)?;
    chart
        .configure_mesh()
        // No minor grid lines: they add nothing to four points and triple the file's size.
        .light_line_style(WHITE)
        .x_desc("spacing h")
        .axis_desc_style((FAMILY, 15))
        .label_style((FAMILY, 13))
        .x_labels(6)
        .y_labels(7)
        .x_label_formatter(&|v| tick_label(*v))
        .y_label_formatter(&|v| y_tick(*v, hi - lo))
        .draw()?;
    let blue = Palette99::pick(0).to_rgba();
    let red = Palette99::pick(1).to_rgba();
    chart.draw_series(LineSeries::new(
        points.iter().copied(),
        blue.stroke_width(2),
    ))?;
    chart.draw_series(points.iter().map(|&p| Circle::new(p, 4, blue.filled())))?;
    if let Some(x) = extrapolated {
        chart.draw_series(std::iter::once(Cross::new(x, 7, red.stroke_width(2))))?;
    }
    if let Some((h, lo, hi)) = band {
        let cap = 0.015 * h_max;
        let bar = [
            vec![(h, lo), (h, hi)],
            vec![(h - cap, lo), (h + cap, lo)],
            vec![(h - cap, hi), (h + cap, hi)],
        ];
        chart.draw_series(
            bar.into_iter()
                .map(|p| PathElement::new(p, red.stroke_width(2))),
        )?;
    }
    Ok(())
}
