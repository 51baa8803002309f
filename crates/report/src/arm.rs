//! The arm of a run (for the kinematic figure, Fig 7): the URDF named by `scenario.toml`.

use std::path::{Path, PathBuf};

use admittance_dynamics::Model;

use crate::folder::RunFolder;

/// Finds and loads the arm named by `scenario.toml` (`[arm] urdf`, `base`, `tip`): an
/// absolute path, or relative to `scenario_dir` (the folder of the original scenario
/// file), the run folder or `./scenarios`.
pub fn load_arm(folder: &RunFolder, scenario_dir: Option<&Path>) -> Result<Model, String> {
    let text = |key: &str| folder.scenario_value(key).and_then(toml::Value::as_str);
    let urdf = text("arm.urdf").ok_or("scenario.toml (in the run folder) names no `[arm] urdf`")?;
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
            candidates
                .iter()
                .map(|c| c.display().to_string())
                .collect::<Vec<_>>()
                .join(" or ")
        )
    })?;
    let lock = folder
        .scenario_value("arm.lock")
        .and_then(toml::Value::as_table)
        .map(|t| {
            t.iter()
                .filter_map(|(j, v)| {
                    Some((
                        j.clone(),
                        v.as_float().or(v.as_integer().map(|i| i as f64))?,
                    ))
                })
                .collect()
        })
        .unwrap_or_default();
    let drop = folder
        .scenario_value("arm.drop")
        .and_then(toml::Value::as_array)
        .map(|a| {
            a.iter()
                .filter_map(|v| v.as_str().map(String::from))
                .collect()
        })
        .unwrap_or_default();
    let options = admittance_dynamics::UrdfOptions {
        base: text("arm.base").map(String::from),
        tip: text("arm.tip").map(String::from),
        // The run loaded it; its warnings are in summary.json already.
        strict: false,
        lock,
        drop,
    };
    Model::from_urdf_file_with(found, &options).map_err(|e| e.to_string())
}
