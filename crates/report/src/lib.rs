//! The report of a run folder: the paper's figures (Figs 7-26) as PNG and SVG, `report.md`,
//! a self-contained `report.html` and `recording.mcap` (for Foxglove), all made from the
//! files of the folder (`summary.json`, `scenario.toml`, `VARIANT.csv`), so that they can be
//! regenerated at any time with `admittance report DIR`.

pub mod document;
pub mod figures;
pub mod folder;
pub mod plot;
pub mod recording;
pub mod table;

pub use folder::RunFolder;
pub use table::Table;

/// A failure to make the report.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// A file of the run folder is missing or malformed.
    #[error("{path}: {message}")]
    Input {
        /// The file.
        path: String,
        /// What is wrong and how to fix it.
        message: String,
    },
    /// Writing an output failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The error.
        source: std::io::Error,
    },
    /// Drawing a figure or writing the recording failed.
    #[error("{0}")]
    Output(String),
}

use std::path::{Path, PathBuf};

use admittance_dynamics::Model;

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
    /// Messages in `recording.mcap` (0 when not written).
    pub recording_messages: u64,
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> ReportError + '_ {
    move |source| ReportError::Io {
        path: path.display().to_string(),
        source,
    }
}

/// Writes `bytes` to `path` through a temporary file in the same folder and a rename, so
/// that `path` is either the old or the new file, never a partial one.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), ReportError> {
    let tmp = temp_sibling(path);
    std::fs::write(&tmp, bytes).map_err(io(&tmp))?;
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        io(path)(e)
    })
}

fn temp_sibling(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.tmp-{}", std::process::id()))
}

/// Finds and loads the arm named by `scenario.toml` (`[arm] urdf`, `base`, `tip`).
pub fn load_arm(folder: &RunFolder, scenario_dir: Option<&Path>) -> Result<Model, String> {
    let urdf = folder
        .scenario_value("arm.urdf")
        .and_then(toml::Value::as_str)
        .ok_or("scenario.toml (in the run folder) names no `[arm] urdf`")?;
    let base = folder
        .scenario_value("arm.base")
        .and_then(toml::Value::as_str);
    let tip = folder
        .scenario_value("arm.tip")
        .and_then(toml::Value::as_str);
    let p = Path::new(urdf);
    let candidates: Vec<PathBuf> = if p.is_absolute() {
        vec![p.to_path_buf()]
    } else {
        scenario_dir
            .map(|d| d.join(p))
            .into_iter()
            .chain([folder.dir.join(p), Path::new("scenarios").join(p)])
            .collect()
    };
    let found = candidates.iter().find(|c| c.is_file()).ok_or_else(|| {
        format!(
            "the URDF `{urdf}` of scenario.toml is not at {}; pass `--scenario-dir` (the folder of the scenario file)",
            candidates.iter().map(|c| c.display().to_string()).collect::<Vec<_>>().join(" or ")
        )
    })?;
    Model::from_urdf_file(found, base, tip).map_err(|e| e.to_string())
}

/// Reads the run folder `dir` and writes into it `figures/*.png`, `figures/*.svg`,
/// `report.md`, `report.html` and (with `options.recording`) `recording.mcap`. Each file
/// is replaced atomically; the `figures` folder is replaced as a whole.
pub fn generate(dir: &Path, options: &Options) -> Result<Outcome, ReportError> {
    let folder = RunFolder::load(dir)?;
    let arm = if folder.scenario == "deadzone" {
        load_arm(&folder, options.scenario_dir.as_deref())
    } else {
        Err("not needed".into())
    };
    let plans = figures::plan(&folder, arm.as_ref().map_err(Clone::clone));

    // Draw the available figures, spread over a few threads.
    let drawable: Vec<(usize, &figures::Figure)> = plans
        .iter()
        .enumerate()
        .filter_map(|(k, p)| p.figure.as_ref().ok().map(|f| (k, f)))
        .collect();
    let threads = options.threads.max(1).min(drawable.len().max(1));
    let mut rendered: Vec<Option<(Vec<u8>, String)>> = vec![None; plans.len()];
    // Per thread: (plan index, PNG, SVG) of each figure it drew.
    type Drawn = Vec<(usize, Vec<u8>, String)>;
    let results: Vec<Result<Drawn, String>> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|t| {
                let mine: Vec<(usize, &figures::Figure)> =
                    drawable.iter().skip(t).step_by(threads).copied().collect();
                s.spawn(move || {
                    mine.into_iter()
                        .map(|(k, f)| Ok((k, plot::render_png(f)?, plot::render_svg(f)?)))
                        .collect::<Result<Vec<_>, String>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| {
                h.join()
                    .unwrap_or_else(|_| Err("a figure thread panicked".into()))
            })
            .collect()
    });
    for r in results {
        for (k, png, svg) in r.map_err(ReportError::Output)? {
            rendered[k] = Some((png, svg));
        }
    }

    // figures/: written into a fresh folder, then swapped in.
    let fig_dir = dir.join("figures");
    let tmp_dir = temp_sibling(&fig_dir);
    let _ = std::fs::remove_dir_all(&tmp_dir);
    std::fs::create_dir_all(&tmp_dir).map_err(io(&tmp_dir))?;
    let write_figures = || -> Result<(), ReportError> {
        for (p, r) in plans.iter().zip(&rendered) {
            if let Some((png, svg)) = r {
                let a = tmp_dir.join(format!("{}.png", p.stem));
                std::fs::write(&a, png).map_err(io(&a))?;
                let b = tmp_dir.join(format!("{}.svg", p.stem));
                std::fs::write(&b, svg).map_err(io(&b))?;
            }
        }
        let old = dir.join(format!(".figures.old-{}", std::process::id()));
        if fig_dir.exists() {
            std::fs::rename(&fig_dir, &old).map_err(io(&fig_dir))?;
        }
        std::fs::rename(&tmp_dir, &fig_dir).map_err(io(&fig_dir))?;
        let _ = std::fs::remove_dir_all(&old);
        Ok(())
    };
    if let Err(e) = write_figures() {
        let _ = std::fs::remove_dir_all(&tmp_dir);
        return Err(e);
    }

    let mut recording_messages = 0;
    let recording_note = if options.recording {
        let path = dir.join("recording.mcap");
        let tmp = temp_sibling(&path);
        let file = std::fs::File::create(&tmp).map_err(io(&tmp))?;
        let written = recording::write(&folder, std::io::BufWriter::new(file));
        match written {
            Ok(n) => recording_messages = n,
            Err(e) => {
                let _ = std::fs::remove_file(&tmp);
                return Err(ReportError::Output(format!("{}: {e}", path.display())));
            }
        }
        std::fs::rename(&tmp, &path).map_err(io(&path))?;
        Some(format!(
            "every variant's time series, topics `/VARIANT/joint_state`, `/reference`, `/torque`, `/external_torque` and more, JSON messages ({recording_messages} in all), log time = `t`."
        ))
    } else {
        None
    };

    let entries: Vec<document::Entry<'_>> = plans
        .iter()
        .zip(&rendered)
        .map(|(p, r)| document::Entry {
            id: &p.id,
            caption: &p.caption,
            data: &p.data,
            stem: r.as_ref().map(|_| p.stem.as_str()),
            png: r.as_ref().map(|(png, _)| png.as_slice()),
            missing: p.figure.as_ref().err().map(String::as_str),
        })
        .collect();
    write_atomic(
        &dir.join("report.md"),
        document::markdown(&folder, &entries, recording_note.as_deref()).as_bytes(),
    )?;
    write_atomic(
        &dir.join("report.html"),
        document::html(&folder, &entries, recording_note.as_deref()).as_bytes(),
    )?;
    Ok(Outcome {
        figures: plans
            .iter()
            .zip(&rendered)
            .filter(|(_, r)| r.is_some())
            .map(|(p, _)| p.id.clone())
            .collect(),
        unavailable: plans
            .iter()
            .filter_map(|p| p.figure.as_ref().err().map(|e| (p.id.clone(), e.clone())))
            .collect(),
        recording_messages,
    })
}
