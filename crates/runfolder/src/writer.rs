//! Writing a run folder (the one writer of `admittance run`, the Python package's
//! co-simulation and any other front end): every file goes into a hidden partial sibling
//! (`.NAME.partial-PID`, marked as this tool's work in progress), which is renamed into place
//! at the end, so that a failed or interrupted run never leaves a folder that looks
//! complete; time series are CSV with the shortest round-trip form of every value.

use std::io::Write as _;
use std::path::{Path, PathBuf};

/// The file inside a partial folder that marks it as this tool's work in progress.
pub const PARTIAL_MARKER: &str = ".admittance-partial";

/// Writes a time series as CSV: a header row of `columns`, then one line per row.
pub fn write_series_csv(path: &Path, columns: &[String], rows: &[Vec<f64>]) -> std::io::Result<()> {
    let file = std::fs::File::create(path)?;
    let mut w = std::io::BufWriter::new(file);
    writeln!(w, "{}", columns.join(","))?;
    let mut line = String::new();
    for row in rows {
        line.clear();
        for (k, v) in row.iter().enumerate() {
            if k > 0 {
                line.push(',');
            }
            use std::fmt::Write as _;
            let _ = write!(line, "{v}");
        }
        writeln!(w, "{line}")?;
    }
    w.flush()
}

/// Removes partial folders (`.NAME.partial-PID`) left in `parent` by runs that were
/// killed: those holding this tool's marker, and empty ones, whose writer no longer runs.
/// Returns the folders removed.
pub fn remove_stale_partials(parent: &Path) -> Vec<PathBuf> {
    let mut removed = Vec::new();
    let Ok(entries) = std::fs::read_dir(parent) else {
        return removed;
    };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().to_string();
        let Some(pid) = name
            .strip_prefix('.')
            .and_then(|n| n.rsplit_once(".partial-"))
            .and_then(|(_, pid)| pid.parse::<u32>().ok())
            .filter(|&pid| pid <= MAX_PID)
        else {
            continue;
        };
        let path = e.path();
        if pid == std::process::id() {
            continue;
        }
        let gone = match std::fs::read_to_string(path.join(PARTIAL_MARKER)) {
            Ok(marker) => !writer_running(pid, &marker) && std::fs::remove_dir_all(&path).is_ok(),
            // Killed between creating the folder and writing its marker: an empty folder
            // holds nothing of anyone's (`remove_dir` refuses any other).
            Err(_) => !writer_running(pid, "") && std::fs::remove_dir(&path).is_ok(),
        };
        if gone {
            removed.push(path);
        }
    }
    removed
}

/// Linux's largest `pid_max` (2^22): a longer number after `.partial-` is not a PID (a
/// temporary folder's random suffix).
const MAX_PID: u32 = 1 << 22;

/// The marker's line that records when its writer started (`/proc/PID/stat`'s start time).
const STARTED_KEY: &str = "process_start_ticks=";

/// The marker's text for this process.
fn marker_text() -> String {
    match process_start(std::process::id()) {
        Some(ticks) => format!("admittance run in progress\n{STARTED_KEY}{ticks}\n"),
        None => "admittance run in progress\n".into(),
    }
}

/// Whether the process that wrote `marker` as `pid` still runs. Linux reuses a PID (and
/// `/proc/PID` answers for a thread too; `pid_max` may be 32768), so a process found under
/// the PID counts only when it started when the marker says its writer did; a marker
/// without that line (an older one) trusts the PID. Elsewhere assumed running, so that
/// nothing is removed that might still be written.
fn writer_running(pid: u32, marker: &str) -> bool {
    if !Path::new("/proc/self").exists() {
        return true;
    }
    let recorded = marker
        .lines()
        .find_map(|l| l.strip_prefix(STARTED_KEY))
        .and_then(|v| v.trim().parse::<u64>().ok());
    match (recorded, process_start(pid)) {
        (_, None) => Path::new("/proc").join(pid.to_string()).exists(),
        (Some(recorded), Some(now)) => recorded == now,
        (None, Some(_)) => true,
    }
}

/// The start time of process `pid` in clock ticks since boot (`/proc/PID/stat`, field 22),
/// if it exists and can be read.
fn process_start(pid: u32) -> Option<u64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // The command name (field 2) is in parentheses and may hold spaces: count after it.
    let rest = &stat[stat.rfind(')')? + 1..];
    rest.split_whitespace().nth(19)?.parse().ok()
}

/// Writes the folder `out_dir` through a hidden partial sibling (`fill` writes into it; an
/// error there removes it) and renames it into place, replacing what is at `out_dir` (the
/// caller decides before whether it may: [`crate::summary::classify_out`]). `io` turns an
/// I/O error at a path into the caller's error type.
pub fn write_folder<E>(
    out_dir: &Path,
    fill: impl FnOnce(&Path) -> Result<(), E>,
    io: impl Fn(&Path, std::io::Error) -> E,
) -> Result<(), E> {
    let parent = out_dir
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(parent).map_err(|e| io(parent, e))?;
    remove_stale_partials(parent);
    let leaf = out_dir
        .file_name()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_else(|| "run".into());
    let partial = parent.join(format!(".{leaf}.partial-{}", std::process::id()));
    if partial.join(PARTIAL_MARKER).is_file() {
        let _ = std::fs::remove_dir_all(&partial);
    }
    std::fs::create_dir(&partial).map_err(|e| io(&partial, e))?;
    let marker = partial.join(PARTIAL_MARKER);
    let result = std::fs::write(&marker, marker_text())
        .map_err(|e| io(&marker, e))
        .and_then(|_| fill(&partial));
    if let Err(e) = result {
        let _ = std::fs::remove_dir_all(&partial);
        return Err(e);
    }
    // From here to the end the partial folder may be the only complete copy: an interrupt's
    // clean-up waits (`crate::commit_guard`).
    let _commit = crate::commit_guard();
    // A failed rename leaves the complete partial folder unmarked, for the user to recover.
    let unmark = || {
        let _ = std::fs::remove_file(&marker);
    };
    let old = parent.join(format!(".{leaf}.old-{}", std::process::id()));
    let replaced = std::fs::symlink_metadata(out_dir).is_ok();
    // Replacing, the two folders swap names in one step where the system can: renamed aside
    // first, a run killed between the two renames left no folder at `out_dir` and its new
    // one marked as partial, for a later run to remove.
    let swapped = replaced
        && match admittance_files::exchange(&partial, out_dir) {
            Ok(swapped) => swapped,
            Err(e) => {
                unmark();
                return Err(io(out_dir, e));
            }
        };
    if swapped {
        // The old folder is now at the partial name, unmarked: moved aside to be removed.
        if std::fs::rename(&partial, &old).is_err() {
            let _ = std::fs::remove_dir_all(&partial);
        }
    } else {
        if replaced {
            if let Err(e) = std::fs::rename(out_dir, &old) {
                unmark();
                return Err(io(out_dir, e));
            }
        }
        if let Err(e) = std::fs::rename(&partial, out_dir) {
            unmark();
            if replaced {
                let _ = std::fs::rename(&old, out_dir);
            }
            return Err(io(out_dir, e));
        }
    }
    // The marker goes last, from the folder in place: a run killed between taking it out of
    // the partial folder and the rename left an unmarked partial folder that no later run
    // removed (1 kill in about 300 of the reliability test's); killed here, the folder is
    // complete and carries a stray marker file.
    let _ = std::fs::remove_file(out_dir.join(PARTIAL_MARKER));
    if replaced {
        let _ = std::fs::remove_dir_all(&old);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_fill_leaves_nothing_and_a_good_one_replaces_the_folder() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("run");
        std::fs::create_dir(&out).unwrap();
        std::fs::write(out.join("old.csv"), "old").unwrap();
        let io = |p: &Path, e: std::io::Error| format!("{}: {e}", p.display());
        let failed = write_folder(
            &out,
            |partial| {
                std::fs::write(partial.join("a.csv"), "x").unwrap();
                Err("broken".to_string())
            },
            io,
        );
        assert_eq!(failed, Err("broken".to_string()));
        assert!(out.join("old.csv").is_file());
        assert_eq!(
            std::fs::read_dir(dir.path()).unwrap().count(),
            1,
            "no partial left"
        );
        write_folder(
            &out,
            |partial| {
                write_series_csv(
                    &partial.join("a.csv"),
                    &["t".into(), "x".into()],
                    &[vec![0.0, 0.1]],
                )
                .map_err(|e| e.to_string())
            },
            io,
        )
        .unwrap();
        assert_eq!(
            std::fs::read_to_string(out.join("a.csv")).unwrap(),
            "t,x\n0,0.1\n"
        );
        assert!(!out.join("old.csv").exists() && !out.join(PARTIAL_MARKER).exists());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn a_partial_folder_whose_pid_now_names_another_process_is_stale() {
        let Some(start) = process_start(std::process::id()) else {
            return; // no /proc: every partial folder is kept
        };
        let dir = tempfile::tempdir().unwrap();
        // PID 1 always runs; a marker that records another start time was written by an
        // earlier process of that PID.
        let init = process_start(1).expect("/proc/1/stat");
        let partial = |name: &str, marker: String| {
            let p = dir.path().join(name);
            std::fs::create_dir(&p).unwrap();
            std::fs::write(p.join(PARTIAL_MARKER), marker).unwrap();
            p
        };
        let reused = partial(
            ".a.partial-1",
            format!("admittance run in progress\n{STARTED_KEY}{}\n", init + 1),
        );
        let running = partial(
            ".b.partial-1",
            format!("admittance run in progress\n{STARTED_KEY}{init}\n"),
        );
        let older = partial(".c.partial-1", "admittance run in progress\n".into());
        // Killed before its marker was written: empty, and its PID runs nothing (the
        // largest one Linux allows, which no process here has).
        let empty = dir.path().join(".d.partial-4194304");
        std::fs::create_dir(&empty).unwrap();
        let unmarked = dir.path().join(".e.partial-4194304");
        // Not a PID: a temporary folder's random digits.
        let random = dir.path().join(".f.partial-48151623");
        std::fs::create_dir(&random).unwrap();
        std::fs::create_dir(&unmarked).unwrap();
        std::fs::write(unmarked.join("user.txt"), "not ours").unwrap();
        let mut removed = remove_stale_partials(dir.path());
        removed.sort();
        assert_eq!(removed, vec![reused.clone(), empty.clone()]);
        assert!(!reused.exists() && !empty.exists());
        assert!(running.exists() && older.exists() && unmarked.join("user.txt").exists());
        assert!(random.exists());
        assert!(marker_text().contains(&format!("{STARTED_KEY}{start}\n")));
    }
}
