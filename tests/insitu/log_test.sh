#!/usr/bin/env bash
# The log of a run with ParaView Catalyst, written to a file from a terminal that claims colours
# (TERM=xterm-256color, as in an interactive shell redirected to a file): every line carries the
# UTC timestamp, ParaView's own messages included, and not one escape sequence reaches the file.
# Usage: log_test.sh SPATE SOURCE_DIR OUT_DIR
set -uo pipefail
spate=$1 src=$2 out=$3
rm -rf "$out"
mkdir -p "$out"
fail() { echo "FAIL: $*"; cat "$out/run.log"; exit 1; }
TERM=xterm-256color "$spate" run "$src/cases/dam_break_2d.yaml" --out "$out/run" --steps 2 --set output.interval=0 \
  --pipeline "$src/pipelines/extract.py" >"$out/run.log" 2>&1 || fail "the run failed"
! grep -q $'\x1b' "$out/run.log" || fail "escape sequences in the log file"
bad=$(grep -v -E '^[0-9]{4}-[0-9]{2}-[0-9]{2}T[0-9]{2}:[0-9]{2}:[0-9]{2}\.[0-9]{3}Z spate: ' "$out/run.log" | grep -v '^$' || true)
[ -z "$bad" ] || fail "lines without the timestamp: $bad"
# ParaView's note at the first in-situ step (docs/insitu.md) comes through the log as a warning.
grep -q "spate: warning: vtkPVTrivialProducer .*New time step is not after last time step" "$out/run.log" ||
  fail "ParaView's message is not in the log as a warning line"
echo "log of a Catalyst run in a file: timestamped, plain text: OK"
