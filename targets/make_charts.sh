#!/usr/bin/env bash
# Regenerates the shipped charts (PNG, 600 dpi) and their descriptions.
# Charts go to ${OUT:-out/charts}; the descriptions are copied to targets/.
# Usage: bash targets/make_charts.sh            (from the repository root)
set -euo pipefail
OUT=${OUT:-out/charts}
BIN=${BIN:-target/release/sweepmtf}
[ -x "$BIN" ] || cargo build --release
mkdir -p "$OUT"
chart() { "$BIN" chart "$@"; }
# Log sweeps, 0.1–5 cy/mm, three contrast rows (0.8 main, 0.4, 0.2).
chart --law log    --f-min 0.1 --f-max 5 --size A4 --dpi 600 --contrasts 0.8,0.4,0.2 -o "$OUT/a4_log.png"
chart --law log    --f-min 0.1 --f-max 5 --size A3 --dpi 600 --contrasts 0.8,0.4,0.2 -o "$OUT/a3_log.png"
# Linear sweeps, 0.1–5 cy/mm, contrast 0.8.
chart --law linear --f-min 0.1 --f-max 5 --size A4 --dpi 600 -o "$OUT/a4_linear.png"
chart --law linear --f-min 0.1 --f-max 5 --size A3 --dpi 600 -o "$OUT/a3_linear.png"
# Twelve constant-frequency sine patches, 0.2–5 cy/mm, contrasts 0.8 and 0.3.
chart --law patches --f-min 0.2 --f-max 5 --patches 12 --size A4 --dpi 600 --contrasts 0.8,0.3 -o "$OUT/a4_patches.png"
for n in a4_log a3_log a4_linear a3_linear a4_patches; do
  cp "$OUT/$n.toml" "targets/$n.toml"
done
