"""The MuJoCo plant: a URDF's chain as a torque-controlled MuJoCo model with joint friction,
damping and armature unknown to the controller, an encoder, and the true external torque."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np

# Joint friction (frictionloss, N m), viscous damping (N m s/rad) and rotor armature
# (kg m^2) of the Franka Research 3's MuJoCo model (MuJoCo Menagerie, franka_fr3/fr3.xml):
# joints 1-4 (87 N m): 1.137, 0.21, 0.195; joints 5-7 (12 N m): frictionloss 0.763, 0.44,
# 0.248 (mean 0.484), damping 0.21, armature 0.074. Scaled to another arm by each joint's
# effort limit against the FR3 joint class it is closest to (doc of `unknown_joint_terms`).
FR3_LARGE = {"effort": 87.0, "frictionloss": 1.137, "damping": 0.21, "armature": 0.195}
FR3_SMALL = {"effort": 12.0, "frictionloss": 0.484, "damping": 0.21, "armature": 0.074}


def unknown_joint_terms(effort_limits, scale=1.0):
    """Friction, damping and armature per joint: the FR3 values of the joint class (87 or
    12 N m) nearest in effort (geometric distance), times effort / class effort, times
    ``scale``. On the Panda (87 and 12 N m) these are the FR3's own values (the wrist's
    frictionloss as the mean of its three joints)."""
    out = []
    for e in effort_limits:
        e = float(e) if np.isfinite(e) and e > 0 else FR3_LARGE["effort"]
        cls = FR3_LARGE if abs(math.log(e / 87.0)) <= abs(math.log(e / 12.0)) else FR3_SMALL
        r = scale * e / cls["effort"]
        out.append({k: cls[k] * r for k in ("frictionloss", "damping", "armature")})
    return out


def chain_urdf(text: str, chain_joints, tip_link: str, wall=None) -> str:
    """The URDF for MuJoCo: geometry stripped, the links that neither lead to the chain's base
    nor hang from it left out (a mobile base's sensors and wheels: fixed to the world, they
    move nothing, and MuJoCo refuses some of their inertias), every moving joint off the chain
    made fixed (held at 0, as the Rust loader locks branches), a MuJoCo compiler block, and a
    small sphere at the tip for contact (with ``wall``)."""
    root = ET.fromstring(text)
    _keep_around_chain(root, set(chain_joints))
    _rename_inner_world(root)
    for link in root.findall("link"):
        for tag in ("visual", "collision"):
            for el in link.findall(tag):
                link.remove(el)
    chain = set(chain_joints)
    for joint in root.findall("joint"):
        if joint.get("type") not in ("fixed",) and joint.get("name") not in chain:
            joint.set("type", "fixed")
            for tag in ("axis", "limit", "mimic", "dynamics", "calibration", "safety_controller"):
                for el in joint.findall(tag):
                    joint.remove(el)
        else:
            for el in joint.findall("dynamics"):
                joint.remove(el)  # the plant's joint terms are set on the model below
    for el in root.findall("mujoco"):
        root.remove(el)
    mj = ET.SubElement(root, "mujoco")
    ET.SubElement(
        mj,
        "compiler",
        {
            "discardvisual": "true",
            "fusestatic": "false",
            "balanceinertia": "true",
            "boundmass": "1e-6",
            "boundinertia": "1e-9",
        },
    )
    if wall is not None:
        for link in root.findall("link"):
            if link.get("name") == tip_link:
                col = ET.SubElement(link, "collision")
                ET.SubElement(col, "origin", {"xyz": "0 0 0", "rpy": "0 0 0"})
                geo = ET.SubElement(col, "geometry")
                ET.SubElement(geo, "sphere", {"radius": "0.02"})
    return ET.tostring(root, encoding="unicode")


def _rename_inner_world(root):
    """MuJoCo takes a link named ``world`` as its own world body wherever it sits in the tree:
    below a turned mount (an arm's file wrapped in a workcell's) that would drop the mount and
    simulate the arm upright. Such a link that is not the root is renamed ``world_link``
    (joints refer to it by name only, and the caller has already used the base's and tip's
    names)."""
    children = {j.find("child").get("link") for j in root.findall("joint")}
    if "world" not in children:
        return
    new = "world_link"
    while any(link.get("name") == new for link in root.findall("link")):
        new += "_"
    for link in root.findall("link"):
        if link.get("name") == "world":
            link.set("name", new)
    for joint in root.findall("joint"):
        for tag in ("parent", "child"):
            el = joint.find(tag)
            if el is not None and el.get("link") == "world":
                el.set("link", new)


def _keep_around_chain(root, chain):
    """Removes from the URDF tree ``root`` every link (and the joint to it) that is neither on
    the path from the root to the chain's base nor below the base."""
    joints = root.findall("joint")
    parent = {j.find("child").get("link"): j.find("parent").get("link") for j in joints}
    children = {}
    for child, up in parent.items():
        children.setdefault(up, []).append(child)
    chain_children = {j.find("child").get("link") for j in joints if j.get("name") in chain}
    bases = [j.find("parent").get("link") for j in joints if j.get("name") in chain]
    bases = [b for b in bases if b not in chain_children]
    if len(bases) != 1:
        return  # not one chain: leave the tree as it is
    keep, link = set(), bases[0]
    while link is not None:
        keep.add(link)
        link = parent.get(link)
    below = [bases[0]]
    while below:
        link = below.pop()
        keep.add(link)
        below += children.get(link, [])
    for link in root.findall("link"):
        if link.get("name") not in keep:
            root.remove(link)
    for joint in joints:
        if joint.find("child").get("link") not in keep:
            root.remove(joint)


@dataclass
class Encoder:
    """Quantised, noisy angles: ``counts`` per revolution and Gaussian noise ``noise_std``."""

    counts: float = 65536.0
    noise_std: float = 5e-5

    @property
    def resolution(self):
        """One count (rad)."""
        return 2.0 * math.pi / self.counts

    def read(self, q, rng):
        resolution = self.resolution
        noisy = q + self.noise_std * rng.standard_normal(q.shape)
        return np.round(noisy / resolution) * resolution

    def noise(self, rng, steps, n):
        """The noise of ``steps`` reads of ``n`` angles, drawn as ``read`` draws them one
        read after the other (``adm.CosimStepper`` adds it and rounds)."""
        return self.noise_std * rng.standard_normal((steps, n))


class MujocoArm:
    """The chain of a URDF as a MuJoCo model, stepped at ``dt`` with joint torques."""

    def __init__(self, urdf_text, chain_joints, tip_link, efforts, dt, friction_scale, wall=None):
        import mujoco

        self.mj = mujoco
        xml = chain_urdf(urdf_text, chain_joints, tip_link, wall)
        spec = mujoco.MjSpec.from_string(xml)
        if wall is not None:
            centre, half, normal = wall
            spec.worldbody.add_geom(
                type=mujoco.mjtGeom.mjGEOM_BOX,
                pos=centre,
                size=half,
                quat=_quat_z_to(normal),
                solref=[0.005, 1.0],
            )
        self.model = spec.compile()
        self.model.opt.timestep = dt
        self.model.opt.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
        self.data = mujoco.MjData(self.model)
        self.joint_ids = [self.model.joint(name).id for name in chain_joints]
        self.qpos = np.array([self.model.jnt_qposadr[j] for j in self.joint_ids])
        self.dofs = np.array([self.model.jnt_dofadr[j] for j in self.joint_ids])
        self.terms = unknown_joint_terms(efforts, friction_scale)
        for d, t in zip(self.dofs, self.terms):
            self.model.dof_frictionloss[d] = t["frictionloss"]
            self.model.dof_damping[d] = t["damping"]
            self.model.dof_armature[d] = t["armature"]
        self.tip_body = self.model.body(tip_link).id
        self.gravity = np.array(self.model.opt.gravity)
        self.jacp = np.zeros((3, self.model.nv))
        self.jacr = np.zeros((3, self.model.nv))

    def stepper_plant(self):
        """The model, data, arrays and indices ``adm.CosimStepper`` steps this arm with
        (what ``step`` and ``external_torque`` use); ``contact_torque``: this arm's
        ``external_torque``, which the stepper calls on steps with contacts, or ``None``
        when nothing can touch the arm (no geometry: no wall)."""
        m, d = self.model, self.data
        return {
            "mj_step": self.mj.mj_step, "mj_jac": self.mj.mj_jac, "model": m, "data": d,
            "nq": m.nq, "nv": m.nv, "nbody": m.nbody,
            "qpos": d.qpos, "qvel": d.qvel, "qfrc_applied": d.qfrc_applied,
            "xfrc_applied": d.xfrc_applied, "xpos": d.xpos, "xipos": d.xipos,
            "tip_xpos": d.xpos[self.tip_body], "jacp": self.jacp, "jacr": self.jacr,
            "qpos_index": [int(i) for i in self.qpos], "dof_index": [int(i) for i in self.dofs],
            "tip_body": int(self.tip_body),
            "contact_torque": self.external_torque if m.ngeom > 0 else None,
        }

    def set_q(self, q):
        self.data.qpos[self.qpos] = q
        self.data.qvel[:] = 0.0
        self.mj.mj_forward(self.model, self.data)

    def q(self):
        return self.data.qpos[self.qpos].copy()

    def qdot(self):
        return self.data.qvel[self.dofs].copy()

    def tip_position(self):
        return self.data.xpos[self.tip_body].copy()

    def step(self, tau, push=None):
        """One step with joint torques ``tau`` and, optionally, a force ``push`` (N, world
        axes) at the tip; returns the true external joint torque of that step."""
        self.data.qfrc_applied[:] = 0.0
        self.data.qfrc_applied[self.dofs] = tau
        self.data.xfrc_applied[:] = 0.0
        if push is not None:
            # A force at the tip frame's origin: xfrc_applied acts at the body's centre of
            # mass, so the moment of the offset is added.
            offset = self.data.xpos[self.tip_body] - self.data.xipos[self.tip_body]
            self.data.xfrc_applied[self.tip_body, :3] = push
            self.data.xfrc_applied[self.tip_body, 3:] = np.cross(offset, push)
        self.mj.mj_step(self.model, self.data)
        return self.external_torque(push)

    def external_torque(self, push):
        """``J^T f`` of the push at the tip, plus every contact force through the Jacobian at
        its contact point (not qfrc_constraint: frictionloss and limits are constraints too)."""
        mj, m, d = self.mj, self.model, self.data
        tau = np.zeros(m.nv)
        if push is not None:
            mj.mj_jac(m, d, self.jacp, self.jacr, d.xpos[self.tip_body], self.tip_body)
            # Row by row, not `jacp.T @ push`: BLAS may fuse the multiply-adds on one CPU and
            # not on another, and the Rust stepper (crates/python/src/cosim.rs) must give the
            # same bits everywhere.
            jacp = self.jacp
            tau += jacp[0] * push[0] + jacp[1] * push[1] + jacp[2] * push[2]
        wrench = np.zeros(6)
        for i in range(d.ncon):
            c = d.contact[i]
            mj.mj_contactForce(m, d, i, wrench)
            # The force on geom2 from geom1, in the contact frame; world axes:
            frame = c.frame.reshape(3, 3)
            f_world = frame.T @ wrench[:3]
            for geom, sign in ((c.geom1, -1.0), (c.geom2, 1.0)):
                body = m.geom_bodyid[geom]
                if body == 0:
                    continue
                mj.mj_jac(m, d, self.jacp, self.jacr, c.pos, body)
                tau += sign * (self.jacp.T @ f_world)
        return tau[self.dofs]

    def contact_force(self):
        """The total contact force on the arm (N, world axes)."""
        wrench = np.zeros(6)
        total = np.zeros(3)
        for i in range(self.data.ncon):
            c = self.data.contact[i]
            self.mj.mj_contactForce(self.model, self.data, i, wrench)
            f_world = c.frame.reshape(3, 3).T @ wrench[:3]
            if self.model.geom_bodyid[c.geom2] != 0:
                total += f_world
            if self.model.geom_bodyid[c.geom1] != 0:
                total -= f_world
        return total


def _quat_z_to(normal):
    """The quaternion turning +z onto ``normal``."""
    n = np.asarray(normal, float)
    n = n / np.linalg.norm(n)
    z = np.array([0.0, 0.0, 1.0])
    axis = np.cross(z, n)
    s = np.linalg.norm(axis)
    if s < 1e-12:
        return [1.0, 0.0, 0.0, 0.0] if n[2] > 0 else [0.0, 1.0, 0.0, 0.0]
    angle = math.atan2(s, float(z @ n))
    axis = axis / s
    return [math.cos(angle / 2), *(axis * math.sin(angle / 2))]
