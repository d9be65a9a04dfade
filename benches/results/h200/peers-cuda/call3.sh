#!/usr/bin/env bash
# Device call 3: Warp and Newton on CUDA beside this build on Warp's cloth; the CPU's implicit
# rows on 2 and 16 threads.
set -u
source .device/setup.sh
log=$OUT/run.log
say() { echo "[$(date +%T)] $*" | tee -a "$log"; }
say "call 3 on $(hostname); PYTHONPATH=${PYTHONPATH:-}"
b=/root/keep/bin; mkdir -p $b /tmp/pr && tar xJf .dk2/drapekits.tar.xz -C $b
python3 -c "import warp, newton, numpy; print('warp', warp.__version__, 'newton', newton.__version__, 'numpy', numpy.__version__)" 2>&1 | tail -n 2 | tee -a "$log"
pack() { tar czf "$OUT/peers.tar.gz" -C /tmp pr; }
say "peers"
PYTHONUNBUFFERED=1 timeout -k 10 330 "$b/drapekit-new" bench peer --systems drapekit,warp,newton --sizes 128,256,512,1024 --newton-sizes 128,256 --frames 30 --python "$(command -v python3)" --no-venv --venv /tmp/pr/peer-driver --out /tmp/pr/peers > /tmp/pr/peers.log 2>&1
say "  rc=$?"; tail -n 40 /tmp/pr/peers.log >> "$log"
pack
for t in 2 16; do
  say "threads $t"
  timeout -k 5 60 "$b/drapekit-new" --threads $t bench peer --systems drapekit --sizes 128 --newton-sizes 128,256 --frames 10 --out /tmp/pr/threads_$t > /tmp/pr/threads_$t.log 2>&1
  say "  rc=$?"; pack
done
say "call 3 done"
