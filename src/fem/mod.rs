//! P1 linear elasticity: materials, element kernels, assembly, loads and constraints.
//!
//! Small-strain linear elasticity, `-div sigma(u) = b` in the body, `sigma n = t` on loaded
//! boundaries, `u_k = g_k` on Dirichlet groups, with `sigma = lambda tr(eps) I + 2 mu eps` and
//! `eps = (grad u + grad u^T) / 2`; plane strain in 2D. The discrete problem is `K u = f` with
//! P1 (linear, continuous) displacements on simplices.
//!
//! The element kernels ([`kernels`]) are separate from the global scatter ([`assembly`]), which
//! fills a pattern computed once ([`SparsityPattern`]).

pub mod assembly;
mod columns;
mod dirichlet;
pub mod kernels;
mod load_vector;
pub mod loads;
mod material;
pub mod rigid_modes;
mod sparsity;
pub mod stress;

pub use columns::NodeColumns;
pub use dirichlet::Constraints;
pub use load_vector::LoadVector;
pub use material::{Material, MaterialError};
pub use sparsity::{NodeGraph, SparsityPattern};
