//! The JSON summary of a run: sizes, reactions, accuracy and timings.

use std::collections::BTreeMap;
use std::path::Path;

use serde::Serialize;

use super::OutputError;
use crate::elastic::SolveStats;

#[derive(Debug, Serialize)]
pub struct CaseSummary {
    pub case: String,
    pub mesh: String,
    pub dimension: usize,
    pub bodies: Vec<BodySummary>,
    /// Seconds per phase of the whole run, in order.
    pub timings: Vec<(String, f64)>,
}

#[derive(Debug, Serialize)]
pub struct BodySummary {
    pub name: String,
    pub youngs_modulus: f64,
    pub poisson_ratio: f64,
    pub num_nodes: usize,
    pub num_cells: usize,
    pub num_dofs: usize,
    /// First row of this body in the `/mesh/geometry` and `/fields/displacement` datasets.
    pub node_offset: usize,
    /// First row of this body in the cell datasets.
    pub cell_offset: usize,
    /// Reaction force of each Dirichlet group.
    pub reactions: BTreeMap<String, Vec<f64>>,
    pub solve: SolveStats,
}

impl CaseSummary {
    pub fn write(&self, path: &Path) -> Result<(), OutputError> {
        let text = serde_json::to_string_pretty(self).map_err(|source| OutputError::Json {
            path: path.to_owned(),
            source,
        })?;
        std::fs::write(path, text + "\n").map_err(|source| OutputError::Io {
            path: path.to_owned(),
            source,
        })
    }
}
