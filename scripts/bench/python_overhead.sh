#!/usr/bin/env bash
# Python call overhead of the bindings against the same calls from Rust (issue 15, part 4;
# see python_overhead.py for what is measured). Makes (or reuses) the scratch virtual
# environment .venv-bench at the repository root (git-ignored), installs numpy and maturin
# from PyPI, builds and installs the package from crates/python in release mode (in the
# workspace's target/), then runs python_overhead.py with the arguments given
# (e.g. --rounds 15 --calls 50000).
#
# Environment: PYTHON (default python3).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
VENV="$ROOT/.venv-bench"
PYTHON="${PYTHON:-python3}"
if [ ! -x "$VENV/bin/python" ]; then
    "$PYTHON" -m venv "$VENV"
fi
"$VENV/bin/python" -m pip install --quiet --disable-pip-version-check maturin==1.16.0 numpy
cd "$ROOT"
PATH="$VENV/bin:$PATH" "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check \
    --no-build-isolation --no-deps --force-reinstall ./crates/python
"$VENV/bin/python" "$ROOT/scripts/bench/python_overhead.py" "$@"
