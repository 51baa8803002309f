#!/usr/bin/env bash
# Experiment A (scenarios/panda_deadzone.toml) copied onto a UR5 (example-robot-data 6.0.0),
# once with the Panda's gains and once with the gains `admittance gains` prints for the UR5
# (docs/experiments.md, "Your arm's gains"). Usage: bash scripts/ur5_experiment_a.sh [WORKDIR]
set -euo pipefail
work=${1:-/tmp/ur5_experiment_a}
mkdir -p "$work"
admittance() { cargo run --quiet --release -p admittance-cli -- "$@"; }
if [ ! -d "$work/erd/cmeel.prefix" ]; then
    python3 -m pip download example-robot-data==6.0.0 --no-deps -d "$work/erd"
    (cd "$work/erd" && python3 -m zipfile -e example_robot_data-6.0.0-0-py3-none-any.whl .)
fi
ur5="$work/erd/cmeel.prefix/share/example-robot-data/robots/ur_description/urdf/ur5_robot.urdf"
pose="0,-1.5708,1.5708,-1.5708,-1.5708,0"
# The Panda's scenario on the UR5: its arm, a pose of the UR5, joint 1 = shoulder_pan_joint,
# the first six of every per-joint list (the Panda's gains).
sed -e "s|^urdf = .*|urdf = \"$ur5\"|" -e '/^base = /d' -e '/^tip = /d' \
    -e "s|^offset = .*|offset = [${pose//,/, }]|" -e 's/panda_joint1/shoulder_pan_joint/g' \
    -e 's/^name = .*/name = "ur5_deadzone"/' \
    -e 's/, 0\.2\]/]/g' -e 's/, 2\.4\]/]/g' -e 's/bound = \[6\.0, 0\.0, 0\.0, 0\.0, 0\.0, 0\.0, 0\.0\]/bound = [6.0, 0.0, 0.0, 0.0, 0.0, 0.0]/' \
    scenarios/panda_deadzone.toml > "$work/ur5_panda_gains.toml"
admittance gains --urdf "$ur5" --q="$pose" > "$work/ur5_gains.toml"
k2=$(sed -n 's/^k2 = //p' "$work/ur5_gains.toml")
kp=$(sed -n 's/^# controller.pd = { kp = \(\[[^]]*\]\).*/\1/p' "$work/ur5_gains.toml")
sed -e "s|^k2 = .*|k2 = $k2|" \
    -e "s|^controller.pd = .*|controller.pd = { kp = $kp, kd = $k2 }|" \
    "$work/ur5_panda_gains.toml" > "$work/ur5_own_gains.toml"
for g in panda_gains own_gains; do
    echo "== UR5 with the $g"
    admittance run "$work/ur5_$g.toml" --out "$work/run_$g" --force --no-recording --quiet && echo "exit 0" || echo "exit $?"
    python3 -c "
import json; s = json.load(open('$work/run_$g/summary.json'))
for v in s['variant_order']:
    m = s['variants'][v]
    print(f\"{v:24s} hand error rms {m['ee_error_rms']:.4f} m, max {m['ee_error_max']:.4f} m; health {s['health']['variants'][v]['status']}\")"
done
