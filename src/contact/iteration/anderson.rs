//! Anderson acceleration of the slip directions of 3D Coulomb friction.
//!
//! In 3D a slipping node's friction traction `mu p d` lies along a unit direction `d` that the
//! loop does not linearize: it solves with the directions `x` of the last update and takes the
//! new ones from the iterate, `x <- F(x)` (`crate::contact::law::coulomb`). The answer is a fixed
//! point, `F(x) = x`, reached when the node states stay put. Near it, the error obeys
//! `e <- J e` with `J` the derivative of `F`; plain iteration contracts only where `J`'s
//! eigenvalues are smaller than 1 in size, and slowly where they are close to 1 (on the 99k-DOF
//! sphere pressed and then sheared: by a factor 0.68 per iteration while pressing, 33
//! iterations; growing by 1.2 per iteration under the shear, never settling).
//!
//! Anderson's method (Walker and Ni, "Anderson acceleration for fixed-point iterations", SIAM
//! J. Numer. Anal. 49, 2011) keeps the last `m` iterates `x_j` and residuals `f_j = F(x_j) -
//! x_j` and takes the combination of the updates whose residual is least:
//!
//! ```text
//! gamma = argmin | f_k - sum_j gamma_j (f_{j+1} - f_j) |
//! x_{k+1} = F(x_k) - sum_j gamma_j (F(x_{j+1}) - F(x_j))
//! ```
//!
//! For a linear `F` it is GMRES on `(I - J) x = F(0)` (Walker and Ni, theorem 2.2): it settles
//! whatever the size of `J`'s eigenvalues, as long as `I - J` is regular, which is why it is
//! used here rather than a relaxation factor tuned to one case. The unknowns are the directions
//! of the nodes that slip, and a node or two may start or stop slipping from one iteration to
//! the next while the others turn (the 99k-DOF sphere sheared twice as far: 326 to 328 slipping
//! nodes for several iterations). Restarting the history at each such change left the plain
//! iteration, which grew there; so the combination is taken over the nodes that slipped in
//! every kept iterate and slip now, and the others take the plain update. After `m` steps the
//! oldest iterate is dropped. Each node's accelerated direction is normalized again; a node
//! where the combination points away from its plain update (a slip that reverses) takes the
//! plain update.

use std::collections::{BTreeMap, VecDeque};

use nalgebra::{DMatrix, DVector};

/// How many earlier iterates the combination uses: a few, as in Walker and Ni's examples; more
/// adds little where each iterate is a coupled solve and the slipping set settles in tens.
const DEPTH: usize = 5;

/// One iterate of the direction iteration: `(F(x_i), f_i)` of each node that slipped in it.
type Iterate = BTreeMap<usize, ([f64; 3], [f64; 3])>;

/// The history of the direction iteration: for each kept iterate, `(F(x_i), f_i)` of each node
/// that slipped in it, oldest first.
#[derive(Debug, Default)]
pub struct DirectionAcceleration {
    history: VecDeque<Iterate>,
}

impl DirectionAcceleration {
    /// The next directions of the nodes in `update` (the plain update the iterate gives), from
    /// the directions `solved` the iterate was solved with: accelerated on the nodes that slip
    /// in every kept iterate and in both of these, plain elsewhere (a node that starts
    /// slipping, or the first iterate).
    pub fn next(
        &mut self,
        solved: &BTreeMap<usize, [f64; 3]>,
        update: &BTreeMap<usize, [f64; 3]>,
    ) -> BTreeMap<usize, [f64; 3]> {
        let current: Iterate = (update.iter())
            .filter_map(|(&i, &g)| {
                let x = solved.get(&i)?;
                Some((i, (g, std::array::from_fn(|c| g[c] - x[c]))))
            })
            .collect();
        let common: Vec<usize> = (current.keys().copied())
            .filter(|i| self.history.iter().all(|kept| kept.contains_key(i)))
            .collect();
        let mut next = update.clone();
        if !self.history.is_empty() && !common.is_empty() {
            for (i, direction) in self.combination(&current, &common) {
                next.insert(i, direction);
            }
        }
        self.history.push_back(current);
        if self.history.len() > DEPTH {
            self.history.pop_front();
        }
        next
    }

    /// Anderson's combination (module doc) over the `common` nodes of the kept iterates and
    /// `current`, each node's direction normalized again (the plain update where it points away
    /// from it).
    fn combination(&self, current: &Iterate, common: &[usize]) -> Vec<(usize, [f64; 3])> {
        let stack = |iterate: &Iterate, part: usize| {
            DVector::from_iterator(
                3 * common.len(),
                common.iter().flat_map(|i| match part {
                    0 => iterate[i].0,
                    _ => iterate[i].1,
                }),
            )
        };
        let iterates: Vec<&Iterate> = self
            .history
            .iter()
            .chain(std::iter::once(current))
            .collect();
        let g: Vec<DVector<f64>> = iterates.iter().map(|it| stack(it, 0)).collect();
        let f: Vec<DVector<f64>> = iterates.iter().map(|it| stack(it, 1)).collect();
        let (rows, columns) = (3 * common.len(), iterates.len() - 1);
        let delta_f = DMatrix::from_fn(rows, columns, |r, c| f[c + 1][r] - f[c][r]);
        let delta_g = DMatrix::from_fn(rows, columns, |r, c| g[c + 1][r] - g[c][r]);
        let (g_k, f_k) = (&g[columns], &f[columns]);
        // A least-squares solve that ignores directions the residual differences do not span
        // (two iterates with the same residual): the combination reverts to the plain update
        // along them.
        let accelerated = match delta_f
            .svd(true, true)
            .solve(f_k, 1e-12 * f_k.norm().max(1e-300))
        {
            Ok(gamma) => g_k - delta_g * gamma,
            Err(_) => g_k.clone(),
        };
        (common.iter().enumerate())
            .map(|(k, &i)| {
                let plain = current[&i].0;
                let direction: [f64; 3] = std::array::from_fn(|c| accelerated[3 * k + c]);
                let length = norm(direction);
                let along: f64 = (0..3).map(|c| direction[c] * plain[c]).sum();
                let direction = if length > 0.0 && along > 0.0 {
                    direction.map(|v| v / length)
                } else {
                    plain
                };
                (i, direction)
            })
            .collect()
    }
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Directions of two nodes in the x-y plane at angles `a`.
    fn directions(a: [f64; 2]) -> BTreeMap<usize, [f64; 3]> {
        BTreeMap::from([
            (3, [a[0].cos(), a[0].sin(), 0.0]),
            (7, [a[1].cos(), a[1].sin(), 0.0]),
        ])
    }

    fn angles(d: &BTreeMap<usize, [f64; 3]>) -> [f64; 2] {
        [d[&3][1].atan2(d[&3][0]), d[&7][1].atan2(d[&7][0])]
    }

    /// A map of the two angles with eigenvalues -1.5 (a swing that grows) and 1.1 (a drift that
    /// grows), around the fixed point (0.2, -0.1).
    fn map(a: [f64; 2]) -> [f64; 2] {
        let e = [a[0] - 0.2, a[1] + 0.1];
        let (u, v) = ((e[0] + e[1]) / 2.0, (e[0] - e[1]) / 2.0);
        let (u, v) = (-1.5 * u, 1.1 * v);
        [0.2 + u + v, -0.1 + u - v]
    }

    #[test]
    fn the_accelerated_directions_settle_where_the_plain_iteration_diverges() {
        let mut plain = [0.25, -0.12];
        let mut x = directions(plain);
        let mut acceleration = DirectionAcceleration::default();
        for _ in 0..12 {
            plain = map(plain);
            x = acceleration.next(&x, &directions(map(angles(&x))));
        }
        let off = |a: [f64; 2]| (a[0] - 0.2).abs().max((a[1] + 0.1).abs());
        assert!(off(plain) > 1.0, "the plain iteration diverges: {plain:?}");
        assert!(off(angles(&x)) < 1e-8, "{:?}", angles(&x));
    }

    #[test]
    fn a_node_that_starts_slipping_takes_the_plain_update_while_the_others_are_accelerated() {
        let mut with_newcomer = DirectionAcceleration::default();
        let mut without = DirectionAcceleration::default();
        let mut x = directions([0.25, -0.12]);
        // The first iterate: the plain update.
        let first = directions(map(angles(&x)));
        assert_eq!(with_newcomer.next(&x, &first), first);
        assert_eq!(without.next(&x, &first), first);
        x = first;
        // Node 9 starts slipping: its direction as the update gives it; nodes 3 and 7 as
        // without it.
        let mut update = directions(map(angles(&x)));
        let plain = update.clone();
        update.insert(9, [0.0, 1.0, 0.0]);
        let next = with_newcomer.next(&x, &update);
        let alone = without.next(&x, &plain);
        assert_eq!(next[&9], [0.0, 1.0, 0.0]);
        assert_eq!((next[&3], next[&7]), (alone[&3], alone[&7]));
        assert_ne!(alone, plain, "the combination is not the plain update");
    }
}
