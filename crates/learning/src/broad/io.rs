//! Versioned, checksummed model files that know what they are (docs/outputs.md, "Model
//! files").
//!
//! Layout (all integers and floats little-endian):
//!
//! ```text
//! 0..8           magic b"ADMBRBF\0"
//! 8..16          u64: length H of the JSON header
//! 16..16+H       JSON header: {"format": "admittance-broad-rbf", "format_version": 2,
//!                "written_by", "d_in", "d_out", "nodes", "pattern_width",
//!                "friction_columns", "growth_samples" (null or N),
//!                "arm" (null or {"joints", "fingerprint"}), "data" (null or
//!                {"input_filter_hz", "validation", "target"}), "fit" (null or {"nodes",
//!                "centres", "lambda_grid", "training_rows", "validation_rows"}),
//!                "growth": [{"nodes_added", "centres"}, ...],
//!                "coverage_threshold" (absent or m_0 in (0, 1], coverage.rs),
//!                "arrays": [{"name", "len"}, ...]}
//! 16+H..end-8    payload: the f64 arrays named in "arrays", in that order
//! end-8..end     u64: FNV-1a-64 of every byte before it
//! ```
//!
//! The model's numbers live in the binary payload (bit-exact round trip); the header's
//! settings (filter, scales, grid) are JSON numbers in their shortest round-trip form,
//! read back bit-exact. Arrays: `input_mean`, `input_std`, `friction_scales`, `centres`
//! (L x d_in, standardised units), `widths`, `weights` (P x d_out row-major), `lambda`
//! ([lambda, lambda_rel]), and with the growth state `gram_lower` (the lower triangle of
//! G, column by column), `aty` (P x d_out row-major), `y_sum`, `y_sq`. The Cholesky factor
//! is recomputed on load.
//!
//! Version 1 files (no "written_by", "arm", "data", "fit", "growth") still load: their
//! provenance is empty, so [`BroadModel::check_arm`] answers
//! [`ArmCheck::Unrecorded`](super::ArmCheck) and users must say that nothing was checked.

use super::config::FrictionFeatures;
use super::data::Standardiser;
use super::error::BroadError;
use super::features::{FeatureMap, NodeSet};
use super::model::{BroadModel, GrowthState};
use super::provenance::{ArmIdentity, DataSettings, FitSettings, GrowthRecord, Provenance};
use super::solve::factor;
use faer::{Mat, Par};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The `format` string of a model file.
pub const FORMAT_NAME: &str = "admittance-broad-rbf";
/// The `format_version` this build writes (it reads this one and every older one).
pub const FORMAT_VERSION: u64 = 2;
pub(crate) const MAGIC: &[u8; 8] = b"ADMBRBF\0";

/// FNV-1a, 64 bit, of `bytes`.
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

#[derive(Serialize, Deserialize)]
struct ArrayInfo {
    name: String,
    len: u64,
}

#[derive(Serialize, Deserialize)]
struct Header {
    format: String,
    format_version: u64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    written_by: Option<String>,
    d_in: u64,
    d_out: u64,
    nodes: u64,
    pattern_width: u64,
    friction_columns: Vec<u64>,
    growth_samples: Option<u64>,
    #[serde(default)]
    arm: Option<ArmIdentity>,
    #[serde(default)]
    data: Option<DataSettings>,
    #[serde(default)]
    fit: Option<FitSettings>,
    #[serde(default)]
    growth: Vec<GrowthRecord>,
    /// Coverage threshold (`coverage.rs`); absent in older files (no coverage).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    coverage_threshold: Option<f64>,
    arrays: Vec<ArrayInfo>,
}

/// Only the two fields needed to tell a wrong format or version from a corrupted file.
#[derive(Deserialize)]
struct HeaderId {
    format: Option<String>,
    format_version: Option<u64>,
}

/// The header and where it ends, after the magic, the length, format and version checks.
fn parse_header(bytes: &[u8], path: &Path) -> Result<(Header, usize), BroadError> {
    let fmt = |reason: String| BroadError::Format {
        path: path.to_path_buf(),
        reason,
    };
    if bytes.len() < 8 || &bytes[..8] != MAGIC {
        if bytes.len() < 8 && MAGIC.starts_with(bytes) {
            return Err(fmt(format!(
                "truncated: {} bytes, not even the 8-byte magic",
                bytes.len()
            )));
        }
        return Err(fmt(format!(
            "not an {FORMAT_NAME} model file (bad magic bytes)"
        )));
    }
    if bytes.len() < 16 {
        return Err(fmt(format!(
            "truncated: {} bytes, the header length field is missing",
            bytes.len()
        )));
    }
    let h_len = u64::from_le_bytes(bytes[8..16].try_into().expect("8 bytes"));
    let h_end = 16u64
        .checked_add(h_len)
        .filter(|&e| e <= bytes.len() as u64);
    let Some(h_end) = h_end else {
        return Err(fmt(format!(
            "truncated: header of {h_len} bytes announced, file has only {} bytes",
            bytes.len()
        )));
    };
    let h_end = h_end as usize;
    let header_bytes = &bytes[16..h_end];
    // Format and version first, so that a file of another version says so.
    let id: HeaderId = serde_json::from_slice(header_bytes)
        .map_err(|e| fmt(format!("corrupted header (not valid JSON: {e})")))?;
    match id.format.as_deref() {
        Some(FORMAT_NAME) => {}
        Some(other) => {
            return Err(fmt(format!(
                "format is {other:?}, expected {FORMAT_NAME:?}"
            )))
        }
        None => return Err(fmt("corrupted header: no \"format\" field".into())),
    }
    match id.format_version {
        Some(1..=FORMAT_VERSION) => {}
        Some(v) => {
            return Err(BroadError::UnsupportedVersion {
                path: path.to_path_buf(),
                found: v,
                supported: FORMAT_VERSION,
            })
        }
        None => return Err(fmt("corrupted header: no \"format_version\" field".into())),
    }
    let header: Header =
        serde_json::from_slice(header_bytes).map_err(|e| fmt(format!("corrupted header: {e}")))?;
    Ok((header, h_end))
}

/// The largest input, output or node count a model file may state (an arm's network has
/// tens of inputs and hundreds to thousands of nodes).
const MAX_DIMENSION: u64 = 100_000;

/// Array names and lengths (values), in file order.
type ArrayList = Vec<(&'static str, u64)>;

/// The arrays the header's dimensions call for, in file order (the header's own list
/// must agree), and the pattern width P.
fn expected_arrays(header: &Header) -> Result<(ArrayList, u64), String> {
    for (name, v) in [
        ("d_in", header.d_in),
        ("d_out", header.d_out),
        ("nodes", header.nodes),
    ] {
        if v > MAX_DIMENSION {
            return Err(format!(
                "corrupted header: {name} = {v} is beyond the {MAX_DIMENSION} a model file may have"
            ));
        }
    }
    let f = header.friction_columns.len() as u64;
    let mul = |a: u64, b: u64| a.checked_mul(b);
    let too_big = || "corrupted header: dimensions overflow".to_string();
    let n_scales_total = header
        .arrays
        .iter()
        .find(|a| a.name == "friction_scales")
        .map(|a| a.len)
        .unwrap_or(0);
    let p = mul(n_scales_total, f)
        .and_then(|fs| (header.d_in).checked_add(fs))
        .and_then(|v| v.checked_add(1))
        .and_then(|v| v.checked_add(header.nodes))
        .ok_or_else(too_big)?;
    if p != header.pattern_width {
        return Err(format!(
            "corrupted header: pattern_width {} does not match d_in {} + friction {} + 1 + nodes {}",
            header.pattern_width,
            header.d_in,
            n_scales_total.saturating_mul(f),
            header.nodes
        ));
    }
    let mut expected: Vec<(&'static str, u64)> = vec![
        ("input_mean", header.d_in),
        ("input_std", header.d_in),
        ("friction_scales", n_scales_total),
        (
            "centres",
            mul(header.nodes, header.d_in).ok_or_else(too_big)?,
        ),
        ("widths", header.nodes),
        ("weights", mul(p, header.d_out).ok_or_else(too_big)?),
        ("lambda", 2),
    ];
    if header.growth_samples.is_some() {
        let tri = mul(p, p.checked_add(1).ok_or_else(too_big)?).ok_or_else(too_big)? / 2;
        expected.push(("gram_lower", tri));
        expected.push(("aty", mul(p, header.d_out).ok_or_else(too_big)?));
        expected.push(("y_sum", header.d_out));
        expected.push(("y_sq", header.d_out));
    }
    if header.arrays.len() != expected.len()
        || header
            .arrays
            .iter()
            .zip(&expected)
            .any(|(a, (name, len))| a.name != *name || a.len != *len)
    {
        return Err(format!(
            "corrupted header: arrays {:?} do not match the dimensions (expected {:?})",
            header
                .arrays
                .iter()
                .map(|a| (a.name.as_str(), a.len))
                .collect::<Vec<_>>(),
            expected
        ));
    }
    Ok((expected, p))
}

/// Checks the file's length and checksum and reads the payload arrays (all finite).
fn read_payload(
    bytes: &[u8],
    h_end: usize,
    expected: &[(&'static str, u64)],
    path: &Path,
) -> Result<Vec<Vec<f64>>, BroadError> {
    let fmt = |reason: String| BroadError::Format {
        path: path.to_path_buf(),
        reason,
    };
    let too_big = || fmt("corrupted header: dimensions overflow".into());
    let payload_len = expected
        .iter()
        .try_fold(0u64, |acc, (_, len)| acc.checked_add(len.checked_mul(8)?))
        .ok_or_else(too_big)?;
    let total = (h_end as u64)
        .checked_add(payload_len)
        .and_then(|v| v.checked_add(8))
        .ok_or_else(too_big)?;
    if (bytes.len() as u64) < total {
        return Err(fmt(format!(
            "truncated: {} bytes, expected {total}",
            bytes.len()
        )));
    }
    if (bytes.len() as u64) > total {
        return Err(fmt(format!(
            "{} trailing bytes after the checksum (expected {total} bytes)",
            bytes.len() as u64 - total
        )));
    }
    let body_end = bytes.len() - 8;
    let stored = u64::from_le_bytes(bytes[body_end..].try_into().expect("8 bytes"));
    let computed = fnv1a64(&bytes[..body_end]);
    if stored != computed {
        return Err(BroadError::Checksum {
            path: path.to_path_buf(),
            stored,
            computed,
        });
    }
    let mut pos = h_end;
    let mut arrays = Vec::with_capacity(expected.len());
    for (name, len) in expected {
        let len = *len as usize;
        let v: Vec<f64> = bytes[pos..pos + 8 * len]
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
            .collect();
        pos += 8 * len;
        if let Some((i, x)) = v.iter().enumerate().find(|(_, x)| !x.is_finite()) {
            return Err(fmt(format!(
                "array {name} holds a non-finite value {x} at index {i}"
            )));
        }
        arrays.push(v);
    }
    Ok(arrays)
}

/// The provenance of a parsed header, checked against the model's dimensions.
fn provenance(header: &mut Header) -> Result<Provenance, String> {
    if let Some(arm) = &header.arm {
        let n = arm.joints.len() as u64;
        if n != header.d_out {
            return Err(format!(
                "corrupted header: {n} arm joints for {} outputs",
                header.d_out
            ));
        }
    }
    if let Some(data) = &header.data {
        data.validate()
            .map_err(|e| format!("corrupted header: data settings: {e}"))?;
    }
    Ok(Provenance {
        arm: header.arm.take(),
        data: header.data.take(),
        fit: header.fit.take(),
        growth: std::mem::take(&mut header.growth),
    })
}

impl BroadModel {
    /// Serialises the model (with its growth state, if any, and its provenance) into the
    /// file format above.
    pub fn to_bytes(&self) -> Vec<u8> {
        let d = self.d_in();
        let n = self.d_out;
        let p = self.pattern_width();
        let fm = &self.fm;
        let mut arrays: Vec<(&str, Vec<f64>)> = vec![
            ("input_mean", fm.standardiser.mean.clone()),
            ("input_std", fm.standardiser.std.clone()),
            ("friction_scales", fm.friction.scales.clone()),
            ("centres", fm.nodes.centres.clone()),
            ("widths", fm.nodes.widths.clone()),
            ("weights", self.w.clone()),
            ("lambda", vec![self.lambda, self.lambda_rel]),
        ];
        if let Some(s) = &self.state {
            let mut g = Vec::with_capacity(p * (p + 1) / 2);
            for j in 0..p {
                for i in j..p {
                    g.push(s.gram[(i, j)]);
                }
            }
            arrays.push(("gram_lower", g));
            let mut aty = Vec::with_capacity(p * n);
            for i in 0..p {
                for o in 0..n {
                    aty.push(s.aty[(i, o)]);
                }
            }
            arrays.push(("aty", aty));
            arrays.push(("y_sum", s.y_sum.clone()));
            arrays.push(("y_sq", s.y_sq.clone()));
        }
        let prov = &self.provenance;
        let header = Header {
            format: FORMAT_NAME.to_string(),
            format_version: FORMAT_VERSION,
            written_by: Some(concat!("admittance-learning ", env!("CARGO_PKG_VERSION")).into()),
            d_in: d as u64,
            d_out: n as u64,
            nodes: self.n_nodes() as u64,
            pattern_width: p as u64,
            friction_columns: fm.friction.columns.iter().map(|&c| c as u64).collect(),
            growth_samples: self.state.as_ref().map(|s| s.n_samples as u64),
            arm: prov.arm.clone(),
            data: prov.data,
            fit: prov.fit.clone(),
            growth: prov.growth.clone(),
            coverage_threshold: self.coverage_threshold,
            arrays: arrays
                .iter()
                .map(|(name, v)| ArrayInfo {
                    name: name.to_string(),
                    len: v.len() as u64,
                })
                .collect(),
        };
        // Every float of the header is finite (validated settings), so this cannot fail.
        let header = serde_json::to_vec(&header).expect("header serialises");
        let payload_len: usize = arrays.iter().map(|(_, v)| v.len() * 8).sum();
        let mut out = Vec::with_capacity(16 + header.len() + payload_len + 8);
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&(header.len() as u64).to_le_bytes());
        out.extend_from_slice(&header);
        for (_, v) in &arrays {
            for x in v {
                out.extend_from_slice(&x.to_le_bytes());
            }
        }
        let h = fnv1a64(&out);
        out.extend_from_slice(&h.to_le_bytes());
        out
    }

    /// Reads a model written by [`save`](Self::save) (any format version up to
    /// [`FORMAT_VERSION`]). A missing, truncated, corrupted or newer-version file gives an
    /// error naming the file and the problem.
    pub fn load(path: impl AsRef<Path>) -> Result<BroadModel, BroadError> {
        let path = path.as_ref();
        let bytes =
            admittance_files::read_regular(path, admittance_files::DATA_LIMIT).map_err(|e| {
                BroadError::Io {
                    path: path.to_path_buf(),
                    source: e,
                }
            })?;
        Self::from_bytes(&bytes, path)
    }

    /// Parses the bytes of a model file; `path` only names the source in errors.
    pub fn from_bytes(bytes: &[u8], path: impl AsRef<Path>) -> Result<BroadModel, BroadError> {
        let path = path.as_ref();
        let fmt = |reason: String| BroadError::Format {
            path: path.to_path_buf(),
            reason,
        };
        let (mut header, h_end) = parse_header(bytes, path)?;
        let (expected, p) = expected_arrays(&header).map_err(fmt)?;
        let arrays = read_payload(bytes, h_end, &expected, path)?;
        let provenance = provenance(&mut header).map_err(fmt)?;
        let mut model = assemble(&header, arrays, p as usize).map_err(fmt)?;
        model.provenance = provenance;
        Ok(model)
    }
}

/// The model from its checked arrays (in [`expected_arrays`] order).
fn assemble(header: &Header, arrays: Vec<Vec<f64>>, p: usize) -> Result<BroadModel, String> {
    let d = header.d_in as usize;
    let n = header.d_out as usize;
    let mut arrays = arrays.into_iter();
    let mut next = || arrays.next().unwrap_or_default();
    let (mean, std, scales) = (next(), next(), next());
    let (centres, widths, w, lambda) = (next(), next(), next(), next());
    let friction = FrictionFeatures {
        columns: header
            .friction_columns
            .iter()
            .map(|&c| c as usize)
            .collect(),
        scales,
    };
    friction
        .validate(d)
        .map_err(|e| format!("invalid friction features: {e}"))?;
    if d == 0 || n == 0 {
        return Err("invalid dimensions: d_in and d_out must be > 0".into());
    }
    if std.iter().any(|&s| s <= 0.0) {
        return Err("invalid standardisation: a standard deviation is <= 0".into());
    }
    let nodes = NodeSet {
        dim: d,
        centres,
        widths,
    };
    nodes
        .validate(d)
        .map_err(|e| format!("invalid nodes: {e}"))?;
    if !(lambda[0] > 0.0 && lambda[1] > 0.0) {
        return Err(format!("invalid lambda {lambda:?}"));
    }
    if let Some(t) = header.coverage_threshold {
        if !(t.is_finite() && t > 0.0 && t <= 1.0) {
            return Err(format!("invalid coverage threshold {t}"));
        }
    }
    let fm = FeatureMap::new(Standardiser { mean, std }, friction, nodes);
    let mut model = BroadModel {
        fm,
        d_out: n,
        lambda: lambda[0],
        lambda_rel: lambda[1],
        w: Vec::new(),
        wt: Vec::new(),
        state: None,
        coverage_threshold: header.coverage_threshold,
        provenance: Provenance::default(),
    };
    model.set_weights(faer::MatRef::from_row_major_slice(&w, p, n));
    if let Some(ns) = header.growth_samples {
        let (g_packed, aty_v, y_sum, y_sq) = (next(), next(), next(), next());
        let mut gram = Mat::<f64>::zeros(p, p);
        let mut idx = 0;
        for j in 0..p {
            for i in j..p {
                gram[(i, j)] = g_packed[idx];
                idx += 1;
            }
        }
        let aty = faer::MatRef::from_row_major_slice(&aty_v, p, n).to_owned();
        let threads = std::thread::available_parallelism()
            .map(|v| v.get())
            .unwrap_or(1);
        let par = if threads > 1 {
            Par::rayon(threads)
        } else {
            Par::Seq
        };
        let chol = factor(gram.as_ref(), model.lambda, model.bias_index(), par)
            .ok_or("growth state: G + lambda D is not positive definite")?;
        model.state = Some(GrowthState {
            gram,
            aty,
            chol,
            n_samples: ns as usize,
            y_sum,
            y_sq,
        });
    }
    Ok(model)
}
