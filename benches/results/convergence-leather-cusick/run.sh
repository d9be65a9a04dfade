#!/bin/sh
# Newton's convergence on the leather Cusick specimen (isotropic springs, 4 implicit steps a
# frame), on the substep after frame 30, with 8 (shipped), 32 and 128 conjugate-gradient
# iterations per Newton step. Run from the repository root; writes li-8/, li-32/, li-128/ here.
set -e
bin=${DRAPEKIT:-target/release/drapekit}
here=benches/results/convergence-leather-cusick
tmp=$(mktemp -d)
"$bin" bench fabric --integrator implicit --presets leather --tests cusick --out "$tmp" > /dev/null
for n in 8 32 128; do
  "$bin" bench convergence "$tmp/specimens/cusick-leather/scene.toml" --frames 30 \
    --refinements 1 --max-newton 8 --max-sweeps 64 --linear-iterations "$n" --out "$here/li-$n" > /dev/null
done
