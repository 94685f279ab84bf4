//! The body solvers: CG + AMG (feature `petsc`) against sparse Cholesky, and the error a build
//! without PETSc gives for `body = "cg-amg"`.
//!
//! Tolerance: CG stops at the relative residual `rtol` = 1e-10 (the default); its error is
//! bounded by the residual times the condition number, and measured at 1e-11 to 1e-10 on
//! these fixtures, so solutions are compared at 1e-8 relative to the largest displacement.

mod common;

use common::{block_3d_case, read_fixture};
use internodes::case::{Case, CaseError};
use internodes::elastic::{DirichletCondition, ElasticProblem, LoadCondition, SolverSettings};
use internodes::fem::Material;
use internodes::fem::loads::{PressureField, SurfaceLoad};
use internodes::linalg::BodySolverKind;
use internodes::mesh::BodyMesh;

fn material() -> Material {
    Material::new(1000.0, 0.3).unwrap()
}

fn settings(body: BodySolverKind) -> SolverSettings {
    SolverSettings {
        body,
        verbose: false,
        ..Default::default()
    }
}

/// A block clamped at its base under a Hertzian pressure on its top.
fn hertz_block(body: &BodyMesh) -> ElasticProblem<'_> {
    let dim = body.dim;
    ElasticProblem::new(
        body,
        material(),
        vec![DirichletCondition {
            group: "block_base".into(),
            components: [Some(0.0), Some(0.0), (dim == 3).then_some(0.0)],
            path: None,
        }],
        vec![LoadCondition {
            group: "block_top".into(),
            load: SurfaceLoad::Pressure(PressureField::Hertz {
                p0: 10.0,
                a: 0.5,
                center: [0.0; 3],
            }),
            path: None,
        }],
        Some([0.0, 0.0, 0.0]),
    )
    .unwrap()
}

#[cfg(feature = "petsc")]
fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

/// `max |a - b| / max |b|`.
#[cfg(feature = "petsc")]
fn relative_difference(a: &[f64], b: &[f64]) -> f64 {
    let diff: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
    max_abs(&diff) / max_abs(b)
}

#[test]
fn rtol_outside_zero_one_is_rejected() {
    for rtol in [0.0, 1.0, -1e-10, f64::NAN] {
        let (_dir, path) = block_3d_case().rtol(rtol).write();
        let e = Case::load(&path).unwrap_err();
        assert!(
            matches!(e, CaseError::Invalid { .. }) && e.to_string().contains("rtol"),
            "{rtol}: {e}"
        );
    }
}

#[test]
fn rtol_above_the_residual_tolerance_is_rejected_for_cg_amg_and_makes_auto_cholesky() {
    let solver = |body: &str| {
        block_3d_case()
            .body_solver(body)
            .rtol(1e-6)
            .residual_tolerance(1e-8)
    };
    let (_dir, path) = solver("cg-amg").write();
    let e = Case::load(&path).unwrap_err();
    assert!(
        e.to_string().contains("rtol") && e.to_string().contains("residual_tolerance"),
        "{e}"
    );
    for body in ["auto", "cholesky"] {
        let (_dir, path) = solver(body).write();
        let case = Case::load(&path).unwrap();
        assert_eq!(
            case.solver.body_solver(3, 10_000_000),
            BodySolverKind::Cholesky
        );
    }
}

#[test]
fn auto_is_cholesky_for_small_bodies_and_in_2d() {
    assert_eq!(
        BodySolverKind::Auto.resolve(3, 1000),
        BodySolverKind::Cholesky
    );
    assert_eq!(
        BodySolverKind::Auto.resolve(2, 10_000_000),
        BodySolverKind::Cholesky
    );
    assert_eq!(
        BodySolverKind::Cholesky.resolve(3, 10_000_000),
        BodySolverKind::Cholesky
    );
}

#[cfg(not(feature = "petsc"))]
mod without_petsc {
    use super::*;
    use internodes::elastic::{SolveError, solve};
    use internodes::linalg::LinalgError;

    #[test]
    fn a_case_asking_for_cg_amg_names_the_key_and_petsc() {
        let (_dir, path) = block_3d_case().body_solver("cg-amg").write();
        let e = Case::load(&path).unwrap_err();
        let message = e.to_string();
        assert!(matches!(e, CaseError::Invalid { .. }), "{message}");
        assert!(
            message.contains("[solver]")
                && message.contains("cg-amg")
                && message.contains("built without")
                && message.contains("PETSc"),
            "{message}"
        );
    }

    #[test]
    fn the_library_asked_for_cg_amg_says_petsc_is_missing() {
        let mesh = read_fixture("block_3d.msh");
        let problem = hertz_block(&mesh.bodies[0]);
        let e = solve(&problem, &settings(BodySolverKind::CgAmg)).unwrap_err();
        assert!(
            matches!(
                e,
                SolveError::Linalg {
                    source: LinalgError::PetscUnavailable,
                    ..
                }
            ),
            "{e}"
        );
        assert!(e.to_string().contains("without"), "{e}");
    }

    #[test]
    fn auto_is_cholesky_at_any_size() {
        assert_eq!(
            BodySolverKind::Auto.resolve(3, usize::MAX),
            BodySolverKind::Cholesky
        );
    }
}

#[cfg(feature = "petsc")]
mod with_petsc {
    use super::*;
    use internodes::elastic::{ElasticSolution, assemble, solve};
    use internodes::fem::Constraints;
    use internodes::fem::assembly::{assemble_stiffness, stiffness_pattern};
    use internodes::linalg::{
        AUTO_CG_AMG_MIN_DOFS_3D, BodySolver, LinalgError, mat_vec, relative_residual,
    };

    fn solve_both(file: &str) -> (ElasticSolution, ElasticSolution) {
        let mesh = read_fixture(file);
        let problem = hertz_block(&mesh.bodies[0]);
        let cholesky = solve(&problem, &settings(BodySolverKind::Cholesky)).unwrap();
        let cg = solve(&problem, &settings(BodySolverKind::CgAmg)).unwrap();
        (cholesky, cg)
    }

    #[test]
    fn cg_amg_agrees_with_cholesky_in_2d_and_3d() {
        for file in ["block_3d.msh", "block_2d.msh"] {
            let (cholesky, cg) = solve_both(file);
            let d = relative_difference(&cg.displacement, &cholesky.displacement);
            assert!(d < 1e-8, "{file}: relative difference {d:.2e}");
            assert!(cg.stats.relative_residual <= 1e-10, "{file}");
            assert_eq!(cg.stats.body_solver, Some(BodySolverKind::CgAmg));
            assert!(cg.stats.cg_iterations.is_some_and(|n| n > 0), "{file}");
            assert_eq!(cholesky.stats.body_solver, Some(BodySolverKind::Cholesky));
            assert_eq!(cholesky.stats.cg_iterations, None);
            for ((_, r_cg), (_, r_ch)) in cg.reactions.iter().zip(&cholesky.reactions) {
                assert!(relative_difference(r_cg, r_ch) < 1e-8, "{file}: reactions");
            }
        }
    }

    #[test]
    fn auto_is_cg_amg_for_large_3d_bodies() {
        assert_eq!(
            BodySolverKind::Auto.resolve(3, AUTO_CG_AMG_MIN_DOFS_3D),
            BodySolverKind::CgAmg
        );
        assert_eq!(
            BodySolverKind::Auto.resolve(3, AUTO_CG_AMG_MIN_DOFS_3D - 1),
            BodySolverKind::Cholesky
        );
    }

    #[test]
    fn summary_records_the_solver_and_its_iterations() {
        let (dir, path) = block_3d_case().body_solver("cg-amg").write();
        let output = common::run_solve(&path);
        assert!(output.status.success(), "{output:?}");
        let text = std::fs::read_to_string(dir.path().join("out/summary.json")).unwrap();
        let summary: serde_json::Value = serde_json::from_str(&text).unwrap();
        let solve = &summary["bodies"][0]["solve"];
        assert_eq!(solve["body_solver"], "cg-amg", "{solve}");
        assert!(
            solve["cg_iterations"].as_u64().is_some_and(|n| n > 0),
            "{solve}"
        );
    }

    /// The linear field `u(x) = A x + b`.
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

    #[test]
    fn patch_test_with_cg_amg() {
        for file in ["block_3d.msh", "block_2d.msh"] {
            let mesh = read_fixture(file);
            let body = &mesh.bodies[0];
            let dim = body.dim;
            let pattern = stiffness_pattern(body);
            let k = assemble_stiffness(body, &material(), &pattern);
            // The linear field on the whole boundary, no load: the interior must follow.
            let mut boundary: Vec<usize> = body
                .boundary_groups
                .values()
                .flat_map(|g| g.nodes())
                .collect();
            boundary.sort_unstable();
            boundary.dedup();
            let mut constraints = Constraints::new(body.num_dofs());
            for &node in &boundary {
                let u = linear_field(&body.coords[node], dim);
                for (c, value) in u.iter().enumerate().take(dim) {
                    constraints.prescribe(dim * node + c, *value).unwrap();
                }
            }
            assert!(constraints.num_fixed() < body.num_dofs());
            let (k_c, mut u) = constraints.apply(k, &vec![0.0; body.num_dofs()]);
            let coords = body.coords.flat(dim);
            let solver = BodySolver::cg_amg(&k_c, dim, &coords, 1e-12).unwrap();
            solver.solve_in_place(&mut u, 1).unwrap();
            let exact: Vec<f64> = (body.coords.as_whole().unwrap().iter())
                .flat_map(|x| linear_field(x, dim)[..dim].to_vec())
                .collect();
            let d = relative_difference(&u, &exact);
            assert!(d < 1e-9, "{file}: relative error {d:.2e}");
        }
    }

    #[test]
    fn a_solver_that_holds_the_only_copy_gives_products_and_the_matrix_back() {
        // A contact solve frees its own K_c once PETSc holds it
        // (`coupled_solver::petsc_solvers`): products read PETSc's rows, and a fallback to
        // Cholesky factors copies them. The rows of a symmetric matrix are its columns, PETSc's
        // with the nodes in another order (along a Z curve): the product is our own column
        // sums, the same terms summed in another order, so within the rounding bound of two
        // sums of m terms, 2 m eps sum |a_ij x_i|; the copy is K_c, bit for bit.
        for file in ["block_3d.msh", "block_2d.msh"] {
            let mesh = read_fixture(file);
            let problem = hertz_block(&mesh.bodies[0]);
            let mut stats = Default::default();
            let system = assemble(&problem, &mut stats, false).unwrap();
            let k_c = system.stiffness.whole().unwrap();
            let solver = BodySolver::cg_amg(
                k_c,
                system.dim,
                system.stiffness.coordinates().unwrap(),
                1e-10,
            )
            .unwrap();
            let n = system.f_c.len();
            let x: Vec<f64> = (0..n)
                .map(|i| ((i * 7919) % 1000) as f64 / 1000.0 - 0.5)
                .collect();
            let (symbolic, values) = k_c.parts();
            let column_terms = |j: usize| {
                (symbolic.col_ptr()[j]..symbolic.col_ptr()[j + 1])
                    .map(|p| values[p] * x[symbolic.row_idx()[p]])
            };
            let mut petsc = vec![f64::NAN; n];
            solver.multiply(&x, &mut petsc).unwrap();
            for (j, &y) in petsc.iter().enumerate() {
                let ours: f64 = column_terms(j).sum();
                let terms = column_terms(j).count() as f64;
                let bound = 2.0 * terms * f64::EPSILON * column_terms(j).map(f64::abs).sum::<f64>();
                assert!(
                    (y - ours).abs() <= bound,
                    "{file}: the product's entry {j}: {y} against {ours}"
                );
            }
            let copy = solver.matrix().expect("a whole matrix on one process");
            assert_eq!(copy.symbolic().col_ptr(), symbolic.col_ptr(), "{file}");
            assert_eq!(copy.symbolic().row_idx(), symbolic.row_idx(), "{file}");
            assert_eq!(copy.parts().1, values, "{file}: the values");
            let mut short = vec![0.0; n - 1];
            assert!(solver.multiply(&x, &mut short).is_err(), "{file}: sizes");
        }
    }

    #[test]
    fn one_setup_serves_many_right_hand_sides() {
        let mesh = read_fixture("block_3d.msh");
        let problem = hertz_block(&mesh.bodies[0]);
        let mut stats = Default::default();
        let system = assemble(&problem, &mut stats, false).unwrap();
        let solver = BodySolver::cg_amg(
            system.stiffness.whole().unwrap(),
            system.dim,
            system.stiffness.coordinates().unwrap(),
            1e-10,
        )
        .unwrap();
        let reference = solve(&problem, &settings(BodySolverKind::Cholesky)).unwrap();
        let n = system.f_c.len();
        // Columns: f_c, 2 f_c, a point load at a free dof, and zero.
        let free = (0..n).find(|&d| !system.constraints.is_fixed(d)).unwrap();
        let mut rhs = system.f_c.to_vec();
        rhs.extend(system.f_c.scaled(2.0));
        rhs.extend((0..n).map(|d| if d == free { 1.0 } else { 0.0 }));
        rhs.extend(vec![0.0; n]);
        let columns = rhs.clone();
        let most = solver.solve_in_place(&mut rhs, 4).unwrap();
        assert!(most > 0);
        let x = |j: usize| &rhs[j * n..(j + 1) * n];
        assert!(relative_difference(x(0), &reference.displacement) < 1e-8);
        let doubled: Vec<f64> = reference.displacement.iter().map(|v| 2.0 * v).collect();
        assert!(relative_difference(x(1), &doubled) < 1e-8);
        assert!(
            relative_residual(
                system.stiffness.whole().unwrap(),
                x(2),
                &columns[2 * n..3 * n]
            ) <= 1e-10
        );
        assert!(x(3).iter().all(|&v| v == 0.0));
        // And again, the same answer from the same setup.
        let mut again = system.f_c.to_vec();
        solver.solve_in_place(&mut again, 1).unwrap();
        assert!(relative_difference(&again, x(0)) < 1e-12);
        let residual = mat_vec(system.stiffness.whole().unwrap(), &again);
        assert!(relative_difference(&residual, &system.f_c.to_vec()) < 1e-8);
    }

    #[test]
    fn an_indefinite_matrix_is_a_typed_error_not_a_crash() {
        let mesh = read_fixture("block_2d.msh");
        let problem = hertz_block(&mesh.bodies[0]);
        let mut stats = Default::default();
        let system = assemble(&problem, &mut stats, false).unwrap();
        // K_c - sigma I, sigma the mean diagonal entry: inside K_c's spectrum.
        let (symbolic, values) = system.stiffness.whole().unwrap().parts();
        let n = symbolic.ncols();
        let mut shifted = values.to_vec();
        let diagonal: Vec<usize> = (0..n)
            .map(|j| {
                let rows = &symbolic.row_idx()[symbolic.col_ptr()[j]..symbolic.col_ptr()[j + 1]];
                symbolic.col_ptr()[j] + rows.binary_search(&j).unwrap()
            })
            .collect();
        let sigma = diagonal.iter().map(|&p| values[p]).sum::<f64>() / n as f64;
        for &p in &diagonal {
            shifted[p] -= sigma;
        }
        let shifted = faer::sparse::SparseColMat::new(symbolic.to_owned().unwrap(), shifted);
        let outcome = BodySolver::cg_amg(
            &shifted,
            system.dim,
            system.stiffness.coordinates().unwrap(),
            1e-10,
        )
        .and_then(|solver| solver.solve_in_place(&mut system.f_c.to_vec(), 1));
        match outcome {
            Err(e @ (LinalgError::NotConverged { .. } | LinalgError::Petsc { .. })) => {
                eprintln!("{e}");
            }
            other => panic!("expected a CG or PETSc error, got {other:?}"),
        }
    }

    /// PETSc is initialized without its signal handlers (which it installs by default for
    /// SIGFPE, SIGSEGV, SIGBUS, SIGILL and SIGHUP): a fault stays the process's own, not a
    /// PETSc message and `MPI_Abort`. (Open MPI's initialization installs its own backtrace
    /// printer on SIGFPE, SIGSEGV and SIGBUS where no handler was set; it re-raises.)
    #[test]
    fn petsc_installs_no_signal_handler() {
        let mesh = read_fixture("block_2d.msh");
        let problem = hertz_block(&mesh.bodies[0]);
        solve(&problem, &settings(BodySolverKind::CgAmg)).unwrap();
        for signal in [
            libc::SIGFPE,
            libc::SIGSEGV,
            libc::SIGBUS,
            libc::SIGILL,
            libc::SIGHUP,
        ] {
            // SAFETY: a query (null new action) into a zeroed sigaction, then a lookup of the
            // handler's address among the loaded libraries.
            let library = unsafe {
                let mut old: libc::sigaction = std::mem::zeroed();
                assert_eq!(libc::sigaction(signal, std::ptr::null(), &mut old), 0);
                let mut info: libc::Dl_info = std::mem::zeroed();
                if old.sa_sigaction > 1
                    && libc::dladdr(old.sa_sigaction as *const libc::c_void, &mut info) != 0
                    && !info.dli_fname.is_null()
                {
                    std::ffi::CStr::from_ptr(info.dli_fname)
                        .to_string_lossy()
                        .into_owned()
                } else {
                    String::new()
                }
            };
            let file = library.rsplit('/').next().unwrap_or_default();
            assert!(
                !file.starts_with("libpetsc"),
                "signal {signal} is handled by {library}"
            );
        }
    }

    #[test]
    fn inconsistent_sizes_are_errors() {
        let mesh = read_fixture("block_2d.msh");
        let problem = hertz_block(&mesh.bodies[0]);
        let mut stats = Default::default();
        let system = assemble(&problem, &mut stats, false).unwrap();
        let short = &system.stiffness.coordinates().unwrap()[1..];
        assert!(matches!(
            BodySolver::cg_amg(system.stiffness.whole().unwrap(), system.dim, short, 1e-10),
            Err(LinalgError::Sizes(_))
        ));
    }

    #[test]
    fn solves_on_several_threads_at_once_agree() {
        let mesh = read_fixture("block_3d.msh");
        let problem = hertz_block(&mesh.bodies[0]);
        let reference = solve(&problem, &settings(BodySolverKind::Cholesky)).unwrap();
        std::thread::scope(|scope| {
            let handles: Vec<_> = (0..4)
                .map(|_| {
                    scope.spawn(|| {
                        (0..3)
                            .map(|_| {
                                solve(&problem, &settings(BodySolverKind::CgAmg))
                                    .unwrap()
                                    .displacement
                            })
                            .collect::<Vec<_>>()
                    })
                })
                .collect();
            for handle in handles {
                for u in handle.join().unwrap() {
                    assert!(relative_difference(&u, &reference.displacement) < 1e-8);
                }
            }
        });
    }

    #[test]
    fn contact_with_cg_amg_agrees_with_cholesky() {
        use internodes::contact::{ContactStatus, solve_contact};
        use internodes::mesh::read_msh;
        let (_dir, path) =
            common::contact::with_rollers(common::contact::stacked_blocks(3), 3).write();
        let case = Case::load(&path).unwrap();
        let mesh = read_msh(&case.mesh).unwrap();
        let run = |body| {
            let problem = case.contact_problems(&mesh).unwrap().remove(0);
            solve_contact(vec![problem], &settings(body), &case.load_steps())
                .unwrap()
                .solutions
                .remove(0)
        };
        let cholesky = run(BodySolverKind::Cholesky);
        let cg = run(BodySolverKind::CgAmg);
        assert_eq!(cg.status, ContactStatus::Converged);
        let d = relative_difference(&cg.force_primary, &cholesky.force_primary);
        assert!(d < 1e-8, "contact force: relative difference {d:.2e}");
        let d = relative_difference(
            &cg.primary_fields.pressure,
            &cholesky.primary_fields.pressure,
        );
        assert!(d < 1e-8, "pressure: relative difference {d:.2e}");
    }
}
