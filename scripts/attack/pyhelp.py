"""Helpers the Python cases import (run inside the case's interpreter)."""
import math

import numpy as np


def nonfinite(*arrays):
    """A problem when any array holds a NaN or an infinity."""
    for a in arrays:
        a = np.asarray(a, dtype=float)
        if not np.all(np.isfinite(a)):
            return f"returned non-finite values ({a.ravel()[~np.isfinite(a.ravel())][:3]})"
    return None


def differs(a, b, tol=1e-9, what="result"):
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.shape != b.shape:
        return f"{what}: shape {a.shape} instead of {b.shape}"
    gap = float(np.max(np.abs(a - b) / (1.0 + np.abs(b)))) if a.size else 0.0
    if not gap <= tol:
        return f"{what} differs from the clean call's by {gap:.3g}"
    return None


def load_csv(path):
    """A free-motion CSV as the dict the API takes."""
    with open(path) as fh:
        header = fh.readline().strip().split(",")
    a = np.loadtxt(path, delimiter=",", skiprows=1)
    cols = lambda p: [i for i, h in enumerate(header) if h.startswith(p + ".")]  # noqa: E731
    return {"t": a[:, 0].copy(), **{k: a[:, cols(k)].copy() for k in ("q", "qdot", "qddot", "tau")}}


def ident_problem(ident):
    """What is physically impossible or non-finite in an Identification."""
    m = ident.model
    summary = ident.summary
    for j, t in enumerate(ident.joint_terms):
        if t["armature"] < 0 or t["viscous"] < 0 or not all(map(math.isfinite, [t["armature"], t["viscous"]])):
            return f"joint {j}: armature {t['armature']}, viscous {t['viscous']}"
        c1, c2 = t["coulomb"]
        if c1 + c2 < -1e-9 or 10 * c1 + c2 < -1e-9:
            return f"joint {j}: Coulomb levels {t['coulomb']}"
    e = summary.get("expected_false_torque_rms")
    if e is not None and not all(x is not None and math.isfinite(x) for x in np.ravel(e)):
        return f"expected_false_torque_rms {e}"
    c = summary.get("condition_number")
    if c is not None and not math.isfinite(c):
        return f"condition number {c}"
    return None
