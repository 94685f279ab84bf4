//! `internodes._internodes`: the native part of the `internodes` Python package.
//!
//! A thin layer over the Rust library: a case is read and checked by `internodes::case`, a mesh
//! by `internodes::mesh`, the solve is `internodes::run::solve_case_on` and the result files are
//! `internodes::run::write_results`, exactly as the command line runs them. This module only
//! converts: Python values in, NumPy arrays and the summary's JSON out, Rust errors into Python
//! exceptions. `docs/python.md` is the user's page.

use std::collections::BTreeMap;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use numpy::{PyArray1, PyArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::{
    PyException, PyFileExistsError, PyIndexError, PyKeyboardInterrupt, PyOSError, PyRuntimeError,
    PyValueError,
};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyList};

use internodes::case::{Case as CaseFile, CaseError, check_geo_parameters};
use internodes::contact::{ContactStatus, StepRecord};
use internodes::fem::stress::cell_fields;
use internodes::mesh::{
    GmshModel, Mesh as BodyMeshes, MeshError, ModelElements, ModelGroup, mesh_from_model, mesh_geo,
    read_msh, read_msh_bytes,
};
use internodes::output::{
    CaseSummary, ContactSummary, FAILURE_MARK, GENERATED_MESH, OutputError, RESULT_FILES,
    ResultFolder, Verdict, unsaid_causes,
};
use internodes::run::{CaseSolution, RunError, Timings, solve_case_on, write_results};
use internodes::study::{Study as StudyRun, StudyError, StudyOptions, StudySpec, run_study};

create_exception!(
    internodes,
    InputError,
    PyValueError,
    "A case or a mesh that cannot be used; the message is the command line's."
);
create_exception!(
    internodes,
    SolveError,
    PyRuntimeError,
    "A solve that failed: a body's linear solve, or the contact solve, named in the message."
);
create_exception!(
    internodes,
    NotSolvedError,
    PyRuntimeError,
    "Raised by Result.raise_for_status: the contact problem was not solved, or its accuracy \
     report failed."
);
create_exception!(
    internodes,
    Cancelled,
    PyException,
    "Raised by solve() when its Cancel token was cancelled (from another thread): the solve \
     stopped at its next load step, active-set iteration or coupled GMRES iteration."
);
create_exception!(
    internodes,
    WriteError,
    PyOSError,
    "The result files could not be written."
);

/// An error's message and the causes its message does not already say, as the command line
/// prints them.
fn message(error: &dyn std::error::Error) -> String {
    // The TOML parser's messages end with a newline, which an exception's text does not need.
    let mut text = error.to_string().trim_end().to_string();
    for cause in unsaid_causes(error) {
        text += &format!("\n  caused by: {cause}");
    }
    text
}

/// The Python exception of a run's error.
fn run_error(error: RunError) -> PyErr {
    let text = message(&error);
    match error {
        RunError::Case(_) => InputError::new_err(text),
        // A Python process is one rank: it never meets an MPI error, but would be told as a
        // failed solve.
        RunError::Solve { .. } | RunError::Contact { .. } | RunError::Parallel(_) => {
            SolveError::new_err(text)
        }
        RunError::Output(_) => WriteError::new_err(text),
        RunError::Cancelled(_) => Cancelled::new_err(text),
    }
}

/// Runs `f`; a panic (a bug of the solver) becomes a `SolveError` instead of crossing into
/// Python as pyo3's `PanicException`, which derives from `BaseException` and escapes
/// `except Exception`.
fn guarded<T>(what: &str, f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    catch_unwind(AssertUnwindSafe(f)).unwrap_or_else(|panic| {
        let why = (panic.downcast_ref::<String>().cloned())
            .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_else(|| "unknown".to_string());
        Err(SolveError::new_err(format!(
            "internal error of the solver during {what} (a bug; please report it with the \
             case): {why}"
        )))
    })
}

/// A case: bodies, materials, boundary conditions, loads, and the contact settings, with the
/// keys of a case file (`docs/case-file.md`) and the same checks.
#[pyclass(module = "internodes", frozen)]
struct Case {
    file: CaseFile,
    /// Whether the case names a mesh (a case built in code may leave it to `solve(mesh=...)`).
    names_mesh: bool,
    /// What the case was made from, for pickling ([`CaseSource`]).
    source: CaseSource,
}

#[pymethods]
impl Case {
    /// Reads a case file. Relative paths in it are relative to its folder.
    #[staticmethod]
    fn from_toml(path: PathBuf) -> PyResult<Self> {
        let file = CaseFile::load(&path).map_err(|e| InputError::new_err(message(&e)))?;
        let text =
            std::fs::read_to_string(&path).map_err(|e| InputError::new_err(e.to_string()))?;
        Ok(Case {
            file,
            names_mesh: true,
            source: CaseSource {
                text,
                name: path.to_string_lossy().into_owned(),
                folder: path.parent().unwrap_or(Path::new("")).to_owned(),
                from_dict: false,
            },
        })
    }

    /// A case from a dict with the case file's keys (`{"mesh": ..., "body": [...], "contact":
    /// {...}}`; `"contact"` a list of such dicts for several pairs). `mesh` may be left out when
    /// a `Mesh` is passed to `solve`. `name` names the case in messages (`case 'NAME' (from a
    /// dict)`) and the plot title; relative paths are relative to `folder` (default: the
    /// current directory). Numbers may be NumPy scalars or arrays, `Fraction`s or `Decimal`s
    /// (taken as the nearest float); NaN and infinities are refused, naming the key.
    #[staticmethod]
    #[pyo3(signature = (table, name = "case", folder = None))]
    fn from_dict(
        py: Python<'_>,
        table: &Bound<'_, PyAny>,
        name: &str,
        folder: Option<PathBuf>,
    ) -> PyResult<Self> {
        let label = dict_label(name);
        // The dict goes through JSON, then into the same schema as a file. Its values are made
        // JSON's first (`internodes._values.plain`: path objects, NumPy values, fractions and
        // decimals become strings, numbers and lists), where a value JSON cannot hold (NaN, an
        // infinity, an object) is refused naming its key: `json.dumps` would name none.
        let plain = (py.import("internodes._values")?)
            .call_method1("plain", (table,))
            .map_err(|e| InputError::new_err(format!("{label}: {}", e.value(py))))?;
        let text: String = (py.import("json")?)
            .call_method1("dumps", (plain,))?
            .extract()?;
        let json: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| InputError::new_err(e.to_string()))?;
        if let Some(key) = first_none(&json, String::new()) {
            return Err(InputError::new_err(format!(
                "{label}: {key} is None: a case file has no null; leave the key out to take its \
                 default"
            )));
        }
        let mut value: toml::Table = serde_json::from_value(json).map_err(|e| {
            InputError::new_err(format!("{label}: expected a dict of case-file keys ({e})"))
        })?;
        let names_mesh = value.contains_key("mesh");
        if !names_mesh {
            value.insert("mesh".to_string(), toml::Value::String(String::new()));
        }
        let folder = folder.unwrap_or_default();
        let text = toml::to_string(&value).map_err(|e| InputError::new_err(e.to_string()))?;
        let source = CaseSource {
            text,
            name: name.to_string(),
            folder,
            from_dict: true,
        };
        let file = CaseFile::from_table(value, name, &source.folder)
            .map_err(|e| InputError::new_err(source.relabel(message(&e))))?;
        Ok(Case {
            file,
            names_mesh,
            source,
        })
    }

    /// The case file, or the name given to `from_dict`.
    #[getter]
    fn path(&self) -> PathBuf {
        self.file.path.clone()
    }

    /// The mesh the case names (`None` if it names none).
    #[getter]
    fn mesh(&self) -> Option<PathBuf> {
        self.names_mesh.then(|| self.file.mesh.clone())
    }

    /// The bodies' names, in the case's order.
    #[getter]
    fn bodies(&self) -> Vec<String> {
        self.file.bodies.iter().map(|b| b.name.clone()).collect()
    }

    /// The load factors of the contact solve (`[1.0]` unless the case lists steps); with a
    /// `[load_path]`, those of the entries without `path` (1 at each step unless the case
    /// lists steps).
    #[getter]
    fn load_steps(&self) -> Vec<f64> {
        self.file.load_steps()
    }

    /// The case's `[load_path]`: each named path's factors, one per load step (empty without
    /// one).
    #[getter]
    fn load_path(&self) -> BTreeMap<String, Vec<f64>> {
        self.file.load_path.clone().unwrap_or_default()
    }

    /// The contact pairs' names, in the case's order (`[contact] name`, default
    /// `"BODY1-BODY2"`; empty without contact).
    #[getter]
    fn pairs(&self) -> Vec<String> {
        self.file.contacts.iter().map(|c| c.name.clone()).collect()
    }

    /// Pickling: the case's keys (as TOML), name and folder, read again with the same checks.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let restore = py
            .import("internodes._internodes")?
            .getattr("_restore_case")?;
        let CaseSource {
            text,
            name,
            folder,
            from_dict,
        } = &self.source;
        let arguments = (text, name, folder, self.names_mesh, from_dict).into_pyobject(py)?;
        Ok((restore, arguments.into_any()))
    }

    fn __repr__(&self) -> String {
        format!(
            "Case('{}', bodies={:?}, pairs={})",
            self.file.path.display(),
            self.bodies(),
            self.file.contacts.len()
        )
    }
}

/// The place of the first `None` in a case's dict (`body[0].youngs_modulus`), if any.
fn first_none(value: &serde_json::Value, at: String) -> Option<String> {
    match value {
        serde_json::Value::Null => Some(at),
        serde_json::Value::Array(items) => {
            (items.iter().enumerate()).find_map(|(k, item)| first_none(item, format!("{at}[{k}]")))
        }
        serde_json::Value::Object(table) => table.iter().find_map(|(key, item)| {
            first_none(
                item,
                if at.is_empty() {
                    key.clone()
                } else {
                    format!("{at}.{key}")
                },
            )
        }),
        _ => None,
    }
}

/// What a `Case` was made from: its keys as TOML text, the name that stands for its file, the
/// folder its relative paths are relative to, and whether it was a dict. A pickled case is
/// this, read again by [`restore_case`] with the same checks; it holds no solver state.
#[derive(Clone)]
struct CaseSource {
    text: String,
    name: String,
    folder: PathBuf,
    from_dict: bool,
}

impl CaseSource {
    /// A message of the library about this case as the user knows the case: the library names
    /// every case "case file NAME", which for a dict's case names a file that does not exist.
    fn relabel(&self, text: String) -> String {
        match self.from_dict {
            true => text.replace(&format!("case file {}", self.name), &dict_label(&self.name)),
            false => text,
        }
    }
}

/// How messages name a case made from a dict: `case 'NAME' (from a dict)`.
fn dict_label(name: &str) -> String {
    format!("case '{name}' (from a dict)")
}

impl Case {
    /// How messages name this case: its file, or the dict's name.
    fn label(&self) -> String {
        self.source
            .relabel(format!("case file {}", self.file.path.display()))
    }

    /// `error` (an exception of this module, whose argument is its message) with the case
    /// named as the user knows it ([`CaseSource::relabel`]).
    fn relabel(&self, py: Python<'_>, error: PyErr) -> PyErr {
        let value = error.value(py);
        let ours = [
            py.get_type::<InputError>(),
            py.get_type::<SolveError>(),
            py.get_type::<WriteError>(),
            py.get_type::<Cancelled>(),
        ];
        let Some(kind) = ours.into_iter().find(|t| value.get_type().is(t)) else {
            return error;
        };
        let Ok(text) = value.str().map(|t| t.to_string()) else {
            return error;
        };
        let relabeled = self.source.relabel(text.clone());
        if relabeled == text {
            return error;
        }
        match kind.call1((relabeled,)) {
            Ok(new) => PyErr::from_value(new),
            Err(e) => e,
        }
    }
}

/// The `Case` of a pickle ([`Case::__reduce__`]).
#[pyfunction]
#[pyo3(name = "_restore_case")]
fn restore_case(
    text: String,
    name: String,
    folder: PathBuf,
    names_mesh: bool,
    from_dict: bool,
) -> PyResult<Case> {
    let table: toml::Table =
        toml::from_str(&text).map_err(|e| InputError::new_err(e.to_string()))?;
    let source = CaseSource {
        text,
        name,
        folder,
        from_dict,
    };
    let file = CaseFile::from_table(table, &source.name, &source.folder)
        .map_err(|e| InputError::new_err(source.relabel(message(&e))))?;
    Ok(Case {
        file,
        names_mesh,
        source,
    })
}

/// Where a `Mesh` came from, for pickling: a file is read again by path, a mesh gmsh made of a
/// `.geo` is its MSH bytes (kept anyway, for `mesh.msh`), a gmsh model is the arrays read from it.
#[derive(Clone)]
enum MeshSource {
    File,
    Generated,
    Model(Arc<Py<PyAny>>),
}

/// The `Mesh` of a pickle of a `.geo`'s mesh: the MSH bytes gmsh made, named after the `.geo`.
#[pyfunction]
#[pyo3(name = "_restore_generated_mesh")]
fn restore_generated_mesh(geo: PathBuf, bytes: Vec<u8>) -> PyResult<Mesh> {
    let mesh = read_msh_bytes(&geo, &bytes).map_err(|e| mesh_error(e, None))?;
    Ok(Mesh {
        mesh: Arc::new(mesh),
        generated: Some(Arc::new(bytes)),
        source: MeshSource::Generated,
    })
}

/// The `Mesh` of a pickle of a gmsh model's mesh: the arrays `internodes._gmsh` read.
#[pyfunction]
#[pyo3(name = "_restore_model_mesh")]
fn restore_model_mesh(py: Python<'_>, arrays: Bound<'_, PyAny>) -> PyResult<Mesh> {
    mesh_of_model(py, arrays)
}

/// A mesh from the arrays of a gmsh model (`internodes._gmsh.model_arrays`).
fn mesh_of_model(py: Python<'_>, arrays: Bound<'_, PyAny>) -> PyResult<Mesh> {
    let label: String = arrays.get_item("label")?.extract()?;
    let model = gmsh_model(&arrays)?;
    let mesh = py
        .detach(|| mesh_from_model(Path::new(&label), model))
        .map_err(|e| mesh_error(e, None))?;
    Ok(Mesh {
        mesh: Arc::new(mesh),
        generated: None,
        source: MeshSource::Model(Arc::new(arrays.unbind())),
    })
}

/// A mesh: the bodies (physical surfaces in 2D, volumes in 3D), their boundary groups and point
/// groups, as `docs/meshes.md` describes.
#[pyclass(module = "internodes", frozen)]
#[derive(Clone)]
struct Mesh {
    mesh: Arc<BodyMeshes>,
    /// The MSH file gmsh made of a `.geo`: written as `mesh.msh` with the results, as the
    /// command line does.
    generated: Option<Arc<Vec<u8>>>,
    source: MeshSource,
}

#[pymethods]
impl Mesh {
    /// Reads a gmsh MSH 4.1 file.
    #[staticmethod]
    fn from_msh(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let mesh = py
            .detach(|| read_msh(&path))
            .map_err(|e| mesh_error(e, None))?;
        Ok(Mesh {
            mesh: Arc::new(mesh),
            generated: None,
            source: MeshSource::File,
        })
    }

    /// Meshes a `.geo` script with gmsh (the `gmsh` program), with `parameters` as gmsh's
    /// `-setnumber` values, checked as a case's `geo_parameters` are: a name the script does
    /// not use is refused with the case file's message.
    #[staticmethod]
    #[pyo3(signature = (path, parameters = None))]
    fn from_geo(
        py: Python<'_>,
        path: PathBuf,
        parameters: Option<BTreeMap<String, f64>>,
    ) -> PyResult<Self> {
        let parameters = parameters.unwrap_or_default();
        check_geo_parameters(&path, &parameters).map_err(|e| InputError::new_err(e.to_string()))?;
        let parameters: Vec<(String, f64)> = parameters.into_iter().collect();
        py.detach(|| generate(&path, &parameters, None))
    }

    /// The current model of the `gmsh` Python module (or the model named `model`), meshed,
    /// without a file: its physical groups, nodes and elements are read through gmsh's API.
    #[staticmethod]
    #[pyo3(signature = (model = None))]
    fn from_gmsh(py: Python<'_>, model: Option<String>) -> PyResult<Self> {
        let arrays = (py.import("internodes._gmsh")?).call_method1("model_arrays", (model,))?;
        mesh_of_model(py, arrays)
    }

    /// The file (or model) the mesh came from.
    #[getter]
    fn path(&self) -> PathBuf {
        self.mesh.path.clone()
    }

    /// 2 or 3.
    #[getter]
    fn dim(&self) -> usize {
        self.mesh.dim
    }

    /// The bodies' names.
    #[getter]
    fn bodies(&self) -> Vec<String> {
        self.mesh.bodies.iter().map(|b| b.name.clone()).collect()
    }

    /// The names of every physical group.
    #[getter]
    fn groups(&self) -> Vec<String> {
        self.mesh
            .physical_groups
            .iter()
            .map(|g| g.name.clone())
            .collect()
    }

    /// Pickling: a mesh read from a file is read again from its path (in the process that
    /// unpickles it), a mesh gmsh made of a `.geo` travels as its MSH bytes, a gmsh model's mesh
    /// as the arrays read from the model.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let module = py.import("internodes._internodes")?;
        let path = &self.mesh.path;
        Ok(match (&self.source, &self.generated) {
            (MeshSource::Generated, Some(bytes)) => (
                module.getattr("_restore_generated_mesh")?,
                (path, pyo3::types::PyBytes::new(py, bytes))
                    .into_pyobject(py)?
                    .into_any(),
            ),
            (MeshSource::Model(arrays), _) => (
                module.getattr("_restore_model_mesh")?,
                (arrays.clone_ref(py),).into_pyobject(py)?.into_any(),
            ),
            _ => (
                module.getattr("Mesh")?.getattr("from_msh")?,
                (path,).into_pyobject(py)?.into_any(),
            ),
        })
    }

    /// Each body's number of nodes, by name.
    #[getter]
    fn num_nodes(&self) -> BTreeMap<String, usize> {
        (self.mesh.bodies.iter())
            .map(|b| (b.name.clone(), b.num_nodes()))
            .collect()
    }

    /// Each body's number of cells (triangles in 2D, tetrahedra in 3D), by name.
    #[getter]
    fn num_cells(&self) -> BTreeMap<String, usize> {
        (self.mesh.bodies.iter())
            .map(|b| (b.name.clone(), b.num_cells()))
            .collect()
    }

    fn __repr__(&self) -> String {
        let bodies: Vec<String> = (self.mesh.bodies.iter())
            .map(|b| {
                format!(
                    "'{}': {} nodes, {} cells",
                    b.name,
                    b.num_nodes(),
                    b.num_cells()
                )
            })
            .collect();
        format!(
            "Mesh('{}', dim={}, bodies={{{}}})",
            self.mesh.path.display(),
            self.mesh.dim,
            bodies.join(", ")
        )
    }
}

/// Meshes `geo` with gmsh into a temporary folder and reads the mesh, which is named after the
/// `.geo`. Errors name `case` when the case named the `.geo`, as the command line's do.
fn generate(geo: &Path, parameters: &[(String, f64)], case: Option<&Path>) -> PyResult<Mesh> {
    let folder = tempfile::tempdir().map_err(|e| WriteError::new_err(e.to_string()))?;
    let msh = folder.path().join(GENERATED_MESH);
    if let Err(e) = mesh_geo(geo, &msh, parameters) {
        return Err(InputError::new_err(match case {
            Some(path) => message(&CaseError::Gmsh {
                path: path.to_owned(),
                geo: geo.to_owned(),
                message: e,
            }),
            None => format!("cannot mesh {} with gmsh: {e}", geo.display()),
        }));
    }
    let bytes = std::fs::read(&msh).map_err(|e| WriteError::new_err(e.to_string()))?;
    let mesh = read_msh_bytes(geo, &bytes).map_err(|e| mesh_error(e, case))?;
    Ok(Mesh {
        mesh: Arc::new(mesh),
        generated: Some(Arc::new(bytes)),
        source: MeshSource::Generated,
    })
}

/// A mesh error as an `InputError`, naming `case` when the case named the mesh.
fn mesh_error(error: MeshError, case: Option<&Path>) -> PyErr {
    match case {
        Some(path) => InputError::new_err(message(&CaseError::Mesh {
            path: path.to_owned(),
            source: error,
        })),
        None => InputError::new_err(message(&error)),
    }
}

/// The model that `internodes._gmsh.model_arrays` read from gmsh's API.
fn gmsh_model(arrays: &Bound<'_, PyAny>) -> PyResult<GmshModel> {
    let mut model = GmshModel {
        num_volumes: arrays.get_item("num_volumes")?.extract()?,
        node_tags: vector(arrays.get_item("node_tags")?)?,
        coords: vector(arrays.get_item("coords")?)?,
        ..GmshModel::default()
    };
    for group in arrays.get_item("groups")?.cast_into::<PyList>()?.iter() {
        let (dim, tag, name, entities): (usize, i32, String, Vec<i32>) = group.extract()?;
        model.physical_groups.push(ModelGroup {
            dim,
            tag,
            name,
            entities,
        });
    }
    for block in arrays.get_item("blocks")?.cast_into::<PyList>()?.iter() {
        let (entity_dim, entity_tag, element_type, element_tags, node_tags): (
            usize,
            i32,
            i32,
            Bound<'_, PyAny>,
            Bound<'_, PyAny>,
        ) = block.extract()?;
        model.element_blocks.push(ModelElements {
            entity_dim,
            entity_tag,
            element_type,
            element_tags: vector(element_tags)?,
            node_tags: vector(node_tags)?,
        });
    }
    Ok(model)
}

/// A contiguous one-dimensional NumPy array (as `internodes._gmsh` makes them) as a vector.
fn vector<T: numpy::Element + Copy>(array: Bound<'_, PyAny>) -> PyResult<Vec<T>> {
    Ok(array
        .cast_into::<PyArray1<T>>()?
        .readonly()
        .as_slice()?
        .to_vec())
}

/// Solves a case, on `mesh` or on the mesh the case names (read, or meshed with gmsh when it
/// is a `.geo`). The solve runs without the GIL.
///
/// Raises `InputError` for a case or mesh that cannot be used and `SolveError` when a solve
/// fails; a contact problem that was not solved, or whose accuracy report failed, is a result
/// with that status (see `Result.exit_code` and `Result.raise_for_status`), as the command line
/// writes its results and says so in its exit status.
///
/// Ctrl-C stops the solve within about a second (at its next safe point) with
/// `KeyboardInterrupt`; `cancel`, a `Cancel` token, stops it from another thread with
/// `Cancelled`.
///
/// `threads`: the solver's threads for this solve, in a pool of its own (default: the number of
/// cores, or `RAYON_NUM_THREADS`), so that solves in several Python threads run side by side;
/// with `w` workers on `c` cores, `threads = c // w`. The answer does not depend on it.
#[pyfunction]
#[pyo3(signature = (case, mesh = None, *, cancel = None, threads = None))]
fn solve(
    py: Python<'_>,
    case: &Case,
    mesh: Option<PyRef<'_, Mesh>>,
    cancel: Option<PyRef<'_, Cancel>>,
    threads: Option<usize>,
) -> PyResult<Result> {
    solve_named(py, case, mesh, cancel, threads).map_err(|e| case.relabel(py, e))
}

/// [`solve`], its errors naming a dict's case as the library names a case file.
fn solve_named(
    py: Python<'_>,
    case: &Case,
    mesh: Option<PyRef<'_, Mesh>>,
    cancel: Option<PyRef<'_, Cancel>>,
    threads: Option<usize>,
) -> PyResult<Result> {
    if threads == Some(0) {
        return Err(PyValueError::new_err(
            "threads must be at least 1 (leave it out for the default)",
        ));
    }
    let mesh = match mesh {
        Some(mesh) => mesh.clone(),
        None if !case.names_mesh => {
            return Err(InputError::new_err(format!(
                "{} names no mesh: give it the `mesh` key, or pass mesh= to solve()",
                case.label()
            )));
        }
        None if case.file.generates_mesh() => {
            let parameters: Vec<(String, f64)> = (case.file.geo_parameters.iter())
                .map(|(k, v)| (k.clone(), *v))
                .collect();
            py.detach(|| generate(&case.file.mesh, &parameters, Some(&case.file.path)))?
        }
        None => Mesh {
            mesh: Arc::new(
                py.detach(|| read_msh(&case.file.mesh))
                    .map_err(|e| mesh_error(e, Some(&case.file.path)))?,
            ),
            generated: None,
            source: MeshSource::File,
        },
    };
    let mut file = case.file.clone();
    file.solver.verbose = true;
    // Every load step's fields are the result's (`Result.step_bodies`).
    file.solver.keep_step_fields = true;
    file.solver.cancel = cancel.map(|c| c.token.clone()).unwrap_or_default();
    let solution = interruptible(py, &file.solver.cancel, || {
        in_own_pool(threads, || {
            guarded("the solve", || {
                solve_case_on(&file, &mesh.mesh, Timings::start()).map_err(|e| {
                    match e.is_cancelled() {
                        true => Cancelled::new_err(message(&e)),
                        false => run_error(e),
                    }
                })
            })
        })
    })?;
    let summary = solution.summary(&file, &mesh.mesh);
    Ok(Result {
        case: file,
        mesh,
        solution,
        summary,
        bodies: PyOnceLock::new(),
        contacts: PyOnceLock::new(),
    })
}

/// A token that cancels the solves given it (`solve(case, cancel=token)`) from another thread:
/// `token.cancel()` stops them at their next load step, active-set iteration or coupled GMRES
/// iteration, and they raise `Cancelled`. A cancelled token stays cancelled.
#[pyclass(module = "internodes", frozen)]
struct Cancel {
    token: internodes::cancel::Cancel,
}

#[pymethods]
impl Cancel {
    #[new]
    fn new() -> Self {
        Cancel {
            token: internodes::cancel::Cancel::new(),
        }
    }

    /// Stops every solve holding this token at its next safe point.
    fn cancel(&self) {
        self.token.cancel();
    }

    /// Whether `cancel()` was called.
    #[getter]
    fn cancelled(&self) -> bool {
        self.token.is_cancelled()
    }

    fn __repr__(&self) -> String {
        format!("Cancel(cancelled={})", self.cancelled())
    }
}

/// How often a waiting `solve` looks for Ctrl-C (Python's signal handlers).
const SIGNAL_POLL: std::time::Duration = std::time::Duration::from_millis(50);

/// Runs `work` on a thread of its own, without the GIL, while this thread checks Python's
/// signals every [`SIGNAL_POLL`]: a signal handler that raises (Ctrl-C's `KeyboardInterrupt`)
/// cancels `token`, the work stops at its next safe point, and its exception is raised once the
/// work has returned (nothing of it is left running). Signals are only handled on Python's
/// main thread; a solve run from another thread is cancelled by its token.
fn interruptible<T: Send>(
    py: Python<'_>,
    token: &internodes::cancel::Cancel,
    work: impl FnOnce() -> PyResult<T> + Send,
) -> PyResult<T> {
    use std::sync::mpsc::{RecvTimeoutError, channel};
    std::thread::scope(|scope| {
        let (sender, receiver) = channel();
        // A receiver is not `Sync`: it crosses into `detach` behind a lock.
        let receiver = std::sync::Mutex::new(receiver);
        let worker = scope.spawn(move || {
            // `work` catches its own panics (`guarded`), so it always sends.
            let _ = sender.send(work());
        });
        let mut interrupt: Option<PyErr> = None;
        let outcome = loop {
            let received = py.detach(|| {
                let receiver = receiver.lock().unwrap_or_else(|e| e.into_inner());
                receiver.recv_timeout(SIGNAL_POLL)
            });
            match received {
                Ok(outcome) => break outcome,
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => {
                    break Err(SolveError::new_err(
                        "the solve's thread ended without an answer",
                    ));
                }
            }
            if interrupt.is_none()
                && let Err(e) = py.check_signals()
            {
                token.cancel();
                interrupt = Some(e);
            }
        };
        let _ = py.detach(|| worker.join());
        match interrupt {
            Some(e) => Err(e),
            None => outcome,
        }
    })
}

/// Runs `work` in a rayon pool of its own with `threads` threads (`None`: rayon's default, the
/// cores or `RAYON_NUM_THREADS`), whose threads have ended when it returns. Solves from several
/// Python threads then run side by side instead of queueing on rayon's one global pool (two
/// workers solved only 1.07 times as fast as one there).
fn in_own_pool<T: Send>(
    threads: Option<usize>,
    work: impl FnOnce() -> PyResult<T> + Send,
) -> PyResult<T> {
    std::thread::scope(|scope| {
        // The pool's threads are joined once it is dropped (a scope alone only waits for their
        // work to end, not for the threads to exit).
        let handles = std::sync::Mutex::new(Vec::new());
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads.unwrap_or(0))
            .thread_name(|k| format!("internodes-solve-{k}"))
            .spawn_handler(|thread| {
                let handle = std::thread::Builder::new()
                    .name(thread.name().unwrap_or("internodes-solve").to_string())
                    .spawn_scoped(scope, || thread.run())?;
                handles
                    .lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .push(handle);
                Ok(())
            })
            .build()
            .map_err(|e| SolveError::new_err(format!("cannot start the solve's threads: {e}")));
        let outcome = pool.map(|pool| pool.install(work));
        let handles = handles.into_inner().unwrap_or_else(|e| e.into_inner());
        for handle in handles {
            let _ = handle.join();
        }
        outcome?
    })
}

/// The solver's `log` messages into Python's `logging`, to the logger named after their Rust
/// module (`internodes.contact.driver`, ...), looked up at each message so that a logging
/// configuration made after the import holds. A Python exception raised while logging never
/// stays pending (which would make the next call into Python fail with `SystemError`): a
/// `KeyboardInterrupt` is handed back to Python's signal machinery, to be raised where the
/// interpreter next checks for signals (`solve` checks while it waits), and any other
/// exception is reported as unraisable, as `logging` reports a handler's error.
struct LogBridge;

impl LogBridge {
    fn forward(py: Python<'_>, record: &log::Record) -> PyResult<()> {
        let level = match record.level() {
            log::Level::Error => 40,
            log::Level::Warn => 30,
            log::Level::Info => 20,
            log::Level::Debug => 10,
            log::Level::Trace => 5,
        };
        let name = record.target().replace("::", ".");
        let logger = (py.import("logging")?).call_method1("getLogger", (name,))?;
        if logger.call_method1("isEnabledFor", (level,))?.is_truthy()? {
            logger.call_method1("log", (level, "%s", record.args().to_string()))?;
        }
        Ok(())
    }
}

impl log::Log for LogBridge {
    fn enabled(&self, _: &log::Metadata) -> bool {
        true
    }

    fn log(&self, record: &log::Record) {
        Python::attach(|py| {
            // An exception pending before this message is left as it was found.
            let pending = PyErr::take(py);
            if let Err(e) = Self::forward(py, record) {
                if e.is_instance_of::<PyKeyboardInterrupt>(py) {
                    // SAFETY: called with the GIL held; it only sets the interpreter's flag.
                    unsafe { pyo3::ffi::PyErr_SetInterrupt() };
                } else {
                    e.write_unraisable(py, None);
                }
            }
            if let Some(e) = pending {
                e.restore(py);
            }
        })
    }

    fn flush(&self) {}
}

/// A solved case: the summary (`summary.json`'s contents), every body's fields as NumPy
/// arrays, and the result files on request.
#[pyclass(module = "internodes", frozen)]
struct Result {
    case: CaseFile,
    mesh: Mesh,
    solution: CaseSolution,
    summary: CaseSummary,
    bodies: PyOnceLock<Py<PyDict>>,
    contacts: PyOnceLock<Py<PyDict>>,
}

#[pymethods]
impl Result {
    /// What `summary.json` holds: status, certificate and accuracy report, forces, Hertz fit,
    /// iteration history and load-step records, per-body sizes and reactions, timings.
    #[getter]
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let text = serde_json::to_string(&self.summary)
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        py.import("json")?.call_method1("loads", (text,))
    }

    /// The contact status (`"converged"`, `"no-contact"`, `"iteration-limit"`, ...), or `None`
    /// when the case has no contact. With several pairs, the worst pair's: the first pair (in
    /// the case's order) whose status is not a solution, else `"converged"` if any pair
    /// converged, else `"no-contact"` (each pair's: `contacts[name].status`).
    #[getter]
    fn status(&self) -> Option<&'static str> {
        let statuses: Vec<ContactStatus> = self.pair_summaries().map(|c| c.status).collect();
        if statuses.is_empty() {
            return None;
        }
        let status = (statuses.iter())
            .find(|s| !s.is_solution())
            .or_else(|| (statuses.iter()).find(|s| matches!(s, ContactStatus::Converged)))
            .unwrap_or(&ContactStatus::NoContact);
        Some(status.name())
    }

    /// Each contact pair's result by name (a `dict` of `ContactResult`, in the case's order;
    /// empty without contact), built on first access.
    #[getter]
    fn contacts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let contacts = self
            .contacts
            .get_or_try_init(py, || -> PyResult<Py<PyDict>> {
                let dict = PyDict::new(py);
                for pair in self.pair_summaries() {
                    let mut alone = self.summary.clone();
                    alone.contact = Some(pair.clone());
                    alone.contacts = Vec::new();
                    let result = ContactResult {
                        summary: pair.clone(),
                        verdict: alone.verdict(),
                    };
                    dict.set_item(&pair.name, Py::new(py, result)?)?;
                }
                Ok(dict.unbind())
            })?;
        Ok(contacts.bind(py).clone())
    }

    /// Whether every body was solved and the contact problem, if any, was solved (every pair's,
    /// with several pairs).
    #[getter]
    fn solved(&self) -> bool {
        !matches!(self.summary.verdict(), Verdict::NotSolved(_))
    }

    /// Whether the answer passed its accuracy report too (the command line's exit status 0).
    #[getter]
    fn accurate(&self) -> bool {
        self.summary.verdict() == Verdict::Solved
    }

    /// The command line's exit status for this result: 0 solved, 2 not solved, 3 solved but
    /// inaccurate.
    #[getter]
    fn exit_code(&self) -> u8 {
        self.summary.verdict().exit_status()
    }

    /// Raises `NotSolvedError` unless every load step was solved and passed its accuracy
    /// report (`exit_code` 0), with the command line's message, which names the failed steps
    /// (and, with several pairs, the worst pair).
    fn raise_for_status(&self) -> PyResult<()> {
        match self.summary.verdict() {
            Verdict::Solved => Ok(()),
            Verdict::NotSolved(why) | Verdict::Inaccurate(why) => Err(NotSolvedError::new_err(why)),
        }
    }

    /// One `Step` per load step solved, in order (empty without contact). The solve stops at
    /// the first step whose active set did not settle, so there may be fewer than the case's
    /// `load_steps`. A case of several contact pairs raises `ValueError`: each pair has its
    /// own steps (`contacts[name].steps`).
    #[getter]
    fn steps(&self, py: Python<'_>) -> PyResult<Vec<Step>> {
        match &self.summary.contact {
            Some(contact) => steps(py, &contact.steps),
            None if self.summary.contacts.is_empty() => Ok(Vec::new()),
            None => Err(PyValueError::new_err(format!(
                "the case has {} contact pairs ({}), each with its own load steps: use \
                 result.contacts[name].steps",
                self.summary.contacts.len(),
                quoted(self.summary.contacts.iter().map(|c| c.name.as_str()))
            ))),
        }
    }

    /// Each body's fields at the last load step by name (a `dict` of `BodyResult`), built on
    /// first access.
    #[getter]
    fn bodies<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let bodies = self
            .bodies
            .get_or_try_init(py, || -> PyResult<Py<PyDict>> {
                let dict = PyDict::new(py);
                for solved in &self.solution.bodies {
                    let body = BodyResult::new(py, &self.mesh.mesh, solved)?;
                    dict.set_item(&solved.name, Py::new(py, body)?)?;
                }
                Ok(dict.unbind())
            })?;
        Ok(bodies.bind(py).clone())
    }

    /// Each body's fields at load step `k + 1` (the step of `steps[k]`; negative `k` counts
    /// from the last, `step_bodies(-1)` holds the fields of `bodies`), by name. A body in no
    /// contact pair is solved once, at its full load: its fields are the same at every step.
    /// Without contact there is one step.
    fn step_bodies<'py>(&self, py: Python<'py>, k: isize) -> PyResult<Bound<'py, PyDict>> {
        let count = self.solution.earlier_steps.len() + 1;
        let index = if k < 0 { k + count as isize } else { k };
        if index < 0 || index >= count as isize {
            return Err(PyIndexError::new_err(format!(
                "load step index {k} out of range: the result has {count} load step{}",
                if count == 1 { "" } else { "s" }
            )));
        }
        let index = index as usize;
        if index + 1 == count {
            return self.bodies(py);
        }
        let earlier = &self.solution.earlier_steps[index];
        let dict = PyDict::new(py);
        for last in &self.solution.bodies {
            let solved = earlier.iter().find(|b| b.name == last.name).unwrap_or(last);
            let body = BodyResult::new(py, &self.mesh.mesh, solved)?;
            dict.set_item(&last.name, Py::new(py, body)?)?;
        }
        Ok(dict)
    }

    /// Writes the command line's result files into `folder` (`solution.xdmf` and `.h5`,
    /// `summary.json`, `force_displacement.csv` and `.png`, `matrices/` when the case exports
    /// them, and `mesh.msh` when the mesh was made from a `.geo`), and returns the folder. A
    /// folder that holds result files already (or a failed run's `FAILED.txt`) is refused with
    /// `FileExistsError` naming them, unless `overwrite=True`: then those are replaced, as the
    /// command line replaces the results in its output folder. Other files are never touched.
    #[pyo3(signature = (folder, *, overwrite = false))]
    fn write(&self, py: Python<'_>, folder: PathBuf, overwrite: bool) -> PyResult<PathBuf> {
        if !overwrite {
            let generated = self.mesh.generated.is_some().then_some(GENERATED_MESH);
            let earlier: Vec<&str> = (RESULT_FILES.iter().copied())
                .chain([FAILURE_MARK])
                .chain(generated)
                .filter(|name| folder.join(name).exists())
                .collect();
            if !earlier.is_empty() {
                return Err(PyFileExistsError::new_err(format!(
                    "{} holds results already ({}): pass overwrite=True to replace them",
                    folder.display(),
                    earlier.join(", ")
                )));
            }
        }
        py.detach(|| guarded("writing the results", || self.write_into(&folder)))?;
        Ok(folder)
    }

    fn __repr__(&self) -> String {
        format!(
            "Result(status={}, exit_code={}, bodies={:?})",
            self.status().unwrap_or("solved"),
            self.exit_code(),
            (self.solution.bodies.iter())
                .map(|b| &b.name)
                .collect::<Vec<_>>()
        )
    }
}

impl Result {
    /// Each pair's summary, in the case's order (the summary's `contact` for one pair,
    /// `contacts` for several).
    fn pair_summaries(&self) -> impl Iterator<Item = &ContactSummary> {
        self.summary.contact.iter().chain(&self.summary.contacts)
    }

    fn write_into(&self, folder: &Path) -> PyResult<()> {
        let write_error = |e: OutputError| WriteError::new_err(message(&e));
        let mut inputs = vec![self.mesh.mesh.path.as_path()];
        if self.case.path.is_file() {
            inputs.push(self.case.path.as_path());
        }
        let origin = format!("Result.write({})", folder.display());
        let generated = self.mesh.generated.as_deref();
        let results = ResultFolder::create(folder, &origin, &inputs, generated.is_some())
            .map_err(write_error)?;
        let written = (|| {
            if let Some(bytes) = generated {
                let staged = results.staging().join(GENERATED_MESH);
                std::fs::write(&staged, bytes.as_slice()).map_err(|source| OutputError::Io {
                    path: staged,
                    source,
                })?;
                results.publish(GENERATED_MESH)?;
            }
            write_results(
                &self.solution,
                &self.case,
                &self.mesh.mesh,
                results.staging(),
            )?;
            results.commit()?;
            Ok::<(), RunError>(())
        })();
        written.map_err(|e| {
            results.fail("Result.write", &e);
            run_error(e)
        })
    }
}

/// A mesh refinement study: `case` (whose mesh is a `.geo`) solved once per value of the gmsh
/// parameter `parameter`, each level written into `<output>/<parameter>_<value>/`, and the
/// study's files (`study.json`, `.csv`, `.md`, `.png`) into `output` (default: the case's
/// `output` folder followed by `/study`), as `internodes study` does. The solves run without
/// the GIL.
///
/// Raises `InputError` for a case, parameter or values that cannot be used (a parameter the
/// `.geo` does not use is refused with the ones it defines), `SolveError` when a level's solve
/// fails and `WriteError` when a file cannot be written.
#[pyfunction]
#[pyo3(signature = (case, parameter, values, output = None))]
fn study(
    py: Python<'_>,
    case: &Case,
    parameter: String,
    values: Vec<f64>,
    output: Option<PathBuf>,
) -> PyResult<Study> {
    if !case.names_mesh {
        return Err(InputError::new_err(format!(
            "{} names no mesh: a study needs the `mesh` key naming a .geo",
            case.label()
        )));
    }
    let spec = StudySpec { parameter, values };
    let file = case.file.clone();
    let options = StudyOptions {
        output,
        quiet: false,
        cancel: Default::default(),
    };
    let study = py
        .detach(|| {
            guarded("the study", || {
                run_study(&file, &spec, &options).map_err(study_error)
            })
        })
        .map_err(|e| case.relabel(py, e))?;
    Ok(Study { study })
}

/// The Python exception of a study's error.
fn study_error(error: StudyError) -> PyErr {
    match error {
        StudyError::Level {
            parameter,
            value,
            source,
        } => {
            let text = format!("study level {parameter} = {value}: {}", message(&*source));
            match *source {
                RunError::Case(_) => InputError::new_err(text),
                RunError::Solve { .. } | RunError::Contact { .. } | RunError::Parallel(_) => {
                    SolveError::new_err(text)
                }
                RunError::Cancelled(_) => Cancelled::new_err(text),
                RunError::Output(_) => WriteError::new_err(text),
            }
        }
        StudyError::Io { .. } => WriteError::new_err(message(&error)),
        StudyError::Case(_) | StudyError::Invalid { .. } => InputError::new_err(message(&error)),
    }
}

/// A finished refinement study: `summary` is `study.json`'s contents; `values`, `h` and each
/// quantity's column are NumPy arrays, one entry per level in the order given.
#[pyclass(module = "internodes", frozen)]
struct Study {
    study: StudyRun,
}

#[pymethods]
impl Study {
    /// What `study.json` holds: the levels, the estimates with their flags, the exit status.
    #[getter]
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let text = serde_json::to_string(&self.study)
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        py.import("json")?.call_method1("loads", (text,))
    }

    /// The gmsh parameter the study varied.
    #[getter]
    fn parameter(&self) -> String {
        self.study.parameter.clone()
    }

    /// `(n,)` the parameter's values.
    #[getter]
    fn values(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        let values: Vec<f64> = self.study.levels.iter().map(|l| l.value).collect();
        array(py, values.clone(), &[values.len()])
    }

    /// `(n,)` each level's measured spacing.
    #[getter]
    fn h(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        let h: Vec<f64> = self.study.levels.iter().map(|l| l.spacing.h).collect();
        array(py, h.clone(), &[h.len()])
    }

    /// Each quantity's `(n,)` values by key (`force`, `a`, `p0`, `max_pressure`); NaN where a
    /// level has none.
    #[getter]
    fn quantities<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        for (k, q) in self.study.estimates.iter().enumerate() {
            let column: Vec<f64> = (self.study.levels.iter())
                .map(|l| l.quantities[k].1.unwrap_or(f64::NAN))
                .collect();
            dict.set_item(&q.key, array(py, column.clone(), &[column.len()])?)?;
        }
        Ok(dict)
    }

    /// Each quantity's estimate by key, as in `study.json` (`None` with an `error` when a level
    /// has no value).
    #[getter]
    fn estimates<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let summary = self.summary(py)?;
        let dict = PyDict::new(py);
        for item in summary.get_item("estimates")?.try_iter()? {
            let item = item?;
            dict.set_item(item.get_item("key")?, item)?;
        }
        Ok(dict.into_any())
    }

    /// The worst level's exit status: 0 all solved and accurate, 2 a level not solved, 3 a
    /// level inaccurate.
    #[getter]
    fn exit_code(&self) -> u8 {
        self.study.exit_status
    }

    /// The study's folder.
    #[getter]
    fn folder(&self) -> PathBuf {
        self.study.folder.clone()
    }

    fn __repr__(&self) -> String {
        let values: Vec<f64> = self.study.levels.iter().map(|l| l.value).collect();
        let orders: Vec<String> = (self.study.estimates.iter())
            .map(|q| {
                let p = q.estimate.as_ref().and_then(|e| e.order);
                format!(
                    "{}: p={}",
                    q.key,
                    p.map_or("-".to_string(), |p| format!("{p:.2}"))
                )
            })
            .collect();
        format!(
            "Study('{}', parameter='{}', values={values:?}, exit_code={}, {})",
            self.study.case,
            self.study.parameter,
            self.study.exit_status,
            orders.join(", ")
        )
    }
}

/// How one load step ended: the library's record of it (`StepRecord`). Each step's status,
/// accuracy verdict, failed checks, forces and Hertz fit are its own; the accuracy report's
/// details (each check's value and tolerance) and the iteration history are kept for the last
/// step only (`Result.summary["contact"]`, or the pair's `ContactResult.summary`).
#[pyclass(module = "internodes", frozen, get_all)]
struct Step {
    /// 1, 2, ... in the order solved.
    step: usize,
    /// The factor of the loads, forces and prescribed displacements without a load path.
    load_factor: f64,
    /// Each named load path's factor at this step (empty without a `[load_path]`).
    path_factors: BTreeMap<String, f64>,
    /// The contact status of this step (`"converged"`, `"not-solved"`, ...).
    status: &'static str,
    /// Whether the status is a solution (`"converged"` or `"no-contact"`).
    solved: bool,
    /// Whether this step's accuracy report passed.
    accurate: bool,
    /// The checks this step failed: residuals and accuracy indicators, by name.
    failed_checks: Vec<&'static str>,
    /// Active-set iterations.
    iterations: usize,
    /// `(dim,)` total contact force on each body.
    force_primary: Py<PyAny>,
    force_secondary: Py<PyAny>,
    force_imbalance: f64,
    /// The Hertz fit of the primary pressure (contact radius or half-width, peak), if any.
    hertz_a: Option<f64>,
    hertz_p0: Option<f64>,
    /// Each force-controlled group's force at this step and the displacement it gave: a
    /// `list` of `dict`s with the keys `body`, `group`, `component`, `force`, `displacement`.
    forced: Py<PyAny>,
    /// A Coulomb pair's tangential answer at this step, `None` for the other laws: a `dict`
    /// with `tangential_force` (`(dim,)`, on the primary), `normal_force`, `stick_nodes` and
    /// `slip_nodes`.
    friction: Option<Py<PyAny>>,
    seconds: f64,
}

impl Step {
    fn new(py: Python<'_>, record: &StepRecord) -> PyResult<Self> {
        let dim = record.force_primary.len();
        Ok(Step {
            step: record.step,
            load_factor: record.load_factor,
            path_factors: record.path_factors.clone(),
            status: record.status.name(),
            solved: record.status.is_solution(),
            accurate: record.accurate,
            failed_checks: record.failed_checks.iter().map(|c| c.name()).collect(),
            iterations: record.iterations,
            force_primary: array(py, record.force_primary.clone(), &[dim])?,
            force_secondary: array(py, record.force_secondary.clone(), &[dim])?,
            force_imbalance: record.force_imbalance,
            hertz_a: record.hertz_a,
            hertz_p0: record.hertz_p0,
            forced: {
                let list = PyList::empty(py);
                for forced in &record.forced {
                    let dict = PyDict::new(py);
                    dict.set_item("body", &forced.body)?;
                    dict.set_item("group", &forced.group)?;
                    dict.set_item("component", forced.component)?;
                    dict.set_item("force", forced.force)?;
                    dict.set_item("displacement", forced.displacement)?;
                    list.append(dict)?;
                }
                list.into_any().unbind()
            },
            friction: match &record.friction {
                None => None,
                Some(friction) => {
                    let dict = PyDict::new(py);
                    let tangential = friction.tangential_force.clone();
                    dict.set_item("tangential_force", array(py, tangential, &[dim])?)?;
                    dict.set_item("normal_force", friction.normal_force)?;
                    dict.set_item("stick_nodes", friction.stick_nodes)?;
                    dict.set_item("slip_nodes", friction.slip_nodes)?;
                    Some(dict.into_any().unbind())
                }
            },
            seconds: record.seconds,
        })
    }
}

#[pymethods]
impl Step {
    fn __repr__(&self) -> String {
        format!(
            "Step({}, load_factor={}, status={}, accurate={})",
            self.step, self.load_factor, self.status, self.accurate
        )
    }
}

/// The `Step` of each record.
fn steps(py: Python<'_>, records: &[StepRecord]) -> PyResult<Vec<Step>> {
    records.iter().map(|record| Step::new(py, record)).collect()
}

/// Names as `'a', 'b'`, for messages.
fn quoted<'a>(names: impl Iterator<Item = &'a str>) -> String {
    names
        .map(|n| format!("'{n}'"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// One contact pair's result: its status, bodies, load steps and summary (an entry of the
/// summary's `contacts` with several pairs, its `contact` with one).
#[pyclass(module = "internodes", frozen)]
struct ContactResult {
    summary: ContactSummary,
    /// This pair's verdict alone.
    verdict: Verdict,
}

#[pymethods]
impl ContactResult {
    /// The pair's name (`[contact] name`, default `"BODY1-BODY2"`).
    #[getter]
    fn name(&self) -> String {
        self.summary.name.clone()
    }

    /// This pair's contact status (`"converged"`, `"no-contact"`, `"iteration-limit"`, ...).
    #[getter]
    fn status(&self) -> &'static str {
        self.summary.status.name()
    }

    /// The body that carries the multiplier.
    #[getter]
    fn primary(&self) -> String {
        self.summary.primary.clone()
    }

    /// The other body.
    #[getter]
    fn secondary(&self) -> String {
        self.summary.secondary.clone()
    }

    /// Whether this pair's contact problem was solved at every load step.
    #[getter]
    fn solved(&self) -> bool {
        !matches!(self.verdict, Verdict::NotSolved(_))
    }

    /// Whether it was solved and passed its accuracy report at every load step.
    #[getter]
    fn accurate(&self) -> bool {
        self.verdict == Verdict::Solved
    }

    /// The command line's exit status were this the only pair: 0 solved, 2 not solved, 3
    /// solved but inaccurate.
    #[getter]
    fn exit_code(&self) -> u8 {
        self.verdict.exit_status()
    }

    /// One `Step` per load step solved, in order: this pair's forces, status and accuracy.
    #[getter]
    fn steps(&self, py: Python<'_>) -> PyResult<Vec<Step>> {
        steps(py, &self.summary.steps)
    }

    /// This pair's part of `summary.json` (its `contact`, or its entry of `contacts`).
    #[getter]
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let text = serde_json::to_string(&self.summary)
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        py.import("json")?.call_method1("loads", (text,))
    }

    fn __repr__(&self) -> String {
        format!(
            "ContactResult('{}', status={}, primary='{}', secondary='{}')",
            self.summary.name,
            self.summary.status.name(),
            self.summary.primary,
            self.summary.secondary
        )
    }
}

/// One body's fields: node-wise arrays in the body's local numbering, cell-wise arrays in its
/// cell order.
#[pyclass(module = "internodes", frozen, get_all)]
struct BodyResult {
    name: String,
    /// `(n, dim)` node coordinates.
    coordinates: Py<PyAny>,
    /// `(n,)` gmsh node tags.
    node_tags: Py<PyAny>,
    /// `(n, dim)` displacement.
    displacement: Py<PyAny>,
    /// `(m, dim + 1)` cell connectivity (local node indices).
    cells: Py<PyAny>,
    /// `(m,)` gmsh element tags.
    cell_tags: Py<PyAny>,
    /// `(m, 3, 3)` strain and Cauchy stress per cell (plane strain in 2D: the zz component).
    strain: Py<PyAny>,
    stress: Py<PyAny>,
    /// `(m,)` von Mises stress per cell.
    von_mises: Py<PyAny>,
    /// Its contact surface's fields in each contact pair it is in, by pair name (in the case's
    /// order; empty for a body in no pair).
    surfaces: Py<PyDict>,
}

/// Interface fields on a body's contact candidate surface.
#[pyclass(module = "internodes", frozen, get_all)]
struct SurfaceResult {
    /// `(k,)` body-local node index of each surface node.
    nodes: Py<PyAny>,
    /// `(k,)` contact pressure (positive in compression).
    pressure: Py<PyAny>,
    /// `(k,)` normal contact force over the node's area.
    mean_pressure: Py<PyAny>,
    /// `(k, dim)` contact traction.
    traction: Py<PyAny>,
    /// `(k,)` signed distance to the other body in the deformed configuration (negative
    /// inside it).
    gap: Py<PyAny>,
    /// `(k,)` whether the node is in contact.
    active: Py<PyAny>,
}

#[pymethods]
impl SurfaceResult {
    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let k = self.nodes.bind(py).len()?;
        let active: usize = (self.active.bind(py).call_method0("sum")?).extract()?;
        Ok(format!("SurfaceResult({k} nodes, {active} active)"))
    }
}

/// A flat vector as a read-only NumPy array of shape `shape`. Read-only because a result is
/// the solver's answer: an array edited in place would change what `to_meshio` exports but not
/// what `Result.write` writes (which reads the solver's own copy).
fn array<T: numpy::Element>(py: Python<'_>, data: Vec<T>, shape: &[usize]) -> PyResult<Py<PyAny>> {
    let array = PyArray1::from_vec(py, data).reshape(shape)?.into_any();
    let kwargs = PyDict::new(py);
    kwargs.set_item("write", false)?;
    array.call_method("setflags", (), Some(&kwargs))?;
    Ok(array.unbind())
}

impl BodyResult {
    fn new(
        py: Python<'_>,
        mesh: &BodyMeshes,
        solved: &internodes::run::SolvedBody,
    ) -> PyResult<Self> {
        let body = mesh
            .body(&solved.name)
            .expect("solved bodies are mesh bodies");
        let (n, m, dim) = (body.num_nodes(), body.num_cells(), body.dim);
        let fields = cell_fields(body, &solved.material, &solved.solution.displacement);
        // One process keeps every node's coordinates (only a distributed run divides them).
        let coordinates = body.coords.flat(dim);
        let tensors = |t: &[[f64; 9]]| t.iter().flatten().copied().collect::<Vec<f64>>();
        let surfaces = PyDict::new(py);
        for surface in &solved.surfaces {
            let s = &surface.fields;
            let k = s.nodes.len();
            let traction = s.traction.iter().flat_map(|t| t[..dim].to_vec()).collect();
            let fields = SurfaceResult {
                nodes: array(py, s.nodes.clone(), &[k])?,
                pressure: array(py, s.pressure.clone(), &[k])?,
                mean_pressure: array(py, s.mean_pressure.clone(), &[k])?,
                traction: array(py, traction, &[k, dim])?,
                gap: array(py, s.normal_gap.clone(), &[k])?,
                active: array(py, s.active.clone(), &[k])?,
            };
            surfaces.set_item(&surface.pair, Py::new(py, fields)?)?;
        }
        Ok(BodyResult {
            name: solved.name.clone(),
            coordinates: array(py, coordinates, &[n, dim])?,
            node_tags: array(py, body.node_tags.to_vec(), &[n])?,
            displacement: array(py, solved.solution.displacement.clone(), &[n, dim])?,
            cells: array(
                py,
                body.cells.iter().map(|&n| n as usize).collect::<Vec<_>>(),
                &[m, dim + 1],
            )?,
            cell_tags: array(py, body.cell_tags.to_vec(), &[m])?,
            strain: array(py, tensors(&fields.strain), &[m, 3, 3])?,
            stress: array(py, tensors(&fields.stress), &[m, 3, 3])?,
            von_mises: array(py, fields.von_mises.clone(), &[m])?,
            surfaces: surfaces.unbind(),
        })
    }
}

#[pymethods]
impl BodyResult {
    /// The contact surface's fields for a body in one contact pair, `None` for a body in none;
    /// a body in several pairs raises `ValueError` (use `surfaces[pair]`).
    #[getter]
    fn surface<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        let surfaces = self.surfaces.bind(py);
        match surfaces.len() {
            0 => Ok(None),
            1 => Ok(Some(surfaces.values().get_item(0)?)),
            n => {
                let names: Vec<String> = surfaces.keys().extract()?;
                Err(PyValueError::new_err(format!(
                    "body '{}' is in {n} contact pairs ({}), with a contact surface in each: \
                     use surfaces[pair name]",
                    self.name,
                    quoted(names.iter().map(String::as_str))
                )))
            }
        }
    }

    fn __repr__(&self) -> String {
        format!("BodyResult('{}')", self.name)
    }
}

#[pymodule]
fn _internodes(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // Results must not depend on the number of threads, as in the command line: faer's sparse
    // LUs take faer's global setting, whose default splits work by thread count.
    faer::set_global_parallelism(faer::Par::Seq);
    // The solver's messages go to Python's logging ([`LogBridge`]); a second import of the
    // module (a subinterpreter) keeps the first bridge.
    // Every level reaches Python, whose logger levels choose (docs/python.md, "Logging"): the
    // command line's default log is INFO, its -v DEBUG, its -vv level 5 (the Krylov solves).
    if log::set_boxed_logger(Box::new(LogBridge)).is_ok() {
        log::set_max_level(log::LevelFilter::Trace);
    }
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<Case>()?;
    m.add_class::<Mesh>()?;
    m.add_class::<Result>()?;
    m.add_class::<BodyResult>()?;
    m.add_class::<SurfaceResult>()?;
    m.add_class::<Study>()?;
    m.add_class::<Cancel>()?;
    m.add_class::<Step>()?;
    m.add_class::<ContactResult>()?;
    m.add_function(wrap_pyfunction!(solve, m)?)?;
    m.add_function(wrap_pyfunction!(study, m)?)?;
    // What pickles of cases and meshes are read back with.
    m.add_function(wrap_pyfunction!(restore_case, m)?)?;
    m.add_function(wrap_pyfunction!(restore_generated_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(restore_model_mesh, m)?)?;
    let py = m.py();
    m.add("InputError", py.get_type::<InputError>())?;
    m.add("SolveError", py.get_type::<SolveError>())?;
    m.add("NotSolvedError", py.get_type::<NotSolvedError>())?;
    m.add("WriteError", py.get_type::<WriteError>())?;
    m.add("Cancelled", py.get_type::<Cancelled>())?;
    Ok(())
}
