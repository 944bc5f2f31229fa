"""Blender's own glTF importer on a desal LOD file (issue 42, item 6: "check Blender for
real"): every mesh object with its faces, UV layers, armature, materials, image
textures and shape keys (morph targets), then the images and actions.

    blender -b --python docs/rig/blender_lods.py -- out/avatar-sample/simplified-lods.glb

(Debian: `apt-get install blender python3-numpy`.)
"""
import sys

import numpy

# Debian's Blender 3.4 importer uses `numpy.bool`, which numpy 1.24 removed.
numpy.bool = bool

import bpy  # noqa: E402
path = sys.argv[sys.argv.index("--") + 1]
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=path)
meshes = [o for o in bpy.context.scene.objects if o.type == 'MESH']
for o in meshes:
    keys = [k.name for k in o.data.shape_keys.key_blocks] if o.data.shape_keys else []
    arm = [m.object.name for m in o.modifiers if m.type == 'ARMATURE' and m.object]
    mats = [m.name for m in o.data.materials if m]
    tex = sum(1 for m in o.data.materials if m and m.use_nodes for n in m.node_tree.nodes if n.type == 'TEX_IMAGE' and n.image)
    print(f"MESH {o.name}: {len(o.data.polygons)} faces, {len(o.data.uv_layers)} uv, armature {arm}, materials {mats}, textures {tex}, shape keys {keys}")
print("IMAGES", len(bpy.data.images), "ACTIONS", len(bpy.data.actions))
