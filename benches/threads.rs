//! Timings of the parallel phases with 1 and 2 threads, and a check that both give the same
//! results bit for bit.
//!
//! ```sh
//! cargo bench --bench threads -- CASE.toml [LEVEL [REPEATS]]
//! cargo bench --bench threads -- geo/hemisphere_on_block.toml 0 10
//! ```
//!
//! A case naming a `.geo` is meshed with gmsh first, with its `geo_parameters` and the optional
//! `LEVEL` (ignored for a `.msh`). Each phase runs `REPEATS` times (default 10) in rayon pools
//! of 1 and 2 threads, alternately (the machine is shared: alternating spreads other processes'
//! load over both), and the fastest run is reported.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use internodes::case::Case;
use internodes::contact::ContactSolver;
use internodes::elastic::{SolveStats, StepFactors, assemble, solve};
use internodes::fem::assembly::{assemble_stiffness, stiffness_pattern};
use internodes::linalg::{Cholesky, CholeskySymbolic};
use internodes::mesh::{mesh_geo, read_msh};

const REPEATS: usize = 10;
/// Right-hand sides of the multi-column solve (a contact interface of this many multipliers).
const NUM_RHS: usize = 256;
const THREADS: [usize; 2] = [1, 2];

fn main() {
    // As the command line does: faer's own parallelism would otherwise cut its LU
    // factorizations by the pool's thread count, and the answers would differ in their last bits
    // (`src/lib.rs`, "Threads").
    faer::set_global_parallelism(faer::Par::Seq);
    // `cargo bench` passes `--bench` to harness-less benches; the case is the first other
    // argument.
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    let Some(case_path) = args.first() else {
        eprintln!("usage: cargo bench --bench threads -- CASE.toml [LEVEL [REPEATS]]");
        std::process::exit(2);
    };
    let level: Option<f64> = args.get(1).map(|l| {
        l.parse()
            .unwrap_or_else(|_| exit(format!("LEVEL {l} is not a number")))
    });
    let repeats: usize = args.get(2).map_or(REPEATS, |r| {
        r.parse()
            .unwrap_or_else(|_| exit(format!("REPEATS {r} is not a count")))
    });
    let mut case = Case::load(Path::new(case_path)).unwrap_or_else(exit);
    case.solver.verbose = false;
    let scratch = tempfile::tempdir().expect("a temporary folder");
    let msh = mesh_file(&case, level, scratch.path());
    let mesh = read_msh(&msh).unwrap_or_else(exit);
    let pools: Vec<rayon::ThreadPool> = THREADS
        .iter()
        .map(|&t| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .unwrap()
        })
        .collect();

    let mut best: BTreeMap<(String, usize), f64> = BTreeMap::new();
    let mut results: BTreeMap<(String, usize), Vec<u64>> = BTreeMap::new();
    let mut record = |name: String, threads: usize, seconds: f64| {
        let entry = best.entry((name, threads)).or_insert(f64::INFINITY);
        *entry = entry.min(seconds);
    };
    let mut keep = |name: &str, threads: usize, values: &[f64]| {
        let bits = values.iter().map(|v| v.to_bits()).collect();
        results.insert((name.to_string(), threads), bits);
    };

    // The bodies, assembled and factored once for the solve timings.
    let bodies: Vec<_> = case
        .bodies
        .iter()
        .map(|spec| {
            let body = case.body_mesh(&mesh, spec).unwrap_or_else(exit);
            let problem = case.elastic_problem(body, spec).unwrap_or_else(exit);
            let system = assemble(&problem, &mut SolveStats::default(), false).unwrap();
            let symbolic = CholeskySymbolic::new(
                system.graph.as_ref().expect("the whole K_c has its graph"),
                system.stiffness.whole().unwrap().symbolic(),
                case.solver.ordering,
            )
            .unwrap();
            let factor = Cholesky::factorize(symbolic, system.stiffness.whole().unwrap()).unwrap();
            (body, problem, system, factor)
        })
        .collect();
    let contact = case.contact_problems(&mesh).unwrap_or_else(exit);

    for _ in 0..repeats {
        for (pool, &threads) in pools.iter().zip(&THREADS) {
            pool.install(|| {
                for (body, problem, system, factor) in &bodies {
                    let name =
                        |what: &str| format!("{} ({} dofs): {what}", body.name, body.num_dofs());
                    let (seconds, pattern) = timed(|| stiffness_pattern(body));
                    record(name("sparsity pattern"), threads, seconds);
                    let (seconds, k) =
                        timed(|| assemble_stiffness(body, &problem.material, &pattern));
                    record(name("stiffness K"), threads, seconds);
                    keep(&name("K"), threads, k.val());

                    let (seconds, _) = timed(|| {
                        let symbolic = CholeskySymbolic::new(
                            system.graph.as_ref().expect("the whole K_c has its graph"),
                            system.stiffness.whole().unwrap().symbolic(),
                            case.solver.ordering,
                        )
                        .unwrap();
                        Cholesky::factorize(symbolic, system.stiffness.whole().unwrap()).unwrap()
                    });
                    record(name("Cholesky (ordering + numeric)"), threads, seconds);

                    let n = system.f_c.len();
                    let (seconds, x) = timed(|| {
                        let mut x = system.f_c.to_vec();
                        factor.solve_in_place(&mut x, 1);
                        x
                    });
                    record(name("solve, 1 right-hand side"), threads, seconds);
                    keep(&name("1 solution"), threads, &x);
                    let rhs: Vec<f64> = (0..n * NUM_RHS)
                        .map(|i| ((i * 7919) % 1000) as f64 / 1000.0 - 0.5)
                        .collect();
                    let (seconds, x) = timed(|| {
                        let mut x = rhs;
                        factor.solve_in_place(&mut x, NUM_RHS);
                        x
                    });
                    record(
                        name(&format!("solve, {NUM_RHS} right-hand sides")),
                        threads,
                        seconds,
                    );
                    keep(&name(&format!("{NUM_RHS} solutions")), threads, &x);
                }
                match contact.first() {
                    Some(problem) => {
                        let (seconds, mut solver) = timed(|| {
                            ContactSolver::new(std::slice::from_ref(problem), &case.solver).unwrap()
                        });
                        record("contact set-up".into(), threads, seconds);
                        let (seconds, solution) = timed(|| {
                            solver
                                .solve(&StepFactors::uniform(1.0), None)
                                .unwrap()
                                .remove(0)
                        });
                        record(
                            format!(
                                "contact solve ({} iterations, {} active)",
                                solution.history.len(),
                                solution
                                    .primary_fields
                                    .active
                                    .iter()
                                    .filter(|&&a| a)
                                    .count()
                            ),
                            threads,
                            seconds,
                        );
                        keep("contact u1", threads, &solution.primary.displacement);
                        keep("contact u2", threads, &solution.secondary.displacement);
                        keep(
                            "contact pressure",
                            threads,
                            &solution.primary_fields.pressure,
                        );
                    }
                    None => {
                        for (_, problem, _, _) in &bodies {
                            let (seconds, solution) =
                                timed(|| solve(problem, &case.solver).unwrap());
                            record(
                                format!("elastic solve of '{}'", problem.body.name),
                                threads,
                                seconds,
                            );
                            keep(&problem.body.name, threads, &solution.displacement);
                        }
                    }
                }
            });
        }
    }

    println!(
        "{} ({} bodies), fastest of {repeats} runs, seconds",
        msh.display(),
        bodies.len()
    );
    println!(
        "{:<64} {:>9} {:>9} {:>8}",
        "phase", "1 thread", "2 threads", "speed-up"
    );
    let names: Vec<&String> = best
        .keys()
        .map(|(n, _)| n)
        .collect::<std::collections::BTreeSet<_>>()
        .into_iter()
        .collect();
    for name in names {
        let one = best[&(name.clone(), 1)];
        let two = best[&(name.clone(), 2)];
        println!("{name:<64} {one:>9.4} {two:>9.4} {:>7.2}x", one / two);
    }
    let differing: Vec<&String> = results
        .keys()
        .filter(|(_, t)| *t == 1)
        .map(|(n, _)| n)
        .filter(|n| results[&((*n).clone(), 1)] != results[&((*n).clone(), 2)])
        .collect();
    if differing.is_empty() {
        println!("1 and 2 threads: every result identical bit for bit");
    } else {
        println!("1 and 2 threads: DIFFERENT results: {differing:?}");
        std::process::exit(1);
    }
}

/// Bad input ends the benchmark with its message.
fn exit<T>(error: impl std::fmt::Display) -> T {
    eprintln!("error: {error}");
    std::process::exit(1)
}

fn timed<T>(f: impl FnOnce() -> T) -> (f64, T) {
    let start = Instant::now();
    let value = f();
    (start.elapsed().as_secs_f64(), value)
}

/// The case's mesh: its `.msh`, or its `.geo` meshed by gmsh into `dir`.
fn mesh_file(case: &Case, level: Option<f64>, dir: &Path) -> PathBuf {
    if case.mesh.extension().is_none_or(|e| e != "geo") {
        return case.mesh.clone();
    }
    let mut parameters: Vec<(String, f64)> = case
        .geo_parameters
        .iter()
        .map(|(k, v)| (k.clone(), *v))
        .collect();
    parameters.extend(level.map(|l| ("level".to_string(), l)));
    let msh = dir.join("mesh.msh");
    mesh_geo(&case.mesh, &msh, &parameters).unwrap_or_else(|e| exit(format!("gmsh: {e}")));
    msh
}
