//! The `internodes` command line: `solve CASE`, `study CASE --parameter NAME=V1,V2,...` and
//! `info MESH`.

use std::error::Error;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicI32, Ordering};
use std::sync::{Mutex, OnceLock};

use clap::{Parser, Subcommand};
use internodes::cancel::Cancel;
use internodes::case::Case;
use internodes::mesh::{MeshSummary, read_msh};
use internodes::output::{Verdict, unsaid_causes};
use internodes::parallel;
use internodes::run::{RunOptions, solve_case};
use internodes::study::{StudyOptions, StudySpec, files::markdown, run_study};

#[derive(Parser)]
#[command(version, about = "Elastic bodies in contact, solved with INTERNODES")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Solve the case described by a TOML case file.
    Solve {
        /// The case file.
        case: PathBuf,
        /// Output folder (overrides the case file's `output`).
        #[arg(long, short)]
        output: Option<PathBuf>,
        /// Also write the assembled stiffness and surface mass matrices (Matrix Market).
        #[arg(long)]
        export_matrices: bool,
        /// Print nothing but errors.
        #[arg(long, short, conflicts_with = "verbose")]
        quiet: bool,
        /// More detail: -v each active-set iteration and the checks, -vv the Krylov solves.
        #[arg(long, short, action = clap::ArgAction::Count)]
        verbose: u8,
    },
    /// Refinement study: solve a .geo case on a sequence of meshes and estimate its error (GCI).
    ///
    /// One solve per value of a gmsh parameter of the case's .geo, each into its own folder; for
    /// the contact force, contact radius and peak pressure the observed order, the Richardson
    /// extrapolation and the grid convergence index (Celik et al. 2008), with flags for a
    /// sequence not in its asymptotic range. See docs/study.md.
    Study {
        /// The case file (its `mesh` a .geo script).
        case: PathBuf,
        /// The gmsh parameter of the .geo and its values, one mesh each: NAME=V1,V2,...
        /// (e.g. level=0,1,2).
        #[arg(long, short)]
        parameter: StudySpec,
        /// The study's folder (default: the case's `output` folder followed by /study).
        #[arg(long, short)]
        output: Option<PathBuf>,
        /// Print nothing but errors.
        #[arg(long, short, conflicts_with = "verbose")]
        quiet: bool,
        /// More detail: -v each active-set iteration and the checks, -vv the Krylov solves.
        #[arg(long, short, action = clap::ArgAction::Count)]
        verbose: u8,
    },
    /// Print the physical groups, element counts and bounding boxes of a gmsh mesh.
    Info {
        /// A gmsh MSH 4.1 file.
        mesh: PathBuf,
    },
}

fn main() -> ExitCode {
    // A closed pipe on stdout or stderr (`internodes solve case 2>&1 | head -1`) ends the
    // process as it ends every Unix tool, by SIGPIPE, instead of a panic in `eprintln!` (Rust
    // ignores SIGPIPE by default and turns the failed write into a panic).
    #[cfg(unix)]
    // SAFETY: restoring the default disposition of a signal before any thread is started.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    // Results must not depend on the number of threads (RAYON_NUM_THREADS). The Cholesky
    // solves guarantee it themselves; faer's sparse LUs (RBF interpolation, the monolithic
    // reference solver) take faer's global setting, whose default splits work by thread count.
    faer::set_global_parallelism(faer::Par::Seq);
    // A usage error (an unknown flag, a missing argument, a bad `--parameter` value) is an
    // error like bad input: exit 1 with clap's message. clap's own exit status for it, 2, is the
    // one that says "contact not solved" here. `--help` and `--version` print and exit 0.
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let usage = e.use_stderr();
            // Nothing useful is left to do if the terminal is gone.
            let _ = e.print();
            return if usage {
                ExitCode::FAILURE
            } else {
                ExitCode::SUCCESS
            };
        }
    };
    // Under an MPI launcher (`mpirun -n N internodes solve CASE`): join the run. Every rank
    // solves; rank 0 alone prints and writes.
    let ranks = match parallel::start() {
        Ok(ranks) => ranks,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    // The levels of docs/output.md ("The log"): info by default, debug with -v, trace with -vv.
    let level = match cli.command {
        _ if ranks.rank != 0 => log::LevelFilter::Warn,
        Command::Solve { quiet: true, .. } | Command::Study { quiet: true, .. } => {
            log::LevelFilter::Warn
        }
        Command::Solve { verbose, .. } | Command::Study { verbose, .. } => match verbose {
            0 => log::LevelFilter::Info,
            1 => log::LevelFilter::Debug,
            _ => log::LevelFilter::Trace,
        },
        Command::Info { .. } => log::LevelFilter::Info,
    };
    // A study's default log is one line per level: each level's own solve log needs -v.
    let study_lines_only =
        matches!(cli.command, Command::Study { .. }) && level == log::LevelFilter::Info;
    StderrLogger::install(level, study_lines_only);
    // Under MPI the ranks would stop at different safe points and wait for each other: the
    // launcher ends them as it ends any program.
    let cancel = match ranks.size {
        1 => cancel_on_interrupt(),
        _ => Cancel::new(),
    };
    let result: Result<u8, Box<dyn Error>> = match cli.command {
        Command::Solve {
            case,
            output,
            export_matrices,
            quiet,
            ..
        } => solve_case(
            &case,
            &RunOptions {
                output,
                export_matrices,
                quiet: quiet || ranks.rank != 0,
                cancel,
            },
        )
        .map_err(Into::into)
        .map(|report| {
            log::logger().flush();
            let folder = report.output_dir.display();
            let verdict = report.summary.verdict();
            match &verdict {
                _ if ranks.rank != 0 => {}
                Verdict::NotSolved(why) => eprintln!(
                    "error: {why} (see {folder}/summary.json); the last iterate was written for inspection"
                ),
                Verdict::Inaccurate(why) => eprintln!("error: {why} (see {folder}/summary.json)"),
                Verdict::Solved => {}
            }
            verdict.exit_status()
        }),
        Command::Study { .. } if ranks.size > 1 => Err(format!(
            "internodes study runs on one process (launched on {} MPI ranks): run the study \
             without mpirun, or each level with `mpirun -n N internodes solve`",
            ranks.size
        )
        .into()),
        Command::Study {
            case,
            parameter,
            output,
            quiet,
            ..
        } => study(
            &case,
            &parameter,
            &StudyOptions {
                output,
                quiet,
                cancel,
            },
        ),
        Command::Info { mesh } => read_msh(&mesh)
            .map_err(Into::into)
            .and_then(|m| match ranks.rank {
                0 => print_stdout(&MeshSummary(&m).to_string()),
                _ => Ok(()),
            })
            .map(|()| 0),
    };
    log::logger().flush();
    match result {
        Ok(code) => match parallel::finish() {
            Ok(()) => ExitCode::from(code),
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::FAILURE
            }
        },
        Err(e) => {
            // Every rank that fails says so (one may fail alone), then ends the whole run: the
            // others may be waiting for it. Most errors are every rank's (a bad case file): the
            // other ranks give rank 0 a moment to say it once and end them all, before saying it
            // themselves.
            if ranks.rank != 0 {
                std::thread::sleep(std::time::Duration::from_secs(2));
            }
            let rank = match ranks.size {
                1 => String::new(),
                size => format!(" (rank {} of {size})", ranks.rank),
            };
            // One write: the lines of two ranks' errors do not interleave.
            let mut message = format!("error{rank}: {e}\n");
            for cause in unsaid_causes(&*e) {
                message.push_str(&format!("  caused by: {cause}\n"));
            }
            eprint!("{message}");
            if ranks.size > 1 {
                parallel::abort(1)
            }
            // A launcher's single rank finalizes MPI all the same.
            let _ = parallel::finish();
            // Stopped by a signal: the shell's status for a process it ended (130 for Ctrl-C).
            match INTERRUPTED_BY.load(Ordering::Relaxed) {
                0 => ExitCode::FAILURE,
                signal => ExitCode::from(128 + signal as u8),
            }
        }
    }
}

/// The token [`on_interrupt`] cancels.
static INTERRUPT_TOKEN: OnceLock<Cancel> = OnceLock::new();

/// The signal that cancelled the run, 0 before one came.
static INTERRUPTED_BY: AtomicI32 = AtomicI32::new(0);

/// A token that the first SIGINT (Ctrl-C) or SIGTERM cancels. The run then stops at its next
/// safe point and fails as an error does, so its output folder keeps no staging folder and
/// says it failed; being killed outright would leave the staging folder behind. A second
/// signal ends the process at once, for a run that takes long to reach a safe point.
fn cancel_on_interrupt() -> Cancel {
    let token = INTERRUPT_TOKEN.get_or_init(Cancel::new).clone();
    #[cfg(unix)]
    for signal in [libc::SIGINT, libc::SIGTERM] {
        // SAFETY: the handler only stores to atomics and calls `signal`, which is
        // async-signal-safe.
        unsafe {
            libc::signal(
                signal,
                on_interrupt as extern "C" fn(libc::c_int) as libc::sighandler_t,
            );
        }
    }
    token
}

#[cfg(unix)]
extern "C" fn on_interrupt(signal: libc::c_int) {
    INTERRUPTED_BY.store(signal, Ordering::Relaxed);
    if let Some(token) = INTERRUPT_TOKEN.get() {
        token.cancel();
    }
    // SAFETY: `signal` is async-signal-safe; the default disposition ends the process.
    unsafe {
        libc::signal(signal, libc::SIG_DFL);
    }
}

/// `internodes study`: runs the study, prints its tables on stdout (unless quiet) and returns its
/// exit status, the worst level's.
fn study(case: &Path, spec: &StudySpec, options: &StudyOptions) -> Result<u8, Box<dyn Error>> {
    let case = Case::load(case)?;
    let study = run_study(&case, spec, options)?;
    log::logger().flush();
    if !options.quiet {
        print_stdout(&markdown(&study))?;
    }
    let folder = study.folder.display();
    for level in study.levels.iter().filter(|l| l.exit_status != 0) {
        eprintln!(
            "error: {} = {}: {} (exit status {}; see {folder}/{}/summary.json)",
            spec.parameter, level.value, level.status, level.exit_status, level.folder
        );
    }
    Ok(study.exit_status)
}

/// Prints the library's messages on stderr, its warnings prefixed with `warning: `.
/// Hand-written: the `log` facade needs a logger, and the ones on crates.io add timestamps,
/// levels and colours the CLI's output has never had.
///
/// Two things make the default level read at a glance (docs/output.md, "The log"): an info
/// message longer than [`WIDTH`] is wrapped at its spaces (a long name, path or reason stays
/// on screen; debug and trace lines are left whole for scripts that parse them), and the
/// progress lines of long phases ([`internodes::progress`]) rewrite one line in place on a
/// terminal, the next message replacing it, but are plain lines elsewhere (a log file, a pipe),
/// where a carriage return would garble the text.
struct StderrLogger {
    terminal: bool,
    /// Whether the only info lines shown are the study's own ([`internodes::study::LOG_TARGET`])
    /// and progress lines.
    study_lines_only: bool,
    /// Whether a progress line is on screen, not ended by a newline.
    progress_shown: Mutex<bool>,
}

/// The widest line of an info message.
const WIDTH: usize = 120;

impl StderrLogger {
    fn install(level: log::LevelFilter, study_lines_only: bool) {
        static LOGGER: OnceLock<StderrLogger> = OnceLock::new();
        let logger = LOGGER.get_or_init(|| StderrLogger {
            terminal: std::io::stderr().is_terminal(),
            study_lines_only,
            progress_shown: Mutex::new(false),
        });
        // Only fails when a logger is already installed, which nothing else in the CLI does.
        let _ = log::set_logger(logger);
        log::set_max_level(level);
    }
}

impl log::Log for StderrLogger {
    fn enabled(&self, metadata: &log::Metadata) -> bool {
        let shown = |target: &str| {
            target == internodes::study::LOG_TARGET || target == internodes::progress::TARGET
        };
        metadata.level() <= log::max_level()
            && (!self.study_lines_only
                || metadata.level() <= log::Level::Warn
                || shown(metadata.target()))
    }

    fn log(&self, record: &log::Record) {
        if !self.enabled(record.metadata()) {
            return;
        }
        // One lock for the whole write: a heartbeat's thread and the solve may log at once.
        let mut shown = self
            .progress_shown
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        let clear = if *shown { "\r\x1b[2K" } else { "" };
        let text = record.args().to_string();
        let progress = record.target() == internodes::progress::TARGET;
        *shown = progress && self.terminal;
        match record.level() {
            log::Level::Error | log::Level::Warn => eprintln!("{clear}warning: {text}"),
            _ if progress && self.terminal => eprint!("{clear}{text}"),
            log::Level::Info => eprintln!("{clear}{}", wrap(&text, WIDTH)),
            _ => eprintln!("{clear}{text}"),
        }
    }

    /// Ends a progress line on screen, before a message not written through the logger (an
    /// error) starts on a line of its own.
    fn flush(&self) {
        let mut shown = self
            .progress_shown
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        if *shown {
            eprint!("\r\x1b[2K");
            *shown = false;
        }
    }
}

/// `text` with every line longer than `width` (in characters) broken at spaces; a continuation
/// is indented four spaces past its line's own indentation. A word longer than the width (a long path)
/// stays whole.
fn wrap(text: &str, width: usize) -> String {
    let mut lines = Vec::new();
    let count = |s: &str| s.chars().count();
    for line in text.lines() {
        // A line that fits keeps its spacing (aligned columns).
        if count(line) <= width {
            lines.push(line.to_string());
            continue;
        }
        let indent = line.len() - line.trim_start().len();
        let mut current = line[..indent].to_string();
        let mut empty = true;
        for word in line.split_whitespace() {
            if !empty && count(&current) + 1 + count(word) > width {
                lines.push(std::mem::take(&mut current));
                current = " ".repeat(indent + 4);
                empty = true;
            }
            if !empty {
                current.push(' ');
            }
            current.push_str(word);
            empty = false;
        }
        lines.push(current);
    }
    lines.join("\n")
}

/// Writes `text` to stdout. A reader that stops early (`internodes info m.msh | head`) closes
/// the pipe: that is not an error, and `print!` would panic on it.
fn print_stdout(text: &str) -> Result<(), Box<dyn Error>> {
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        result => result.map_err(Into::into),
    }
}
