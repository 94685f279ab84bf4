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
    /// At each node, the largest angle in degrees between the normals of two facets that meet
    /// there (2D) or along an edge through it (3D), in the reference configuration; zero at a
    /// node of one facet.
    turns: Vec<f64>,
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
        let meeting = facets_meeting(&facets, dim);
        let rim = Rim::new(&meeting, &facets, dim, nodes.len());
        let turns = turns(&meeting, &facets, dim, &coords);
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
            turns,
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
        self.turns.iter().copied().fold(0.0, f64::max)
    }

    /// The surface's corners (the nodes at which it turns by more than `angle` degrees) and
    /// the nodes that share a facet with one, increasing.
    pub fn beside_corners(&self, angle: f64) -> Vec<usize> {
        let mut nodes: Vec<usize> = (0..self.num_facets())
            .map(|f| self.facet_nodes(f))
            .filter(|corners| corners.iter().any(|&s| self.turns[s] > angle))
            .flatten()
            .copied()
            .collect();
        nodes.sort_unstable();
        nodes.dedup();
        nodes
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

/// Where the facets of a surface meet ([`meeting_key`]: at a node in 2D, along an edge in 3D),
/// and which facets meet there.
fn facets_meeting(facets: &[usize], dim: usize) -> HashMap<(usize, usize), Vec<usize>> {
    let mut meeting: HashMap<(usize, usize), Vec<usize>> = HashMap::new();
    for (f, corners) in facets.chunks_exact(dim).enumerate() {
        for k in 0..dim {
            meeting.entry(meeting_key(corners, k)).or_default().push(f);
        }
    }
    meeting
}

/// The `k`-th place where a facet with `corners` meets others: its corner `k` in 2D (the key
/// `(s, s)`), the edge opposite its corner `k` in 3D (its two nodes, in increasing order).
fn meeting_key(corners: &[usize], k: usize) -> (usize, usize) {
    match corners.len() {
        2 => (corners[k], corners[k]),
        _ => {
            let (a, b) = (corners[(k + 1) % 3], corners[(k + 2) % 3]);
            (a.min(b), a.max(b))
        }
    }
}

/// At each node, the largest angle in degrees between the normals of two facets that meet
/// there or along an edge through it (`ContactSurface::turns`).
fn turns(
    meeting: &HashMap<(usize, usize), Vec<usize>>,
    facets: &[usize],
    dim: usize,
    coords: &[[f64; 3]],
) -> Vec<f64> {
    let normals: Vec<[f64; 3]> = (facets.chunks_exact(dim))
        .map(|corners| {
            let x: Vec<[f64; 3]> = corners.iter().map(|&s| coords[s]).collect();
            facet_measure_and_normal(&x, dim).1
        })
        .collect();
    let mut turns = vec![0.0_f64; coords.len()];
    for (&(a, b), meeting_facets) in meeting {
        for (i, &f) in meeting_facets.iter().enumerate() {
            for &g in &meeting_facets[i + 1..] {
                let cos = (0..3).map(|k| normals[f][k] * normals[g][k]).sum::<f64>();
                let angle = cos.clamp(-1.0, 1.0).acos().to_degrees();
                turns[a] = turns[a].max(angle);
                turns[b] = turns[b].max(angle);
            }
        }
    }
    turns
}

impl Rim {
    /// The rim of the surface of `facets` whose facets meet as `meeting` says
    /// ([`facets_meeting`]): the nodes of one facet (2D), the edges of one facet and their
    /// nodes (3D).
    fn new(
        meeting: &HashMap<(usize, usize), Vec<usize>>,
        facets: &[usize],
        dim: usize,
        num_nodes: usize,
    ) -> Self {
        let mut nodes = vec![false; num_nodes];
        let mut edges = Vec::new();
        let free = |corners: &[usize], k: usize| meeting[&meeting_key(corners, k)].len() == 1;
        if dim == 2 {
            for corners in facets.chunks_exact(2) {
                (0..2).for_each(|k| nodes[corners[k]] |= free(corners, k));
            }
            return Self { nodes, edges };
        }
        for corners in facets.chunks_exact(3) {
            let free: [bool; 3] = std::array::from_fn(|k| free(corners, k));
            for k in (0..3).filter(|&k| free[k]) {
                let (a, b) = meeting_key(corners, k);
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
    use super::{Rim, facets_meeting};

    fn rim(facets: &[usize], dim: usize, num_nodes: usize) -> Rim {
        Rim::new(&facets_meeting(facets, dim), facets, dim, num_nodes)
    }

    #[test]
    fn the_rim_of_a_square_of_four_triangles_is_its_outline() {
        // Corners 0..3 of the unit square and its centre 4, four triangles about the centre.
        let facets = [0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4];
        let rim = rim(&facets, 3, 5);
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
        let rim = rim(&facets, 2, 4);
        assert_eq!(rim.nodes, [true, false, false, true]);
        assert!(rim.contains(&facets[0..2], 0, &[1.0, 0.0, 0.0]));
        assert!(!rim.contains(&facets[0..2], 0, &[0.0, 1.0, 0.0]));
        assert!(!rim.contains(&facets[2..4], 1, &[0.5, 0.5, 0.0]));
    }
}
