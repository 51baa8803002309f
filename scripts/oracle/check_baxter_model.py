#!/usr/bin/env python3
"""Check that the project's Baxter model has exactly the published numbers.

Parses models/baxter_left_arm.urdf (ours) and a reference copy of the published
Baxter left-arm description, and asserts that both have the same links and joints
and that every numeric attribute of every joint (origin, axis, limit, dynamics,
joint type, parent, child) and every link inertial (origin, mass, inertia) is equal
as a float. Collision/visual geometry is not compared (our model has none).

Usage: python3 scripts/oracle/check_baxter_model.py [OURS] REFERENCE
REFERENCE (or the environment variable BAXTER_REFERENCE_URDF): the left-arm chain taken from
the published description, RethinkRobotics/baxter_common on GitHub,
baxter_description/urdf/baxter_base/baxter_base.urdf.xacro (the header of
models/baxter_left_arm.urdf names the revision and what was kept).
Standard library only.
"""
import math
import os
import sys
import xml.etree.ElementTree as ET

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))

# Defaults the URDF specification gives to absent attributes.
DEFAULTS = {
    ("origin", "xyz"): "0 0 0",
    ("origin", "rpy"): "0 0 0",
    ("axis", "xyz"): "1 0 0",
}


def floats(text):
    return [float(t) for t in text.split()]


def element_numbers(parent, tag, attrs):
    """{(tag, attr): [floats]} for a child element; absent element -> defaults/None."""
    out = {}
    el = parent.find(tag)
    for a in attrs:
        if el is not None and a in el.attrib:
            out[(tag, a)] = floats(el.attrib[a])
        elif (tag, a) in DEFAULTS:
            out[(tag, a)] = floats(DEFAULTS[(tag, a)])
        else:
            out[(tag, a)] = None
    return out


def describe(path):
    root = ET.parse(path).getroot()
    links, joints = {}, {}
    for link in root.findall("link"):
        name = link.attrib["name"]
        inertial = link.find("inertial")
        if inertial is None:
            links[name] = None
            continue
        d = {}
        d.update(element_numbers(inertial, "origin", ["xyz", "rpy"]))
        d.update(element_numbers(inertial, "mass", ["value"]))
        d.update(element_numbers(inertial, "inertia",
                                 ["ixx", "ixy", "ixz", "iyy", "iyz", "izz"]))
        links[name] = d
    for joint in root.findall("joint"):
        name = joint.attrib["name"]
        jtype = joint.attrib["type"]
        d = {
            "type": jtype,
            "parent": joint.find("parent").attrib["link"],
            "child": joint.find("child").attrib["link"],
        }
        d.update(element_numbers(joint, "origin", ["xyz", "rpy"]))
        # Axis is meaningless on fixed joints but must still match when present.
        d.update(element_numbers(joint, "axis", ["xyz"]))
        d.update(element_numbers(joint, "limit", ["lower", "upper", "effort", "velocity"]))
        d.update(element_numbers(joint, "dynamics", ["damping", "friction"]))
        joints[name] = d
    return links, joints


def same(a, b):
    if a is None or b is None:
        return a is b
    if isinstance(a, str):
        return a == b
    return len(a) == len(b) and all(float(x) == float(y) for x, y in zip(a, b))


def main():
    args = sys.argv[1:]
    if len(args) == 1:
        args = [os.path.join(ROOT, "models", "baxter_left_arm.urdf")] + args
    ours = args[0] if args else os.path.join(ROOT, "models", "baxter_left_arm.urdf")
    ref = args[1] if len(args) > 1 else os.environ.get("BAXTER_REFERENCE_URDF")
    if not ref:
        print("usage: check_baxter_model.py [OURS] REFERENCE (or set BAXTER_REFERENCE_URDF)",
              file=sys.stderr)
        return 2
    if not os.path.exists(ref):
        print(f"reference not found: {ref}", file=sys.stderr)
        return 2
    ol, oj = describe(ours)
    rl, rj = describe(ref)
    errors = []
    if set(ol) != set(rl):
        errors.append(f"link names differ: ours-only {sorted(set(ol) - set(rl))}, "
                      f"reference-only {sorted(set(rl) - set(ol))}")
    if set(oj) != set(rj):
        errors.append(f"joint names differ: ours-only {sorted(set(oj) - set(rj))}, "
                      f"reference-only {sorted(set(rj) - set(oj))}")
    n_values = 0
    for kind, o, r in (("link", ol, rl), ("joint", oj, rj)):
        for name in sorted(set(o) & set(r)):
            if (o[name] is None) != (r[name] is None):
                errors.append(f"{kind} {name}: inertial present in one file only")
                continue
            if o[name] is None:
                continue
            for key in sorted(set(o[name]) | set(r[name]), key=str):
                a, b = o[name].get(key), r[name].get(key)
                if not same(a, b):
                    errors.append(f"{kind} {name} {key}: ours {a} != reference {b}")
                elif isinstance(a, list):
                    n_values += len(a)
    for e in errors:
        print("MISMATCH:", e)
    assert not errors, f"{len(errors)} mismatches"
    for n in (ol, rl):
        assert not any(math.isnan(v) for d in n.values() if d for vals in d.values() if vals for v in vals)
    print(f"OK: {len(ol)} links, {len(oj)} joints, {n_values} numeric values identical "
          f"({os.path.relpath(ours, ROOT)} vs {ref})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
