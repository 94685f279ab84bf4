//! The active-set loop of a load step over every pair, decided together, and when it stops
//! (the active set it updates, [`crate::contact::active_set`], comes before: a solution carries
//! it). Its files, in order:
//! `safeguard.rs` (when the loop stops, and how it avoids repeating itself), `anderson.rs` (how
//! the slip directions of 3D friction settle), `solve.rs` (the loop,
//! [`crate::contact::ContactSolver`]).

pub mod anderson;
pub mod safeguard;
pub mod solve;
