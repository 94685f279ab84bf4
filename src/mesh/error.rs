use std::path::PathBuf;

use thiserror::Error;

/// Why a mesh file could not be used. Every variant names the file, and the line, physical
/// group or gmsh element tag that is at fault.
#[derive(Debug, Error)]
pub enum MeshError {
    #[error("cannot read mesh file {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error(
        "{path}: MSH format version {version} is not supported; re-export it as MSH 4.1 \
         (gmsh -format msh41, or Mesh.MshFileVersion = 4.1)"
    )]
    UnsupportedVersion { path: PathBuf, version: String },
    #[error("{path}:{line}: {message}")]
    Syntax {
        path: PathBuf,
        line: usize,
        message: String,
    },
    #[error(
        "{path}: element type {element_type} in {location} is not supported: \
         internodes needs P1 meshes ({expected})"
    )]
    UnsupportedElement {
        path: PathBuf,
        element_type: String,
        location: String,
        expected: &'static str,
    },
    #[error(
        "{path}: element {element_tag} refers to node {node_tag}, which the $Nodes section does not define"
    )]
    UndefinedNode {
        path: PathBuf,
        element_tag: u64,
        node_tag: u64,
    },
    #[error(
        "{path}: no body found: a body is a named physical {expected} \
         (the file has no P1 cells in any physical group)"
    )]
    NoBodies {
        path: PathBuf,
        expected: &'static str,
    },
    #[error(
        "{path}: body '{body}', element {element_tag} is degenerate \
         (its {measure_name} is {measure:.3e}, relative size {relative:.1e})"
    )]
    DegenerateCell {
        path: PathBuf,
        body: String,
        element_tag: u64,
        measure_name: &'static str,
        measure: f64,
        relative: f64,
    },
    #[error(
        "{path}: body '{body}', element {element_tag} is inverted: its orientation is opposite \
         to that of the {majority} other cells of the body (the mesh folds over itself)"
    )]
    InvertedCell {
        path: PathBuf,
        body: String,
        element_tag: u64,
        majority: usize,
    },
    #[error(
        "{path}: the file is 2D (its bodies are physical surfaces) but its nodes do not lie in one \
         plane z = const (z from {z_min:e} to {z_max:e}: {bodies}); a 2D mesh must be drawn in \
         the xy plane, with the same z for every body"
    )]
    NotPlanar {
        path: PathBuf,
        z_min: f64,
        z_max: f64,
        bodies: String,
    },
    #[error(
        "{path}: the geometry has {volumes} volume(s) but no physical volume, so no 3D body: \
         a 3D body is a named physical volume (Physical Volume(\"name\") = {{...}} in the .geo)"
    )]
    NoPhysicalVolume { path: PathBuf, volumes: u64 },
    #[error(
        "{path}:{line}: the mesh is partitioned ($PartitionedEntities, written by gmsh -part N or \
         Mesh.NbPartitions > 0), which internodes does not read: its elements lie on partition \
         entities outside the physical groups. Save it unpartitioned: mesh again without -part \
         (Mesh.NbPartitions = 0); files split per partition (Mesh.PartitionSplitMeshFiles) are \
         partitioned too"
    )]
    Partitioned { path: PathBuf, line: usize },
    /// A mesh handed over in memory ([`super::GmshModel`]) whose parts do not fit together.
    #[error("{path}: {message}")]
    Model { path: PathBuf, message: String },
    /// Read again for the output of a distributed run (whose ranks kept only their cells), the
    /// file no longer holds what the run solved on.
    #[error(
        "{path} changed while the run was solving: body '{body}' no longer has the nodes and \
         cells the run read at its start, so its results cannot be written on it (run again)"
    )]
    Changed { path: PathBuf, body: String },
    /// A body a distributed run cannot divide: the ranks number its cells in 32 bits
    /// (`crate::mesh::RankPart::cell_indices`).
    #[error(
        "{path}: body '{body}' has {cells} cells: a distributed run numbers a body's cells in 32 \
         bits, at most 4,294,967,295 (split it into several bodies)"
    )]
    TooManyCells {
        path: PathBuf,
        body: String,
        cells: usize,
    },
    #[error("{path}: body '{body}' has no cells (its element blocks are empty)")]
    EmptyBody { path: PathBuf, body: String },
    #[error(
        "{path}: body '{body}' has {nodes} nodes: at most 4,294,967,295 nodes a body are \
         supported (split it into several bodies)"
    )]
    TooManyNodes {
        path: PathBuf,
        body: String,
        nodes: usize,
    },
}
