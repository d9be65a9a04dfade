#!/bin/sh
# The cotton skirt three ways: isotropic springs, the orthotropic membrane on the straight grain,
# and the membrane on the bias. Run from the repository root:
#   sh benches/results/skirt-grain/run.sh [DRAPEKIT]
# Writes each run to out/skirt-grain/<variant>/ and prints measure.py's figures.
set -e
DK=${1:-target/release/drapekit}
OUT=out/skirt-grain
mkdir -p "$OUT"
# The springs variant: skirt_straight_grain.toml with the membrane lines replaced (kept next to
# the fixtures so that its relative paths resolve).
SPRINGS=fixtures/scenes/.skirt_springs.toml
sed 's/^model = "membrane"/model = "springs"/; /^grain_deg/d' \
    fixtures/scenes/skirt_straight_grain.toml > "$SPRINGS"
trap 'rm -f "$SPRINGS"' EXIT
for v in springs:$SPRINGS straight:fixtures/scenes/skirt_straight_grain.toml \
         bias:fixtures/scenes/skirt_bias_cut.toml; do
    name=${v%%:*}; scene=${v#*:}
    echo "== $name ($scene)"
    "$DK" run "$scene" --backend cpu --out "$OUT/$name" --quiet
    "$DK" preview "$OUT/$name" --camera front --checker 0.05 --size 800x600 \
        --out "$OUT/$name.png"
done
python3 benches/results/skirt-grain/measure.py "$OUT/springs" "$OUT/straight" "$OUT/bias"
