//! The whole boundary of a body (every cell facet that no other cell shares), oriented
//! outward: a closed surface, on which the sign of the distance to the closest point tells
//! inside from outside wherever the point is ([`crate::contact::geometry::projection`]).
//!
//! A candidate contact surface alone is an open patch: a point behind it (the top face of a
//! block seen from its base, two units away) has a negative distance along the patch's normal
//! without being inside the body. Whether a node penetrates is therefore decided on the closed
//! boundary, and how deep on the candidate surface.

use std::collections::HashMap;

use crate::contact::geometry::displacement::BodyDisplacement;
use crate::contact::geometry::projection::SurfaceIndex;
use crate::fem::kernels::facet_measure_and_normal;
use crate::mesh::BodyMesh;

/// The boundary facets of a body: `dim` node indices each, into `nodes`.
#[derive(Debug, Clone)]
pub struct BodyBoundary {
    dim: usize,
    /// Body-local nodes on the boundary.
    nodes: Vec<usize>,
    /// Their reference coordinates.
    coords: Vec<[f64; 3]>,
    /// Facets, `dim` indices into `nodes` each, right-hand normal outward.
    facets: Vec<usize>,
}

impl BodyBoundary {
    pub fn new(body: &BodyMesh) -> Self {
        let dim = body.dim;
        let mut index: HashMap<usize, usize> = HashMap::new();
        let mut nodes = Vec::new();
        let mut facets = Vec::new();
        for entry in body.boundary_facets().chunks_exact(dim + 1) {
            let (mut facet, opposite) = (entry[..dim].to_vec(), entry[dim]);
            let x: Vec<[f64; 3]> = facet.iter().map(|&n| body.coords[n]).collect();
            let (_, normal) = facet_measure_and_normal(&x, dim);
            let inward: f64 = (0..3)
                .map(|k| normal[k] * (body.coords[opposite][k] - x[0][k]))
                .sum();
            if inward > 0.0 {
                facet.swap(0, 1);
            }
            for n in facet {
                let next = nodes.len();
                let i = *index.entry(n).or_insert(next);
                if i == next {
                    nodes.push(n);
                }
                facets.push(i);
            }
        }
        Self {
            dim,
            coords: nodes.iter().map(|&n| body.coords[n]).collect(),
            nodes,
            facets,
        }
    }

    /// The body's nodes on the boundary (each once, in no particular order).
    pub fn nodes(&self) -> &[usize] {
        &self.nodes
    }

    /// The boundary displaced by the body's displacement `u` (`None`: reference), indexed for
    /// closest-point queries.
    pub fn index(&self, u: Option<BodyDisplacement>) -> SurfaceIndex {
        let dim = self.dim;
        let positions: Vec<[f64; 3]> = match u {
            Some(u) => (self.nodes.iter().zip(&self.coords))
                .map(|(&n, x)| {
                    let displacement = u.at(dim, n);
                    std::array::from_fn(|k| x[k] + displacement[k])
                })
                .collect(),
            None => self.coords.clone(),
        };
        SurfaceIndex::new(&self.facets, dim, &positions)
    }
}
