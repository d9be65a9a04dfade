#!/usr/bin/env bash
# Device call 6: the final build on the cotton T-shirt (GPU, and CPU on 16 threads) and drapekit
# bench, in one run.
set -u
source .device/setup.sh
xz -dc .dk3/drapekit.xz > /tmp/drapekit && chmod +x /tmp/drapekit
mkdir -p /tmp/c6; log=$OUT/run.log
say() { echo "[$(date +%T)] $*" | tee -a "$log"; }
pack() { tar czf "$OUT/c6.tar.gz" -C /tmp --exclude='*.obj' --exclude='*.png' --exclude='*.gif' --exclude='*.pc2' --exclude='*.glb' --exclude='*.bin' --exclude=scene.toml c6; }
shirt=fixtures/scenes/tshirt_drape_cotton.toml
for b in gpu cpu gpu cpu; do
  timeout -k 5 60 /tmp/drapekit run $shirt --backend $b --quiet --out /tmp/c6/shirt-$b-$SECONDS > /tmp/c6/shirt-$b-$SECONDS.log 2>&1
  say "shirt $b rc=$?"
done
grep -h '"wall_seconds"\|"frames"\|"backend"' /tmp/c6/shirt-*/summary.json | tr -d ' \n' | tee -a "$log"; echo | tee -a "$log"
pack
timeout -k 5 90 /tmp/drapekit bench --sizes 128,256,512,1024 --out /tmp/c6/bench > /tmp/c6/bench.log 2>&1
say "bench rc=$?"; tail -n 12 /tmp/c6/bench.log | tee -a "$log"
pack
