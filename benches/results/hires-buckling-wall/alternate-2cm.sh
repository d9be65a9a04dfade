#!/bin/sh
# The 2 cm cotton T-shirt as shipped and with `compression = "buckling"` added under [fabric]
# (a copy of the scene, its relative paths made absolute), alternating, twice each: the
# simulation time and settle frame that `drapekit run` prints.
set -e
bin=${DRAPEKIT:-target/release/drapekit}
here=$(pwd)
variant=$(mktemp -d)/tshirt_drape_cotton_buckling.toml
sed "s#\.\./#$here/fixtures/#; s/^preset = \"cotton\"/preset = \"cotton\"\ncompression = \"buckling\"/" \
  fixtures/scenes/tshirt_drape_cotton.toml > "$variant"
for round in 1 2; do
  for scene in fixtures/scenes/tshirt_drape_cotton.toml "$variant"; do
    out=$(mktemp -d)
    "$bin" run "$scene" --backend cpu --quiet --out "$out/run" > "$out/log" 2>&1
    printf '%s round %s: %s; %s\n' "$(basename "$scene" .toml)" "$round" \
      "$(grep -o 'in [0-9.]* s:' "$out/log")" "$(grep -o 'settled  yes, at frame [0-9]*' "$out/log")"
    rm -rf "$out"
  done
done
