//! The certificate of a contact answer: its checks, each a figure against a tolerance with the
//! place of its worst value. The residual checks say whether the discrete problem is solved
//! (they decide the status); the accuracy indicators say whether its answer can be trusted
//! (a report, never the status). `crate::contact::verify::checks` measures them and says why each
//! is what it is.

use serde::Serialize;

/// What a check measures. The first five are residuals of the discrete contact problem: they
/// decide whether it is solved (the status, `contact_status`). The others are accuracy
/// indicators: they say whether the solved problem's answer can be trusted (the accuracy
/// report), and never change the status.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
pub enum CheckKind {
    /// Primal feasibility: no primary node inside the other body (over its spacing).
    #[serde(rename = "penetration")]
    Penetration,
    /// Primal feasibility of the secondary's nodes, which only the transfer holds.
    #[serde(rename = "secondary penetration")]
    SecondaryPenetration,
    /// Dual feasibility: no surface node of either body pulled (over the largest pressure).
    #[serde(rename = "tension")]
    Tension,
    /// Complementarity: every active node on the other surface (over its spacing).
    #[serde(rename = "complementarity")]
    Complementarity,
    /// Equilibrium of the interface: the contact forces on the two bodies balance.
    #[serde(rename = "equilibrium")]
    Equilibrium,
    /// Coulomb's dual feasibility: no tangential traction beyond `mu p` (over `mu p_max`).
    #[serde(rename = "friction cone")]
    FrictionCone,
    /// Coulomb's slip rule: sticking nodes do not slip, slipping nodes slip against their
    /// friction traction (over the spacing).
    #[serde(rename = "slip")]
    Slip,
    /// The secondary's sag between constrained primary nodes, over the indentation depth.
    #[serde(rename = "secondary sag")]
    SecondarySag,
    /// The penalty method's overlap `p / eps` (pressure-weighted), over the indentation depth:
    /// the relative error of the force it makes.
    #[serde(rename = "penalty overlap")]
    PenaltyOverlap,
    /// The contact zone's width in spacings, against the minimum.
    #[serde(rename = "resolution")]
    Resolution,
    /// Where the two bodies' contact forces act, over the coarser spacing.
    #[serde(rename = "force centre")]
    ForceCentre,
    /// The stick zone's width in spacings, against the minimum (Coulomb pairs in partial slip).
    #[serde(rename = "stick zone resolution")]
    StickResolution,
    /// The contact force against the other primary's.
    #[serde(rename = "primary agreement")]
    PrimaryAgreement,
    /// The contact force against the one with the transfer `auto` chooses.
    #[serde(rename = "transfer agreement")]
    TransferAgreement,
}

impl CheckKind {
    /// The name in `summary.json` and in messages.
    pub fn name(self) -> &'static str {
        match self {
            Self::Penetration => "penetration",
            Self::SecondaryPenetration => "secondary penetration",
            Self::Tension => "tension",
            Self::Complementarity => "complementarity",
            Self::Equilibrium => "equilibrium",
            Self::FrictionCone => "friction cone",
            Self::Slip => "slip",
            Self::SecondarySag => "secondary sag",
            Self::PenaltyOverlap => "penalty overlap",
            Self::Resolution => "resolution",
            Self::ForceCentre => "force centre",
            Self::StickResolution => "stick zone resolution",
            Self::PrimaryAgreement => "primary agreement",
            Self::TransferAgreement => "transfer agreement",
        }
    }

    /// A residual of the discrete problem (the status), not an accuracy indicator.
    pub fn is_residual(self) -> bool {
        matches!(
            self,
            Self::Penetration
                | Self::SecondaryPenetration
                | Self::Tension
                | Self::Complementarity
                | Self::Equilibrium
                | Self::FrictionCone
                | Self::Slip
        )
    }

    /// The unit of the figure, for messages.
    fn unit(self) -> &'static str {
        match self {
            Self::Penetration | Self::SecondaryPenetration | Self::Complementarity | Self::Slip => {
                " h"
            }
            Self::FrictionCone => " of mu times the largest pressure",
            Self::Tension => " of the largest pressure",
            Self::SecondarySag | Self::PenaltyOverlap => " of the indentation depth",
            Self::ForceCentre => {
                " of the coarser spacing (between the two bodies' centres of normal force)"
            }
            Self::Resolution => " (spacing over the contact zone's width, over the minimum's, rim)",
            Self::StickResolution => " (spacing over the stick zone's width, over the minimum's)",
            Self::PrimaryAgreement | Self::TransferAgreement | Self::Equilibrium => " of the force",
        }
    }
}

/// The checks of one contact answer: the residuals of the discrete problem and the accuracy
/// indicators ([`CheckKind`]).
#[derive(Debug, Clone)]
pub struct Certificate {
    pub checks: Vec<CertificateCheck>,
}

/// One check: its figure against its tolerance, and where the worst value is.
#[derive(Debug, Clone, Serialize)]
pub struct CertificateCheck {
    pub name: CheckKind,
    pub value: f64,
    pub tolerance: f64,
    pub passed: bool,
    /// Body and gmsh node tag of the worst node (penetration, tension).
    pub body: Option<String>,
    pub node_tag: Option<u64>,
    /// What the figure was compared with, when that is not a node (primary agreement).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

impl Certificate {
    /// Adds a check made outside `crate::contact::verify::checks::certify` (e.g. an agreement
    /// between two discretizations).
    pub fn push(&mut self, check: CertificateCheck) {
        self.checks.push(check);
    }

    /// Every residual check passed: the discrete problem is solved.
    pub fn solved(&self) -> bool {
        self.residuals().all(|c| c.passed)
    }

    /// Every accuracy indicator passed.
    pub fn accurate(&self) -> bool {
        self.indicators().all(|c| c.passed)
    }

    /// The residual checks.
    pub fn residuals(&self) -> impl Iterator<Item = &CertificateCheck> {
        self.checks.iter().filter(|c| c.name.is_residual())
    }

    /// The accuracy indicators.
    pub fn indicators(&self) -> impl Iterator<Item = &CertificateCheck> {
        self.checks.iter().filter(|c| !c.name.is_residual())
    }

    /// The kinds of the failed checks.
    pub fn failed(&self) -> Vec<CheckKind> {
        (self.checks.iter())
            .filter(|c| !c.passed)
            .map(|c| c.name)
            .collect()
    }

    /// The names of the failed checks, "secondary sag, resolution": the short form of
    /// [`Self::failures`].
    pub fn failed_names(&self) -> String {
        (self.failed().iter().map(|k| k.name()))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// The failed checks in one line, e.g. for a status message.
    pub fn failures(&self) -> String {
        self.checks
            .iter()
            .filter(|c| !c.passed)
            .map(CertificateCheck::describe)
            .collect::<Vec<_>>()
            .join("; ")
    }
}

/// One source of error in what a user reads, and the indicators of this answer that estimate
/// it ([`Certificate::coverage`]): the accuracy report claims only what they measured.
#[derive(Debug, Clone, Serialize)]
pub struct ErrorCoverage {
    /// The error's source.
    pub error: &'static str,
    /// What it affects of what a user reads.
    pub affects: &'static str,
    /// The indicators of this answer that estimate it (none: not estimated).
    pub estimated_by: Vec<CheckKind>,
    /// What is not estimated of it in this run, and how to estimate it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub not_estimated: Option<&'static str>,
}

impl Certificate {
    /// Which errors of what a user reads the accuracy report estimates, and which it does not
    /// (`docs/method.md` 4.2):
    /// - the penalty method's overlap, where it enforced the contact: by the penalty overlap;
    /// - the coupling of the two meshes at the interface (the multiplier space, the transfer,
    ///   the secondary's sag between primary nodes): by the sag and the force centres, and by
    ///   another discretization of the coupling only where the other primary or the automatic
    ///   transfer was solved too (primary or transfer agreement);
    /// - the resolution of the contact zone: by the zone's width in spacings;
    /// - the bulk discretization of each body (P1 elements, faceted curved surfaces): never;
    ///   one mesh cannot measure its own error, a refinement study does.
    pub fn coverage(&self) -> Vec<ErrorCoverage> {
        let has = |kind: CheckKind| self.checks.iter().any(|c| c.name == kind);
        let present = |kinds: &[CheckKind]| -> Vec<CheckKind> {
            kinds.iter().copied().filter(|&k| has(k)).collect()
        };
        use CheckKind::*;
        let compared = has(PrimaryAgreement) || has(TransferAgreement);
        // The penalty method's own error, where it enforced the contact.
        let penalty = has(PenaltyOverlap).then(|| ErrorCoverage {
            error: "penalty",
            affects: "contact force, contact zone (the bodies overlap by p / eps)",
            estimated_by: vec![PenaltyOverlap],
            not_estimated: None,
        });
        let mut coverage = vec![
            ErrorCoverage {
                error: "interface coupling",
                affects: "contact force and where it acts",
                estimated_by: present(&[
                    SecondarySag,
                    ForceCentre,
                    PrimaryAgreement,
                    TransferAgreement,
                ]),
                not_estimated: (!compared).then_some(
                    "by another discretization of the coupling: only the secondary's sag and \
                     the force centres were measured; [contact] check_other_primary = true \
                     solves the other body as primary and compares the forces",
                ),
            },
            ErrorCoverage {
                error: "contact zone resolution",
                affects: "contact zone, peak pressure",
                estimated_by: present(&[Resolution]),
                not_estimated: None,
            },
            ErrorCoverage {
                error: "stick zone resolution",
                affects: "stick and slip zones, tangential traction profile",
                estimated_by: present(&[StickResolution]),
                not_estimated: (has(FrictionCone) && !has(StickResolution)).then_some(
                    "no stick zone (every node in contact slips, or none sticks across more \
                     than one node): the tangential force is mu times the normal force node by \
                     node; the other primary's tangential force is compared with \
                     check_other_primary = true (the whole force vector)",
                ),
            },
            ErrorCoverage {
                error: "bulk discretization",
                affects: "contact force, contact zone, peak pressure, stresses",
                estimated_by: Vec::new(),
                not_estimated: Some(
                    "the P1 error of each body's mesh and its faceted surfaces: one mesh \
                     cannot measure its own discretization error; solve a refinement \
                     sequence (internodes study CASE.toml --parameter level=0,1,2)",
                ),
            },
        ];
        coverage.splice(1..1, penalty);
        coverage
    }
}

impl CertificateCheck {
    pub fn describe(&self) -> String {
        let at = match (&self.body, self.node_tag) {
            (Some(body), Some(tag)) => format!(" at node {tag} of '{body}'"),
            _ => String::new(),
        };
        let unit = self.name.unit();
        let note = self
            .note
            .as_ref()
            .map_or(String::new(), |note| format!(": {note}"));
        format!(
            "{} {:.3e}{unit}{at} (tolerance {:.1e}){note}",
            self.name.name(),
            self.value,
            self.tolerance
        )
    }
}
