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
//! used here rather than a relaxation factor tuned to one case. The history is only valid
//! while the same nodes slip (the unknowns are their directions): it restarts whenever the
//! set of slipping nodes changes, and after `m` steps the oldest pair is dropped. Each node's
//! accelerated direction is normalized again; a node where the combination points away from
//! its plain update (a slip that reverses) takes the plain update.

use std::collections::{BTreeMap, VecDeque};

use nalgebra::{DMatrix, DVector};

/// How many earlier iterates the combination uses: a few, as in Walker and Ni's examples; more
/// adds little where each iterate is a coupled solve and the slipping set settles in tens.
const DEPTH: usize = 5;

/// The history of the direction iteration since the slipping set last changed.
#[derive(Debug, Default)]
pub struct DirectionAcceleration {
    /// The slipping nodes the history is about, in order.
    nodes: Vec<usize>,
    /// `(F(x_j), f_j)` of the last iterates, oldest first, each stacked node by node.
    history: VecDeque<(DVector<f64>, DVector<f64>)>,
}

impl DirectionAcceleration {
    /// The next directions of the slipping nodes, from the directions `solved` the iterate was
    /// solved with and the plain update `update` it gives, both keyed by node: the plain update
    /// where the history is empty (a new slipping set), the accelerated one otherwise. Nodes in
    /// `update` but not in `solved` start slipping: the history restarts with them.
    pub fn next(
        &mut self,
        solved: &BTreeMap<usize, [f64; 3]>,
        update: &BTreeMap<usize, [f64; 3]>,
    ) -> BTreeMap<usize, [f64; 3]> {
        let nodes: Vec<usize> = update.keys().copied().collect();
        if nodes != self.nodes {
            self.nodes = nodes;
            self.history.clear();
        }
        if self.nodes.is_empty() || self.nodes.iter().any(|i| !solved.contains_key(i)) {
            self.history.clear();
            return update.clone();
        }
        let stack = |map: &BTreeMap<usize, [f64; 3]>| {
            DVector::from_iterator(3 * self.nodes.len(), self.nodes.iter().flat_map(|i| map[i]))
        };
        let (x, g) = (stack(solved), stack(update));
        let f = &g - &x;
        if self.history.is_empty() {
            self.history.push_back((g, f));
            return update.clone();
        }
        let mut next = g.clone();
        {
            // The differences between successive iterates' residuals and updates.
            let mut pairs: Vec<(&DVector<f64>, &DVector<f64>)> =
                self.history.iter().map(|(g, f)| (g, f)).collect();
            pairs.push((&g, &f));
            let columns = pairs.len() - 1;
            let delta_f =
                DMatrix::from_fn(f.len(), columns, |r, c| pairs[c + 1].1[r] - pairs[c].1[r]);
            let delta_g =
                DMatrix::from_fn(g.len(), columns, |r, c| pairs[c + 1].0[r] - pairs[c].0[r]);
            // A least-squares solve that ignores directions the residual differences do not
            // span (two iterates with the same residual): the combination then reverts to the
            // plain update along them.
            if let Ok(gamma) = delta_f
                .clone()
                .svd(true, true)
                .solve(&f, 1e-12 * f.norm().max(1e-300))
            {
                next = &g - delta_g * gamma;
            }
        }
        self.history.push_back((g.clone(), f));
        if self.history.len() > DEPTH {
            self.history.pop_front();
        }
        (self.nodes.iter().enumerate())
            .map(|(k, &i)| {
                let plain = update[&i];
                let accelerated: [f64; 3] = std::array::from_fn(|c| next[3 * k + c]);
                let length = norm(accelerated);
                let along: f64 = (0..3).map(|c| accelerated[c] * plain[c]).sum();
                let direction = if length > 0.0 && along > 0.0 {
                    accelerated.map(|v| v / length)
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
    fn a_new_slipping_set_restarts_with_the_plain_update() {
        let mut acceleration = DirectionAcceleration::default();
        let x = directions([0.3, 0.0]);
        let first = acceleration.next(&x, &directions([0.1, 0.1]));
        assert_eq!(first, directions([0.1, 0.1]));
        let mut update = directions([0.15, 0.05]);
        update.insert(9, [0.0, 1.0, 0.0]);
        let mut solved = first.clone();
        solved.insert(9, [0.0, 1.0, 0.0]);
        assert_eq!(acceleration.next(&solved, &update), update);
    }
}
