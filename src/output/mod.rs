//! Result files: XDMF + HDF5 for ParaView and h5py, the JSON summary, Matrix Market matrices,
//! the force-displacement plot.

mod folder;
mod matrix_market;
mod plot;
mod summary;
mod xdmf;

pub use folder::{
    FAILURE_MARK, GENERATED_MESH, RESULT_FILES, ResultFolder, mark_failed_folder, unsaid_causes,
};
pub use matrix_market::write_matrix_market;
pub use plot::{PlotError, write_force_displacement_png};
pub use summary::{BodySummary, CaseSummary, ContactSummary, force_displacement_csv};
pub use xdmf::{BodyFields, write_xdmf};

use std::path::PathBuf;

use thiserror::Error;

#[derive(Debug, Error)]
pub enum OutputError {
    #[error("cannot write {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("cannot write HDF5 file {path}: {source}")]
    Hdf5 { path: PathBuf, source: hdf5::Error },
    #[error(
        "the output folder {dir} ({origin}) holds the input {input} under the name '{name}', \
         which a run removes or replaces; set another output folder or rename the input"
    )]
    InputInOutput {
        dir: PathBuf,
        /// Where the folder was set: the case file's `output` key or `--output`.
        origin: String,
        input: PathBuf,
        /// The result name it has.
        name: String,
    },
    #[error("cannot write {path}: {source}")]
    Json {
        path: PathBuf,
        source: serde_json::Error,
    },
}
