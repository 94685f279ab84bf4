//! Which walls the loop holds (`crate::contact::geometry::walls`): an active node takes the row
//! of one wall besides its gap row where it crosses the wall's plane, or where that wall pushed
//! at the last solve.
//!
//! **Taken.** An active node whose wall pushed at the last solve keeps it; otherwise it takes
//! the wall whose plane it has crossed the deepest, by more than the penetration tolerance
//! (`tol_p h`, the gap the checks accept). One wall per node: in 2D a vertex joins two facets,
//! so the closest facet and one wall are all a node in a groove can touch (3D pairs hold none:
//! `ContactSolver::holds_walls` says why).
//!
//! **Held.** After each solve a node's traction is split along the two rows' directions,
//! `t = a n + b n_w` (`n . n_w = c`, `|c| < 1`: `b = (t . n_w - c t . n) / (1 - c^2)`); the wall
//! pushed where `-b > 0`. It is held by the pair of facets (the wall's and the closest one's),
//! so that a node whose closest facet becomes the wall's (it slid across the vertex) holds the
//! facet it left as its wall: without that, the loop swung between the two facets of the
//! groove's bottom, the wall's push dropped at every other iteration.

use std::collections::{HashMap, HashSet};

use crate::contact::geometry::gap::GapRow;
use crate::contact::geometry::walls::{HeldWall, Wall};

/// The walls of one pair through the loop: the candidates' walls at the last iterate, and the
/// walls that pushed at the last solve.
#[derive(Default)]
pub(super) struct PairWalls {
    /// The walls of each primary candidate that has any (candidate index).
    pub(super) found: HashMap<usize, Vec<Wall>>,
    /// `(candidate, facet)` for both facets of each wall that pushed at the last solve.
    held: HashSet<(usize, usize)>,
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| a[k] * b[k]).sum()
}

impl PairWalls {
    /// The wall each of the `active` candidates takes (module doc), `tolerance(i)` the depth
    /// beyond which candidate `i` is taken to cross a wall's plane.
    pub(super) fn taken(
        &self,
        rows: &[GapRow],
        active: &[usize],
        tolerance: impl Fn(usize) -> f64,
    ) -> HashMap<usize, HeldWall> {
        let mut taken = HashMap::new();
        for &i in active {
            let Some(walls) = self.found.get(&i) else {
                continue;
            };
            let held = walls.iter().find(|w| self.held.contains(&(i, w.facets[0])));
            let chosen = held.or_else(|| {
                (walls.iter())
                    .filter(|w| w.gap < -tolerance(i))
                    .min_by(|a, b| a.gap.total_cmp(&b.gap))
            });
            if let Some(held) = chosen.and_then(|wall| wall.held_with(&rows[i])) {
                taken.insert(i, held);
            }
        }
        taken
    }

    /// Records which of the walls `taken` pushed at the solve whose traction at each taken
    /// node is `traction(i)` along the gap row's direction `rows[i].normal` (module doc).
    pub(super) fn record_pushes(
        &mut self,
        taken: &HashMap<usize, HeldWall>,
        rows_normal: impl Fn(usize) -> [f64; 3],
        traction: impl Fn(usize) -> [f64; 3],
    ) {
        self.held.clear();
        for (&i, held) in taken {
            let (n, n_w, t) = (rows_normal(i), held.wall.normal, traction(i));
            let c = dot(n, n_w);
            let b = (dot(t, n_w) - c * dot(t, n)) / (1.0 - c * c);
            if -b > 0.0 {
                self.held.insert((i, held.wall.facets[0]));
                self.held.insert((i, held.wall.facets[1]));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(normal: [f64; 3], target: f64) -> GapRow {
        GapRow {
            corners: vec![(0, 0.5), (1, 0.5)],
            normal,
            gap: 0.0,
            target,
        }
    }

    fn wall(facets: [usize; 2], normal: [f64; 3], gap: f64, target: f64) -> Wall {
        Wall {
            facets,
            corners: vec![(1, 1.0), (2, 0.0)],
            normal,
            gap,
            target,
        }
    }

    /// A node in a right-angled groove, its closest facet's row along `-y`, its wall along `-x`:
    /// taken where it crosses the wall's plane beyond the tolerance, its target the vector
    /// that satisfies both rows, and held by both facets once the wall pushed.
    #[test]
    fn a_node_crossing_a_wall_takes_it_and_holds_it_by_both_facets() {
        let rows = vec![row([0.0, -1.0, 0.0], 0.3)];
        let mut walls = PairWalls::default();
        walls
            .found
            .insert(0, vec![wall([7, 3], [-1.0, 0.0, 0.0], -2e-3, 0.5)]);
        assert!(walls.taken(&rows, &[0], |_| 1e-2).is_empty());
        let taken = walls.taken(&rows, &[0], |_| 1e-3);
        let target = taken[&0].target;
        assert!((dot(target, [0.0, -1.0, 0.0]) - 0.3).abs() < 1e-15);
        assert!((dot(target, [-1.0, 0.0, 0.0]) - 0.5).abs() < 1e-15);
        // The traction on the primary pushes it off the wall (`t = a n + b n_w`, `b = -2`):
        // held by both facets, taken again without crossing, as the wall's facet becomes the
        // closest one.
        walls.record_pushes(&taken, |_| [0.0, -1.0, 0.0], |_| [2.0, 1.0, 0.0]);
        assert!(walls.held.contains(&(0, 7)) && walls.held.contains(&(0, 3)));
        walls
            .found
            .insert(0, vec![wall([3, 7], [1.0, 0.0, 0.0], 1e-3, 0.5)]);
        assert_eq!(walls.taken(&rows, &[0], |_| 1e-3)[&0].wall.facets, [3, 7]);
        // A wall that pulls is let go.
        walls.record_pushes(&taken, |_| [0.0, -1.0, 0.0], |_| [-2.0, 1.0, 0.0]);
        assert!(walls.held.is_empty());
    }
}
