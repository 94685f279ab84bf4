//! Frictionless contact: one scalar multiplier per active node, the pressure along the normal,
//! and only the normal gap held (node to segment, `crate::contact::geometry::gap`). The surfaces
//! slide freely: no tangential traction.

use super::{Multiplier, Reads, Restates};

/// `lambda = lambda_n n`, the row `n . (u1 - u2(point)) + gap_compliance lambda_n = n . target`;
/// dropped where every dof of the node is prescribed.
pub(super) fn multipliers(normal: [f64; 3], gap_compliance: f64) -> Vec<Multiplier> {
    vec![Multiplier {
        force: normal,
        row: normal,
        reads: Reads::Geometric,
        restates: Restates::Node,
        compliance: gap_compliance,
    }]
}
