//! Step 2, the tree: names, parents and children of every link and joint of the file,
//! and nothing else. This is the only pass over the whole file; what is wrong here
//! (a joint naming a link that does not exist, two parents, a loop, several roots) makes
//! the file unreadable as a URDF, so it is an error wherever it is. Numbers are not read
//! here: only the parts the model uses are validated (steps 4 and 5).

use std::collections::HashMap;

use roxmltree::Node;

use super::xml::{child, Ctx};
use crate::error::UrdfError;

/// The URDF joint types (`Unknown` is reported only where the joint is used).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum JointType {
    Fixed,
    Revolute,
    Continuous,
    Prismatic,
    Floating,
    Planar,
    Unknown,
}

impl JointType {
    fn from_name(name: &str) -> Self {
        match name {
            "fixed" => Self::Fixed,
            "revolute" => Self::Revolute,
            "continuous" => Self::Continuous,
            "prismatic" => Self::Prismatic,
            "floating" => Self::Floating,
            "planar" => Self::Planar,
            _ => Self::Unknown,
        }
    }

    /// Revolute, continuous or prismatic: one coordinate.
    pub(super) fn is_one_dof(self) -> bool {
        matches!(self, Self::Revolute | Self::Continuous | Self::Prismatic)
    }
}

pub(super) struct TreeLink<'a, 'i> {
    pub(super) name: &'a str,
    pub(super) node: Node<'a, 'i>,
}

pub(super) struct TreeJoint<'a, 'i> {
    pub(super) name: &'a str,
    pub(super) node: Node<'a, 'i>,
    pub(super) kind: JointType,
    pub(super) type_name: &'a str,
    pub(super) parent: usize,
    pub(super) child: usize,
    /// The `<mimic>` element, when the joint has one.
    pub(super) mimic: Option<Node<'a, 'i>>,
}

impl TreeJoint<'_, '_> {
    /// Anything but fixed (one-coordinate, floating, planar or unknown joints).
    pub(super) fn moves(&self) -> bool {
        self.kind != JointType::Fixed
    }

    /// The joint named by `<mimic joint="..">`.
    pub(super) fn mimic_target(&self) -> Option<&str> {
        self.mimic.and_then(|m| m.attribute("joint"))
    }
}

/// The links and joints of a URDF as a tree (every link but the root has one parent joint).
pub(super) struct Tree<'a, 'i> {
    pub(super) links: Vec<TreeLink<'a, 'i>>,
    pub(super) joints: Vec<TreeJoint<'a, 'i>>,
    pub(super) link_index: HashMap<&'a str, usize>,
    pub(super) joint_index: HashMap<&'a str, usize>,
    /// The joint whose child each link is.
    pub(super) parent_joint: Vec<Option<usize>>,
    /// The joints whose parent each link is, in file order.
    pub(super) children: Vec<Vec<usize>>,
    pub(super) root: usize,
}

fn name_of<'a>(ctx: &Ctx, node: Node<'a, '_>, what: &str) -> Result<&'a str, UrdfError> {
    node.attribute("name")
        .ok_or_else(|| ctx.err(Some(node), format!("<{what}>"), "missing attribute 'name'"))
}

impl<'a, 'i> Tree<'a, 'i> {
    /// Reads the structure of the whole file.
    pub(super) fn read(ctx: &Ctx<'a, 'i>) -> Result<Self, UrdfError> {
        let root = ctx.doc.root_element();
        if root.tag_name().name() != "robot" {
            return Err(ctx.err(
                Some(root),
                format!("<{}>", root.tag_name().name()),
                "the root element must be <robot>",
            ));
        }
        let elements = |tag: &'static str| {
            root.children()
                .filter(move |n| n.is_element() && n.tag_name().name() == tag)
        };
        let mut links = Vec::new();
        let mut link_index = HashMap::new();
        for node in elements("link") {
            let name = name_of(ctx, node, "link")?;
            if let Some(&first) = link_index.get(name) {
                let first: &TreeLink = &links[first];
                return Err(ctx.err(
                    Some(node),
                    format!("link '{name}'"),
                    format!(
                        "duplicate link name (first defined on line {})",
                        ctx.line(first.node)
                    ),
                ));
            }
            link_index.insert(name, links.len());
            links.push(TreeLink { name, node });
        }
        if links.is_empty() {
            return Err(ctx.err(Some(root), "<robot>", "no <link> elements"));
        }
        let mut tree = Tree {
            parent_joint: vec![None; links.len()],
            children: vec![Vec::new(); links.len()],
            links,
            joints: Vec::new(),
            link_index,
            joint_index: HashMap::new(),
            root: 0,
        };
        for node in elements("joint") {
            tree.add_joint(ctx, node)?;
        }
        tree.root = tree.find_root(ctx, root)?;
        Ok(tree)
    }

    fn add_joint(&mut self, ctx: &Ctx<'a, 'i>, node: Node<'a, 'i>) -> Result<(), UrdfError> {
        let name = name_of(ctx, node, "joint")?;
        let element = format!("joint '{name}'");
        let type_name = node
            .attribute("type")
            .ok_or_else(|| ctx.err(Some(node), &element, "missing attribute 'type'"))?;
        let link_ref = |tag: &str| -> Result<usize, UrdfError> {
            let n = child(node, tag)
                .ok_or_else(|| ctx.err(Some(node), &element, format!("missing <{tag}>")))?;
            let el = format!("{element} <{tag}>");
            let link = n
                .attribute("link")
                .ok_or_else(|| ctx.err(Some(n), &el, "missing attribute 'link'"))?;
            self.link_index
                .get(link)
                .copied()
                .ok_or_else(|| ctx.err(Some(n), &el, format!("link '{link}' is not defined")))
        };
        let parent = link_ref("parent")?;
        let child_link = link_ref("child")?;
        if let Some(&first) = self.joint_index.get(name) {
            return Err(ctx.err(
                Some(node),
                element,
                format!(
                    "duplicate joint name (first defined on line {})",
                    ctx.line(self.joints[first].node)
                ),
            ));
        }
        if parent == child_link {
            return Err(ctx.err(Some(node), element, "parent and child are the same link"));
        }
        if let Some(other) = self.parent_joint[child_link] {
            return Err(ctx.err(
                Some(node),
                element,
                format!(
                    "link '{}' is already the child of joint '{}': a URDF must be a tree",
                    self.links[child_link].name, self.joints[other].name
                ),
            ));
        }
        let index = self.joints.len();
        self.parent_joint[child_link] = Some(index);
        self.children[parent].push(index);
        self.joint_index.insert(name, index);
        self.joints.push(TreeJoint {
            name,
            node,
            kind: JointType::from_name(type_name),
            type_name,
            parent,
            child: child_link,
            mimic: child(node, "mimic"),
        });
        Ok(())
    }

    /// The single root; links not reachable from a root sit on a loop.
    fn find_root(&self, ctx: &Ctx, robot: Node) -> Result<usize, UrdfError> {
        let roots: Vec<usize> = (0..self.links.len())
            .filter(|&l| self.parent_joint[l].is_none())
            .collect();
        let mut reached = vec![false; self.links.len()];
        let mut stack = roots.clone();
        while let Some(link) = stack.pop() {
            reached[link] = true;
            stack.extend(self.children[link].iter().map(|&j| self.joints[j].child));
        }
        if let Some(on_loop) = reached.iter().position(|r| !r) {
            // Every link off the roots' trees has a parent: walking up ends on the loop.
            let mut link = on_loop;
            let mut seen = vec![false; self.links.len()];
            while !seen[link] {
                seen[link] = true;
                link = self.joints[self.parent_joint[link].unwrap_or(0)].parent;
            }
            let joint = &self.joints[self.parent_joint[link].unwrap_or(0)];
            return Err(ctx.err(
                Some(joint.node),
                format!("joint '{}'", joint.name),
                "the joints form a loop: a URDF must be a tree",
            ));
        }
        if roots.len() > 1 {
            let names: Vec<&str> = roots.iter().map(|&l| self.links[l].name).collect();
            return Err(ctx.err(
                Some(robot),
                "<robot>",
                format!(
                    "several root links ({}): the links must form one tree",
                    list(&names)
                ),
            ));
        }
        Ok(roots[0])
    }

    /// The joints from `base` down to `tip` (empty when they are the same link), or `None`
    /// when `tip` is not below `base`.
    pub(super) fn path(&self, base: usize, tip: usize) -> Option<Vec<usize>> {
        let mut path = Vec::new();
        let mut link = tip;
        while link != base {
            let j = self.parent_joint[link]?;
            path.push(j);
            link = self.joints[j].parent;
        }
        path.reverse();
        Some(path)
    }

    /// Every link of the subtree below (and including) `link`, depth first.
    pub(super) fn subtree_links(&self, link: usize) -> Vec<usize> {
        let mut out = Vec::new();
        let mut stack = vec![link];
        while let Some(l) = stack.pop() {
            out.push(l);
            stack.extend(self.children[l].iter().rev().map(|&j| self.joints[j].child));
        }
        out
    }
}

/// `a, b, c` for at most ten names, then `and N more`.
pub(super) fn list(names: &[&str]) -> String {
    const SHOWN: usize = 10;
    let mut out = names
        .iter()
        .take(SHOWN)
        .copied()
        .collect::<Vec<_>>()
        .join(", ");
    if names.len() > SHOWN {
        out.push_str(&format!(" and {} more", names.len() - SHOWN));
    }
    out
}
