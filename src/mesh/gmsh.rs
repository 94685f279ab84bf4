//! Reader for gmsh MSH 4.1 files (ASCII and binary) through the `mshio` crate.
//!
//! `mshio` parses `$Entities`, `$Nodes` and `$Elements` but ignores `$PhysicalNames`, which is
//! ASCII even in binary files, so that section is parsed here.

use std::collections::{BTreeMap, HashMap};
use std::fs;
use std::path::Path;

use mshio::{ElementType, MshFile};

use super::{BodyMesh, Dim, FacetGroup, Mesh, MeshError, PhysicalGroup, check_cells};

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
    check_format_version(path, &bytes)?;
    let physical_names = parse_physical_names(path, &bytes)?;
    let msh = mshio::parse_msh_bytes(&bytes).map_err(|e| syntax_error(path, &bytes, &e))?;
    let file = FileContents::new(path, &msh)?;

    let dim = file.dim;
    let name_of = |d: Dim, tag: i32| -> String {
        physical_names
            .get(&(d, tag))
            .cloned()
            .unwrap_or_else(|| tag.to_string())
    };
    let mut physical_groups: Vec<PhysicalGroup> = file
        .groups
        .keys()
        .map(|&(d, tag)| PhysicalGroup {
            dim: d,
            tag,
            name: name_of(d, tag),
        })
        .collect();
    for (&(d, tag), name) in &physical_names {
        if !file.groups.contains_key(&(d, tag)) {
            physical_groups.push(PhysicalGroup {
                dim: d,
                tag,
                name: name.clone(),
            });
        }
    }

    let mut bodies = Vec::new();
    for (&(d, tag), elements) in &file.groups {
        if d != dim {
            continue;
        }
        let mut body = file.body(name_of(d, tag), tag, elements)?;
        for (&(fd, ftag), facets) in &file.groups {
            if fd + 1 == dim {
                let group = file.facet_group(&body, ftag, facets);
                if !group.facets.is_empty() {
                    body.boundary_groups.insert(name_of(fd, ftag), group);
                }
            } else if fd == 0 {
                let nodes = file.point_group(&body, facets);
                if !nodes.is_empty() {
                    body.point_groups.insert(name_of(fd, ftag), nodes);
                }
            }
        }
        check_cells(path, &body)?;
        bodies.push(body);
    }
    if bodies.is_empty() {
        return Err(MeshError::NoBodies {
            path: path.to_owned(),
            expected: "surface (2D) or volume (3D) of triangles / tetrahedra",
        });
    }
    Ok(Mesh {
        path: path.to_owned(),
        dim,
        bodies,
        physical_groups,
    })
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
    coords: HashMap<u64, [f64; 3]>,
    /// (dimension, physical tag) -> its elements, for P1 cells and facets only.
    groups: BTreeMap<(Dim, i32), GroupElements>,
}

impl FileContents {
    fn new(path: &Path, msh: &MshFile<u64, i32, f64>) -> Result<Self, MeshError> {
        let mut coords = HashMap::new();
        if let Some(nodes) = &msh.data.nodes {
            // With contiguous tags mshio drops the per-block maps: tags then run from
            // `min_node_tag` through the blocks in file order.
            let mut next_implicit_tag = nodes.min_node_tag;
            for block in &nodes.node_blocks {
                let mut tags: Vec<(u64, usize)> = match &block.node_tags {
                    Some(map) => map.iter().map(|(&t, &i)| (t, i)).collect(),
                    None => (0..block.nodes.len())
                        .map(|i| (next_implicit_tag + i as u64, i))
                        .collect(),
                };
                tags.sort_unstable();
                next_implicit_tag += block.nodes.len() as u64;
                for (tag, i) in tags {
                    let n = &block.nodes[i];
                    coords.insert(tag, [n.x, n.y, n.z]);
                }
            }
        }

        let physical_tags = entity_physical_tags(msh);
        let blocks = msh
            .data
            .elements
            .as_ref()
            .map(|e| e.element_blocks.as_slice())
            .unwrap_or_default();
        let in_group = |d: i32, tag: i32| {
            physical_tags
                .get(&(d as Dim, tag))
                .is_some_and(|t| !t.is_empty())
        };
        let dim = blocks
            .iter()
            .filter(|b| in_group(b.entity_dim, b.entity_tag))
            .map(|b| b.entity_dim as Dim)
            .max()
            .unwrap_or(0);
        if dim < 2 {
            return Err(MeshError::NoBodies {
                path: path.to_owned(),
                expected: "surface (2D) or volume (3D)",
            });
        }

        let mut groups: BTreeMap<(Dim, i32), GroupElements> = BTreeMap::new();
        for block in blocks {
            let d = block.entity_dim as Dim;
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
                ElementType::Pnt
            } else {
                facet_type(dim)
            };
            if block.element_type != expected_type {
                return Err(MeshError::UnsupportedElement {
                    path: path.to_owned(),
                    element_type: format!("{:?}", block.element_type),
                    location: format!(
                        "entity {} of dimension {} (physical group {:?})",
                        block.entity_tag, d, tags
                    ),
                    expected: if dim == 2 {
                        "3-node triangles with 2-node boundary lines"
                    } else {
                        "4-node tetrahedra with 3-node boundary triangles"
                    },
                });
            }
            for &tag in tags {
                let group = groups.entry((d, tag)).or_default();
                for element in &block.elements {
                    for node in &element.nodes {
                        if !coords.contains_key(node) {
                            return Err(MeshError::UndefinedNode {
                                path: path.to_owned(),
                                element_tag: element.element_tag,
                                node_tag: *node,
                            });
                        }
                    }
                    group.element_tags.push(element.element_tag);
                    group.node_tags.extend_from_slice(&element.nodes);
                }
            }
        }
        Ok(FileContents {
            dim,
            coords,
            groups,
        })
    }

    /// Builds a body from the cells of one physical group; nodes are numbered locally in
    /// increasing gmsh tag order.
    fn body(&self, name: String, tag: i32, cells: &GroupElements) -> Result<BodyMesh, MeshError> {
        let mut node_tags = cells.node_tags.clone();
        node_tags.sort_unstable();
        node_tags.dedup();
        let local: HashMap<u64, usize> =
            node_tags.iter().enumerate().map(|(i, &t)| (t, i)).collect();
        let coords = node_tags.iter().map(|t| self.coords[t]).collect();
        Ok(BodyMesh {
            name,
            physical_tag: tag,
            dim: self.dim,
            coords,
            cells: cells.node_tags.iter().map(|t| local[t]).collect(),
            cell_tags: cells.element_tags.clone(),
            node_tags,
            boundary_groups: BTreeMap::new(),
            point_groups: BTreeMap::new(),
        })
    }

    /// The local nodes of `body` in a group of points, sorted.
    fn point_group(&self, body: &BodyMesh, points: &GroupElements) -> Vec<usize> {
        let mut nodes: Vec<usize> = points
            .node_tags
            .iter()
            .filter_map(|tag| body.node_tags.binary_search(tag).ok())
            .collect();
        nodes.sort_unstable();
        nodes.dedup();
        nodes
    }

    /// The facets of a boundary group that are faces of `body`'s cells, oriented outward.
    fn facet_group(&self, body: &BodyMesh, tag: i32, facets: &GroupElements) -> FacetGroup {
        let dim = self.dim;
        let local: HashMap<u64, usize> = body
            .node_tags
            .iter()
            .enumerate()
            .map(|(i, &t)| (t, i))
            .collect();
        // Facets of the group that lie on the body, keyed by their sorted local nodes.
        let mut wanted: HashMap<Vec<usize>, usize> = HashMap::new();
        for (f, facet) in facets.node_tags.chunks_exact(dim).enumerate() {
            let nodes: Option<Vec<usize>> = facet.iter().map(|t| local.get(t).copied()).collect();
            if let Some(mut nodes) = nodes {
                nodes.sort_unstable();
                wanted.insert(nodes, f);
            }
        }
        let mut found: Vec<(usize, Vec<usize>, usize)> = Vec::new();
        if !wanted.is_empty() {
            for c in 0..body.num_cells() {
                let cell = body.cell(c);
                for opposite in 0..cell.len() {
                    let mut face: Vec<usize> = (0..cell.len())
                        .filter(|&k| k != opposite)
                        .map(|k| cell[k])
                        .collect();
                    let mut key = face.clone();
                    key.sort_unstable();
                    if let Some(f) = wanted.remove(&key) {
                        orient_outward(&body.coords, &mut face, cell[opposite], dim);
                        found.push((f, face, c));
                    }
                }
            }
        }
        // Keep the file's facet order so that results are reproducible.
        found.sort_unstable_by_key(|(f, _, _)| *f);
        FacetGroup {
            physical_tag: tag,
            facets: found.iter().flat_map(|(_, face, _)| face.clone()).collect(),
            facet_cells: found.iter().map(|(_, _, c)| *c).collect(),
        }
    }
}

fn cell_type(dim: Dim) -> ElementType {
    if dim == 2 {
        ElementType::Tri3
    } else {
        ElementType::Tet4
    }
}

fn facet_type(dim: Dim) -> ElementType {
    if dim == 2 {
        ElementType::Lin2
    } else {
        ElementType::Tri3
    }
}

/// Reorders `face` so that its right-hand normal points away from the cell's `opposite` node.
fn orient_outward(coords: &[[f64; 3]], face: &mut [usize], opposite: usize, dim: Dim) {
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

/// (entity dimension, entity tag) -> physical tags, from the `$Entities` section.
fn entity_physical_tags(msh: &MshFile<u64, i32, f64>) -> HashMap<(Dim, i32), Vec<i32>> {
    let mut map = HashMap::new();
    if let Some(e) = &msh.data.entities {
        for p in &e.points {
            map.insert((0, p.tag), p.physical_tags.clone());
        }
        for c in &e.curves {
            map.insert((1, c.tag), c.physical_tags.clone());
        }
        for s in &e.surfaces {
            map.insert((2, s.tag), s.physical_tags.clone());
        }
        for v in &e.volumes {
            map.insert((3, v.tag), v.physical_tags.clone());
        }
    }
    map
}

/// Rejects anything but MSH 4.1 with a message that says how to fix it (mshio would only say
/// "invalid header").
fn check_format_version(path: &Path, bytes: &[u8]) -> Result<(), MeshError> {
    let head = String::from_utf8_lossy(&bytes[..bytes.len().min(256)]);
    let mut lines = head.lines();
    if lines.next().map(str::trim) != Some("$MeshFormat") {
        return Err(MeshError::Syntax {
            path: path.to_owned(),
            line: 1,
            message: "expected '$MeshFormat': this is not a gmsh MSH file".into(),
        });
    }
    let version = lines
        .next()
        .and_then(|l| l.split_whitespace().next())
        .unwrap_or("")
        .to_string();
    if version != "4.1" {
        return Err(MeshError::UnsupportedVersion {
            path: path.to_owned(),
            version,
        });
    }
    Ok(())
}

/// Parses `$PhysicalNames`: a count, then one `dim tag "name"` line per group.
fn parse_physical_names(
    path: &Path,
    bytes: &[u8],
) -> Result<BTreeMap<(Dim, i32), String>, MeshError> {
    let mut names = BTreeMap::new();
    let Some(start) = find(bytes, b"$PhysicalNames") else {
        return Ok(names);
    };
    let first_line = 1 + bytes[..start].iter().filter(|&&b| b == b'\n').count();
    let syntax = |offset: usize, message: String| MeshError::Syntax {
        path: path.to_owned(),
        line: first_line + offset,
        message,
    };
    let section = &bytes[start..];
    let end = find(section, b"$EndPhysicalNames").ok_or_else(|| {
        syntax(
            0,
            "$PhysicalNames is not closed by $EndPhysicalNames".into(),
        )
    })?;
    let text = String::from_utf8_lossy(&section[..end]);
    let lines: Vec<&str> = text.lines().collect();
    let count: usize = lines
        .get(1)
        .and_then(|l| l.trim().parse().ok())
        .ok_or_else(|| syntax(1, "expected the number of physical names".into()))?;
    if lines.len() < count + 2 {
        return Err(syntax(
            lines.len(),
            format!(
                "$PhysicalNames announces {count} names but lists {}",
                lines.len().saturating_sub(2)
            ),
        ));
    }
    for (k, line) in lines[2..2 + count].iter().enumerate() {
        let bad = || {
            syntax(
                k + 2,
                format!("expected 'dim tag \"name\"' in $PhysicalNames, found '{line}'"),
            )
        };
        let mut parts = line.splitn(3, char::is_whitespace);
        let d: Dim = parts.next().and_then(|s| s.parse().ok()).ok_or_else(bad)?;
        let tag: i32 = parts.next().and_then(|s| s.parse().ok()).ok_or_else(bad)?;
        let name = parts.next().map(str::trim).ok_or_else(bad)?;
        let name = name
            .strip_prefix('"')
            .and_then(|s| s.strip_suffix('"'))
            .ok_or_else(bad)?;
        names.insert((d, tag), name.to_string());
    }
    Ok(names)
}

fn find(haystack: &[u8], needle: &[u8]) -> Option<usize> {
    haystack.windows(needle.len()).position(|w| w == needle)
}

/// Turns a parser error into one message with the line where parsing failed.
fn syntax_error(path: &Path, bytes: &[u8], error: &mshio::MshParserError<&[u8]>) -> MeshError {
    let line = error
        .backtrace
        .first()
        .map(|(rest, _)| {
            let offset = bytes.len().saturating_sub(rest.len());
            1 + bytes[..offset].iter().filter(|&&b| b == b'\n').count()
        })
        .unwrap_or(1);
    let mut context: Vec<String> = error
        .filter_msh_errors()
        .map(|(_, kind)| kind.to_string())
        .collect();
    context.reverse();
    let mut message = if context.is_empty() {
        "the file ends early or is malformed".to_string()
    } else {
        context.join(": ")
    };
    if error
        .backtrace
        .first()
        .is_some_and(|(rest, _)| rest.is_empty())
    {
        message.push_str(" (the file ends early: truncated?)");
    }
    MeshError::Syntax {
        path: path.to_owned(),
        line,
        message,
    }
}
