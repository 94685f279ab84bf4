//! The case files of the tests, built as typed values and written as TOML: the structs mirror
//! the tables of `docs/case-file.md` (`src/case/schema.rs` reads them), so a test names what
//! its case changes instead of editing text. A field left `None` or empty is not written, and
//! the code's default applies.

use std::path::{Path, PathBuf};

use serde::Serialize;

use super::{fixture, write_case};

/// A case file: the top-level keys, then the `[solver]`, `[contact]` and `[[body]]` tables.
#[derive(Debug, Clone, Serialize)]
pub struct CaseFile {
    pub mesh: PathBuf,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub output: Option<String>,
    #[serde(skip_serializing_if = "toml::Table::is_empty")]
    pub geo_parameters: toml::Table,
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub export_matrices: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub solver: Option<Solver>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contact: Option<Contact>,
    #[serde(rename = "body")]
    pub bodies: Vec<Body>,
}

/// The `[solver]` table: how each body's linear system is solved.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Solver {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub body: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rtol: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub residual_tolerance: Option<f64>,
}

/// The `[contact]` table: the two bodies, their candidate surfaces, and any of the settings of
/// `ContactSettings` by name (`settings`), written as given so that a test can also name a
/// value out of range.
#[derive(Debug, Clone, Serialize)]
pub struct Contact {
    pub bodies: [String; 2],
    pub surfaces: [String; 2],
    #[serde(skip_serializing_if = "Option::is_none")]
    pub primary: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub load_steps: Option<Vec<f64>>,
    #[serde(flatten)]
    pub settings: toml::Table,
}

/// A `[[body]]` table.
#[derive(Debug, Clone, Serialize)]
pub struct Body {
    pub name: String,
    pub youngs_modulus: f64,
    pub poisson_ratio: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub body_force: Option<Vec<f64>>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub dirichlet: Vec<Dirichlet>,
    #[serde(rename = "force", skip_serializing_if = "Vec::is_empty")]
    pub forces: Vec<Force>,
    #[serde(rename = "load", skip_serializing_if = "Vec::is_empty")]
    pub loads: Vec<Load>,
}

/// A `[[body.force]]` table: the total force on `group` along the given components, along
/// which the group moves rigidly.
#[derive(Debug, Clone, Serialize)]
pub struct Force {
    pub group: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fx: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fy: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fz: Option<f64>,
}

impl Force {
    /// The force `value` along the vertical axis of a `dim`-dimensional mesh (y in 2D, z in 3D).
    pub fn vertical(group: &str, dim: usize, value: f64) -> Self {
        let mut force = Self {
            group: group.to_string(),
            fx: None,
            fy: None,
            fz: None,
        };
        match dim {
            2 => force.fy = Some(value),
            _ => force.fz = Some(value),
        }
        force
    }
}

/// A `[[body.dirichlet]]` table: the prescribed components on `group`, the others free.
#[derive(Debug, Clone, Serialize)]
pub struct Dirichlet {
    pub group: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ux: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub uy: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub uz: Option<f64>,
}

/// A `[[body.load]]` table: a valid load sets exactly one of its three kinds.
#[derive(Debug, Clone, Serialize)]
pub struct Load {
    pub group: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub traction: Option<Vec<f64>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pressure: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hertz_pressure: Option<HertzPressure>,
}

/// The pressure `p0 sqrt(1 - r^2 / a^2)`, `r = |x - center|`.
#[derive(Debug, Clone, Serialize)]
pub struct HertzPressure {
    pub p0: f64,
    pub a: f64,
    pub center: Vec<f64>,
}

impl CaseFile {
    /// A case on `mesh` writing into `out` beside the case file, with no body yet.
    pub fn new(mesh: impl Into<PathBuf>) -> Self {
        Self {
            mesh: mesh.into(),
            output: Some("out".to_string()),
            geo_parameters: toml::Table::new(),
            export_matrices: false,
            solver: None,
            contact: None,
            bodies: Vec::new(),
        }
    }

    /// A case on the committed mesh `tests/fixtures/{name}`.
    pub fn on_fixture(name: &str) -> Self {
        Self::new(fixture(name))
    }

    pub fn output(mut self, folder: &str) -> Self {
        self.output = Some(folder.to_string());
        self
    }

    /// No `output` key: the run needs `--output`.
    pub fn without_output(mut self) -> Self {
        self.output = None;
        self
    }

    /// A gmsh `-setnumber` parameter of a `.geo` mesh, e.g. `("level", 1)`.
    pub fn geo_parameter(mut self, name: &str, value: impl Into<toml::Value>) -> Self {
        self.geo_parameters.insert(name.to_string(), value.into());
        self
    }

    pub fn export_matrices(mut self) -> Self {
        self.export_matrices = true;
        self
    }

    /// `[solver] body`: `"auto"`, `"cholesky"` or `"cg-amg"`.
    pub fn body_solver(mut self, kind: &str) -> Self {
        self.solver.get_or_insert_default().body = Some(kind.to_string());
        self
    }

    pub fn rtol(mut self, rtol: f64) -> Self {
        self.solver.get_or_insert_default().rtol = Some(rtol);
        self
    }

    pub fn residual_tolerance(mut self, tolerance: f64) -> Self {
        self.solver.get_or_insert_default().residual_tolerance = Some(tolerance);
        self
    }

    pub fn body(mut self, body: Body) -> Self {
        self.bodies.push(body);
        self
    }

    /// `bodies` in contact on their candidate `surfaces`, in the same order.
    pub fn contact(mut self, bodies: [&str; 2], surfaces: [&str; 2]) -> Self {
        self.contact = Some(Contact {
            bodies: bodies.map(str::to_string),
            surfaces: surfaces.map(str::to_string),
            primary: None,
            load_steps: None,
            settings: toml::Table::new(),
        });
        self
    }

    /// Other candidate contact surfaces for the two bodies, in their order.
    pub fn contact_surfaces(mut self, surfaces: [&str; 2]) -> Self {
        self.contact_table().surfaces = surfaces.map(str::to_string);
        self
    }

    /// The body that carries the multiplier: `"auto"` or one of the two.
    pub fn primary(mut self, body: &str) -> Self {
        self.contact_table().primary = Some(body.to_string());
        self
    }

    pub fn load_steps(mut self, factors: &[f64]) -> Self {
        self.contact_table().load_steps = Some(factors.to_vec());
        self
    }

    /// A setting of the `[contact]` table by its key, e.g. `("formulation", "tied")`.
    pub fn contact_setting(mut self, key: &str, value: impl Into<toml::Value>) -> Self {
        self.contact_table()
            .settings
            .insert(key.to_string(), value.into());
        self
    }

    /// The case with `change` applied to the body `name`.
    pub fn with_body(mut self, name: &str, change: impl FnOnce(Body) -> Body) -> Self {
        let body = self.body_named(name);
        *body = change(body.clone());
        self
    }

    /// One more Dirichlet condition on the body `name`.
    pub fn support(mut self, name: &str, condition: Dirichlet) -> Self {
        self.body_named(name).dirichlet.push(condition);
        self
    }

    /// The case with `change` applied to the Dirichlet condition on `group` of the body `name`.
    pub fn with_support(
        mut self,
        name: &str,
        group: &str,
        change: impl FnOnce(Dirichlet) -> Dirichlet,
    ) -> Self {
        let condition = (self.body_named(name).dirichlet.iter_mut())
            .find(|d| d.group == group)
            .unwrap_or_else(|| panic!("body '{name}' has no Dirichlet condition on '{group}'"));
        *condition = change(condition.clone());
        self
    }

    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("a case serializes to TOML")
    }

    /// The case written to `case.toml` in a fresh temporary folder (see [`write_case`]).
    pub fn write(&self) -> (tempfile::TempDir, PathBuf) {
        write_case(&self.to_toml())
    }

    /// The case written to `path`.
    pub fn write_to(&self, path: &Path) {
        std::fs::write(path, self.to_toml()).expect("write the case file");
    }

    fn contact_table(&mut self) -> &mut Contact {
        self.contact
            .as_mut()
            .expect("the case has a [contact] table")
    }

    fn body_named(&mut self, name: &str) -> &mut Body {
        (self.bodies.iter_mut())
            .find(|b| b.name == name)
            .unwrap_or_else(|| panic!("the case has no body '{name}'"))
    }
}

impl Body {
    /// The body `name` (its physical group) of the given material, without supports or loads.
    pub fn new(name: &str, youngs_modulus: f64, poisson_ratio: f64) -> Self {
        Self {
            name: name.to_string(),
            youngs_modulus,
            poisson_ratio,
            body_force: None,
            dirichlet: Vec::new(),
            forces: Vec::new(),
            loads: Vec::new(),
        }
    }

    pub fn dirichlet(mut self, condition: Dirichlet) -> Self {
        self.dirichlet.push(condition);
        self
    }

    pub fn load(mut self, load: Load) -> Self {
        self.loads.push(load);
        self
    }

    pub fn force(mut self, force: Force) -> Self {
        self.forces.push(force);
        self
    }

    /// Force per unit volume (per unit area in 2D).
    pub fn body_force(mut self, force: &[f64]) -> Self {
        self.body_force = Some(force.to_vec());
        self
    }
}

impl Dirichlet {
    /// A condition on `group` that prescribes nothing yet.
    pub fn on(group: &str) -> Self {
        Self {
            group: group.to_string(),
            ux: None,
            uy: None,
            uz: None,
        }
    }

    /// Every component of a `dim`-dimensional mesh held at zero.
    pub fn clamped(group: &str, dim: usize) -> Self {
        Self::on(group).lateral(dim, 0.0).vertical(dim, 0.0)
    }

    /// The tangential components held on `{body}_sides`: the body slides along them.
    pub fn rollers(body: &str, dim: usize) -> Self {
        Self::on(&format!("{body}_sides")).lateral(dim, 0.0)
    }

    pub fn ux(mut self, value: f64) -> Self {
        self.ux = Some(value);
        self
    }

    pub fn uy(mut self, value: f64) -> Self {
        self.uy = Some(value);
        self
    }

    pub fn uz(mut self, value: f64) -> Self {
        self.uz = Some(value);
        self
    }

    /// The last component of a `dim`-dimensional mesh: `uy` in 2D, `uz` in 3D.
    pub fn vertical(self, dim: usize, value: f64) -> Self {
        if dim == 2 {
            self.uy(value)
        } else {
            self.uz(value)
        }
    }

    /// The components but the last: `ux` in 2D, `ux` and `uy` in 3D.
    pub fn lateral(self, dim: usize, value: f64) -> Self {
        if dim == 2 {
            self.ux(value)
        } else {
            self.ux(value).uy(value)
        }
    }
}

impl Load {
    fn on(group: &str) -> Self {
        Self {
            group: group.to_string(),
            traction: None,
            pressure: None,
            hertz_pressure: None,
        }
    }

    /// A constant traction vector on `group`.
    pub fn traction(group: &str, traction: &[f64]) -> Self {
        Self {
            traction: Some(traction.to_vec()),
            ..Self::on(group)
        }
    }

    /// A uniform pressure on `group`.
    pub fn pressure(group: &str, pressure: f64) -> Self {
        Self {
            pressure: Some(pressure),
            ..Self::on(group)
        }
    }

    /// The Hertzian pressure of peak `p0` and radius `a` about `center` on `group`.
    pub fn hertz(group: &str, p0: f64, a: f64, center: &[f64]) -> Self {
        Self {
            hertz_pressure: Some(HertzPressure {
                p0,
                a,
                center: center.to_vec(),
            }),
            ..Self::on(group)
        }
    }
}
