#!/usr/bin/env bash
# Fuzzes `admittance import` (the MCAP reader, the decoding, the resampling) on mutated
# bags for a bounded time (default 60 s): bash scripts/fuzz_bag.sh [SECONDS]
# Seeds: the test bags of crates/bag/tests/data. Installs cargo-fuzz from crates.io when
# missing; cargo-fuzz builds with nightly-only flags, which RUSTC_BOOTSTRAP=1 enables on a
# stable toolchain. -rss_limit_mb bounds the memory of one input (the reader's limit is a
# 256 MiB record, the table's 50 million values).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-60}"
command -v cargo-fuzz >/dev/null || cargo install cargo-fuzz --locked
mkdir -p fuzz/corpus/bag_import
for f in crates/bag/tests/data/*.mcap crates/bag/tests/data/*/*.mcap; do
  cp -n "$f" "fuzz/corpus/bag_import/$(basename "$f")" 2>/dev/null || true
done
RUSTC_BOOTSTRAP=1 cargo fuzz run --fuzz-dir fuzz bag_import fuzz/corpus/bag_import -- \
  -max_total_time="$seconds" -max_len=262144 -timeout=10 -rss_limit_mb=2048
