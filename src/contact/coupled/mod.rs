//! The linear algebra of an active-set iteration, for any number of bodies and pairs: the
//! coupled system of an active set, the INTERNODES interface operators that couple the bodies
//! in it, and the ways to solve it. Its files, in order:
//! `compliance.rs` (the bodies' responses to unit tractions), `row_ownership.rs` (which
//! unknowns a rank of a distributed run owns), `system.rs` (the coupled system of an active
//! set), `interface.rs` (the interface operators, built once over all candidates:
//! the interpolation evaluated at each node's closest point on the other surface, the contact
//! normal), `far_field.rs` (sums of a slowly decaying kernel with the zone's far part lumped into
//! clusters), `two_level_inverse.rs` (an approximate inverse of a boundary-integral operator on a
//! zone too large to factor), `half_space.rs` (the interface Schur complement approximated by two
//! elastic half-spaces), `krylov_layout.rs` (how a process holds the vectors of the coupled
//! GMRES), `coupled_krylov.rs` (the whole coupled system by that preconditioned GMRES),
//! `coupled_solver.rs` (which solver, behind one call).

pub mod compliance;
pub mod coupled_krylov;
pub mod coupled_solver;
pub mod far_field;
pub mod half_space;
pub mod interface;
pub mod krylov_layout;
pub mod row_ownership;
pub mod system;
pub mod two_level_inverse;
