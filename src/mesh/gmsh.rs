//! Splitting a gmsh MSH 4.1 file (parsed by [`super::msh41`]) into bodies, boundary groups and
//! point groups.

use std::collections::BTreeMap;
use std::fs;
use std::path::Path;

use rustc_hash::FxHashMap;

use super::msh41::{self, ElementBlock, MshContents, element_type_name};
use super::{
    BodyMesh, Dim, FacetGroup, GmshModel, Mesh, MeshError, NodeCoords, PhysicalGroup, check_cells,
};

/// gmsh element types: 1 the 2-node line, 2 the 3-node triangle, 4 the 4-node tetrahedron, 15
/// the point.
const LIN2: i32 = 1;
const TRI3: i32 = 2;
const TET4: i32 = 4;
const PNT: i32 = 15;

/// A 2D mesh must lie in a plane z = const: its z is dropped, so any spread of z beyond this
/// fraction of the mesh size would be solved as a projection the user did not mesh.
const PLANAR_RELATIVE_TOLERANCE: f64 = 1e-9;

/// Reads a gmsh MSH 4.1 file and splits it into bodies and boundary groups.
///
/// Bodies are the physical groups of the highest element dimension (surfaces in 2D, volumes in
/// 3D); boundary groups are the physical groups one dimension lower. Every cell is checked: a
/// degenerate or inverted cell is an error naming its gmsh element tag.
pub fn read_msh(path: &Path) -> Result<Mesh, MeshError> {
    let bytes = fs::read(path).map_err(|source| MeshError::Io {
        path: path.to_owned(),
        source,
    })?;
    read_msh_bytes(path, &bytes)
}

/// [`read_msh`] on the bytes of a file already read; `path` names it in the mesh and in errors.
/// Any bytes give a mesh or an error, never a panic (the fuzz target in `fuzz/` checks this).
pub fn read_msh_bytes(path: &Path, bytes: &[u8]) -> Result<Mesh, MeshError> {
    split(path, msh41::parse(path, bytes)?)
}

/// A mesh handed over in memory (see [`GmshModel`]), checked and split into bodies as a file
/// is; `label` names it in the mesh and in errors.
pub fn mesh_from_model(label: &Path, model: GmshModel) -> Result<Mesh, MeshError> {
    split(label, model.into_contents(label)?)
}

/// Splits the contents of a file (or model) into bodies, boundary groups and point groups.
fn split(path: &Path, msh: MshContents) -> Result<Mesh, MeshError> {
    let physical_names: BTreeMap<(Dim, i32), String> = msh
        .physical_names
        .iter()
        .map(|n| ((n.dim, n.tag), n.name.clone()))
        .collect();
    let file = FileContents::new(path, msh, &physical_names)?;
    let dim = file.dim;
    let physical_groups = file.physical_groups(&physical_names);
    let bodies = file.bodies(path, &physical_names)?;
    // A 2D mesh off the xy plane has cells that look degenerate in xy: say why first.
    if dim == 2 {
        check_planar(path, &bodies)?;
    }
    for body in &bodies {
        check_cells(path, body)?;
    }
    Ok(Mesh {
        path: path.to_owned(),
        dim,
        bodies,
        physical_groups,
    })
}

/// The name of a physical group: its `$PhysicalNames` entry, or else its tag.
fn group_name(names: &BTreeMap<(Dim, i32), String>, d: Dim, tag: i32) -> String {
    names
        .get(&(d, tag))
        .cloned()
        .unwrap_or_else(|| tag.to_string())
}

/// The raw elements of one physical group: gmsh element tags and node tags.
#[derive(Default)]
struct GroupElements {
    element_tags: Vec<u64>,
    node_tags: Vec<u64>,
}

/// Nodes and grouped elements of a parsed file, before splitting into bodies.
struct FileContents {
    dim: Dim,
    /// gmsh node tag -> coordinates.
    coords: FxHashMap<u64, [f64; 3]>,
    /// (dimension, physical tag) -> its elements, for P1 cells and facets only.
    groups: BTreeMap<(Dim, i32), GroupElements>,
}

impl FileContents {
    /// `names` are the `$PhysicalNames`, to name the groups of unsupported elements.
    fn new(
        path: &Path,
        msh: MshContents,
        names: &BTreeMap<(Dim, i32), String>,
    ) -> Result<Self, MeshError> {
        let physical_tags = &msh.entity_groups;
        let dim = mesh_dim(path, &msh)?;
        let mut groups: BTreeMap<(Dim, i32), GroupElements> = BTreeMap::new();
        for block in &msh.element_blocks {
            let d = block.entity_dim;
            let Some(tags) = physical_tags.get(&(d, block.entity_tag)) else {
                continue;
            };
            // Cells, facets and points (node groups for Dirichlet conditions); edges of a 3D
            // mesh are not used.
            if tags.is_empty() || (d + 1 < dim && d != 0) {
                continue;
            }
            let expected_type = if d == dim {
                cell_type(dim)
            } else if d == 0 {
                PNT
            } else {
                facet_type(dim)
            };
            if block.element_type != expected_type {
                return Err(unsupported_element(path, block, tags, names, dim));
            }
            check_nodes_defined(path, block, &msh.nodes)?;
            for &tag in tags {
                let group = groups.entry((d, tag)).or_default();
                group.element_tags.extend_from_slice(&block.element_tags);
                group.node_tags.extend_from_slice(&block.node_tags);
            }
        }
        Ok(FileContents {
            dim,
            coords: msh.nodes,
            groups,
        })
    }

    /// Every physical group of the file: those with elements, then those only named in
    /// `$PhysicalNames`.
    fn physical_groups(&self, names: &BTreeMap<(Dim, i32), String>) -> Vec<PhysicalGroup> {
        let mut physical_groups: Vec<PhysicalGroup> = self
            .groups
            .keys()
            .map(|&(d, tag)| PhysicalGroup {
                dim: d,
                tag,
                name: group_name(names, d, tag),
                named: names.contains_key(&(d, tag)),
            })
            .collect();
        for (&(d, tag), name) in names {
            if !self.groups.contains_key(&(d, tag)) {
                physical_groups.push(PhysicalGroup {
                    dim: d,
                    tag,
                    name: name.clone(),
                    named: true,
                });
            }
        }
        physical_groups
    }

    /// The bodies (physical groups of the mesh's dimension), each with its boundary and point
    /// groups.
    fn bodies(
        &self,
        path: &Path,
        names: &BTreeMap<(Dim, i32), String>,
    ) -> Result<Vec<BodyMesh>, MeshError> {
        let dim = self.dim;
        let mut bodies = Vec::new();
        for (&(d, tag), elements) in &self.groups {
            if d != dim {
                continue;
            }
            let mut body = self.body(path, group_name(names, d, tag), tag, elements)?;
            if body.cells.is_empty() {
                return Err(MeshError::EmptyBody {
                    path: path.to_owned(),
                    body: body.name,
                });
            }
            self.add_groups(&mut body, names);
            bodies.push(body);
        }
        if bodies.is_empty() {
            return Err(MeshError::NoBodies {
                path: path.to_owned(),
                expected: "surface (2D) or volume (3D) of triangles / tetrahedra",
            });
        }
        Ok(bodies)
    }

    /// Adds to `body` the boundary and point groups with facets or nodes on it.
    fn add_groups(&self, body: &mut BodyMesh, names: &BTreeMap<(Dim, i32), String>) {
        let facet_groups: Vec<(&(Dim, i32), &GroupElements)> = (self.groups.iter())
            .filter(|((fd, _), _)| fd + 1 == self.dim)
            .collect();
        let facets = self.facet_groups(body, facet_groups.iter().map(|(key, g)| (key.1, *g)));
        for (&(fd, ftag), group) in facet_groups.iter().map(|(key, _)| *key).zip(facets) {
            if !group.facets.is_empty() {
                body.boundary_groups
                    .insert(group_name(names, fd, ftag), group);
            }
        }
        for (&(fd, ftag), points) in &self.groups {
            if fd == 0 {
                let nodes = self.point_group(body, points);
                if !nodes.is_empty() {
                    body.point_groups.insert(group_name(names, fd, ftag), nodes);
                }
            }
        }
    }

    /// Builds a body from the cells of one physical group; nodes are numbered locally in
    /// increasing gmsh tag order.
    fn body(
        &self,
        path: &Path,
        name: String,
        tag: i32,
        cells: &GroupElements,
    ) -> Result<BodyMesh, MeshError> {
        let mut node_tags = cells.node_tags.clone();
        node_tags.sort_unstable();
        node_tags.dedup();
        // The copy had room for every cell's nodes (four times a tetrahedral mesh's nodes):
        // without this the body would keep that room to the end of the run (65 MB at 1M DOFs).
        node_tags.shrink_to_fit();
        if u32::try_from(node_tags.len()).is_err() {
            return Err(MeshError::TooManyNodes {
                path: path.to_owned(),
                body: name,
                nodes: node_tags.len(),
            });
        }
        let local: FxHashMap<u64, u32> = (node_tags.iter().enumerate())
            .map(|(i, &t)| (t, i as u32))
            .collect();
        let coords = NodeCoords::from(node_tags.iter().map(|t| self.coords[t]).collect::<Vec<_>>());
        Ok(BodyMesh {
            name,
            physical_tag: tag,
            dim: self.dim,
            coords,
            cells: cells.node_tags.iter().map(|t| local[t]).collect(),
            cell_tags: cells.element_tags.clone().into(),
            node_tags: node_tags.into(),
            boundary_groups: BTreeMap::new(),
            point_groups: BTreeMap::new(),
            part: None,
        })
    }

    /// The local nodes of `body` in a group of points, sorted.
    fn point_group(&self, body: &BodyMesh, points: &GroupElements) -> Vec<usize> {
        let mut nodes: Vec<usize> = points
            .node_tags
            .iter()
            .filter_map(|&tag| body.node_tags.position(tag))
            .collect();
        nodes.sort_unstable();
        nodes.dedup();
        nodes
    }

    /// The facets of each boundary group (`(physical tag, elements)`) that are faces of
    /// `body`'s cells, oriented outward, in the groups' order.
    ///
    /// One pass over the cells for all the groups, each face looked up by its sorted nodes:
    /// a pass per group, with a key allocated per face, took a third of reading a mesh.
    fn facet_groups<'a>(
        &self,
        body: &BodyMesh,
        groups: impl Iterator<Item = (i32, &'a GroupElements)>,
    ) -> Vec<FacetGroup> {
        let dim = self.dim;
        let groups: Vec<(i32, &GroupElements)> = groups.collect();
        // A facet's sorted local nodes, padded: the key of a face (dim nodes).
        let key_of = |nodes: &[usize]| {
            let mut key = [usize::MAX; 3];
            key[..nodes.len()].copy_from_slice(nodes);
            key[..nodes.len()].sort_unstable();
            key
        };
        // The facets of every group that lie on the body, keyed by their sorted local nodes:
        // (group, facet) pairs, a facet repeated in a group standing for its last copy.
        let mut wanted: FxHashMap<[usize; 3], Vec<(usize, usize)>> = FxHashMap::default();
        for (g, (_, facets)) in groups.iter().enumerate() {
            for (f, facet) in facets.node_tags.chunks_exact(dim).enumerate() {
                let nodes: Option<Vec<usize>> =
                    facet.iter().map(|&t| body.node_tags.position(t)).collect();
                let Some(nodes) = nodes else {
                    continue;
                };
                let entries = wanted.entry(key_of(&nodes)).or_default();
                match entries.iter_mut().find(|(other, _)| *other == g) {
                    Some(entry) => entry.1 = f,
                    None => entries.push((g, f)),
                }
            }
        }
        // Per group: (facet, its nodes oriented outward, its cell).
        let mut found: Vec<Vec<(usize, [usize; 3], usize)>> = vec![Vec::new(); groups.len()];
        // A facet that is a face of a second cell lies inside the body (gmsh `Line In Surface`,
        // `Surface In Volume`, or the interface of two volumes in one body): it keeps its first
        // cell, and its element tag is recorded so that a pressure on it can be refused.
        let mut taken: Vec<Vec<bool>> = (groups.iter())
            .map(|(_, facets)| vec![false; facets.element_tags.len()])
            .collect();
        let mut interior: Vec<Vec<(usize, u64)>> = vec![Vec::new(); groups.len()];
        if !wanted.is_empty() {
            for c in 0..body.num_cells() {
                let cell = body.cell(c);
                for opposite in 0..cell.len() {
                    let mut face = [usize::MAX; 3];
                    let others = (0..cell.len()).filter(|&k| k != opposite);
                    for (slot, k) in face.iter_mut().zip(others) {
                        *slot = cell[k];
                    }
                    let Some(entries) = wanted.get(&key_of(&face[..dim])) else {
                        continue;
                    };
                    for &(g, f) in entries {
                        if std::mem::replace(&mut taken[g][f], true) {
                            interior[g].push((f, groups[g].1.element_tags[f]));
                        } else {
                            let mut oriented = face;
                            orient_outward(&body.coords, &mut oriented[..dim], cell[opposite], dim);
                            found[g].push((f, oriented, c));
                        }
                    }
                }
            }
        }
        (groups.iter().zip(found).zip(interior))
            .map(|(((tag, _), mut found), mut interior)| {
                // Keep the file's facet order so that results are reproducible.
                found.sort_unstable_by_key(|(f, _, _)| *f);
                interior.sort_unstable();
                FacetGroup {
                    physical_tag: *tag,
                    facets: found
                        .iter()
                        .flat_map(|(_, face, _)| &face[..dim])
                        .copied()
                        .collect(),
                    facet_cells: found.iter().map(|(_, _, c)| *c).collect(),
                    interior_facets: interior.into_iter().map(|(_, tag)| tag).collect(),
                }
            })
            .collect()
    }
}

/// The mesh's dimension, the highest of the elements in physical groups: 2 or 3.
fn mesh_dim(path: &Path, msh: &MshContents) -> Result<Dim, MeshError> {
    let physical_tags = &msh.entity_groups;
    let in_group = |d: Dim, tag: i32| physical_tags.get(&(d, tag)).is_some_and(|t| !t.is_empty());
    let dim = msh
        .element_blocks
        .iter()
        .filter(|b| in_group(b.entity_dim, b.entity_tag))
        .map(|b| b.entity_dim)
        .max()
        .unwrap_or(0);
    if dim < 2 {
        return Err(MeshError::NoBodies {
            path: path.to_owned(),
            expected: "surface (2D) or volume (3D)",
        });
    }
    // gmsh saves only the elements of physical groups: a 3D geometry with physical surfaces
    // but no physical volume gives a file of surface triangles, which is not a 2D body.
    if dim == 2 && msh.num_volumes > 0 {
        return Err(MeshError::NoPhysicalVolume {
            path: path.to_owned(),
            volumes: msh.num_volumes,
        });
    }
    Ok(dim)
}

/// The error for a block whose element type is not the P1 cell, facet or point its dimension
/// calls for, naming the block's entity and physical groups (`tags`).
fn unsupported_element(
    path: &Path,
    block: &ElementBlock,
    tags: &[i32],
    names: &BTreeMap<(Dim, i32), String>,
    dim: Dim,
) -> MeshError {
    let d = block.entity_dim;
    MeshError::UnsupportedElement {
        path: path.to_owned(),
        element_type: element_type_name(block.element_type),
        location: format!(
            "entity {} of dimension {} (physical group {})",
            block.entity_tag,
            d,
            tags.iter()
                .map(|&t| names
                    .get(&(d, t))
                    .map_or_else(|| format!("{t} (unnamed)"), |n| format!("'{n}'")))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        expected: if dim == 2 {
            "3-node triangles with 2-node boundary lines"
        } else {
            "4-node tetrahedra with 3-node boundary triangles"
        },
    }
}

/// Checks that every node of the block's elements is in `$Nodes`.
fn check_nodes_defined(
    path: &Path,
    block: &ElementBlock,
    nodes: &FxHashMap<u64, [f64; 3]>,
) -> Result<(), MeshError> {
    let elements = block
        .element_tags
        .iter()
        .zip(block.node_tags.chunks_exact(block.nodes_per_element));
    for (&element_tag, element_nodes) in elements {
        if let Some(&node_tag) = element_nodes.iter().find(|t| !nodes.contains_key(t)) {
            return Err(MeshError::UndefinedNode {
                path: path.to_owned(),
                element_tag,
                node_tag,
            });
        }
    }
    Ok(())
}

fn cell_type(dim: Dim) -> i32 {
    if dim == 2 { TRI3 } else { TET4 }
}

fn facet_type(dim: Dim) -> i32 {
    if dim == 2 { LIN2 } else { TRI3 }
}

/// Rejects a 2D mesh whose nodes do not share one z: the solver works on x and y only, while
/// the contact search measures 3D distances, so such a mesh would be solved as a projection.
fn check_planar(path: &Path, bodies: &[BodyMesh]) -> Result<(), MeshError> {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for body in bodies {
        let (l, h) = body.bounding_box();
        for k in 0..3 {
            lo[k] = lo[k].min(l[k]);
            hi[k] = hi[k].max(h[k]);
        }
    }
    let size = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(hi[2] - lo[2]);
    if hi[2] - lo[2] > PLANAR_RELATIVE_TOLERANCE * size {
        let body_z = bodies
            .iter()
            .map(|b| {
                let (l, h) = b.bounding_box();
                format!("'{}' z in [{:e}, {:e}]", b.name, l[2], h[2])
            })
            .collect::<Vec<_>>()
            .join(", ");
        return Err(MeshError::NotPlanar {
            path: path.to_owned(),
            z_min: lo[2],
            z_max: hi[2],
            bodies: body_z,
        });
    }
    Ok(())
}

/// Reorders `face` so that its right-hand normal points away from the cell's `opposite` node.
fn orient_outward<C>(coords: &C, face: &mut [usize], opposite: usize, dim: Dim)
where
    C: std::ops::Index<usize, Output = [f64; 3]> + ?Sized,
{
    let p = |i: usize| nalgebra::Vector3::from(coords[i]);
    let normal = if dim == 2 {
        let t = p(face[1]) - p(face[0]);
        nalgebra::Vector3::new(t.y, -t.x, 0.0)
    } else {
        (p(face[1]) - p(face[0])).cross(&(p(face[2]) - p(face[0])))
    };
    if normal.dot(&(p(opposite) - p(face[0]))) > 0.0 {
        face.swap(0, 1);
    }
}
