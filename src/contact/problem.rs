//! What to solve: two elastic bodies, their candidate surfaces, which one carries the
//! multiplier, and the settings of the active-set loop.

use serde::{Deserialize, Deserializer, Serialize};
use thiserror::Error;

use super::ContactSurface;
use super::coupled_solver::CoupledSolver;
use crate::elastic::ElasticProblem;

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
}

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
///   (`super::linearization`), and the system stays unsymmetric. Onto a secondary finer than the primary it leaves the
///   secondary nodes between the projections of primary nodes unloaded, which is why
///   INTERNODES interpolates there.
/// - `Auto` (default): conservative when the secondary's contact surface is coarser than the
///   primary's near the other body ([`contact_zone_spacing`]), interpolation otherwise.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Transfer {
    #[default]
    Auto,
    Interpolation,
    Conservative,
}

/// A setting outside its range.
#[derive(Debug, Error, PartialEq)]
#[error("{name} must be {expected}, got {value}")]
pub struct SettingsError {
    pub name: &'static str,
    pub expected: &'static str,
    pub value: f64,
}

/// A secondary body whose share of the two bodies' compliance (`1 / E'`) is below this is
/// nearly rigid: the contact zone need not be resolved on it (`super::checks`), and its load
/// is best transferred conservatively ([`ContactProblem::transfer`]).
pub(super) const COMPLIANT_SHARE: f64 = 0.1;

/// The largest `max_iterations` accepted.
const MAX_ITERATIONS_CAP: usize = 1000;

/// The largest `krylov_max_iterations` accepted: GMRES keeps at most 150 vectors of the
/// interface's size between restarts, and each iteration is one solve per body, so a cap
/// beyond this is a run of hours waiting for a failure.
const KRYLOV_MAX_ITERATIONS_CAP: usize = 10_000;

/// Settings of the active-set loop and its certificate; every field has a documented default,
/// and [`ContactSettings::validate`] checks them all (the solver calls it).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ContactSettings {
    /// Default: frictionless.
    pub formulation: Formulation,
    /// How the multiplier's force reaches the secondary (default: auto, [`Transfer`]).
    pub transfer: Transfer,
    /// How each iteration's linear system is solved (default: `auto`, the interface Schur
    /// system by GMRES on the bodies' solvers set up once, the dense Schur complement if
    /// GMRES fails; `super::coupled_solver`).
    pub solver: CoupledSolver,
    /// Cap on active-set iterations (default 50); reaching it is a status, not an error.
    pub max_iterations: usize,
    /// Cap on the interface GMRES iterations of one coupled solve (default 600; the solves
    /// measured take 1 to 16 per active-set iteration, a few dozen when started cold).
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
    /// the other primary or with the automatic transfer when one was named (`super::checks`).
    /// One tolerance, because each of them answers the same question: how far the force the
    /// user reads may be from the one of a better discretization.
    pub accuracy_tolerance: f64,
    /// The certificate's bound on the tensile normal force any surface node receives over its
    /// area (along the node's own outward normal), relative to the largest pressure (default
    /// 0.1). The secondary pressure is the RBF transfer `R21 lambda` of the multiplier, which
    /// is not positivity preserving: it undershoots just outside the rim of the contact zone
    /// (measured up to 0.067 on the 3D hemisphere meshes); a wrong active set leaves tensions
    /// of the order of the peak pressure.
    pub certificate_tension_tolerance: f64,
    /// The certificate's lower bound on the contact zone's width, in primary spacings
    /// (`super::checks`; default 1.5: three nodes across a 2D zone, about seven in 3D).
    pub min_zone_width: f64,
    /// The same bound in secondary spacings, unless the secondary is nearly rigid (default
    /// 2.5: four nodes across a 2D zone).
    pub secondary_min_zone_width: f64,
    /// The certificate's bound on the distance between the centres of the normal contact
    /// forces on the two bodies, over the coarser surface's spacing where they are loaded
    /// (`super::checks`; default 1): equal and opposite forces must also act at the same place.
    pub force_centre_tolerance: f64,
    /// The certificate's bound on `|F1 + F2| / |F1|` (default 0.01): the reported contact force
    /// is known to this fraction.
    pub imbalance_tolerance: f64,
    /// Support radius of each node's RBF in the transfer operators, in units of the distance
    /// to its nearest node (default 2, the radius Algorithm 1 of `docs/method.md` starts from; see
    /// [`crate::contact::rbf::interpolation_radii`] for the measurements behind it).
    pub rbf_radius: f64,
}

impl Default for ContactSettings {
    fn default() -> Self {
        Self {
            formulation: Formulation::default(),
            transfer: Transfer::default(),
            solver: CoupledSolver::default(),
            max_iterations: 50,
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
        }
    }
}

impl ContactSettings {
    /// Checks every setting's range.
    pub fn validate(&self) -> Result<(), SettingsError> {
        let error = |name, expected, value| {
            Err(SettingsError {
                name,
                expected,
                value,
            })
        };
        // The loop ends by itself within a few iterations of a repeat or a stall
        // (`super::solve`); a cap beyond this only postpones a status that is already due.
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

/// Which body carries the multiplier: `"auto"` (default) or a body's name.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub enum PrimaryChoice {
    /// The more compliant body (contact modulus `E / (1 - nu^2)` at least `SIMILAR_STIFFNESS`
    /// times lower); between bodies of similar stiffness, the coarser contact surface. See
    /// [`ContactProblem::new`] for why.
    #[default]
    Auto,
    Body(String),
}

impl<'de> Deserialize<'de> for PrimaryChoice {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let name = String::deserialize(deserializer)?;
        Ok(if name == "auto" {
            Self::Auto
        } else {
            Self::Body(name)
        })
    }
}

/// How the secondary's force is computed, and why (printed, and in the summary).
#[derive(Debug, Clone, Serialize)]
pub struct TransferReport {
    /// `Interpolation` or `Conservative` (never `Auto`: the choice made).
    pub transfer: Transfer,
    pub reason: String,
}

/// Which body was made primary, and why (printed, and in the summary).
#[derive(Debug, Clone, Serialize)]
pub struct PrimaryReport {
    /// "auto" or "explicit".
    pub mode: &'static str,
    pub reason: String,
    /// Whether the other body may carry the multiplier when this choice does not end
    /// `converged`: auto between bodies of similar stiffness. Between a compliant and a stiff
    /// body the stiff primary is the unstable choice (`ContactProblem::new`), and a retry with
    /// it turned uncertified answers into certified wrong ones (`docs/method.md` 3.6).
    #[serde(skip)]
    pub other_may_retry: bool,
    /// Whether the answer must agree with the one the other body gives as primary: an
    /// explicit primary at least `SIMILAR_STIFFNESS` times stiffer than the other body, the
    /// choice "auto" avoids as unstable. Such a primary passed every check of the certificate
    /// with a force 3% off (a stiff block twice finer than an R/25 hemisphere, 3D), so its
    /// certificate gets a `primary agreement` check (`super::driver`).
    #[serde(skip)]
    pub check_other: bool,
}

/// Contact moduli within this ratio are "similar stiffness" for [`PrimaryChoice::Auto`].
pub const SIMILAR_STIFFNESS: f64 = 2.0;

/// The median spacing of the surface's nodes nearest to the other surface in the reference
/// configuration (a tenth of them, at least ten): the spacing where contact starts. Surfaces
/// are graded towards the contact, so the finest spacing of a surface is one close pair of
/// nodes somewhere there, too noisy to compare two surfaces meshed alike.
pub fn contact_zone_spacing(surface: &ContactSurface, other: &ContactSurface) -> f64 {
    let gaps = super::interface::geometric_gaps(surface, other, None, None);
    let mut order: Vec<usize> = (0..surface.len()).collect();
    order.sort_by(|&a, &b| gaps[a].abs().total_cmp(&gaps[b].abs()));
    let count = (surface.len() / 10).max(10).min(surface.len());
    let mut near: Vec<f64> = order[..count].iter().map(|&s| surface.spacing[s]).collect();
    near.sort_by(f64::total_cmp);
    near[count / 2]
}

/// One body of a contact pair: its elastic problem and candidate surface.
pub type ContactSide<'m> = (ElasticProblem<'m>, ContactSurface);

/// Two bodies in contact: body 1 (primary) carries the multiplier.
pub struct ContactProblem<'m> {
    pub primary: ElasticProblem<'m>,
    pub secondary: ElasticProblem<'m>,
    pub primary_surface: ContactSurface,
    pub secondary_surface: ContactSurface,
    pub settings: ContactSettings,
    pub primary_report: PrimaryReport,
    /// [`contact_zone_spacing`] of the primary and secondary surfaces, measured once: the
    /// primary choice and the transfer choice both read them.
    contact_spacing: [f64; 2],
}

impl<'m> ContactProblem<'m> {
    /// The same problem with the roles of the two bodies exchanged (the reason is kept).
    pub fn with_other_primary(self) -> Self {
        let [primary, secondary] = self.contact_spacing;
        Self {
            primary: self.secondary,
            secondary: self.primary,
            primary_surface: self.secondary_surface,
            secondary_surface: self.primary_surface,
            contact_spacing: [secondary, primary],
            ..self
        }
    }

    /// The same problem with the transfer setting `transfer`.
    pub fn with_transfer(mut self, transfer: Transfer) -> Self {
        self.settings.transfer = transfer;
        self
    }

    /// Whether the case names a transfer that `auto` would not choose: the answer is then
    /// checked against the one with auto's (`super::driver`). Conservative onto a finer
    /// secondary leaves its nodes between the primary's projections unevenly loaded; two flat
    /// blocks on rollers, the coarser primary, were 2.3% softer with it than with the
    /// interpolation and passed every other check.
    pub fn transfer_differs_from_auto(&self) -> bool {
        let auto = ContactSettings {
            transfer: Transfer::Auto,
            ..self.settings
        };
        self.settings.transfer != Transfer::Auto
            && self.transfer().transfer != self.transfer_for(&auto).transfer
    }

    /// The same problem, its primary choice's reason extended by `more`.
    pub fn with_reason_appended(mut self, more: &str) -> Self {
        self.primary_report.reason = format!("{}; {more}", self.primary_report.reason);
        self
    }

    /// Whether the secondary body is nearly rigid: its share of the two bodies' compliance
    /// (`1 / E'`) is below `COMPLIANT_SHARE`.
    pub fn secondary_is_nearly_rigid(&self) -> bool {
        self.normal_weights()[0] < COMPLIANT_SHARE
    }

    /// The transfer of the multiplier's force to the secondary that `settings.transfer` asks
    /// for ([`Transfer`]; auto: conservative onto a nearly rigid secondary, otherwise by the
    /// two surfaces' spacings near each other).
    pub fn transfer(&self) -> TransferReport {
        self.transfer_for(&self.settings)
    }

    fn transfer_for(&self, settings: &ContactSettings) -> TransferReport {
        match settings.transfer {
            named @ (Transfer::Interpolation | Transfer::Conservative) => TransferReport {
                transfer: named,
                reason: "named in the case file".into(),
            },
            // A nearly rigid body's deformation does not depend on how its load is spread,
            // only on the resultant, which the conservative transfer carries exactly; the
            // interpolation of a traction that ends at a corner (a flat punch's edge) does
            // not: 2.5% to 2.9% of the force was lost on a stiff 3D punch.
            Transfer::Auto if self.secondary_is_nearly_rigid() => TransferReport {
                transfer: Transfer::Conservative,
                reason: format!(
                    "the secondary is nearly rigid (its share of the compliance {:.1e} < {COMPLIANT_SHARE})",
                    self.normal_weights()[0]
                ),
            },
            Transfer::Auto => {
                let [spacing1, spacing2] = self.contact_spacing;
                let (transfer, relation) = if spacing2 > spacing1 {
                    (Transfer::Conservative, "coarser")
                } else {
                    (Transfer::Interpolation, "not coarser")
                };
                TransferReport {
                    transfer,
                    reason: format!(
                        "the secondary surface is {relation} than the primary near the contact \
                         (spacing {spacing2:.3e} against {spacing1:.3e})"
                    ),
                }
            }
        }
    }

    /// The contact moduli `E / (1 - nu^2)` of the primary and secondary bodies, normalized to
    /// sum to one: the weights of their normals in the contact normal
    /// (`super::interface::contact_normal`).
    pub fn normal_weights(&self) -> [f64; 2] {
        let modulus = |p: &ElasticProblem| {
            p.material.youngs_modulus() / (1.0 - p.material.poisson_ratio().powi(2))
        };
        let (k1, k2) = (modulus(&self.primary), modulus(&self.secondary));
        [k1 / (k1 + k2), k2 / (k1 + k2)]
    }

    /// The combined contact modulus `E* = 1 / (1 / E1' + 1 / E2')`, `E' = E / (1 - nu^2)`.
    pub fn contact_modulus(&self) -> f64 {
        let modulus = |p: &ElasticProblem| {
            p.material.youngs_modulus() / (1.0 - p.material.poisson_ratio().powi(2))
        };
        1.0 / (1.0 / modulus(&self.primary) + 1.0 / modulus(&self.secondary))
    }

    /// The problem of two bodies with the primary chosen by `choice`. An explicit choice must
    /// name one of the two bodies (`Err` gives the names).
    ///
    /// Why the compliant body: the multiplier is controlled through the secondary's
    /// interpolated response `R12 K2^-1 (transfer)`, of rank at most the secondary's node count;
    /// on a nearly rigid primary, multiplier modes are left that nothing controls (the
    /// half-disc at R/500 on a block 1e4 times stiffer, the block primary:
    /// [`super::ContactStatus::Unstable`]), and a curved secondary sags between the constrained
    /// nodes of a coarse flat primary (the certificate's sag check). On the compliant body
    /// `K1^-1` controls every mode.
    ///
    /// Why the coarser surface between similar bodies: a multiplier mesh coarser than the mesh
    /// it constrains is the classical inf-sup-stable choice, and the finer secondary receives
    /// the interpolated traction (`R21`), which balances the forces to the interpolation's
    /// accuracy. The mortar rule (the finer side primary, the conservative transfer to the
    /// coarser one) measured worse on two equal hemispheres meshed 1.5 times apart (`docs/method.md`
    /// 3.6). The price is the sag of a curved secondary between the
    /// nodes of a coarse flat primary, which the certificate measures; the retry with the
    /// other primary (`super::driver`) answers it.
    pub fn new(
        sides: [ContactSide<'m>; 2],
        choice: &PrimaryChoice,
        settings: ContactSettings,
    ) -> Result<Self, String> {
        let modulus = |side: &ContactSide| {
            let m = &side.0.material;
            m.youngs_modulus() / (1.0 - m.poisson_ratio().powi(2))
        };
        let spacing_near = [
            contact_zone_spacing(&sides[0].1, &sides[1].1),
            contact_zone_spacing(&sides[1].1, &sides[0].1),
        ];
        let name = |side: &ContactSide| side.0.body.name.clone();
        // What "auto" chooses (module doc of `PrimaryChoice::Auto`); an explicit choice is
        // compared with it.
        let stiffness = modulus(&sides[1]) / modulus(&sides[0]);
        // Symmetric in the two bodies: at a ratio of exactly 2 the order they are listed in
        // must not decide.
        let similar = stiffness.max(1.0 / stiffness) < SIMILAR_STIFFNESS;
        let (auto_first, auto_reason) = if !similar {
            let first = usize::from(stiffness < 1.0);
            (
                first,
                format!(
                    "the more compliant body: contact modulus E/(1-nu^2) {:.3e} against {:.3e} for '{}'",
                    modulus(&sides[first]),
                    modulus(&sides[1 - first]),
                    name(&sides[1 - first])
                ),
            )
        } else {
            let first = usize::from(spacing_near[1] > spacing_near[0]);
            (
                first,
                format!(
                    "similar stiffness (ratio {:.2}); the coarser contact surface: spacing near the other body {:.3e} against {:.3e} for '{}'",
                    stiffness.max(1.0 / stiffness),
                    spacing_near[first],
                    spacing_near[1 - first],
                    name(&sides[1 - first])
                ),
            )
        };
        let (first, report) = match choice {
            PrimaryChoice::Body(body) => {
                let first = sides
                    .iter()
                    .position(|s| &s.0.body.name == body)
                    .ok_or_else(|| {
                        format!(
                            "primary = '{body}' is neither of the contact bodies '{}' and '{}' (or \"auto\")",
                            name(&sides[0]),
                            name(&sides[1])
                        )
                    })?;
                // Between bodies of similar stiffness either choice is stable (the coarser one
                // is auto's for accuracy), and the other one's answer may be the one that
                // fails; a stiff primary is the unstable choice.
                let check_other = first != auto_first && !similar;
                let reason = if check_other {
                    format!(
                        "named in the case file; \"auto\" would choose '{}' ({auto_reason}), so \
                         the answer is checked against the one with '{}' as primary",
                        name(&sides[auto_first]),
                        name(&sides[auto_first])
                    )
                } else {
                    format!("named in the case file (as \"auto\" would: {auto_reason})")
                };
                (
                    first,
                    PrimaryReport {
                        mode: "explicit",
                        reason,
                        other_may_retry: false,
                        check_other,
                    },
                )
            }
            PrimaryChoice::Auto => (
                auto_first,
                PrimaryReport {
                    mode: "auto",
                    reason: auto_reason,
                    other_may_retry: similar,
                    check_other: false,
                },
            ),
        };
        let [a, b] = sides;
        let ((primary, primary_surface), (secondary, secondary_surface)) =
            if first == 0 { (a, b) } else { (b, a) };
        Ok(Self {
            primary,
            secondary,
            primary_surface,
            secondary_surface,
            settings,
            primary_report: report,
            contact_spacing: [spacing_near[first], spacing_near[1 - first]],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::ContactSettings;

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
