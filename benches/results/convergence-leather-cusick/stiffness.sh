#!/bin/sh
# Is it leather's in-plane stiffness that the multigrid preconditioner carries less well? The
# leather Cusick specimen's substep after frame 30 with the shipped 8 conjugate-gradient
# iterations, the specimen's stretch stiffness set to cotton's 4,050 N/m, left at leather's
# 57,800 N/m, and raised tenfold (578,000 N/m), leather's bending and mass kept; and the cotton
# specimen as it is. Run from the repository root; writes stretch-*/ and cotton/ here.
set -e
bin=${DRAPEKIT:-target/release/drapekit}
here=benches/results/convergence-leather-cusick
tmp=$(mktemp -d)
"$bin" bench fabric --integrator implicit --presets leather,cotton --tests cusick --out "$tmp" > /dev/null
leather=$tmp/specimens/cusick-leather
for k in 4050 57800 578000; do
  sed "s/^preset = \"leather\"/preset = \"leather\"\nstretch_stiffness_n_m = $k.0/" \
    "$leather/scene.toml" > "$leather/scene-$k.toml"
  "$bin" bench convergence "$leather/scene-$k.toml" --frames 30 --refinements 1 \
    --max-newton 8 --max-sweeps 64 --out "$here/stretch-$k" > /dev/null
done
"$bin" bench convergence "$tmp/specimens/cusick-cotton/scene.toml" --frames 30 --refinements 1 \
  --max-newton 8 --max-sweeps 64 --out "$here/cotton" > /dev/null
# Each Newton step's linear residual |f − H·c|/|f| after its 8 iterations, multigrid and
# block-Jacobi preconditioned, and the RMS force residual over the weight after each step.
for d in stretch-4050 stretch-57800 stretch-578000 cotton; do
  for m in newton-multigrid newton-block-jacobi; do
    printf '%s %s linear:' "$d" "$m"
    grep ",$m," "$here/$d/convergence.csv" | cut -d, -f9 | tr '\n' ' '
    printf '\n%s %s force rms:' "$d" "$m"
    grep ",$m," "$here/$d/convergence.csv" | cut -d, -f8 | tr '\n' ' '
    echo
  done
done
