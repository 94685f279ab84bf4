//! Element kernels for P1 simplices: each fills a small dense matrix or vector for one cell or
//! facet; [`super::assembly`] scatters them.
//!
//! On a simplex with vertices `x_0 .. x_d`, `J = [x_1 - x_0, ..., x_d - x_0]`, the gradients of
//! the barycentric basis functions are the rows of `J^-1` (for `phi_1 .. phi_d`) and
//! `grad phi_0 = -sum_k grad phi_k`; the measure is `|det J| / d!`.
//!
//! Stiffness: `K_e = |T| B^T D B`, with `B` the strain-displacement matrix (Voigt, engineering
//! shear) and dofs interleaved per node, `(u_x, u_y[, u_z])`.
//!
//! Facet mass (the interface mass matrix, `docs/method.md` 2.1): `M_e[a, b] = int phi_a phi_b ds`
//! = `L/6 [[2,1],[1,2]]` on a segment of length `L` and `A/12 (1 + delta_ab)` on a triangle of
//! area `A`.

use nalgebra::{Matrix2, Matrix3, SMatrix, Vector3};

use super::Material;

/// Gradients of the P1 basis functions and measure of a triangle (x, y used).
pub fn triangle_gradients(x: &[[f64; 3]; 3]) -> ([[f64; 2]; 3], f64) {
    let j = Matrix2::new(
        x[1][0] - x[0][0],
        x[2][0] - x[0][0],
        x[1][1] - x[0][1],
        x[2][1] - x[0][1],
    );
    let det = j.determinant();
    // J^-1 = adj(J) / det; its rows are grad phi_1, grad phi_2.
    let inv = Matrix2::new(j[(1, 1)], -j[(0, 1)], -j[(1, 0)], j[(0, 0)]) / det;
    let g1 = [inv[(0, 0)], inv[(0, 1)]];
    let g2 = [inv[(1, 0)], inv[(1, 1)]];
    ([[-g1[0] - g2[0], -g1[1] - g2[1]], g1, g2], det.abs() / 2.0)
}

/// Gradients of the P1 basis functions and measure of a tetrahedron.
pub fn tetrahedron_gradients(x: &[[f64; 3]; 4]) -> ([[f64; 3]; 4], f64) {
    let p = |k: usize| Vector3::from(x[k]);
    let j = Matrix3::from_columns(&[p(1) - p(0), p(2) - p(0), p(3) - p(0)]);
    let det = j.determinant();
    let inv = j.try_inverse().unwrap_or_else(Matrix3::zeros);
    let mut g = [[0.0; 3]; 4];
    for k in 0..3 {
        for c in 0..3 {
            g[k + 1][c] = inv[(k, c)];
            g[0][c] -= inv[(k, c)];
        }
    }
    (g, det.abs() / 6.0)
}

/// Plane-strain `B` (3 x 6): rows `exx, eyy, 2exy`.
pub fn strain_matrix_2d(g: &[[f64; 2]; 3]) -> SMatrix<f64, 3, 6> {
    let mut b = SMatrix::<f64, 3, 6>::zeros();
    for (a, ga) in g.iter().enumerate() {
        b[(0, 2 * a)] = ga[0];
        b[(1, 2 * a + 1)] = ga[1];
        b[(2, 2 * a)] = ga[1];
        b[(2, 2 * a + 1)] = ga[0];
    }
    b
}

/// 3D `B` (6 x 12): rows `exx, eyy, ezz, 2eyz, 2exz, 2exy`.
pub fn strain_matrix_3d(g: &[[f64; 3]; 4]) -> SMatrix<f64, 6, 12> {
    let mut b = SMatrix::<f64, 6, 12>::zeros();
    for (a, ga) in g.iter().enumerate() {
        let c = 3 * a;
        b[(0, c)] = ga[0];
        b[(1, c + 1)] = ga[1];
        b[(2, c + 2)] = ga[2];
        b[(3, c + 1)] = ga[2];
        b[(3, c + 2)] = ga[1];
        b[(4, c)] = ga[2];
        b[(4, c + 2)] = ga[0];
        b[(5, c)] = ga[1];
        b[(5, c + 1)] = ga[0];
    }
    b
}

/// Plane-strain stiffness of a triangle (6 x 6).
pub fn triangle_stiffness(x: &[[f64; 3]; 3], material: &Material) -> SMatrix<f64, 6, 6> {
    let (g, area) = triangle_gradients(x);
    let b = strain_matrix_2d(&g);
    b.transpose() * material.plane_strain_matrix() * b * area
}

/// Stiffness of a tetrahedron (12 x 12).
pub fn tetrahedron_stiffness(x: &[[f64; 3]; 4], material: &Material) -> SMatrix<f64, 12, 12> {
    let (g, volume) = tetrahedron_gradients(x);
    let b = strain_matrix_3d(&g);
    b.transpose() * material.elasticity_matrix_3d() * b * volume
}

/// Measure (length or area) and outward unit normal of a facet whose nodes are ordered so that
/// the right-hand normal points outward (as [`crate::mesh::FacetGroup`] stores them).
pub fn facet_measure_and_normal(x: &[[f64; 3]], dim: usize) -> (f64, [f64; 3]) {
    let p = |k: usize| Vector3::from(x[k]);
    let n = if dim == 2 {
        let t = p(1) - p(0);
        Vector3::new(t.y, -t.x, 0.0)
    } else {
        (p(1) - p(0)).cross(&(p(2) - p(0))) / 2.0
    };
    let measure = n.norm();
    (measure, (n / measure).into())
}

/// Scalar facet mass matrix `int phi_a phi_b ds`, `dim` x `dim` (2 nodes in 2D, 3 in 3D),
/// stored in the leading block of a 3 x 3 array.
pub fn facet_mass(measure: f64, dim: usize) -> [[f64; 3]; 3] {
    let (diagonal, off_diagonal) = if dim == 2 {
        (measure / 3.0, measure / 6.0)
    } else {
        (measure / 6.0, measure / 12.0)
    };
    let mut m = [[0.0; 3]; 3];
    for (a, row) in m.iter_mut().enumerate().take(dim) {
        for (b, v) in row.iter_mut().enumerate().take(dim) {
            *v = if a == b { diagonal } else { off_diagonal };
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reference_tet() -> [[f64; 3]; 4] {
        [
            [0.1, 0.0, 0.2],
            [1.3, 0.1, 0.0],
            [0.2, 0.9, 0.1],
            [0.3, 0.2, 1.1],
        ]
    }

    #[test]
    fn gradients_reproduce_linear_functions() {
        // sum_a f(x_a) grad phi_a = grad f for f linear.
        let x = reference_tet();
        let (g, _) = tetrahedron_gradients(&x);
        let f = |p: &[f64; 3]| 2.0 * p[0] - 3.0 * p[1] + 0.5 * p[2] + 1.0;
        for c in 0..3 {
            let grad: f64 = (0..4).map(|a| f(&x[a]) * g[a][c]).sum();
            assert!((grad - [2.0, -3.0, 0.5][c]).abs() < 1e-13);
        }
        let t = [[0.0, 0.0, 0.0], [2.0, 0.1, 0.0], [0.3, 1.5, 0.0]];
        let (g, area) = triangle_gradients(&t);
        assert!((area - (2.0 * 1.5 - 0.1 * 0.3) / 2.0).abs() < 1e-14);
        let f = |p: &[f64; 3]| 4.0 * p[0] + 7.0 * p[1];
        for c in 0..2 {
            let grad: f64 = (0..3).map(|a| f(&t[a]) * g[a][c]).sum();
            assert!((grad - [4.0, 7.0][c]).abs() < 1e-13);
        }
    }

    #[test]
    fn stiffness_is_independent_of_vertex_orientation() {
        let m = Material::new(1.0, 0.25).unwrap();
        let x = reference_tet();
        let mut y = x;
        y.swap(1, 2);
        let kx = tetrahedron_stiffness(&x, &m);
        let ky = tetrahedron_stiffness(&y, &m);
        // Swapping nodes 1 and 2 permutes the dof blocks 1 and 2.
        let perm = |i: usize| match i / 3 {
            1 => 6 + i % 3,
            2 => 3 + i % 3,
            _ => i,
        };
        for i in 0..12 {
            for j in 0..12 {
                assert!((kx[(perm(i), perm(j))] - ky[(i, j)]).abs() < 1e-13);
            }
        }
    }

    #[test]
    fn facet_mass_integrates_to_the_measure() {
        for (dim, measure) in [(2, 0.7), (3, 0.35)] {
            let m = facet_mass(measure, dim);
            let total: f64 = m.iter().flatten().sum();
            assert!((total - measure).abs() < 1e-15);
        }
    }
}
