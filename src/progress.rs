//! Progress lines of long phases, so that a run of minutes never looks hung.
//!
//! A [`Heartbeat`] covers one phase (meshing, an assembly, a body solver's set-up, one
//! active-set iteration, ...): from 5 seconds on, a thread of its own says how long the phase
//! has been running, every 5 seconds (every 30 seconds after the first minute: an hour-long
//! phase written to a log file adds about a hundred lines, not seven hundred), until the phase
//! ends ([`Cadence::DEFAULT`]). A phase shorter than 5 seconds says nothing. Code deep inside
//! a phase that knows how far it is (the coupled GMRES) adds that to the next line with
//! [`note`].
//!
//! The lines are `log` records at level info with the target [`TARGET`]: the command line
//! rewrites one line in place on a terminal and prints plain lines elsewhere (a log file, a
//! pipe); the Python module hands them to `logging` like every other message. A thread rather
//! than checks sprinkled through the phases: most of the time of a long phase is spent inside
//! one call (a factorization, PETSc's AMG set-up) that cannot report.

use std::cell::RefCell;
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// The `log` target of progress lines.
pub const TARGET: &str = "internodes::progress";

/// When a heartbeat speaks.
#[derive(Debug, Clone, Copy)]
pub struct Cadence {
    /// Nothing before this.
    pub first: Duration,
    /// Between two lines, until `slower_after`.
    pub every: Duration,
    /// Between two lines after `slower_after`.
    pub slower: Duration,
    pub slower_after: Duration,
}

impl Cadence {
    /// The command line's and the Python module's ([module doc](self)).
    pub const DEFAULT: Cadence = Cadence {
        first: Duration::from_secs(5),
        every: Duration::from_secs(5),
        slower: Duration::from_secs(30),
        slower_after: Duration::from_secs(60),
    };
}

/// What a heartbeat's thread shares with the phase.
struct Shared {
    /// Set when the phase ends.
    done: Mutex<bool>,
    ended: Condvar,
    /// The phase's own word on how far it is ([`note`]), shown with the next line.
    note: Mutex<Option<String>>,
}

thread_local! {
    /// The innermost heartbeat started on this thread, which [`note`] writes to.
    static CURRENT: RefCell<Option<Arc<Shared>>> = const { RefCell::new(None) };
}

/// Progress lines of one phase while it lasts ([module doc](self)); ends with the value.
pub struct Heartbeat {
    running: Option<(Arc<Shared>, JoinHandle<()>)>,
    /// The heartbeat this one covers, current again when this one ends.
    outer: Option<Arc<Shared>>,
}

impl Heartbeat {
    /// Starts the progress lines of the phase `what` ("  iteration 3"), unless `verbose` is
    /// false or nothing would print them (`--quiet`, a rank other than 0 of a distributed run,
    /// a library user without a logger): then it is inert and starts no thread.
    pub fn start(verbose: bool, what: impl Into<String>) -> Self {
        Self::with_cadence(verbose, what, Cadence::DEFAULT)
    }

    /// [`Heartbeat::start`] at another `cadence`.
    pub fn with_cadence(verbose: bool, what: impl Into<String>, cadence: Cadence) -> Self {
        if !verbose || !log::log_enabled!(target: TARGET, log::Level::Info) {
            return Self {
                running: None,
                outer: None,
            };
        }
        let shared = Arc::new(Shared {
            done: Mutex::new(false),
            ended: Condvar::new(),
            note: Mutex::new(None),
        });
        let what = what.into();
        let beat = Arc::clone(&shared);
        let start = Instant::now();
        let thread = std::thread::spawn(move || {
            let lock = || beat.done.lock().unwrap_or_else(|e| e.into_inner());
            let mut next = cadence.first;
            loop {
                // `done` is read under the lock the wait releases: an end signalled before
                // the wait began (a phase shorter than the thread's start) is not missed.
                let mut done = lock();
                while !*done && start.elapsed() < next {
                    let wait = next.saturating_sub(start.elapsed());
                    done = (beat.ended.wait_timeout(done, wait))
                        .unwrap_or_else(|e| e.into_inner())
                        .0;
                }
                if *done {
                    return;
                }
                // Not logged under the lock: the phase's end does not wait for a logger.
                drop(done);
                let elapsed = start.elapsed();
                let note = (beat.note.lock().unwrap_or_else(|e| e.into_inner()))
                    .as_ref()
                    .map_or(String::new(), |n| format!(" ({n})"));
                log::info!(target: TARGET, "{what}: {:.0} s{note}", elapsed.as_secs_f64());
                next = elapsed
                    + match elapsed < cadence.slower_after {
                        true => cadence.every,
                        false => cadence.slower,
                    };
            }
        });
        let outer = CURRENT.with(|c| c.replace(Some(Arc::clone(&shared))));
        Self {
            running: Some((shared, thread)),
            outer,
        }
    }
}

impl Drop for Heartbeat {
    fn drop(&mut self) {
        if let Some((shared, thread)) = self.running.take() {
            CURRENT.with(|c| c.replace(self.outer.take()));
            *shared.done.lock().unwrap_or_else(|e| e.into_inner()) = true;
            shared.ended.notify_one();
            // The thread only logs; a panic there (a logger's) is not the phase's.
            let _ = thread.join();
        }
    }
}

/// Tells the innermost heartbeat of this thread how far its phase is (shown with its next
/// line). `text` is called only when a heartbeat runs: a silent run formats nothing.
pub fn note(text: impl FnOnce() -> String) {
    CURRENT.with(|c| {
        if let Some(shared) = c.borrow().as_ref() {
            *shared.note.lock().unwrap_or_else(|e| e.into_inner()) = Some(text());
        }
    });
}
