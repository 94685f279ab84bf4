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
//! rather than pulled sideways onto the corner point. A node that lies beside the secondary
//! surface's rim in the reference configuration already (a block's node beside a punch) is
//! measured by its distance to the rim instead, and linearized along that distance's
//! gradient ([`geometric_gaps`]).
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
//! (`R21` or `R12^T`, [`crate::contact::Transfer`]), and at the answer every active node is on the
//! secondary's P1 surface, as before; only the path there changed. The earlier constraint used
//! the rows of `R12` with a correction `e = g - g_lin` from the last iterate: a fixed-point
//! iteration on `e` that contracts only where `R12` reproduces the P1 surface, and diverged
//! (error doubling each iteration) where it extrapolates, at the ends of two clamped blocks.

use crate::contact::geometry::displacement::BodyDisplacement;
use crate::contact::geometry::projection::{Projection, SurfaceIndex};
use crate::contact::geometry::surface::ContactSurface;

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

/// How far beyond the rim of the other surface, in units of the node's own spacing, a node
/// must lie to be measured by its distance rather than by the plane of the rim's facet: the
/// scale of `penetration_tolerance` (1e-3), so that a node on the rim to the precision the
/// checks judge a gap is held on the facet's plane as before.
pub const BEYOND_RIM: f64 = 1e-3;

/// The direction a node's gap row holds it along ([`gap_rows`]), where the node faces a facet.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RowNormal {
    /// The facet's own outward normal `m`: the gradient of the gap, so that the loop is Newton's
    /// method on it (module doc). It jumps from facet to facet.
    Facet,
    /// The displaced secondary's nodal normals (each the area-weighted mean of its facets'
    /// normals) interpolated at the closest point, `m = sum_k b_k N_k / |sum_k b_k N_k|`:
    /// continuous across the facets' edges, so that a node held on an edge reads the same
    /// direction from either facet (the smoothed normal of node-to-surface contact). The row
    /// `m . (x - q)` vanishes where the gap does, so the contact it holds is the same; only the
    /// direction of the force changes, by at most half the angle between two facets. Used by
    /// Coulomb friction (`crate::contact::law::coulomb`), whose answer is a fixed point in that
    /// direction: with facet normals, a node near an edge of the indented 3D block was held
    /// along one facet's normal, slipped onto the other's side, was held along that one's,
    /// slipped back, and the loop never settled; in 2D a node at the stick zone's rim
    /// alternated between stick and slip.
    Averaged,
}

/// The geometric gap of every node of `own` to the `other` body, each displaced by its body's
/// displacement (`None`: reference geometry), the one gap measure of the loop's penetration
/// test, the checks and the `normal_gap` output. The node's closest point `q` on the other
/// candidate surface's P1 facets ([`crate::contact::geometry::projection`], on the facet that faces
/// the node's own normal where several share it, as its linearization does, [`gap_rows`]) and that
/// facet's outward normal `m` give:
/// - for a node **beside the surface**, whose closest point is on the other surface's rim
///   (its free edges or end points) and which lies beyond the rim, along the facet's plane, by
///   more than [`BEYOND_RIM`] of its spacing, both in the reference configuration and now:
///   the distance `|x - q|`, negative only when the node is inside the other body (decided on
///   that body's closed boundary, [`crate::contact::geometry::boundary`]). Such a node faces no
///   facet: the plane of the rim's facet extends the surface where there is no surface, and a node
///   of a block bulging up beside a punch would read as penetrating the punch it does not touch
///   (`docs/method.md` 3.1). The reference configuration decides too because whether a node
///   faces a surface is a property of the two meshes: two blocks meant to end flush end a hair
///   apart once deformed, and a node whose side flips with that hair makes the loop cycle;
/// - otherwise, within [`NEAR_SURFACE`] of the facet, `g = m . (x - q)`, the distance to the
///   facet's plane: positive outside, negative inside, exact against a flat;
/// - farther, the distance `|x - q|`, negative when the node is inside the other body.
///
/// Defined at any distance.
pub fn geometric_gaps(
    own: &ContactSurface,
    other: &ContactSurface,
    u_own: Option<BodyDisplacement>,
    u_other: Option<BodyDisplacement>,
) -> Vec<f64> {
    let measure = Measure::new(own, other, u_own, u_other, RowNormal::Facet);
    (0..own.len())
        .map(|s| measure.geometric(&measure.at(s)))
        .collect()
}

/// The gap of one node of a surface to the other body (the rule of [`geometric_gaps`]).
struct NodeGap {
    /// The node's position.
    position: [f64; 3],
    closest: Projection,
    /// The gap's gradient with respect to the node's position: the facet's outward normal `m`,
    /// or, beside the rim, the unit vector `sign (x - q) / |x - q|`.
    direction: [f64; 3],
    /// `direction . (x - q)`: the distance to the facet's plane, or the signed distance beside
    /// the rim.
    value: f64,
    distance: f64,
    beside_rim: bool,
    facet_size: f64,
}

/// The projections one gap evaluation needs: the other surface displaced and its closed
/// boundary, and the other surface in the reference configuration, where whether a node lies
/// beside the other surface's rim is decided.
struct Measure<'a> {
    own: &'a ContactSurface,
    other: &'a ContactSurface,
    u_own: Option<BodyDisplacement<'a>>,
    surface: SurfaceIndex,
    /// The other surface in the reference configuration (`None`: it is `surface`).
    reference: Option<SurfaceIndex>,
    /// The other surface's displaced nodal normals, for [`RowNormal::Averaged`].
    nodal_normals: Option<Vec<[f64; 3]>>,
    boundary: SurfaceIndex,
}

/// A node's position, and its closest point on the other surface (`beside`: on the rim, with
/// the node beyond it).
struct Closest {
    position: [f64; 3],
    beside: Option<Projection>,
    point: Projection,
}

impl<'a> Measure<'a> {
    fn new(
        own: &'a ContactSurface,
        other: &'a ContactSurface,
        u_own: Option<BodyDisplacement<'a>>,
        u_other: Option<BodyDisplacement<'a>>,
        row_normal: RowNormal,
    ) -> Self {
        let nodal_normals = (row_normal == RowNormal::Averaged).then(|| match u_other {
            Some(u) => other.displaced_normals(u),
            None => other.normals.clone(),
        });
        Self {
            own,
            other,
            u_own,
            boundary: other.boundary.index(u_other),
            surface: other.index(u_other),
            reference: u_other.map(|_| other.index(None)),
            nodal_normals,
        }
    }

    /// Node `s`'s gap along the direction its row asks for ([`RowNormal`]).
    fn at(&self, s: usize) -> NodeGap {
        self.gap_of(&self.closest(s), self.nodal_normals.as_deref())
    }

    /// Where node `s` is and its closest point on the other surface: beside the rim (as judged
    /// in the reference configuration, then at the displaced position) or facing it.
    fn closest(&self, s: usize) -> Closest {
        let x = self
            .u_own
            .map_or(self.own.coords[s], |u| self.own.deformed(u, s));
        let reference = self.reference.as_ref().unwrap_or(&self.surface);
        let beside_in_reference =
            beside_rim(self.own, self.other, reference, &self.own.coords[s], s).is_some();
        let beside = beside_in_reference
            .then(|| beside_rim(self.own, self.other, &self.surface, &x, s))
            .flatten();
        let point = beside.unwrap_or_else(|| {
            (self.surface.project_facing(&x, Some(&self.own.normals[s])))
                .expect("a contact surface has facets")
        });
        Closest {
            position: x,
            beside,
            point,
        }
    }

    /// The gap at `closest` along the facet's normal, or the other surface's interpolated
    /// `nodal_normals` where given.
    fn gap_of(&self, closest: &Closest, nodal_normals: Option<&[[f64; 3]]>) -> NodeGap {
        let (x, beside, closest) = (closest.position, closest.beside, closest.point);
        let offset: [f64; 3] = std::array::from_fn(|k| x[k] - closest.point[k]);
        let distance = closest.signed_distance.abs();
        let direction = match beside {
            Some(_) => {
                let sign = if self.inside(&x) { -1.0 } else { 1.0 };
                offset.map(|v| sign * v / distance)
            }
            None => match nodal_normals {
                Some(normals) => {
                    let corners = self.other.facet_nodes(closest.facet);
                    let sum: [f64; 3] = std::array::from_fn(|k| {
                        (corners.iter().zip(closest.barycentric))
                            .map(|(&s, b)| b * normals[s][k])
                            .sum()
                    });
                    let length = (0..3).map(|k| sum[k] * sum[k]).sum::<f64>().sqrt();
                    sum.map(|v| v / length)
                }
                None => self.surface.normal(closest.facet),
            },
        };
        NodeGap {
            position: x,
            value: (0..3).map(|k| direction[k] * offset[k]).sum(),
            closest,
            direction,
            distance,
            beside_rim: beside.is_some(),
            facet_size: self.surface.facet_size(closest.facet),
        }
    }

    /// The geometric gap ([`geometric_gaps`]) of a node whose gap along the facet's normal is
    /// `gap`.
    fn geometric(&self, gap: &NodeGap) -> f64 {
        if gap.beside_rim || gap.distance <= NEAR_SURFACE * gap.facet_size {
            return gap.value;
        }
        if self.inside(&gap.position) {
            -gap.distance
        } else {
            gap.distance
        }
    }

    fn inside(&self, x: &[f64; 3]) -> bool {
        (self.boundary.project(x)).is_some_and(|p| p.signed_distance < 0.0)
    }
}

/// The closest point of `x` (node `s` of `own`) on `other`'s surface `index`, if it is on the
/// rim and `x` lies beyond it along the facet's plane by more than [`BEYOND_RIM`] of the
/// node's spacing.
fn beside_rim(
    own: &ContactSurface,
    other: &ContactSurface,
    index: &SurfaceIndex,
    x: &[f64; 3],
    s: usize,
) -> Option<Projection> {
    let closest =
        (index.project_facing(x, Some(&own.normals[s]))).expect("a contact surface has facets");
    if !other.on_rim(closest.facet, &closest.barycentric) {
        return None;
    }
    let m = index.normal(closest.facet);
    let offset: [f64; 3] = std::array::from_fn(|k| x[k] - closest.point[k]);
    let normal: f64 = (0..3).map(|k| m[k] * offset[k]).sum();
    let along: f64 = (0..3)
        .map(|k| (offset[k] - normal * m[k]).powi(2))
        .sum::<f64>();
    (along.sqrt() > BEYOND_RIM * own.spacing[s]).then_some(closest)
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

/// The gap rows of every primary candidate at the displacements `u1`, `u2` (`None`: the
/// reference configuration), each along the `row_normal` the pair's law asks for
/// (`crate::contact::law::ContactLaw::row_normal`).
pub fn gap_rows(
    primary: &ContactSurface,
    secondary: &ContactSurface,
    u1: Option<BodyDisplacement>,
    u2: Option<BodyDisplacement>,
    row_normal: RowNormal,
) -> Vec<GapRow> {
    let measure = Measure::new(primary, secondary, u1, u2, row_normal);
    (0..primary.len())
        .map(|i| row(&measure, u2, i, &measure.at(i)))
        .collect()
}

/// The geometric gap ([`geometric_gaps`]) and the gap row ([`gap_rows`]) of the primary
/// candidates `nodes`, with one search for the closest point of each: the two functions'
/// values, bit for bit, for the loop's iterate (a rank of a distributed run computes its
/// share of the candidates).
pub fn gaps_and_rows(
    primary: &ContactSurface,
    secondary: &ContactSurface,
    [u1, u2]: [BodyDisplacement; 2],
    row_normal: RowNormal,
    nodes: &[usize],
) -> Vec<(f64, GapRow)> {
    let measure = Measure::new(primary, secondary, Some(u1), Some(u2), row_normal);
    (nodes.iter())
        .map(|&i| {
            let closest = measure.closest(i);
            let along_facet = measure.gap_of(&closest, None);
            let gap = measure.geometric(&along_facet);
            let row = match &measure.nodal_normals {
                None => row(&measure, Some(u2), i, &along_facet),
                Some(normals) => row(
                    &measure,
                    Some(u2),
                    i,
                    &measure.gap_of(&closest, Some(normals)),
                ),
            };
            (gap, row)
        })
        .collect()
}

/// The gap row of primary node `i` whose gap along its row's direction is `node_gap`.
fn row(measure: &Measure, u2: Option<BodyDisplacement>, i: usize, node_gap: &NodeGap) -> GapRow {
    let (primary, secondary) = (measure.own, measure.other);
    let dim = primary.dim;
    let displacement = |surface: &ContactSurface, u: Option<BodyDisplacement>, s: usize| {
        u.map_or([0.0; 3], |u| u.at(dim, surface.nodes[s]))
    };
    let normal = node_gap.direction.map(|v| -v);
    let corners: Vec<(usize, f64)> = (secondary.facet_nodes(node_gap.closest.facet))
        .iter()
        .zip(node_gap.closest.barycentric)
        .map(|(&s, b)| (s, b))
        .collect();
    let own = displacement(primary, measure.u_own, i);
    let jump: [f64; 3] = std::array::from_fn(|k| {
        own[k]
            - (corners.iter())
                .map(|&(s, b)| b * displacement(secondary, u2, s)[k])
                .sum::<f64>()
    });
    let target = (0..3).map(|k| normal[k] * jump[k]).sum::<f64>() + node_gap.value;
    GapRow {
        corners,
        normal,
        gap: node_gap.value,
        target,
    }
}
