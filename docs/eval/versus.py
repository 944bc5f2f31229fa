#!/usr/bin/env python3
"""One method of a `desal eval` run against every other, pose by pose.

eval.md compares every method with one baseline (qslim-optimal). Issue 17 asks whether
desal's own method is lower than *each* other method, paired per pose, with a sign
test; this reads eval.json and prints that table, from the same per-pose records the
Rust report uses (held out, against the full-resolution pose). It also splits v2f into
its two halves (paper Eq. 6):
  - simplified -> full: the deformed simplified vertices' squared distance to the full
    pose's surface (the mean over the simplified vertices);
  - full -> simplified: the full pose's vertices' squared distance to the deformed
    simplified surface (the mean over the full vertices; 5/6 of v2f at 2500 of 12500).

    python3 docs/eval/versus.py OUT/scape/eval/eval.json [METHOD]   (default: desal)

Only the standard library. The sign test is the exact two-sided binomial test over the
poses whose errors differ, as `sign_test` in crates/experiment/src/report.rs.
"""
import json
import math
import sys


def sign_test(wins, n):
    if n == 0:
        return 1.0
    k = min(wins, n - wins)
    tail = sum(math.comb(n, i) for i in range(k + 1)) / 2.0**n
    return min(1.0, 2.0 * tail)


def held_out_full(method, key):
    return [p["held_out"]["vs_full"][key] for p in method["poses"]]


def main():
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__)
    path = sys.argv[1]
    name = sys.argv[2] if len(sys.argv) == 3 else "desal"
    with open(path) as f:
        report = json.load(f)
    methods = {m["name"]: m for m in report["methods"]}
    if name not in methods:
        sys.exit(f"{path}: no method '{name}' (it has {', '.join(methods)})")
    ours = methods[name]
    keys = [
        ("v2f", "v2f"),
        ("v2v", "v2v"),
        ("v2f simplified -> full", "v2f_deformed_to_target"),
        ("v2f full -> simplified", "v2f_target_to_deformed"),
    ]
    print(f"`{name}` against each method: held out, vs the full-resolution pose, {report['dataset']}, "
          f"{len(ours['poses'])} poses. Δ is {name}'s mean against the other's; won counts the poses "
          f"where {name} is lower; p is the two-sided sign test.\n")
    print("| against | " + " | ".join(f"{label}: Δ, won, p" for label, _ in keys) + " |")
    print("|---|" + "---|" * len(keys))
    for other_name, other in methods.items():
        if other_name == name:
            continue
        if [p["pose"] for p in other["poses"]] != [p["pose"] for p in ours["poses"]]:
            sys.exit(f"{path}: '{other_name}' was measured on other poses than '{name}'")
        cells = []
        for _, key in keys:
            a, b = held_out_full(ours, key), held_out_full(other, key)
            won = sum(x < y for x, y in zip(a, b))
            differing = sum(x != y for x, y in zip(a, b))
            change = 100.0 * (sum(a) / sum(b) - 1.0)
            cells.append(f"{change:+.1f} %, {won}, {sign_test(won, differing):.1g}")
        print(f"| {other_name} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
