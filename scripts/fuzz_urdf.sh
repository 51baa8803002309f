#!/usr/bin/env bash
# Fuzzes the URDF loader for a bounded time (default 60 s): bash scripts/fuzz_urdf.sh [SECONDS]
# Installs cargo-fuzz from crates.io when missing. cargo-fuzz builds with nightly-only
# flags; on a stable toolchain RUSTC_BOOTSTRAP=1 enables them.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-60}"
command -v cargo-fuzz >/dev/null || cargo install cargo-fuzz --locked
mkdir -p fuzz/corpus/urdf_loader
cp -n fuzz/seeds/*.urdf fuzz/corpus/urdf_loader/ 2>/dev/null || true
RUSTC_BOOTSTRAP=1 cargo fuzz run --fuzz-dir fuzz urdf_loader fuzz/corpus/urdf_loader -- \
  -max_total_time="$seconds" -max_len=65536 -timeout=10
