//! The contact law of a pair: what holds at each of its active primary nodes, and how the
//! loop decides each node's state. Everything the loop, the coupled system and the checks need
//! to know about the law is asked here; nothing else matches on the formulation. Its files, in
//! order, after this one (the law, [`ContactLaw`], and what a multiplier is): `state.rs` (the
//! loop's per-node state), `frictionless.rs`, `tied.rs`, `coulomb.rs` (each law's multipliers;
//! for Coulomb, the tangential state of a node and its update).
//!
//! Every law shares the normal part: a node is open (no multiplier) or in contact (its gap
//! held at zero, its pressure `p = -lambda . n >= 0`), decided by the primal-dual active-set
//! update of the active-set loop (`crate::contact::iteration::solve`). The laws differ in the
//! tangential part:
//!
//! | law          | node state          | multipliers per node          | constraint rows |
//! |--------------|---------------------|-------------------------------|-----------------|
//! | frictionless | contact             | 1: `lambda_n n`               | the normal gap, node to segment (`crate::contact::geometry::gap`) |
//! | tied         | contact             | `dim`: the traction's components | `u1 - R12 u2 = (d + e) n` (`crate::contact::coupled::interface`) |
//! | Coulomb      | stick               | `dim`: `lambda_n n + sum lambda_a t_a` | the normal gap; `t_a . (u1 - R12 u2)` unchanged over the step |
//! | Coulomb      | slip along `d`      | 1: `lambda_n (n - mu d)`; 3D also `lambda_e e`, `e = n x d` | the normal gap; 3D the slip law across `d`, linearized (`coulomb::Turning`) |
//!
//! A multiplier ([`Multiplier`]) is a column (the traction one unit of it exerts on the
//! primary) and a row (a direction of the constraint, read at a point of the secondary): the
//! coupled system (`crate::contact::coupled::system`) assembles any such list, and only a slipping
//! node's column differs from its row, which makes the system unsymmetric.

pub mod coulomb;
mod frictionless;
mod state;
mod tied;

pub use state::NodeStates;

use crate::contact::geometry::gap::RowNormal;
use crate::contact::settings::{ContactSettings, Formulation, Transfer};

/// Which point of the secondary surface a constraint row reads: the P1 corners of the facet
/// the node projects onto (the geometric gap linearized, `crate::contact::geometry::gap`), or the
/// row of the interpolation `R12` at the node's paired point
/// (`crate::contact::coupled::interface`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reads {
    Geometric,
    Interpolated,
    /// The corners of a wall the node holds beside its closest facet
    /// (`crate::contact::geometry::walls`).
    Wall,
}

/// When a multiplier only restates Dirichlet conditions of the primary (and is dropped from
/// the system: its column would be empty, `crate::contact::coupled::system`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Restates {
    /// When every component of its node is prescribed.
    Node,
    /// When this component of its node is prescribed.
    Component(usize),
}

/// One multiplier of an active node.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Multiplier {
    /// The traction on the primary per unit of the multiplier: its column.
    pub force: [f64; 3],
    /// The direction of its constraint: `row . (u1_i - u2(point)) = row . target_i`.
    pub row: [f64; 3],
    pub reads: Reads,
    pub restates: Restates,
    /// The multiplier's own term in its row, `row . (u1_i - u2(point)) + compliance lambda =
    /// row . target_i` (a length per traction): the penalty method's `1 / eps` on the rows
    /// that hold the gap (`crate::contact::method`), and the row that linearizes a slipping
    /// node's direction in 3D ([`coulomb::Turning`]); zero on the others.
    pub compliance: f64,
}

/// The tangential state of an active node of a Coulomb pair.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Tangential {
    /// No slip over the load step.
    Stick,
    /// Slipping: the friction traction on the primary is `mu p d` (`d` a unit tangent), and in
    /// 3D the direction is linearized as `turning` says.
    Slip {
        direction: [f64; 3],
        turning: coulomb::Turning,
    },
}

/// The contact law of a pair.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContactLaw {
    Frictionless,
    Tied,
    Coulomb { friction_coefficient: f64 },
}

impl ContactLaw {
    /// The law `settings` ask for (validated: a Coulomb pair has its coefficient).
    pub fn of(settings: &ContactSettings) -> Self {
        match settings.formulation {
            Formulation::Frictionless => Self::Frictionless,
            Formulation::Tied => Self::Tied,
            Formulation::Coulomb => Self::Coulomb {
                friction_coefficient: settings.friction_coefficient.unwrap_or(0.0),
            },
        }
    }

    /// The multipliers of an active node in `tangential` state (ignored but by Coulomb)
    /// whose constraint acts along the unit normal `normal` (pointing out of the primary).
    /// `gap_compliance` is the own term of the rows that hold the node on the other surface
    /// (`crate::contact::method`: zero under INTERNODES, `1 / eps` under the penalty method):
    /// the normal row, and every row of tied contact's glue; a Coulomb node's stick is held
    /// exactly under either method.
    pub fn multipliers(
        &self,
        normal: [f64; 3],
        tangential: Tangential,
        dim: usize,
        gap_compliance: f64,
    ) -> Vec<Multiplier> {
        match *self {
            Self::Frictionless => frictionless::multipliers(normal, gap_compliance),
            Self::Tied => tied::multipliers(dim, gap_compliance),
            Self::Coulomb {
                friction_coefficient,
            } => coulomb::multipliers(
                normal,
                tangential,
                friction_coefficient,
                dim,
                gap_compliance,
            ),
        }
    }

    /// Whether the normal gap of an active node is held node to segment (the geometric gap
    /// linearized at the iterate, `crate::contact::geometry::gap`); otherwise (tied) through `R12`
    /// with the gap correction `e` of the last iterate (`crate::contact::coupled::interface`).
    pub fn holds_geometric_gap(&self) -> bool {
        !matches!(self, Self::Tied)
    }

    /// The direction a node's gap row holds it along
    /// (`crate::contact::geometry::gap::RowNormal`) when the secondary's force is sent by
    /// `transfer`: the facet's normal, the gradient of the gap, except for Coulomb pairs, whose
    /// answer (a slip direction in 3D, a node's state at the stick zone's edge in 2D) has no
    /// fixed point when the normal jumps between facets, and under the node-to-facet transfer,
    /// whose rows cross the small kinks of the groove an edge digs (`crate::contact::Transfer`).
    pub fn row_normal(&self, transfer: Transfer) -> RowNormal {
        match (self, transfer) {
            (ContactLaw::Coulomb { .. }, _) | (_, Transfer::NodeToFacet) => RowNormal::Averaged,
            _ => RowNormal::Facet,
        }
    }

    /// Whether an active node in a concave vertex of the other surface holds the second facet
    /// too (`crate::contact::geometry::walls`): frictionless contact. A Coulomb node's
    /// tangential rows already hold it along the surface while it sticks, and a slipping one's
    /// friction along the wall would need its own slip law; tied contact holds every direction.
    pub fn holds_walls(&self) -> bool {
        matches!(self, Self::Frictionless)
    }

    /// Whether the tangential slip of an active node is constrained through `R12` and the
    /// loop keeps a stick/slip state per node.
    pub fn has_friction(&self) -> bool {
        matches!(self, Self::Coulomb { .. })
    }

    /// The directions an active node in state `tangential` holds its body along, against the
    /// body's rigid motions (`crate::contact::iteration::solve`, `check_held`): the normal alone,
    /// or every direction (tied, and a sticking node).
    pub fn holds_every_direction(&self, tangential: Tangential) -> bool {
        match self {
            Self::Frictionless => false,
            Self::Tied => true,
            Self::Coulomb { .. } => tangential == Tangential::Stick,
        }
    }

    /// Whether the first iteration may start from the half-space model's prediction of the
    /// contact zone (`crate::contact::coupled::half_space::predicted_set`): a model of frictionless
    /// contact between half-spaces, which a tied or frictional zone's normal part follows only for
    /// equal materials.
    pub fn predicts_zone(&self) -> bool {
        matches!(self, Self::Frictionless)
    }
}
