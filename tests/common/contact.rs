//! Helpers of the contact tests: solving a case, and the committed fixtures' cases (two
//! blocks, the half-disc and the hemisphere on a block, a flat punch).

use super::case_builder::{Body, CaseFile, Dirichlet};
use super::run_solve;
use internodes::case::Case;
use internodes::contact::{ContactSolution, ContactSolver, solve_contact};
use internodes::elastic::{SolverSettings, StepFactors};
use internodes::mesh::read_msh;

/// Solves the `[contact]` of `case` with the library's [`solve_contact`]
/// (its load steps, the retry and the agreement check included); `loop_only` runs one
/// active-set loop at the full load instead.
pub fn solve_with(case: &CaseFile, loop_only: bool) -> Result<ContactSolution, String> {
    let (_dir, path) = case.write();
    let case = Case::load(&path).map_err(|e| e.to_string())?;
    let mesh = read_msh(&case.mesh).map_err(|e| e.to_string())?;
    let mut problems = case.contact_problems(&mesh).map_err(|e| e.to_string())?;
    assert_eq!(problems.len(), 1, "the case has one [contact] table");
    let problem = problems.remove(0);
    let settings = SolverSettings {
        verbose: false,
        ..case.solver.clone()
    };
    if loop_only {
        let mut solver = ContactSolver::new(std::slice::from_ref(&problem), &settings)
            .map_err(|e| e.to_string())?;
        let mut solutions = solver
            .solve(&StepFactors::uniform(1.0), None)
            .map_err(|e| e.to_string())?;
        return Ok(solutions.remove(0));
    }
    let mut run =
        solve_contact(vec![problem], &settings, &case.load_steps()).map_err(|e| e.to_string())?;
    Ok(run.solutions.remove(0))
}

pub fn solve(case: &CaseFile) -> Result<ContactSolution, String> {
    solve_with(case, false)
}

/// Two stacked unit blocks with non-matching meshes, compressed by 0.01 through the top of
/// the upper one (the primary), the lower one on its base; only the vertical components are
/// held, so that each test adds the other supports.
pub fn stacked_blocks(dim: usize) -> CaseFile {
    CaseFile::on_fixture(&format!("two_blocks_{dim}d.msh"))
        .contact(["upper", "lower"], ["upper_contact", "lower_contact"])
        .primary("upper")
        .body(
            Body::new("lower", 1000.0, 0.3)
                .dirichlet(Dirichlet::on("lower_base").vertical(dim, 0.0)),
        )
        .body(
            Body::new("upper", 1000.0, 0.3)
                .dirichlet(Dirichlet::on("upper_top").vertical(dim, -0.01)),
        )
}

/// [`stacked_blocks`] with the contact `formulation` named.
pub fn two_blocks(dim: usize, formulation: &str) -> CaseFile {
    stacked_blocks(dim).contact_setting("formulation", formulation)
}

/// [`two_blocks`] with both blocks on rollers along their sides.
pub fn two_blocks_on_rollers(dim: usize, formulation: &str) -> CaseFile {
    with_rollers(two_blocks(dim, formulation), dim)
}

/// Two blocks (`lower` and `upper`) on rollers along their sides.
pub fn with_rollers(case: CaseFile, dim: usize) -> CaseFile {
    case.support("lower", Dirichlet::rollers("lower", dim))
        .support("upper", Dirichlet::rollers("upper", dim))
}

/// Two blocks (`lower` and `upper`) each pinned at corners (points) against its rigid-body
/// motions alone, free to expand laterally.
pub fn pinned_at_corners(mut case: CaseFile, dim: usize) -> CaseFile {
    for body in ["lower", "upper"] {
        let pins = if dim == 2 {
            vec![Dirichlet::on(&format!("{body}_corner")).ux(0.0)]
        } else {
            vec![
                Dirichlet::on(&format!("{body}_corner_a")).ux(0.0).uy(0.0),
                Dirichlet::on(&format!("{body}_corner_b")).uy(0.0),
            ]
        };
        for pin in pins {
            case = case.support(body, pin);
        }
    }
    case
}

/// The half-disc (R = 1) pressed by 0.02 onto the block, both E = 1000, nu = 0.3, on the mesh
/// refined to R/80 in the contact zone.
pub fn half_disc_on_block() -> CaseFile {
    super::half_disc_on_block("half_disc_on_block_hertz.msh")
}

/// The block 1e4 times stiffer than the disc, on `mesh` (R = 1, pressed by 0.02), with the
/// primary body `primary` ("auto", "disc" or "block").
pub fn stiff_block(mesh: &str, primary: &str) -> CaseFile {
    super::half_disc_on_block(mesh)
        .primary(primary)
        .with_body("block", |b| Body {
            youngs_modulus: 1.0e7,
            ..b
        })
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

/// Solves `case` on the command line: exit status and summary.json.
pub fn solve_cli(case: &CaseFile) -> (Option<i32>, serde_json::Value) {
    let (dir, path) = case.write();
    let output = run_solve(&path);
    let summary = std::fs::read_to_string(dir.path().join("out/summary.json")).unwrap();
    (
        output.status.code(),
        serde_json::from_str(&summary).unwrap(),
    )
}

/// A stiff flat punch (E = 1e7) with sharp corners pressed by `delta` onto a block (E = 1000)
/// twice its width and more, from `tests/fixtures/flat_punch_{dim}d.msh`.
pub fn flat_punch(dim: usize, delta: f64, primary: &str) -> CaseFile {
    CaseFile::on_fixture(&format!("flat_punch_{dim}d.msh"))
        .contact(["punch", "block"], ["punch_face", "block_top"])
        .primary(primary)
        .body(
            Body::new("punch", 1.0e7, 0.3).dirichlet(
                Dirichlet::on("punch_top")
                    .lateral(dim, 0.0)
                    .vertical(dim, -delta),
            ),
        )
        .body(Body::new("block", 1000.0, 0.3).dirichlet(Dirichlet::clamped("block_base", dim)))
}

/// The reaction on `group` of body `body` of the fixture `mesh` solved alone (E = 1000,
/// nu = 0.3) with the Dirichlet conditions `conditions`.
pub fn one_body_reaction(
    mesh: &str,
    body: &str,
    conditions: &[Dirichlet],
    group: &str,
) -> Vec<f64> {
    let mut one_body = Body::new(body, 1000.0, 0.3);
    one_body.dirichlet = conditions.to_vec();
    let (_dir, path) = CaseFile::on_fixture(mesh).body(one_body).write();
    let case = Case::load(&path).unwrap();
    let mesh = read_msh(&case.mesh).unwrap();
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
    let conditions = [
        Dirichlet::clamped("block_base", dim),
        Dirichlet::on("block_under_punch").vertical(dim, -delta),
    ];
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
/// by 0.01.
pub fn narrow_blocks() -> CaseFile {
    CaseFile::on_fixture("flat_blocks_narrow_2d.msh")
        .contact(["upper", "lower"], ["upper_contact", "lower_contact"])
        .body(
            Body::new("upper", 1000.0, 0.3)
                .dirichlet(Dirichlet::on("upper_top").uy(-0.01))
                .dirichlet(Dirichlet::rollers("upper", 2)),
        )
        .body(
            Body::new("lower", 1000.0, 0.3)
                .dirichlet(Dirichlet::on("lower_base").uy(0.0))
                .dirichlet(Dirichlet::rollers("lower", 2)),
        )
}

/// The hemisphere (R = 1) pressed by `delta` onto the block, frictionless, the sphere primary;
/// `e_sphere` and `e_block` are the Young's moduli, nu = 0.3 for both.
pub fn hemisphere_on_block(mesh: &str, delta: f64, e_sphere: f64, e_block: f64) -> CaseFile {
    CaseFile::on_fixture(mesh)
        .contact(["sphere", "block"], ["sphere_contact", "block_contact"])
        .primary("sphere")
        .body(
            Body::new("sphere", e_sphere, 0.3)
                .dirichlet(Dirichlet::on("sphere_top").lateral(3, 0.0).uz(-delta)),
        )
        .body(Body::new("block", e_block, 0.3).dirichlet(Dirichlet::clamped("block_base", 3)))
}
