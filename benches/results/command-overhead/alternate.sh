#!/bin/bash
# Alternating A/B of two builds: before the whole-command overhead changes (old) and after (final).
# Usage: BIN_DIR=DIR OUT_DIR=DIR alternate.sh, with DIR/drapekit_old and DIR/drapekit_final the two
# builds. Prints the whole command's wall time, the simulation time the summary reports
# (wall_seconds) and the settled frame.
cd "$(dirname "$0")/../../.."
run() { # bin scene tag
  local out="${OUT_DIR:?set OUT_DIR}/ab_$3"
  rm -rf "$out"
  local s=$(date +%s.%N)
  "${BIN_DIR:?set BIN_DIR}/drapekit_$1" run "fixtures/scenes/$2.toml" --backend cpu --out "$out" --quiet >/dev/null 2>&1
  local e=$(date +%s.%N)
  python3 -c "import json;s=json.load(open('$out/summary.json'));print('$1 $2 whole %.2f sim %.2f settled %s' % ($e-$s, s['wall_seconds'], s['settled']['frame']))"
}
for i in 1 2; do
  run old tshirt_drape_hires h_old_$i; run final tshirt_drape_hires h_final_$i
done
run old tshirt_drape_hires_buckling b_old; run final tshirt_drape_hires_buckling b_final
for i in 1 2 3; do
  run old tshirt_drape_cotton c_old_$i; run final tshirt_drape_cotton c_final_$i
done
date
