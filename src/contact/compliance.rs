//! The interface response of a body to each multiplier: `Y_k = K_c^-1 b_k`, `b_k` the force
//! that a unit multiplier `k` puts on the body (its column of the coupling block `B`, without
//! the system's scaling), kept on the body's candidate-surface dofs.
//!
//! An active-set iteration needs `K^-1 B` only where the constraint rows `C` read it, and the
//! columns of `C` (the interface displacements) are candidate-surface dofs, so the Schur
//! complement is `D - s C Y` with `Y = [Y_k]` restricted to those dofs. While the operators
//! stay as built (`super::interface`), `b_k` depends only on which primary node (and
//! component, for tied contact) multiplier `k` belongs to: `Y_k` is computed (one solve with
//! the body's Cholesky factor) the first time that node is active, and kept for every later
//! iteration and load step, until the operators are paired again.
//!
//! One solve per multiplier, rather than one per loaded dof: the secondary's column `M2 R21 e_k`
//! loads every secondary node the interpolation reaches, nearly the whole facing surface
//! (the rows of `R12` and columns of `R21` are dense over it), so a dof-by-dof compliance
//! needs about `dim` times the facing secondary nodes in solves, against one per active node.

use std::collections::HashMap;

use crate::linalg::Cholesky;

/// Identifies a multiplier across iterations: the primary body node it acts at, and its
/// component (tied) or `None` (frictionless: one normal multiplier per node).
pub type MultiplierKey = (usize, Option<usize>);

/// The responses `Y_k` of one body computed so far, on its candidate-surface dofs.
pub struct SurfaceResponse {
    /// Row of each body dof in a stored response (`usize::MAX` off the candidate surface).
    row: Vec<usize>,
    /// Body dof of each row.
    surface_dofs: Vec<usize>,
    responses: HashMap<MultiplierKey, Vec<f64>>,
}

impl SurfaceResponse {
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
            responses: HashMap::new(),
        }
    }

    /// Forgets every response: the interface operators they were computed with changed.
    pub fn clear(&mut self) {
        self.responses.clear();
    }

    /// Whether the response of `key` is known.
    pub fn contains(&self, key: &MultiplierKey) -> bool {
        self.responses.contains_key(key)
    }

    /// Computes and keeps the responses to the `loads` (each a key and its sparse body force
    /// `(dof, value)`), with multi-right-hand-side solves; a key already known is skipped.
    pub fn extend(&mut self, factor: &Cholesky, loads: &[(MultiplierKey, Vec<(usize, f64)>)]) {
        // In chunks, so that the right-hand sides of a large first active set fit in memory.
        const CHUNK: usize = 64;
        let n = self.row.len();
        let missing: Vec<&(MultiplierKey, Vec<(usize, f64)>)> = loads
            .iter()
            .filter(|(key, _)| !self.contains(key))
            .collect();
        for chunk in missing.chunks(CHUNK) {
            let mut rhs = vec![0.0; n * chunk.len()];
            for (j, (_, load)) in chunk.iter().enumerate() {
                for &(dof, value) in load {
                    rhs[j * n + dof] += value;
                }
            }
            factor.solve_in_place(&mut rhs, chunk.len());
            for (j, (key, _)) in chunk.iter().enumerate() {
                let full = &rhs[j * n..(j + 1) * n];
                let response = self.surface_dofs.iter().map(|&d| full[d]).collect();
                self.responses.insert(*key, response);
            }
        }
    }

    /// The rows of the stored responses that hold the body dofs `dofs`.
    ///
    /// # Panics
    /// If a dof is off the candidate surface (the constraint rows only read surface dofs).
    pub fn rows(&self, dofs: &[usize]) -> Vec<usize> {
        dofs.iter()
            .map(|&dof| {
                let row = self.row[dof];
                assert!(
                    row != usize::MAX,
                    "dof {dof} is not on the candidate surface"
                );
                row
            })
            .collect()
    }

    /// `Y_key` at the stored rows `rows` (from [`Self::rows`]), into `out`; the response must
    /// have been computed by [`Self::extend`].
    pub fn gather(&self, key: &MultiplierKey, rows: &[usize], out: &mut [f64]) {
        let response = &self.responses[key];
        for (value, &row) in out.iter_mut().zip(rows) {
            *value = response[row];
        }
    }
}
