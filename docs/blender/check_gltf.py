"""Checks the book's Blender steps for the glTF export (docs/src/exports.md).

Imports RUN/garment.glb with Blender's glTF importer, Merge Vertices on (the book's one
setting), and checks that:
- the garment is one object whose mesh is one connected piece, with one material per panel
  (the panels' groups in drapekit's frame_NNNN.obj);
- the animation plays: at each frame the glTF holds, every vertex of Blender's evaluated garment
  lies within TOL of a particle of drapekit's frame_NNNN.obj, and every particle within TOL of a
  vertex. A welded seam vertex is the mean of particles less than seam_closed_gap_m (1 mm by
  default) apart, so it lies within 1 mm of each of them; TOL is 1 mm.

    python check_gltf.py RUN           # Blender as a Python module: pip install bpy
    blender -b -P check_gltf.py -- RUN

Prints what it checked and exits 1 on any failure.
"""
import json
import os
import sys

import bpy
import bmesh  # importable once bpy is
import numpy as np

TOL = 1e-3
run = sys.argv[-1]
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=os.path.join(run, "garment.glb"), merge_vertices=True)
garment = bpy.data.objects["garment"]
failures = []


def islands(mesh):
    """Connected pieces of a mesh, by shared edges."""
    bm = bmesh.new()
    bm.from_mesh(mesh)
    seen, count = set(), 0
    for v in bm.verts:
        if v.index in seen:
            continue
        count += 1
        stack = [v]
        seen.add(v.index)
        while stack:
            for e in stack.pop().link_edges:
                for u in e.verts:
                    if u.index not in seen:
                        seen.add(u.index)
                        stack.append(u)
    return count


def obj_frame(n):
    """drapekit's frame n in Blender's world (y up becomes z up), and its panel names."""
    v, groups = [], []
    for line in open(os.path.join(run, f"frame_{n:04}.obj")):
        if line.startswith("v "):
            v.append([float(x) for x in line.split()[1:4]])
        elif line.startswith("g "):
            groups.append(line[2:].strip())
    v = np.array(v)
    return np.c_[v[:, 0], -v[:, 2], v[:, 1]], groups


def blender_garment(frame):
    bpy.context.scene.frame_set(frame)
    evaluated = garment.evaluated_get(bpy.context.evaluated_depsgraph_get())
    world = np.array(evaluated.matrix_world)
    co = np.array([v.co for v in evaluated.data.vertices])
    return (np.c_[co, np.ones(len(co))] @ world.T)[:, :3]


def farthest(a, b):
    """The largest distance from a point of a to its nearest point of b."""
    worst = 0.0
    for chunk in np.array_split(a, max(1, len(a) // 512)):
        d = np.sqrt(((chunk[:, None, :] - b[None, :, :]) ** 2).sum(-1)).min(1)
        worst = max(worst, float(d.max()))
    return worst


pieces = islands(garment.data)
print(f"garment: {len(garment.data.vertices)} vertices in {pieces} connected piece(s)")
if pieces != 1:
    failures.append(f"{pieces} pieces, not one")
summary = json.load(open(os.path.join(run, "summary.json")))
written = sorted(int(o[6:10]) for o in summary["outputs"] if o.startswith("frame_"))
_, panels = obj_frame(written[-1])
materials = sorted(m.name for m in garment.data.materials)
print(f"materials: {materials}")
if materials != sorted(panels):
    failures.append(f"materials {materials} are not the panels {sorted(panels)}")
# The glTF's keys are at frame / fps seconds; Blender's importer places them at the scene's
# frame rate, which it sets from nothing: 24 frames per second by default.
fps = summary["fps"]
action = garment.data.shape_keys.animation_data.action
first, last = (round(f) for f in action.frame_range)
print(f"shape-key animation: Blender frames {first} to {last}")
for n in [f for f in written if first <= f * 24 / fps <= last]:
    blender = blender_garment(round(n * 24 / fps))
    drapekit, _ = obj_frame(n)
    error = max(farthest(blender, drapekit), farthest(drapekit, blender))
    print(f"frame {n}: farthest vertex {error:.2e} m")
    if error > TOL:
        failures.append(f"frame {n}: {error:.2e} m")
for f in failures:
    print("FAILED:", f)
sys.exit(1 if failures else 0)
