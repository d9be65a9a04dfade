#!/usr/bin/env bash
# One device call: the implicit solve's targets on an NVIDIA H200 machine with this build.
# The cotton T-shirt on the GPU and on the machine's 16 CPU threads (alternating), the two 5 mm
# shirts on the GPU, the fabric tests on the GPU and on the CPU, the GPU's stage profile of the
# two shirts, the fabric tests to a tolerance on the GPU, and drapekit on Warp's cloth.
# Run as: source .device/setup.sh && bash benches/results/h200/converged/device-run.sh
set -u
bin=.device/drapekit
r=/tmp/r; mkdir -p $r/logs
log=$OUT/run.log
say() { echo "[$(date +%T)] $*" | tee -a "$log"; }
pack() {
  tar czf "$OUT/r.tar.gz" -C /tmp --exclude='*.obj' --exclude='*.png' --exclude='*.gif' \
    --exclude='*.pc2' --exclude='*.glb' --exclude='*.bin' --exclude='*.ckpt' r
}
# step NAME LIMIT CMD...: runs CMD under a time limit, its output in logs/NAME.log, and says its
# exit status and whole wall time.
step() {
  local name=$1 limit=$2; shift 2
  local t0=$(date +%s.%N)
  timeout --signal=INT -k 10 "$limit" "$@" > $r/logs/$name.log 2>&1
  local rc=$?
  say "$name rc=$rc whole=$(awk "BEGIN{print $(date +%s.%N) - $t0}") s"
  pack
}
{ $bin info; nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm --format=csv; lscpu | head -20; } > $r/machine.txt 2>&1
cotton=fixtures/scenes/tshirt_drape_cotton.toml
hires=fixtures/scenes/tshirt_drape_hires.toml
buckling=fixtures/scenes/tshirt_drape_hires_buckling.toml
for k in 1 2; do
  step cotton-gpu-$k 60 $bin run $cotton --backend gpu --quiet --out $r/cotton-gpu-$k
  step cotton-cpu-$k 60 $bin run $cotton --backend cpu --quiet --out $r/cotton-cpu-$k
done
step hires-gpu 120 $bin run $hires --backend gpu --quiet --out $r/hires-gpu
step buckling-gpu 120 $bin run $buckling --backend gpu --quiet --out $r/buckling-gpu
# The settled frames of the GPU's shirts, to look at.
tar cJf $OUT/frames.tar.xz -C $r $(cd $r && for d in cotton-gpu-1 hires-gpu buckling-gpu; do
  ls $d/frame_*.obj 2>/dev/null | tail -1; echo $d/scene.toml $d/summary.json; done) 2>>$log
step fabric-gpu 150 $bin bench fabric --integrator implicit --backend gpu --out $r/fabric-gpu
step fabric-cpu 150 $bin bench fabric --integrator implicit --backend cpu --out $r/fabric-cpu
step profile 90 $bin bench profile --sizes 0 --scene $cotton --frames 5 --out $r/profile-cotton
step profile-hires 90 $bin bench profile --sizes 0 --scene $hires --frames 3 --out $r/profile-hires
step fabric-gpu-tolerance 200 $bin bench fabric --integrator implicit --iterations 8 --tolerance 0.02 --backend gpu --out $r/fabric-gpu-tolerance
step peer 90 $bin bench peer --systems drapekit --sizes 128,256,512,1024 --newton-sizes 128,256 --frames 30 --out $r/peer
say done
