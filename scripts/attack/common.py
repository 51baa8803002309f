"""What every family shares: the case, the fixtures (made once per campaign from the
project's own models, scenarios and test data), the checks of a written output."""
import csv
import json
import math
import subprocess
from dataclasses import dataclass, field
from decimal import Decimal
from pathlib import Path
from typing import Callable, Optional


@dataclass
class Case:
    name: str
    argv: object  # a list, or a function of the case folder returning one
    expect: str = "any"  # "refuse": exit 0 is wrong; "ok": a refusal is noted; "any"
    check: Optional[Callable] = None  # (stdout, stderr) -> problem or None, on exit 0
    prepare: Optional[Callable] = None  # (case folder) -> None, before the run
    after: Optional[Callable] = None  # (case folder) -> problem or None, after any run
    timeout: float = 60.0
    cwd: Optional[Path] = None
    kind: str = "cli"
    family: str = ""


@dataclass
class Env:
    root: Path
    binary: Path
    library: Path
    python: str
    work: Path
    seed: int
    timeout: float
    keep: bool
    fx: dict = field(default_factory=dict)

    def cli(self, *args):
        return [str(self.binary)] + [str(a) for a in args]

    def sh(self, *args):
        """Runs the CLI for a fixture; a failure stops the campaign."""
        r = subprocess.run(self.cli(*args), capture_output=True, text=True, timeout=600)
        if r.returncode != 0:
            raise SystemExit(f"fixture failed: {' '.join(map(str, args))}\n{r.stderr}")
        return r

    def prepare(self):
        """The recordings, identifications, networks, deployment and run folder the cases
        damage or combine (each made by the tool itself)."""
        f, w, m = self.fx, self.work / "fixtures", self.root / "models"
        w.mkdir(parents=True)
        f["baxter_urdf"], f["panda_urdf"] = m / "baxter_left_arm.urdf", m / "franka_panda.urdf"
        f["bags"] = self.root / "crates/bag/tests/data"
        for name, urdf, seed in (("bax", "baxter_urdf", 1), ("bax2", "baxter_urdf", 2), ("panda", "panda_urdf", 1)):
            f[name] = w / f"{name}.csv"
            self.sh("excite", "--urdf", f[urdf], "--duration", 20, "--seed", seed, "--out", f[name])
        for name, data in (("bax_ident", "bax"), ("bax2_ident", "bax2")):
            f[name] = w / f"{name}.json"
            self.sh("identify", "--data", f[data], "--urdf", f["baxter_urdf"], "--folds", 2,
                    "--out", f[name], "--quiet")
        for name, data, urdf in (("bax_net", "bax", "baxter_urdf"), ("panda_net", "panda", "panda_urdf")):
            f[name] = w / f"{name}.broad"
            self.sh("train", "--data", f[data], "--urdf", f[urdf], "--nodes", 50, "--folds", 2,
                    "--out", f[name], "--quiet")
        f["bax_resid"] = w / "bax_resid.broad"
        self.sh("train", "--data", f["bax"], "--urdf", f["baxter_urdf"], "--nodes", 50,
                "--nominal", f["bax_ident"], "--validation", f["bax2"], "--out", f["bax_resid"], "--quiet")
        # the loop of scenarios/admittance.toml with this campaign's identification and
        # networks (deploy never trains), their input conditioning (none)
        given = {"momentum": [],
                 "learned": ["--set", f'observer.network="{f["bax_net"]}"', "--set", "observer.input_filter_hz=0"],
                 "hybrid": ["--set", "observer.training.identify=false", "--set", "observer.nominal_inertia_scale=1",
                            "--set", f'observer.identification="{f["bax_ident"]}"',
                            "--set", f'observer.network="{f["bax_resid"]}"', "--set", "observer.input_filter_hz=0"]}
        for kind, sets in given.items():
            f[f"deploy_{kind}"] = w / f"deploy_{kind}"
            self.sh("deploy", self.root / "scenarios/admittance.toml", "--variant", kind, *sets,
                    "--out", f[f"deploy_{kind}"])
        f["run"] = w / "run_pd"
        self.sh("run", self.root / "scenarios/deadzone.toml", "--variant", "pd", "--out", f["run"],
                "--set", "duration=0.3", "--set", "evaluation_start=0.1", "--quiet")


# --- checks of written outputs ---------------------------------------------------------------


def read_csv(path):
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    return rows[0], rows[1:]


def csv_problem(path, max_rows=None, max_span=None):
    """What is wrong with a free-motion CSV the tool wrote (None: nothing)."""
    if not Path(path).is_file():
        return f"exit 0 but {path} was not written"
    header, rows = read_csv(path)
    if len(set(header)) != len(header):
        dup = sorted({h for h in header if header.count(h) > 1})
        return f"duplicate columns {dup[:3]}"
    for h in header:
        if h != h.strip() or "," in h or "\n" in h or not h:
            return f"malformed column name {h!r}"
    if any(len(r) != len(header) for r in rows):
        return "rows of another width than the header"
    if not rows:
        return "no rows"
    for r in rows:
        for v in r:
            try:
                x = float(v)
            except ValueError:
                return f"non-numeric value {v!r}"
            if not math.isfinite(x):
                return f"non-finite value {v!r}"
    t = [float(r[header.index("t")]) for r in rows] if "t" in header else []
    if any(b <= a for a, b in zip(t, t[1:])):
        return "t not strictly increasing"
    if max_rows is not None and len(rows) > max_rows:
        return f"{len(rows)} rows, more than the clean bag's {max_rows}"
    if max_span is not None and t and t[-1] - t[0] > max_span:
        return f"spans {t[-1] - t[0]:.3f} s, more than the clean bag's {max_span:.3f} s"
    return None


def identification_problem(path):
    """What is physically impossible or non-finite in an identification file written."""
    if not Path(path).is_file():
        return f"exit 0 but {path} was not written"
    p = json.loads(Path(path).read_text())["payload"]
    ip = p["inertial_parameters"]
    if not all(math.isfinite(x) for x in ip):
        return "non-finite inertial parameter"
    for i in range(0, len(ip), 10):
        if ip[i] <= 0:
            return f"body {i // 10} has mass {ip[i]}"
        ixx, iyy, izz = ip[i + 4], ip[i + 6], ip[i + 9]
        if min(ixx, iyy, izz) < 0 or ixx > iyy + izz + 1e-9 or iyy > ixx + izz + 1e-9 or izz > ixx + iyy + 1e-9:
            return f"body {i // 10} inertia violates the triangle inequality ({ixx}, {iyy}, {izz})"
    for j, t in enumerate(p["joint_terms"]):
        for k in ("armature", "viscous"):
            if not (t[k] >= 0 and math.isfinite(t[k])):
                return f"joint {j} {k} = {t[k]}"
        c1, c2 = t["coulomb"]
        slack = -1e-9 * (abs(c1) + abs(c2)) - 1e-12
        if not (math.isfinite(c1) and math.isfinite(c2)) or c1 + c2 < slack or 10 * c1 + c2 < slack:
            return f"joint {j} Coulomb levels {t['coulomb']} push the joint along"
    cn = p["summary"].get("condition_number")
    if cn is not None and not (isinstance(cn, (int, float)) and math.isfinite(cn)):
        return f"condition number {cn}"
    text = json.dumps(p["summary"])
    if "NaN" in text or "Infinity" in text or "null" in text.replace('"ridge": null', ""):
        bad = [k for k, v in p["summary"].items() if v is None or (isinstance(v, float) and not math.isfinite(v))]
        if bad:
            return f"summary has non-finite {bad[:3]}"
    return None


# --- identification files: the envelope's checksum, as crates/dynamics computes it ----------


def _ryu(x):
    """serde_json's text of an f64: the shortest round-trip digits, plain between 1e-5 and
    1e16, else d.ddde+NN / d.ddde-NN (checked against the loader's own checksum)."""
    if x == 0:
        return "-0.0" if math.copysign(1, x) < 0 else "0.0"
    sign = "-" if x < 0 else ""
    t = Decimal(repr(abs(x))).normalize().as_tuple()
    digits, k = "".join(map(str, t.digits)), t.exponent
    n = len(digits)
    kk = n + k
    if 0 <= k and kk <= 16:
        s = digits + "0" * k + ".0"
    elif 0 < kk <= 16:
        s = digits[:kk] + "." + digits[kk:]
    elif -5 < kk <= 0:
        s = "0." + "0" * (-kk) + digits
    else:
        s = digits[0] + ("." + digits[1:] if n > 1 else "") + "e" + ("+" if kk > 0 else "") + str(kk - 1)
    return sign + s


def canonical_json(v):
    """serde_json::Value's compact text (keys sorted: no preserve_order)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if v is None:
        return "null"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return _ryu(v)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)
    if isinstance(v, list):
        return "[" + ",".join(canonical_json(x) for x in v) + "]"
    return "{" + ",".join(json.dumps(k, ensure_ascii=False) + ":" + canonical_json(v[k]) for k in sorted(v)) + "}"


def fnv1a64(data: bytes):
    h = 0xCBF29CE484222325
    for b in data:
        h ^= b
        h = (h * 0x100000001B3) & 0xFFFFFFFFFFFFFFFF
    return f"{h:016x}"


def write_identification(src, dst, edit):
    """Copies an identification file with `edit(payload)` applied and the envelope's
    checksum recomputed (crates/dynamics/src/identification/file.rs: FNV-1a 64 of the
    payload's canonical JSON)."""
    env = json.loads(Path(src).read_text())
    edit(env["payload"])
    env["checksum"] = fnv1a64(canonical_json(env["payload"]).encode())
    Path(dst).write_text(json.dumps(env, indent=2))


def rewrite_manifest(folder):
    """Recomputes a deployment folder's manifest (size and FNV-1a 64 of every file)."""
    man_path = Path(folder) / "manifest.json"
    man = json.loads(man_path.read_text())
    for name, entry in man["files"].items():
        data = (Path(folder) / name).read_bytes()
        entry["bytes"], entry["fnv1a64"] = len(data), fnv1a64(data)
    man_path.write_text(json.dumps(man, indent=2))


# --- cases run in a Python interpreter (the API, the C ABI through ctypes) -----------------

_HARNESS = '''import json, math, sys
sys.path.insert(0, {here!r})
import numpy as np
import admittance as adm
from pyhelp import *
FX = json.loads({fx!r})


def run():
{body}


try:
    problem = run()
except BaseException as e:
    name = type(e).__name__
    if name == "PanicException":
        print("panicked: " + str(e), file=sys.stderr)
        sys.exit(101)
    print(f"{{name}}: {{e}}", file=sys.stderr)
    sys.exit(3)
if problem:
    print("PROBLEM: " + str(problem))
sys.exit(0)
'''


def py_problem(stdout, stderr):
    for line in stdout.splitlines():
        if line.startswith("PROBLEM: "):
            return line[len("PROBLEM: "):]
    return None


def py_case(env, name, body, expect="any", timeout=None):
    """A case running `body` (the statements of a function returning a problem or None)
    in a fresh interpreter: an exception is a refusal, a PanicException a panic."""
    import textwrap

    fx = json.dumps({k: str(v) for k, v in env.fx.items()} | {"library": str(env.library), "root": str(env.root)})
    text = _HARNESS.format(here=str(Path(__file__).parent), fx=fx,
                           body=textwrap.indent(textwrap.dedent(body).strip("\n"), "    "))

    def prepare(d):
        (d / "case.py").write_text(text)

    return Case(name, lambda d: [env.python, str(d / "case.py")], expect=expect, check=py_problem,
                prepare=prepare, timeout=timeout or env.timeout, kind="py")
