//! [`generate`]: reads a run folder and writes its figures, reports and recording.

use std::path::{Path, PathBuf};

use admittance_runfolder::{files, write_atomic};

use crate::document::{self, Entry};
use crate::experiment::Experiment;
use crate::figures::{self, Planned};
use crate::folder::RunFolder;
use crate::plot::{self, Rendered};
use crate::{recording, ReportError};

/// Options of [`generate`].
#[derive(Clone, Debug)]
pub struct Options {
    /// The folder the scenario's relative paths (the URDF) are relative to: the folder of
    /// the original scenario file. Without it the run folder itself and `./scenarios` are
    /// tried.
    pub scenario_dir: Option<PathBuf>,
    /// Write `recording.mcap`.
    pub recording: bool,
    /// Draw the figures on this many threads (at least 1).
    pub threads: usize,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            scenario_dir: None,
            recording: true,
            threads: std::thread::available_parallelism().map_or(1, |n| n.get().min(4)),
        }
    }
}

/// What [`generate`] wrote.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// Figures drawn (each as PNG and SVG).
    pub figures: Vec<String>,
    /// Figures not drawn, with the reason.
    pub unavailable: Vec<(String, String)>,
    /// Notes of drawn figures on data they could not show: (figure, note).
    pub notes: Vec<(String, String)>,
    /// Messages in `recording.mcap` (0 when not written).
    pub recording_messages: u64,
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> ReportError + '_ {
    move |source| ReportError::Io {
        path: path.display().to_string(),
        source,
    }
}

/// Draws the available figures on a few threads; a figure whose drawing fails is reported
/// unavailable with the reason instead of failing the report.
fn render_all(plans: &[Planned], threads: usize) -> Vec<Result<Rendered, String>> {
    let drawable: Vec<(usize, &figures::Figure)> = plans
        .iter()
        .enumerate()
        .filter_map(|(k, p)| p.figure.as_ref().ok().map(|f| (k, f)))
        .collect();
    let threads = threads.max(1).min(drawable.len().max(1));
    let mut out: Vec<Result<Rendered, String>> = plans
        .iter()
        .map(|p| Err(p.figure.as_ref().err().cloned().unwrap_or_default()))
        .collect();
    let results: Vec<Vec<(usize, Result<Rendered, String>)>> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|t| {
                let mine: Vec<(usize, &figures::Figure)> =
                    drawable.iter().skip(t).step_by(threads).copied().collect();
                s.spawn(move || {
                    mine.into_iter()
                        .map(|(k, f)| {
                            let drawn =
                                std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                                    plot::render(f)
                                }))
                                .unwrap_or_else(|_| Err("drawing it panicked".into()));
                            (k, drawn.map_err(|e| format!("could not be drawn: {e}")))
                        })
                        .collect()
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().unwrap_or_default())
            .collect()
    });
    for (k, r) in results.into_iter().flatten() {
        out[k] = r;
    }
    out
}

/// Writes the figures into a fresh folder and swaps it in for `figures/`.
fn write_figures(
    dir: &Path,
    plans: &[Planned],
    rendered: &[Result<Rendered, String>],
) -> Result<(), ReportError> {
    let fig_dir = dir.join(files::FIGURES);
    // A new folder with an unpredictable name (mkdir fails on anything planted there), so
    // that the figures are never written through a link.
    let tmp_dir = admittance_files::temp_dir_beside(&fig_dir).map_err(io(&fig_dir))?;
    let write = || -> Result<(), ReportError> {
        for (p, r) in plans.iter().zip(rendered) {
            if let Ok(r) = r {
                let a = tmp_dir.join(format!("{}.png", p.stem));
                std::fs::write(&a, &r.png).map_err(io(&a))?;
                let b = tmp_dir.join(format!("{}.svg", p.stem));
                std::fs::write(&b, &r.svg).map_err(io(&b))?;
            }
        }
        let old = dir.join(format!(".{}.old-{}", files::FIGURES, std::process::id()));
        let _commit = admittance_runfolder::commit_guard();
        // In one step where the system can (the old figures then hold the temporary name,
        // removed with it); else aside and back on a failure.
        if fig_dir.exists()
            && admittance_files::exchange(&tmp_dir, &fig_dir).map_err(io(&fig_dir))?
        {
            let _ = std::fs::remove_dir_all(&tmp_dir);
            return Ok(());
        }
        if fig_dir.exists() {
            std::fs::rename(&fig_dir, &old).map_err(io(&fig_dir))?;
        }
        if let Err(e) = std::fs::rename(&tmp_dir, &fig_dir) {
            let _ = std::fs::rename(&old, &fig_dir);
            return Err(io(&fig_dir)(e));
        }
        let _ = std::fs::remove_dir_all(&old);
        Ok(())
    };
    let result = write().inspect_err(|_| {
        let _ = std::fs::remove_dir_all(&tmp_dir);
    });
    admittance_files::release(&tmp_dir);
    result
}

/// Writes `recording.mcap`; returns its message count and the report's line about it.
fn write_recording(dir: &Path, folder: &RunFolder) -> Result<(u64, String), ReportError> {
    let path = dir.join(files::RECORDING);
    let n = admittance_files::write_atomic_with(&path, |w| {
        recording::write(folder, w).map_err(std::io::Error::other)
    })
    .map_err(|e| ReportError::Output(format!("{}: {e}", path.display())))?;
    Ok((n, format!(
        "every variant's time series, topics `/VARIANT/joint_state`, `/reference`, `/torque`, `/external_torque` and more, JSON messages ({n} in all), log time = `t`."
    )))
}

/// Reads the run folder `dir` and writes into it `figures/*.png`, `figures/*.svg`,
/// `report.md`, `report.html` and (with `options.recording`) `recording.mcap`. Each file
/// is replaced atomically; the `figures` folder is replaced as a whole.
pub fn generate(dir: &Path, options: &Options) -> Result<Outcome, ReportError> {
    let folder = RunFolder::load(dir)?;
    let arm = if Experiment::of(&folder) == Experiment::Deadzone {
        crate::arm::load_arm(&folder, options.scenario_dir.as_deref())
    } else {
        Err("not needed".into())
    };
    let plans = figures::plan(&folder, arm.as_ref().map_err(Clone::clone));
    let rendered = render_all(&plans, options.threads);
    write_figures(dir, &plans, &rendered)?;
    let (recording_messages, recording_note) = if options.recording {
        let (n, note) = write_recording(dir, &folder)?;
        (n, Some(note))
    } else {
        (0, None)
    };
    let entries: Vec<Entry<'_>> = plans
        .iter()
        .zip(&rendered)
        .map(|(p, r)| Entry {
            id: &p.id,
            caption: &p.caption,
            data: &p.data,
            stem: r.as_ref().ok().map(|_| p.stem.as_str()),
            png: r.as_ref().ok().map(|r| r.png.as_slice()),
            missing: r.as_ref().err().map(String::as_str),
            notes: r.as_ref().map_or(&[], |r| r.notes.as_slice()),
        })
        .collect();
    for (name, text) in [
        (
            files::REPORT_MD,
            document::markdown(&folder, &entries, recording_note.as_deref()),
        ),
        (
            files::REPORT_HTML,
            document::html(&folder, &entries, recording_note.as_deref()),
        ),
    ] {
        let path = dir.join(name);
        write_atomic(&path, text.as_bytes()).map_err(io(&path))?;
    }
    let mut outcome = Outcome {
        figures: Vec::new(),
        unavailable: Vec::new(),
        notes: Vec::new(),
        recording_messages,
    };
    for (p, r) in plans.iter().zip(&rendered) {
        match r {
            Ok(r) => {
                outcome.figures.push(p.id.clone());
                outcome
                    .notes
                    .extend(r.notes.iter().map(|n| (p.id.clone(), n.text.clone())));
            }
            Err(e) => outcome.unavailable.push((p.id.clone(), e.clone())),
        }
    }
    Ok(outcome)
}
