//! Helpers shared by the dynamics integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

use admittance_dynamics::Model;

pub fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

pub fn baxter() -> Model {
    Model::from_urdf_file(
        &repo_root().join("models/baxter_left_arm.urdf"),
        Some("base"),
        Some("left_hand"),
    )
    .expect("the project's Baxter model loads")
}

pub fn fixtures_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

/// Every fixture arm (URDF files under tests/fixtures/arms) plus Baxter.
pub fn all_arms() -> Vec<Model> {
    let mut out = vec![baxter()];
    let dir = fixtures_dir().join("arms");
    let mut paths: Vec<_> = std::fs::read_dir(&dir)
        .map(|d| d.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    paths.sort();
    for p in paths {
        if p.extension().is_some_and(|e| e == "urdf") {
            out.push(Model::from_urdf_file(&p, None, None).unwrap_or_else(|e| panic!("{e}")));
        }
    }
    out
}
