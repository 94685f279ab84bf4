//! How one body's unknowns are shared among the ranks of a distributed run.
//!
//! The body's nodes are split into one part per rank by METIS (`METIS_PartGraphKway` on the
//! node graph of the matrix: parts of nearly equal size with few edges between them, so that a
//! matrix-vector product or a V-cycle exchanges little). PETSc owns its rows by contiguous
//! ranges, so PETSc's numbering puts the nodes of rank 0 first, then those of rank 1, and so
//! on, each in our order, each node's `dim` unknowns together (the block structure GAMG
//! aggregates by). Every rank computes the same partition (METIS is deterministic for a given
//! graph), and keeps of the matrix only its own rows.
//!
//! Vectors cross between the two numberings here: [`Distribution::local_part`] takes this
//! rank's rows out of a whole vector in our numbering, [`Distribution::gather`] puts every
//! rank's rows back into one whole vector on every rank (`MPI_Allgatherv`).

use faer::sparse::SparseColMat;

use super::{LinalgError, gather_values};
use crate::linalg::ordering::partition;
use crate::parallel::Ranks;

pub struct Distribution {
    /// Our unknown at each of PETSc's rows: `ours[p]`.
    ours: Vec<usize>,
    /// The rows of each rank (unknowns), in rank order.
    counts: Vec<usize>,
    /// PETSc's first row of this rank.
    first: usize,
    /// This rank's number of rows.
    local: usize,
}

impl Distribution {
    /// The distribution of the unknowns of `matrix` (symmetric, `dim` unknowns per node,
    /// interleaved) over `ranks`.
    pub fn new(
        matrix: &SparseColMat<usize, f64>,
        dim: usize,
        ranks: Ranks,
    ) -> Result<Self, LinalgError> {
        let (symbolic, _) = matrix.parts();
        let nodes = symbolic.ncols() / dim;
        let (col_ptr, row_idx) = (symbolic.col_ptr(), symbolic.row_idx());
        // The node graph: node a's neighbours are the nodes of the entries of its first
        // unknown's column (every node's dim x dim blocks are stored whole).
        let mut neighbours: Vec<Vec<usize>> = Vec::with_capacity(nodes);
        for a in 0..nodes {
            let column = a * dim;
            let mut adjacent: Vec<usize> = (col_ptr[column]..col_ptr[column + 1])
                .map(|p| row_idx[p] / dim)
                .filter(|&b| b != a)
                .collect();
            adjacent.dedup();
            neighbours.push(adjacent);
        }
        let part = partition(&neighbours, ranks.size)?;
        let mut ours = Vec::with_capacity(nodes * dim);
        let mut counts = vec![0; ranks.size];
        for (rank, count) in counts.iter_mut().enumerate() {
            for node in (0..nodes).filter(|&a| part[a] == rank) {
                ours.extend((0..dim).map(|c| node * dim + c));
                *count += dim;
            }
        }
        let first = counts[..ranks.rank].iter().sum();
        Ok(Self {
            ours,
            counts: counts.clone(),
            first,
            local: counts[ranks.rank],
        })
    }

    /// Each rank's number of unknowns, in rank order.
    pub fn counts(&self) -> &[usize] {
        &self.counts
    }

    /// This rank's number of unknowns.
    pub fn local(&self) -> usize {
        self.local
    }

    /// This rank's rows of `matrix` in PETSc's numbering, as compressed rows (row pointers
    /// from 0, global column indices sorted in each row, values), with the coordinates of its
    /// nodes (`coords`: `dim` values per node, in our order).
    pub fn local_rows(
        &self,
        matrix: &SparseColMat<usize, f64>,
        coords: &[f64],
    ) -> (Vec<i64>, Vec<i64>, Vec<f64>, Vec<f64>) {
        let (symbolic, values) = matrix.parts();
        let (col_ptr, row_idx) = (symbolic.col_ptr(), symbolic.row_idx());
        let mut petsc_of = vec![0usize; self.ours.len()];
        for (p, &ours) in self.ours.iter().enumerate() {
            petsc_of[ours] = p;
        }
        let rows = &self.ours[self.first..self.first + self.local];
        let mut row_ptr = Vec::with_capacity(rows.len() + 1);
        let mut columns = Vec::new();
        let mut entries = Vec::new();
        let mut row: Vec<(i64, f64)> = Vec::new();
        row_ptr.push(0i64);
        for &ours in rows {
            // Row `ours` of the symmetric matrix is its column `ours`.
            row.clear();
            row.extend(
                (col_ptr[ours]..col_ptr[ours + 1])
                    .map(|p| (petsc_of[row_idx[p]] as i64, values[p])),
            );
            row.sort_unstable_by_key(|&(column, _)| column);
            columns.extend(row.iter().map(|&(column, _)| column));
            entries.extend(row.iter().map(|&(_, value)| value));
            row_ptr.push(columns.len() as i64);
        }
        let local_coords = rows.iter().map(|&ours| coords[ours]).collect();
        (row_ptr, columns, entries, local_coords)
    }

    /// This rank's rows of `whole` (our numbering), in PETSc's order.
    pub fn local_part(&self, whole: &[f64]) -> Vec<f64> {
        self.ours[self.first..self.first + self.local]
            .iter()
            .map(|&ours| whole[ours])
            .collect()
    }

    /// Every rank's `local` rows (PETSc's order) into `whole` (our numbering), on every rank.
    pub fn gather(&self, local: &[f64], whole: &mut [f64]) -> Result<(), LinalgError> {
        let petsc = gather_values(local, &self.counts)?;
        for (&ours, value) in self.ours.iter().zip(petsc) {
            whole[ours] = value;
        }
        Ok(())
    }
}
