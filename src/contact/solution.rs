//! How a contact solve ended, and what it found.

use serde::Serialize;

use super::solve::Candidates;
use crate::elastic::ElasticSolution;

/// How the active-set loop ended. Only `Converged` is a contact solution; the others carry the
/// last iterate so that it can be inspected.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ContactStatus {
    /// No active node in tension, no candidate node penetrating beyond the tolerance.
    Converged,
    /// The candidate surfaces never come within interpolation range: each body was solved
    /// alone.
    NoContact,
    /// The iteration cap was reached.
    IterationLimit,
    /// An active set seen before came back: the loop would repeat forever.
    Cycling,
}

/// One line of the iteration history.
#[derive(Debug, Clone, Serialize)]
pub struct IterationRecord {
    pub iteration: usize,
    pub active_primary: usize,
    pub active_secondary: usize,
    pub added: usize,
    pub removed: usize,
    /// Largest penetration of an inactive candidate node, absolute and relative to its
    /// spacing h.
    pub max_penetration: f64,
    pub max_penetration_over_h: f64,
    /// Largest tension (negative mean pressure) of an active node (0 when none is in tension).
    pub max_tension: f64,
    pub relative_residual: f64,
    pub seconds: f64,
}

/// Interface fields on a candidate surface, one entry per surface node.
#[derive(Debug, Clone, Default)]
pub struct SurfaceFields {
    /// Body-local node of each surface node.
    pub nodes: Vec<usize>,
    /// Contact traction on this body (zero at inactive nodes).
    pub traction: Vec<[f64; 3]>,
    /// Contact pressure `p = -traction . n` (positive in compression), nodal values of the P1
    /// field.
    pub pressure: Vec<f64>,
    /// The pressure averaged over each node's patch with the node's hat function as weight
    /// ([`super::ContactSurface::mean_pressure`]): the quantity the tension check uses. Nonzero
    /// also at the inactive neighbours of active nodes, which the P1 traction reaches.
    pub mean_pressure: Vec<f64>,
    /// Gap to the other surface along the outward normal, deformed configuration (NaN where
    /// the other surface is out of interpolation range).
    pub normal_gap: Vec<f64>,
    pub active: Vec<bool>,
}

/// Least-squares fit of the Hertz ellipse `p^2 = p0^2 (1 - r^2 / a^2)` to the mean pressures of
/// the active nodes.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct HertzFit {
    /// Contact radius (3D) or half-width (2D).
    pub a: f64,
    pub p0: f64,
    /// Centre of the contact zone (mean-pressure-weighted centroid of the active nodes).
    pub center: [f64; 3],
}

/// Everything a contact solve produces.
pub struct ContactSolution {
    pub status: ContactStatus,
    pub history: Vec<IterationRecord>,
    pub primary: ElasticSolution,
    pub secondary: ElasticSolution,
    pub primary_fields: SurfaceFields,
    pub secondary_fields: SurfaceFields,
    /// Total contact force on each body, and `|F1 + F2| / |F1|`.
    pub force_primary: [f64; 3],
    pub force_secondary: [f64; 3],
    pub force_imbalance: f64,
    /// Largest tangential traction `|lambda - (lambda . n) n|` on the primary surface: zero
    /// for frictionless contact, the shear the glue carries for tied contact.
    pub max_tangential_traction: f64,
    pub hertz_primary: Option<HertzFit>,
    /// The factor the loads and prescribed displacements were scaled by.
    pub load_factor: f64,
    /// The candidate sets at the end, from which a next load step starts.
    pub candidates: Candidates,
}
