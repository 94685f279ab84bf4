//! Case files: the TOML that names the mesh, the bodies, their materials and boundary
//! conditions, the solver settings and the output folder. The format is documented in
//! `docs/case-file.md`; every key has one meaning, unknown or misspelled keys are errors.

mod error;
mod schema;

pub use error::CaseError;
pub use schema::{
    BodySpec, Case, ContactSpec, DirichletSpec, GeoParameterError, HertzSpec, LoadSpec,
    MAX_LOAD_STEPS, check_geo_parameters,
};
