//! Writing the table as the free-motion CSV, atomically, and only over a file this tool
//! wrote: its header ends with the marker column [`STAMP_COLUMN`].

use std::io::{BufRead, Read, Write};
use std::path::Path;

use crate::error::BagError;
use crate::resample::Table;

/// The last column of an imported CSV: each row's absolute stamp (ns since the epoch). The
/// free-motion reader ignores it; this tool recognises its own files by it.
pub const STAMP_COLUMN: &str = "bag_stamp_ns";

fn refuse(path: &Path, reason: impl Into<String>) -> BagError {
    BagError::Destination {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

/// Whether the file's first line is the header of an imported CSV.
fn written_by_import(path: &Path) -> std::io::Result<bool> {
    let mut first = String::new();
    let file = std::fs::File::open(path)?;
    std::io::BufReader::new(file.take(1 << 20)).read_line(&mut first)?;
    let first = first.trim_end();
    Ok(first.starts_with("t,") && first.ends_with(&format!(",{STAMP_COLUMN}")))
}

/// Checks that the CSV may be written at `path` (before any work): a new name in an
/// existing folder, or a CSV this tool wrote. A folder, a link, a device or any other
/// file is refused.
pub fn check_destination(path: &Path) -> Result<(), BagError> {
    if path.as_os_str().is_empty() || path.file_name().is_none() {
        return Err(refuse(path, "not a file name"));
    }
    match std::fs::symlink_metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
            match std::fs::metadata(dir) {
                Ok(m) if m.is_dir() => Ok(()),
                Ok(_) => Err(refuse(path, format!("{} is not a folder", dir.display()))),
                Err(e) => Err(refuse(path, format!("its folder {}: {e}", dir.display()))),
            }
        }
        Err(e) => Err(refuse(path, e.to_string())),
        Ok(m) if m.file_type().is_symlink() => Err(refuse(path, "is a symbolic link; name the file itself or a new name")),
        Ok(m) if !m.is_file() => Err(refuse(path, "exists and is not a regular file")),
        Ok(_) => match written_by_import(path) {
            Ok(true) => Ok(()),
            Ok(false) => Err(refuse(
                path,
                format!("exists and was not written by `admittance import` (its header does not end with `{STAMP_COLUMN}`); refusing to replace it: remove it or choose another name"),
            )),
            Err(e) => Err(refuse(path, format!("exists and cannot be read to tell whether it was written by `admittance import`: {e}"))),
        },
    }
}

/// The CSV's header fields.
fn header(table: &Table) -> Vec<String> {
    let mut header = vec!["t".to_string()];
    for prefix in ["q", "qdot", "qddot", "tau"] {
        header.extend(table.joints.iter().map(|j| format!("{prefix}.{j}")));
    }
    if let Some((cols, _)) = &table.label {
        header.extend(cols.iter().map(|c| format!("label.{c}")));
    }
    header.push(STAMP_COLUMN.to_string());
    header
}

/// The names must make an honest CSV header: no comma, quote, line break or other control
/// character (they would split, shift or hide the columns), not empty, no two alike.
pub fn check_columns(bag: &Path, table: &Table) -> Result<(), BagError> {
    let bad = |message: String| BagError::Data {
        bag: bag.to_path_buf(),
        message,
    };
    let label = table.label.iter().flat_map(|(c, _)| c.iter());
    for name in table.joints.iter().chain(label) {
        if name.is_empty()
            || name.contains([',', '"'])
            || name.chars().any(char::is_control)
            || name.trim() != name
        {
            return Err(bad(format!(
                "joint or label name {name:?} cannot be a CSV column name (empty, or a comma, quote, line break, control character or outer space): rename it in the profile's `joints`"
            )));
        }
    }
    let mut h = header(table);
    h.sort();
    if let Some(w) = h.windows(2).find(|w| w[0] == w[1]) {
        return Err(bad(format!(
            "column `{}` would appear twice in the CSV: list each joint once in the profile's `joints`",
            w[0]
        )));
    }
    Ok(())
}

fn write_rows(out: &mut impl Write, table: &Table) -> std::io::Result<()> {
    let n = table.joints.len();
    writeln!(out, "{}", header(table).join(","))?;
    for k in 0..table.len() {
        write!(out, "{}", table.t[k])?;
        for x in [&table.q, &table.qdot, &table.qddot, &table.tau] {
            for v in &x[k * n..(k + 1) * n] {
                write!(out, ",{v}")?;
            }
        }
        if let Some((cols, v)) = &table.label {
            let m = cols.len();
            for v in &v[k * m..(k + 1) * m] {
                write!(out, ",{v}")?;
            }
        }
        writeln!(out, ",{}", table.stamps_ns[k])?;
    }
    Ok(())
}

/// The CSV text: `t, q.J..., qdot.J..., qddot.J..., tau.J..., label.X..., bag_stamp_ns`,
/// numbers in Rust's shortest round-trip form.
pub fn csv_text(table: &Table) -> String {
    let mut out = Vec::new();
    let _ = write_rows(&mut out, table);
    String::from_utf8_lossy(&out).into_owned()
}

/// A name nobody can guess before the run (a planted link there would be refused anyway:
/// the file is created exclusively).
fn unpredictable_suffix() -> String {
    use std::hash::{BuildHasher, Hasher};
    let mut h = std::collections::hash_map::RandomState::new().build_hasher();
    h.write_u128(
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos()),
    );
    format!("{}-{:016x}", std::process::id(), h.finish())
}

/// Writes the table to `path` (checked again) through a temporary sibling that is written
/// row by row, flushed to disk and renamed: `path` holds the old file or the new one,
/// never a part.
pub fn write_csv(path: &Path, table: &Table) -> Result<(), BagError> {
    check_destination(path)?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.tmp-{}", unpredictable_suffix()));
    let result = (|| {
        let f = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)?;
        let mut w = std::io::BufWriter::new(f);
        write_rows(&mut w, table)?;
        let f = w.into_inner().map_err(|e| e.into_error())?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(BagError::Write {
            path: path.to_path_buf(),
            message: e.to_string(),
        });
    }
    Ok(())
}
