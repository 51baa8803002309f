//! URDF loading: a serial chain between a base link and a tip link.
//!
//! roxmltree is used for the XML (rather than a serde mapping) because every error must
//! name the file, the line and the element: roxmltree keeps node positions.
//!
//! What is built:
//! * the path from `base` to `tip`; its revolute, continuous and prismatic joints become
//!   the model's joints, in order; fixed joints on the path are folded into the placement
//!   of the next moving joint, and their child links become frames of the body before them;
//! * links hanging off the chain through fixed joints only (sensors, flanges) fold their
//!   inertia into the body that carries them and stay addressable as frames;
//! * links hanging off through moving joints that are not on the path are excluded and
//!   listed in [`Model::excluded_links`];
//! * links before the first moving joint belong to the base (their mass never moves).

use std::collections::HashMap;
use std::path::Path;

use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use roxmltree::{Document, Node};

use crate::error::{DynamicsError, UrdfError};
use crate::model::{Frame, Joint, JointKind, JointLimits, LinkMass, Model};
use crate::spatial::{rpy_to_matrix, Inertia, Transform};

/// Relative tolerance on the triangle inequality of principal moments (URDF numbers are
/// often printed with few digits).
const TRIANGLE_TOLERANCE: f64 = 1e-9;

struct LinkInfo {
    name: String,
    line: u32,
    /// Inertia in the link frame, and mass.
    inertia: Option<(Inertia, f64)>,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum RawKind {
    Fixed,
    Moving(JointKind),
}

struct JointInfo {
    name: String,
    line: u32,
    kind: RawKind,
    parent: usize,
    child: usize,
    origin: Transform,
    axis: Vector3<f64>,
    limits: JointLimits,
    damping: f64,
    friction: f64,
}

struct Ctx<'a> {
    file: &'a str,
    doc: &'a Document<'a>,
}

impl Ctx<'_> {
    fn line(&self, node: Node) -> u32 {
        self.doc.text_pos_at(node.range().start).row
    }

    fn err(
        &self,
        node: Option<Node>,
        element: impl Into<String>,
        problem: impl Into<String>,
    ) -> UrdfError {
        UrdfError {
            file: self.file.to_string(),
            line: node.map(|n| self.line(n)),
            element: element.into(),
            problem: problem.into(),
        }
    }

    fn number(&self, node: Node, element: &str, attr: &str) -> Result<Option<f64>, UrdfError> {
        let Some(text) = node.attribute(attr) else {
            return Ok(None);
        };
        parse_finite(text.trim())
            .map(Some)
            .map_err(|p| self.err(Some(node), format!("{element} attribute '{attr}'"), p))
    }

    fn required_number(&self, node: Node, element: &str, attr: &str) -> Result<f64, UrdfError> {
        self.number(node, element, attr)?
            .ok_or_else(|| self.err(Some(node), element, format!("missing attribute '{attr}'")))
    }

    fn vector3(
        &self,
        node: Node,
        element: &str,
        attr: &str,
    ) -> Result<Option<Vector3<f64>>, UrdfError> {
        let Some(text) = node.attribute(attr) else {
            return Ok(None);
        };
        let parts: Vec<&str> = text.split_whitespace().collect();
        if parts.len() != 3 {
            return Err(self.err(
                Some(node),
                format!("{element} attribute '{attr}'"),
                format!("expected 3 numbers, found {:?}", text),
            ));
        }
        let mut v = Vector3::zeros();
        for (i, p) in parts.iter().enumerate() {
            v[i] = parse_finite(p)
                .map_err(|e| self.err(Some(node), format!("{element} attribute '{attr}'"), e))?;
        }
        Ok(Some(v))
    }

    fn origin(&self, parent: Node, element: &str) -> Result<Transform, UrdfError> {
        let Some(origin) = child(parent, "origin") else {
            return Ok(Transform::identity());
        };
        let el = format!("{element} <origin>");
        let xyz = self
            .vector3(origin, &el, "xyz")?
            .unwrap_or_else(Vector3::zeros);
        let rpy = self
            .vector3(origin, &el, "rpy")?
            .unwrap_or_else(Vector3::zeros);
        Ok(Transform::new(rpy_to_matrix(rpy.x, rpy.y, rpy.z), xyz))
    }
}

fn parse_finite(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(format!("'{text}' is not a finite number")),
        Err(_) => Err(format!("'{text}' is not a number")),
    }
}

fn child<'a, 'i>(node: Node<'a, 'i>, tag: &str) -> Option<Node<'a, 'i>> {
    node.children()
        .find(|c| c.is_element() && c.tag_name().name() == tag)
}

fn parse_link(ctx: &Ctx, node: Node) -> Result<LinkInfo, UrdfError> {
    let name = node
        .attribute("name")
        .ok_or_else(|| ctx.err(Some(node), "<link>", "missing attribute 'name'"))?
        .to_string();
    let element = format!("link '{name}'");
    let inertia = match child(node, "inertial") {
        None => None,
        Some(inertial) => {
            let el = format!("{element} <inertial>");
            let origin = ctx.origin(inertial, &el)?;
            let mass_node = child(inertial, "mass")
                .ok_or_else(|| ctx.err(Some(inertial), &el, "missing <mass>"))?;
            let mass = ctx.required_number(mass_node, &format!("{el} <mass>"), "value")?;
            if mass <= 0.0 {
                return Err(ctx.err(
                    Some(mass_node),
                    format!("{el} <mass>"),
                    format!("mass {mass} is not positive (remove <inertial> for a massless link)"),
                ));
            }
            let inode = child(inertial, "inertia")
                .ok_or_else(|| ctx.err(Some(inertial), &el, "missing <inertia>"))?;
            let iel = format!("{el} <inertia>");
            let mut v = [0.0; 6];
            for (k, attr) in ["ixx", "ixy", "ixz", "iyy", "iyz", "izz"]
                .iter()
                .enumerate()
            {
                v[k] = ctx.required_number(inode, &iel, attr)?;
            }
            let tensor = Matrix3::new(v[0], v[1], v[2], v[1], v[3], v[4], v[2], v[4], v[5]);
            check_inertia_tensor(&tensor).map_err(|p| ctx.err(Some(inode), &iel, p))?;
            // Inertia tensor given in the inertial frame: rotate into the link frame.
            let r = origin.rotation;
            let about_com = r * tensor * r.transpose();
            Some((Inertia::from_com(mass, origin.translation, about_com), mass))
        }
    };
    Ok(LinkInfo {
        name,
        line: ctx.line(node),
        inertia,
    })
}

/// Positive definite with principal moments satisfying the triangle inequality.
fn check_inertia_tensor(tensor: &Matrix3<f64>) -> Result<(), String> {
    let eig = SymmetricEigen::new(*tensor);
    let mut p = [eig.eigenvalues[0], eig.eigenvalues[1], eig.eigenvalues[2]];
    p.sort_by(|a, b| a.total_cmp(b));
    if p[0] <= 0.0 {
        return Err(format!(
            "inertia tensor is not positive definite (principal moments {:.3e}, {:.3e}, {:.3e})",
            p[0], p[1], p[2]
        ));
    }
    if p[0] + p[1] < p[2] * (1.0 - TRIANGLE_TOLERANCE) {
        return Err(format!(
            "principal moments {:.6e}, {:.6e}, {:.6e} break the triangle inequality \
             (no rigid body has them)",
            p[0], p[1], p[2]
        ));
    }
    Ok(())
}

fn parse_joint(
    ctx: &Ctx,
    node: Node,
    links: &HashMap<String, usize>,
) -> Result<JointInfo, UrdfError> {
    let name = node
        .attribute("name")
        .ok_or_else(|| ctx.err(Some(node), "<joint>", "missing attribute 'name'"))?
        .to_string();
    let element = format!("joint '{name}'");
    let type_name = node
        .attribute("type")
        .ok_or_else(|| ctx.err(Some(node), &element, "missing attribute 'type'"))?;
    let kind = match type_name {
        "fixed" => RawKind::Fixed,
        "revolute" => RawKind::Moving(JointKind::Revolute),
        "continuous" => RawKind::Moving(JointKind::Continuous),
        "prismatic" => RawKind::Moving(JointKind::Prismatic),
        "floating" | "planar" => {
            return Err(ctx.err(
                Some(node),
                &element,
                format!("joint type '{type_name}' is not supported: only revolute, continuous, prismatic and fixed joints make a serial arm"),
            ))
        }
        other => {
            return Err(ctx.err(
                Some(node),
                &element,
                format!("unknown joint type '{other}' (expected revolute, continuous, prismatic or fixed)"),
            ))
        }
    };
    if let Some(m) = child(node, "mimic") {
        return Err(ctx.err(
            Some(m),
            format!("{element} <mimic>"),
            "mimic joints are not supported",
        ));
    }
    let link_ref = |tag: &str| -> Result<usize, UrdfError> {
        let n = child(node, tag)
            .ok_or_else(|| ctx.err(Some(node), &element, format!("missing <{tag}>")))?;
        let link = n.attribute("link").ok_or_else(|| {
            ctx.err(
                Some(n),
                format!("{element} <{tag}>"),
                "missing attribute 'link'",
            )
        })?;
        links.get(link).copied().ok_or_else(|| {
            ctx.err(
                Some(n),
                format!("{element} <{tag}>"),
                format!("link '{link}' is not defined"),
            )
        })
    };
    let parent = link_ref("parent")?;
    let child_link = link_ref("child")?;
    let origin = ctx.origin(node, &element)?;
    let mut axis = Vector3::x();
    if let Some(a) = child(node, "axis") {
        if let Some(v) = ctx.vector3(a, &format!("{element} <axis>"), "xyz")? {
            let n = v.norm();
            if kind != RawKind::Fixed && n < 1e-12 {
                return Err(ctx.err(Some(a), format!("{element} <axis>"), "axis has zero length"));
            }
            if n > 0.0 {
                axis = v / n;
            }
        }
    }
    let mut limits = JointLimits::default();
    let limit_node = child(node, "limit");
    if let Some(l) = limit_node {
        let el = format!("{element} <limit>");
        if let Some(v) = ctx.number(l, &el, "effort")? {
            limits.effort = v;
        }
        if let Some(v) = ctx.number(l, &el, "velocity")? {
            limits.velocity = v;
        }
        if matches!(
            kind,
            RawKind::Moving(JointKind::Revolute | JointKind::Prismatic)
        ) {
            limits.lower = ctx.number(l, &el, "lower")?.unwrap_or(0.0);
            limits.upper = ctx.number(l, &el, "upper")?.unwrap_or(0.0);
            if limits.lower > limits.upper {
                return Err(ctx.err(
                    Some(l),
                    el,
                    format!(
                        "lower limit {} is above upper limit {}",
                        limits.lower, limits.upper
                    ),
                ));
            }
        }
        if limits.effort < 0.0 || limits.velocity < 0.0 {
            return Err(ctx.err(
                Some(l),
                el,
                "effort and velocity limits must not be negative",
            ));
        }
    } else if matches!(
        kind,
        RawKind::Moving(JointKind::Revolute | JointKind::Prismatic)
    ) {
        return Err(ctx.err(
            Some(node),
            &element,
            format!("a {type_name} joint needs <limit lower=.. upper=.. effort=.. velocity=..>"),
        ));
    }
    let (mut damping, mut friction) = (0.0, 0.0);
    if let Some(d) = child(node, "dynamics") {
        let el = format!("{element} <dynamics>");
        damping = ctx.number(d, &el, "damping")?.unwrap_or(0.0);
        friction = ctx.number(d, &el, "friction")?.unwrap_or(0.0);
        if damping < 0.0 || friction < 0.0 {
            return Err(ctx.err(Some(d), el, "damping and friction must not be negative"));
        }
    }
    Ok(JointInfo {
        name,
        line: ctx.line(node),
        kind,
        parent,
        child: child_link,
        origin,
        axis,
        limits,
        damping,
        friction,
    })
}

/// Loads the chain from a URDF file. `base` defaults to the root link, `tip` to the
/// single leaf link (an error when there are several).
pub fn load_file(
    path: &Path,
    base: Option<&str>,
    tip: Option<&str>,
) -> Result<Model, DynamicsError> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|source| DynamicsError::Io {
        file: file.clone(),
        source,
    })?;
    load_str(&text, &file, base, tip)
}

/// Loads the chain from URDF text; `source` names it in errors.
pub fn load_str(
    text: &str,
    source: &str,
    base: Option<&str>,
    tip: Option<&str>,
) -> Result<Model, DynamicsError> {
    let doc = Document::parse(text).map_err(|e| UrdfError {
        file: source.to_string(),
        line: Some(e.pos().row),
        element: "XML".into(),
        problem: format!("not well-formed XML: {e}"),
    })?;
    let ctx = Ctx {
        file: source,
        doc: &doc,
    };
    build(&ctx, base, tip).map_err(DynamicsError::from)
}

fn build(ctx: &Ctx, base: Option<&str>, tip: Option<&str>) -> Result<Model, UrdfError> {
    let root = ctx.doc.root_element();
    if root.tag_name().name() != "robot" {
        return Err(ctx.err(
            Some(root),
            format!("<{}>", root.tag_name().name()),
            "the root element must be <robot>",
        ));
    }
    let robot_name = root.attribute("name").unwrap_or("").to_string();

    let mut links: Vec<LinkInfo> = Vec::new();
    let mut link_index: HashMap<String, usize> = HashMap::new();
    for node in root
        .children()
        .filter(|n| n.is_element() && n.tag_name().name() == "link")
    {
        let info = parse_link(ctx, node)?;
        if let Some(&prev) = link_index.get(&info.name) {
            return Err(ctx.err(
                Some(node),
                format!("link '{}'", info.name),
                format!(
                    "duplicate link name (first defined on line {})",
                    links[prev].line
                ),
            ));
        }
        link_index.insert(info.name.clone(), links.len());
        links.push(info);
    }
    if links.is_empty() {
        return Err(ctx.err(Some(root), "<robot>", "no <link> elements"));
    }

    let mut joints: Vec<JointInfo> = Vec::new();
    let mut joint_names: HashMap<String, usize> = HashMap::new();
    let mut parent_joint: Vec<Option<usize>> = vec![None; links.len()];
    for node in root
        .children()
        .filter(|n| n.is_element() && n.tag_name().name() == "joint")
    {
        let info = parse_joint(ctx, node, &link_index)?;
        let element = format!("joint '{}'", info.name);
        if let Some(&prev) = joint_names.get(&info.name) {
            return Err(ctx.err(
                Some(node),
                element,
                format!(
                    "duplicate joint name (first defined on line {})",
                    joints[prev].line
                ),
            ));
        }
        if info.parent == info.child {
            return Err(ctx.err(Some(node), element, "parent and child are the same link"));
        }
        if let Some(other) = parent_joint[info.child] {
            return Err(ctx.err(
                Some(node),
                element,
                format!(
                    "link '{}' is already the child of joint '{}': a URDF must be a tree",
                    links[info.child].name, joints[other].name
                ),
            ));
        }
        parent_joint[info.child] = Some(joints.len());
        joint_names.insert(info.name.clone(), joints.len());
        joints.push(info);
    }

    // Loops: walking up from any link must reach a root within |links| steps.
    for start in 0..links.len() {
        let mut link = start;
        let mut steps = 0;
        while let Some(j) = parent_joint[link] {
            link = joints[j].parent;
            steps += 1;
            if steps > links.len() {
                return Err(ctx.err(
                    None,
                    format!("joint '{}'", joints[j].name),
                    "the joints form a loop: a URDF must be a tree",
                ));
            }
        }
    }
    let roots: Vec<usize> = (0..links.len())
        .filter(|&l| parent_joint[l].is_none())
        .collect();
    if roots.len() > 1 {
        let names: Vec<&str> = roots.iter().map(|&l| links[l].name.as_str()).collect();
        return Err(ctx.err(
            Some(root),
            "<robot>",
            format!(
                "several root links ({}): the links must form one tree",
                names.join(", ")
            ),
        ));
    }
    let root_link = roots[0];

    let mut children: Vec<Vec<usize>> = vec![Vec::new(); links.len()];
    for (j, info) in joints.iter().enumerate() {
        children[info.parent].push(j);
    }

    let base_link = match base {
        None => root_link,
        Some(name) => *link_index.get(name).ok_or_else(|| {
            ctx.err(
                None,
                format!("base link '{name}'"),
                "no link of that name in the file",
            )
        })?,
    };
    let tip_link = match tip {
        Some(name) => *link_index.get(name).ok_or_else(|| {
            ctx.err(
                None,
                format!("tip link '{name}'"),
                "no link of that name in the file",
            )
        })?,
        None => {
            let mut leaves = Vec::new();
            let mut stack = vec![base_link];
            while let Some(l) = stack.pop() {
                if children[l].is_empty() {
                    leaves.push(l);
                }
                stack.extend(children[l].iter().map(|&j| joints[j].child));
            }
            if leaves.len() != 1 {
                let names: Vec<&str> = leaves.iter().map(|&l| links[l].name.as_str()).collect();
                return Err(ctx.err(
                    None,
                    "tip link",
                    format!(
                        "ambiguous: the tree below '{}' has {} leaf links ({}); name one with --tip",
                        links[base_link].name,
                        leaves.len(),
                        names.join(", ")
                    ),
                ));
            }
            leaves[0]
        }
    };

    // Path of joints from base to tip.
    let mut path = Vec::new();
    let mut link = tip_link;
    while link != base_link {
        let Some(j) = parent_joint[link] else {
            return Err(ctx.err(
                None,
                format!("tip link '{}'", links[tip_link].name),
                format!("not below the base link '{}'", links[base_link].name),
            ));
        };
        path.push(j);
        link = joints[j].parent;
    }
    path.reverse();

    let mut model_joints: Vec<Joint> = Vec::new();
    let mut bodies: Vec<Inertia> = Vec::new();
    let mut frames: Vec<Frame> = Vec::new();
    let mut link_masses: Vec<LinkMass> = Vec::new();
    let mut excluded: Vec<String> = Vec::new();
    let on_path: Vec<bool> = {
        let mut v = vec![false; joints.len()];
        for &j in &path {
            v[j] = true;
        }
        v
    };

    // Attaches `link` (placed at `placement` in the current body or base) and, through
    // fixed joints off the path, everything rigidly attached to it.
    #[allow(clippy::too_many_arguments)]
    fn attach(
        link: usize,
        placement: Transform,
        body: Option<usize>,
        links: &[LinkInfo],
        joints: &[JointInfo],
        children: &[Vec<usize>],
        on_path: &[bool],
        frames: &mut Vec<Frame>,
        bodies: &mut [Inertia],
        link_masses: &mut Vec<LinkMass>,
        excluded: &mut Vec<String>,
    ) {
        frames.push(Frame {
            name: links[link].name.clone(),
            parent_joint: body,
            placement,
        });
        let mass = links[link].inertia.map(|(_, m)| m).unwrap_or(0.0);
        link_masses.push(LinkMass {
            link: links[link].name.clone(),
            mass,
            joint: body,
        });
        if let (Some(b), Some((inertia, _))) = (body, links[link].inertia) {
            bodies[b] = bodies[b].add(&inertia.transformed(&placement));
        }
        for &j in &children[link] {
            if on_path[j] {
                continue;
            }
            match joints[j].kind {
                RawKind::Fixed => attach(
                    joints[j].child,
                    placement.compose(&joints[j].origin),
                    body,
                    links,
                    joints,
                    children,
                    on_path,
                    frames,
                    bodies,
                    link_masses,
                    excluded,
                ),
                RawKind::Moving(_) => {
                    collect_subtree(joints[j].child, links, joints, children, excluded)
                }
            }
        }
    }
    fn collect_subtree(
        link: usize,
        links: &[LinkInfo],
        joints: &[JointInfo],
        children: &[Vec<usize>],
        out: &mut Vec<String>,
    ) {
        out.push(links[link].name.clone());
        for &j in &children[link] {
            collect_subtree(joints[j].child, links, joints, children, out);
        }
    }

    // First pass: create the moving joints so bodies can be indexed.
    let mut pending = Transform::identity();
    let mut moving_lines = Vec::new();
    for &j in &path {
        let info = &joints[j];
        match info.kind {
            RawKind::Fixed => pending = pending.compose(&info.origin),
            RawKind::Moving(kind) => {
                model_joints.push(Joint {
                    name: info.name.clone(),
                    kind,
                    axis: info.axis,
                    placement: pending.compose(&info.origin),
                    limits: info.limits,
                    damping: info.damping,
                    friction: info.friction,
                    child_link: links[info.child].name.clone(),
                });
                moving_lines.push(info.line);
                pending = Transform::identity();
            }
        }
    }
    bodies.resize(model_joints.len(), Inertia::zero());

    // Second pass: frames and inertia.
    let mut body: Option<usize> = None;
    let mut placement = Transform::identity();
    attach(
        base_link,
        placement,
        None,
        &links,
        &joints,
        &children,
        &on_path,
        &mut frames,
        &mut bodies,
        &mut link_masses,
        &mut excluded,
    );
    for &j in &path {
        let info = &joints[j];
        match info.kind {
            RawKind::Fixed => placement = placement.compose(&info.origin),
            RawKind::Moving(_) => {
                body = Some(body.map_or(0, |b| b + 1));
                placement = Transform::identity();
            }
        }
        attach(
            info.child,
            placement,
            body,
            &links,
            &joints,
            &children,
            &on_path,
            &mut frames,
            &mut bodies,
            &mut link_masses,
            &mut excluded,
        );
    }

    if model_joints.is_empty() {
        return Err(ctx.err(
            None,
            format!(
                "chain '{}' -> '{}'",
                links[base_link].name, links[tip_link].name
            ),
            "has no moving joint",
        ));
    }
    // The last body must resist motion about (along) its own axis, or the forward
    // dynamics are singular whatever the state.
    let last = model_joints.len() - 1;
    let lj = &model_joints[last];
    let lb = &bodies[last];
    let resisting = match lj.kind {
        JointKind::Prismatic => lb.mass,
        _ => lj.axis.dot(&(lb.rotational * lj.axis)),
    };
    // Also rejects NaN.
    if resisting.is_nan() || resisting <= 0.0 {
        return Err(UrdfError {
            file: ctx.file.to_string(),
            line: moving_lines.last().copied(),
            element: format!("joint '{}'", lj.name),
            problem: "moves no mass or inertia: the links after it need an <inertial>".into(),
        });
    }

    let tip_name = &links[tip_link].name;
    let tip_frame = frames
        .iter()
        .position(|f| &f.name == tip_name)
        .unwrap_or(frames.len() - 1);
    Ok(Model {
        robot_name,
        source: ctx.file.to_string(),
        base_link: links[base_link].name.clone(),
        joints: model_joints,
        bodies,
        frames,
        tip_frame,
        gravity: Vector3::new(0.0, 0.0, -9.81),
        link_masses,
        excluded_links: excluded,
    })
}
