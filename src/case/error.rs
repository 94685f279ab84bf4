use std::path::PathBuf;

use thiserror::Error;

use crate::elastic::ProblemError;
use crate::fem::MaterialError;
use crate::mesh::MeshError;

/// Why a case could not be set up. Every variant names the case file.
#[derive(Debug, Error)]
pub enum CaseError {
    #[error("cannot read case file {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// The message of the TOML parser names the line, the column and the key.
    #[error("case file {path}: {message}")]
    Syntax { path: PathBuf, message: String },
    #[error("case file {path}: {context}: {message}")]
    Invalid {
        path: PathBuf,
        context: String,
        message: String,
    },
    #[error("case file {path}: body '{body}' is not a body of mesh {mesh} (its bodies: {})", .available.join(", "))]
    UnknownBody {
        path: PathBuf,
        body: String,
        mesh: PathBuf,
        available: Vec<String>,
    },
    #[error("case file {path}: body '{body}': {source}")]
    Material {
        path: PathBuf,
        body: String,
        source: MaterialError,
    },
    #[error("case file {path}: {source}")]
    Problem { path: PathBuf, source: ProblemError },
    #[error("case file {path}: {source}")]
    Mesh { path: PathBuf, source: MeshError },
    #[error("case file {path}: cannot mesh {geo} with gmsh: {message}")]
    Gmsh {
        path: PathBuf,
        geo: PathBuf,
        message: String,
    },
}
