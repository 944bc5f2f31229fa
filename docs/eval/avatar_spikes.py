"""Where the avatar's rest-pose spikes sit (EVAL.md, "Spikes"): the faces of a simplified
`.glb` whose normal points away from the normal of the nearest face of the full `.glb`,
judged against the whole avatar and against the face's own mesh; and how many body faces
lie more than 1 mm inside the (closed) eyes.

    pip install numpy scipy trimesh rtree
    python docs/eval/avatar_spikes.py data-samples/avatar.glb out/avatar-sample/simplified.glb
    gltfpack -i data-samples/avatar.glb -o /tmp/gp.glb -si 0.2 -noq
    python docs/eval/avatar_spikes.py data-samples/avatar.glb /tmp/gp.glb

Meshes are matched in document order (gltfpack renames them), so both files must keep
the input's meshes in its order.
"""
import sys

import numpy as np
import trimesh


def meshes(path):
    return list(trimesh.load(path, force="scene", process=False).geometry.values())


def turned(simplified, surface):
    """Faces of `simplified` turned against the nearest face of `surface`."""
    _, _, nearest = trimesh.proximity.ProximityQuery(surface).on_surface(simplified.triangles_center)
    return (simplified.face_normals * surface.face_normals[nearest]).sum(axis=1) < 0


full, simplified = meshes(sys.argv[1]), meshes(sys.argv[2])
whole = trimesh.util.concatenate(full)
print("mesh: faces, spikes judged against the whole avatar / against its own mesh")
for own, simple in zip(full, simplified):
    print(f"  {len(simple.faces)} faces: {turned(simple, whole).sum()} / {turned(simple, own).sum()}")
eyes = next((m for m in full if m.is_watertight and len(m.faces) < 1000), None)
if eyes is not None:
    depth = trimesh.proximity.ProximityQuery(eyes).signed_distance(simplified[0].triangles_center)
    print(f"first mesh's faces more than 1 mm inside the closed mesh of {len(eyes.faces)} faces: {(depth > 0.001).sum()}")
