//! The spacing `h` of a level, measured on its mesh rather than assumed from the parameter:
//! refinement ratios of unstructured meshes are never exactly the ratio of the size parameters.

use serde::Serialize;

use crate::mesh::Mesh;
use crate::run::CaseSolution;

/// What [`Spacing::h`] is, for the study's files.
pub const SPACING_DEFINITION: &str = "mean edge length of the primary body's candidate-surface \
     facets that have an active node (the contact zone); of all its candidate-surface facets \
     when none is active";

/// A level's spacing.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Spacing {
    /// Mean edge length of the facets measured.
    pub h: f64,
    /// How many facets were measured.
    pub facets: usize,
    /// Whether they are the contact zone's (else the whole candidate surface's).
    pub contact_zone: bool,
}

/// The spacing of the contact zone on the primary body `primary`, whose candidate surface is
/// the one `contact` (the case's `[contact]` bodies and surfaces) pairs with it: the mean length
/// of the edges of the surface's facets (segments in 2D, triangles in 3D) with at least one
/// active node, or of all its facets when none is active. NaN (no facet) when the primary or
/// its surface is not found.
pub fn contact_zone_spacing(
    mesh: &Mesh,
    solution: &CaseSolution,
    primary: &str,
    contact: Option<&([String; 2], [String; 2])>,
) -> Spacing {
    let none = Spacing {
        h: f64::NAN,
        facets: 0,
        contact_zone: false,
    };
    let Some((bodies, surfaces)) = contact else {
        return none;
    };
    let Some(k) = bodies.iter().position(|b| b == primary) else {
        return none;
    };
    let (Some(body), Some(solved)) = (
        mesh.body(primary),
        solution.bodies.iter().find(|b| b.name == primary),
    ) else {
        return none;
    };
    let Some(group) = body.boundary_group(&surfaces[k]) else {
        return none;
    };
    let mut active = vec![false; body.num_nodes()];
    for surface in &solved.surfaces {
        let fields = &surface.fields;
        for (&node, &on) in fields.nodes.iter().zip(&fields.active) {
            active[node] |= on;
        }
    }
    let facets: Vec<&[usize]> = (0..group.num_facets(body.dim))
        .map(|f| group.facet(f, body.dim))
        .collect();
    let zone: Vec<&[usize]> = (facets.iter().copied())
        .filter(|facet| facet.iter().any(|&n| active[n]))
        .collect();
    let contact_zone = !zone.is_empty();
    let measured = if contact_zone { zone } else { facets };
    Spacing {
        h: mean_edge_length(&body.coords, &measured),
        facets: measured.len(),
        contact_zone,
    }
}

/// The mean length of the edges of `facets` (each facet's nodes in order, closed in 3D).
fn mean_edge_length<C>(coords: &C, facets: &[&[usize]]) -> f64
where
    C: std::ops::Index<usize, Output = [f64; 3]> + ?Sized,
{
    let distance = |a: usize, b: usize| {
        (0..3)
            .map(|i| (coords[a][i] - coords[b][i]).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    let mut total = 0.0;
    let mut count = 0usize;
    for facet in facets {
        // A segment has one edge; a triangle three (its last node back to the first).
        let edges = if facet.len() == 2 { 1 } else { facet.len() };
        for e in 0..edges {
            total += distance(facet[e], facet[(e + 1) % facet.len()]);
            count += 1;
        }
    }
    if count == 0 {
        f64::NAN
    } else {
        total / count as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edges_of_segments_and_triangles() {
        let coords = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        assert_eq!(mean_edge_length(&coords, &[&[0, 1], &[0, 2]]), 1.5);
        let triangle = mean_edge_length(&coords, &[&[0, 1, 2]]);
        assert!((triangle - (2.0 + 1.0 + 5f64.sqrt()) / 3.0).abs() < 1e-15);
        assert!(mean_edge_length(&coords, &[]).is_nan());
    }
}
