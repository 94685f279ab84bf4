//! Rescaled, compactly supported radial-basis interpolation between contact interfaces.
//!
//! The INTERNODES method transfers fields between the two non-matching interfaces of a contact
//! problem with the rescaled localized radial-basis interpolation of Deparis, Forti and
//! Quarteroni (2014; `docs/method.md`, section 2.2):
//!
//! * Wendland C2 basis: `phi(delta) = (1 - delta)^4_+ (1 + 4 delta)`, with
//!   `delta = |x - xi_j| / r_j` and a support radius `r_j` per interpolation node.
//! * Source nodes `xi_1..xi_M` with radii `r_j`, target points `zeta_1..zeta_N`:
//!   `(Phi_MM)_ij = phi(|xi_i - xi_j| / r_j)`, `(Phi_NM)_ij = phi(|zeta_i - xi_j| / r_j)`, and the
//!   interpolation matrix is `R_NM = D_NN^-1 Phi_NM Phi_MM^-1` with
//!   `D_NN = diag(Phi_NM Phi_MM^-1 1)`. Every row of `R_NM` therefore sums to one:
//!   constants are reproduced exactly.
//! * Because column `j` uses its own radius `r_j`, `Phi_MM` is not symmetric: its solves are
//!   GMRES (whole fields) and sparse LU on patches (rows and columns of `R`; [`Interpolation`]).
//!   Both RBF matrices are sparse (compact support), their rows found by k-d tree radius
//!   searches, never by visiting all pairs.
//! * Radii: Algorithm 1 ([`support_radii`]) is the reference; the transfer operators of a
//!   contact solve use radii of the same form with `c` held at Algorithm 1's starting value
//!   ([`interpolation_radii`]), for the accuracy reason given there. An iterative search for
//!   interface nodes (keeping only the nodes within reach of the other side) is not needed: the
//!   operators interpolate at each node's projection onto the source surface, which every
//!   support covers (`crate::contact::coupled::interface`).
//!
//! Points are `[f64; 3]`; 2D problems pass `z = 0` (points on a curve), 3D problems points on a
//! surface. Nothing here depends on the dimension.
//!
//! Accuracy: with radii tied to the nodal spacing the rescaled interpolation is first order,
//! `O(h)` (see `tests/interpolation.rs` for the measured rates).

use std::num::NonZeroUsize;
use std::ops::Range;
use std::sync::OnceLock;

use faer::linalg::solvers::Solve;
use faer::sparse::SymbolicSparseRowMat;
use kiddo::{ImmutableKdTree, SquaredEuclidean};

use crate::contact::geometry::rbf_patch::{
    self as patch, BlockShare, CompressedRows, NodeCache, PatchMatrix, PatchNode, row_entries,
};
use crate::linalg::gmres;

/// Starting value of the constant `c` of Algorithm 1 (`r_i = d_i / c`).
pub const C_START: f64 = 0.5;

/// Upper bound `C` of Algorithm 1: it fails when `c` would exceed it.
pub const C_MAX: f64 = 0.95;

/// Relative threshold for the rescaling factors `D_ii`.
///
/// Target `i` is *uncovered* when `D_ii = sum_j (Phi_NM)_ij y_j <= UNCOVERED_TOL * sum_j
/// (Phi_NM)_ij |y_j|`, with `y = Phi_MM^-1 1`. The right-hand side is the size of the terms that are
/// summed, so the test is independent of how deep the target lies in the supports (the rescaled
/// row of `R` does not depend on the scale of the row of `Phi_NM`). A target outside every support
/// has an empty row (`0 <= 0`) and is uncovered; so is a target whose `D_ii` is negative or lost
/// to cancellation.
pub const UNCOVERED_TOL: f64 = 1e-10;

/// Errors of the radial-basis interpolation.
#[derive(Debug, thiserror::Error)]
pub enum RbfError {
    /// A point has a NaN or infinite coordinate.
    #[error("point {index} has a non-finite coordinate")]
    NonFinite {
        /// Index of the point in the given slice.
        index: usize,
    },
    /// Two nodes of the same set coincide: the nearest-neighbour distance is zero, so Condition 2
    /// cannot hold for any radius.
    #[error("nodes {first} and {second} coincide")]
    CoincidentNodes {
        /// Index of the first node.
        first: usize,
        /// Index of the second node.
        second: usize,
    },
    /// A single node has no neighbour, so Algorithm 1 cannot size its support.
    #[error("a single node has no neighbour to derive its support radius from")]
    SingleNode,
    /// Algorithm 1 raised `c` up to [`C_MAX`] and Condition 1 still fails.
    #[error(
        "no radius parameters satisfy Condition 1: {points} nodes still have too many neighbours at c = {c}"
    )]
    NoRadius {
        /// Number of nodes that violate Condition 1 at the last `c` tried.
        points: usize,
        /// The last `c` tried.
        c: f64,
    },
    /// An interpolation was requested without source nodes.
    #[error("no source nodes to interpolate from")]
    NoSources,
    /// The number of radii differs from the number of source nodes.
    #[error("{radii} radii given for {sources} source nodes")]
    LengthMismatch {
        /// Number of source nodes.
        sources: usize,
        /// Number of radii.
        radii: usize,
    },
    /// A support radius is not positive and finite.
    #[error("support radius {radius} of source node {index} is not positive and finite")]
    InvalidRadius {
        /// Index of the source node.
        index: usize,
        /// The offending radius.
        radius: f64,
    },
    /// A solve with `Phi_MM` failed: GMRES stopped short and the whole matrix could not be
    /// factored, a patch's matrix could not be factored although it held every source its
    /// graph reaches, or a solve gave a non-finite value.
    #[error("the RBF matrix Phi_MM is singular: {detail}")]
    SingularPhi {
        /// What failed.
        detail: String,
    },
    /// The ranks sharing the interpolation could not exchange their rows' values.
    #[error("sharing the interpolation among the ranks: {0}")]
    Ranks(String),
    /// The k-d tree could not be built (more than `u32::MAX` points).
    #[error("k-d tree construction failed: {0}")]
    KdTree(#[from] kiddo::kd_tree::ConstructionError),
}

/// Wendland C2 radial basis function: `phi(delta) = (1 - delta)^4_+ (1 + 4 delta)`
/// for `delta >= 0`. It is `1` at `0`, vanishes with its first and second derivatives at `1` and is
/// zero beyond.
pub fn wendland_c2(delta: f64) -> f64 {
    if delta >= 1.0 {
        0.0
    } else {
        let t = 1.0 - delta;
        let t2 = t * t;
        t2 * t2 * (1.0 + 4.0 * delta)
    }
}

/// Support radii of a node set by Algorithm 1 (`docs/method.md`, section 2.2).
///
/// With `d_i` the distance from node `i` to its nearest other node, the radii are `r_i = d_i / c`
/// for the smallest `c` of the sequence `0.5, 0.75, 0.875, 0.9375` (`c <- (1 + c) / 2`, bounded by
/// [`C_MAX`]) such that every node satisfies Condition 1:
/// `n_i = #{j != i : |xi_i - xi_j| < r_i} < 1 / phi(c)`. Condition 2 (`|xi_i - xi_j| >= c r_j`)
/// holds by construction. Together they make `Phi_MM` strictly column diagonally dominant (column
/// `j` has fewer than `1 / phi(c)` off-diagonal entries, each at most `phi(c)`), hence invertible.
///
/// An empty set gives no radii. A single node has no neighbour and gives
/// [`RbfError::SingleNode`]. Coincident nodes
/// give [`RbfError::CoincidentNodes`]; if `c` would exceed `C_MAX` the result is
/// [`RbfError::NoRadius`].
pub fn support_radii(points: &[[f64; 3]]) -> Result<Vec<f64>, RbfError> {
    check_finite(points)?;
    match points.len() {
        0 => return Ok(Vec::new()),
        1 => return Err(RbfError::SingleNode),
        _ => {}
    }
    let tree = ImmutableKdTree::<f64, 3>::new_from_slice(points)?;
    let nearest = nearest_other_distances(&tree, points)?;
    let mut c = C_START;
    loop {
        let bound = 1.0 / wendland_c2(c);
        let radii: Vec<f64> = nearest.iter().map(|d| d / c).collect();
        let violating = points
            .iter()
            .zip(&radii)
            .enumerate()
            .filter(|&(i, (p, &r))| {
                let n_i = tree
                    .query(p)
                    .within::<SquaredEuclidean<f64>>(r * r)
                    .unsorted()
                    .execute()
                    .into_iter()
                    .filter(|hit| {
                        hit.item as usize != i && distance(p, &points[hit.item as usize]) < r
                    })
                    .count();
                n_i as f64 >= bound
            })
            .count();
        if violating == 0 {
            return Ok(radii);
        }
        let next = 0.5 * (1.0 + c);
        if next > C_MAX {
            return Err(RbfError::NoRadius {
                points: violating,
                c,
            });
        }
        c = next;
    }
}

/// Support radii for the transfer operators: `r_i = radius * d_i`, `d_i` the distance from
/// node `i` to its nearest other node.
///
/// This is the form of Algorithm 1 (`r_i = d_i / c`, one `c` for all nodes) with `c` held
/// at `1 / radius` instead of raised until Condition 1 holds. With the default `radius = 2`,
/// `c` stays at the value Algorithm 1 starts from, 0.5. On a curve (2D) Condition 1 holds there
/// already, so the radii are Algorithm 1's. On a triangulated surface (3D) a node has more than
/// five neighbours within `2 d_i`, so Algorithm 1 raises `c` to 0.75 and returns `r_i = 1.33
/// d_i`: a target point then sees little more than its nearest source node, and even a linear
/// field is interpolated with an error of a sizeable fraction of `h`. Every nodal gap of a
/// contact solve carries that error, and the pressure answers it with `E* / h` per unit gap, so
/// the pressure noise does not fall with `h`.
///
/// On the 3D Hertz test mesh a linear field interpolated between the two contact surfaces is
/// off by up to 0.19-0.21 h with Algorithm 1's radii and 0.041-0.065 h with `radius = 2`
/// (`tests/interpolation.rs`); larger supports (8/3) did no better, and on graded or
/// overlapping meshes reach from targets into regions their sources do not represent.
///
/// Radii above Algorithm 1's give up its diagonal-dominance guarantee: the sparse LU of
/// `Phi_MM` and the positivity of every rescaling factor are still checked in
/// [`Interpolation::new`].
pub fn interpolation_radii(points: &[[f64; 3]], radius: f64) -> Result<Vec<f64>, RbfError> {
    Ok(nearest_distances(points)?
        .into_iter()
        .map(|d| d * radius)
        .collect())
}

/// Rescaled localized RBF interpolation `R_NM = D_NN^-1 Phi_NM Phi_MM^-1` from source nodes with
/// support radii to target points.
///
/// Holds the rows of `Phi_MM` and `Phi_NM` of its share (`rbf_patch::BlockShare`: every row on
/// one process) and `D_NN^-1`; any other row of either matrix, and the graph of `Phi_MM`, it
/// computes when it needs them, from the points and k-d trees (`Sources`). `R_NM` (dense in
/// general) is never formed, except on request by [`Interpolation::matrix`], and `Phi_MM` is
/// not factored where GMRES serves. Two kinds of solve with `Phi_MM`:
///
/// * **Whole fields** ([`Interpolation::apply`], and `D_NN` itself): GMRES on `Phi_MM`, stopped
///   at a residual of [`SOLVE_TOL`] of the right-hand side. Wendland's matrix with the radii of
///   [`interpolation_radii`] at their default is well conditioned (`docs/method.md` 2.2), so the
///   solve costs a few dozen sparse products and keeps nothing but its Krylov vectors while it
///   runs. Where GMRES stops short (wide supports), the whole `Phi_MM` is factored by sparse LU
///   and that factor serves every solve after (`rbf_patch::WholeFactor`).
/// * **Rows and columns of `R`** ([`Interpolation::rows`], [`Interpolation::columns`]): each
///   from a solve on a patch of sources around it (`rbf_patch.rs`), since the entries of
///   `Phi_MM^-1` decay exponentially with the number of steps in `Phi_MM`'s graph.
///
/// Why not the whole factor always: its fill is many times `Phi_MM`'s nonzeros and grows
/// faster than the surface, every rank of a distributed run held it, and each row cost a solve
/// with all of it; a patch's solve costs the same on any surface.
///
/// **Shared among ranks.** Built with a share of `N > 1` ranks, rank `r` holds the rows of
/// `Phi_MM` of the `r`-th of `N` consecutive ranges of sources and the rows of `Phi_NM` of the
/// `r`-th range of targets, and each product of a whole-field GMRES is every rank's rows
/// gathered on every rank (`MPI_Allgatherv` of `M` values); `D_NN` and an applied field are
/// gathered the same way. Every rank then runs the same GMRES on the same numbers, the
/// serial one's, bit for bit: a row is summed in the same order wherever it is computed. So
/// [`Interpolation::shared`] and [`Interpolation::apply`] are collective. Why not whole on
/// every rank: `Phi_MM`, `Phi_NM` and `Phi_MM`'s graph took about 0.7 KB per candidate node,
/// on every rank, where the points and the tree take about 0.1 KB (`docs/parallel.md`).
#[derive(Debug)]
pub struct Interpolation {
    /// The sources and their radii: any row of `Phi_MM` or `Phi_NM`, on demand.
    sources: Sources,
    /// Where the targets lie: the order in which rows are computed in blocks of nearby ones.
    targets: Vec<[f64; 3]>,
    /// The rows this process holds and how the ranks share them.
    held: HeldRows,
    /// `1 / D_ii` for covered targets, `0` for uncovered ones.
    inv_d: Vec<f64>,
    /// Targets with `D_ii` not clearly positive (see [`UNCOVERED_TOL`]).
    uncovered: Vec<usize>,
    /// The whole `Phi_MM`'s sparse LU, factored only where a solve needs it
    /// (`rbf_patch::WholeFactor`).
    whole: patch::WholeFactor,
}

/// The source nodes, their radii and k-d trees over them: any row of the RBF matrices
/// (`(Phi)_tj = phi(|x_t - xi_j| / r_j)` against every source `j`), and node `i`'s row of
/// `Phi_MM` with its neighbours in the graph of `Phi_MM`, for a patch ([`PatchMatrix`]).
#[derive(Debug)]
struct Sources {
    points: Vec<[f64; 3]>,
    radii: Vec<f64>,
    /// The sources by their radii ([`RadiusClass`]).
    classes: Vec<RadiusClass>,
}

/// The sources whose radii lie within a factor of two of each other (`[2^k, 2^(k + 1))` times
/// the smallest), in a k-d tree of their own. Why not one tree searched to the largest radius:
/// on a graded surface the coarse far field's radii are many times the contact zone's, and a
/// search to them from a node of the zone returns many times the sources its row holds,
/// which the patches, computing their rows by search, pay for every node
/// (`docs/decisions.md`, 2026-12-07, night); searched class by class to the class's largest
/// radius, a search reaches at most twice as far as the row it serves.
#[derive(Debug)]
struct RadiusClass {
    largest: f64,
    /// Source index of each of the tree's items.
    members: Vec<usize>,
    tree: ImmutableKdTree<f64, 3>,
}

impl Sources {
    fn new(points: &[[f64; 3]], radii: &[f64]) -> Result<Self, RbfError> {
        let smallest = radii.iter().copied().fold(f64::INFINITY, f64::min);
        let class_of = |r: f64| (r / smallest).log2().floor().max(0.0) as usize;
        let count = radii.iter().map(|&r| class_of(r) + 1).max().unwrap_or(0);
        let mut members = vec![Vec::new(); count];
        for (j, &r) in radii.iter().enumerate() {
            members[class_of(r)].push(j);
        }
        let classes = (members.into_iter())
            .filter(|members| !members.is_empty())
            .map(|members| {
                let at: Vec<[f64; 3]> = members.iter().map(|&j| points[j]).collect();
                Ok(RadiusClass {
                    largest: members.iter().map(|&j| radii[j]).fold(0.0, f64::max),
                    tree: ImmutableKdTree::<f64, 3>::new_from_slice(&at)?,
                    members,
                })
            })
            .collect::<Result<_, RbfError>>()?;
        Ok(Self {
            points: points.to_vec(),
            radii: radii.to_vec(),
            classes,
        })
    }

    /// The sources within `max(r_j, reach)` of `point`, and more, with `|point - xi_j|`:
    /// every source of `point`'s row (`reach = 0`), unsorted.
    fn within_reach<'a>(
        &'a self,
        point: &'a [f64; 3],
        reach: f64,
    ) -> impl Iterator<Item = (usize, f64)> + 'a {
        self.classes.iter().flat_map(move |class| {
            let radius = class.largest.max(reach);
            let hits = (class.tree.query(point))
                .within::<SquaredEuclidean<f64>>(search_radius_squared(radius))
                .unsorted()
                .execute();
            hits.into_iter().map(move |hit| {
                let j = class.members[hit.item as usize];
                (j, distance(point, &self.points[j]))
            })
        })
    }

    /// The row of `point`: `(j, phi(|point - xi_j| / r_j))` for the sources whose support
    /// holds it, the columns increasing.
    fn row(&self, point: &[f64; 3]) -> Entries {
        let mut row: Entries = (self.within_reach(point, 0.0))
            .filter_map(|(j, d)| {
                let delta = d / self.radii[j];
                (delta < 1.0).then(|| (j, wendland_c2(delta)))
            })
            .collect();
        row.sort_unstable_by_key(|&(j, _)| j);
        row
    }

    /// The rows of `points`, in compressed rows over every source.
    fn rows(&self, points: &[[f64; 3]]) -> CompressedRows {
        let mut offsets = Vec::with_capacity(points.len() + 1);
        offsets.push(0);
        let (mut cols, mut vals) = (Vec::new(), Vec::new());
        for p in points {
            for (j, v) in self.row(p) {
                cols.push(j);
                vals.push(v);
            }
            offsets.push(cols.len());
        }
        let symbolic =
            SymbolicSparseRowMat::new_checked(points.len(), self.points.len(), offsets, None, cols);
        CompressedRows::new(symbolic, vals)
    }
}

impl PatchMatrix for Sources {
    fn len(&self) -> usize {
        self.points.len()
    }

    /// Row `i` of `Phi_MM` and the sources `j != i` either of whose supports holds the other
    /// (`|xi_i - xi_j| < r_j`: `j` in row `i`; `< r_i`: `i` in row `j`), from one radius search.
    fn node(&self, i: usize) -> PatchNode {
        let point = &self.points[i];
        let (mut row, mut neighbours) = (Vec::new(), Vec::new());
        for (j, d) in self.within_reach(point, self.radii[i]) {
            let delta = d / self.radii[j];
            if delta < 1.0 {
                row.push((j, wendland_c2(delta)));
            }
            if j != i && (delta < 1.0 || d / self.radii[i] < 1.0) {
                neighbours.push(j);
            }
        }
        row.sort_unstable_by_key(|&(j, _)| j);
        neighbours.sort_unstable();
        PatchNode { row, neighbours }
    }
}

/// The rows of `Phi_MM` and `Phi_NM` one process holds: those of its share's ranges of sources
/// and targets ([`Interpolation`]'s doc), with every rank's number of them.
#[derive(Debug)]
struct HeldRows {
    sources: Range<usize>,
    targets: Range<usize>,
    /// The held rows of `Phi_MM` (row `k` is source `sources.start + k`).
    phi_mm: CompressedRows,
    /// The held rows of `Phi_NM` (row `k` is target `targets.start + k`).
    phi_nm: CompressedRows,
    /// Each rank's number of sources and of targets.
    source_counts: Vec<usize>,
    target_counts: Vec<usize>,
}

/// The `rank`-th of `size` consecutive ranges of `0..len`, as even as can be.
fn range_of(len: usize, rank: usize, size: usize) -> Range<usize> {
    len * rank / size..len * (rank + 1) / size
}

/// Every rank's values, each rank's `local` ones (`counts[r]` from rank `r`), on every rank.
fn gathered(local: Vec<f64>, counts: &[usize]) -> Result<Vec<f64>, RbfError> {
    match counts.len() {
        1 => Ok(local),
        _ => {
            crate::parallel::all_gather(&local, counts).map_err(|e| RbfError::Ranks(e.to_string()))
        }
    }
}

/// The whole-field solves with `Phi_MM` stop at a residual of this fraction of the right-hand
/// side's. With `Phi_MM`'s condition number about 6, the solution is then within a few
/// `1e-15` of the exact one, the round-off of a direct solve.
pub const SOLVE_TOL: f64 = 1e-15;

/// GMRES on `Phi_MM` with no preconditioner (its diagonal is one): each rank's held rows, the
/// product gathered.
struct PhiOperator<'a>(&'a HeldRows);

impl gmres::Operators for PhiOperator<'_> {
    type Error = RbfError;
    fn apply(&mut self, x: &[f64], out: &mut [f64]) -> Result<(), Self::Error> {
        let held = self.0;
        let local: Vec<f64> = (0..held.sources.len())
            .map(|k| row_entries(&held.phi_mm, k).map(|(j, v)| v * x[j]).sum())
            .collect();
        out.copy_from_slice(&gathered(local, &held.source_counts)?);
        Ok(())
    }
    fn precondition(&mut self, r: &[f64], out: &mut [f64]) -> Result<(), Self::Error> {
        out.copy_from_slice(r);
        Ok(())
    }
}

impl Interpolation {
    /// [`Self::shared`] on one process: every row held.
    pub fn new(
        sources: &[[f64; 3]],
        radii: &[f64],
        targets: &[[f64; 3]],
    ) -> Result<Self, RbfError> {
        Self::shared(sources, radii, targets, BlockShare::ALL)
    }

    /// Assembles this process's rows of `Phi_MM` and `Phi_NM` (those of `share`: the type's
    /// doc) with a k-d tree radius search and computes `D_NN = diag(Phi_NM Phi_MM^-1 1)`.
    /// Collective with a share of several ranks.
    ///
    /// Targets whose `D_ii` is not clearly positive (outside every source support; threshold
    /// [`UNCOVERED_TOL`]) do not make it fail: their row of `R` is zero and they are listed by
    /// [`Interpolation::uncovered_targets`].
    ///
    /// Cost: one radius search per held source and target (radius `max_j r_j`) and one GMRES
    /// solve with `Phi_MM`.
    pub fn shared(
        sources: &[[f64; 3]],
        radii: &[f64],
        targets: &[[f64; 3]],
        share: BlockShare,
    ) -> Result<Self, RbfError> {
        if sources.is_empty() {
            return Err(RbfError::NoSources);
        }
        if radii.len() != sources.len() {
            return Err(RbfError::LengthMismatch {
                sources: sources.len(),
                radii: radii.len(),
            });
        }
        if let Some((index, &radius)) = radii
            .iter()
            .enumerate()
            .find(|&(_, r)| !(r.is_finite() && *r > 0.0))
        {
            return Err(RbfError::InvalidRadius { index, radius });
        }
        check_finite(sources)?;
        check_finite(targets)?;
        let (m, n) = (sources.len(), targets.len());
        let sources = Sources::new(sources, radii)?;
        let (rank, size) = (share.rank, share.size);
        let (held_sources, held_targets) = (range_of(m, rank, size), range_of(n, rank, size));
        let held = HeldRows {
            phi_mm: sources.rows(&sources.points[held_sources.clone()]),
            phi_nm: sources.rows(&targets[held_targets.clone()]),
            sources: held_sources,
            targets: held_targets,
            source_counts: (0..size).map(|r| range_of(m, r, size).len()).collect(),
            target_counts: (0..size).map(|r| range_of(n, r, size).len()).collect(),
        };
        let mut interpolation = Self {
            sources,
            targets: targets.to_vec(),
            held,
            inv_d: Vec::new(),
            uncovered: Vec::new(),
            whole: patch::WholeFactor::new(),
        };

        // y = Phi_MM^-1 1; each held target's 1 / D_ii and whether it is covered.
        let y = interpolation.solve(&vec![1.0; m])?;
        let held = &interpolation.held;
        let mut local = Vec::with_capacity(2 * held.targets.len());
        for k in 0..held.targets.len() {
            let (sum, magnitude) = row_entries(&held.phi_nm, k)
                .fold((0.0, 0.0), |(s, a), (j, v)| {
                    (s + v * y[j], a + v * y[j].abs())
                });
            let covered = sum > UNCOVERED_TOL * magnitude;
            local.extend([if covered { 1.0 / sum } else { 0.0 }, f64::from(covered)]);
        }
        let counts: Vec<usize> = held.target_counts.iter().map(|c| 2 * c).collect();
        let all = gathered(local, &counts)?;
        interpolation.inv_d = all.iter().step_by(2).copied().collect();
        interpolation.uncovered = (all.chunks_exact(2).enumerate())
            .filter(|(_, d)| d[1] == 0.0)
            .map(|(t, _)| t)
            .collect();
        Ok(interpolation)
    }

    /// `Phi_MM^-1 b`: by GMRES ([`SOLVE_TOL`]), or with the whole factor where it exists or
    /// GMRES stops short of its tolerance (wide supports make `Phi_MM` ill-conditioned: with
    /// `rbf_radius = 10` on the 3D hemisphere's surfaces GMRES is still at `3e-6` after 200
    /// products). A matrix that cannot be factored then is [`RbfError::SingularPhi`], with why
    /// GMRES stopped. Collective with a share of several ranks (each product is).
    fn solve(&self, b: &[f64]) -> Result<Vec<f64>, RbfError> {
        let m = b.len();
        let with_factor = |lu: &faer::sparse::linalg::solvers::Lu<usize, f64>| {
            let mut x = b.to_vec();
            lu.solve_in_place(faer::MatMut::from_column_major_slice_mut(&mut x, m, 1));
            x
        };
        if let Some(Ok(lu)) = self.whole.get() {
            return finite(with_factor(lu));
        }
        let mut x = vec![0.0; m];
        let settings = gmres::GmresSettings {
            tolerance: SOLVE_TOL * gmres::norm(b),
            reduction: None,
            max_iterations: MAX_SOLVE_ITERATIONS,
            restart: MAX_SOLVE_ITERATIONS,
        };
        let stats = gmres::solve(&mut PhiOperator(&self.held), b, &mut x, settings)?;
        let Some(failure) = stats.failure else {
            return Ok(x);
        };
        // Every rank gets here together (the same GMRES on the same numbers), and each
        // factors the whole matrix: the rare case of supports too wide for GMRES.
        let whole_rows;
        let phi_mm = match self.held.sources.len() == m {
            true => &self.held.phi_mm,
            false => {
                whole_rows = self.sources.rows(&self.sources.points);
                &whole_rows
            }
        };
        match patch::whole_factor(phi_mm, &self.whole) {
            Ok(lu) => finite(with_factor(lu)),
            Err(detail) => Err(RbfError::SingularPhi {
                detail: format!(
                    "GMRES {failure} after {} iterations (residual {:.1e} of the right-hand \
                     side's), and {detail}",
                    stats.iterations,
                    stats.residual / stats.initial_residual
                ),
            }),
        }
    }

    /// Number of source nodes `M`.
    pub fn num_sources(&self) -> usize {
        self.sources.points.len()
    }

    /// Number of target points `N`.
    pub fn num_targets(&self) -> usize {
        self.inv_d.len()
    }

    /// Row `t` of `Phi_NM`: held, or computed.
    fn target_row(&self, t: usize) -> Entries {
        match self.held.targets.contains(&t) {
            true => row_entries(&self.held.phi_nm, t - self.held.targets.start).collect(),
            false => self.sources.row(&self.targets[t]),
        }
    }

    /// Interpolates a field with `components` values per source node, interleaved
    /// (`values[j * components + k]`), to the targets: returns `R_NM g` in the same interleaved
    /// layout (`N * components` values). Rows of uncovered targets are zero. Collective with a
    /// share of several ranks.
    ///
    /// Cost: one GMRES solve with `Phi_MM` per component and one product with `Phi_NM`.
    ///
    /// # Panics
    /// If `values.len() != num_sources() * components`.
    pub fn apply(&self, values: &[f64], components: usize) -> Result<Vec<f64>, RbfError> {
        let m = self.num_sources();
        assert_eq!(
            values.len(),
            m * components,
            "expected {components} values for each of the {m} source nodes"
        );
        let solved: Vec<Vec<f64>> = (0..components)
            .map(|k| {
                let g: Vec<f64> = values.iter().skip(k).step_by(components).copied().collect();
                self.solve(&g)
            })
            .collect::<Result<_, _>>()?;
        let held = &self.held;
        let mut local = vec![0.0; held.targets.len() * components];
        for (k, row) in local.chunks_exact_mut(components).enumerate() {
            let t = held.targets.start + k;
            for (c, x) in solved.iter().enumerate() {
                let value: f64 = row_entries(&held.phi_nm, k).map(|(j, v)| v * x[j]).sum();
                row[c] = self.inv_d[t] * value;
            }
        }
        let counts: Vec<usize> = held.target_counts.iter().map(|c| c * components).collect();
        gathered(local, &counts)
    }

    /// The dense `N x M` interpolation matrix `R_NM`, column by column ([`Self::apply`] of
    /// each unit vector). Costs `M` solves and `N * M` memory: meant for small interfaces and
    /// tests.
    pub fn matrix(&self) -> Result<nalgebra::DMatrix<f64>, RbfError> {
        let (n, m) = (self.num_targets(), self.num_sources());
        let mut r = nalgebra::DMatrix::zeros(n, m);
        let mut unit = vec![0.0; m];
        for j in 0..m {
            unit[j] = 1.0;
            r.set_column(j, &nalgebra::DVector::from_vec(self.apply(&unit, 1)?));
            unit[j] = 0.0;
        }
        Ok(r)
    }

    /// Rows `targets` of `R_NM`, each as its entries `(source, weight)` with `|weight| >`
    /// [`DROP_TOL`]: `R[t, :] = D_tt^-1 z_t` with `Phi_MM^T z_t =
    /// Phi_NM[t, :]^T`, solved on a patch around the row's sources (`rbf_patch.rs`), nearby
    /// rows together. `D_tt` is the sum of `z_t` (`Phi_NM[t, :] Phi_MM^-1 1`), so that each row
    /// sums to one to round-off. A solve on a patch that fails is [`RbfError::SingularPhi`].
    pub fn rows(&self, targets: &[usize]) -> Result<Vec<Entries>, RbfError> {
        let rows = self.rows_of_share(targets, BlockShare::ALL)?;
        Ok(rows.into_iter().map(Option::unwrap_or_default).collect())
    }

    /// [`Self::rows`] of the blocks of nearby rows that `share` gives this process
    /// (`rbf_patch::in_blocks`), `None` for the others; an uncovered target's empty row is
    /// everyone's. Not collective: any process can compute any row.
    pub fn rows_of_share(
        &self,
        targets: &[usize],
        share: BlockShare,
    ) -> Result<Vec<Option<Entries>>, RbfError> {
        let covered: Vec<usize> = (targets.iter().copied())
            .filter(|&t| self.inv_d[t] != 0.0)
            .collect();
        if covered.is_empty() {
            // Nothing to solve (an iteration whose rows are all known): no cache to make.
            return Ok(targets.iter().map(|_| Some(Vec::new())).collect());
        }
        let nodes = NodeCache::new(&self.sources);
        let solved = patch::in_blocks(&self.targets, &covered, share, |block| {
            let rows: Vec<Entries> = block.iter().map(|&t| self.target_row(t)).collect();
            let seeds: Vec<usize> = (rows.iter())
                .flat_map(|row| row.iter().map(|&(j, _)| j))
                .collect();
            let right_hand_side = |k: usize, set: &mut dyn FnMut(usize, f64)| {
                rows[k].iter().for_each(|&(j, v)| set(j, v))
            };
            let solution = patch::solve(
                &nodes,
                &self.whole,
                &seeds,
                block.len(),
                true,
                right_hand_side,
            )
            .map_err(|detail| RbfError::SingularPhi { detail })?;
            Ok::<_, RbfError>(
                (0..block.len())
                    .map(|k| {
                        let z = solution.values(k);
                        let scale = 1.0 / z.iter().sum::<f64>();
                        let entries =
                            (solution.nodes.iter().copied()).zip(z.iter().map(|v| scale * v));
                        sparse(entries)
                    })
                    .collect(),
            )
        })?;
        // The uncovered targets' rows are empty.
        let mut solved = solved.into_iter();
        Ok((targets.iter())
            .map(|&t| match self.inv_d[t] != 0.0 {
                true => solved.next().flatten(),
                false => Some(Vec::new()),
            })
            .collect())
    }

    /// Columns `sources` of `R_NM`, each as its entries `(target, weight)` with `|weight| >`
    /// [`DROP_TOL`]: `R[:, j] = D^-1 Phi_NM x_j` with `Phi_MM x_j
    /// = e_j`, solved on a patch around source `j` (`rbf_patch.rs`), nearby columns together.
    /// A solve on a patch that fails is [`RbfError::SingularPhi`].
    pub fn columns(&self, sources: &[usize]) -> Result<Vec<Entries>, RbfError> {
        let columns = self.columns_of_share(sources, BlockShare::ALL)?;
        Ok(columns.into_iter().map(Option::unwrap_or_default).collect())
    }

    /// [`Self::columns`] of the blocks of nearby columns that `share` gives this process
    /// (`rbf_patch::in_blocks`), `None` for the others. Not collective.
    pub fn columns_of_share(
        &self,
        sources: &[usize],
        share: BlockShare,
    ) -> Result<Vec<Option<Entries>>, RbfError> {
        if sources.is_empty() {
            // An iteration whose columns are all known: no tree or cache to make.
            return Ok(Vec::new());
        }
        // The covered targets each source's support holds (those a patch's solution reaches),
        // by a radius search among the targets; each source's and each target's row once for
        // the whole request, as the patches' nodes ([`NodeCache`]).
        let tree = match self.targets.is_empty() {
            true => None,
            false => Some(ImmutableKdTree::<f64, 3>::new_from_slice(&self.targets)?),
        };
        let reached: Vec<OnceLock<Vec<usize>>> =
            (0..self.num_sources()).map(|_| OnceLock::new()).collect();
        let reached = |j: usize| -> &[usize] {
            reached[j].get_or_init(|| {
                let (point, radius) = (&self.sources.points[j], self.sources.radii[j]);
                let Some(tree) = &tree else {
                    return Vec::new();
                };
                (tree.query(point))
                    .within::<SquaredEuclidean<f64>>(search_radius_squared(radius))
                    .unsorted()
                    .execute()
                    .into_iter()
                    .map(|hit| hit.item as usize)
                    .filter(|&t| {
                        self.inv_d[t] != 0.0 && distance(&self.targets[t], point) / radius < 1.0
                    })
                    .collect()
            })
        };
        let target_rows: Vec<OnceLock<Entries>> =
            (0..self.num_targets()).map(|_| OnceLock::new()).collect();
        let nodes = NodeCache::new(&self.sources);
        patch::in_blocks(&self.sources.points, sources, share, |block| {
            let right_hand_side = |k: usize, set: &mut dyn FnMut(usize, f64)| set(block[k], 1.0);
            let solution = patch::solve(
                &nodes,
                &self.whole,
                block,
                block.len(),
                false,
                right_hand_side,
            )
            .map_err(|detail| RbfError::SingularPhi { detail })?;
            let mut candidates: Vec<usize> = (solution.nodes.iter())
                .flat_map(|&j| reached(j).iter().copied())
                .collect();
            candidates.sort_unstable();
            candidates.dedup();
            let rows: Vec<&Entries> = (candidates.iter())
                .map(|&t| target_rows[t].get_or_init(|| self.target_row(t)))
                .collect();
            Ok((0..block.len())
                .map(|k| {
                    let column = candidates.iter().zip(&rows).map(|(&t, row)| {
                        let value: f64 = row.iter().map(|&(j, v)| v * solution.at(k, j)).sum();
                        (t, self.inv_d[t] * value)
                    });
                    sparse(column)
                })
                .collect())
        })
    }

    /// Targets outside every source support: `D_ii` not clearly positive (see
    /// [`UNCOVERED_TOL`]). Their rows of `R` are zero. Sorted increasingly.
    pub fn uncovered_targets(&self) -> &[usize] {
        &self.uncovered
    }
}

/// A row or column of `R` as its entries `(index, weight)` above [`DROP_TOL`].
pub type Entries = Vec<(usize, f64)>;

/// Entries of `R` at or below this magnitude are dropped from the rows and columns returned by
/// [`Interpolation::rows`] and [`Interpolation::columns`]. Entries of `R` are of order one (its
/// rows sum to one), so the dropped part of a row changes an interpolated value by at most
/// `M * DROP_TOL` of the field's size.
pub const DROP_TOL: f64 = 1e-13;

/// GMRES products a whole-field solve with `Phi_MM` may take before the whole factor is used
/// instead (its Krylov vectors are kept without restart, so this bounds them to 100 values
/// per source): about 35 reach [`SOLVE_TOL`] on the 3D contact surfaces with the default radius.
const MAX_SOLVE_ITERATIONS: usize = 100;

/// `x`, or [`RbfError::SingularPhi`] naming its first non-finite entry.
fn finite(x: Vec<f64>) -> Result<Vec<f64>, RbfError> {
    match x.iter().position(|v| !v.is_finite()) {
        None => Ok(x),
        Some(j) => Err(RbfError::SingularPhi {
            detail: format!("entry {j} of a solve with Phi_MM is not finite"),
        }),
    }
}

/// The entries `(position, value)` above [`DROP_TOL`], sorted
/// by position.
fn sparse(entries: impl Iterator<Item = (usize, f64)>) -> Vec<(usize, f64)> {
    let mut kept: Vec<(usize, f64)> = entries.filter(|&(_, v)| v.abs() > DROP_TOL).collect();
    kept.sort_unstable_by_key(|&(i, _)| i);
    kept
}

/// Euclidean distance.
fn distance(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
}

fn check_finite(points: &[[f64; 3]]) -> Result<(), RbfError> {
    match points.iter().position(|p| p.iter().any(|v| !v.is_finite())) {
        Some(index) => Err(RbfError::NonFinite { index }),
        None => Ok(()),
    }
}

/// Distance from every point to its nearest other point: the nodal spacing `d_i` of
/// Algorithm 1, also the local spacing `h` of the contact tolerances. Needs two or more
/// distinct, finite points.
pub fn nearest_distances(points: &[[f64; 3]]) -> Result<Vec<f64>, RbfError> {
    check_finite(points)?;
    if points.len() < 2 {
        return Err(RbfError::SingleNode);
    }
    let tree = ImmutableKdTree::<f64, 3>::new_from_slice(points)?;
    nearest_other_distances(&tree, points)
}

/// Distance from every point to its nearest other point (at least two points in the tree).
fn nearest_other_distances(
    tree: &ImmutableKdTree<f64, 3>,
    points: &[[f64; 3]],
) -> Result<Vec<f64>, RbfError> {
    let two = NonZeroUsize::MIN.saturating_add(1);
    points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let hits = tree
                .query(p)
                .nearest_n::<SquaredEuclidean<f64>>(two)
                .execute();
            // With coincident points the query point itself need not come first.
            let j = hits
                .iter()
                .map(|hit| hit.item as usize)
                .find(|&j| j != i)
                .ok_or(RbfError::SingleNode)?;
            let d = distance(p, &points[j]);
            if d > 0.0 {
                Ok(d)
            } else {
                Err(RbfError::CoincidentNodes {
                    first: i.min(j),
                    second: i.max(j),
                })
            }
        })
        .collect()
}

/// Squared search radius for the k-d tree, slightly enlarged so that rounding in the tree's
/// distance never drops a node that the exact filter `distance < radius` keeps.
fn search_radius_squared(radius: f64) -> f64 {
    radius * radius * (1.0 + 1e-12)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(n: usize, h: f64) -> Vec<[f64; 3]> {
        (0..n)
            .flat_map(|i| (0..n).map(move |j| [i as f64 * h, j as f64 * h, 0.0]))
            .collect()
    }

    #[test]
    fn wendland_values() {
        assert_eq!(wendland_c2(0.0), 1.0);
        assert_eq!(wendland_c2(1.0), 0.0);
        assert_eq!(wendland_c2(1.5), 0.0);
        assert_eq!(wendland_c2(1e3), 0.0);
        // (1 - 0.5)^4 (1 + 2) = 3 / 16
        assert!((wendland_c2(0.5) - 3.0 / 16.0).abs() < 1e-15);
        // Monotone decreasing on [0, 1].
        let samples: Vec<f64> = (0..=100).map(|k| wendland_c2(k as f64 / 100.0)).collect();
        assert!(samples.windows(2).all(|w| w[1] <= w[0]));
    }

    #[test]
    fn wendland_is_c2_at_one() {
        // phi, phi' and phi'' vanish as delta -> 1-: phi = O(e^4), phi' = O(e^3), phi'' = O(e^2).
        let h = 1e-3;
        for e in [1e-2, 1e-3] {
            let d = 1.0 - e;
            let f = |x: f64| wendland_c2(x);
            let d1 = (f(d + h * e) - f(d - h * e)) / (2.0 * h * e);
            let d2 = (f(d + h * e) - 2.0 * f(d) + f(d - h * e)) / (h * e * h * e);
            assert!(f(d) < 6.0 * e.powi(4));
            assert!(d1.abs() < 25.0 * e.powi(3), "phi'({d}) = {d1}");
            assert!(d2.abs() < 80.0 * e.powi(2), "phi''({d}) = {d2}");
        }
        // Exact derivatives phi' = -20 delta (1 - delta)^3, phi'' = 20 (1 - delta)^2 (4 delta - 1)
        // checked against differences in the interior.
        let d = 0.3;
        let fd1 = (wendland_c2(d + 1e-6) - wendland_c2(d - 1e-6)) / 2e-6;
        assert!((fd1 + 20.0 * d * (1.0f64 - d).powi(3)).abs() < 1e-8);
    }

    #[test]
    fn radii_on_uniform_grid_are_equal_and_satisfy_condition_1() {
        let h = 0.125; // exact in binary: all distances between grid points are exact multiples
        let points = grid(9, h);
        let radii = support_radii(&points).expect("radii on a grid");
        assert_eq!(radii.len(), points.len());
        assert!(radii.iter().all(|&r| r == radii[0]), "{radii:?}");
        // r = d / c with d = h.
        let c = h / radii[0];
        assert!((C_START..=C_MAX).contains(&c));
        let bound = 1.0 / wendland_c2(c);
        for (i, p) in points.iter().enumerate() {
            let n_i = points
                .iter()
                .enumerate()
                .filter(|&(j, q)| j != i && distance(p, q) < radii[i])
                .count();
            assert!(
                (n_i as f64) < bound,
                "node {i}: {n_i} neighbours, bound {bound}"
            );
            // Condition 2.
            for (j, q) in points.iter().enumerate() {
                if j != i {
                    assert!(distance(p, q) >= c * radii[j]);
                }
            }
        }
        // On a 2D grid c = 0.5 gives r = 2h with 8 neighbours inside (>= 1/phi(0.5) = 5.33),
        // so Algorithm 1 must have moved on to c = 0.75 (4 neighbours < 64).
        assert_eq!(c, 0.75);
    }

    #[test]
    fn radii_errors() {
        assert!(support_radii(&[]).expect("empty").is_empty());
        assert!(matches!(
            support_radii(&[[0.0; 3]]),
            Err(RbfError::SingleNode)
        ));
        assert!(matches!(
            support_radii(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0; 3]]),
            Err(RbfError::CoincidentNodes {
                first: 0,
                second: 2
            })
        ));
        assert!(matches!(
            support_radii(&[[0.0; 3], [f64::NAN, 0.0, 0.0]]),
            Err(RbfError::NonFinite { index: 1 })
        ));
    }

    #[test]
    fn sparse_phi_mm_matches_dense() {
        // Irregular 3D points on a sphere cap with their Algorithm 1 radii.
        let points: Vec<[f64; 3]> = (0..40)
            .map(|k| {
                let t = 0.15 * k as f64;
                let (theta, psi) = (0.6 * (k as f64 * 0.37).sin().abs(), t);
                [
                    theta.sin() * psi.cos(),
                    theta.sin() * psi.sin(),
                    theta.cos(),
                ]
            })
            .collect();
        let radii = support_radii(&points).expect("radii");
        let phi = cap_sources(&points, &radii).rows(&points);
        let m = points.len();
        let mut sparse = vec![0.0; m * m];
        for i in 0..m {
            for (j, v) in row_entries(&phi, i) {
                sparse[i * m + j] = v;
            }
        }
        let mut off_diagonal = 0;
        for i in 0..m {
            for j in 0..m {
                let dense = wendland_c2(distance(&points[i], &points[j]) / radii[j]);
                assert_eq!(sparse[i * m + j], dense, "entry ({i}, {j})");
                if i != j && dense > 0.0 {
                    off_diagonal += 1;
                }
            }
        }
        assert!(off_diagonal > 0, "the test set must couple some nodes");
        // Column diagonal dominance from Conditions 1 and 2.
        for j in 0..m {
            let col: f64 = (0..m).filter(|&i| i != j).map(|i| sparse[i * m + j]).sum();
            assert!(col < 1.0, "column {j}: off-diagonal sum {col}");
        }
    }

    fn cap_sources(points: &[[f64; 3]], radii: &[f64]) -> Sources {
        Sources::new(points, radii).expect("trees")
    }

    #[test]
    fn a_patch_node_is_its_row_of_phi_mm_and_its_neighbours_in_the_graph() {
        // A graded, uneven spacing: radii of several classes, and pairs that hold each other
        // one way only.
        let points: Vec<[f64; 3]> = (0..60)
            .map(|k| {
                let x = 0.02 * (1.06f64.powi(k) - 1.0) / 0.06;
                [x, 0.2 * x * (k as f64 * 0.9).cos(), 0.0]
            })
            .collect();
        let radii = interpolation_radii(&points, 2.5).unwrap();
        let sources = cap_sources(&points, &radii);
        assert!(
            sources.classes.len() > 2,
            "{} radius classes",
            sources.classes.len()
        );
        let phi = sources.rows(&points);
        let (mut one_way, m) = (0, points.len());
        for i in 0..m {
            let node = sources.node(i);
            assert_eq!(
                node.row,
                row_entries(&phi, i).collect::<Vec<_>>(),
                "row {i}"
            );
            // The pattern of Phi_MM + Phi_MM^T without the diagonal, from the whole matrix.
            let expected: Vec<usize> = (0..m)
                .filter(|&j| {
                    let in_row = |a: usize, b: usize| row_entries(&phi, a).any(|(c, _)| c == b);
                    j != i && (in_row(i, j) || in_row(j, i))
                })
                .collect();
            one_way += (expected.iter())
                .filter(|&&j| !row_entries(&phi, i).any(|(c, _)| c == j))
                .count();
            assert_eq!(node.neighbours, expected, "neighbours of {i}");
        }
        assert!(one_way > 0, "the test set must have one-way pairs");
    }

    #[test]
    fn uncovered_target_gets_zero_row() {
        let sources: Vec<[f64; 3]> = (0..5).map(|k| [k as f64 * 0.25, 0.0, 0.0]).collect();
        let radii = support_radii(&sources).expect("radii");
        let targets = [[0.3, 0.0, 0.0], [10.0, 0.0, 0.0], [0.9, 0.01, 0.0]];
        let interp = Interpolation::new(&sources, &radii, &targets).expect("interpolation");
        assert_eq!(interp.uncovered_targets(), &[1]);
        let r = interp.matrix().expect("matrix");
        assert!(r.row(1).iter().all(|&v| v == 0.0));
        for t in [0, 2] {
            assert!((r.row(t).sum() - 1.0).abs() < 1e-14);
        }
        let out = interp.apply(&[2.0; 5], 1).expect("apply");
        assert_eq!(out[1], 0.0);
        assert!((out[0] - 2.0).abs() < 1e-14 && (out[2] - 2.0).abs() < 1e-14);
    }

    #[test]
    fn interpolation_input_errors() {
        let s = [[0.0; 3], [1.0, 0.0, 0.0]];
        assert!(matches!(
            Interpolation::new(&[], &[], &s),
            Err(RbfError::NoSources)
        ));
        assert!(matches!(
            Interpolation::new(&s, &[1.0], &s),
            Err(RbfError::LengthMismatch {
                sources: 2,
                radii: 1
            })
        ));
        assert!(matches!(
            Interpolation::new(&s, &[1.0, 0.0], &s),
            Err(RbfError::InvalidRadius { index: 1, .. })
        ));
    }

    #[test]
    fn rows_and_columns_computed_in_shares_are_the_whole_ones_each_computed_once() {
        // A 20 x 20 grid of sources and a shifted 18 x 18 grid of targets: several blocks of
        // rows and of columns, shared among three ranks as a distributed run shares them.
        let sources = grid(20, 0.05);
        let targets: Vec<[f64; 3]> = (grid(18, 0.05).iter())
            .map(|p| [p[0] + 0.031, p[1] + 0.017, 0.0])
            .collect();
        let radii = interpolation_radii(&sources, 2.0).unwrap();
        let r = Interpolation::new(&sources, &radii, &targets).unwrap();
        let all_targets: Vec<usize> = (0..targets.len()).collect();
        let all_sources: Vec<usize> = (0..sources.len()).collect();
        let whole = [
            r.rows(&all_targets).unwrap(),
            r.columns(&all_sources).unwrap(),
        ];
        let shares: Vec<[Vec<Option<Entries>>; 2]> = (0..3)
            .map(|rank| {
                let share = BlockShare { rank, size: 3 };
                [
                    r.rows_of_share(&all_targets, share).unwrap(),
                    r.columns_of_share(&all_sources, share).unwrap(),
                ]
            })
            .collect();
        for (kind, whole) in whole.iter().enumerate() {
            assert!(whole.len() > 2 * patch::BLOCK, "more than two blocks");
            for (k, entries) in whole.iter().enumerate() {
                let computed: Vec<&Entries> = (shares.iter())
                    .filter_map(|share| share[kind][k].as_ref())
                    .collect();
                assert_eq!(computed.len(), 1, "row or column {k} computed once");
                assert_eq!(computed[0], entries);
            }
            let per_rank: Vec<usize> = (shares.iter())
                .map(|share| share[kind].iter().flatten().count())
                .collect();
            assert!(
                per_rank.iter().all(|&n| n > 0),
                "every rank computes some: {per_rank:?}"
            );
        }
    }
}
