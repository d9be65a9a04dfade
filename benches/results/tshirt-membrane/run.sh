#!/bin/sh
# The cotton T-shirt as shipped (isotropic springs) and with the orthotropic membrane
# (`model = "membrane"` under [fabric]), on the CPU path, each rendered as the book shows it.
# Run from the repository root: sh benches/results/tshirt-membrane/run.sh [DRAPEKIT]
set -e
DK=${1:-target/release/drapekit}
OUT=out/tshirt-membrane
mkdir -p "$OUT"
MEMBRANE=fixtures/scenes/.tshirt_membrane.toml
sed 's/^preset = "cotton"/preset = "cotton"\nmodel = "membrane"/' \
    fixtures/scenes/tshirt_drape_cotton.toml > "$MEMBRANE"
trap 'rm -f "$MEMBRANE"' EXIT
for v in springs:fixtures/scenes/tshirt_drape_cotton.toml membrane:$MEMBRANE; do
    name=${v%%:*}; scene=${v#*:}
    echo "== $name ($scene)"
    "$DK" run "$scene" --backend cpu --out "$OUT/$name" 2>&1 | grep -v "^drapekit: "
    "$DK" preview "$OUT/$name" --camera three-quarter --seams --size 800x600 \
        --out "$OUT/$name.png"
done
