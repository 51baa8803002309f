"""The families that feed the command line damaged files: bags, CSVs, identification files,
files made for another arm or identification, special files and planted links."""
import csv
import io
import os
import random
import shutil
import struct
from pathlib import Path

import mcap
from common import (Case, csv_problem, identification_problem, py_case, read_csv,
                    rewrite_manifest, write_identification)

# (name, file under crates/bag/tests/data, profile)
BAGS = [("franka_zstd", "franka_zstd/franka_zstd.mcap", "franka"),
        ("franka_crc_zstd", "franka_crc_zstd.mcap", "franka"),
        ("lbr_zstd", "lbr_zstd/lbr_zstd.mcap", "lbr"),
        ("franka_plain", "franka_plain.mcap", "franka")]
MODES = ([], ["--accept-damaged"])


def _write(path, data):
    Path(path).write_bytes(bytes(data))


def _clean_import(env, bag, profile):
    """(rows, span) of the clean bag's import: a damaged bag gives no more."""
    out = env.work / "fixtures" / f"clean_{Path(bag).stem}.csv"
    if not out.exists():
        env.sh("import", bag, "--profile", profile, "--out", out)
    header, rows = read_csv(out)
    t = [float(r[0]) for r in rows]
    return len(rows), t[-1] - t[0]


def _import_case(env, name, data, profile, flags, clean, expect="any", max_rows=True):
    rows, span = clean

    def prepare(d):
        _write(d / "bag.mcap", data)

    case = Case(name, None, expect=expect, prepare=prepare)
    case.argv = lambda d: env.cli("import", d / "bag.mcap", "--profile", profile, "--out", d / "out.csv", *flags)
    case.after = lambda d: (csv_problem(d / "out.csv", max_rows=int(rows * 1.02) + 2 if max_rows else 10_000_000,
                                        max_span=span * 1.02 + 0.01 if max_rows else None)
                            if _exited_zero(d) else None)
    return case


def _exited_zero(d):
    """Whether the case's process exited 0 (its out.csv is then checked)."""
    return (d / "out.csv").exists()


def bags(env):
    data_dir = env.fx["bags"]
    rng = random.Random(env.seed)
    for name, rel, profile in BAGS:
        path = data_dir / rel
        buf = path.read_bytes()
        clean = _clean_import(env, path, profile)
        chunk = mcap.chunks(buf)[0]
        off, size = chunk["fields"]["uncompressed_size"]
        modes = MODES if name == "franka_zstd" else ([],)
        for flags in modes:
            tag = " --accept-damaged" if flags else ""
            for bit in range(64):
                yield _import_case(env, f"{name} uncompressed_size bit {bit}{tag}",
                                   mcap.flip_bit(buf, off, bit), profile, flags, clean)
            for delta in (1, -1):
                b = bytearray(buf)
                (v,) = struct.unpack_from("<Q", b, off)
                struct.pack_into("<Q", b, off, (v + delta) % 2**64)
                yield _import_case(env, f"{name} uncompressed_size {delta:+d}{tag}", b, profile, flags, clean)
            if name in ("franka_zstd", "franka_plain"):
                for field, (foff, fsize) in chunk["fields"].items():
                    if field == "uncompressed_size":
                        continue
                    for bit in (0, 3, 8, 17, 31, 33, 47, 62, 63):
                        if bit < 8 * fsize:
                            yield _import_case(env, f"{name} {field} bit {bit}{tag}",
                                               mcap.flip_bit(buf, foff, bit), profile, flags, clean)
            for k in range(40 if name == "franka_zstd" else 15):
                b = bytearray(buf)
                at = chunk["data"] + rng.randrange(chunk["data_length"])
                b[at] ^= 1 << rng.randrange(8)
                yield _import_case(env, f"{name} data byte {at - chunk['data']} flipped{tag}", b, profile, flags, clean)
            for frac in (0.0005, 0.01, 0.05, 0.2, 0.5, 0.8, 0.95, 0.99, 0.9995):
                cut = int(len(buf) * frac)
                yield _import_case(env, f"{name} truncated at {cut}/{len(buf)}{tag}", buf[:cut], profile, flags, clean)
    zstd = (data_dir / BAGS[0][1]).read_bytes()
    clean = _clean_import(env, data_dir / BAGS[0][1], "franka")
    for rate in ("5e7", "1e9", "1e300", "0", "-1", "nan", "inf", "1e-3"):
        for extra in ([], ["--accept-low-rate"]):
            yield _import_case(env, f"franka_zstd --rate {rate} {' '.join(extra)}", zstd, "franka",
                               ["--rate", rate] + extra, clean, max_rows=False)
    yield from _clock_jumps(env, data_dir)
    yield from _python_imports(env, data_dir)


def _clock_jumps(env, data_dir):
    """A plain bag whose last (or first, or a middle) message is stamped a day off: in the
    record's log time, in the message's header stamp, or both."""
    path = data_dir / "franka_plain.mcap"
    buf = path.read_bytes()
    clean = _clean_import(env, path, "franka")
    chunk = mcap.chunks(buf)[0]
    msgs = mcap.messages_of_plain_chunk(buf, chunk)
    day = 86400
    for which, idx in (("last", -1), ("first", 0), ("middle", len(msgs) // 2)):
        rec, log_at, data_at, _ = msgs[idx]
        for where in ("log_time", "header stamp", "both"):
            for sign in (1, -1):
                b = bytearray(buf)
                if where in ("log_time", "both"):
                    (v,) = struct.unpack_from("<Q", b, log_at)
                    struct.pack_into("<Q", b, log_at, max(0, v + sign * day * 10**9))
                    struct.pack_into("<Q", b, log_at + 8, max(0, v + sign * day * 10**9))
                if where in ("header stamp", "both"):
                    (sec,) = struct.unpack_from("<i", b, data_at + 4)
                    struct.pack_into("<i", b, data_at + 4, sec + sign * day)
                mcap.fix_crc(b, chunk)
                for flags in MODES:
                    tag = " --accept-damaged" if flags else ""
                    yield _import_case(env, f"franka_plain {which} message {where} {sign * day:+d} s{tag}",
                                       b, "franka", flags, clean)
    b = bytearray(buf)
    struct.pack_into("<Q", b, msgs[-1][1], 2**64 - 1)
    yield _import_case(env, "franka_plain last log_time u64::MAX", b, "franka", [], clean)


def _python_imports(env, data_dir):
    path = data_dir / BAGS[0][1]
    buf = path.read_bytes()
    rows, span = _clean_import(env, path, "franka")
    chunk = mcap.chunks(buf)[0]
    off, _ = chunk["fields"]["uncompressed_size"]
    rng = random.Random(env.seed + 1)
    variants = [(f"uncompressed_size bit {bit}", mcap.flip_bit(buf, off, bit)) for bit in (0, 5, 20, 40, 63)]
    for _ in range(6):
        b = bytearray(buf)
        at = chunk["data"] + rng.randrange(chunk["data_length"])
        b[at] ^= 1 << rng.randrange(8)
        variants.append((f"data byte {at - chunk['data']} flipped", b))
    variants.append(("truncated at half", buf[: len(buf) // 2]))
    for label, data in variants:
        for accept in (False, True):
            case = py_case(env, f"adm.import_bag {label} accept_damaged={accept}", f"""
                r = adm.import_bag(FX_CASE + "/bag.mcap", "franka", accept_damaged={accept})
                n = len(r["t"])
                if n > {int(rows * 1.02) + 2}:
                    return f"{{n}} rows, more than the clean bag's {rows}"
                if np.any(np.diff(r["t"]) <= 0):
                    return "t not increasing"
                return nonfinite(r["q"], r["qdot"], r["qddot"], r["tau"])
            """)
            yield _with_bag(case, data)
    for rate in ("5e7", "1e300", "float('nan')"):
        case = py_case(env, f"adm.import_bag rate={rate}", f"""
            r = adm.import_bag(FX_CASE + "/bag.mcap", "franka", rate={rate})
            return nonfinite(r["q"], r["qdot"], r["qddot"], r["tau"])
        """)
        yield _with_bag(case, buf)


def _with_bag(case, data):
    inner = case.prepare

    def prepare(d):
        _write(d / "bag.mcap", data)
        inner(d)
        text = (d / "case.py").read_text().replace("FX_CASE", repr(str(d)))
        (d / "case.py").write_text(text)

    case.prepare = prepare
    return case


# --- CSVs ------------------------------------------------------------------------------------


def _csv_text(header, rows):
    s = io.StringIO()
    w = csv.writer(s, lineterminator="\n")
    w.writerow(header)
    w.writerows(rows)
    return s.getvalue()


def _cols(header, prefix):
    return [i for i, h in enumerate(header) if h.startswith(prefix + ".")]


def csv_mutations(env):
    """(name, text of the CSV, must be refused by identify) from the Baxter excitation."""
    header, rows = read_csv(env.fx["bax"])
    rows = [list(r) for r in rows]

    def edit(fn):
        h, r = list(header), [list(x) for x in rows]
        fn(h, r)
        return _csv_text(h, r)

    def rename(h, r, old, new):
        for i, x in enumerate(h):
            if x.endswith("." + old):
                h[i] = x[: -len(old)] + new

    def scale(prefix, factor, rows_sel=None):
        def fn(h, r):
            for k, row in enumerate(r):
                if rows_sel is None or k in rows_sel:
                    for i in _cols(h, prefix):
                        row[i] = repr(float(row[i]) * factor)
        return fn

    def setcol(prefix, value, rows_sel=None):
        def fn(h, r):
            for k, row in enumerate(r):
                if rows_sel is None or k in rows_sel:
                    for i in _cols(h, prefix):
                        row[i] = value
        return fn

    def still(h, r):
        for row in r:
            for p in ("q", "tau"):
                for i in _cols(h, p):
                    row[i] = r[0][i]
            for p in ("qdot", "qddot"):
                for i in _cols(h, p):
                    row[i] = "0.0"

    yield "duplicate joint name", edit(lambda h, r: rename(h, r, "left_s1", "left_s0")), True
    yield "comma in a joint name", edit(lambda h, r: rename(h, r, "left_s0", "left,s0")), True
    yield "newline in a joint name", edit(lambda h, r: rename(h, r, "left_s0", "left\ns0")), True
    yield "duplicated column", edit(lambda h, r: (h.append(h[1]), [row.append(row[1]) for row in r])), True
    yield "velocities 1e306 in 20 rows", edit(setcol("qdot", "1e306", set(range(100, 120)))), True
    yield "everything but t times 1e300", edit(lambda h, r: [scale(p, 1e300)(h, r) for p in ("q", "qdot", "qddot", "tau")]), True
    yield "no motion", edit(still), True
    yield "all-zero torque", edit(setcol("tau", "0.0")), False
    yield "sign-flipped torque", edit(scale("tau", -1.0)), False
    yield "torque times 1e300", edit(scale("tau", 1e300)), True
    yield "torque 1e300 in one row", edit(setcol("tau", "1e300", {2000})), True
    yield "one NaN torque", edit(setcol("tau", "NaN", {1000})), True
    yield "one inf angle", edit(setcol("q", "inf", {1000})), True
    yield "text in a cell", edit(setcol("qdot", "abc", {5})), True
    yield "empty cell", edit(setcol("qddot", "", {7})), True
    yield "short row", edit(lambda h, r: r[10].pop()), True
    yield "header only", _csv_text(header, []), True
    yield "empty file", "", True
    yield "three rows", _csv_text(header, rows[:3]), True
    yield "rows shuffled", edit(lambda h, r: random.Random(env.seed).shuffle(r)), True
    yield "t repeated", edit(lambda h, r: [row.__setitem__(0, r[0][0]) for row in r]), True
    yield "t NaN", edit(lambda h, r: r[50].__setitem__(0, "NaN")), True


def csvs(env):
    urdf = env.fx["baxter_urdf"]
    for name, text, refuse in csv_mutations(env):
        def prepare(d, text=text):
            (d / "data.csv").write_text(text)
        yield Case(f"identify: {name}", lambda d: env.cli("identify", "--data", d / "data.csv", "--urdf", urdf,
                                                           "--folds", 2, "--quiet", "--out", d / "out.json"),
                   expect="refuse" if refuse else "any", prepare=prepare,
                   after=lambda d: identification_problem(d / "out.json") if (d / "out.json").exists() else None)
        yield Case(f"train: {name}", lambda d: env.cli("train", "--data", d / "data.csv", "--urdf", urdf,
                                                        "--nodes", 50, "--folds", 2, "--quiet", "--out", d / "out.broad"),
                   expect="refuse" if refuse else "any", prepare=prepare, check=_no_nonfinite_text)
        yield Case(f"evaluate: {name}", lambda d: env.cli("evaluate", "--data", d / "data.csv", "--urdf", urdf,
                                                           "--identification", env.fx["bax_ident"]),
                   expect="refuse" if refuse and name != "no motion" else "any", prepare=prepare,
                   check=_no_nonfinite_text)
        body = f"""
            m = adm.Model.from_urdf({str(urdf)!r})
            ident = adm.identify(FX_CASE + "/data.csv", m)
            return ident_problem(ident)
        """
        case = py_case(env, f"adm.identify: {name}", body, expect="refuse" if refuse else "any")
        yield _with_text(case, text)
    yield from _import_names(env)
    yield from _real_recording(env)


# The published Baxter recording (found as the tests find it: ADMITTANCE_DATA, else the
# shared data folder beside the clone); skipped when absent.
REAL = Path(os.environ.get("ADMITTANCE_DATA", Path(__file__).resolve().parents[3] / "shared/data")) / "baxter_rand/baxter_rand.csv"


def _real_recording(env):
    """The real Baxter recording (its README: 15,000 rows of random motion), identified as
    recorded (a control) and with its torque zeroed or sign-flipped: physical or refused."""
    if not REAL.is_file():
        return
    header, rows = read_csv(REAL)
    tau = _cols(header, "tau")

    def edited(factor):
        out = [list(r) for r in rows]
        for r in out:
            for i in tau:
                r[i] = repr(float(r[i]) * factor)
        return _csv_text(header, out)
    for name, text, expect in (("as recorded", None, "ok"), ("torque zeroed", 0.0, "any"), ("torque sign-flipped", -1.0, "any")):
        def prepare(d, factor=text):
            if factor is None:
                os.symlink(REAL, d / "data.csv")
            else:
                (d / "data.csv").write_text(edited(factor))
        yield Case(f"identify real Baxter recording: {name}",
                   lambda d: env.cli("identify", "--data", d / "data.csv", "--urdf", env.fx["baxter_urdf"], "--folds", 2,
                                     "--input-filter-hz", 4, "--quiet", "--out", d / "out.json"),
                   expect=expect, prepare=prepare,
                   after=lambda d: identification_problem(d / "out.json") if (d / "out.json").exists() else None)


def _with_text(case, text):
    inner = case.prepare

    def prepare(d):
        (d / "data.csv").write_text(text)
        inner(d)
        (d / "case.py").write_text((d / "case.py").read_text().replace("FX_CASE", repr(str(d))))

    case.prepare = prepare
    return case


def _no_nonfinite_text(stdout, stderr):
    for word in ("NaN", "nan ", " inf", "inf\n", "-inf"):
        if word in stdout or word in stderr:
            line = next((l for l in (stdout + stderr).splitlines() if word.strip() in l), "")
            return f"prints a non-finite number: {line.strip()[:200]}"
    return None


def _import_names(env):
    """Joint names a CSV cannot carry and values beyond any arm, in a plain bag's messages."""
    path = env.fx["bags"] / "franka_plain.mcap"
    buf = path.read_bytes()
    clean = _clean_import(env, path, "franka")
    for label, new, expect in (("duplicate joint name", b"fr3_joint1", "refuse"), ("comma in a joint name", b"fr3,joint2", "refuse"),
                               ("newline in a joint name", b"fr3\njoint2", "refuse"), ("space in a joint name", b"fr3 joint2", "any"),
                               ("quote in a joint name", b'fr3"joint2', "refuse"), ("NUL in a joint name", b"fr3\x00joint2", "refuse"),
                               ("tab in a joint name", b"fr3\tjoint2", "refuse"), ("outer space in a joint name", b"fr3_joint \x00", "refuse")):
        data = buf.replace(b"fr3_joint2\x00", new + b"\x00"[: 11 - len(new)])
        yield _import_case(env, f"import: {label}", data, "franka", [], clean, expect=expect)
    chunk = mcap.chunks(buf)[0]
    for field_index, label in ((1, "velocity"), (0, "position"), (2, "effort")):
        for value in (1e306, 1e300, -1e200, float("nan"), float("inf")):
            b = bytearray(buf)
            for _, _, data_at, length in mcap.messages_of_plain_chunk(buf, chunk)[40:60]:
                at = _joint_state_array(b, data_at, length, field_index)
                if at is not None:
                    struct.pack_into("<d", b, at + 8, value)
            yield _import_case(env, f"import: {label} {value} in 20 messages", b, "franka", [], clean)


def _joint_state_array(b, data_at, length, field_index):
    """Offset of the first double of sensor_msgs/JointState's position (0), velocity (1) or
    effort (2) sequence in a CDR message (little endian), or None if it is not one."""
    base = data_at + 4
    pos = base + 8
    try:
        (n,) = struct.unpack_from("<I", b, pos)
        pos += 4 + n
        pos = base + ((pos - base + 3) & ~3)
        (names,) = struct.unpack_from("<I", b, pos)
        if names > 64:
            return None
        pos += 4
        for _ in range(names):
            (n,) = struct.unpack_from("<I", b, pos)
            pos += 4 + n
            pos = base + ((pos - base + 3) & ~3)
        for k in range(3):
            pos = base + ((pos - base + 3) & ~3)
            (count,) = struct.unpack_from("<I", b, pos)
            pos += 4
            pos = base + ((pos - base + 7) & ~7)
            if k == field_index:
                return pos if count >= 2 and pos + 16 <= data_at + length else None
            pos += 8 * count
    except struct.error:
        return None
    return None


# --- identification files ----------------------------------------------------------------------


def identification_edits():
    """(name, edit of the payload): every one must be refused on load."""
    def ip(k, v):
        return lambda p: p["inertial_parameters"].__setitem__(k, v)

    def jt(key, v, j=0):
        return lambda p: p["joint_terms"][j].__setitem__(key, v)

    def triangle(p):
        x = p["inertial_parameters"]
        x[4] = x[6] + x[9] + 1.0

    yield "mass -5", ip(0, -5.0)
    yield "mass 0", ip(0, 0.0)
    yield "mass 1e300", ip(10, 1e300)
    yield "inertia 1e300", ip(4, 1e300)
    yield "inertia -1", ip(6, -1.0)
    yield "inertia violating the triangle inequality", triangle
    yield "first moment 1e3", ip(1, 1e3)
    yield "armature -1", jt("armature", -1.0)
    yield "armature 1e300", jt("armature", 1e300)
    yield "viscous -1", jt("viscous", -1.0, 3)
    yield "coulomb [-1, -1]", jt("coulomb", [-1.0, -1.0], 2)
    yield "coulomb_width 0", jt("coulomb_width", 0.0)
    yield "coulomb_width -0.01", jt("coulomb_width", -0.01)
    yield "offset 1e300", jt("offset", 1e300)
    yield "spring 1e300", jt("spring", [1e300, 0.0, 0.0, 0.0])
    yield "a joint renamed", lambda p: p["joints"].__setitem__(0, "elsewhere")
    yield "another fingerprint", lambda p: p.__setitem__("urdf_fingerprint", "0123456789abcdef")
    yield "one body short", lambda p: p.__setitem__("inertial_parameters", p["inertial_parameters"][:-10])
    yield "one joint short", lambda p: p.__setitem__("joint_terms", p["joint_terms"][:-1])
    yield "input filter -5 Hz", lambda p: (p["data"].__setitem__("input_filter_hz", -5.0), p["summary"].__setitem__("input_filter_hz", -5.0))
    yield "input filter 1e300 Hz", lambda p: (p["data"].__setitem__("input_filter_hz", 1e300), p["summary"].__setitem__("input_filter_hz", 1e300))
    yield "expected error -1", lambda p: p["summary"].__setitem__("expected_false_torque_rms", [-1.0] * len(p["joints"]))
    yield "unknown key", lambda p: p.__setitem__("extra", 1)


def identification_files(env):
    src, urdf, data = env.fx["bax_ident"], env.fx["baxter_urdf"], env.fx["bax"]
    loaders = {
        "evaluate": lambda d: env.cli("evaluate", "--data", data, "--urdf", urdf, "--identification", d / "id.json"),
        "train --nominal": lambda d: env.cli("train", "--data", data, "--urdf", urdf, "--nominal", d / "id.json",
                                             "--nodes", 30, "--folds", 2, "--quiet", "--out", d / "out.broad"),
        "identify --payload": lambda d: env.cli("identify", "--payload", data, "--identification", d / "id.json",
                                                "--urdf", urdf, "--quiet", "--out", d / "out.json"),
        "calibrate-contact": lambda d: env.cli("calibrate-contact", env.fx["bax2"], "--identification", d / "id.json",
                                               "--out", d / "floor.json"),
        "deploy": lambda d: env.cli("deploy", env.root / "scenarios/admittance.toml", "--variant", "momentum",
                                    "--set", "observer.nominal_inertia_scale=1",
                                    "--set", f'observer.identification="{d / "id.json"}"', "--out", d / "deploy"),
    }
    for name, edit in identification_edits():
        def prepare(d, edit=edit):
            write_identification(src, d / "id.json", edit)
        for loader, argv in loaders.items():
            yield Case(f"{loader}: {name}", argv, expect="refuse", prepare=prepare)
        for with_model in (False, True):
            body = f"""
                m = adm.Model.from_urdf({str(urdf)!r}) if {with_model} else None
                ident = adm.load_identification(FX_CASE + "/id.json", m)
                return "loaded: " + str(ident_problem(ident))
            """
            case = py_case(env, f"load_identification{' with m' if with_model else ''}: {name}", body, expect="refuse")
            yield _with_prepare(case, prepare)
        # adm_create on a deployment whose identification is the edited one, manifest recomputed
        def prepare_deploy(d, edit=edit):
            shutil.copytree(env.fx["deploy_hybrid"], d / "deploy")
            write_identification(env.fx["deploy_hybrid"] / "identification.json", d / "deploy/identification.json", edit)
            rewrite_manifest(d / "deploy")
        body = """
            import cabi
            h, err = cabi.create(FX["library"], FX_CASE + "/deploy")
            if h:
                return "adm_create accepted it"
            raise ValueError(err)
        """
        case = py_case(env, f"adm_create: {name}", body, expect="refuse")
        yield _with_prepare(case, prepare_deploy)
    # not JSON numbers
    for name, old, new in (("NaN in the text", '"viscous": ', '"viscous": NaN, "x": '),
                           ("Infinity in the text", '"offset": ', '"offset": Infinity, "y": ')):
        def prepare(d, old=old, new=new):
            (d / "id.json").write_text(Path(src).read_text().replace(old, new, 1))
        yield Case(f"evaluate: {name}", loaders["evaluate"], expect="refuse", prepare=prepare)


def _with_prepare(case, extra):
    inner = case.prepare

    def prepare(d):
        extra(d)
        inner(d)
        (d / "case.py").write_text((d / "case.py").read_text().replace("FX_CASE", repr(str(d))))

    case.prepare = prepare
    return case


# --- files made for another arm or identification ----------------------------------------------


def cross_files(env):
    fx = env.fx
    bax, panda, baxu, pandau = fx["bax"], fx["panda"], fx["baxter_urdf"], fx["panda_urdf"]

    def cli(name, *args, expect="refuse", prepare=None):
        return Case(name, lambda d: env.cli(*[a(d) if callable(a) else a for a in args]), expect=expect,
                    prepare=prepare, check=_no_nonfinite_text)

    out = lambda name: (lambda d: d / name)  # noqa: E731
    yield cli("evaluate: Baxter network on the Panda", "evaluate", "--data", panda, "--urdf", pandau, "--network", fx["bax_net"])
    yield cli("evaluate: Panda network on Baxter", "evaluate", "--data", bax, "--urdf", baxu, "--network", fx["panda_net"])
    yield cli("evaluate: residual of another identification", "evaluate", "--data", bax, "--urdf", baxu,
              "--identification", fx["bax2_ident"], "--residual", fx["bax_resid"])
    yield cli("evaluate: Baxter identification on the Panda", "evaluate", "--data", panda, "--urdf", pandau,
              "--identification", fx["bax_ident"])
    yield cli("evaluate: residual as --network without its identification", "evaluate", "--data", bax, "--urdf", baxu,
              "--network", fx["bax_resid"], expect="any")
    yield cli("evaluate: torque network as --residual", "evaluate", "--data", bax, "--urdf", baxu,
              "--identification", fx["bax_ident"], "--residual", fx["bax_net"])
    yield cli("evaluate (control): own residual", "evaluate", "--data", bax, "--urdf", baxu,
              "--identification", fx["bax_ident"], "--residual", fx["bax_resid"], expect="ok")
    yield cli("evaluate (control): own network", "evaluate", "--data", bax, "--urdf", baxu, "--network", fx["bax_net"], expect="ok")
    for args, name in ((["--from", "1e300"], "--from beyond the data"), (["--from", "nan"], "--from nan"),
                       (["--gain", "0"], "--gain 0"), (["--gain", "-1"], "--gain -1"), (["--gain", "inf"], "--gain inf"),
                       (["--gain", "nan"], "--gain nan"), (["--input-filter-hz", "-1"], "--input-filter-hz -1"),
                       (["--input-filter-hz", "nan"], "--input-filter-hz nan")):
        yield cli(f"evaluate {name}", "evaluate", "--data", bax, "--urdf", baxu, "--identification", fx["bax_ident"], *args)
    yield cli("grow: Panda network with Baxter data", "grow", "--model", fx["panda_net"], "--data", bax, "--urdf", baxu,
              "--nodes", 10, "--quiet", "--out", out("g.broad"))
    yield cli("grow: Panda network with Panda data and the Baxter URDF", "grow", "--model", fx["panda_net"], "--data", panda,
              "--urdf", baxu, "--nodes", 10, "--quiet", "--out", out("g.broad"))
    yield cli("grow: another recording than the one trained on", "grow", "--model", fx["bax_net"], "--data", fx["bax2"],
              "--nodes", 10, "--quiet", "--out", out("g.broad"))

    def shuffled(d):
        header, rows = read_csv(bax)
        random.Random(env.seed).shuffle(rows)
        (d / "shuffled.csv").write_text(_csv_text(header, rows))
    yield cli("grow: the training rows shuffled", "grow", "--model", fx["bax_net"], "--data", out("shuffled.csv"),
              "--nodes", 10, "--quiet", "--out", out("g.broad"), prepare=shuffled)

    def first_half(d):
        header, rows = read_csv(bax)
        (d / "half.csv").write_text(_csv_text(header, rows[: len(rows) // 2]))
    yield cli("grow: half the training rows", "grow", "--model", fx["bax_net"], "--data", out("half.csv"),
              "--nodes", 10, "--quiet", "--out", out("g.broad"), prepare=first_half)
    yield cli("grow: residual with another identification", "grow", "--model", fx["bax_resid"], "--data", bax,
              "--nominal", fx["bax2_ident"], "--nodes", 10, "--quiet", "--out", out("g.broad"))
    yield cli("grow (control): own data", "grow", "--model", fx["bax_net"], "--data", bax, "--nodes", 10, "--quiet",
              "--out", out("g.broad"), expect="ok")
    for nodes in ("0", "-1", "4000000000", "18446744073709551615"):
        yield cli(f"train --nodes {nodes}", "train", "--data", bax, "--urdf", baxu, "--nodes", nodes, "--quiet",
                  "--out", out("t.broad"))
    yield cli("grow --nodes 0", "grow", "--model", fx["bax_net"], "--data", bax, "--nodes", 0, "--quiet", "--out", out("g.broad"))
    for args in (["--folds", "0"], ["--folds", "1"], ["--folds", "100000"], ["--validation-fraction", "0"],
                 ["--validation-fraction", "1"], ["--validation-fraction", "nan"], ["--input-filter-hz", "-4"],
                 ["--max-memory-gb", "nan"], ["--validation", panda]):
        yield cli(f"train {' '.join(map(str, args))}", "train", "--data", bax, "--urdf", baxu, "--nodes", 30, "--quiet",
                  *args, "--out", out("t.broad"))
    yield cli("train: Panda data with the Baxter URDF", "train", "--data", panda, "--urdf", baxu, "--nodes", 30, "--quiet",
              "--out", out("t.broad"))
    yield cli("train --nominal: Baxter identification on the Panda", "train", "--data", panda, "--urdf", pandau,
              "--nominal", fx["bax_ident"], "--nodes", 30, "--quiet", "--out", out("t.broad"))

    def still(d):
        text = next(t for n, t, _ in csv_mutations(env) if n == "no motion")
        (d / "still.csv").write_text(text)
    yield cli("train: motionless data", "train", "--data", out("still.csv"), "--urdf", baxu, "--nodes", 30, "--quiet",
              "--out", out("t.broad"), prepare=still)
    yield cli("train: motionless data, --validation motionless", "train", "--data", out("still.csv"), "--urdf", baxu,
              "--nodes", 30, "--validation", out("still.csv"), "--quiet", "--out", out("t.broad"), prepare=still)
    yield cli("deploy: identification conditioned otherwise than the loop", "deploy", env.root / "scenarios/admittance.toml",
              "--variant", "hybrid", "--set", "observer.training.identify=false", "--set", "observer.nominal_inertia_scale=1",
              "--set", f'observer.identification="{fx["bax_ident"]}"', "--set", f'observer.network="{fx["bax_resid"]}"',
              "--set", "observer.input_filter_hz=10", "--out", out("dep"))
    yield cli("deploy: the Panda network on Baxter", "deploy", env.root / "scenarios/admittance.toml", "--variant", "learned",
              "--set", f'observer.network="{fx["panda_net"]}"', "--out", out("dep"))
    yield cli("deploy: a residual of another identification", "deploy", env.root / "scenarios/admittance.toml",
              "--variant", "hybrid", "--set", "observer.nominal_inertia_scale=1",
              "--set", f'observer.identification="{fx["bax2_ident"]}"', "--set", f'observer.network="{fx["bax_resid"]}"',
              "--out", out("dep"))
    for body, name in (("adm.train(FX['bax'], m, 0)", "nodes=0"), ("adm.train(FX['bax'], m, -3)", "nodes=-3"),
                       ("adm.train(still, m, 30)", "motionless data"),
                       ("adm.train(FX['bax'], m, 30, nominal=adm.load_identification(FX['bax_ident'], mp))", "Baxter data, Panda nominal"),
                       ("adm.identify(still, m)", "identify motionless")):
        yield py_case(env, f"python {name}", f"""
            m = adm.Model.from_urdf(FX["baxter_urdf"])
            mp = adm.Model.from_urdf(FX["panda_urdf"])
            d = load_csv(FX["bax"])
            still = {{k: (np.repeat(v[:1], len(v), axis=0) if k in ("q", "tau") else (v if k == "t" else np.zeros_like(v))) for k, v in d.items()}}
            r = {body}
            return f"returned {{type(r).__name__}}"
        """, expect="refuse")


# --- special files and planted links ---------------------------------------------------------


def _fifo(path):
    os.mkfifo(path)


def special_files(env):
    fx = env.fx
    baxu, bax = fx["baxter_urdf"], fx["bax"]
    t = 30.0

    def case(name, argv, prepare, expect="refuse", after=None):
        return Case(name, argv, expect=expect, prepare=prepare, timeout=t, after=after)

    fifo = lambda name: (lambda d: _fifo(d / name))  # noqa: E731
    yield case("import: a FIFO .mcap", lambda d: env.cli("import", d / "bag.mcap", "--profile", "franka", "--out", d / "o.csv"), fifo("bag.mcap"))

    def bag_folder(kind):
        def prep(d):
            (d / "bag").mkdir()
            src = fx["bags"] / "franka_zstd"
            if kind == "metadata":
                _fifo(d / "bag/metadata.yaml")
                shutil.copy(src / "franka_zstd.mcap", d / "bag")
            elif kind == "mcap":
                shutil.copy(src / "metadata.yaml", d / "bag")
                _fifo(d / "bag/franka_zstd.mcap")
            else:
                shutil.copy(src / "metadata.yaml", d / "bag")
                os.symlink("/dev/zero", d / "bag/franka_zstd.mcap")
        return prep
    for kind in ("metadata", "mcap", "devzero"):
        # metadata.yaml is not read (docs/import.md): a FIFO there may import the .mcap beside it
        yield case(f"import: bag folder whose {kind} is special",
                   lambda d: env.cli("import", d / "bag", "--profile", "franka", "--out", d / "o.csv"), bag_folder(kind),
                   expect="any" if kind == "metadata" else "refuse",
                   after=lambda d: csv_problem(d / "o.csv") if (d / "o.csv").exists() else None)
    yield case("import: /dev/zero", lambda d: env.cli("import", "/dev/zero", "--profile", "franka", "--out", d / "o.csv"), None)
    yield case("import: --profile FIFO", lambda d: env.cli("import", fx["bags"] / "franka_zstd", "--profile", d / "p.toml",
                                                            "--out", d / "o.csv"), fifo("p.toml"))
    yield case("import: --profile /dev/zero", lambda d: env.cli("import", fx["bags"] / "franka_zstd", "--profile", "/dev/zero",
                                                                 "--out", d / "o.csv"), None)
    for cmd in ("identify", "train", "evaluate", "excite"):
        def args(d, cmd=cmd, what="data"):
            data = d / "f.csv" if what == "data" else bax
            urdf = d / "f.urdf" if what == "urdf" else baxu
            a = {"identify": ["identify", "--data", data, "--urdf", urdf, "--quiet", "--out", d / "o.json"],
                 "train": ["train", "--data", data, "--urdf", urdf, "--nodes", 30, "--quiet", "--out", d / "o.broad"],
                 "evaluate": ["evaluate", "--data", data, "--urdf", urdf],
                 "excite": ["excite", "--urdf", urdf, "--duration", 5, "--out", d / "o.csv"]}[cmd]
            return env.cli(*a)
        if cmd != "excite":
            yield case(f"{cmd}: --data FIFO", args, fifo("f.csv"))
            yield case(f"{cmd}: --data /dev/zero", args, lambda d: os.symlink("/dev/zero", d / "f.csv"))
        yield case(f"{cmd}: --urdf FIFO", lambda d, cmd=cmd: args(d, cmd, "urdf"), fifo("f.urdf"))
        yield case(f"{cmd}: --urdf /dev/zero", lambda d, cmd=cmd: args(d, cmd, "urdf"),
                   lambda d: os.symlink("/dev/zero", d / "f.urdf"))

    def ident_naming(special):
        def prep(d):
            if special == "fifo":
                _fifo(d / "arm.urdf")
            else:
                os.symlink("/dev/zero", d / "arm.urdf")
            write_identification(fx["bax_ident"], d / "id.json", lambda p: p.__setitem__("urdf", str(d / "arm.urdf")))
        return prep
    for special in ("fifo", "devzero"):
        yield case(f"identify --payload: identification naming a {special} URDF",
                   lambda d: env.cli("identify", "--payload", bax, "--identification", d / "id.json", "--urdf", baxu,
                                     "--quiet", "--out", d / "o.json"), ident_naming(special), expect="any")
        yield case(f"calibrate-contact: identification naming a {special} URDF",
                   lambda d: env.cli("calibrate-contact", fx["bax2"], "--identification", d / "id.json", "--out", d / "f.json"),
                   ident_naming(special))
        c = py_case(env, f"load_identification: naming a {special} URDF",
                    "adm.load_identification(FX_CASE + '/id.json')\nreturn 'loaded'", expect="refuse", timeout=t)
        yield _with_prepare(c, ident_naming(special))
    yield case("evaluate: --identification FIFO", lambda d: env.cli("evaluate", "--data", bax, "--urdf", baxu,
                                                                     "--identification", d / "i.json"), fifo("i.json"))
    yield case("evaluate: --network FIFO", lambda d: env.cli("evaluate", "--data", bax, "--urdf", baxu,
                                                              "--network", d / "n.broad"), fifo("n.broad"))
    yield case("grow: --model /dev/zero", lambda d: env.cli("grow", "--model", "/dev/zero", "--data", bax, "--nodes", 5,
                                                             "--out", d / "g.broad"), None)
    # the C ABI and RobotLoop on a deployment folder with a special file
    for member in ("loop.toml", "arm.urdf", "identification.json", "observer.broad", "manifest.json"):
        for special in ("fifo", "devzero"):
            def prep(d, member=member, special=special):
                shutil.copytree(fx["deploy_hybrid"], d / "deploy")
                (d / "deploy" / member).unlink()
                if special == "fifo":
                    _fifo(d / "deploy" / member)
                else:
                    os.symlink("/dev/zero", d / "deploy" / member)
            body = """
                import cabi
                h, err = cabi.create(FX["library"], FX_CASE + "/deploy")
                if h:
                    return "adm_create accepted it"
                raise ValueError(err)
            """
            yield _with_prepare(py_case(env, f"adm_create: {member} is a {special}", body, expect="refuse", timeout=t), prep)
            yield _with_prepare(py_case(env, f"RobotLoop.load: {member} is a {special}",
                                        "adm.RobotLoop.load(FX_CASE + '/deploy')\nreturn 'loaded'", expect="refuse", timeout=t), prep)
    for what in ("fifo", "devzero"):
        def prep(d, what=what):
            if what == "fifo":
                _fifo(d / "x")
            else:
                os.symlink("/dev/zero", d / "x")
        for call in ("adm.import_bag(X, 'franka')", "adm.Model.from_urdf(X)", "adm.identify(X, adm.Model.from_urdf(FX['baxter_urdf']))",
                     "adm.load_network(X)", "adm.load_identification(X)"):
            body = f"X = FX_CASE + '/x'\n{call}\nreturn 'accepted'"
            yield _with_prepare(py_case(env, f"python {call.split('(')[0]}: {what}", body, expect="refuse", timeout=t), prep)
    yield from _planted_links(env)
    yield _deploy_into_linked_folder(env)


TEMP_GUESSES = ("{n}.tmp", ".{n}.tmp", ".{n}.tmp-0000000000000000", "{n}~", ".{n}.swp", "{n}.partial",
                ".{n}.partial", "{n}.part", "{n}.new")


def _planted_links(env):
    """Links at the output itself and at names a temporary file might have: the tool must
    neither write through them nor create their targets."""
    fx = env.fx
    writers = {
        "excite": (lambda d: env.cli("excite", "--urdf", fx["baxter_urdf"], "--duration", 4, "--iterations", 20, "--out", d / "out.csv"), "out.csv"),
        "identify": (lambda d: env.cli("identify", "--data", fx["bax"], "--urdf", fx["baxter_urdf"], "--folds", 2, "--quiet",
                                       "--out", d / "out.json"), "out.json"),
        "train": (lambda d: env.cli("train", "--data", fx["bax"], "--urdf", fx["baxter_urdf"], "--nodes", 30, "--folds", 2,
                                    "--quiet", "--out", d / "out.broad"), "out.broad"),
        "grow": (lambda d: env.cli("grow", "--model", fx["bax_net"], "--data", fx["bax"], "--nodes", 5, "--quiet",
                                   "--out", d / "out.broad"), "out.broad"),
        "import": (lambda d: env.cli("import", fx["bags"] / "franka_zstd", "--profile", "franka", "--out", d / "out.csv"), "out.csv"),
        "calibrate-contact": (lambda d: env.cli("calibrate-contact", fx["bax2"], "--identification", fx["bax_ident"],
                                                "--out", d / "out.json"), "out.json"),
        "report": (lambda d: env.cli("report", d / "run", "--quiet"), "run/report.html"),
        "report (report.md)": (lambda d: env.cli("report", d / "run", "--quiet"), "run/report.md"),
        "report (summary.json)": (lambda d: env.cli("report", d / "run", "--quiet"), "run/summary.json"),
        "report (recording.mcap)": (lambda d: env.cli("report", d / "run", "--quiet"), "run/recording.mcap"),
        "deploy": (lambda d: env.cli("deploy", env.root / "scenarios/admittance.toml", "--variant", "momentum",
                                     "--out", d / "dep"), "dep"),
        "python Identification.save": (None, "out.json"),
        "python Network.save": (None, "out.broad"),
    }
    for tool, (argv, target) in writers.items():
        for mode in ("output is a link to a file", "output is a dangling link", "links at temporary names"):
            def prepare(d, target=target, mode=mode, tool=tool):
                if tool.startswith("report"):
                    shutil.copytree(fx["run"], d / "run")
                (d / "victim.txt").write_text("precious\n")
                out = d / target
                if mode.startswith("output is a link to a file"):
                    if out.exists():
                        out.unlink()
                    os.symlink(d / "victim.txt", out)
                elif mode == "output is a dangling link":
                    if out.exists():
                        out.unlink()
                    os.symlink(d / "created.txt", out)
                else:
                    for i, g in enumerate(TEMP_GUESSES):
                        os.symlink(d / f"victim{i}.txt", out.parent / g.format(n=out.name))
                        (d / f"victim{i}.txt").write_text("precious\n")

            def after(d):
                for v in [d / "victim.txt"] + [d / f"victim{i}.txt" for i in range(len(TEMP_GUESSES))]:
                    if v.exists() and v.read_text() != "precious\n":
                        return f"wrote through a link into {v.name}"
                if (d / "created.txt").exists():
                    return "created the target of a dangling link"
                return None
            if argv is None:
                save = ("adm.identify(FX['bax'], m).save(OUT)" if "Identification" in tool
                        else "adm.train(FX['bax'], m, 30).save(OUT)")
                body = f"m = adm.Model.from_urdf(FX['baxter_urdf'])\nOUT = FX_CASE + '/{target}'\n{save}"
                yield _with_prepare(_after(py_case(env, f"{tool}: {mode}", body), after), prepare)
            else:
                yield Case(f"{tool}: {mode}", argv, expect="any", prepare=prepare, after=after)


def _deploy_into_linked_folder(env):
    """`deploy --out` naming a link to a folder of the user's: refused or replaced, never
    written into."""
    def prepare(d):
        (d / "mine").mkdir()
        (d / "mine/victim.txt").write_text("precious\n")
        os.symlink(d / "mine", d / "dep")

    def after(d):
        names = sorted(p.name for p in (d / "mine").iterdir())
        if names != ["victim.txt"] or (d / "mine/victim.txt").read_text() != "precious\n":
            return f"wrote into the linked folder: {names}"
        return None
    return Case("deploy: --out is a link to a folder of the user's",
                lambda d: env.cli("deploy", env.root / "scenarios/admittance.toml", "--variant", "momentum", "--out", d / "dep"),
                prepare=prepare, after=after)


def _after(case, after):
    case.after = after
    return case
