//! How a contact solve ended, and what it found.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::contact::active_set::ActiveSet;
use crate::contact::certificate::{Certificate, CheckKind};
use crate::contact::settings::Formulation;
use crate::elastic::ElasticSolution;

/// How the active-set loop ended. Only `Converged` is a contact solution; the others carry the
/// last iterate so that it can be inspected.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ContactStatus {
    /// The discrete contact problem is solved: the active set settled and every residual,
    /// measured independently of the loop, is within its tolerance: no node of either surface
    /// penetrates the other body or receives a tensile force, every active node lies on the
    /// other surface, and the contact forces balance. Whether the answer is accurate is the
    /// accuracy report's question ([`crate::contact::Certificate::accurate`]), not the status's.
    Converged,
    /// The active set settled but a residual check failed (it says which, where, and by how
    /// much): the discrete problem is not solved.
    NotSolved,
    /// The active set settled empty and every residual check passed: the bodies do not touch.
    NoContact,
    /// The iteration cap was reached.
    IterationLimit,
    /// An active node ended a spacing or more off the other body's surface: the interpolated
    /// constraint no longer controls the geometry. Seen with a primary body much stiffer than
    /// the secondary and a contact surface as fine as the secondary's, whose multiplier has
    /// modes that nothing controls (the inf-sup condition; `primary = "auto"` avoids it).
    Unstable,
    /// An active set seen before came back: the loop would repeat forever.
    Cycling,
    /// On an unchanged active set, the active nodes' distance to the other surface stopped
    /// shrinking (by half per iteration, twice in a row): the linearized constraint no longer
    /// converges to the geometric one, and iterating on would not end.
    Stalled,
}

impl ContactStatus {
    /// `converged` or `no-contact`: the loop's answer is a contact solution.
    pub fn is_solution(self) -> bool {
        matches!(self, Self::Converged | Self::NoContact)
    }

    /// The status as written in `summary.json` (kebab case).
    pub fn name(self) -> &'static str {
        match self {
            Self::Converged => "converged",
            Self::NotSolved => "not-solved",
            Self::NoContact => "no-contact",
            Self::IterationLimit => "iteration-limit",
            Self::Unstable => "unstable",
            Self::Cycling => "cycling",
            Self::Stalled => "stalled",
        }
    }
}

/// Wall-clock seconds of the phases of one iteration.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct PhaseSeconds {
    /// Rows and columns of the interface operators for the active set.
    pub operators: f64,
    /// Assembly and solution of the coupled system, residual check.
    pub solve: f64,
    /// The interface search: closest-point projection of every candidate (geometric gaps) and
    /// the linearized gaps.
    pub search: f64,
    /// The active-set update.
    pub checks: f64,
}

/// A failed solve's surfaces slid this many spacings or more from the pairing are named in its
/// explanation ([`ContactSolution::summary`]): the RBF supports reach about two spacings, and a
/// pairing a spacing off reads the other body's displacement at the wrong nodes.
const SLID_OFF_PAIRING: f64 = 1.0;

/// One line of the iteration history.
#[derive(Debug, Clone, Serialize)]
pub struct IterationRecord {
    pub iteration: usize,
    /// Active primary nodes of this iteration.
    pub active: usize,
    /// Nodes the update adds (inactive, penetrating) and removes (active, in tension).
    pub added: usize,
    pub removed: usize,
    /// Largest penetration of an inactive primary candidate over its spacing h (0 if none).
    pub max_penetration_over_h: f64,
    /// Largest tension of an active node over the largest pressure (0 if none; 1 if no active
    /// node is compressed: the tension is then measured against the largest tension).
    pub max_tension_over_p: f64,
    /// Largest |geometric gap| of an active node over its h: how far the active nodes are
    /// from the other body's discrete surface.
    pub max_gap_error_over_h: f64,
    /// How far the surfaces have slid over each other from where the interface operators were
    /// paired (the active nodes' mean slide against the pairing's), over the smallest spacing
    /// of the active primary nodes (the pairing follows the slide on a grid of 0.05 of that
    /// spacing, unslid within one step: `docs/method.md` 3.5).
    pub pairing_drift_over_h: f64,
    /// The interface operators were paired again after this iteration, where the surfaces
    /// had slid to (`docs/method.md` 3.5): the next iteration solves on the new pairing.
    pub paired_again: bool,
    pub relative_residual: f64,
    /// GMRES iterations of the iteration's interface solves (a loose solve and, when its
    /// answer keeps the active set, the exact one); `None` on the dense paths.
    pub krylov_iterations: Option<usize>,
    /// Coulomb pairs: the nodes in contact that slip next, and the largest change of a
    /// slipping node's direction.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub slipping: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_direction_change: Option<f64>,
    pub seconds: PhaseSeconds,
}

impl IterationRecord {
    /// The log line of this iteration; with `phases` (the `-vv` log) the seconds of its
    /// phases too, which keeps the `-v` line near 120 characters.
    pub fn line(&self, phases: bool) -> String {
        let t = &self.seconds;
        let phases = match phases {
            true => format!(
                " (operators {:.3}, solve {:.3}, search {:.3})",
                t.operators, t.solve, t.search
            ),
            false => String::new(),
        };
        format!(
            "  iteration {:>3}: active {:>5}, +{:<4} -{:<4} penetration {:.1e} h, tension {:.1e} p_max, active gap {:.1e} h, slid {:.1e} h; {:.3} s{phases}",
            self.iteration,
            self.active,
            self.added,
            self.removed,
            self.max_penetration_over_h,
            self.max_tension_over_p,
            self.max_gap_error_over_h,
            self.pairing_drift_over_h,
            t.operators + t.solve + t.search + t.checks,
        ) + match self.paired_again {
            true => "; paired again",
            false => "",
        } + &self.slipping.map_or(String::new(), |slip| {
            format!(
                "; slipping {slip}, direction change {:.1e}",
                self.max_direction_change.unwrap_or(0.0)
            )
        })
    }
}

/// Interface fields on a candidate surface, one entry per surface node.
#[derive(Debug, Clone, Default)]
pub struct SurfaceFields {
    /// Body-local node of each surface node.
    pub nodes: Vec<usize>,
    /// Contact traction on this body (zero at inactive nodes).
    pub traction: Vec<[f64; 3]>,
    /// Contact pressure `p = -traction . n` (positive in compression), `n` the node's outward
    /// normal.
    pub pressure: Vec<f64>,
    /// Normal contact force of each node over its area
    /// ([`crate::contact::ContactSurface::mean_pressure`]); with the lumped interface mass, equal
    /// to `pressure` on the primary surface.
    pub mean_pressure: Vec<f64>,
    /// Geometric gap to the other body's surface in the deformed configuration: signed distance
    /// to its closest point, negative inside the other body (defined at any distance).
    pub normal_gap: Vec<f64>,
    pub active: Vec<bool>,
    /// A Coulomb pair's primary: the tangential answer at every node.
    pub friction: Option<FrictionFields>,
}

/// The state of a primary candidate of a Coulomb pair.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum FrictionState {
    Open,
    Stick,
    Slip,
}

impl FrictionState {
    /// The value written to the surface fields: 0 open, 1 stick, 2 slip.
    pub fn code(self) -> f64 {
        match self {
            Self::Open => 0.0,
            Self::Stick => 1.0,
            Self::Slip => 2.0,
        }
    }
}

/// A Coulomb pair's tangential answer on its primary surface (`crate::contact::law::coulomb`),
/// every candidate node in the order of [`SurfaceFields::nodes`].
#[derive(Debug, Clone, PartialEq)]
pub struct FrictionFields {
    pub state: Vec<FrictionState>,
    /// The tangential traction on the primary, `t_T = lambda - (lambda . n) n`.
    pub tangential_traction: Vec<[f64; 3]>,
    /// The tangential slip of the primary relative to the secondary over the load step.
    pub slip_increment: Vec<[f64; 3]>,
    /// The length of each node's tangential slip path over all load steps so far.
    pub accumulated_slip: Vec<f64>,
    /// The total contact force on the primary split along the contact zone's mean normal
    /// `N` (the primary's own outward normals weighted by the nodes' normal forces): the normal force
    /// `P = -F . N` and the tangential force `Q = F + P N` (Johnson's P and Q). Each node's
    /// `tangential_traction` is relative to its own contact normal instead (the normal of the
    /// facet of the other surface it is held on).
    pub tangential_force: [f64; 3],
    pub normal_force: f64,
    pub stick_nodes: usize,
    pub slip_nodes: usize,
}

/// Least-squares fit of the Hertz ellipse `p^2 = p0^2 (1 - r^2 / a^2)` to the mean pressures of
/// the active nodes.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct HertzFit {
    /// Contact radius (3D) or half-width (2D).
    pub a: f64,
    pub p0: f64,
    /// Centre of the contact zone: the vertex of the fitted profile
    /// (`crate::contact::verify::hertz`).
    pub center: [f64; 3],
}

/// The linear solvers a contact solve ran, `auto` resolved.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LinearSolvers {
    /// Each body's: `"cholesky"` or `"cg-amg"` (`"monolithic-lu"` factors the whole system).
    pub body: &'static str,
    /// The coupled system's: `"krylov"` (one preconditioned GMRES on the whole system),
    /// `"schur"` (the dense interface Schur complement) or `"monolithic-lu"`.
    pub interface: &'static str,
    /// Why an `auto` solve left GMRES for the dense Schur complement (then `interface` is
    /// `"schur"` from that iteration on).
    pub krylov_failure: Option<String>,
    /// On the Krylov path, the applications of each body's block of the preconditioner over
    /// the whole solve, `[primary, secondary]`, all load steps: one AMG V-cycle each with
    /// `"cg-amg"` bodies, one pair of triangular solves with `"cholesky"`.
    pub body_applications: Option<Vec<usize>>,
}

/// Everything a contact solve produces.
pub struct ContactSolution {
    pub linear_solvers: LinearSolvers,
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
    /// The independent checks of the answer.
    pub certificate: Certificate,
    pub hertz_primary: Option<HertzFit>,
    /// The factor the loads and prescribed displacements were scaled by (those that follow the
    /// default load path).
    pub load_factor: f64,
    /// The factor of each named load path the solve was given (`solve_contact_steps` gives
    /// those the pairs' bodies follow; empty without a `[load_path]`).
    pub path_factors: BTreeMap<String, f64>,
    /// The displacement of each force-controlled component, primary's first.
    pub forced: Vec<ForcedDisplacement>,
    /// The active set at the end, from which a next load step starts.
    pub active_set: ActiveSet,
}

/// How far a force-controlled group moved under its force (`[[body.force]]`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ForcedDisplacement {
    pub body: String,
    pub group: String,
    /// `"x"`, `"y"` or `"z"`.
    pub component: &'static str,
    /// The force at this load step: the prescribed one times its load path's factor.
    pub force: f64,
    /// The group's displacement along the component: the solve's unknown.
    pub displacement: f64,
}

impl ContactSolution {
    /// How the solve ended, in the one line of the default log: for an answer the iterations,
    /// the force, the contact size (and the penalty method's largest overlap) and the accuracy
    /// report's failed indicators by name (the
    /// checks themselves are [`Self::details`]); any other ending with its explanation, which
    /// the error message (the status's name) does not give.
    pub fn summary(&self) -> String {
        if self.status != ContactStatus::Converged {
            return self.outcome();
        }
        let nodes = self.primary_fields.active.iter().filter(|&&a| a).count();
        let slipping = (self.primary_fields.friction.as_ref())
            .map_or(String::new(), |f| format!(" ({} slipping)", f.slip_nodes));
        let accuracy = match self.certificate.accurate() {
            true => String::new(),
            false => format!(
                ", accuracy report failed ({})",
                self.certificate.failed_names()
            ),
        };
        // The penalty method's overlap, its own error (the indicator's note holds it).
        let overlap = (self.certificate.checks.iter())
            .find(|c| c.name == CheckKind::PenaltyOverlap)
            .and_then(|c| c.note.clone())
            .map_or(String::new(), |note| format!(", {note}"));
        format!(
            "{}{accuracy}; force {:.4e}, {nodes} contact nodes{slipping}{overlap}",
            self.outcome(),
            norm(&self.force_primary)
        )
    }

    /// What [`Self::summary`] leaves out (the `-v` log): the force to seven digits and the
    /// Hertz fit of an answer, then each check on a line of its own (one line of all of them
    /// ran to 700 characters) and the accuracy report's verdict.
    pub fn details(&self, formulation: Formulation) -> String {
        let mut lines = Vec::new();
        if self.status == ContactStatus::Converged {
            lines.push(format!(
                "  contact force {:.6e}{}{}",
                norm(&self.force_primary),
                self.hertz_primary.map_or(String::new(), |h| format!(
                    ", Hertz fit a = {:.6e}, p0 = {:.6e}",
                    h.a, h.p0
                )),
                if formulation == Formulation::Tied {
                    format!(
                        ", largest tangential traction {:.3e}",
                        self.max_tangential_traction
                    )
                } else {
                    String::new()
                }
            ));
        }
        lines.push("  checks:".to_string());
        lines.extend((self.certificate.checks.iter()).map(|c| format!("    {}", c.describe())));
        lines.push(format!(
            "  accuracy report: {}",
            match self.certificate.accurate() {
                true => "passed".to_string(),
                false => format!("FAILED ({})", self.certificate.failed_names()),
            }
        ));
        lines.join("\n")
    }

    /// The status in words, with the explanation of an ending that is not an answer.
    fn outcome(&self) -> String {
        let iterations = self.history.len();
        match self.status {
            ContactStatus::Converged => {
                format!("converged in {iterations} iterations")
            }
            ContactStatus::NoContact => {
                "no contact: the bodies do not touch; each body was solved alone".to_string()
            }
            ContactStatus::NotSolved => format!(
                "NOT solved: the active set settled in {iterations} iterations but a residual check failed: {}",
                self.certificate.failures()
            ),
            ContactStatus::IterationLimit => format!(
                "NOT converged: the iteration cap ({iterations}) was reached{}",
                self.slid_off_pairing()
            ),
            ContactStatus::Unstable => match self.slid_off_pairing() {
                slid if slid.is_empty() => format!(
                    "NOT converged: at iteration {iterations} an active node is {:.1e} spacings off the other body's surface: the interpolated constraint does not control the geometry, typically a primary much stiffer than the secondary with as fine a contact surface (inf-sup; primary = \"auto\" takes the compliant body)",
                    self.last_gap_error()
                ),
                slid => format!(
                    "NOT converged: at iteration {iterations} an active node is {:.1e} spacings off the other body's surface{slid}",
                    self.last_gap_error()
                ),
            },
            ContactStatus::Cycling => format!(
                "NOT converged: the active set cycles (an earlier set came back at iteration {iterations}){}",
                self.slid_off_pairing()
            ),
            ContactStatus::Stalled => format!(
                "NOT converged: on an unchanged active set the active nodes' distance to the other surface stopped shrinking ({:.1e} spacings at iteration {iterations}){}",
                self.last_gap_error(),
                self.slid_off_pairing()
            ),
        }
    }

    /// The active nodes' largest distance to the other surface at the last iteration, in
    /// spacings.
    fn last_gap_error(&self) -> f64 {
        (self.history.last()).map_or(f64::NAN, |r| r.max_gap_error_over_h)
    }

    /// Where a solve ended with the surfaces slid a spacing or more from where its operators
    /// were paired, what that means (empty otherwise): the pairing follows the slide only once
    /// an active set settles (`docs/method.md` 3.5), so a loop whose surfaces keep sliding
    /// reads the other body's displacement and sends its force where the contact is no longer.
    /// The equal-material corner as the secondary ends so (its two sides slide apart by up to
    /// ten spacings on refined meshes), a body pushed sideways whose set settles does not.
    fn slid_off_pairing(&self) -> String {
        let slid = (self.history.last()).map_or(0.0, |r| r.pairing_drift_over_h);
        if slid.is_nan() || slid < SLID_OFF_PAIRING {
            return String::new();
        }
        format!(
            "; the surfaces had slid {slid:.1} spacings from where the interface was paired, which \
             follows them only once an active set settles (at every iteration only where a corner \
             of the primary digs a groove): contact that slides this far before it settles (a \
             corner of the secondary pressed into a body as compliant as itself) is beyond it"
        )
    }

    /// How the solve ended, in a few words (for the primary choice's reason): the status, and
    /// the failed checks of a `not-solved` one or of a failed accuracy report.
    pub fn ending(&self) -> String {
        let status = self.status.name();
        let failures = self.certificate.failures();
        match self.status {
            ContactStatus::NotSolved => format!("{status} ({failures})"),
            _ if self.status.is_solution() && !failures.is_empty() => {
                format!("{status}, accuracy report failed ({failures})")
            }
            _ => status.to_string(),
        }
    }

    /// Whether this is an answer to rely on: the problem solved (or no contact) and the
    /// accuracy report passed.
    pub fn is_trusted(&self) -> bool {
        self.status.is_solution() && self.certificate.accurate()
    }

    /// Whether another primary could give a better answer: not where this one is solved and
    /// every indicator passed but the penalty overlap, the penalty method's own error, which
    /// another primary does not mend (it only changes `eps` with the primary's spacing).
    pub fn wants_other_primary(&self) -> bool {
        let discretized = (self.certificate.indicators())
            .all(|c| c.passed || c.name == CheckKind::PenaltyOverlap);
        !(self.status.is_solution() && discretized)
    }

    /// Adds an accuracy indicator computed after the loop (e.g.
    /// `crate::contact::verify::checks::agreement`) to the report.
    pub fn certify_further(&mut self, check: crate::contact::certificate::CertificateCheck) {
        debug_assert!(!check.name.is_residual());
        self.certificate.push(check);
    }
}

fn norm(f: &[f64; 3]) -> f64 {
    (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt()
}

#[cfg(test)]
mod tests {
    use super::ContactStatus;

    #[test]
    fn status_names_are_the_summary_json_names() {
        use ContactStatus::*;
        for status in [
            Converged,
            NotSolved,
            NoContact,
            IterationLimit,
            Unstable,
            Cycling,
            Stalled,
        ] {
            assert_eq!(serde_json::to_value(status).unwrap(), status.name());
        }
    }
}
