//! Cancelling a solve from outside it: a [`Cancel`] token shared with the caller, which the
//! solve checks at safe points (each load step, each active-set iteration, each coupled GMRES
//! iteration) and answers with [`Cancelled`]. A cancelled solve leaves nothing behind: its
//! error unwinds the solve like any other.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use thiserror::Error;

/// A cancellation token: clones share one flag. The default token is never cancelled unless
/// [`Cancel::cancel`] is called on it or a clone.
#[derive(Debug, Clone, Default)]
pub struct Cancel(Arc<AtomicBool>);

/// The error of a solve stopped by its [`Cancel`] token.
#[derive(Debug, Error, Clone, Copy, PartialEq, Eq)]
#[error("the solve was cancelled")]
pub struct Cancelled;

impl Cancel {
    /// A new token, not cancelled.
    pub fn new() -> Self {
        Self::default()
    }

    /// Asks every solve holding this token (or a clone) to stop at its next safe point.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// Whether [`Cancel::cancel`] was called.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }

    /// `Err(Cancelled)` once cancelled: `token.check()?` at a safe point.
    pub fn check(&self) -> Result<(), Cancelled> {
        match self.is_cancelled() {
            true => Err(Cancelled),
            false => Ok(()),
        }
    }
}

/// Settings compare equal whatever their tokens: a token is not a setting of the answer.
impl PartialEq for Cancel {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clones_share_the_flag() {
        let token = Cancel::new();
        let clone = token.clone();
        assert_eq!(clone.check(), Ok(()));
        token.cancel();
        assert!(clone.is_cancelled());
        assert_eq!(clone.check(), Err(Cancelled));
    }
}
