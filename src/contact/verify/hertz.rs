//! Hertz estimates from a computed pressure field.
//!
//! Hertz's pressure is `p(r) = p0 sqrt(1 - r^2 / a^2)`, so `p^2 = p0^2 - (p0^2 / a^2) r^2`,
//! with `r` the distance from the centre `c` of the zone, in the plane normal to the mean normal
//! of the loaded nodes (in 2D, along the surface line). Written in in-plane coordinates `x`,
//! `p^2 = A + B . x - s |x|^2` is linear in `(A, B, s)`: a least-squares fit over the active
//! nodes in compression gives the centre `c = B / (2 s)`, `p0^2 = A + s |c|^2` and
//! `a^2 = p0^2 / s` (`docs/method.md` 5). The centre is fitted, not taken as the
//! pressure-weighted centroid: on a half or quarter model (a symmetry plane through the centre)
//! the loaded nodes lie on one side of the centre, and the centroid's distances gave a 3D
//! quarter ball a contact radius 32% short.
//!
//! `p_i` is the mean pressure of node `i` (its normal contact force over its area), the
//! recovery that FE contact codes and our dolfinx reference use; with the lumped interface mass
//! it is the nodal pressure itself.

use nalgebra::{DMatrix, DVector, SVD};

use crate::contact::geometry::surface::ContactSurface;
use crate::contact::solution::{HertzFit, SurfaceFields};

/// The SVD's sweeps at most: a design of a few columns converges in a few dozen.
const SVD_ITERATIONS: usize = 1000;

/// The fit over the active nodes of `surface` with positive mean pressure; `None` with fewer
/// nodes than unknowns (plus one), a profile that does not decrease outward, or a fitted radius
/// more than twice the extent of the loaded nodes.
pub fn fit(surface: &ContactSurface, fields: &SurfaceFields) -> Option<HertzFit> {
    let dim = surface.dim;
    let loaded: Vec<usize> = (0..surface.len())
        .filter(|&i| fields.active[i] && fields.mean_pressure[i] > 0.0)
        .collect();
    // Unknowns: A, the dim - 1 components of B, s.
    let unknowns = dim + 1;
    if loaded.len() < unknowns + 1 {
        return None;
    }
    // The fit is the same for any unit of pressure: in units of the largest, so that neither
    // the weights nor the squares underflow (pressures of 1e-298 made the mean normal 0 / 0, on
    // which the SVD below never returned).
    let scale = loaded
        .iter()
        .map(|&i| fields.mean_pressure[i])
        .fold(0.0, f64::max);
    let pressure: Vec<f64> = fields.mean_pressure.iter().map(|p| p / scale).collect();
    let total: f64 = loaded.iter().map(|&i| pressure[i]).sum();
    let mut centroid = [0.0; 3];
    let mut normal = [0.0; 3];
    for &i in &loaded {
        for k in 0..3 {
            centroid[k] += pressure[i] * surface.coords[i][k] / total;
            normal[k] += pressure[i] * surface.normals[i][k];
        }
    }
    let norm = (normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]).sqrt();
    normal.iter_mut().for_each(|v| *v /= norm);
    let tangents = in_plane_axes(normal, dim);
    // In-plane coordinates from the centroid (for the conditioning of the fit).
    let coordinates: Vec<Vec<f64>> = (loaded.iter())
        .map(|&i| {
            let d: [f64; 3] = std::array::from_fn(|k| surface.coords[i][k] - centroid[k]);
            tangents.iter().map(|t| dot(&d, t)).collect()
        })
        .collect();
    let rows = loaded.len();
    let design = DMatrix::from_fn(rows, unknowns, |r, c| {
        let x = &coordinates[r];
        match c {
            0 => 1.0,
            c if c < unknowns - 1 => x[c - 1],
            _ => -x.iter().map(|v| v * v).sum::<f64>(),
        }
    });
    let target = DVector::from_iterator(rows, loaded.iter().map(|&i| pressure[i].powi(2)));
    // Bounded, as `svd()` is not: a design that is not finite ends here with no fit.
    let svd = SVD::try_new(design, true, true, f64::EPSILON, SVD_ITERATIONS)?;
    let solution = svd.solve(&target, 1e-12).ok()?;
    let slope = solution[unknowns - 1];
    if slope <= 0.0 {
        return None;
    }
    let centre_in_plane: Vec<f64> = (1..unknowns - 1)
        .map(|c| solution[c] / (2.0 * slope))
        .collect();
    let p0_squared = solution[0] + slope * centre_in_plane.iter().map(|v| v * v).sum::<f64>();
    if p0_squared <= 0.0 {
        return None;
    }
    let mut center = centroid;
    for (t, c) in tangents.iter().zip(&centre_in_plane) {
        (0..3).for_each(|k| center[k] += c * t[k]);
    }
    let points: Vec<f64> = (coordinates.iter())
        .map(|x| {
            (x.iter().zip(&centre_in_plane))
                .map(|(v, c)| (v - c).powi(2))
                .sum::<f64>()
        })
        .collect();
    // A fitted radius far beyond the loaded nodes means the profile is not an ellipse (a flat
    // punch or a uniform pressure): no Hertz estimate then.
    let a = (p0_squared / slope).sqrt();
    let extent = points.iter().copied().fold(0.0, f64::max).sqrt();
    if a > 2.0 * extent {
        return None;
    }
    Some(HertzFit {
        a,
        p0: p0_squared.sqrt() * scale,
        center,
    })
}

/// Orthonormal axes of the plane normal to `normal` (unit): one in 2D (the surface line,
/// `normal` rotated a quarter turn), two in 3D.
fn in_plane_axes(normal: [f64; 3], dim: usize) -> Vec<[f64; 3]> {
    if dim == 2 {
        return vec![[-normal[1], normal[0], 0.0]];
    }
    // The coordinate axis least aligned with the normal, made orthogonal to it.
    let k = (0..3)
        .min_by(|&a, &b| normal[a].abs().total_cmp(&normal[b].abs()))
        .unwrap_or(0);
    let mut first = [0.0; 3];
    first[k] = 1.0;
    let along = dot(&first, &normal);
    (0..3).for_each(|j| first[j] -= along * normal[j]);
    let length = dot(&first, &first).sqrt();
    first.iter_mut().for_each(|v| *v /= length);
    let second = [
        normal[1] * first[2] - normal[2] * first[1],
        normal[2] * first[0] - normal[0] * first[2],
        normal[0] * first[1] - normal[1] * first[0],
    ];
    vec![first, second]
}

fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hertz's pressure about the origin on the flat top of the block of
    /// `tests/fixtures/hemisphere_on_block_hertz.msh`, on the nodes where `keep` holds: the fit must
    /// give back `a`, `p0` and the centre, `p^2` being exactly its paraboloid.
    fn fitted(keep: impl Fn(&[f64; 3]) -> bool) -> HertzFit {
        fitted_at(30.0, keep)
    }

    /// [`fitted`] with the peak pressure `p0`.
    fn fitted_at(p0: f64, keep: impl Fn(&[f64; 3]) -> bool) -> HertzFit {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/fixtures/hemisphere_on_block_hertz.msh");
        let mesh = crate::mesh::read_msh(&path).unwrap();
        let surface = ContactSurface::new(mesh.body("block").unwrap(), "block_contact").unwrap();
        let a = 0.1;
        let pressure: Vec<f64> = (surface.coords.iter())
            .map(|x| {
                let r2 = x[0] * x[0] + x[1] * x[1];
                if r2 < a * a && keep(x) {
                    p0 * (1.0 - r2 / (a * a)).sqrt()
                } else {
                    0.0
                }
            })
            .collect();
        let fields = SurfaceFields {
            active: pressure.iter().map(|&p| p > 0.0).collect(),
            mean_pressure: pressure,
            ..SurfaceFields::default()
        };
        fit(&surface, &fields).expect("enough loaded nodes")
    }

    #[test]
    fn the_centre_is_fitted_so_that_a_quarter_model_gives_the_whole_contact() {
        for (what, fit) in [
            ("whole", fitted(|_| true)),
            ("quarter", fitted(|x| x[0] >= 0.0 && x[1] >= 0.0)),
            ("half", fitted(|x| x[0] >= 0.0)),
        ] {
            assert!((fit.a - 0.1).abs() < 1e-9, "{what}: a = {}", fit.a);
            assert!((fit.p0 - 30.0).abs() < 1e-7, "{what}: p0 = {}", fit.p0);
            let off = fit.center[0].hypot(fit.center[1]);
            assert!(
                off < 1e-9 && fit.center[2].abs() < 1e-12,
                "{what}: {:?}",
                fit.center
            );
        }
    }

    #[test]
    fn the_fit_holds_at_any_unit_of_pressure() {
        // At 1e-298 the squares and the pressure-weighted normal underflowed, and the SVD of a
        // design of NaN never returned.
        for p0 in [1e-298, 1e298] {
            let fit = fitted_at(p0, |_| true);
            assert!((fit.a - 0.1).abs() < 1e-9, "p0 {p0}: a = {}", fit.a);
            assert!((fit.p0 / p0 - 1.0).abs() < 1e-9, "p0 {p0}: {}", fit.p0);
        }
    }
}
