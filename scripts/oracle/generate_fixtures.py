#!/usr/bin/env python3
"""Generate the Pinocchio oracle fixtures of admittance-dynamics.

Writes, deterministically (fixed seed):
  crates/dynamics/tests/fixtures/arms/arm_NN.urdf      random serial arms
  crates/dynamics/tests/fixtures/pinocchio/<name>.json Pinocchio's answers on random states
for every random arm and for models/baxter_left_arm.urdf.

Run through scripts/oracle/generate_fixtures.sh (it makes the virtual environment with
`pin` and `numpy`). See crates/dynamics/tests/fixtures/README.md for the schema.

Besides Pinocchio's own consistency (M symmetric positive definite, RNEA(ABA(tau)) == tau,
C v + g == nle, RNEA with fext == tau - J^T w) the script checks Pinocchio against an
independent numpy reading of each URDF: world placement of every link, and the spatial
inertia of every moving body after folding the links behind fixed joints into it. A failed
check aborts before anything is written.
"""
import json
import math
import os
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
FIXTURES = os.path.join(ROOT, "crates", "dynamics", "tests", "fixtures")
ARMS_DIR = os.path.join(FIXTURES, "arms")
OUT_DIR = os.path.join(FIXTURES, "pinocchio")
BAXTER = os.path.join(ROOT, "models", "baxter_left_arm.urdf")

SEED = 20240611
N_ARMS = 32
CASES_PER_ARM = 6
CASES_BAXTER = 12
GRAVITY = np.array([0.0, 0.0, -9.81])


# ---------------------------------------------------------------------------------------------
# small rotation helpers (URDF convention: R = Rz(yaw) Ry(pitch) Rx(roll))
# ---------------------------------------------------------------------------------------------
def rot_x(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def rot_y(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rot_z(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def rpy_matrix(rpy):
    return rot_z(rpy[2]) @ rot_y(rpy[1]) @ rot_x(rpy[0])


def axis_angle(axis, angle):
    k = np.asarray(axis, dtype=float)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * kx + (1 - math.cos(angle)) * kx @ kx


def skew(p):
    return np.array([[0, -p[2], p[1]], [p[2], 0, -p[0]], [-p[1], p[0], 0]])


def fmt(x):
    """Number as written into the URDF: 9 significant digits, no '-0'."""
    s = "%.9g" % x
    return "0" if float(s) == 0.0 else s


def fmtv(v):
    return " ".join(fmt(x) for x in v)


# ---------------------------------------------------------------------------------------------
# random arm generation
# ---------------------------------------------------------------------------------------------
def random_rotation(rng):
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def random_inertial(rng, omit_origin=False, omit_rpy=False):
    """A physically valid inertial: principal moments of a random solid box (so they
    satisfy the triangle inequality), rotated by a random R, in an inertial frame with
    nonzero xyz and rpy. Values are rounded as written and re-checked after rounding."""
    while True:
        mass = float(fmt(rng.uniform(0.1, 10.0)))
        d = rng.uniform(0.02, 0.4, size=3)
        principal = mass / 12.0 * np.array([d[1] ** 2 + d[2] ** 2, d[0] ** 2 + d[2] ** 2,
                                            d[0] ** 2 + d[1] ** 2])
        R = random_rotation(rng)
        I = R @ np.diag(principal) @ R.T
        vals = [I[0, 0], I[0, 1], I[0, 2], I[1, 1], I[1, 2], I[2, 2]]
        vals = [float(fmt(x)) for x in vals]
        Ir = np.array([[vals[0], vals[1], vals[2]], [vals[1], vals[3], vals[4]],
                       [vals[2], vals[4], vals[5]]])
        ev = np.sort(np.linalg.eigvalsh(Ir))
        if ev[0] > 0 and ev[0] + ev[1] > ev[2] * (1 + 1e-6):
            break
    xyz = [0.0, 0.0, 0.0] if omit_origin else [float(fmt(x)) for x in rng.uniform(-0.12, 0.12, 3)]
    rpy = [0.0, 0.0, 0.0] if (omit_origin or omit_rpy) else \
        [float(fmt(x)) for x in rng.uniform(-math.pi, math.pi, 3)]
    return {"mass": mass, "xyz": xyz, "rpy": rpy, "I": vals,
            "omit_origin": omit_origin, "omit_rpy": omit_rpy}


def random_axis(rng, exact_ok=True):
    u = rng.uniform()
    if exact_ok and u < 0.4:
        e = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]][rng.integers(3)]
        return e
    if exact_ok and u < 0.45:  # a negative coordinate axis now and then
        return [[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]][rng.integers(3)]
    a = rng.normal(size=3)
    a /= np.linalg.norm(a)
    return [float(x) for x in a]  # full precision: a unit vector to the last bit


def random_origin(rng):
    xyz = [float(fmt(x)) for x in rng.uniform(-0.35, 0.35, 3)]
    rpy = [float(fmt(x)) for x in rng.uniform(-math.pi, math.pi, 3)]
    return xyz, rpy


def make_arm(rng, index):
    """Return (links, joints, tip) with links/joints in chain order."""
    n_moving = 2 + index % 8  # 2..9, every count four times over 32 arms
    links, joints = [], []
    base = "base_link"
    links.append({"name": base,
                  "inertial": random_inertial(rng) if rng.uniform() < 0.3 else None})
    parent = base
    # sometimes a massive fixed "pedestal" before the first moving joint: folds into the
    # universe/root and must not influence any dynamics
    if rng.uniform() < 0.35:
        links.append({"name": "pedestal", "inertial": random_inertial(rng)})
        xyz, rpy = random_origin(rng)
        joints.append({"name": "base_to_pedestal", "type": "fixed", "parent": parent,
                       "child": "pedestal", "xyz": xyz, "rpy": rpy})
        parent = "pedestal"
    # the moving-joint types: make sure small arms still vary
    for i in range(1, n_moving + 1):
        u = rng.uniform()
        jtype = "revolute" if u < 0.5 else ("continuous" if u < 0.7 else "prismatic")
        child = "link_%d" % i
        links.append({"name": child, "inertial": random_inertial(
            rng, omit_origin=rng.uniform() < 0.08, omit_rpy=rng.uniform() < 0.1)})
        xyz, rpy = random_origin(rng)
        if rng.uniform() < 0.1:
            rpy = [0.0, 0.0, 0.0]
        j = {"name": "j%d" % i, "type": jtype, "parent": parent, "child": child,
             "xyz": xyz, "rpy": rpy, "axis": random_axis(rng)}
        if jtype == "revolute":
            lo = float(fmt(rng.uniform(-3.0, -0.3)))
            hi = float(fmt(rng.uniform(0.3, 3.0)))
            j["limit"] = {"lower": lo, "upper": hi,
                          "effort": float(fmt(rng.uniform(5, 200))),
                          "velocity": float(fmt(rng.uniform(0.5, 6)))}
        elif jtype == "prismatic":
            lo = float(fmt(rng.uniform(-0.4, 0.0)))
            hi = float(fmt(rng.uniform(0.05, 0.5)))
            j["limit"] = {"lower": lo, "upper": hi,
                          "effort": float(fmt(rng.uniform(20, 500))),
                          "velocity": float(fmt(rng.uniform(0.1, 2)))}
        elif rng.uniform() < 0.5:  # continuous: effort/velocity only, sometimes
            j["limit"] = {"effort": float(fmt(rng.uniform(5, 200))),
                          "velocity": float(fmt(rng.uniform(0.5, 6)))}
        if rng.uniform() < 0.4:
            j["dynamics"] = {"damping": float(fmt(rng.uniform(0, 2))),
                             "friction": float(fmt(rng.uniform(0, 1)))}
        joints.append(j)
        parent = child
        # fixed joints mid-chain: one or two extra links rigidly attached to this body
        if i < n_moving and rng.uniform() < 0.35:
            for k in range(1 if rng.uniform() < 0.7 else 2):
                ext = "link_%d_%s" % (i, "ab"[k])
                inertial = random_inertial(rng) if rng.uniform() < 0.75 else None
                links.append({"name": ext, "inertial": inertial})
                xyz, rpy = random_origin(rng)
                joints.append({"name": "fixed_%d%s" % (i, "ab"[k]), "type": "fixed",
                               "parent": parent, "child": ext, "xyz": xyz, "rpy": rpy})
                parent = ext
    # tip behind 0, 1 or 2 fixed joints
    u = rng.uniform()
    n_tail = 0 if u < 0.4 else (1 if u < 0.75 else 2)
    for k, name in enumerate(["flange", "tcp"][:n_tail] if n_tail == 2 else ["tool"][:n_tail]):
        inertial = random_inertial(rng) if rng.uniform() < 0.6 else None
        links.append({"name": name, "inertial": inertial})
        xyz, rpy = random_origin(rng)
        # sometimes the joint has the same name as its child link (as Baxter's left_hand)
        jname = name if rng.uniform() < 0.3 else "%s_joint" % name
        joints.append({"name": jname, "type": "fixed", "parent": parent, "child": name,
                       "xyz": xyz, "rpy": rpy})
        parent = name
    return links, joints, parent


def urdf_text(robot, links, joints):
    by_child = {j["child"]: j for j in joints}
    out = ['<?xml version="1.0"?>',
           "<!-- admittance oracle fixture: random serial arm %s, generated by"
           " scripts/oracle/generate_fixtures.py (do not edit by hand) -->" % robot,
           '<robot name="%s">' % robot]
    for link in links:
        ine = link["inertial"]
        if ine is None:
            out.append('  <link name="%s"/>' % link["name"])
        else:
            out.append('  <link name="%s">' % link["name"])
            out.append("    <inertial>")
            if not ine["omit_origin"]:
                if ine["omit_rpy"]:
                    out.append('      <origin xyz="%s"/>' % fmtv(ine["xyz"]))
                else:
                    out.append('      <origin xyz="%s" rpy="%s"/>' % (fmtv(ine["xyz"]), fmtv(ine["rpy"])))
            out.append('      <mass value="%s"/>' % fmt(ine["mass"]))
            I = ine["I"]
            out.append('      <inertia ixx="%s" ixy="%s" ixz="%s" iyy="%s" iyz="%s" izz="%s"/>'
                       % tuple(fmt(x) for x in I))
            out.append("    </inertial>")
            out.append("  </link>")
        j = by_child.get(link["name"])
        if j is None:
            continue
        out.append('  <joint name="%s" type="%s">' % (j["name"], j["type"]))
        out.append('    <parent link="%s"/>' % j["parent"])
        out.append('    <child link="%s"/>' % j["child"])
        out.append('    <origin xyz="%s" rpy="%s"/>' % (fmtv(j["xyz"]), fmtv(j["rpy"])))
        if "axis" in j:
            out.append('    <axis xyz="%s"/>' % " ".join(repr(float(x)) for x in j["axis"]))
        if "limit" in j:
            lim = j["limit"]
            attrs = " ".join('%s="%s"' % (k, fmt(lim[k]))
                             for k in ("effort", "velocity", "lower", "upper") if k in lim)
            out.append("    <limit %s/>" % attrs)
        if "dynamics" in j:
            out.append('    <dynamics damping="%s" friction="%s"/>'
                       % (fmt(j["dynamics"]["damping"]), fmt(j["dynamics"]["friction"])))
        out.append("  </joint>")
    out.append("</robot>")
    return "\n".join(out) + "\n"


# ---------------------------------------------------------------------------------------------
# independent reading of a chain URDF (numpy only), used to check Pinocchio
# ---------------------------------------------------------------------------------------------
def parse_chain(path, base, tip):
    root = ET.parse(path).getroot()

    def vec(el, attr, default):
        if el is None or attr not in el.attrib:
            return np.array(default, dtype=float)
        return np.array([float(t) for t in el.attrib[attr].split()])

    links = {}
    for l in root.findall("link"):
        ine = l.find("inertial")
        if ine is None:
            links[l.attrib["name"]] = None
            continue
        o = ine.find("origin")
        I = ine.find("inertia").attrib
        Imat = np.array([[float(I["ixx"]), float(I["ixy"]), float(I["ixz"])],
                         [float(I["ixy"]), float(I["iyy"]), float(I["iyz"])],
                         [float(I["ixz"]), float(I["iyz"]), float(I["izz"])]])
        R = rpy_matrix(vec(o, "rpy", [0, 0, 0]))
        links[l.attrib["name"]] = {"mass": float(ine.find("mass").attrib["value"]),
                                   "com": vec(o, "xyz", [0, 0, 0]),
                                   "I": R @ Imat @ R.T}  # about the COM, link axes
    joint_into = {}
    for j in root.findall("joint"):
        o = j.find("origin")
        lim = j.find("limit")
        joint_into[j.find("child").attrib["link"]] = {
            "name": j.attrib["name"], "type": j.attrib["type"],
            "parent": j.find("parent").attrib["link"],
            "xyz": vec(o, "xyz", [0, 0, 0]), "rpy": vec(o, "rpy", [0, 0, 0]),
            "axis": vec(j.find("axis"), "xyz", [1, 0, 0]),
            "lower": float(lim.attrib["lower"]) if lim is not None and "lower" in lim.attrib else None,
            "upper": float(lim.attrib["upper"]) if lim is not None and "upper" in lim.attrib else None,
        }
    chain = [tip]
    while chain[-1] != base:
        chain.append(joint_into[chain[-1]]["parent"])
    chain.reverse()
    return links, [(name, joint_into.get(name)) for name in chain]


def numpy_fk(links_chain, qmap):
    """World placement (R, p) of every chain link; qmap: joint name -> position."""
    out = {}
    R, p = np.eye(3), np.zeros(3)
    for name, j in links_chain:
        if j is not None:
            p = p + R @ j["xyz"]
            R = R @ rpy_matrix(j["rpy"])
            if j["type"] in ("revolute", "continuous"):
                R = R @ axis_angle(j["axis"] / np.linalg.norm(j["axis"]), qmap[j["name"]])
            elif j["type"] == "prismatic":
                p = p + R @ (j["axis"] / np.linalg.norm(j["axis"])) * qmap[j["name"]]
        out[name] = (R, p)
    return out


def numpy_body_inertias(links, links_chain):
    """Spatial inertia (mass, com, I_com) of each moving body, expressed in the frame of its
    joint, with all links behind fixed joints folded in. Index 0: the root's (universe)."""
    bodies = []
    R, p = np.eye(3), np.zeros(3)  # placement of current link in current body frame
    cur = {"m": 0.0, "h": np.zeros(3), "Io": np.zeros((3, 3))}  # mass, m*c, inertia about origin
    for name, j in links_chain:
        if j is not None:
            if j["type"] == "fixed":
                p = p + R @ j["xyz"]
                R = R @ rpy_matrix(j["rpy"])
            else:
                bodies.append(cur)
                cur = {"m": 0.0, "h": np.zeros(3), "Io": np.zeros((3, 3))}
                R, p = np.eye(3), np.zeros(3)
        li = links[name]
        if li is not None:
            c = p + R @ li["com"]
            Ic = R @ li["I"] @ R.T
            cur["m"] += li["mass"]
            cur["h"] += li["mass"] * c
            cur["Io"] += Ic - li["mass"] * skew(c) @ skew(c)
    bodies.append(cur)
    return bodies


# ---------------------------------------------------------------------------------------------
# Pinocchio side
# ---------------------------------------------------------------------------------------------
class Arm:
    def __init__(self, urdf_path, base, tip):
        self.path = urdf_path
        self.model = pin.buildModelFromUrdf(urdf_path)
        self.model.gravity = pin.Motion(GRAVITY, np.zeros(3))
        self.data = self.model.createData()
        self.links, self.chain = parse_chain(urdf_path, base, tip)
        self.base, self.tip = base, tip
        self.moving = [j for _, j in self.chain if j is not None and j["type"] != "fixed"]
        m = self.model
        assert m.njoints - 1 == len(self.moving), "fixed joints must not become joints"
        assert list(m.names)[1:] == [j["name"] for j in self.moving], \
            (list(m.names), [j["name"] for j in self.moving])
        for i, j in enumerate(self.moving, start=1):
            assert m.parents[i] == i - 1
            assert m.joints[i].idx_v == i - 1
        assert m.nv == len(self.moving)
        self.tip_id = m.getFrameId(tip, pin.BODY)
        assert m.frames[self.tip_id].type == pin.BODY and m.frames[self.tip_id].name == tip
        self.frame_ids = {}
        for name, _ in self.chain:
            fid = m.getFrameId(name, pin.BODY)
            assert fid < len(m.frames) and m.frames[fid].name == name, name
            self.frame_ids[name] = fid
        self.check_inertias()

    def check_inertias(self):
        """Pinocchio's body inertias == our own fold of fixed-joint links into bodies."""
        bodies = numpy_body_inertias(self.links, self.chain)
        assert len(bodies) == self.model.njoints
        for i in range(1, self.model.njoints):
            b, Y = bodies[i], self.model.inertias[i]
            assert abs(b["m"] - Y.mass) <= 1e-12 * max(1.0, b["m"]), (i, b["m"], Y.mass)
            c = b["h"] / b["m"]
            assert np.allclose(c, Y.lever, atol=1e-12), (i, c, Y.lever)
            Ic = b["Io"] + b["m"] * skew(c) @ skew(c)
            assert np.allclose(Ic, Y.inertia, atol=1e-12, rtol=1e-10), (i, Ic, Y.inertia)

    def q_pin(self, q):
        """Our q (one number per moving joint) -> Pinocchio's q (cos, sin for continuous)."""
        out = np.zeros(self.model.nq)
        for i, j in enumerate(self.moving, start=1):
            jm = self.model.joints[i]
            if jm.nq == 2:
                out[jm.idx_q] = math.cos(q[i - 1])
                out[jm.idx_q + 1] = math.sin(q[i - 1])
            else:
                assert jm.nq == 1
                out[jm.idx_q] = q[i - 1]
        return out

    def random_state(self, rng):
        q = []
        for j in self.moving:
            if j["type"] == "continuous":
                q.append(rng.uniform(-math.pi, math.pi))
            else:
                q.append(rng.uniform(j["lower"], j["upper"]))
        n = len(self.moving)
        return np.array(q), rng.uniform(-2, 2, n), rng.uniform(-5, 5, n)

    def case(self, rng):
        m, d = self.model, self.data
        n = m.nv
        q, v, a = self.random_state(rng)
        qp = self.q_pin(q)
        tau = pin.rnea(m, d, qp, v, a).copy()
        M = pin.crba(m, d, qp).copy()
        M = np.triu(M) + np.triu(M, 1).T
        g = pin.computeGeneralizedGravity(m, d, qp).copy()
        C = pin.computeCoriolisMatrix(m, d, qp, v).copy()
        nle = pin.nonLinearEffects(m, d, qp, v).copy()
        # ABA on a random torque: the inverse dynamics of a second random acceleration plus
        # noise, so that the resulting qddot stays of order 1..10
        aba_tau = pin.rnea(m, d, qp, v, rng.uniform(-5, 5, n)).copy() + rng.uniform(-1, 1, n)
        aba_qddot = pin.aba(m, d, qp, v, aba_tau).copy()

        pin.forwardKinematics(m, d, qp)
        pin.updateFramePlacements(m, d)
        oMtip = d.oMf[self.tip_id]
        tip_p, tip_R = oMtip.translation.copy(), oMtip.rotation.copy()
        frames = {name: {"position": d.oMf[fid].translation.tolist(),
                         "rotation": d.oMf[fid].rotation.tolist()}
                  for name, fid in self.frame_ids.items()}
        J = pin.computeFrameJacobian(m, d, qp, self.tip_id, pin.LOCAL_WORLD_ALIGNED).copy()

        pin.forwardKinematics(m, d, qp, v, np.zeros(n))
        pin.updateFramePlacements(m, d)
        acc = pin.getFrameClassicalAcceleration(m, d, self.tip_id, pin.LOCAL_WORLD_ALIGNED)
        jdot_qdot = np.concatenate([acc.linear, acc.angular])

        w = np.concatenate([rng.uniform(-20, 20, 3), rng.uniform(-5, 5, 3)])
        tau_w = tau - J.T @ w

        # ---- checks ------------------------------------------------------------------------
        scale = 1.0 + np.abs(tau).max()
        assert np.allclose(M, M.T, rtol=0, atol=1e-14)
        assert np.linalg.eigvalsh(M).min() > 0, "M not positive definite"
        assert np.allclose(M @ a + nle, tau, atol=1e-9 * scale), "M a + nle != rnea"
        assert np.allclose(C @ v + g, nle, atol=1e-9 * scale), "C v + g != nle"
        assert np.allclose(pin.rnea(m, d, qp, np.zeros(n), np.zeros(n)), g, atol=1e-10 * scale)
        assert np.allclose(pin.rnea(m, d, qp, v, aba_qddot), aba_tau,
                           atol=1e-9 * (1 + np.abs(aba_tau).max())), "rnea(aba(tau)) != tau"
        # RNEA with the wrench given to Pinocchio as fext in the parent joint's local frame
        pin.forwardKinematics(m, d, qp)
        pin.updateFramePlacements(m, d)
        pj = m.frames[self.tip_id].parentJoint
        f_world = pin.SE3(np.eye(3), tip_p).act(pin.Force(w[:3], w[3:]))  # about world origin
        fext = pin.StdVec_Force()
        for i in range(m.njoints):
            fext.append(pin.Force.Zero())
        fext[pj] = d.oMi[pj].actInv(f_world)
        tau_fext = pin.rnea(m, d, qp, v, a, fext)
        assert np.allclose(tau_fext, tau_w, atol=1e-9 * (1 + np.abs(tau_w).max())), "fext"
        # independent kinematics: every link's placement, then J and Jdot qdot by differences
        qmap = {j["name"]: q[k] for k, j in enumerate(self.moving)}
        fk = numpy_fk(self.chain, qmap)
        for name, (R, p) in fk.items():
            assert np.allclose(R, frames[name]["rotation"], atol=1e-12), name
            assert np.allclose(p, frames[name]["position"], atol=1e-12), name
        h = 1e-6

        def tip_twist(qq):
            qqp = self.q_pin(qq)
            return pin.computeFrameJacobian(m, d, qqp, self.tip_id, pin.LOCAL_WORLD_ALIGNED) @ v

        def tip_pos(qq):
            R, p = numpy_fk(self.chain, {j["name"]: qq[k] for k, j in enumerate(self.moving)})[self.tip]
            return p, R

        p1, R1 = tip_pos(q + h * v)
        p0, R0 = tip_pos(q - h * v)
        lin_fd = (p1 - p0) / (2 * h)
        Wfd = (R1 - R0) / (2 * h) @ tip_R.T
        ang_fd = np.array([Wfd[2, 1], Wfd[0, 2], Wfd[1, 0]])
        assert np.allclose(J @ v, np.concatenate([lin_fd, ang_fd]), atol=1e-6), "J vs FD"
        jd_fd = (tip_twist(q + h * v) - tip_twist(q - h * v)) / (2 * h)
        assert np.allclose(jd_fd, jdot_qdot, atol=1e-5 * (1 + np.abs(jdot_qdot).max())), "Jdot"
        # Pinocchio's Coriolis factorisation: dM/dt = C + C^T (so dM/dt - 2C is skew)
        Mp = pin.crba(m, d, self.q_pin(q + h * v)).copy()
        Mm = pin.crba(m, d, self.q_pin(q - h * v)).copy()
        Mdot = (np.triu(Mp) + np.triu(Mp, 1).T - np.triu(Mm) - np.triu(Mm, 1).T) / (2 * h)
        assert np.allclose(Mdot, C + C.T, atol=1e-6 * (1 + np.abs(Mdot).max())), "Mdot != C + C^T"

        return {
            "q": q.tolist(), "v": v.tolist(), "a": a.tolist(),
            "tau": tau.tolist(),
            "mass_matrix": M.tolist(),
            "gravity_torque": g.tolist(),
            "coriolis": C.tolist(),
            "nonlinear_effects": nle.tolist(),
            "aba_tau": aba_tau.tolist(), "aba_qddot": aba_qddot.tolist(),
            "tip_position": tip_p.tolist(), "tip_rotation": tip_R.tolist(),
            "jacobian": J.tolist(),
            "jdot_qdot": jdot_qdot.tolist(),
            "frames": frames,
            "external_wrench": w.tolist(),
            "tau_with_wrench": tau_w.tolist(),
        }


# ---------------------------------------------------------------------------------------------
# output: readable JSON, one matrix row per line, full precision numbers
# ---------------------------------------------------------------------------------------------
def dump(obj, indent=0):
    pad = "  " * indent
    if isinstance(obj, dict):
        if not obj:
            return "{}"
        items = ["%s  %s: %s" % (pad, json.dumps(k), dump(v, indent + 1)) for k, v in obj.items()]
        return "{\n" + ",\n".join(items) + "\n" + pad + "}"
    if isinstance(obj, list) and obj and all(isinstance(r, list) for r in obj) \
            and all(not isinstance(x, (list, dict)) for r in obj for x in r):
        rows = ["%s  %s" % (pad, json.dumps(r)) for r in obj]
        return "[\n" + ",\n".join(rows) + "\n" + pad + "]"
    if isinstance(obj, list) and any(isinstance(x, dict) for x in obj):
        items = ["%s  %s" % (pad, dump(x, indent + 1)) for x in obj]
        return "[\n" + ",\n".join(items) + "\n" + pad + "]"
    return json.dumps(obj)


def write_fixture(name, urdf_rel, arm, n_cases, rng):
    cases = [arm.case(rng) for _ in range(n_cases)]
    doc = {
        "urdf": urdf_rel,
        "base": arm.base, "tip": arm.tip,
        "joints": [j["name"] for j in arm.moving],
        "gravity": GRAVITY.tolist(),
        "pinocchio_version": pin.__version__,
        "cases": cases,
    }
    text = dump(doc) + "\n"
    assert json.loads(text) == json.loads(json.dumps(doc))
    with open(os.path.join(OUT_DIR, name + ".json"), "w") as f:
        f.write(text)


def main():
    rng = np.random.default_rng(SEED)
    os.makedirs(ARMS_DIR, exist_ok=True)
    os.makedirs(OUT_DIR, exist_ok=True)
    summary = []
    for k in range(N_ARMS):
        name = "arm_%02d" % k
        links, joints, tip = make_arm(rng, k)
        path = os.path.join(ARMS_DIR, name + ".urdf")
        with open(path, "w") as f:
            f.write(urdf_text(name, links, joints))
        arm = Arm(path, "base_link", tip)
        write_fixture(name, "arms/%s.urdf" % name, arm, CASES_PER_ARM, rng)
        types = [j["type"][0] for j in arm.moving]
        n_fixed = sum(1 for j in joints if j["type"] == "fixed")
        summary.append("%s: %d moving (%s), %d fixed, tip %s"
                       % (name, len(types), "".join(types), n_fixed, tip))
    arm = Arm(BAXTER, "base", "left_hand")
    write_fixture("baxter_left_arm", "../../../../models/baxter_left_arm.urdf", arm,
                  CASES_BAXTER, rng)
    summary.append("baxter_left_arm: 7 moving, tip left_hand")
    print("\n".join(summary))
    print("pinocchio %s: %d random arms x %d cases + Baxter x %d cases, all checks passed"
          % (pin.__version__, N_ARMS, CASES_PER_ARM, CASES_BAXTER))


if __name__ == "__main__":
    sys.exit(main())
