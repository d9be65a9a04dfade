#!/bin/bash
# Alternating A/B, whole command wall time, 2-core machine otherwise idle.
cd /tmp/ab2
S=/work/main/fixtures/scenes
for k in 1 2; do for b in old new; do
  /usr/bin/time -f "WALL %e" ./b_$b run $S/tshirt_drape_hires.toml --backend cpu --out /tmp/ab2/hires_$b$k > hires_$b$k.log 2>&1
  echo "hires $b $k $(grep WALL hires_$b$k.log) $(grep -o 'settled at frame [0-9]*\|in [0-9.]* s:' hires_$b$k.log | tr '\n' ' ')"
done; done
for k in 1 2 3; do for b in old new; do
  /usr/bin/time -f "WALL %e" ./b_$b run $S/tshirt_drape_cotton.toml --backend cpu --out /tmp/ab2/cotton_$b$k > cotton_$b$k.log 2>&1
  echo "cotton $b $k $(grep WALL cotton_$b$k.log) $(grep -o 'in [0-9.]* s:' cotton_$b$k.log)"
done; done
