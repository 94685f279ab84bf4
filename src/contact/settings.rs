//! The settings of a contact solve, each with its default and range: the constraint, the
//! transfer, the linear solver, and the tolerances of the active-set loop and its checks.

use serde::{Deserialize, Serialize};
use thiserror::Error;
/// Which constraint couples the active surfaces (`docs/method.md` 1.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Formulation {
    /// Normal constraint only, one scalar multiplier per primary node: surfaces may slide.
    #[default]
    Frictionless,
    /// Vector constraint (the original INTERNODES contact system): active surfaces are glued
    /// together.
    Tied,
    /// Coulomb friction with the pair's `friction_coefficient`: each active node sticks
    /// (its tangential slip over the load step is zero) or slips (its tangential traction is
    /// `mu` times its pressure, against its slip) (`crate::contact::law::coulomb`).
    Coulomb,
}

impl Formulation {
    /// The name used in case files and summaries.
    pub fn name(self) -> &'static str {
        match self {
            Self::Frictionless => "frictionless",
            Self::Tied => "tied",
            Self::Coulomb => "coulomb",
        }
    }
}

/// How a pair's contact law is enforced (`docs/method.md` 5): the one thing that differs
/// between the two methods (`crate::contact::method`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Lagrange multipliers on the primary's active nodes, the traction carried to the
    /// secondary by the transfer (`transfer`): the constraint holds exactly.
    #[default]
    Internodes,
    /// A pressure `eps max(0, -g)` on each primary node's gap `g` (the same gap as
    /// INTERNODES'), carried to the secondary by the same transfer, `eps = penalty E* / h`: the
    /// bodies overlap by `p / eps` where they touch.
    Penalty,
}

impl Method {
    /// The name used in case files and summaries.
    pub fn name(self) -> &'static str {
        match self {
            Self::Internodes => "internodes",
            Self::Penalty => "penalty",
        }
    }
}

/// The penalty factor of `method = "penalty"` when the case gives none: `eps = 100 E* / h`,
/// an overlap of `p / (100 E*)` spacings, 1e-4 of a spacing at a pressure of `E* / 100` (a
/// contact zone a tenth of the radius of a Hertzian contact): a tenth of
/// `penetration_tolerance`'s default.
pub const DEFAULT_PENALTY: f64 = 100.0;

/// How the multiplier's force reaches the secondary body (`docs/method.md` 2.4).
///
/// - `Interpolation` (INTERNODES' own transfer): the secondary receives the traction
///   interpolated at its own nodes, `lambda_2 = -R21 lambda`, integrated by its interface mass:
///   nodal forces `-M2 R21 lambda`. A secondary coarser than the primary samples a field finer
///   than itself there, and the total force no longer balances `M1 lambda` (the imbalance grows
///   as the contact zone spans fewer secondary spacings).
/// - `Conservative`: the secondary receives the primary's nodal forces distributed by the
///   transpose of the displacement interpolation, `-R12^T M1 lambda` (the mortar method's
///   transfer). The rows of `R12` sum to one, so the forces on the two bodies balance exactly.
///   For tied contact the coupling is then the transpose of the constraint (the Lagrange
///   multiplier form of `u1 - R12 u2 = d`); frictionless rows are node to segment
///   (`crate::contact::geometry::gap`), and the system stays unsymmetric. Onto a secondary finer
///   than the primary it leaves the secondary nodes between the projections of primary nodes
///   unloaded, which is why INTERNODES interpolates there.
/// - `NodeToFacet`: the secondary receives each primary node's force at the corners of the
///   facet its gap row holds it against, by the P1 weights of its closest point there (the
///   transpose of the rows, so the forces balance exactly and never pull), and the rows hold
///   each node along the secondary's nodal normals interpolated at that point
///   (`crate::contact::geometry::gap::RowNormal::Averaged`) rather than the facet's: the
///   node-to-surface formulation with smoothed normals, for the geometric rows of frictionless
///   and Coulomb pairs (a tied pair's rows are `R12`'s: refused there).
/// - `Auto` (default): conservative onto a nearly rigid secondary; node to facet in 3D from a
///   frictionless primary with an edge or corner (`crate::contact::problem::CORNER_TURN`)
///   pressed into a body of similar stiffness (`crate::contact::problem::SIMILAR_STIFFNESS`),
///   conservative from such a primary otherwise (its traction concentrates at the corner, and
///   its interpolation does not keep the resultant); conservative when the secondary's contact
///   surface is coarser than the primary's near the other body
///   (`crate::contact::problem::contact_zone_spacing`); interpolation otherwise. Why node to
///   facet at a 3D edge between similar bodies: both surfaces deform there, the secondary into
///   a groove along the edge whose facets turn by a few degrees each, and the primary's nodes
///   slide across them; a row along the closest facet's normal jumps as the closest facet
///   does, with no fixed point for the loop to settle on, and `R12^T`, whose Wendland weights
///   are not all positive, pulls secondary nodes beside a zone one node across (`docs/method.md`
///   4.1). In 2D the groove's two sides are held by walls (`crate::contact::geometry::walls`),
///   and a stiff primary's edge in a compliant body settles with the conservative transfer
///   within 0.05% of the same-mesh reference: both keep it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Transfer {
    #[default]
    Auto,
    Interpolation,
    Conservative,
    NodeToFacet,
}

impl Transfer {
    /// Whether the secondary's force goes through the interpolation `R21` (otherwise no `R21`
    /// is built).
    pub fn interpolates(self) -> bool {
        matches!(self, Self::Interpolation)
    }
}

/// A setting outside its range.
#[derive(Debug, Error, PartialEq)]
#[error("{name} must be {expected}, got {value}")]
pub struct SettingsError {
    pub name: &'static str,
    pub expected: &'static str,
    /// The value given, as the case file spells it.
    pub value: String,
}

/// How each iteration's coupled system is solved (`crate::contact::coupled::coupled_solver` says
/// how each works and why `auto` is the default).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CoupledSolver {
    /// The default: [`Self::Krylov`], and [`Self::Schur`] from the first iteration whose GMRES
    /// solve fails (`crate::contact::coupled::coupled_solver`).
    #[default]
    Auto,
    /// Each body's solver set up once, dense Schur complement on the multipliers per
    /// iteration: exact whatever the conditioning of the interface problem.
    Schur,
    /// Sparse LU of the whole saddle-point matrix per iteration (reference).
    MonolithicLu,
    /// Each body's solver set up once, the whole coupled system solved by one
    /// block-preconditioned GMRES per iteration (also what `schur` runs with CG + AMG bodies);
    /// a GMRES solve that fails ends the contact solve with that error.
    Krylov,
}

impl CoupledSolver {
    /// The name used in case files and summaries.
    pub fn name(self) -> &'static str {
        match self {
            Self::Auto => "auto",
            Self::Schur => "schur",
            Self::MonolithicLu => "monolithic-lu",
            Self::Krylov => "krylov",
        }
    }
}

/// The largest `max_iterations` accepted.
const MAX_ITERATIONS_CAP: usize = 1000;

/// The largest `krylov_max_iterations` accepted: each iteration is one V-cycle per body,
/// and the solves measured take at most a few dozen, so a cap beyond this is a run of hours
/// waiting for a failure.
const KRYLOV_MAX_ITERATIONS_CAP: usize = 10_000;

/// Settings of the active-set loop and its certificate; every field has a documented default,
/// and [`ContactSettings::validate`] checks them all (the solver calls it).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ContactSettings {
    /// Default: frictionless.
    pub formulation: Formulation,
    /// How the law is enforced (default: INTERNODES, [`Method`]).
    pub method: Method,
    /// The penalty `eps` of `method = "penalty"` as a multiple of the contact stiffness
    /// `E* / h` (`E*` the pair's contact modulus, `h` the primary's spacing where contact
    /// starts; default [`DEFAULT_PENALTY`]); refused with `method = "internodes"`.
    pub penalty: Option<f64>,
    /// The Coulomb friction coefficient `mu` (> 0, finite): required by `formulation =
    /// "coulomb"`, refused by the others.
    pub friction_coefficient: Option<f64>,
    /// How the multiplier's force reaches the secondary (default: auto, [`Transfer`]).
    pub transfer: Transfer,
    /// How each iteration's linear system is solved (default: `auto`, the interface Schur
    /// system by GMRES on the bodies' solvers set up once, the dense Schur complement if
    /// GMRES fails; `crate::contact::coupled::coupled_solver`).
    pub solver: CoupledSolver,
    /// Cap on active-set iterations (default 200); reaching it is a status, not an error. The
    /// safeguard's stops end a loop that does not settle long before it (no run of the
    /// validation suites reaches 50) except while a corner of the primary digs a groove into the
    /// other body, whose crater the loop crosses node by node with those stops held off
    /// (`crate::contact::iteration::walls`): 16 to 34 iterations on the edge sweep's corners,
    /// 63 on the coarse corner of `tests/contact_corner.rs`.
    pub max_iterations: usize,
    /// Cap on the GMRES iterations of one coupled solve (default 600; the solves
    /// measured take 0 to 30).
    /// Reaching it fails that solve: under `solver = "auto"` the solve and every later one
    /// move to the dense Schur complement (recorded in `summary.json`), under `"krylov"` the
    /// run ends with an error naming it. The same cap as PETSc's `ksp_max_it`: it bounds the
    /// time a solve that is not converging may take.
    pub krylov_max_iterations: usize,
    /// A node penetrates when its geometric gap is below `-tol * h`, `h` its distance to the
    /// nearest node of its own surface (default 1e-3); the same bound holds the active nodes
    /// on the other surface and certifies the answer.
    pub penetration_tolerance: f64,
    /// An active node is in tension when its pressure is below `-tol * p_max`, `p_max` the
    /// largest pressure of the iteration (default 1e-8).
    pub tension_tolerance: f64,
    /// The certificate's bound on the penetration of a SECONDARY node into the primary body,
    /// over its spacing (default 0.05). The constraint holds the primary nodes on the
    /// secondary surface; the secondary nodes between them can cross the primary's P1 surface
    /// by the transfer's consistency error (measured up to 0.016 h on a 3D mesh with three
    /// spacings across the contact zone, falling with h), far below the spacing-sized
    /// penetration of a wrong active set.
    pub secondary_penetration_tolerance: f64,
    /// The accuracy report's bound on the relative error of the contact force, for each
    /// indicator that estimates it (default 0.01): the secondary's sag, and the agreement with
    /// the other primary or with the automatic transfer when one was named
    /// (`crate::contact::verify::checks`). One tolerance, because each of them answers the same
    /// question: how far the force the user reads may be from the one of a better discretization.
    pub accuracy_tolerance: f64,
    /// The certificate's bound on the tensile normal force any surface node receives over its
    /// area (along the node's own outward normal), relative to the largest pressure (default
    /// 0.1). The secondary pressure is the RBF transfer `R21 lambda` of the multiplier, which
    /// is not positivity preserving: it undershoots just outside the rim of the contact zone
    /// (measured up to 0.067 on the 3D hemisphere meshes); a wrong active set leaves tensions
    /// of the order of the peak pressure.
    pub certificate_tension_tolerance: f64,
    /// The certificate's lower bound on the contact zone's width, in primary spacings
    /// (`crate::contact::verify::checks`; default 1.5: three nodes across a 2D zone, about seven in
    /// 3D).
    pub min_zone_width: f64,
    /// The same bound in secondary spacings, unless the secondary is nearly rigid (default
    /// 2.5: four nodes across a 2D zone).
    pub secondary_min_zone_width: f64,
    /// The certificate's bound on the distance between the centres of the normal contact
    /// forces on the two bodies, over the coarser surface's spacing where they are loaded
    /// (`crate::contact::verify::checks`; default 1): equal and opposite forces must also act at
    /// the same place.
    pub force_centre_tolerance: f64,
    /// The certificate's bound on `|F1 + F2| / |F1|` (default 0.01): the reported contact force
    /// is known to this fraction.
    pub imbalance_tolerance: f64,
    /// Support radius of each node's RBF in the transfer operators, in units of the distance
    /// to its nearest node (default 2, the radius Algorithm 1 of `docs/method.md` starts from; see
    /// [`crate::contact::geometry::rbf::interpolation_radii`] for the measurements behind it).
    pub rbf_radius: f64,
    /// Solve every load step again with the other body as primary and check that the two
    /// contact forces agree within `accuracy_tolerance` (`primary agreement`), whatever the
    /// primary (default false: done anyway for a named primary that `auto` avoids). The other
    /// primary is an independent discretization of the coupling of the two meshes, the one
    /// error of the interface that the other indicators estimate only in part; it doubles the
    /// cost, and where the other body is much stiffer its answer is the unstable choice's.
    pub check_other_primary: bool,
}

impl Default for ContactSettings {
    fn default() -> Self {
        Self {
            formulation: Formulation::default(),
            method: Method::default(),
            penalty: None,
            friction_coefficient: None,
            transfer: Transfer::default(),
            solver: CoupledSolver::default(),
            max_iterations: 200,
            krylov_max_iterations: 600,
            penetration_tolerance: 1e-3,
            tension_tolerance: 1e-8,
            secondary_penetration_tolerance: 0.05,
            accuracy_tolerance: 0.01,
            min_zone_width: 1.5,
            secondary_min_zone_width: 2.5,
            certificate_tension_tolerance: 0.1,
            imbalance_tolerance: 0.01,
            force_centre_tolerance: 1.0,
            rbf_radius: 2.0,
            check_other_primary: false,
        }
    }
}

impl ContactSettings {
    /// The penalty factor of a penalty pair (times `E* / h`); `None` under INTERNODES.
    pub fn penalty_factor(&self) -> Option<f64> {
        match self.method {
            Method::Internodes => None,
            Method::Penalty => Some(self.penalty.unwrap_or(DEFAULT_PENALTY)),
        }
    }

    /// Checks every setting's range.
    pub fn validate(&self) -> Result<(), SettingsError> {
        let error = |name, expected, value: f64| {
            Err(SettingsError {
                name,
                expected,
                value: value.to_string(),
            })
        };
        if self.formulation == Formulation::Tied && self.transfer == Transfer::NodeToFacet {
            return Err(SettingsError {
                name: "transfer",
                expected: "\"auto\", \"interpolation\" or \"conservative\" for formulation = \"tied\" \
                           (node to facet sends the force through the rows of the geometric gap, \
                           and a tied pair's rows are the interpolation's)",
                value: "\"node-to-facet\"".into(),
            });
        }
        match (self.formulation, self.friction_coefficient) {
            (Formulation::Coulomb, None) => {
                return error(
                    "friction_coefficient",
                    "given for formulation = \"coulomb\" (a finite number > 0)",
                    f64::NAN,
                );
            }
            (Formulation::Coulomb, Some(mu)) if !(mu > 0.0 && mu.is_finite()) => {
                return error("friction_coefficient", "a finite number > 0", mu);
            }
            (Formulation::Frictionless | Formulation::Tied, Some(mu)) => {
                return error(
                    "friction_coefficient",
                    "left out unless formulation = \"coulomb\" (frictionless and tied \
                     contact have no friction coefficient)",
                    mu,
                );
            }
            _ => {}
        }
        match (self.method, self.penalty) {
            (Method::Internodes, Some(penalty)) => {
                return error(
                    "penalty",
                    "left out unless method = \"penalty\" (INTERNODES holds the constraint \
                     exactly)",
                    penalty,
                );
            }
            // Beyond 1e12 the overlap `p / eps` is below the round-off of the gap.
            (Method::Penalty, Some(penalty)) if !(penalty > 0.0 && penalty <= 1e12) => {
                return error(
                    "penalty",
                    "a number > 0 and <= 1e12 (times E* / h)",
                    penalty,
                );
            }
            _ => {}
        }
        // The loop ends by itself within a few iterations of a repeat or a stall
        // (`crate::contact::iteration::solve`); a cap beyond this only postpones a status that is
        // already due.
        if !(1..=MAX_ITERATIONS_CAP).contains(&self.max_iterations) {
            return error(
                "max_iterations",
                "between 1 and 1000",
                self.max_iterations as f64,
            );
        }
        if !(1..=KRYLOV_MAX_ITERATIONS_CAP).contains(&self.krylov_max_iterations) {
            return error(
                "krylov_max_iterations",
                "between 1 and 10000",
                self.krylov_max_iterations as f64,
            );
        }
        // A support that does not reach the nearest node interpolates nothing. One of 10
        // nearest-node distances already holds about 20 nodes of a curve and 300 of a surface,
        // where 8/3 did no better than the default 2 (`rbf::interpolation_radii`); beyond it
        // the interpolation matrices fill up and no longer interpolate locally (on the 2D
        // half-disc, 1e9 ended `unstable`, nodes a spacing deep, and 1e300 made Phi_MM singular).
        if !(self.rbf_radius > 1.0 && self.rbf_radius <= 10.0) {
            return error(
                "rbf_radius",
                "a number > 1 and <= 10 (units of the nearest-node distance)",
                self.rbf_radius,
            );
        }
        for (name, value) in [
            ("min_zone_width", self.min_zone_width),
            ("secondary_min_zone_width", self.secondary_min_zone_width),
        ] {
            if !(value > 0.0 && value.is_finite()) {
                return error(name, "a finite number > 0 (spacings)", value);
            }
        }
        for (name, value) in [
            ("penetration_tolerance", self.penetration_tolerance),
            ("tension_tolerance", self.tension_tolerance),
            (
                "secondary_penetration_tolerance",
                self.secondary_penetration_tolerance,
            ),
            (
                "certificate_tension_tolerance",
                self.certificate_tension_tolerance,
            ),
            ("accuracy_tolerance", self.accuracy_tolerance),
            ("imbalance_tolerance", self.imbalance_tolerance),
            ("force_centre_tolerance", self.force_centre_tolerance),
        ] {
            if !(value >= 0.0 && value.is_finite()) {
                return error(name, "a finite number >= 0", value);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::{ContactSettings, Formulation, Transfer};

    #[test]
    fn node_to_facet_is_refused_for_tied_contact_alone() {
        let with = |formulation, friction_coefficient| ContactSettings {
            formulation,
            friction_coefficient,
            transfer: Transfer::NodeToFacet,
            ..ContactSettings::default()
        };
        let error = with(Formulation::Tied, None).validate().unwrap_err();
        assert_eq!(error.name, "transfer");
        let message = error.to_string();
        assert!(
            message.contains("tied") && message.contains("got \"node-to-facet\""),
            "{message}"
        );
        assert!(with(Formulation::Frictionless, None).validate().is_ok());
        assert!(with(Formulation::Coulomb, Some(0.3)).validate().is_ok());
    }

    #[test]
    fn the_iteration_cap_has_bounds() {
        for (cap, accepted) in [(0, false), (1, true), (1000, true), (1001, false)] {
            let settings = ContactSettings {
                max_iterations: cap,
                ..ContactSettings::default()
            };
            assert_eq!(
                settings.validate().is_ok(),
                accepted,
                "max_iterations = {cap}"
            );
        }
    }
}
