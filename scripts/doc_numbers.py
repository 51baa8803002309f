#!/usr/bin/env python3
"""The numbers of README.md's and docs/*.md's tables, from run folders (issue 25).

docs/numbers.toml lists, for each number, the line it is on, its context in that line, the
run that produces it (a command writing a run folder), the expression over that folder's
summary.json that gives it, its format and its tolerance. Then

  python3 scripts/doc_numbers.py --write [--runs DIR] [RUN...]   writes the numbers into the markdown
  python3 scripts/doc_numbers.py --check [--runs DIR] [RUN...]   compares them, within each tolerance

Run folders are DIR/NAME (default DIR: runs/ of the checkout); a missing one is made by its
command first (`--fresh` remakes them all). `--ci` restricts to the runs marked `ci = true`
(the ones CI's time allows); the others are checked locally with
`python3 scripts/doc_numbers.py --check --fresh`. Commands run in the checkout with
`admittance` = --bin (default target/release/admittance) and `python` = this interpreter.
Exit 1 when a number is off by more than its tolerance, a line or context is not found, or
a run fails. Python 3.11 (tomllib), or 3.10 with pip.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import shlex
import subprocess
import sys
import time
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10: the same parser, as pip vendors it
    try:
        from pip._vendor import tomli as tomllib
    except ImportError:
        sys.exit("doc_numbers.py needs Python 3.11 (tomllib), or pip in this interpreter")

ROOT = Path(__file__).resolve().parent.parent
NUMBER = r"[-+]?(?:\d{1,3}(?:,\d{3})+|\d+)(?:\.\d+)?(?:[eE][-+]?\d+)?"


class Summary:
    """Accessors over one run folder's summary.json, for the `value` expressions."""

    def __init__(self, path: Path):
        self.path = path
        self.data = json.loads(path.read_text(encoding="utf-8"))
        self.joints = self.data.get("joints", [])

    def joint_index(self, joint) -> int:
        if isinstance(joint, int):
            return joint
        hits = [i for i, j in enumerate(self.joints) if j == joint or j.endswith("_" + joint)]
        if len(hits) != 1:
            raise KeyError(f"joint {joint!r} not one of {self.joints}")
        return hits[0]

    def v(self, variant: str, metric: str, joint=None):
        """A metric of a variant; per-joint metrics need `joint` (index or name, e.g. 's0')."""
        variants = self.data["variants"]
        if variant not in variants:
            raise KeyError(f"variant {variant!r} not in {sorted(variants)}")
        value = variants[variant]
        for part in metric.split("."):
            if part not in value:
                raise KeyError(f"metric {metric!r} not in variant {variant!r}")
            value = value[part]
        if joint is not None:
            value = value[self.joint_index(joint)]
        if isinstance(value, list):
            raise TypeError(f"{variant}.{metric} is per joint: give a joint")
        return value

    def top(self, key: str):
        """A top-level key of summary.json (dotted path)."""
        value = self.data
        for part in key.split("."):
            value = value[part]
        return value


def evaluate(expr: str, summary: Summary) -> float:
    names = {"v": summary.v, "top": summary.top, "max": max, "min": min, "abs": abs,
             "sum": sum, "len": len, "math": math}
    names["__builtins__"] = {}
    value = eval(expr, names)  # expressions of this repository's manifest only
    return float(value)


def locate(text: str, entry: dict) -> tuple[int, re.Match, list[str]]:
    """The line holding the number and the match of its context; errors name the entry."""
    lines = text.split("\n")
    lo, hi = 0, len(lines)
    if "section" in entry:  # a heading: search from it to the next heading of its level or above
        heads = [i for i, l in enumerate(lines) if l.strip() == entry["section"].strip()]
        if len(heads) != 1:
            raise LookupError(f"section {entry['section']!r} found {len(heads)} times, must be once")
        lo = heads[0] + 1
        level = len(entry["section"]) - len(entry["section"].lstrip("#"))
        for j in range(lo, len(lines)):
            h = len(lines[j]) - len(lines[j].lstrip("#"))
            if 0 < h <= level and lines[j][h:h + 1] == " ":
                hi = j
                break
    hits = [i for i in range(lo, hi) if entry["line"] in lines[i]]
    if len(hits) != 1:
        raise LookupError(f"line {entry['line']!r} found {len(hits)} times"
                          f"{' in ' + entry['section'] if 'section' in entry else ''}, must be once")
    i = hits[0]
    if "cell" in entry:  # a table row: the nth number (default 1st) of cell `cell` (1-based)
        bars = [k for k, ch in enumerate(lines[i]) if ch == "|"]
        c = int(entry["cell"])
        if c < 1 or c >= len(bars):
            raise LookupError(f"line {i + 1} has no cell {c}")
        start, end = bars[c - 1] + 1, bars[c]
        found = list(re.finditer(r"(?<![\w.])(" + NUMBER + r")(?![\w.])", lines[i][start:end]))
        nth = int(entry.get("nth", 1))
        if len(found) < nth:
            raise LookupError(f"cell {c} of line {i + 1} holds {len(found)} numbers, not {nth}")
        m = found[nth - 1]
        return i, start + m.start(1), start + m.end(1), m.group(1), lines
    before, _, after = entry["text"].partition("{}")
    pattern = re.escape(before) + f"({NUMBER})" + re.escape(after)
    found = list(re.finditer(pattern, lines[i]))
    if len(found) != 1:
        raise LookupError(f"context {entry['text']!r} found {len(found)} times on line {i + 1}, must be once")
    return i, found[0].start(1), found[0].end(1), found[0].group(1), lines


def parse_number(s: str) -> float:
    return float(s.replace(",", ""))


def format_value(value: float, fmt: str) -> str:
    if fmt == ",d":
        return f"{round(value):,d}"
    return format(value, fmt)


def overrides_of(folder: Path) -> list[str]:
    """The --set overrides a run folder's scenario.toml lists in its opening comment."""
    path = folder / "scenario.toml"
    if not path.is_file():
        return []
    lines = path.read_text(encoding="utf-8").splitlines()
    if not lines or not lines[0].startswith("# The scenario as run, with these command-line overrides"):
        return []
    out = []
    for line in lines[1:]:
        m = re.match(r"#\s+--set\s+(.*)$", line)
        if not m:
            break
        out.append(m.group(1).strip())
    return out


def run_folder(name: str, spec: dict, runs: Path, fresh: bool, binary: Path) -> Path:
    out = runs / name
    if (out / "summary.json").is_file() and not fresh:
        # an existing folder counts only if it was run with the command's own overrides
        wanted = sorted(a.strip("'\"") for a in re.findall(r"--set\s+('[^']*'|\"[^\"]*\"|\S+)", spec["command"]))
        found = sorted(overrides_of(out))
        if wanted == found:
            return out
        raise RuntimeError(f"{out} was run with --set {found}, the command has {wanted}: "
                           "remove it, use --fresh or another --runs")
    shims = runs / ".doc-shims"
    shims.mkdir(parents=True, exist_ok=True)
    for cmd, target in (("admittance", str(binary)), ("python", sys.executable)):
        p = shims / cmd
        p.write_text(f'#!/usr/bin/env bash\nexec {shlex.quote(target)} "$@"\n')
        p.chmod(0o755)
    env = dict(os.environ, PATH=f"{shims}{os.pathsep}{os.environ.get('PATH', '')}")
    command = spec["command"].replace("{out}", shlex.quote(str(out)))
    if fresh and out.exists():
        command += " --force"
    print(f"-- run {name}: {command}", flush=True)
    t0 = time.monotonic()
    r = subprocess.run(["bash", "-c", "set -euo pipefail\n" + command], cwd=ROOT, env=env,
                       capture_output=True, text=True)
    print(f"   exit {r.returncode} in {time.monotonic() - t0:.0f} s", flush=True)
    # `exit` in the manifest: a run documented to fail a health rule (exit 4) still writes
    # its numbers; any other code is a failure.
    if r.returncode != spec.get("exit", 0) or not (out / "summary.json").is_file():
        tail = "\n".join("    " + l for l in (r.stderr or r.stdout).rstrip().splitlines()[-20:])
        raise RuntimeError(f"run {name} failed (exit {r.returncode}):\n{tail}")
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    mode = ap.add_mutually_exclusive_group(required=True)
    mode.add_argument("--write", action="store_true", help="write the numbers into the markdown")
    mode.add_argument("--check", action="store_true", help="compare the markdown with the run folders")
    mode.add_argument("--list", action="store_true", help="list the runs and how many numbers each gives")
    ap.add_argument("names", nargs="*", help="only these runs (default: all)")
    ap.add_argument("--runs", default=str(ROOT / "runs"), help="folder of the run folders (default runs/)")
    ap.add_argument("--ci", action="store_true", help="only the runs marked ci = true")
    ap.add_argument("--fresh", action="store_true", help="remake every run folder first")
    ap.add_argument("--bin", default=str(ROOT / "target/release/admittance"))
    ap.add_argument("--manifest", default=str(ROOT / "docs/numbers.toml"))
    args = ap.parse_args()

    manifest = tomllib.loads(Path(args.manifest).read_text(encoding="utf-8"))
    runs_spec: dict = manifest.get("run", {})
    numbers: list[dict] = list(manifest.get("number", []))
    problems = []
    for t, table in enumerate(manifest.get("table", []), 1):
        # shorthand: every row (a variant) times every column (a cell) is one number; "{variant}"
        # in a column's value is the row's variant; a row's `skip_cells` have no number ("-");
        # a row's `format` / `tol` tables, keyed "cell.nth", override a column's
        common = {k: table[k] for k in ("file", "section", "run") if k in table}
        for row in table.get("rows", []):
            for col in table.get("columns", []):
                if col.get("cell") in row.get("skip_cells", []):
                    continue
                e = dict(common, **col, line=row["line"])
                key = f"{col.get('cell')}.{col.get('nth', 1)}"  # a row's own format/tol of a cell
                for k in ("format", "tol"):
                    if key in row.get(k, {}):
                        e[k] = row[k][key]
                e["value"] = col["value"].replace("{variant}", row["variant"])
                e["tolerance"] = col.get("tolerance", table.get("tolerance", ""))
                numbers.append(e)
    for n, e in enumerate(numbers, 1):
        missing = {"file", "line", "run", "value", "format", "tol"} - set(e)
        if missing:
            problems.append(f"[[number]] #{n}: missing {sorted(missing)}")
        elif e["run"] not in runs_spec:
            problems.append(f"[[number]] #{n}: unknown run {e['run']!r}")
        elif ("text" in e) == ("cell" in e):
            problems.append(f"[[number]] #{n}: give either text or cell")
        elif "text" in e and e["text"].count("{}") != 1:
            problems.append(f"[[number]] #{n}: text must hold one {{}}")
    for name, spec in runs_spec.items():
        if not spec.get("ci", False) and not spec.get("not_ci"):
            problems.append(f"run {name}: ci = false needs a reason in not_ci")
    unknown = [n for n in args.names if n not in runs_spec]
    if unknown:
        problems.append(f"unknown runs {unknown}; known: {sorted(runs_spec)}")
    if problems:
        print("docs/numbers.toml:\n  " + "\n  ".join(problems))
        return 1

    selected = [n for n in runs_spec if (not args.names or n in args.names)
                and (not args.ci or runs_spec[n].get("ci", False))]
    if args.list:
        for name in runs_spec:
            spec = runs_spec[name]
            count = sum(1 for e in numbers if e["run"] == name)
            where = "CI" if spec.get("ci") else f"local ({spec['not_ci']})"
            print(f"{name:20} {count:3} numbers  {where}\n{'':20} {spec['command']}")
        return 0

    runs = Path(args.runs).resolve()
    binary = Path(args.bin).resolve()
    failures, checked, written = [], 0, 0
    texts: dict[str, str] = {}
    t_all = time.monotonic()
    for name in selected:
        try:
            folder = run_folder(name, runs_spec[name], runs, args.fresh, binary)
            summary = Summary(folder / "summary.json")
        except (RuntimeError, OSError, json.JSONDecodeError) as err:
            failures.append(f"run {name}: {err}")
            continue
        for e in (e for e in numbers if e["run"] == name):
            label = f"{e['file']}: {e.get('text') or e['line']!r} ({name})"
            text = texts.setdefault(e["file"], (ROOT / e["file"]).read_text(encoding="utf-8"))
            try:
                i, start, end, shown_text, lines = locate(text, e)
                value = evaluate(e["value"], summary)
            except (LookupError, TypeError, ValueError, ZeroDivisionError) as err:
                failures.append(f"{label}: {err}")
                continue
            shown = parse_number(shown_text)
            if args.write:
                new = format_value(value, e["format"])
                lines[i] = lines[i][:start] + new + lines[i][end:]
                texts[e["file"]] = "\n".join(lines)
                written += new != shown_text
                continue
            checked += 1
            diff = abs(shown - value)
            # rtol is relative to the smaller magnitude: rtol 1.0 is "within a factor of two" both ways
            allowed = float(e["tol"]) + float(e.get("rtol", 0.0)) * min(abs(value), abs(shown))
            ok = math.isfinite(value) and diff <= allowed + 1e-12 * abs(value)
            status = "ok  " if ok else "OFF "
            desc = e.get("text") or f"cell {e['cell']}#{e.get('nth', 1)} of {e['line'].strip()!r}"
            print(f"{status}{e['file']}:{i + 1} {shown_text:>10} fresh {format_value(value, e['format']):>10}"
                  f" (raw {value:.6g}, tol {e['tol']}{', rtol ' + str(e['rtol']) if 'rtol' in e else ''})  {desc}")
            if not ok:
                failures.append(f"{e['file']}:{i + 1}: {desc} shows {shown_text}, the run gives "
                                f"{value:.6g} (|diff| {diff:.3g} > {allowed:.3g}; run {name}, {e['value']})")
    if args.write:
        for f, text in texts.items():
            if text != (ROOT / f).read_text(encoding="utf-8"):
                (ROOT / f).write_text(text, encoding="utf-8")
        print(f"{written} numbers changed in {len(texts)} files")
    else:
        print(f"\ndoc numbers: {checked} checked from runs {', '.join(selected) or '-'}, "
              f"{len(failures)} problems, {time.monotonic() - t_all:.0f} s")
        skipped = [n for n in runs_spec if n not in selected]
        for n in skipped:
            count = sum(1 for e in numbers if e["run"] == n)
            print(f"  not checked here: run {n} ({count} numbers): {runs_spec[n].get('not_ci', 'not selected')}")
    for f in failures:
        print("FAILED " + f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
