#!/bin/bash
# Both builds at once, one thread each, so that both see the same machine: the shipped 5 mm
# shirt for 45 frames (33 of coarse start, then 12 of the 5 mm mesh), twice.
cd /tmp/ab2
S=/work/main/fixtures/scenes
for k in 1 2; do
  for b in old new; do
    ./b_$b --threads 1 run $S/tshirt_drape_hires.toml --backend cpu --frames 45 --quiet --out /tmp/ab2/sbs_$b$k > sbs_$b$k.log 2>&1 &
  done
  wait
  for b in old new; do echo "pair $k $b: $(grep -o 'in [0-9.]* s:' sbs_$b$k.log) coarse $(grep -o 'settled at frame [0-9]* in [0-9.]* s' sbs_$b$k.log)"; done
done
