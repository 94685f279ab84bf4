//! Tied contact (the original INTERNODES contact system): one multiplier per component of the
//! traction, and the vector constraint `u1_i - (R12 u2)_i = (d_i + e_i) n_i` through the
//! interpolation, `e` the gap correction of the last iterate
//! (`crate::contact::coupled::interface`). The active surfaces are glued together.

use super::{Multiplier, Reads, Restates};

/// `lambda = sum_c lambda_c e_c`, row `c` the component `c` of the constraint (plus
/// `gap_compliance lambda_c`: the glue is a spring under the penalty method); each dropped
/// where its own dof is prescribed.
pub(super) fn multipliers(dim: usize, gap_compliance: f64) -> Vec<Multiplier> {
    (0..dim)
        .map(|c| {
            let axis: [f64; 3] = std::array::from_fn(|k| f64::from(u8::from(k == c)));
            Multiplier {
                force: axis,
                row: axis,
                reads: Reads::Interpolated,
                restates: Restates::Component(c),
                compliance: gap_compliance,
            }
        })
        .collect()
}
