#!/usr/bin/env python3
"""Run every command and code block of README.md and docs/*.md (issue 25).

Every fenced block tagged sh, bash, shell, console or python is extracted and run, in
document order, from a clean clone's point of view: a scratch folder holding a copy of the
repository's tracked files (git ls-files), so that the runs/ and files the commands write
never touch the checkout. In shell blocks `admittance` is the built binary (a shim first on
PATH) and `cargo run --release -p admittance-cli --` is read as `admittance` (the README
says they are the same); `python` and `pip` are the interpreter running this script (CI:
.venv-ci, with the package installed by the Python stage). Python blocks run in that
interpreter, in the scratch folder.

A block runs verbatim unless docs/commands.toml has an entry for it (matched by its file
and a substring of its text), which may: run it in the checkout itself (cwd = "repo", for
cargo and pip, whose outputs go to the git-ignored target/ and the venv), run a `setup`
first (placeholders such as my_arm.urdf made from the repository's models), shorten it
(`replace` pairs, `append_run` arguments added to every `admittance run`), leave out lines
(`drop`, each with a reason), check a usage synopsis against `--help` (`synopsis = true`),
or skip it (`skip`, a reason). Every manifest entry, replacement and drop must match, so a
stale manifest fails. `needs = "data"` blocks are skipped, with a message, when
ADMITTANCE_DATA is unset (as the tests on published recordings are).

Usage: python3 scripts/doc_commands.py [--bin target/release/admittance] [--only TEXT]
       [--keep DIR] [--list]
Exit 0 when every block that ran passed; 1 otherwise, each failure named by file:line with
the tail of its stderr. Python 3.11 (tomllib), or 3.10 with pip.
"""

from __future__ import annotations

import argparse
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10: the same parser, as pip vendors it
    try:
        from pip._vendor import tomli as tomllib
    except ImportError:
        sys.exit("doc_commands.py needs Python 3.11 (tomllib), or pip in this interpreter")

ROOT = Path(__file__).resolve().parent.parent
SHELL_LANGS = {"sh", "bash", "shell", "console"}
PYTHON_LANGS = {"python", "py", "python3"}
CARGO_RUN_CLI = re.compile(r"cargo run --release -p admittance-cli --(?=\s|$)")


@dataclass
class Block:
    file: str  # relative to the repository root
    line: int  # line of the opening fence (1-based)
    lang: str
    text: str
    entry: dict | None = None
    notes: list[str] = field(default_factory=list)

    @property
    def where(self) -> str:
        return f"{self.file}:{self.line}"

    @property
    def kind(self) -> str:
        return "python" if self.lang in PYTHON_LANGS else "shell"


def doc_files() -> list[Path]:
    files = [ROOT / "README.md"] + sorted((ROOT / "docs").glob("*.md"))
    return [f for f in files if f.is_file()]


def extract(path: Path) -> list[Block]:
    """Fenced blocks of one markdown file: ``` or ~~~ fences, the info string's first word."""
    blocks = []
    rel = path.relative_to(ROOT).as_posix()
    lines = path.read_text(encoding="utf-8").splitlines()
    i = 0
    while i < len(lines):
        m = re.match(r"^(\s*)(`{3,}|~{3,})\s*([\w+-]*)", lines[i])
        if not m:
            i += 1
            continue
        fence, lang, start = m.group(2), m.group(3).lower(), i
        body = []
        i += 1
        while i < len(lines) and not lines[i].strip().startswith(fence):
            body.append(lines[i])
            i += 1
        i += 1
        if lang in SHELL_LANGS or lang in PYTHON_LANGS:
            blocks.append(Block(rel, start + 1, lang, "\n".join(body) + "\n"))
    return blocks


def load_manifest(path: Path, blocks: list[Block]) -> list[str]:
    """Attach each manifest entry to the one block it matches; the problems found."""
    problems = []
    data = tomllib.loads(path.read_text(encoding="utf-8"))
    for n, entry in enumerate(data.get("block", []), 1):
        label = f"{path.name} [[block]] #{n} ({entry.get('file')!r}, match {entry.get('match')!r})"
        unknown = set(entry) - {"file", "match", "cwd", "needs", "setup", "replace", "append_run",
                                "drop", "skip", "synopsis", "timeout", "why"}
        if unknown:
            problems.append(f"{label}: unknown keys {sorted(unknown)}")
        hits = [b for b in blocks if b.file == entry.get("file") and entry.get("match", "") in b.text]
        if len(hits) != 1:
            problems.append(f"{label}: matches {len(hits)} blocks, must match exactly one")
            continue
        if hits[0].entry is not None:
            problems.append(f"{label}: {hits[0].where} already has an entry")
            continue
        if "skip" in entry and not str(entry["skip"]).strip():
            problems.append(f"{label}: a skip needs a reason")
        for d in entry.get("drop", []):
            if not d.get("reason"):
                problems.append(f"{label}: drop {d.get('match')!r} needs a reason")
        hits[0].entry = entry
    return problems


def continued_commands(text: str) -> list[str]:
    """Shell lines with backslash continuations joined (for drop and synopsis)."""
    out, cur = [], ""
    for line in text.splitlines():
        if line.rstrip().endswith("\\"):
            cur += line.rstrip()[:-1] + " "
            continue
        out.append(cur + line)
        cur = ""
    if cur:
        out.append(cur)
    return out


def prepare_shell(block: Block) -> str:
    """The script a shell block runs: console prompts stripped, manifest edits applied."""
    e = block.entry or {}
    text = block.text
    if block.lang == "console":  # only the `$ ` lines are commands; the rest is output
        text = "\n".join(l[2:] for l in text.splitlines() if l.startswith("$ ")) + "\n"
    if CARGO_RUN_CLI.search(text):
        text = CARGO_RUN_CLI.sub("admittance", text)
        block.notes.append("`cargo run --release -p admittance-cli --` run as `admittance`")
    lines = continued_commands(text)
    for d in e.get("drop", []):
        hit = [l for l in lines if d["match"] in l]
        if not hit:
            raise ValueError(f"drop {d['match']!r} matches no line")
        lines = [l for l in lines if d["match"] not in l]
        block.notes.append(f"not run: {d['match']!r} ({d['reason']})")
    text = "\n".join(lines) + "\n"
    for old, new in e.get("replace", []):
        if old not in text:
            raise ValueError(f"replace {old!r} matches nothing")
        text = text.replace(old, new)
        block.notes.append(f"shortened: {old!r} -> {new!r}")
    extra = e.get("append_run")
    if extra:
        pat = re.compile(r"^(\s*admittance run .*?)(\s*#.*)?$", re.M)
        if not pat.search(text):
            raise ValueError("append_run: no `admittance run` line")
        text = pat.sub(lambda m: m.group(1) + " " + shlex.join(extra) + (m.group(2) or ""), text)
        block.notes.append(f"shortened: `admittance run ... {shlex.join(extra)}`")
    setup = e.get("setup", "")
    return "set -euo pipefail\n" + (setup + "\n" if setup else "") + text


def check_synopsis(block: Block, env: dict, cwd: Path) -> tuple[bool, str]:
    """A usage synopsis: every `admittance SUB` exists and knows every --flag shown."""
    problems, checked = [], 0
    for line in continued_commands(block.text):
        code = line.split("#", 1)[0]
        m = re.match(r"\s*admittance\s+([a-z-]+)", code)
        if not m:
            continue
        sub = m.group(1)
        r = subprocess.run(["admittance", sub, "--help"], env=env, cwd=cwd, capture_output=True, text=True)
        helptext = r.stdout + r.stderr
        if r.returncode != 0:
            problems.append(f"`admittance {sub} --help` exits {r.returncode}: {helptext.strip()[-300:]}")
            continue
        for flag in sorted(set(re.findall(r"(?<![\w-])--[a-z][a-z0-9-]*", code))):
            checked += 1
            if not re.search(re.escape(flag) + r"(?![\w-])", helptext):
                problems.append(f"`admittance {sub}` has no {flag} (its --help does not list it)")
    if checked == 0:
        problems.append("synopsis block names no `admittance SUB --flag`")
    return (not problems), "\n".join(problems)


def make_scratch(dest: Path) -> None:
    """A copy of the tracked files: what a fresh clone holds (no target/, no runs/)."""
    files = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True).stdout
    for name in files.decode().split("\0"):
        if not name:
            continue
        src = ROOT / name
        if not src.exists():  # deleted in the work tree, not yet committed
            continue
        out = dest / name
        out.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(src, out, follow_symlinks=False)
    # cargo in the copy builds into the checkout's target/ (what CI's cargo test built: the
    # copy's files keep their times, so cargo finds them fresh) instead of building it all again
    if (ROOT / "target").is_dir() and not (dest / "target").exists():
        (dest / "target").symlink_to(ROOT / "target")


def make_shims(shim_dir: Path, binary: Path, python: str) -> None:
    shim_dir.mkdir(parents=True, exist_ok=True)
    for name, target in (("admittance", str(binary)), ("python", python), ("python3", python)):
        p = shim_dir / name
        p.write_text(f'#!/usr/bin/env bash\nexec {shlex.quote(target)} "$@"\n')
        p.chmod(0o755)
    p = shim_dir / "pip"
    p.write_text(f'#!/usr/bin/env bash\nexec {shlex.quote(python)} -m pip "$@"\n')
    p.chmod(0o755)


def tail(text: str, n: int = 25) -> str:
    lines = text.rstrip().splitlines()
    return "\n".join(("    " + l) for l in lines[-n:])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin", default=str(ROOT / "target/release/admittance"), help="the admittance binary")
    ap.add_argument("--manifest", default=str(ROOT / "docs/commands.toml"))
    ap.add_argument("--only", help="run only blocks whose file:line or text contains this")
    ap.add_argument("--keep", help="use this scratch folder (created; kept afterwards)")
    ap.add_argument("--list", action="store_true", help="list the blocks and what would be done")
    args = ap.parse_args()

    blocks = [b for f in doc_files() for b in extract(f)]
    problems = load_manifest(Path(args.manifest), blocks)
    if problems:
        print("docs/commands.toml does not fit the documents:\n  " + "\n  ".join(problems))
        return 1

    binary = Path(args.bin).resolve()
    if not args.list and not binary.is_file():
        print(f"no binary at {binary}: cargo build --release -p admittance-cli")
        return 1
    python = sys.executable
    if args.keep:
        scratch = Path(args.keep).resolve()
        scratch.mkdir(parents=True, exist_ok=True)
        cleanup = False
    else:
        scratch = Path(tempfile.mkdtemp(prefix="admittance-docs-"))
        cleanup = True
    shims = scratch / ".doc-shims"
    if not args.list:
        make_scratch(scratch)
        make_shims(shims, binary, python)
    env = dict(os.environ)
    env["PATH"] = f"{shims}{os.pathsep}{env.get('PATH', '')}"
    env.pop("PYTHONPATH", None)

    ran = passed = 0
    ran_blocks: list[Block] = []
    skipped: list[tuple[Block, str]] = []
    failed: list[tuple[Block, str]] = []
    t_all = time.monotonic()
    for b in blocks:
        if args.only and args.only not in b.where and args.only not in b.text:
            continue
        e = b.entry or {}
        if "skip" in e:
            skipped.append((b, e["skip"]))
            continue
        if e.get("needs") == "data" and not os.environ.get("ADMITTANCE_DATA"):
            skipped.append((b, "needs a published data set and ADMITTANCE_DATA is unset"))
            continue
        cwd = ROOT if e.get("cwd") == "repo" else scratch
        try:
            script = prepare_shell(b) if b.kind == "shell" else None
        except ValueError as err:
            failed.append((b, f"docs/commands.toml: {err}"))
            continue
        if args.list:
            mode = "synopsis" if e.get("synopsis") else b.kind
            print(f"{b.where:28} {mode:8} cwd={'repo' if cwd == ROOT else 'scratch'} {'; '.join(b.notes)}")
            continue
        ran += 1
        ran_blocks.append(b)
        t0 = time.monotonic()
        timeout = float(e.get("timeout", 1800))
        print(f"-- {b.where} ({b.lang}{', synopsis' if e.get('synopsis') else ''}"
              f"{', in the checkout' if cwd == ROOT else ''})", flush=True)
        for note in b.notes:
            print(f"   {note}")
        try:
            if e.get("synopsis"):
                ok, err = check_synopsis(b, env, cwd)
            elif b.kind == "shell":
                r = subprocess.run(["bash", "-c", script], cwd=cwd, env=env, capture_output=True,
                                   text=True, timeout=timeout)
                ok, err = r.returncode == 0, f"exit {r.returncode}\n{r.stderr or r.stdout}"
            else:
                code = (e.get("setup", "") + "\n" if e.get("setup") else "") + b.text
                r = subprocess.run([python, "-c", code], cwd=cwd, env=env, capture_output=True,
                                   text=True, timeout=timeout)
                ok, err = r.returncode == 0, f"exit {r.returncode}\n{r.stderr or r.stdout}"
        except subprocess.TimeoutExpired:
            ok, err = False, f"timed out after {timeout:.0f} s"
        dt = time.monotonic() - t0
        print(f"   {'ok' if ok else 'FAILED'} in {dt:.1f} s", flush=True)
        if ok:
            passed += 1
        else:
            failed.append((b, err))
    if args.list:
        for b, why in skipped:
            print(f"{b.where:28} skipped: {why}")
        return 0
    total = time.monotonic() - t_all
    print(f"\ndocumented blocks: {ran} run ({passed} passed, {len(failed)} failed), {len(skipped)} skipped, {total:.0f} s")
    for b, why in skipped:
        print(f"  skipped {b.where}: {why}")
    for b in ran_blocks:
        for d in (b.entry or {}).get("drop", []):
            print(f"  line left out of {b.where}: {d['match']!r}: {d['reason']}")
    for b, err in failed:
        print(f"\nFAILED {b.where} ({b.lang} block):\n{tail(err)}")
    if cleanup and not failed:
        shutil.rmtree(scratch, ignore_errors=True)
    elif failed:
        print(f"\nscratch folder kept: {scratch}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
