//! P1 elasticity on the committed fixtures: the properties every correct assembly has.
//!
//! Tolerances: entries are compared relative to the largest entry of the matrix; solves are
//! compared relative to the largest value of the exact field, at 1e-10, which is round-off
//! times the condition number of these small graded meshes (about 1e4) with margin.

mod common;

use common::read_fixture;
use internodes::elastic::{
    DirichletCondition, ElasticProblem, LoadCondition, SolverSettings, solve,
};
use internodes::fem::assembly::{assemble_stiffness, assemble_surface_mass, stiffness_pattern};
use internodes::fem::loads::{PressureField, SurfaceLoad};
use internodes::fem::rigid_modes::rigid_body_modes;
use internodes::fem::stress::cell_fields;
use internodes::fem::{Constraints, Material};
use internodes::linalg::{Cholesky, CholeskySymbolic, Ordering, mat_vec};
use internodes::mesh::BodyMesh;

const FIXTURES: [&str; 2] = ["block_2d.msh", "block_3d.msh"];

fn material() -> Material {
    Material::new(1000.0, 0.3).unwrap()
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

/// The linear field `u(x) = A x + b` used by the patch test.
fn linear_field(x: &[f64; 3], dim: usize) -> [f64; 3] {
    let a = [
        [1.0e-3, 2.0e-3, -1.5e-3],
        [-0.5e-3, 3.0e-3, 0.7e-3],
        [0.9e-3, -1.1e-3, 2.2e-3],
    ];
    let b = [0.01, -0.02, 0.005];
    let mut u = [0.0; 3];
    for i in 0..dim {
        u[i] = b[i] + (0..dim).map(|j| a[i][j] * x[j]).sum::<f64>();
    }
    u
}

fn boundary_nodes(body: &BodyMesh) -> Vec<usize> {
    let mut nodes: Vec<usize> = body
        .boundary_groups
        .values()
        .flat_map(|g| g.nodes())
        .collect();
    nodes.sort_unstable();
    nodes.dedup();
    nodes
}

#[test]
fn patch_test_reproduces_a_linear_displacement_field() {
    for file in FIXTURES {
        let mesh = read_fixture(file);
        let body = &mesh.bodies[0];
        let dim = body.dim;
        let pattern = stiffness_pattern(body);
        let k = assemble_stiffness(body, &material(), &pattern);
        // Prescribe the linear field on the whole boundary, no load: the interior must follow.
        let mut constraints = Constraints::new(body.num_dofs());
        for node in boundary_nodes(body) {
            let u = linear_field(&body.coords[node], dim);
            for (c, value) in u.iter().enumerate().take(dim) {
                constraints.prescribe(dim * node + c, *value).unwrap();
            }
        }
        assert!(
            constraints.num_fixed() < body.num_dofs(),
            "{file}: the mesh has interior nodes"
        );
        let (k_c, mut u) = constraints.apply(k, &vec![0.0; body.num_dofs()]);
        let factor = Cholesky::factorize(
            CholeskySymbolic::new(
                pattern.graph(),
                pattern.symbolic(),
                Ordering::NestedDissection,
            )
            .unwrap(),
            &k_c,
        )
        .unwrap();
        factor.solve_in_place(&mut u, 1);

        let exact: Vec<f64> = body
            .coords
            .as_whole()
            .unwrap()
            .iter()
            .flat_map(|x| linear_field(x, dim)[..dim].to_vec())
            .collect();
        let error: Vec<f64> = u.iter().zip(&exact).map(|(a, b)| a - b).collect();
        assert!(
            max_abs(&error) <= 1e-10 * max_abs(&exact),
            "{file}: patch test error {:.2e}",
            max_abs(&error) / max_abs(&exact)
        );

        // The strain is the same constant on every cell.
        let fields = cell_fields(body, &material(), &u);
        let first = fields.strain[0];
        for s in &fields.strain {
            for k in 0..9 {
                assert!(
                    (s[k] - first[k]).abs() <= 1e-9 * max_abs(&first),
                    "{file}: strain not constant"
                );
            }
        }
    }
}

#[test]
fn rigid_body_motions_are_in_the_kernel_of_the_stiffness() {
    for file in FIXTURES {
        let mesh = read_fixture(file);
        let body = &mesh.bodies[0];
        let k = assemble_stiffness(body, &material(), &stiffness_pattern(body));
        let k_max = max_abs(k.val());
        let modes = rigid_body_modes(body);
        assert_eq!(modes.len(), if body.dim == 2 { 3 } else { 6 });
        for (i, r) in modes.iter().enumerate() {
            let kr = mat_vec(&k, r);
            // Each row of K r sums at most ~30 entries of size k_max times |r| <= 1.
            assert!(
                max_abs(&kr) <= 1e-12 * k_max,
                "{file}: mode {i}: |K r| = {:.2e} k_max",
                max_abs(&kr) / k_max
            );
        }
    }
}

#[test]
fn stiffness_is_symmetric() {
    for file in FIXTURES {
        let mesh = read_fixture(file);
        let body = &mesh.bodies[0];
        let k = assemble_stiffness(body, &material(), &stiffness_pattern(body)).to_dense();
        let mut asymmetry: f64 = 0.0;
        let mut largest: f64 = 0.0;
        for i in 0..k.nrows() {
            for j in 0..k.ncols() {
                asymmetry = asymmetry.max((k[(i, j)] - k[(j, i)]).abs());
                largest = largest.max(k[(i, j)].abs());
            }
        }
        assert!(
            asymmetry <= 1e-14 * largest,
            "{file}: asymmetry {:.2e}",
            asymmetry / largest
        );
    }
}

#[test]
fn surface_mass_matrix_sums_to_the_facet_area() {
    // The blocks span [-2, 2] laterally: top face area 16 in 3D, top edge length 4 in 2D; the
    // sides of the 3D block are 4 faces of 4 x 2, those of the 2D block 2 edges of length 2.
    for (file, group, measure) in [
        ("block_3d.msh", "block_top", 16.0),
        ("block_3d.msh", "block_sides", 32.0),
        ("block_2d.msh", "block_top", 4.0),
        ("block_2d.msh", "block_sides", 4.0),
    ] {
        let mesh = read_fixture(file);
        let body = &mesh.bodies[0];
        let m = assemble_surface_mass(body, body.boundary_group(group).unwrap());
        let total: f64 = m.val().iter().sum();
        assert!(
            (total - measure).abs() <= 1e-12 * measure,
            "{file} {group}: sum {total}"
        );
        // Rows of nodes off the group are empty; every entry is non-negative.
        assert!(m.val().iter().all(|&v| v >= 0.0));
    }
}

fn solver_settings() -> SolverSettings {
    SolverSettings {
        verbose: false,
        ..Default::default()
    }
}

#[test]
fn uniaxial_strain_under_uniform_pressure_is_exact() {
    // Rollers on the sides (normal displacement 0), base fixed vertically, pressure p on top:
    // eps_vertical = -p / (lambda + 2 mu), linear in the height, so P1 is exact; the base
    // reaction balances p times the top area.
    for (file, top_area) in [("block_3d.msh", 16.0), ("block_2d.msh", 4.0)] {
        let mesh = read_fixture(file);
        let body = &mesh.bodies[0];
        let dim = body.dim;
        let vertical = dim - 1;
        let (lambda, mu) = material().lame();
        let p = 2.5;
        let mut base = [None; 3];
        base[vertical] = Some(0.0);
        let mut sides = [Some(0.0); 3];
        sides[vertical] = None;
        if dim == 2 {
            sides[2] = None;
        }
        let problem = ElasticProblem::new(
            body,
            material(),
            vec![
                DirichletCondition {
                    group: "block_base".into(),
                    components: base,
                    path: None,
                },
                DirichletCondition {
                    group: "block_sides".into(),
                    components: sides,
                    path: None,
                },
            ],
            vec![LoadCondition {
                group: "block_top".into(),
                load: SurfaceLoad::Pressure(PressureField::Uniform(p)),
                path: None,
            }],
            None,
        )
        .unwrap();
        let solution = solve(&problem, &solver_settings()).unwrap();
        let strain = -p / (lambda + 2.0 * mu);
        let (lo, _) = body.bounding_box();
        let mut worst: f64 = 0.0;
        for (a, x) in body.coords.as_whole().unwrap().iter().enumerate() {
            let exact = strain * (x[vertical] - lo[vertical]);
            worst = worst.max((solution.displacement[dim * a + vertical] - exact).abs());
            for c in (0..dim).filter(|&c| c != vertical) {
                worst = worst.max(solution.displacement[dim * a + c].abs());
            }
        }
        let scale = (strain * 2.0).abs();
        assert!(
            worst <= 1e-10 * scale,
            "{file}: error {:.2e}",
            worst / scale
        );
        let (_, reaction) = &solution.reactions[0];
        assert!(
            (reaction[vertical] - p * top_area).abs() <= 1e-10 * p * top_area,
            "{file}: reaction {reaction:?}"
        );
        for s in &cell_fields(body, &material(), &solution.displacement).stress {
            assert!(
                (s[4 * vertical] + p).abs() <= 1e-9 * p,
                "{file}: vertical stress {}",
                s[4 * vertical]
            );
        }
    }
}

#[test]
fn reactions_balance_a_hertzian_load() {
    for file in FIXTURES {
        let mesh = read_fixture(file);
        let body = &mesh.bodies[0];
        let dim = body.dim;
        let hertz = PressureField::Hertz {
            p0: 10.0,
            a: 0.5,
            center: [0.0; 3],
        };
        let problem = ElasticProblem::new(
            body,
            material(),
            vec![DirichletCondition {
                group: "block_base".into(),
                components: [Some(0.0), Some(0.0), (dim == 3).then_some(0.0)],
                path: None,
            }],
            vec![LoadCondition {
                group: "block_top".into(),
                load: SurfaceLoad::Pressure(hertz.clone()),
                path: None,
            }],
            None,
        )
        .unwrap();
        let solution = solve(&problem, &solver_settings()).unwrap();
        // The load is -n times the integral of the P1 interpolant of p: sum_ab M_ab p_b.
        let top = body.boundary_group("block_top").unwrap();
        let m = assemble_surface_mass(body, top);
        let p: Vec<f64> = body
            .coords
            .as_whole()
            .unwrap()
            .iter()
            .map(|x| hertz.at(x))
            .collect();
        let load: f64 = mat_vec(&m, &p).iter().sum();
        let reaction = &solution.reactions[0].1;
        assert!(
            (reaction[dim - 1] - load).abs() <= 1e-10 * load,
            "{file}: reaction {reaction:?} load {load}"
        );
        for horizontal in &reaction[..dim - 1] {
            assert!(horizontal.abs() <= 1e-10 * load);
        }
        assert!(solution.stats.relative_residual < 1e-12);
    }
}

#[test]
fn orderings_give_the_same_solution() {
    let mesh = read_fixture("block_3d.msh");
    let body = &mesh.bodies[0];
    let problem = ElasticProblem::new(
        body,
        material(),
        vec![DirichletCondition {
            group: "block_base".into(),
            components: [Some(0.0); 3],
            path: None,
        }],
        vec![LoadCondition {
            group: "block_top".into(),
            load: SurfaceLoad::Traction([0.1, 0.0, -1.0]),
            path: None,
        }],
        Some([0.0, 0.0, -0.5]),
    )
    .unwrap();
    let nd = solve(&problem, &solver_settings()).unwrap();
    let amd = solve(
        &problem,
        &SolverSettings {
            ordering: Ordering::Amd,
            ..solver_settings()
        },
    )
    .unwrap();
    let diff: Vec<f64> = nd
        .displacement
        .iter()
        .zip(&amd.displacement)
        .map(|(a, b)| a - b)
        .collect();
    assert!(max_abs(&diff) <= 1e-12 * max_abs(&nd.displacement));
}
