//! Discretization error of one quantity from its values on a sequence of meshes: the observed
//! order, Richardson extrapolation and the grid convergence index (GCI), by the procedure of
//! Celik, Ghia, Roache, Freitas, Coleman and Raad (2008), "Procedure for estimation and
//! reporting of uncertainty due to discretization in CFD applications", J. Fluids Eng. 130,
//! 078001, which allows refinement ratios that differ from one pair of meshes to the next.
//!
//! The meshes are numbered from the finest: `h1 < h2 < h3 < ...` are their spacings and `phi1`,
//! `phi2`, ... the quantity on them. Every triplet of consecutive meshes (`1-2-3`, `2-3-4`, ...)
//! gives an estimate of its own; for the finest three, with
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
//! ```
//!
//! and the same with the indices shifted for each coarser triplet. The finest triplet's is the
//! estimate reported. `GCI_fine21` is a relative uncertainty of `phi1`: the band
//! `phi1 (1 +- GCI_fine21)` is meant to hold the exact value with about 95% confidence when the
//! sequence is in its asymptotic range (Roache's safety factor 1.25 for three or more meshes, as
//! ASME V&V 20 uses it). Whether it is in that range is judged on every triplet by [`Flag`]s:
//!
//! - the sign `s`: `s < 0` is oscillatory convergence (the differences change sign);
//! - divergence: `ln|eps32 / eps21| + q(p) < 0`, i.e. the order equation holds only with the
//!   absolute value taken, the errors growing under refinement. With equal ratios this is the
//!   usual `|R| >= 1` on the convergence ratio `R = eps21 / eps32` (reported too), which alone
//!   would misjudge unequal ratios: `phi = 2 + 0.7 h^1.7` on `h = 0.1, 0.23, 0.31` has `R = 1.15`;
//! - `p` within [`ORDER_RANGE`];
//!
//! and across them: the triplets' orders within a factor [`ORDER_AGREEMENT`] of each other. A
//! quantity is asymptotic only when no triplet is flagged and the orders agree: one triplet
//! always yields some order, and only a second one can show that the same leading term governs
//! the sequence. (Roache's ratio `GCI_32 / (r21^p GCI_fine21)` was checked here once; it equals
//! `|phi1 / phi2|` on every triplet whose differences keep their sign, whatever the ratios, so
//! it tested nothing about the range.)
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

/// The largest ratio between the orders of two triplets of one sequence that still agree. In
/// the asymptotic range every triplet observes the same leading order, the higher terms'
/// share shrinking with h. P1's two formal orders, 1 and 2, are a factor 2 apart: orders
/// further apart than half of that on a log scale, `sqrt(2)`, could be one of each, and then no
/// one leading term governs the sequence (an order 1.60 on the coarse triplet and 3.88 on the
/// fine one is no order at all). Within it the triplets of the validation cases' force
/// sequences agree.
pub const ORDER_AGREEMENT: f64 = std::f64::consts::SQRT_2;

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
    /// The triplets' orders are more than [`ORDER_AGREEMENT`] apart (a quantity's flag, never
    /// one triplet's).
    OrdersDisagree,
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
            Flag::OrdersDisagree => "the triplets' orders differ by more than a factor 1.41",
        }
    }
}

/// The estimate of three consecutive meshes, numbered from the finest of them.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Triplet {
    /// Their spacings `h1 < h2 < h3` (as in [`Estimate::h`]).
    pub h: [f64; 3],
    /// `R = eps21 / eps32`.
    pub convergence_ratio: Option<f64>,
    /// The observed order `p` and the iterations it took.
    pub order: Option<f64>,
    pub iterations: Option<usize>,
    /// `phi_ext`, `e_ext21` and `GCI_fine21`.
    pub extrapolated: Option<f64>,
    pub extrapolated_error: Option<f64>,
    pub gci_fine: Option<f64>,
    /// Empty when the triplet passed every test of the asymptotic range.
    pub flags: Vec<Flag>,
}

/// One quantity's estimate from its values on every mesh (numbered from the finest).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Estimate {
    /// `phi1`, `phi2`, ... of every mesh.
    pub phi: Vec<f64>,
    /// `h1 < h2 < ...`.
    pub h: Vec<f64>,
    /// `r21`, `r32`, ...
    pub ratios: Vec<f64>,
    /// `phi1 - phi2`.
    pub difference: f64,
    /// `e_a21 = |(phi1 - phi2) / phi1|`.
    pub relative_difference: f64,
    /// The finest triplet's `R`, `p`, its iterations, `phi_ext`, `e_ext21` and `GCI_fine21`:
    /// the estimate reported (also `triplets[0]`).
    pub convergence_ratio: Option<f64>,
    pub order: Option<f64>,
    pub iterations: Option<usize>,
    pub extrapolated: Option<f64>,
    pub extrapolated_error: Option<f64>,
    pub gci_fine: Option<f64>,
    /// Every triplet of consecutive meshes, the finest first (none with two meshes).
    pub triplets: Vec<Triplet>,
    /// Every flag of a triplet (each once) and [`Flag::OrdersDisagree`].
    pub flags: Vec<Flag>,
    /// No flag: every triplet is in its asymptotic range and their orders agree.
    pub asymptotic: bool,
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
    let (h, phi): (Vec<f64>, Vec<f64>) = sorted.into_iter().unzip();
    let ratios: Vec<f64> = h.windows(2).map(|w| w[1] / w[0]).collect();
    let triplets: Vec<Triplet> = (0..h.len().saturating_sub(2))
        .map(|k| triplet([h[k], h[k + 1], h[k + 2]], [phi[k], phi[k + 1], phi[k + 2]]))
        .collect();
    let mut flags = Vec::new();
    if triplets.is_empty() {
        flags.push(Flag::TwoLevels);
    }
    for flag in triplets.iter().flat_map(|t| &t.flags) {
        if !flags.contains(flag) {
            flags.push(*flag);
        }
    }
    let orders: Vec<f64> = triplets.iter().filter_map(|t| t.order).collect();
    let (lowest, highest) = (orders.iter()).fold((f64::INFINITY, 0.0_f64), |(lo, hi), &p| {
        (lo.min(p), hi.max(p))
    });
    if orders.len() > 1 && highest > ORDER_AGREEMENT * lowest {
        flags.push(Flag::OrdersDisagree);
    }
    let finest = triplets.first();
    let of_finest = |field: fn(&Triplet) -> Option<f64>| finest.and_then(field);
    Ok(Estimate {
        difference: phi[0] - phi[1],
        relative_difference: ((phi[0] - phi[1]) / phi[0]).abs(),
        convergence_ratio: of_finest(|t| t.convergence_ratio),
        order: of_finest(|t| t.order),
        iterations: finest.and_then(|t| t.iterations),
        extrapolated: of_finest(|t| t.extrapolated),
        extrapolated_error: of_finest(|t| t.extrapolated_error),
        gci_fine: of_finest(|t| t.gci_fine),
        asymptotic: flags.is_empty(),
        phi,
        h,
        ratios,
        triplets,
        flags,
    })
}

/// The order, extrapolation, GCI and flags of three meshes, the finest first.
fn triplet(h: [f64; 3], [phi1, phi2, phi3]: [f64; 3]) -> Triplet {
    let mut t = Triplet {
        h,
        convergence_ratio: None,
        order: None,
        iterations: None,
        extrapolated: None,
        extrapolated_error: None,
        gci_fine: None,
        flags: Vec::new(),
    };
    let [r21, r32] = [h[1] / h[0], h[2] / h[1]];
    let (eps21, eps32) = (phi2 - phi1, phi3 - phi2);
    let round_off = ROUND_OFF * phi1.abs().max(f64::MIN_POSITIVE);
    if eps21.abs() <= round_off || eps32.abs() <= round_off {
        t.flags.push(Flag::NoDifference);
        return t;
    }
    t.convergence_ratio = Some(eps21 / eps32);
    let sign = (eps32 / eps21).signum();
    let Some((p, iterations)) = observed_order(r21, r32, eps21, eps32) else {
        t.flags.push(Flag::NoOrder);
        return t;
    };
    // The order solves |ln|eps32/eps21| + q(p)| = p ln r21; where the expression inside the
    // bars is negative the errors grow with refinement (with r21 = r32: |R| > 1).
    let growing = (eps32 / eps21).abs().ln() + q(p, r21, r32, sign) < 0.0;
    t.flags.extend(match (growing, sign > 0.0) {
        (false, true) => None,
        (false, false) => Some(Flag::OscillatoryConvergence),
        (true, true) => Some(Flag::MonotonicDivergence),
        (true, false) => Some(Flag::OscillatoryDivergence),
    });
    t.order = Some(p);
    t.iterations = Some(iterations);
    if !(ORDER_RANGE.0..=ORDER_RANGE.1).contains(&p) {
        t.flags.push(Flag::OrderOutOfRange);
    }
    let r21p = r21.powf(p);
    let extrapolated = (r21p * phi1 - phi2) / (r21p - 1.0);
    t.extrapolated = Some(extrapolated);
    t.extrapolated_error = Some(((extrapolated - phi1) / extrapolated).abs());
    t.gci_fine = Some(SAFETY_FACTOR * ((phi1 - phi2) / phi1).abs() / (r21p - 1.0));
    t
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
    /// order of the levels, on both triplets of its four levels, and is in its asymptotic range.
    #[test]
    fn manufactured_sequence_gives_its_order_and_limit() {
        for (phi0, c, p) in [(2.0, 0.7, 1.7), (5.0, -3.0, 1.0), (-1.0, 0.2, 2.5)] {
            let hs: [f64; 4] = [0.5, 0.23, 0.1, 0.31];
            let levels: Vec<(f64, f64)> = hs.iter().map(|&h| (h, phi0 + c * h.powf(p))).collect();
            let e = estimate(&levels).unwrap();
            assert_eq!(e.h, vec![0.1, 0.23, 0.31, 0.5]);
            assert_eq!(e.triplets.len(), 2);
            assert_eq!(e.triplets[0].h, [0.1, 0.23, 0.31]);
            for t in &e.triplets {
                assert!((t.order.unwrap() - p).abs() < 1e-8, "{e:?}");
                assert!(
                    (t.extrapolated.unwrap() - phi0).abs() < 1e-9 * phi0.abs(),
                    "{e:?}"
                );
            }
            assert_eq!(e.order, e.triplets[0].order);
            assert!(e.flags.is_empty() && e.asymptotic, "{e:?}");
            // The exact value lies in the GCI band of the finest mesh.
            let band = e.gci_fine.unwrap() * e.phi[0].abs();
            assert!((e.phi[0] - phi0).abs() <= band);
        }
    }

    /// `phi` on `h = 1, 2, 4, 8` whose finest triplet has the order `fine` and the coarser one
    /// `coarse` (constant ratio 2: each order is `log2` of the ratio of its two differences);
    /// `sign` is that of the finest difference against the others'.
    fn two_triplets(fine: f64, coarse: f64, sign: f64) -> Vec<(f64, f64)> {
        let d1 = 0.01 * sign;
        let d2 = 0.01 * 2f64.powf(fine);
        let d3 = d2 * 2f64.powf(coarse);
        vec![
            (1.0, 1.0),
            (2.0, 1.0 + d1),
            (4.0, 1.0 + d1 + d2),
            (8.0, 1.0 + d1 + d2 + d3),
        ]
    }

    #[test]
    fn order_2_on_four_levels_is_asymptotic() {
        let levels: Vec<(f64, f64)> = [0.1f64, 0.2, 0.4, 0.8]
            .iter()
            .map(|&h| (h, 1.0 + 0.3 * h * h))
            .collect();
        let e = estimate(&levels).unwrap();
        let orders: Vec<f64> = e.triplets.iter().map(|t| t.order.unwrap()).collect();
        assert!(orders.iter().all(|p| (p - 2.0).abs() < 1e-8), "{orders:?}");
        assert!(e.asymptotic && e.flags.is_empty(), "{e:?}");
    }

    #[test]
    fn a_finest_triplet_that_oscillates_is_not_asymptotic() {
        let e = estimate(&two_triplets(2.0, 2.0, -1.0)).unwrap();
        assert_eq!(e.triplets[0].flags, vec![Flag::OscillatoryConvergence]);
        assert!(e.triplets[1].flags.is_empty(), "{e:?}");
        assert!((e.triplets[1].order.unwrap() - 2.0).abs() < 1e-8);
        assert_eq!(e.flags, vec![Flag::OscillatoryConvergence]);
        assert!(!e.asymptotic);
    }

    #[test]
    fn triplets_whose_orders_disagree_are_flagged() {
        // The force of a half-disc study: 1.60 on levels 0-1-2, 3.88 on 1-2-3.
        let e = estimate(&two_triplets(3.88, 1.60, 1.0)).unwrap();
        let orders: Vec<f64> = e.triplets.iter().map(|t| t.order.unwrap()).collect();
        assert!((orders[0] - 3.88).abs() < 1e-8 && (orders[1] - 1.60).abs() < 1e-8);
        assert_eq!(e.flags, vec![Flag::OrderOutOfRange, Flag::OrdersDisagree]);
        assert!(!e.asymptotic);
        // Each order in range and each triplet clean: only their disagreement flags them.
        let e = estimate(&two_triplets(2.0, 1.0, 1.0)).unwrap();
        assert!(e.triplets.iter().all(|t| t.flags.is_empty()), "{e:?}");
        assert_eq!(e.flags, vec![Flag::OrdersDisagree]);
        assert!(!e.asymptotic);
        // Within a factor sqrt(2) they agree.
        let e = estimate(&two_triplets(1.7, 1.4, 1.0)).unwrap();
        assert!(e.asymptotic, "{e:?}");
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
        assert!(e.triplets.is_empty() && !e.asymptotic);
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
