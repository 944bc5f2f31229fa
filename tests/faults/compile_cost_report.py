#!/usr/bin/env python3
"""The Markdown report of tests/faults/compile_cost.sh, from the files it wrote.

Usage: compile_cost_report.py OUT_DIR > OUT_DIR/compile_cost.md

Per-crate CPU-seconds come from rustc_cpu.sh's logs (user + sys of every rustc run for the
package: lib, bins, build script compile; the linker included). Per-crate wall seconds come
from the UNIT_DATA array cargo embeds in cargo-timing.html (stable cargo has no JSON timing
output): each unit's `duration`, summed over a package's units (build script runs too).
Load from other processes inflates wall seconds, not CPU-seconds; CPU-seconds are the
figures to compare between builds. What rustc does not account for (cargo, build script
runs such as meshopt's C++ compile through cc, and for (a) the run itself) is the command's
CPU-seconds less rustc's.
"""

import collections
import json
import pathlib
import re
import sys

OUT = pathlib.Path(sys.argv[1])
TOP = 15
# Crate families summed as one line too (the figures name them).
FAMILIES = ["desal", "faer", "nano-gemm", "gltf", "pyo3", "clap", "meshopt", "nalgebra", "serde", "numpy"]


def time_v(name: str) -> dict:
    """/usr/bin/time -v's output: wall, user, sys seconds and peak RSS."""
    text = (OUT / name).read_text()

    def field(label: str) -> str:
        m = re.search(r"^\s*" + re.escape(label) + r": (.*)$", text, re.M)
        if not m:
            raise SystemExit(f"{name}: no {label!r}")
        return m.group(1).strip()

    wall = 0.0
    for part in field("Elapsed (wall clock) time (h:mm:ss or m:ss)").split(":"):
        wall = wall * 60 + float(part)
    user, system = float(field("User time (seconds)")), float(field("System time (seconds)"))
    return dict(
        wall=wall,
        user=user,
        sys=system,
        cpu=user + system,
        rss_mb=int(field("Maximum resident set size (kbytes)")) / 1024,
        status=field("Exit status"),
    )


def units(name: str) -> list:
    text = (OUT / name).read_text()
    m = re.search(r"const UNIT_DATA = (\[.*?\n\]);", text, re.S)
    if not m:
        raise SystemExit(f"{name}: no UNIT_DATA")
    return json.loads(m.group(1))


def rustc_cpu(name: str) -> collections.Counter:
    """Package -> CPU-seconds of its rustc runs, from rustc_cpu.sh's log."""
    sums = collections.Counter()
    path = OUT / name
    if not path.exists():
        return sums
    for line in path.read_text().splitlines():
        fields = line.split()
        if len(fields) != 5:
            continue  # "Command exited with non-zero status N"
        try:
            user, system = float(fields[2]), float(fields[3])
        except ValueError:
            continue
        sums[fields[0]] += user + system
    return sums


def per_crate(data: list) -> collections.Counter:
    sums = collections.Counter()
    for u in data:
        sums[u["name"]] += u["duration"]
    return sums


def summary_of(name: str) -> dict:
    text = (OUT / name).read_text()
    info = {}
    for label in ("Total units", "Fresh units", "Dirty units", "Total time", "Max concurrency", "Profile"):
        m = re.search(r"<td>" + re.escape(label) + r":</td><td>(.*?)</td>", text)
        info[label] = m.group(1) if m else "?"
    return info


def fmt_mb(n: int) -> str:
    return f"{n / 1e6:.1f} MB ({n / 2**20:.1f} MiB)"


def table(title: str, stem: str, command_cpu: float) -> list:
    data = units(f"{stem}-timing.html")
    wall = per_crate(data)
    cpu = rustc_cpu(f"{stem}.rustc-cpu")
    cpu.pop("-", None)
    info = summary_of(f"{stem}-timing.html")
    total_cpu, total_wall = sum(cpu.values()), sum(wall.values())
    lines = [
        f"#### {title}: crates by rustc CPU-seconds (top {TOP} of {len(wall)})",
        "",
        f"{len(data)} units ({info['Fresh units']} fresh, {info['Dirty units']} dirty), cargo's total time "
        f"{info['Total time']}, {info['Max concurrency']}, profile {info['Profile']}. "
        f"rustc CPU-seconds: {total_cpu:.1f} s of the command's {command_cpu:.1f} s (the rest, "
        f"{command_cpu - total_cpu:.1f} s: cargo, build script runs with their C/C++ such as meshoptimizer's, "
        f"and the run for (a), pip and maturin for (b)); "
        f"unit wall seconds summed: {total_wall:.1f} s.",
        "",
        "| crate | CPU s (rustc) | share of rustc CPU | unit wall s |",
        "|---|---:|---:|---:|",
    ]
    ranked = cpu.most_common(TOP) if cpu else wall.most_common(TOP)
    for crate, _ in ranked:
        share = f"{100 * cpu[crate] / total_cpu:.1f} %" if total_cpu else "?"
        lines.append(f"| {crate} | {cpu[crate]:.1f} | {share} | {wall[crate]:.1f} |")
    families = [
        f"{f}* {sum(s for c, s in cpu.items() if c.startswith(f)):.1f} s CPU"
        f" ({sum(s for c, s in wall.items() if c.startswith(f)):.1f} s wall)"
        for f in FAMILIES
        if any(c.startswith(f) for c in wall)
    ]
    if families:
        lines += ["", "Families (every crate whose name starts so): " + ", ".join(families) + "."]
    return lines + [""]


def main() -> None:
    env = (OUT / "environment.txt").read_text().strip().splitlines()
    main_job, all_bins, python = time_v("main-job.time"), time_v("all-bins.time"), time_v("python.time")
    sizes = {}
    for line in (OUT / "python-sizes.txt").read_text().splitlines():
        key, value, *rest = line.split()
        sizes[key] = (int(value) if value.isdigit() else None, rest[0] if rest else "")
    loads = [float(line.split()[1]) for line in (OUT / "load-samples.txt").read_text().splitlines() if line.strip()]
    load_note = (
        f"1-min load average sampled every 15 s: mean {sum(loads) / len(loads):.1f}, min {min(loads):.1f}, "
        f"max {max(loads):.1f} ({len(loads)} samples)"
        if loads
        else "no load samples"
    )

    so, so_name = sizes["so"]
    stripped, _ = sizes["so_stripped"]
    wheel, wheel_name = sizes["wheel"]
    out = [
        f"# Compile cost: {env[0]}",
        "",
        "Measured by `tests/faults/compile_cost.sh` from a fresh clone with an empty `CARGO_TARGET_DIR` "
        "(registry sources already downloaded in `~/.cargo`).",
        "",
        "```",
        *env,
        f"start: {(OUT / 'load-start.txt').read_text().strip()}",
        f"end:   {(OUT / 'load-end.txt').read_text().strip()}",
        "```",
        "",
        f"{load_note}. The machine is shared: compare CPU-seconds (user + sys) rather than wall time.",
        "",
        "## Summary",
        "",
        "| what | CPU s (user + sys) | wall | peak RSS |",
        "|---|---:|---:|---:|",
        f"| (a) README main job cold: `cargo run --release -- run pipelines/sample.toml` | "
        f"**{main_job['cpu']:.0f}** ({main_job['user']:.0f} + {main_job['sys']:.0f}) | {main_job['wall'] / 60:.1f} min "
        f"({main_job['wall']:.0f} s) | {main_job['rss_mb']:.0f} MB |",
        f"| (a′) then `cargo build --release` (every other binary, warm) | {all_bins['cpu']:.0f} | "
        f"{all_bins['wall']:.0f} s | {all_bins['rss_mb']:.0f} MB |",
        f"| (b) Python package cold: `pip install ./crates/python` (fresh venv) | **{python['cpu']:.0f}** "
        f"({python['user']:.0f} + {python['sys']:.0f}) | {python['wall'] / 60:.1f} min ({python['wall']:.0f} s) | "
        f"{python['rss_mb']:.0f} MB |",
        "",
        f"- `{so_name}` installed: **{fmt_mb(so)}**" + (f"; stripped: {fmt_mb(stripped)}" if stripped else ""),
        f"- wheel `{wheel_name}`: **{fmt_mb(wheel)}**",
        "",
        "## Crates that dominate",
        "",
        *table("(a) main job", "main-job", main_job["cpu"]),
        *table("(b) Python package", "python", python["cpu"]),
        "Files beside this report: the cargo timing pages (`*-timing.html`), /usr/bin/time's outputs "
        "(`*.time`), the build logs and the load samples.",
    ]
    print("\n".join(out))


if __name__ == "__main__":
    main()
