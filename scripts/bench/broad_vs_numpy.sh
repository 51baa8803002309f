#!/usr/bin/env bash
# Times the broad RBF network fit at the paper's size (N = 450,000, L = 1000, d_in = 21,
# d_out = 7; docs/method.md section 5) in Rust and in numpy on the same data, centres and widths,
# checks that both give the same weights, times a growth by 100 nodes against a full
# retrain, and reports peak memory.
#
#   scripts/bench/broad_vs_numpy.sh [--rows N] [--nodes L] [--threads T] [--rounds R]
#
# The ratio to numpy comes from R rounds (default 3) that each run one Rust fit and one
# numpy fit back to back, so that both see the same load on this shared machine; the
# script prints every round's ratio and their median.
#
# Needs python3 (a scratch venv .venv-bench with numpy and scipy is made if missing).
# Scratch files go to $BROAD_BENCH_DIR (default: a temporary directory, removed at exit).
set -euo pipefail
cd "$(dirname "$0")/../.."

ROWS=450000
NODES=1000
THREADS=0
ROUNDS=3
while [[ $# -gt 0 ]]; do
  case "$1" in
    --rows) ROWS="$2"; shift 2 ;;
    --nodes) NODES="$2"; shift 2 ;;
    --threads) THREADS="$2"; shift 2 ;;
    --rounds) ROUNDS="$2"; shift 2 ;;
    *) echo "unknown argument $1" >&2; exit 2 ;;
  esac
done

export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$PWD/target}"
VENV=.venv-bench
if ! "$VENV/bin/python" -c 'import numpy, scipy' 2>/dev/null; then
  python3 -m venv "$VENV"
  "$VENV/bin/pip" install -q numpy scipy
fi

DIR="${BROAD_BENCH_DIR:-}"
if [[ -z "$DIR" ]]; then
  DIR="$(mktemp -d)"
  trap 'rm -rf "$DIR"' EXIT
fi
mkdir -p "$DIR"

cargo build --release -q -p admittance-learning --example broad_train_timing
BIN="$CARGO_TARGET_DIR/release/examples/broad_train_timing"

echo "== Rust (release): fit with centres + lambda scan, fixed-node refit, growth by 100 ==" >&2
/usr/bin/time -v "$BIN" --rows "$ROWS" --nodes "$NODES" --threads "$THREADS" --out "$DIR" \
  > "$DIR/rust.json" 2> "$DIR/rust.time"

echo "== numpy: same fit (features + Gram + Cholesky solve), two Gram variants ==" >&2
for mode in matmul syrk; do
  /usr/bin/time -v "$VENV/bin/python" scripts/bench/broad_numpy.py "$DIR" --gram "$mode" \
    > "$DIR/numpy_$mode.json" 2> "$DIR/numpy_$mode.time"
done

echo "== $ROUNDS alternating rounds: one Rust fit, one numpy (A.T @ A) fit ==" >&2
for ((r = 1; r <= ROUNDS; r++)); do
  "$BIN" --threads "$THREADS" --fixed-from "$DIR" > "$DIR/round_${r}_rust.json"
  "$VENV/bin/python" scripts/bench/broad_numpy.py "$DIR" --gram matmul --repeat 1 \
    > "$DIR/round_${r}_numpy.json"
done

ROUNDS="$ROUNDS" "$VENV/bin/python" - "$DIR" <<'EOF'
import json, re, sys, os
d = sys.argv[1]
def maxrss(f):
    m = re.search(r"Maximum resident set size \(kbytes\): (\d+)", open(f).read())
    return int(m.group(1)) / 1024.0 if m else float("nan")
r = json.load(open(os.path.join(d, "rust.json")))
fr = r["fit_report"]
print(f"rows {r['rows']}, nodes {r['nodes']}, pattern width {fr['pattern_width']}, chosen lambda_rel {fr['lambda_rel']:g}")
print(f"Rust full fit (centres + Gram + {len(fr['lambda_scan'])} lambdas + validation): {fr['times']['total_s']:.2f} s "
      f"(gram {fr['times']['gram_s']:.2f}, solve {fr['times']['solve_s']:.2f}, validation {fr['times']['validation_s']:.2f})")
rust = r["fixed_nodes_fit_s"]
print(f"Rust fixed-node fit (features + Gram + solve): {rust:.2f} s (fastest of {[round(v, 2) for v in r['fixed_nodes_fit_runs_s']]}), "
      f"CPU {r['fixed_nodes_fit_cpu_s']:.2f} s")
print(f"Rust features-only pass over the training data: {r['features_pass_s']:.2f} s")
for mode in ("matmul", "syrk"):
    n = json.load(open(os.path.join(d, f"numpy_{mode}.json")))
    print(f"numpy ({mode}) same fit: {n['total_s']:.2f} s (fastest of {[round(v, 2) for v in n['runs_s']]})   Rust/numpy = {rust / n['total_s']:.3f}   "
          f"CPU {n['cpu_s']:.2f} s (Rust/numpy {r['fixed_nodes_fit_cpu_s'] / n['cpu_s']:.3f})   weights rel diff {n['weights_rel_diff_vs_rust']:.2e}   peak RSS {maxrss(os.path.join(d, f'numpy_{mode}.time')):.0f} MB")
rounds = []
for k in range(1, int(os.environ.get("ROUNDS", "0")) + 1):
    a = json.load(open(os.path.join(d, f"round_{k}_rust.json")))
    b = json.load(open(os.path.join(d, f"round_{k}_numpy.json")))
    rounds.append((a["fixed_nodes_fit_s"], b["total_s"], a["weights_rel_diff"]))
if rounds:
    ratios = sorted(x / y for x, y, _ in rounds)
    med = ratios[len(ratios) // 2] if len(ratios) % 2 else 0.5 * (ratios[len(ratios) // 2 - 1] + ratios[len(ratios) // 2])
    print("alternating rounds (Rust s, numpy A.T @ A s, ratio): "
          + ", ".join(f"({x:.2f}, {y:.2f}, {x / y:.3f})" for x, y, _ in rounds))
    print(f"median Rust/numpy over {len(rounds)} alternating rounds: {med:.3f} "
          f"(Rust weights equal to the first run's to {max(w for _, _, w in rounds):.1e})")
g = r.get("growth")
if g:
    print(f"growth by {g['nodes_added']} nodes: {g['grow_s']:.2f} s (cross terms {g['grow_cross_terms_s']:.2f}), "
          f"fixed-node retrain on the grown nodes {g['retrain_s']:.2f} s, ratio {g['grow_over_retrain']:.3f}; "
          f"ratio to the full fit {g['grow_over_full_fit']:.3f}; CPU ratio {min(g['grow_cpu_s']) / min(g['retrain_cpu_s']):.3f}; "
          f"weights rel diff vs retrain {g['weights_rel_diff_vs_retrain']:.1e}")
print(f"Rust peak RSS (whole example, data sets included): {maxrss(os.path.join(d, 'rust.time')):.0f} MB")
print(f"exp: fast {r['fast_exp_ns_per_value']:.2f} ns/value, libm {r['libm_exp_ns_per_value']:.2f} ns/value")
EOF
