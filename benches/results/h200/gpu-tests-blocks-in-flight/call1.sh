#!/usr/bin/env bash
# Device call 1: the GPU tests of this build on the device's GPU; results to $OUT.
set -u
source .device/setup.sh
log=$OUT/run.log
say() { echo "[$(date +%T)] $*" | tee -a "$log"; }
say "call 1 on $(hostname)"; nvidia-smi --query-gpu=name,driver_version,clocks.sm --format=csv | tee -a "$log"
mkdir -p /root/keep/bin /tmp/tests && tar xJf .dk1/tests.tar.xz -C /root/keep/bin
export DRAPEKIT_TEST_ADAPTER=auto CI=true DRAPEKIT_REPO=$PWD
for t in implicit_stages implicit_gpu gpu_layout parity; do
  say "test $t"
  timeout -k 5 150 /root/keep/bin/$t > /tmp/tests/test-$t.log 2>&1
  echo "$t rc=$?" | tee -a /tmp/tests/test-rc.txt "$log"
  grep -E "^test |test result" /tmp/tests/test-$t.log | tee -a "$log" >/dev/null
  tar czf "$OUT/tests.tar.gz" -C /tmp tests
done
say "call 1 done"
