//! Meshes: bodies, boundary groups and point groups read from gmsh physical groups.
//!
//! A mesh file holds one or more **bodies** (named physical surfaces in 2D, physical volumes in
//! 3D) meshed with P1 simplices, and **boundary groups** (named physical curves in 2D, surfaces in
//! 3D). Each body is numbered locally, `0..num_nodes`, and keeps the map back to gmsh node tags,
//! so that bodies never share a degree of freedom even when the mesh file shares a node.
//!
//! Every boundary facet is stored with the node order that makes its right-hand normal point
//! out of the body (worked out from the adjacent cell, never from the file's facet order).

mod coords;
mod error;
mod extent;
mod generate;
mod gmsh;
mod gmsh_tags;
mod model;
mod msh41;
mod part;
mod quality;
mod summary;

pub use coords::NodeCoords;
pub use error::MeshError;
pub use extent::BodyExtent;
pub use generate::mesh_geo;
pub use gmsh::{mesh_from_model, read_msh, read_msh_bytes};
pub use gmsh_tags::GmshTags;
pub use model::{GmshModel, ModelElements, ModelGroup};
pub use part::{CellsByRank, NODE_WORDS, NodesByRank, RankPart};
pub use quality::{check_cells, signed_measure};
pub use summary::MeshSummary;

use std::collections::BTreeMap;
use std::path::PathBuf;

use serde::{Deserialize, Serialize};

/// Spatial dimension of a mesh: 2 (triangles, plane strain) or 3 (tetrahedra).
pub type Dim = usize;

/// Everything read from one mesh file.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Mesh {
    /// The file it was read from, for error messages.
    #[serde(with = "path_bytes")]
    pub path: PathBuf,
    /// 2 or 3.
    pub dim: Dim,
    /// One body per named physical group of dimension `dim`, in the file's order of tags.
    pub bodies: Vec<BodyMesh>,
    /// Every physical group of the file, including the ones no body uses.
    pub physical_groups: Vec<PhysicalGroup>,
}

/// A path as its bytes in what rank 0 sends the ranks (`crate::run`'s partition): serde's own
/// form of a path refuses one that is not UTF-8, which a folder's name may be.
mod path_bytes {
    use std::path::{Path, PathBuf};

    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(path: &Path, serializer: S) -> Result<S::Ok, S::Error> {
        #[cfg(unix)]
        let bytes = std::os::unix::ffi::OsStrExt::as_bytes(path.as_os_str()).to_vec();
        #[cfg(not(unix))]
        let bytes = path.to_string_lossy().into_owned().into_bytes();
        bytes.serialize(serializer)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(deserializer: D) -> Result<PathBuf, D::Error> {
        let bytes = Vec::<u8>::deserialize(deserializer)?;
        #[cfg(unix)]
        let path =
            PathBuf::from(<std::ffi::OsString as std::os::unix::ffi::OsStringExt>::from_vec(bytes));
        #[cfg(not(unix))]
        let path = PathBuf::from(String::from_utf8_lossy(&bytes).into_owned());
        Ok(path)
    }
}

/// A physical group as declared in the file (`$PhysicalNames`).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct PhysicalGroup {
    pub dim: Dim,
    pub tag: i32,
    /// Its name in `$PhysicalNames`, or its tag written out when it has none.
    pub name: String,
    /// Whether `$PhysicalNames` names it. An unnamed group goes by its tag, which groups of
    /// other dimensions may share.
    pub named: bool,
}

/// One body: P1 simplices, numbered locally.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct BodyMesh {
    pub name: String,
    pub physical_tag: i32,
    pub dim: Dim,
    /// Node coordinates; `z = 0` in 2D. On a rank of a distributed run, only those of the
    /// nodes it reads ([`NodeCoords`]).
    pub coords: NodeCoords,
    /// Local node index -> gmsh node tag, increasing (the nodes are numbered in tag order).
    pub node_tags: GmshTags,
    /// Cell connectivity, `dim + 1` local node indices per cell, flat. Stored as `u32`, half
    /// the bytes of the largest array of a mesh (a body of 2^32 nodes or more is refused when
    /// read); [`Self::cell`] and [`Self::cells`] give them as `usize`.
    pub cells: Vec<u32>,
    /// Local cell index -> gmsh element tag.
    pub cell_tags: GmshTags,
    /// Boundary groups that have at least one facet on this body, by name.
    pub boundary_groups: BTreeMap<String, FacetGroup>,
    /// Groups of points (gmsh physical points) on this body: sorted local nodes, by name. They
    /// can carry Dirichlet conditions, e.g. to pin a corner against rigid-body motions.
    pub point_groups: BTreeMap<String, Vec<usize>>,
    /// On a rank of a distributed run, once the body's nodes are partitioned: `cells` holds
    /// only the cells this rank assembles and `cell_tags` none, and this is what it keeps of
    /// the whole body besides ([`RankPart`]). `None`: every cell and tag is here.
    pub part: Option<RankPart>,
}

/// The local nodes of one cell (3 in 2D, 4 in 3D) as `usize`, from the `u32` the mesh stores
/// ([`BodyMesh::cells`]); it reads as a slice.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CellNodes {
    nodes: [usize; 4],
    len: usize,
}

impl CellNodes {
    /// The nodes of a stored cell (at most 4: P1 triangles and tetrahedra).
    pub fn of(stored: &[u32]) -> Self {
        debug_assert!(stored.len() <= 4, "a P1 cell has at most 4 nodes");
        let mut nodes = [0; 4];
        for (node, &n) in nodes.iter_mut().zip(stored) {
            *node = n as usize;
        }
        Self {
            nodes,
            len: stored.len(),
        }
    }
}

impl std::ops::Deref for CellNodes {
    type Target = [usize];

    fn deref(&self) -> &[usize] {
        &self.nodes[..self.len]
    }
}

/// A local node index as a mesh stores it: `u32` in the cells, `usize` in the facets and
/// groups (their arrays are small). The graph and pattern of a matrix are built from either.
pub trait NodeIndex: Copy + Send + Sync {
    fn index(self) -> usize;
}

impl NodeIndex for usize {
    fn index(self) -> usize {
        self
    }
}

impl NodeIndex for u32 {
    fn index(self) -> usize {
        self as usize
    }
}

/// Facets of one boundary group that lie on one body.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct FacetGroup {
    pub physical_tag: i32,
    /// `dim` local node indices per facet, flat, ordered so the right-hand normal points outward.
    pub facets: Vec<usize>,
    /// The body cell each facet belongs to.
    pub facet_cells: Vec<usize>,
    /// gmsh element tags of the facets that are faces of two cells of the body, in the file's
    /// order: such a group lies (in part) inside the body, where a pressure has no outward side.
    /// Empty for a boundary group.
    pub interior_facets: Vec<u64>,
}

impl BodyMesh {
    pub fn num_nodes(&self) -> usize {
        self.coords.len()
    }

    pub fn nodes_per_cell(&self) -> usize {
        self.dim + 1
    }

    pub fn num_cells(&self) -> usize {
        self.cells.len() / self.nodes_per_cell()
    }

    pub fn num_dofs(&self) -> usize {
        self.dim * self.num_nodes()
    }

    /// Local node indices of cell `c`.
    pub fn cell(&self, c: usize) -> CellNodes {
        let n = self.nodes_per_cell();
        CellNodes::of(&self.cells[n * c..n * (c + 1)])
    }

    /// The local node indices of every cell, in order.
    pub fn cells(&self) -> impl ExactSizeIterator<Item = CellNodes> + '_ {
        self.cells
            .chunks_exact(self.nodes_per_cell())
            .map(CellNodes::of)
    }

    /// The boundary group `name`, if it has facets on this body.
    pub fn boundary_group(&self, name: &str) -> Option<&FacetGroup> {
        self.boundary_groups.get(name)
    }

    /// The nodes of a boundary group or a point group, sorted.
    pub fn group_nodes(&self, name: &str) -> Option<Vec<usize>> {
        self.boundary_groups
            .get(name)
            .map(FacetGroup::nodes)
            .or_else(|| self.point_groups.get(name).cloned())
    }

    /// Names of the boundary and point groups on this body.
    pub fn group_names(&self) -> Vec<String> {
        self.boundary_groups
            .keys()
            .chain(self.point_groups.keys())
            .cloned()
            .collect()
    }

    /// Axis-aligned bounding box `(min, max)` of the nodes.
    pub fn bounding_box(&self) -> ([f64; 3], [f64; 3]) {
        let extent = self.extent();
        (extent.low, extent.high)
    }

    /// The extent of the whole body's nodes; on a rank that keeps the coordinates of some of
    /// them only, as rank 0 measured it before the partition ([`RankPart::extent`]).
    pub fn extent(&self) -> BodyExtent {
        match (&self.part, self.coords.as_whole()) {
            (Some(part), _) => part.extent.clone(),
            (None, Some(coords)) => BodyExtent::of(coords, self.dim),
            (None, None) => unreachable!("only the partition keeps some coordinates"),
        }
    }
}

impl FacetGroup {
    /// Local node indices of facet `f`, given the mesh dimension (nodes per facet).
    pub fn facet(&self, f: usize, dim: Dim) -> &[usize] {
        &self.facets[dim * f..dim * (f + 1)]
    }

    pub fn num_facets(&self, dim: Dim) -> usize {
        self.facets.len() / dim
    }

    /// Whether every facet lies on one cell of the body only (none is inside it).
    pub fn is_boundary(&self) -> bool {
        self.interior_facets.is_empty()
    }

    /// The distinct local nodes of the group, sorted.
    pub fn nodes(&self) -> Vec<usize> {
        let mut nodes = self.facets.clone();
        nodes.sort_unstable();
        nodes.dedup();
        nodes.shrink_to_fit();
        nodes
    }
}

impl Mesh {
    pub fn body(&self, name: &str) -> Option<&BodyMesh> {
        self.bodies.iter().find(|b| b.name == name)
    }

    /// The boundary and point groups (dimension below the bodies') called `name`: more than one
    /// when unnamed groups of two dimensions go by the same tag, and a case file naming it is
    /// ambiguous.
    pub fn groups_below_bodies(&self, name: &str) -> Vec<&PhysicalGroup> {
        self.physical_groups
            .iter()
            .filter(|g| g.dim < self.dim && g.name == name)
            .collect()
    }

    /// The physical group called `name`, if the file declares one.
    pub fn physical_group(&self, name: &str) -> Option<&PhysicalGroup> {
        self.physical_groups.iter().find(|g| g.name == name)
    }
}
