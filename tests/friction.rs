//! Coulomb friction (`formulation = "coulomb"`) on the half-disc pressed onto a block (2D,
//! plane strain, R = 1): its limits (a vanishing coefficient is frictionless contact, a large
//! one sticks like tied contact from rest) and the load path of Cattaneo and Mindlin (pressed,
//! then sheared at a fixed approach), against Johnson's closed form for the stick zone, and full
//! slip carrying exactly `mu` times the normal force.
//!
//! A load path here is a sequence of cases on the same meshes, each solved from the node states
//! and displacements the last one ended in (`ContactSolution::active_set`).

mod common;

use common::case_builder::{Body, CaseFile, Dirichlet, Force};
use common::contact::{hemisphere_on_block, stacked_blocks};
use common::{half_disc_on_block, run_solve, write_case};
use internodes::case::Case;
use internodes::contact::{
    ActiveSet, ContactSettings, ContactSolution, ContactSolver, ContactStatus, Formulation,
    FrictionState,
};
use internodes::elastic::{SolverSettings, StepFactors};
use internodes::mesh::read_msh;

const MU: f64 = 0.3;
/// How far the disc's top is pushed down (R = 1: a / R about 0.11).
const APPROACH: f64 = 0.02;

/// The half-disc on the block, both of one material, the disc's top moved by `(shift,
/// -APPROACH)`, under `formulation`; the disc is the primary.
fn disc_on_block(shift: f64, formulation: &str, mu: Option<f64>) -> CaseFile {
    let case = half_disc_on_block("half_disc_on_block_hertz.msh")
        .with_body("disc", |_| {
            Body::new("disc", 1000.0, 0.3)
                .dirichlet(Dirichlet::on("disc_top").ux(shift).uy(-APPROACH))
        })
        .contact_setting("formulation", formulation);
    match mu {
        Some(mu) => case.contact_setting("friction_coefficient", mu),
        None => case,
    }
}

/// Solves the cases in turn, each from where the last one ended: one answer per case, and
/// the coordinates of the primary's candidate nodes.
fn along_path(cases: &[CaseFile]) -> (Vec<ContactSolution>, Vec<[f64; 3]>) {
    let mut start: Option<Vec<ActiveSet>> = None;
    let mut answers = Vec::new();
    let mut coords = Vec::new();
    for case in cases {
        let (_dir, path) = case.write();
        let case = Case::load(&path).unwrap();
        let mesh = read_msh(&case.mesh).unwrap();
        let problems = case.contact_problems(&mesh).unwrap();
        let settings = SolverSettings {
            verbose: false,
            ..case.solver.clone()
        };
        coords = problems[0].primary_surface.coords.clone();
        let mut solver = ContactSolver::new(&problems, &settings).unwrap();
        let mut solutions = (solver.solve(&StepFactors::uniform(1.0), start.as_deref())).unwrap();
        start = Some(solutions.iter().map(|s| s.active_set.clone()).collect());
        if std::env::var_os("FRICTION_HISTORY").is_some() {
            for record in &solutions[0].history {
                eprintln!("{}", record.line(true));
            }
        }
        answers.push(solutions.remove(0));
    }
    (answers, coords)
}

fn one(case: CaseFile) -> ContactSolution {
    along_path(&[case]).0.remove(0)
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

fn relative(a: [f64; 3], b: [f64; 3]) -> f64 {
    norm(std::array::from_fn(|k| a[k] - b[k])) / norm(b)
}

/// The half-width of the stick zone: half the distance between its outermost nodes, and the
/// largest spacing there (the resolution of that measure).
fn stick_half_width(solution: &ContactSolution, coords: &[[f64; 3]]) -> (f64, f64) {
    let friction = solution.primary_fields.friction.as_ref().unwrap();
    let x: Vec<f64> = (friction.state.iter().zip(coords))
        .filter(|(s, _)| **s == FrictionState::Stick)
        .map(|(_, x)| x[0])
        .collect();
    let (lo, hi) = x
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
            (l.min(v), h.max(v))
        });
    let mut sorted = x.clone();
    sorted.sort_by(f64::total_cmp);
    let spacing = sorted.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max);
    ((hi - lo) / 2.0, spacing)
}

#[test]
fn a_vanishing_coefficient_is_frictionless_and_a_large_one_sticks_like_tied_contact() {
    // Dissimilar materials, so that the frictionless and the tied answers differ: the block
    // 20 times stiffer pulls the disc's surface inwards as they are pressed together.
    // Each loop settles its active nodes on the other surface to 0.01 penetration_tolerance
    // of a spacing (method.md 3.3), so two answers on different paths differ by that much: a
    // tolerance of 1e-9 makes the differences of the laws themselves (of the order of mu)
    // the ones measured.
    let dissimilar = |formulation: &str, mu: Option<f64>| {
        disc_on_block(0.0, formulation, mu)
            .with_body("block", |b| Body {
                youngs_modulus: 2.0e4,
                ..b
            })
            .contact_setting("penetration_tolerance", 1e-9)
    };
    let frictionless = one(dissimilar("frictionless", None));
    let tied = one(dissimilar("tied", None));
    let sheared = relative(tied.force_primary, frictionless.force_primary);
    assert!(sheared > 1e-3, "the two limits differ by {sheared:.2e}");
    assert!(tied.max_tangential_traction > 1e-2 * tied.hertz_primary.unwrap().p0);

    let small = one(dissimilar("coulomb", Some(1e-9)));
    assert_eq!(small.status, ContactStatus::Converged);
    let friction = small.primary_fields.friction.as_ref().unwrap();
    assert_eq!(
        friction.stick_nodes, 0,
        "mu -> 0: every node in contact slips"
    );
    assert_eq!(
        small.primary_fields.active,
        frictionless.primary_fields.active
    );
    // Coulomb pairs hold a node along the block's averaged nodal normal, frictionless ones
    // along its facet's normal (method.md 1.4): the two differ by up to half the kink between
    // neighbouring facets of the indented block, h / R times the block's share of the
    // curvature (E*_disc / (E*_disc + E*_block) = 1/21 here), and each node's force turns by
    // as much. The force may differ by that angle; the law itself adds mu = 1e-9. Measured:
    // 2.2e-5 (2026-12-02), against 3e-4.
    let (_, coords) = along_path(&[dissimilar("frictionless", None)]);
    let mut x: Vec<f64> = coords
        .iter()
        .map(|c| c[0])
        .filter(|x| x.abs() < 0.1)
        .collect();
    x.sort_by(f64::total_cmp);
    let h = x.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max);
    let half_kink = 0.5 * h / 1.0 / 21.0;
    let off = relative(small.force_primary, frictionless.force_primary);
    assert!(
        off < half_kink,
        "mu = 1e-9 against frictionless: {off:.2e} (half the kink: {half_kink:.2e})"
    );

    let large = one(dissimilar("coulomb", Some(100.0)));
    assert_eq!(large.status, ContactStatus::Converged);
    let friction = large.primary_fields.friction.as_ref().unwrap();
    assert_eq!(
        friction.slip_nodes, 0,
        "mu = 100: every node in contact sticks"
    );
    // Tied contact holds the whole jump through R12 and corrects the gap by the fixed point
    // of section 3.2; Coulomb's sticking nodes hold the normal gap node to segment: the two
    // agree to the settled gap tolerance, not to round-off.
    let off = relative(large.force_primary, tied.force_primary);
    assert!(off < 1e-4, "mu = 100 against tied: {off:.2e}");
}

#[test]
fn a_disc_pressed_then_sheared_has_the_stick_zone_of_cattaneo_and_mindlin() {
    // Pressed, then sheared in steps at the same approach: both bodies of one material, so that
    // the shear does not change the pressure (Johnson 1985, 7.1): c = a sqrt(1 - Q / (mu P)).
    let shifts = [0.0, 0.002, 0.004, 0.006];
    let cases: Vec<CaseFile> = (shifts.iter())
        .map(|&s| disc_on_block(s, "coulomb", Some(MU)))
        .collect();
    let (answers, coords) = along_path(&cases);
    let pressed = &answers[0];
    let a = pressed.hertz_primary.unwrap().a;
    for (shift, answer) in shifts.iter().zip(&answers).skip(1) {
        assert_eq!(answer.status, ContactStatus::Converged, "shift {shift}");
        let friction = answer.primary_fields.friction.as_ref().unwrap();
        let (q, p) = (friction.tangential_force[0].abs(), friction.normal_force);
        let ratio = q / (MU * p);
        let (c, h) = stick_half_width(answer, &coords);
        let expected = a * (1.0 - ratio).sqrt();
        eprintln!(
            "shift {shift}: Q/(mu P) = {ratio:.3}, c = {c:.4}, Johnson {expected:.4}, a = {a:.4}, h = {h:.4}, stick {} slip {}",
            friction.stick_nodes, friction.slip_nodes
        );
        assert!(ratio > 0.05 && ratio < 0.95, "shift {shift}: partial slip");
        // The measured half-width lies between nodes: within a spacing of the closed form,
        // plus the spacing of the Hertz fit's a.
        assert!(
            (c - expected).abs() <= 1.5 * h,
            "shift {shift}: c = {c:.4} against {expected:.4} (h = {h:.4})"
        );
    }
}

/// The two stacked blocks of the fixture (2D, non-matching meshes), the upper one pressed
/// 0.01 into the lower one and dragged along it by `drag` (the upper one is the primary). The
/// upper block's edge overhangs the lower one's as it slides; the conservative transfer keeps
/// the two bodies' forces balanced there (the interpolation's was 11% off at a drag of 0.05).
fn block_dragged(drag: f64) -> CaseFile {
    stacked_blocks(2)
        .with_body("upper", |_| {
            Body::new("upper", 1000.0, 0.3).dirichlet(Dirichlet::on("upper_top").ux(drag).uy(-0.01))
        })
        .support("lower", Dirichlet::on("lower_base").ux(0.0))
        .contact_setting("transfer", "conservative")
        .contact_setting("formulation", "coulomb")
        .contact_setting("friction_coefficient", MU)
}

#[test]
fn a_block_dragged_in_full_slip_carries_mu_times_its_normal_force() {
    // A flat contact in full slip: the tangential force is mu times the normal force.
    let drags = [0.0, 0.05, 0.1, 0.15];
    let cases: Vec<CaseFile> = drags.iter().map(|&d| block_dragged(d)).collect();
    let (answers, _) = along_path(&cases);
    for (drag, answer) in drags.iter().zip(&answers).skip(1) {
        assert_eq!(answer.status, ContactStatus::Converged, "drag {drag}");
        let friction = answer.primary_fields.friction.as_ref().unwrap();
        assert_eq!(friction.stick_nodes, 0, "drag {drag}: full slip");
        // Every node carries mu times its pressure along its contact normal (the deformed lower
        // surface's where it is held), read from the output fields: the traction on the primary
        // is lambda = t_T - p n, so p = |lambda - t_T|.
        let fields = &answer.primary_fields;
        let (mut worst, mut p_max) = (0.0_f64, 0.0_f64);
        for (i, state) in friction.state.iter().enumerate() {
            if *state == FrictionState::Open {
                continue;
            }
            let (t, lambda) = (friction.tangential_traction[i], fields.traction[i]);
            let p = norm(std::array::from_fn(|k| lambda[k] - t[k]));
            worst = worst.max((norm(t) - MU * p).abs());
            p_max = p_max.max(p);
        }
        assert!(
            worst <= 1e-9 * MU * p_max,
            "drag {drag}: |t_T| - mu p up to {worst:.3e}"
        );
        // The summary's Q and P split the total force along the primary's own (flat, undeformed)
        // normal instead: the lower surface's deformed facets tilt under the drag (shear strains
        // of a few percent at these drags), so |Q| / P is below mu by about the tilt over mu
        // (3.3% at a drag of 0.05): a small-deformation model with the gap measured on the
        // deformed surfaces.
        let q = friction.tangential_force;
        let p = friction.normal_force;
        assert!(
            q[0].abs() < MU * p,
            "drag {drag}: Q {:.6e}, mu P {:.6e}",
            q[0],
            MU * p
        );
        let q = q[0];
        // The friction on the upper block opposes its slip (it is dragged along +x).
        assert!(q < 0.0, "drag {drag}: Q = {q:.3e}");
        // The force the contact puts on the block balances the punch's.
        let imbalance = (answer.force_primary[0] + answer.force_secondary[0]).abs() / q.abs();
        assert!(
            imbalance < 1e-2,
            "drag {drag}: tangential imbalance {imbalance:.2e}"
        );
    }
}

#[test]
fn a_friction_coefficient_is_refused_without_coulomb_and_required_with_it() {
    for (formulation, mu) in [
        ("frictionless", Some(0.3)),
        ("tied", Some(0.3)),
        ("coulomb", None),
    ] {
        let (_dir, path) = disc_on_block(0.0, formulation, mu).write();
        let case = Case::load(&path).unwrap();
        let mesh = read_msh(&case.mesh).unwrap();
        let error = (case.contact_problems(&mesh).err())
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(
            error.contains("friction_coefficient") && error.contains("[contact]"),
            "{formulation}: {error}"
        );
    }
    for mu in [0.0, -1.0, f64::INFINITY, f64::NAN] {
        let settings = ContactSettings {
            formulation: Formulation::Coulomb,
            friction_coefficient: Some(mu),
            ..ContactSettings::default()
        };
        let error = settings.validate().unwrap_err().to_string();
        assert!(error.contains("friction_coefficient"), "mu = {mu}: {error}");
    }
}

/// The hemisphere (R = 1, the contact zone meshed at R/67) pressed 0.01 into the block of the
/// same material, its top shifted by `shift` along x.
fn sphere(shift: f64) -> CaseFile {
    hemisphere_on_block("hemisphere_on_block_hertz.msh", 0.01, 1000.0, 1000.0)
        .with_body("sphere", |_| {
            Body::new("sphere", 1000.0, 0.3)
                .dirichlet(Dirichlet::on("sphere_top").ux(shift).uy(0.0).uz(-0.01))
        })
        .contact_setting("formulation", "coulomb")
        .contact_setting("friction_coefficient", MU)
}

#[test]
fn a_sphere_pressed_then_sheared_has_the_stick_zone_of_mindlin() {
    // 3D: the hemisphere (R = 1, the contact zone meshed at R/67) pressed 0.01 into the block
    // of the same material, then sheared along x at the same approach:
    // c = a (1 - Q / (mu P))^(1/3) (Mindlin 1949; Johnson 1985, 7.2).
    let shifts = [0.0, 0.0012];
    let cases: Vec<CaseFile> = shifts.iter().map(|&s| sphere(s)).collect();
    let (answers, coords) = along_path(&cases);
    let fit = answers[0].hertz_primary.unwrap();
    for (shift, answer) in shifts.iter().zip(&answers).skip(1) {
        assert_eq!(answer.status, ContactStatus::Converged, "shift {shift}");
        let friction = answer.primary_fields.friction.as_ref().unwrap();
        let (q, p) = (friction.tangential_force[0].abs(), friction.normal_force);
        let ratio = q / (MU * p);
        // The stick zone's radius: the largest distance from the zone's centre of a sticking
        // node, against the smallest of a node in contact that slips.
        let radius = |i: usize| {
            let x = coords[i];
            ((x[0] - fit.center[0]).powi(2) + (x[1] - fit.center[1]).powi(2)).sqrt()
        };
        let (mut stick, mut slip) = (0.0_f64, f64::INFINITY);
        for (i, state) in friction.state.iter().enumerate() {
            match state {
                FrictionState::Stick => stick = stick.max(radius(i)),
                FrictionState::Slip => slip = slip.min(radius(i)),
                FrictionState::Open => {}
            }
        }
        let expected = fit.a * (1.0 - ratio).cbrt();
        eprintln!(
            "shift {shift}: Q/(mu P) = {ratio:.3}, stick to r = {stick:.4}, slip from r = {slip:.4}, Mindlin c = {expected:.4}, a = {:.4}",
            fit.a
        );
        assert!(ratio > 0.1 && ratio < 0.9, "shift {shift}: partial slip");
        // The slip directions settle by Newton's method (`docs/method.md` 1.4): near the
        // answer one iteration shrinks their change by far more than a fixed-point update of
        // the directions does (Anderson-accelerated, at best 0.17 per iteration here).
        let changes: Vec<f64> = (answer.history.iter())
            .filter_map(|record| record.max_direction_change)
            .filter(|&change| change > 0.0)
            .collect();
        let fastest = (changes.windows(2))
            .map(|pair| pair[1] / pair[0])
            .fold(f64::INFINITY, f64::min);
        eprintln!(
            "shift {shift}: direction changes {changes:?}, fastest contraction {fastest:.1e}"
        );
        assert!(
            fastest < 1e-2,
            "shift {shift}: direction changes {changes:?}"
        );
        // The edge lies between the outermost sticking node and the innermost slipping one,
        // within a spacing (R/67 = 0.015) of each.
        let h = 0.015;
        assert!(
            stick <= expected + h && slip >= expected - h,
            "shift {shift}: stick to {stick:.4}, slip from {slip:.4}, Mindlin {expected:.4}"
        );
    }
}

/// The upper of the two stacked blocks pushed down by `push` and sideways by `shear` (total
/// forces on its top, which moves rigidly), held sideways by nothing but friction.
fn block_pushed(push: f64, shear: f64) -> CaseFile {
    stacked_blocks(2)
        .with_body("upper", |_| {
            Body::new("upper", 1000.0, 0.3).force(Force {
                group: "upper_top".to_string(),
                fx: Some(shear),
                fy: Some(-push),
                fz: None,
            })
        })
        .support("lower", Dirichlet::on("lower_base").ux(0.0))
        .contact_setting("transfer", "conservative")
        .contact_setting("formulation", "coulomb")
        .contact_setting("friction_coefficient", MU)
}

#[test]
fn a_block_held_sideways_by_friction_alone_is_accepted_while_it_sticks_and_refused_by_name_beyond()
{
    // Below the cone (shear = mu push / 2) the friction holds the block: a solved answer whose
    // contact carries the whole shear.
    let held = one(block_pushed(10.0, 0.5 * MU * 10.0));
    assert_eq!(held.status, ContactStatus::Converged);
    let friction = held.primary_fields.friction.as_ref().unwrap();
    let q = friction.tangential_force[0];
    assert!((q + 0.5 * MU * 10.0).abs() < 1e-6 * 10.0, "Q = {q:.9e}");
    // Beyond it (shear = 1.5 mu push) every node slips and nothing holds the block sideways.
    let (_dir, path) = block_pushed(10.0, 1.5 * MU * 10.0).write();
    let case = Case::load(&path).unwrap();
    let mesh = read_msh(&case.mesh).unwrap();
    let problems = case.contact_problems(&mesh).unwrap();
    let settings = SolverSettings {
        verbose: false,
        ..case.solver.clone()
    };
    let error = ContactSolver::new(&problems, &settings)
        .and_then(|mut solver| solver.solve(&StepFactors::uniform(1.0), None))
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(
        error.contains("'upper'") && error.contains("friction"),
        "{error}"
    );
}

#[test]
fn a_load_path_in_one_run_is_the_chain_of_its_steps_with_each_steps_friction_in_the_outputs() {
    // The disc pressed (path "press"), then sheared (path "shear") in one run of the command
    // line: each step starts from the last, as the library's chain of cases does.
    let shifts = [0.0, 0.003, 0.006];
    let chained = along_path(
        &(shifts.iter())
            .map(|&s| disc_on_block(s, "coulomb", Some(MU)))
            .collect::<Vec<_>>(),
    )
    .0;
    let case = disc_on_block(0.0, "coulomb", Some(MU)).with_body("disc", |_| {
        Body::new("disc", 1000.0, 0.3)
            .dirichlet(Dirichlet::on("disc_top").uy(-APPROACH))
            .dirichlet(Dirichlet::on("disc_top").ux(0.006))
    });
    let mut table: toml::Table = toml::from_str(&case.to_toml()).unwrap();
    let list = |v: &[f64]| toml::Value::Array(v.iter().map(|&f| toml::Value::Float(f)).collect());
    let mut paths = toml::Table::new();
    paths.insert("press".into(), list(&[1.0, 1.0, 1.0]));
    paths.insert("shear".into(), list(&[0.0, 0.5, 1.0]));
    table.insert("load_path".into(), toml::Value::Table(paths));
    let entries = table["body"].as_array_mut().unwrap()[0]["dirichlet"]
        .as_array_mut()
        .unwrap();
    for (entry, path) in entries.iter_mut().zip(["press", "shear"]) {
        let entry = entry.as_table_mut().unwrap();
        entry.insert("path".into(), toml::Value::String(path.into()));
    }
    let (dir, path) = write_case(&toml::to_string(&table).unwrap());
    let output = run_solve(&path);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let text = std::fs::read_to_string(dir.path().join("out/summary.json")).unwrap();
    let summary: serde_json::Value = serde_json::from_str(&text).unwrap();
    let steps = summary["contact"]["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 3);
    for (step, chain) in steps.iter().zip(&chained) {
        let friction = &step["friction"];
        let expected = chain.primary_fields.friction.as_ref().unwrap();
        let q = friction["tangential_force"][0].as_f64().unwrap();
        // Both end when their active nodes settle within 0.01 penetration_tolerance h: the
        // same answer to that precision, not to round-off.
        let off = (q - expected.tangential_force[0]).abs() / (MU * expected.normal_force);
        assert!(
            off < 1e-4,
            "step {}: Q {q:.6e} against {:.6e}",
            step["step"],
            expected.tangential_force[0]
        );
        assert_eq!(friction["stick_nodes"], expected.stick_nodes);
        assert_eq!(friction["slip_nodes"], expected.slip_nodes);
    }
    // The CSV has the friction columns, and the XDMF the friction fields.
    let csv = std::fs::read_to_string(dir.path().join("out/force_displacement.csv")).unwrap();
    assert!(
        csv.lines()
            .next()
            .unwrap()
            .contains("tangential_force_x,tangential_force_y,normal_force,stick_nodes,slip_nodes"),
        "{csv}"
    );
    let xdmf = std::fs::read_to_string(dir.path().join("out/solution.xdmf")).unwrap();
    for field in [
        "friction_state",
        "tangential_traction",
        "slip_increment",
        "accumulated_slip",
    ] {
        assert!(xdmf.contains(&format!("Name=\"{field}\"")), "{field}");
    }
}

#[test]
fn a_sphere_sheared_back_and_forth_follows_the_hysteresis_loop_of_mindlin_and_deresiewicz() {
    // The sphere of the test above, pressed, sheared by its top's shift to d* in three steps
    // (d*/4, d*/2, d*), then back to -d* (d*/2, 0, -d*). Mindlin and Deresiewicz (1953;
    // Johnson 1985, 7.3): where shear does not change the pressure (one material), the
    // unloading from the turning point (d*, Q*) is the loading curve doubled,
    //
    //     Q_unload(d* - 2s) = Q* - 2 Q_load(s),
    //
    // since the change from the turning point solves the loading problem with the friction
    // bound 2 mu p. The discrete law node by node obeys the same superposition: what departs
    // from it is the shear's effect on the pressure of these finite bodies, and the stick zone's
    // edge, known to a node. The check reads only forces, against a property of the exact
    // solution, not against the solver's own quantities.
    let d = 0.0012;
    let shifts = [0.0, d / 4.0, d / 2.0, d, d / 2.0, 0.0, -d];
    let cases: Vec<CaseFile> = shifts.iter().map(|&s| sphere(s)).collect();
    let (answers, _) = along_path(&cases);
    let forces: Vec<(f64, f64)> = answers
        .iter()
        .map(|answer| {
            assert_eq!(answer.status, ContactStatus::Converged);
            let friction = answer.primary_fields.friction.as_ref().unwrap();
            (friction.tangential_force[0], friction.normal_force)
        })
        .collect();
    let (q, p): (Vec<f64>, Vec<f64>) = forces.into_iter().unzip();
    let mu_p = MU * p[0];
    eprintln!(
        "shifts {shifts:?}\nQ/(mu P) {:?}",
        q.iter().map(|q| q / mu_p).collect::<Vec<_>>()
    );
    let turning = q[3].abs() / mu_p;
    assert!(
        turning > 0.3 && turning < 0.6,
        "partial slip at the turning point: {turning}"
    );
    // (loading step s, unloading step at d* - 2 s)
    for (load, unload) in [(1, 4), (2, 5), (3, 6)] {
        let masing = q[3] - 2.0 * q[load];
        let off = (q[unload] - masing).abs() / mu_p;
        eprintln!(
            "shift {}: Q/(mu P) = {:.4}, Mindlin-Deresiewicz {:.4}, off by {off:.2e} mu P",
            shifts[unload],
            q[unload] / mu_p,
            masing / mu_p
        );
        // The bound: each force is known to the stick zone's edge, a node (about 560 in
        // contact: one node's share of mu P is 0.2%), and the relation combines four of them
        // (one doubled): 4 x 0.2%, rounded up to 1%. The press alone makes a tangential force
        // of 0.1% of mu P (zero on half-spaces). Measured: 0.3%, 0.5%, 0.6% of mu P.
        assert!(
            off < 0.01,
            "shift {}: off by {off:.3e} of mu P",
            shifts[unload]
        );
    }
    // The pressure hardly moves with the shear (the premise of the closed form).
    let p_change = p.iter().map(|x| (x - p[0]).abs()).fold(0.0, f64::max) / p[0];
    eprintln!(
        "normal force changed by {p_change:.2e} of P; the press alone made Q = {:.2e} mu P",
        q[0].abs() / mu_p
    );
    assert!(p_change < 1e-2, "normal force changed by {p_change:.2e}");
    assert!(q[0].abs() < 1e-3 * mu_p);
}
