//! Load paths (`[load_path]`): each load, force and prescribed displacement scaled at each step
//! by the factor of its own path. Without named paths nothing changes, bit for bit; frictionless
//! contact does not depend on the path, so a path that ends where a single step is gives its
//! answer; every mistake in a `[load_path]` or a `path` key is an error that names it.

mod common;

use common::case_builder::{Body, CaseFile, Dirichlet, Force, Load};
use common::contact::stiff_block;
use common::{half_disc_on_block, run_solve, write_case};
use internodes::case::Case;
use internodes::contact::{
    ContactSolution, ContactSolver, ContactStatus, StepRecord, solve_contact_steps,
};
use internodes::elastic::{SolverSettings, StepFactors};
use internodes::mesh::read_msh;

/// The case's TOML with `edit` applied to its table.
fn edited(case: &CaseFile, edit: impl FnOnce(&mut toml::Table)) -> String {
    let mut table: toml::Table = toml::from_str(&case.to_toml()).unwrap();
    edit(&mut table);
    toml::to_string(&table).unwrap()
}

/// `[load_path]` with the lists `paths`.
fn set_paths(table: &mut toml::Table, paths: &[(&str, &[f64])]) {
    let mut load_path = toml::Table::new();
    for (name, factors) in paths {
        let list = factors.iter().map(|&f| toml::Value::Float(f)).collect();
        load_path.insert(name.to_string(), toml::Value::Array(list));
    }
    table.insert("load_path".into(), toml::Value::Table(load_path));
}

/// `path = "{path}"` on the entries of kind `kind` ("dirichlet", "load", "force") on `group` of
/// the body `body`.
fn set_path(table: &mut toml::Table, body: &str, kind: &str, group: &str, path: &str) {
    let bodies = table["body"].as_array_mut().unwrap();
    let body = (bodies.iter_mut())
        .find(|b| b["name"].as_str() == Some(body))
        .unwrap_or_else(|| panic!("no body '{body}'"));
    let entries = body[kind].as_array_mut().unwrap();
    let mut found = false;
    for entry in entries
        .iter_mut()
        .filter(|e| e["group"].as_str() == Some(group))
    {
        entry
            .as_table_mut()
            .unwrap()
            .insert("path".into(), toml::Value::String(path.into()));
        found = true;
    }
    assert!(found, "no {kind} on '{group}'");
}

/// Every entry of every body on the path `path`.
fn everything_on(table: &mut toml::Table, path: &str) {
    for body in table["body"].as_array_mut().unwrap() {
        for kind in ["dirichlet", "load", "force"] {
            if let Some(entries) = body.get_mut(kind).and_then(|e| e.as_array_mut()) {
                for entry in entries {
                    (entry.as_table_mut().unwrap())
                        .insert("path".into(), toml::Value::String(path.into()));
                }
            }
        }
    }
}

/// The case file `text` solved by the library as the command line solves it
/// (`Case::step_factors`): each pair's answer at the last step, and its step records.
fn solve_text(text: &str) -> Result<(Vec<ContactSolution>, Vec<Vec<StepRecord>>), String> {
    let (_dir, path) = write_case(text);
    let case = Case::load(&path).map_err(|e| e.to_string())?;
    let mesh = read_msh(&case.mesh).map_err(|e| e.to_string())?;
    let problems = case.contact_problems(&mesh).map_err(|e| e.to_string())?;
    let settings = SolverSettings {
        verbose: false,
        ..case.solver.clone()
    };
    let run = solve_contact_steps(problems, &settings, &case.step_factors())
        .map_err(|e| e.to_string())?;
    Ok((run.solutions, run.steps))
}

/// The error of loading the case file `text`.
fn load_error(text: &str) -> String {
    let (_dir, path) = write_case(text);
    match Case::load(&path) {
        Ok(_) => panic!("the case should be refused:\n{text}"),
        Err(e) => e.to_string(),
    }
}

fn assert_mentions(message: &str, parts: &[&str]) {
    for part in parts {
        assert!(message.contains(part), "{part:?} not in: {message}");
    }
}

/// The half-disc pressed onto the block (coarse mesh), the block also squeezed by a pressure on
/// its sides.
fn squeezed() -> CaseFile {
    half_disc_on_block("half_disc_on_block.msh")
        .with_body("block", |b| b.load(Load::pressure("block_sides", 2.0)))
}

#[test]
fn paths_equal_to_the_load_steps_give_the_same_answer_bit_for_bit() {
    let steps = [0.5, 1.0];
    let plain = squeezed().load_steps(&steps);
    let reference = solve_text(&plain.to_toml()).unwrap();
    let variants = [
        // Every entry on a path equal to the load steps.
        edited(&plain, |t| {
            set_paths(t, &[("ramp", &steps)]);
            everything_on(t, "ramp");
        }),
        // Some entries on it, the others on the load steps.
        edited(&plain, |t| {
            set_paths(t, &[("ramp", &steps)]);
            set_path(t, "disc", "dirichlet", "disc_top", "ramp");
        }),
        // A path that nothing follows.
        edited(&plain, |t| set_paths(t, &[("unused", &[0.3, 0.7])])),
    ];
    for text in variants {
        let (solutions, records) = solve_text(&text).unwrap();
        let (expected, expected_records) = (&reference.0[0], &reference.1[0]);
        let solution = &solutions[0];
        assert_eq!(solution.status, ContactStatus::Converged, "{text}");
        assert_eq!(
            solution.primary.displacement, expected.primary.displacement,
            "{text}"
        );
        assert_eq!(
            solution.secondary.displacement, expected.secondary.displacement,
            "{text}"
        );
        assert_eq!(solution.primary.reactions, expected.primary.reactions);
        assert_eq!(solution.secondary.reactions, expected.secondary.reactions);
        assert_eq!(solution.force_primary, expected.force_primary);
        assert_eq!(records[0].len(), expected_records.len());
        for (record, expected) in records[0].iter().zip(expected_records) {
            assert_eq!(record.force_primary, expected.force_primary, "{text}");
            assert_eq!(record.force_secondary, expected.force_secondary);
            assert_eq!(record.iterations, expected.iterations);
            assert_eq!(record.load_factor, expected.load_factor);
            assert!(!record.path_factors.is_empty());
        }
    }
    assert!(reference.1[0].iter().all(|r| r.path_factors.is_empty()));
}

/// The largest `|a - b|` over two displacement vectors.
fn largest_difference(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max)
}

/// The loop's settling margin `0.01 tol_p h` (tol_p = 1e-3) of the case file `text` on the
/// half-disc fixture, `h` the smallest spacing of its primary's candidates.
fn settling_margin(text: &str) -> f64 {
    let mesh = read_msh(&common::fixture("half_disc_on_block.msh")).unwrap();
    let h_min = (Case::load(&write_case(text).1).unwrap())
        .contact_problems(&mesh)
        .unwrap()[0]
        .primary_surface
        .spacing
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    1e-2 * 1e-3 * h_min
}

/// Both bodies' displacements of `a` and `b` agree within `bound`.
fn assert_displacements_agree(a: &ContactSolution, b: &ContactSolution, bound: f64) {
    for (u, v) in [
        (&a.primary.displacement, &b.primary.displacement),
        (&a.secondary.displacement, &b.secondary.displacement),
    ] {
        let d = largest_difference(u, v);
        assert!(d <= bound, "differs by {d:.2e} (bound {bound:.2e})");
    }
}

#[test]
fn frictionless_contact_ends_where_a_single_step_does() {
    // Pressed halfway, then fully, then squeezed: the last step has every factor at 1, and
    // frictionless contact does not depend on the path to it. The second step (pressed, not
    // squeezed) is the case without the squeeze.
    let case = squeezed();
    let path = edited(&case, |t| {
        set_paths(
            t,
            &[("press", &[0.5, 1.0, 1.0]), ("squeeze", &[0.0, 0.0, 1.0])],
        );
        set_path(t, "disc", "dirichlet", "disc_top", "press");
        set_path(t, "block", "load", "block_sides", "squeeze");
    });
    let (stepped, records) = solve_text(&path).unwrap();
    let (single, _) = solve_text(&case.to_toml()).unwrap();
    let (stepped, single) = (&stepped[0], &single[0]);
    let records = &records[0];
    assert_eq!(records.len(), 3);
    for (record, (press, squeeze)) in records.iter().zip([(0.5, 0.0), (1.0, 0.0), (1.0, 1.0)]) {
        assert_eq!(record.status, ContactStatus::Converged);
        assert_eq!(record.load_factor, 1.0, "no load_steps: 1 at every step");
        assert_eq!(record.path_factors["press"], press);
        assert_eq!(record.path_factors["squeeze"], squeeze);
    }
    // The loop stops when every active node lies within 0.01 tol_p h of the other surface
    // (tol_p = 1e-3): two answers of one problem agree to that order.
    assert_eq!(stepped.primary_fields.active, single.primary_fields.active);
    assert_displacements_agree(stepped, single, settling_margin(&case.to_toml()));
    let force = |s: &ContactSolution| s.force_primary[1];
    let relative = (force(stepped) - force(single)).abs() / force(single).abs();
    assert!(relative < 1e-6, "contact force differs by {relative:.2e}");

    // The squeeze changes the answer: step 2 is the case without it.
    let unsqueezed = half_disc_on_block("half_disc_on_block.msh");
    let (alone, _) = solve_text(&unsqueezed.to_toml()).unwrap();
    let relative = (records[1].force_primary[1] - alone[0].force_primary[1]).abs()
        / alone[0].force_primary[1].abs();
    assert!(relative < 1e-6, "step 2 against no squeeze: {relative:.2e}");
    let moved = (records[2].force_primary[1] - records[1].force_primary[1]).abs()
        / records[1].force_primary[1].abs();
    assert!(moved > 1e-3, "the squeeze moves the force by {moved:.2e}");
}

#[test]
fn a_prescribed_value_follows_its_own_path() {
    // The disc's top is pushed down by 0.02 along `press`, at 0.5 here while the default path
    // is at 1: the displacement at its prescribed dofs is 0.5 times the value.
    let case = edited(&half_disc_on_block("half_disc_on_block.msh"), |t| {
        set_paths(t, &[("press", &[1.0])]);
        set_path(t, "disc", "dirichlet", "disc_top", "press");
    });
    let (_dir, path) = write_case(&case);
    let case = Case::load(&path).unwrap();
    let mesh = read_msh(&case.mesh).unwrap();
    let problem = case.contact_problems(&mesh).unwrap().remove(0);
    let settings = SolverSettings {
        verbose: false,
        ..case.solver.clone()
    };
    let mut solver = ContactSolver::new(std::slice::from_ref(&problem), &settings).unwrap();
    let mut factors = StepFactors::uniform(1.0);
    factors.paths.insert("press".into(), 0.5);
    let solution = solver.solve(&factors, None).unwrap().remove(0);
    assert_eq!(solution.status, ContactStatus::Converged);
    assert_eq!(solution.path_factors["press"], 0.5);
    assert_eq!(problem.primary.body.name, "disc");
    let disc = problem.primary.body;
    let u = &solution.primary.displacement;
    for node in disc.group_nodes("disc_top").unwrap() {
        let uy = u[2 * node + 1];
        assert!(
            (uy + 0.01).abs() <= 1e-9 * 0.01,
            "uy = {uy}, expected -0.01"
        );
        assert!(u[2 * node].abs() <= 1e-12, "ux = {}", u[2 * node]);
    }
    // A step that does not give the path is an error, not a panic.
    let error = solver
        .solve(&StepFactors::uniform(1.0), None)
        .err()
        .expect("a step without the path 'press'")
        .to_string();
    assert_mentions(&error, &["load path", "'press'", "disc"]);
}

#[test]
fn a_force_follows_its_path() {
    // The disc pressed by a force (its top a rigid plate) along `push`: the same answer as the
    // load steps [0.5, 1], the force at each step the path's factor times the force.
    let plain = stiff_block("half_disc_on_block.msh", "auto")
        .with_body("block", |b| Body {
            youngs_modulus: 1000.0,
            ..b
        })
        .with_support("disc", "disc_top", |d| Dirichlet { uy: None, ..d })
        .with_body("disc", |b| b.force(Force::vertical("disc_top", 2, -5.0)))
        .load_steps(&[0.5, 1.0]);
    let path = edited(&plain, |t| {
        t["contact"].as_table_mut().unwrap().remove("load_steps");
        set_paths(t, &[("push", &[0.5, 1.0])]);
        set_path(t, "disc", "force", "disc_top", "push");
    });
    let (expected, expected_records) = solve_text(&plain.to_toml()).unwrap();
    let (solutions, records) = solve_text(&path).unwrap();
    for (record, expected) in records[0].iter().zip(&expected_records[0]) {
        assert_eq!(record.forced.len(), 1);
        assert_eq!(record.forced[0].force, expected.forced[0].force);
        assert_eq!(record.forced[0].force, -5.0 * record.path_factors["push"]);
        let (a, b) = (
            record.forced[0].displacement,
            expected.forced[0].displacement,
        );
        assert!((a - b).abs() <= 1e-6 * b.abs(), "{a} against {b}");
    }
    let d = largest_difference(
        &solutions[0].primary.displacement,
        &expected[0].primary.displacement,
    );
    assert!(d <= 1e-8, "differs by {d:.2e}");
}

#[test]
fn the_outputs_name_each_path() {
    let case = squeezed();
    let path = edited(&case, |t| {
        set_paths(t, &[("press", &[0.5, 1.0]), ("squeeze", &[0.0, 1.0])]);
        set_path(t, "disc", "dirichlet", "disc_top", "press");
        set_path(t, "block", "load", "block_sides", "squeeze");
    });
    let (dir, file) = write_case(&path);
    let output = run_solve(&file);
    assert!(output.status.success(), "{output:?}");
    let out = dir.path().join("out");
    let csv = std::fs::read_to_string(out.join("force_displacement.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().collect();
    assert!(
        rows[0].starts_with("step,load_factor,path_press,path_squeeze,status,iterations,"),
        "{}",
        rows[0]
    );
    assert!(rows[1].starts_with("1,1,0.5,0,converged,"), "{}", rows[1]);
    assert!(rows[2].starts_with("2,1,1,1,converged,"), "{}", rows[2]);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let steps = summary["contact"]["steps"].as_array().unwrap();
    assert_eq!(steps[0]["path_factors"]["press"], 0.5);
    assert_eq!(steps[1]["path_factors"]["squeeze"], 1.0);

    // Without a [load_path], neither the CSV nor the summary has them.
    let (dir, file) = case.load_steps(&[0.5, 1.0]).write();
    assert!(run_solve(&file).status.success());
    let out = dir.path().join("out");
    let csv = std::fs::read_to_string(out.join("force_displacement.csv")).unwrap();
    assert!(
        csv.starts_with("step,load_factor,status,iterations,"),
        "{csv}"
    );
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert!(!summary.contains("path_factors"));
}

#[test]
fn mistakes_in_a_load_path_are_errors_that_name_them() {
    let case = squeezed();
    let on_press = |t: &mut toml::Table| set_path(t, "disc", "dirichlet", "disc_top", "press");
    let cases: Vec<(String, Vec<&str>)> = vec![
        // A path that the [load_path] does not have.
        (
            edited(&case, |t| {
                set_paths(t, &[("press", &[0.5, 1.0])]);
                set_path(t, "block", "load", "block_sides", "shear");
            }),
            vec![
                "body 'block', load on 'block_sides', path",
                "no path 'shear'",
                "press",
            ],
        ),
        // A path without a [load_path].
        (
            edited(&case, on_press),
            vec![
                "body 'disc', Dirichlet condition on 'disc_top', path",
                "'press'",
                "no [load_path]",
            ],
        ),
        // Lists of different lengths.
        (
            edited(&case, |t| {
                set_paths(t, &[("press", &[0.5, 1.0]), ("squeeze", &[1.0])]);
                on_press(t);
            }),
            vec!["[load_path]", "'press' has 2 factors", "'squeeze' 1"],
        ),
        // An empty list.
        (
            edited(&case, |t| {
                set_paths(t, &[("press", &[])]);
                on_press(t);
            }),
            vec!["[load_path] press", "non-empty", "an empty list"],
        ),
        // Factors that are not finite, or too large.
        (
            edited(&case, |t| {
                set_paths(t, &[("press", &[0.5, f64::NAN])]);
                on_press(t);
            }),
            vec!["[load_path] press", "finite", "NaN"],
        ),
        (
            edited(&case, |t| {
                set_paths(t, &[("press", &[f64::INFINITY])]);
                on_press(t);
            }),
            vec!["[load_path] press", "finite", "inf"],
        ),
        (
            edited(&case, |t| {
                set_paths(t, &[("press", &[1e300])]);
                on_press(t);
            }),
            vec!["[load_path] press", "1e300"],
        ),
        // load_steps of another length than the lists.
        (
            edited(&case.clone().load_steps(&[0.5, 0.75, 1.0]), |t| {
                set_paths(t, &[("press", &[0.5, 1.0])]);
                on_press(t);
            }),
            vec!["load_steps", "3 factors", "[load_path] lists have 2"],
        ),
        // An empty [load_path].
        (
            edited(&case, |t| set_paths(t, &[])),
            vec!["[load_path]", "names no path"],
        ),
        // load_steps written after the [load_path] line: a path of that table.
        (
            edited(&case, |t| {
                set_paths(t, &[("press", &[0.5, 1.0]), ("load_steps", &[0.5, 1.0])]);
                on_press(t);
            }),
            vec!["[load_path] load_steps", "before the first table"],
        ),
        // A name that cannot head a CSV column.
        (
            edited(&case, |t| set_paths(t, &[("a,b", &[1.0])])),
            vec!["[load_path] 'a,b'", "path_<name>"],
        ),
    ];
    for (text, parts) in cases {
        let error = load_error(&text);
        assert_mentions(&error, &parts);
    }
}

#[test]
fn load_paths_need_a_contact_solve() {
    // A body in no contact pair is solved once, at its full load.
    let block = common::block_3d_case();
    let error = load_error(&edited(&block, |t| set_paths(t, &[("press", &[1.0])])));
    assert_mentions(&error, &["[load_path]", "no [contact]"]);

    let error = load_error(&edited(&block, |t| {
        set_paths(t, &[("press", &[1.0])]);
        set_path(t, "block", "load", "block_top", "press");
    }));
    assert_mentions(&error, &["[load_path]", "no [contact]"]);

    // A body beside the pair, solved alone.
    let beside = CaseFile::on_fixture("three_blocks_2d.msh")
        .contact(["upper", "middle"], ["upper_contact", "middle_top"])
        .body(Body::new("upper", 1000.0, 0.3).dirichlet(Dirichlet::on("upper_top").uy(-0.01)))
        .body(Body::new("middle", 1000.0, 0.3).dirichlet(Dirichlet::clamped("middle_bottom", 2)))
        .body(
            Body::new("lower", 1000.0, 0.3)
                .dirichlet(Dirichlet::clamped("lower_base", 2))
                .load(Load::pressure("lower_contact", 1.0)),
        );
    let error = load_error(&edited(&beside, |t| {
        set_paths(t, &[("press", &[0.5, 1.0])]);
        set_path(t, "lower", "load", "lower_contact", "press");
    }));
    assert_mentions(
        &error,
        &[
            "body 'lower', load on 'lower_contact', path",
            "in no contact pair",
        ],
    );
}

#[test]
fn one_value_on_two_paths_is_an_error() {
    // disc_top's uy prescribed -0.02 along the default path and along `press`: the value at a
    // step would depend on which one wins.
    let case = squeezed().support("disc", Dirichlet::on("disc_top").uy(-0.02));
    let text = edited(&case, |t| {
        set_paths(t, &[("press", &[1.0])]);
        let bodies = t["body"].as_array_mut().unwrap();
        let disc = bodies
            .iter_mut()
            .find(|b| b["name"].as_str() == Some("disc"))
            .unwrap();
        let first = &mut disc["dirichlet"].as_array_mut().unwrap()[0];
        (first.as_table_mut().unwrap()).insert("path".into(), "press".into());
    });
    let (_dir, path) = write_case(&text);
    let error = common::hostile::run_quiet(&path)
        .err()
        .expect("refused")
        .to_string();
    assert_mentions(
        &error,
        &[
            "disc",
            "load path 'press'",
            "default load path",
            "one load path",
        ],
    );
}

#[test]
fn a_slide_reached_in_steps_ends_where_a_single_step_does() {
    // Frictionless: the half-disc pressed by 0.02 and pushed sideways by 0.1 (four spacings),
    // in one step or in ten (pressed, then pushed 0.01 at a time). The interface is paired for
    // the answer's slide rounded to a grid (0.05 of the smallest spacing), the same on both
    // paths, and a slid pair stops only once its gaps and its slide have settled within the
    // margin m = 0.01 tol_p h: both runs solve one discrete problem, each to within m of
    // its answer, and agree within 2 m. Paired again wherever a path happened to leave
    // its slide 0.05 spacings from the last pairing, and stopped on the gaps alone, they
    // differed by 3.4e-5 (140 m).
    let case = |steps: usize| {
        let disc = Body::new("disc", 1000.0, 0.3)
            .dirichlet(Dirichlet::on("disc_top").uy(-0.02))
            .dirichlet(Dirichlet::on("disc_top").ux(0.1));
        let case = CaseFile::on_fixture("half_disc_on_block.msh")
            .contact(["disc", "block"], ["disc_contact", "block_contact"])
            .primary("disc")
            .body(disc)
            .body(Body::new("block", 1000.0, 0.3).dirichlet(Dirichlet::clamped("block_base", 2)));
        edited(&case, |t| {
            let slide: Vec<f64> = (1..=steps).map(|k| k as f64 / steps as f64).collect();
            set_paths(t, &[("press", &vec![1.0; steps]), ("slide", &slide)]);
            let disc = &mut t["body"].as_array_mut().unwrap()[0];
            let entries = disc["dirichlet"].as_array_mut().unwrap();
            for (entry, path) in entries.iter_mut().zip(["press", "slide"]) {
                (entry.as_table_mut().unwrap()).insert("path".into(), path.into());
            }
        })
    };
    let (stepped, records) = solve_text(&case(10)).unwrap();
    let (single, _) = solve_text(&case(1)).unwrap();
    assert!(
        records[0]
            .iter()
            .all(|r| r.status == ContactStatus::Converged)
    );
    let (stepped, single) = (&stepped[0], &single[0]);
    assert_eq!(single.status, ContactStatus::Converged);
    let seen = (single.history.iter()).fold(0.0f64, |m, r| m.max(r.pairing_drift_over_h));
    assert!(seen > 1.0, "the slide was not seen: {seen} h");
    assert_eq!(stepped.primary_fields.active, single.primary_fields.active);
    assert_displacements_agree(stepped, single, 2.0 * settling_margin(&case(1)));
}
