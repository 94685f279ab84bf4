//! Which rank of the run this process is, and how many there are: set once by
//! [`super::start`], read everywhere (the linear algebra hands PETSc its rows by it).

use std::sync::OnceLock;

use serde::Serialize;

/// This process's place in the run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Ranks {
    /// 0 to `size - 1`.
    pub rank: usize,
    /// The number of processes of the run.
    pub size: usize,
}

impl Ranks {
    /// A run of one process.
    pub const ONE: Self = Self { rank: 0, size: 1 };
}

static RUN: OnceLock<Ranks> = OnceLock::new();

/// Records this process's place (the first call wins: [`super::start`] runs once).
pub(super) fn settle(ranks: Ranks) -> Ranks {
    *RUN.get_or_init(|| ranks)
}

/// This process's place in the run (one rank unless [`super::start`] joined more).
pub fn ranks() -> Ranks {
    RUN.get().copied().unwrap_or(Ranks::ONE)
}

/// Whether the run has more than one rank.
pub fn distributed() -> bool {
    ranks().size > 1
}

/// Whether this rank writes the results and prints (rank 0).
pub fn is_root() -> bool {
    ranks().rank == 0
}
