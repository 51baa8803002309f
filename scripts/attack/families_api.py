"""The families that call the loop and the library: absurd samples through the C ABI (ctypes
on the built cdylib) and Python's RobotLoop, and bad arrays through the Python API."""
import textwrap

from common import py_case


def B(*parts):
    """A case body from parts each indented on its own."""
    return "\n".join(textwrap.dedent(p).strip("\n") for p in parts)

# (name, inject body for (k, inp), first hit step, last hit step, input flags, must be flagged)
INJECTIONS = [
    ("one torque 1e300", "if k == 1000: inp['tau'][1] = 1e300", 1000, 1000, "IN_TAU", True),
    ("one torque -1e300", "if k == 1000: inp['tau'][1] = -1e300", 1000, 1000, "IN_TAU", True),
    ("one torque 1e20", "if k == 1000: inp['tau'][4] = 1e20", 1000, 1000, "IN_TAU", True),
    ("one torque 1e4 (beyond 3x the effort limit)", "if k == 1000: inp['tau'][0] = 1e4", 1000, 1000, "IN_TAU", True),
    ("every torque 1e300", "if k == 1000: inp['tau'][:] = 1e300", 1000, 1000, "IN_TAU", True),
    ("one angle 1e20", "if k == 1000: inp['q'][3] = 1e20", 1000, 1000, "IN_TAU", True),
    ("one angle -1e20", "if k == 1000: inp['q'][3] = -1e20", 1000, 1000, "IN_TAU", True),
    ("one angle 1e3", "if k == 1000: inp['q'][2] = 1e3", 1000, 1000, "IN_TAU", True),
    ("one angle jumps 0.5 rad", "if k == 1000: inp['q'][1] += 0.5", 1000, 1000, "IN_TAU", True),
    ("one angle 1e300 without measured torque", "if k == 1000: inp['q'][3] = 1e300", 1000, 1000, "0", True),
    ("one velocity 1e300 (measured qdot)", "if k == 1000: inp['qdot'][2] = 1e300", 1000, 1000, "IN_TAU | IN_QDOT", True),
    ("50 NaN angles", "if 1000 <= k < 1050: inp['q'][3] = float('nan')", 1000, 1049, "IN_TAU", True),
    ("50 infinite torques", "if 1000 <= k < 1050: inp['tau'][5] = float('inf')", 1000, 1049, "IN_TAU", True),
    ("random NaN, inf and 1e300 bursts for 2 s", """
        import random
        r = random.Random(k // 20)
        if 1000 <= k < 3000 and r.random() < 0.3:
            f = r.choice(['q', 'tau', 'qdot'])
            inp[f][r.randrange(7)] = r.choice([float('nan'), float('inf'), -float('inf'), 1e300, -1e300])
    """, 1000, 2999, "IN_TAU | IN_QDOT", False),
    ("one desired angle 1e300", "inp['q_d'] = POSE.copy()\nif k == 1000: inp['q_d'][3] = 1e300", 1000, 1000, "IN_TAU", False),
    ("desired angles NaN for 10 steps", "inp['q_d'] = POSE.copy()\nif 1000 <= k < 1010: inp['q_d'][0] = float('nan')", 1000, 1009, "IN_TAU", True),
    ("time NaN once", "if k == 1000: inp['t'] = float('nan')", 1000, 1000, "IN_TAU", True),
    ("time 1 s back once", "if k == 1000: inp['t'] -= 1.0", 1000, 1000, "IN_TAU", False),
    ("time a day ahead once", "if k == 1000: inp['t'] += 86400.0", 1000, 1000, "IN_TAU", False),
    ("angles repeated for 15 ms (a driver repeating its last packet)", """
        if k == 1000:
            FROZEN[:] = inp['q']
        if 1000 <= k < 1015:
            inp['q'][:] = FROZEN
    """, 1001, 1014, "IN_TAU", "'any'"),
    ("six joints once", "if k == 1000: inp['n'] = 6", 1000, 1000, "IN_TAU", True),
]


def _attack_body(front, deploy, inject, first, last, flags, must_flag, steps):
    return B("import cabi", "from cabi import IN_TAU, IN_QDOT, POSE", "FROZEN = np.zeros(7)",
             "def inject(k, inp):\n" + textwrap.indent(textwrap.dedent(inject).strip("\n"), "    "),
             f"h = cabi.Harness(FX['library'], FX[{deploy!r}], front={front!r}, steps={steps})",
             f"return h.attack(inject, {first}, {last}, flags={flags}, must_flag={must_flag})")


def c_abi(env):
    for kind in ("momentum", "learned", "hybrid"):
        for name, inject, first, last, flags, must_flag in INJECTIONS:
            steps = 5000 if last > 2000 else 3000
            for front in ("c", "py"):
                if front == "py" and name.startswith("six joints"):
                    continue
                label = "adm_step" if front == "c" else "RobotLoop.step"
                yield py_case(env, f"{label} {kind}: {name}",
                              _attack_body(front, f"deploy_{kind}", inject, first, last, flags, must_flag, steps),
                              expect="ok")
    refusals = [("abi_version 1", "None", "abi=1"), ("6 joints", "None", "n=6"), ("null path", "None", "deploy_none=True"),
                ("missing folder", "None", "missing=True"), ("a scenario file", "None", "scenario=True"),
                ("observer.kind=oracle", "'observer.kind=\"oracle\"'", ""), ("control_rate_hz=0", "'control_rate_hz=0'", ""),
                ("control_rate_hz=1e300", "'control_rate_hz=1e300'", ""), ("control_rate_hz=nan", "'control_rate_hz=nan'", ""),
                ("gates torque_factor=-1", "'signals.gates.torque_factor=-1'", ""),
                ("gates angle_margin=nan", "'signals.gates.angle_margin=nan'", ""),
                ("filter_cutoff_hz=-5", "'signals.filter_cutoff_hz=-5'", ""),

                ("kp negative", "'controller.pd.kp=[-100, 150, 50, 50, 10, 10, 2]'", ""),
                ("damping 0", "'admittance.damping=[0, 1e4, 1e4, 1e4, 1e4, 1e4, 1e4]'", ""),
                ("garbage override", "'= = ='", "")]
    yield py_case(env, "adm_create: kp of 1e300 (accepted or refused; the command stays within the limits)", """
        import cabi
        h, err = cabi.create(FX["library"], FX["deploy_momentum"], overrides="controller.pd.kp=[1e300, 150, 50, 50, 10, 10, 2]")
        if not h:
            raise ValueError(err)
    """)
    for name, overrides, extra in refusals:
        kw = {"abi=1": "abi=1", "n=6": "n=6"}.get(extra, "")
        path = ("None" if extra == "deploy_none=True" else "FX['root'] + '/nonexistent'" if extra == "missing=True"
                else "FX['root'] + '/scenarios/admittance.toml'" if extra == "scenario=True" else "FX['deploy_momentum']")
        yield py_case(env, f"adm_create: {name}", f"""
            import cabi
            h, err = cabi.create(FX["library"], {path}, overrides={overrides}{', ' + kw if kw else ''})
            if h:
                return "adm_create accepted it"
            if not err or len(err.splitlines()) > 2:
                return "refused without a one-line message: " + repr(err)
            raise ValueError(err)
        """, expect="refuse")


def python_api(env):
    setup = """
        m = adm.Model.from_urdf(FX["baxter_urdf"])
        q0 = np.array([0.0, -1.0, 1.19, 1.94, -0.67, 1.03, -0.5])
        z = np.zeros(7)
    """
    dyn = [  # (name, call with Q standing for the attacked q, how the clean call compares)
        ("int angles", "np.zeros(7, dtype=int)", "same"),
        ("float32 angles", "q0.astype(np.float32)", "close"),
        ("bool angles", "np.ones(7, dtype=bool)", "any"),
        ("string angles", "np.array(['a'] * 7)", "refuse"),
        ("object angles", "np.array([object()] * 7)", "refuse"),
        ("complex angles", "q0 + 1j", "refuse"),
        ("non-contiguous angles", "np.repeat(q0, 2)[::2]", "same"),
        ("reversed-stride angles", "q0[::-1].copy()[::-1]", "same"),
        ("2-D angles", "q0.reshape(7, 1)", "refuse"),
        ("6 angles", "q0[:6]", "refuse"),
        ("a list of floats", "list(q0)", "same"),
        ("a None", "None", "refuse"),
        ("NaN angle", "np.where(np.arange(7) == 2, np.nan, q0)", "refuse-or-finite"),
        ("inf angle", "np.where(np.arange(7) == 2, np.inf, q0)", "refuse-or-finite"),
        ("1e300 angle", "np.where(np.arange(7) == 2, 1e300, q0)", "refuse-or-finite"),
    ]
    for fn in ("rnea", "gravity", "crba"):
        for name, expr, how in dyn:
            call = {"rnea": "adm.rnea(m, Q, z, z)", "gravity": "adm.gravity(m, Q)", "crba": "adm.crba(m, Q)"}[fn]
            clean = call.replace("Q", "np.asarray(Q, dtype=float) if Q is not None else q0")
            check = {"same": f"return differs(r, {clean}, 0.0)", "close": f"return differs(r, {clean}, 1e-5)",
                     "any": "return nonfinite(r)", "refuse": "return 'accepted: ' + repr(r)[:80]",
                     "refuse-or-finite": "return nonfinite(r)"}[how]
            yield py_case(env, f"adm.{fn}: {name}", B(setup, f"""
                Q = {expr}
                r = {call}
                {check}
            """), expect="refuse" if how == "refuse" else "any")
    obs_setup = setup + """
        ident = adm.load_identification(FX["bax_ident"], m)
        net = adm.load_network(FX["bax_net"])
        resid = adm.load_network(FX["bax_resid"])
        make = {
            "momentum": lambda: adm.MomentumObserver(m, gain=50.0),
            "learned": lambda: adm.LearnedObserver(net, 5.0),
            "hybrid": lambda: adm.HybridObserver(ident, resid, gain=50.0),
        }[KIND]
        tau0 = adm.rnea(m, q0, z, z)
        def feed(o, k, q=None, tau=None, dt=1e-3, qdot=None):
            return o.update(k * 1e-3, q0 if q is None else q, z if qdot is None else qdot, z, tau0 if tau is None else tau, dt)
    """
    obs_attacks = [
        ("NaN torque", "feed(o, 100, tau=np.full(7, np.nan))", "fault"),
        ("inf angle", "feed(o, 100, q=np.where(np.arange(7) == 1, np.inf, q0))", "fault"),
        ("dt 0", "feed(o, 100, dt=0.0)", "fault"),
        ("dt -1", "feed(o, 100, dt=-1.0)", "fault"),
        ("dt NaN", "feed(o, 100, dt=float('nan'))", "fault"),
        ("torque 1e300", "feed(o, 100, tau=np.full(7, 1e300))", "finite"),
        ("velocity 1e300", "feed(o, 100, qdot=np.full(7, 1e300))", "finite"),
        ("int torque", "feed(o, 100, tau=np.zeros(7, dtype=int))", "finite"),
        ("string torque", "feed(o, 100, tau=np.array(['x'] * 7))", "refuse"),
        ("non-contiguous torque", "feed(o, 100, tau=np.repeat(tau0, 3)[::3])", "same"),
        ("5 torques", "feed(o, 100, tau=tau0[:5])", "refuse"),
        ("out= float32", "o.update(0.1, q0, z, z, tau0, 1e-3, out=np.zeros(7, dtype=np.float32))", "refuse"),
        ("out= non-contiguous", "o.update(0.1, q0, z, z, tau0, 1e-3, out=np.zeros(14)[::2])", "any"),
        ("out= read-only", "(lambda a: (a.setflags(write=False), o.update(0.1, q0, z, z, tau0, 1e-3, out=a))[1])(np.zeros(7))", "refuse"),
    ]
    for kind in ("momentum", "learned", "hybrid"):
        for name, expr, how in obs_attacks:
            base = obs_setup.replace("KIND", repr(kind))
            if how == "refuse":
                body = B(base, "o = make()", f"r = {expr}", "return 'accepted: ' + repr(r)[:80]")
            else:
                first = {"fault": "if o.fault is None or nonfinite(r): return f'no fault, estimate {r}'",
                         "finite": "p = nonfinite(r)\nif p: return p",
                         "same": "o2 = make()\nfor k in range(100): feed(o2, k)\np = differs(r, feed(o2, 100), 0.0)\nif p: return p",
                         "any": "p = nonfinite(r)\nif p: return p"}[how]
                recover = "" if kind == "learned" or how not in ("fault", "finite") else f"""
                    after = [feed(o, k) for k in range(101, 1200)][-1]
                    o3 = make()
                    ref = [feed(o3, k) for k in range(0, 1200)][-1]
                    if np.max(np.abs(after - ref)) > 1e-3:
                        return f"estimate {{np.max(np.abs(after - ref)):.3g}} N m off a clean run 1.1 s later"
                """
                body = B(base, "o = make()", "for k in range(100): feed(o, k)", f"r = {expr}", first, recover, "return None")
            yield py_case(env, f"{kind} observer: {name}", body, expect="refuse" if how == "refuse" else "any")
    # identify and train on arrays
    data_setup = setup + """
        d = load_csv(FX["bax"])
        def edit(key, fn):
            e = {k: v.copy() for k, v in d.items()}
            e[key] = fn(e[key])
            return e
    """
    data_attacks = [
        ("int torque", "edit('tau', lambda a: a.astype(int))", "any"),
        ("float32 everything", "{k: v.astype(np.float32) for k, v in d.items()}", "any"),
        ("non-contiguous q", "edit('q', lambda a: np.repeat(a, 2, axis=1)[:, ::2])", "same"),
        ("Fortran-ordered tau", "edit('tau', np.asfortranarray)", "same"),
        ("string t", "edit('t', lambda a: a.astype(str))", "refuse"),
        ("NaN torque", "edit('tau', lambda a: np.where(np.arange(len(a))[:, None] == 50, np.nan, a))", "refuse"),
        ("inf velocity", "edit('qdot', lambda a: np.where(np.arange(len(a))[:, None] == 50, np.inf, a))", "refuse"),
        ("torque x 1e300", "edit('tau', lambda a: a * 1e300)", "refuse"),
        ("velocities 1e306 in 20 rows", "edit('qdot', lambda a: np.where((np.arange(len(a))[:, None] >= 100) & (np.arange(len(a))[:, None] < 120), 1e306, a))", "refuse"),
        ("torque rows short by one", "edit('tau', lambda a: a[:-1])", "refuse"),
        ("6 joints of torque", "edit('tau', lambda a: a[:, :6])", "refuse"),
        ("empty", "{k: v[:0] for k, v in d.items()}", "refuse"),
        ("all-zero torque", "edit('tau', np.zeros_like)", "any"),
        ("sign-flipped torque", "edit('tau', lambda a: -a)", "any"),
        ("t decreasing", "edit('t', lambda a: a[::-1].copy())", "refuse"),
    ]
    for fn in ("identify", "train"):
        for name, expr, how in data_attacks:
            call = "adm.identify(X, m)" if fn == "identify" else "adm.train(X, m, 30, seed=1, folds=2)"
            value = ("ident_problem(r)" if fn == "identify"
                     else "nonfinite(r.predict(d['q'][:50], d['qdot'][:50], d['qddot'][:50]) if hasattr(r, 'predict') else [0])")
            check = {"any": f"return {value}",
                     "same": f"p = {value}\n                if p: return p\n                "
                             + ("return differs(r.predict(q0, z, z), " + call.replace("X", "d") + ".predict(q0, z, z), 1e-9)"),
                     "refuse": "return 'accepted'"}[how]
            yield py_case(env, f"adm.{fn}: {name}", B(data_setup, f"""
                X = {expr}
                r = {call}
                {check}
            """), expect="refuse" if how == "refuse" else "any")
    yield py_case(env, "Identification.predict: NaN row", B(setup, """
        ident = adm.load_identification(FX["bax_ident"], m)
        r = ident.predict(np.full(7, np.nan), z, z)
        return nonfinite(r)
    """))
    yield py_case(env, "Identification.predict: non-contiguous rows", B(setup, """
        ident = adm.load_identification(FX["bax_ident"], m)
        d = load_csv(FX["bax"])
        q = np.asfortranarray(d["q"][:100])
        return differs(ident.predict(q, d["qdot"][:100], d["qddot"][:100]), ident.predict(np.ascontiguousarray(q), d["qdot"][:100], d["qddot"][:100]), 0.0)
    """))
    yield py_case(env, "RobotLoop.step: int angles", B(setup, """
        L = adm.RobotLoop.load(FX["deploy_momentum"]); L2 = adm.RobotLoop.load(FX["deploy_momentum"])
        qi = np.round(q0).astype(int)
        a = L.step(0.0, qi, np.zeros(7)); b = L2.step(0.0, qi.astype(float), np.zeros(7))
        return differs(a[0], b[0], 0.0)
    """))
    yield py_case(env, "RobotLoop.step: non-contiguous angles", B(setup, """
        L = adm.RobotLoop.load(FX["deploy_momentum"]); L2 = adm.RobotLoop.load(FX["deploy_momentum"])
        a = L.step(0.0, np.repeat(q0, 2)[::2], np.zeros(7)); b = L2.step(0.0, q0, np.zeros(7))
        return differs(a[0], b[0], 0.0)
    """))
    for name, expr in (("string angles", "np.array(['a'] * 7)"), ("8 angles", "np.zeros(8)"), ("2-D angles", "np.zeros((7, 1))"),
                       ("time NaN", None)):
        call = "L.step(float('nan'), q0, np.zeros(7))" if expr is None else f"L.step(0.0, {expr}, np.zeros(7))"
        yield py_case(env, f"RobotLoop.step: {name}", B(setup, f"""
            L = adm.RobotLoop.load(FX["deploy_momentum"])
            r = {call}
            if {expr is None} and not L.status["ok"]:
                return None
            return "accepted: " + repr(r)[:80]
        """), expect="any" if expr is None else "refuse")
