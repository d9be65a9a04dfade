#!/usr/bin/env bash
# Device call 2: the previous build (old), this build (new: 4 blocks in flight) and a variant
# (v8: 8 in flight) side by side on the cotton T-shirt's GPU solve; profiles; the 5 mm shirt.
set -u
source .device/setup.sh
log=$OUT/run.log
say() { echo "[$(date +%T)] $*" | tee -a "$log"; }
say "call 2 on $(hostname)"
b=/root/keep/bin; mkdir -p $b /tmp/ab && tar xJf .dk2/drapekits.tar.xz -C $b
shirt=fixtures/scenes/tshirt_drape_cotton.toml
pack() { tar czf "$OUT/ab.tar.gz" -C /tmp --exclude='*.obj' --exclude='*.png' --exclude='*.gif' --exclude='*.pc2' --exclude='*.glb' --exclude='*.gltf' --exclude='*.bin' ab; }
"$b/drapekit-new" info > /tmp/ab/info.txt 2>&1
for r in 1 2; do
  for v in old new v8; do
    say "shirt $v $r"
    timeout -k 5 60 "$b/drapekit-$v" run $shirt --backend gpu --quiet --out /tmp/ab/shirt-$v-$r > /tmp/ab/shirt-$v-$r.log 2>&1
    say "  rc=$? $(grep -h '"wall_seconds"\|"frames"' /tmp/ab/shirt-$v-$r/summary.json | tr -d '\n ')"
  done
  pack
done
for v in old new v8; do
  say "profile $v"
  timeout -k 5 60 "$b/drapekit-$v" bench profile --sizes 0 --scene $shirt --frames 5 --out /tmp/ab/profile-$v > /tmp/ab/profile-$v.log 2>&1
  say "  rc=$? $(grep -h 'coarse_cycle\|smooth L0' /tmp/ab/profile-$v/profile.md | tr -d '\n')"
done
pack
say "hires new"
timeout --signal=INT -k 15 150 "$b/drapekit-new" run fixtures/scenes/tshirt_drape_hires.toml --backend gpu --quiet --out /tmp/ab/hires-new > /tmp/ab/hires-new.log 2>&1
say "  rc=$? $(grep -h '"wall_seconds"\|"frames"' /tmp/ab/hires-new/summary.json | tr -d '\n ')"
pack
say "call 2 done"
