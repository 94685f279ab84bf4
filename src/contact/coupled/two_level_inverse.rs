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
//! M^-1 r = V y + F (r - P y),        y = (V^T P)^-1 V^T r,        P ~ S~ V
//! ```
//!
//! - **coarse**: `V` has, per cluster of at most [`CLUSTER_NODES`] nodes (recursive coordinate
//!   bisection, `crate::contact::coupled::far_field::clusters`), the uniform tractions along the
//!   axes projected on each unknown's column direction, orthonormalized within the cluster.
//!   `P` is `S~ V` with the far field lumped: the operator is `S~_ij = (p_i . q_j) G(x_i, x_j)`
//!   between unknowns of distinct nodes ([`Unknown`]), so a coarse column `c` of a cluster `b`
//!   centred at `X_b`, seen from a node `x_i` of a cluster far from `b` (centres further apart
//!   than [`ADMISSIBILITY`] times the sum of the radii), is its monopole and dipole,
//!
//!   ```text
//!   (S~ V)_ic ~ p_i . (G(x_i, X_b) T_c + Q_c grad_y G(x_i, X_b)),
//!   T_c = sum_(j in b) q_j V_jc,   Q_c = sum_(j in b) q_j V_jc (x_j - X_b)^T
//!   ```
//!
//!   (`crate::contact::coupled::far_field`'s lumped sums, with vector weights), and is summed
//!   entry by entry only over the near clusters. `P` is stored for the near clusters alone, the
//!   far part evaluated when applied (one kernel value per far cluster and row); `V^T P` is
//!   dense and LU-factored. Using the same `P` in the coarse matrix and in the residual keeps
//!   the coarse correction exact for it: `V^T (r - P y) = 0`;
//! - **fine**: `F` is a sparse approximate right inverse with a fixed pattern (Grote and Huckle,
//!   *SIAM J. Sci. Comput.* 18, 1997): its column `i` is supported on the unknowns of the
//!   [`PATTERN_NODES`] nodes nearest to `i`'s node and minimizes `|S~ f_i - e_i|` over the rows of
//!   the [`SHADOW_NODES`] nearest (one least-squares problem per node, which its unknowns share).
//!
//! Memory: `m (PATTERN_NODES u + k)` numbers (`u` unknowns per node, `k` the coarse columns of
//! the near clusters: up to `dim` per cluster, and in 3D about 45 clusters whatever the zone's
//! size, measured in the tests below) and the coarse factor's `n0^2` (`n0` at most `dim m / 128`
//! in 3D), against `2 m^2` for the dense LU and `m n0` for `S~ V` stored whole. `S~` itself is never
//! stored, and summed entry by entry only over each row's near clusters. Measured on a disc of
//! points with the 3D kernel (GMRES on `S~ x = b` right-preconditioned by `M`, to `1e-10`), with
//! `P = S~ V` exact: 9 iterations at 1,000, 4,000 and 9,000 unknowns with clusters of about 140
//! nodes; the fine level alone took 12, 16 and 20 (the smooth part it misses grows with the
//! zone), the two levels added instead of applied in turn 20 to 24. The tests below check the
//! iterations with the lumped `P` on the half-space operator in 2D and 3D, and the lumped
//! rows against the exact ones.

use std::num::NonZeroUsize;
use std::ops::Range;

use faer::Mat;
use faer::prelude::*;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::DMatrix;
use rayon::prelude::*;

use crate::contact::coupled::far_field::{ADMISSIBILITY, clusters, distance};

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
/// logarithmic kernel's smooth part is larger).
pub const CLUSTER_NODES: [usize; 2] = [128, 32];

/// Rows of `P` computed at once while the coarse matrix is summed: the rows are computed in
/// parallel and added in their order, so that the sum does not depend on the threads.
const ROW_BLOCK: usize = 256;

/// The kernel `G` of the operator, for the lumped far field: its value between a point `x`
/// and a point `y` apart from it, and its gradient in `y`.
pub trait FarField: Send + Sync {
    /// `(G(x, y), grad_y G(x, y))`.
    fn field(&self, x: &[f64; 3], y: &[f64; 3]) -> (f64, [f64; 3]);
}

impl<G: FarField + ?Sized> FarField for &G {
    fn field(&self, x: &[f64; 3], y: &[f64; 3]) -> (f64, [f64; 3]) {
        (**self).field(x, y)
    }
}

/// The two-level approximate inverse of the module doc.
pub struct TwoLevelInverse<G: FarField> {
    /// Coarse basis: for each unknown, its coarse columns and weights (the columns of its
    /// cluster).
    basis: Vec<CoarseRow>,
    product: LumpedProduct<G>,
    coarse: faer::linalg::solvers::PartialPivLu<f64>,
    /// Column `i` of `F`.
    fine: Vec<FineColumn>,
}

/// `P` of the module doc: `S~ V` summed over the near clusters, lumped over the far ones.
struct LumpedProduct<G: FarField> {
    /// The near part of each unknown's row: its values at its cluster's `near` columns, from
    /// `near_offsets[i]` (the rows one after the other, allocated once).
    near_values: Vec<f64>,
    near_offsets: Vec<usize>,
    /// Each unknown's node's point, its row vector `p_i` and its node's cluster.
    at: Vec<[f64; 3]>,
    reads: Vec<[f64; 3]>,
    cluster_of: Vec<usize>,
    clusters: Vec<Cluster>,
    kernel: G,
    n0: usize,
}

/// A cluster of the coarse level: its centre, its coarse columns with their monopoles and
/// dipoles (`T_c`, `Q_c` of the module doc), the clusters far from it (sorted), and the coarse
/// columns of the others (near it, itself included), which its rows of `P` store.
struct Cluster {
    centre: [f64; 3],
    columns: Range<usize>,
    moments: Vec<Moments>,
    far: Vec<usize>,
    near: Vec<u32>,
}

/// `T_c` and `Q_c` of the module doc (`Q_c[k][l]` the `k` component of `q` times the `l` of the
/// offset).
#[derive(Clone, Copy, Default)]
struct Moments {
    total: [f64; 3],
    first: [[f64; 3]; 3],
}

impl Moments {
    /// Adds `weight` times the moments of a load `q` at `offset` from the centre.
    fn add(&mut self, weight: f64, q: &[f64; 3], offset: &[f64; 3]) {
        for ((total, first), qk) in self.total.iter_mut().zip(&mut self.first).zip(q) {
            *total += weight * qk;
            first
                .iter_mut()
                .zip(offset)
                .for_each(|(f, o)| *f += weight * qk * o);
        }
    }

    /// Adds `weight` times `other`.
    fn add_scaled(&mut self, weight: f64, other: &Moments) {
        for k in 0..3 {
            self.total[k] += weight * other.total[k];
            for l in 0..3 {
                self.first[k][l] += weight * other.first[k][l];
            }
        }
    }

    /// `p . (g T + Q grad)`: what a row reading along `p` sees of these moments through the
    /// kernel's value `g` and gradient `grad` at their centre.
    fn seen(&self, p: &[f64; 3], g: f64, grad: &[f64; 3]) -> f64 {
        (0..3)
            .map(|k| {
                let dipole: f64 = (0..3).map(|l| self.first[k][l] * grad[l]).sum();
                p[k] * (g * self.total[k] + dipole)
            })
            .sum()
    }
}

/// An unknown of the operator: where it acts, along which direction its column loads, and the
/// vectors its row and column contract the kernel with, `S~_ij = (reads_i . loads_j) G(x_i,
/// x_j)` between unknowns of distinct nodes.
#[derive(Debug, Clone, Copy)]
pub struct Unknown {
    /// Index of its node (unknowns of one node share it), from 0.
    pub node: usize,
    /// Its column's direction (a unit traction's), for the coarse basis.
    pub direction: [f64; 3],
    /// `p_i`.
    pub reads: [f64; 3],
    /// `q_j`.
    pub loads: [f64; 3],
}

impl<G: FarField> TwoLevelInverse<G> {
    /// The approximate inverse of the `m x m` operator `entry(i, j)` on `unknowns` (`m` of
    /// them), whose nodes are at `nodes` (in `dim` dimensions; distinct, finite), with
    /// `entry(i, j) = (reads_i . loads_j) G(x_i, x_j)` between unknowns of distinct nodes, `G`
    /// given by `kernel`.
    ///
    /// # Panics
    /// If an unknown names a node that is not in `nodes`.
    pub fn new(
        nodes: &[[f64; 3]],
        unknowns: &[Unknown],
        dim: usize,
        entry: impl Fn(usize, usize) -> f64 + Sync,
        kernel: G,
    ) -> Self {
        let m = unknowns.len();
        let mut of_node = vec![Vec::new(); nodes.len()];
        for (k, unknown) in unknowns.iter().enumerate() {
            of_node[unknown.node].push(k);
        }
        let most = CLUSTER_NODES[if dim == 3 { 0 } else { 1 }];
        let node_clusters = clusters(nodes, dim, most);
        let (basis, columns) = coarse_basis(&node_clusters, &of_node, unknowns, dim);
        let n0 = columns.last().map_or(0, |c| c.end);
        let clusters = lumped_clusters(nodes, &node_clusters, &of_node, unknowns, &basis, columns);
        let mut cluster_of = vec![0; m];
        for (b, cluster) in node_clusters.iter().enumerate() {
            for &node in cluster {
                of_node[node].iter().for_each(|&k| cluster_of[k] = b);
            }
        }
        // The near part of each row of P: each entry of S~ between near clusters once, a block
        // of rows at a time into one allocation.
        let mut near_offsets = Vec::with_capacity(m + 1);
        near_offsets.push(0);
        for &b in &cluster_of {
            near_offsets.push(near_offsets.last().unwrap_or(&0) + clusters[b].near.len());
        }
        let mut near_values = Vec::with_capacity(near_offsets[m]);
        let all: Vec<usize> = (0..m).collect();
        for block in all.chunks(ROW_BLOCK) {
            let rows: Vec<Vec<f64>> = (block.par_iter())
                .map(|&i| {
                    let far = &clusters[cluster_of[i]].far;
                    let mut row = Vec::with_capacity(clusters[cluster_of[i]].near.len());
                    for (b, cluster) in clusters.iter().enumerate() {
                        if far.binary_search(&b).is_ok() {
                            continue;
                        }
                        let start = row.len();
                        row.resize(start + cluster.columns.len(), 0.0);
                        for &j in node_clusters[b].iter().flat_map(|&node| &of_node[node]) {
                            let a = entry(i, j);
                            for &(c, v) in &basis[j] {
                                row[start + c - cluster.columns.start] += a * v;
                            }
                        }
                    }
                    row
                })
                .collect();
            rows.iter()
                .for_each(|row| near_values.extend_from_slice(row));
        }
        let product = LumpedProduct {
            near_values,
            near_offsets,
            at: unknowns.iter().map(|u| nodes[u.node]).collect(),
            reads: unknowns.iter().map(|u| u.reads).collect(),
            cluster_of,
            clusters,
            kernel,
            n0,
        };
        // V^T P, a block of rows of P at a time, added in the rows' order.
        let mut coarse = Mat::<f64>::zeros(n0, n0);
        for block in all.chunks(ROW_BLOCK) {
            let rows: Vec<Vec<f64>> = block.par_iter().map(|&i| product.row(i)).collect();
            for (&i, row) in block.iter().zip(rows) {
                for &(a, v) in &basis[i] {
                    for (b, p) in row.iter().enumerate() {
                        coarse[(a, b)] += v * p;
                    }
                }
            }
        }
        Self {
            basis,
            product,
            coarse: coarse.partial_piv_lu(),
            fine: fine_level(nodes, &of_node, m, &entry),
        }
    }

    /// `out = M^-1 r`.
    pub fn apply(&self, r: &[f64], out: &mut [f64]) {
        let mut y = Mat::<f64>::zeros(self.product.n0, 1);
        for (columns, ri) in self.basis.iter().zip(r) {
            for &(c, v) in columns {
                y[(c, 0)] += v * ri;
            }
        }
        self.coarse.solve_in_place(y.as_mut());
        let y: Vec<f64> = (0..self.product.n0).map(|c| y[(c, 0)]).collect();
        let p_y = self.product.times(&y);
        out.fill(0.0);
        for (i, columns) in self.basis.iter().enumerate() {
            // The coarse correction, and the residual it leaves in this row.
            out[i] += columns.iter().map(|&(c, v)| v * y[c]).sum::<f64>();
            let residual = r[i] - p_y[i];
            let (rows, values) = &self.fine[i];
            for (&row, value) in rows.iter().zip(values) {
                out[row] += value * residual;
            }
        }
    }
}

impl<G: FarField> LumpedProduct<G> {
    /// The near part of row `i`: its columns and values.
    fn near_row(&self, i: usize) -> impl Iterator<Item = (&u32, &f64)> {
        let columns = &self.clusters[self.cluster_of[i]].near;
        let values = &self.near_values[self.near_offsets[i]..self.near_offsets[i + 1]];
        columns.iter().zip(values)
    }

    /// Row `i`, dense over the `n0` coarse columns.
    fn row(&self, i: usize) -> Vec<f64> {
        let mut row = vec![0.0; self.n0];
        for (&c, &v) in self.near_row(i) {
            row[c as usize] = v;
        }
        for &b in &self.clusters[self.cluster_of[i]].far {
            let cluster = &self.clusters[b];
            let (g, grad) = self.kernel.field(&self.at[i], &cluster.centre);
            for (c, moments) in cluster.columns.clone().zip(&cluster.moments) {
                row[c] = moments.seen(&self.reads[i], g, &grad);
            }
        }
        row
    }

    /// `P y`: the far clusters' columns combined into one set of moments per cluster first,
    /// so that a row costs its near entries and one kernel value per far cluster.
    fn times(&self, y: &[f64]) -> Vec<f64> {
        let lumped: Vec<Moments> = (self.clusters.iter())
            .map(|cluster| {
                let mut sum = Moments::default();
                for (c, moments) in cluster.columns.clone().zip(&cluster.moments) {
                    sum.add_scaled(y[c], moments);
                }
                sum
            })
            .collect();
        (0..self.at.len())
            .into_par_iter()
            .map(|i| {
                let near: f64 = (self.near_row(i)).map(|(&c, &v)| v * y[c as usize]).sum();
                let far: f64 = (self.clusters[self.cluster_of[i]].far.iter())
                    .map(|&b| {
                        let (g, grad) = self.kernel.field(&self.at[i], &self.clusters[b].centre);
                        lumped[b].seen(&self.reads[i], g, &grad)
                    })
                    .sum();
                near + far
            })
            .collect()
    }
}

/// The coarse basis `V` of the module doc: per cluster of nodes, the unknowns' directions'
/// components along each axis, orthonormalized by modified Gram-Schmidt (a component that the
/// others span, to `1e-3` of its own size, is dropped: on a flat zone the tangential components
/// of normal directions are zero). Returns each unknown's coarse columns and weights, and each
/// cluster's columns.
fn coarse_basis(
    node_clusters: &[Vec<usize>],
    of_node: &[Vec<usize>],
    unknowns: &[Unknown],
    dim: usize,
) -> (Vec<CoarseRow>, Vec<Range<usize>>) {
    let mut basis = vec![Vec::new(); unknowns.len()];
    let mut n0 = 0;
    let mut columns = Vec::with_capacity(node_clusters.len());
    for cluster in node_clusters {
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
        let start = n0;
        for w in kept {
            for (&k, &value) in members.iter().zip(&w) {
                if value != 0.0 {
                    basis[k].push((n0, value));
                }
            }
            n0 += 1;
        }
        columns.push(start..n0);
    }
    (basis, columns)
}

/// The clusters of the coarse level with their centres (the mean of their nodes), the
/// moments of their coarse columns, and which clusters are far from each
/// ([`ADMISSIBILITY`]; sorted).
fn lumped_clusters(
    nodes: &[[f64; 3]],
    node_clusters: &[Vec<usize>],
    of_node: &[Vec<usize>],
    unknowns: &[Unknown],
    basis: &[CoarseRow],
    columns: Vec<Range<usize>>,
) -> Vec<Cluster> {
    let mut centres = Vec::with_capacity(node_clusters.len());
    let mut radii = Vec::with_capacity(node_clusters.len());
    for cluster in node_clusters {
        let mut centre = [0.0; 3];
        for &node in cluster {
            (0..3).for_each(|c| centre[c] += nodes[node][c] / cluster.len() as f64);
        }
        let radius = (cluster.iter())
            .map(|&node| distance(&nodes[node], &centre))
            .fold(0.0, f64::max);
        centres.push(centre);
        radii.push(radius);
    }
    let mut clusters = (node_clusters.iter().zip(columns).enumerate())
        .map(|(b, (cluster, columns))| {
            let centre = centres[b];
            let mut moments = vec![Moments::default(); columns.len()];
            for &node in cluster {
                let offset: [f64; 3] = std::array::from_fn(|c| nodes[node][c] - centre[c]);
                for &j in &of_node[node] {
                    for &(c, v) in &basis[j] {
                        moments[c - columns.start].add(v, &unknowns[j].loads, &offset);
                    }
                }
            }
            let far: Vec<usize> = (0..node_clusters.len())
                .filter(|&a| {
                    a != b
                        && distance(&centres[a], &centre) >= ADMISSIBILITY * (radii[a] + radii[b])
                })
                .collect();
            Cluster {
                centre,
                columns,
                moments,
                far,
                near: Vec::new(),
            }
        })
        .collect::<Vec<Cluster>>();
    for b in 0..clusters.len() {
        let near: Vec<u32> = (0..clusters.len())
            .filter(|a| clusters[b].far.binary_search(a).is_err())
            .flat_map(|a| clusters[a].columns.clone().map(|c| c as u32))
            .collect();
        clusters[b].near = near;
    }
    clusters
}

/// Each unknown's coarse columns and weights: a row of `V`.
type CoarseRow = Vec<(usize, f64)>;

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
                        Unknown {
                            node,
                            direction,
                            reads: direction,
                            loads: direction.map(|d| d * area),
                        }
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
            let g = match a.node == b.node {
                true if self.dim == 3 => 2.0 / (self.area / std::f64::consts::PI).sqrt(),
                true => 1.0 - (self.area / 2.0 / 10.0).ln(),
                false => self.field(&self.nodes[a.node], &self.nodes[b.node]).0,
            };
            along * g * self.area
        }
    }

    impl FarField for Zone {
        /// `1 / r` in 3D, `-ln(r / 10)` in 2D.
        fn field(&self, x: &[f64; 3], y: &[f64; 3]) -> (f64, [f64; 3]) {
            let r = distance(x, y);
            let (g, slope) = match self.dim {
                3 => (1.0 / r, -1.0 / (r * r)),
                _ => (-(r / 10.0).ln(), -1.0 / r),
            };
            (g, std::array::from_fn(|c| -slope * (x[c] - y[c]) / r))
        }
    }

    /// `S~` and `M^-1` as GMRES' operators.
    struct Preconditioned<'a> {
        zone: &'a Zone,
        inverse: Option<&'a TwoLevelInverse<&'a Zone>>,
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
    /// solution's largest error against a dense LU solve (on at most [`DENSE_CHECK`] unknowns).
    fn iterations(zone: &Zone) -> (usize, usize, Option<f64>) {
        let m = zone.unknowns.len();
        let inverse = TwoLevelInverse::new(
            &zone.nodes,
            &zone.unknowns,
            zone.dim,
            |i, j| zone.entry(i, j),
            zone,
        );
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
        if m > DENSE_CHECK {
            return (counts[0], counts[1], None);
        }
        let dense = Mat::<f64>::from_fn(m, m, |i, j| zone.entry(i, j));
        let exact = dense
            .partial_piv_lu()
            .solve(Mat::<f64>::from_fn(m, 1, |i, _| b[i]));
        let scale = (0..m).map(|i| exact[(i, 0)].abs()).fold(0.0, f64::max);
        let error = (0..m)
            .map(|i| (x[i] - exact[(i, 0)]).abs())
            .fold(0.0, f64::max);
        (counts[0], counts[1], Some(error / scale))
    }

    /// The most unknowns [`iterations`] checks against a dense solve.
    const DENSE_CHECK: usize = 4000;

    #[test]
    fn a_lumped_row_is_within_the_taylor_bound_of_the_exact_one() {
        // The far columns of P against S~ V summed entry by entry, on zones with far clusters.
        for (dim, spacing, per_node) in
            [(3, 0.032, 1), (3, 0.016, 1), (3, 0.032, 3), (2, 0.00125, 2)]
        {
            let zone = Zone::new(dim, spacing, per_node);
            let inverse = TwoLevelInverse::new(
                &zone.nodes,
                &zone.unknowns,
                zone.dim,
                |i, j| zone.entry(i, j),
                &zone,
            );
            let product = &inverse.product;
            let m = zone.unknowns.len();
            let (mut far_entries, mut worst) = (0, 0.0_f64);
            for i in (0..m).step_by(11) {
                let mut exact = vec![0.0; product.n0];
                for j in 0..m {
                    let a = zone.entry(i, j);
                    for &(c, v) in &inverse.basis[j] {
                        exact[c] += a * v;
                    }
                }
                let lumped = product.row(i);
                let largest = exact.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
                for &b in &product.clusters[product.cluster_of[i]].far {
                    let cluster = &product.clusters[b];
                    let members: Vec<usize> =
                        (0..m).filter(|&j| product.cluster_of[j] == b).collect();
                    let reach = (members.iter())
                        .map(|&j| distance(&product.at[j], &cluster.centre))
                        .fold(0.0, f64::max);
                    let d = distance(&product.at[i], &cluster.centre);
                    // The remainder of the first-order Taylor series in y about the centre:
                    // half the offset squared times the Hessian's norm along the segment, at
                    // most 3 / (d - reach)^3 for 1 / r and 1 / (d - reach)^2 for -ln r.
                    let hessian = match dim {
                        3 => 3.0 / (d - reach).powi(3),
                        _ => 1.0 / (d - reach).powi(2),
                    };
                    let size = |v: &[f64; 3]| v.iter().map(|a| a * a).sum::<f64>().sqrt();
                    for c in cluster.columns.clone() {
                        let bound: f64 = (members.iter())
                            .filter_map(|&j| {
                                let v = inverse.basis[j].iter().find(|e| e.0 == c)?.1;
                                let offset = distance(&product.at[j], &cluster.centre);
                                let loads = size(&zone.unknowns[j].loads);
                                Some(0.5 * offset * offset * hessian * (v * loads).abs())
                            })
                            .sum::<f64>()
                            * size(&zone.unknowns[i].reads);
                        let error = (lumped[c] - exact[c]).abs();
                        assert!(
                            error <= bound * (1.0 + 1e-9) + 1e-12 * largest,
                            "dim {dim}, row {i}, column {c}: {error:.3e} > {bound:.3e}"
                        );
                        worst = worst.max(error / largest);
                        far_entries += 1;
                    }
                }
                // The near columns are the exact sums.
                for (&c, &v) in product.near_row(i) {
                    assert!((v - exact[c as usize]).abs() <= 1e-12 * largest);
                }
            }
            let stored = product.near_values.len() as f64 / m as f64;
            eprintln!(
                "dim {dim}, m {m}: {far_entries} far entries, largest error {worst:.1e} of the \
                 row; {stored:.0} near entries stored per row of {} columns",
                product.n0
            );
            assert!(far_entries > 0, "dim {dim}: no cluster is far");
            if m > 10_000 {
                // The near clusters are those within a few cluster radii: their number does not
                // grow with the zone, so most of a large zone's row is not stored.
                assert!(
                    stored < 0.5 * product.n0 as f64,
                    "dim {dim}, m {m}: {stored:.0}"
                );
            }
        }
    }

    #[test]
    fn two_levels_hold_the_iterations_of_a_growing_zone() {
        // Normal unknowns on a growing zone, and vector unknowns, in 3D and 2D; the larger
        // zones have far clusters, whose part of `P` is lumped.
        for (dim, spacing, per_node, most) in [
            (3, 0.064, 1, 12),
            (3, 0.032, 1, 12),
            (3, 0.02, 1, 12),
            (3, 0.064, 3, 12),
            (2, 0.0025, 1, 12),
            (2, 0.00125, 1, 12),
            (2, 0.0025, 2, 12),
        ] {
            let zone = Zone::new(dim, spacing, per_node);
            let (with, without, error) = iterations(&zone);
            let m = zone.unknowns.len();
            let checked = error.map_or("not checked".into(), |e| format!("error {e:.1e}"));
            eprintln!("dim {dim}, m {m}: {with} iterations with M, {without} without, {checked}");
            assert!(with <= most, "dim {dim}, m {m}: {with} iterations");
            assert!(
                3 * with <= without,
                "dim {dim}, m {m}: {with} against {without}"
            );
            assert!(
                error.is_none_or(|e| e < 1e-8),
                "dim {dim}, m {m}: error {error:?}"
            );
        }
    }
}
