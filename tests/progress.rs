//! The progress lines of a long phase ([`internodes::progress`]): none for a short phase, then
//! one at each beat of the cadence with the phase's note, none once the phase has ended. The
//! cadence is scaled down to milliseconds; the command line's is 5 s.

use std::sync::Mutex;
use std::time::Duration;

use internodes::progress::{Cadence, Heartbeat, TARGET, note};

/// Keeps the progress records.
struct Capture(Mutex<Vec<String>>);

static CAPTURE: Capture = Capture(Mutex::new(Vec::new()));

impl log::Log for Capture {
    fn enabled(&self, metadata: &log::Metadata) -> bool {
        metadata.level() <= log::max_level()
    }

    fn log(&self, record: &log::Record) {
        if record.target() == TARGET && record.level() == log::Level::Info {
            self.0.lock().unwrap().push(record.args().to_string());
        }
    }

    fn flush(&self) {}
}

fn taken() -> Vec<String> {
    std::mem::take(&mut *CAPTURE.0.lock().unwrap())
}

const CADENCE: Cadence = Cadence {
    first: Duration::from_millis(200),
    every: Duration::from_millis(200),
    slower: Duration::from_secs(3600),
    slower_after: Duration::from_secs(3600),
};

// One test: the logger and its level are the process's.
#[test]
fn a_long_phase_says_how_long_it_runs_a_short_one_nothing() {
    log::set_logger(&CAPTURE).unwrap();
    log::set_max_level(log::LevelFilter::Info);

    // A phase shorter than the first beat.
    drop(Heartbeat::with_cadence(true, "short", CADENCE));
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(taken(), Vec::<String>::new());

    // A phase ends when it ends, even before its heartbeat's thread has begun to wait (an
    // end signalled then once went unseen, and each active-set iteration of a small case
    // took the 5 s of the first beat).
    let patient = Cadence {
        first: Duration::from_secs(60),
        ..CADENCE
    };
    let clock = std::time::Instant::now();
    for _ in 0..50 {
        drop(Heartbeat::with_cadence(true, "instant", patient));
    }
    assert!(
        clock.elapsed() < Duration::from_secs(5),
        "{:?}",
        clock.elapsed()
    );

    // A phase of five beats and a bit, with a note after the second.
    let beat = Heartbeat::with_cadence(true, "  long", CADENCE);
    std::thread::sleep(Duration::from_millis(500));
    note(|| "halfway".to_string());
    std::thread::sleep(Duration::from_millis(600));
    drop(beat);
    std::thread::sleep(Duration::from_millis(300));
    let lines = taken();
    // Beats at 0.2, 0.4, 0.6, 0.8 and 1.0 s; a loaded machine may lose one.
    assert!((4..=5).contains(&lines.len()), "{lines:?}");
    assert!(lines.iter().all(|l| l.starts_with("  long: ")), "{lines:?}");
    assert!(!lines[0].contains("halfway"), "{lines:?}");
    assert!(lines.last().unwrap().ends_with(" s (halfway)"), "{lines:?}");

    // Not verbose, or nothing would print the lines (--quiet): no line, no note taken.
    for (verbose, level) in [
        (false, log::LevelFilter::Info),
        (true, log::LevelFilter::Warn),
    ] {
        log::set_max_level(level);
        let beat = Heartbeat::with_cadence(verbose, "silent", CADENCE);
        let mut noted = false;
        note(|| {
            noted = true;
            String::new()
        });
        std::thread::sleep(Duration::from_millis(300));
        drop(beat);
        assert!(!noted);
        assert_eq!(taken(), Vec::<String>::new());
    }
}
