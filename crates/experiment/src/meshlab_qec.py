"""MeshLab's quadric edge collapse (VCG, through pymeshlab), as `desal eval` runs it.

usage: python meshlab_qec.py IN.ply WEIGHTS.txt OUT.ply TARGET_FACES [--plain]

The five-minute way a user imitates the paper's Eq. 3 with an existing tool: desal's
per-vertex saliency weights as MeshLab's vertex quality, `qualityweight=True` (MeshLab
scales each vertex quadric by its quality: higher = kept longer). `--plain` ignores the
weights (plain MeshLab, same settings). The settings are those of
`../shared/peers/meshlab_weighted.py`: preservetopology, optimalplacement, no planar
quadric. Embedded in the desal binary (crates/experiment/src/meshlab.rs) and written to a
temporary folder for each run; prints SIMPLIFY_SECONDS=<seconds>.
"""
import sys
import time

import numpy as np
import pymeshlab


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    plain = "--plain" in sys.argv[1:]
    if len(args) != 4:
        sys.exit(__doc__)
    src, weights_path, dst, target = args[0], args[1], args[2], int(args[3])
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(src)
    loaded = ms.current_mesh()
    v = np.asarray(loaded.vertex_matrix(), dtype=np.float64)
    f = np.asarray(loaded.face_matrix(), dtype=np.int32)
    w = np.ones(len(v)) if plain else np.loadtxt(weights_path, dtype=np.float64, ndmin=1)
    if w.shape[0] != v.shape[0]:
        sys.exit(f"{weights_path}: {w.shape[0]} weights for {v.shape[0]} vertices of {src}")
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=v, face_matrix=f, v_scalar_array=w))
    started = time.perf_counter()
    ms.meshing_decimation_quadric_edge_collapse(
        targetfacenum=target,
        qualityweight=not plain,
        preservetopology=True,
        planarquadric=False,
        optimalplacement=True,
    )
    seconds = time.perf_counter() - started
    ms.save_current_mesh(dst, binary=True, save_vertex_quality=False, save_vertex_color=False)
    print(f"SIMPLIFY_SECONDS={seconds:.6f}")


if __name__ == "__main__":
    main()
