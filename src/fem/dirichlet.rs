//! Dirichlet conditions imposed by symmetric elimination on the assembled pattern.
//!
//! With fixed dofs `D` of values `g`, the free equations become `K_FF u_F = f_F - K_FD g`. To
//! keep the pattern (so the symbolic factorization of `K` serves every constrained variant),
//! the rows and columns of `D` are zeroed in place and their diagonal keeps `K_dd`, with right
//! hand side `K_dd g_d`: the constrained matrix stays symmetric positive definite and its
//! scaling is that of `K`.

use faer::sparse::SparseColMat;

use super::NodeColumns;

/// Which dofs are prescribed, and to what.
#[derive(Debug, Clone)]
pub struct Constraints {
    prescribed: Vec<Option<f64>>,
}

impl Constraints {
    pub fn new(num_dofs: usize) -> Self {
        Self {
            prescribed: vec![None; num_dofs],
        }
    }

    /// Prescribes `value` on `dof`; returns the value already prescribed there if it differs.
    pub fn prescribe(&mut self, dof: usize, value: f64) -> Result<(), f64> {
        match self.prescribed[dof] {
            Some(old) if old != value => Err(old),
            _ => {
                self.prescribed[dof] = Some(value);
                Ok(())
            }
        }
    }

    pub fn value(&self, dof: usize) -> Option<f64> {
        self.prescribed[dof]
    }

    pub fn is_fixed(&self, dof: usize) -> bool {
        self.prescribed[dof].is_some()
    }

    pub fn num_fixed(&self) -> usize {
        self.prescribed.iter().filter(|v| v.is_some()).count()
    }

    /// The constrained system `(K_c, f_c)` of `(k, f)`, on the pattern of `k`, whose storage it
    /// takes over: a copy would double the largest allocation of a solve.
    pub fn apply(
        &self,
        k: SparseColMat<usize, f64>,
        f: &[f64],
    ) -> (SparseColMat<usize, f64>, Vec<f64>) {
        let (symbolic, mut values) = k.into_parts();
        let mut rhs = f.to_vec();
        let col_ptr = symbolic.col_ptr();
        let row_idx = symbolic.row_idx();
        for j in 0..symbolic.ncols() {
            for p in col_ptr[j]..col_ptr[j + 1] {
                let i = row_idx[p];
                if let Some(g) = self.prescribed[j] {
                    if i == j {
                        rhs[j] = values[p] * g;
                    } else {
                        if self.prescribed[i].is_none() {
                            rhs[i] -= values[p] * g;
                        }
                        values[p] = 0.0;
                    }
                } else if self.prescribed[i].is_some() {
                    values[p] = 0.0;
                }
            }
        }
        (SparseColMat::new(symbolic, values), rhs)
    }

    /// [`Self::apply`] on some columns of `K` (a rank's rows in a distributed run): the columns
    /// are constrained in place as `apply` leaves them in `K_c`, and the entries of `f_c` at
    /// their unknowns are returned, in column order. A free unknown's pull by the prescribed
    /// ones, `-sum_d K_jd g_d`, is read from its own column (`K` is symmetric), in the order
    /// `apply` sums it.
    pub fn apply_to_columns(&self, columns: &mut NodeColumns, f: &[f64]) -> Vec<f64> {
        (0..columns.num_columns())
            .map(|q| {
                let j = columns.dof(q);
                let (rows, values) = columns.column_mut(q);
                match self.prescribed[j] {
                    Some(g) => {
                        let mut rhs = 0.0;
                        for (&i, value) in rows.iter().zip(values.iter_mut()) {
                            match i == j {
                                true => rhs = *value * g,
                                false => *value = 0.0,
                            }
                        }
                        rhs
                    }
                    None => {
                        let mut rhs = f[j];
                        for (&i, value) in rows.iter().zip(values.iter_mut()) {
                            if let Some(g) = self.prescribed[i] {
                                rhs -= *value * g;
                                *value = 0.0;
                            }
                        }
                        rhs
                    }
                }
            })
            .collect()
    }
}
