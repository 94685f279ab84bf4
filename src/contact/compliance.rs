//! The interface compliance of a body: the block of `K_c^-1` on its candidate-surface dofs,
//! `G[a, b] = (K_c^-1)[a, b]`, the displacement at dof `a` under a unit load at dof `b`.
//!
//! An active-set iteration needs `Y = K^-1 B` only where the constraint rows `C` read it, and
//! both the rows of `B` (the interface forces) and the columns of `C` (the interface
//! displacements) are candidate-surface dofs, so `C K^-1 B = C G B`. From one iteration or
//! load step to the next the active set changes by a few nodes: a column of `G` is computed
//! (one solve with the body's Cholesky factor) the first time a dof is loaded, and kept for
//! every later iteration and load step. The alternative, `m` solves per iteration for `Y`,
//! redoes the same solves every time.

use std::collections::{BTreeSet, HashMap};

use crate::linalg::Cholesky;

/// Columns of `G`, computed on demand. Rows are the candidate-surface dofs of the body.
pub struct SurfaceCompliance {
    /// Row of `G` of each body dof (`usize::MAX` off the candidate surface).
    row: Vec<usize>,
    /// Body dof of each row.
    surface_dofs: Vec<usize>,
    /// Column of `G` (all its rows) of each loaded dof.
    columns: HashMap<usize, Vec<f64>>,
}

impl SurfaceCompliance {
    /// An empty cache for the candidate surface `surface_nodes` (body nodes) of a body with
    /// `num_dofs` dofs, `dim` per node.
    pub fn new(surface_nodes: &[usize], dim: usize, num_dofs: usize) -> Self {
        let surface_dofs: Vec<usize> = surface_nodes
            .iter()
            .flat_map(|&node| (0..dim).map(move |c| dim * node + c))
            .collect();
        let mut row = vec![usize::MAX; num_dofs];
        for (r, &dof) in surface_dofs.iter().enumerate() {
            row[dof] = r;
        }
        Self {
            row,
            surface_dofs,
            columns: HashMap::new(),
        }
    }

    /// Computes the columns of the `dofs` not known yet, with one multi-right-hand-side solve;
    /// returns how many were new.
    ///
    /// # Panics
    /// If a dof is off the candidate surface (the coupling only loads surface dofs).
    pub fn extend(&mut self, factor: &Cholesky, dofs: impl IntoIterator<Item = usize>) -> usize {
        let missing: BTreeSet<usize> = dofs
            .into_iter()
            .filter(|dof| !self.columns.contains_key(dof))
            .collect();
        if missing.is_empty() {
            return 0;
        }
        // In chunks, so that the right-hand sides of a large first active set fit in memory.
        const CHUNK: usize = 64;
        let n = self.row.len();
        let missing: Vec<usize> = missing.into_iter().collect();
        for chunk in missing.chunks(CHUNK) {
            let mut rhs = vec![0.0; n * chunk.len()];
            for (k, &dof) in chunk.iter().enumerate() {
                assert!(
                    self.row[dof] != usize::MAX,
                    "dof {dof} is not on the candidate surface"
                );
                rhs[k * n + dof] = 1.0;
            }
            factor.solve_in_place(&mut rhs, chunk.len());
            for (k, &dof) in chunk.iter().enumerate() {
                let full = &rhs[k * n..(k + 1) * n];
                let column = self.surface_dofs.iter().map(|&d| full[d]).collect();
                self.columns.insert(dof, column);
            }
        }
        missing.len()
    }

    /// `G[a, b]`; the column of `b` must have been computed by [`Self::extend`].
    pub fn entry(&self, a: usize, b: usize) -> f64 {
        self.columns[&b][self.row[a]]
    }
}
