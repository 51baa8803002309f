"""``python -m admittance.mujoco.arms``: every single-arm description of example-robot-data
on the MuJoCo plant, trained on 60 s of excitation, evaluated on other motion with pushes
and in free motion (the module ``_arms`` says how; docs/experiments.md has the table)."""

import argparse
import math
import sys

import admittance as adm


def main(argv=None):
    p = argparse.ArgumentParser(
        prog="python -m admittance.mujoco.arms",
        description="Every single-arm URDF of example-robot-data on MuJoCo: identification, the paper's "
        "network, the friction-input network and the hybrid, trained on excitation, judged on other motion.",
    )
    p.add_argument("--out", default="runs/mujoco_arms", help="folder for results.json and table.md")
    p.add_argument("--arms", help="comma-separated subset (default: all; with --urdf, that arm alone)")
    p.add_argument("--urdf", help="your own arm's URDF, run with the table's plant, recordings and scoring")
    p.add_argument("--base", help="with --urdf: the chain's base link (default: the URDF's root)")
    p.add_argument("--tip", help="with --urdf: the chain's tip link (default: the end of the only chain)")
    p.add_argument("--name", help="with --urdf: the arm's name in the table and its folder (default: the file's stem)")
    p.add_argument("--training-duration", type=float, default=60.0)
    p.add_argument("--evaluation-duration", type=float, default=30.0)
    p.add_argument("--validation-duration", type=float, default=20.0, help="seconds of a third excitation (seed 3) that chooses every setting; 0: none (one recording: blocked cross-validation chooses, and the estimate low-pass is chosen on the training recording)")
    p.add_argument("--nodes", type=int, default=1000)
    p.add_argument("--push-force", type=float, default=10.0, help="peak of each push at the hand, N (10)")
    p.add_argument("--friction-scale", type=float, default=1.0)
    p.add_argument("--input-filter-hz", type=float, default=10.0)
    p.add_argument("--coulomb-width", type=float, default=None, help="the identification's Coulomb width w of tanh(qdot / w), rad/s (default: chosen on held-out motion)")
    p.add_argument("--estimate-cutoff-hz", type=float, default=0.0, help="the estimate's low-pass, Hz (0: chosen per arm on the validation recording among 5, 10, 20, 40)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--list", action="store_true", help="print the arms included and excluded, and exit")
    p.add_argument("--jobs", type=int, default=None, help="arms at once, each in a process of its own (default: every core)")
    p.add_argument("--ray", metavar="ADDRESS", help="run the arms on the Ray cluster at ADDRESS ('auto', 'local', or ray://HOST:PORT)")
    p.add_argument("--retries", type=int, default=0, help="re-run a failed arm at once, alone, up to this many times (0)")
    p.add_argument("--force", action="store_true", help="replace arm folders in --out made with other settings")
    p.add_argument("--quiet", action="store_true", help="no progress on the terminal")
    a = p.parse_args(argv)
    if a.jobs is not None and a.jobs < 1:
        p.error("--jobs must be at least 1")
    if a.coulomb_width is not None and not (math.isfinite(a.coulomb_width) and a.coulomb_width > 0):
        p.error(f"--coulomb-width {a.coulomb_width}: must be a positive width in rad/s (or left out: chosen)")
    if a.quiet:
        from admittance import _progress

        _progress.set_quiet(True)
    try:
        import mujoco  # noqa: F401
    except ImportError:
        print("admittance.mujoco.arms: needs MuJoCo: pip install './crates/python[mujoco]'", file=sys.stderr)
        return 2
    from ._arms import ARMS, EXCLUDED, ArmsConfig, run_all

    if a.list:
        for name, (rel, _, _) in ARMS.items():
            print(f"included  {name:<16} {rel}")
        for what, why in EXCLUDED.items():
            print(f"excluded  {what}: {why}")
        return 0
    urdf_arms = {}
    if a.urdf:
        import pathlib

        urdf = pathlib.Path(a.urdf)
        if not urdf.is_file():
            p.error(f"--urdf {a.urdf}: no such file")
        name = a.name or urdf.stem
        if name in ARMS:
            p.error(f"--name {name}: an arm of the table has that name; give another with --name")
        try:
            adm.Model.from_urdf(str(urdf), base=a.base, tip=a.tip)
        except Exception as e:  # the loader's message names the file and element
            p.error(f"--urdf {a.urdf}: {e}")
        urdf_arms[name] = [str(urdf.resolve()), a.base, a.tip]
    elif a.base or a.tip or a.name:
        p.error("--base, --tip and --name go with --urdf")
    default = list(urdf_arms) if urdf_arms else list(ARMS)
    arms = [x for x in (a.arms.split(",") if a.arms else default) if x]
    unknown = [x for x in arms if x not in ARMS and x not in urdf_arms]
    if unknown:
        p.error(f"--arms: unknown {unknown}; choose among {list(ARMS) + list(urdf_arms)}")
    cfg = ArmsConfig(
        out=a.out, arms=arms, training_duration=a.training_duration, evaluation_duration=a.evaluation_duration, validation_duration=a.validation_duration,
        nodes=a.nodes, push_force=a.push_force, friction_scale=a.friction_scale,
        input_filter_hz=a.input_filter_hz, coulomb_width=a.coulomb_width, estimate_cutoff_hz=a.estimate_cutoff_hz, seed=a.seed, urdf_arms=urdf_arms,
    )
    from admittance import _progress
    from admittance.sweep import SweepError

    try:
        _, failed = run_all(cfg, log=_progress.log_line, jobs=a.jobs, ray=a.ray, retries=a.retries, force=a.force)
    except FileNotFoundError as e:
        print(f"admittance.mujoco.arms: {e}", file=sys.stderr)
        return 2
    except RuntimeError as e:  # Ray missing or unreachable
        print(f"admittance.mujoco.arms: {e}", file=sys.stderr)
        return 2
    except (SweepError, OSError) as e:
        print(f"admittance.mujoco.arms: {e}", file=sys.stderr)
        return 3
    except KeyboardInterrupt:
        print(f"admittance.mujoco.arms: interrupted; the finished arms' folders in {a.out} are kept: run the same "
              "command again to go on", file=sys.stderr)
        return 130
    print(f"wrote {a.out}/results.json, {a.out}/table.md and {a.out}/summary.csv (one folder per arm)", file=sys.stderr)
    if failed:
        print(f"admittance.mujoco.arms: {len(failed)} arm(s) failed ({', '.join(failed)}): run the same command "
              "again to run only those", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
