//! Restarted GMRES, right-preconditioned: `A P^-1 y = b`, `x = P^-1 y` (Saad, *Iterative Methods
//! for Sparse Linear Systems*, 2nd ed., 2003, algorithm 9.5), with modified Gram-Schmidt applied
//! twice and Givens rotations.
//!
//! Right preconditioning keeps the residual GMRES minimizes the true one, `|b - A x|`, so the
//! stopping test reads the residual a caller checks. Each restart cycle recomputes it from `x`
//! (not the Arnoldi estimate) before deciding to stop, and forms its update as `P^-1 (V y)`,
//! one extra application of `P^-1` per cycle, instead of keeping the `P^-1 v_j` of every
//! direction (flexible GMRES): half the memory, which is what bounds the restart length on a
//! million unknowns. This needs `P^-1` to be the same linear map at every application, which
//! a fixed number of multigrid cycles or an exact factor solve is.
//!
//! # Why written here
//!
//! The operators are sums of a caller's sparse blocks and solves that can fail (a PETSc error, a
//! cancelled run): `apply` returns a `Result`, and its error reaches the caller as it is. faer
//! 0.24's matrix-free solvers (`faer::operator`) have no GMRES, and their operators are
//! infallible.

use std::fmt;

/// Where a solve stops and what it may spend.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GmresSettings {
    /// The solve stops once the true residual `|b - A x|` is at most this (absolute)...
    pub tolerance: f64,
    /// ...and, if set, at most this fraction of the starting guess's residual.
    pub reduction: Option<f64>,
    /// The most products with `A P^-1` (iterations) the solve may take.
    pub max_iterations: usize,
    /// Krylov vectors kept before a restart.
    pub restart: usize,
}

/// A restart cycle must bring the true residual below this fraction of the one it started
/// from; otherwise the iteration has stagnated (an inexact or singular operator sets a floor).
const STAGNATION: f64 = 0.9;

/// Why a solve stopped without reaching its tolerance.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GmresFailure {
    /// [`GmresSettings::max_iterations`] iterations were spent.
    IterationLimit,
    /// A restart cycle did not reduce the true residual.
    Stagnated,
    /// An operator produced a non-finite value.
    NotFinite,
}

impl fmt::Display for GmresFailure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::IterationLimit => "iteration limit reached",
            Self::Stagnated => "stagnated: a restart cycle did not reduce the true residual",
            Self::NotFinite => "a non-finite value appeared",
        })
    }
}

/// What a solve did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct GmresStats {
    /// Products with `A P^-1`.
    pub iterations: usize,
    /// Products with `A` alone: the true residual of each cycle's start.
    pub residual_products: usize,
    /// Applications of `P^-1`: one per iteration and one per cycle's update.
    pub preconditioner_applications: usize,
    /// `|b - A x|` at the start and at the end.
    pub initial_residual: f64,
    pub residual: f64,
    /// Why it stopped short of the tolerance (`None`: converged).
    pub failure: Option<GmresFailure>,
}

/// The operators of one solve. `A` and `P^-1` write their result into `out` (of the length of
/// `x`), which holds garbage on entry.
pub trait Operators {
    type Error;
    /// `out = A x`.
    fn apply(&mut self, x: &[f64], out: &mut [f64]) -> Result<(), Self::Error>;
    /// `out = P^-1 r`.
    fn precondition(&mut self, r: &[f64], out: &mut [f64]) -> Result<(), Self::Error>;
    /// `a . b` of two vectors as the operators hold them: the default is the sum over `a`'s
    /// entries, for vectors whole on this process; vectors shared among ranks add every rank's
    /// part (`crate::contact::coupled::krylov_layout`).
    fn dot(&mut self, a: &[f64], b: &[f64]) -> Result<f64, Self::Error> {
        Ok(dot(a, b))
    }
    /// Called after every iteration with the estimated residual norm: a progress report, or an
    /// error that stops the solve (a cancelled run).
    fn progress(&mut self, _stats: &GmresStats, _estimate: f64) -> Result<(), Self::Error> {
        Ok(())
    }
}

/// Solves `A x = b` from the guess in `x`, which receives the last iterate. Ends with
/// `stats.failure` set when the tolerance was not reached (the iterate is then the best one
/// found), and with `Err` only when an operator failed.
pub fn solve<O: Operators>(
    operators: &mut O,
    b: &[f64],
    x: &mut [f64],
    settings: GmresSettings,
) -> Result<GmresStats, O::Error> {
    let n = b.len();
    let mut stats = GmresStats::default();
    let mut residual = vec![0.0; n];
    let mut last = f64::INFINITY;
    let mut tolerance = settings.tolerance;
    loop {
        operators.apply(x, &mut residual)?;
        stats.residual_products += 1;
        for (r, b) in residual.iter_mut().zip(b) {
            *r = b - *r;
        }
        let beta = operators.dot(&residual, &residual)?.sqrt();
        stats.residual = beta;
        if stats.residual_products == 1 {
            stats.initial_residual = beta;
            if let Some(reduction) = settings.reduction {
                tolerance = tolerance.min(reduction * beta);
            }
        }
        stats.failure = if !beta.is_finite() {
            Some(GmresFailure::NotFinite)
        } else if beta <= tolerance {
            return Ok(stats);
        } else if stats.iterations >= settings.max_iterations {
            Some(GmresFailure::IterationLimit)
        } else if beta > STAGNATION * last {
            Some(GmresFailure::Stagnated)
        } else {
            None
        };
        if stats.failure.is_some() {
            return Ok(stats);
        }
        last = beta;
        let steps = settings
            .restart
            .min(n)
            .min(settings.max_iterations - stats.iterations)
            .max(1);
        let cycle = cycle(operators, &residual, beta, steps, tolerance, &mut stats)?;
        if let Some(failure) = cycle.failure {
            stats.failure = Some(failure);
            return Ok(stats);
        }
        // x += P^-1 (V y).
        let mut combined = vec![0.0; n];
        for (yi, v) in cycle.y.iter().zip(&cycle.basis) {
            for (c, vi) in combined.iter_mut().zip(v) {
                *c += yi * vi;
            }
        }
        operators.precondition(&combined, &mut residual)?;
        stats.preconditioner_applications += 1;
        for (xi, d) in x.iter_mut().zip(&residual) {
            *xi += d;
        }
    }
}

/// What one restart cycle leaves: the Arnoldi basis `V` and the least-squares solution `y`.
struct Cycle {
    basis: Vec<Vec<f64>>,
    y: Vec<f64>,
    failure: Option<GmresFailure>,
}

/// Arnoldi on `A P^-1` from `residual` (of norm `beta`), at most `steps` vectors, with the
/// Hessenberg matrix rotated as it grows so that `|g[j + 1]|` is the residual's estimate; stops
/// at half the `tolerance`, so that the true residual recomputed next passes too.
fn cycle<O: Operators>(
    operators: &mut O,
    residual: &[f64],
    beta: f64,
    steps: usize,
    tolerance: f64,
    stats: &mut GmresStats,
) -> Result<Cycle, O::Error> {
    let n = residual.len();
    let mut basis: Vec<Vec<f64>> = vec![residual.iter().map(|x| x / beta).collect()];
    let mut h = vec![vec![0.0; steps]; steps + 1];
    let (mut cs, mut sn) = (vec![0.0; steps], vec![0.0; steps]);
    let mut g = vec![0.0; steps + 1];
    g[0] = beta;
    let (mut z, mut used) = (vec![0.0; n], 0);
    for j in 0..steps {
        operators.precondition(&basis[j], &mut z)?;
        let mut w = vec![0.0; n];
        operators.apply(&z, &mut w)?;
        stats.preconditioner_applications += 1;
        stats.iterations += 1;
        orthogonalize(operators, &mut w, &basis, &mut h, j)?;
        let next = operators.dot(&w, &w)?.sqrt();
        h[j + 1][j] = next;
        for i in 0..j {
            let (a, b) = (h[i][j], h[i + 1][j]);
            h[i][j] = cs[i] * a + sn[i] * b;
            h[i + 1][j] = -sn[i] * a + cs[i] * b;
        }
        let (a, b) = (h[j][j], h[j + 1][j]);
        let rho = a.hypot(b);
        if !rho.is_finite() {
            return Ok(Cycle {
                basis,
                y: Vec::new(),
                failure: Some(GmresFailure::NotFinite),
            });
        }
        (cs[j], sn[j]) = if rho > 0.0 {
            (a / rho, b / rho)
        } else {
            (1.0, 0.0)
        };
        h[j][j] = rho;
        h[j + 1][j] = 0.0;
        g[j + 1] = -sn[j] * g[j];
        g[j] *= cs[j];
        used = j + 1;
        operators.progress(stats, g[j + 1].abs())?;
        if g[j + 1].abs() <= 0.5 * tolerance || next == 0.0 {
            break;
        }
        basis.push(w.iter().map(|x| x / next).collect());
    }
    // y = H^-1 g by back substitution.
    let mut y = vec![0.0; used];
    for i in (0..used).rev() {
        let tail: f64 = (i + 1..used).map(|k| h[i][k] * y[k]).sum();
        y[i] = if h[i][i] != 0.0 {
            (g[i] - tail) / h[i][i]
        } else {
            0.0
        };
    }
    basis.truncate(used);
    Ok(Cycle {
        basis,
        y,
        failure: None,
    })
}

/// Modified Gram-Schmidt of `w` against `basis`, twice: the basis stays orthogonal to round-off
/// however many vectors it holds. The coefficients accumulate in column `j` of `h`.
fn orthogonalize<O: Operators>(
    operators: &mut O,
    w: &mut [f64],
    basis: &[Vec<f64>],
    h: &mut [Vec<f64>],
    j: usize,
) -> Result<(), O::Error> {
    for _ in 0..2 {
        for (i, q) in basis.iter().enumerate() {
            let c = operators.dot(w, q)?;
            h[i][j] += c;
            for (wi, qi) in w.iter_mut().zip(q) {
                *wi -= c * qi;
            }
        }
    }
    Ok(())
}

pub fn norm(v: &[f64]) -> f64 {
    dot(v, v).sqrt()
}

/// `a . b`, summed in order.
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A nonsymmetric tridiagonal matrix, preconditioned by its diagonal.
    struct Tridiagonal {
        n: usize,
    }

    impl Operators for Tridiagonal {
        type Error = ();
        fn apply(&mut self, x: &[f64], out: &mut [f64]) -> Result<(), ()> {
            for i in 0..self.n {
                let left = if i > 0 { -x[i - 1] } else { 0.0 };
                let right = if i + 1 < self.n { -0.5 * x[i + 1] } else { 0.0 };
                out[i] = (3.0 + i as f64) * x[i] + left + right;
            }
            Ok(())
        }
        fn precondition(&mut self, r: &[f64], out: &mut [f64]) -> Result<(), ()> {
            for i in 0..self.n {
                out[i] = r[i] / (3.0 + i as f64);
            }
            Ok(())
        }
    }

    #[test]
    fn solves_a_nonsymmetric_system_across_restarts() {
        let n = 200;
        let mut ops = Tridiagonal { n };
        let exact: Vec<f64> = (0..n).map(|i| (i as f64 * 0.1).sin()).collect();
        let mut b = vec![0.0; n];
        ops.apply(&exact, &mut b).unwrap();
        let mut x = vec![0.0; n];
        let settings = GmresSettings {
            tolerance: 1e-12 * norm(&b),
            reduction: None,
            max_iterations: 500,
            restart: 5,
        };
        let stats = solve(&mut ops, &b, &mut x, settings).unwrap();
        assert_eq!(stats.failure, None);
        assert!(stats.residual <= settings.tolerance);
        assert!(stats.residual_products > 2, "restarted: {stats:?}");
        let error = x
            .iter()
            .zip(&exact)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(error < 1e-10, "error {error}");
    }

    #[test]
    fn a_reduction_is_asked_of_a_start_already_within_the_tolerance() {
        let n = 200;
        let mut ops = Tridiagonal { n };
        let exact: Vec<f64> = (0..n).map(|i| (i as f64 * 0.1).sin()).collect();
        let mut b = vec![0.0; n];
        ops.apply(&exact, &mut b).unwrap();
        // A start 1e-4 off the answer: within an absolute tolerance of 1e-3 |b|.
        let start: Vec<f64> = exact.iter().map(|v| v + 1e-4 * (v * 7.0).cos()).collect();
        for reduction in [None, Some(1e-2)] {
            let mut x = start.clone();
            let settings = GmresSettings {
                tolerance: 1e-3 * norm(&b),
                reduction,
                max_iterations: 500,
                restart: 50,
            };
            let stats = solve(&mut ops, &b, &mut x, settings).unwrap();
            assert_eq!(stats.failure, None);
            match reduction {
                None => assert_eq!(stats.iterations, 0),
                Some(r) => {
                    assert!(stats.iterations > 0);
                    assert!(stats.residual <= r * stats.initial_residual, "{stats:?}");
                }
            }
        }
    }

    /// The tridiagonal system held as `y = S x` with `S = diag(s)`: every value `s_i` times
    /// the unknown's, as a distributed vector holds its own rows in an order of its own. With
    /// the inner product of the unknowns, `(a . b) = sum a_i b_i / s_i^2`, GMRES takes the
    /// same iterates as on `x` itself.
    struct Scaled {
        inner: Tridiagonal,
        s: Vec<f64>,
    }

    impl Scaled {
        fn unscale(&self, y: &[f64]) -> Vec<f64> {
            y.iter().zip(&self.s).map(|(y, s)| y / s).collect()
        }
    }

    impl Operators for Scaled {
        type Error = ();
        fn apply(&mut self, y: &[f64], out: &mut [f64]) -> Result<(), ()> {
            let x = self.unscale(y);
            self.inner.apply(&x, out)?;
            out.iter_mut().zip(&self.s).for_each(|(o, s)| *o *= s);
            Ok(())
        }
        fn precondition(&mut self, r: &[f64], out: &mut [f64]) -> Result<(), ()> {
            let r = self.unscale(r);
            self.inner.precondition(&r, out)?;
            out.iter_mut().zip(&self.s).for_each(|(o, s)| *o *= s);
            Ok(())
        }
        fn dot(&mut self, a: &[f64], b: &[f64]) -> Result<f64, ()> {
            Ok(dot(&self.unscale(a), &self.unscale(b)))
        }
    }

    #[test]
    fn the_operators_inner_product_is_the_one_minimized() {
        let n = 200;
        let exact: Vec<f64> = (0..n).map(|i| (i as f64 * 0.1).sin()).collect();
        let mut b = vec![0.0; n];
        Tridiagonal { n }.apply(&exact, &mut b).unwrap();
        let settings = GmresSettings {
            tolerance: 1e-10 * norm(&b),
            reduction: None,
            max_iterations: 500,
            restart: 5,
        };
        let mut x = vec![0.0; n];
        let plain = solve(&mut Tridiagonal { n }, &b, &mut x, settings).unwrap();

        let s: Vec<f64> = (0..n).map(|i| 1.0 + 99.0 * (i % 2) as f64).collect();
        let mut scaled = Scaled {
            inner: Tridiagonal { n },
            s,
        };
        let b_scaled: Vec<f64> = b.iter().zip(&scaled.s).map(|(b, s)| b * s).collect();
        let mut y = vec![0.0; n];
        let held = solve(&mut scaled, &b_scaled, &mut y, settings).unwrap();
        assert_eq!(held.failure, None);
        // The residual it reports is the unknowns' (not the scaled values'), and the iterates
        // are those of the plain solve: the same count, the same answer.
        assert_eq!(held.iterations, plain.iterations);
        assert!((held.residual - plain.residual).abs() <= 1e-6 * plain.residual);
        let difference = (scaled.unscale(&y).iter().zip(&x))
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(difference < 1e-12, "{difference}");
    }

    #[test]
    fn names_the_iteration_limit() {
        let n = 200;
        let mut ops = Tridiagonal { n };
        let b = vec![1.0; n];
        let mut x = vec![0.0; n];
        let settings = GmresSettings {
            tolerance: 1e-14,
            reduction: None,
            max_iterations: 3,
            restart: 50,
        };
        let stats = solve(&mut ops, &b, &mut x, settings).unwrap();
        assert_eq!(stats.failure, Some(GmresFailure::IterationLimit));
        assert_eq!(stats.iterations, 3);
        assert!(stats.residual < stats.initial_residual);
    }
}
