#!/usr/bin/env bash
# The C++ test of the C ABI (issues 24, 32; docs/ffi.md), called by .ci/test after the Rust
# tests:
#   1. builds the static library, the CLI and the Rust reference program (release, --locked);
#   2. `admittance deploy` writes the deployment folder of scenarios/admittance.toml, variant
#      `momentum` (PD, joint admittance, momentum observer): what adm_create reads;
#   3. the Rust loop of that folder records 100,000 periods of inputs and outputs
#      (examples/reference_run.rs: a measured motion, a NaN burst, two absurd samples);
#   4. g++ compiles loop_test.cpp against include/admittance.h and libadmittance_ffi.a;
#   5. loop_test loads the folder and replays the inputs through adm_step: 0 allocations in
#      the loop, every output bit-identical to the Rust loop's. Exits non-zero otherwise.
# Files go to target/ffi-cpp/ (about 80 MB of reference data).
set -euo pipefail
cd "$(dirname "$0")/../../../.."
STEPS="${ADM_CPP_STEPS:-100000}"
SCENARIO=scenarios/admittance.toml
VARIANT=momentum
OUT=target/ffi-cpp
DEPLOY="$OUT/deploy_momentum"
mkdir -p "$OUT"

cargo build --release --locked -p admittance-ffi --lib --example reference_run
cargo build --release --locked -p admittance-cli
target/release/admittance deploy "$SCENARIO" --variant "$VARIANT" --out "$DEPLOY"
target/release/examples/reference_run "$DEPLOY" "$OUT" "$STEPS"

CXX="${CXX:-g++}"
"$CXX" --version | head -1
"$CXX" -std=c++17 -O2 -Wall -Wextra -Werror \
    -I crates/ffi/include \
    crates/ffi/tests/cpp/loop_test.cpp \
    target/release/libadmittance_ffi.a \
    -lpthread -ldl -lm \
    -o "$OUT/loop_test"
"$OUT/loop_test" "$DEPLOY" "$OUT"
