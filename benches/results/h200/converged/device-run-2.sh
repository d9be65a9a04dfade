#!/usr/bin/env bash
# Second device call: the two 5 mm shirts again on the GPU, and on the machine's 16 CPU threads,
# alternating, for the spread of their times and the CPU beside the GPU.
# Run as: source .device/setup.sh && bash benches/results/h200/converged/device-run-2.sh
set -u
bin=.device/drapekit
r=/tmp/r2; mkdir -p $r/logs
log=$OUT/run2.log
say() { echo "[$(date +%T)] $*" | tee -a "$log"; }
pack() {
  tar czf "$OUT/r2.tar.gz" -C /tmp --exclude='*.obj' --exclude='*.png' --exclude='*.gif' \
    --exclude='*.pc2' --exclude='*.glb' --exclude='*.bin' --exclude='*.ckpt' r2
}
step() {
  local name=$1 limit=$2; shift 2
  local t0=$(date +%s.%N)
  timeout --signal=INT -k 10 "$limit" "$@" > $r/logs/$name.log 2>&1
  local rc=$?
  say "$name rc=$rc whole=$(awk "BEGIN{print $(date +%s.%N) - $t0}") s"
  pack
}
hires=fixtures/scenes/tshirt_drape_hires.toml
buckling=fixtures/scenes/tshirt_drape_hires_buckling.toml
# The body's distance field, baked once before the timed runs (as in the first call).
step warm 60 $bin run fixtures/scenes/tshirt_drape_cotton.toml --backend cpu --quiet --frames 1 --out $r/warm
step hires-gpu-2 90 $bin run $hires --backend gpu --quiet --out $r/hires-gpu-2
step hires-cpu-1 120 $bin run $hires --backend cpu --quiet --out $r/hires-cpu-1
step buckling-gpu-2 90 $bin run $buckling --backend gpu --quiet --out $r/buckling-gpu-2
step buckling-cpu-1 120 $bin run $buckling --backend cpu --quiet --out $r/buckling-cpu-1
say done
