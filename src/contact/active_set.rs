//! The active set of the loop (`crate::contact::iteration::solve`): where it starts, and its
//! primal-dual update from an iterate's pressures and gaps.

use std::collections::{BTreeMap, BTreeSet, HashSet};

use crate::contact::law::NodeStates;
use crate::contact::law::coulomb::Turning;

use crate::contact::geometry::gap::GapRow;
use crate::contact::problem::ContactProblem;

/// The active nodes count as lying on the other surface when their geometric gaps are within
/// this fraction of the penetration tolerance. The gap corrections contract by about ten per
/// iteration, so settling to well inside the tolerance costs a solve or two with an unchanged
/// active set, and makes the answer independent of the path (load steps or one solve) to that
/// precision.
pub(super) const SETTLED: f64 = 0.01;

/// An iterate whose active nodes' gaps are more than this many times [`SETTLED`] of the
/// tolerance, and [`LOOSE_GAP_ERROR`], off the other surface cannot stop the loop: however
/// accurately it was solved, the next Newton step on the gap follows it.
pub(super) const FAR_FROM_SETTLED: f64 = 10.0;

/// Ten times the largest gap error (over `h`) a loose solve was measured to add: 4e-7 h to
/// 1e-5 h on the hemisphere on block at 217k and 1M DOFs (the loose and the tight solve of one
/// iteration against each other). An error beyond it is the linearization's, not the solve's.
/// At the default tolerance it is `FAR_FROM_SETTLED` times `SETTLED`; it matters at a tighter
/// one, where a loose solve's own error would otherwise read as far from settled.
const LOOSE_GAP_ERROR: f64 = 1e-4;

/// Where an active-set loop starts: the active primary candidates (surface indices) and the
/// linearization point of their constraints: the gap rows of every primary candidate
/// (frictionless and Coulomb, `crate::contact::geometry::gap`) or the gap corrections `e` (tied,
/// `crate::contact::coupled::interface`); for a Coulomb pair, the history the next load step starts
/// from.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ActiveSet {
    pub nodes: BTreeSet<usize>,
    pub rows: Vec<GapRow>,
    pub corrections: Vec<f64>,
    /// Coulomb: the slipping nodes and the direction of their friction traction.
    pub slip: BTreeMap<usize, [f64; 3]>,
    /// Coulomb: the two bodies' displacements at the end of the step (the start of the
    /// next one's slip), and each primary candidate's accumulated slip (the length of its
    /// tangential slip path over the steps).
    pub history: Option<FrictionHistory>,
}

/// What a Coulomb pair's next load step starts from.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FrictionHistory {
    /// The primary's and the secondary's displacements at their contact surfaces' nodes alone
    /// (`crate::contact::geometry::surface::ContactSurface::values`: three components per
    /// node), all that the next step's jumps read, where the bodies' whole vectors would be
    /// held on every rank through the next step.
    pub displacements: [Vec<f64>; 2],
    /// The accumulated slip of every primary candidate.
    pub accumulated_slip: Vec<f64>,
}

/// The active-set update of one iteration (step 4 of the loop, `crate::contact::iteration::solve`),
/// in surface indices.
pub(super) struct Update {
    pub(super) next: NodeStates,
    /// Coulomb pairs: the direction of each node slipping next (loop indices), and the
    /// largest change of a slipping node's direction weighed by its pressure over the largest
    /// ([`crate::contact::law::coulomb::DIRECTION_SETTLED`]).
    pub(super) directions: BTreeMap<usize, [f64; 3]>,
    /// Coulomb pairs in 3D: how the direction of each node slipping next is linearized.
    pub(super) turnings: BTreeMap<usize, Turning>,
    pub(super) max_direction_change: f64,
    /// Coulomb pairs: the nodes in contact whose tangential state changes (stick to slip or
    /// back), with how far beyond the edge of the cone the update found them, over `mu p_max`.
    pub(super) switching: Vec<(usize, f64)>,
    /// Active nodes (not pinned) with `p_i < -tol_t p_max`, with their tension over `p_max`.
    pub(super) tension: Vec<(usize, f64)>,
    /// Inactive nodes with `g_i < -tol_p h_i`, with their penetration over `h_i`: every
    /// primary candidate, as the certificate's penetration check measures them. (Only the nodes
    /// that faced the other surface in the reference configuration were once tested, and a
    /// block node under a punch's corner, whose line along the contact normal meets the punch's
    /// side, was left penetrating by 1% of a spacing for the certificate to refuse.)
    pub(super) penetrating: Vec<(usize, f64)>,
    /// Every active node lies on the other surface: `|g_i| <= SETTLED tol_p h_i`.
    pub(super) settled: bool,
    /// Some active node is off it by more than `FAR_FROM_SETTLED SETTLED tol_p h_i` and
    /// `LOOSE_GAP_ERROR h_i`.
    pub(super) far_from_settled: bool,
    /// Every active node lies on the other surface within the penetration tolerance,
    /// `|g_i| <= tol_p h_i`: the complementarity residual passes.
    pub(super) within_tolerance: bool,
    pub(super) active: usize,
    pub(super) max_gap_error_over_h: f64,
}

impl Update {
    pub(super) fn new(
        problem: &ContactProblem,
        active: &[usize],
        traction: &[[f64; 3]],
        normals: &[[f64; 3]],
        [gaps, held]: [&[f64]; 2],
        pinned: &HashSet<usize>,
    ) -> Self {
        let settings = &problem.settings;
        let s1 = &problem.primary_surface;
        let pressure: Vec<f64> = traction
            .iter()
            .zip(normals)
            .map(|(t, n)| -(t[0] * n[0] + t[1] * n[1] + t[2] * n[2]))
            .collect();
        let p_max = pressure.iter().copied().fold(0.0, f64::max);
        // Tension is measured against the largest pressure; with no node in compression
        // (bodies pulled apart) against the largest tension, so the worst node's is 1, not
        // p / f64::MIN_POSITIVE, which overflowed to inf (`null` in summary.json).
        let scale = if p_max > 0.0 {
            p_max
        } else {
            -pressure.iter().copied().fold(0.0, f64::min)
        };
        let tension: Vec<(usize, f64)> = active
            .iter()
            .zip(&pressure)
            .filter(|&(i, &p)| p < -settings.tension_tolerance * p_max && !pinned.contains(i))
            .map(|(&i, &p)| (i, -p / scale))
            .collect();
        let is_active: HashSet<usize> = active.iter().copied().collect();
        let penetrating: Vec<(usize, f64)> = (0..s1.len())
            .filter(|&i| !is_active.contains(&i))
            .map(|i| (i, -gaps[i] / s1.spacing[i]))
            .filter(|&(_, over_h)| over_h > settings.penetration_tolerance)
            .collect();
        let max_gap_error_over_h = active
            .iter()
            .map(|&i| held[i].abs() / s1.spacing[i])
            .fold(0.0, f64::max);
        let settled_bound = SETTLED * settings.penetration_tolerance;
        let mut next: BTreeSet<usize> = active.iter().copied().collect();
        for (i, _) in &tension {
            next.remove(i);
        }
        next.extend(penetrating.iter().map(|&(i, _)| i));
        Self {
            next: NodeStates::in_contact(next),
            directions: BTreeMap::new(),
            turnings: BTreeMap::new(),
            max_direction_change: 0.0,
            switching: Vec::new(),
            settled: max_gap_error_over_h <= settled_bound,
            far_from_settled: max_gap_error_over_h
                > (FAR_FROM_SETTLED * settled_bound).max(LOOSE_GAP_ERROR),
            within_tolerance: max_gap_error_over_h <= settings.penetration_tolerance,
            tension,
            penetrating,
            active: active.len(),
            max_gap_error_over_h,
        }
    }

    /// The update of the loop's whole active set from each pair's `(offset, update)`: the
    /// pairs' nodes shifted by their offsets ([`crate::contact::ContactSolver`]); settled (within
    /// the tolerance) when every pair is, with the largest gap error.
    pub(super) fn merge(parts: Vec<(usize, Update)>) -> Self {
        let shift = |v: &[(usize, f64)], offset: usize| -> Vec<(usize, f64)> {
            v.iter().map(|&(i, x)| (offset + i, x)).collect()
        };
        let mut merged = Self {
            next: NodeStates::default(),
            directions: BTreeMap::new(),
            turnings: BTreeMap::new(),
            max_direction_change: 0.0,
            switching: Vec::new(),
            tension: Vec::new(),
            penetrating: Vec::new(),
            settled: true,
            far_from_settled: false,
            within_tolerance: true,
            active: 0,
            max_gap_error_over_h: 0.0,
        };
        for (offset, update) in parts {
            let shifted =
                |set: &BTreeSet<usize>| set.iter().map(|&i| offset + i).collect::<Vec<_>>();
            merged.next.contact.extend(shifted(&update.next.contact));
            merged.next.slip.extend(shifted(&update.next.slip));
            (merged.directions).extend(update.directions.iter().map(|(&i, &d)| (offset + i, d)));
            (merged.turnings).extend(update.turnings.iter().map(|(&i, &t)| (offset + i, t)));
            merged.max_direction_change =
                merged.max_direction_change.max(update.max_direction_change);
            merged.switching.extend(shift(&update.switching, offset));
            merged.tension.extend(shift(&update.tension, offset));
            merged
                .penetrating
                .extend(shift(&update.penetrating, offset));
            merged.settled &= update.settled;
            merged.far_from_settled |= update.far_from_settled;
            merged.within_tolerance &= update.within_tolerance;
            merged.active += update.active;
            merged.max_gap_error_over_h =
                merged.max_gap_error_over_h.max(update.max_gap_error_over_h);
        }
        merged
    }

    /// The states `active` with only the worst violation of the normal conditions switched,
    /// if any (the slipping nodes kept as they are); without one, only the tangential state of
    /// the node furthest beyond the cone's edge.
    pub(super) fn single_switch(&self, active: &NodeStates) -> Option<NodeStates> {
        let worst = |v: &[(usize, f64)]| v.iter().copied().max_by(|a, b| a.1.total_cmp(&b.1));
        if self.tension.is_empty() && self.penetrating.is_empty() {
            let (node, _) = worst(&self.switching)?;
            let mut next = active.clone();
            if !next.slip.remove(&node) {
                next.slip.insert(node);
            }
            return Some(next);
        }
        let mut next = active.contact.clone();
        match (worst(&self.tension), worst(&self.penetrating)) {
            (Some(t), Some(p)) if p.1 >= t.1 => next.insert(p.0),
            (Some(t), _) => next.remove(&t.0),
            (None, Some(p)) => next.insert(p.0),
            (None, None) => return None,
        };
        Some(active.with_contact(next))
    }
}
