//! A vector of nodal forces on a body as it is kept beyond the moment it is made: the load
//! vector `f` and the constrained right-hand side `f_c` after assembly, and the forces the
//! contact interfaces put on a body (`crate::contact::coupled::system::CoupledSolution`).
//!
//! Most contact cases load a body through its supports and its contacts, not through loads:
//! `f` is then zero, `f_c` is nonzero only at the prescribed dofs and their neighbours, and the
//! contact forces only at the interface's nodes. Kept whole, each would cost every rank 8 bytes
//! per unknown of the body (at 1M unknowns 8 MB a vector, at 100M 800 MB). So a vector with
//! few nonzero entries keeps only those; one that most dofs load (a body force) is kept whole.
//!
//! A body force loads most dofs, and in a distributed run a rank keeps only the cells around
//! its own nodes (and the prescribed ones): it knows the force there only, and keeps a
//! [`LoadVector::Part`], the entries of those dofs, which are all it reads (its rows of the
//! system and the reactions at the prescribed dofs). Gathered whole, `f` and `f_c` would cost
//! every rank 16 bytes per unknown of the body for the whole run.
//!
//! Every value read from it is the one the whole vector gives, to the bit: a missing entry
//! reads as `0.0`, and [`LoadVector::scaled`] writes `s * 0.0` there as the whole vector's
//! product would (`-0.0` for a negative `s`); [`LoadVector::component_sum`] adds the entries
//! in the whole vector's order, and its zeros change no partial sum. Only the sign of a zero
//! can differ, where [`LoadVector::add_scaled_to`] skips the zeros.

/// A load vector (the module doc).
#[derive(Debug, Clone, PartialEq)]
pub enum LoadVector {
    /// Every entry.
    Whole(Vec<f64>),
    /// The entries that are not zero, by increasing dof, of a vector of `len` entries.
    Sparse {
        len: usize,
        entries: Vec<(usize, f64)>,
    },
    /// A rank's part of a vector of `len` entries (the module doc): the nonzero entries at
    /// the dofs whose value this rank knows, by increasing dof. It reads as the vector that is
    /// zero elsewhere, so only those dofs may be read from it.
    Part {
        len: usize,
        entries: Vec<(usize, f64)>,
    },
}

impl LoadVector {
    /// `whole`, kept sparse when at most a quarter of its entries are not zero (an entry
    /// kept sparse takes 16 bytes against 8, so half would only break even).
    pub fn new(whole: Vec<f64>) -> Self {
        let nonzero = whole.iter().filter(|&&v| v != 0.0).count();
        if 4 * nonzero > whole.len() {
            return Self::Whole(whole);
        }
        let entries = (whole.iter().copied().enumerate())
            .filter(|&(_, v)| v != 0.0)
            .collect();
        Self::Sparse {
            len: whole.len(),
            entries,
        }
    }

    /// The vector of `len` entries whose nonzero entries are `entries` (by increasing dof),
    /// kept as [`Self::new`] keeps it.
    pub fn from_entries(len: usize, entries: Vec<(usize, f64)>) -> Self {
        debug_assert!(
            entries.windows(2).all(|w| w[0].0 < w[1].0),
            "dofs increasing"
        );
        debug_assert!(entries.iter().all(|&(_, v)| v != 0.0), "nonzero entries");
        if 4 * entries.len() > len {
            let mut whole = vec![0.0; len];
            for (dof, value) in entries {
                whole[dof] = value;
            }
            return Self::Whole(whole);
        }
        Self::Sparse { len, entries }
    }

    /// A rank's part of a vector of `len` entries: its nonzero `entries` (by increasing dof) at
    /// the dofs whose values it knows, never made whole.
    pub fn part(len: usize, entries: Vec<(usize, f64)>) -> Self {
        debug_assert!(
            entries.windows(2).all(|w| w[0].0 < w[1].0),
            "dofs increasing"
        );
        Self::Part { len, entries }
    }

    /// The number of entries (the body's dofs).
    pub fn len(&self) -> usize {
        match self {
            Self::Whole(whole) => whole.len(),
            Self::Sparse { len, .. } | Self::Part { len, .. } => *len,
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The entry at `dof`.
    pub fn get(&self, dof: usize) -> f64 {
        match self {
            Self::Whole(whole) => whole[dof],
            Self::Sparse { entries, .. } | Self::Part { entries, .. } => entries
                .binary_search_by_key(&dof, |&(d, _)| d)
                .map_or(0.0, |k| entries[k].1),
        }
    }

    /// The entry at `dof` as it is kept: `None` where a sparse vector keeps none (what
    /// [`Self::add_scaled_to`] skips).
    pub fn kept_entry(&self, dof: usize) -> Option<f64> {
        match self {
            Self::Whole(whole) => Some(whole[dof]),
            Self::Sparse { entries, .. } | Self::Part { entries, .. } => entries
                .binary_search_by_key(&dof, |&(d, _)| d)
                .ok()
                .map(|k| entries[k].1),
        }
    }

    /// The entries that are not zero, by increasing dof.
    pub fn nonzero_entries(&self) -> Box<dyn Iterator<Item = (usize, f64)> + '_> {
        match self {
            Self::Whole(whole) => {
                Box::new((whole.iter().copied().enumerate()).filter(|&(_, v)| v != 0.0))
            }
            Self::Sparse { entries, .. } | Self::Part { entries, .. } => {
                Box::new(entries.iter().copied())
            }
        }
    }

    /// The whole vector.
    pub fn to_vec(&self) -> Vec<f64> {
        self.scaled(1.0)
    }

    /// `s v`, whole.
    pub fn scaled(&self, s: f64) -> Vec<f64> {
        match self {
            Self::Whole(whole) => whole.iter().map(|v| s * v).collect(),
            Self::Sparse { len, entries } | Self::Part { len, entries } => {
                let mut out = vec![s * 0.0; *len];
                for &(d, v) in entries {
                    out[d] = s * v;
                }
                out
            }
        }
    }

    /// `out += s v`. The zeros it skips would add `±0.0`, which changes no entry but a `-0.0`
    /// (to `+0.0`).
    pub fn add_scaled_to(&self, s: f64, out: &mut [f64]) {
        match self {
            Self::Whole(whole) => out.iter_mut().zip(whole).for_each(|(o, v)| *o += s * v),
            Self::Sparse { entries, .. } | Self::Part { entries, .. } => {
                for &(d, v) in entries {
                    out[d] += s * v;
                }
            }
        }
    }

    /// The sum of the entries of component `c` (`dim` components per node), in dof order: the
    /// whole vector's sum to the bit (`+ 0.0` turns the empty sum's `-0.0` into the `+0.0`
    /// that the whole vector's zeros sum to, and changes no other sum). Of a [`Self::Part`],
    /// the sum of the entries it keeps, which several ranks may keep: not the vector's sum,
    /// which the ranks' sums over their own dofs make (the assembly's `load_sums`).
    pub fn component_sum(&self, c: usize, dim: usize) -> f64 {
        match self {
            Self::Whole(whole) => whole.iter().skip(c).step_by(dim).sum(),
            Self::Sparse { entries, .. } | Self::Part { entries, .. } => {
                let sum: f64 = (entries.iter())
                    .filter(|&&(d, _)| d % dim == c)
                    .map(|&(_, v)| v)
                    .sum();
                sum + 0.0
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Kept sparse or whole, every value read is the whole vector's, bit for bit.
    #[test]
    fn a_vector_kept_sparse_or_whole_reads_as_the_whole_one() {
        let few = vec![0.0, 0.0, 1.5, 0.0, 0.0, 0.0, -2.25, 0.0, 0.0, 0.0, 0.0, 0.0];
        let most: Vec<f64> = (0..12)
            .map(|k| if k == 5 { 0.0 } else { k as f64 - 3.5 })
            .collect();
        for (whole, sparse) in [(few, true), (most, false)] {
            let kept = LoadVector::new(whole.clone());
            assert_eq!(matches!(kept, LoadVector::Sparse { .. }), sparse);
            assert_eq!(kept.len(), whole.len());
            for (d, v) in whole.iter().enumerate() {
                assert_eq!(kept.get(d).to_bits(), v.to_bits());
            }
            for s in [2.0, -0.5] {
                let expected: Vec<u64> = whole.iter().map(|v| (s * v).to_bits()).collect();
                let scaled: Vec<u64> = kept.scaled(s).iter().map(|v| v.to_bits()).collect();
                assert_eq!(scaled, expected);
                let mut out = vec![0.0; whole.len()];
                kept.add_scaled_to(s, &mut out);
                let mut expected = vec![0.0; whole.len()];
                (expected.iter_mut().zip(&whole)).for_each(|(o, v)| *o += s * v);
                assert_eq!(out, expected);
            }
            let nonzero: Vec<(usize, f64)> = (whole.iter().copied().enumerate())
                .filter(|&(_, v)| v != 0.0)
                .collect();
            assert_eq!(kept.nonzero_entries().collect::<Vec<_>>(), nonzero);
            // A sparse vector keeps its nonzero entries; a whole one every entry.
            for (d, v) in whole.iter().enumerate() {
                let kept_here = !sparse || *v != 0.0;
                assert_eq!(kept.kept_entry(d), kept_here.then_some(*v));
            }
            for c in 0..3 {
                let expected: f64 = whole.iter().skip(c).step_by(3).sum();
                assert_eq!(kept.component_sum(c, 3).to_bits(), expected.to_bits());
            }
        }
    }
}
