#!/usr/bin/env bash
# The program's CUDA behaviour that needs no GPU: `run --backend cuda` without a device exits 2
# with a clear message, `info --backend cuda` sizes the device memory per GPU, and
# scripts/gpu-check says "no GPU" and exits 2 (never 0), leaving its summary under $OUT.
# CUDA_VISIBLE_DEVICES=-1 hides every device, so this holds on GPU machines too.
set -uo pipefail
spate=$1
case_file=$2
source_dir=$3
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

CUDA_VISIBLE_DEVICES=-1 "$spate" run "$case_file" --backend cuda --steps 1 --quiet --out "$out/run" 2>"$out/err"
code=$?
cat "$out/err"
[ "$code" -eq 2 ] || fail "run --backend cuda without a device: exit $code, expected 2"
grep -q "no CUDA device" "$out/err" || fail "no 'no CUDA device' in the message"
# A refused run writes nothing but the summary.json of its refusal (docs/cli.md).
[ "$(ls "$out/run")" = "summary.json" ] || fail "a run without a device wrote outputs: $(ls "$out/run")"
grep -q '"exit_status": "bad_input"' "$out/run/summary.json" || fail "its summary.json does not say bad_input"

"$spate" info "$case_file" --backend cuda --devices 2 | tee "$out/info" || fail "info --backend cuda failed"
grep -q "device memory" "$out/info" || fail "info prints no device memory"
[ "$(grep -c '^  GPU ' "$out/info")" -eq 2 ] || fail "info does not list 2 GPUs"
"$spate" info "$case_file" --backend cuda --devices 2 --json >"$out/info.json" || fail "info --json failed"
python3 - "$out/info.json" <<'PY' || fail "info --json: device memory fields"
import json, sys
j = json.load(open(sys.argv[1]))
assert j["backend"] == "cuda"
assert j["device_bytes_per_particle"] <= 150, j["device_bytes_per_particle"]
assert len(j["device_memory"]) == 2
assert sum(s["owned"] for s in j["device_memory"]) >= j["particles"]["total"]
assert j["device_memory_max_bytes"] == max(s["bytes"] for s in j["device_memory"])
PY
CUDA_VISIBLE_DEVICES=-1 OUT=$out/check "$source_dir/scripts/gpu-check" --bin "$(dirname "$spate")" --budget 60 >"$out/check.txt" 2>&1
code=$?
cat "$out/check.txt"
[ "$code" -eq 2 ] || fail "gpu-check without a GPU: exit $code, expected 2"
tail -1 "$out/check.txt" | grep -q "^gpu-check: no GPU: " || fail "gpu-check's last line does not say 'gpu-check: no GPU: ...'"
grep -q "no GPU" "$out/check/summary.txt" || fail "gpu-check left no summary.txt saying 'no GPU' under \$OUT"
echo "PASS"
