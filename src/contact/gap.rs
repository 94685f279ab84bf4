//! The gap: the geometric gap of a surface node to the other body ([`geometric_gaps`], the one
//! gap measure of the loop's tests, the checks and the output), and the primary nodes' gap
//! linearized at an iterate: the constraint rows of frictionless contact, which make the
//! active-set loop Newton's method on the gap it checks.
//!
//! **The gap.** A primary node at `x = X + u1` has its closest point `q` on the secondary's
//! displaced P1 surface, on facet `f` with barycentric coordinates `b_k` of its corners `y_k`
//! (`q = sum_k b_k y_k`; where several facets share `q`, the one that faces the node's own
//! outward normal the most), and `m` the facet's outward unit normal (out of body 2). Its gap is
//! the distance to the plane of that facet, `g = m . (x - q)`: positive outside body 2,
//! negative inside. Where `q` lies inside the facet (every node that touches a smooth or flat
//! surface) this is the signed closest-point distance of the certificate
//! ([`geometric_gaps`]); where the node has slid past the end of the
//! secondary surface (the corner of a block pressed onto a block as wide), it is the distance
//! to the end facet's plane, so a node at the corner is held level with the face it left
//! rather than pulled sideways onto the corner point.
//!
//! **Its linearization.** With the facet and `b` fixed, `g` is linear in the positions along
//! `m`, and the rotation of `m` does not change it to first order (`dm . m = 0` and
//! `x - q = g m`):
//!
//! ```text
//! g(u) ~ g(u^k) - n . [(u1 - u1^k) - sum_k b_k (u2_k - u2_k^k)],     n = -m (out of body 1)
//! ```
//!
//! so the constraint of an active node, `g(u) = 0`, becomes the row
//! `n . (u1 - sum_k b_k u2_k) = n . (u1^k - sum_k b_k u2_k^k) + g(u^k)`: node to segment,
//! whose Jacobian is the gap's own. The loop is then Newton's method on the nodal
//! complementarity problem of the gap the certificate measures, and converges quadratically
//! while the active set and the facets stay put (one or two iterations on a flat, where `g` is
//! linear in `u`). The INTERNODES interpolation still carries the traction to the secondary
//! (`R21` or `R12^T`, [`super::Transfer`]), and at the answer every active node is on the
//! secondary's P1 surface, as before; only the path there changed. The earlier constraint used
//! the rows of `R12` with a correction `e = g - g_lin` from the last iterate: a fixed-point
//! iteration on `e` that contracts only where `R12` reproduces the P1 surface, and diverged
//! (error doubling each iteration) where it extrapolates, at the ends of two clamped blocks.

use super::ContactSurface;

/// Within what distance of a contact surface a node is judged by the plane of the facet it
/// faces, in units of that facet's longest edge. Two faces meant to end flush (equal blocks
/// pressed together) end where each body's own P1 solution puts its edge: the two bulges
/// differ by the discretization's error, a small fraction of a facet (1e-3 of a spacing on the
/// 3D blocks). Measured by its distance to the other body, a node there flips from `-delta` to
/// `+delta` as its edge crosses the other's by a hair: released, the edge of one block sagged
/// 4% of the approach below the other's face, which the other pierced. Near the surface the
/// plane of the facet decides, as for any node over the surface: the extension zone of
/// node-to-surface contact (a tenth of the facet, as in the commercial codes), far below the
/// facet's own resolution of a body's edge and far above the flush mismatch. Farther away the
/// other body's closed boundary decides: a node on the far side of the other body is behind
/// the plane of the facet it faces, yet outside.
pub const NEAR_SURFACE: f64 = 0.1;

/// The geometric gap of every node of `own` to the `other` body, each displaced by its body's
/// displacement (`None`: reference geometry), the one gap measure of the loop's penetration
/// test, the checks and the `normal_gap` output. The node's closest point `q` on the other
/// candidate surface's P1 facets ([`super::projection`], on the facet that faces the node's own
/// normal where several share it, as its linearization does, [`gap_rows`]) and that
/// facet's outward normal `m` give:
/// - within [`NEAR_SURFACE`] of the facet (beyond the surface's rim too), `g = m . (x - q)`,
///   the distance to the facet's plane: positive outside, negative inside, exact against a
///   flat;
/// - farther, the distance `|x - q|`, negative when the node is inside the other body (decided
///   on that body's closed boundary, [`super::boundary`]).
///
/// Defined at any distance.
pub fn geometric_gaps(
    own: &ContactSurface,
    other: &ContactSurface,
    u_own: Option<&[f64]>,
    u_other: Option<&[f64]>,
) -> Vec<f64> {
    let surface = other.index(u_other);
    let boundary = other.boundary.index(u_other);
    (0..own.len())
        .map(|s| {
            let x = u_own.map_or(own.coords[s], |u| own.deformed(u, s));
            let closest = (surface.project_facing(&x, Some(&own.normals[s])))
                .expect("a contact surface has facets");
            let m = surface.normal(closest.facet);
            let offset: [f64; 3] = std::array::from_fn(|k| x[k] - closest.point[k]);
            let plane: f64 = (0..3).map(|k| m[k] * offset[k]).sum();
            let distance = closest.signed_distance.abs();
            if distance <= NEAR_SURFACE * surface.facet_size(closest.facet) {
                return plane;
            }
            let inside = boundary
                .project(&x)
                .is_some_and(|p| p.signed_distance < 0.0);
            if inside { -distance } else { distance }
        })
        .collect()
}

/// The gap of one primary node linearized at an iterate.
#[derive(Debug, Clone, PartialEq)]
pub struct GapRow {
    /// The corners of the secondary facet the node projects onto (secondary surface indices)
    /// and the barycentric coordinates `b_k` of its closest point.
    pub corners: Vec<(usize, f64)>,
    /// The constraint direction `n = -m`, out of body 1.
    pub normal: [f64; 3],
    /// The gap `g(u^k)`.
    pub gap: f64,
    /// The right-hand side `n . (u1^k - sum_k b_k u2_k^k) + g(u^k)` of the row.
    pub target: f64,
}

/// The gap rows of every primary candidate at the displacements `u1`, `u2` (body dofs; `None`:
/// the reference configuration).
pub fn gap_rows(
    primary: &ContactSurface,
    secondary: &ContactSurface,
    u1: Option<&[f64]>,
    u2: Option<&[f64]>,
) -> Vec<GapRow> {
    let index = secondary.index(u2);
    let dim = primary.dim;
    let displacement = |surface: &ContactSurface, u: Option<&[f64]>, s: usize| -> [f64; 3] {
        let node = surface.nodes[s];
        std::array::from_fn(|k| match u {
            Some(u) if k < dim => u[dim * node + k],
            _ => 0.0,
        })
    };
    (0..primary.len())
        .map(|i| {
            let x = u1.map_or(primary.coords[i], |u| primary.deformed(u, i));
            let closest = (index.project_facing(&x, Some(&primary.normals[i])))
                .expect("a contact surface has facets");
            let m = index.normal(closest.facet);
            let normal = m.map(|v| -v);
            let gap: f64 = (0..3).map(|k| m[k] * (x[k] - closest.point[k])).sum();
            let corners: Vec<(usize, f64)> = (secondary.facet_nodes(closest.facet).iter())
                .zip(closest.barycentric)
                .map(|(&s, b)| (s, b))
                .collect();
            let own = displacement(primary, u1, i);
            let jump: [f64; 3] = std::array::from_fn(|k| {
                own[k]
                    - (corners.iter())
                        .map(|&(s, b)| b * displacement(secondary, u2, s)[k])
                        .sum::<f64>()
            });
            let target = (0..3).map(|k| normal[k] * jump[k]).sum::<f64>() + gap;
            GapRow {
                corners,
                normal,
                gap,
                target,
            }
        })
        .collect()
}
