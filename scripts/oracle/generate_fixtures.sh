#!/usr/bin/env bash
# Regenerate the Pinocchio oracle fixtures of admittance-dynamics:
#   crates/dynamics/tests/fixtures/arms/*.urdf and crates/dynamics/tests/fixtures/pinocchio/*.json
# Makes (or reuses) a scratch virtual environment .venv-oracle at the repository root
# (git-ignored) with Pinocchio's Python bindings from PyPI, then runs generate_fixtures.py.
# The fixtures are committed: building and testing the workspace needs no Python.
#
# Environment: PYTHON (default python3), PIN_VERSION (default 4.1.0, the version the
# committed fixtures were made with), NUMPY_VERSION (default 2.4.6).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
VENV="$ROOT/.venv-oracle"
PYTHON="${PYTHON:-python3}"
PIN_VERSION="${PIN_VERSION:-4.1.0}"
NUMPY_VERSION="${NUMPY_VERSION:-2.4.6}"

if [ ! -x "$VENV/bin/python" ]; then
    "$PYTHON" -m venv "$VENV"
fi
if ! "$VENV/bin/python" -c "import pinocchio, numpy, sys
sys.exit(0 if pinocchio.__version__ == '$PIN_VERSION' and numpy.__version__ == '$NUMPY_VERSION' else 1)" 2>/dev/null; then
    "$VENV/bin/python" -m pip install --quiet --upgrade pip
    "$VENV/bin/python" -m pip install --quiet "pin==$PIN_VERSION" "numpy==$NUMPY_VERSION"
fi
"$VENV/bin/python" "$ROOT/scripts/oracle/generate_fixtures.py" "$@"
"$VENV/bin/python" "$ROOT/scripts/oracle/generate_regressor_fixtures.py"
