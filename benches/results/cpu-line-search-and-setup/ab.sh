#!/usr/bin/env bash
# Alternating A/B of two drapekit builds on the shipped 5 mm T-shirt, whole command, the machine
# otherwise idle (README.md says which builds each log compares).
# Usage: ab.sh OLD_BINARY NEW_BINARY ROUNDS
set -euo pipefail
old=$1 new=$2 rounds=${3:-2}
scene=fixtures/scenes/tshirt_drape_hires.toml
for r in $(seq 1 "$rounds"); do
  for b in old new; do
    bin=${!b}
    out=$(mktemp -d)
    start=$(date +%s.%N)
    "$bin" run "$scene" --backend cpu --quiet --out "$out/run" > "$out/log" 2>&1
    end=$(date +%s.%N)
    sim=$(python3 -c "import json;d=json.load(open('$out/run/summary.json'));print(d['wall_seconds'], d['coarse_start']['wall_seconds'], d['frames'])")
    printf '%s round %s: whole command %.1f s; full mesh, coarse start (s), settled frame: %s\n' \
      "$b" "$r" "$(echo "$end - $start" | bc)" "$sim"
    sha256sum "$out/run/frame_0072.obj" | cut -c1-16
    rm -rf "$out"
  done
done
