#!/usr/bin/env bash
# The C++ test of the C ABI (issue 24; docs/ffi.md), called by .ci/test after the Rust tests:
#   1. builds the static library and the Rust reference program (release, --locked);
#   2. the Rust loop, closed around the simulated Baxter arm of scenarios/admittance.toml
#      (variant `momentum`: PD, joint admittance, momentum observer), records 100,000
#      periods of inputs and outputs (examples/reference_run.rs);
#   3. g++ compiles loop_test.cpp against include/admittance.h and libadmittance_ffi.a;
#   4. loop_test replays the inputs through adm_step: 0 allocations in the loop, every
#      output bit-identical to the Rust loop's. Exits non-zero with a message otherwise.
# Files go to target/ffi-cpp/ (about 75 MB of reference data).
set -euo pipefail
cd "$(dirname "$0")/../../../.."
STEPS="${ADM_CPP_STEPS:-100000}"
SCENARIO=scenarios/admittance.toml
VARIANT=momentum
OUT=target/ffi-cpp
mkdir -p "$OUT"

cargo build --release --locked -p admittance-ffi --lib --example reference_run
target/release/examples/reference_run "$SCENARIO" "$VARIANT" "$OUT" "$STEPS"

CXX="${CXX:-g++}"
"$CXX" --version | head -1
"$CXX" -std=c++17 -O2 -Wall -Wextra -Werror \
    -I crates/ffi/include \
    crates/ffi/tests/cpp/loop_test.cpp \
    target/release/libadmittance_ffi.a \
    -lpthread -ldl -lm \
    -o "$OUT/loop_test"
"$OUT/loop_test" "$SCENARIO" "$VARIANT" "$OUT"
