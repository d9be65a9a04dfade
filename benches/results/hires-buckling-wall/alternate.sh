#!/bin/sh
# The 5 mm T-shirt with linear springs and with springs that buckle, alternating, twice each:
# the whole command's wall time, where it settled, and a hash of the final frame.
set -e
bin=${DRAPEKIT:-target/release/drapekit}
for round in 1 2; do
  for scene in tshirt_drape_hires tshirt_drape_hires_buckling; do
    out=$(mktemp -d)
    start=$(date +%s.%N)
    "$bin" run fixtures/scenes/$scene.toml --backend cpu --quiet --out "$out/run" > "$out/log" 2>&1
    end=$(date +%s.%N)
    settled=$(grep -o 'settled  yes, at frame [0-9]*' "$out/log" | grep -o '[0-9]*$')
    last=$(ls "$out"/run/frame_*.obj | tail -1)
    printf '%s round %s: %.1f s, settled at frame %s, %s %s\n' "$scene" "$round" \
      "$(echo "$end - $start" | bc)" "$settled" "$(basename "$last")" \
      "$(sha256sum "$last" | cut -c1-16)"
    rm -rf "$out"
  done
done
