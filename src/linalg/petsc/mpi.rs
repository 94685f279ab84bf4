//! The MPI calls of a distributed run, through PETSc's initialization of MPI: this process's
//! place among the ranks, gathering and exchanging values, broadcasting bytes, aborting and
//! finalizing
//! (`crate::parallel` puts them behind calls that also work without PETSc).

use std::ffi::{c_char, c_int};

use super::runtime::{petsc, petsc_error};
use crate::linalg::LinalgError;
use crate::parallel::ranks::Ranks;

unsafe extern "C" {
    fn internodes_mpi_rank_size(
        rank: *mut c_int,
        size: *mut c_int,
        step: *mut *const c_char,
    ) -> c_int;
    fn internodes_mpi_gather(
        local: *const f64,
        count: c_int,
        global: *mut f64,
        counts: *const c_int,
        displs: *const c_int,
        root_only: c_int,
        step: *mut *const c_char,
    ) -> c_int;
    fn internodes_mpi_exchange(
        sent: *const f64,
        send_counts: *const c_int,
        send_displs: *const c_int,
        received: *mut f64,
        recv_counts: *const c_int,
        recv_displs: *const c_int,
        step: *mut *const c_char,
    ) -> c_int;
    fn internodes_mpi_exchange_counts(
        send_counts: *const c_int,
        recv_counts: *mut c_int,
        step: *mut *const c_char,
    ) -> c_int;
    fn internodes_mpi_broadcast_length(len: *mut i64, step: *mut *const c_char) -> c_int;
    fn internodes_mpi_broadcast(data: *mut u8, len: i64, step: *mut *const c_char) -> c_int;
    fn internodes_mpi_scatter_count(
        counts: *const i64,
        mine: *mut i64,
        step: *mut *const c_char,
    ) -> c_int;
    fn internodes_mpi_scatter_cells(
        all: *const u32,
        counts: *const c_int,
        displs: *const c_int,
        mine: *mut u32,
        count: c_int,
        width: c_int,
        step: *mut *const c_char,
    ) -> c_int;
    fn internodes_mpi_abort(code: c_int);
    fn internodes_petsc_finalize(step: *mut *const c_char) -> c_int;
}

/// This process's rank and the number of ranks of `PETSC_COMM_WORLD` (initializes PETSc, and
/// MPI, if needed: collective the first time).
pub fn world_ranks() -> Result<Ranks, LinalgError> {
    let _lock = petsc()?;
    let (mut rank, mut size) = (0, 0);
    let mut step = std::ptr::null();
    // SAFETY: PETSc is initialized, the lock is held.
    let code = unsafe { internodes_mpi_rank_size(&mut rank, &mut size, &mut step) };
    if code != 0 {
        return Err(petsc_error(step, code));
    }
    Ok(Ranks {
        rank: rank as usize,
        size: size as usize,
    })
}

/// An MPI count: the counts of our vectors fit in an `int` as long as PETSc's 32-bit indices do.
fn mpi_count(n: usize) -> Result<c_int, LinalgError> {
    c_int::try_from(n).map_err(|_| LinalgError::Sizes(format!("{n} values in one MPI message")))
}

/// `counts` as MPI counts, and where each rank's part starts (`MPI_Allgatherv`'s and
/// `MPI_Scatterv`'s `displs`).
fn counts_and_displacements(counts: &[usize]) -> Result<(Vec<c_int>, Vec<c_int>), LinalgError> {
    let mut displs = Vec::with_capacity(counts.len());
    let mut at = 0;
    for &count in counts {
        displs.push(mpi_count(at)?);
        at += count;
    }
    let counts = counts
        .iter()
        .map(|&c| mpi_count(c))
        .collect::<Result<Vec<_>, _>>()?;
    Ok((counts, displs))
}

/// Every rank's `local` values (`counts[r]` from rank r, this rank's being `local`), in rank
/// order, on every rank, or with `root_only` on rank 0 alone (the others receive an empty
/// vector); collective over `PETSC_COMM_WORLD`.
pub fn gather_values(
    local: &[f64],
    counts: &[usize],
    root_only: bool,
) -> Result<Vec<f64>, LinalgError> {
    let receives = !root_only || world_ranks()?.rank == 0;
    let total = if receives { counts.iter().sum() } else { 0 };
    let (counts, displs) = counts_and_displacements(counts)?;
    let mut global = vec![0.0; total];
    let mut step = std::ptr::null();
    let _lock = petsc()?;
    // SAFETY: where it receives, `global` holds the sum of `counts`; `counts` and `displs`
    // hold one value per rank, `local` this rank's count; the lock is held.
    let code = unsafe {
        internodes_mpi_gather(
            local.as_ptr(),
            mpi_count(local.len())?,
            global.as_mut_ptr(),
            counts.as_ptr(),
            displs.as_ptr(),
            c_int::from(root_only),
            &mut step,
        )
    };
    match code {
        0 => Ok(global),
        _ => Err(petsc_error(step, code)),
    }
}

/// What every rank sent this one: `sends[r]` goes to rank r, and the result's `r`th vector
/// is what rank r sent this one (`MPI_Alltoall` of the counts, then `MPI_Alltoallv`;
/// collective over `PETSC_COMM_WORLD`, `sends` holding one vector per rank).
pub fn exchange_values(sends: &[Vec<f64>]) -> Result<Vec<Vec<f64>>, LinalgError> {
    let send_lengths: Vec<usize> = sends.iter().map(Vec::len).collect();
    let (send_counts, send_displs) = counts_and_displacements(&send_lengths)?;
    let mut recv_counts = vec![0 as c_int; sends.len()];
    let mut step = std::ptr::null();
    let _lock = petsc()?;
    // SAFETY: both arrays hold one value per rank (the caller's contract); the lock is held.
    let code = unsafe {
        internodes_mpi_exchange_counts(send_counts.as_ptr(), recv_counts.as_mut_ptr(), &mut step)
    };
    if code != 0 {
        return Err(petsc_error(step, code));
    }
    let recv_lengths: Vec<usize> = recv_counts.iter().map(|&c| c as usize).collect();
    let (_, recv_displs) = counts_and_displacements(&recv_lengths)?;
    let sent: Vec<f64> = sends.concat();
    let mut received = vec![0.0; recv_lengths.iter().sum()];
    // SAFETY: `sent` holds the sum of `send_counts` values, `received` the sum of
    // `recv_counts`, the counts and displacements one value per rank; the lock is held.
    let code = unsafe {
        internodes_mpi_exchange(
            sent.as_ptr(),
            send_counts.as_ptr(),
            send_displs.as_ptr(),
            received.as_mut_ptr(),
            recv_counts.as_ptr(),
            recv_displs.as_ptr(),
            &mut step,
        )
    };
    if code != 0 {
        return Err(petsc_error(step, code));
    }
    let mut rest = &received[..];
    Ok((recv_lengths.iter())
        .map(|&n| {
            let (from, after) = rest.split_at(n);
            rest = after;
            from.to_vec()
        })
        .collect())
}

/// Rank 0's `bytes` on every rank (collective over `PETSC_COMM_WORLD`; the other ranks'
/// `bytes` are not read).
pub fn broadcast_bytes(bytes: Vec<u8>) -> Result<Vec<u8>, LinalgError> {
    let mut len = bytes.len() as i64;
    let mut step = std::ptr::null();
    let _lock = petsc()?;
    // SAFETY: the lock is held; `len` is one value.
    let code = unsafe { internodes_mpi_broadcast_length(&mut len, &mut step) };
    if code != 0 {
        return Err(petsc_error(step, code));
    }
    let mut data = bytes;
    data.resize(len.max(0) as usize, 0);
    // SAFETY: `data` holds `len` bytes on every rank; the lock is held.
    let code = unsafe { internodes_mpi_broadcast(data.as_mut_ptr(), len, &mut step) };
    match code {
        0 => Ok(data),
        _ => Err(petsc_error(step, code)),
    }
}

/// Each rank's cells from rank 0 (collective over `PETSC_COMM_WORLD`): on rank 0, `all` holds
/// every rank's cells one rank after the other, `counts[r]` cells of `width` values for rank
/// r; on the others both are empty. Returns this rank's `width * counts[rank]` values.
pub fn scatter_cells(all: &[u32], counts: &[usize], width: usize) -> Result<Vec<u32>, LinalgError> {
    let mut step = std::ptr::null();
    let counts64: Vec<i64> = counts.iter().map(|&c| c as i64).collect();
    let mut mine = 0i64;
    let _lock = petsc()?;
    // SAFETY: on rank 0 `counts64` holds a value per rank (the caller's contract), read there
    // only; `mine` is one value; the lock is held.
    let code = unsafe { internodes_mpi_scatter_count(counts64.as_ptr(), &mut mine, &mut step) };
    if code != 0 {
        return Err(petsc_error(step, code));
    }
    let (counts, displs) = counts_and_displacements(counts)?;
    let mut cells = vec![0u32; width * mine as usize];
    // SAFETY: on rank 0 `all` holds `width` values for each of the counts' cells, `counts` and
    // `displs` one value per rank; `cells` holds this rank's count of cells; the lock is held.
    let code = unsafe {
        internodes_mpi_scatter_cells(
            all.as_ptr(),
            counts.as_ptr(),
            displs.as_ptr(),
            cells.as_mut_ptr(),
            mpi_count(mine as usize)?,
            mpi_count(width)?,
            &mut step,
        )
    };
    match code {
        0 => Ok(cells),
        _ => Err(petsc_error(step, code)),
    }
}

/// Ends every rank of the run with `code` (`MPI_Abort`).
pub fn abort_world(code: i32) -> ! {
    // No lock: the thread that holds it may be the one waiting for the other ranks.
    // SAFETY: PETSc (MPI) is initialized in a distributed run; MPI_Abort does not return.
    unsafe { internodes_mpi_abort(code) };
    std::process::exit(code)
}

/// `PetscFinalize` (and MPI's): the last PETSc call of the process.
pub fn finalize() -> Result<(), LinalgError> {
    let _lock = petsc()?;
    let mut step = std::ptr::null();
    // SAFETY: the lock is held; the caller has dropped every PETSc object.
    match unsafe { internodes_petsc_finalize(&mut step) } {
        0 => Ok(()),
        code => Err(petsc_error(step, code)),
    }
}
