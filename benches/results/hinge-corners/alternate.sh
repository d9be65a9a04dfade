#!/usr/bin/env bash
# A scene run whole with two builds, alternating: OLD (each hinge's corners as world positions
# xₙ + D) and NEW (relative to the hinge's first vertex). Usage:
#   alternate.sh OLD_BINARY NEW_BINARY OUT_DIR SCENE ROUNDS
set -euo pipefail
old=$1 new=$2 out=$3 scene=$4 rounds=$5
name=$(basename "$scene" .toml)
for round in $(seq "$rounds"); do
    for which in old new; do
        bin=$old
        if [ "$which" = new ]; then bin=$new; fi
        dir="$out/$name-$which-$round"
        start=$(date +%s.%N)
        "$bin" run "$scene" --backend cpu --out "$dir" --quiet > /dev/null 2>&1
        end=$(date +%s.%N)
        python3 - "$dir/summary.json" "$which" "$round" "$start" "$end" "$name" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
wall = float(sys.argv[5]) - float(sys.argv[4])
print(f"{sys.argv[6]} {sys.argv[2]} run {sys.argv[3]}: settled at frame {s['settled']['frame']}, "
      f"residual {s['force_residual_rms']:.4f}, largest strain {s['last_frame_max_edge_strain']:.4f}, "
      f"p99 {s['last_frame_edge_strain_p99']:.4f}, seam gap {s['max_seam_gap_m'] * 1000:.2f} mm, "
      f"simulation {s['wall_seconds']:.1f} s, wall {wall:.1f} s")
PY
    done
done
