//! A contact solve whose `Cancel` token is cancelled stops with `ContactError::Cancelled`, from
//! the library's own API (the Python module's Ctrl-C and `Cancel` rest on it).

mod common;

use std::time::{Duration, Instant};

use common::contact::half_disc_on_block;
use internodes::cancel::Cancel;
use internodes::case::Case;
use internodes::contact::{ContactError, solve_contact};
use internodes::elastic::SolverSettings;
use internodes::mesh::{Mesh, read_msh};

/// The half-disc on the block, its mesh, and quiet solver settings with a fresh token.
fn half_disc_with_a_token() -> (Case, Mesh, SolverSettings) {
    let (_dir, path) = half_disc_on_block().write();
    let case = Case::load(&path).unwrap();
    let mesh = read_msh(&case.mesh).unwrap();
    let settings = SolverSettings {
        verbose: false,
        cancel: Cancel::new(),
        ..case.solver.clone()
    };
    (case, mesh, settings)
}

#[test]
fn a_cancelled_token_stops_the_contact_solve() {
    let (case, mesh, settings) = half_disc_with_a_token();
    let steps = [0.25, 0.5, 0.75, 1.0];
    // Not cancelled: solved.
    let problem = case.contact_problems(&mesh).unwrap().remove(0);
    assert!(solve_contact(vec![problem], &settings, &steps).is_ok());
    // Cancelled, here before the solve starts: the first safe point stops it.
    settings.cancel.cancel();
    let problem = case.contact_problems(&mesh).unwrap().remove(0);
    let error = solve_contact(vec![problem], &settings, &steps)
        .err()
        .unwrap();
    assert!(matches!(error, ContactError::Cancelled(_)), "{error}");
    assert_eq!(error.to_string(), "the solve was cancelled");
}

#[test]
fn a_token_cancelled_from_another_thread_stops_a_running_solve() {
    let (case, mesh, settings) = half_disc_with_a_token();
    // Many load steps, so that the solve outlasts the wait below by far.
    let steps: Vec<f64> = (1..=2000).map(|k| f64::from(k) / 2000.0).collect();
    let token = settings.cancel.clone();
    let problem = case.contact_problems(&mesh).unwrap().remove(0);
    let cancelled_at = std::thread::scope(|scope| {
        let solve = scope.spawn(|| solve_contact(vec![problem], &settings, &steps));
        std::thread::sleep(Duration::from_millis(300));
        let at = Instant::now();
        token.cancel();
        let error = solve.join().unwrap().err().expect("the solve was stopped");
        assert!(matches!(error, ContactError::Cancelled(_)), "{error}");
        at.elapsed()
    });
    assert!(cancelled_at < Duration::from_secs(2), "{cancelled_at:?}");
}
