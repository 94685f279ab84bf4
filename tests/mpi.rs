//! Distributed runs: `mpirun -n 2 internodes solve CASE` gives the answer of one process and
//! writes the same output folder; a rank that fails alone ends every rank; what cannot be
//! distributed is refused.
//!
//! The reference is the serial run with the same body solver (CG + AMG): two ranks build GAMG
//! on a partitioned matrix, a different preconditioner of the same systems, so the answers
//! agree to the solves' tolerance, not bit for bit. The bound is the one that
//! `tests/contact_solvers.rs` sets between CG + AMG and Cholesky bodies (1e-6 of the largest
//! value; its reason is there: gaps settle within 1e-5 h); measured here 2e-8 to 7e-8 on most
//! cases. It asks for less than the settled gaps imply (1e-5 h is 1.5e-5 of the hemisphere's
//! approach), so at the default tolerance it holds while the two preconditioners lead the loop
//! along close paths; the cases whose runs ended farther apart (the floating ball, the Coulomb
//! pair, the force-controlled hemisphere) are solved to 1e-9 h, where the answer is pinned far
//! below the bound.

#![cfg(feature = "petsc")]

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

const BINARY: &str = env!("CARGO_BIN_EXE_internodes");

/// Agreement of a 2-rank run with the serial one (see the module doc).
const AGREEMENT: f64 = 1e-6;

/// Longer than any run here takes (a few seconds each); a run still going then is hung.
const HANG: Duration = Duration::from_secs(300);

/// `mpirun` with the flags a container's root needs: `ranks` processes of the binary with `args`.
fn mpirun(ranks: usize, args: &[&str]) -> Output {
    let mut command = Command::new("mpirun");
    command.args([
        "--allow-run-as-root",
        "--oversubscribe",
        "-n",
        &ranks.to_string(),
        BINARY,
    ]);
    command.args(args);
    // Open MPI's shared-memory transport copies between processes with CMA (process_vm_readv)
    // where the kernel lets it, which some containers forbid (a warning per message); plain
    // copies through shared memory work everywhere.
    command.env("OMPI_MCA_btl_vader_single_copy_mechanism", "none");
    run_within(command, HANG)
}

/// Runs `command`, failing the test if it has not ended after `limit`.
fn run_within(mut command: Command, limit: Duration) -> Output {
    let mut child = command
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("mpirun (Debian: openmpi-bin) on PATH");
    let start = Instant::now();
    while child.try_wait().expect("waiting for mpirun").is_none() {
        if start.elapsed() > limit {
            child.kill().ok();
            let output = child.wait_with_output().unwrap();
            panic!(
                "still running after {limit:?}: a hang\n{}",
                String::from_utf8_lossy(&output.stderr)
            );
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    child.wait_with_output().unwrap()
}

fn serial(args: &[&str]) -> Output {
    Command::new(BINARY).args(args).output().unwrap()
}

fn text(output: &Output) -> String {
    format!(
        "status {:?}\nstdout:\n{}\nstderr:\n{}",
        output.status,
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    )
}

/// The example case `geo/<name>.toml`, its mesh path made absolute, with `extra` appended,
/// written into `dir`.
fn example_case(dir: &Path, name: &str, extra: &str) -> PathBuf {
    edited_example_case(dir, name, extra, &|_| {})
}

/// [`example_case`] with `edit` applied to its table first.
fn edited_example_case(
    dir: &Path,
    name: &str,
    extra: &str,
    edit: &dyn Fn(&mut toml::Table),
) -> PathBuf {
    let geo = Path::new(env!("CARGO_MANIFEST_DIR")).join("geo");
    let original = std::fs::read_to_string(geo.join(format!("{name}.toml"))).unwrap();
    let mut case: toml::Table = toml::from_str(&original).unwrap();
    edit(&mut case);
    let mesh = case["mesh"].as_str().unwrap().to_string();
    case.insert("mesh".into(), geo.join(mesh).display().to_string().into());
    let mut text = toml::to_string(&case).unwrap();
    text.push_str(extra);
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

fn read(dir: &Path, name: &str) -> Vec<f64> {
    let file = hdf5::File::open(dir.join("solution.h5")).unwrap();
    file.dataset(name).unwrap().read_raw::<f64>().unwrap()
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

/// Each pair's summary: `contact` (one pair) or `contacts` (several).
fn pairs(summary: &serde_json::Value) -> Vec<serde_json::Value> {
    match summary.get("contact") {
        Some(pair) => vec![pair.clone()],
        None => summary["contacts"].as_array().cloned().unwrap_or_default(),
    }
}

/// Whether each iteration of a pair's history (the last load step's) paired the interface again.
fn paired_again(pair: &serde_json::Value) -> Vec<bool> {
    (pair["iterations"].as_array().unwrap().iter())
        .map(|record| record["paired_again"].as_bool().unwrap())
        .collect()
}

/// `max |a - b| / max |a|`.
fn relative_difference(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let diff = a
        .iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    if scale > 0.0 { diff / scale } else { diff }
}

/// The mesh datasets of two runs' `solution.h5` are the same: on ranks, rank 0 holds only
/// its part of the cells and the others send it the rows of theirs, which must land in the
/// serial run's order.
fn same_mesh_written(one: &Path, two: &Path, name: &str) {
    for dataset in [
        "mesh/geometry",
        "mesh/node_tag",
        "mesh/topology",
        "mesh/cell_tag",
        "mesh/cell_body",
    ] {
        assert_eq!(read(one, dataset), read(two, dataset), "{name}: {dataset}");
    }
}

fn files(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// Solves the example `name` with CG + AMG bodies on one process and on `ranks` ranks, and
/// compares everything a user reads: statuses, active sets, forces per load step, fields, the
/// accuracy report, the folder's files; and the rank record of the summary.
///
/// `contact_settings` go into every contact table. `laterals_from_step`: the load step from
/// which every force component is compared; before it, only the component along the load
/// (see the floating ball's test).
fn ranks_give_the_serial_answer(
    ranks: usize,
    name: &str,
    contact_settings: &str,
    laterals_from_step: usize,
) {
    ranks_give_the_serial_answer_of(
        ranks,
        name,
        contact_settings,
        laterals_from_step,
        0,
        &|_| {},
    );
}

/// [`ranks_give_the_serial_answer`] with `edit` applied to the example's table, and
/// `extra_iterations` more active-set iterations allowed to one run than to the other in a
/// step (0 but where the runs are solved to a tight tolerance: see the Coulomb pair's test).
/// Returns the folder of the runs (the serial run's output in `one`).
fn ranks_give_the_serial_answer_of(
    ranks: usize,
    name: &str,
    contact_settings: &str,
    laterals_from_step: usize,
    extra_iterations: u64,
    edit: &dyn Fn(&mut toml::Table),
) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let cg_amg = "\n[solver]\nbody = \"cg-amg\"\n";
    let case = edited_example_case(dir.path(), name, cg_amg, edit);
    if !contact_settings.is_empty() {
        let text = std::fs::read_to_string(&case).unwrap();
        let text = text
            .replace(
                "[[contact]]\n",
                &format!("[[contact]]\n{contact_settings}\n"),
            )
            .replace("[contact]\n", &format!("[contact]\n{contact_settings}\n"));
        std::fs::write(&case, text).unwrap();
    }
    let case = case.to_str().unwrap();
    let (one, two) = (dir.path().join("one"), dir.path().join("two"));
    let serial_run = serial(&["solve", case, "-q", "-o", one.to_str().unwrap()]);
    let parallel_run = mpirun(ranks, &["solve", case, "-q", "-o", two.to_str().unwrap()]);
    assert!(
        serial_run.status.success(),
        "{name} serial: {}",
        text(&serial_run)
    );
    assert!(
        parallel_run.status.success(),
        "{name} on {ranks} ranks: {}",
        text(&parallel_run)
    );
    // Quiet (-q): no rank prints a progress line, a warning or an error.
    let printed = String::from_utf8_lossy(&parallel_run.stderr);
    assert!(
        !printed.contains("error")
            && !printed.contains("warning")
            && !printed.contains("contact status"),
        "{}",
        text(&parallel_run)
    );

    assert_eq!(
        files(&one),
        files(&two),
        "{name}: the output folders' files"
    );
    same_mesh_written(&one, &two, name);
    for field in [
        "fields/displacement",
        "fields/contact_pressure",
        "fields/strain",
        "fields/stress",
        "fields/von_mises",
    ] {
        let d = relative_difference(&read(&one, field), &read(&two, field));
        assert!(d <= AGREEMENT, "{name}: {field} differs by {d:.2e}");
    }
    assert_eq!(
        read(&one, "fields/contact_active"),
        read(&two, "fields/contact_active"),
        "{name}: active sets"
    );

    let (a, b) = (summary(&one), summary(&two));
    assert_eq!(a["ranks"], 1);
    assert_eq!(b["ranks"], ranks);
    assert_eq!(
        b["rank_peak_memory_mb"].as_array().map(Vec::len),
        Some(ranks)
    );
    // The bodies' reactions (every rank reads its displacement at the nodes it keeps, the
    // prescribed rows' columns among them), within the solves' agreement of the largest (a
    // body held by its contacts has reactions of round-off alone).
    let reactions = |summary: &serde_json::Value| -> Vec<f64> {
        (summary["bodies"].as_array().unwrap().iter())
            .flat_map(|body| body["reactions"].as_object().unwrap().values())
            .flat_map(|r| r.as_array().unwrap().iter().map(|v| v.as_f64().unwrap()))
            .collect()
    };
    let (r, q) = (reactions(&a), reactions(&b));
    assert!(r.iter().any(|&v| v != 0.0), "{name}: no reaction");
    let d = relative_difference(&r, &q);
    assert!(d <= AGREEMENT, "{name}: the reactions differ by {d:.2e}");
    let mut totals = vec![0i64; ranks];
    let mut largest_difference = 0;
    for body in b["bodies"].as_array().unwrap() {
        let shares: Vec<u64> = (body["solve"]["rank_dofs"].as_array().unwrap().iter())
            .map(|v| v.as_u64().unwrap())
            .collect();
        assert_eq!(shares.len(), ranks, "{name}: {body}");
        assert_eq!(
            shares.iter().sum::<u64>(),
            body["num_dofs"].as_u64().unwrap()
        );
        // METIS's parts: within its 3% imbalance of an even split.
        let even = body["num_dofs"].as_f64().unwrap() / ranks as f64;
        assert!(
            shares
                .iter()
                .all(|&s| (s as f64 - even).abs() <= 0.03 * even + 3.0),
            "{shares:?}"
        );
        for (total, &share) in totals.iter_mut().zip(&shares) {
            *total += share as i64;
        }
        largest_difference =
            largest_difference.max(shares.iter().max().unwrap() - shares.iter().min().unwrap());
    }
    // Each body's parts go to the ranks that even out the totals (`linalg::spread_parts`): on
    // two ranks the totals then differ by no more than one body's parts do, where labels left
    // as METIS gives them add up when the bodies' larger parts fall on one rank.
    if ranks == 2 {
        assert!(
            (totals[0] - totals[1]).unsigned_abs() <= largest_difference,
            "{name}: the ranks' unknowns {totals:?}, a body's parts at most {largest_difference} apart"
        );
    }
    let (pairs_a, pairs_b) = (pairs(&a), pairs(&b));
    assert!(!pairs_a.is_empty());
    for (p, q) in pairs_a.iter().zip(&pairs_b) {
        assert_eq!(p["status"], q["status"], "{name}");
        // The same checks pass and fail (their values agree to the solves' tolerance; where a
        // value is round-off, as a penetration of 1e-14 h, its node may differ).
        for report in ["solved", "accuracy"] {
            let verdicts = |pair: &serde_json::Value| -> Vec<String> {
                (pair[report]["checks"].as_array().into_iter().flatten())
                    .map(|c| format!("{} {}", c["name"], c["passed"]))
                    .collect()
            };
            assert_eq!(verdicts(p), verdicts(q), "{name}: {report}");
            assert_eq!(p[report]["passed"], q[report]["passed"], "{name}: {report}");
        }
        // The same iterations paired the interface again where the surfaces had slid to (on
        // ranks a collective set-up: every rank pairs at once or the run hangs).
        if extra_iterations == 0 {
            assert_eq!(
                paired_again(p),
                paired_again(q),
                "{name}: the iterations that paired the interface again"
            );
        }
        let (steps_p, steps_q) = (
            p["steps"].as_array().unwrap(),
            q["steps"].as_array().unwrap(),
        );
        assert_eq!(steps_p.len(), steps_q.len());
        for (k, (s, t)) in steps_p.iter().zip(steps_q).enumerate() {
            assert_eq!(s["status"], t["status"], "{name}");
            let (i, j) = (s["iterations"].as_u64(), t["iterations"].as_u64());
            assert!(
                i.zip(j)
                    .is_some_and(|(i, j)| i.abs_diff(j) <= extra_iterations),
                "{name}: step {}: active-set iterations {i:?} and {j:?}",
                k + 1
            );
            assert_eq!(s["accurate"], t["accurate"], "{name}: the accuracy report");
            assert_eq!(s["failed_checks"], t["failed_checks"], "{name}");
            let force = |step: &serde_json::Value| -> Vec<f64> {
                (step["force_primary"].as_array().unwrap().iter())
                    .map(|v| v.as_f64().unwrap())
                    .collect()
            };
            let (f, g) = (force(s), force(t));
            let d = match k + 1 >= laterals_from_step {
                true => relative_difference(&f, &g),
                false => (f[f.len() - 1] - g[g.len() - 1]).abs() / f[f.len() - 1].abs(),
            };
            assert!(
                d <= AGREEMENT,
                "{name}: step {}: force differs by {d:.2e}",
                k + 1
            );
        }
    }
    dir
}

#[test]
fn the_demo_on_two_ranks_gives_the_serial_answer() {
    // 3D Hertz, five load steps; the mesh made by gmsh on rank 0 and sent to rank 1.
    ranks_give_the_serial_answer(2, "hemisphere_on_block", "", 1);
}

#[test]
fn a_load_path_on_two_ranks_gives_the_serial_answer() {
    // The demo's sphere pushed down along a load path that presses, then releases part way,
    // its lateral supports on the default path: each path's part of f_c is lifted from the
    // rows of K at the prescribed dofs, which every rank holds whole.
    ranks_give_the_serial_answer_of(2, "hemisphere_on_block", "", 1, 0, &pressed_along_a_path);
}

#[test]
fn a_body_force_beside_a_load_path_on_three_ranks_gives_the_serial_answer() {
    // The load path above with each body under its weight (on the default path): each rank
    // keeps its part of f and of each path's f_c (its own and the prescribed dofs), never the
    // whole vectors, and the reactions at the base read the weight at the prescribed dofs.
    ranks_give_the_serial_answer_of(3, "hemisphere_on_block", "", 1, 0, &|case| {
        pressed_along_a_path(case);
        under_weight(case, [0.02, 0.1]);
    });
}

/// The demo's sphere pushed down along the load path `press`, which presses, then releases
/// part way, its lateral supports on the default path.
fn pressed_along_a_path(case: &mut toml::Table) {
    case["contact"].as_table_mut().unwrap().remove("load_steps");
    let paths: toml::Table = toml::from_str("press = [0.4, 1.0, 0.7]").unwrap();
    case.insert("load_path".into(), paths.into());
    let sphere = &mut case["body"].as_array_mut().unwrap()[0];
    let top = sphere["dirichlet"].as_array_mut().unwrap();
    let mut pushed = top[0].as_table().unwrap().clone();
    for key in ["ux", "uy"] {
        pushed.remove(key);
    }
    pushed.insert("path".into(), "press".into());
    top[0].as_table_mut().unwrap().remove("uz");
    top.push(pushed.into());
}

/// Each body of `case` under a body force `-weights[k]` along `z`.
fn under_weight(case: &mut toml::Table, weights: [f64; 2]) {
    let bodies = case["body"].as_array_mut().unwrap();
    for (body, weight) in bodies.iter_mut().zip(weights) {
        let force = toml::Value::Array(vec![0.0.into(), 0.0.into(), (-weight).into()]);
        body.as_table_mut()
            .unwrap()
            .insert("body_force".into(), force);
    }
}

#[test]
fn the_penalty_method_on_two_ranks_gives_the_serial_answer() {
    // The demo under the penalty method: the rows' own term 1 / eps on the distributed path.
    ranks_give_the_serial_answer(2, "hemisphere_on_block", "method = \"penalty\"", 1);
}

#[test]
fn the_demo_refined_on_two_ranks_shares_its_contact_surfaces_and_gives_the_serial_answer() {
    // Refined (level 0.9, 108k DOFs, one load step) until each body has at least
    // `BALANCED_INTERFACE_PER_RANK` contact-surface nodes a rank: the partition then shares
    // those nodes out evenly as a second METIS constraint, which the coarser cases above never
    // reach, and the answer stays the serial one.
    let dir = ranks_give_the_serial_answer_of(2, "hemisphere_on_block", "", 1, 0, &|case| {
        case["contact"]["load_steps"] = toml::Value::Array(vec![1.0.into()]);
        let geo = case["geo_parameters"].as_table_mut().unwrap();
        geo.insert("level".into(), 0.9.into());
    });
    let mesh = dir.path().join("one/mesh.msh");
    let info = serial(&["info", mesh.to_str().unwrap()]);
    let info = String::from_utf8_lossy(&info.stdout).into_owned();
    for surface in ["sphere_contact", "block_contact"] {
        let nodes: usize = (info.lines())
            .find_map(|l| l.trim().strip_prefix(&format!("boundary '{surface}': ")))
            .and_then(|rest| {
                rest.split(", ")
                    .nth(1)?
                    .strip_suffix(" nodes")?
                    .parse()
                    .ok()
            })
            .unwrap_or_else(|| panic!("{surface} in:\n{info}"));
        assert!(
            nodes >= 2 * internodes::linalg::BALANCED_INTERFACE_PER_RANK,
            "{surface}: {nodes} nodes"
        );
    }
}

#[test]
fn the_demo_on_three_ranks_gives_the_serial_answer() {
    // Any number of ranks, not only two: three parts per body (oversubscribed on two cores).
    ranks_give_the_serial_answer(3, "hemisphere_on_block", "", 1);
}

#[test]
fn a_floating_ball_between_plates_under_a_force_on_two_ranks_gives_the_serial_answer() {
    // Two pairs, a body held by its contacts alone, force control. Solved to a penetration
    // tolerance of 1e-9 h: at the default (1e-3 h) the loop stops once the gaps settle within
    // 1e-5 h, and the floating ball's position may differ by that much between any two
    // preconditioners (measured: 1.1e-5 of the largest displacement, CG + AMG against
    // Cholesky, one process).
    //
    // The ball is each pair's primary. With the plates as primary (`auto`'s choice) the lower
    // plate's node at the ball's south pole sits on the ball's pole vertex, where the facets'
    // normals differ and the answer depends on the path to it (docs/method.md 3.4): the 2-rank
    // run then ends 1.1e-5 of the displacement from the serial one or on it, as the two
    // preconditioners happen to lead. With the ball as primary every node meets a flat plate,
    // and the two runs agree to 7e-11 (displacement) and 2e-9 (stress).
    //
    // The lateral force components of the first step (load factor 0.5) are left out: the two
    // runs' loose first solves differ at 1e-7, their active-set paths then differ (the same
    // final set), and the lateral components of the upper pair differ by 2.6e-5 of its force
    // (the z components by 1e-12). Neither run pairs its interface again in that step (its
    // slide stays under 0.01 h), so the pairing is not the cause; the cause is not
    // established. At the last step every component agrees (7e-11).
    ranks_give_the_serial_answer(
        2,
        "ball_between_plates_3d",
        "penetration_tolerance = 1e-9\nprimary = \"ball\"",
        2,
    );
}

#[test]
fn the_demo_on_four_ranks_gives_the_serial_answer() {
    // Four parts per body (oversubscribed on two cores).
    ranks_give_the_serial_answer(4, "hemisphere_on_block", "", 1);
}

#[test]
fn two_pairs_sharing_a_block_on_three_ranks_give_the_serial_answer() {
    // Several pairs: two hemispheres pressed on one block, each pair with its own interface
    // operators, the block's rows shared among three ranks.
    ranks_give_the_serial_answer(3, "two_hemispheres_on_block", "", 1);
}

#[test]
fn a_hemisphere_pressed_by_a_force_on_three_ranks_gives_the_serial_answer() {
    // Force control: the approach is an unknown of the coupled solve, its column `k` and row
    // held whole by every rank (the rigid block), the sphere's rows shared among three ranks;
    // four load steps. Solved to 1e-9 h, as the floating ball: at the default tolerance the
    // two runs ended 1.5e-6 of the largest stress apart (displacement 1.2e-7) once each
    // rank's nodes went to PETSc along a Z curve, within what gaps settled to 1e-5 h allow;
    // at 1e-9 h, 3.4e-9 (displacement 3.5e-10).
    ranks_give_the_serial_answer(
        3,
        "hemisphere_pressed_by_force",
        "penetration_tolerance = 1e-9",
        1,
    );
}

#[test]
fn a_coulomb_pair_sheared_on_two_ranks_gives_the_serial_answer() {
    // Friction: a sticking node's tangential rows read the interpolation R12, whose entries
    // each rank keeps at its own nodes only; a 2D half-disc pressed, then sheared in steps.
    //
    // Solved to a penetration tolerance of 1e-9 h, as the floating ball: at the default the
    // loop stops once the gaps settle within 1e-5 h (and the slip directions within their
    // margin), 1e-5 h / 0.02 = 6e-6 of the press here, and two preconditioners' answers may
    // differ by that much (measured: stress 1.09e-6 of its largest value apart, displacement
    // 2e-8, with the serial nodes along a Z curve in PETSc). At 1e-9 h the fields agree to
    // 6e-11, but the last settling iterations follow the preconditioners' round-off: the
    // second step took 6 iterations serially and 5 on 2 ranks (so it did before the Z curve).
    ranks_give_the_serial_answer_of(
        2,
        "half_disc_sheared",
        "penetration_tolerance = 1e-9",
        1,
        1,
        &|_| {},
    );
}

#[test]
fn the_conservative_transfer_on_two_ranks_gives_the_serial_answer() {
    // The demo with the force on the secondary sent by R12^T (its rows, each rank's entries
    // at its own nodes) instead of the columns of R21.
    ranks_give_the_serial_answer(2, "hemisphere_on_block", "transfer = \"conservative\"", 1);
}

#[test]
fn tied_contact_on_two_ranks_gives_the_serial_answer() {
    // The demo tied: each iterate's gap corrections read the jumps `R12 u2`, a whole-field
    // interpolation every rank computes with its rows of Phi_MM and Phi_NM (collective).
    ranks_give_the_serial_answer(2, "hemisphere_on_block", "formulation = \"tied\"", 1);
}

#[test]
fn supports_too_wide_for_gmres_on_two_ranks_give_the_serial_answer() {
    // The demo with supports of ten spacings: Phi_MM is ill-conditioned, its whole-field GMRES
    // stops short, and every rank factors the whole matrix, which it builds from the sources
    // for that (a rank stores only its range of Phi_MM's rows).
    ranks_give_the_serial_answer(2, "hemisphere_on_block", "rbf_radius = 10", 1);
}

#[test]
fn a_corner_in_the_crater_it_digs_on_two_ranks_gives_the_serial_answer() {
    // A 2D square's corner pressed into a block of its own material: the corner's node held
    // against both walls of its crater, the pairing following the slide at every iteration
    // (each rank finds the walls from the gathered gap rows).
    let dir = ranks_give_the_serial_answer_of(2, "square_corner_on_block_2d", "", 1, 0, &|_| {});
    // It goes through the ranks' pairing again (compared iteration by iteration above).
    let pair = &pairs(&summary(&dir.path().join("one")))[0];
    assert!(paired_again(pair).contains(&true), "{pair}");
}

#[test]
fn a_stack_of_three_2d_bodies_on_two_ranks_gives_the_serial_answer() {
    // Two pairs in a chain (the middle body in both) in 2D, two load steps.
    ranks_give_the_serial_answer(2, "stack_2d", "", 1);
}

#[test]
fn a_body_force_on_three_ranks_gives_the_serial_answer() {
    // The hemisphere pressed by a force, each body under its weight (the block's 3.2, which
    // its base carries, the sphere's 0.04 against the force of 0.8). Each rank keeps only the
    // cells around its own and the prescribed nodes, so its body force is right at its own and
    // the prescribed nodes only, and that part is all it keeps of the load vector (the answer
    // reads it there alone; the resultant that places a force-controlled body's first contact
    // zone, which must be the same on every rank, adds the ranks' sums over their own dofs).
    // Solved to 1e-9 h as the test without weight.
    ranks_give_the_serial_answer_of(
        3,
        "hemisphere_pressed_by_force",
        "penetration_tolerance = 1e-9",
        1,
        0,
        &|case| under_weight(case, [0.02, 0.1]),
    );
}

#[test]
fn a_single_body_on_two_ranks_gives_the_serial_answer() {
    let dir = tempfile::tempdir().unwrap();
    let case = example_case(dir.path(), "block_3d", "\n[solver]\nbody = \"cg-amg\"\n");
    let case = case.to_str().unwrap();
    let (one, two) = (dir.path().join("one"), dir.path().join("two"));
    let export = "--export-matrices";
    let serial_run = serial(&["solve", case, "-q", export, "-o", one.to_str().unwrap()]);
    let parallel_run = mpirun(
        2,
        &["solve", case, "-q", export, "-o", two.to_str().unwrap()],
    );
    assert!(serial_run.status.success(), "{}", text(&serial_run));
    assert!(parallel_run.status.success(), "{}", text(&parallel_run));
    assert_eq!(files(&one), files(&two));
    same_mesh_written(&one, &two, "block_3d");
    // One CG solve to the case's rtol (1e-10 by default) with either preconditioner.
    for field in ["fields/displacement", "fields/stress"] {
        let d = relative_difference(&read(&one, field), &read(&two, field));
        assert!(d <= 1e-8, "{field} differs by {d:.2e}");
    }
    // The whole body's matrices, which rank 0 assembles from the mesh file read again.
    let matrices = |dir: &Path| files(&dir.join("matrices"));
    assert!(!matrices(&one).is_empty());
    assert_eq!(matrices(&one), matrices(&two));
    for file in matrices(&one) {
        let bytes = |dir: &Path| std::fs::read(dir.join("matrices").join(&file)).unwrap();
        assert!(bytes(&one) == bytes(&two), "matrices/{file} differs");
    }
    // Each rank kept only its part of the cells; the counts are the whole body's.
    let cells = |dir: &Path| summary(dir)["bodies"][0]["num_cells"].as_u64();
    assert_eq!(cells(&one), cells(&two));
}

#[test]
fn a_single_body_under_a_force_on_two_ranks_gives_the_serial_answer() {
    // The block's top face pushed by a total force (one displacement for the face, an unknown
    // bordering the body's system): each rank solves on its rows alone and adds its part of
    // `k^T W` and `k^T u0` to the others'.
    let dir = tempfile::tempdir().unwrap();
    let force = "\n[[body.force]]\ngroup = \"block_top\"\nfz = -1.0\n";
    let extra = format!("{force}\n[solver]\nbody = \"cg-amg\"\n");
    let case = example_case(dir.path(), "block_3d", &extra);
    let case = case.to_str().unwrap();
    let (one, two) = (dir.path().join("one"), dir.path().join("two"));
    let serial_run = serial(&["solve", case, "-q", "-o", one.to_str().unwrap()]);
    let parallel_run = mpirun(2, &["solve", case, "-q", "-o", two.to_str().unwrap()]);
    assert!(serial_run.status.success(), "{}", text(&serial_run));
    assert!(parallel_run.status.success(), "{}", text(&parallel_run));
    same_mesh_written(&one, &two, "block_3d");
    for field in ["fields/displacement", "fields/stress"] {
        let d = relative_difference(&read(&one, field), &read(&two, field));
        assert!(d <= 1e-8, "{field} differs by {d:.2e}");
    }
    // The top face (z = 0) moves as one: every node of it has the same `uz`, on either run.
    for dir in [&one, &two] {
        let (geometry, u) = (read(dir, "mesh/geometry"), read(dir, "fields/displacement"));
        let top: Vec<f64> = (geometry.chunks_exact(3).zip(u.chunks_exact(3)))
            .filter(|(x, _)| x[2] == 0.0)
            .map(|(_, u)| u[2])
            .collect();
        assert!(top.len() > 10 && top[0] < 0.0, "{top:?}");
        assert!(top.iter().all(|&uz| uz == top[0]), "{top:?}");
    }
    let (a, b) = (summary(&one), summary(&two));
    for s in [&a, &b] {
        let reactions = &s["bodies"][0]["reactions"];
        let top = reactions["block_top"][2].as_f64().unwrap();
        let base = reactions["block_base"][2].as_f64().unwrap();
        // The face's reaction is the force it carries; the base holds it and the pressure.
        assert!((top + 1.0).abs() <= 1e-8, "{reactions}");
        assert!(base > 1.0, "{reactions}");
        let residual = s["bodies"][0]["solve"]["relative_residual"]
            .as_f64()
            .unwrap();
        assert!(residual <= 1e-8, "relative residual {residual:.2e}");
    }
    let base = |s: &serde_json::Value| s["bodies"][0]["reactions"]["block_base"][2].as_f64();
    let (p, q) = (base(&a).unwrap(), base(&b).unwrap());
    assert!(
        (p - q).abs() <= 1e-8 * p.abs(),
        "base reactions {p} and {q}"
    );
}

#[test]
fn a_rank_that_fails_alone_ends_every_rank_with_its_error() {
    // Rank 0 alone writes, so it alone finds that the output folder is a file; rank 1 goes on
    // into the body solver's collective set-up and would wait for rank 0 for ever.
    let dir = tempfile::tempdir().unwrap();
    let case = example_case(dir.path(), "block_3d", "\n[solver]\nbody = \"cg-amg\"\n");
    let out = dir.path().join("a_file");
    std::fs::write(&out, "not a folder").unwrap();
    fails_on_rank_0_alone(&case, &out, "a_file");
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "not a folder");
}

/// Solves `case` into `out` on 2 ranks, which must fail with rank 0's error alone, naming
/// `named`.
fn fails_on_rank_0_alone(case: &Path, out: &Path, named: &str) {
    let run = mpirun(
        2,
        &[
            "solve",
            case.to_str().unwrap(),
            "-q",
            "-o",
            out.to_str().unwrap(),
        ],
    );
    assert!(!run.status.success(), "{}", text(&run));
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(stderr.contains("error (rank 0 of 2)"), "{}", text(&run));
    assert!(stderr.contains(named), "{}", text(&run));
    assert!(!stderr.contains("error (rank 1 of 2)"), "{}", text(&run));
}

#[test]
fn a_case_that_does_not_fit_its_mesh_is_refused_once_by_the_rank_that_reads_the_mesh() {
    // Rank 0 alone reads the mesh and checks the case against it; rank 1 waits for its part,
    // and is ended with rank 0's error.
    let dir = tempfile::tempdir().unwrap();
    let case = example_case(dir.path(), "block_3d", "");
    let original = std::fs::read_to_string(&case).unwrap();
    let edited = original.replace("\"block_base\"", "\"no_such_group\"");
    std::fs::write(&case, edited).unwrap();
    fails_on_rank_0_alone(&case, &dir.path().join("out"), "no_such_group");
}

#[test]
fn what_runs_on_one_process_only_is_refused_on_two_ranks() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            "[solver] body",
            "\n[solver]\nbody = \"cholesky\"\n",
            "block_3d",
        ),
        ("[contact] solver", "", "hemisphere_on_block"),
    ];
    for (context, extra, name) in cases {
        let case = example_case(dir.path(), name, extra);
        if name == "hemisphere_on_block" {
            let text = std::fs::read_to_string(&case).unwrap();
            let text = text.replace("[contact]\n", "[contact]\nsolver = \"monolithic-lu\"\n");
            std::fs::write(&case, text).unwrap();
        }
        let out = dir.path().join("out");
        let run = mpirun(
            2,
            &["solve", case.to_str().unwrap(), "-o", out.to_str().unwrap()],
        );
        assert!(!run.status.success(), "{}", text(&run));
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(
            stderr.contains(context) && stderr.contains("2 MPI ranks"),
            "{context}: {}",
            text(&run)
        );
        // Every rank meets this error; it is said once, by rank 0.
        assert_eq!(stderr.matches("error (rank").count(), 1, "{}", text(&run));
        assert!(stderr.contains("error (rank 0 of 2)"), "{}", text(&run));
    }
    let run = mpirun(
        2,
        &[
            "study",
            "geo/hemisphere_on_block.toml",
            "--parameter",
            "level=0,1",
        ],
    );
    assert!(!run.status.success());
    assert!(String::from_utf8_lossy(&run.stderr).contains("runs on one process"));
}
