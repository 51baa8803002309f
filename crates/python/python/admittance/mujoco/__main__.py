"""``python -m admittance.mujoco``: experiment B on a MuJoCo plant (see the package docs)."""

import argparse
import sys

import admittance as adm

#: What the co-simulation needs beyond the package, and the one line that says how to get it.
MISSING_MUJOCO = (
    "admittance.mujoco: the co-simulation needs MuJoCo, which is not installed; "
    "install the package's `mujoco` extra: pip install './crates/python[mujoco]'"
)


def main(argv=None):
    """The command; returns its exit code (docs/python.md): 0 done, 1 a variant failed,
    2 bad arguments or MuJoCo missing, 3 a bad input or output path, 130 interrupted."""
    try:
        return _main(argv)
    except KeyboardInterrupt:
        # Nothing is written before the last step, and the run folder appears only complete
        # (a hidden sibling renamed into place): an interrupted run leaves the --out folder
        # as it was.
        print("admittance.mujoco: interrupted (Ctrl-C); the --out folder was not written or changed",
              file=sys.stderr)
        return 130


def _log_line(text):
    from admittance import _progress

    _progress.log_line(text)


def _main(argv):
    from ._cosim import VARIANTS, CosimConfig, run_cosimulation

    p = argparse.ArgumentParser(
        prog="python -m admittance.mujoco",
        description="Experiment B (observers driving the admittance model) on the arm's URDF simulated by MuJoCo, "
        "with joint friction, damping and armature the controller and observers do not know.",
    )
    p.add_argument("--urdf", required=True, help="the arm's URDF")
    p.add_argument("--base", help="base link (default: the URDF's root)")
    p.add_argument("--tip", help="the hand link (default: as `admittance model` finds it, the end of the URDF's chain)")
    p.add_argument("--out", required=True, help="the run folder to write (refused if it holds files this tool did not write)")
    p.add_argument("--contact", choices=["push", "wall"], default="push")
    p.add_argument("--duration", type=float, default=30.0, help="seconds of the admittance experiment per variant (30)")
    p.add_argument("--training-duration", type=float, default=450.0, help="seconds of free-motion data (450, as experiment B)")
    p.add_argument("--validation-duration", type=float, default=90.0)
    p.add_argument("--nodes", type=int, default=adm.DEFAULT_NODES, help=f"nodes of each network ({adm.DEFAULT_NODES})")
    p.add_argument("--width-scale", type=float, default=2.0, help="Gaussian widths: this times the mean distance to the nearest centres (2, as admittance train)")
    p.add_argument("--push-force", type=float, default=10.0, help="peak of the scripted push at the hand, N (10)")
    p.add_argument("--friction-scale", type=float, default=1.0, help="scales the unknown joint friction, damping and armature (1)")
    p.add_argument("--variant", "--variants", dest="variant", action="append", metavar="NAME",
                   help="a variant to run, repeated for more (or comma-separated), of " + ", ".join(VARIANTS)
                   + " (default: all, in this order)")
    p.add_argument("--training-motion", choices=["excitation", "multisine"], default="excitation",
                   help="free-motion data on the optimised excitation (default) or on a multi-sine about the pose (the recipe before issue 22)")
    p.add_argument("--hybrid-nominal", choices=["identified", "nominal"], default="identified",
                   help="the hybrid on the identification (default) or on the 0.8-inertia URDF (before issue 22)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--force", action="store_true", help="replace an --out folder this tool did not write")
    p.add_argument("--quiet", action="store_true", help="no progress on the terminal")
    a = p.parse_args(argv)
    if a.quiet:
        from admittance import _progress

        _progress.set_quiet(True)
    # Without the identification (--hybrid-nominal nominal) there is no momentum_identified.
    default = VARIANTS if a.hybrid_nominal == "identified" else [v for v in VARIANTS if v != "momentum_identified"]
    if a.hybrid_nominal == "nominal" and a.variant and any("momentum_identified" in v for v in a.variant):
        p.error("--variant momentum_identified needs the identification: drop --hybrid-nominal nominal")
    variants = []
    for v in (name for arg in (a.variant or default) for name in arg.split(",") if name):
        if v not in variants:
            variants.append(v)
    unknown = [v for v in variants if v not in VARIANTS]
    if unknown:
        p.error(f"--variant: unknown {unknown}; choose among {VARIANTS}")
    for name in ("duration", "training_duration", "validation_duration", "friction_scale", "push_force", "width_scale"):
        value = getattr(a, name)
        if not (value == value and 0 < value < 1e6):
            p.error(f"--{name.replace('_', '-')} {value}: must be a positive number")
    if a.nodes < 1:
        p.error("--nodes must be at least 1")
    try:
        import mujoco  # noqa: F401  (the plant; imported again where it is used)
    except ImportError:
        print(MISSING_MUJOCO, file=sys.stderr)
        return 2
    cfg = CosimConfig(
        urdf=a.urdf, base=a.base, tip=a.tip, out=a.out, contact=a.contact, duration=a.duration,
        training_duration=a.training_duration, validation_duration=a.validation_duration,
        nodes=a.nodes, friction_scale=a.friction_scale, push_force=a.push_force, width_scale=a.width_scale, seed=a.seed, force=a.force, variants=variants,
        training_motion=a.training_motion, hybrid_nominal=a.hybrid_nominal,
    )
    try:
        summary = run_cosimulation(cfg, log=_log_line)
    except (OSError, ValueError) as e:
        print(f"admittance.mujoco: {e}", file=sys.stderr)
        return 3
    if summary["failures"]:
        # As `admittance run`: 1 when a variant's numbers are not usable (it diverged or a
        # metric is not finite), 4 when the run finished but broke another health rule.
        stopping = {"divergence", "nonfinite_metric"}
        rules = {
            v.get("rule")
            for h in summary.get("health", {}).get("variants", {}).values()
            for v in h.get("verdicts", [])
            if v.get("severity") == "failure"
        }
        code = 1 if rules & stopping or not rules else 4
        print("admittance.mujoco: the run failed: " + "; ".join(summary["failures"]) + f"; {a.out} holds what ran (exit {code})", file=sys.stderr)
        return code
    print(f"wrote {a.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
