#!/bin/sh
# The cotton T-shirt scene with the jersey preset as the orthotropic membrane, linear in tension
# and stiffening (`tension = "stiffening"`), alternating, twice each, on the CPU path: the run's
# summary lines (seams, strain, threads, settle) and its simulation time. Run from the
# repository root. Each variant is the shipped scene with its `preset = "cotton"` line replaced
# by three lines (its relative paths made absolute) and, with $SEAM set, `seam_stiffness_n_m =
# $SEAM` added under [cloth.pattern] (default: the fabric's, twice its stiffest small-strain
# stretch); the last round's run folders are kept in $KEEP (default: none kept).
set -e
bin=${DRAPEKIT:-target/release/drapekit}
here=$(pwd)
dir=$(mktemp -d)
for tension in linear stiffening; do
  seam=""
  if [ -n "$SEAM" ]; then seam="\nseam_stiffness_n_m = $SEAM"; fi
  sed "s#\.\./#$here/fixtures/#; s/^preset = \"cotton\"/preset = \"jersey\"\nmodel = \"membrane\"\ntension = \"$tension\"/; s/^seam_sewing_time_s = 0.6/seam_sewing_time_s = 0.6$seam/" \
    fixtures/scenes/tshirt_drape_cotton.toml > "$dir/tshirt_jersey_$tension.toml"
done
for round in 1 2; do
  for tension in linear stiffening; do
    out="$dir/run_${tension}_$round"
    "$bin" run "$dir/tshirt_jersey_$tension.toml" --backend cpu --out "$out" > "$dir/log" 2>&1
    echo "== $tension, round $round"
    grep -E "^simulated|^  (seams|strain|threads|body|settled)" "$dir/log"
    if [ -n "$KEEP" ] && [ "$round" = 2 ]; then mkdir -p "$KEEP"; cp -r "$out" "$KEEP/$tension"; fi
  done
done
