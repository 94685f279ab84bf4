//! The TOML schema of a case file, and its translation into [`ElasticProblem`]s.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::CaseError;
use crate::contact::{ContactProblem, ContactSettings, ContactSide, ContactSurface, PrimaryChoice};
use crate::elastic::{
    DirichletCondition, ElasticProblem, ForceCondition, LoadCondition, SolverSettings, StepFactors,
};
use crate::fem::Material;
use crate::fem::loads::{PressureField, SurfaceLoad};
use crate::linalg::{BodySolverKind, CG_AMG_AVAILABLE};
use crate::mesh::{BodyMesh, Mesh};

/// The most load steps a case may list (see [`Case::load`]).
pub const MAX_LOAD_STEPS: usize = 1000;

/// The largest magnitude a case accepts for a load (traction, pressure, Hertz `p0`), a body
/// force, a prescribed displacement, a Hertz `a` and centre, a load factor and a Young's
/// modulus, and the inverse of the smallest Young's modulus.
///
/// The principle: each figure the solver forms is a product of at most three of these (a load
/// factor times a load over a modulus is a displacement; a modulus times a displacement is a
/// stress or a force), so at most `1e120`, and a norm squares it, `1e240`: that leaves f64's
/// range (`1.8e308`) a factor of `1e68` for the mesh's sizes and the sums over its nodes. A
/// finite value beyond it (a load of `1e308`, `load_steps = [1e300]`) used to be accepted and
/// fail in the solve with an unmet residual or a singular matrix that did not name it. No
/// physical case in consistent units comes near `1e40` (steel in pascals is `2e11`).
pub const MAX_MAGNITUDE: f64 = 1e40;

/// A case file. Relative paths are relative to the case file's folder.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Case {
    /// The mesh: a gmsh `.msh` (MSH 4.1), or a `.geo` that is meshed with gmsh first.
    pub mesh: PathBuf,
    /// Output folder (optional: `--output` gives it too, and overrides it; a run needs one of
    /// the two).
    pub output: Option<PathBuf>,
    /// gmsh `-setnumber` parameters for a `.geo` mesh (e.g. `{ level = 1 }`).
    #[serde(default)]
    pub geo_parameters: BTreeMap<String, f64>,
    /// Also write the assembled stiffness and surface mass matrices (Matrix Market).
    #[serde(default)]
    pub export_matrices: bool,
    #[serde(default)]
    pub solver: SolverSettings,
    #[serde(rename = "body")]
    pub bodies: Vec<BodySpec>,
    /// The contact pairs: a `[contact]` table (one pair) or `[[contact]]` tables (several,
    /// decided together; a body may be in several). None: every body is solved alone.
    #[serde(default, rename = "contact", deserialize_with = "one_or_many")]
    pub contacts: Vec<ContactSpec>,
    /// The load factors of the contact solve, applied in turn to every load, force and
    /// prescribed displacement; each step starts from the previous active sets and reuses every
    /// factorization. Default: one step at factor 1. (A single `[contact]` table may hold them
    /// instead.) With a `[load_path]`, the factors of the entries that name no path.
    pub load_steps: Option<Vec<f64>>,
    /// `[load_path]`: named lists of load factors, all of one length, the number of load steps.
    /// A `[[body.dirichlet]]`, `[[body.load]]` or `[[body.force]]` entry with `path = "NAME"`
    /// is scaled at each step by that list's factor; an entry without `path` by `load_steps`,
    /// or by 1 at every step when the case gives no `load_steps`. See [`Case::step_factors`].
    pub load_path: Option<BTreeMap<String, Vec<f64>>>,
    /// The case file itself, set by [`Case::load`].
    #[serde(skip)]
    pub path: PathBuf,
}

/// The `contact` key: one `[contact]` table or a list of `[[contact]]` tables.
fn one_or_many<'de, D: serde::Deserializer<'de>>(
    deserializer: D,
) -> Result<Vec<ContactSpec>, D::Error> {
    use serde::de::Error;
    match toml::Value::deserialize(deserializer)? {
        toml::Value::Array(pairs) => pairs
            .into_iter()
            .map(|pair| ContactSpec::deserialize(pair).map_err(D::Error::custom))
            .collect(),
        table @ toml::Value::Table(_) => ContactSpec::deserialize(table)
            .map(|pair| vec![pair])
            .map_err(D::Error::custom),
        other => Err(D::Error::custom(format!(
            "contact: expected a [contact] table or [[contact]] tables, got a {}",
            other.type_str()
        ))),
    }
}

/// A `[contact]` (or `[[contact]]`) table: which bodies and surfaces meet, which carries the
/// multiplier, and the loop's settings ([`ContactSettings`], deserialized from the same
/// table's remaining keys, so that the library's own type and defaults are the schema).
#[derive(Debug, Clone)]
pub struct ContactSpec {
    /// What outputs call the pair (the `name` key; default `"BODY1-BODY2"`, the bodies in the
    /// order given).
    pub name: String,
    /// The two bodies in contact.
    pub bodies: [String; 2],
    /// Their candidate contact surfaces (boundary groups), in the same order.
    pub surfaces: [String; 2],
    /// "auto" (default) or one of the two bodies.
    pub primary: PrimaryChoice,
    /// The case's load factors ([`Case::load_steps`]), given in a single `[contact]` table.
    pub load_steps: Option<Vec<f64>>,
    pub settings: ContactSettings,
}

impl<'de> Deserialize<'de> for ContactSpec {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let mut table = toml::Table::deserialize(deserializer)?;
        fn take<T: serde::de::DeserializeOwned, E: Error>(
            table: &mut toml::Table,
            key: &str,
            expected: &str,
        ) -> Result<Option<T>, E> {
            table
                .remove(key)
                .map(|value| {
                    value.try_into().map_err(|e| {
                        E::custom(format!("[contact] {key}: expected {expected} ({e})"))
                    })
                })
                .transpose()
        }
        let required = |key: &str| {
            D::Error::custom(format!(
                "[contact] needs `{key}` (e.g. bodies = [\"disc\", \"block\"], surfaces = [\"disc_contact\", \"block_contact\"])"
            ))
        };
        let pair = "a list of two names";
        let name: Option<String> = take(&mut table, "name", "a name")?;
        let bodies: [String; 2] =
            take(&mut table, "bodies", pair)?.ok_or_else(|| required("bodies"))?;
        let surfaces = take(&mut table, "surfaces", pair)?.ok_or_else(|| required("surfaces"))?;
        let primary = take(&mut table, "primary", "\"auto\" or a body name")?.unwrap_or_default();
        let load_steps = take(&mut table, "load_steps", "a list of load factors")?;
        let settings = ContactSettings::deserialize(toml::Value::Table(table))
            .map_err(|e| D::Error::custom(format!("[contact]: {e}")))?;
        Ok(Self {
            name: name.unwrap_or_else(|| format!("{}-{}", bodies[0], bodies[1])),
            bodies,
            surfaces,
            primary,
            load_steps,
            settings,
        })
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    /// The body's physical group: a surface in 2D, a volume in 3D.
    pub name: String,
    pub youngs_modulus: f64,
    pub poisson_ratio: f64,
    /// Force per unit volume (per unit area in 2D).
    pub body_force: Option<Vec<f64>>,
    #[serde(default)]
    pub dirichlet: Vec<DirichletSpec>,
    /// Force-controlled groups (`[[body.force]]`).
    #[serde(default, rename = "force")]
    pub forces: Vec<ForceSpec>,
    #[serde(default, rename = "load")]
    pub loads: Vec<LoadSpec>,
}

/// Prescribed displacement components on a boundary group; omitted components are free.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DirichletSpec {
    pub group: String,
    pub ux: Option<f64>,
    pub uy: Option<f64>,
    pub uz: Option<f64>,
    /// The `[load_path]` list that scales the values (default: `load_steps`).
    pub path: Option<String>,
}

/// A prescribed total force on a group, per component; omitted components are not
/// force-controlled. Along each given component the group moves rigidly, by a displacement the
/// solve finds, such that the force it passes to the body is the given one (a loading plate).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ForceSpec {
    pub group: String,
    pub fx: Option<f64>,
    pub fy: Option<f64>,
    pub fz: Option<f64>,
    /// The `[load_path]` list that scales the force (default: `load_steps`).
    pub path: Option<String>,
}

/// A surface load: exactly one of `traction`, `pressure`, `hertz_pressure`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadSpec {
    pub group: String,
    /// Constant traction vector, `dim` components.
    pub traction: Option<Vec<f64>>,
    /// Uniform pressure: traction `-p n` with `n` the outward normal.
    pub pressure: Option<f64>,
    /// Hertzian pressure `p0 sqrt(1 - r^2 / a^2)`, `r = |x - center|`.
    pub hertz_pressure: Option<HertzSpec>,
    /// The `[load_path]` list that scales the load (default: `load_steps`).
    pub path: Option<String>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HertzSpec {
    pub p0: f64,
    pub a: f64,
    /// `dim` coordinates.
    pub center: Vec<f64>,
}

impl Case {
    /// Reads and parses a case file; paths in it become relative to the current directory.
    pub fn load(path: &Path) -> Result<Self, CaseError> {
        let text = std::fs::read_to_string(path).map_err(|source| CaseError::Io {
            path: path.to_owned(),
            source,
        })?;
        let case: Case = toml::from_str(&text).map_err(|e| CaseError::Syntax {
            path: path.to_owned(),
            message: e.to_string(),
        })?;
        let folder = path.parent().unwrap_or(Path::new(""));
        case.checked(path, folder)
    }

    /// A case given as a table of the case file's keys rather than as a file (the Python
    /// module's `Case.from_dict`), with the same checks as [`Case::load`]. `name` stands for the
    /// case file in error messages and the plot title; relative paths are relative to `folder`.
    pub fn from_table(table: toml::Table, name: &str, folder: &Path) -> Result<Self, CaseError> {
        let path = Path::new(name);
        let case = Case::deserialize(toml::Value::Table(table)).map_err(|e| CaseError::Syntax {
            path: path.to_owned(),
            message: e.to_string(),
        })?;
        case.checked(path, folder)
    }

    /// Resolves the case's paths against `folder` and checks what the schema alone cannot.
    fn checked(self, path: &Path, folder: &Path) -> Result<Self, CaseError> {
        let case = Case {
            mesh: folder.join(&self.mesh),
            output: self.output.map(|output| folder.join(output)),
            path: path.to_owned(),
            ..self
        };
        if case.bodies.is_empty() {
            return Err(case.invalid("[[body]]", "the case names no body"));
        }
        if case.solver.residual_tolerance.is_nan() || case.solver.residual_tolerance <= 0.0 {
            return Err(case.invalid("[solver]", "residual_tolerance must be positive"));
        }
        if !(case.solver.rtol > 0.0 && case.solver.rtol < 1.0) {
            return Err(case.invalid("[solver]", "rtol must be in (0, 1)"));
        }
        if case.solver.body == BodySolverKind::CgAmg
            && case.solver.rtol > case.solver.residual_tolerance
        {
            return Err(case.invalid(
                "[solver]",
                format!(
                    "rtol ({:e}) is above residual_tolerance ({:e}): a CG solve stopped at rtol \
                     would fail the residual check",
                    case.solver.rtol, case.solver.residual_tolerance
                ),
            ));
        }
        if case.solver.body == BodySolverKind::CgAmg && !CG_AMG_AVAILABLE {
            return Err(case.invalid(
                "[solver]",
                "body = \"cg-amg\" needs PETSc, and this binary was built without it \
                 (rebuild with `cargo build --release --features petsc`, as `make build` does, \
                 or use body = \"cholesky\" or \"auto\")",
            ));
        }
        // Each body's material now, not only when its problem is set up on a mesh: a study
        // learns of a Young's modulus <= 0 when it builds the case.
        for spec in &case.bodies {
            case.material(spec)?;
        }
        case.check_unique_bodies()?;
        case.check_pairs()?;
        case.check_geo_parameters()?;
        case.check_load_steps()?;
        case.check_load_path()?;
        Ok(case)
    }

    /// This case with the gmsh parameter `name` set to `value` (the refinement study's levels),
    /// checked as the case file's `geo_parameters` are: a name the script does not use is
    /// refused with the parameters it defines.
    pub fn with_geo_parameter(&self, name: &str, value: f64) -> Result<Case, CaseError> {
        let mut case = self.clone();
        case.geo_parameters.insert(name.to_string(), value);
        case.check_geo_parameters()?;
        Ok(case)
    }

    /// Whether the run meshes a `.geo` with gmsh (into `mesh.msh` in the output folder) rather
    /// than reading a `.msh`.
    pub fn generates_mesh(&self) -> bool {
        self.mesh.extension().is_some_and(|e| e == "geo")
    }

    /// The output folder a case file names, read from its raw TOML: where a run whose case
    /// does not parse as a whole can still mark its failure.
    pub fn output_folder_of(path: &Path) -> Option<PathBuf> {
        let text = std::fs::read_to_string(path).ok()?;
        let table: toml::Table = toml::from_str(&text).ok()?;
        let output = table.get("output")?.as_str()?;
        Some(path.parent().unwrap_or(Path::new("")).join(output))
    }

    /// A body listed in two `[[body]]` tables would be solved with the first and silently
    /// ignore the second.
    fn check_unique_bodies(&self) -> Result<(), CaseError> {
        for (k, body) in self.bodies.iter().enumerate() {
            if let Some(j) = self.bodies[..k].iter().position(|b| b.name == body.name) {
                return Err(self.invalid(
                    "[[body]]",
                    format!(
                        "body '{}' has two [[body]] tables (number {} and {}); give each body one",
                        body.name,
                        j + 1,
                        k + 1
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Each pair named once, of two different bodies that have `[[body]]` tables; the load
    /// steps given once, for the whole case.
    fn check_pairs(&self) -> Result<(), CaseError> {
        for (p, pair) in self.contacts.iter().enumerate() {
            let context = self.pair_context(p);
            if pair.bodies[0] == pair.bodies[1] {
                return Err(self.invalid(
                    context,
                    format!(
                        "bodies must name two different bodies, got '{}' twice (a body in \
                         contact with itself is not supported)",
                        pair.bodies[0]
                    ),
                ));
            }
            if let Some(body) =
                (pair.bodies.iter()).find(|b| !self.bodies.iter().any(|s| &s.name == *b))
            {
                let known: Vec<&str> = self.bodies.iter().map(|b| b.name.as_str()).collect();
                return Err(self.invalid(
                    context,
                    format!(
                        "body '{body}' has no [[body]] table (materials and supports are \
                         needed; the case's bodies: {})",
                        known.join(", ")
                    ),
                ));
            }
            let allowed = |c: char| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.');
            if pair.name.is_empty() || !pair.name.chars().all(allowed) {
                return Err(self.invalid(
                    format!("{context} name"),
                    format!(
                        "'{}': a pair's name goes into the file names \
                         force_displacement_<name>.png and the column names \
                         <name>.<column> of force_displacement.csv, so it must be made of \
                         letters, digits, '_', '-' and '.' (without a `name` key it is \
                         BODY1-BODY2: give the pair a `name` if a body's name has other \
                         characters)",
                        pair.name.escape_debug()
                    ),
                ));
            }
            fn sides(spec: &ContactSpec) -> [(&str, &str); 2] {
                let mut sides = [
                    (spec.bodies[0].as_str(), spec.surfaces[0].as_str()),
                    (spec.bodies[1].as_str(), spec.surfaces[1].as_str()),
                ];
                sides.sort();
                sides
            }
            if let Some(q) =
                (self.contacts[..p].iter()).position(|other| sides(other) == sides(pair))
            {
                return Err(self.invalid(
                    context,
                    format!(
                        "pairs {} ('{}') and {} ('{}') are the same two surfaces ('{}' of '{}' \
                         and '{}' of '{}'); list each pair once (two copies would share its \
                         force between them)",
                        q + 1,
                        self.contacts[q].name,
                        p + 1,
                        pair.name,
                        pair.surfaces[0],
                        pair.bodies[0],
                        pair.surfaces[1],
                        pair.bodies[1]
                    ),
                ));
            }
            if let Some(q) = self.contacts[..p]
                .iter()
                .position(|other| other.name == pair.name)
            {
                return Err(self.invalid(
                    context,
                    format!(
                        "pairs {} and {} are both named '{}'; give each pair its own name \
                         (the `name` key), or do not list a pair twice",
                        q + 1,
                        p + 1,
                        pair.name
                    ),
                ));
            }
            if pair.load_steps.is_some() && (self.contacts.len() > 1 || self.load_steps.is_some()) {
                return Err(self.invalid(
                    format!("{context} load_steps"),
                    "the load steps are the whole case's: give them once, as `load_steps = \
                     [...]` at the top of the case file (before the first table)",
                ));
            }
        }
        if self.contacts.is_empty() && self.load_steps.is_some() {
            return Err(self.invalid(
                "load_steps",
                "load steps scale a contact solve, and the case has no [contact] table",
            ));
        }
        Ok(())
    }

    /// How messages name pair `p`: `[contact]` for a case of one pair, `[[contact]] 'NAME'`.
    pub fn pair_context(&self, p: usize) -> String {
        match self.contacts.len() {
            1 => "[contact]".to_string(),
            _ => format!("[[contact]] '{}' (pair {})", self.contacts[p].name, p + 1),
        }
    }

    /// `geo_parameters` must be finite, belong to a `.geo` mesh and be names the script uses:
    /// gmsh ignores a `-setnumber` the script never reads and meshes its defaults.
    fn check_geo_parameters(&self) -> Result<(), CaseError> {
        if self.geo_parameters.is_empty() {
            return Ok(());
        }
        if !self.generates_mesh() {
            return Err(self.invalid(
                "geo_parameters",
                format!(
                    "they are gmsh parameters of a .geo script, but the mesh {} is not a .geo: \
                     they would be ignored; remove them or name the .geo",
                    self.mesh.display()
                ),
            ));
        }
        check_geo_parameters(&self.mesh, &self.geo_parameters)
            .map_err(|e| self.invalid(e.key, e.message))
    }

    /// Each load step is a whole contact solve, and its record goes into the summary: a list
    /// longer than [`MAX_LOAD_STEPS`] is a mistake (it once took minutes and wrote a 490 MB
    /// summary), not a load history. Each factor is finite and within [`MAX_MAGNITUDE`].
    fn check_load_steps(&self) -> Result<(), CaseError> {
        let key = match self.load_steps {
            Some(_) => "load_steps",
            None => "[contact] load_steps",
        };
        let Some(steps) = (self.load_steps.as_ref())
            .or_else(|| self.contacts.first().and_then(|c| c.load_steps.as_ref()))
        else {
            return Ok(());
        };
        let count = steps.len();
        if count > MAX_LOAD_STEPS {
            return Err(self.invalid(
                key,
                format!(
                    "{count} load steps; at most {MAX_LOAD_STEPS} are allowed (each step is a \
                     whole contact solve)"
                ),
            ));
        }
        if steps.is_empty() || steps.iter().any(|&f| !in_range(f)) {
            return Err(self.invalid(
                key,
                format!(
                    "expected a non-empty list of finite factors {}, got {}",
                    magnitude_range(),
                    match steps.iter().find(|&&f| !in_range(f)) {
                        Some(f) => format!("{f:e}"),
                        None => "an empty list".to_string(),
                    }
                ),
            ));
        }
        Ok(())
    }

    /// `[load_path]`: named non-empty lists of finite factors, of one length, which
    /// `load_steps` (if given) shares, in a contact case; and each entry's `path` the name of
    /// one of them, on a body in contact.
    fn check_load_path(&self) -> Result<(), CaseError> {
        if let Some(paths) = &self.load_path {
            if paths.is_empty() {
                return Err(self.invalid(
                    "[load_path]",
                    "the table names no path; give one list of factors per path, e.g. \
                     press = [0.5, 1.0]",
                ));
            }
            if self.contacts.is_empty() {
                return Err(self.invalid(
                    "[load_path]",
                    "load paths scale the load steps of a contact solve, and the case has no \
                     [contact] table (a body solved alone is solved once, with every load at \
                     its full value)",
                ));
            }
            if paths.contains_key("load_steps") {
                return Err(self.invalid(
                    "[load_path] load_steps",
                    "a path named load_steps: a `load_steps = [...]` line after `[load_path]` \
                     belongs to that table; write load_steps before the first table (or name \
                     the path otherwise)",
                ));
            }
            for (name, factors) in paths {
                let key = format!("[load_path] {name}");
                let allowed = |c: char| c.is_ascii_alphanumeric() || c == '_' || c == '-';
                if name.is_empty() || !name.chars().all(allowed) {
                    return Err(self.invalid(
                        format!("[load_path] '{name}'"),
                        "a path's name goes into the column path_<name> of \
                         force_displacement.csv: use letters, digits, '_' and '-' only",
                    ));
                }
                if factors.len() > MAX_LOAD_STEPS {
                    return Err(self.invalid(
                        key,
                        format!(
                            "{} factors; at most {MAX_LOAD_STEPS} load steps are allowed (each \
                             step is a whole contact solve)",
                            factors.len()
                        ),
                    ));
                }
                if factors.is_empty() || factors.iter().any(|&f| !in_range(f)) {
                    return Err(self.invalid(
                        key,
                        format!(
                            "expected a non-empty list of finite factors {}, got {}",
                            magnitude_range(),
                            match factors.iter().find(|&&f| !in_range(f)) {
                                Some(f) => format!("{f:e}"),
                                None => "an empty list".to_string(),
                            }
                        ),
                    ));
                }
            }
            let (first, steps) = paths.iter().next().expect("checked non-empty");
            if let Some((other, factors)) = paths.iter().find(|(_, f)| f.len() != steps.len()) {
                return Err(self.invalid(
                    "[load_path]",
                    format!(
                        "'{first}' has {} factors and '{other}' {}: each path gives one factor \
                         per load step, so every list has the same length",
                        steps.len(),
                        factors.len()
                    ),
                ));
            }
            if let Some(given) = self.given_load_steps().filter(|l| l.len() != steps.len()) {
                let key = match self.load_steps {
                    Some(_) => "load_steps",
                    None => "[contact] load_steps",
                };
                return Err(self.invalid(
                    key,
                    format!(
                        "{} factors, and the [load_path] lists have {}: with a [load_path], \
                         load_steps gives the factor of the entries without `path` at each of \
                         its steps, so it has the same length (or leave it out: those entries \
                         then keep the factor 1)",
                        given.len(),
                        steps.len()
                    ),
                ));
            }
        }
        for spec in &self.bodies {
            let entries = (spec.dirichlet.iter())
                .map(|d| ("Dirichlet condition", &d.group, &d.path))
                .chain(spec.forces.iter().map(|f| ("force", &f.group, &f.path)))
                .chain(spec.loads.iter().map(|l| ("load", &l.group, &l.path)));
            for (kind, group, path) in entries {
                let Some(path) = path else { continue };
                let context = format!("body '{}', {kind} on '{group}', path", spec.name);
                let Some(paths) = &self.load_path else {
                    return Err(self.invalid(
                        context,
                        format!(
                            "'{path}' names a load path, but the case has no [load_path] table; \
                             add one with a list of factors named '{path}' (one per load step), \
                             or remove `path`"
                        ),
                    ));
                };
                if !paths.contains_key(path) {
                    let known: Vec<&str> = paths.keys().map(String::as_str).collect();
                    return Err(self.invalid(
                        context,
                        format!(
                            "the [load_path] table has no path '{path}' (its paths: {})",
                            known.join(", ")
                        ),
                    ));
                }
                if !(self.contacts.iter()).any(|c| c.bodies.contains(&spec.name)) {
                    return Err(self.invalid(
                        context,
                        format!(
                            "body '{}' is in no contact pair: it is solved alone, once, with \
                             every load at its full value; a load path scales the load steps \
                             of a contact solve",
                            spec.name
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Builds the problem of every body, so that a wrong group, material, load or support of
    /// any body is an error before anything is solved or written.
    pub fn check_bodies(&self, mesh: &Mesh) -> Result<(), CaseError> {
        for spec in &self.bodies {
            let body = self.body_mesh(mesh, spec)?;
            let groups = (spec.dirichlet.iter().map(|d| &d.group))
                .chain(spec.forces.iter().map(|f| &f.group));
            for group in groups.chain(spec.loads.iter().map(|l| &l.group)) {
                let context = format!("body '{}'", spec.name);
                self.check_unambiguous(mesh, &context, group)?;
                self.check_group_dimension(mesh, body, &context, group)?;
            }
            self.elastic_problem(body, spec)?;
        }
        for (p, contact) in self.contacts.iter().enumerate() {
            for group in &contact.surfaces {
                let context = format!("{} surfaces", self.pair_context(p));
                self.check_unambiguous(mesh, &context, group)?;
            }
        }
        Ok(())
    }

    /// With `export_matrices`, body and boundary group names go into the file names
    /// `matrices/<body>_stiffness.mtx` and `matrices/<body>__<group>_mass.mtx`: a `/` (or `\`)
    /// there names a folder, or one outside the output folder (`../..`), so the export would
    /// fail after the solve or write where it must not. Checked before anything is solved.
    pub fn check_export_names(&self, mesh: &Mesh) -> Result<(), CaseError> {
        let bad = |name: &str| name.contains(['/', '\\']);
        for spec in &self.bodies {
            let body = self.body_mesh(mesh, spec)?;
            let groups = spec.dirichlet.iter().map(|d| &d.group);
            let mut groups = groups.chain(spec.loads.iter().map(|l| &l.group));
            let (what, file) = if bad(&spec.name) {
                (
                    "its name".to_string(),
                    format!("{}_stiffness.mtx", spec.name),
                )
            } else if let Some(group) = groups.find(|g| bad(g) && body.boundary_group(g).is_some())
            {
                (
                    format!("the name of group '{group}'"),
                    format!("{}__{group}_mass.mtx", spec.name),
                )
            } else {
                continue;
            };
            return Err(self.invalid(
                format!("body '{}', export_matrices", spec.name),
                format!(
                    "{what} goes into the file name matrices/{file}, where a '/' or '\\' would \
                     name a folder; rename the physical group or do not export the matrices"
                ),
            ));
        }
        Ok(())
    }

    /// A group that is not on the body but is a physical group of another dimension than
    /// boundary groups and points (a curve of a 3D mesh, whose edges the reader does not keep, or
    /// a body) would be reported as missing: say what it is and what is needed instead.
    fn check_group_dimension(
        &self,
        mesh: &Mesh,
        body: &BodyMesh,
        context: &str,
        group: &str,
    ) -> Result<(), CaseError> {
        if body.group_nodes(group).is_some() {
            return Ok(());
        }
        let kind = ["point", "curve", "surface", "volume"];
        let Some(found) = mesh
            .physical_groups
            .iter()
            .find(|g| g.name == group && g.dim != 0 && g.dim + 1 != mesh.dim)
        else {
            return Ok(());
        };
        let what = if found.dim == mesh.dim {
            "a body, not a boundary group".to_string()
        } else {
            format!(
                "a {} of a {}D body, which is not a boundary group",
                kind[found.dim], mesh.dim
            )
        };
        Err(self.invalid(
            format!("{context}, group '{group}'"),
            format!(
                "'{group}' is a physical {} of {}: {what}; Dirichlet conditions and loads act on \
                 boundary groups, the physical {}s on the body's boundary (Dirichlet conditions \
                 also on physical points)",
                kind[found.dim],
                mesh.path.display(),
                kind[mesh.dim - 1]
            ),
        ))
    }

    /// Unnamed physical groups go by their tag, so an unnamed Physical Curve(1) and Physical
    /// Point(1) are both '1': a case naming '1' would silently get one of them.
    fn check_unambiguous(&self, mesh: &Mesh, context: &str, group: &str) -> Result<(), CaseError> {
        let groups = mesh.groups_below_bodies(group);
        if groups.len() < 2 {
            return Ok(());
        }
        let listed: Vec<String> = groups
            .iter()
            .map(|g| {
                format!(
                    "dimension {} tag {}{}",
                    g.dim,
                    g.tag,
                    if g.named { "" } else { " (unnamed)" }
                )
            })
            .collect();
        Err(self.invalid(
            format!("{context}, group '{group}'"),
            format!(
                "'{group}' is ambiguous in {}: it names the physical groups {}; give them \
                 distinct names in the .geo (e.g. Physical Curve(\"base\") = {{...}})",
                mesh.path.display(),
                listed.join(" and ")
            ),
        ))
    }

    fn invalid(&self, context: impl Into<String>, message: impl Into<String>) -> CaseError {
        CaseError::Invalid {
            path: self.path.clone(),
            context: context.into(),
            message: message.into(),
        }
    }

    /// The mesh body named by `spec`.
    pub fn body_mesh<'m>(
        &self,
        mesh: &'m Mesh,
        spec: &BodySpec,
    ) -> Result<&'m BodyMesh, CaseError> {
        mesh.body(&spec.name).ok_or_else(|| CaseError::UnknownBody {
            path: self.path.clone(),
            body: spec.name.clone(),
            mesh: mesh.path.clone(),
            available: mesh.bodies.iter().map(|b| b.name.clone()).collect(),
        })
    }

    /// The elastic problem of one body: material, Dirichlet conditions, forces, loads, body
    /// force. A body in contact may be left free to move by its supports
    /// (`ElasticProblem::floating`); any other must be held.
    pub fn elastic_problem<'m>(
        &self,
        body: &'m BodyMesh,
        spec: &BodySpec,
    ) -> Result<ElasticProblem<'m>, CaseError> {
        let in_contact = (self.contacts.iter()).any(|c| c.bodies.contains(&spec.name));
        let values = BodyValues {
            case: self,
            body: &spec.name,
            dim: body.dim,
            range: magnitude_range(),
        };
        let material = self.material(spec)?;
        values.check_dirichlet_values(&spec.dirichlet)?;
        let dirichlet = spec
            .dirichlet
            .iter()
            .map(|d| DirichletCondition {
                group: d.group.clone(),
                components: [d.ux, d.uy, d.uz],
                path: d.path.clone(),
            })
            .collect();
        let mut loads = Vec::new();
        for l in &spec.loads {
            loads.push(values.load_condition(body, l)?);
        }
        let body_force = spec
            .body_force
            .as_deref()
            .map(|b| values.vector(b, "body_force"))
            .transpose()?;
        values.check_force_values(&spec.forces)?;
        let forces = spec
            .forces
            .iter()
            .map(|f| ForceCondition {
                group: f.group.clone(),
                components: [f.fx, f.fy, f.fz],
                path: f.path.clone(),
            })
            .collect();
        let problem = match in_contact {
            true => ElasticProblem::floating,
            false => ElasticProblem::with_forces,
        };
        problem(body, material, dirichlet, forces, loads, body_force).map_err(|source| {
            CaseError::Problem {
                path: self.path.clone(),
                source,
            }
        })
    }

    /// The body's material, its Young's modulus also within the range [`MAX_MAGNITUDE`] allows.
    fn material(&self, spec: &BodySpec) -> Result<Material, CaseError> {
        let material =
            Material::new(spec.youngs_modulus, spec.poisson_ratio).map_err(|source| {
                CaseError::Material {
                    path: self.path.clone(),
                    body: spec.name.clone(),
                    source,
                }
            })?;
        let modulus = spec.youngs_modulus;
        if !(1.0 / MAX_MAGNITUDE..=MAX_MAGNITUDE).contains(&modulus) {
            return Err(self.invalid(
                format!("body '{}', youngs_modulus", spec.name),
                format!(
                    "expected a value from {:e} to {MAX_MAGNITUDE:e} (MAX_MAGNITUDE in \
                     src/case/schema.rs says why), got {modulus:e}",
                    1.0 / MAX_MAGNITUDE
                ),
            ));
        }
        Ok(material)
    }

    /// The load factors of the contact solve (default: one step at 1); with a `[load_path]`,
    /// those of the entries without `path` (default: 1 at each of its steps).
    pub fn load_steps(&self) -> Vec<f64> {
        let steps = match &self.load_path {
            Some(paths) => paths.values().next().map_or(1, Vec::len),
            None => 1,
        };
        (self.given_load_steps().cloned()).unwrap_or_else(|| vec![1.0; steps])
    }

    /// `load_steps` as the case gives them, at the top or in its `[contact]` table.
    fn given_load_steps(&self) -> Option<&Vec<f64>> {
        (self.load_steps.as_ref())
            .or_else(|| self.contacts.first().and_then(|c| c.load_steps.as_ref()))
    }

    /// The factors of each load step: [`Self::load_steps`] for the entries without `path`,
    /// and each `[load_path]` list's factor at that step for the entries that name it.
    pub fn step_factors(&self) -> Vec<StepFactors> {
        let paths = self.load_path.clone().unwrap_or_default();
        (self.load_steps().into_iter().enumerate())
            .map(|(k, default)| StepFactors {
                default,
                paths: (paths.iter())
                    .map(|(name, factors)| (name.clone(), factors[k]))
                    .collect(),
            })
            .collect()
    }

    /// The contact problem of each pair, in the case's order, with its primary body chosen
    /// (empty without contact).
    pub fn contact_problems<'m>(
        &self,
        mesh: &'m Mesh,
    ) -> Result<Vec<ContactProblem<'m>>, CaseError> {
        let mut problems = Vec::with_capacity(self.contacts.len());
        for (p, spec) in self.contacts.iter().enumerate() {
            let context = self.pair_context(p);
            spec.settings
                .validate()
                .map_err(|e| self.invalid(&context, e.to_string()))?;
            let side = |body: &str, surface: &str| -> Result<ContactSide<'m>, CaseError> {
                let body_spec = (self.bodies.iter().find(|b| b.name == body))
                    .expect("check_pairs: every pair's bodies have [[body]] tables");
                let body_mesh = self.body_mesh(mesh, body_spec)?;
                let surface = ContactSurface::new(body_mesh, surface)
                    .map_err(|e| self.invalid(&context, e.to_string()))?;
                Ok((self.elastic_problem(body_mesh, body_spec)?, surface))
            };
            let sides = [
                side(&spec.bodies[0], &spec.surfaces[0])?,
                side(&spec.bodies[1], &spec.surfaces[1])?,
            ];
            let problem = ContactProblem::new(sides, &spec.primary, spec.settings)
                .map_err(|message| self.invalid(&context, message))?;
            problems.push(problem);
        }
        Ok(problems)
    }
}

/// The checks of one body's values, whose messages name the case file and the body.
struct BodyValues<'a> {
    case: &'a Case,
    body: &'a str,
    dim: usize,
    /// [`magnitude_range`], for messages.
    range: String,
}

impl BodyValues<'_> {
    fn invalid(&self, what: &str, message: impl Into<String>) -> CaseError {
        self.case
            .invalid(format!("body '{}', {what}", self.body), message)
    }

    fn finite(&self, value: f64, what: &str) -> Result<f64, CaseError> {
        if in_range(value) {
            Ok(value)
        } else {
            Err(self.invalid(
                what,
                format!("expected a finite number {}, got {value:e}", self.range),
            ))
        }
    }

    /// `v` as a 3-vector, its components past the mesh's dimension zero.
    fn vector(&self, v: &[f64], what: &str) -> Result<[f64; 3], CaseError> {
        let dim = self.dim;
        if let Some(bad) = v.iter().find(|&&x| !in_range(x)) {
            return Err(self.invalid(
                what,
                format!(
                    "expected finite components {}, got {bad:e} in {v:?}",
                    self.range
                ),
            ));
        }
        if v.len() != dim {
            return Err(self.invalid(
                what,
                format!(
                    "expected {dim} components (the mesh is {dim}D), got {}",
                    v.len()
                ),
            ));
        }
        let mut out = [0.0; 3];
        out[..dim].copy_from_slice(v);
        Ok(out)
    }

    fn check_dirichlet_values(&self, dirichlet: &[DirichletSpec]) -> Result<(), CaseError> {
        for d in dirichlet {
            for (key, value) in ["ux", "uy", "uz"].iter().zip([d.ux, d.uy, d.uz]) {
                if let Some(value) = value.filter(|&v| !in_range(v)) {
                    return Err(self.invalid(
                        &format!("Dirichlet condition on '{}', {key}", d.group),
                        format!("expected a finite number {}, got {value:e}", self.range),
                    ));
                }
            }
        }
        Ok(())
    }

    fn check_force_values(&self, forces: &[ForceSpec]) -> Result<(), CaseError> {
        for f in forces {
            for (key, value) in ["fx", "fy", "fz"].iter().zip([f.fx, f.fy, f.fz]) {
                if let Some(value) = value.filter(|&v| !in_range(v)) {
                    return Err(self.invalid(
                        &format!("force on '{}', {key}", f.group),
                        format!("expected a finite number {}, got {value:e}", self.range),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The load `l` on `body`, its group checked to be one a load of its kind can act on.
    fn load_condition(&self, body: &BodyMesh, l: &LoadSpec) -> Result<LoadCondition, CaseError> {
        let what = format!("load on '{}'", l.group);
        if body.point_groups.contains_key(&l.group) && body.boundary_group(&l.group).is_none() {
            return Err(self.invalid(
                &what,
                format!(
                    "'{}' is a group of points; a load needs a boundary group (a physical {} \
                     of this body) to act on",
                    l.group,
                    if self.dim == 2 { "curve" } else { "surface" }
                ),
            ));
        }
        // A pressure pushes along the outward normal of each facet's cell; a facet between
        // two cells has two, and the pushes of the facets of an embedded line or surface
        // cancel (the run once succeeded with zero reaction). A traction vector does not
        // depend on the side: inside the body it is a line (surface) force, and stays.
        if l.traction.is_none()
            && let Some(group) = body.boundary_group(&l.group)
            && !group.is_boundary()
        {
            return Err(self.invalid(
                &what,
                format!(
                    "'{}' lies inside the body: {} of its facets (gmsh element {}{}) are \
                     shared by two cells of '{}', where a pressure has no outward side; a \
                     pressure needs a boundary group, whose facets lie on one cell only",
                    l.group,
                    group.interior_facets.len(),
                    group.interior_facets[0],
                    if group.interior_facets.len() > 1 {
                        " and others"
                    } else {
                        ""
                    },
                    self.body
                ),
            ));
        }
        Ok(LoadCondition {
            group: l.group.clone(),
            load: self.surface_load(l, &what)?,
            path: l.path.clone(),
        })
    }

    fn surface_load(&self, l: &LoadSpec, what: &str) -> Result<SurfaceLoad, CaseError> {
        Ok(match (&l.traction, l.pressure, &l.hertz_pressure) {
            (Some(t), None, None) => SurfaceLoad::Traction(self.vector(t, what)?),
            (None, Some(p), None) => SurfaceLoad::Pressure(PressureField::Uniform(
                self.finite(p, &format!("{what}, pressure"))?,
            )),
            (None, None, Some(h)) => {
                self.finite(h.p0, &format!("{what}, hertz_pressure.p0"))?;
                if !(h.a > 0.0 && in_range(h.a)) {
                    return Err(self.invalid(
                        what,
                        format!(
                            "hertz_pressure.a must be positive and {}, got {:e}",
                            self.range, h.a
                        ),
                    ));
                }
                SurfaceLoad::Pressure(PressureField::Hertz {
                    p0: h.p0,
                    a: h.a,
                    center: self.vector(&h.center, &format!("{what}, hertz_pressure.center"))?,
                })
            }
            _ => {
                return Err(self.invalid(
                    what,
                    "give exactly one of traction, pressure, hertz_pressure",
                ));
            }
        })
    }
}

/// Whether `value` is finite and within [`MAX_MAGNITUDE`].
fn in_range(value: f64) -> bool {
    value.abs() <= MAX_MAGNITUDE
}

/// The accepted range of [`in_range`], for messages.
fn magnitude_range() -> String {
    format!("of magnitude at most {MAX_MAGNITUDE:e} (MAX_MAGNITUDE in src/case/schema.rs says why)")
}

/// A gmsh parameter that a `.geo` script cannot take: its key (`geo_parameters.NAME`) and why.
#[derive(Debug, Clone, PartialEq)]
pub struct GeoParameterError {
    pub key: String,
    pub message: String,
}

impl std::fmt::Display for GeoParameterError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.key, self.message)
    }
}

impl std::error::Error for GeoParameterError {}

/// The check of gmsh parameters (`-setnumber NAME VALUE`) for the script `geo`, wherever they
/// are given (a case's `geo_parameters`, the Python module's `Mesh.from_geo`): each finite, and
/// a name the script uses, since gmsh ignores a `-setnumber` the script never reads and meshes
/// its defaults. A script that cannot be read passes (gmsh's own error says so when it meshes).
pub fn check_geo_parameters(
    geo: &Path,
    parameters: &BTreeMap<String, f64>,
) -> Result<(), GeoParameterError> {
    for (name, value) in parameters {
        if !value.is_finite() {
            return Err(GeoParameterError {
                key: format!("geo_parameters.{name}"),
                message: format!("expected a finite number, got {value}"),
            });
        }
    }
    let Ok(script) = std::fs::read_to_string(geo) else {
        return Ok(());
    };
    let used = geo_identifiers(&script);
    for name in parameters.keys() {
        if !used.contains(name.as_str()) {
            let defined = geo_defined_constants(&script);
            return Err(GeoParameterError {
                key: format!("geo_parameters.{name}"),
                message: format!(
                    "{} does not use a parameter '{name}', so gmsh would ignore it \
                     (the parameters it defines: {})",
                    geo.display(),
                    if defined.is_empty() {
                        "none".to_string()
                    } else {
                        defined.join(", ")
                    }
                ),
            });
        }
    }
    Ok(())
}

/// The identifiers a gmsh script mentions outside `//` comments: a parameter the script never
/// mentions cannot change its mesh.
fn geo_identifiers(script: &str) -> std::collections::BTreeSet<&str> {
    script
        .lines()
        .map(|line| line.split("//").next().unwrap_or(""))
        .flat_map(|line| line.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_')))
        .filter(|word| word.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_'))
        .collect()
}

/// The names a gmsh script declares in `DefineConstant[ name = {...}, ... ]`, for messages.
fn geo_defined_constants(script: &str) -> Vec<String> {
    let mut names = Vec::new();
    let mut rest = script;
    while let Some(start) = rest.find("DefineConstant[") {
        rest = &rest[start + "DefineConstant[".len()..];
        let block = rest.split(']').next().unwrap_or("");
        for (k, _) in block.match_indices("= {") {
            let before = block[..k].trim_end();
            let name: String = before
                .chars()
                .rev()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect::<Vec<_>>()
                .into_iter()
                .rev()
                .collect();
            if !name.is_empty() {
                names.push(name);
            }
        }
    }
    names
}
