#!/usr/bin/env bash
# RUSTC_WRAPPER for tests/faults/compile_cost.sh: runs rustc under /usr/bin/time and appends
# "PACKAGE CRATE USER SYS WALL" to $RUSTC_CPU_LOG, so that each crate's CPU-seconds are known
# however loaded the machine is (cargo's timing page has only wall time per unit). USER and
# SYS include what rustc waits for (the linker). Cargo's own queries (`rustc -vV`, ...) are
# logged with package `-`.
rustc=$1
shift
crate=-
prev=
for arg in "$@"; do
  if [ "$prev" = --crate-name ]; then crate=$arg; fi
  prev=$arg
done
exec /usr/bin/time -a -o "${RUSTC_CPU_LOG:?}" -f "${CARGO_PKG_NAME:--} $crate %U %S %e" "$rustc" "$@"
