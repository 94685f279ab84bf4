//! The output folder of a run: it holds one run's complete results, or a failure mark and
//! nothing that looks like a result.
//!
//! A run removes the result files of earlier runs when it starts (so a run that is killed
//! leaves no stale results), writes its own into a private staging folder inside the output
//! folder, and moves them into place only when every body has been solved and every file
//! written ([`ResultFolder::commit`]). A run that fails removes its staging folder and writes
//! [`FAILURE_MARK`] with the error ([`ResultFolder::fail`]); the next successful run removes it.
//! A [`ResultFolder`] dropped uncommitted removes its staging folder whatever the way out (an
//! error passed up with `?`, a panic, a cancelled run), so only a process killed outright leaves
//! one behind.
//! The staging folder's name carries the process id and a counter, so concurrent runs never
//! write into each other's files, and a lock file makes each commit (or failure mark) whole:
//! the run that finishes last owns the folder, with all of its files.
//!
//! A run never removes or replaces its own input: `mesh.msh` is ours only when the run meshes a
//! `.geo` (a `.msh` case may well read a `mesh.msh` that lies in its output folder), and an
//! output folder that holds the case file or the mesh under a result file's name is refused
//! before anything is removed ([`check_inputs`]).

use std::ffi::OsStr;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use super::OutputError;

/// The results a run writes into its output folder, as file or folder names.
pub const RESULT_FILES: [&str; 6] = [
    "solution.xdmf",
    "solution.h5",
    "summary.json",
    "force_displacement.csv",
    "force_displacement.png",
    MATRICES,
];

/// The folder of exported matrices, one of [`RESULT_FILES`].
const MATRICES: &str = "matrices";

/// The mesh gmsh made for a `.geo` case: the run's input, kept when the run fails so that the
/// mesh an error names can be inspected.
pub const GENERATED_MESH: &str = "mesh.msh";

/// Written into the output folder by a run that failed, with its error.
pub const FAILURE_MARK: &str = "FAILED.txt";

/// Prefix of the staging folders of running (or killed) runs.
const STAGING_PREFIX: &str = ".internodes-partial-";

/// Held while results are moved into place, so that two runs finishing together do not mix
/// their files.
const COMMIT_LOCK: &str = ".internodes-commit.lock";

/// A lock older than this belongs to a run that was killed while committing (a commit is a few
/// renames): it is removed. A lock's age is the distance between its modification time and
/// now, either way: one dated more than this in the future (a clock set back, a folder copied
/// from a machine whose clock was ahead) was not made by a run committing now, and is removed
/// too; one dated less far ahead (clocks of a network file system a little apart) is stale
/// within twice this.
const STALE_LOCK: Duration = Duration::from_secs(30);

/// The longest a run waits for the commit lock before it fails, naming the lock. A commit is a
/// few file renames and takes milliseconds, and a lock left by a killed run is stale within
/// `2 * STALE_LOCK` (above), so a run waits this long only when other runs have held the lock
/// all that time or the lock cannot be removed: something is wrong, and it must be said rather
/// than waited for without a word.
const MAX_LOCK_WAIT: Duration = Duration::from_secs(90);

/// After this long waiting for the commit lock, a run says which lock it waits for.
const LOCK_WAIT_NOTICE: Duration = Duration::from_secs(2);

/// Distinguishes staging folders of runs in one process (tests run cases in parallel).
static RUNS: AtomicUsize = AtomicUsize::new(0);

/// An output folder with a run's staging folder in it.
#[derive(Debug)]
pub struct ResultFolder {
    dir: PathBuf,
    staging: PathBuf,
    /// The commit waited [`MAX_LOCK_WAIT`] for the lock in vain: the failure mark does not
    /// wait for it a second time.
    lock_timed_out: AtomicBool,
}

impl ResultFolder {
    /// Creates `dir` if needed, removes earlier results (and the generated mesh, when this
    /// run generates one) and creates the staging folder. `inputs` are the files the run reads
    /// (case file, mesh): if one of them lies in `dir` under a name the run would remove or
    /// replace, nothing is touched and the error names it and `origin` (where `dir` was set).
    pub fn create(
        dir: &Path,
        origin: &str,
        inputs: &[&Path],
        generates_mesh: bool,
    ) -> Result<Self, OutputError> {
        check_inputs(dir, origin, inputs, generates_mesh)?;
        create_dir(dir)?;
        {
            let _lock = CommitLock::acquire(dir)?;
            remove_results(dir)?;
            if generates_mesh {
                remove_file(&dir.join(GENERATED_MESH))?;
            }
        }
        let run = RUNS.fetch_add(1, Ordering::Relaxed);
        let staging = dir.join(format!("{STAGING_PREFIX}{}-{run}", std::process::id()));
        remove_staging(&staging)?;
        create_dir(&staging)?;
        Ok(ResultFolder {
            dir: dir.to_owned(),
            staging,
            lock_timed_out: AtomicBool::new(false),
        })
    }

    /// The output folder the results end up in.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Where this run writes its result files until [`ResultFolder::commit`].
    pub fn staging(&self) -> &Path {
        &self.staging
    }

    /// Moves a staged file into the output folder at once: the mesh gmsh made, which is the
    /// run's input and is kept even if the run fails.
    pub fn publish(&self, name: &str) -> Result<PathBuf, OutputError> {
        let target = self.dir.join(name);
        rename(&self.staging.join(name), &target)?;
        Ok(target)
    }

    /// Moves every staged result into the output folder, replacing earlier ones, and removes
    /// the failure mark of an earlier run.
    pub fn commit(&self) -> Result<(), OutputError> {
        let _lock = CommitLock::acquire(&self.dir).inspect_err(|e| {
            if matches!(e, OutputError::LockTimeout { .. }) {
                self.lock_timed_out.store(true, Ordering::Relaxed);
            }
        })?;
        remove_results(&self.dir)?;
        for name in RESULT_FILES {
            let staged = self.staging.join(name);
            let target = self.dir.join(name);
            if staged.is_dir() {
                // File by file: the folder may hold files of the user's beside ours.
                create_dir(&target)?;
                for entry in read_dir(&staged)? {
                    rename(&entry, &target.join(entry.file_name().unwrap_or_default()))?;
                }
            } else if staged.exists() {
                rename(&staged, &target)?;
            }
        }
        remove_staging(&self.staging)?;
        remove_file(&self.dir.join(FAILURE_MARK))
    }

    /// Removes this run's staged files and results, and writes [`FAILURE_MARK`] with `error`.
    /// Best effort: the error itself is what the caller reports, so a folder that cannot be
    /// cleaned is only logged as a warning.
    pub fn fail(&self, command: &str, error: &dyn std::error::Error) {
        let wait = if self.lock_timed_out.load(Ordering::Relaxed) {
            Duration::ZERO
        } else {
            MAX_LOCK_WAIT
        };
        match mark_failed(&self.dir, Some(&self.staging), command, error, wait) {
            // The run's own error names the lock: no mark can be written without it.
            Err(OutputError::LockTimeout { .. }) if wait.is_zero() => {}
            Err(e) => log::warn!("{e}"),
            Ok(()) => {}
        }
    }
}

/// Marks `dir` as holding the failure of a run that stopped before it had a
/// [`ResultFolder`] (a case file that does not parse): earlier results are removed and
/// [`FAILURE_MARK`] written. `mesh.msh` stays: whether this run would have generated it is not
/// known, and it may be the mesh the case reads. Nothing is done if `dir` does not exist, or if
/// it holds `case_file` under a result file's name (logged as a warning).
pub fn mark_failed_folder(
    dir: &Path,
    origin: &str,
    case_file: &Path,
    command: &str,
    error: &dyn std::error::Error,
) {
    if !dir.is_dir() {
        return;
    }
    let marked = check_inputs(dir, origin, &[case_file], false)
        .and_then(|()| mark_failed(dir, None, command, error, MAX_LOCK_WAIT));
    if let Err(e) = marked {
        log::warn!("{e}");
    }
}

/// Whether everything in `dir` is what runs write into an output folder: the result files
/// (`matrices/` with `.mtx` files only), the generated mesh, the failure mark, staging folders
/// and the commit lock. Such a folder holds nothing of the user's, and can go whole.
pub fn holds_only_run_outputs(dir: &Path) -> std::io::Result<bool> {
    let paths = |dir: &Path| -> std::io::Result<Vec<PathBuf>> {
        std::fs::read_dir(dir)?
            .map(|e| e.map(|e| e.path()))
            .collect()
    };
    for entry in paths(dir)? {
        let name = entry.file_name().unwrap_or_default().to_string_lossy();
        let ours = if name.starts_with(STAGING_PREFIX) {
            true
        } else if entry.is_dir() {
            name == MATRICES
                && (paths(&entry)?.iter())
                    .all(|f| f.extension().is_some_and(|e| e == "mtx") && f.is_file())
        } else {
            name != MATRICES
                && (RESULT_FILES.contains(&name.as_ref())
                    || [GENERATED_MESH, FAILURE_MARK, COMMIT_LOCK].contains(&name.as_ref()))
        };
        if !ours {
            return Ok(false);
        }
    }
    Ok(true)
}

/// Refuses an output folder `dir` that holds one of the run's `inputs` under a name the run
/// removes or replaces: a result file, the failure mark, an `.mtx` file in `matrices/`, or
/// `mesh.msh` when the run generates the mesh. Paths are compared after resolving symbolic
/// links and `..`, so `output = "."` beside the inputs is caught; a folder that does not exist
/// yet holds nothing.
pub fn check_inputs(
    dir: &Path,
    origin: &str,
    inputs: &[&Path],
    generates_mesh: bool,
) -> Result<(), OutputError> {
    let Ok(dir_resolved) = dir.canonicalize() else {
        return Ok(());
    };
    let mut names: Vec<&str> = RESULT_FILES.to_vec();
    names.push(FAILURE_MARK);
    if generates_mesh {
        names.push(GENERATED_MESH);
    }
    for &input in inputs {
        let (Some(folder), Some(name)) = (resolved_folder(input), input.file_name()) else {
            continue;
        };
        let clash = if folder == dir_resolved {
            names
                .iter()
                .find(|&&n| OsStr::new(n) == name)
                .map(|n| n.to_string())
        } else if folder == dir_resolved.join(MATRICES)
            && Path::new(name).extension() == Some(OsStr::new("mtx"))
        {
            Some(format!("{MATRICES}/{}", name.to_string_lossy()))
        } else {
            None
        };
        if let Some(name) = clash {
            return Err(OutputError::InputInOutput {
                dir: dir.to_owned(),
                origin: origin.to_owned(),
                input: input.to_owned(),
                name,
            });
        }
    }
    Ok(())
}

/// The folder that holds `path`, with symbolic links and `..` resolved (`None` if it does not
/// exist).
fn resolved_folder(path: &Path) -> Option<PathBuf> {
    let parent = path.parent().filter(|p| !p.as_os_str().is_empty());
    parent.unwrap_or(Path::new(".")).canonicalize().ok()
}

fn mark_failed(
    dir: &Path,
    staging: Option<&Path>,
    command: &str,
    error: &dyn std::error::Error,
    lock_wait: Duration,
) -> Result<(), OutputError> {
    if let Some(staging) = staging {
        remove_staging(staging)?;
    }
    let _lock = CommitLock::acquire_within(dir, lock_wait)?;
    remove_results(dir)?;
    let path = dir.join(FAILURE_MARK);
    std::fs::write(&path, failure_text(command, error))
        .map_err(|source| OutputError::Io { path, source })
}

/// The failure mark's text: what ran, when, and the error with its causes.
fn failure_text(command: &str, error: &dyn std::error::Error) -> String {
    let seconds = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let mut text = format!(
        "The last run into this folder failed; it wrote no results, and the results of earlier \
         runs were removed.\ncommand: {command}\ntime: {}\nerror: {error}\n",
        utc(seconds)
    );
    for cause in unsaid_causes(error) {
        let _ = writeln!(text, "  caused by: {cause}");
    }
    text
}

/// The messages of the causes (sources) of `error` that the messages before them do not already
/// hold. Most of our errors write their source into their own message (`case file c.toml:
/// m.msh: ...`), so printing every source repeats the same sentence; a source that adds
/// something (an I/O error under a message that does not quote it) is kept.
pub fn unsaid_causes(error: &dyn std::error::Error) -> Vec<String> {
    let mut said = error.to_string();
    let mut causes = Vec::new();
    let mut source = error.source();
    while let Some(cause) = source {
        let text = cause.to_string();
        if !said.contains(&text) {
            said.push_str(&text);
            causes.push(text);
        }
        source = cause.source();
    }
    causes
}

/// `seconds` since 1970 as a UTC date and time (the civil-from-days algorithm of H. Hinnant's
/// "chrono-compatible low-level date algorithms"; no date crate for one line of a text file).
fn utc(seconds: u64) -> String {
    let days = i64::try_from(seconds / 86_400).unwrap_or(0) + 719_468;
    let era = days.div_euclid(146_097);
    let day_of_era = days - era * 146_097;
    let year_of_era =
        (day_of_era - day_of_era / 1460 + day_of_era / 36_524 - day_of_era / 146_096) / 365;
    let day_of_year = day_of_era - (365 * year_of_era + year_of_era / 4 - year_of_era / 100);
    let shifted_month = (5 * day_of_year + 2) / 153;
    let day = day_of_year - (153 * shifted_month + 2) / 5 + 1;
    let month = if shifted_month < 10 {
        shifted_month + 3
    } else {
        shifted_month - 9
    };
    let year = year_of_era + era * 400 + i64::from(month <= 2);
    let time = seconds % 86_400;
    format!(
        "{year:04}-{month:02}-{day:02} {:02}:{:02}:{:02} UTC",
        time / 3600,
        time % 3600 / 60,
        time % 60
    )
}

/// Removes the result files of earlier runs from `dir`. In `matrices/` only the `.mtx` files
/// go (and the folder, if that empties it): the output folder may be one the user keeps other
/// files in, and nothing but our own files may be removed.
fn remove_results(dir: &Path) -> Result<(), OutputError> {
    for name in RESULT_FILES {
        let path = dir.join(name);
        if name == MATRICES && path.is_dir() {
            for file in read_dir(&path)? {
                if file.extension().is_some_and(|e| e == "mtx") && file.is_file() {
                    remove_file(&file)?;
                }
            }
            // Not empty: the user's files stay, and so does the folder.
            let _ = std::fs::remove_dir(&path);
        } else {
            remove_file(&path)?;
        }
    }
    Ok(())
}

/// The paths of the entries of a folder.
fn read_dir(dir: &Path) -> Result<Vec<PathBuf>, OutputError> {
    let io = |source| OutputError::Io {
        path: dir.to_owned(),
        source,
    };
    std::fs::read_dir(dir)
        .map_err(io)?
        .map(|entry| entry.map(|e| e.path()).map_err(io))
        .collect()
}

fn create_dir(dir: &Path) -> Result<(), OutputError> {
    std::fs::create_dir_all(dir).map_err(|source| OutputError::Io {
        path: dir.to_owned(),
        source,
    })
}

fn rename(from: &Path, to: &Path) -> Result<(), OutputError> {
    std::fs::rename(from, to).map_err(|source| OutputError::Io {
        path: to.to_owned(),
        source,
    })
}

/// Removes a file; a missing one is fine (also one that another run removes at the same time),
/// and a folder of that name is the user's and stays.
fn remove_file(path: &Path) -> Result<(), OutputError> {
    if path.is_dir() {
        return Ok(());
    }
    not_found_is_fine(path, std::fs::remove_file(path))
}

/// Removes a staging folder of ours with its contents.
fn remove_staging(path: &Path) -> Result<(), OutputError> {
    not_found_is_fine(path, std::fs::remove_dir_all(path))
}

fn not_found_is_fine(path: &Path, result: std::io::Result<()>) -> Result<(), OutputError> {
    match result {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(OutputError::Io {
            path: path.to_owned(),
            source: e,
        }),
        _ => Ok(()),
    }
}

/// The staging folder goes with the [`ResultFolder`]: committed or failed, it is gone already;
/// on any other way out it would be left holding a partial result set that nothing removes.
/// Best effort: a drop has no one to report to.
impl Drop for ResultFolder {
    fn drop(&mut self) {
        let _ = remove_staging(&self.staging);
    }
}

/// The commit lock of an output folder, released when dropped.
#[derive(Debug)]
struct CommitLock(PathBuf);

impl CommitLock {
    fn acquire(dir: &Path) -> Result<Self, OutputError> {
        Self::acquire_within(dir, MAX_LOCK_WAIT)
    }

    /// Takes the lock of `dir`, waiting at most `max_wait` (tests pass a short one). A lock
    /// older than [`STALE_LOCK`] is removed; a folder of the lock's name is an error at once
    /// (it is no lock of ours, and would never go away).
    fn acquire_within(dir: &Path, max_wait: Duration) -> Result<Self, OutputError> {
        let path = dir.join(COMMIT_LOCK);
        let start = std::time::Instant::now();
        let mut said = false;
        loop {
            match std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&path)
            {
                Ok(_) => return Ok(CommitLock(path)),
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    let metadata = std::fs::symlink_metadata(&path);
                    if metadata.as_ref().is_ok_and(std::fs::Metadata::is_dir) {
                        return Err(OutputError::LockIsFolder { path });
                    }
                    let age = metadata
                        .and_then(|m| m.modified())
                        .ok()
                        .map(|t| t.elapsed().unwrap_or_else(|future| future.duration()));
                    if age.is_some_and(|a| a > STALE_LOCK) {
                        not_found_is_fine(&path, std::fs::remove_file(&path))?;
                        continue;
                    }
                    let waited = start.elapsed();
                    if waited >= max_wait {
                        return Err(OutputError::LockTimeout {
                            path,
                            seconds: waited.as_secs_f64(),
                        });
                    }
                    if !said && waited >= LOCK_WAIT_NOTICE {
                        log::warn!(
                            "waiting for the commit lock {} (another run into this folder is \
                             moving its results into place; a lock older than {} s is removed, \
                             and the wait ends with an error after {} s)",
                            path.display(),
                            STALE_LOCK.as_secs(),
                            max_wait.as_secs()
                        );
                        said = true;
                    }
                    std::thread::sleep(Duration::from_millis(10));
                }
                Err(source) => return Err(OutputError::Io { path, source }),
            }
        }
    }
}

impl Drop for CommitLock {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

#[cfg(test)]
mod tests {
    use super::{CommitLock, Duration, OutputError, ResultFolder, utc};

    #[test]
    fn a_result_folder_dropped_uncommitted_removes_its_staging_folder() {
        let dir = tempfile::tempdir().unwrap();
        let results = ResultFolder::create(dir.path(), "a test", &[], false).unwrap();
        let staging = results.staging().to_owned();
        std::fs::write(staging.join("summary.json"), "{}").unwrap();
        drop(results);
        assert!(!staging.exists());
        assert!(!dir.path().join("summary.json").exists());
    }

    #[test]
    fn a_lock_held_past_the_wait_is_an_error_naming_it_and_its_removal() {
        let dir = tempfile::tempdir().unwrap();
        let held = CommitLock::acquire(dir.path()).unwrap();
        let e = CommitLock::acquire_within(dir.path(), Duration::from_millis(50)).unwrap_err();
        assert!(matches!(e, OutputError::LockTimeout { .. }), "{e}");
        let message = e.to_string();
        let lock = dir.path().join(".internodes-commit.lock");
        assert!(
            message.contains(&format!("rm '{}'", lock.display())),
            "{message}"
        );
        drop(held);
        CommitLock::acquire_within(dir.path(), Duration::ZERO).unwrap();
    }

    #[test]
    fn utc_dates_match_known_timestamps() {
        assert_eq!(utc(0), "1970-01-01 00:00:00 UTC");
        assert_eq!(utc(951_782_400), "2000-02-29 00:00:00 UTC");
        assert_eq!(utc(1_795_589_057), "2026-11-25 06:44:17 UTC");
    }
}
