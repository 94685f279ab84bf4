//! Dirichlet conditions imposed by symmetric elimination on the assembled pattern.
//!
//! With fixed dofs `D` of values `g`, the free equations become `K_FF u_F = f_F - K_FD g`. To
//! keep the pattern (so the symbolic factorization of `K` serves every constrained variant),
//! the rows and columns of `D` are zeroed in place and their diagonal keeps `K_dd`, with right
//! hand side `K_dd g_d`: the constrained matrix stays symmetric positive definite and its
//! scaling is that of `K`.

use std::collections::BTreeMap;

use faer::sparse::SparseColMat;

use super::{LoadVector, NodeColumns};

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
    /// `apply` sums it. `f(dof)` is the load at `dof`, read at the columns' unknowns only.
    pub fn apply_to_columns(
        &self,
        columns: &mut NodeColumns,
        f: impl Fn(usize) -> f64,
    ) -> Vec<f64> {
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
                        let mut rhs = f(j);
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

    /// The constrained right-hand side of the load vector `f` alone, as [`Self::apply`]
    /// eliminates it, with the values `value(dof)` at the prescribed dofs: at a free dof
    /// `f_i - sum_j K_ij g_j`, at a prescribed one `K_jj g_j`. `prescribed_rows` are the rows
    /// of `K` at the prescribed dofs by increasing dof (`K` is symmetric: a row is a column),
    /// `(dof, [(column, value)])`; a prescribed dof without a row keeps `f_c = 0`. The result is
    /// kept as `f` is: whole, sparse, or a rank's part, which is then right at the dofs where
    /// `f` is (the rows at the prescribed dofs are whole), and the caller keeps those. Each
    /// entry is the same bits as a whole vector's.
    pub fn apply_to_load(
        &self,
        f: &LoadVector,
        prescribed_rows: &[(usize, Vec<(usize, f64)>)],
        value: impl Fn(usize) -> f64,
    ) -> LoadVector {
        let mut f_c: BTreeMap<usize, f64> = BTreeMap::new();
        let whole = match f {
            LoadVector::Whole(whole) => Some(whole.clone()),
            _ => {
                f_c.extend(f.nonzero_entries());
                None
            }
        };
        // The same operations on a whole vector or on the entries that are kept: a missing
        // entry is a 0.0 that the whole vector would hold.
        let mut f_c = Entries { whole, f_c };
        for (j, _) in prescribed_rows {
            f_c.set(*j, 0.0);
        }
        for (j, row) in prescribed_rows {
            let g = value(*j);
            if g == 0.0 {
                continue;
            }
            for &(i, k) in row {
                if i == *j {
                    f_c.set(i, k * g);
                } else if !self.is_fixed(i) {
                    f_c.subtract(i, k * g);
                }
            }
        }
        let len = f.len();
        match (f_c.whole.take(), f) {
            (Some(whole), _) => LoadVector::new(whole),
            (None, LoadVector::Part { .. }) => LoadVector::part(len, f_c.nonzero()),
            (None, _) => LoadVector::from_entries(len, f_c.nonzero()),
        }
    }
}

/// A right-hand side being constrained ([`Constraints::apply_to_load`]): a whole vector, or
/// its entries by dof.
struct Entries {
    whole: Option<Vec<f64>>,
    f_c: BTreeMap<usize, f64>,
}

impl Entries {
    fn set(&mut self, dof: usize, value: f64) {
        match &mut self.whole {
            Some(whole) => whole[dof] = value,
            None => {
                self.f_c.insert(dof, value);
            }
        }
    }

    fn subtract(&mut self, dof: usize, value: f64) {
        match &mut self.whole {
            Some(whole) => whole[dof] -= value,
            None => *self.f_c.entry(dof).or_insert(0.0) -= value,
        }
    }

    /// The nonzero entries by increasing dof (of entries kept by dof).
    fn nonzero(self) -> Vec<(usize, f64)> {
        (self.f_c.into_iter()).filter(|&(_, v)| v != 0.0).collect()
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

    /// `apply_to_load` gives `apply`'s right-hand side, kept as its load is: whole, sparse, or
    /// a rank's part (right at the dofs where its load is), with the same values.
    #[test]
    fn a_load_constrained_alone_is_the_constrained_systems_right_hand_side() {
        use faer::sparse::Triplet;
        // A chain of 40 springs of stiffness 1 + i / 10 (tridiagonal), three dofs prescribed.
        let n = 40;
        let mut triplets = Vec::new();
        for i in 0..n - 1 {
            let k = 1.0 + i as f64 / 10.0;
            for (a, b, v) in [(i, i, k), (i + 1, i + 1, k), (i, i + 1, -k), (i + 1, i, -k)] {
                triplets.push(Triplet::new(a, b, v));
            }
        }
        let k = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &triplets).unwrap();
        let mut constraints = Constraints::new(n);
        for (dof, value) in [(0, 0.0), (20, 0.25), (39, -0.5)] {
            constraints.prescribe(dof, value).unwrap();
        }
        let prescribed_rows: Vec<(usize, Vec<(usize, f64)>)> = {
            let (symbolic, values) = k.parts();
            let (col_ptr, row_idx) = (symbolic.col_ptr(), symbolic.row_idx());
            (0..n)
                .filter(|&d| constraints.is_fixed(d))
                .map(|d| {
                    (
                        d,
                        (col_ptr[d]..col_ptr[d + 1])
                            .map(|p| (row_idx[p], values[p]))
                            .collect(),
                    )
                })
                .collect()
        };
        let value = |dof| constraints.value(dof).unwrap_or(0.0);
        // A load on every dof (kept whole) and one on two dofs (kept sparse).
        let loads = [
            (0..n).map(|i| 0.5 - i as f64 / 7.0).collect::<Vec<_>>(),
            (0..n)
                .map(|i| if i == 3 || i == 30 { 2.0 } else { 0.0 })
                .collect(),
        ];
        for (f, whole) in loads.iter().zip([true, false]) {
            let (_, expected) = constraints.apply(k.clone(), f);
            let load = LoadVector::new(f.clone());
            assert_eq!(matches!(load, LoadVector::Whole(_)), whole);
            let f_c = constraints.apply_to_load(&load, &prescribed_rows, value);
            assert_eq!(matches!(f_c, LoadVector::Whole(_)), whole);
            for (dof, &expected) in expected.iter().enumerate() {
                assert_eq!(f_c.get(dof), expected, "dof {dof}");
            }
            // A rank that knows the load at dofs 0 to 24 (its own and the prescribed ones).
            let known = |dof: usize| dof <= 24 || constraints.is_fixed(dof);
            let entries = (f.iter().copied().enumerate())
                .filter(|&(d, v)| known(d) && v != 0.0)
                .collect();
            let part = LoadVector::part(n, entries);
            let f_c = constraints.apply_to_load(&part, &prescribed_rows, value);
            assert!(matches!(f_c, LoadVector::Part { .. }));
            for dof in (0..n).filter(|&d| known(d)) {
                assert_eq!(f_c.get(dof), expected[dof], "dof {dof} of the part");
            }
        }
    }
}
