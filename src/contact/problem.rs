//! What to solve: two elastic bodies, their candidate surfaces, and how to treat the contact.

use serde::{Deserialize, Serialize};

use super::ContactSurface;
use super::coupled_solver::CoupledSolver;
use crate::elastic::ElasticProblem;

/// Which constraint couples the active surfaces (README, "Contact formulations").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Formulation {
    /// Normal constraint only, one scalar multiplier per primary node: surfaces may slide.
    #[default]
    Frictionless,
    /// Vector constraint (the seed's system): active surfaces are glued together.
    Tied,
}

/// Settings of the active-set loop; every field has a documented default.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ContactSettings {
    /// Default: frictionless.
    pub formulation: Formulation,
    /// How each iteration's linear system is solved (default: Schur complement on Cholesky
    /// factors computed once).
    pub solver: CoupledSolver,
    /// Cap on active-set iterations (default 50); reaching it is a status, not an error.
    pub max_iterations: usize,
    /// A candidate node penetrates when its gap along its normal is below `-tol * h`, `h` its
    /// distance to the nearest node of its own surface (default 1e-3).
    pub penetration_tolerance: f64,
    /// An active node is in tension when its mean pressure (the contact pressure averaged over
    /// its patch, see [`ContactSurface::mean_pressure`]) is below `-tol * p_max`, `p_max` the
    /// largest mean pressure of the iteration (default 1e-8).
    pub tension_tolerance: f64,
    /// Support radius of each node's RBF in the transfer operators, in units of the distance
    /// to its nearest node (default 2, the radius seed Algorithm 1 starts from; see
    /// [`crate::contact::rbf::interpolation_radii`] for the measurements behind it).
    pub rbf_radius: f64,
}

impl Default for ContactSettings {
    fn default() -> Self {
        Self {
            formulation: Formulation::default(),
            solver: CoupledSolver::default(),
            max_iterations: 50,
            penetration_tolerance: 1e-3,
            tension_tolerance: 1e-8,
            rbf_radius: 2.0,
        }
    }
}

/// Two bodies in contact: body 1 (primary) carries the multiplier.
pub struct ContactProblem<'m> {
    pub primary: ElasticProblem<'m>,
    pub secondary: ElasticProblem<'m>,
    pub primary_surface: ContactSurface,
    pub secondary_surface: ContactSurface,
    pub settings: ContactSettings,
}
