//! When the active-set loop (`crate::contact::iteration::solve`) stops, and how it avoids repeating
//! itself: the sets seen, the nodes kept active for good, the single switch, and the tests of the
//! gap error on one active set (converged, stalled, unstable).

use std::collections::HashSet;

use crate::contact::active_set::Update;
use crate::contact::law::NodeStates;
use crate::contact::law::coulomb::{DIRECTION_SETTLED, STILL_TURNING};
use crate::contact::solution::ContactStatus;

/// An active node this many spacings off the other surface after two solves in a row, the second
/// not closer by [`CONTRACTION`], means the constraint no longer controls the geometry
/// ([`ContactStatus::Unstable`]): the stiff half-disc primary at R/500 was 1.3 to 1.8 h off at
/// its second solve, and further off at every solve after. One solve that far off is Newton's
/// method linearizing the gap far from the answer, which the next solve contracts: after the
/// unconstrained first iteration the gap is linearized where the bodies overlap by the whole
/// approach, and the error of that linearization grows with the overlap over the spacing (0.36 h
/// after an overlap of 1.8 h on the 3D R/159 hemisphere; 1.4 h after 3.2 h at R/270, the
/// contact benchmark's 1M DOFs).
const UNSTABLE_GAP_OVER_H: f64 = 1.0;

/// What the loop does after an iteration.
pub(super) enum Step {
    /// Solve again with these node states (possibly the same, with corrected gaps).
    Solve(NodeStates),
    Stop(ContactStatus),
}

/// The loop's memory against repeats (module doc): the sets seen, the nodes removed for
/// tension, those of them added back for penetration, and those kept active for good, beside
/// the [`Counters`] of the iterations.
#[derive(Default)]
pub(super) struct Safeguard {
    pub(super) seen: HashSet<NodeStates>,
    released: HashSet<usize>,
    readded: HashSet<usize>,
    pub(super) pinned: HashSet<usize>,
    counters: Counters,
    /// Whether the last iterate left active nodes in a concave vertex of the other surface
    /// (`crate::contact::geometry::walls`), set by the loop before each update: [`Self::next`]
    /// then lets the iteration cap alone end a loop that does not settle.
    pub(super) in_groove: bool,
}

/// What the safeguard counts from one iteration to the next: small and `Copy`, so that what an
/// update would make of them can be asked without recording it ([`Safeguard::only_linearizes`]).
#[derive(Clone, Copy, Default)]
struct Counters {
    /// The smallest active nodes' gap error of the iterations on the current active set.
    best_error: Option<f64>,
    /// The active nodes' gap error (over h) of the last iteration, when beyond
    /// [`UNSTABLE_GAP_OVER_H`].
    off_surface: Option<f64>,
    /// How many iterations in a row on one active set failed to contract the gap error.
    slow: usize,
    /// The smallest violation of the contact conditions so far ([`violation`]), and how many
    /// iterations have passed without going below it.
    best_violation: Option<f64>,
    since_best: usize,
}

/// What the counters make of an update, before the sets seen are asked.
enum Verdict {
    Stop(ContactStatus),
    /// The same node states solved again: Newton's next step on the gap, or (`turning`) on a
    /// slipping node's direction.
    SameSet {
        turning: bool,
    },
    /// The update changes the node states; the sets seen decide ([`Safeguard::next`]).
    NewSet,
}

/// The largest violation of the nodal contact conditions an update found: penetration of an
/// inactive node (over `h`), tension of an active one (over `p_max`), and the active nodes'
/// distance to the other surface (over `h`).
fn violation(update: &Update) -> f64 {
    let max = |v: &[(usize, f64)]| v.iter().map(|x| x.1).fold(0.0, f64::max);
    max(&update.penetrating) + max(&update.tension) + update.max_gap_error_over_h
}

/// The primal-dual active set method converges superlinearly once near the solution: on the
/// sweep the set settles in 3 to 9 iterations. An iteration that does not reduce the smallest
/// violation found so far makes no progress; this many in a row end the loop as
/// [`ContactStatus::Stalled`] (the active set wandering through new sets, as a stiff primary
/// named by hand did for 50 iterations on a 3D foreign mesh), instead of running to the cap.
const NO_PROGRESS_AFTER: usize = 10;

/// On an unchanged active set the linearized constraint must shrink the active nodes' gap
/// error (`Update::max_gap_error_over_h`) to at most this factor of the smallest error seen on
/// that set (not of the last one: an error alternating between two values, 9.6e-5 h and
/// 2.9e-5 h on a 3D block held by a narrower one, halves every other iteration): Newton's
/// method on the gap ([`crate::contact::geometry::gap`]) does far better (quadratic, exact in one
/// step on a flat), the tied fixed-point correction by about ten. An iteration that does not is
/// outside the regime where the iteration converges for a reason: [`STALLED_AFTER`] such
/// iterations in a row end the loop, converged if the error is within the penetration
/// tolerance (the complementarity residual the certificate checks), as
/// [`ContactStatus::Stalled`] otherwise, instead of running to the iteration cap. (A node on
/// an edge of the other P1 surface can hold the error at 1e-5 h, its closest facet changing
/// every iteration: seen on the half-disc, whose block surface bends at each node.)
pub(super) const CONTRACTION: f64 = 0.5;

/// See [`CONTRACTION`].
const STALLED_AFTER: usize = 2;

impl Counters {
    /// The counters after `update` on the `active` states, and what they call for: a stop
    /// (unstable, no progress, converged or stalled on one set), the same states again, or a
    /// new set for the sets seen to judge.
    fn after(mut self, active: &NodeStates, update: &Update, in_groove: bool) -> (Self, Verdict) {
        let off = update.max_gap_error_over_h;
        if off > UNSTABLE_GAP_OVER_H && !in_groove {
            if self
                .off_surface
                .is_some_and(|last| off > CONTRACTION * last)
            {
                return (self, Verdict::Stop(ContactStatus::Unstable));
            }
            self.off_surface = Some(off);
        } else {
            self.off_surface = None;
        }
        let v = violation(update);
        if self.best_violation.is_none_or(|best| v < best) {
            (self.best_violation, self.since_best) = (Some(v), 0);
        } else {
            self.since_best += 1;
            if self.since_best >= NO_PROGRESS_AFTER && !update.settled && !in_groove {
                return (self, Verdict::Stop(ContactStatus::Stalled));
            }
        }
        if update.next != *active {
            (self.best_error, self.slow) = (None, 0);
            return (self, Verdict::NewSet);
        }
        // A slipping node's direction (3D Coulomb) is iterated on by Newton's method: the loop
        // goes on with the same states until it stops moving (`crate::contact::law::coulomb`).
        let directions_settled = update.max_direction_change <= DIRECTION_SETTLED;
        if update.settled && directions_settled {
            return (self, Verdict::Stop(ContactStatus::Converged));
        }
        if !directions_settled {
            return (self, Verdict::SameSet { turning: true });
        }
        let error = update.max_gap_error_over_h;
        let contracted = (self.best_error).is_none_or(|best| error <= CONTRACTION * best);
        self.slow = if contracted { 0 } else { self.slow + 1 };
        self.best_error = Some(self.best_error.map_or(error, |best| best.min(error)));
        if self.slow >= STALLED_AFTER {
            // Newton's method on a piecewise linear gap stops contracting where a node sits on
            // an edge of the other surface, its closest facet changing from one iteration to
            // the next; within the complementarity tolerance that is an answer, beyond it a
            // failure.
            match (update.within_tolerance, in_groove) {
                (true, _) => return (self, Verdict::Stop(ContactStatus::Converged)),
                (false, false) => return (self, Verdict::Stop(ContactStatus::Stalled)),
                (false, true) => {}
            }
        }
        (self, Verdict::SameSet { turning: false })
    }
}

impl Safeguard {
    /// Whether the last iteration left active nodes more than [`UNSTABLE_GAP_OVER_H`] spacings
    /// off the other surface.
    pub(super) fn off_surface(&self) -> bool {
        self.counters.off_surface.is_some()
    }

    /// Whether [`Safeguard::next`] would answer `update` by Newton's next step on the gap of
    /// the same `active` set, with nothing that could stop the loop at the next iteration
    /// resting on this one: the counters' verdict is the same set again (no slip direction
    /// turning), the error contracted (the slow count back at zero) and within a spacing (the
    /// unstable test cleared), and the gap error far from settled (`Update::far_from_settled`).
    /// Such an iterate only feeds the next linearization, so the loop may take it from a loose
    /// solve: nothing it would decide rests on the solve's accuracy.
    pub(super) fn only_linearizes(&self, active: &NodeStates, update: &Update) -> bool {
        let (after, verdict) = self.counters.after(active, update, self.in_groove);
        matches!(verdict, Verdict::SameSet { turning: false })
            && after.slow == 0
            && after.off_surface.is_none()
            && update.far_from_settled
    }

    pub(super) fn next(&mut self, active: &NodeStates, update: &Update) -> Step {
        let nodes = |v: &[(usize, f64)]| v.iter().map(|&(i, _)| i).collect::<Vec<_>>();
        let added_back = nodes(&update.penetrating);
        let released = &self.released;
        self.readded
            .extend(added_back.into_iter().filter(|i| released.contains(i)));
        self.released.extend(nodes(&update.tension));
        let verdict;
        (self.counters, verdict) = self.counters.after(active, update, self.in_groove);
        match verdict {
            Verdict::Stop(status) => return Step::Stop(status),
            Verdict::SameSet { .. } => return Step::Solve(active.clone()),
            Verdict::NewSet => {}
        }
        self.seen.insert(active.clone());
        let mut next = update.next.clone();
        // In 3D the loop's state is the partition and the slipping nodes' directions: a
        // partition seen before while the directions still turn is not a state seen before
        // (the 99k-DOF sphere sheared twice as far, the block primary: a node at the cone's
        // edge stuck and slipped in turn while the directions turned by 0.13, and the loop
        // ended `cycling`; going on, it settled in 26 iterations within 0.02% of the force
        // with the sphere as primary). A partition that keeps returning once they have settled
        // is a repeat, handled below; one that never lets them settle runs into the
        // no-progress rule or the iteration cap.
        if update.max_direction_change > STILL_TURNING || self.in_groove {
            return Step::Solve(next);
        }
        if self.seen.contains(&next) {
            // First keep active the nodes in tension that came back after an earlier removal.
            let readded = &self.readded;
            let alternating: Vec<usize> = nodes(&update.tension)
                .into_iter()
                .filter(|i| readded.contains(i))
                .collect();
            self.pinned.extend(alternating.iter().copied());
            let mut contact = next.contact.clone();
            contact.extend(alternating);
            next = next.with_contact(contact);
            if next == *active {
                return Step::Solve(next);
            }
        }
        if self.seen.contains(&next) {
            match update.single_switch(active) {
                Some(switched) if !self.seen.contains(&switched) => next = switched,
                _ => return Step::Stop(ContactStatus::Cycling),
            }
        }
        Step::Solve(next)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An update that keeps `active` as it is, with the active nodes' gap error `error` (over
    /// h), settled or not.
    fn unchanged(active: &NodeStates, error: f64, settled: bool) -> Update {
        Update {
            next: active.clone(),
            directions: Default::default(),
            turnings: Default::default(),
            max_direction_change: 0.0,
            switching: Vec::new(),
            tension: Vec::new(),
            penetrating: Vec::new(),
            settled,
            far_from_settled: !settled,
            within_tolerance: error <= 1e-3,
            active: active.contact.len(),
            max_gap_error_over_h: error,
        }
    }

    fn status(step: Step) -> Option<ContactStatus> {
        match step {
            Step::Stop(status) => Some(status),
            Step::Solve(_) => None,
        }
    }

    #[test]
    fn a_partition_seen_before_is_a_repeat_only_once_the_directions_settle() {
        let (first, second) = (
            NodeStates::in_contact([1, 2].into()),
            NodeStates::in_contact([1, 2, 3].into()),
        );
        for (turn, expected) in [
            (1e-2, None),
            (STILL_TURNING / 2.0, Some(ContactStatus::Cycling)),
        ] {
            let mut safeguard = Safeguard::default();
            let mut grow = unchanged(&first, 1e-4, false);
            grow.next = second.clone();
            assert_eq!(status(safeguard.next(&first, &grow)), None);
            // Back to the first partition, which nothing tells apart by a single switch.
            let mut back = unchanged(&second, 1e-4, false);
            back.next = first.clone();
            back.max_direction_change = turn;
            assert_eq!(
                status(safeguard.next(&second, &back)),
                expected,
                "turn {turn}"
            );
        }
    }

    #[test]
    fn an_iterate_that_only_linearizes_is_one_the_loop_solves_again() {
        let active = NodeStates::in_contact([1, 2, 3].into());
        let mut safeguard = Safeguard::default();
        // (gap error over h, far from settled, expected): Newton contracting from far off; an
        // error that did not halve (the slow count would grow); errors near settling (a tight
        // solve might stop the loop). After them: one a spacing off (the unstable test reads
        // it) and a set that changes.
        let steps = [
            (1e-2, true, true),
            (4e-3, true, true),
            (3e-3, true, false),
            (1e-3, true, true),
            (5e-5, false, false),
            (1e-6, false, false),
        ];
        for (error, far, expected) in steps {
            let mut update = unchanged(&active, error, false);
            update.far_from_settled = far;
            let linearizes = safeguard.only_linearizes(&active, &update);
            assert_eq!(linearizes, expected, "error {error}");
            let step = safeguard.next(&active, &update);
            if linearizes {
                assert!(matches!(step, Step::Solve(ref same) if *same == active));
            }
        }
        let far_off = unchanged(&active, 1.4, false);
        assert!(!Safeguard::default().only_linearizes(&active, &far_off));
        let mut grows = unchanged(&active, 1e-2, false);
        grows.next = NodeStates::in_contact([1, 2, 3, 4].into());
        assert!(!Safeguard::default().only_linearizes(&active, &grows));
        // The no-progress count one short of its limit: an iterate without a new smallest
        // violation stops the loop, so it is solved tightly first.
        let mut tired = Safeguard::default();
        (tired.counters.best_violation, tired.counters.since_best) =
            (Some(0.0), NO_PROGRESS_AFTER - 1);
        let no_progress = unchanged(&active, 1e-2, false);
        assert!(!tired.only_linearizes(&active, &no_progress));
        assert_eq!(
            status(tired.next(&active, &no_progress)),
            Some(ContactStatus::Stalled)
        );
    }

    #[test]
    fn a_gap_error_that_stops_contracting_ends_stalled() {
        let active = NodeStates::in_contact([1, 2, 3].into());
        let mut safeguard = Safeguard::default();
        // The first solve of a set has nothing to compare with; then 0.9 and 0.95 of the last.
        assert_eq!(
            status(safeguard.next(&active, &unchanged(&active, 1e-2, false))),
            None
        );
        assert_eq!(
            status(safeguard.next(&active, &unchanged(&active, 9e-3, false))),
            None
        );
        assert_eq!(
            status(safeguard.next(&active, &unchanged(&active, 8.5e-3, false))),
            Some(ContactStatus::Stalled)
        );
    }

    #[test]
    fn an_alternating_gap_error_ends_the_loop() {
        let active = NodeStates::in_contact([1, 2].into());
        let mut safeguard = Safeguard::default();
        let errors = [4.6e-4, 9.6e-5, 2.9e-5, 9.6e-5, 2.9e-5];
        for error in &errors[..4] {
            assert_eq!(
                status(safeguard.next(&active, &unchanged(&active, *error, false))),
                None
            );
        }
        assert_eq!(
            status(safeguard.next(&active, &unchanged(&active, errors[4], false))),
            Some(ContactStatus::Converged)
        );
    }

    #[test]
    fn active_nodes_off_the_surface_twice_without_contracting_end_unstable() {
        let active = NodeStates::in_contact([1, 2].into());
        // Once far off, then contracting by Newton's method: goes on.
        let mut safeguard = Safeguard::default();
        assert_eq!(
            status(safeguard.next(&active, &unchanged(&active, 1.4, false))),
            None
        );
        assert_eq!(
            status(safeguard.next(&active, &unchanged(&active, 0.2, false))),
            None
        );
        // Far off twice, the second no closer: the constraint does not hold the geometry.
        let mut safeguard = Safeguard::default();
        assert_eq!(
            status(safeguard.next(&active, &unchanged(&active, 1.3, false))),
            None
        );
        assert_eq!(
            status(safeguard.next(&active, &unchanged(&active, 1.8, false))),
            Some(ContactStatus::Unstable)
        );
    }

    #[test]
    fn an_active_set_that_wanders_without_progress_ends_stalled() {
        let mut safeguard = Safeguard::default();
        for k in 0..NO_PROGRESS_AFTER + 1 {
            let active = NodeStates::in_contact([k].into());
            let mut update = unchanged(&active, 1e-4, false);
            update.next = NodeStates::in_contact([k + 1].into());
            update.penetrating = vec![(k + 1, 0.02)];
            let expected = (k == NO_PROGRESS_AFTER).then_some(ContactStatus::Stalled);
            assert_eq!(
                status(safeguard.next(&active, &update)),
                expected,
                "iteration {k}"
            );
        }
    }

    #[test]
    fn a_stalled_gap_error_within_the_tolerance_is_converged() {
        let active = NodeStates::in_contact([4].into());
        let mut safeguard = Safeguard::default();
        for error in [1.2e-5, 1.1e-5] {
            assert_eq!(
                status(safeguard.next(&active, &unchanged(&active, error, false))),
                None
            );
        }
        assert_eq!(
            status(safeguard.next(&active, &unchanged(&active, 1.2e-5, false))),
            Some(ContactStatus::Converged)
        );
    }

    #[test]
    fn a_contracting_gap_error_goes_on_until_it_settles() {
        let active = NodeStates::in_contact([1, 2].into());
        let mut safeguard = Safeguard::default();
        for error in [1e-1, 4e-2, 1e-3, 1e-6] {
            assert_eq!(
                status(safeguard.next(&active, &unchanged(&active, error, false))),
                None
            );
        }
        assert_eq!(
            status(safeguard.next(&active, &unchanged(&active, 1e-9, true))),
            Some(ContactStatus::Converged)
        );
    }

    #[test]
    fn a_slow_iteration_on_a_new_active_set_starts_the_count_again() {
        let (first, second) = (
            NodeStates::in_contact([1, 2].into()),
            NodeStates::in_contact([1, 2, 3].into()),
        );
        let mut safeguard = Safeguard::default();
        assert_eq!(
            status(safeguard.next(&first, &unchanged(&first, 1e-2, false))),
            None
        );
        assert_eq!(
            status(safeguard.next(&first, &unchanged(&first, 9e-3, false))),
            None
        );
        let mut grow = unchanged(&first, 9e-3, false);
        grow.next = second.clone();
        assert_eq!(status(safeguard.next(&first, &grow)), None);
        assert_eq!(
            status(safeguard.next(&second, &unchanged(&second, 8e-3, false))),
            None
        );
        assert_eq!(
            status(safeguard.next(&second, &unchanged(&second, 7.9e-3, false))),
            None
        );
        assert_eq!(
            status(safeguard.next(&second, &unchanged(&second, 7.8e-3, false))),
            Some(ContactStatus::Stalled)
        );
    }
}
