#!/usr/bin/env bash
# Side-by-side of the plant step of admittance-sim with MuJoCo's mj_step on the same arm,
# same timestep, same scheme (semi-implicit Euler), plus the cost of the default
# integrator and a trajectory agreement check. See compare_mujoco.py for what is measured.
#
# Makes (or reuses) a scratch virtual environment .venv-bench at the repository root
# (git-ignored) with MuJoCo and NumPy from PyPI, builds the Rust timing example
# (crates/sim/examples/plant_timing.rs) in release mode, then runs compare_mujoco.py.
# Arguments are passed on to it (e.g. --dt 5e-4 --rounds 5 --json out.json).
#
# Environment: PYTHON (default python3), MUJOCO_VERSION (default 4.0.0, the version the
# reported numbers were taken with), CARGO_TARGET_DIR (default target/).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
VENV="$ROOT/.venv-bench"
PYTHON="${PYTHON:-python3}"
MUJOCO_VERSION="${MUJOCO_VERSION:-4.0.0}"
TARGET_DIR="${CARGO_TARGET_DIR:-$ROOT/target}"

if [ ! -x "$VENV/bin/python" ]; then
    "$PYTHON" -m venv "$VENV"
fi
if ! "$VENV/bin/python" -c "import mujoco, numpy, sys
sys.exit(0 if mujoco.__version__ == '$MUJOCO_VERSION' else 1)" 2>/dev/null; then
    "$VENV/bin/python" -m pip install --quiet "mujoco==$MUJOCO_VERSION" numpy
fi
cd "$ROOT"
cargo build --release --quiet -p admittance-sim --example plant_timing
"$VENV/bin/python" "$ROOT/scripts/bench/compare_mujoco.py" --rust-bin "$TARGET_DIR/release/examples/plant_timing" "$@"
