//! The MPI ranks of a run: `mpirun -n N internodes solve CASE` runs the same program on `N`
//! processes (`docs/parallel.md`).
//!
//! Every rank reads the case and runs the contact loop; rank 0 reads the mesh, partitions each
//! body's nodes (METIS) and sends every rank the nodes, groups and partition and the cells it
//! assembles (`crate::run`'s partition). What is distributed is each body's stiffness and
//! linear algebra: each rank assembles the rows of its own nodes
//! (`crate::linalg::Distribution`) and hands them to PETSc, which builds the
//! GAMG hierarchy and runs the V-cycles, CG solves and products on them
//! (`crate::linalg::petsc`), and the coupled GMRES, whose vectors hold each rank's rows of the
//! bodies (`crate::contact::coupled::krylov_layout`). The answers every rank then receives whole,
//! so every rank takes the same decisions on the same numbers, and only rank 0 writes: the
//! output folder is the serial run's, with the ranks recorded.
//!
//! A rank runs one thread (one rank per core): the calls into PETSc are collective, and with
//! one thread every rank makes them in the same order.
//!
//! Without the cargo feature `petsc` a run is always one rank; launched by `mpirun` on more,
//! [`start`] refuses.

pub mod ranks;

use thiserror::Error;

pub use ranks::{Ranks, distributed, is_root, ranks};

#[derive(Debug, Error)]
pub enum ParallelError {
    #[error(
        "launched on {0} MPI ranks, but this binary was built without PETSc, which carries the \
         distribution (rebuild with `cargo build --release --features petsc`, as `make` does)"
    )]
    NoPetsc(usize),
    #[error("MPI: {0}")]
    Mpi(String),
    /// What rank 0 sent could not be encoded or read back (a bug, not an input's fault).
    #[error("a message between the ranks: {0}")]
    Message(String),
    #[error("the rayon thread pool of a rank: {0}")]
    Threads(String),
}

/// The number of ranks the environment of an MPI launcher announces (Open MPI's `mpirun`,
/// and the PMI of MPICH, Intel MPI and Slurm's `srun`), if it names one.
fn announced_size() -> Option<usize> {
    ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE"]
        .iter()
        .find_map(|name| std::env::var(name).ok()?.trim().parse().ok())
}

/// Joins the run when an MPI launcher started this process: initializes MPI (through
/// PETSc), learns this rank and the number of ranks, and on more than one keeps this process
/// to one thread. Without a launcher, or on one rank, the run is serial and nothing changes.
/// Called once, first thing, by the command line (never by the library: a Python process is
/// always a serial run).
pub fn start() -> Result<Ranks, ParallelError> {
    let Some(announced) = announced_size() else {
        return Ok(ranks::settle(Ranks::ONE));
    };
    let world = join_world(announced)?;
    if world.size > 1 {
        rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build_global()
            .map_err(|e| ParallelError::Threads(e.to_string()))?;
        fix_mmap_threshold();
    }
    Ok(ranks::settle(world))
}

/// Blocks of [`MMAP_THRESHOLD`] bytes or more get a mapping of their own, returned to the
/// system when freed, whatever was freed before. glibc's default raises the threshold to the
/// size of the largest mapped block freed (up to 32 MB), after which such blocks come from the
/// main heap, where a long-lived block keeps the freed memory around it resident: a rank's
/// peak then depends on where its long-lived blocks happen to fall (at 1M DOFs on 2 ranks the
/// largest rank 1,335 to 1,347 MB in some runs and 1,394 to 1,420 in others of the same
/// binary; with the threshold fixed, 1,336 to 1,343 in three runs, and no slower).
fn fix_mmap_threshold() {
    #[cfg(target_env = "gnu")]
    // SAFETY: sets one of the allocator's parameters, before the run allocates its data.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, MMAP_THRESHOLD);
    }
}

/// [`fix_mmap_threshold`]'s bound: 4 MiB.
const MMAP_THRESHOLD: i32 = 4 << 20;

#[cfg(feature = "petsc")]
fn join_world(_announced: usize) -> Result<Ranks, ParallelError> {
    crate::linalg::petsc::world_ranks().map_err(|e| ParallelError::Mpi(e.to_string()))
}

#[cfg(not(feature = "petsc"))]
fn join_world(announced: usize) -> Result<Ranks, ParallelError> {
    match announced {
        0 | 1 => Ok(Ranks::ONE),
        size => Err(ParallelError::NoPetsc(size)),
    }
}

/// Rank 0's `bytes` on every rank (`bytes` is read on rank 0 only). Serial: `bytes` itself.
pub fn share_from_root(bytes: Vec<u8>) -> Result<Vec<u8>, ParallelError> {
    if !distributed() {
        return Ok(bytes);
    }
    #[cfg(feature = "petsc")]
    {
        crate::linalg::petsc::broadcast_bytes(bytes).map_err(|e| ParallelError::Mpi(e.to_string()))
    }
    #[cfg(not(feature = "petsc"))]
    unreachable!("a run without PETSc is never distributed (`start`)")
}

/// This rank's cells of what rank 0 divides among the ranks (`MPI_Scatterv`): on rank 0,
/// `all` holds every rank's cells one rank after the other, `counts[r]` cells of `width`
/// values for rank r; on the others both are empty (not read). Serial: `all` itself.
pub fn scatter_cells(
    all: Vec<u32>,
    counts: &[usize],
    width: usize,
) -> Result<Vec<u32>, ParallelError> {
    if !distributed() {
        return Ok(all);
    }
    #[cfg(feature = "petsc")]
    {
        crate::linalg::petsc::scatter_cells(&all, counts, width)
            .map_err(|e| ParallelError::Mpi(e.to_string()))
    }
    #[cfg(not(feature = "petsc"))]
    unreachable!("a run without PETSc is never distributed (`start`): {counts:?} {width}")
}

/// Every rank's `value`, in rank order, on every rank. Serial: `[value]`.
pub fn gather(value: f64) -> Result<Vec<f64>, ParallelError> {
    all_gather(&[value], &vec![1; ranks().size])
}

/// Every rank's `local` values (`counts[r]` of them from rank r, in rank order) on every
/// rank (`MPI_Allgatherv`). With one count: `local` itself.
pub fn all_gather(local: &[f64], counts: &[usize]) -> Result<Vec<f64>, ParallelError> {
    gather_values(local, counts, false)
}

/// What every rank sent this one, by rank, where `sends[r]` is what this rank sends rank r
/// (`MPI_Alltoallv`; `sends` holds one vector per rank). On one rank: `sends` itself.
pub fn exchange(sends: Vec<Vec<f64>>) -> Result<Vec<Vec<f64>>, ParallelError> {
    if sends.len() <= 1 {
        return Ok(sends);
    }
    #[cfg(feature = "petsc")]
    {
        crate::linalg::petsc::exchange_values(&sends).map_err(|e| ParallelError::Mpi(e.to_string()))
    }
    #[cfg(not(feature = "petsc"))]
    {
        Err(ParallelError::NoPetsc(sends.len()))
    }
}

/// [`all_gather`] onto rank 0 alone (`MPI_Gatherv`): the other ranks receive an empty
/// vector. With one count: `local` itself.
pub fn gather_to_root(local: &[f64], counts: &[usize]) -> Result<Vec<f64>, ParallelError> {
    gather_values(local, counts, true)
}

fn gather_values(
    local: &[f64],
    counts: &[usize],
    root_only: bool,
) -> Result<Vec<f64>, ParallelError> {
    if counts.len() <= 1 {
        return Ok(local.to_vec());
    }
    #[cfg(feature = "petsc")]
    {
        crate::linalg::petsc::gather_values(local, counts, root_only)
            .map_err(|e| ParallelError::Mpi(e.to_string()))
    }
    #[cfg(not(feature = "petsc"))]
    {
        let _ = root_only;
        Err(ParallelError::NoPetsc(counts.len()))
    }
}

/// Ends the run: on several ranks, every rank with `code` (`MPI_Abort`), since the others may
/// be waiting for this one in a collective call; on one, this process.
pub fn abort(code: u8) -> ! {
    #[cfg(feature = "petsc")]
    if distributed() {
        crate::linalg::petsc::abort_world(i32::from(code));
    }
    std::process::exit(i32::from(code))
}

/// Finalizes MPI on a run that joined it (mpirun reports a rank that exits without it as
/// ended improperly). Every PETSc object must be gone.
pub fn finish() -> Result<(), ParallelError> {
    #[cfg(feature = "petsc")]
    if announced_size().is_some() {
        return crate::linalg::petsc::finalize().map_err(|e| ParallelError::Mpi(e.to_string()));
    }
    Ok(())
}
