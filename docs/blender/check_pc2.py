"""Checks the book's Blender steps for a PC2 export (docs/src/exports.md).

Imports RUN/rest.obj with Blender's OBJ importer at its default settings, adds a Mesh Cache
modifier reading RUN/cloth.pc2 at its default axes, and compares the evaluated mesh, in world
space, with drapekit's own frame_NNNN.obj files at several Blender frames.

    python check_pc2.py RUN EVERY      # Blender as a Python module: pip install bpy
    blender -b -P check_pc2.py -- RUN EVERY

EVERY is the scene's [output] every: the modifier's Frame Scale is set to 1/EVERY, so that
Blender frame N shows drapekit frame N. Prints the largest distance per checked frame and exits
1 if any exceeds 1 µm (the files hold f32 coordinates: rounding is under 1e-7 m at 2 m).
"""
import os
import sys

import bpy
import numpy as np

run, every = sys.argv[-2], int(sys.argv[-1])
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.wm.obj_import(filepath=os.path.join(run, "rest.obj"))
obj = bpy.context.selected_objects[0]
cache = obj.modifiers.new("cloth", "MESH_CACHE")
cache.cache_format = "PC2"
cache.filepath = os.path.join(run, "cloth.pc2")
cache.frame_scale = 1.0 / every


def drapekit_frame(n):
    """A frame's vertices in Blender's world: drapekit's y up becomes Blender's z up."""
    path = os.path.join(run, f"frame_{n:04}.obj")
    v = np.array([[float(x) for x in l.split()[1:4]] for l in open(path) if l.startswith("v ")])
    return np.c_[v[:, 0], -v[:, 2], v[:, 1]]


def blender_frame(n):
    bpy.context.scene.frame_set(n)
    evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    world = np.array(evaluated.matrix_world)
    co = np.array([v.co for v in evaluated.data.vertices])
    return (np.c_[co, np.ones(len(co))] @ world.T)[:, :3]


written = sorted(int(f[6:10]) for f in os.listdir(run) if f.startswith("frame_"))
worst = 0.0
for n in written[:: max(1, len(written) // 4)] + written[-1:]:
    error = float(np.abs(blender_frame(n) - drapekit_frame(n)).max())
    worst = max(worst, error)
    print(f"frame {n}: largest distance {error:.2e} m")
sys.exit(0 if worst < 1e-6 else 1)
