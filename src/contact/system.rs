//! The linear system of one active-set iteration (method.md section 2), assembled in one place.
//!
//! ```text
//! [ K1        0        -M1 (rows I)  ] [u1    ]   [f1]
//! [ 0         K2     M2 R21 (rows J) ] [u2    ] = [f2]
//! [ I (cols I)  -R12 (cols J)    0   ] [lambda]   [d ]
//! ```
//!
//! `K_k`, `f_k` are Dirichlet-constrained (rows and columns of prescribed dofs hold only their
//! diagonal, and carry no coupling). `lambda` is the traction on body 1 at its active nodes I;
//! body 2 receives `lambda_2 = -R21 lambda`. Tied: one vector multiplier per node and the vector
//! constraint `u1 - R12 u2 = d`. Frictionless: `lambda = lambda_n n1`, one scalar per node, and
//! only the normal constraint `n1 . (u1 - R12 u2) = n1 . d`.
//!
//! A multiplier whose constraint only restates a Dirichlet condition of body 1 (tied: its dof
//! is prescribed; frictionless: every dof of its node is) is dropped: its row becomes
//! `lambda = 0` and it acts on neither body. Keeping it would leave an empty column, since the
//! rows of prescribed dofs carry no coupling.
//!
//! Scaling: the multiplier columns are multiplied by `s = k / m` and the constraint rows by `k`,
//! with `k` the largest diagonal entry of `K1` and `m` that of `M1`, so that every block has
//! the magnitude of `K`; the solution is unscaled on return.

use faer::prelude::*;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{SparseColMat, Triplet};
use nalgebra::DMatrix;

use super::{ContactError, Formulation};
use crate::elastic::AssembledBody;
use crate::linalg::relative_residual;

/// The interface operators of one iteration, on the active nodes (surface indices).
pub struct Coupling {
    pub formulation: Formulation,
    /// Body-local node of each active primary node (I) and secondary node (J).
    pub primary_nodes: Vec<usize>,
    pub secondary_nodes: Vec<usize>,
    /// Outward normals of body 1 at I.
    pub normals: Vec<[f64; 3]>,
    /// `R12` (|I| x |r12_nodes|), interpolating the secondary displacement to I from the
    /// secondary nodes `r12_nodes` (J and the ring of nodes around it).
    pub r12: DMatrix<f64>,
    pub r12_nodes: Vec<usize>,
    /// `R21` (|J| x |I|), interpolating from I to J.
    pub r21: DMatrix<f64>,
    /// Interface mass matrices of the facets with an active node: rows are the body nodes of
    /// those facets (`m1_rows`, `m2_rows`), columns the active nodes I (resp. J).
    pub m1_rows: Vec<usize>,
    pub m1: DMatrix<f64>,
    pub m2_rows: Vec<usize>,
    pub m2: DMatrix<f64>,
    /// Nodal gaps in the reference configuration: the normal part of `R12 x2(J) - x1(I)`.
    pub gaps: Vec<[f64; 3]>,
}

/// The solution of one iteration.
pub struct CoupledSolution {
    pub u1: Vec<f64>,
    pub u2: Vec<f64>,
    /// Traction on body 1 at I, one vector per node (for frictionless, `lambda_n n1`).
    pub traction: Vec<[f64; 3]>,
    /// Forces the interface applies to each body's dofs: `M1 lambda`, `-M2 R21 lambda`.
    pub contact_force1: Vec<f64>,
    pub contact_force2: Vec<f64>,
    pub relative_residual: f64,
}

impl Coupling {
    fn num_multipliers(&self, dim: usize) -> usize {
        match self.formulation {
            Formulation::Tied => dim * self.primary_nodes.len(),
            Formulation::Frictionless => self.primary_nodes.len(),
        }
    }

    /// Whether multiplier `col` restates a Dirichlet condition of body 1 (see the module doc).
    fn is_dropped(&self, col: usize, body1: &AssembledBody, dim: usize) -> bool {
        match self.formulation {
            Formulation::Tied => body1
                .constraints
                .is_fixed(dim * self.primary_nodes[col / dim] + col % dim),
            Formulation::Frictionless => (0..dim).all(|c| {
                body1
                    .constraints
                    .is_fixed(dim * self.primary_nodes[col] + c)
            }),
        }
    }

    /// Column `(multiplier, component)` coefficients of the traction at node `b`:
    /// tied `lambda(b, c)` is its own unknown; frictionless `lambda(b) n_b[c]`.
    fn multiplier_terms(&self, b: usize, c: usize, dim: usize) -> (usize, f64) {
        match self.formulation {
            Formulation::Tied => (dim * b + c, 1.0),
            Formulation::Frictionless => (b, self.normals[b][c]),
        }
    }
}

/// Assembles and solves the coupled system with a sparse LU of the whole matrix.
pub fn solve_coupled(
    body1: &AssembledBody,
    body2: &AssembledBody,
    coupling: &Coupling,
    dim: usize,
) -> Result<CoupledSolution, ContactError> {
    let n1 = body1.f_c.len();
    let n2 = body2.f_c.len();
    let m = coupling.num_multipliers(dim);
    let n = n1 + n2 + m;
    let k_scale = diagonal_max(&body1.k_c).max(diagonal_max(&body2.k_c));
    let m_scale = coupling.m1.iter().cloned().fold(0.0, f64::max);
    if m > 0 && m_scale <= 0.0 {
        return Err(ContactError::EmptyInterfaceMass);
    }
    let s = if m > 0 { k_scale / m_scale } else { 1.0 };
    let t = k_scale;

    let dropped: Vec<bool> = (0..m)
        .map(|col| coupling.is_dropped(col, body1, dim))
        .collect();
    let mut triplets = Vec::new();
    for (body, offset) in [(body1, 0), (body2, n1)] {
        let (symbolic, values) = body.k_c.parts();
        let (col_ptr, row_idx) = (symbolic.col_ptr(), symbolic.row_idx());
        for j in 0..symbolic.ncols() {
            for p in col_ptr[j]..col_ptr[j + 1] {
                if values[p] != 0.0 {
                    triplets.push(Triplet::new(offset + row_idx[p], offset + j, values[p]));
                }
            }
        }
    }
    // Coupling columns: -M1 lambda on body 1, +M2 R21 lambda on body 2.
    let m2_r21 = &coupling.m2 * &coupling.r21;
    for (nodes, matrix, sign, offset, body) in [
        (&coupling.m1_rows, &coupling.m1, -1.0, 0, body1),
        (&coupling.m2_rows, &m2_r21, 1.0, n1, body2),
    ] {
        for (a, &node) in nodes.iter().enumerate() {
            for c in 0..dim {
                let dof = dim * node + c;
                if body.constraints.is_fixed(dof) {
                    continue;
                }
                for b in 0..coupling.primary_nodes.len() {
                    let (col, weight) = coupling.multiplier_terms(b, c, dim);
                    if dropped[col] {
                        continue;
                    }
                    let value = sign * s * matrix[(a, b)] * weight;
                    if value != 0.0 {
                        triplets.push(Triplet::new(offset + dof, n1 + n2 + col, value));
                    }
                }
            }
        }
    }
    // Constraint rows: u1 - R12 u2 = d (tied), or its normal component (frictionless).
    let mut rhs = Vec::with_capacity(n);
    rhs.extend_from_slice(&body1.f_c);
    rhs.extend_from_slice(&body2.f_c);
    rhs.resize(n, 0.0);
    for col in (0..m).filter(|&col| dropped[col]) {
        triplets.push(Triplet::new(n1 + n2 + col, n1 + n2 + col, t));
    }
    for (a, &node) in coupling.primary_nodes.iter().enumerate() {
        for c in 0..dim {
            let (row, weight) = coupling.multiplier_terms(a, c, dim);
            if dropped[row] {
                continue;
            }
            let row = n1 + n2 + row;
            triplets.push(Triplet::new(row, dim * node + c, t * weight));
            for (j, &node2) in coupling.r12_nodes.iter().enumerate() {
                let value = -t * coupling.r12[(a, j)] * weight;
                if value != 0.0 {
                    triplets.push(Triplet::new(row, n1 + dim * node2 + c, value));
                }
            }
            rhs[row] += t * weight * coupling.gaps[a][c];
        }
    }

    let matrix = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &triplets)
        .map_err(|e| ContactError::Linalg(format!("assembling the coupled system: {e:?}")))?;
    let lu_error =
        |e: String| ContactError::Linalg(format!("sparse LU of the coupled system: {e}"));
    let symbolic =
        SymbolicLu::try_new(matrix.symbolic()).map_err(|e| lu_error(format!("{e:?}")))?;
    let lu = Lu::try_new_with_symbolic(symbolic, matrix.as_ref())
        .map_err(|e| lu_error(format!("{e:?}")))?;
    let mut x = rhs.clone();
    lu.solve_in_place(faer::MatMut::from_column_major_slice_mut(&mut x, n, 1));
    let relative_residual = relative_residual(&matrix, &x, &rhs);

    // Unscale the multipliers and form the tractions and interface forces.
    let traction: Vec<[f64; 3]> = (0..coupling.primary_nodes.len())
        .map(|b| {
            let mut lambda = [0.0; 3];
            for (c, value) in lambda.iter_mut().enumerate().take(dim) {
                let (col, weight) = coupling.multiplier_terms(b, c, dim);
                *value = s * x[n1 + n2 + col] * weight;
            }
            lambda
        })
        .collect();
    let mut contact_force1 = vec![0.0; n1];
    let mut contact_force2 = vec![0.0; n2];
    for (nodes, matrix, sign, force) in [
        (&coupling.m1_rows, &coupling.m1, 1.0, &mut contact_force1),
        (&coupling.m2_rows, &m2_r21, -1.0, &mut contact_force2),
    ] {
        for (a, &node) in nodes.iter().enumerate() {
            for (b, lambda) in traction.iter().enumerate() {
                for c in 0..dim {
                    force[dim * node + c] += sign * matrix[(a, b)] * lambda[c];
                }
            }
        }
    }
    Ok(CoupledSolution {
        u1: x[..n1].to_vec(),
        u2: x[n1..n1 + n2].to_vec(),
        traction,
        contact_force1,
        contact_force2,
        relative_residual,
    })
}

fn diagonal_max(k: &SparseColMat<usize, f64>) -> f64 {
    let (symbolic, values) = k.parts();
    let (col_ptr, row_idx) = (symbolic.col_ptr(), symbolic.row_idx());
    (0..symbolic.ncols())
        .flat_map(|j| (col_ptr[j]..col_ptr[j + 1]).filter(move |&p| row_idx[p] == j))
        .map(|p| values[p].abs())
        .fold(0.0, f64::max)
}
