#!/usr/bin/env bash
# The 5 mm T-shirt run whole with two builds, alternating: OLD (the line search on G's change
# alone) and NEW (a change within its rounding decided by G's slopes). Usage:
#   alternate.sh OLD_BINARY NEW_BINARY OUT_DIR
set -euo pipefail
old=$1 new=$2 out=$3
scene=fixtures/scenes/tshirt_drape_hires.toml
for round in 1 2; do
    for which in old new; do
        bin=$old
        if [ "$which" = new ]; then bin=$new; fi
        start=$(date +%s.%N)
        "$bin" run "$scene" --backend cpu --out "$out/$which-$round" --quiet > /dev/null
        end=$(date +%s.%N)
        python3 - "$out/$which-$round/summary.json" "$which" "$round" "$start" "$end" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
wall = float(sys.argv[5]) - float(sys.argv[4])
print(f"{sys.argv[2]} run {sys.argv[3]}: settled at frame {s['settled']['frame']}, "
      f"residual {s['force_residual_rms']:.4f}, largest strain {s['last_frame_max_edge_strain']:.4f}, "
      f"p99 {s['last_frame_edge_strain_p99']:.4f}, wall {wall:.1f} s")
PY
    done
done
