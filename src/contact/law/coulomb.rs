//! Coulomb friction: at an active node the tangential traction `t_T` obeys `|t_T| <= mu p`;
//! where `|t_T| < mu p` the node sticks (its tangential slip over the load step is zero), where
//! `|t_T| = mu p` it slips, against its slip: `t_T = -mu p v / |v|`, `v` the slip increment of
//! the primary relative to the secondary over the step.
//!
//! **Multipliers.** A sticking node carries `dim` multipliers in the local basis `(n, t_1,
//! t_2)`: the traction `lambda_n n + sum_a lambda_a t_a`, the normal row the geometric gap
//! (as frictionless contact, node to segment) and each tangential row `t_a . (u1_i - (R12
//! u2)_i) = t_a . J0_i`, `J0_i` the jump `u1_i - (R12 u2)_i` at the start of the step, read
//! through the same interpolation the tied formulation reads. A slipping node carries one,
//! `lambda_n (n - mu d)` with the normal row: its friction traction `mu p d` (`p = -lambda_n`)
//! rides on its pressure, in the direction `d` the last update chose, and in 3D a second one
//! across `d` ([`Turning`]). Its first column is not its row: the coupled system is unsymmetric (the coupled GMRES and its half-space preconditioner,
//! `crate::contact::coupled::half_space`, take rows and columns apart).
//!
//! **The update** is the primal-dual active set (semismooth Newton) step of the complementarity
//! function of Hüeber, Stadler and Wohlmuth (2008), node by node, for the tangential part:
//! with `xi = t_T - c_t v` (`c_t = E* / h`),
//!
//! ```text
//! stick next  if |xi| <  mu p      (on a sticking node v = 0, so |t_T| < mu p)
//! slip next   if |xi| >= mu p,     along d = xi / |xi|
//! ```
//!
//! A slipping node goes on slipping while its slip opposes its traction (`v . d <= 0` gives
//! `|xi| >= mu p`), and sticks again when it would slip along its traction. In 2D `d` is one
//! of the two tangents: the update is a choice among finitely many states, as the normal
//! active-set update is. In 3D the direction turns: a slipping node also carries a multiplier
//! across its direction whose row is the slip law linearized at the iterate ([`Turning`]), so
//! that the directions follow Newton's method, and the loop settles only when no direction
//! changes by more than [`DIRECTION_SETTLED`] (`docs/method.md` 1.4: why, and what happens when
//! it does not).

use super::{Multiplier, Reads, Restates, Tangential};

/// The slipping nodes' directions have settled when each changes by less than this from one
/// iteration to the next (the norm of the difference of the two unit vectors), weighed by the
/// node's pressure over the largest: the change of its friction traction over `mu p_max`. A
/// node at the rim of the zone, where the pressure vanishes, carries a friction traction whose
/// direction hardly matters, and on the 99k-DOF sphere its direction was still turning by 6%
/// after 50 iterations when unweighed.
pub const DIRECTION_SETTLED: f64 = 1e-6;

/// The slipping nodes' directions still turn when a change is over this, a hundred times
/// [`DIRECTION_SETTLED`]: the loop then goes on from a loose solve
/// (`crate::contact::iteration::solve`), and a partition open / stick / slip it has seen before
/// is not a state it has seen before (`crate::contact::iteration::safeguard`).
pub const STILL_TURNING: f64 = 100.0 * DIRECTION_SETTLED;

/// A unit tangent basis at the unit normal `n`: one tangent in 2D (`n` rotated by +90
/// degrees in the x-y plane), two in 3D (`t_1` orthogonal to `n` and to the axis least aligned
/// with it, `t_2 = n x t_1`).
pub fn tangents(n: [f64; 3], dim: usize) -> Vec<[f64; 3]> {
    if dim == 2 {
        return vec![[-n[1], n[0], 0.0]];
    }
    let axis = (0..3)
        .min_by(|&a, &b| n[a].abs().total_cmp(&n[b].abs()))
        .unwrap_or(0);
    let e: [f64; 3] = std::array::from_fn(|k| f64::from(u8::from(k == axis)));
    let t1 = unit(cross(e, n));
    vec![t1, cross(n, t1)]
}

/// How a slipping node's direction `d` is linearized in 3D: the Newton step of the slip law
/// `t_T = mu p d`, `v = -|v| d` (`docs/method.md` 1.4). A traction `t_perp` along the tangent
/// `e = n x d` across the direction turns the slip the other way, `v_perp = -|v| t_perp / (mu
/// p)` to first order, which the node's second multiplier (column `e`) holds as the row
///
/// ```text
/// a v_perp + (1 - a) t_perp / c_t = 0,      a = mu p / (mu p + c_t |v|)
/// ```
///
/// at the iterate's `p` and `|v|`, with `v_perp = e . (J - J0)` read through the interpolation
/// as a sticking node's tangential rows are. The weights `a` and `1 - a` keep it bounded at
/// both ends: a node that has just started to slip (`v = 0`) is held across its direction, a
/// rim node whose pressure vanishes takes no traction across it. At the solution `t_perp = 0`
/// and the row holds with `v_perp = 0`: the slip runs against the traction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Turning {
    /// `a`: the weight of the slip across the direction in the row.
    pub slip_weight: f64,
    /// `(1 - a) / c_t`: the multiplier's own term in the row.
    pub compliance: f64,
}

impl Turning {
    /// The linearization of a node that has not slipped yet (`v = 0`): held across its
    /// direction.
    pub const HELD: Self = Self {
        slip_weight: 1.0,
        compliance: 0.0,
    };

    /// The linearization at pressure `p`, slip `v` (tangential), with `c_t`.
    fn at(mu: f64, p: f64, v: [f64; 3], c_t: f64) -> Self {
        let (bound, slip) = (mu * p.max(0.0), c_t * norm(v));
        if bound + slip <= 0.0 {
            return Self::HELD;
        }
        let slip_weight = bound / (bound + slip);
        Self {
            slip_weight,
            compliance: (1.0 - slip_weight) / c_t,
        }
    }
}

pub(super) fn multipliers(
    normal: [f64; 3],
    tangential: Tangential,
    mu: f64,
    dim: usize,
    gap_compliance: f64,
) -> Vec<Multiplier> {
    let normal_row = |force: [f64; 3]| Multiplier {
        force,
        row: normal,
        reads: Reads::Geometric,
        restates: Restates::Node,
        compliance: gap_compliance,
    };
    match tangential {
        Tangential::Slip { direction, turning } => {
            // The direction was chosen tangent to the last iterate's normal; made tangent to
            // this one, so that the traction's normal part is the pressure and its tangential
            // part exactly `mu p` (the cone's edge).
            let d = unit(tangential_part(direction, normal));
            let slipping = normal_row(std::array::from_fn(|k| normal[k] - mu * d[k]));
            if dim == 2 {
                return vec![slipping];
            }
            let across = cross(normal, d);
            vec![
                slipping,
                Multiplier {
                    force: across,
                    row: across.map(|x| turning.slip_weight * x),
                    reads: Reads::Interpolated,
                    restates: Restates::Node,
                    compliance: turning.compliance,
                },
            ]
        }
        Tangential::Stick => std::iter::once(normal_row(normal))
            .chain(tangents(normal, dim).into_iter().map(|t| Multiplier {
                force: t,
                row: t,
                reads: Reads::Interpolated,
                restates: Restates::Node,
                compliance: 0.0,
            }))
            .collect(),
    }
}

/// What the update found at one active node.
#[derive(Debug, Clone, Copy)]
pub struct NodeUpdate {
    pub next: Tangential,
    /// How far from the cone's edge the test found the node, `| |xi| - mu p |` (a traction).
    pub margin: f64,
    /// `|d_next - d|` for a node that slips before and after (0 otherwise).
    pub direction_change: f64,
}

/// The tangential update of the module doc at an active node with pressure `p`, tangential
/// traction `t_t` and slip increment `v` (tangential, over the step), in state `state`;
/// `c_t = E* / h`. `slack` (a traction) keeps round-off at the cone's edge from switching a
/// sticking node to slip, and `settled` (a length) a slipping node from sticking again: it
/// sticks only if it also slips along its own traction by more than `settled`. Without it, a
/// node at the stick zone's edge on the 99k-DOF sphere switched at every iteration (its slip
/// along its traction 1e-6 of a spacing, far inside what the slip check accepts) and the loop
/// ended `cycling`.
#[allow(clippy::too_many_arguments)]
pub fn update(
    state: Tangential,
    p: f64,
    t_t: [f64; 3],
    v: [f64; 3],
    mu: f64,
    c_t: f64,
    slack: f64,
    settled: f64,
) -> NodeUpdate {
    let xi: [f64; 3] = std::array::from_fn(|k| t_t[k] - c_t * v[k]);
    let size = norm(xi);
    let bound = mu * p.max(0.0);
    let stick = match state {
        Tangential::Stick => size <= bound + slack,
        Tangential::Slip { direction, .. } => {
            let along: f64 = (0..3).map(|k| v[k] * direction[k]).sum();
            size < bound - slack && along > settled
        }
    };
    let margin = (size - bound).abs();
    if stick || size == 0.0 {
        return NodeUpdate {
            next: Tangential::Stick,
            margin,
            direction_change: 0.0,
        };
    }
    let direction = xi.map(|x| x / size);
    let direction_change = match state {
        Tangential::Slip { direction: old, .. } => {
            norm(std::array::from_fn(|k| direction[k] - old[k]))
        }
        Tangential::Stick => 0.0,
    };
    NodeUpdate {
        next: Tangential::Slip {
            direction,
            turning: Turning::at(mu, p, v, c_t),
        },
        margin,
        direction_change,
    }
}

/// The tangential part of `v` with respect to the unit normal `n`.
pub fn tangential_part(v: [f64; 3], n: [f64; 3]) -> [f64; 3] {
    let along: f64 = (0..3).map(|k| v[k] * n[k]).sum();
    std::array::from_fn(|k| v[k] - along * n[k])
}

pub fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn unit(v: [f64; 3]) -> [f64; 3] {
    let length = norm(v);
    v.map(|x| x / length)
}

#[cfg(test)]
mod tests {
    use super::*;

    const N: [f64; 3] = [0.0, 1.0, 0.0];

    #[test]
    fn the_tangents_are_an_orthonormal_basis_with_the_normal() {
        for n in [
            [0.0, 0.0, 1.0],
            unit([1.0, 2.0, -0.5]),
            unit([0.3, -0.1, 0.9]),
        ] {
            let t = tangents(n, 3);
            let dot = |a: [f64; 3], b: [f64; 3]| (0..3).map(|k| a[k] * b[k]).sum::<f64>();
            for (a, b) in [(t[0], n), (t[1], n), (t[0], t[1])] {
                assert!(dot(a, b).abs() < 1e-15);
            }
            assert!((norm(t[0]) - 1.0).abs() < 1e-15 && (norm(t[1]) - 1.0).abs() < 1e-15);
        }
        let t = tangents(N, 2);
        assert_eq!(t, vec![[-1.0, 0.0, 0.0]]);
    }

    #[test]
    fn a_sticking_node_inside_the_cone_sticks_and_outside_slips_along_its_traction() {
        let inside = update(
            Tangential::Stick,
            1.0,
            [0.29, 0.0, 0.0],
            [0.0; 3],
            0.3,
            1.0,
            0.0,
            0.0,
        );
        assert_eq!(inside.next, Tangential::Stick);
        let outside = update(
            Tangential::Stick,
            1.0,
            [-0.31, 0.0, 0.0],
            [0.0; 3],
            0.3,
            1.0,
            0.0,
            0.0,
        );
        assert_eq!(
            outside.next,
            Tangential::Slip {
                direction: [-1.0, 0.0, 0.0],
                turning: Turning::HELD,
            }
        );
    }

    #[test]
    fn a_slipping_node_slips_on_while_its_slip_opposes_its_traction() {
        let state = Tangential::Slip {
            direction: [1.0, 0.0, 0.0],
            turning: Turning::HELD,
        };
        // Traction mu p along +x, slip along -x: a valid slip.
        let on = update(
            state,
            1.0,
            [0.3, 0.0, 0.0],
            [-1e-3, 0.0, 0.0],
            0.3,
            10.0,
            0.0,
            0.0,
        );
        // Linearized at its slip: a = mu p / (mu p + c_t |v|) = 0.3 / 0.31.
        let Tangential::Slip { direction, turning } = on.next else {
            panic!("{:?}", on.next);
        };
        assert_eq!(direction, [1.0, 0.0, 0.0]);
        assert!((turning.slip_weight - 0.3 / 0.31).abs() < 1e-15);
        assert!((turning.compliance - (1.0 - 0.3 / 0.31) / 10.0).abs() < 1e-15);
        assert_eq!(on.direction_change, 0.0);
        // Slipping along its own traction: it sticks.
        let back = update(
            state,
            1.0,
            [0.3, 0.0, 0.0],
            [1e-3, 0.0, 0.0],
            0.3,
            10.0,
            0.0,
            0.0,
        );
        assert_eq!(back.next, Tangential::Stick);
    }

    #[test]
    fn a_slipping_node_gets_two_columns_apart_from_its_row() {
        let slip = multipliers(
            N,
            Tangential::Slip {
                direction: [1.0, 0.0, 0.0],
                turning: Turning::HELD,
            },
            0.5,
            2,
            0.0,
        );
        assert_eq!(slip.len(), 1);
        assert_eq!(slip[0].force, [-0.5, 1.0, 0.0]);
        assert_eq!(slip[0].row, N);
        assert_eq!(multipliers(N, Tangential::Stick, 0.5, 3, 0.0).len(), 3);
    }

    #[test]
    fn in_3d_a_slipping_node_is_also_held_across_its_direction_as_linearized() {
        let turning = Turning::at(0.5, 2.0, [0.0, 0.0, -0.1], 10.0);
        // mu p = 1, c_t |v| = 1: half the row on the slip, half on the traction.
        assert_eq!(turning.slip_weight, 0.5);
        assert_eq!(turning.compliance, 0.05);
        let slip = multipliers(
            N,
            Tangential::Slip {
                direction: [1.0, 0.0, 0.0],
                turning,
            },
            0.5,
            3,
            0.0,
        );
        assert_eq!(slip.len(), 2);
        assert_eq!(slip[0].force, [-0.5, 1.0, 0.0]);
        // Across the direction: the tangent n x d, its row half of it, read through the
        // interpolation, with its own term.
        let across = slip[1];
        assert_eq!(across.force, [0.0, 0.0, -1.0]);
        assert_eq!(across.row, [0.0, 0.0, -0.5]);
        assert_eq!(across.reads, Reads::Interpolated);
        assert_eq!(across.compliance, 0.05);
        // A node that has not slipped yet is held across it; one without pressure takes no
        // traction across it.
        assert_eq!(Turning::at(0.5, 2.0, [0.0; 3], 10.0), Turning::HELD);
        let unloaded = Turning::at(0.5, 0.0, [0.0, 0.0, -0.1], 10.0);
        assert_eq!((unloaded.slip_weight, unloaded.compliance), (0.0, 0.1));
    }
}
