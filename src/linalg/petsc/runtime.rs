//! PETSc's initialization and the lock that orders every PETSc call of the process (the
//! parent module's doc says why both are needed and how they are used).

use std::ffi::{CStr, c_char, c_int};
use std::sync::{OnceLock, PoisonError, RwLock, RwLockWriteGuard};

use crate::linalg::LinalgError;

/// MPI's Fortran communicator handle (`MPI_Fint`, an `int` in Open MPI and MPICH alike).
pub(super) type MpiFint = c_int;

unsafe extern "C" {
    fn internodes_petsc_initialize(step: *mut *const c_char) -> c_int;
    fn internodes_petsc_options_are_ours(ours: *mut c_int, step: *mut *const c_char) -> c_int;
    fn internodes_petsc_error_text(code: c_int) -> *const c_char;
}

/// Orders every PETSc call of the process: V-cycles ([`super::CgAmg::precondition`]) take it shared,
/// every other call exclusively (see the module's doc).
pub(super) static PETSC: RwLock<()> = RwLock::new(());
/// The outcome of PETSc's initialization (made once, under [`PETSC`] held exclusively): on
/// success, whether V-cycles of distinct objects may run at once (no option in PETSc's
/// database but ours).
static INITIALIZED: OnceLock<Result<bool, (String, i32)>> = OnceLock::new();

/// Whether V-cycles ([`super::CgAmg::precondition`]) of distinct objects run at the same time: PETSc
/// is initialized and its options database holds no option but ours (see the module's doc).
pub fn concurrent_v_cycles() -> bool {
    matches!(INITIALIZED.get(), Some(Ok(true)))
}

/// A C string from the shim (static storage) as Rust text.
pub(super) fn text(s: *const c_char) -> String {
    if s.is_null() {
        return String::from("?");
    }
    // SAFETY: the shim returns null or pointers to static NUL-terminated strings.
    unsafe { CStr::from_ptr(s) }.to_string_lossy().into_owned()
}

pub(super) fn petsc_error(step: *const c_char, code: c_int) -> LinalgError {
    LinalgError::Petsc {
        step: text(step),
        code,
        // SAFETY: plain lookup of a static string.
        message: text(unsafe { internodes_petsc_error_text(code) }),
    }
}

/// The PETSc lock held exclusively, with PETSc initialized. A poisoned lock is taken anyway:
/// a panic cannot happen inside a PETSc call (they return codes), so PETSc's state is whole.
pub(super) fn petsc() -> Result<RwLockWriteGuard<'static, ()>, LinalgError> {
    let guard = PETSC.write().unwrap_or_else(PoisonError::into_inner);
    let outcome = INITIALIZED.get_or_init(|| {
        let mut step = std::ptr::null();
        // SAFETY: called once per process, under the exclusive lock.
        let code = unsafe { internodes_petsc_initialize(&mut step) };
        if code != 0 {
            return Err((text(step), code));
        }
        // SAFETY: PETSc is initialized; the exclusive lock is held.
        unsafe { database_is_ours() }.map_err(|(step, code)| (text(step), code))
    });
    match outcome {
        Ok(_) => Ok(guard),
        Err((step, code)) => Err(LinalgError::Petsc {
            step: format!("initializing PETSc: {step}"),
            code: *code,
            message: text(unsafe { internodes_petsc_error_text(*code) }),
        }),
    }
}

/// Whether PETSc's options database holds no option but ours now. It is read once at
/// initialization ([`concurrent_v_cycles`]); an option set for one call (the shim's
/// `-matptap_via` around a one-process GAMG set-up) must be gone after it, which this tells.
pub fn options_are_ours() -> Result<bool, LinalgError> {
    let _guard = petsc()?;
    // SAFETY: `petsc` initialized PETSc and holds the exclusive lock.
    unsafe { database_is_ours() }.map_err(|(step, code)| petsc_error(step, code))
}

/// The shim's `internodes_petsc_options_are_ours`: the shim's step and code of a failure.
///
/// # Safety
/// PETSc is initialized and the caller holds [`PETSC`] exclusively.
unsafe fn database_is_ours() -> Result<bool, (*const c_char, c_int)> {
    let (mut ours, mut step) = (0, std::ptr::null());
    // SAFETY: the caller's guarantee.
    let code = unsafe { internodes_petsc_options_are_ours(&mut ours, &mut step) };
    if code == 0 {
        Ok(ours != 0)
    } else {
        Err((step, code))
    }
}
