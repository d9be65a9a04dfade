#!/bin/bash
# Alternating A/B of the buckling shirt, after alternate.sh and side-by-side.sh.
cd /tmp/ab2
S=/work/main/fixtures/scenes
for k in 1 2; do for b in old new; do
  /usr/bin/time -f "WALL %e" ./b_$b run $S/tshirt_drape_hires_buckling.toml --backend cpu --out /tmp/ab2/buck_$b$k > buck_$b$k.log 2>&1
  echo "buckling $b $k $(grep WALL buck_$b$k.log) $(grep -o 'settled at frame [0-9]*\|in [0-9.]* s:' buck_$b$k.log | tr '\n' ' ')"
done; done
