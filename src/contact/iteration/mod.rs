//! The active-set loop of a load step over every pair, decided together, and when it stops
//! (the active set it updates, [`crate::contact::active_set`], comes before: a solution carries
//! it). Its files, in order:
//! `safeguard.rs` (when the loop stops, and how it avoids repeating itself), `walls.rs` (which walls at a concave
//! vertex the loop holds), `solve.rs` (the loop, [`crate::contact::ContactSolver`]).

pub mod safeguard;
pub mod solve;
pub mod walls;
