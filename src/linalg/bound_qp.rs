//! Convex quadratic programs with non-negative unknowns, by MPRGP (modified proportioning with
//! reduced gradient projections; Dostál and Schöberl, *Comput. Optim. Appl.* 30, 2005; Dostál,
//! *Optimal Quadratic Programming Algorithms*, Springer 2009, algorithm 5.8):
//!
//! ```text
//! min  1/2 x^T A x + c^T x   over  x >= 0,        A symmetric positive definite
//! ```
//!
//! whose solution is that of the linear complementarity problem `x >= 0`, `g = A x + c >= 0`,
//! `x . g = 0`. Write `F = {i : x_i > 0}` (free) and the parts of the gradient `g`: the free
//! gradient `phi_i = g_i` on `F` (0 off it), the chopped gradient `beta_i = min(g_i, 0)` off `F`
//! (0 on it), and the projected gradient `g^P = phi + beta`, zero exactly at the solution. Each
//! iteration takes one of three steps:
//!
//! * **conjugate gradients** on the free unknowns while the chopped gradient is small against the
//!   free one (`|beta|^2 <= Gamma^2 phi~ . phi`, with the reduced free gradient
//!   `phi~_i = min(x_i / alpha, phi_i)` on `F`) and the CG step stays feasible;
//! * **expansion**, where the CG step would leave the feasible set: the largest feasible step
//!   along the CG direction, then a projected gradient step of fixed length `alpha` (in
//!   `(0, 2 / |A|]`), which may free or bind many unknowns at once;
//! * **proportioning** otherwise: a minimizing step along `-beta`, releasing the bound unknowns
//!   whose gradient says they should leave the bound.
//!
//! The cost is the products with `A`: one a step (two an expansion). It converges R-linearly
//! for any `Gamma > 0` and `alpha` in `(0, 2 / |A|]`, and where the solution is not degenerate
//! it finds the final free set after finitely many steps, from which on it is CG on the free
//! unknowns, at the rate the square root of `A`'s condition number sets (Dostál and Schöberl).
//!
//! Why hand-written: the crates that solve QPs (Clarabel, OSQP) take `A` as an assembled sparse
//! matrix and factor it, and the matrices this serves are dense and never assembled (the
//! half-space compliance of a contact zone, `crate::contact::coupled::half_space`, whose far part
//! is lumped); MPRGP needs only products.

use super::gmres::dot;

/// `A` of the program, through its products.
pub trait SymmetricOperator {
    /// Why a product could not be made (a sum over the ranks of a distributed run).
    type Error;
    /// `out = A x`.
    fn apply(&mut self, x: &[f64], out: &mut [f64]) -> Result<(), Self::Error>;
}

/// When [`solve`] stops.
#[derive(Debug, Clone, Copy)]
pub struct BoundQpSettings {
    /// The largest entry of the projected gradient `g^P` accepted (an absolute value, in the
    /// units of `g`).
    pub tolerance: f64,
    /// Products with `A` at most.
    pub max_products: usize,
}

/// How [`solve`] ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoundQpOutcome {
    /// Whether the projected gradient reached the tolerance.
    pub converged: bool,
    /// Products with `A` taken.
    pub products: usize,
    /// The largest entry of the projected gradient at the end.
    pub projected_gradient: f64,
}

/// The proportioning constant `Gamma`: 1 balances the two tests (Dostál's choice in his
/// contact examples).
const GAMMA: f64 = 1.0;

/// The expansion step's length `alpha` as a fraction of `2 / |A|`'s bound: below 2 keeps the
/// projected gradient step a descent step when `norm_bound` is close to `|A|`.
const EXPANSION: f64 = 0.95;

/// Solves the program from `x` (projected onto `x >= 0` first) with `g = A x + c` at that
/// start, both overwritten by the last iterate and its gradient; `norm_bound` is an upper bound
/// of the 2-norm of `A` (for a matrix of positive entries, its largest row sum). Running out
/// of products is an outcome, not an error: the iterate is the best found. The only error is
/// a product's.
pub fn solve<A: SymmetricOperator>(
    a: &mut A,
    x: &mut [f64],
    g: &mut [f64],
    norm_bound: f64,
    settings: BoundQpSettings,
) -> Result<BoundQpOutcome, A::Error> {
    let n = x.len();
    assert_eq!(g.len(), n, "one gradient entry per unknown");
    let mut outcome = BoundQpOutcome {
        converged: false,
        products: 0,
        projected_gradient: 0.0,
    };
    let alpha = 2.0 * EXPANSION / norm_bound;
    let mut ap = vec![0.0; n];
    // A start outside the bounds is moved onto them, its gradient with it.
    let shift: Vec<f64> = x.iter().map(|&v| (-v).max(0.0)).collect();
    if shift.iter().any(|&s| s > 0.0) {
        a.apply(&shift, &mut ap)?;
        outcome.products += 1;
        for i in 0..n {
            x[i] += shift[i];
            g[i] += ap[i];
        }
    }
    let free = |x: &[f64], g: &[f64]| -> Vec<f64> {
        (0..n)
            .map(|i| if x[i] > 0.0 { g[i] } else { 0.0 })
            .collect()
    };
    let mut p = free(x, g);
    loop {
        let phi = free(x, g);
        let beta: Vec<f64> = (0..n)
            .map(|i| if x[i] > 0.0 { 0.0 } else { g[i].min(0.0) })
            .collect();
        outcome.projected_gradient = (0..n).map(|i| (phi[i] + beta[i]).abs()).fold(0.0, f64::max);
        if outcome.projected_gradient <= settings.tolerance {
            outcome.converged = true;
            return Ok(outcome);
        }
        if outcome.products >= settings.max_products || !outcome.projected_gradient.is_finite() {
            return Ok(outcome);
        }
        let chopped: f64 = beta.iter().map(|b| b * b).sum();
        let reduced: f64 = (0..n)
            .filter(|&i| x[i] > 0.0)
            .map(|i| (x[i] / alpha).min(phi[i]) * phi[i])
            .sum();
        if chopped <= GAMMA * GAMMA * reduced {
            a.apply(&p, &mut ap)?;
            outcome.products += 1;
            let pap = dot(&p, &ap);
            if pap.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
                // Not positive definite along p, p = 0, or NaN: nothing more to gain.
                return Ok(outcome);
            }
            let cg_step = dot(g, &p) / pap;
            let feasible_step = (0..n)
                .filter(|&i| p[i] > 0.0)
                .map(|i| x[i] / p[i])
                .fold(f64::INFINITY, f64::min);
            if cg_step <= feasible_step {
                // Conjugate gradients.
                for i in 0..n {
                    x[i] -= cg_step * p[i];
                    g[i] -= cg_step * ap[i];
                }
                let phi = free(x, g);
                let gamma = dot(&phi, &ap) / pap;
                for i in 0..n {
                    p[i] = phi[i] - gamma * p[i];
                }
            } else {
                // Expansion: to the bound, then a projected gradient step.
                for i in 0..n {
                    x[i] = (x[i] - feasible_step * p[i]).max(0.0);
                    g[i] -= feasible_step * ap[i];
                }
                let phi = free(x, g);
                let step: Vec<f64> = (0..n)
                    .map(|i| (x[i] - alpha * phi[i]).max(0.0) - x[i])
                    .collect();
                a.apply(&step, &mut ap)?;
                outcome.products += 1;
                for i in 0..n {
                    x[i] += step[i];
                    g[i] += ap[i];
                }
                p = free(x, g);
            }
        } else {
            // Proportioning: along -beta, which only raises bound unknowns.
            a.apply(&beta, &mut ap)?;
            outcome.products += 1;
            let step = chopped / dot(&beta, &ap);
            if !(step > 0.0 && step.is_finite()) {
                return Ok(outcome);
            }
            for i in 0..n {
                x[i] -= step * beta[i];
                g[i] -= step * ap[i];
            }
            p = free(x, g);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A dense symmetric matrix, row by row.
    struct Dense(Vec<Vec<f64>>);

    impl SymmetricOperator for Dense {
        type Error = std::convert::Infallible;
        fn apply(&mut self, x: &[f64], out: &mut [f64]) -> Result<(), Self::Error> {
            for (o, row) in out.iter_mut().zip(&self.0) {
                *o = dot(row, x);
            }
            Ok(())
        }
    }

    /// The matrix `exp(-|i - j| / 3) + delta_ij` (positive definite: a Gram matrix of a
    /// positive definite kernel plus the identity) of size `n`, and its largest row sum.
    fn kernel_matrix(n: usize) -> (Dense, f64) {
        let rows: Vec<Vec<f64>> = (0..n)
            .map(|i| {
                (0..n)
                    .map(|j| (-(i as f64 - j as f64).abs() / 3.0).exp() + f64::from(i == j))
                    .collect()
            })
            .collect();
        let bound = rows
            .iter()
            .map(|r| r.iter().sum::<f64>())
            .fold(0.0, f64::max);
        (Dense(rows), bound)
    }

    #[test]
    fn the_solution_holds_the_complementarity_conditions() {
        // c with both signs: some unknowns end free, some on the bound.
        let n = 60;
        let (mut a, bound) = kernel_matrix(n);
        let c: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).sin() - 0.2).collect();
        let mut x = vec![0.0; n];
        let mut g = c.clone();
        let settings = BoundQpSettings {
            tolerance: 1e-12,
            max_products: 500,
        };
        let Ok(outcome) = solve(&mut a, &mut x, &mut g, bound, settings);
        assert!(outcome.converged, "{outcome:?}");
        // The gradient the solver kept is A x + c, recomputed here.
        let mut ax = vec![0.0; n];
        let Ok(()) = a.apply(&x, &mut ax);
        let (mut free, mut bound_count) = (0, 0);
        for i in 0..n {
            let gi = ax[i] + c[i];
            assert!(
                (gi - g[i]).abs() < 1e-10,
                "gradient {i}: {gi} against {}",
                g[i]
            );
            assert!(x[i] >= 0.0, "x[{i}] = {}", x[i]);
            if x[i] > 0.0 {
                assert!(gi.abs() < 1e-10, "free {i}: gradient {gi}");
                free += 1;
            } else {
                assert!(gi > -1e-10, "bound {i}: gradient {gi}");
                bound_count += 1;
            }
        }
        assert!(
            free > 5 && bound_count > 5,
            "{free} free, {bound_count} bound"
        );
    }

    #[test]
    fn it_matches_projected_gauss_seidel_run_to_convergence() {
        // An independent solver of the same complementarity problem: projected Gauss-Seidel
        // (convergent for a symmetric positive definite matrix), run for many sweeps.
        let n = 40;
        let (mut a, bound) = kernel_matrix(n);
        let c: Vec<f64> = (0..n).map(|i| (i as f64 * 1.3).cos() - 0.1).collect();
        let mut reference = vec![0.0; n];
        for _ in 0..5_000 {
            for i in 0..n {
                let gi = dot(&a.0[i], &reference) + c[i];
                reference[i] = (reference[i] - gi / a.0[i][i]).max(0.0);
            }
        }
        // A start outside the bounds, with its gradient.
        let mut x: Vec<f64> = (0..n)
            .map(|i| if i % 3 == 0 { -1.0 } else { 0.5 })
            .collect();
        let mut g = vec![0.0; n];
        let Ok(()) = a.apply(&x, &mut g);
        g.iter_mut().zip(&c).for_each(|(g, c)| *g += c);
        let settings = BoundQpSettings {
            tolerance: 1e-13,
            max_products: 500,
        };
        let Ok(outcome) = solve(&mut a, &mut x, &mut g, bound, settings);
        assert!(outcome.converged, "{outcome:?}");
        for i in 0..n {
            assert!(
                (x[i] - reference[i]).abs() < 1e-11,
                "{i}: {} against {}",
                x[i],
                reference[i]
            );
        }
    }

    #[test]
    fn running_out_of_products_is_an_outcome() {
        let (mut a, bound) = kernel_matrix(30);
        let c: Vec<f64> = (0..30).map(|i| (i as f64).sin()).collect();
        let (mut x, mut g) = (vec![0.0; 30], c.clone());
        let settings = BoundQpSettings {
            tolerance: 0.0,
            max_products: 3,
        };
        let Ok(outcome) = solve(&mut a, &mut x, &mut g, bound, settings);
        assert!(!outcome.converged);
        assert!(
            outcome.products >= 3 && outcome.products <= 4,
            "{outcome:?}"
        );
        assert!(outcome.projected_gradient > 0.0);
    }
}
