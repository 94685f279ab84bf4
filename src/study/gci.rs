//! Discretization error of one quantity from its values on a sequence of meshes: the observed
//! order, Richardson extrapolation and the grid convergence index (GCI), by the procedure of
//! Celik, Ghia, Roache, Freitas, Coleman and Raad (2008), "Procedure for estimation and
//! reporting of uncertainty due to discretization in CFD applications", J. Fluids Eng. 130,
//! 078001, which allows refinement ratios that differ from one pair of meshes to the next.
//!
//! The meshes are numbered from the finest: `h1 < h2 < h3` are their spacings and `phi1`,
//! `phi2`, `phi3` the quantity on them (only the three finest of a longer sequence are used).
//! With
//!
//! ```text
//! r21 = h2 / h1,   r32 = h3 / h2,   eps21 = phi2 - phi1,   eps32 = phi3 - phi2,
//! s = sign(eps32 / eps21),
//! ```
//!
//! the observed order `p` solves, by fixed-point iteration from `q = 0`,
//!
//! ```text
//! p = |ln|eps32 / eps21| + q(p)| / ln r21,   q(p) = ln((r21^p - s) / (r32^p - s))
//! ```
//!
//! (`q = 0` when `r21 = r32`: then `p = |ln|eps32 / eps21|| / ln r`). Then
//!
//! ```text
//! phi_ext    = (r21^p phi1 - phi2) / (r21^p - 1)          Richardson extrapolation
//! e_a21      = |(phi1 - phi2) / phi1|                      approximate relative error
//! e_ext21    = |(phi_ext - phi1) / phi_ext|                extrapolated relative error
//! GCI_fine21 = Fs e_a21 / (r21^p - 1),   Fs = 1.25         fine-grid convergence index
//! GCI_32     = Fs e_a32 / (r32^p - 1),   e_a32 = |(phi2 - phi3) / phi2|
//! ```
//!
//! `GCI_fine21` is a relative uncertainty of `phi1`: the band `phi1 (1 +- GCI_fine21)` is meant to
//! hold the exact value with about 95% confidence when the sequence is in its asymptotic range
//! (Roache's safety factor 1.25 for three or more meshes, as ASME V&V 20 uses it). Whether it is
//! in that range is judged by [`Flag`]s:
//!
//! - the sign `s`: `s < 0` is oscillatory convergence (the differences change sign);
//! - divergence: `ln|eps32 / eps21| + q(p) < 0`, i.e. the order equation holds only with the
//!   absolute value taken, the errors growing under refinement. With equal ratios this is the
//!   usual `|R| >= 1` on the convergence ratio `R = eps21 / eps32` (reported too), which alone
//!   would misjudge unequal ratios: `phi = 2 + 0.7 h^1.7` on `h = 0.1, 0.23, 0.31` has `R = 1.15`;
//! - `p` within [`ORDER_RANGE`];
//! - Roache's ratio `GCI_32 / (r21^p GCI_fine21)` within [`GCI_RATIO_RANGE`] of 1: on a sequence
//!   `phi = phi0 + C h^p` it is exactly `|phi1 / phi2|`.
//!
//! With two meshes only no order can be observed: the difference `phi1 - phi2` and `e_a21` are
//! reported, with the flag [`Flag::TwoLevels`], and nothing else.

use serde::Serialize;

/// Roache's safety factor for three or more meshes.
pub const SAFETY_FACTOR: f64 = 1.25;

/// Observed orders outside this range flag the sequence: P1 elements have formal orders 1
/// (tractions) to 2 (displacements, energy-like quantities), and the kinks of a contact solution
/// lower them; an order below 0.5 or above 3 says the differences are not yet (or no longer)
/// dominated by the leading error term.
pub const ORDER_RANGE: (f64, f64) = (0.5, 3.0);

/// Roache's asymptotic-range ratio `GCI_32 / (r21^p GCI_fine21)` outside this range flags the
/// sequence.
pub const GCI_RATIO_RANGE: (f64, f64) = (0.9, 1.1);

/// Differences below this fraction of `|phi1|` are round-off: no order is computed from them.
pub const ROUND_OFF: f64 = 1e-12;

/// Iterations of the fixed-point iteration for `p`, and its relative tolerance.
const MAX_ITERATIONS: usize = 500;
const ORDER_TOLERANCE: f64 = 1e-12;

/// Why a sequence is not (shown to be) in its asymptotic range.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Flag {
    /// Two meshes: the difference only, no order, no extrapolation, no GCI.
    TwoLevels,
    /// `phi1 - phi2` or `phi2 - phi3` is round-off ([`ROUND_OFF`]): no order can be observed.
    NoDifference,
    /// The differences change sign (`s < 0`).
    OscillatoryConvergence,
    /// The errors grow with refinement, one sign.
    MonotonicDivergence,
    /// The errors grow with refinement and change sign.
    OscillatoryDivergence,
    /// The fixed-point iteration for `p` did not converge (or left the finite numbers).
    NoOrder,
    /// `p` outside [`ORDER_RANGE`].
    OrderOutOfRange,
    /// `GCI_32 / (r21^p GCI_fine21)` outside [`GCI_RATIO_RANGE`].
    GciRatio,
}

impl Flag {
    /// One line for tables and the documentation.
    pub fn describe(self) -> &'static str {
        match self {
            Flag::TwoLevels => "two levels: difference only, no order",
            Flag::NoDifference => "differences at round-off: no order",
            Flag::OscillatoryConvergence => "oscillatory convergence (differences change sign)",
            Flag::MonotonicDivergence => "monotonic divergence (differences grow)",
            Flag::OscillatoryDivergence => "oscillatory divergence",
            Flag::NoOrder => "the iteration for p did not converge",
            Flag::OrderOutOfRange => "p outside [0.5, 3]",
            Flag::GciRatio => "GCI ratio outside [0.9, 1.1]",
        }
    }
}

/// One quantity's estimate from the finest two or three meshes (numbered from the finest).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Estimate {
    /// `phi1`, `phi2`, and `phi3` with three or more meshes.
    pub phi: Vec<f64>,
    /// `h1`, `h2`, and `h3` with three or more meshes.
    pub h: Vec<f64>,
    /// `r21`, and `r32` with three or more meshes.
    pub ratios: Vec<f64>,
    /// `phi1 - phi2`.
    pub difference: f64,
    /// `e_a21 = |(phi1 - phi2) / phi1|`.
    pub relative_difference: f64,
    /// `R = eps21 / eps32` (three meshes).
    pub convergence_ratio: Option<f64>,
    /// The observed order `p` and the iterations it took.
    pub order: Option<f64>,
    pub iterations: Option<usize>,
    /// `phi_ext`, `e_ext21`, `GCI_fine21`, `GCI_32` and `GCI_32 / (r21^p GCI_fine21)`.
    pub extrapolated: Option<f64>,
    pub extrapolated_error: Option<f64>,
    pub gci_fine: Option<f64>,
    pub gci_coarse: Option<f64>,
    pub gci_ratio: Option<f64>,
    /// Empty when the sequence passed every test of the asymptotic range.
    pub flags: Vec<Flag>,
}

/// Why no estimate can be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GciError {
    #[error("at least two meshes are needed, got {0}")]
    TooFewMeshes(usize),
    #[error("spacing {0} is not a positive finite number")]
    BadSpacing(f64),
    #[error("two meshes have the same spacing {0}: refinement must change it")]
    SameSpacing(f64),
    #[error("the quantity {0} is not finite")]
    NotFinite(f64),
}

/// The estimate from `(h, phi)` pairs of any number (at least two) of meshes in any order.
pub fn estimate(levels: &[(f64, f64)]) -> Result<Estimate, GciError> {
    if levels.len() < 2 {
        return Err(GciError::TooFewMeshes(levels.len()));
    }
    let mut sorted = levels.to_vec();
    for &(h, phi) in &sorted {
        if !(h.is_finite() && h > 0.0) {
            return Err(GciError::BadSpacing(h));
        }
        if !phi.is_finite() {
            return Err(GciError::NotFinite(phi));
        }
    }
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    if let Some(pair) = sorted.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(GciError::SameSpacing(pair[0].0));
    }
    sorted.truncate(3);
    let (h, phi): (Vec<f64>, Vec<f64>) = sorted.into_iter().unzip();
    let ratios: Vec<f64> = h.windows(2).map(|w| w[1] / w[0]).collect();
    let mut estimate = Estimate {
        difference: phi[0] - phi[1],
        relative_difference: ((phi[0] - phi[1]) / phi[0]).abs(),
        phi,
        h,
        ratios,
        convergence_ratio: None,
        order: None,
        iterations: None,
        extrapolated: None,
        extrapolated_error: None,
        gci_fine: None,
        gci_coarse: None,
        gci_ratio: None,
        flags: Vec::new(),
    };
    if estimate.phi.len() == 2 {
        estimate.flags.push(Flag::TwoLevels);
    } else {
        three_meshes(&mut estimate);
    }
    Ok(estimate)
}

/// The order, extrapolation, GCIs and flags of a sequence of three meshes.
fn three_meshes(e: &mut Estimate) {
    let [phi1, phi2, phi3] = [e.phi[0], e.phi[1], e.phi[2]];
    let [r21, r32] = [e.ratios[0], e.ratios[1]];
    let (eps21, eps32) = (phi2 - phi1, phi3 - phi2);
    let round_off = ROUND_OFF * phi1.abs().max(f64::MIN_POSITIVE);
    if eps21.abs() <= round_off || eps32.abs() <= round_off {
        e.flags.push(Flag::NoDifference);
        return;
    }
    let ratio = eps21 / eps32;
    e.convergence_ratio = Some(ratio);
    let sign = (eps32 / eps21).signum();
    let Some((p, iterations)) = observed_order(r21, r32, eps21, eps32) else {
        e.flags.push(Flag::NoOrder);
        return;
    };
    // The order solves |ln|eps32/eps21| + q(p)| = p ln r21; where the expression inside the
    // bars is negative the errors grow with refinement (with r21 = r32: |R| > 1).
    let growing = (eps32 / eps21).abs().ln() + q(p, r21, r32, sign) < 0.0;
    e.flags.extend(match (growing, sign > 0.0) {
        (false, true) => None,
        (false, false) => Some(Flag::OscillatoryConvergence),
        (true, true) => Some(Flag::MonotonicDivergence),
        (true, false) => Some(Flag::OscillatoryDivergence),
    });
    e.order = Some(p);
    e.iterations = Some(iterations);
    if !(ORDER_RANGE.0..=ORDER_RANGE.1).contains(&p) {
        e.flags.push(Flag::OrderOutOfRange);
    }
    let (r21p, r32p) = (r21.powf(p), r32.powf(p));
    let extrapolated = (r21p * phi1 - phi2) / (r21p - 1.0);
    let gci_fine = SAFETY_FACTOR * e.relative_difference / (r21p - 1.0);
    let gci_coarse = SAFETY_FACTOR * ((phi2 - phi3) / phi2).abs() / (r32p - 1.0);
    let gci_ratio = gci_coarse / (r21p * gci_fine);
    if !(GCI_RATIO_RANGE.0..=GCI_RATIO_RANGE.1).contains(&gci_ratio) {
        e.flags.push(Flag::GciRatio);
    }
    e.extrapolated = Some(extrapolated);
    e.extrapolated_error = Some(((extrapolated - phi1) / extrapolated).abs());
    e.gci_fine = Some(gci_fine);
    e.gci_coarse = Some(gci_coarse);
    e.gci_ratio = Some(gci_ratio);
}

/// The observed order `p` of the differences `eps21 = phi2 - phi1` and `eps32 = phi3 - phi2`
/// at the refinement ratios `r21`, `r32`, and the iterations it took: the fixed-point iteration
/// `p <- |ln|eps32 / eps21| + q(p)| / ln r21`, `q(p) = ln((r21^p - s) / (r32^p - s))`,
/// `s = sign(eps32 / eps21)`, from `q = 0`. `None` when it does not converge to a finite
/// positive `p` within 500 iterations.
pub fn observed_order(r21: f64, r32: f64, eps21: f64, eps32: f64) -> Option<(f64, usize)> {
    let s = (eps32 / eps21).signum();
    let log_ratio = (eps32 / eps21).abs().ln();
    let mut p = log_ratio.abs() / r21.ln();
    for iteration in 1..=MAX_ITERATIONS {
        let next = (log_ratio + q(p, r21, r32, s)).abs() / r21.ln();
        if !next.is_finite() {
            return None;
        }
        if (next - p).abs() <= ORDER_TOLERANCE * next.max(1.0) {
            return (next > 0.0).then_some((next, iteration));
        }
        p = next;
    }
    None
}

/// `q(p) = ln((r21^p - s) / (r32^p - s))`.
fn q(p: f64, r21: f64, r32: f64, s: f64) -> f64 {
    ((r21.powf(p) - s) / (r32.powf(p) - s)).ln()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Celik et al. (2008), Table 1, the column of the dimensionless reattachment length: three
    /// 2D grids of N = 18000, 8000, 4500 cells (h ~ N^(-1/2), r21 = 1.5, r32 = 1.333), phi =
    /// 6.063, 5.972, 5.863; the table gives p = 1.53, phi_ext = 6.1685, e_a = 1.5%,
    /// e_ext = 1.7%, GCI_fine = 2.2%.
    #[test]
    fn celik_table_1_reattachment_length() {
        let h = |n: f64| n.powf(-0.5);
        let e = estimate(&[(h(18000.0), 6.063), (h(8000.0), 5.972), (h(4500.0), 5.863)]).unwrap();
        assert!((e.ratios[0] - 1.5).abs() < 1e-12 && (e.ratios[1] - 1.333).abs() < 1e-3);
        assert!((e.order.unwrap() - 1.53).abs() < 0.005, "{e:?}");
        assert!((e.extrapolated.unwrap() - 6.1685).abs() < 5e-5, "{e:?}");
        assert!((e.relative_difference - 0.015).abs() < 5e-4);
        assert!((e.extrapolated_error.unwrap() - 0.017).abs() < 5e-4);
        assert!((e.gci_fine.unwrap() - 0.022).abs() < 5e-4);
        assert_eq!(e.convergence_ratio.map(|r| r > 0.0 && r < 1.0), Some(true));
    }

    /// The next column of the same table: the axial velocity at x/H = 8, y = 0 on grids of
    /// N = 18000, 4500, 980 (r21 = 2, r32 = 2.143), phi = 10.7880, 10.7250, 10.6050; the table
    /// gives p = 0.75, phi_ext = 10.8801, e_a = 0.6%, e_ext = 0.8%, GCI_fine = 1.1%.
    #[test]
    fn celik_table_1_axial_velocity() {
        let e = estimate(&[(1.0, 10.7880), (2.0, 10.7250), (4.286, 10.6050)]).unwrap();
        assert!((e.order.unwrap() - 0.75).abs() < 0.005, "{e:?}");
        assert!((e.extrapolated.unwrap() - 10.8801).abs() < 5e-5, "{e:?}");
        assert!((e.relative_difference - 0.006).abs() < 5e-4);
        assert!((e.extrapolated_error.unwrap() - 0.008).abs() < 5e-4);
        assert!((e.gci_fine.unwrap() - 0.011).abs() < 5e-4);
    }

    /// `phi = phi0 + C h^p` on non-constant ratios gives back p and phi0 to round-off, in any
    /// order of the levels, and is in its asymptotic range (GCI ratio `|phi1 / phi2|`).
    #[test]
    fn manufactured_sequence_gives_its_order_and_limit() {
        for (phi0, c, p) in [(2.0, 0.7, 1.7), (5.0, -3.0, 1.0), (-1.0, 0.2, 2.5)] {
            let hs: [f64; 4] = [0.5, 0.23, 0.1, 0.31];
            let levels: Vec<(f64, f64)> = hs.iter().map(|&h| (h, phi0 + c * h.powf(p))).collect();
            let e = estimate(&levels).unwrap();
            assert_eq!(e.h, vec![0.1, 0.23, 0.31]);
            assert!((e.order.unwrap() - p).abs() < 1e-8, "{e:?}");
            assert!(
                (e.extrapolated.unwrap() - phi0).abs() < 1e-9 * phi0.abs(),
                "{e:?}"
            );
            let ratio = (e.phi[0] / e.phi[1]).abs();
            assert!((e.gci_ratio.unwrap() - ratio).abs() < 1e-9, "{e:?}");
            assert!(e.flags.is_empty(), "{e:?}");
            // The exact value lies in the GCI band of the finest mesh.
            let band = e.gci_fine.unwrap() * e.phi[0].abs();
            assert!((e.phi[0] - phi0).abs() <= band);
        }
    }

    #[test]
    fn an_order_outside_its_range_is_flagged() {
        let levels: Vec<(f64, f64)> = [0.1f64, 0.2, 0.4]
            .iter()
            .map(|&h| (h, 1.0 + h.powf(4.0)))
            .collect();
        let e = estimate(&levels).unwrap();
        assert!((e.order.unwrap() - 4.0).abs() < 1e-8);
        assert_eq!(e.flags, vec![Flag::OrderOutOfRange]);
    }

    #[test]
    fn sign_changes_and_growth_are_flagged() {
        let oscillating = estimate(&[(0.1, 1.0), (0.2, 1.1), (0.4, 0.7)]).unwrap();
        assert!(
            oscillating.flags.contains(&Flag::OscillatoryConvergence),
            "{oscillating:?}"
        );
        let growing = estimate(&[(0.1, 1.0), (0.2, 1.2), (0.4, 1.3)]).unwrap();
        assert!(
            growing.flags.contains(&Flag::MonotonicDivergence),
            "{growing:?}"
        );
        let both = estimate(&[(0.1, 1.0), (0.2, 1.2), (0.4, 1.1)]).unwrap();
        assert!(
            both.flags.contains(&Flag::OscillatoryDivergence),
            "{both:?}"
        );
    }

    #[test]
    fn two_meshes_give_the_difference_and_no_order() {
        let e = estimate(&[(0.2, 4.0), (0.1, 5.0)]).unwrap();
        assert_eq!((e.difference, e.relative_difference), (1.0, 0.2));
        assert_eq!((e.order, e.gci_fine, e.extrapolated), (None, None, None));
        assert_eq!(e.flags, vec![Flag::TwoLevels]);
    }

    #[test]
    fn equal_values_and_bad_input() {
        let flat = estimate(&[(0.1, 3.0), (0.2, 3.0), (0.4, 3.0)]).unwrap();
        assert_eq!(
            (flat.order, flat.flags.clone()),
            (None, vec![Flag::NoDifference])
        );
        assert_eq!(estimate(&[(0.1, 1.0)]), Err(GciError::TooFewMeshes(1)));
        assert_eq!(
            estimate(&[(0.1, 1.0), (0.1, 2.0)]),
            Err(GciError::SameSpacing(0.1))
        );
        assert_eq!(
            estimate(&[(0.0, 1.0), (0.1, 2.0)]),
            Err(GciError::BadSpacing(0.0))
        );
        assert!(matches!(
            estimate(&[(0.2, f64::NAN), (0.1, 2.0)]),
            Err(GciError::NotFinite(_))
        ));
    }
}
