//! Results do not depend on the number of threads, bit for bit: assembly, Cholesky solves and an
//! elastic solve in rayon pools of 1, 2 and 3 threads, on a cube large enough for faer's
//! thread-split kernels (solves with faer's `Par::rayon(0)` fail here); and whole runs of the
//! command line with `RAYON_NUM_THREADS` = 1, 2, 3 on fixtures (one body; two bodies in contact,
//! in load steps). The fixtures are too small for those kernels: the runs check that the
//! command line honours the variable and that the rest of the pipeline (interpolation, active
//! sets, load steps, output) stays identical.

mod common;

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

use common::block_3d_case;
use common::case_builder::CaseFile;
use internodes::elastic::{
    DirichletCondition, ElasticProblem, SolveStats, SolverSettings, assemble, solve,
};
use internodes::fem::Material;
use internodes::fem::assembly::{assemble_stiffness, node_coords, stiffness_pattern};
use internodes::fem::kernels::tetrahedron_stiffness;
use internodes::linalg::{Cholesky, CholeskySymbolic, Ordering};
use internodes::mesh::BodyMesh;

const THREADS: [usize; 3] = [1, 2, 3];

/// Runs `f` in a rayon pool of `threads` threads.
fn with_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
        .install(f)
}

/// The unit cube cut into `n^3` cubes of 6 tetrahedra each, its nodes slightly and
/// reproducibly moved off the grid so that no two element matrices are alike; its base
/// (z = 0) is the point group `base`. At n = 12 (6,591 dofs) the top separator of the nested
/// dissection holds about 500 dofs: large enough for dense kernels that split work by thread
/// count (faer's parallel matrix-vector product starts at 256 x 256).
fn jittered_cube(n: usize) -> BodyMesh {
    let index = |i: usize, j: usize, k: usize| (k * (n + 1) + j) * (n + 1) + i;
    let h = 1.0 / n as f64;
    let mut coords = Vec::new();
    for k in 0..=n {
        for j in 0..=n {
            for i in 0..=n {
                let node = index(i, j, k);
                let jitter = |axis: usize| {
                    let hash = (node * 2654435761 + axis * 40503) % 1000;
                    0.2 * h * (hash as f64 / 1000.0 - 0.5)
                };
                coords.push([
                    i as f64 * h + jitter(0),
                    j as f64 * h + jitter(1),
                    k as f64 * h + jitter(2),
                ]);
            }
        }
    }
    // Kuhn's 6 tetrahedra of a cube, all sharing its main diagonal 0-7.
    const PATHS: [[usize; 2]; 6] = [[1, 3], [1, 5], [2, 3], [2, 6], [4, 5], [4, 6]];
    let mut cells = Vec::new();
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let corner = |c: usize| index(i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2));
                for [a, b] in PATHS {
                    cells.extend([corner(0), corner(a), corner(b), corner(7)].map(|n| n as u32));
                }
            }
        }
    }
    let num_cells = cells.len() / 4;
    BodyMesh {
        name: "cube".into(),
        physical_tag: 1,
        dim: 3,
        node_tags: (1..=coords.len() as u64).collect(),
        coords: coords.into(),
        cells,
        cell_tags: (1..=num_cells as u64).collect(),
        boundary_groups: BTreeMap::new(),
        point_groups: BTreeMap::from([("base".to_string(), (0..(n + 1) * (n + 1)).collect())]),
        part: None,
    }
}

fn material() -> Material {
    Material::new(1000.0, 0.3).expect("valid material")
}

#[test]
fn stiffness_assembly_is_identical_for_any_thread_count() {
    let body = jittered_cube(12);
    let material = material();
    let pattern = stiffness_pattern(&body);
    // The plain sequential scatter, one cell after another.
    let mut sequential = vec![0.0; pattern.nnz()];
    for c in 0..body.num_cells() {
        let ke = tetrahedron_stiffness(&node_coords(&body.coords, &body.cell(c)), &material);
        pattern.add_element(&body.cell(c), ke.as_slice(), &mut sequential);
    }
    for threads in THREADS {
        let k = with_threads(threads, || assemble_stiffness(&body, &material, &pattern));
        assert!(
            k.val()
                .iter()
                .zip(&sequential)
                .all(|(a, b)| a.to_bits() == b.to_bits()),
            "{threads} threads: K differs from the sequential assembly"
        );
    }
}

/// The cube clamped on its base (a point group of the nodes at z = 0) under an oblique body
/// force.
fn clamped_cube(body: &BodyMesh) -> ElasticProblem<'_> {
    ElasticProblem::new(
        body,
        material(),
        vec![DirichletCondition {
            group: "base".into(),
            components: [Some(0.0); 3],
            path: None,
        }],
        Vec::new(),
        Some([0.3, 0.1, -1.0]),
    )
    .expect("a well-posed problem")
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

#[test]
fn cholesky_solves_are_identical_for_any_thread_count() {
    let body = jittered_cube(12);
    let problem = clamped_cube(&body);
    let system = assemble(&problem, &mut SolveStats::default(), false).unwrap();
    let n = body.num_dofs();
    let num_rhs = 40;
    let rhs: Vec<f64> = (0..n * num_rhs)
        .map(|i| ((i * 7919) % 1000) as f64 / 1000.0 - 0.5)
        .collect();
    let solve = |threads: usize| {
        with_threads(threads, || {
            let symbolic = CholeskySymbolic::new(
                system.graph.as_ref().expect("the whole K_c has its graph"),
                system.stiffness.whole().unwrap().symbolic(),
                Ordering::NestedDissection,
            )
            .unwrap();
            let factor = Cholesky::factorize(symbolic, system.stiffness.whole().unwrap()).unwrap();
            let mut one = system.f_c.to_vec();
            factor.solve_in_place(&mut one, 1);
            let mut many = rhs.clone();
            factor.solve_in_place(&mut many, num_rhs);
            (one, many)
        })
    };
    let (one, many) = solve(1);
    assert!(one.iter().any(|&u| u != 0.0));
    for threads in &THREADS[1..] {
        let (one_t, many_t) = solve(*threads);
        assert!(
            bits(&one) == bits(&one_t),
            "{threads} threads: one right-hand side differs"
        );
        assert!(
            bits(&many) == bits(&many_t),
            "{threads} threads: {num_rhs} right-hand sides differ"
        );
    }
}

#[test]
fn an_elastic_solve_is_identical_for_any_thread_count() {
    let body = jittered_cube(12);
    let problem = clamped_cube(&body);
    let settings = SolverSettings {
        verbose: false,
        ..SolverSettings::default()
    };
    let solve = |threads: usize| with_threads(threads, || solve(&problem, &settings).unwrap());
    let reference = solve(1);
    for threads in &THREADS[1..] {
        let solution = solve(*threads);
        assert!(
            bits(&solution.displacement) == bits(&reference.displacement),
            "{threads} threads: the displacement differs"
        );
    }
}

/// `internodes solve` of `case` with `RAYON_NUM_THREADS=threads` into `out`; returns the listed
/// datasets of `solution.h5`.
fn solve_with_threads(case: &Path, out: &Path, threads: usize, fields: &[&str]) -> Vec<Vec<f64>> {
    let output = Command::new(env!("CARGO_BIN_EXE_internodes"))
        .args(["solve", case.to_str().unwrap(), "--quiet", "--output"])
        .arg(out)
        .env("RAYON_NUM_THREADS", threads.to_string())
        .output()
        .expect("run the internodes binary");
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let file = hdf5::File::open(out.join("solution.h5")).unwrap();
    fields
        .iter()
        .map(|name| file.dataset(name).unwrap().read_raw::<f64>().unwrap())
        .collect()
}

/// Solves `case` with 1, 2 and 3 threads and checks `fields` are equal bit for bit.
fn assert_thread_independent(case: &CaseFile, fields: &[&str]) {
    let (dir, path) = case.write();
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let reference = solve_with_threads(&path, &dir.path().join("t1"), 1, fields);
    for threads in &THREADS[1..] {
        let out = dir.path().join(format!("t{threads}"));
        let result = solve_with_threads(&path, &out, *threads, fields);
        for ((name, a), b) in fields.iter().zip(&reference).zip(&result) {
            assert!(!a.is_empty());
            assert!(bits(a) == bits(b), "{name} differs with {threads} threads");
        }
    }
}

#[test]
fn a_single_body_run_is_identical_for_any_thread_count() {
    assert_thread_independent(&block_3d_case(), &["fields/displacement", "fields/stress"]);
}

#[test]
fn a_contact_run_is_identical_for_any_thread_count() {
    // Two stacked 3D blocks with non-matching meshes, the upper one pressed down, each pinned at
    // corners only (the frictionless patch test of tests/contact_accuracy.rs), in two load steps.
    let case = common::contact::pinned_at_corners(common::contact::stacked_blocks(3), 3)
        .load_steps(&[0.5, 1.0]);
    assert_thread_independent(
        &case,
        &[
            "fields/displacement",
            "fields/contact_pressure",
            "fields/contact_traction",
        ],
    );
}

/// V-cycles of CG + AMG (feature `petsc`): applied from several threads at once, to distinct
/// objects (which run at the same time) or to one object (which take turns), they give the
/// same bits as applied one after another.
#[cfg(feature = "petsc")]
mod v_cycles {
    use super::*;
    use internodes::linalg::BodySolver;
    use std::sync::Barrier;

    /// The clamped cube's `K_c` on an `n^3` grid with its CG + AMG solver.
    fn cube_solver(n: usize) -> BodySolver {
        let body = jittered_cube(n);
        let problem = clamped_cube(&body);
        let mut stats = SolveStats::default();
        let system = assemble(&problem, &mut stats, false).expect("assembly");
        BodySolver::cg_amg(
            system.stiffness.whole().unwrap(),
            system.dim,
            system.stiffness.coordinates().unwrap(),
            1e-10,
        )
        .expect("set-up")
    }

    /// The `k`-th right-hand side of `n` values: reproducible, different for every `k`.
    fn rhs(n: usize, k: usize) -> Vec<f64> {
        (0..n)
            .map(|i| ((i * 7919 + k * 104_729) % 1000) as f64 / 500.0 - 1.0)
            .collect()
    }

    /// The bits of `x = P^-1 rhs(k)` for each `k` of `ks`, one after another.
    fn apply_all(solver: &BodySolver, n: usize, ks: impl Iterator<Item = usize>) -> Vec<Vec<u64>> {
        ks.map(|k| {
            let mut x = vec![0.0; n];
            solver.precondition(&rhs(n, k), &mut x).expect("a V-cycle");
            bits(&x)
        })
        .collect()
    }

    const APPLICATIONS: usize = 300;

    #[test]
    fn v_cycles_of_two_bodies_at_once_match_them_one_after_another() {
        let bodies = [cube_solver(12), cube_solver(9)];
        // Without options of PETSc's own, the V-cycles do run at once (else they take turns).
        if std::env::var_os("PETSC_OPTIONS").is_none() {
            assert!(internodes::linalg::petsc::concurrent_v_cycles());
            // The set-ups left PETSc's options as they found them (the shim sets
            // -matptap_via around a one-process set-up alone).
            assert!(internodes::linalg::petsc::options_are_ours().expect("PETSc's options"));
        }
        let sizes = [3 * 13 * 13 * 13, 3 * 10 * 10 * 10];
        // Fresh objects first: their first V-cycles, too, run at once.
        let mut rounds = Vec::new();
        let mut sequential = Vec::new();
        for round in 0..3 {
            if round == 1 {
                sequential = (0..2)
                    .map(|b| apply_all(&bodies[b], sizes[b], 0..APPLICATIONS))
                    .collect();
            }
            let start = Barrier::new(2);
            let concurrent: Vec<_> = std::thread::scope(|scope| {
                let handles: Vec<_> = (0..2)
                    .map(|b| {
                        let (solver, start) = (&bodies[b], &start);
                        scope.spawn(move || {
                            start.wait();
                            apply_all(solver, sizes[b], 0..APPLICATIONS)
                        })
                    })
                    .collect();
                handles.into_iter().map(|h| h.join().unwrap()).collect()
            });
            rounds.push(concurrent);
        }
        for (round, concurrent) in rounds.iter().enumerate() {
            for b in 0..2 {
                for (k, (c, s)) in concurrent[b].iter().zip(&sequential[b]).enumerate() {
                    assert!(
                        c == s,
                        "round {round}, body {b}, application {k}: bits differ"
                    );
                }
            }
        }
        // And through rayon::join, as the coupled Krylov solve calls them.
        let (x0, x1) = rayon::join(
            || apply_all(&bodies[0], sizes[0], 0..APPLICATIONS),
            || apply_all(&bodies[1], sizes[1], 0..APPLICATIONS),
        );
        assert!(x0 == sequential[0] && x1 == sequential[1]);
    }

    #[test]
    fn v_cycles_of_one_body_from_several_threads_match_them_one_after_another() {
        const THREADS: usize = 4;
        const EACH: usize = 75;
        let solver = cube_solver(10);
        let n = 3 * 11 * 11 * 11;
        let sequential = apply_all(&solver, n, 0..THREADS * EACH);
        let start = Barrier::new(THREADS);
        let concurrent: Vec<Vec<Vec<u64>>> = std::thread::scope(|scope| {
            let handles: Vec<_> = (0..THREADS)
                .map(|t| {
                    let (solver, start) = (&solver, &start);
                    scope.spawn(move || {
                        start.wait();
                        apply_all(solver, n, (0..EACH).map(|j| j * THREADS + t))
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap()).collect()
        });
        for (t, results) in concurrent.iter().enumerate() {
            for (j, x) in results.iter().enumerate() {
                let k = j * THREADS + t;
                assert!(
                    *x == sequential[k],
                    "thread {t}, application {k}: bits differ"
                );
            }
        }
    }

    /// Set-ups, solves and destruction of other objects while V-cycles run: the exclusive
    /// calls wait for the V-cycles, and the V-cycles' bits do not change.
    #[test]
    fn v_cycles_beside_set_ups_and_solves_match_them_alone() {
        let body = cube_solver(9);
        let n = 3 * 10 * 10 * 10;
        let sequential = apply_all(&body, n, 0..APPLICATIONS);
        let concurrent = std::thread::scope(|scope| {
            let cycles = scope.spawn(|| apply_all(&body, n, 0..APPLICATIONS));
            scope.spawn(|| {
                for _ in 0..3 {
                    let other = cube_solver(6);
                    let mut u = rhs(3 * 7 * 7 * 7, 1);
                    other.solve_in_place(&mut u, 1).expect("a CG solve");
                    let mut x = vec![0.0; u.len()];
                    other.precondition(&u, &mut x).expect("a V-cycle");
                }
            });
            cycles.join().unwrap()
        });
        assert!(concurrent == sequential);
    }
}
