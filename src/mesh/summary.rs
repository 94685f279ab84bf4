//! What `internodes info MESH` prints: groups, element counts and bounding boxes.

use std::fmt;

use super::Mesh;

/// A printable overview of a mesh file.
pub struct MeshSummary<'a>(pub &'a Mesh);

impl fmt::Display for MeshSummary<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mesh = self.0;
        let (cell, facet) = if mesh.dim == 2 {
            ("triangles", "segments")
        } else {
            ("tetrahedra", "triangles")
        };
        writeln!(f, "{} ({}D, P1)", mesh.path.display(), mesh.dim)?;
        writeln!(f, "physical groups:")?;
        for g in &mesh.physical_groups {
            write!(f, "  dim {}  tag {:>4}  {}", g.dim, g.tag, g.name)?;
            if !g.named {
                write!(f, "  (no name: goes by its tag)")?;
            }
            // Which group a case file means by this name cannot be told: say so here.
            if g.dim < mesh.dim {
                let others: Vec<String> = mesh
                    .groups_below_bodies(&g.name)
                    .iter()
                    .filter(|o| (o.dim, o.tag) != (g.dim, g.tag))
                    .map(|o| format!("dim {} tag {}", o.dim, o.tag))
                    .collect();
                if !others.is_empty() {
                    write!(
                        f,
                        "  (ambiguous in a case file: also {})",
                        others.join(", ")
                    )?;
                }
            }
            writeln!(f)?;
        }
        for body in &mesh.bodies {
            let (lo, hi) = body.bounding_box();
            let d = mesh.dim;
            writeln!(
                f,
                "body '{}': {} nodes, {} {}, {} dofs",
                body.name,
                body.num_nodes(),
                body.num_cells(),
                cell,
                body.num_dofs()
            )?;
            writeln!(
                f,
                "  bounding box [{}] .. [{}]",
                fmt_point(&lo[..d]),
                fmt_point(&hi[..d])
            )?;
            for (name, nodes) in &body.point_groups {
                writeln!(f, "  points '{}': {} nodes", name, nodes.len())?;
            }
            for (name, group) in &body.boundary_groups {
                write!(
                    f,
                    "  boundary '{}': {} {}, {} nodes",
                    name,
                    group.num_facets(d),
                    facet,
                    group.nodes().len()
                )?;
                if group.is_boundary() {
                    writeln!(f)?;
                } else {
                    // A pressure on it is refused: say so where the groups are listed.
                    writeln!(
                        f,
                        " ({} of them inside the body, between two cells)",
                        group.interior_facets.len()
                    )?;
                }
            }
        }
        Ok(())
    }
}

fn fmt_point(p: &[f64]) -> String {
    p.iter()
        .map(|x| format!("{x:.6}"))
        .collect::<Vec<_>>()
        .join(", ")
}
