//! Dirichlet conditions imposed by symmetric elimination on the assembled pattern.
//!
//! With fixed dofs `D` of values `g`, the free equations become `K_FF u_F = f_F - K_FD g`. To
//! keep the pattern (so the symbolic factorization of `K` serves every constrained variant),
//! the rows and columns of `D` are zeroed in place and their diagonal keeps `K_dd`, with right
//! hand side `K_dd g_d`: the constrained matrix stays symmetric positive definite and its
//! scaling is that of `K`.

use std::collections::BTreeMap;

use faer::sparse::SparseColMat;

use super::NodeColumns;

/// Which dofs are prescribed, and to what.
///
/// A bit per dof says whether it is prescribed, and the values are kept for the prescribed
/// dofs only (a body's boundary groups, a small share of its dofs): an `Option<f64>` per dof
/// took 16 bytes a dof on every rank (16 MB at 1M DOFs).
#[derive(Debug, Clone)]
pub struct Constraints {
    /// Bit `d % 64` of word `d / 64`: whether dof `d` is prescribed.
    fixed: Vec<u64>,
    values: BTreeMap<usize, f64>,
}

impl Constraints {
    pub fn new(num_dofs: usize) -> Self {
        Self {
            fixed: vec![0; num_dofs.div_ceil(64)],
            values: BTreeMap::new(),
        }
    }

    /// Prescribes `value` on `dof`; returns the value already prescribed there if it differs.
    pub fn prescribe(&mut self, dof: usize, value: f64) -> Result<(), f64> {
        match self.value(dof) {
            Some(old) if old != value => Err(old),
            _ => {
                self.fixed[dof / 64] |= 1 << (dof % 64);
                self.values.insert(dof, value);
                Ok(())
            }
        }
    }

    pub fn value(&self, dof: usize) -> Option<f64> {
        match self.is_fixed(dof) {
            true => self.values.get(&dof).copied(),
            false => None,
        }
    }

    pub fn is_fixed(&self, dof: usize) -> bool {
        self.fixed[dof / 64] & (1 << (dof % 64)) != 0
    }

    pub fn num_fixed(&self) -> usize {
        self.values.len()
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
                if let Some(g) = self.value(j) {
                    if i == j {
                        rhs[j] = values[p] * g;
                    } else {
                        if !self.is_fixed(i) {
                            rhs[i] -= values[p] * g;
                        }
                        values[p] = 0.0;
                    }
                } else if self.is_fixed(i) {
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
                match self.value(j) {
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
                            if let Some(g) = self.value(i) {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prescribed_dofs_on_both_sides_of_a_word_keep_their_values() {
        let mut constraints = Constraints::new(130);
        for (dof, value) in [(0, 1.5), (63, -2.0), (64, 0.0), (129, 3.0)] {
            assert_eq!(constraints.prescribe(dof, value), Ok(()));
        }
        // The same value again is accepted; another one is refused with the first.
        assert_eq!(constraints.prescribe(63, -2.0), Ok(()));
        assert_eq!(constraints.prescribe(63, 1.0), Err(-2.0));
        assert_eq!(constraints.num_fixed(), 4);
        let fixed: Vec<usize> = (0..130).filter(|&d| constraints.is_fixed(d)).collect();
        assert_eq!(fixed, [0, 63, 64, 129]);
        assert_eq!(constraints.value(64), Some(0.0));
        assert_eq!(constraints.value(65), None);
        assert_eq!(constraints.value(129), Some(3.0));
    }
}
