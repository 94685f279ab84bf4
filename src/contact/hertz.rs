//! Hertz estimates from a computed pressure field.
//!
//! Hertz's pressure is `p(r) = p0 sqrt(1 - r^2 / a^2)`, so `p^2 = p0^2 - (p0^2 / a^2) r^2` is
//! linear in `r^2`: a least-squares line through `(r_i^2, p_i^2)` over the active nodes in
//! compression gives `p0^2` (intercept) and `-p0^2 / a^2` (slope) (`docs/method.md` 5). `r` is
//! the distance from the pressure-weighted centroid, measured in the plane normal to the mean
//! normal of the loaded nodes (in 2D, along the surface line).
//!
//! `p_i` is the mean pressure of node `i` (its normal contact force over its area), the
//! recovery that FE contact codes and our dolfinx reference use; with the lumped interface mass
//! it is the nodal pressure itself.

use super::ContactSurface;
use super::solution::{HertzFit, SurfaceFields};

/// The fit over the active nodes of `surface` with positive mean pressure; `None` with fewer than three
/// such nodes, a profile that does not decrease outward, or a fitted radius more than twice the
/// extent of the loaded nodes.
pub fn fit(surface: &ContactSurface, fields: &SurfaceFields) -> Option<HertzFit> {
    let loaded: Vec<usize> = (0..surface.len())
        .filter(|&i| fields.active[i] && fields.mean_pressure[i] > 0.0)
        .collect();
    if loaded.len() < 3 {
        return None;
    }
    let pressure = &fields.mean_pressure;
    let total: f64 = loaded.iter().map(|&i| pressure[i]).sum();
    let mut center = [0.0; 3];
    let mut normal = [0.0; 3];
    for &i in &loaded {
        for k in 0..3 {
            center[k] += pressure[i] * surface.coords[i][k] / total;
            normal[k] += pressure[i] * surface.normals[i][k];
        }
    }
    let norm = (normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]).sqrt();
    normal.iter_mut().for_each(|v| *v /= norm);
    let points: Vec<(f64, f64)> = loaded
        .iter()
        .map(|&i| {
            let d: [f64; 3] = std::array::from_fn(|k| surface.coords[i][k] - center[k]);
            let along = d[0] * normal[0] + d[1] * normal[1] + d[2] * normal[2];
            let r2 = d.iter().map(|v| v * v).sum::<f64>() - along * along;
            (r2, pressure[i] * pressure[i])
        })
        .collect();
    let n = points.len() as f64;
    let (mean_x, mean_y) = (
        points.iter().map(|p| p.0).sum::<f64>() / n,
        points.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxx: f64 = points.iter().map(|p| (p.0 - mean_x).powi(2)).sum();
    let sxy: f64 = points.iter().map(|p| (p.0 - mean_x) * (p.1 - mean_y)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let slope = sxy / sxx;
    let intercept = mean_y - slope * mean_x;
    if slope >= 0.0 || intercept <= 0.0 {
        return None;
    }
    // A fitted radius far beyond the loaded nodes means the profile is not an ellipse (a flat
    // punch or a uniform pressure): no Hertz estimate then.
    let a = (-intercept / slope).sqrt();
    let extent = points.iter().map(|p| p.0).fold(0.0, f64::max).sqrt();
    if a > 2.0 * extent {
        return None;
    }
    Some(HertzFit {
        a,
        p0: intercept.sqrt(),
        center,
    })
}
