//! The interface Schur complement approximated by two elastic half-spaces: the multiplier block
//! of the coupled Krylov solve's preconditioner (`crate::contact::coupled::coupled_krylov`).
//!
//! The Schur complement `S = D - C K^-1 B` of the coupled system maps the (scaled) multipliers to
//! the (scaled) gaps they open: `(S lambda)_k = t s sum_l (r_k . e_l) c(x_k, x_l) A_l lambda_l`,
//! with `c(x_k, x_l)` the relative displacement of the two bodies at `x_k`, along the row
//! direction `r_k` of multiplier `k`, under a unit force at `x_l` along the column direction
//! `e_l` of multiplier `l` (the facet normal for frictionless contact, an axis for tied, the
//! local normal and tangents at a sticking node; at a slipping node `e = n - mu d` and `r = n`,
//! `crate::contact::law::coulomb`); `t`, `s` the system's scalings
//! (`crate::contact::coupled::system`). Its spectrum spans the ratio of the contact zone to the
//! spacing (the compliance operator is of order -1), so a diagonal approximation leaves iteration
//! counts growing under refinement. The approximation is the same operator for two elastic
//! half-spaces in contact (Boussinesq; Johnson, *Contact Mechanics*, 1985, 3.2 and 2.2), on the
//! active nodes' reference positions:
//!
//! ```text
//! S~_kl = t s c0 (r_k . e_l) G_kl A_l,        1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2
//!   3D: c0 = 1 / (pi E*),   G_kl = 1 / |x_k - x_l|,          G_kk = 2 / a_k,        a_k = (A_k / pi)^(1/2)
//!   2D: c0 = 2 / (pi E*),   G_kl = -ln(|x_k - x_l| / L),     G_kk = 1 - ln(a_k / L), a_k = A_k / 2
//! ```
//!
//! The self terms are the centre displacement under a uniform traction on a disc (3D) or a
//! segment (2D) of the node's area; `L` is twice the diagonal of the active nodes' bounding box
//! plus the largest `a_k` (the 2D half-plane displacement is defined up to a constant; a length
//! well above the zone's keeps the logarithmic kernel positive definite). The tangential
//! (Cerruti) compliance is taken equal to the normal one: within a factor `2(1 - nu)/(2 - nu)`
//! of it. The material factor `c0` matters here, unlike in a preconditioner of `S` alone: the
//! block preconditioner's two diagonal blocks must have the scale of the operator's, so that
//! its eigenvalues cluster at one place and not at two. A finite body is stiffer than a
//! half-space, so `S~` overestimates `S` by a factor of order one, which the Krylov iteration
//! absorbs. Measured 2026-11-28 (the demo's hemisphere on block at 25k DOFs, CG + AMG bodies,
//! two load steps, 5 active-set iterations each way, the same force to 8 digits): V-cycles per
//! body over the whole solve with `c0` as above, and with it multiplied by 0.001, 0.1, 10 and
//! 1000: 189 against 479, 253, 346 and 824.
//!
//! With several contact pairs, `S~` is block diagonal, one such block per pair: one pair's
//! tractions reach another pair's gaps only through the far field of a body they share, a
//! coupling of lower order that the Krylov iteration absorbs. A multiplier that only restates a
//! Dirichlet condition (no column, `D_kk != 0`) keeps its exact block `D_kk`; a coupled one with
//! its own term in its row (a slipping node's direction row, `crate::contact::law::coulomb`) has
//! `D_kk` added to its diagonal of `S~`.
//!
//! `S~^-1` is applied exactly on a small zone (at most [`DENSE_LIMIT`] multipliers: `S~`
//! assembled and LU-factored once per active-set iteration), and beyond it by the two-level
//! approximate inverse of `crate::contact::coupled::two_level_inverse`, which never assembles
//! `S~`: the dense LU takes `2 m^2` numbers and `m^3 / 3` multiply-adds (by the memory model of
//! `docs/parallel.md`, 65 GB per rank at 100M DOFs), the two-level inverse about
//! `m (20 u + 45 dim)` numbers and a coarse factor of `(dim m / 128)^2` (`u` multipliers per
//! node).

use std::collections::HashMap;
use std::ops::Range;

use faer::Mat;
use faer::prelude::*;
use rayon::prelude::*;

use crate::contact::coupled::compliance::MultiplierKey;
use crate::contact::coupled::far_field::{LumpedSums, distance};
use crate::contact::coupled::system::{CoupledSystem, Coupling};
use crate::contact::coupled::two_level_inverse::{FarField, TwoLevelInverse, Unknown};
use crate::contact::geometry::surface::ContactSurface;
use crate::fem::Material;
use crate::linalg::bound_qp::{self, BoundQpOutcome, SymmetricOperator};
use crate::parallel::{ParallelError, Ranks};

/// The half-space approximation of the Schur complement, inverted exactly or approximately.
pub struct HalfSpace {
    /// The pair's coupled multipliers (those with a column), numbered within the pair.
    coupled: Vec<usize>,
    inverse: Inverse,
    /// `D_kk` of every multiplier of the pair (an uncoupled one is solved by it alone).
    diagonal: Vec<f64>,
}

/// How `S~^-1` is applied on the coupled multipliers.
enum Inverse {
    /// Assembled and LU-factored: at most [`DENSE_LIMIT`] multipliers.
    Dense(faer::linalg::solvers::PartialPivLu<f64>),
    /// Above: never assembled, `crate::contact::coupled::two_level_inverse`.
    TwoLevel(Box<TwoLevelInverse<Kernel>>),
}

/// The most coupled multipliers whose `S~` is assembled and factored exactly. Why 1000: above,
/// the two-level inverse is as good a preconditioner and cheaper (the hemisphere on block at
/// 217k and 1M DOFs, up to 1,834 and 2,982 multipliers: the same active sets and V-cycles,
/// forces within 1.5e-9 of the force, and at 1M 124 MB less at the peak; `docs/decisions.md`);
/// below, the exact inverse costs nothing (16 MB, 3e8 multiply-adds) and the small zone leaves
/// few clusters.
pub const DENSE_LIMIT: usize = 1000;

/// `c0` of the module doc: the compliance factor of two half-spaces of `materials` in
/// dimension `dim` (2D: plane strain).
pub fn compliance_factor(materials: [&Material; 2], dim: usize) -> f64 {
    let inverse_e_star: f64 = materials
        .iter()
        .map(|m| (1.0 - m.poisson_ratio().powi(2)) / m.youngs_modulus())
        .sum();
    let per_e_star = inverse_e_star / std::f64::consts::PI;
    if dim == 3 {
        per_e_star
    } else {
        2.0 * per_e_star
    }
}

impl HalfSpace {
    /// `S~` on the multipliers of pair `pair` of `system`, whose `coupling` has its active
    /// primary nodes at its `points`, with the compliance factor `c0` ([`compliance_factor`]).
    /// It acts on the pair's multipliers alone (numbered from 0): the pairs' blocks of the
    /// preconditioner are independent.
    pub fn new(
        system: &CoupledSystem,
        pair: usize,
        coupling: &Coupling,
        dim: usize,
        c0: f64,
    ) -> Self {
        // Each active node's place in the coupling, for its area and point.
        let place: HashMap<usize, usize> = (coupling.primary_nodes.iter().copied())
            .enumerate()
            .map(|(i, node)| (node, i))
            .collect();
        let multipliers = system.pair_multipliers(pair);
        let diagonal = system.d[multipliers.clone()].to_vec();
        // Node, direction and area of each coupled multiplier (its column of B combines the
        // components of one node's traction).
        let mut coupled = Vec::new();
        let mut owners = Vec::new();
        let mut points = Vec::new();
        for (k, column) in system.columns[multipliers].iter().enumerate() {
            let Some((key, _)) = column.first() else {
                continue;
            };
            let MultiplierKey::Traction { node, .. } = *key else {
                continue;
            };
            let mut e = [0.0; 3];
            for (key, weight) in column {
                if let MultiplierKey::Traction { component, .. } = *key {
                    e[component] = *weight;
                }
            }
            let row = system.rows[system.pair_multipliers(pair).start + k];
            let (mut x, mut a) = ([0.0; 3], 0.0);
            if let Some(&i) = place.get(&node) {
                x[..dim].copy_from_slice(&coupling.points[i][..dim]);
                a = coupling.areas1[i];
            }
            coupled.push(k);
            owners.push(node);
            points.push((x, row, e, a));
        }
        let kernel = Kernel::new(dim, points.iter().map(|(x, _, _, a)| (*x, *a)));
        let scale = system.t * system.s * c0;
        let entry = |i: usize, j: usize| {
            // Row i's direction against column j's: the same vector but at a slipping node.
            let ((xi, ei, _, ai), (xj, _, ej, aj)) = (&points[i], &points[j]);
            // A multiplier's own term in its row (`D_kk`, a slipping node's direction row).
            let own = if i == j { diagonal[coupled[i]] } else { 0.0 };
            let along: f64 = (0..3).map(|c| ei[c] * ej[c]).sum();
            if along == 0.0 {
                return own;
            }
            let r = distance(xi, xj);
            // Distinct nodes of a mesh never coincide; the same node's components have
            // orthogonal directions, so only the self term is left.
            let g = if i == j || r == 0.0 {
                kernel.own(*ai)
            } else {
                kernel.between(r)
            };
            own + scale * along * g * aj
        };
        let inverse = if points.len() <= DENSE_LIMIT {
            Inverse::Dense(Mat::<f64>::from_fn(points.len(), points.len(), entry).partial_piv_lu())
        } else {
            // The multipliers of one node share its point.
            let mut nodes: Vec<[f64; 3]> = Vec::new();
            let mut node_of: HashMap<usize, usize> = HashMap::new();
            let unknowns: Vec<Unknown> = (points.iter().zip(&owners))
                .map(|((x, r, e, a), owner)| {
                    let node = *node_of.entry(*owner).or_insert_with(|| {
                        nodes.push(*x);
                        nodes.len() - 1
                    });
                    // S~_kl = (t s c0 r_k) . (A_l e_l) G_kl between distinct nodes.
                    Unknown {
                        node,
                        direction: *e,
                        reads: r.map(|v| scale * v),
                        loads: e.map(|v| a * v),
                    }
                })
                .collect();
            Inverse::TwoLevel(Box::new(TwoLevelInverse::new(
                &nodes, &unknowns, dim, entry, kernel,
            )))
        };
        Self {
            coupled,
            inverse,
            diagonal,
        }
    }

    /// `out = S~^-1 v` on every multiplier of the pair.
    pub fn apply(&self, v: &[f64], out: &mut [f64]) {
        for ((o, x), d) in out.iter_mut().zip(v).zip(&self.diagonal) {
            *o = if *d != 0.0 { x / d } else { 0.0 };
        }
        if self.coupled.is_empty() {
            return;
        }
        let rhs: Vec<f64> = self.coupled.iter().map(|&k| v[k]).collect();
        let solution = match &self.inverse {
            Inverse::Dense(lu) => {
                let mut x = Mat::<f64>::from_fn(rhs.len(), 1, |i, _| rhs[i]);
                lu.solve_in_place(x.as_mut());
                (0..rhs.len()).map(|i| x[(i, 0)]).collect()
            }
            Inverse::TwoLevel(inverse) => {
                let mut x = vec![0.0; rhs.len()];
                inverse.apply(&rhs, &mut x);
                x
            }
        };
        for (&k, x) in self.coupled.iter().zip(solution) {
            out[k] = x;
        }
    }
}

/// The half-space kernel `G` of the module doc on a set of surface points: `L` from their
/// bounding box and areas.
#[derive(Clone, Copy)]
struct Kernel {
    dim: usize,
    length: f64,
}

impl Kernel {
    /// The kernel of the points `(x, area)` in dimension `dim`.
    fn new(dim: usize, points: impl Iterator<Item = ([f64; 3], f64)>) -> Self {
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        let mut largest = 0.0_f64;
        for (x, a) in points {
            for c in 0..dim {
                lo[c] = lo[c].min(x[c]);
                hi[c] = hi[c].max(x[c]);
            }
            largest = largest.max(radius(dim, a));
        }
        let diagonal = (0..dim)
            .map(|c| (hi[c] - lo[c]).powi(2))
            .sum::<f64>()
            .sqrt();
        Self {
            dim,
            length: 2.0 * diagonal + largest,
        }
    }

    /// `G` between two distinct points `r` apart.
    fn between(&self, r: f64) -> f64 {
        if self.dim == 3 {
            1.0 / r
        } else {
            -(r / self.length).ln()
        }
    }

    /// `dG / dr` at a distance `r`.
    fn slope(&self, r: f64) -> f64 {
        if self.dim == 3 {
            -1.0 / (r * r)
        } else {
            -1.0 / r
        }
    }

    /// `G` of a point on itself: a uniformly loaded disc (segment) of `area`.
    fn own(&self, area: f64) -> f64 {
        let a = radius(self.dim, area);
        if self.dim == 3 {
            2.0 / a
        } else {
            1.0 - (a / self.length).ln()
        }
    }
}

impl FarField for Kernel {
    /// `G(|x - y|)` and its gradient in `y`, `-G'(r) (x - y) / r`.
    fn field(&self, x: &[f64; 3], y: &[f64; 3]) -> (f64, [f64; 3]) {
        let r = distance(x, y);
        let slope = self.slope(r);
        (
            self.between(r),
            std::array::from_fn(|c| -slope * (x[c] - y[c]) / r),
        )
    }
}

/// The radius of a disc (3D) or half-width of a segment (2D) of `area`.
fn radius(dim: usize, area: f64) -> f64 {
    match dim {
        3 => (area / std::f64::consts::PI).sqrt(),
        _ => area / 2.0,
    }
}

/// The active set the half-space model predicts from an iterate: the nodes in compression at
/// the solution of the contact problem of two elastic half-spaces whose gaps are the iterate's
/// and whose pressures start from the iterate's,
///
/// ```text
/// p >= 0,   g + C (p - p0) >= 0,   p . (g + C (p - p0)) = 0,   C_ij = c0 G_ij A_j
/// ```
///
/// on the `candidates` (surface indices of the primary surface `surface`; `gaps` over every
/// primary candidate, `p0` the iterate's pressure of each candidate, positive in compression),
/// with `G` and `c0` of the module doc, widened by the candidates the model leaves within
/// [`PREDICTION_MARGIN`] of a spacing of touching. Solved by MPRGP ([`model_contact`]), at most
/// [`PREDICTION_PRODUCTS`] products: the result is only where the next active-set iteration
/// starts, which the loop then corrects like any other.
///
/// Why: the first iterate of a solve started cold has every overlapping node penetrating, about
/// twice the contact zone for a Hertz contact (the overlap's radius is `sqrt(2)` times the
/// contact radius), and the primal-dual update then removes one rim of nodes per iteration. The
/// half-space model spreads the contact pressure over the zone at once.
///
/// Returns the set with how the model's solve ended. Collective in a distributed run (the
/// ranks share each product, [`Compliance`]); its error is that of a sum over the ranks.
pub fn predicted_set(
    surface: &ContactSurface,
    candidates: &[usize],
    gaps: &[f64],
    p0: &[f64],
    c0: f64,
) -> Result<(Vec<usize>, BoundQpOutcome), ParallelError> {
    let (p, r, outcome) = half_space_contact(surface, candidates, gaps, p0, c0)?;
    let set = (0..candidates.len())
        .filter(|&i| p[i] > 0.0 || r[i] < PREDICTION_MARGIN * surface.spacing[candidates[i]])
        .map(|i| candidates[i])
        .collect();
    Ok((set, outcome))
}

/// The active set the half-space model predicts for a body held only by its contact and
/// pressed onto it by a total normal force `force`: [`predicted_set`]'s model from no pressure,
/// with the gaps `gaps - delta` of a rigid approach `delta` found such that the pressures carry
/// the force, `sum A_i p_i = force`. The force grows with `delta` (more overlap, more
/// pressure), so `delta` is bracketed by doubling from the first touch and then found by the
/// Illinois variant of regula falsi to [`FORCE_TOLERANCE`] of the force.
///
/// Why: a force-controlled body has no approach of its own until its contact carries the
/// force. Started from the nodes that touch (the pole of a sphere), the first iterate
/// concentrates the whole force on them: in 3D a point load sinks the body several times its
/// final approach (an R/67 hemisphere on a block, 3 times), and the linearized gaps at that
/// iterate leave the loop unstable. Started from this set, the first iterate is about the
/// answer (see `tests/force_control.rs`). Collective in a distributed run, as
/// [`predicted_set`] is.
pub fn force_controlled_set(
    surface: &ContactSurface,
    gaps: &[f64],
    force: f64,
    c0: f64,
) -> Result<Vec<usize>, ParallelError> {
    let no_pressure = vec![0.0; surface.len()];
    let first_touch = gaps.iter().copied().fold(f64::INFINITY, f64::min);
    let spacing = surface
        .spacing
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    // NaN-safe: a force or spacing that is not a positive number predicts nothing.
    if force.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
        || !first_touch.is_finite()
        || spacing.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
    {
        return Ok(Vec::new());
    }
    // The model's pressures at the approach `delta`: only candidates that overlap can carry
    // any (the compliance only opens gaps), so the others are left out.
    let solve = |delta: f64| {
        let candidates: Vec<usize> = (0..surface.len()).filter(|&i| gaps[i] < delta).collect();
        let shifted: Vec<f64> = gaps.iter().map(|g| g - delta).collect();
        let (p, r, _) = half_space_contact(surface, &candidates, &shifted, &no_pressure, c0)?;
        let carried: f64 = (candidates.iter().zip(&p))
            .map(|(&i, p)| surface.nodal_area[i] * p)
            .sum();
        Ok::<_, ParallelError>((candidates, p, r, carried))
    };
    let (mut low, mut high) = (first_touch, first_touch + spacing);
    let (mut f_low, mut f_high) = (-force, solve(high)?.3 - force);
    let mut doublings = 0;
    while f_high < 0.0 && doublings < FORCE_BRACKETING {
        (low, f_low) = (high, f_high);
        high = first_touch + 2.0 * (high - first_touch);
        f_high = solve(high)?.3 - force;
        doublings += 1;
    }
    // Regula falsi keeping the bracket [low, high]; `high` carries at least the force, and
    // is the answer (the prediction errs on the large side, as `PREDICTION_MARGIN` says).
    let mut side = 0;
    let steps = if f_high <= FORCE_TOLERANCE * force {
        0
    } else {
        FORCE_STEPS
    };
    for _ in 0..steps {
        let delta = (low * f_high - high * f_low) / (f_high - f_low);
        let f = solve(delta)?.3 - force;
        if f.abs() <= FORCE_TOLERANCE * force {
            high = delta;
            break;
        }
        if f > 0.0 {
            (high, f_high) = (delta, f);
            if side == 1 {
                f_low /= 2.0;
            }
            side = 1;
        } else {
            (low, f_low) = (delta, f);
            if side == -1 {
                f_high /= 2.0;
            }
            side = -1;
        }
    }
    let (candidates, p, r, _) = solve(high)?;
    Ok((0..candidates.len())
        .filter(|&i| p[i] > 0.0 || r[i] < PREDICTION_MARGIN * surface.spacing[candidates[i]])
        .map(|i| candidates[i])
        .collect())
}

/// [`force_controlled_set`] finds the force to this fraction.
const FORCE_TOLERANCE: f64 = 1e-3;

/// [`force_controlled_set`] doubles the approach at most this many times to bracket the force.
const FORCE_BRACKETING: usize = 40;

/// [`force_controlled_set`]'s regula falsi steps at most.
const FORCE_STEPS: usize = 60;

/// The pressures `p` and model gaps `r` of the half-space contact problem of
/// [`predicted_set`] on `candidates`: `C` assembled on at most [`DENSE_LIMIT`] candidates, its
/// far part lumped beyond (`crate::contact::coupled::far_field`: `m^2` numbers are 200 MB at
/// 5,000 candidates, 65 GB at 90,000).
fn half_space_contact(
    surface: &ContactSurface,
    candidates: &[usize],
    gaps: &[f64],
    p0: &[f64],
    c0: f64,
) -> Result<(Vec<f64>, Vec<f64>, BoundQpOutcome), ParallelError> {
    let points: Vec<[f64; 3]> = candidates.iter().map(|&i| surface.coords[i]).collect();
    let areas: Vec<f64> = candidates.iter().map(|&i| surface.nodal_area[i]).collect();
    let p: Vec<f64> = candidates.iter().map(|&i| p0[i].max(0.0)).collect();
    let shifts: Vec<f64> = (candidates.iter().zip(&p))
        .map(|(&i, p)| p - p0[i])
        .collect();
    let gaps: Vec<f64> = candidates.iter().map(|&i| gaps[i]).collect();
    let zone = ModelZone {
        points: &points,
        areas: &areas,
        dim: surface.dim,
    };
    let lumped = candidates.len() > DENSE_LIMIT;
    model_contact(&zone, gaps, p, &shifts, c0, lumped)
}

/// The points of a half-space model: where they are, their areas, in `dim` dimensions.
struct ModelZone<'a> {
    points: &'a [[f64; 3]],
    areas: &'a [f64],
    dim: usize,
}

/// The pressures `p` and model gaps `r` of the half-space contact problem on `zone` with the
/// gaps `gaps` at the pressures `p - shifts`, from the pressures `p`: `C` assembled, or its far
/// part `lumped`; and how the solve ended.
///
/// In the area-weighted pressures `x = A p` the problem is symmetric, `r = q + c0 G x` with
/// `q` constant, the complementarity conditions of `min 1/2 x^T c0 G x + q^T x` over `x >= 0`,
/// solved by MPRGP (`crate::linalg::bound_qp`) until no model gap of a free node and no
/// negative one of a bound node exceeds [`PREDICTION_TOLERANCE`] of the largest starting gap,
/// at most [`PREDICTION_PRODUCTS`] products with `G`. Why not projected Gauss-Seidel (used
/// until 2026-12-06): its error falls by a constant factor a sweep set by `G`'s condition number
/// rather than its square root, 0.96 on the hemisphere on block at 217k DOFs (151 sweeps, 1.25 s,
/// to the tolerance) and short of it after its 200 sweeps at 1M (5,309 candidates, 6.1 s), and
/// each sweep is sequential; MPRGP's products run on every thread.
fn model_contact(
    zone: &ModelZone,
    gaps: Vec<f64>,
    p: Vec<f64>,
    shifts: &[f64],
    c0: f64,
    lumped: bool,
) -> Result<(Vec<f64>, Vec<f64>, BoundQpOutcome), ParallelError> {
    let (points, areas) = (zone.points, zone.areas);
    let m = points.len();
    let kernel = Kernel::new(zone.dim, points.iter().copied().zip(areas.iter().copied()));
    let kernel = match lumped {
        true => CompliancePart::Lumped {
            points,
            areas,
            kernel,
            sums: LumpedSums::new(points, areas, zone.dim),
        },
        false => CompliancePart::assembled(points, areas, &kernel, ranks_rows(m)),
    };
    let mut compliance = Compliance { kernel, c0 };
    // The gaps at the starting pressures: r = gaps + c0 G A shifts.
    let mut r = gaps;
    let weighted_shifts: Vec<f64> = areas.iter().zip(shifts).map(|(a, s)| a * s).collect();
    let mut product = vec![0.0; m];
    if weighted_shifts.iter().any(|&w| w != 0.0) {
        compliance.apply(&weighted_shifts, &mut product)?;
        r.iter_mut().zip(&product).for_each(|(r, c)| *r += c);
    }
    // G has positive entries, so its largest row sum bounds its norm.
    compliance.apply(&vec![1.0; m], &mut product)?;
    let norm_bound = product.iter().copied().fold(0.0, f64::max);
    let scale = r.iter().map(|r| r.abs()).fold(0.0, f64::max);
    let mut x: Vec<f64> = areas.iter().zip(&p).map(|(a, p)| a * p).collect();
    let settings = bound_qp::BoundQpSettings {
        tolerance: PREDICTION_TOLERANCE * scale,
        max_products: PREDICTION_PRODUCTS,
    };
    let outcome = bound_qp::solve(&mut compliance, &mut x, &mut r, norm_bound, settings)?;
    let p = (x.iter().zip(areas))
        .map(|(x, &a)| if a > 0.0 { x / a } else { 0.0 })
        .collect();
    Ok((p, r, outcome))
}

/// `c0 G` on a zone's points, as MPRGP multiplies by it. In a distributed run every rank
/// holds the same model (the same gaps and pressures, from the same gathered numbers), so each
/// computes its share of a product's rows ([`ranks_rows`]) and receives the others'
/// (`MPI_Allgatherv`): a row is summed in the same order wherever it is computed, so a product
/// is the same bits on any number of ranks, and the model's answer too.
struct Compliance<'a> {
    kernel: CompliancePart<'a>,
    c0: f64,
}

/// `G`, or what a product with it needs.
enum CompliancePart<'a> {
    /// Assembled: this rank's rows of it ([`ranks_rows`]; all of them on one process), row by
    /// row.
    Assembled { kernel: Vec<f64> },
    /// Never assembled: each product summed afresh with the zone's far part lumped into
    /// clusters (`crate::contact::coupled::far_field`).
    Lumped {
        points: &'a [[f64; 3]],
        areas: &'a [f64],
        kernel: Kernel,
        sums: LumpedSums,
    },
}

impl CompliancePart<'_> {
    /// The `rows` of `G` on the points `x` of `areas`.
    fn assembled(x: &[[f64; 3]], areas: &[f64], kernel: &Kernel, rows: Range<usize>) -> Self {
        let m = x.len();
        let g = |i: usize, j: usize| match i == j {
            true => kernel.own(areas[i]),
            false => kernel.between(distance(&x[i], &x[j])),
        };
        let kernel = rows.flat_map(|i| (0..m).map(move |j| g(i, j))).collect();
        Self::Assembled { kernel }
    }
}

/// This rank's share of `m` rows ([`rows_of_rank`]).
fn ranks_rows(m: usize) -> Range<usize> {
    let Ranks { rank, size } = crate::parallel::ranks();
    rows_of_rank(m, rank, size)
}

/// Rank `rank`'s share of `m` rows among `size` ranks: `m / size` rows each, the first
/// `m % size` ranks one more, in rank order.
fn rows_of_rank(m: usize, rank: usize, size: usize) -> Range<usize> {
    let (share, extra) = (m / size, m % size);
    let start = rank * share + rank.min(extra);
    start..start + share + usize::from(rank < extra)
}

impl SymmetricOperator for Compliance<'_> {
    type Error = ParallelError;

    fn apply(&mut self, x: &[f64], out: &mut [f64]) -> Result<(), ParallelError> {
        let (m, c0) = (x.len(), self.c0);
        let rows = ranks_rows(m);
        let mut local = vec![0.0; rows.len()];
        match &mut self.kernel {
            CompliancePart::Assembled { kernel } => {
                (local.par_iter_mut().enumerate()).for_each(|(k, o)| {
                    let row = &kernel[k * m..(k + 1) * m];
                    *o = c0 * row.iter().zip(x).map(|(g, x)| g * x).sum::<f64>();
                });
            }
            CompliancePart::Lumped {
                points,
                areas,
                kernel,
                sums,
            } => {
                sums.clear();
                for (j, &w) in x.iter().enumerate() {
                    sums.add(j, w);
                }
                let (points, areas, kernel, sums) = (*points, *areas, *kernel, &*sums);
                let start = rows.start;
                (local.par_iter_mut().enumerate()).for_each(|(k, o)| {
                    *o = c0
                        * sums.sum(
                            start + k,
                            x,
                            |i| kernel.own(areas[i]),
                            |i, j| kernel.between(distance(&points[i], &points[j])),
                            |i, centre| kernel.field(&points[i], centre),
                        );
                });
            }
        }
        if !crate::parallel::distributed() {
            out.copy_from_slice(&local);
            return Ok(());
        }
        let size = crate::parallel::ranks().size;
        let counts: Vec<usize> = (0..size).map(|r| rows_of_rank(m, r, size).len()).collect();
        out.copy_from_slice(&crate::parallel::all_gather(&local, &counts)?);
        Ok(())
    }
}

/// [`predicted_set`] also keeps the candidates whose model gap is below this fraction of their
/// spacing. Why: the prediction should err on the large side, so that the loop approaches the
/// contact zone from above, removing nodes in tension (to `tension_tolerance`, 1e-8 of the
/// largest pressure) rather than adding nodes that penetrate (beyond `penetration_tolerance`,
/// 1e-3 of a spacing): it then ends on the set the primal-dual update alone ends on. Measured on
/// the hemisphere on block at 99k DOFs (2026-11-28): with no margin the loop ended on 553 nodes
/// instead of 558 (force 1.4e-5 lower), with 0.01 on 557, with 0.05 on the same 558 nodes and
/// force to 1e-9 as without a prediction, in 5 iterations instead of 8 and 91 V-cycles per body
/// instead of 143; 0.2 took 7 iterations. 0.01 took 4 iterations in one step and 4 + 4 instead
/// of 5 + 6 in two load steps, but ended on 557 nodes in one step, and its load steps then
/// differed from independent solves by twice the settled gap tolerance
/// (`tests/contact_load_steps.rs`): a margin that reproduces the loop's answer is worth an
/// iteration or two.
const PREDICTION_MARGIN: f64 = 0.05;

/// Products with `G` of [`predicted_set`]'s model at most (each `m^2` multiply-adds, or the
/// lumped sums'): the model's answer is only where the loop starts.
const PREDICTION_PRODUCTS: usize = 200;

/// [`predicted_set`]'s model is solved when no node's model gap is off its complementarity
/// condition by more than this fraction of the largest starting gap.
const PREDICTION_TOLERANCE: f64 = 1e-4;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::Material;

    /// The model's pressures and predicted set.
    type Prediction = (Vec<f64>, Vec<usize>);

    /// A sphere of radius 1 pressed by `approach` into a flat, both of `E = 1000`, `nu = 0.3`,
    /// on a jittered grid of spacing `h` over a disc twice the Hertz radius: the model's
    /// prediction, assembled and lumped, with the zone, the Hertz radius and force.
    fn hertz(h: f64, approach: f64) -> (ModelZone<'static>, [Prediction; 2], f64, f64) {
        let material = Material::new(1000.0, 0.3).unwrap();
        let c0 = compliance_factor([&material, &material], 3);
        let e_star = 1.0 / (std::f64::consts::PI * c0);
        let a = approach.sqrt();
        let n = (2.0 * a / h).ceil() as i64;
        let mut points = Vec::new();
        for i in -n..=n {
            for j in -n..=n {
                let jitter = ((i * 7919 + j * 104_729).rem_euclid(97) as f64 / 97.0 - 0.5) * 0.2;
                let x = [(i as f64 + jitter) * h, (j as f64 - jitter) * h, 0.0];
                if x[0].hypot(x[1]) <= 2.0 * a {
                    points.push(x);
                }
            }
        }
        let m = points.len();
        let areas = vec![h * h; m];
        let gaps: Vec<f64> = (points.iter())
            .map(|x| (x[0] * x[0] + x[1] * x[1]) / 2.0 - approach)
            .collect();
        let zone = ModelZone {
            points: points.leak(),
            areas: areas.leak(),
            dim: 3,
        };
        let solve = |lumped| {
            let (p, r, outcome) =
                model_contact(&zone, gaps.clone(), vec![0.0; m], &vec![0.0; m], c0, lumped)
                    .expect("one process sums alone");
            assert!(outcome.converged, "{outcome:?}");
            // predicted_set's rule.
            let set = (0..m)
                .filter(|&i| p[i] > 0.0 || r[i] < PREDICTION_MARGIN * h)
                .collect();
            (p, set)
        };
        let pressures = [solve(false), solve(true)];
        let force = 4.0 * e_star * a.powi(3) / 3.0;
        (zone, pressures, a, force)
    }

    #[test]
    fn the_ranks_rows_cover_every_row_once_in_order() {
        for (m, size) in [(0, 1), (7, 1), (7, 2), (7, 3), (2, 4), (1000, 7)] {
            let rows: Vec<usize> = (0..size).flat_map(|r| rows_of_rank(m, r, size)).collect();
            assert_eq!(rows, (0..m).collect::<Vec<_>>(), "{m} rows on {size} ranks");
            let lengths: Vec<usize> = (0..size).map(|r| rows_of_rank(m, r, size).len()).collect();
            let (least, most) = (lengths.iter().min(), lengths.iter().max());
            assert!(most.unwrap() - least.unwrap() <= 1, "{lengths:?}");
        }
    }

    #[test]
    fn the_lumped_model_gives_the_hertz_contact_of_the_assembled_one() {
        for (h, approach) in [(0.004, 0.01), (0.003, 0.004)] {
            let (zone, [(dense, dense_set), (lumped, lumped_set)], a, force) = hertz(h, approach);
            let m = zone.points.len();
            for (name, p) in [("assembled", &dense), ("lumped", &lumped)] {
                // Against Hertz (an exact solution of the continuous model): the force, and the
                // zone's radius to within a spacing.
                let carried: f64 = p.iter().zip(zone.areas).map(|(p, a)| p * a).sum();
                let radius = (zone.points.iter().zip(p.iter()))
                    .filter(|(_, p)| **p > 0.0)
                    .map(|(x, _)| x[0].hypot(x[1]))
                    .fold(0.0, f64::max);
                eprintln!(
                    "h {h}, m {m}, {name}: force {:+.4} from Hertz, radius {:+.2} spacings",
                    carried / force - 1.0,
                    (radius - a) / h
                );
                assert!(
                    (carried / force - 1.0).abs() < 0.01,
                    "{name}: force {carried} against {force}"
                );
                assert!(
                    (radius - a).abs() < h,
                    "{name}: radius {radius} against {a}"
                );
            }
            // The predicted sets: the same but for a few nodes of the rim (about 2 pi a / h).
            let differ = (dense_set.iter())
                .filter(|i| !lumped_set.contains(i))
                .chain(lumped_set.iter().filter(|i| !dense_set.contains(i)))
                .count();
            let rim = 2.0 * std::f64::consts::PI * a / h;
            eprintln!(
                "h {h}: predicted sets of {} and {} nodes, {differ} differ (rim {rim:.0})",
                dense_set.len(),
                lumped_set.len()
            );
            assert!((differ as f64) < 0.05 * rim, "{differ} nodes differ");
        }
    }
}
