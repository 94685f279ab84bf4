//! Progress lines of long phases, so that a run of minutes never looks hung.
//!
//! A [`Heartbeat`] covers one phase (meshing, an assembly, a body solver's set-up, one
//! active-set iteration, ...): from 5 seconds on, the process's progress thread says how long
//! the phase has been running, every 5 seconds (every 30 seconds after the first minute: an
//! hour-long phase written to a log file adds about a hundred lines, not seven hundred), until
//! the phase ends ([`Cadence::DEFAULT`]). A phase shorter than 5 seconds says nothing. Code
//! deep inside a phase that knows how far it is (the coupled GMRES) adds that to the next line
//! with [`note`].
//!
//! The lines are `log` records at level info with the target [`TARGET`]: the command line
//! rewrites one line in place on a terminal and prints plain lines elsewhere (a log file, a
//! pipe); the Python module hands them to `logging` like every other message. A thread rather
//! than checks sprinkled through the phases: most of the time of a long phase is spent inside
//! one call (a factorization, PETSc's AMG set-up) that cannot report.

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
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

/// What the progress thread and a phase share: the phase's own word on how far it is
/// ([`note`]), shown with its next line.
struct Shared {
    note: Mutex<Option<String>>,
}

thread_local! {
    /// The innermost heartbeat started on this thread, which [`note`] writes to.
    static CURRENT: RefCell<Option<Arc<Shared>>> = const { RefCell::new(None) };
}

/// A running phase, as the progress thread sees it.
struct Beat {
    what: String,
    start: Instant,
    cadence: Cadence,
    /// When its next line is due, from its start.
    next: Duration,
    shared: Arc<Shared>,
}

/// The running phases of the process, by number, and the one thread that writes their lines.
///
/// One thread for the whole process, started with the first heartbeat, rather than one per
/// phase: with a thread per phase (each active-set iteration, each step of an assembly) a
/// serial run of a million unknowns peaked 120 to 180 MB above its runs with one thread in two
/// of three runs, where those three peaked within 6 MB of each other (`docs/decisions.md`,
/// where the likely cause, glibc's per-thread malloc arenas, is discussed).
struct Board {
    beats: Mutex<(u64, BTreeMap<u64, Beat>)>,
    changed: Condvar,
}

impl Board {
    /// The process's board; its thread starts with the first call. A process forked after
    /// its parent's thread started (a Python process pool) has a copy of the board but no
    /// thread, so it starts a board of its own.
    fn get() -> &'static Board {
        static BOARD: Mutex<Option<(u32, &'static Board)>> = Mutex::new(None);
        let pid = std::process::id();
        let mut slot = BOARD.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((owner, board)) = *slot
            && owner == pid
        {
            return board;
        }
        // One per process, for its lifetime: leaked, like the thread that reads it.
        let board: &'static Board = Box::leak(Box::new(Board {
            beats: Mutex::new((0, BTreeMap::new())),
            changed: Condvar::new(),
        }));
        // Never joined: it sleeps while no phase runs, and ends with the process.
        let spawned = std::thread::Builder::new()
            .name("internodes-progress".into())
            .spawn(|| board.write_lines());
        if let Err(e) = spawned {
            log::debug!("no progress lines: their thread did not start ({e})");
        }
        *slot = Some((pid, board));
        board
    }

    fn lock(&self) -> MutexGuard<'_, (u64, BTreeMap<u64, Beat>)> {
        self.beats.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The progress thread: sleeps until the next line is due (or a phase starts or ends),
    /// then writes the lines due. They are written under the lock, so a phase that ends
    /// waits for its line being written and none follows its end (a logger's time is the
    /// phase's, as when each phase joined a thread of its own).
    fn write_lines(&self) {
        let mut beats = self.lock();
        loop {
            let due = (beats.1.values()).map(|b| b.start + b.next).min();
            beats = match due {
                None => (self.changed.wait(beats)).unwrap_or_else(|e| e.into_inner()),
                Some(due) => {
                    let wait = due.saturating_duration_since(Instant::now());
                    (self.changed.wait_timeout(beats, wait))
                        .unwrap_or_else(|e| e.into_inner())
                        .0
                }
            };
            for beat in beats.1.values_mut() {
                let elapsed = beat.start.elapsed();
                if elapsed < beat.next {
                    continue;
                }
                let note = (beat.shared.note.lock().unwrap_or_else(|e| e.into_inner()))
                    .as_ref()
                    .map_or(String::new(), |n| format!(" ({n})"));
                let what = &beat.what;
                log::info!(target: TARGET, "{what}: {:.0} s{note}", elapsed.as_secs_f64());
                beat.next = elapsed
                    + match elapsed < beat.cadence.slower_after {
                        true => beat.cadence.every,
                        false => beat.cadence.slower,
                    };
            }
        }
    }
}

/// Progress lines of one phase while it lasts ([module doc](self)); ends with the value.
pub struct Heartbeat {
    /// Its number on the [`Board`], and what it shares with the progress thread.
    running: Option<(u64, Arc<Shared>)>,
    /// The heartbeat this one covers, current again when this one ends.
    outer: Option<Arc<Shared>>,
}

impl Heartbeat {
    /// Starts the progress lines of the phase `what` ("  iteration 3"), unless `verbose` is
    /// false or nothing would print them (`--quiet`, a rank other than 0 of a distributed run,
    /// a library user without a logger): then it is inert.
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
            note: Mutex::new(None),
        });
        let board = Board::get();
        let id = {
            let mut beats = board.lock();
            let id = beats.0;
            beats.0 += 1;
            let beat = Beat {
                what: what.into(),
                start: Instant::now(),
                cadence,
                next: cadence.first,
                shared: Arc::clone(&shared),
            };
            beats.1.insert(id, beat);
            id
        };
        board.changed.notify_one();
        let outer = CURRENT.with(|c| c.replace(Some(Arc::clone(&shared))));
        Self {
            running: Some((id, shared)),
            outer,
        }
    }
}

impl Drop for Heartbeat {
    fn drop(&mut self) {
        if let Some((id, _)) = self.running.take() {
            CURRENT.with(|c| c.replace(self.outer.take()));
            let board = Board::get();
            board.lock().1.remove(&id);
            board.changed.notify_one();
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
