//! The walls at a concave vertex or edge: the second facet a primary node must not cross where
//! its closest facet on the other surface meets another at a concave vertex (2D) or edge (3D).
//!
//! A node's gap row ([`crate::contact::geometry::gap`]) holds it on the plane of one facet,
//! the one its closest point lies on. Where the other surface is concave, as the crater a
//! corner digs into a body of its own stiffness, the node sits in a vertex between two facets:
//! held on one facet's plane it can slide through the other facet, and at the next iterate it
//! faces that one and is held on its plane instead, sliding back through the first. With both
//! facets' rows the node is held at the vertex, in the normal cone of the two planes, which is
//! what a node in a V-shaped groove is at the answer (in 3D the groove an edge digs along its
//! length: the node held on the groove's bottom edge). Each facet that shares a vertex with the
//! closest facet and turns towards the node (its corners off the closest facet on the node's
//! side of the closest facet's plane) by more than [`WALL_ANGLE`] is a *wall*: its gap
//! `g_w = m_w . (x - q_w)` (`q_w` the node's closest point on that facet, `m_w` its outward
//! normal) linearized as the gap is, the row
//! `n_w . (u1 - sum_k b_k u2_k) = n_w . (u1^k - sum_k b_k u2_k^k) + g_w(u^k)`, `n_w = -m_w`.
//! Which of them an active node holds is the loop's decision
//! (`crate::contact::iteration::walls`).

use std::collections::HashMap;

use crate::contact::geometry::displacement::BodyDisplacement;
use crate::contact::geometry::gap::GapRow;
use crate::contact::geometry::projection::closest_point;
use crate::contact::geometry::surface::ContactSurface;
use crate::fem::kernels::facet_measure_and_normal;

/// The least angle between the closest facet and a facet meeting it for the second to be a
/// wall. Below it the two planes hold the node at nearly the same place (the second row
/// differs from the first by under 1.5% of a gap, `1 - cos 10°`) and the two rows are nearly
/// parallel, which would make the pair of them ill-conditioned; a P1 surface bending under a
/// smooth body turns by a few degrees per facet (the Hertz sweep's blocks: under 3).
pub const WALL_ANGLE: f64 = 10.0;

/// Two rows whose directions are closer than this (`|n . n_w|`) would hold the node along one
/// direction twice: [`WALL_ANGLE`] keeps walls far from it.
const PARALLEL: f64 = 0.999;

/// One wall of a primary node: a facet meeting its closest facet at a concave vertex, and the
/// node's gap to its plane linearized at the iterate, as [`GapRow`] is for the closest facet.
#[derive(Debug, Clone, PartialEq)]
pub struct Wall {
    /// The wall's facet and the node's closest facet (secondary facet indices): a wall is held
    /// by this pair, so that it is the same wall when the node's closest facet becomes the
    /// other one of the two.
    pub facets: [usize; 2],
    /// The wall's corners (secondary surface indices) and the barycentric coordinates of the
    /// node's closest point on it.
    pub corners: Vec<(usize, f64)>,
    /// The row's direction `n_w = -m_w`, out of body 1.
    pub normal: [f64; 3],
    /// The gap to the wall's plane, `g_w(u^k)`.
    pub gap: f64,
    /// The right-hand side `n_w . (u1^k - sum_k b_k u2_k^k) + g_w(u^k)`.
    pub target: f64,
}

/// A wall an active node holds beside its gap row, and the target vector of the two rows:
/// both hold the same node, so its target (`crate::contact::coupled::system::Coupling::gaps`,
/// `r . (u1 - u2(point)) = r . T` for each row `r`) is the one vector that satisfies both, `T =
/// alpha n + beta n_w` with `alpha = (t - c t_w) / (1 - c^2)`, `beta = (t_w - c t) / (1 - c^2)`
/// (`t`, `t_w` the two rows' targets, `c = n . n_w`).
#[derive(Debug, Clone)]
pub struct HeldWall {
    pub wall: Wall,
    pub target: [f64; 3],
}

impl Wall {
    /// The wall held beside the gap row `row` of its node; `None` where the two rows are
    /// nearly parallel ([`PARALLEL`]).
    pub fn held_with(&self, row: &GapRow) -> Option<HeldWall> {
        let (n, n_w) = (row.normal, self.normal);
        let c = dot(n, n_w);
        if c.abs() > PARALLEL {
            return None;
        }
        let (t, t_w) = (row.target, self.target);
        let det = 1.0 - c * c;
        let (alpha, beta) = ((t - c * t_w) / det, (t_w - c * t) / det);
        Some(HeldWall {
            wall: self.clone(),
            target: std::array::from_fn(|k| alpha * n[k] + beta * n_w[k]),
        })
    }
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| a[k] * b[k]).sum()
}

/// The walls ([`Wall`]) of each of the primary candidates `nodes` whose gap rows are `rows`
/// (indexed by candidate), at the displacements `u1`, `u2`: in 2D the facets at either end of
/// the closest one, in 3D those around its corners (each listed once), where they are walls.
/// A row measured beside the other surface's rim (its direction not the closest facet's normal)
/// has none.
pub fn walls(
    primary: &ContactSurface,
    secondary: &ContactSurface,
    [u1, u2]: [BodyDisplacement; 2],
    rows: &[GapRow],
    nodes: &[usize],
) -> HashMap<usize, Vec<Wall>> {
    let dim = secondary.dim;
    let mut facets_at: HashMap<usize, Vec<usize>> = HashMap::new();
    for f in 0..secondary.num_facets() {
        for &s in secondary.facet_nodes(f) {
            facets_at.entry(s).or_default().push(f);
        }
    }
    let position = |s: usize| secondary.deformed(u2, s);
    let displacement = |s: usize| u2.at(dim, secondary.nodes[s]);
    let corners_at = |f: usize| -> Vec<[f64; 3]> {
        (secondary.facet_nodes(f).iter())
            .map(|&s| position(s))
            .collect()
    };
    let normal = |f: usize| facet_measure_and_normal(&corners_at(f), dim).1;
    let min_cos = WALL_ANGLE.to_radians().cos();
    let mut found = HashMap::new();
    for &i in nodes {
        let row = &rows[i];
        let ends: Vec<usize> = row.corners.iter().map(|c| c.0).collect();
        let Some(&closest) = (facets_at.get(&ends[0]).into_iter().flatten())
            .find(|&&f| secondary.facet_nodes(f) == ends.as_slice())
        else {
            continue;
        };
        let m_f = normal(closest);
        if dot(m_f, row.normal) > -1.0 + 1e-12 {
            continue; // beside the rim: measured by its distance, no facet's plane
        }
        let x = primary.deformed(u1, i);
        let own = u1.at(dim, primary.nodes[i]);
        let base = position(ends[0]);
        // The facets sharing a vertex (in 3D possibly an edge: listed once) with the closest.
        let mut around: Vec<usize> = (ends.iter())
            .flat_map(|vertex| facets_at.get(vertex).into_iter().flatten().copied())
            .filter(|&g| g != closest)
            .collect();
        around.sort_unstable();
        around.dedup();
        let mut node_walls = Vec::new();
        for g in around {
            let corners = secondary.facet_nodes(g);
            // Concave: every corner of the wall off the closest facet on the node's side of
            // the closest facet's plane.
            let concave = (corners.iter())
                .filter(|s| !ends.contains(s))
                .all(|&s| dot(m_f, std::array::from_fn(|k| position(s)[k] - base[k])) > 0.0);
            let m_g = normal(g);
            if !concave || dot(m_f, m_g) > min_cos {
                continue;
            }
            let y = corners_at(g);
            let (_, barycentric) = closest_point(&y, &x);
            // x - q with q = y_0 + sum_j b_j (y_j - y_0), the closest point on the wall.
            let gap = dot(
                m_g,
                std::array::from_fn(|k| {
                    x[k] - y[0][k]
                        - (1..y.len())
                            .map(|j| barycentric[j] * (y[j][k] - y[0][k]))
                            .sum::<f64>()
                }),
            );
            let corners: Vec<(usize, f64)> = (corners.iter().copied()).zip(barycentric).collect();
            let jump: [f64; 3] = std::array::from_fn(|k| {
                own[k]
                    - (corners.iter())
                        .map(|&(s, b)| b * displacement(s)[k])
                        .sum::<f64>()
            });
            let n_w = m_g.map(|v| -v);
            node_walls.push(Wall {
                facets: [g, closest],
                corners,
                normal: n_w,
                gap,
                target: dot(n_w, jump) + gap,
            });
        }
        if !node_walls.is_empty() {
            found.insert(i, node_walls);
        }
    }
    found
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::contact::geometry::gap::{RowNormal, gap_rows};
    use crate::mesh::{mesh_geo, read_msh};

    /// The walls of the tilted square's corner node (`geo/tilted_square_2d.geo`, meshed by gmsh
    /// at 0.004) in a V-shaped groove made by hand in the block's top: the block's surface moved
    /// down by `depth (1 - |x - x_v| / w)` within `w` of its node `v` under the corner, so that it
    /// turns at `v` by `2 atan(depth / w)`, and the corner's node moved into the groove below both
    /// of its sides' planes. The node's wall is the side it is not held on, read by its plane: its
    /// normal is that side's (computed from the slope, not from the mesh), its gap the node's
    /// distance to that plane. A groove turning by less than the wall angle, and the flat block,
    /// have none.
    #[test]
    fn a_node_in_a_groove_has_the_other_side_as_its_wall() {
        let folder = tempfile::tempdir().unwrap();
        let geo = Path::new(env!("CARGO_MANIFEST_DIR")).join("geo/tilted_square_2d.geo");
        let msh = folder.path().join("tilted_square_2d.msh");
        let parameters = [("h_c".to_string(), 0.004), ("h_b".to_string(), 0.0056)];
        mesh_geo(&geo, &msh, &parameters).expect("gmsh meshes");
        let mesh = read_msh(&msh).unwrap();
        let (square_mesh, block_mesh) = (mesh.body("square").unwrap(), mesh.body("block").unwrap());
        let square = ContactSurface::new(square_mesh, "square_contact").unwrap();
        let block = ContactSurface::new(block_mesh, "block_contact").unwrap();
        let corner = (square.beside_corners(45.0).into_iter())
            .min_by(|&a, &b| square.coords[a][1].total_cmp(&square.coords[b][1]))
            .unwrap();
        let x_c = square.coords[corner];
        let v = (0..block.len())
            .min_by(|&a, &b| {
                let d = |s: usize| (block.coords[s][0] - x_c[0]).abs();
                d(a).total_cmp(&d(b))
            })
            .unwrap();
        let x_v = block.coords[v];
        let w = 0.02;
        let groove = |slope: f64| {
            let mut u2 = vec![0.0; 2 * block_mesh.num_nodes()];
            for s in 0..block.len() {
                let along = (block.coords[s][0] - x_v[0]).abs();
                u2[2 * block.nodes[s] + 1] = -slope * w * (1.0 - along / w).max(0.0);
            }
            u2
        };
        let walls_of_corner = |slope: f64| {
            let u2 = groove(slope);
            // The corner's node half a block spacing right of the vertex, below both sides' planes.
            let dx = 0.5 * block.spacing[v];
            let target = [x_v[0] + dx, x_v[1] - slope * w - slope * dx - 1e-4];
            let mut u1 = vec![0.0; 2 * square_mesh.num_nodes()];
            (0..2).for_each(|k| u1[2 * square.nodes[corner] + k] = target[k] - x_c[k]);
            let u = [BodyDisplacement::Whole(&u1), BodyDisplacement::Whole(&u2)];
            let rows = gap_rows(&square, &block, Some(u[0]), Some(u[1]), RowNormal::Facet);
            let found = walls(&square, &block, u, &rows, &[corner]);
            (
                rows[corner].clone(),
                found.get(&corner).cloned().unwrap_or_default(),
                target,
            )
        };
        let slope = 0.5; // each side 26.6 degrees, the vertex turning by 53
        let (row, found, x) = walls_of_corner(slope);
        assert_eq!(found.len(), 1, "{found:?}");
        let wall = &found[0];
        let length = (1.0 + slope * slope).sqrt();
        let up_left = [slope / length, 1.0 / length, 0.0]; // out of the block, the side x < x_v
        let up_right = [-slope / length, 1.0 / length, 0.0];
        let close = |a: [f64; 3], b: [f64; 3]| (0..3).all(|k| (a[k] + b[k]).abs() < 1e-9);
        let held_left = close(row.normal, up_left);
        assert!(held_left || close(row.normal, up_right), "{:?}", row.normal);
        let m_w = if held_left { up_right } else { up_left };
        assert!(close(wall.normal, m_w), "{:?} against {m_w:?}", wall.normal);
        let bottom = [x_v[0], x_v[1] - slope * w];
        let gap = (0..2).map(|k| m_w[k] * (x[k] - bottom[k])).sum::<f64>();
        assert!(
            gap < 0.0 && (wall.gap - gap).abs() < 1e-12,
            "{} against {gap}",
            wall.gap
        );
        // Below the wall angle, and flat: none.
        let shallow = (WALL_ANGLE / 2.0 * 0.9).to_radians().tan();
        assert!(walls_of_corner(shallow).1.is_empty());
        assert!(walls_of_corner(0.0).1.is_empty());
    }

    /// A box's node pressed into a straight V-shaped groove in a block's structured top (3D): the
    /// top meshed by gmsh as a 4 x 4 grid of squares, each cut in two triangles, so that its
    /// line x = 0 is a line of the mesh and every facet lies on one side of the groove,
    /// `z = -slope (w - |x|)` within `w` (one square) of it. The node, on the side x > 0 below
    /// both sides' planes, is held on that side's facet; its walls are the facets of the other
    /// side around that facet (every one on the plane of that side), each with that side's
    /// normal (from the slope, not the mesh) and the node's signed distance to that plane. A
    /// groove turning by less than the wall angle and the flat top have none, a ridge none on
    /// its far side.
    #[test]
    fn a_node_in_a_straight_groove_has_the_far_side_as_its_walls_in_3d() {
        let folder = tempfile::tempdir().unwrap();
        let geo = folder.path().join("box_on_block.geo");
        std::fs::write(
            &geo,
            "SetFactory(\"OpenCASCADE\");\n\
             Box(1) = {-1, -1, -1, 2, 2, 1};\n\
             Box(2) = {-0.3, -0.3, 0.1, 0.6, 0.6, 0.3};\n\
             Transfinite Curve{:} = 5;\n\
             Transfinite Surface{:};\n\
             Physical Volume(\"block\") = {1};\n\
             Physical Volume(\"box\") = {2};\n\
             Physical Surface(\"block_contact\") = {6};\n\
             Physical Surface(\"box_contact\") = {11};\n",
        )
        .unwrap();
        let msh = folder.path().join("box_on_block.msh");
        mesh_geo(&geo, &msh, &[]).expect("gmsh meshes");
        let mesh = read_msh(&msh).unwrap();
        let (box_mesh, block_mesh) = (mesh.body("box").unwrap(), mesh.body("block").unwrap());
        let pressed = ContactSurface::new(box_mesh, "box_contact").unwrap();
        let block = ContactSurface::new(block_mesh, "block_contact").unwrap();
        let w = 0.5;
        let node = 0;
        let walls_of_node = |slope: f64| {
            let mut u2 = vec![0.0; 3 * block_mesh.num_nodes()];
            for s in 0..block.len() {
                let x = block.coords[s][0];
                u2[3 * block.nodes[s] + 2] = -slope * (w - x.abs()).max(0.0);
            }
            // A tenth of a square right of the groove's bottom, 1e-3 below the far side's plane
            // (and so below the near side's).
            let target = [0.1, 0.05, -slope * (w + 0.1) - 1e-3];
            let x0 = pressed.coords[node];
            let mut u1 = vec![0.0; 3 * box_mesh.num_nodes()];
            (0..3).for_each(|k| u1[3 * pressed.nodes[node] + k] = target[k] - x0[k]);
            let u = [BodyDisplacement::Whole(&u1), BodyDisplacement::Whole(&u2)];
            let rows = gap_rows(&pressed, &block, Some(u[0]), Some(u[1]), RowNormal::Facet);
            let found = walls(&pressed, &block, u, &rows, &[node]);
            (
                rows[node].clone(),
                found.get(&node).cloned().unwrap_or_default(),
                target,
            )
        };
        let slope = 0.5; // each side 26.6 degrees, the groove turning by 53
        let (row, found, x) = walls_of_node(slope);
        let length = (1.0 + slope * slope).sqrt();
        let near = [-slope / length, 0.0, 1.0 / length]; // out of the block, the side x > 0
        let far = [slope / length, 0.0, 1.0 / length];
        let close = |a: [f64; 3], b: [f64; 3]| (0..3).all(|k| (a[k] + b[k]).abs() < 1e-9);
        assert!(close(row.normal, near), "{:?}", row.normal);
        assert!(!found.is_empty());
        let bottom = [0.0, 0.0, -slope * w];
        let gap = (0..3).map(|k| far[k] * (x[k] - bottom[k])).sum::<f64>();
        assert!(gap < 0.0);
        for wall in &found {
            assert!(close(wall.normal, far), "{:?} against {far:?}", wall.normal);
            assert!((wall.gap - gap).abs() < 1e-12, "{} against {gap}", wall.gap);
            let corners: Vec<usize> = wall.corners.iter().map(|c| c.0).collect();
            assert!(corners.iter().all(|&s| block.coords[s][0] <= 1e-12));
        }
        // Below the wall angle, a ridge, and flat: none.
        let shallow = (WALL_ANGLE / 2.0 * 0.9).to_radians().tan();
        assert!(walls_of_node(shallow).1.is_empty());
        // A ridge's far side is no wall: only the flat top at its foot, where the slope meets
        // it concavely.
        let ridge = walls_of_node(-slope).1;
        let at_foot =
            |wall: &Wall| (wall.corners.iter()).all(|c| block.coords[c.0][0] >= w - 1e-12);
        assert!(ridge.iter().all(at_foot), "{ridge:?}");
        assert!(walls_of_node(0.0).1.is_empty());
    }
}
