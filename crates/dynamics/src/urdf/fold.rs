//! Step 5, folding and locking: everything that hangs off a link of the chain joins the
//! body that carries that link.
//!
//! * Links behind fixed joints are rigidly attached: their inertia folds into the body
//!   and they stay addressable as frames.
//! * Branches behind moving joints off the chain (fingers, a head, another arm) are
//!   *locked*: every joint of the branch is held at a position (0 unless the options say
//!   otherwise; Pinocchio's reduced-model convention, `buildReducedModel` at the neutral
//!   configuration) and the branch folds in like a rigid attachment, mass kept. A mimic
//!   joint without a lock position of its own follows its reference joint's lock position
//!   when that one is given (`position = multiplier * reference + offset`).
//! * Branches named in the `drop` option are left out, their mass with them.
//!
//! What hangs off the base (and the base's own links) never moves: those links become
//! frames of the base and their inertia is not validated.

use super::chain::Chain;
use super::inertial::{lenient_mass, moving_inertial};
use super::joint::{placement_at, position_range};
use super::tree::Tree;
use super::xml::Ctx;
use super::UrdfOptions;
use crate::error::{LoadWarning, UrdfError};
use crate::model::{DroppedBranch, Frame, LinkMass, LockedBranch};
use crate::spatial::{Inertia, Transform};

/// What folding produced, for assembly.
#[derive(Default)]
pub(super) struct Folded {
    pub(super) frames: Vec<Frame>,
    pub(super) link_masses: Vec<LinkMass>,
    pub(super) bodies: Vec<Inertia>,
    pub(super) locked: Vec<LockedBranch>,
    pub(super) dropped: Vec<DroppedBranch>,
    pub(super) excluded_links: Vec<String>,
    pub(super) warnings: Vec<LoadWarning>,
}

/// The folding pass: options resolved per joint, and what has been built so far.
pub(super) struct Folder<'c, 'a, 'i> {
    ctx: &'c Ctx<'a, 'i>,
    tree: &'c Tree<'a, 'i>,
    chain: &'c Chain,
    strict: bool,
    /// Per joint: the lock position given in the options.
    lock: Vec<Option<f64>>,
    /// Per joint: named in the `drop` option.
    drop: Vec<bool>,
    /// Per joint: reached by folding (to report options naming joints outside the model).
    reached: Vec<bool>,
    /// Per joint: inside a dropped branch.
    in_dropped: Vec<bool>,
    pub(super) out: Folded,
}

impl<'c, 'a, 'i> Folder<'c, 'a, 'i> {
    /// Checks the lock and drop options against the file and the chain.
    pub(super) fn new(
        ctx: &'c Ctx<'a, 'i>,
        tree: &'c Tree<'a, 'i>,
        chain: &'c Chain,
        options: &UrdfOptions,
        n_bodies: usize,
    ) -> Result<Self, UrdfError> {
        let n = tree.joints.len();
        let mut folder = Folder {
            ctx,
            tree,
            chain,
            strict: options.strict,
            lock: vec![None; n],
            drop: vec![false; n],
            reached: vec![false; n],
            in_dropped: vec![false; n],
            out: Folded {
                bodies: vec![Inertia::zero(); n_bodies],
                ..Folded::default()
            },
        };
        for (name, value) in &options.lock {
            let j = folder.option_joint("lock", name)?;
            let joint = &tree.joints[j];
            let bad = |problem: String| {
                ctx.err(Some(joint.node), format!("lock option '{name}'"), problem)
            };
            if !value.is_finite() {
                return Err(bad(format!("lock position {value} is not a finite number")));
            }
            if !joint.kind.is_one_dof() {
                return Err(bad(format!(
                    "joint '{name}' is {}: only revolute, continuous and prismatic joints take a \
                     lock position",
                    joint.type_name
                )));
            }
            if folder.lock[j].replace(*value).is_some() {
                return Err(bad("the joint is given a lock position twice".into()));
            }
        }
        for name in &options.drop {
            let j = folder.option_joint("drop", name)?;
            if std::mem::replace(&mut folder.drop[j], true) {
                return Err(ctx.err(
                    Some(tree.joints[j].node),
                    format!("drop option '{name}'"),
                    "the joint is named twice",
                ));
            }
        }
        Ok(folder)
    }

    /// The joint an option names: it must exist and must not be on the chain.
    fn option_joint(&self, option: &str, name: &str) -> Result<usize, UrdfError> {
        let element = format!("{option} option '{name}'");
        let Some(&j) = self.tree.joint_index.get(name) else {
            return Err(self
                .ctx
                .err(None, element, "no joint of that name in the file"));
        };
        if self.chain.on_path[j] {
            return Err(self.ctx.err(
                Some(self.tree.joints[j].node),
                element,
                format!(
                    "joint '{name}' is on the chain '{}' -> '{}': it is a coordinate of the model, \
                     not a branch off it (to hold it, end the chain before it, --tip {}, or \
                     start it after, --base {})",
                    self.tree.links[self.chain.base].name,
                    self.tree.links[self.chain.tip].name,
                    self.tree.links[self.tree.joints[j].parent].name,
                    self.tree.links[self.tree.joints[j].child].name
                ),
            ));
        }
        Ok(j)
    }

    /// Attaches `link` (placed at `placement` in `body`'s frame, or the base frame for
    /// `None`) and everything hanging off it that is not on the chain.
    pub(super) fn attach(
        &mut self,
        link: usize,
        placement: Transform,
        body: Option<usize>,
    ) -> Result<(), UrdfError> {
        let (tree, ctx) = (self.tree, self.ctx);
        // Depth first in file order (children pushed in reverse), as frames were always listed.
        let mut stack = vec![(link, placement, None::<usize>)];
        while let Some((link, placement, branch)) = stack.pop() {
            self.add_link(link, &placement, body, branch)?;
            for &j in tree.children[link].iter().rev() {
                if self.chain.on_path[j] {
                    continue;
                }
                self.reached[j] = true;
                if self.drop[j] {
                    self.drop_branch(j);
                    continue;
                }
                let joint = &tree.joints[j];
                if !joint.moves() {
                    let origin = ctx.origin(joint.node, &format!("joint '{}'", joint.name))?;
                    stack.push((joint.child, placement.compose(&origin), branch));
                    continue;
                }
                let value = self.lock_position(j)?;
                let at = placement.compose(&placement_at(ctx, joint, value)?);
                let b = match branch {
                    Some(b) => b,
                    None => {
                        self.out.locked.push(LockedBranch {
                            joint: joint.name.to_string(),
                            joints: Vec::new(),
                            mass: 0.0,
                            carried_by: body,
                        });
                        self.out.locked.len() - 1
                    }
                };
                self.out.locked[b]
                    .joints
                    .push((joint.name.to_string(), value));
                stack.push((joint.child, at, Some(b)));
            }
        }
        Ok(())
    }

    /// Adds the frame, the mass summary and (for a moving body) the inertia of one link.
    fn add_link(
        &mut self,
        link: usize,
        placement: &Transform,
        body: Option<usize>,
        branch: Option<usize>,
    ) -> Result<(), UrdfError> {
        let tree_link = &self.tree.links[link];
        let ctx = self.ctx;
        let name = tree_link.name.to_string();
        let mass = match body {
            Some(b) => {
                let found = moving_inertial(
                    ctx,
                    tree_link.node,
                    tree_link.name,
                    self.strict,
                    &mut self.out.warnings,
                )?;
                match found {
                    Some(li) => {
                        self.out.bodies[b] =
                            self.out.bodies[b].add(&li.inertia.transformed(placement));
                        li.mass
                    }
                    None => 0.0,
                }
            }
            None => lenient_mass(tree_link.node),
        };
        if let Some(k) = branch {
            self.out.locked[k].mass += mass;
        }
        self.out.frames.push(Frame {
            name: name.clone(),
            parent_joint: body,
            placement: *placement,
        });
        self.out.link_masses.push(LinkMass {
            link: name,
            mass,
            joint: body,
        });
        Ok(())
    }

    /// The position joint `j` (off the chain, moving) is locked at.
    fn lock_position(&mut self, j: usize) -> Result<f64, UrdfError> {
        let tree = self.tree;
        let joint = &tree.joints[j];
        let element = format!("joint '{}'", joint.name);
        let mut value = self.lock[j];
        if let Some(mimic) = joint.mimic {
            let target = joint.mimic_target().unwrap_or("");
            let followed = self.tree.joint_index.get(target).copied();
            if let Some(t) = followed.filter(|&t| self.chain.on_path[t]) {
                return Err(self.ctx.err(
                    Some(mimic),
                    format!("{element} <mimic>"),
                    format!(
                        "follows joint '{}' on the chain, so its branch moves with the chain and \
                         cannot be locked; drop it (drop option '{}') or choose a tip through it",
                        self.tree.joints[t].name, joint.name
                    ),
                ));
            }
            if let (None, Some(reference)) = (value, followed.and_then(|t| self.lock[t])) {
                let el = format!("{element} <mimic>");
                let multiplier = self.ctx.number(mimic, &el, "multiplier")?.unwrap_or(1.0);
                let offset = self.ctx.number(mimic, &el, "offset")?.unwrap_or(0.0);
                value = Some(multiplier * reference + offset);
            }
        }
        let value = value.unwrap_or(0.0);
        if let Some((lower, upper)) = position_range(joint) {
            if value < lower || value > upper {
                self.out.warnings.push(LoadWarning {
                    file: self.ctx.file.to_string(),
                    line: Some(self.ctx.line(joint.node)),
                    element,
                    problem: format!(
                        "locked at {value}, outside its limits [{lower}, {upper}] (give a \
                         position with the lock option)"
                    ),
                });
            }
        }
        Ok(value)
    }

    /// Leaves out the subtree of joint `j`, recording its links and their mass.
    fn drop_branch(&mut self, j: usize) {
        let tree = self.tree;
        let links = tree.subtree_links(tree.joints[j].child);
        let mut mass = 0.0;
        let mut names = Vec::with_capacity(links.len());
        for &l in &links {
            mass += lenient_mass(tree.links[l].node);
            names.push(tree.links[l].name.to_string());
            for &inner in &tree.children[l] {
                self.in_dropped[inner] = true;
            }
        }
        self.out.excluded_links.extend(names.iter().cloned());
        self.out.dropped.push(DroppedBranch {
            joint: tree.joints[j].name.to_string(),
            links: names,
            mass,
        });
    }

    /// Checks that every joint named in the options was reached (or, for a lock, lies
    /// `above_base`: it turns the mount), and returns the result.
    pub(super) fn finish(
        self,
        options: &UrdfOptions,
        above_base: &[usize],
    ) -> Result<Folded, UrdfError> {
        let named = options
            .lock
            .iter()
            .map(|(n, _)| ("lock", n))
            .chain(options.drop.iter().map(|n| ("drop", n)));
        for (option, name) in named {
            let j = self.tree.joint_index[name.as_str()];
            if self.reached[j] || (option == "lock" && above_base.contains(&j)) {
                continue;
            }
            let why = if self.in_dropped[j] {
                "it is inside a dropped branch".to_string()
            } else {
                format!(
                    "it is not below the base link '{}'",
                    self.tree.links[self.chain.base].name
                )
            };
            return Err(self.ctx.err(
                Some(self.tree.joints[j].node),
                format!("{option} option '{name}'"),
                format!("joint '{name}' is not part of the model: {why}"),
            ));
        }
        Ok(self.out)
    }
}
