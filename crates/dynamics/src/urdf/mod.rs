//! URDF loading: a serial chain between a base link and a tip link, with everything
//! else the arm carries.
//!
//! Steps, one file each: [`xml`] (parse, line numbers), [`tree`] (links and joints as a
//! tree: the only pass over the whole file), [`chain`] (base, tip, the joints between;
//! the default tip rule), [`inertial`] (validation of the masses the model uses),
//! [`fold`] (fixed attachments and locked or dropped branches join the bodies),
//! [`mount`] (the base's pose in the root, gravity), [`assemble`] (the [`Model`]).
//!
//! What is built:
//! * the path from `base` to `tip`; its revolute, continuous and prismatic joints become
//!   the model's joints, in order; fixed joints on the path are folded into the placement
//!   of the next moving joint, and their child links become frames of the body before them;
//! * links hanging off the chain through fixed joints (sensors, flanges) fold their
//!   inertia into the body that carries them and stay addressable as frames;
//! * branches hanging off through moving joints not on the path are locked (their joints
//!   held at 0 unless [`UrdfOptions::lock`] says otherwise) and fold in the same way, or
//!   are left out when named in [`UrdfOptions::drop`]; [`Model::locked_branches`] and
//!   [`Model::dropped_branches`] list them;
//! * links before the first moving joint belong to the base (their mass never moves);
//! * gravity is the root link's `-z` (9.81 m/s^2) in the base link's axes ([`mount`]): the
//!   joints above a base that is not the root turn it (moving ones held at their
//!   [`UrdfOptions::lock`] position, 0 by default).
//!
//! Only the parts of the file the model uses are validated: a broken inertia on a
//! robot's other arm does not stop loading this one.

mod assemble;
mod chain;
mod fold;
mod inertial;
mod joint;
mod mount;
mod tree;
mod xml;

use std::path::Path;

use crate::error::DynamicsError;
use crate::model::Model;

/// How to read a URDF into a [`Model`]. `UrdfOptions::default()` is what
/// [`Model::from_urdf_file`] does: root to default tip, branches locked at 0, physically
/// impossible inertias on the chain loaded with a warning.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct UrdfOptions {
    /// The base link, fixed in the world (default: the root link).
    pub base: Option<String>,
    /// The tip link, the arm's hand (default: the rule in the crate documentation of
    /// [`Model::from_urdf_file_with`]; an error listing the candidates when ambiguous).
    pub tip: Option<String>,
    /// Make the warnings about inertias on the chain errors.
    pub strict: bool,
    /// Lock positions (rad or m) of joints in branches off the chain, or above the base
    /// (they turn its mount, and with it gravity); the others are locked at 0.
    pub lock: Vec<(String, f64)>,
    /// Joints whose subtree is left out of the model (mass and all) instead of locked.
    pub drop: Vec<String>,
}

impl UrdfOptions {
    /// Options naming base and tip, defaults otherwise.
    pub fn chain(base: Option<&str>, tip: Option<&str>) -> Self {
        Self {
            base: base.map(String::from),
            tip: tip.map(String::from),
            ..Self::default()
        }
    }
}

/// Loads a model from a URDF file.
pub(crate) fn load_file(path: &Path, options: &UrdfOptions) -> Result<Model, DynamicsError> {
    let file = path.display().to_string();
    let bytes =
        admittance_files::read_regular(path, admittance_files::TEXT_LIMIT).map_err(|source| {
            DynamicsError::Io {
                file: file.clone(),
                source,
            }
        })?;
    let text = xml::utf8_text(bytes, &file)?;
    load_str(&text, &file, options)
}

/// Loads a model from URDF text; `source` names it in errors.
pub(crate) fn load_str(
    text: &str,
    source: &str,
    options: &UrdfOptions,
) -> Result<Model, DynamicsError> {
    let doc = xml::parse_document(text, source)?;
    let ctx = xml::Ctx::new(source, &doc, text);
    let tree = tree::Tree::read(&ctx)?;
    let chain = chain::select(&ctx, &tree, options)?;
    Ok(assemble::assemble(&ctx, &tree, &chain, options)?)
}
