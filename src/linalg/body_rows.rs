//! A body's vectors as this process holds them in a solve of its own stiffness: whole, in our
//! numbering, on one process; on a rank of a distributed run, this rank's rows alone in
//! PETSc's order ([`Distribution`]), so that no rank holds a vector of the body's size.
//!
//! What a solve of one body reads of its vectors besides the solver's products: the
//! right-hand side from a load vector, the columns of the force-controlled components
//! (sparse), inner products with those columns, norms, and the answer at the nodes the rank's
//! mesh keeps. Each sum over a distributed vector is every rank's partial sum added in rank
//! order (`MPI_Allgatherv` of the partials), so that every rank holds the same bits. On one
//! process every value is what the whole vector gives, in the same order of summation.

use super::{Distribution, LinalgError, relative_difference};
use crate::fem::LoadVector;
use crate::mesh::NodeCoords;

/// How this process holds a body's vectors in a solve (the module doc).
#[derive(Debug, Clone, Copy)]
pub struct BodyRows<'a> {
    /// The body's distribution on a rank of a distributed run; `None` on one process.
    distribution: Option<&'a Distribution>,
    /// The body's unknowns.
    num_dofs: usize,
}

impl<'a> BodyRows<'a> {
    /// The vectors of a body of `num_dofs` unknowns, shared as `distribution` says (whole
    /// where `None`).
    pub fn new(distribution: Option<&'a Distribution>, num_dofs: usize) -> Self {
        Self {
            distribution,
            num_dofs,
        }
    }

    /// The values this process holds of a vector.
    pub fn len(&self) -> usize {
        self.distribution.map_or(self.num_dofs, Distribution::local)
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Where this process holds unknown `dof` (our numbering), if it holds it.
    pub fn row(&self, dof: usize) -> Option<usize> {
        match self.distribution {
            None => (dof < self.num_dofs).then_some(dof),
            Some(distribution) => distribution.own_row(dof),
        }
    }

    /// This process's values of `load`.
    pub fn of_load(&self, load: &LoadVector) -> Vec<f64> {
        match self.distribution {
            None => load.to_vec(),
            Some(distribution) => distribution.own().map(|dof| load.get(dof)).collect(),
        }
    }

    /// This process's values of the vector whose nonzero entries are `entries` (dof, value).
    pub fn of_entries(&self, entries: &[(usize, f64)]) -> Vec<f64> {
        let mut values = vec![0.0; self.len()];
        for &(dof, value) in entries {
            if let Some(row) = self.row(dof) {
                values[row] = value;
            }
        }
        values
    }

    /// This process's part of `sum value x[dof]` over `entries` (dof, value), in their order;
    /// [`Self::sum_over_ranks`] completes it.
    pub fn dot_entries(&self, entries: &[(usize, f64)], x: &[f64]) -> f64 {
        (entries.iter())
            .filter_map(|&(dof, value)| self.row(dof).map(|row| value * x[row]))
            .sum()
    }

    /// Every rank's `partials` added entry by entry in rank order, on every rank (collective);
    /// `partials` itself on one process.
    pub fn sum_over_ranks(&self, partials: Vec<f64>) -> Result<Vec<f64>, LinalgError> {
        let Some(distribution) = self.distribution else {
            return Ok(partials);
        };
        let ranks = distribution.counts().len();
        let every = crate::parallel::all_gather(&partials, &vec![partials.len(); ranks])
            .map_err(|e| LinalgError::Mpi(e.to_string()))?;
        let mut sums = vec![0.0; partials.len()];
        for rank in every.chunks_exact(partials.len().max(1)) {
            sums.iter_mut().zip(rank).for_each(|(sum, v)| *sum += v);
        }
        Ok(sums)
    }

    /// `||ax - b|| / ||b||` (`||ax||` when `b = 0`) of two vectors held this way
    /// (collective): `crate::linalg::relative_difference` of the whole vectors.
    pub fn relative_difference(&self, ax: &[f64], b: &[f64]) -> Result<f64, LinalgError> {
        if self.distribution.is_none() {
            return Ok(relative_difference(ax, b));
        }
        let difference = ax.iter().zip(b).map(|(p, q)| (p - q).powi(2)).sum::<f64>();
        let norm = b.iter().map(|v| v * v).sum::<f64>();
        let sums = self.sum_over_ranks(vec![difference, norm])?;
        let (r, nb) = (sums[0].sqrt(), sums[1].sqrt());
        Ok(if nb > 0.0 { r / nb } else { r })
    }

    /// The values of `x` (held this way, `dim` a node) at the nodes whose coordinates `coords`
    /// keeps, in their order (`NodeCoords::kept_values`; collective): on a rank, its own rows'
    /// and the others' from their owners (`Distribution::at_read_nodes`).
    pub fn at_kept_nodes(
        &self,
        x: Vec<f64>,
        coords: &NodeCoords,
        dim: usize,
    ) -> Result<Vec<f64>, LinalgError> {
        match self.distribution {
            None => Ok(coords.kept_values(x, dim)),
            Some(distribution) => distribution.at_read_nodes(&x),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_process_reads_the_whole_vector() {
        // Without a distribution every dof is held where it is, and the sums are the whole
        // vector's.
        let rows = BodyRows::new(None, 4);
        assert_eq!(rows.len(), 4);
        assert_eq!(rows.row(3), Some(3));
        assert_eq!(rows.row(4), None);
        let load = LoadVector::from_entries(4, vec![(1, 2.0)]);
        assert_eq!(rows.of_load(&load), vec![0.0, 2.0, 0.0, 0.0]);
        let column = [(0, 1.5), (3, -2.0)];
        assert_eq!(rows.of_entries(&column), vec![1.5, 0.0, 0.0, -2.0]);
        assert_eq!(rows.dot_entries(&column, &[2.0, 9.0, 9.0, 1.0]), 1.0);
        assert_eq!(
            rows.sum_over_ranks(vec![1.0, -3.0]).unwrap(),
            vec![1.0, -3.0]
        );
        let (ax, b) = ([1.0, 2.0, 2.0, 0.0], [1.0, 2.0, 2.0, 3.0]);
        assert_eq!(
            rows.relative_difference(&ax, &b).unwrap(),
            3.0 / 18f64.sqrt()
        );
    }
}
