//! Conjugate gradients preconditioned by smoothed-aggregation algebraic multigrid (PETSc's
//! `KSPCG` + `PCGAMG`) for one body's constrained stiffness `K_c`: an iterative alternative to
//! the sparse Cholesky factor, whose memory grows like `n^(4/3)` and work like `n^2` in 3D
//! (out of memory near 1M dofs on a 24 GiB machine), where CG + AMG costs about `O(n)` per
//! iteration with a nearly constant iteration count.
//!
//! The C side (`shim.c`, built by `build.rs` with the cargo feature `petsc`) builds the AIJ
//! matrix from our compressed arrays with block size `dim`, the rigid-body modes of the nodes
//! as GAMG's near-null space (`MatNullSpaceCreateRigidBody` on the nodal coordinates: the
//! modes of `crate::fem::rigid_modes`), and the KSP; [`CgAmgMatrix::new`] does this once, then
//! [`CgAmgMatrix::set_up`] builds the GAMG hierarchy, and [`CgAmg::solve`] can be called for
//! any number of right-hand sides.
//!
//! # PETSc in a Rust process
//!
//! - PETSc is initialized once per process, on first use, without its signal handlers and
//!   with `PetscReturnErrorHandler`: a PETSc error is a return code, turned into
//!   [`LinalgError::Petsc`], never a message and an abort. (MPI's initialization, inside
//!   PETSc's, lets Open MPI put a backtrace printer on SIGSEGV, SIGBUS and SIGFPE where no
//!   handler was set; it re-raises the signal.) PETSc is finalized only at the end of a
//!   process an MPI launcher started ([`finalize`], from `crate::parallel::finish`); otherwise
//!   the process ends instead. PETSc's objects are destroyed with their Rust owners.
//! - PETSc is not thread-safe (Debian's 3.18 is built without `PETSC_HAVE_THREADSAFETY`), and
//!   `cargo test` and rayon call from several threads. One global `RwLock` orders the calls:
//!   initialization, [`CgAmgMatrix::new`] and [`CgAmgMatrix::set_up`] (set-up),
//!   [`CgAmg::solve_within`] (CG), [`CgAmg::multiply`] on several ranks and destruction hold it
//!   exclusively (on one process a product reads PETSc's arrays without it: `PetscRows`); [`CgAmg::precondition`] (one V-cycle, `PCApply`) holds it shared,
//!   plus a mutex of its object, so that the V-cycles of two bodies in a coupled Krylov
//!   solve (`rayon::join`) run at the same time, while one object is never applied from two
//!   threads at once and nothing else runs beside an application.
//! - Why concurrent `PCApply` on distinct objects is safe (read in PETSc 3.18.5's source:
//!   `PCApply` -> `PCApply_MG` -> `PCMGMCycle_Private` -> `KSPSolve` of the Chebyshev/Jacobi
//!   smoothers and of the coarse level's preonly + block Jacobi + LU, `MatMult`/
//!   `MatMultAdd`/`MatMultTranspose` of `SeqAIJ`, `MatSolve` of the `SeqAIJ` factor): an
//!   application writes its own objects' memory (vectors, work vectors, object states and
//!   reference counts, `ksp->reason`) and, process-wide, only
//!   - `petsc_TotalFlops` (`PetscLogFlops`, a plain `+=`): increments may be lost; nothing
//!     reads it without `-log_view`;
//!   - `static PetscInt level` of `src/ksp/ksp/interface/itfunc.c` (`++`/`--` in `KSPSetUp`,
//!     `KSPSetUpOnBlocks`, `KSPSolve_Private`): it may drift, and is read only when a KSP has
//!     `KSPSetErrorIfNotConverged`, which the shim never sets (the option
//!     `-ksp_error_if_not_converged` could: see options below).
//!
//!   What it reads of process-wide state is written only at initialization or set-up: the
//!   log handler pointers of `PetscLogEventBegin`/`End` (null: logging never starts; the
//!   build is optimized, `PetscFunctionBegin` pushes no stack and `CHKMEMQ` returns at once),
//!   `PetscInfo`'s flags, the malloc hooks (`PetscMalloc` is `posix_memalign`), and the
//!   options database: each smoother `KSPSolve` looks up `-<prefix>ksp_converged_reason` in
//!   its hash table, built by the first lookup at initialization. A lookup that finds its
//!   option marks it used and takes a viewer shared by all objects (stdout's); so when the
//!   database holds any option besides ours (`PETSC_OPTIONS`, `PETSC_OPTIONS_YAML`, a
//!   `.petscrc`), applications stay exclusive, as every call was before. The first
//!   application of an object still finishes its set-up (the coarse LU factor, through
//!   `PCSetUp`, `MatGetFactor`, `MatGetOrdering` and the event log's deactivation stack):
//!   the shim's create applies the V-cycle once, under the exclusive lock. The
//!   `PetscFPTrapPush` stack and `PetscCitationsRegister` are reached only in set-up
//!   (Chebyshev's eigenvalue estimate in `KSPSetUp`); no MPI call is on the path on
//!   `PETSC_COMM_SELF`.
//! - A whole matrix ([`CgAmgMatrix::new`]) goes to PETSc on `PETSC_COMM_SELF`, its nodes
//!   along a Z curve (`crate::linalg::node_order`: locality for GAMG's products), every vector permuted on
//!   its way in and out; in a
//!   distributed run ([`crate::parallel`]) each rank hands PETSc only its own rows of a body
//!   ([`CgAmgMatrix::distributed`], on `PETSC_COMM_WORLD`; `crate::linalg::Distribution`),
//!   and a solve, a product or a V-cycle takes and returns whole vectors in our numbering
//!   (each rank passes its rows in, and receives every rank's rows of the result), or this
//!   rank's rows alone (`multiply_rows`, `precondition_rows`: the coupled GMRES, whose vectors
//!   hold them, `crate::contact::coupled::krylov_layout`). Every call on
//!   such an object is collective: a distributed run has one thread per rank, so every rank
//!   makes them in the same order, and V-cycles never overlap.

mod mpi;
mod runtime;

use std::ffi::{c_char, c_int};
use std::ptr::NonNull;
use std::sync::{Mutex, PoisonError};

use faer::sparse::SparseColMat;

use super::LinalgError;
use super::distribution::{Distribution, RankRows};
use super::node_order::NodeOrder;
use crate::parallel::ranks::Ranks;
pub use mpi::{
    abort_world, broadcast_bytes, exchange_values, finalize, gather_values, scatter_cells,
    world_ranks,
};
use runtime::{MpiFint, PETSC, petsc, petsc_error, text};
pub use runtime::{concurrent_v_cycles, options_are_ours};

#[repr(C)]
struct RawCgAmg {
    _opaque: [u8; 0],
}

unsafe extern "C" {
    fn internodes_petsc_comm_self() -> MpiFint;
    fn internodes_petsc_comm_world() -> MpiFint;
    fn internodes_ksp_reason_name(reason: c_int) -> *const c_char;
    fn internodes_cgamg_create(
        comm: MpiFint,
        n: i64,
        block: i64,
        row_ptr: *const i64,
        col_idx: *const i64,
        values: *const f64,
        petsc_nodes: *const i64,
        coords: *const f64,
        rtol: f64,
        max_iterations: i64,
        out: *mut *mut RawCgAmg,
        step: *mut *const c_char,
    ) -> c_int;
    fn internodes_cgamg_solve(
        solver: *mut RawCgAmg,
        rhs: *const f64,
        x: *mut f64,
        rtol: f64,
        iterations: *mut i64,
        residual_norm: *mut f64,
        reason: *mut c_int,
        step: *mut *const c_char,
    ) -> c_int;
    fn internodes_cgamg_precondition(
        solver: *mut RawCgAmg,
        rhs: *const f64,
        x: *mut f64,
        step: *mut *const c_char,
    ) -> c_int;
    fn internodes_cgamg_set_up(solver: *mut RawCgAmg, step: *mut *const c_char) -> c_int;
    fn internodes_cgamg_multiply(
        solver: *mut RawCgAmg,
        x: *const f64,
        y: *mut f64,
        step: *mut *const c_char,
    ) -> c_int;
    fn internodes_cgamg_rows(
        solver: *mut RawCgAmg,
        row_ptr: *mut *const std::ffi::c_void,
        col_idx: *mut *const std::ffi::c_void,
        values: *mut *const f64,
        index_bytes: *mut c_int,
        step: *mut *const c_char,
    ) -> c_int;
    fn internodes_cgamg_destroy(solver: *mut RawCgAmg);
}

/// The communicator PETSc objects are created on, with this process's place in it.
#[derive(Debug, Clone, Copy)]
struct Communicator {
    handle: MpiFint,
    ranks: Ranks,
}

impl Communicator {
    /// `PETSC_COMM_SELF`: this process alone (initializes PETSc if needed).
    fn solo() -> Result<Self, LinalgError> {
        let _lock = petsc()?;
        Ok(Self {
            // SAFETY: PETSc is initialized.
            handle: unsafe { internodes_petsc_comm_self() },
            ranks: Ranks::ONE,
        })
    }

    /// `PETSC_COMM_WORLD`: every rank of the run (initializes PETSc, and MPI, if needed).
    fn world() -> Result<Self, LinalgError> {
        let ranks = world_ranks()?;
        let _lock = petsc()?;
        Ok(Self {
            // SAFETY: PETSc is initialized.
            handle: unsafe { internodes_petsc_comm_world() },
            ranks,
        })
    }
}

/// How one CG solve went.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CgStats {
    pub iterations: usize,
    /// `||b - K x|| / ||b||` as CG last computed it (0 when `b = 0`).
    pub relative_residual: f64,
}

/// Where a matrix's rows are in PETSc, and in which order.
enum Layout {
    /// All on this process, the nodes along a Z curve ([`NodeOrder`]): every vector is
    /// permuted on its way to PETSc and back, so callers keep our numbering.
    Whole(NodeOrder),
    /// Shared among the ranks, each rank's rows in our order.
    Shared(Distribution),
}

/// CG + GAMG set up for one matrix.
pub struct CgAmg {
    raw: NonNull<RawCgAmg>,
    /// The matrix's size.
    n: usize,
    /// Where PETSc's rows are, and in which order.
    layout: Layout,
    /// PETSc's own arrays of the matrix, where it is whole on this process: what
    /// [`Self::multiply`] reads and [`Self::matrix`] copies.
    rows: Option<PetscRows>,
    /// The relative residual [`Self::solve`] stops at.
    rtol: f64,
    /// Held by [`Self::precondition`] under the shared [`PETSC`] lock: the object's vectors
    /// and its hierarchy's work vectors are written by every V-cycle.
    applying: Mutex<()>,
}

// SAFETY: the PETSc objects behind `raw` belong to no thread; they are touched only under
// the global PETSc lock (see below).
unsafe impl Send for CgAmg {}
// SAFETY: every `&self` method that calls PETSc holds the global lock exclusively, except
// `precondition`, which holds it shared and also `self.applying`: so the objects behind one
// `raw` are touched by one thread at a time, and beside an application run only applications
// of other objects, which write process-wide state only as the module's doc shows to be
// harmless (PETSc 3.18's `PCApply` of a set-up GAMG hierarchy).
unsafe impl Sync for CgAmg {}

/// The iteration cap of a solve: CG + GAMG takes 21 to 26 iterations at rtol 1e-10 on the
/// block_3d meshes from 6k to 677k dofs (`AUTO_CG_AMG_MIN_DOFS_3D`'s table,
/// validation/BODY_SOLVER_BENCHMARK.md), so a cap this far above only stops a solve that is
/// not converging.
const MAX_ITERATIONS: i64 = 2000;

/// PETSc's copy of a body's matrix with its CG + GAMG solver, before the GAMG hierarchy is
/// built ([`CgAmgMatrix::set_up`]): the caller may free its own copy of the matrix in between,
/// so that the two and the hierarchy's set-up never peak together.
pub struct CgAmgMatrix(CgAmg);

impl CgAmgMatrix {
    /// PETSc's copy of `matrix` (symmetric positive definite; its compressed columns are read
    /// as compressed rows), whole on this process, with `dim` dofs per node, interleaved, the
    /// nodes at `coords` (`dim` per node). Solves will stop at the relative residual `rtol`.
    pub fn new(
        matrix: &SparseColMat<usize, f64>,
        dim: usize,
        coords: &[f64],
        rtol: f64,
    ) -> Result<Self, LinalgError> {
        let (symbolic, values) = matrix.parts();
        let n = symbolic.nrows();
        // Compressed columns without gaps (`col_nnz` absent): the layout the shim reads.
        if symbolic.ncols() != n
            || coords.len() != n
            || dim == 0
            || n % dim != 0
            || symbolic.col_nnz().is_some()
        {
            return Err(LinalgError::Sizes(format!(
                "CG + AMG of a {n} x {} matrix (compact: {}) with {} coordinates, {dim} per node",
                symbolic.ncols(),
                symbolic.col_nnz().is_none(),
                coords.len()
            )));
        }
        // The index arrays go to the shim as they are, read as `int64_t`: usize has that size
        // here (checked below), and its values, counts of allocated entries, are below
        // i64::MAX. A converted copy would cost 8 bytes per stored entry at the peak.
        const _: () = assert!(size_of::<usize>() == size_of::<i64>());
        // The nodes go to PETSc along a Z curve: the shim puts each row at its place, and the
        // coordinates (one value per dof) are permuted here.
        let order = NodeOrder::along_z_curve(coords, dim);
        let petsc_nodes = order.petsc_nodes();
        let petsc_coords = order.to_petsc(coords);
        let rows = LocalRows {
            num_rows: n,
            row_ptr: symbolic.col_ptr().as_ptr().cast::<i64>(),
            columns: symbolic.row_idx().as_ptr().cast::<i64>(),
            values,
            petsc_nodes: Some(&petsc_nodes),
            coords: &petsc_coords,
        };
        CgAmg::build(
            Communicator::solo()?,
            n,
            dim,
            rows,
            Layout::Whole(order),
            rtol,
        )
        .map(Self)
    }

    /// PETSc's copy of a body shared among the ranks of the run, from this rank's `rows`
    /// (collective: every rank calls it with its own). Solves will stop at the relative
    /// residual `rtol`.
    pub fn distributed(rows: RankRows, rtol: f64) -> Result<Self, LinalgError> {
        let (n, dim) = (rows.num_dofs(), rows.block());
        if rows.coords.len() != rows.num_rows() || rows.columns.len() != rows.values.len() {
            return Err(LinalgError::Sizes(format!(
                "CG + AMG of {} rows with {} coordinates, {} columns and {} values",
                rows.num_rows(),
                rows.coords.len(),
                rows.columns.len(),
                rows.values.len()
            )));
        }
        let local = LocalRows {
            num_rows: rows.num_rows(),
            row_ptr: rows.row_ptr.as_ptr(),
            columns: rows.columns.as_ptr(),
            values: &rows.values,
            petsc_nodes: None,
            coords: &rows.coords,
        };
        CgAmg::build(
            Communicator::world()?,
            n,
            dim,
            local,
            Layout::Shared(rows.distribution),
            rtol,
        )
        .map(Self)
    }

    /// Builds the GAMG hierarchy: the solver is ready.
    pub fn set_up(self) -> Result<CgAmg, LinalgError> {
        let _lock = petsc()?;
        let mut step = std::ptr::null();
        // SAFETY: `raw` is alive and built; the lock is held.
        let code = unsafe { internodes_cgamg_set_up(self.0.raw.as_ptr(), &mut step) };
        match code {
            0 => Ok(self.0),
            _ => Err(petsc_error(step, code)),
        }
    }
}

/// PETSc's own compressed rows of a matrix whole on this process (`internodes_cgamg_rows`):
/// pointers into the AIJ matrix of a live [`CgAmg`], which owns them. PETSc never moves or
/// writes them after assembly (no nonzero is ever inserted; CG and GAMG only read the
/// operator), so reading them from any thread beside a V-cycle is a read beside reads. They
/// let one process hold `K_c` once: the caller may free its own copy
/// (`crate::elastic::Stiffness::Released`) and still have products (the same terms: `K_c` is
/// symmetric, so PETSc's rows are its columns, summed in PETSc's node order) and the matrix
/// back for a Cholesky factor.
struct PetscRows {
    row_ptr: *const std::ffi::c_void,
    columns: *const std::ffi::c_void,
    values: *const f64,
    /// The size of PETSc's index type (`PetscInt`: 4 in Debian's build, 8 in a 64-bit one).
    index_bytes: usize,
    n: usize,
}

/// An integer PETSc may index with.
trait PetscIndex: Copy + Sync {
    fn index(self) -> usize;
}

impl PetscIndex for i32 {
    fn index(self) -> usize {
        self as usize
    }
}

impl PetscIndex for i64 {
    fn index(self) -> usize {
        self as usize
    }
}

impl PetscRows {
    /// The arrays of `raw`'s matrix of `n` rows.
    ///
    /// # Safety
    /// `raw` is a live object whose matrix is whole on this process, and PETSc's lock is held.
    unsafe fn of(raw: NonNull<RawCgAmg>, n: usize) -> Result<Self, LinalgError> {
        let (mut row_ptr, mut columns, mut values) =
            (std::ptr::null(), std::ptr::null(), std::ptr::null());
        let (mut index_bytes, mut step) = (0, std::ptr::null());
        // SAFETY: as the caller guarantees; the shim writes the four outputs.
        let code = unsafe {
            internodes_cgamg_rows(
                raw.as_ptr(),
                &mut row_ptr,
                &mut columns,
                &mut values,
                &mut index_bytes,
                &mut step,
            )
        };
        if code != 0 {
            return Err(petsc_error(step, code));
        }
        if !matches!(index_bytes, 4 | 8) || row_ptr.is_null() || columns.is_null() {
            return Err(LinalgError::Sizes(format!(
                "PETSc's rows: indices of {index_bytes} bytes"
            )));
        }
        Ok(Self {
            row_ptr,
            columns,
            values,
            index_bytes: index_bytes as usize,
            n,
        })
    }

    /// `(row pointers, column indices, values)` as slices of PETSc's index type `I`.
    ///
    /// # Safety
    /// `I` has `self.index_bytes` bytes.
    unsafe fn slices<I: PetscIndex>(&self) -> (&[I], &[I], &[f64]) {
        // SAFETY: the arrays live as long as the `CgAmg` that owns `self` (type doc); the row
        // pointers are n + 1 of type `I` (caller), the last one the number of entries.
        unsafe {
            let row_ptr = std::slice::from_raw_parts(self.row_ptr.cast::<I>(), self.n + 1);
            let nnz = row_ptr[self.n].index();
            let columns = std::slice::from_raw_parts(self.columns.cast::<I>(), nnz);
            let values = match nnz {
                0 => &[][..],
                _ => std::slice::from_raw_parts(self.values, nnz),
            };
            (row_ptr, columns, values)
        }
    }

    fn multiply(&self, x: &[f64], y: &mut [f64]) {
        // SAFETY: the index type matches `index_bytes` (checked in `of`).
        match self.index_bytes {
            4 => product(unsafe { self.slices::<i32>() }, x, y),
            _ => product(unsafe { self.slices::<i64>() }, x, y),
        }
    }

    /// A copy of the matrix in our numbering (PETSc's is `order`), its rows read as columns
    /// (it is symmetric).
    fn matrix(&self, order: &NodeOrder) -> SparseColMat<usize, f64> {
        // SAFETY: the index type matches `index_bytes` (checked in `of`).
        match self.index_bytes {
            4 => columns_of(unsafe { self.slices::<i32>() }, order),
            _ => columns_of(unsafe { self.slices::<i64>() }, order),
        }
    }
}

/// `y = A x` for compressed rows, each row's entries summed in their order.
fn product<I: PetscIndex>(
    (row_ptr, columns, values): (&[I], &[I], &[f64]),
    x: &[f64],
    y: &mut [f64],
) {
    use rayon::prelude::*;
    y.par_iter_mut().enumerate().for_each(|(i, y)| {
        *y = (row_ptr[i].index()..row_ptr[i + 1].index())
            .map(|p| values[p] * x[columns[p].index()])
            .sum();
    });
}

/// The symmetric matrix of compressed rows in PETSc's `order` as compressed columns in ours:
/// our column `j` is PETSc's row of `j`, each entry's row ours, sorted.
fn columns_of<I: PetscIndex>(
    (row_ptr, columns, values): (&[I], &[I], &[f64]),
    order: &NodeOrder,
) -> SparseColMat<usize, f64> {
    let n = row_ptr.len() - 1;
    let mut col_ptr = Vec::with_capacity(n + 1);
    let (mut row_idx, mut entries) = (Vec::with_capacity(values.len()), Vec::new());
    let mut sorted = Vec::with_capacity(values.len());
    col_ptr.push(0);
    for j in 0..n {
        let p = order.petsc_dof(j);
        entries.clear();
        entries.extend(
            (row_ptr[p].index()..row_ptr[p + 1].index())
                .map(|k| (order.our_dof(columns[k].index()), values[k])),
        );
        entries.sort_unstable_by_key(|&(i, _)| i);
        row_idx.extend(entries.iter().map(|&(i, _)| i));
        sorted.extend(entries.iter().map(|&(_, v)| v));
        col_ptr.push(row_idx.len());
    }
    let symbolic = faer::sparse::SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
    SparseColMat::new(symbolic, sorted)
}

/// The rows this process hands PETSc, as the shim reads them: `num_rows + 1` row pointers from
/// 0, each entry's global column and value, where each node goes in PETSc's order (one value
/// per node; `None`: where it is), and the coordinates of the nodes in PETSc's order (`dim`
/// per node: one value per row).
struct LocalRows<'a> {
    num_rows: usize,
    row_ptr: *const i64,
    columns: *const i64,
    values: &'a [f64],
    petsc_nodes: Option<&'a [i64]>,
    coords: &'a [f64],
}

impl CgAmg {
    /// The PETSc objects of [`CgAmgMatrix`], without the hierarchy: a matrix of `n` unknowns
    /// (`dim` per node) of which this process holds `rows`, laid out as `layout` says.
    fn build(
        comm: Communicator,
        n: usize,
        dim: usize,
        rows: LocalRows,
        layout: Layout,
        rtol: f64,
    ) -> Result<Self, LinalgError> {
        let _lock = petsc()?;
        let mut raw = std::ptr::null_mut();
        let mut step = std::ptr::null();
        // SAFETY: the arrays have the lengths the shim reads (num_rows + 1, nnz, nnz,
        // num_rows / dim or none, num_rows: checked by the callers), it copies them, and the
        // lock is held.
        let code = unsafe {
            internodes_cgamg_create(
                comm.handle,
                rows.num_rows as i64,
                dim as i64,
                rows.row_ptr,
                rows.columns,
                rows.values.as_ptr(),
                rows.petsc_nodes.map_or(std::ptr::null(), <[i64]>::as_ptr),
                rows.coords.as_ptr(),
                rtol,
                MAX_ITERATIONS,
                &mut raw,
                &mut step,
            )
        };
        if code != 0 {
            return Err(petsc_error(step, code));
        }
        debug_assert_eq!(comm.ranks.size > 1, matches!(layout, Layout::Shared(_)));
        let raw = NonNull::new(raw).ok_or_else(|| petsc_error(step, 0))?;
        let rows = match layout {
            Layout::Shared(_) => None,
            // SAFETY: `raw` is alive and built, whole on this process; the lock is held.
            Layout::Whole(_) => Some(unsafe { PetscRows::of(raw, n) }?),
        };
        Ok(Self {
            raw,
            n,
            layout,
            rows,
            rtol,
            applying: Mutex::new(()),
        })
    }

    /// Each rank's number of unknowns of this matrix, in rank order (one value on one process).
    pub fn rank_dofs(&self) -> Vec<usize> {
        match &self.layout {
            Layout::Whole(_) => vec![self.n],
            Layout::Shared(d) => d.counts().to_vec(),
        }
    }

    /// A copy of the matrix, where it is whole on this process (`None` on several ranks).
    pub fn matrix(&self) -> Option<SparseColMat<usize, f64>> {
        match (&self.rows, &self.layout) {
            (Some(rows), Layout::Whole(order)) => Some(rows.matrix(order)),
            _ => None,
        }
    }

    /// This rank's part of `whole` (our numbering), as PETSc's vectors hold it.
    fn local_part(&self, whole: &[f64]) -> Vec<f64> {
        match &self.layout {
            Layout::Whole(order) => order.to_petsc(whole),
            Layout::Shared(d) => d.local_part(whole),
        }
    }

    /// A buffer for this rank's part of a result.
    fn local_buffer(&self) -> Vec<f64> {
        vec![0.0; self.local_len()]
    }

    /// This rank's number of rows (the whole matrix's on one process).
    fn local_len(&self) -> usize {
        match &self.layout {
            Layout::Whole(_) => self.n,
            Layout::Shared(d) => d.local(),
        }
    }

    /// Every rank's part of a result (`local`, as PETSc's vectors hold it) into `whole` (our
    /// numbering), on every rank.
    fn assemble_whole(&self, local: Vec<f64>, whole: &mut [f64]) -> Result<(), LinalgError> {
        match &self.layout {
            Layout::Whole(order) => order.to_ours(&local, whole),
            Layout::Shared(d) => d.gather(&local, whole)?,
        }
        Ok(())
    }

    /// Solves `K x = rhs` from `x = 0`. Fails with [`LinalgError::NotConverged`] unless CG
    /// reached the relative residual it was set up with.
    pub fn solve(&self, rhs: &[f64]) -> Result<(Vec<f64>, CgStats), LinalgError> {
        self.solve_within(rhs, self.rtol)
    }

    /// [`Self::solve`] to the relative residual `rtol` instead of the one it was set up with.
    pub fn solve_within(&self, rhs: &[f64], rtol: f64) -> Result<(Vec<f64>, CgStats), LinalgError> {
        if rhs.len() != self.n {
            return Err(LinalgError::Sizes(format!(
                "a right-hand side of {} values for {} unknowns",
                rhs.len(),
                self.n
            )));
        }
        let (local_x, iterations, residual, reason) =
            self.solve_local(&self.local_part(rhs), rtol)?;
        let mut x = vec![0.0; self.n];
        self.assemble_whole(local_x, &mut x)?;
        let norm = rhs.iter().map(|v| v * v).sum::<f64>().sqrt();
        converged(x, iterations, residual, norm, reason)
    }

    /// [`Self::solve`] on this rank's rows alone (PETSc's order, [`Self::distribution`];
    /// collective): `rhs` and the answer hold this rank's rows, and no rank holds a whole
    /// vector. On one process, the whole vectors in our numbering.
    pub fn solve_rows(&self, rhs: &[f64]) -> Result<(Vec<f64>, CgStats), LinalgError> {
        let Layout::Shared(_) = &self.layout else {
            return self.solve(rhs);
        };
        if rhs.len() != self.local_len() {
            return Err(LinalgError::Sizes(format!(
                "a right-hand side of {} values for this rank's {} rows",
                rhs.len(),
                self.local_len()
            )));
        }
        let (x, iterations, residual, reason) = self.solve_local(rhs, self.rtol)?;
        // Every rank's sum of squares, added in rank order: the same norm on every rank.
        let squares = rhs.iter().map(|v| v * v).sum::<f64>();
        let squares = gather_values(&[squares], &vec![1; world_ranks()?.size], false)?;
        converged(
            x,
            iterations,
            residual,
            squares.iter().sum::<f64>().sqrt(),
            reason,
        )
    }

    /// PETSc's CG from `x = 0` on this rank's rows of the right-hand side (as PETSc's vectors
    /// hold them): the rows of the answer, the iterations, the residual's norm and PETSc's
    /// reason.
    fn solve_local(
        &self,
        local_rhs: &[f64],
        rtol: f64,
    ) -> Result<(Vec<f64>, usize, f64, c_int), LinalgError> {
        let mut local_x = self.local_buffer();
        let (mut iterations, mut residual, mut reason) = (0i64, 0.0, 0);
        let mut step = std::ptr::null();
        let code = {
            let _lock = petsc()?;
            // SAFETY: `local_rhs` and `local_x` hold this rank's rows, `raw` is alive, the lock
            // is held.
            unsafe {
                internodes_cgamg_solve(
                    self.raw.as_ptr(),
                    local_rhs.as_ptr(),
                    local_x.as_mut_ptr(),
                    rtol,
                    &mut iterations,
                    &mut residual,
                    &mut reason,
                    &mut step,
                )
            }
        };
        if code != 0 {
            return Err(petsc_error(step, code));
        }
        Ok((local_x, iterations.max(0) as usize, residual, reason))
    }
}

/// The answer `x` of a CG solve with its statistics, or [`LinalgError::NotConverged`] unless
/// PETSc's `reason` says it converged; `residual` is the residual's norm, `norm` the
/// right-hand side's.
fn converged(
    x: Vec<f64>,
    iterations: usize,
    residual: f64,
    norm: f64,
    reason: c_int,
) -> Result<(Vec<f64>, CgStats), LinalgError> {
    let relative_residual = if norm > 0.0 {
        residual / norm
    } else {
        residual
    };
    // Converged on the relative (2, 1) or absolute (3, 9) residual, or CG's exact
    // breakdown (8); CONVERGED_ITS and the CG trust-region reasons do not apply here.
    if !matches!(reason, 1 | 2 | 3 | 8 | 9) {
        return Err(LinalgError::NotConverged {
            // SAFETY: plain lookup of a static string.
            reason: text(unsafe { internodes_ksp_reason_name(reason) }),
            iterations,
            relative_residual,
        });
    }
    Ok((
        x,
        CgStats {
            iterations,
            relative_residual,
        },
    ))
}

impl CgAmg {
    /// `y = K x` by PETSc's copy of the matrix (on several ranks each computes its rows, and
    /// every rank receives all of `y`). On one process the product reads PETSc's arrays
    /// from this side, on every thread, without PETSc's lock (`PetscRows`).
    pub fn multiply(&self, x: &[f64], y: &mut [f64]) -> Result<(), LinalgError> {
        self.on_whole("a product", x, y, |x, y| self.multiply_rows(x, y))
    }

    /// `y = K x` on this rank's rows alone (in our order, [`Self::distribution`]): `x` and `y`
    /// hold this rank's rows, and PETSc exchanges the rows of `x` the product reads across
    /// ranks (collective). On one process, the whole vectors.
    pub fn multiply_rows(&self, x: &[f64], y: &mut [f64]) -> Result<(), LinalgError> {
        if let (Some(rows), Layout::Whole(order)) = (&self.rows, &self.layout) {
            self.check_rows("a product", x, y)?;
            let mut petsc_y = vec![0.0; self.n];
            rows.multiply(&order.to_petsc(x), &mut petsc_y);
            order.to_ours(&petsc_y, y);
            return Ok(());
        }
        self.call_on_rows("a product", x, y, |x, y, step| {
            let _lock = petsc()?;
            // SAFETY: `x` and `y` hold this rank's rows, `raw` is alive, the lock is held.
            Ok(unsafe { internodes_cgamg_multiply(self.raw.as_ptr(), x, y, step) })
        })
    }

    /// `x = P^-1 rhs` for GAMG's preconditioner `P` alone: one V-cycle (the smoothers are
    /// Chebyshev polynomials with eigenvalue bounds estimated once at set-up, so the map is the
    /// same linear one at every call).
    ///
    /// V-cycles of distinct objects run at the same time when called from several threads
    /// (unless PETSc's options database holds options of its own: see the module's doc); those
    /// of one object take turns.
    pub fn precondition(&self, rhs: &[f64], x: &mut [f64]) -> Result<(), LinalgError> {
        self.on_whole("a V-cycle", rhs, x, |rhs, x| self.precondition_rows(rhs, x))
    }

    /// [`Self::precondition`] on this rank's rows alone (in our order, [`Self::distribution`];
    /// collective). On one process, the whole vectors.
    pub fn precondition_rows(&self, rhs: &[f64], x: &mut [f64]) -> Result<(), LinalgError> {
        self.call_on_rows("a V-cycle", rhs, x, |rhs, x, step| {
            // PETSc is initialized (`self` exists). `applying` is taken under the shared lock,
            // never the other way round, and released first (reverse order of declaration).
            // A distributed V-cycle is collective: never beside another call.
            let concurrent = concurrent_v_cycles() && matches!(self.layout, Layout::Whole(_));
            let _exclusive = if concurrent { None } else { Some(petsc()?) };
            let _shared = concurrent.then(|| PETSC.read().unwrap_or_else(PoisonError::into_inner));
            let _own =
                concurrent.then(|| self.applying.lock().unwrap_or_else(PoisonError::into_inner));
            // SAFETY: `rhs` and `x` hold this rank's rows, `raw` is alive, and either PETSc is
            // held exclusively or it is held shared with this object's mutex (see `impl Sync`).
            Ok(unsafe { internodes_cgamg_precondition(self.raw.as_ptr(), rhs, x, step) })
        })
    }

    /// How the matrix's rows are shared among the ranks (`None` on one process).
    pub fn distribution(&self) -> Option<&Distribution> {
        match &self.layout {
            Layout::Whole(_) => None,
            Layout::Shared(d) => Some(d),
        }
    }

    /// A linear map on this rank's rows (`on_rows`, vectors in our numbering) applied to whole
    /// vectors: every rank receives every rank's rows of `output`.
    fn on_whole(
        &self,
        what: &str,
        input: &[f64],
        output: &mut [f64],
        on_rows: impl FnOnce(&[f64], &mut [f64]) -> Result<(), LinalgError>,
    ) -> Result<(), LinalgError> {
        if input.len() != self.n || output.len() != self.n {
            return Err(LinalgError::Sizes(format!(
                "{what} on {} values into {} for {} unknowns",
                input.len(),
                output.len(),
                self.n
            )));
        }
        match &self.layout {
            Layout::Whole(_) => on_rows(input, output),
            Layout::Shared(d) => {
                let mut local_output = self.local_buffer();
                on_rows(&d.local_part(input), &mut local_output)?;
                Ok(d.gather(&local_output, output)?)
            }
        }
    }

    /// `input` and `output` hold this rank's rows.
    fn check_rows(&self, what: &str, input: &[f64], output: &[f64]) -> Result<(), LinalgError> {
        let local = self.local_len();
        if input.len() != local || output.len() != local {
            return Err(LinalgError::Sizes(format!(
                "{what} on {} values into {} for this rank's {local} rows",
                input.len(),
                output.len(),
            )));
        }
        Ok(())
    }

    /// A call of the shim (`call`: this rank's rows of `input` in, of the result out, as
    /// PETSc's vectors hold them; it returns the shim's code and sets `step` on error) on
    /// vectors of this rank's rows in our order.
    fn call_on_rows(
        &self,
        what: &str,
        input: &[f64],
        output: &mut [f64],
        call: impl FnOnce(*const f64, *mut f64, &mut *const c_char) -> Result<c_int, LinalgError>,
    ) -> Result<(), LinalgError> {
        self.check_rows(what, input, output)?;
        let mut step = std::ptr::null();
        let code = match &self.layout {
            Layout::Shared(_) => call(input.as_ptr(), output.as_mut_ptr(), &mut step)?,
            Layout::Whole(order) => {
                let (petsc_input, mut petsc_output) = (order.to_petsc(input), self.local_buffer());
                let code = call(petsc_input.as_ptr(), petsc_output.as_mut_ptr(), &mut step)?;
                order.to_ours(&petsc_output, output);
                code
            }
        };
        match code {
            0 => Ok(()),
            code => Err(petsc_error(step, code)),
        }
    }
}

impl Drop for CgAmg {
    fn drop(&mut self) {
        // The lock is taken even if initialization had failed (it cannot have: `self` exists).
        let _lock = PETSC.write().unwrap_or_else(PoisonError::into_inner);
        // SAFETY: `raw` came from the shim's create and is destroyed once.
        unsafe { internodes_cgamg_destroy(self.raw.as_ptr()) };
    }
}
