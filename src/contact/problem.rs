//! What to solve: two elastic bodies, their candidate surfaces, which one carries the
//! multiplier, and the settings of the active-set loop (`crate::contact::settings`).

use serde::{Deserialize, Deserializer, Serialize};

use crate::contact::ContactError;
use crate::contact::geometry::surface::ContactSurface;
use crate::contact::settings::{ContactSettings, Formulation, Transfer};
use crate::elastic::{ElasticProblem, StepFactors};

/// A secondary body whose share of the two bodies' compliance (`1 / E'`) is below this is
/// nearly rigid: the contact zone need not be resolved on it (`crate::contact::verify::checks`),
/// and its load is best transferred conservatively ([`ContactProblem::transfer`]).
pub(super) const COMPLIANT_SHARE: f64 = 0.1;

/// A contact surface whose facets turn by more than this many degrees where they meet has a
/// corner (2D) or an edge (3D): a primary with one is transferred conservatively by `auto`
/// ([`ContactProblem::transfer`]), and in 2D chosen by `auto` between bodies of similar
/// stiffness. Meshes of curved surfaces turn by far less per facet: at most 24 degrees on those
/// of the validation suites and the test fixtures (a hemisphere meshed coarsely away from the
/// contact), 90 at the tilted square's corner and the tilted cube's edge.
pub const CORNER_TURN: f64 = 45.0;

/// Which body carries the multiplier: `"auto"` (default) or a body's name.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub enum PrimaryChoice {
    /// The more compliant body (contact modulus `E / (1 - nu^2)` at least `SIMILAR_STIFFNESS`
    /// times lower); between bodies of similar stiffness, the one whose contact surface has a
    /// corner or edge (`CORNER_TURN`) where the other's has none; otherwise the coarser
    /// contact surface. See [`ContactProblem::new`] for why.
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
    /// `Interpolation`, `Conservative` or `NodeToFacet` (never `Auto`: the choice made).
    pub transfer: Transfer,
    pub reason: String,
}

/// Which body was made primary, and why (printed, and in the summary).
#[derive(Debug, Clone, Serialize)]
pub struct PrimaryReport {
    /// "auto" or "explicit".
    pub mode: &'static str,
    pub reason: String,
    /// What the driver does with the other body as primary.
    #[serde(skip)]
    pub other_primary: OtherPrimary,
}

/// What a solve does with the other body as primary (`crate::contact::driver`), decided with the
/// primary.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OtherPrimary {
    /// Nothing: the choice is auto's between bodies of different stiffness (the compliant body;
    /// a stiff primary is the unstable choice, and a retry with it turned uncertified answers
    /// into certified wrong ones, `docs/method.md` 3.6), or a named primary auto would make.
    Unused,
    /// Solve again with it when this answer is not trusted, and keep its answer if that one
    /// is: auto between bodies of similar stiffness, where either choice is stable and the
    /// coarser one (auto's, for accuracy) may be the one that fails.
    RetryIfUntrusted,
    /// Solve with it too, and check that the two contact forces agree: a named primary at
    /// least `SIMILAR_STIFFNESS` times stiffer than the other body, the choice auto avoids.
    /// Such a primary passed every check of the certificate with a force 3% off (a stiff block
    /// twice finer than an R/25 hemisphere, 3D).
    CheckAgreement,
}

/// Contact moduli within this ratio are "similar stiffness" for [`PrimaryChoice::Auto`].
pub const SIMILAR_STIFFNESS: f64 = 2.0;

/// The median spacing of the surface's nodes nearest to the other surface in the reference
/// configuration (a tenth of them, at least ten): the spacing where contact starts. Surfaces
/// are graded towards the contact, so the finest spacing of a surface is one close pair of
/// nodes somewhere there, too noisy to compare two surfaces meshed alike.
pub fn contact_zone_spacing(surface: &ContactSurface, other: &ContactSurface) -> f64 {
    let gaps = crate::contact::geometry::gap::geometric_gaps(surface, other, None, None);
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
#[derive(Clone)]
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
    /// An error unless `factors` gives every named load path a condition of its two bodies
    /// follows.
    pub fn check_paths(&self, factors: &StepFactors) -> Result<(), ContactError> {
        for elastic in [&self.primary, &self.secondary] {
            if let Some(path) = factors.missing(elastic.paths()) {
                return Err(ContactError::LoadPath(format!(
                    "body '{}' has a condition that follows the path '{path}', and the load \
                     step gives no factor for it (its paths: {:?})",
                    elastic.body.name,
                    factors.paths.keys().collect::<Vec<_>>()
                )));
            }
        }
        Ok(())
    }

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
    /// checked against the one with auto's (`crate::contact::driver`). Conservative onto a finer
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
            named @ (Transfer::Interpolation | Transfer::Conservative | Transfer::NodeToFacet) => {
                TransferReport {
                    transfer: named,
                    reason: "named in the case file".into(),
                }
            }
            Transfer::Auto if self.groove_at_an_edge(settings) => TransferReport {
                transfer: Transfer::NodeToFacet,
                reason: format!(
                    "the primary surface has an edge or corner (its facets turn by {:.0} degrees \
                     > {CORNER_TURN}) pressed into a body of similar stiffness, in 3D",
                    self.primary_surface.sharpest_turn()
                ),
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
            // A corner of the primary (a square's, pressed into a body as compliant) carries
            // its traction on one or two nodes, and the interpolation of such a traction does
            // not keep its resultant either: 8% to 12% of the force off balance at a 2D square's
            // corner, with the secondary finer. A surface meshed to resolve a curve turns by far
            // less per facet.
            Transfer::Auto if self.primary_surface.sharpest_turn() > CORNER_TURN => {
                TransferReport {
                    transfer: Transfer::Conservative,
                    reason: format!(
                        "the primary surface has a corner (its facets turn by {:.0} degrees > \
                         {CORNER_TURN})",
                        self.primary_surface.sharpest_turn()
                    ),
                }
            }
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

    /// Whether auto sends the force node to facet ([`Transfer`]): a frictionless 3D pair whose
    /// primary has an edge or corner ([`CORNER_TURN`]) and whose bodies are of similar
    /// stiffness ([`SIMILAR_STIFFNESS`]), the groove the edge digs deforming with it.
    fn groove_at_an_edge(&self, settings: &ContactSettings) -> bool {
        let [w1, w2] = self.normal_weights();
        settings.formulation == Formulation::Frictionless
            && self.primary_surface.dim == 3
            && self.primary_surface.sharpest_turn() > CORNER_TURN
            && (w1 / w2).max(w2 / w1) < SIMILAR_STIFFNESS
    }

    /// The contact moduli `E / (1 - nu^2)` of the primary and secondary bodies, normalized to
    /// sum to one: the weights of their normals in the contact normal
    /// (`crate::contact::coupled::interface::contact_normal`).
    pub fn normal_weights(&self) -> [f64; 2] {
        let modulus = |p: &ElasticProblem| {
            p.material.youngs_modulus() / (1.0 - p.material.poisson_ratio().powi(2))
        };
        let (k1, k2) = (modulus(&self.primary), modulus(&self.secondary));
        [k1 / (k1 + k2), k2 / (k1 + k2)]
    }

    /// The penalty `eps = penalty E* / h` of a penalty pair (`crate::contact::method`), `h` the
    /// primary's spacing where contact starts (`contact_zone_spacing`): one number per pair,
    /// as the penalty codes take it; `None` under INTERNODES.
    pub fn penalty_stiffness(&self) -> Option<f64> {
        let factor = self.settings.penalty_factor()?;
        Some(factor * self.contact_modulus() / self.contact_spacing[0])
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
    /// [`crate::contact::ContactStatus::Unstable`]), and a curved secondary sags between the
    /// constrained nodes of a coarse flat primary (the certificate's sag check). On the compliant
    /// body `K1^-1` controls every mode.
    ///
    /// Why the coarser surface between similar bodies: a multiplier mesh coarser than the mesh
    /// it constrains is the classical inf-sup-stable choice, and the finer secondary receives
    /// the interpolated traction (`R21`), which balances the forces to the interpolation's
    /// accuracy. The mortar rule (the finer side primary, the conservative transfer to the
    /// coarser one) measured worse on two equal hemispheres meshed 1.5 times apart (`docs/method.md`
    /// 3.6). The price is the sag of a curved secondary between the
    /// nodes of a coarse flat primary, which the certificate measures; the retry with the
    /// other primary (`crate::contact::driver`) answers it.
    pub fn new(
        sides: [ContactSide<'m>; 2],
        choice: &PrimaryChoice,
        settings: ContactSettings,
    ) -> Result<Self, String> {
        let spacing_near = [
            contact_zone_spacing(&sides[0].1, &sides[1].1),
            contact_zone_spacing(&sides[1].1, &sides[0].1),
        ];
        let (first, report) = choose_primary(choice, &sides, spacing_near)?;
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

/// The contact modulus `E / (1 - nu^2)` of a side's body.
fn contact_modulus(side: &ContactSide) -> f64 {
    let m = &side.0.material;
    m.youngs_modulus() / (1.0 - m.poisson_ratio().powi(2))
}

/// The side whose contact surface has a corner or edge ([`CORNER_TURN`]) where the other's has
/// none. Held on the other body node to facet, a corner's node cannot cross the other surface;
/// as the secondary, the corner cuts into it between the primary's nodes, which the constraint
/// does not see: on the edge sweep's square pressed into a block of its own material, the block
/// as primary ended not solved or named in all six cases (forces -5.9% to +3.0% off the
/// reference), the square as primary certified in five (its node in the crater held by two
/// walls, `crate::contact::geometry::walls`). The same holds for a cube's edge in 3D (the block
/// as primary 23% and 45% below the same-mesh reference, the cube within 2%).
fn cornered_side(sides: &[ContactSide; 2]) -> Option<usize> {
    let cornered = sides
        .each_ref()
        .map(|side| side.1.sharpest_turn() > CORNER_TURN);
    match cornered {
        [true, false] => Some(0),
        [false, true] => Some(1),
        _ => None,
    }
}

/// Which of `sides` carries the multiplier (its index) under `choice`, and the report of why;
/// `spacing_near` is [`contact_zone_spacing`] of each side. An explicit choice is compared with
/// what "auto" would choose (module doc of [`PrimaryChoice::Auto`]).
fn choose_primary(
    choice: &PrimaryChoice,
    sides: &[ContactSide; 2],
    spacing_near: [f64; 2],
) -> Result<(usize, PrimaryReport), String> {
    let name = |side: &ContactSide| side.0.body.name.clone();
    let stiffness = contact_modulus(&sides[1]) / contact_modulus(&sides[0]);
    // Symmetric in the two bodies: at a ratio of exactly 2 the order they are listed in must
    // not decide.
    let similar = stiffness.max(1.0 / stiffness) < SIMILAR_STIFFNESS;
    let (auto_first, auto_reason) = if !similar {
        let first = usize::from(stiffness < 1.0);
        (
            first,
            format!(
                "the more compliant body: contact modulus E/(1-nu^2) {:.3e} against {:.3e} for '{}'",
                contact_modulus(&sides[first]),
                contact_modulus(&sides[1 - first]),
                name(&sides[1 - first])
            ),
        )
    } else if let Some(first) = cornered_side(sides) {
        (
            first,
            format!(
                "similar stiffness (ratio {:.2}); the body with a corner: '{}''s contact surface \
                 turns by {:.0} degrees at a vertex or edge, '{}''s by at most {CORNER_TURN}",
                stiffness.max(1.0 / stiffness),
                name(&sides[first]),
                sides[first].1.sharpest_turn(),
                name(&sides[1 - first]),
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
    let PrimaryChoice::Body(body) = choice else {
        let other_primary = match similar {
            true => OtherPrimary::RetryIfUntrusted,
            false => OtherPrimary::Unused,
        };
        let report = PrimaryReport {
            mode: "auto",
            reason: auto_reason,
            other_primary,
        };
        return Ok((auto_first, report));
    };
    let first = (sides.iter().position(|s| &s.0.body.name == body)).ok_or_else(|| {
        format!(
            "primary = '{body}' is neither of the contact bodies '{}' and '{}' (or \"auto\")",
            name(&sides[0]),
            name(&sides[1])
        )
    })?;
    // Between bodies of similar stiffness either choice is stable (the coarser one is auto's
    // for accuracy), and the other one's answer may be the one that fails; a stiff primary is
    // the unstable choice.
    let auto = name(&sides[auto_first]);
    let (other_primary, reason) = if first == auto_first {
        let reason = format!("named in the case file (as \"auto\" would: {auto_reason})");
        (OtherPrimary::Unused, reason)
    } else if similar {
        let reason = format!(
            "named in the case file; \"auto\" would choose '{auto}' ({auto_reason}); between \
             bodies of similar stiffness either primary is stable"
        );
        (OtherPrimary::Unused, reason)
    } else {
        let reason = format!(
            "named in the case file; \"auto\" would choose '{auto}' ({auto_reason}), so the \
             answer is checked against the one with '{auto}' as primary"
        );
        (OtherPrimary::CheckAgreement, reason)
    };
    let report = PrimaryReport {
        mode: "explicit",
        reason,
        other_primary,
    };
    Ok((first, report))
}
