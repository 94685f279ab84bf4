//! A two-level approximate inverse of a dense operator with the structure of a boundary
//! integral: the half-space compliance `S~` of `crate::contact::coupled::half_space` on a
//! contact zone too large to keep it dense and factored (`m^2` numbers twice: at 90,000
//! multipliers, 130 GB).
//!
//! `S~` is of order -1: a smooth, slowly decaying kernel (`1/r` in 3D, `-ln r` in 2D). Its
//! inverse, the zone's contact stiffness, is of order +1 and quasi-local (a hypersingular kernel,
//! decaying like `1/r^3` in 3D and `1/r^2` in 2D): its action on the oscillating part of a
//! vector is held by each node's few neighbours. What a local pattern misses is the smooth part
//! over the whole zone, which a few unknowns per cluster of nodes hold. Hence two levels, the
//! coarse one first and the fine one on what it leaves:
//!
//! ```text
//! M^-1 r = V y + F (r - (S~ V) y),        y = (V^T S~ V)^-1 V^T r
//! ```
//!
//! - **coarse**: `V` has, per cluster of at most [`CLUSTER_NODES`] nodes (recursive coordinate
//!   bisection, `crate::contact::coupled::far_field::clusters`), the uniform tractions along the
//!   axes projected on each unknown's column direction, orthonormalized within the cluster;
//!   `V^T S~ V` is dense and LU-factored, and `S~ V` (`m` rows, `dim` columns per cluster at
//!   most) is kept;
//! - **fine**: `F` is a sparse approximate right inverse with a fixed pattern (Grote and Huckle,
//!   *SIAM J. Sci. Comput.* 18, 1997): its column `i` is supported on the unknowns of the
//!   [`PATTERN_NODES`] nodes nearest to `i`'s node and minimizes `|S~ f_i - e_i|` over the rows of
//!   the [`SHADOW_NODES`] nearest (one least-squares problem per node, which its unknowns share).
//!
//! Memory: `m (PATTERN_NODES u + n0)` numbers (`u` unknowns per node, `n0` coarse unknowns, at
//! most `dim m / 128` in 3D), against `2 m^2` for the dense LU. `S~` itself is never stored:
//! `S~ V` and `V^T S~ V` are summed entry by entry (`m^2` evaluations of the kernel). Measured on
//! a disc of points with the 3D kernel (GMRES on `S~ x = b` right-preconditioned by `M`, to
//! `1e-10`): 9 iterations at 1,000, 4,000 and 9,000 unknowns with clusters of about 140 nodes;
//! the fine level alone took 12, 16 and 20 (the smooth part it misses grows with the zone), the
//! two levels added instead of applied in turn 20 to 24. The test below checks the same on the
//! half-space operator in 2D and 3D.

use std::num::NonZeroUsize;

use faer::Mat;
use faer::prelude::*;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::DMatrix;
use rayon::prelude::*;

use crate::contact::coupled::far_field::clusters;

/// Nodes whose unknowns carry a column of the fine level's `F`. Why 20: on the disc above, 20
/// took 9 iterations with the coarse level, 40 took 8 to 9 at twice the memory.
pub const PATTERN_NODES: usize = 20;

/// Nodes whose rows each column of `F` is fitted on: three times the pattern, so that the
/// least-squares problem sees the response around its support and not only on it.
pub const SHADOW_NODES: usize = 60;

/// Nodes per cluster of the coarse level, at most, in 3D and in 2D. Why: on the disc of 9,000
/// points, clusters of 140 nodes took 9 iterations, of 290 12, of 570 14 (the coarse level
/// resolves the smooth part to the scale of a cluster); on a 2D zone of 800 nodes, clusters of
/// 128 took 16, of 32 11 (a line's 20 nearest nodes reach less far than a surface's, and the
/// logarithmic kernel's smooth part is larger). 2D zones are small: at 4,000 nodes, `S~ V`
/// then holds 0.5M numbers.
pub const CLUSTER_NODES: [usize; 2] = [128, 32];

/// The two-level approximate inverse of the module doc.
pub struct TwoLevelInverse {
    /// Coarse basis: for each unknown, its coarse columns and weights (the columns of its
    /// cluster).
    basis: Vec<Vec<(usize, f64)>>,
    /// `S~ V`, row-major, `n0` columns.
    product: Vec<f64>,
    coarse: faer::linalg::solvers::PartialPivLu<f64>,
    n0: usize,
    /// Column `i` of `F`.
    fine: Vec<FineColumn>,
}

/// An unknown of the operator: where it acts and along which direction its column loads.
#[derive(Debug, Clone, Copy)]
pub struct Unknown {
    /// Index of its node (unknowns of one node share it), from 0.
    pub node: usize,
    /// Its column's direction (a unit traction's), for the coarse basis.
    pub direction: [f64; 3],
}

impl TwoLevelInverse {
    /// The approximate inverse of the `m x m` operator `entry(i, j)` on `unknowns` (`m` of
    /// them), whose nodes are at `nodes` (in `dim` dimensions; distinct, finite).
    ///
    /// # Panics
    /// If an unknown names a node that is not in `nodes`.
    pub fn new(
        nodes: &[[f64; 3]],
        unknowns: &[Unknown],
        dim: usize,
        entry: impl Fn(usize, usize) -> f64 + Sync,
    ) -> Self {
        let m = unknowns.len();
        let mut of_node = vec![Vec::new(); nodes.len()];
        for (k, unknown) in unknowns.iter().enumerate() {
            of_node[unknown.node].push(k);
        }
        let (basis, n0) = coarse_basis(nodes, &of_node, unknowns, dim);
        // S~ V, a row at a time: every entry of S~ once.
        let product: Vec<f64> = (0..m)
            .into_par_iter()
            .flat_map_iter(|i| {
                let mut row = vec![0.0; n0];
                for (j, columns) in basis.iter().enumerate() {
                    let a = entry(i, j);
                    for &(c, v) in columns {
                        row[c] += a * v;
                    }
                }
                row
            })
            .collect();
        let mut coarse = Mat::<f64>::zeros(n0, n0);
        for (i, columns) in basis.iter().enumerate() {
            for &(a, v) in columns {
                for b in 0..n0 {
                    coarse[(a, b)] += v * product[i * n0 + b];
                }
            }
        }
        let fine = fine_level(nodes, &of_node, m, &entry);
        Self {
            basis,
            product,
            coarse: coarse.partial_piv_lu(),
            n0,
            fine,
        }
    }

    /// `out = M^-1 r`.
    pub fn apply(&self, r: &[f64], out: &mut [f64]) {
        let n0 = self.n0;
        let mut y = Mat::<f64>::zeros(n0, 1);
        for (columns, ri) in self.basis.iter().zip(r) {
            for &(c, v) in columns {
                y[(c, 0)] += v * ri;
            }
        }
        self.coarse.solve_in_place(y.as_mut());
        out.fill(0.0);
        for (i, columns) in self.basis.iter().enumerate() {
            // The coarse correction, and the residual it leaves in this row.
            let v_y: f64 = columns.iter().map(|&(c, v)| v * y[(c, 0)]).sum();
            out[i] += v_y;
            let s_v_y: f64 = (0..n0).map(|c| self.product[i * n0 + c] * y[(c, 0)]).sum();
            let residual = r[i] - s_v_y;
            let (rows, values) = &self.fine[i];
            for (&row, value) in rows.iter().zip(values) {
                out[row] += value * residual;
            }
        }
    }
}

/// The coarse basis `V` of the module doc: per cluster of at most [`CLUSTER_NODES`] nodes, the
/// unknowns' directions' components along each axis, orthonormalized by modified Gram-Schmidt
/// (a component that the others span, to `1e-3` of its own size, is dropped: on a flat zone the
/// tangential components of normal directions are zero). Returns each unknown's coarse columns
/// and the number of columns.
fn coarse_basis(
    nodes: &[[f64; 3]],
    of_node: &[Vec<usize>],
    unknowns: &[Unknown],
    dim: usize,
) -> (Vec<Vec<(usize, f64)>>, usize) {
    let most = if dim == 3 {
        CLUSTER_NODES[0]
    } else {
        CLUSTER_NODES[1]
    };
    let mut basis = vec![Vec::new(); unknowns.len()];
    let mut n0 = 0;
    for cluster in clusters(nodes, dim, most) {
        let members: Vec<usize> = (cluster.iter())
            .flat_map(|&node| of_node[node].iter().copied())
            .collect();
        let mut kept: Vec<Vec<f64>> = Vec::new();
        for axis in 0..dim {
            let mut v: Vec<f64> = (members.iter())
                .map(|&k| unknowns[k].direction[axis])
                .collect();
            let size = norm(&v);
            for w in &kept {
                let along: f64 = v.iter().zip(w).map(|(a, b)| a * b).sum();
                v.iter_mut().zip(w).for_each(|(a, b)| *a -= along * b);
            }
            let left = norm(&v);
            if size == 0.0 || left <= 1e-3 * size {
                continue;
            }
            v.iter_mut().for_each(|a| *a /= left);
            kept.push(v);
        }
        for w in kept {
            for (&k, &value) in members.iter().zip(&w) {
                if value != 0.0 {
                    basis[k].push((n0, value));
                }
            }
            n0 += 1;
        }
    }
    (basis, n0)
}

/// A column of the fine level's `F`: its rows and values.
type FineColumn = (Vec<usize>, Vec<f64>);

/// The columns of the fine level's `F`, unknown by unknown.
fn fine_level(
    nodes: &[[f64; 3]],
    of_node: &[Vec<usize>],
    m: usize,
    entry: &(impl Fn(usize, usize) -> f64 + Sync),
) -> Vec<FineColumn> {
    let tree = ImmutableKdTree::<f64, 3>::new_from_slice(nodes)
        .expect("a k-d tree of finite, distinct contact nodes");
    let nearest = |node: usize, count: usize| -> Vec<usize> {
        let count = NonZeroUsize::new(count.min(nodes.len())).unwrap_or(NonZeroUsize::MIN);
        let hits = tree
            .query(&nodes[node])
            .nearest_n::<SquaredEuclidean<f64>>(count)
            .execute();
        hits.iter().map(|hit| hit.item as usize).collect()
    };
    let per_node: Vec<Vec<(usize, FineColumn)>> = (0..nodes.len())
        .into_par_iter()
        .map(|node| {
            let own = &of_node[node];
            if own.is_empty() {
                return Vec::new();
            }
            // The support's nodes first, so that the fitted rows hold the support's.
            let support_nodes = nearest(node, PATTERN_NODES);
            let mut fit_nodes = support_nodes.clone();
            for other in nearest(node, SHADOW_NODES) {
                if !fit_nodes.contains(&other) {
                    fit_nodes.push(other);
                }
            }
            let unknowns_of = |list: &[usize]| -> Vec<usize> {
                (list.iter())
                    .flat_map(|&n| of_node[n].iter().copied())
                    .collect()
            };
            let (support, fitted) = (unknowns_of(&support_nodes), unknowns_of(&fit_nodes));
            let a = DMatrix::from_fn(fitted.len(), support.len(), |r, c| {
                entry(fitted[r], support[c])
            });
            let rhs = DMatrix::from_fn(fitted.len(), own.len(), |r, c| {
                if fitted[r] == own[c] { 1.0 } else { 0.0 }
            });
            // Least squares by nalgebra's Householder QR, not faer's: these run on rayon's
            // workers, and faer's dense products reserve on each thread that calls them a
            // packing buffer of twice the reported L3 cache (1 GB each on this machine's
            // processor; measured at 217k DOFs: 3.0 GB reserved instead of 1.0). The rows
            // of the support's own unknowns make `R` regular (`S~` restricted to them is a
            // principal block of a positive definite kernel times positive areas).
            let qr = a.qr();
            let columns = qr.r().solve_upper_triangular(&(qr.q().transpose() * rhs));
            (own.iter().enumerate())
                .map(|(c, &k)| {
                    let values = match &columns {
                        Some(columns) => columns.column(c).iter().copied().collect(),
                        // Not seen; the diagonal inverse keeps the preconditioner defined.
                        None => (support.iter())
                            .map(|&j| if j == k { 1.0 / entry(k, k) } else { 0.0 })
                            .collect(),
                    };
                    (k, (support.clone(), values))
                })
                .collect()
        })
        .collect();
    let mut fine = vec![(Vec::new(), Vec::new()); m];
    for (k, column) in per_node.into_iter().flatten() {
        fine[k] = column;
    }
    fine
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|a| a * a).sum::<f64>().sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::gmres::{self, GmresSettings, Operators};

    /// `S~` of two half-spaces (unit compliance factor) on jittered grid points of a disc (3D)
    /// or a segment (2D) of unit radius, one unknown per node along the normal, or `dim` along
    /// the axes.
    struct Zone {
        nodes: Vec<[f64; 3]>,
        area: f64,
        unknowns: Vec<Unknown>,
        dim: usize,
    }

    impl Zone {
        fn new(dim: usize, spacing: f64, per_node: usize) -> Self {
            let n = (2.0 / spacing) as i64;
            let mut nodes = Vec::new();
            // A deterministic jitter of a fifth of the spacing.
            let jitter = |i: i64, j: i64, c: i64| {
                0.2 * spacing * (((i * 7919 + j * 104_729 + c * 31) % 200) as f64 / 100.0 - 1.0)
            };
            for i in -n..=n {
                for j in if dim == 3 { -n..=n } else { 0..=0 } {
                    let mut x = [i as f64 * spacing + jitter(i, j, 0), 0.0, 0.0];
                    if dim == 3 {
                        x[1] = j as f64 * spacing + jitter(i, j, 1);
                    }
                    if x[0] * x[0] + x[1] * x[1] <= 1.0 {
                        nodes.push(x);
                    }
                }
            }
            let area = spacing.powi(dim as i32 - 1);
            let normal = if dim == 3 { 2 } else { 1 };
            let unknowns = (0..nodes.len())
                .flat_map(|node| {
                    (0..per_node).map(move |c| {
                        let mut direction = [0.0; 3];
                        direction[if per_node == 1 { normal } else { c }] = 1.0;
                        Unknown { node, direction }
                    })
                })
                .collect();
            Self {
                nodes,
                area,
                unknowns,
                dim,
            }
        }

        fn entry(&self, i: usize, j: usize) -> f64 {
            let (a, b) = (self.unknowns[i], self.unknowns[j]);
            let along: f64 = (0..3).map(|c| a.direction[c] * b.direction[c]).sum();
            if along == 0.0 {
                return 0.0;
            }
            let (x, y) = (self.nodes[a.node], self.nodes[b.node]);
            let r = crate::contact::coupled::far_field::distance(&x, &y);
            let g = match (self.dim, a.node == b.node) {
                (3, true) => 2.0 / (self.area / std::f64::consts::PI).sqrt(),
                (3, false) => 1.0 / r,
                (_, true) => 1.0 - (self.area / 2.0 / 10.0).ln(),
                (_, false) => -(r / 10.0).ln(),
            };
            along * g * self.area
        }
    }

    /// `S~` and `M^-1` as GMRES' operators.
    struct Preconditioned<'a> {
        zone: &'a Zone,
        inverse: Option<&'a TwoLevelInverse>,
    }

    impl Operators for Preconditioned<'_> {
        type Error = std::convert::Infallible;

        fn apply(&mut self, x: &[f64], out: &mut [f64]) -> Result<(), Self::Error> {
            for (i, o) in out.iter_mut().enumerate() {
                *o = (0..x.len()).map(|j| self.zone.entry(i, j) * x[j]).sum();
            }
            Ok(())
        }

        fn precondition(&mut self, r: &[f64], out: &mut [f64]) -> Result<(), Self::Error> {
            match self.inverse {
                Some(inverse) => inverse.apply(r, out),
                None => out.copy_from_slice(r),
            }
            Ok(())
        }
    }

    /// GMRES iterations to solve `S~ x = b` to `1e-10` with and without `M^-1`, and the
    /// solution's largest error against a dense LU solve.
    fn iterations(zone: &Zone) -> (usize, usize, f64) {
        let m = zone.unknowns.len();
        let inverse = TwoLevelInverse::new(&zone.nodes, &zone.unknowns, zone.dim, |i, j| {
            zone.entry(i, j)
        });
        let b: Vec<f64> = (0..m)
            .map(|i| ((i * 37 % 101) as f64 / 50.0) - 1.0)
            .collect();
        let settings = GmresSettings {
            tolerance: 1e-10 * gmres::norm(&b),
            reduction: None,
            max_iterations: 400,
            restart: 400,
        };
        let mut counts = [0; 2];
        let mut x = vec![0.0; m];
        for (count, inverse) in counts.iter_mut().zip([Some(&inverse), None]) {
            x.fill(0.0);
            let mut operators = Preconditioned { zone, inverse };
            let stats = gmres::solve(&mut operators, &b, &mut x, settings).unwrap();
            assert!(stats.failure.is_none(), "{:?}", stats.failure);
            *count = stats.iterations;
        }
        let dense = Mat::<f64>::from_fn(m, m, |i, j| zone.entry(i, j));
        let exact = dense
            .partial_piv_lu()
            .solve(Mat::<f64>::from_fn(m, 1, |i, _| b[i]));
        let scale = (0..m).map(|i| exact[(i, 0)].abs()).fold(0.0, f64::max);
        let error = (0..m)
            .map(|i| (x[i] - exact[(i, 0)]).abs())
            .fold(0.0, f64::max);
        (counts[0], counts[1], error / scale)
    }

    #[test]
    fn two_levels_hold_the_iterations_of_a_growing_zone() {
        // Normal unknowns on a growing zone, and vector unknowns, in 3D and 2D.
        for (dim, spacing, per_node, most) in [
            (3, 0.064, 1, 12),
            (3, 0.032, 1, 12),
            (3, 0.064, 3, 12),
            (2, 0.0025, 1, 12),
            (2, 0.00125, 1, 12),
            (2, 0.0025, 2, 12),
        ] {
            let zone = Zone::new(dim, spacing, per_node);
            let (with, without, error) = iterations(&zone);
            let m = zone.unknowns.len();
            eprintln!(
                "dim {dim}, m {m}: {with} iterations with M, {without} without, error {error:.1e}"
            );
            assert!(with <= most, "dim {dim}, m {m}: {with} iterations");
            assert!(
                3 * with <= without,
                "dim {dim}, m {m}: {with} against {without}"
            );
            assert!(error < 1e-8, "dim {dim}, m {m}: error {error:.1e}");
        }
    }
}
