#!/usr/bin/env bash
# Two scenes run whole with one build, alternating, on the CPU path. Usage:
#   alternate.sh BINARY OUT_DIR ROUNDS SCENE_A SCENE_B
# Each line: the settle frame (and the coarse start's), the residual, strains and seam gap
# there, the simulation's and the whole command's wall time. Each run's folder keeps its
# summary and its last frame.
set -euo pipefail
bin=$1 out=$2 rounds=$3
shift 3
for round in $(seq "$rounds"); do
    for scene in "$@"; do
        name=$(basename "$scene" .toml)
        dir="$out/$name-$round"
        start=$(date +%s.%N)
        "$bin" run "$scene" --backend cpu --out "$dir" --quiet > /dev/null 2>&1
        end=$(date +%s.%N)
        python3 - "$dir/summary.json" "$round" "$start" "$end" "$name" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
wall = float(sys.argv[4]) - float(sys.argv[3])
coarse = s.get("coarse_start") or {}
print(f"{sys.argv[5]} run {sys.argv[2]}: settled at frame {s['settled']['frame']} "
      f"(coarse start {coarse.get('frame')}), "
      f"residual {s['force_residual_rms']:.4f}, largest strain {s['last_frame_max_edge_strain']:.4f}, "
      f"p99 {s['last_frame_edge_strain_p99']:.4f}, seam gap {s['max_seam_gap_m'] * 1000:.2f} mm, "
      f"simulation {s['wall_seconds']:.1f} s, wall {wall:.1f} s", flush=True)
PY
        # Keep the settled frame (the last written) for previews; drop the others.
        last=$(ls "$dir"/frame_*.obj | tail -1)
        find "$dir" -name 'frame_*.obj' ! -path "$last" -delete
    done
done
