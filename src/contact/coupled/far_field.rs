//! Sums of a slowly decaying kernel over a contact zone with the far part of the zone lumped
//! into clusters (Barnes and Hut, *Nature* 324, 1986): for a point `x_i`,
//!
//! ```text
//! sum_j G(x_i, x_j) w_j  ~  sum_(j in clusters near i's) G(x_i, x_j) w_j
//!                          + sum_(far b) [G(x_i, X_b) W_b + grad_y G(x_i, X_b) . M_b]
//! ```
//!
//! with `X_b` a cluster's area-weighted centre, `W_b = sum_(j in b) w_j` its total weight and
//! `M_b = sum_(j in b) w_j (x_j - X_b)` its first moment: the first two terms of the kernel's
//! Taylor series about the centre (a monopole and a dipole). Two clusters are near when their
//! centres are closer than [`ADMISSIBILITY`] times the sum of their radii (the largest distance
//! of a member from the centre); far, the series' remainder is of the order of
//! `(r / d)^2 |G(x_i, X_b)|` per unit weight, `r` the radius and `d` the distance. Nothing of the
//! zone's square is stored: a sum costs the near members and one term per cluster. (Weights of
//! one sign, as contact pressures are, do not cancel in the remainder: a monopole alone left
//! the half-space model's pressures 3.5% of the largest from the assembled model's.)
//!
//! The clusters are the zone cut by recursive coordinate bisection: [`clusters`], also the
//! coarse level of `crate::contact::coupled::two_level_inverse`.

/// Two clusters whose centres are closer than this times the sum of their radii are summed
/// member by member.
pub const ADMISSIBILITY: f64 = 3.0;

/// Nodes per cluster of the lumped sums, at most: a sum costs about `9 CLUSTER_SIZE` near
/// terms (a cluster's near neighbours on a surface) and one per cluster.
pub const CLUSTER_SIZE: usize = 32;

/// The node indices of `nodes` (in `dim` dimensions) cut at the median of the widest coordinate
/// until each part has at most `most` nodes.
pub fn clusters(nodes: &[[f64; 3]], dim: usize, most: usize) -> Vec<Vec<usize>> {
    let mut out = Vec::new();
    bisect(
        nodes,
        (0..nodes.len()).collect(),
        dim,
        most.max(1),
        &mut out,
    );
    out
}

fn bisect(
    nodes: &[[f64; 3]],
    mut cluster: Vec<usize>,
    dim: usize,
    most: usize,
    out: &mut Vec<Vec<usize>>,
) {
    if cluster.len() <= most {
        if !cluster.is_empty() {
            out.push(cluster);
        }
        return;
    }
    let extent = |c: usize| {
        let (lo, hi) = (cluster.iter()).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &n| {
            (lo.min(nodes[n][c]), hi.max(nodes[n][c]))
        });
        hi - lo
    };
    let widest = (0..dim)
        .max_by(|&a, &b| extent(a).total_cmp(&extent(b)))
        .unwrap_or(0);
    cluster.sort_by(|&a, &b| nodes[a][widest].total_cmp(&nodes[b][widest]));
    let upper = cluster.split_off(cluster.len() / 2);
    bisect(nodes, cluster, dim, most, out);
    bisect(nodes, upper, dim, most, out);
}

/// A zone of weighted points cut into clusters, with each cluster's near neighbours and total
/// weight, for the lumped sums of the module doc.
pub struct LumpedSums {
    /// Cluster of each point.
    cluster_of: Vec<usize>,
    members: Vec<Vec<usize>>,
    centres: Vec<[f64; 3]>,
    /// For each cluster, whether each other cluster is near it.
    near: Vec<Vec<bool>>,
    /// `W_b` of each cluster.
    totals: Vec<f64>,
    /// `M_b` of each cluster.
    moments: Vec<[f64; 3]>,
    /// Each point's offset from its cluster's centre.
    offsets: Vec<[f64; 3]>,
}

impl LumpedSums {
    /// The clusters of `points`, centred by the weights `areas`, every weight zero.
    pub fn new(points: &[[f64; 3]], areas: &[f64], dim: usize) -> Self {
        let members = clusters(points, dim, CLUSTER_SIZE);
        let mut cluster_of = vec![0; points.len()];
        let mut offsets = vec![[0.0; 3]; points.len()];
        let mut centres = Vec::with_capacity(members.len());
        let mut radii = Vec::with_capacity(members.len());
        for (b, cluster) in members.iter().enumerate() {
            let area: f64 = cluster.iter().map(|&j| areas[j]).sum();
            let mut centre = [0.0; 3];
            for &j in cluster {
                cluster_of[j] = b;
                for c in 0..3 {
                    centre[c] += points[j][c] * areas[j] / area;
                }
            }
            let radius = (cluster.iter())
                .map(|&j| distance(&points[j], &centre))
                .fold(0.0, f64::max);
            for &j in cluster {
                offsets[j] = std::array::from_fn(|c| points[j][c] - centre[c]);
            }
            centres.push(centre);
            radii.push(radius);
        }
        let near = (0..members.len())
            .map(|a| {
                (0..members.len())
                    .map(|b| {
                        distance(&centres[a], &centres[b]) < ADMISSIBILITY * (radii[a] + radii[b])
                    })
                    .collect()
            })
            .collect();
        Self {
            cluster_of,
            totals: vec![0.0; members.len()],
            moments: vec![[0.0; 3]; members.len()],
            offsets,
            members,
            centres,
            near,
        }
    }

    /// Sets every weight to zero.
    pub fn clear(&mut self) {
        self.totals.fill(0.0);
        self.moments.fill([0.0; 3]);
    }

    /// Adds `change` to the weight of point `j` (whose weights are `weights`, kept by the
    /// caller).
    pub fn add(&mut self, j: usize, change: f64) {
        let b = self.cluster_of[j];
        self.totals[b] += change;
        for c in 0..3 {
            self.moments[b][c] += change * self.offsets[j][c];
        }
    }

    /// `sum_j G(x_i, x_j) w_j` with the far clusters lumped, for the weights `weights` (whose
    /// changes were passed to [`Self::add`]), `G` given by `between(i, j)` for two points
    /// (`own(i)` for `i` on itself), and `lumped(i, X)` the kernel between point `i` and a
    /// cluster centre `X` and its gradient in `X`.
    pub fn sum(
        &self,
        i: usize,
        weights: &[f64],
        own: impl Fn(usize) -> f64,
        between: impl Fn(usize, usize) -> f64,
        lumped: impl Fn(usize, &[f64; 3]) -> (f64, [f64; 3]),
    ) -> f64 {
        let near = &self.near[self.cluster_of[i]];
        let mut sum = 0.0;
        for (b, cluster) in self.members.iter().enumerate() {
            if !near[b] {
                let (g, gradient) = lumped(i, &self.centres[b]);
                let moment = &self.moments[b];
                sum += g * self.totals[b] + (0..3).map(|c| gradient[c] * moment[c]).sum::<f64>();
                continue;
            }
            for &j in cluster {
                let g = if j == i { own(i) } else { between(i, j) };
                sum += g * weights[j];
            }
        }
        sum
    }
}

/// The Euclidean distance of two points.
pub fn distance(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    (0..3).map(|c| (a[c] - b[c]).powi(2)).sum::<f64>().sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lumped_sum_is_within_the_bound_of_its_far_clusters() {
        // 3,025 points of a jittered grid on a unit square, `1/r`, weights of both signs.
        let n = 55;
        let points: Vec<[f64; 3]> = (0..n * n)
            .map(|k| {
                let (i, j) = ((k / n) as f64, (k % n) as f64);
                let jitter = ((k * 7919 % 97) as f64 / 97.0 - 0.5) * 0.3;
                [(i + jitter) / n as f64, (j - jitter) / n as f64, 0.0]
            })
            .collect();
        let areas = vec![1.0 / (n * n) as f64; points.len()];
        let weights: Vec<f64> = (0..points.len())
            .map(|k| ((k * 37 % 101) as f64 / 50.0 - 0.7) * areas[k])
            .collect();
        let mut sums = LumpedSums::new(&points, &areas, 2);
        for (j, w) in weights.iter().enumerate() {
            sums.add(j, *w);
        }
        let g = |a: &[f64; 3], b: &[f64; 3]| 1.0 / distance(a, b);
        let own = |_: usize| 2.0 / (areas[0] / std::f64::consts::PI).sqrt();
        let (mut far_clusters, mut worst) = (0, 0.0_f64);
        for i in (0..points.len()).step_by(7) {
            let exact: f64 = (0..points.len())
                .map(|j| if j == i { own(i) } else { g(&points[i], &points[j]) } * weights[j])
                .sum();
            // The remainder of the first-order Taylor series of 1/|x - y| about X, for y
            // within r of X and d = |x - X| > r: |y - X|^2 times the largest second
            // derivative along the segment, at most 3 / (d - r)^3 (the Hessian's norm).
            let near = &sums.near[sums.cluster_of[i]];
            let mut bound = 0.0;
            for (b, cluster) in sums.members.iter().enumerate().filter(|(b, _)| !near[*b]) {
                let centre = &sums.centres[b];
                let r = (cluster.iter())
                    .map(|&j| distance(&points[j], centre))
                    .fold(0.0, f64::max);
                let d = distance(&points[i], centre);
                let size: f64 = cluster.iter().map(|&j| weights[j].abs()).sum();
                bound += size * 3.0 * r * r / (d - r).powi(3);
                far_clusters += 1;
            }
            let lumped = sums.sum(
                i,
                &weights,
                own,
                |i, j| g(&points[i], &points[j]),
                |i, x| {
                    let d = distance(&points[i], x);
                    (
                        1.0 / d,
                        std::array::from_fn(|c| (points[i][c] - x[c]) / d.powi(3)),
                    )
                },
            );
            let error = (lumped - exact).abs();
            assert!(
                error <= bound * (1.0 + 1e-12) + 1e-12 * exact.abs(),
                "point {i}: {error:.3e} > {bound:.3e}"
            );
            worst = worst.max(error / exact.abs());
        }
        assert!(far_clusters > 0, "some cluster is far");
        eprintln!("largest relative error of a lumped sum: {worst:.2e}");
    }
}
