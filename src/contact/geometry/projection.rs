//! The geometric gap: closest-point projection of a point onto a contact surface (`docs/method.md`
//! section 3.1), the one gap measure of the contact checks, the `normal_gap` output and the
//! certificate.
//!
//! A surface is its P1 facets (segments in 2D, triangles in 3D) at given node positions, the
//! reference ones or displaced ones. The facets go into an R*-tree (`rstar`) over their bounding
//! boxes, so that the closest facet of any point is found whatever its distance: unlike an
//! RBF-interpolated gap, this one is defined for every node, and exact against a flat.
//!
//! The signed gap of a point `x` with closest surface point `p` is `g = (x - p) . n`, `n` the
//! outward unit normal of the closest facet: positive outside the body, negative inside. When
//! the closest point is on an edge or a vertex shared by several facets (a convex corner), the
//! normals of all the facets at the same distance are averaged (the pseudo-normal), which gives
//! the right sign on both sides of the corner.

use rstar::{AABB, PointDistance, RTree, RTreeObject};

use crate::fem::kernels::facet_measure_and_normal;

/// The closest point of a surface to a query point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projection {
    /// The closest point `p` on the surface.
    pub point: [f64; 3],
    /// The facet it lies on (index into the surface's facets).
    pub facet: usize,
    /// Barycentric coordinates of `p` on that facet (the last is 0 for a segment).
    pub barycentric: [f64; 3],
    /// Signed distance `(x - p) . n`: positive outside the surface's body, negative inside.
    pub signed_distance: f64,
}

/// A facet with its corner positions, as stored in the R*-tree.
struct Facet {
    index: usize,
    corners: Vec<[f64; 3]>,
    envelope: AABB<[f64; 3]>,
}

impl RTreeObject for Facet {
    type Envelope = AABB<[f64; 3]>;

    fn envelope(&self) -> Self::Envelope {
        self.envelope
    }
}

impl PointDistance for Facet {
    fn distance_2(&self, point: &[f64; 3]) -> f64 {
        let (p, _) = closest_point(&self.corners, point);
        distance_squared(&p, point)
    }
}

/// A surface's facets at given node positions, indexed for closest-point queries.
pub struct SurfaceIndex {
    tree: RTree<Facet>,
    /// Outward unit normal of each facet.
    normals: Vec<[f64; 3]>,
    /// Longest edge of each facet.
    sizes: Vec<f64>,
    /// Mean facet diameter: the length scale of "on the surface".
    length: f64,
}

impl SurfaceIndex {
    /// `facets` lists `dim` node indices per facet (outward orientation, as the mesh reader
    /// leaves boundary facets), `positions` the node positions they index.
    pub fn new(facets: &[usize], dim: usize, positions: &[[f64; 3]]) -> Self {
        let facets: Vec<Facet> = facets
            .chunks_exact(dim)
            .enumerate()
            .map(|(index, nodes)| {
                let corners: Vec<[f64; 3]> = nodes.iter().map(|&n| positions[n]).collect();
                let envelope = AABB::from_points(corners.iter());
                Facet {
                    index,
                    corners,
                    envelope,
                }
            })
            .collect();
        let mut normals = vec![[0.0; 3]; facets.len()];
        let mut sizes = vec![0.0; facets.len()];
        for facet in &facets {
            normals[facet.index] = facet_measure_and_normal(&facet.corners, dim).1;
            let corners = &facet.corners;
            sizes[facet.index] = (0..corners.len())
                .map(|a| distance_squared(&corners[a], &corners[(a + 1) % corners.len()]).sqrt())
                .fold(0.0, f64::max);
        }
        let length = facets
            .iter()
            .map(|f| distance_squared(&f.corners[0], &f.corners[1]).sqrt())
            .sum::<f64>()
            / facets.len().max(1) as f64;
        Self {
            tree: RTree::bulk_load(facets),
            normals,
            sizes,
            length,
        }
    }

    /// The closest point of the surface to `x`, with the signed distance (module doc). `None`
    /// only for a surface without facets.
    pub fn project(&self, x: &[f64; 3]) -> Option<Projection> {
        self.project_facing(x, None)
    }

    /// [`Self::project`], on the facet that faces `towards` the most when several share the
    /// closest point (an edge or a vertex of the surface): the one whose outward normal is the
    /// most opposed to `towards`. The gap's linearization holds the node on that facet's plane
    /// (`crate::contact::geometry::gap`): a block's node under a punch's corner is held on the
    /// punch's face, not on its side.
    pub fn project_facing(&self, x: &[f64; 3], towards: Option<&[f64; 3]>) -> Option<Projection> {
        let mut nearest = self.tree.nearest_neighbor_iter_with_distance_2(x);
        let (first, d2) = nearest.next()?;
        let (mut point, mut barycentric) = closest_point(&first.corners, x);
        let mut facet = first.index;
        let facing = |f: usize| towards.map_or(0.0, |t| dot(&self.normals[f], t));
        // Facets sharing the closest point (to rounding) contribute to the pseudo-normal.
        let tie = d2 * (1.0 + 1e-9) + 1e-300;
        let mut normal = self.normals[first.index];
        for (other, other_d2) in nearest {
            if other_d2 > tie {
                break;
            }
            let n = self.normals[other.index];
            normal = std::array::from_fn(|k| normal[k] + n[k]);
            if facing(other.index) < facing(facet) {
                facet = other.index;
                (point, barycentric) = closest_point(&other.corners, x);
            }
        }
        let offset: [f64; 3] = std::array::from_fn(|k| x[k] - point[k]);
        let distance = d2.sqrt();
        let along = offset[0] * normal[0] + offset[1] * normal[1] + offset[2] * normal[2];
        // The distance is exact; the pseudo-normal only decides the side.
        let signed_distance = if along < 0.0 { -distance } else { distance };
        Some(Projection {
            point,
            facet,
            barycentric,
            signed_distance,
        })
    }
}

impl SurfaceIndex {
    /// The point where the line through `x` along the unit vector `direction` meets the
    /// surface, found by repeated closest-point projection of points on that line:
    /// `q_0 = x`, `q_{k+1} = x + ((p(q_k) - x) . direction) direction`, `p` the closest point.
    /// A point of the surface on the line is a fixed point; the iteration contracts when the
    /// line crosses the surface at an angle well away from tangent (facing contact surfaces).
    /// Falls back to the closest point of `x` when it does not converge to within `1e-10` of
    /// the distance plus the facet size (the line misses the surface, e.g. beyond its edge).
    /// The flag says whether
    /// the line met the surface.
    pub fn project_along(&self, x: &[f64; 3], direction: &[f64; 3]) -> Option<(Projection, bool)> {
        let closest = self.project(x)?;
        let scale = dot(&sub(&closest.point, x), &sub(&closest.point, x)).sqrt();
        let mut p = closest;
        for _ in 0..50 {
            let t = dot(&sub(&p.point, x), direction);
            let q: [f64; 3] = std::array::from_fn(|k| x[k] + t * direction[k]);
            p = self.project(&q)?;
            let miss = dot(&sub(&p.point, &q), &sub(&p.point, &q)).sqrt();
            if miss <= 1e-10 * (scale + self.length) {
                return Some((p, true));
            }
        }
        Some((closest, false))
    }

    /// Outward unit normal of facet `facet`.
    pub fn normal(&self, facet: usize) -> [f64; 3] {
        self.normals[facet]
    }

    /// Longest edge of facet `facet` (its length in 2D).
    pub fn facet_size(&self, facet: usize) -> f64 {
        self.sizes[facet]
    }
}

fn distance_squared(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]) * (a[k] - b[k])).sum()
}

fn sub(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    std::array::from_fn(|k| a[k] - b[k])
}

fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Closest point of a segment (2 corners) or triangle (3 corners) to `x`, and its barycentric
/// coordinates.
pub(crate) fn closest_point(corners: &[[f64; 3]], x: &[f64; 3]) -> ([f64; 3], [f64; 3]) {
    match corners {
        [a, b] => {
            let ab = sub(b, a);
            let length2 = dot(&ab, &ab);
            let t = if length2 > 0.0 {
                (dot(&sub(x, a), &ab) / length2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (std::array::from_fn(|k| a[k] + t * ab[k]), [1.0 - t, t, 0.0])
        }
        [a, b, c] => closest_point_on_triangle(a, b, c, x),
        _ => unreachable!("facets have 2 or 3 corners"),
    }
}

/// Closest point of triangle `abc` to `x` by its Voronoi regions (Ericson, Real-Time Collision
/// Detection, section 5.1.5), with barycentric coordinates.
fn closest_point_on_triangle(
    a: &[f64; 3],
    b: &[f64; 3],
    c: &[f64; 3],
    x: &[f64; 3],
) -> ([f64; 3], [f64; 3]) {
    let at = |u: f64, v: f64, w: f64| -> ([f64; 3], [f64; 3]) {
        (
            std::array::from_fn(|k| u * a[k] + v * b[k] + w * c[k]),
            [u, v, w],
        )
    };
    let (ab, ac, ax) = (sub(b, a), sub(c, a), sub(x, a));
    let (d1, d2) = (dot(&ab, &ax), dot(&ac, &ax));
    if d1 <= 0.0 && d2 <= 0.0 {
        return at(1.0, 0.0, 0.0);
    }
    let bx = sub(x, b);
    let (d3, d4) = (dot(&ab, &bx), dot(&ac, &bx));
    if d3 >= 0.0 && d4 <= d3 {
        return at(0.0, 1.0, 0.0);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return at(1.0 - v, v, 0.0);
    }
    let cx = sub(x, c);
    let (d5, d6) = (dot(&ab, &cx), dot(&ac, &cx));
    if d6 >= 0.0 && d5 <= d6 {
        return at(0.0, 0.0, 1.0);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return at(1.0 - w, 0.0, w);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return at(0.0, 1.0 - w, w);
    }
    let denominator = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denominator, vc * denominator);
    at(1.0 - v - w, v, w)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unit square [0,1]^2 at z = 0 in two triangles, normal +z.
    fn square() -> SurfaceIndex {
        let positions = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        SurfaceIndex::new(&[0, 1, 2, 0, 2, 3], 3, &positions)
    }

    #[test]
    fn gap_to_a_flat_is_exact_at_any_distance() {
        let surface = square();
        for (x, expected) in [
            ([0.3, 0.6, 1e-7], 1e-7),
            ([0.3, 0.6, -0.25], -0.25),
            ([0.9, 0.1, 40.0], 40.0),
            ([0.5, 0.5, -3.0], -3.0),
        ] {
            let p = surface.project(&x).unwrap();
            assert!((p.signed_distance - expected).abs() < 1e-14 * (1.0 + expected.abs()));
            assert!((p.point[0] - x[0]).abs() < 1e-14 && (p.point[1] - x[1]).abs() < 1e-14);
            let sum: f64 = p.barycentric.iter().sum();
            assert!((sum - 1.0).abs() < 1e-14);
        }
    }

    #[test]
    fn off_the_edge_the_closest_point_is_on_the_boundary() {
        let p = square().project(&[2.0, 0.5, 1.0]).unwrap();
        assert!((p.point[0] - 1.0).abs() < 1e-14 && (p.point[1] - 0.5).abs() < 1e-14);
        assert!((p.signed_distance - 2f64.sqrt()).abs() < 1e-14);
    }

    #[test]
    fn corner_of_a_convex_polyline_is_signed_by_the_pseudo_normal() {
        // A roof /\ with its apex at (0, 1): outward normals up-left and up-right (body below).
        let positions = [[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]];
        let surface = SurfaceIndex::new(&[1, 0, 2, 1], 2, &positions);
        // Both facets' orientation: check their normals point up.
        assert!(surface.normals.iter().all(|n| n[1] > 0.0));
        let above = surface.project(&[0.0, 1.5, 0.0]).unwrap();
        assert!((above.signed_distance - 0.5).abs() < 1e-14);
        let below = surface.project(&[0.0, 0.8, 0.0]).unwrap();
        assert!(below.signed_distance < 0.0);
    }
}
