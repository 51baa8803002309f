#!/usr/bin/env bash
# Side-by-side timing of admittance-dynamics and Pinocchio's C++ on the same URDF.
#
#   bash scripts/bench/compare_pinocchio.sh [URDF] [TIP]      (default: models/baxter_left_arm.urdf left_hand)
#
# 1. Creates or reuses the git-ignored virtual environment .venv-bench with Pinocchio's C++
#    library and headers from PyPI (pin, cmeel-eigen, cmeel-urdfdom-headers, cmeel-boost).
# 2. Compiles scripts/bench/pinocchio_timing.cpp into target/pinocchio_timing
#    (-O3 -march=native -DNDEBUG, C++17; only when the source or the flags changed: the first
#    compile takes several minutes, Pinocchio is all templates).
# 3. Builds our timing program: cargo build --release -p admittance-dynamics --example timing
#    (skipped, with a note, while crates/dynamics/examples/timing.rs does not exist).
# 4. Runs both alternately, ROUNDS times (ours, pinocchio, ours, pinocchio, ...); each run
#    prints "<algorithm> <median ns per call>"; the table shows the median over rounds, and
#    the ratio of each side's fastest round (the least disturbed on a shared machine).
#
# Environment: ROUNDS (default 3); STATES (default 1000), BATCHES (default 1000) and PER_BATCH
# (default 100) for the Pinocchio program (see pinocchio_timing.cpp: short batches keep the
# median clear of preemptions on a busy machine); PIN_VERSION (default 4.1.0), PYTHON (default
# python3), CXX (default g++).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$ROOT"
URDF="${1:-models/baxter_left_arm.urdf}"
TIP="${2:-left_hand}"
ROUNDS="${ROUNDS:-3}"
STATES="${STATES:-1000}"
BATCHES="${BATCHES:-1000}"
PER_BATCH="${PER_BATCH:-100}"
PIN_VERSION="${PIN_VERSION:-4.1.0}"
PYTHON="${PYTHON:-python3}"
CXX="${CXX:-g++}"
VENV="$ROOT/.venv-bench"
TARGET_DIR="${CARGO_TARGET_DIR:-$ROOT/target}"
case "$TARGET_DIR" in /*) ;; *) TARGET_DIR="$ROOT/$TARGET_DIR" ;; esac
PIN_BIN="$TARGET_DIR/pinocchio_timing"
# Ours is built for the host CPU, as Pinocchio's program is (-march=native), in a target
# directory of its own so that the normal build is not invalidated.
OURS_TARGET="$TARGET_DIR/bench-native"
OURS_BIN="$OURS_TARGET/release/examples/timing"
ALGOS="rnea crba aba jacobian coriolis gravity fk regressor"

[ -f "$URDF" ] || { echo "no such URDF: $URDF" >&2; exit 2; }

# ---- 1. Pinocchio from PyPI ----------------------------------------------------------------
prefix() { ls -d "$VENV"/lib/python3*/site-packages/cmeel.prefix 2>/dev/null | head -n 1; }
PREFIX="$(prefix || true)"
if [ ! -x "$VENV/bin/python" ]; then
    "$PYTHON" -m venv "$VENV"
fi
if [ -z "$PREFIX" ] || [ ! -f "$PREFIX/include/pinocchio/config.hpp" ] \
    || [ ! -d "$PREFIX/include/eigen3" ] || [ ! -f "$PREFIX/include/urdfdom_headers/urdf_model/model.h" ] \
    || [ ! -d "$PREFIX/include/boost" ] \
    || ! grep -q "PINOCCHIO_VERSION \"$PIN_VERSION\"" "$PREFIX/include/pinocchio/config.hpp"; then
    echo "== installing pin==$PIN_VERSION cmeel-eigen cmeel-urdfdom-headers cmeel-boost into .venv-bench" >&2
    "$VENV/bin/python" -m pip install --quiet --upgrade pip
    "$VENV/bin/python" -m pip install --quiet "pin==$PIN_VERSION" cmeel-eigen cmeel-urdfdom-headers cmeel-boost
    PREFIX="$(prefix)"
fi

# ---- 2. the C++ timing program -------------------------------------------------------------
# EIGEN_MAX_ALIGN_BYTES=16 EIGEN_MALLOC_ALREADY_ALIGNED=1: the PyPI libraries are built for
# baseline x86-64, where Eigen aligns to 16 bytes and allocates with plain malloc. With
# -march=native on an AVX machine Eigen would otherwise align fixed-size members to 32 bytes
# and allocate heap storage with its own offset-storing allocator; the URDF parser inside
# libpinocchio_parsers fills our Model, so Eigen storage allocated on one side and freed on the
# other crashes (segmentation fault). These two defines keep the library's memory layout and
# allocator; code generation in this file still uses AVX2/FMA (unaligned packet loads).
# Pinocchio's algorithms are templates: without PINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION they
# are compiled here, with these flags, rather than called in the prebuilt library.
CXXFLAGS=(-std=c++17 -O3 -march=native -DNDEBUG -DEIGEN_MAX_ALIGN_BYTES=16 -DEIGEN_MALLOC_ALREADY_ALIGNED=1
    -DBOOST_MPL_LIMIT_LIST_SIZE=30 -DBOOST_MPL_LIMIT_VECTOR_SIZE=30
    -DBOOST_MPL_CFG_NO_PREPROCESSED_HEADERS -DBOOST_FUSION_INVOKE_MAX_ARITY=12
    -DPINOCCHIO_WITH_URDFDOM -DPINOCCHIO_URDFDOM_HEADERS_MAJOR_VERSION=3
    -DPINOCCHIO_URDFDOM_HEADERS_MINOR_VERSION=0 -DPINOCCHIO_URDFDOM_HEADERS_PATCH_VERSION=0
    -I"$PREFIX/include" -I"$PREFIX/include/eigen3" -I"$PREFIX/include/urdfdom_headers"
    -I"$PREFIX/include/urdfdom")
LDFLAGS=(-L"$PREFIX/lib" -Wl,-rpath,"$PREFIX/lib" -lpinocchio_parsers -lpinocchio_default -lurdfdom_model)
SRC="$ROOT/scripts/bench/pinocchio_timing.cpp"
STAMP="$PIN_BIN.flags"
WANT="$($CXX --version | head -n 1) ${CXXFLAGS[*]} ${LDFLAGS[*]} $(cksum < "$SRC")"
mkdir -p "$TARGET_DIR"
if [ ! -x "$PIN_BIN" ] || [ ! -f "$STAMP" ] || [ "$(cat "$STAMP")" != "$WANT" ]; then
    echo "== compiling scripts/bench/pinocchio_timing.cpp (several minutes: Pinocchio is header templates)" >&2
    "$CXX" "${CXXFLAGS[@]}" "$SRC" -o "$PIN_BIN.tmp" "${LDFLAGS[@]}"
    mv "$PIN_BIN.tmp" "$PIN_BIN"
    printf '%s' "$WANT" > "$STAMP"
fi

# ---- 3. our timing program -----------------------------------------------------------------
HAVE_OURS=0
if [ -f "$ROOT/crates/dynamics/examples/timing.rs" ]; then
    echo "== cargo build --release -p admittance-dynamics --example timing" >&2
    RUSTFLAGS="-C target-cpu=native" CARGO_TARGET_DIR="$OURS_TARGET" cargo build --quiet --release -p admittance-dynamics --example timing
    HAVE_OURS=1
else
    echo "== crates/dynamics/examples/timing.rs does not exist yet: timing Pinocchio only" >&2
fi

# ---- 4. alternate runs ----------------------------------------------------------------------
RUNS="$(mktemp -d)"
trap 'rm -rf "$RUNS"' EXIT
for r in $(seq 1 "$ROUNDS"); do
    if [ "$HAVE_OURS" = 1 ]; then
        echo "== round $r/$ROUNDS: ours" >&2
        "$OURS_BIN" "$URDF" "$TIP" > "$RUNS/ours.$r"
    fi
    echo "== round $r/$ROUNDS: pinocchio" >&2
    "$PIN_BIN" "$URDF" "$TIP" "$STATES" "$BATCHES" "$PER_BATCH" > "$RUNS/pin.$r" 2> "$RUNS/pinerr.$r"
done

# fastest round of one algorithm's figures in files $2.* (the round least disturbed by
# other work on a shared machine)
best_of() {
    cat "$RUNS/$2".[0-9]* 2>/dev/null | awk -v a="$1" '$1 == a { print $2 }' | sort -g | head -n 1
}

# median over rounds of one algorithm's figures in files $2.*
median_of() {
    local algo="$1" side="$2"
    cat "$RUNS/$side".[0-9]* 2>/dev/null | awk -v a="$algo" '$1 == a { print $2 }' | sort -g \
        | awk '{ v[NR] = $1 } END { if (NR == 0) print "-"; else if (NR % 2) print v[(NR + 1) / 2];
                                   else print (v[NR / 2] + v[NR / 2 + 1]) / 2 }'
}

CPU="$(grep -m1 'model name' /proc/cpuinfo 2>/dev/null | sed 's/.*: //')"
echo
echo "URDF: $URDF   tip: $TIP   rounds: $ROUNDS (median of per-run medians)"
echo "CPU: ${CPU:-unknown} ($(nproc) cores)"
grep -h '^# pinocchio' "$RUNS"/pinerr.1 | sed 's/^# /Pinocchio: /' || true
echo
printf '%-10s | %10s | %15s | %18s | %18s\n' algorithm "ours (us)" "pinocchio (us)" "ratio ours/pin" "best rounds ratio"
printf '%-10s-+-%10s-+-%15s-+-%18s-+-%18s\n' ---------- ---------- --------------- ------------------ ------------------
for a in $ALGOS; do
    o="$(median_of "$a" ours)"
    p="$(median_of "$a" pin)"
    bo="$(best_of "$a" ours)"
    bp="$(best_of "$a" pin)"
    awk -v a="$a" -v o="$o" -v p="$p" -v bo="${bo:--}" -v bp="${bp:--}" 'BEGIN {
        os = (o == "-") ? "-" : sprintf("%.3f", o / 1000);
        ps = (p == "-") ? "-" : sprintf("%.3f", p / 1000);
        rs = (o == "-" || p == "-" || p == 0) ? "-" : sprintf("%.2f", o / p);
        bs = (bo == "-" || bp == "-" || bp == 0) ? "-" : sprintf("%.2f", bo / bp);
        printf "%-10s | %10s | %15s | %18s | %18s\n", a, os, ps, rs, bs }'
done
