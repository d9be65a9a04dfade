#!/bin/sh
# The 5 mm cotton T-shirt (tshirt_drape_hires.toml) with the orthotropic membrane, on the CPU
# path, rendered as the book's 5 mm pictures are. Run from the repository root:
#   sh benches/results/tshirt-membrane/run-hires.sh [DRAPEKIT]
set -e
DK=${1:-target/release/drapekit}
OUT=out/tshirt-membrane
mkdir -p "$OUT"
MEMBRANE=fixtures/scenes/.tshirt_hires_membrane.toml
sed 's/^preset = "cotton"/preset = "cotton"\nmodel = "membrane"/' \
    fixtures/scenes/tshirt_drape_hires.toml > "$MEMBRANE"
trap 'rm -f "$MEMBRANE"' EXIT
"$DK" run "$MEMBRANE" --backend cpu --out "$OUT/hires-membrane"
"$DK" preview "$OUT/hires-membrane" --camera front --size 600x600 --out "$OUT/hires-membrane.png"
