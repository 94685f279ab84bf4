//! The interface response of a body to a unit traction: `Y_(i,c) = K_c^-1 b_(i,c)`, `b_(i,c)`
//! the force that a unit traction of component `c` at active primary node `i` puts on the body
//! (through the lumped mass on body 1, the transfer on body 2, without the system's scaling),
//! kept on the body's candidate-surface dofs. A multiplier's response is their combination:
//! tied, one component; frictionless, `sum_c n_c Y_(i,c)` along its normal `n`.
//!
//! An active-set iteration needs `K^-1 B` only where the constraint rows `C` read it, and the
//! columns of `C` (the interface displacements) are candidate-surface dofs, so the Schur
//! complement is `D - s C Y` with `Y = [Y_k]` restricted to those dofs. While the operators
//! stay as built (`crate::contact::coupled::interface`), `b_(i,c)` depends only on the node and the
//! component: it is computed (one solve with the body's solver per component) the first time
//! the node is active, and kept for every later iteration and load step, until the operators
//! are paired again; a response is kept with a fingerprint of the load it answers, and a load
//! that changed is solved again (under the node-to-facet transfer the secondary's load is the
//! P1 weights of the node's closest point, which move with every iterate). Per component, not
//! per multiplier: the frictionless traction acts along
//! the normal of the secondary facet the node is held on (`crate::contact::geometry::gap`), which
//! turns with the displacement from one iteration to the next; the price is `dim` solves per
//! node instead of one.
//!
//! One solve per node and component, rather than one per loaded dof: the secondary's column
//! `M2 R21 e_k` loads every secondary node the interpolation reaches, nearly the whole facing
//! surface (the rows of `R12` and columns of `R21` are dense over it), so a dof-by-dof
//! compliance needs about `dim` times the facing secondary nodes in solves.
//!
//! A force-controlled group's unknown displacement `a` is handled like a multiplier: its
//! column `k` (`crate::elastic::RigidColumn`) is a unit load of its own, whose response is
//! kept beside the tractions' on the dofs its row reads.

use std::collections::HashMap;
use std::hash::{DefaultHasher, Hash, Hasher};

use crate::contact::ContactError;
use crate::linalg::BodySolver;

/// Identifies a unit load across iterations
/// (`crate::contact::coupled::system::CoupledSystem::columns` combines them into the columns of the
/// multiplier block).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MultiplierKey {
    /// A unit traction of `component` at the primary body node `node` of contact pair `pair`.
    Traction {
        pair: usize,
        node: usize,
        component: usize,
    },
    /// The displacement of the force-controlled component `index` of body `body`
    /// (`crate::elastic::RigidColumn`), whose column in the body's rows is `k`: `K_c u + k a =
    /// f_c`.
    Rigid { body: usize, index: usize },
}

/// The responses `Y_k` of one body computed so far, on its candidate-surface dofs.
pub struct SurfaceResponse {
    /// Row of each body dof in a stored response (`usize::MAX` off the candidate surface).
    row: Vec<usize>,
    /// Body dof of each row.
    surface_dofs: Vec<usize>,
    /// Each response with the fingerprint of its load ([`fingerprint`]).
    responses: HashMap<MultiplierKey, (u64, Vec<f64>)>,
}

/// A hash of a sparse load `(dof, value)`, entry by entry: two loads with the same fingerprint
/// are taken as the same (a collision of 64-bit hashes is beyond any run's count of loads).
fn fingerprint(load: &[(usize, f64)]) -> u64 {
    let mut hasher = DefaultHasher::new();
    for &(dof, value) in load {
        (dof, value.to_bits()).hash(&mut hasher);
    }
    hasher.finish()
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
    /// `(dof, value)`; empty where the force does not reach the body, whose response is then
    /// dropped), with multi-right-hand-side solves; a key known with the same load is skipped.
    pub fn extend(
        &mut self,
        factor: &BodySolver,
        loads: &[(MultiplierKey, Vec<(usize, f64)>)],
    ) -> Result<(), ContactError> {
        // In chunks, so that the right-hand sides of a large first active set fit in memory.
        const CHUNK: usize = 64;
        let n = self.row.len();
        for (key, _) in loads.iter().filter(|(_, load)| load.is_empty()) {
            self.responses.remove(key);
        }
        let missing: Vec<_> = (loads.iter())
            .filter(|(_, load)| !load.is_empty())
            .map(|(key, load)| (fingerprint(load), key, load))
            .filter(|(print, key, _)| (self.responses.get(key)).is_none_or(|(f, _)| f != print))
            .collect();
        for chunk in missing.chunks(CHUNK) {
            let mut rhs = vec![0.0; n * chunk.len()];
            for (j, (_, _, load)) in chunk.iter().enumerate() {
                for &(dof, value) in load.iter() {
                    rhs[j * n + dof] += value;
                }
            }
            factor
                .solve_in_place(&mut rhs, chunk.len())
                .map_err(|e| ContactError::Linalg(format!("a body's response: {e}")))?;
            for (j, &(print, key, _)) in chunk.iter().enumerate() {
                let full = &rhs[j * n..(j + 1) * n];
                let response = self.surface_dofs.iter().map(|&d| full[d]).collect();
                self.responses.insert(*key, (print, response));
            }
        }
        Ok(())
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
        let (_, response) = &self.responses[key];
        for (value, &row) in out.iter_mut().zip(rows) {
            *value = response[row];
        }
    }
}
