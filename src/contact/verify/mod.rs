//! The last iterate of the active-set loop measured without the loop's operators, and made
//! into the answer. Its files, in order:
//! `checks.rs` (the certificate: the residuals that decide the status, the accuracy report),
//! `hertz.rs` (a Hertz profile fitted to the pressure), `post.rs` (the fields and forces of the
//! last iterate: each body's solution, the interface fields of both surfaces, total forces).

pub mod checks;
pub mod hertz;
pub mod post;
