"""The settled skirts' shape: where the waist rests and how wide the hem hangs.

For each run directory: its last frame (the highest-numbered frame_*.obj), and from summary.json
the frame it settled at, its largest edge strain and, for a membrane, its thread strain and
shear. The waist is the height of the skirt's highest particle; the hem radius is the mean
horizontal distance, from the skirt's centre (the mean x and z of all its particles), of the
particles within 1 cm of its lowest one.
"""
import glob
import json
import math
import os
import sys


def positions(path):
    with open(path) as f:
        return [tuple(map(float, l.split()[1:4])) for l in f if l.startswith("v ")]


def measure(run):
    last = sorted(glob.glob(os.path.join(run, "frame_*.obj")))[-1]
    p = positions(last)
    cx = sum(x for x, _, _ in p) / len(p)
    cz = sum(z for _, _, z in p) / len(p)
    low = min(y for _, y, _ in p)
    hem = [math.hypot(x - cx, z - cz) for x, y, z in p if y < low + 0.01]
    s = json.load(open(os.path.join(run, "summary.json")))
    settled = f"settled at frame {s['settled']['frame']}" if s["settled"] else "not settled"
    line = (f"{os.path.basename(run)}: {settled} of {s['frames']}; "
            f"waist {max(y for _, y, _ in p):.3f} m, hem radius {100 * sum(hem) / len(hem):.1f} cm "
            f"({len(hem)} particles); edge strain {100 * s['last_frame_max_edge_strain']:.1f}% largest")
    t = s.get("last_frame_thread_strain")
    if t:
        line += f"; threads {json.dumps(t)}"
    print(line)


for run in sys.argv[1:]:
    measure(run)
