#!/usr/bin/env python3
"""Fault-injection sweep: kill `desal run` at the k-th filesystem system call, for every k,
and check that the next normal run recovers.

For each scenario the sweep first counts each filesystem syscall's calls in one run under
strace, then, for every syscall s and k = 1..count(s), kills a fresh copy of the
scenario's starting state at the k-th call of s (strace's `inject=s:signal=KILL:when=k`,
counted per thread, so a k beyond every thread's count does not land) and runs desal
normally. After each kill:

- the normal run must succeed;
- every output file (.dsa, .ply, .png, .txt) must be byte-identical to a clean run's;
- no leftover temp/old folder or file may remain in the output folder, beside it, or in
  the cache (`.NAME.tmp-PID-N`, `.NAME.old-PID-N`, `.NAME.PID.N.tmp`, `.NAME.partial-PID`);
- in the scenario with `eval/` present, `eval/` must be there, byte-identical.

Scenarios: `cold` (empty output and cache), `force` (`--force` over a complete run), and
`replace` (a changed target over a complete run that has `eval/`).

Usage: sweep.py DESAL_BINARY [--stride S] [--scenarios cold,force,replace]
Prints one line per scenario: kill points tried, kills that landed, failures.
Exit status 1 on any failure. Needs strace.
"""

import argparse
import hashlib
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SYSCALLS = "rename,renameat,renameat2,unlinkat,unlink,rmdir,mkdir,mkdirat,openat,fsync,fdatasync,write,link,linkat"
LEFTOVER = re.compile(r"^\..*(\.tmp-\d+-\d+|\.old-\d+-\d+|\.\d+\.\d+\.tmp|\.partial-\d+)$")
COMPARED = (".dsa", ".ply", ".png", ".txt")


def pipeline(work: Path, target: int) -> Path:
    """The bundled sample as a pipeline file writing into `work/out`."""
    text = (ROOT / "pipelines/sample.toml").read_text()
    # Relative to the pipeline file, so a copy of `work` is a self-contained state.
    text = text.replace('out = "../out"', 'out = "out"')
    text = text.replace("../data-samples", str(ROOT / "data-samples"))
    text = re.sub(r"target_vertices = \d+", f"target_vertices = {target}", text)
    path = work / f"sample-{target}.toml"
    path.write_text(text)
    return path


def run(binary, args, kill_at=None, check=True, cwd=None):
    """Runs desal; with `kill_at = (syscall, k)`, under strace, killed at the k-th call of
    that syscall (strace counts per syscall and per thread)."""
    cmd = [binary] + args + ["--quiet"]
    if kill_at is not None:
        syscall, k = kill_at
        cmd = ["strace", "-f", "-qq", "-o", "/dev/null", "-e", f"trace={syscall}",
               "-e", f"inject={syscall}:signal=KILL:when={k}"] + cmd
    result = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=cwd)
    if check and result.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({result.returncode}):\n{result.stderr}")
    return result


def count_calls(binary, args, cwd) -> dict:
    """Calls of each filesystem syscall in one run (all threads together)."""
    out = subprocess.run(["strace", "-f", "-qq", "-c", "-e", f"trace={SYSCALLS}", binary] + args + ["--quiet"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=cwd)
    counts = {}
    for line in out.stderr.splitlines():
        fields = line.split()
        if len(fields) >= 5 and fields[-1] in SYSCALLS.split(",") and fields[0][0].isdigit():
            counts[fields[-1]] = int(fields[3])
    if not counts:
        raise RuntimeError(f"could not count system calls:\n{out.stderr}")
    return counts


def digest(folder: Path) -> dict:
    """sha256 of every compared file under `folder` (relative path -> hex)."""
    out = {}
    for path in sorted(folder.rglob("*")):
        if path.is_file() and path.suffix in COMPARED and ".cache" not in path.parts:
            out[str(path.relative_to(folder))] = hashlib.sha256(path.read_bytes()).hexdigest()
    return out


def leftovers(work: Path) -> list:
    return [str(p.relative_to(work)) for p in work.rglob("*") if LEFTOVER.match(p.name)]


class Scenario:
    def __init__(self, name, binary, scratch: Path):
        self.name, self.binary, self.scratch = name, binary, scratch

    def prepare(self, work: Path):
        """Builds the starting state in `work` (self-contained: it may be copied); returns
        (args of the killed run, args of the recovery run), relative to `work`."""
        p2500, p2000 = pipeline(work, 2500), pipeline(work, 2000)
        if self.name != "cold":
            run(self.binary, ["run", str(p2500)])
        if self.name == "replace":
            run(self.binary, ["eval", str(p2500), "--folds", "2", "--methods", "qslim-optimal"])
        if self.name == "cold":
            return ["run", p2500.name], ["run", p2500.name]
        if self.name == "force":
            return ["run", p2500.name, "--force"], ["run", p2500.name]
        return ["run", p2000.name], ["run", p2000.name]


def sweep(scenario: Scenario, stride: int) -> tuple:
    base = Path(tempfile.mkdtemp(dir=scenario.scratch))
    # The starting state, built once and copied for every kill point.
    start = base / "start"
    start.mkdir()
    killed_args, recover_args = scenario.prepare(start)
    eval_before = digest(start / "out/sample/eval") if (start / "out/sample/eval").is_dir() else None
    # The reference: the recovery command's outputs after an unkilled run.
    ref = base / "ref"
    shutil.copytree(start, ref, symlinks=True)
    run(scenario.binary, killed_args, cwd=ref)
    run(scenario.binary, recover_args, cwd=ref)
    expected = digest(ref / "out/sample")
    probe = base / "probe"
    shutil.copytree(start, probe, symlinks=True)
    counts = count_calls(scenario.binary, killed_args, probe)
    shutil.rmtree(probe)
    total = sum(counts.values())
    tried = landed = 0
    failures = []
    points = [(syscall, k) for syscall, n in sorted(counts.items()) for k in range(1, n + 1, stride)]
    for syscall, k in points:
        work = base / f"{syscall}-{k}"
        shutil.copytree(start, work, symlinks=True)
        tried += 1
        result = run(scenario.binary, killed_args, kill_at=(syscall, k), check=False, cwd=work)
        if result.returncode != 0:
            landed += 1
        try:
            run(scenario.binary, recover_args, cwd=work)
            got = digest(work / "out/sample")
            if got != expected:
                diff = sorted(set(got.items()) ^ set(expected.items()))[:4]
                failures.append(f"{syscall} #{k}: outputs differ from a clean run: {diff}")
            stray = leftovers(work)
            if stray:
                failures.append(f"{syscall} #{k}: leftovers after the recovery run: {stray}")
            if eval_before is not None:
                eval_dir = work / "out/sample/eval"
                if not eval_dir.is_dir() or digest(eval_dir) != eval_before:
                    failures.append(f"{syscall} #{k}: eval/ was lost or changed")
        except RuntimeError as e:
            failures.append(f"{syscall} #{k}: the recovery run failed: {e}")
        shutil.rmtree(work)
    shutil.rmtree(base)
    return total, tried, landed, failures


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("binary")
    parser.add_argument("--stride", type=int, default=1, help="try every S-th kill point (default: every one)")
    parser.add_argument("--scenarios", default="cold,force,replace")
    args = parser.parse_args()
    if shutil.which("strace") is None:
        sys.exit("error: strace is needed (apt-get install strace)")
    binary = str(Path(args.binary).resolve())
    scratch = Path(tempfile.mkdtemp(prefix="desal-faults-"))
    failed = False
    for name in args.scenarios.split(","):
        total, tried, landed, failures = sweep(Scenario(name, binary, scratch), args.stride)
        print(f"faults {name}: {total} filesystem calls, {tried} kill points tried, {landed} kills landed, "
              f"{len(failures)} failures")
        for f in failures[:20]:
            print(f"  {f}")
        failed |= bool(failures)
        if tried == 0 or landed == 0:
            print(f"  error: no kill landed in scenario {name}: the sweep tested nothing")
            failed = True
    shutil.rmtree(scratch, ignore_errors=True)
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
