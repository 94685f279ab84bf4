//! The geometry of the contact surfaces and the interpolation between them: what a solve
//! measures and interpolates on, with no method (no active set, no coupled system) and no
//! contact law. Its files, in order:
//! `displacement.rs` (a body's displacement, whole or at its boundary's nodes), `projection.rs`
//! (closest points on a P1 surface), `boundary.rs` (a body's closed boundary,
//! which tells inside from outside), `rbf_patch.rs` (solves with a sparse matrix restricted to a patch of its graph), `rbf.rs`
//! (rescaled Wendland C2 interpolation),
//! `surface.rs` (a candidate surface: nodes, facets, spacings, lumped interface mass), `gap.rs`
//! (the geometric gap, and the gap linearized at an iterate), `walls.rs` (the second facet a node
//! in a concave vertex must not cross).

pub mod boundary;
pub mod displacement;
pub mod gap;
pub mod projection;
pub mod rbf;
pub mod rbf_patch;
pub mod surface;
pub mod walls;
