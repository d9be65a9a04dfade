#!/usr/bin/env bash
# Device call 5: tests/parity.rs with the frame-by-frame trajectory check, on the H200.
set -u
source .device/setup.sh
xz -dc .dk3/parity.xz > /tmp/parity && chmod +x /tmp/parity
DRAPEKIT_REPO=$PWD DRAPEKIT_TEST_ADAPTER=auto CI=true timeout -k 5 200 /tmp/parity --nocapture > $OUT/test-parity.log 2>&1
echo "parity rc=$?"
grep -E "^test |test result|panicked|bound" $OUT/test-parity.log | head -40
