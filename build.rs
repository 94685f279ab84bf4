//! With the cargo feature `petsc`: compiles src/linalg/petsc/shim.c against PETSc and MPI,
//! both found by pkg-config (`petsc`, and `mpi` for the `mpi.h` that PETSc's headers include
//! and the `MPI_Comm_c2f`/`f2c` the shim calls). Without the feature: nothing.

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    #[cfg(feature = "petsc")]
    petsc();
}

#[cfg(feature = "petsc")]
fn petsc() {
    const SHIM: &str = "src/linalg/petsc/shim.c";
    println!("cargo:rerun-if-changed={SHIM}");
    let probe = |name: &str| {
        pkg_config::Config::new().probe(name).unwrap_or_else(|e| {
            panic!(
                "the feature `petsc` needs the pkg-config package `{name}` \
                 (Debian: libpetsc-real3.18-dev, which brings libopenmpi-dev): {e}"
            )
        })
    };
    let petsc = probe("petsc");
    let mpi = probe("mpi");
    let mut build = cc::Build::new();
    build.file(SHIM).warnings(true).extra_warnings(true);
    for dir in petsc.include_paths.iter().chain(&mpi.include_paths) {
        build.include(dir);
    }
    build.compile("internodes_petsc_shim");
}
