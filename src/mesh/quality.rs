//! Cell validity: every P1 cell must have a non-vanishing measure, and all cells of a body the
//! same orientation.
//!
//! The P1 kernels use |det J|, so a body meshed consistently clockwise (a 2D surface whose curve
//! loop runs clockwise) is valid. A cell whose orientation differs from the rest of its body,
//! however, means the mesh folds over itself: that is reported as inverted.

use std::path::Path;

use nalgebra::{Matrix2, Matrix3, Vector3};
use rayon::prelude::*;

use super::{BodyMesh, Dim, MeshError};

/// A cell is degenerate when its measure is below this fraction of (longest edge)^dim; a
/// regular tetrahedron has 0.118, a regular triangle 0.433.
const DEGENERATE_RELATIVE_MEASURE: f64 = 1e-10;

/// Signed measure (area in 2D, volume in 3D) of a P1 simplex, positive when counter-clockwise
/// (2D) or right-handed (3D).
pub fn signed_measure<C>(coords: &C, cell: &[usize], dim: Dim) -> f64
where
    C: std::ops::Index<usize, Output = [f64; 3]> + ?Sized,
{
    let p = |k: usize| Vector3::from(coords[cell[k]]);
    if dim == 2 {
        let (a, b) = (p(1) - p(0), p(2) - p(0));
        Matrix2::new(a.x, b.x, a.y, b.y).determinant() / 2.0
    } else {
        let j = Matrix3::from_columns(&[p(1) - p(0), p(2) - p(0), p(3) - p(0)]);
        j.determinant() / 6.0
    }
}

fn longest_edge<C>(coords: &C, cell: &[usize]) -> f64
where
    C: std::ops::Index<usize, Output = [f64; 3]> + ?Sized,
{
    let mut longest: f64 = 0.0;
    for i in 0..cell.len() {
        for j in i + 1..cell.len() {
            let d = Vector3::from(coords[cell[i]]) - Vector3::from(coords[cell[j]]);
            longest = longest.max(d.norm());
        }
    }
    longest
}

/// Checks that no cell of `body` is degenerate or inverted.
pub fn check_cells(path: &Path, body: &BodyMesh) -> Result<(), MeshError> {
    let dim = body.dim;
    // Each cell on its own: in parallel (a tenth of reading a 1M-DOF mesh serially), the
    // first degenerate cell in the file's order reported as before.
    let measures: Vec<f64> = (0..body.num_cells())
        .into_par_iter()
        .map(|c| signed_measure(&body.coords, &body.cell(c), dim))
        .collect();
    let degenerate = (measures.par_iter().enumerate())
        .map(|(c, &m)| {
            (
                c,
                m,
                m.abs() / longest_edge(&body.coords, &body.cell(c)).powi(dim as i32),
            )
        })
        .find_first(|&(_, _, relative)| {
            relative.is_nan() || relative < DEGENERATE_RELATIVE_MEASURE
        });
    if let Some((c, m, relative)) = degenerate {
        return Err(MeshError::DegenerateCell {
            path: path.to_owned(),
            body: body.name.clone(),
            element_tag: body.cell_tags.get(c),
            measure_name: if dim == 2 { "area" } else { "volume" },
            measure: m.abs(),
            relative,
        });
    }
    let positive = measures.iter().filter(|&&m| m > 0.0).count();
    let negative = measures.len() - positive;
    let minority_is_positive = positive < negative;
    if positive.min(negative) > 0 {
        let c = measures
            .iter()
            .position(|&m| (m > 0.0) == minority_is_positive)
            .expect("the minority orientation has at least one cell");
        return Err(MeshError::InvertedCell {
            path: path.to_owned(),
            body: body.name.clone(),
            element_tag: body.cell_tags.get(c),
            majority: positive.max(negative),
        });
    }
    Ok(())
}
