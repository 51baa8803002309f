"""``python -m admittance.sweep._worker FOLDER``: runs one call job (its JSON on stdin) in
this process: imports ``spec["function"]`` (``"module:name"``), calls it with the folder and
``spec["params"]``, and writes the dict it returns to ``FOLDER/result.json``. A job that
crashes or is killed leaves no ``result.json``: the sweep reports it as failed."""

import importlib
import json
import pathlib
import sys


def resolve(function: str):
    """The callable named ``"module:name"`` (``name`` may be dotted)."""
    module, _, name = function.partition(":")
    if not module or not name:
        raise ValueError(f"function {function!r}: expected \"module:name\"")
    obj = importlib.import_module(module)
    for part in name.split("."):
        obj = getattr(obj, part)
    return obj


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    folder = pathlib.Path(argv[0])
    job = json.loads(sys.stdin.read())
    from admittance import _progress

    _progress.set_quiet(True)  # the sweep draws the progress of its jobs
    result = resolve(job["spec"]["function"])(folder, **job["spec"].get("params", {}))
    if not isinstance(result, dict):
        raise TypeError(f"{job['spec']['function']} returned {type(result).__name__}, not a dict")
    text = json.dumps(result, indent=2, allow_nan=False) + "\n"
    tmp = folder / (".result.json.partial")
    tmp.write_text(text)
    tmp.rename(folder / "result.json")
    return 0


if __name__ == "__main__":
    sys.exit(main())
