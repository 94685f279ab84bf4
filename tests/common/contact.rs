//! Helpers of the contact tests: solving a case given as TOML text, and the committed
//! fixtures' cases (two blocks, the half-disc and the hemisphere on a block, a flat punch).

use super::{Edit, fixture, run_solve, write_case};
use internodes::case::Case;
use internodes::contact::{ContactSolution, ContactSolver, solve_contact};
use internodes::elastic::SolverSettings;
use internodes::mesh::read_msh;

/// Solves the `[contact]` of a case given as TOML text with the library's [`solve_contact`]
/// (its load steps, the retry and the agreement check included); `loop_only` runs one
/// active-set loop at the full load instead.
pub fn solve_with(text: &str, loop_only: bool) -> Result<ContactSolution, String> {
    let (_dir, path) = write_case(text);
    let case = Case::load(&path).map_err(|e| e.to_string())?;
    let mesh = read_msh(&case.mesh).map_err(|e| e.to_string())?;
    let problem = case
        .contact_problem(&mesh)
        .map_err(|e| e.to_string())?
        .expect("the case has a [contact] table");
    let settings = SolverSettings {
        verbose: false,
        ..case.solver
    };
    if loop_only {
        let mut solver = ContactSolver::new(&problem, &settings).map_err(|e| e.to_string())?;
        return solver.solve(1.0, None).map_err(|e| e.to_string());
    }
    let run = solve_contact(problem, &settings, &case.load_steps()).map_err(|e| e.to_string())?;
    Ok(run.solution)
}

pub fn solve(text: &str) -> Result<ContactSolution, String> {
    solve_with(text, false)
}

/// Two stacked unit blocks with non-matching meshes, compressed by `delta` through the top of
/// the upper one, the lower one on its base; `sides` are extra Dirichlet lines for both
/// bodies' side groups (e.g. rollers).
pub fn two_blocks(dim: usize, formulation: &str, lower_sides: &str, upper_sides: &str) -> String {
    let vertical = if dim == 2 { "uy" } else { "uz" };
    format!(
        r#"mesh = "{mesh}"
output = "out"

[contact]
bodies = ["upper", "lower"]
surfaces = ["upper_contact", "lower_contact"]
primary = "upper"
formulation = "{formulation}"

[[body]]
name = "lower"
youngs_modulus = 1000.0
poisson_ratio = 0.3
[[body.dirichlet]]
group = "lower_base"
{vertical} = 0.0
{lower_sides}

[[body]]
name = "upper"
youngs_modulus = 1000.0
poisson_ratio = 0.3
[[body.dirichlet]]
group = "upper_top"
{vertical} = -0.01
{upper_sides}
"#,
        mesh = fixture(&format!("two_blocks_{dim}d.msh")).display()
    )
}

pub fn rollers(body: &str, dim: usize) -> String {
    let lateral = if dim == 2 {
        "ux = 0.0"
    } else {
        "ux = 0.0\nuy = 0.0"
    };
    format!("[[body.dirichlet]]\ngroup = \"{body}_sides\"\n{lateral}")
}

/// The half-disc (R = 1) pressed by 0.02 onto the block, both E = 1000, nu = 0.3, on the mesh
/// refined to R/80 in the contact zone.
pub fn half_disc_on_block(extra: &str) -> String {
    super::half_disc_on_block("half_disc_on_block_hertz.msh", extra)
}

/// The block 1e4 times stiffer than the disc, on `mesh` (R = 1, pressed by 0.02), with the
/// primary body `primary` ("auto", "disc" or "block").
pub fn stiff_block(mesh: &str, primary: &str) -> String {
    super::half_disc_on_block(mesh, "")
        .edit("primary = \"disc\"", &format!("primary = \"{primary}\""))
        .edit(
            "name = \"block\"\nyoungs_modulus = 1000.0",
            "name = \"block\"\nyoungs_modulus = 1.0e7",
        )
}

/// The names of the checks (residuals and accuracy indicators) a solution failed.
pub fn failed_checks(solution: &ContactSolution) -> Vec<&'static str> {
    (solution.certificate.checks.iter())
        .filter(|c| !c.passed)
        .map(|c| c.name.name())
        .collect()
}

/// The names of the failed checks in a `summary.json` contact object: residuals, then
/// accuracy indicators.
pub fn failed_in_summary(contact: &serde_json::Value) -> Vec<String> {
    let solved = contact["solved"]["checks"].as_array().unwrap().iter();
    let accuracy = contact["accuracy"]["indicators"].as_array().unwrap().iter();
    (solved.chain(accuracy))
        .filter(|c| c["passed"] == false)
        .map(|c| c["name"].as_str().unwrap().to_string())
        .collect()
}

/// Solves `text` on the command line: exit status and summary.json.
pub fn solve_cli(text: &str) -> (Option<i32>, serde_json::Value) {
    let (dir, path) = write_case(text);
    let output = run_solve(&path);
    let summary = std::fs::read_to_string(dir.path().join("out/summary.json")).unwrap();
    (
        output.status.code(),
        serde_json::from_str(&summary).unwrap(),
    )
}

/// A stiff flat punch (E = 1e7) with sharp corners pressed by `delta` onto a block (E = 1000)
/// twice its width and more, from `tests/fixtures/flat_punch_{dim}d.msh`.
pub fn flat_punch(dim: usize, delta: f64, primary: &str) -> String {
    let (top, base) = if dim == 2 {
        (format!("ux = 0.0\nuy = {}", -delta), "ux = 0.0\nuy = 0.0")
    } else {
        (
            format!("ux = 0.0\nuy = 0.0\nuz = {}", -delta),
            "ux = 0.0\nuy = 0.0\nuz = 0.0",
        )
    };
    format!(
        r#"mesh = "{mesh}"
output = "out"

[contact]
bodies = ["punch", "block"]
surfaces = ["punch_face", "block_top"]
primary = "{primary}"

[[body]]
name = "punch"
youngs_modulus = 1.0e7
poisson_ratio = 0.3
[[body.dirichlet]]
group = "punch_top"
{top}

[[body]]
name = "block"
youngs_modulus = 1000.0
poisson_ratio = 0.3
[[body.dirichlet]]
group = "block_base"
{base}
"#,
        mesh = fixture(&format!("flat_punch_{dim}d.msh")).display()
    )
}

/// The reaction on `group` of body `body` of the fixture `mesh` solved alone (E = 1000,
/// nu = 0.3) with the Dirichlet conditions `conditions` (TOML `[[body.dirichlet]]` tables).
pub fn one_body_reaction(mesh: &str, body: &str, conditions: &str, group: &str) -> Vec<f64> {
    let mesh_path = fixture(mesh);
    let text = format!(
        "mesh = \"{}\"\noutput = \"out\"\n[[body]]\nname = \"{body}\"\nyoungs_modulus = 1000.0\npoisson_ratio = 0.3\n{conditions}",
        mesh_path.display()
    );
    let (_dir, path) = write_case(&text);
    let case = Case::load(&path).unwrap();
    let mesh = read_msh(&mesh_path).unwrap();
    let problem = case
        .elastic_problem(mesh.body(body).unwrap(), &case.bodies[0])
        .unwrap();
    let settings = SolverSettings {
        verbose: false,
        ..SolverSettings::default()
    };
    let solution = internodes::elastic::solve(&problem, &settings).unwrap();
    (solution.reactions.iter())
        .find(|(name, _)| name == group)
        .unwrap()
        .1
        .clone()
}

/// The vertical force on the block of `flat_punch_{dim}d.msh` alone, its base clamped and the
/// punch's footprint `block_under_punch` pushed down by `delta` and free to slide: the rigid
/// frictionless punch on the same block mesh, by the elastic solver.
pub fn footprint_force(dim: usize, delta: f64) -> f64 {
    let (vertical, base) = if dim == 2 {
        ("uy", "ux = 0.0\nuy = 0.0")
    } else {
        ("uz", "ux = 0.0\nuy = 0.0\nuz = 0.0")
    };
    let conditions = format!(
        "[[body.dirichlet]]\ngroup = \"block_base\"\n{base}\n[[body.dirichlet]]\ngroup = \"block_under_punch\"\n{vertical} = {}\n",
        -delta
    );
    let reaction = one_body_reaction(
        &format!("flat_punch_{dim}d.msh"),
        "block",
        &conditions,
        "block_under_punch",
    );
    reaction[dim - 1].abs()
}

/// Two equal-material flat blocks on rollers, the upper 0.6 times as wide and meshed twice
/// coarser (`tests/fixtures/flat_blocks_narrow_2d.msh`, from `geo/flat_blocks_2d.geo`), pressed
/// by 0.01, with `extra` in the `[contact]` table.
pub fn narrow_blocks(extra: &str) -> String {
    format!(
        r#"mesh = "{mesh}"
output = "out"

[contact]
bodies = ["upper", "lower"]
surfaces = ["upper_contact", "lower_contact"]
{extra}

[[body]]
name = "upper"
youngs_modulus = 1000.0
poisson_ratio = 0.3
[[body.dirichlet]]
group = "upper_top"
uy = -0.01
[[body.dirichlet]]
group = "upper_sides"
ux = 0.0

[[body]]
name = "lower"
youngs_modulus = 1000.0
poisson_ratio = 0.3
[[body.dirichlet]]
group = "lower_base"
uy = 0.0
[[body.dirichlet]]
group = "lower_sides"
ux = 0.0
"#,
        mesh = fixture("flat_blocks_narrow_2d.msh").display()
    )
}

/// The hemisphere (R = 1) pressed by `delta` onto the block, frictionless unless `extra` says
/// otherwise; `e_sphere` and `e_block` are the Young's moduli, nu = 0.3 for both.
pub fn hemisphere_on_block(
    mesh: &str,
    delta: f64,
    e_sphere: f64,
    e_block: f64,
    extra: &str,
) -> String {
    format!(
        r#"mesh = "{mesh}"
output = "out"

[contact]
bodies = ["sphere", "block"]
surfaces = ["sphere_contact", "block_contact"]
primary = "sphere"
{extra}

[[body]]
name = "sphere"
youngs_modulus = {e_sphere:?}
poisson_ratio = 0.3
[[body.dirichlet]]
group = "sphere_top"
ux = 0.0
uy = 0.0
uz = {uz:?}

[[body]]
name = "block"
youngs_modulus = {e_block:?}
poisson_ratio = 0.3
[[body.dirichlet]]
group = "block_base"
ux = 0.0
uy = 0.0
uz = 0.0
"#,
        mesh = fixture(mesh).display(),
        uz = -delta
    )
}
