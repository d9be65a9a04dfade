#!/usr/bin/env bash
# Device call 4: GPU tests of the workgroup-memory build; the cotton T-shirt with the previous
# build (base), coarse levels smoothed in workgroup memory (cache4) and that with eight blocks
# in flight in the coarse cycle (cache8), side by side; profiles; the 5 mm shirt; implicit rows.
set -u
source .device/setup.sh
log=$OUT/run.log
say() { echo "[$(date +%T)] $*" | tee -a "$log"; }
say "call 4 on $(hostname)"; nvidia-smi --query-gpu=name,driver_version --format=csv | tee -a "$log"
b=/tmp/bin; mkdir -p $b /tmp/c4 && tar xJf .dk3/bins.tar.xz -C $b
pack() { tar czf "$OUT/c4.tar.gz" -C /tmp --exclude='*.obj' --exclude='*.png' --exclude='*.gif' --exclude='*.pc2' --exclude='*.glb' --exclude='*.bin' --exclude=scene.toml c4; }
export DRAPEKIT_REPO=$PWD
for t in implicit_stages implicit_gpu gpu_layout; do
  say "test $t"
  DRAPEKIT_TEST_ADAPTER=auto CI=true timeout -k 5 120 $b/$t > /tmp/c4/test-$t.log 2>&1
  say "  $t rc=$? $(grep 'test result' /tmp/c4/test-$t.log)"
done
pack
shirt=fixtures/scenes/tshirt_drape_cotton.toml
for r in 1 2; do
  for v in base cache4 cache8; do
    timeout -k 5 60 $b/drapekit-$v run $shirt --backend gpu --quiet --out /tmp/c4/shirt-$v-$r > /tmp/c4/shirt-$v-$r.log 2>&1
    say "shirt $v $r rc=$? $(grep -h '"wall_seconds"\|"frames"' /tmp/c4/shirt-$v-$r/summary.json | tr -d '\n ')"
  done
done
pack
for v in base cache4 cache8; do
  timeout -k 5 60 $b/drapekit-$v bench profile --sizes 0 --scene $shirt --frames 5 --out /tmp/c4/profile-$v > /tmp/c4/profile-$v.log 2>&1
  say "profile $v rc=$? $(grep -h 'GPU .*µs\|coarse_cycle\|smooth L0' /tmp/c4/profile-$v/profile.md | tr -d '\n')"
done
pack
for v in base cache4; do
  timeout -k 5 60 $b/drapekit-$v bench peer --systems drapekit --sizes 128 --newton-sizes 128,256 --frames 30 --out /tmp/c4/peer-$v > /tmp/c4/peer-$v.log 2>&1
  say "peer $v rc=$? $(grep -h 'gpu,.*implicit' /tmp/c4/peer-$v/peer.csv | cut -d, -f3,6 | tr '\n' ' ')"
  pack
done
timeout --signal=INT -k 15 120 $b/drapekit-cache4 run fixtures/scenes/tshirt_drape_hires.toml --backend gpu --quiet --out /tmp/c4/hires-cache4 > /tmp/c4/hires-cache4.log 2>&1
say "hires cache4 rc=$? $(grep -h '"wall_seconds"\|"frames"' /tmp/c4/hires-cache4/summary.json | tr -d '\n ')"
pack
say "call 4 done"
