#!/usr/bin/env bash
# `adm.identify` beside a plain least-squares fit on the same conditioned data, on every
# recording the project has (issue 30, item 4; see identify_vs_least_squares.py for what is
# measured). Makes (or reuses) the scratch virtual environment .venv-bench at the repository
# root (git-ignored), installs NumPy, MuJoCo, example-robot-data (the arms), pin (Pinocchio's
# regressor) and maturin from PyPI, builds and installs the package from crates/python in
# release mode (in the workspace's target/), then runs identify_vs_least_squares.py with the
# arguments given (e.g. --arms panda ur5 --no-baxter --json out.json).
#
# Environment: PYTHON (default python3); ADMITTANCE_DATA, the folder holding
# baxter_rand/baxter_rand.csv (default: ../shared/data beside the checkout, when present);
# SKIP_PACKAGE_BUILD=1 keeps the package already installed in .venv-bench.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
VENV="$ROOT/.venv-bench"
PYTHON="${PYTHON:-python3}"
if [ -z "${ADMITTANCE_DATA:-}" ] && [ -d "$ROOT/../shared/data" ]; then
    export ADMITTANCE_DATA="$(cd "$ROOT/../shared/data" && pwd)"
fi
if [ ! -x "$VENV/bin/python" ]; then
    "$PYTHON" -m venv "$VENV"
fi
"$VENV/bin/python" -m pip install --quiet --disable-pip-version-check \
    maturin==1.16.0 numpy==2.4.6 mujoco==4.0.0 example-robot-data==6.0.0 pin==4.1.0
cd "$ROOT"
if [ -z "${SKIP_PACKAGE_BUILD:-}" ]; then
    PATH="$VENV/bin:$PATH" MATURIN_PEP517_ARGS="--locked" "$VENV/bin/python" -m pip install --quiet \
        --disable-pip-version-check --no-build-isolation --no-deps --force-reinstall ./crates/python
fi
"$VENV/bin/python" "$ROOT/scripts/bench/identify_vs_least_squares.py" "$@"
