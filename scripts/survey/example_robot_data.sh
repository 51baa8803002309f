#!/usr/bin/env bash
# `admittance model` on every URDF of the `example-robot-data` package (PyPI), and
# `admittance dynamics` against Pinocchio's reduced model on every one that loads
# (example_robot_data.py says how). Makes (or reuses) the scratch virtual environment
# .venv-survey at the repository root (git-ignored), builds the CLI in release mode, runs
# the survey with the arguments given (e.g. --states 10 --seed 2).
#
# Environment: PYTHON (default python3).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
VENV="$ROOT/.venv-survey"
PYTHON="${PYTHON:-python3}"
if [ ! -x "$VENV/bin/python" ]; then
    "$PYTHON" -m venv "$VENV"
fi
"$VENV/bin/python" -m pip install --quiet --disable-pip-version-check example-robot-data==6.0.0 pin==4.1.0 numpy
cargo build --release --quiet -p admittance-cli --manifest-path "$ROOT/Cargo.toml"
"$VENV/bin/python" "$ROOT/scripts/survey/example_robot_data.py" "$@"
