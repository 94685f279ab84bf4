//! Rigid-body motions: the kernel of an unconstrained stiffness matrix.
//!
//! Translations `e_k` and infinitesimal rotations `omega x (x - x_c)` (one about z in 2D, three
//! in 3D). A body's Dirichlet conditions make its stiffness non-singular exactly when no
//! combination of these motions vanishes on every fixed dof.

use nalgebra::{DMatrix, SymmetricEigen};

use super::Constraints;
use crate::mesh::BodyMesh;

/// The rigid-body motions of one body, centred on its centroid and scaled by its size so that
/// all have comparable norms: 3 in 2D (two translations, the rotation about z), 6 in 3D.
pub struct RigidModes {
    dim: usize,
    centre: [f64; 3],
    size: f64,
}

impl RigidModes {
    /// The motions of `body`, about the centroid of its nodes and scaled by their largest
    /// distance from it (of the whole body, also on a rank that keeps only some of its nodes:
    /// [`BodyMesh::extent`]).
    pub fn of(body: &BodyMesh) -> Self {
        let extent = body.extent();
        Self {
            dim: body.dim,
            centre: extent.centroid,
            size: extent.radius.max(f64::MIN_POSITIVE),
        }
    }

    /// The number of motions: 3 in 2D, 6 in 3D.
    pub fn count(&self) -> usize {
        if self.dim == 2 { 3 } else { 6 }
    }

    /// The displacement of each motion at the point `x` (components past `dim` are 0).
    pub fn at(&self, x: &[f64; 3]) -> Vec<[f64; 3]> {
        let rotations: &[[f64; 3]] = if self.dim == 2 {
            &[[0.0, 0.0, 1.0]]
        } else {
            &[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
        };
        let mut modes = Vec::with_capacity(self.count());
        for t in 0..self.dim {
            let mut m = [0.0; 3];
            m[t] = 1.0;
            modes.push(m);
        }
        let r: [f64; 3] = std::array::from_fn(|k| (x[k] - self.centre[k]) / self.size);
        for w in rotations {
            let v = [
                w[1] * r[2] - w[2] * r[1],
                w[2] * r[0] - w[0] * r[2],
                w[0] * r[1] - w[1] * r[0],
            ];
            let mut m = [0.0; 3];
            m[..self.dim].copy_from_slice(&v[..self.dim]);
            modes.push(m);
        }
        modes
    }
}

/// The rigid-body modes ([`RigidModes`]) of a body whose nodes are all kept, as dof vectors
/// (interleaved, `dim` per node).
pub fn rigid_body_modes(body: &BodyMesh) -> Vec<Vec<f64>> {
    let (modes, dim) = (RigidModes::of(body), body.dim);
    let mut vectors = vec![vec![0.0; body.num_dofs()]; modes.count()];
    for (a, x) in body.coords.kept() {
        for (vector, m) in vectors.iter_mut().zip(modes.at(x)) {
            vector[dim * a..dim * a + dim].copy_from_slice(&m[..dim]);
        }
    }
    vectors
}

/// The rigid-body motions (combinations of [`RigidModes`], one per column) that the fixed dofs
/// of `constraints` do not hold: the eigenvectors of the Gram matrix of the modes restricted
/// to the fixed dofs whose eigenvalues vanish.
pub fn free_rigid_motions(body: &BodyMesh, constraints: &Constraints) -> DMatrix<f64> {
    let (gram, largest) = gram(body, constraints);
    let eigen = SymmetricEigen::new(gram);
    let free: Vec<usize> = (0..eigen.eigenvalues.len())
        .filter(|&i| eigen.eigenvalues[i] <= 1e-10 * largest || largest == 0.0)
        .collect();
    DMatrix::from_fn(eigen.eigenvectors.nrows(), free.len(), |r, c| {
        eigen.eigenvectors[(r, free[c])]
    })
}

/// The Gram matrix of the rigid modes on the fixed dofs, and its largest eigenvalue. The
/// modes are evaluated at the fixed dofs' nodes only (a rank keeps those nodes' coordinates:
/// they lie on the body's groups and boundary).
fn gram(body: &BodyMesh, constraints: &Constraints) -> (DMatrix<f64>, f64) {
    let (modes, dim) = (RigidModes::of(body), body.dim);
    let m = modes.count();
    let mut gram = DMatrix::<f64>::zeros(m, m);
    for d in (0..body.num_dofs()).filter(|&d| constraints.is_fixed(d)) {
        let at = modes.at(&body.coords[d / dim]);
        for i in 0..m {
            for j in 0..m {
                gram[(i, j)] += at[i][d % dim] * at[j][d % dim];
            }
        }
    }
    let largest = SymmetricEigen::new(gram.clone())
        .eigenvalues
        .iter()
        .cloned()
        .fold(0.0, f64::max);
    (gram, largest)
}

/// How many independent rigid-body motions the constraints leave free (0 when the constrained
/// stiffness is non-singular).
///
/// The Gram matrix `G_ij = sum_{d fixed} r_i[d] r_j[d]` of the modes restricted to the fixed
/// dofs is singular along every motion that the constraints do not see.
pub fn free_rigid_modes(body: &BodyMesh, constraints: &Constraints) -> usize {
    free_rigid_motions(body, constraints).ncols()
}
