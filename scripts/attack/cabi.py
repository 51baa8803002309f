"""A ctypes harness on target/release/libadmittance_ffi.so (its structs and constants read
from crates/ffi/include/admittance.h), and the absurd-sample attack shared by the C ABI and RobotLoop cases:
a clean run and a hit run of the same motion, compared."""
import ctypes as C
import math
import re
from pathlib import Path

import numpy as np

HEADER = Path(__file__).resolve().parents[2] / "crates/ffi/include/admittance.h"
_TYPES = {"double": C.c_double, "uint32_t": C.c_uint32, "int32_t": C.c_int32, "uint64_t": C.c_uint64,
          "const char *": C.c_char_p}


def _header():
    """ADM_ABI_VERSION, ADM_MAX_JOINTS and the ctypes fields of each struct, read from the
    committed header, so that the harness follows the ABI as it changes."""
    text = HEADER.read_text()
    consts = dict(re.findall(r"#define (ADM_\w+) (-?\d+)\b", text))
    structs = {}
    for name, body in re.findall(r"typedef struct (Adm\w+) \{(.*?)\} \1;", text, re.S):
        fields = []
        for ctype, field, size in re.findall(r"^\s*(const char \*|\w+) ?(\w+)(?:\[(\w+)\])?;", body, re.M):
            t = _TYPES[ctype.strip() if ctype.strip() != "const char *" else "const char *"]
            if size:
                t = t * int(consts.get(size, size))
            fields.append((field, t))
        structs[name] = fields
    return int(consts["ADM_ABI_VERSION"]), int(consts["ADM_MAX_JOINTS"]), structs


ABI, MAXJ, _STRUCTS = _header()
OK, FAULT = 0, 1
OUT_CONTROLLER_FAULT, OUT_OBSERVER_FAULT, OUT_NONFINITE, OUT_IMPLAUSIBLE, OUT_STALE = 1, 2, 1 << 2, 1 << 6, 1 << 11
# What says "this sample was not used as it came": a fault status or one of these flags.
FLAGGED = OUT_CONTROLLER_FAULT | OUT_OBSERVER_FAULT | OUT_NONFINITE | OUT_IMPLAUSIBLE | OUT_STALE
IN_QDOT, IN_TAU, IN_DESIRED = 1, 2, 4
POSE = np.array([0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5])


class Config(C.Structure):
    _fields_ = _STRUCTS["AdmConfig"]


class Input(C.Structure):
    _fields_ = _STRUCTS["AdmInput"]


class Output(C.Structure):
    _fields_ = _STRUCTS["AdmOutput"]


def library(path):
    lib = C.CDLL(path)
    lib.adm_create.restype = C.c_void_p
    lib.adm_create.argtypes = [C.POINTER(Config)]
    lib.adm_step.restype = C.c_int32
    lib.adm_step.argtypes = [C.c_void_p, C.POINTER(Input), C.POINTER(Output)]
    lib.adm_destroy.argtypes = [C.c_void_p]
    lib.adm_last_error.restype = C.c_size_t
    lib.adm_last_error.argtypes = [C.c_void_p, C.c_char_p, C.c_size_t]
    lib.adm_control_period.restype = C.c_double
    lib.adm_control_period.argtypes = [C.c_void_p]
    return lib


def last_error(lib, handle=None):
    buf = C.create_string_buffer(4096)
    lib.adm_last_error(handle, buf, 4096)
    return buf.value.decode("utf-8", "replace")


def create(lib_path, deploy, n=7, overrides=None, abi=ABI):
    """(handle or None, error message) of adm_create."""
    lib = library(lib_path) if isinstance(lib_path, str) else lib_path
    cfg = Config(abi_version=abi, n_joints=n, deployment_path=None if deploy is None else str(deploy).encode(),
                 overrides=None if overrides is None else overrides.encode())
    h = lib.adm_create(C.byref(cfg))
    return h, ("" if h else last_error(lib))


def motion(m, steps, dt):
    """A slow motion about Baxter's pose of experiment B with the torques it needs."""
    import admittance as adm
    t = np.arange(steps) * dt
    w = 2 * math.pi * 0.3
    ph = np.arange(7)
    q = POSE + 0.2 * np.sin(w * t[:, None] + ph)
    qd = 0.2 * w * np.cos(w * t[:, None] + ph)
    qdd = -0.2 * w * w * np.sin(w * t[:, None] + ph)
    tau = np.array([adm.rnea(m, q[k], qd[k], qdd[k]) for k in range(steps)])
    return t, q, qd, tau


class Harness:
    """One deployment folder's motion, stepped through the C ABI or Python's RobotLoop."""

    def __init__(self, lib_path, deploy, front="c", steps=3000):
        import admittance as adm
        self.deploy, self.front, self.steps = Path(deploy), front, steps
        self.lib = library(lib_path)
        self.m = adm.Model.from_urdf(str(self.deploy / "arm.urdf"), "base", "left_hand")
        self.effort = np.asarray(self.m.effort_limit, dtype=float)
        self.dt = 1e-3
        self.t, self.q, self.qd, self.tau = motion(self.m, steps, self.dt)

    def run(self, inject=None, flags=IN_TAU):
        """(status, out flags, tau_cmd, tau_ext, implausible counts) per step; `inject(k,
        inp)` edits step k's input (a dict t, q, qdot, tau, q_d, n, flags)."""
        import admittance as adm
        n, steps = 7, self.steps
        status = np.zeros(steps, dtype=int)
        oflags = np.zeros(steps, dtype=int)
        cmd, est = np.zeros((steps, n)), np.zeros((steps, n))
        if self.front == "c":
            h, err = create(self.lib, self.deploy)
            if not h:
                raise RuntimeError(err)
            out = Output()
        else:
            loop = adm.RobotLoop.load(str(self.deploy))
        try:
            for k in range(steps):
                inp = {"t": self.t[k], "q": self.q[k].copy(), "qdot": self.qd[k].copy(), "tau": self.tau[k].copy(),
                       "q_d": None, "n": n, "flags": flags}
                if inject:
                    inject(k, inp)
                if self.front == "c":
                    c = Input(time=inp["t"], n_joints=inp["n"], flags=inp["flags"])
                    c.q[:n], c.qdot[:n], c.tau[:n] = inp["q"], inp["qdot"], inp["tau"]
                    if inp["q_d"] is not None:
                        c.flags |= IN_DESIRED
                        c.q_d[:n] = inp["q_d"]
                    status[k] = self.lib.adm_step(h, C.byref(c), C.byref(out))
                    oflags[k] = out.flags | (out.fault << 16)
                    cmd[k], est[k] = out.tau_cmd[:n], out.tau_ext[:n]
                else:
                    kw = {"qdot": inp["qdot"]} if inp["flags"] & IN_QDOT else {}
                    if inp["q_d"] is not None:
                        kw["q_d"] = inp["q_d"]
                    try:
                        c_, e_ = loop.step(inp["t"], inp["q"][: inp["n"]], inp["tau"], **kw)
                        s = loop.status
                        status[k] = 0 if s["ok"] else 1
                        oflags[k] = FLAGGED if (s["implausible"] or s["nonfinite_input"] or s["stale_input"]
                                                or s["observer_fault"] or s["controller_fault"]) else 0
                        cmd[k], est[k] = c_, e_
                    except ValueError:
                        status[k] = -1  # refused: nothing stepped
                        cmd[k], est[k] = cmd[k - 1], est[k - 1]
        finally:
            if self.front == "c":
                self.lib.adm_destroy(h)
        return status, oflags, cmd, est

    def attack(self, inject, first, last, flags=IN_TAU, must_flag=True, recover_s=1.0, tol=1e-3):
        """A problem (or None): the hit steps first..last flagged, every command finite and
        within the effort limits, no absurd estimate with status OK, the estimate within
        `tol` of the clean run's from `recover_s` after the last hit step on."""
        _, _, _, clean = self.run(None, flags)
        status, oflags, cmd, est = self.run(inject, flags)
        if must_flag == "any":  # a repeated reading is reported once the chain sees it stale
            if not any(status[k] != OK or oflags[k] & FLAGGED for k in range(first, last + 1)):
                return f"steps {first}..{last}: status ADM_OK and no fault flag on every one"
        elif must_flag:
            for k in range(first, last + 1):
                if status[k] == OK and not oflags[k] & FLAGGED:
                    return f"step {k}: status ADM_OK and no fault flag on the hit sample"
        bad = ~np.all(np.isfinite(cmd), axis=1) | np.any(np.abs(cmd) > self.effort * (1 + 1e-9), axis=1)
        if bad.any():
            k = int(np.argmax(bad))
            return f"step {k}: command {cmd[k]} not finite or beyond the effort limits"
        absurd = (status == OK) & ~np.all(np.abs(est) < 1e3, axis=1)
        if absurd.any():
            k = int(np.argmax(absurd))
            return f"step {k}: estimate {np.max(np.abs(est[k])):.3g} N m with status OK"
        back = last + int(round(recover_s / self.dt))
        # Without a measured torque the loop observes its own command, which the hit changed
        # (the safe hold): this open-loop replay then has no clean run to return to.
        if back < self.steps and flags & IN_TAU:
            gap = float(np.max(np.abs(est[back:] - clean[back:])))
            if not gap <= tol:
                return f"estimate {gap:.3g} N m from the clean run's {recover_s} s after the hit"
        return None
