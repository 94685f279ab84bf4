//! A mesh handed over in memory as the gmsh API describes a model: its physical groups with
//! their entities, its nodes, and its elements in blocks of one type on one entity. The Python
//! module fills it from the gmsh module's current model (`internodes.Mesh.from_gmsh`), so that a
//! geometry built in Python needs no file. It is checked as the MSH reader checks a file, then
//! split into bodies by the same code ([`super::mesh_from_model`]).

use std::collections::HashMap;
use std::collections::hash_map::Entry;
use std::path::Path;

use rustc_hash::FxHashMap;

use super::msh41::{ElementBlock, MshContents, PhysicalName, element_type_name, nodes_per_element};
use super::{Dim, MeshError};

/// A gmsh model's mesh, as `gmsh.model.getPhysicalGroups`, `gmsh.model.mesh.getNodes` and
/// `gmsh.model.mesh.getElements` return it.
#[derive(Debug, Clone, Default)]
pub struct GmshModel {
    pub physical_groups: Vec<ModelGroup>,
    /// Volume entities of the model: a 3D geometry with no physical volume is not a 2D mesh.
    pub num_volumes: u64,
    /// gmsh node tags.
    pub node_tags: Vec<u64>,
    /// Three coordinates per node tag, flat.
    pub coords: Vec<f64>,
    pub element_blocks: Vec<ModelElements>,
}

/// One physical group: `gmsh.model.getPhysicalName` and `getEntitiesForPhysicalGroup`.
#[derive(Debug, Clone)]
pub struct ModelGroup {
    pub dim: Dim,
    pub tag: i32,
    /// Empty when the group has no name (it then goes by its tag, as in a file).
    pub name: String,
    /// Tags of the entities of dimension `dim` it holds.
    pub entities: Vec<i32>,
}

/// The elements of one type on one entity.
#[derive(Debug, Clone)]
pub struct ModelElements {
    pub entity_dim: Dim,
    pub entity_tag: i32,
    /// gmsh element type (2: 3-node triangle, 4: 4-node tetrahedron, ...).
    pub element_type: i32,
    pub element_tags: Vec<u64>,
    /// The node tags of each element in turn, flat.
    pub node_tags: Vec<u64>,
}

impl GmshModel {
    /// The model as the contents of a file, or an error naming what does not fit together
    /// (`label` names the model in it).
    pub(super) fn into_contents(self, label: &Path) -> Result<MshContents, MeshError> {
        let invalid = |message: String| MeshError::Model {
            path: label.to_owned(),
            message,
        };
        let nodes = nodes(&self.node_tags, &self.coords).map_err(invalid)?;
        let (physical_names, entity_groups) = groups(&self.physical_groups).map_err(invalid)?;
        let element_blocks = (self.element_blocks.into_iter())
            .map(element_block)
            .collect::<Result<_, _>>()
            .map_err(invalid)?;
        Ok(MshContents {
            physical_names,
            entity_groups,
            num_volumes: self.num_volumes,
            nodes,
            element_blocks,
        })
    }
}

/// gmsh node tag -> coordinates: three finite coordinates per tag, each tag once.
fn nodes(tags: &[u64], coords: &[f64]) -> Result<FxHashMap<u64, [f64; 3]>, String> {
    if coords.len() != 3 * tags.len() {
        return Err(format!(
            "{} node tags but {} coordinates: expected three per node",
            tags.len(),
            coords.len()
        ));
    }
    let mut nodes = FxHashMap::with_capacity_and_hasher(tags.len(), Default::default());
    for (&tag, xyz) in tags.iter().zip(coords.chunks_exact(3)) {
        if !xyz.iter().all(|x| x.is_finite()) {
            return Err(format!("node {tag} has a coordinate that is not finite"));
        }
        match nodes.entry(tag) {
            Entry::Occupied(_) => return Err(format!("node tag {tag} appears twice")),
            Entry::Vacant(slot) => slot.insert([xyz[0], xyz[1], xyz[2]]),
        };
    }
    Ok(nodes)
}

/// The named groups (a file's `$PhysicalNames`) and each entity's physical tags (its
/// `$Entities`).
#[allow(clippy::type_complexity)]
fn groups(
    groups: &[ModelGroup],
) -> Result<(Vec<PhysicalName>, HashMap<(Dim, i32), Vec<i32>>), String> {
    let mut entity_groups: HashMap<(Dim, i32), Vec<i32>> = HashMap::new();
    let mut physical_names = Vec::new();
    for group in groups {
        if group.dim > 3 {
            return Err(format!(
                "physical group {} has dimension {}: expected 0 to 3",
                group.tag, group.dim
            ));
        }
        for &entity in &group.entities {
            entity_groups
                .entry((group.dim, entity))
                .or_default()
                .push(group.tag);
        }
        if !group.name.is_empty() {
            physical_names.push(PhysicalName {
                dim: group.dim,
                tag: group.tag,
                name: group.name.clone(),
            });
        }
    }
    Ok((physical_names, entity_groups))
}

/// One block of elements, with as many node tags as its element type has nodes.
fn element_block(block: ModelElements) -> Result<ElementBlock, String> {
    let count = block.element_tags.len();
    let Some(per_element) = nodes_per_element(block.element_type) else {
        return Err(format!(
            "entity {} (dimension {}) has elements of type {}, which gmsh does not define up to \
             order 4",
            block.entity_tag, block.entity_dim, block.element_type
        ));
    };
    if block.node_tags.len() != per_element * count {
        return Err(format!(
            "the {count} {} elements of entity {} (dimension {}) have {} node tags in all: \
             expected {per_element} per element",
            element_type_name(block.element_type),
            block.entity_tag,
            block.entity_dim,
            block.node_tags.len(),
        ));
    }
    Ok(ElementBlock {
        entity_dim: block.entity_dim,
        entity_tag: block.entity_tag,
        element_type: block.element_type,
        nodes_per_element: per_element,
        element_tags: block.element_tags,
        node_tags: block.node_tags,
    })
}
