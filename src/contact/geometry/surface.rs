//! A body's contact candidate surface: its nodes, their outward normals, spacing and areas, and
//! its facets for the geometric gap ([`crate::contact::geometry::projection`]).
//!
//! Nodal normals are area-weighted averages of the normals of ALL candidate facets touching a
//! node (not only active ones, so rim nodes have well-defined normals), each facet oriented out
//! of its adjacent cell by the mesh reader (`docs/method.md`, section 1.3).
//!
//! The interface mass matrix is lumped: node `s` stands for the area `A_s = int phi_s ds`
//! ([`ContactSurface::nodal_area`]), so a nodal traction `t_s` exerts the force `A_s t_s` and the
//! mean pressure of a node (its normal force over its area) is its nodal pressure. The contact
//! conditions are then nodewise, `p_s >= 0, g_s >= 0, p_s g_s = 0`, and the active-set test on
//! the pressure judges exactly the unknown the system solves for (`docs/method.md` 2.1; with the
//! consistent matrix the two differ at the rim, where the P1 multiplier undershoots).

use std::collections::HashMap;

use thiserror::Error;

use crate::contact::geometry::boundary::BodyBoundary;
use crate::contact::geometry::displacement::BodyDisplacement;
use crate::contact::geometry::projection::SurfaceIndex;
use crate::contact::geometry::rbf::nearest_distances;
use crate::fem::LoadVector;
use crate::fem::kernels::facet_measure_and_normal;
use crate::mesh::BodyMesh;

#[derive(Debug, Error, PartialEq)]
pub enum SurfaceError {
    #[error("body '{body}' has no boundary group '{group}' (groups with facets on this body: {})", .on_body.join(", "))]
    MissingGroup {
        body: String,
        group: String,
        on_body: Vec<String>,
    },
    #[error("contact surface '{group}' of body '{body}' has fewer than two nodes")]
    TooSmall { body: String, group: String },
    #[error("contact surface '{group}' of body '{body}': {message}")]
    Spacing {
        body: String,
        group: String,
        message: String,
    },
}

/// The candidate surface of one body. Surface node `s` is body node `nodes[s]`.
#[derive(Debug, Clone)]
pub struct ContactSurface {
    pub body: String,
    pub group: String,
    pub dim: usize,
    /// Body-local node indices, sorted.
    pub nodes: Vec<usize>,
    /// gmsh node tag of each surface node (for messages and output).
    pub tags: Vec<u64>,
    /// Reference coordinates of the surface nodes.
    pub coords: Vec<[f64; 3]>,
    /// Outward unit normals.
    pub normals: Vec<[f64; 3]>,
    /// Distance to the nearest other surface node (the local spacing h).
    pub spacing: Vec<f64>,
    /// `int phi_s ds` over the candidate surface: the area (2D: length) a node stands for.
    pub nodal_area: Vec<f64>,
    /// Facets as surface node indices, `dim` per facet.
    facets: Vec<usize>,
    /// The surface's rim ([`Rim`]): where it ends.
    rim: Rim,
    /// The body's whole boundary, which tells inside from outside.
    pub boundary: BodyBoundary,
}

impl ContactSurface {
    pub fn new(body: &BodyMesh, group_name: &str) -> Result<Self, SurfaceError> {
        let dim = body.dim;
        let group = body
            .boundary_group(group_name)
            .ok_or_else(|| SurfaceError::MissingGroup {
                body: body.name.clone(),
                group: group_name.to_string(),
                on_body: body.boundary_groups.keys().cloned().collect(),
            })?;
        let nodes = group.nodes();
        if nodes.len() < 2 {
            return Err(SurfaceError::TooSmall {
                body: body.name.clone(),
                group: group_name.to_string(),
            });
        }
        let index: HashMap<usize, usize> = nodes.iter().enumerate().map(|(s, &n)| (n, s)).collect();
        let coords: Vec<[f64; 3]> = nodes.iter().map(|&n| body.coords[n]).collect();
        let mut facets = Vec::with_capacity(group.facets.len());
        let mut nodal_area = vec![0.0; nodes.len()];
        for f in 0..group.num_facets(dim) {
            let facet = group.facet(f, dim);
            let x: Vec<[f64; 3]> = facet.iter().map(|&n| body.coords[n]).collect();
            let (measure, _) = facet_measure_and_normal(&x, dim);
            for &n in facet {
                let s = index[&n];
                facets.push(s);
                nodal_area[s] += measure / dim as f64;
            }
        }
        let normals = area_weighted_normals(&facets, dim, &coords);
        let spacing = nearest_distances(&coords).map_err(|e| SurfaceError::Spacing {
            body: body.name.clone(),
            group: group_name.to_string(),
            message: e.to_string(),
        })?;
        let rim = Rim::new(&facets, dim, nodes.len());
        Ok(Self {
            body: body.name.clone(),
            group: group_name.to_string(),
            dim,
            tags: nodes.iter().map(|&n| body.node_tags.get(n)).collect(),
            nodes,
            coords,
            normals,
            spacing,
            nodal_area,
            facets,
            rim,
            boundary: BodyBoundary::new(body),
        })
    }

    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// The position of node `s` displaced by the body's displacement `u`.
    pub fn deformed(&self, u: BodyDisplacement, s: usize) -> [f64; 3] {
        let displacement = u.at(self.dim, self.nodes[s]);
        std::array::from_fn(|k| self.coords[s][k] + displacement[k])
    }

    /// The body's displacement `u` at this surface's nodes, three components per node in the
    /// surface's order (the third 0 in 2D).
    pub fn values(&self, u: BodyDisplacement) -> Vec<f64> {
        (self.nodes.iter())
            .flat_map(|&node| u.at(self.dim, node))
            .collect()
    }

    /// The contact pressure averaged over the patch of node `s` with its hat function as
    /// weight, `int p phi_s ds / int phi_s ds`, from the nodal contact forces `force` that the
    /// interface exerts on this body (body dofs, `dim` per node).
    pub fn mean_pressure(&self, force: &LoadVector, s: usize) -> f64 {
        let node = self.nodes[s];
        let normal_force: f64 = (0..self.dim)
            .map(|k| force.get(self.dim * node + k) * self.normals[s][k])
            .sum();
        -normal_force / self.nodal_area[s]
    }

    /// The largest angle, in degrees, between the normals of two facets that meet (at a node
    /// in 2D, along an edge in 3D), in the reference configuration: 180 / N on a circle of N
    /// facets, 90 at a square's corner.
    pub fn sharpest_turn(&self) -> f64 {
        self.turns().into_iter().fold(0.0, f64::max)
    }

    /// The surface's corners (the nodes at which it turns by more than `angle` degrees,
    /// `Self::turns`) and the nodes that share a facet with one, increasing.
    pub fn beside_corners(&self, angle: f64) -> Vec<usize> {
        let turns = self.turns();
        let mut nodes: Vec<usize> = (0..self.num_facets())
            .map(|f| self.facet_nodes(f))
            .filter(|corners| corners.iter().any(|&s| turns[s] > angle))
            .flatten()
            .copied()
            .collect();
        nodes.sort_unstable();
        nodes.dedup();
        nodes
    }

    /// At each node, the largest angle in degrees between the normals of two facets that meet
    /// there (2D) or along an edge through it (3D), in the reference configuration; zero at a
    /// node of one facet.
    fn turns(&self) -> Vec<f64> {
        let normal = |f: usize| {
            let x: Vec<[f64; 3]> = (self.facet_nodes(f).iter())
                .map(|&s| self.coords[s])
                .collect();
            facet_measure_and_normal(&x, self.dim).1
        };
        let normals: Vec<[f64; 3]> = (0..self.num_facets()).map(normal).collect();
        let mut meeting: HashMap<Vec<usize>, Vec<usize>> = HashMap::new();
        for f in 0..self.num_facets() {
            let corners = self.facet_nodes(f);
            for k in 0..self.dim {
                // 2D: each corner; 3D: the edge opposite each corner.
                let mut shared: Vec<usize> = match self.dim {
                    2 => vec![corners[k]],
                    _ => vec![corners[(k + 1) % 3], corners[(k + 2) % 3]],
                };
                shared.sort_unstable();
                meeting.entry(shared).or_default().push(f);
            }
        }
        let mut turns = vec![0.0_f64; self.len()];
        for (shared, facets) in &meeting {
            for (a, &f) in facets.iter().enumerate() {
                for &g in &facets[a + 1..] {
                    let cos = (0..3).map(|k| normals[f][k] * normals[g][k]).sum::<f64>();
                    let angle = cos.clamp(-1.0, 1.0).acos().to_degrees();
                    shared.iter().for_each(|&s| turns[s] = turns[s].max(angle));
                }
            }
        }
        turns
    }

    /// The number of facets.
    pub fn num_facets(&self) -> usize {
        self.facets.len() / self.dim
    }

    /// The corners of facet `facet` (surface node indices), in the order of the barycentric
    /// coordinates of a [`crate::contact::geometry::projection::Projection`] onto it.
    /// The outward unit normal at each node of the surface displaced by `u` (body dofs), as
    /// [`Self::normals`] are in the reference configuration.
    pub fn displaced_normals(&self, u: BodyDisplacement) -> Vec<[f64; 3]> {
        let positions: Vec<[f64; 3]> = (0..self.len()).map(|s| self.deformed(u, s)).collect();
        area_weighted_normals(&self.facets, self.dim, &positions)
    }

    pub fn facet_nodes(&self, facet: usize) -> &[usize] {
        &self.facets[self.dim * facet..self.dim * (facet + 1)]
    }

    /// Whether the point with `barycentric` coordinates on facet `facet` (a closest point,
    /// [`crate::contact::geometry::projection::Projection`]) lies on the surface's rim (`Rim`).
    pub fn on_rim(&self, facet: usize, barycentric: &[f64; 3]) -> bool {
        self.rim
            .contains(self.facet_nodes(facet), facet, barycentric)
    }

    /// The reference position of the point with `barycentric` coordinates on facet `facet`: the
    /// material point a projection onto the displaced surface found.
    pub fn reference_point(&self, facet: usize, barycentric: &[f64; 3]) -> [f64; 3] {
        let corners = &self.facets[self.dim * facet..self.dim * (facet + 1)];
        std::array::from_fn(|k| {
            (corners.iter().zip(barycentric))
                .map(|(&s, b)| b * self.coords[s][k])
                .sum()
        })
    }

    /// The surface's facets at its nodes' positions displaced by `u` (`None`: the reference
    /// positions), indexed for closest-point projection.
    pub fn index(&self, u: Option<BodyDisplacement>) -> SurfaceIndex {
        let positions: Vec<[f64; 3]> = match u {
            Some(u) => (0..self.len()).map(|s| self.deformed(u, s)).collect(),
            None => self.coords.clone(),
        };
        SurfaceIndex::new(&self.facets, self.dim, &positions)
    }
}

/// The mean of the facets' outward normals at each node, weighted by the facets' areas (2D:
/// lengths), of unit length; `facets` lists `dim` node indices into `positions` per facet.
fn area_weighted_normals(facets: &[usize], dim: usize, positions: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let mut normals = vec![[0.0; 3]; positions.len()];
    for facet in facets.chunks_exact(dim) {
        let x: Vec<[f64; 3]> = facet.iter().map(|&s| positions[s]).collect();
        let (measure, normal) = facet_measure_and_normal(&x, dim);
        for &s in facet {
            for k in 0..3 {
                normals[s][k] += measure * normal[k];
            }
        }
    }
    for n in &mut normals {
        let norm = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        n.iter_mut().for_each(|v| *v /= norm);
    }
    normals
}

/// Where a candidate surface ends: its free edges (3D: the edges of one facet only) and their
/// nodes, or its end points (2D: the nodes of one facet only). A closed candidate surface has
/// none. A point beyond the rim faces no facet, so the plane of the facet it is closest to
/// says nothing about it (`crate::contact::geometry::gap`).
#[derive(Debug, Clone)]
struct Rim {
    /// Surface nodes on the rim.
    nodes: Vec<bool>,
    /// 3D: per facet, whether the edge opposite each corner is a free edge.
    edges: Vec<[bool; 3]>,
}

impl Rim {
    fn new(facets: &[usize], dim: usize, num_nodes: usize) -> Self {
        let mut nodes = vec![false; num_nodes];
        let mut edges = Vec::new();
        if dim == 2 {
            let mut count = vec![0usize; num_nodes];
            facets.iter().for_each(|&s| count[s] += 1);
            (nodes.iter_mut().zip(count)).for_each(|(rim, c)| *rim = c == 1);
            return Self { nodes, edges };
        }
        let edge = |corners: &[usize], k: usize| {
            let (a, b) = (corners[(k + 1) % 3], corners[(k + 2) % 3]);
            (a.min(b), a.max(b))
        };
        let mut count: HashMap<(usize, usize), usize> = HashMap::new();
        for corners in facets.chunks_exact(3) {
            (0..3).for_each(|k| *count.entry(edge(corners, k)).or_default() += 1);
        }
        for corners in facets.chunks_exact(3) {
            let free: [bool; 3] = std::array::from_fn(|k| count[&edge(corners, k)] == 1);
            for k in (0..3).filter(|&k| free[k]) {
                let (a, b) = edge(corners, k);
                nodes[a] = true;
                nodes[b] = true;
            }
            edges.push(free);
        }
        Self { nodes, edges }
    }

    /// Whether the point with `barycentric` coordinates on the facet with `corners` (index
    /// `facet`) is on the rim: at a rim node, or (3D) inside a free edge. The closest-point
    /// projection puts exact zeros in the coordinates of a point on an edge or a corner.
    fn contains(&self, corners: &[usize], facet: usize, barycentric: &[f64; 3]) -> bool {
        let dim = corners.len();
        let zeros: Vec<usize> = (0..dim).filter(|&k| barycentric[k] == 0.0).collect();
        match zeros.len() {
            // At a corner: the one with coordinate 1.
            n if n == dim - 1 => (0..dim).any(|k| !zeros.contains(&k) && self.nodes[corners[k]]),
            1 => self.edges[facet][zeros[0]],
            _ => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Rim;

    #[test]
    fn the_rim_of_a_square_of_four_triangles_is_its_outline() {
        // Corners 0..3 of the unit square and its centre 4, four triangles about the centre.
        let facets = [0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4];
        let rim = Rim::new(&facets, 3, 5);
        assert_eq!(rim.nodes, [true, true, true, true, false]);
        // Each triangle's free edge is the one opposite the centre (its third corner).
        assert!(rim.edges.iter().all(|e| *e == [false, false, true]));
        // On the free edge 0-1, at corner 1, inside the facet, on the inner edge 1-4.
        assert!(rim.contains(&facets[0..3], 0, &[0.5, 0.5, 0.0]));
        assert!(rim.contains(&facets[0..3], 0, &[0.0, 1.0, 0.0]));
        assert!(!rim.contains(&facets[0..3], 0, &[0.2, 0.3, 0.5]));
        assert!(!rim.contains(&facets[0..3], 0, &[0.0, 0.5, 0.5]));
        // The centre is no rim node.
        assert!(!rim.contains(&facets[0..3], 0, &[0.0, 0.0, 1.0]));
    }

    #[test]
    fn the_rim_of_a_polyline_is_its_two_ends() {
        let facets = [0, 1, 1, 2, 2, 3];
        let rim = Rim::new(&facets, 2, 4);
        assert_eq!(rim.nodes, [true, false, false, true]);
        assert!(rim.contains(&facets[0..2], 0, &[1.0, 0.0, 0.0]));
        assert!(!rim.contains(&facets[0..2], 0, &[0.0, 1.0, 0.0]));
        assert!(!rim.contains(&facets[2..4], 1, &[0.5, 0.5, 0.0]));
    }
}
