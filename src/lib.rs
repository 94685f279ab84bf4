//! # internodes
//!
//! Elastic bodies with non-matching meshes in contact (frictionless, tied or Coulomb), solved
//! with the INTERNODES method (Deparis, Forti, Gervasio, Quarteroni 2016), or with a penalty
//! beside it; the method is described in `docs/method.md`.
//!
//! Each body `k` is a P1 linear-elastic body, `K_k u_k = f_k`. Two bodies in contact are
//! coupled on their active interface nodes through rescaled Wendland C2 radial-basis
//! interpolation (`R12`, `R21`) and the interface (surface) mass matrices `M1`, `M2`:
//!
//! ```text
//! [ K1   0    -M1        ] [u1    ]   [f1]
//! [ 0    K2    M2 R21    ] [u2    ] = [f2]
//! [ I   -R12   0         ] [lambda]   [d ]
//! ```
//!
//! with `lambda` the traction on body 1 and `d` the nodal gaps, the active set updated until no
//! node is in tension and none penetrates (`docs/method.md`, section 3).
//!
//! The crate is organised as the solve proceeds:
//! - [`mesh`]: gmsh MSH 4.1 input, bodies and boundary groups by physical name;
//! - [`fem`]: P1 elasticity kernels, sparsity patterns, assembly, loads, Dirichlet conditions;
//! - [`linalg`]: fill-reducing orderings, the sparse Cholesky factorization, and the iterative
//!   body solver (PETSc CG + GAMG, cargo feature `petsc`) beside it;
//! - [`elastic`]: one body's problem, solve and solution;
//! - [`contact`]: two bodies coupled by INTERNODES: interpolation, interface operators, the
//!   coupled system and its solvers, the active-set loop;
//! - [`case`]: the TOML case file;
//! - [`output`]: XDMF/HDF5, JSON summary, Matrix Market;
//! - [`cancel`]: the token that stops a solve from outside it;
//! - [`parallel`]: the MPI ranks of a distributed run (`mpirun -n N internodes solve`);
//! - [`progress`]: progress lines of long phases;
//! - [`run`]: `internodes solve CASE`, from the case file to the result files;
//! - [`study`]: `internodes study CASE`, a mesh refinement study with the grid convergence index.
//!
//! **Threads.** The work runs on rayon's threads, cut into parts fixed by the problem, so that
//! the answers are the same bits for any number of threads. faer's dense and sparse LU
//! factorizations (the RBF patches, the half-space preconditioner, the Schur complement) take
//! faer's global parallelism, whose default cuts the work by the thread count: the command
//! line and the Python module set it to `faer::Par::Seq` before anything is solved, and a
//! program that calls this library should do the same for its answers not to depend on the
//! thread count.

pub mod cancel;
pub mod case;
pub mod contact;
pub mod elastic;
pub mod fem;
pub mod linalg;
pub mod mesh;
pub mod output;
pub mod parallel;
pub mod progress;
pub mod run;
pub mod study;
