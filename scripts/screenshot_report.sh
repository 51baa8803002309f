#!/usr/bin/env bash
# Opens a run folder's report.html in headless Chromium and saves a screenshot, to check
# that the self-contained page renders (figures, tables, embedded font) without a network.
#
#   bash scripts/screenshot_report.sh runs/deadzone [OUT.png] [WIDTHxHEIGHT]
#
# Installs Debian's `chromium` when it is missing (apt-get; as root or through sudo).
set -euo pipefail
dir="${1:?usage: screenshot_report.sh RUN_DIR [OUT.png] [WIDTHxHEIGHT]}"
out="${2:-$dir/report_screenshot.png}"
size="${3:-1200x3000}"
html="$dir/report.html"
[ -f "$html" ] || { echo "screenshot_report.sh: $html not found (run \`admittance run SCENARIO --out $dir\` or \`admittance report $dir\` first)" >&2; exit 3; }

browser="$(command -v chromium || command -v chromium-browser || true)"
if [ -z "$browser" ]; then
  sudo=""; [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq chromium >/dev/null
  browser="$(command -v chromium)"
fi

abs_html="$(cd "$(dirname "$html")" && pwd)/$(basename "$html")"
abs_out="$(cd "$(dirname "$out")" && pwd)/$(basename "$out")"
profile="$(mktemp -d)"
trap 'rm -rf "$profile"' EXIT
# --no-sandbox: root in a container has no user namespaces for the sandbox.
"$browser" --headless --no-sandbox --disable-gpu --hide-scrollbars \
  --user-data-dir="$profile" --window-size="${size/x/,}" \
  --screenshot="$abs_out" "file://$abs_html" 2>/dev/null
[ -s "$abs_out" ] || { echo "screenshot_report.sh: chromium wrote no screenshot" >&2; exit 1; }
echo "wrote $out"
