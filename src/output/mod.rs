//! Result files: XDMF + HDF5 for ParaView and h5py, the JSON summary, Matrix Market matrices,
//! the force-displacement plot.

mod folder;
mod matrix_market;
pub(crate) mod plot;
mod summary;
mod xdmf;

pub use folder::{
    FAILURE_MARK, GENERATED_MESH, RESULT_FILES, ResultFolder, holds_only_run_outputs,
    mark_failed_folder, unsaid_causes,
};
pub use matrix_market::write_matrix_market;
pub use plot::{PLOT_SIZE, PlotError, write_force_displacement_png};
pub use summary::{
    BodySummary, CaseSummary, ContactSummary, Verdict, force_displacement_csv, peak_memory_mb,
};
pub use xdmf::{
    BodyFields, CellRows, CellRowsOf, NodeRowsOf, NodeTable, row_chunks, write_xdmf,
    write_xdmf_with,
};

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
    #[error(
        "the commit lock {path} is a folder: a run creates that name as a file while it moves \
         its results into place, so no run into this output folder can finish; remove the \
         folder (rm -r '{path}')"
    )]
    LockIsFolder { path: PathBuf },
    #[error(
        "waited {seconds:.0} s for the commit lock {path}: a commit takes milliseconds, so \
         other runs into this output folder held it all that time or it cannot be removed; if \
         no other run is writing into this folder, remove the lock (rm '{path}')"
    )]
    LockTimeout { path: PathBuf, seconds: f64 },
    #[error("cannot write {path}: {source}")]
    Json {
        path: PathBuf,
        source: serde_json::Error,
    },
}
