//! Rigid-body motions: the kernel of an unconstrained stiffness matrix.
//!
//! Translations `e_k` and infinitesimal rotations `omega x (x - x_c)` (one about z in 2D, three
//! in 3D). A body's Dirichlet conditions make its stiffness non-singular exactly when no
//! combination of these motions vanishes on every fixed dof.

use nalgebra::{DMatrix, SymmetricEigen};

use super::Constraints;

/// The rigid-body modes as dof vectors (interleaved, `dim` per node), centred on the centroid
/// and scaled by the body size so that all have comparable norms: 3 in 2D, 6 in 3D.
pub fn rigid_body_modes(coords: &[[f64; 3]], dim: usize) -> Vec<Vec<f64>> {
    let n = coords.len();
    let mut centre = [0.0; 3];
    for x in coords {
        for k in 0..3 {
            centre[k] += x[k] / n as f64;
        }
    }
    let size = coords
        .iter()
        .map(|x| {
            (0..3)
                .map(|k| (x[k] - centre[k]).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let rotations: &[[f64; 3]] = if dim == 2 {
        &[[0.0, 0.0, 1.0]]
    } else {
        &[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    };
    let mut modes = Vec::new();
    for t in 0..dim {
        let mut m = vec![0.0; dim * n];
        for a in 0..n {
            m[dim * a + t] = 1.0;
        }
        modes.push(m);
    }
    for w in rotations {
        let mut m = vec![0.0; dim * n];
        for (a, x) in coords.iter().enumerate() {
            let r: Vec<f64> = (0..3).map(|k| (x[k] - centre[k]) / size).collect();
            let v = [
                w[1] * r[2] - w[2] * r[1],
                w[2] * r[0] - w[0] * r[2],
                w[0] * r[1] - w[1] * r[0],
            ];
            m[dim * a..dim * a + dim].copy_from_slice(&v[..dim]);
        }
        modes.push(m);
    }
    modes
}

/// How many independent rigid-body motions the constraints leave free (0 when the constrained
/// stiffness is non-singular).
///
/// The Gram matrix `G_ij = sum_{d fixed} r_i[d] r_j[d]` of the modes restricted to the fixed
/// dofs is singular along every motion that the constraints do not see.
pub fn free_rigid_modes(coords: &[[f64; 3]], dim: usize, constraints: &Constraints) -> usize {
    let modes = rigid_body_modes(coords, dim);
    let m = modes.len();
    let mut gram = DMatrix::<f64>::zeros(m, m);
    for d in (0..dim * coords.len()).filter(|&d| constraints.is_fixed(d)) {
        for i in 0..m {
            for j in 0..m {
                gram[(i, j)] += modes[i][d] * modes[j][d];
            }
        }
    }
    let eigenvalues = SymmetricEigen::new(gram).eigenvalues;
    let largest = eigenvalues.iter().cloned().fold(0.0, f64::max);
    eigenvalues
        .iter()
        .filter(|&&e| e <= 1e-10 * largest || largest == 0.0)
        .count()
}
