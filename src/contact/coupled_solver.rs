//! How the coupled system of an iteration is solved, behind one interface.
//!
//! - [`CoupledSolver::Schur`] (default): each body's constrained stiffness is factored once
//!   (sparse Cholesky) for the whole contact solve, and every iteration solves only the
//!   interface problem by block elimination:
//!   `Y = K^-1 B`, `z = K^-1 f`, `(D - C Y) lambda = g - C z`, `u = z - Y lambda`.
//!   The Schur complement `S = D - C Y` is formed densely from multi-right-hand-side solves
//!   (m columns) and factored by dense LU with partial pivoting: interfaces have hundreds to a
//!   few thousand multipliers, where a dense m x m LU is negligible next to the m solves.
//! - [`CoupledSolver::MonolithicLu`]: a sparse LU of the whole unsymmetric matrix, refactored
//!   every iteration; the reference the Schur path is tested against.

use faer::prelude::*;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use super::ContactError;
use super::system::CoupledSystem;
use crate::elastic::AssembledBody;
use crate::linalg::{Cholesky, CholeskySymbolic, Ordering};

#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CoupledSolver {
    /// Cholesky of each body once, dense Schur complement on the multipliers per iteration.
    #[default]
    Schur,
    /// Sparse LU of the whole saddle-point matrix per iteration (reference).
    MonolithicLu,
}

/// The Cholesky factors of both bodies' constrained stiffness matrices.
pub struct BodyFactors {
    factor1: Cholesky,
    factor2: Cholesky,
}

impl BodyFactors {
    pub fn new(
        body1: &AssembledBody,
        body2: &AssembledBody,
        ordering: Ordering,
    ) -> Result<Self, ContactError> {
        let factor = |body: &AssembledBody| {
            CholeskySymbolic::new(&body.pattern, ordering)
                .and_then(|symbolic| Cholesky::factorize(symbolic, &body.k_c))
                .map_err(|e| ContactError::Linalg(format!("Cholesky of a body's stiffness: {e}")))
        };
        // The two factorizations are independent: side by side.
        let (factor1, factor2) = rayon::join(|| factor(body1), || factor(body2));
        Ok(Self {
            factor1: factor1?,
            factor2: factor2?,
        })
    }
}

/// Solves the coupled system; returns `x = [u1; u2; lambda / s]`.
pub fn solve(
    system: &CoupledSystem,
    body1: &AssembledBody,
    body2: &AssembledBody,
    factors: Option<&BodyFactors>,
) -> Result<Vec<f64>, ContactError> {
    match factors {
        Some(factors) => solve_schur(system, factors),
        None => solve_monolithic(system, body1, body2),
    }
}

fn solve_monolithic(
    system: &CoupledSystem,
    body1: &AssembledBody,
    body2: &AssembledBody,
) -> Result<Vec<f64>, ContactError> {
    let matrix = system.matrix(body1, body2)?;
    let lu_error =
        |e: String| ContactError::Linalg(format!("sparse LU of the coupled system: {e}"));
    let symbolic =
        SymbolicLu::try_new(matrix.symbolic()).map_err(|e| lu_error(format!("{e:?}")))?;
    let lu = Lu::try_new_with_symbolic(symbolic, matrix.as_ref())
        .map_err(|e| lu_error(format!("{e:?}")))?;
    let mut x = system.rhs();
    let n = x.len();
    lu.solve_in_place(faer::MatMut::from_column_major_slice_mut(&mut x, n, 1));
    Ok(x)
}

fn solve_schur(system: &CoupledSystem, factors: &BodyFactors) -> Result<Vec<f64>, ContactError> {
    let (n1, n2, m) = (system.n1, system.n2, system.m);
    // Y = K^-1 B, per body, m right-hand sides at once (column-major n_k x m).
    let mut y1 = vec![0.0; n1 * m];
    let mut y2 = vec![0.0; n2 * m];
    for &(row, k, value) in &system.b {
        if row < n1 {
            y1[k * n1 + row] += value;
        } else {
            y2[k * n2 + row - n1] += value;
        }
    }
    // z = K^-1 f.
    let mut z1 = system.f[..n1].to_vec();
    let mut z2 = system.f[n1..].to_vec();
    // The bodies are independent: solved side by side (each also splits its columns).
    rayon::join(
        || {
            factors.factor1.solve_in_place(&mut y1, m);
            factors.factor1.solve_in_place(&mut z1, 1);
        },
        || {
            factors.factor2.solve_in_place(&mut y2, m);
            factors.factor2.solve_in_place(&mut z2, 1);
        },
    );

    // S = D - C Y and r = g - C z.
    let mut schur = DMatrix::<f64>::from_diagonal(&nalgebra::DVector::from_column_slice(&system.d));
    let mut r = system.g.clone();
    for &(k, col, value) in &system.c {
        if col < n1 {
            for j in 0..m {
                schur[(k, j)] -= value * y1[j * n1 + col];
            }
            r[k] -= value * z1[col];
        } else {
            let col = col - n1;
            for j in 0..m {
                schur[(k, j)] -= value * y2[j * n2 + col];
            }
            r[k] -= value * z2[col];
        }
    }
    let lambda = if m > 0 {
        schur
            .lu()
            .solve(&nalgebra::DVector::from_vec(r))
            .ok_or_else(|| {
                ContactError::Linalg("the interface Schur complement is singular".into())
            })?
    } else {
        nalgebra::DVector::zeros(0)
    };

    // u = z - Y lambda.
    for (z, y, n) in [(&mut z1, &y1, n1), (&mut z2, &y2, n2)] {
        for (j, &l) in lambda.iter().enumerate() {
            if l != 0.0 {
                for (zi, yi) in z.iter_mut().zip(&y[j * n..(j + 1) * n]) {
                    *zi -= yi * l;
                }
            }
        }
    }
    let mut x = z1;
    x.extend_from_slice(&z2);
    x.extend(lambda.iter());
    Ok(x)
}
