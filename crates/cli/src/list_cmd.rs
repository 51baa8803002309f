//! `admittance list`: the scenario files of a folder, one line each: file, name,
//! description.

use std::path::PathBuf;

use clap::Args;

use crate::CliError;

#[derive(Args)]
pub struct ListArgs {
    /// Folder of scenario files (*.toml).
    #[arg(long, default_value = "scenarios")]
    dir: PathBuf,
}

/// One line of the listing: file name, scenario name, description (or what is wrong).
fn describe(path: &std::path::Path) -> Result<(String, String), String> {
    let text = admittance_files::read_regular_text(path, admittance_files::TEXT_LIMIT)
        .map_err(|e| format!("unreadable: {e}"))?;
    let table: toml::Table = text
        .parse()
        .map_err(|e: toml::de::Error| format!("not valid TOML: {}", e.message()))?;
    let name = table
        .get("name")
        .and_then(toml::Value::as_str)
        .ok_or("no `name` key")?
        .to_string();
    let description = table
        .get("description")
        .and_then(toml::Value::as_str)
        .unwrap_or("(no description)")
        .to_string();
    Ok((name, description))
}

pub fn list(args: &ListArgs) -> Result<(), CliError> {
    let entries = std::fs::read_dir(&args.dir).map_err(|e| {
        CliError::input(format!(
            "{}: cannot list ({e}); run from the repository root or pass --dir FOLDER",
            args.dir.display()
        ))
    })?;
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml") && p.is_file())
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(CliError::input(format!(
            "{}: no scenario files (*.toml); pass --dir FOLDER",
            args.dir.display()
        )));
    }
    type Row = (String, Result<(String, String), String>);
    let rows: Vec<Row> = files
        .iter()
        .map(|f| {
            (
                f.file_name()
                    .map(|n| n.to_string_lossy().to_string())
                    .unwrap_or_default(),
                describe(f),
            )
        })
        .collect();
    let w_file = rows.iter().map(|(f, _)| f.len()).max().unwrap_or(0);
    let w_name = rows
        .iter()
        .filter_map(|(_, r)| r.as_ref().ok().map(|(n, _)| n.len()))
        .max()
        .unwrap_or(0);
    let mut out = String::new();
    let mut bad = Vec::new();
    for (file, r) in &rows {
        match r {
            Ok((name, description)) => out.push_str(&format!(
                "{file:<w_file$}  {name:<w_name$}  {description}\n"
            )),
            Err(e) => {
                out.push_str(&format!(
                    "{file:<w_file$}  {:<w_name$}  (invalid: {e})\n",
                    "?"
                ));
                bad.push(format!("{}: {e}", args.dir.join(file).display()));
            }
        }
    }
    crate::write_stdout(&out);
    if let Some(first) = bad.first() {
        return Err(CliError::input(format!(
            "{first}{}",
            if bad.len() > 1 {
                format!(" (and {} more)", bad.len() - 1)
            } else {
                String::new()
            }
        )));
    }
    Ok(())
}
