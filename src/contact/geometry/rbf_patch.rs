//! Solves with the RBF matrix `Phi_MM` restricted to a patch of source nodes: the rows and
//! columns of the interpolation matrix, each computed from the sources near it
//! ([`crate::contact::geometry::rbf`]).
//!
//! A row of `R` is `z_t` with `Phi_MM^T z_t = Phi_NM[t, :]^T` (scaled), a column `D^-1 Phi_NM
//! x_j` with `Phi_MM x_j = e_j`. `Phi_MM^-1` is dense, but its entries decay exponentially with
//! the number of steps between two sources in the graph of `Phi_MM` (a bound `C q^d` with `q <
//! 1` set by the condition number holds for well-conditioned sparse matrices: Demko, Moss and
//! Smith 1984 for banded ones, Benzi and Razouk 2007 for any sparsity graph). Measured on the
//! 3D hemisphere-on-block's block surface with the default radius (`Phi_MM`'s condition number
//! about 6): about a factor of ten per step, the entries of `Phi_MM^-1` below `1e-14` twelve
//! steps from the diagonal.
//!
//! So `z_t` is solved for on the **patch**: the sources within `k` steps of the right-hand
//! side's support (breadth-first layers of the graph), the solution taken as zero outside. The
//! solve on the patch differs from the whole solve by the whole solution's size beyond the patch
//! (the coupling through the patch's boundary), which is below its size on the patch's outermost
//! layer: measured, the error is 0.05 to 0.1 times the largest value on that layer. The patch
//! starts at [`START_STEPS`] layers and grows by [`GROW_STEPS`] until the solution on its
//! outermost layer is at most [`PATCH_TOL`] of its largest value (or the patch has taken every
//! source its graph reaches, where the solve is exact), so the truncation stays two orders below
//! [`crate::contact::geometry::rbf::DROP_TOL`], the entries the rows keep, whatever the radius
//! or the mesh grading does to the decay.
//!
//! Nearby rows (columns) share a patch: the requested ones are sorted along a Z curve and taken
//! in blocks of [`BLOCK`], each block's patch factored once by faer's sparse LU, the blocks in
//! parallel. A patch reads the matrix node by node ([`PatchMatrix`]: a node's row and its
//! neighbours in the graph), each node computed once for all the blocks of one request
//! ([`NodeCache`]), so that no process stores the matrix or its graph. On the 3D contact
//! surfaces with the default radius a patch holds a few thousand sources, whatever the size of
//! the surface: a row costs the same on any surface, and nothing of the surface's size is
//! factored. Where the whole-field solves needed the whole factor
//! ([`WholeFactor`]: `Phi_MM` ill-conditioned, its inverse decaying slowly) it serves the rows
//! and columns too.

use std::sync::OnceLock;

use faer::MatMut;
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{SparseColMat, SparseRowMat, Triplet};
use rayon::prelude::*;

use crate::linalg::z_curve_keys;

/// Layers of the graph a patch starts with around its right-hand sides' support: on the 3D
/// surfaces with the default radius most blocks of rows settle there (starting at 12, two
/// thirds of them had to grow).
pub const START_STEPS: usize = 14;

/// Layers a patch grows by while its solution is not small enough on its outermost layer.
pub const GROW_STEPS: usize = 2;

/// A patch's solution is accepted once its largest magnitude on the patch's outermost layer is
/// at most this fraction of its largest magnitude anywhere.
pub const PATCH_TOL: f64 = 1e-14;

/// Rows (columns) solved together on one patch.
pub const BLOCK: usize = 64;

/// A sparse matrix in compressed rows (faer's), the columns of each row sorted.
pub type CompressedRows = SparseRowMat<usize, f64>;

/// The entries `(column, value)` of row `i` of `a`.
pub fn row_entries(a: &CompressedRows, i: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
    (a.col_idx_of_row_raw(i).iter().copied()).zip(a.val_of_row(i).iter().copied())
}

/// A square sparse matrix read one node at a time, as a patch grows along its graph and
/// factors its rows: computed on demand rather than stored, so that a process needs none of
/// the matrix to solve on a patch of it ([`NodeCache`] over
/// `crate::contact::geometry::rbf`'s sources).
pub trait PatchMatrix: Sync {
    /// Number of nodes (rows).
    fn len(&self) -> usize;
    /// Node `i`'s row and its neighbours in the graph.
    fn node(&self, i: usize) -> PatchNode;
}

/// The nodes of a [`PatchMatrix`] computed so far, each once: what the blocks of one request
/// share (a patch of a few thousand sources around a block of [`BLOCK`] rows overlaps many
/// others). Made for one request of
/// rows or columns and dropped after it, so that it holds the nodes of this process's blocks'
/// patches only ([`BlockShare`]), and those only while they are solved.
pub struct NodeCache<'a, A> {
    matrix: &'a A,
    nodes: Vec<OnceLock<PatchNode>>,
}

impl<'a, A: PatchMatrix> NodeCache<'a, A> {
    pub fn new(matrix: &'a A) -> Self {
        Self {
            matrix,
            nodes: (0..matrix.len()).map(|_| OnceLock::new()).collect(),
        }
    }

    fn len(&self) -> usize {
        self.nodes.len()
    }

    fn node(&self, i: usize) -> &PatchNode {
        self.nodes[i].get_or_init(|| self.matrix.node(i))
    }
}

/// One node of a [`PatchMatrix`].
#[derive(Debug, Clone, PartialEq)]
pub struct PatchNode {
    /// Its row's entries `(column, value)`, the columns increasing.
    pub row: Vec<(usize, f64)>,
    /// Its neighbours in the matrix's graph (the pattern of `A + A^T` without the diagonal),
    /// increasing.
    pub neighbours: Vec<usize>,
}

/// The solutions of one patch: `count` vectors over its nodes.
pub struct PatchSolution {
    /// The patch's nodes (global indices), layer by layer from the right-hand sides' support.
    pub nodes: Vec<usize>,
    /// `local[global]`: the node's place in `nodes`, `u32::MAX` outside.
    local: Vec<u32>,
    /// Column-major, `nodes.len()` values per solution.
    values: Vec<f64>,
}

impl PatchSolution {
    /// Solution `k` at the patch's nodes (in the order of [`Self::nodes`]).
    pub fn values(&self, k: usize) -> &[f64] {
        let n = self.nodes.len();
        &self.values[k * n..(k + 1) * n]
    }

    /// Solution `k` at a global index: zero outside the patch.
    pub fn at(&self, k: usize, global: usize) -> f64 {
        match self.local[global] {
            u32::MAX => 0.0,
            p => self.values(k)[p as usize],
        }
    }
}

/// The whole matrix's sparse LU, factored only where a whole-field solve's GMRES stopped
/// short of its tolerance (`crate::contact::geometry::rbf`), or why it failed. Where it exists
/// the rows and columns are solved with it too: GMRES stalls where `Phi_MM` is ill-conditioned
/// (wide supports, `rbf_radius` well above its default), and there `Phi_MM^-1` decays slowly,
/// so a patch would be most of the surface for every block of rows.
pub type WholeFactor = OnceLock<Result<Lu<usize, f64>, String>>;

/// The whole factor of `a` ([`WholeFactor`]), factored on first use.
pub fn whole_factor<'w>(
    a: &CompressedRows,
    whole: &'w WholeFactor,
) -> Result<&'w Lu<usize, f64>, String> {
    let n = a.nrows();
    let rows = (0..n).map(|i| row_entries(a, i));
    (whole.get_or_init(|| factor(n, rows, Some)).as_ref()).map_err(|e| e.clone())
}

/// Solves `A x_k = b_k` (or `A^T x_k = b_k` with `transpose`) for `count` right-hand sides whose
/// entries lie at `seeds`, on a patch of `A`'s graph grown from the seeds (module doc), or with
/// the whole factor where it exists ([`WholeFactor`]).
/// `fill(k, set)` calls `set(global index, value)` for the entries of `b_k`. A failure is said
/// in words: a non-finite value, or a matrix that cannot be factored.
pub fn solve<A: PatchMatrix>(
    a: &NodeCache<'_, A>,
    whole: &WholeFactor,
    seeds: &[usize],
    count: usize,
    transpose: bool,
    fill: impl Fn(usize, &mut dyn FnMut(usize, f64)),
) -> Result<PatchSolution, String> {
    if let Some(Ok(lu)) = whole.get() {
        let patch = Patch::whole(a.len());
        let values = solve_with(lu, &patch, count, transpose, &fill);
        return patch.into_solution(values);
    }
    let mut patch = Patch::new(a, seeds);
    patch.grow(a, START_STEPS);
    let values = loop {
        let local = |j: usize| Some(patch.local[j] as usize).filter(|&q| q != u32::MAX as usize);
        let rows = patch.data.iter().map(|node| node.row.iter().copied());
        let factored = factor(patch.nodes.len(), rows, local);
        let settled = match &factored {
            Ok(lu) => {
                let values = solve_with(lu, &patch, count, transpose, &fill);
                match patch.exhausted || patch.settled(&values, count) {
                    true => Some(values),
                    false => None,
                }
            }
            Err(detail) if patch.exhausted => return Err(detail.clone()),
            // A patch's matrix may be singular where the whole one is not: a larger patch.
            Err(_) => None,
        };
        match settled {
            Some(values) => break values,
            None => patch.grow(a, GROW_STEPS),
        }
    };
    patch.into_solution(values)
}

/// The `count` solutions on `patch` with its factor `lu`, column-major over its nodes.
fn solve_with(
    lu: &Lu<usize, f64>,
    patch: &Patch,
    count: usize,
    transpose: bool,
    fill: &impl Fn(usize, &mut dyn FnMut(usize, f64)),
) -> Vec<f64> {
    let n = patch.nodes.len();
    let mut values = vec![0.0; n * count];
    for k in 0..count {
        let column = &mut values[k * n..(k + 1) * n];
        fill(k, &mut |global, value| {
            column[patch.local[global] as usize] += value
        });
    }
    let rhs = MatMut::from_column_major_slice_mut(&mut values, n, count);
    match transpose {
        true => lu.solve_transpose_in_place(rhs),
        false => lu.solve_in_place(rhs),
    }
    values
}

/// Which of the blocks of rows (columns) one process computes ([`in_blocks`]): in a distributed
/// run rank `r` of `N` the `r`-th of `N` consecutive runs of blocks along the Z curve, as even
/// as can be, so that its blocks' patches cover one region of the surface (the nodes its
/// [`NodeCache`] computes); on one process every block.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BlockShare {
    pub rank: usize,
    pub size: usize,
}

impl BlockShare {
    /// Every block.
    pub const ALL: Self = Self { rank: 0, size: 1 };

    /// Whether this process computes block `block` of `blocks`.
    fn takes(&self, block: usize, blocks: usize) -> bool {
        (blocks * self.rank / self.size..blocks * (self.rank + 1) / self.size).contains(&block)
    }
}

/// Requested rows (columns) `indices`, of points at `points[index]`, computed by `block` in
/// blocks of [`BLOCK`] nearby ones (sorted along a Z curve), the blocks of this process's
/// `share` in parallel; the results in the order of `indices`, `None` where another rank
/// computes it. The blocks are the same whatever the share, so a row is the same bits
/// whichever rank computes it.
pub fn in_blocks<T: Send, E: Send>(
    points: &[[f64; 3]],
    indices: &[usize],
    share: BlockShare,
    block: impl Fn(&[usize]) -> Result<Vec<T>, E> + Sync,
) -> Result<Vec<Option<T>>, E> {
    let coords: Vec<f64> = indices.iter().flat_map(|&i| points[i]).collect();
    let keys = z_curve_keys(&coords, 3);
    let mut order: Vec<usize> = (0..indices.len()).collect();
    order.sort_unstable_by_key(|&k| (keys[k], k));
    let blocks = order.len().div_ceil(BLOCK);
    let mine: Vec<&[usize]> = (order.chunks(BLOCK).enumerate())
        .filter(|&(b, _)| share.takes(b, blocks))
        .map(|(_, chunk)| chunk)
        .collect();
    let results: Vec<Vec<T>> = (mine.par_iter())
        .map(|chunk| block(&chunk.iter().map(|&k| indices[k]).collect::<Vec<_>>()))
        .collect::<Result<_, _>>()?;
    let mut out: Vec<Option<T>> = (0..indices.len()).map(|_| None).collect();
    for (chunk, result) in mine.iter().zip(results) {
        for (&k, value) in chunk.iter().zip(result) {
            out[k] = Some(value);
        }
    }
    Ok(out)
}

/// A patch being grown: its nodes layer by layer, and each node's place in it.
struct Patch<'a> {
    nodes: Vec<usize>,
    /// Each node's row and neighbours, in the order of `nodes` (empty for [`Patch::whole`],
    /// which is never factored nor grown).
    data: Vec<&'a PatchNode>,
    /// Where the outermost layer starts in `nodes`.
    outer: usize,
    /// `local[global]`: the node's place in `nodes`, `u32::MAX` outside.
    local: Vec<u32>,
    /// The last layer added nothing: the patch holds every node the seeds' graph reaches.
    exhausted: bool,
}

impl<'a> Patch<'a> {
    fn new<A: PatchMatrix>(a: &'a NodeCache<'_, A>, seeds: &[usize]) -> Self {
        let mut patch = Self {
            nodes: Vec::new(),
            data: Vec::new(),
            outer: 0,
            local: vec![u32::MAX; a.len()],
            exhausted: false,
        };
        for &s in seeds {
            patch.add(a, s);
        }
        patch
    }

    /// Every node, in order.
    fn whole(n: usize) -> Self {
        Self {
            nodes: (0..n).collect(),
            data: Vec::new(),
            outer: n,
            local: (0..n as u32).collect(),
            exhausted: true,
        }
    }

    fn add<A: PatchMatrix>(&mut self, a: &'a NodeCache<'_, A>, node: usize) {
        if self.local[node] == u32::MAX {
            self.local[node] = self.nodes.len() as u32;
            self.nodes.push(node);
            self.data.push(a.node(node));
        }
    }

    /// Adds `steps` layers: the neighbours of the outermost layer not yet in the patch.
    fn grow<A: PatchMatrix>(&mut self, a: &'a NodeCache<'_, A>, steps: usize) {
        for _ in 0..steps {
            let (start, end) = (self.outer, self.nodes.len());
            for p in start..end {
                let node: &'a PatchNode = self.data[p];
                for &j in &node.neighbours {
                    self.add(a, j);
                }
            }
            if self.nodes.len() == end {
                self.exhausted = true;
                return;
            }
            self.outer = end;
        }
    }

    /// Whether the solutions (`count` columns over the patch) are small enough on the
    /// outermost layer ([`PATCH_TOL`]).
    fn settled(&self, values: &[f64], count: usize) -> bool {
        let n = self.nodes.len();
        let (mut outer, mut largest) = (0.0f64, 0.0f64);
        for k in 0..count {
            let column = &values[k * n..(k + 1) * n];
            largest = column.iter().fold(largest, |a, v| a.max(v.abs()));
            outer = column[self.outer..]
                .iter()
                .fold(outer, |a, v| a.max(v.abs()));
        }
        outer <= PATCH_TOL * largest
    }

    /// The solution, or why not: a non-finite value.
    fn into_solution(self, values: Vec<f64>) -> Result<PatchSolution, String> {
        if let Some(j) = values.iter().position(|v| !v.is_finite()) {
            return Err(format!(
                "a solve on {} sources gave a non-finite value at source {}",
                self.nodes.len(),
                self.nodes[j % self.nodes.len()]
            ));
        }
        Ok(PatchSolution {
            nodes: self.nodes,
            local: self.local,
            values,
        })
    }
}

/// The sparse LU of a matrix restricted to `n` nodes, from their `rows` (in the nodes' order;
/// `local` gives a column's place among the nodes, `None` outside), or why it failed.
fn factor<R: Iterator<Item = (usize, f64)>>(
    n: usize,
    rows: impl Iterator<Item = R>,
    local: impl Fn(usize) -> Option<usize>,
) -> Result<Lu<usize, f64>, String> {
    let mut triplets = Vec::new();
    for (p, row) in rows.enumerate() {
        for (j, value) in row {
            if let Some(q) = local(j) {
                triplets.push(Triplet::new(p, q, value));
            }
        }
    }
    let matrix = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &triplets)
        .map_err(|e| format!("{e:?}"))?;
    let symbolic = SymbolicLu::try_new(matrix.symbolic()).map_err(|e| format!("{e:?}"))?;
    Lu::try_new_with_symbolic(symbolic, matrix.as_ref())
        .map_err(|e| format!("the LU of {n} sources' rows: {e:?}"))
}
