#!/usr/bin/env bash
# Rebuilds crates/report/fonts/DejaVuSans-subset.ttf, the font embedded in every figure and
# report (so that nothing depends on the fonts of the viewer's system): DejaVu Sans reduced
# to ASCII, a few symbols and Greek. Needs Debian's fonts-dejavu-core and Python 3; installs
# fonttools from PyPI into a scratch virtual environment.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
src="${DEJAVU_TTF:-/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf}"
[ -f "$src" ] || { echo "subset_font.sh: $src not found (apt-get install fonts-dejavu-core, or set DEJAVU_TTF)" >&2; exit 1; }
venv="${TMPDIR:-/tmp}/admittance-fonttools"
[ -x "$venv/bin/pyftsubset" ] || { python3 -m venv "$venv" && "$venv/bin/pip" install -q fonttools; }
"$venv/bin/pyftsubset" "$src" \
  --unicodes="U+0020-007E,U+00B0,U+00B1,U+00B5,U+00B7,U+00D7,U+0391-03A9,U+03B1-03C9,U+2013,U+2014,U+2019,U+2022,U+2026,U+2032,U+2192,U+2212,U+2264,U+2265,U+2248,U+221A" \
  --layout-features='kern' --no-hinting --desubroutinize \
  --output-file="$root/crates/report/fonts/DejaVuSans-subset.ttf"
echo "wrote crates/report/fonts/DejaVuSans-subset.ttf"
