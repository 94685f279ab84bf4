//! How a pair's contact law is enforced: INTERNODES or the penalty method, switched by the
//! pair's `method` key ([`crate::contact::Method`]); the only place that tells the two apart.
//! Everything else is shared: the candidates, the geometric gap and its linearization
//! (`crate::contact::geometry::gap`), the law's multipliers (`crate::contact::law`), the
//! active-set loop, the coupled system, the checks and the outputs.
//!
//! **INTERNODES.** The primary's active nodes carry the multiplier `lambda`, and each row holds
//! its node on the other surface exactly, `g_lin = 0`; the secondary receives `-M2 R21 lambda`
//! or `-R12^T M1 lambda` (the pair's transfer, [`crate::contact::Transfer`]).
//!
//! **Penalty.** Each primary node is pushed out of the other body by the pressure
//! `p = eps max(0, -g)` on its gap `g` (the same gap and rim rule), `eps = penalty E* / h`
//! (`E*` the pair's contact modulus, `h` the primary's spacing where contact starts,
//! [`crate::contact::ContactProblem::penalty_stiffness`]). The pressure stays an unknown of the
//! system (the perturbed Lagrangian form): at an active node the row is INTERNODES' with the
//! own term `1 / eps`,
//!
//! ```text
//! g_lin(u) + p / eps = 0,    i.e.   n . (u1 - sum_k b_k u2_k) + lambda_n / eps = n . target,
//! ```
//!
//! and eliminating `p` gives the penalty stiffness `eps A n n^T` of the pure penalty method,
//! hence the same answer. Kept as an unknown, it adds the diagonal `1 / eps` to the interface
//! block instead of `eps` to the bodies' stiffness: the system tends to INTERNODES' as `eps`
//! grows, and no penalty makes it ill-conditioned. The loop's update is unchanged: an active
//! node stays active while `p > 0`, which is `g < 0`, and an open node becomes active where
//! `g < 0`, the semismooth Newton step of `p - eps max(0, -g) = 0`.
//!
//! The traction reaches the secondary through the pair's transfer, as INTERNODES' multiplier
//! does: the enforcement is the one thing that differs, and as `eps` grows the answer tends to
//! INTERNODES' on the same meshes. (Node to segment, the transpose of the gap row, was tried:
//! between two blocks meshed apart it spreads a uniform pressure unevenly onto the secondary, and
//! the uniaxial stress came out 0.5% low in 3D at any penalty; the interpolation reproduces it.)
//! Which rows the penalty relaxes is the law's: the normal row, and the glue of tied contact; a
//! Coulomb node's stick stays exact (`crate::contact::law`).
//!
//! What the penalty leaves: active nodes overlap the other body by `p / eps`, the method's own
//! error (the checks measure the penetration beyond it, `crate::contact::verify::checks`), and
//! the force of a displacement-controlled run is low by about the share of that overlap in the
//! approach.

use crate::contact::problem::ContactProblem;

/// How one pair's law is enforced (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Enforcement {
    Internodes,
    /// The penalty `eps` (a pressure per length of overlap).
    Penalty {
        stiffness: f64,
    },
}

impl Enforcement {
    /// The enforcement `problem`'s settings ask for.
    pub fn of(problem: &ContactProblem) -> Self {
        match problem.penalty_stiffness() {
            None => Self::Internodes,
            Some(stiffness) => Self::Penalty { stiffness },
        }
    }

    /// The own term of the rows that hold a node on the other surface: `1 / eps`, or zero.
    pub fn gap_compliance(self) -> f64 {
        match self {
            Self::Internodes => 0.0,
            Self::Penalty { stiffness } => 1.0 / stiffness,
        }
    }

    /// What the row of an active node with gap `gap` and pressure `pressure` leaves
    /// unbalanced: `g + p / eps` (INTERNODES: `g`), zero at the answer.
    pub fn row_residual(self, gap: f64, pressure: f64) -> f64 {
        gap + pressure * self.gap_compliance()
    }
}
