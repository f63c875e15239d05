#!/usr/bin/env bash
# In-situ error behaviour through the command line:
#  - a missing script or one that fails to load stops the run before the first step: exit 2, the
#    Python traceback on stderr;
#  - a script that fails later is switched off with its traceback in summary.json, the run and the
#    other pipelines go on to the end (nothing lost);
#  - the case file's insitu: section works like --pipeline/--insitu-every.
# Usage: check_errors.sh SPATE SOURCE_DIR OUT_DIR
set -uo pipefail
spate=$1 src=$2 out=$3
rm -rf "$out"
mkdir -p "$out"
fail() { echo "FAIL: $*"; exit 1; }
case_2d="$src/cases/dam_break_2d.yaml"
common=(--set output.interval=0 --quiet)

"$spate" run "$case_2d" --out "$out/missing" --steps 2 --pipeline "$src/no/such/script.py" "${common[@]}" 2>"$out/missing.err"
[ $? -eq 2 ] || fail "missing script: expected exit 2"
grep -q "no such script" "$out/missing.err" || fail "missing script: no clear message"

"$spate" run "$case_2d" --out "$out/load" --steps 2 --pipeline "$src/tests/insitu/fail_on_load.py" "${common[@]}" 2>"$out/load.err"
[ $? -eq 2 ] || fail "failing load: expected exit 2"
grep -q "failed to load" "$out/load.err" || fail "failing load: no message"
grep -q "Traceback" "$out/load.err" || fail "failing load: no Python traceback"
grep -q "NoSuchFilterInParaView" "$out/load.err" || fail "failing load: traceback does not name the error"
[ ! -e "$out/load/probes" ] || [ -z "$(ls "$out/load/checkpoints" 2>/dev/null)" ] || fail "failing load: the run went on"
python3 -c "import json,sys; s=json.load(open(sys.argv[1])); sys.exit(s['exit_code'] != 2)" "$out/load/summary.json" ||
  fail "failing load: summary.json missing or not exit 2"

SPATE_FAIL_AT_STEP=2 "$spate" run "$case_2d" --out "$out/later" --steps 4 --pipeline "$src/tests/insitu/fail_at_step.py" \
  --pipeline "$src/pipelines/extract.py" "${common[@]}" 2>"$out/later.err"
[ $? -eq 0 ] || fail "failing later: the run should finish with exit 0"
python3 - "$out/later/summary.json" <<'PY' || fail "failing later: summary.json does not record the failure"
import json, sys
s = json.load(open(sys.argv[1]))
f = s["insitu_failures"]
assert len(f) == 1 and "fail_at_step.py" in f[0] and "step 2" in f[0] and "deliberate failure at step 2" in f[0], f
assert s["steps"] == 4 or s.get("final_step", 4) == 4
PY
for step in 0 1 2 3 4; do
  [ -f "$out/later/insitu/particles_00000$step.vtm" ] || fail "failing later: extract of step $step lost"
done

"$spate" run "$case_2d" --out "$out/casefile" --steps 4 --set "insitu.pipelines=[$src/pipelines/extract.py]" \
  --set insitu.every=2 "${common[@]}" 2>"$out/casefile.err" || fail "insitu: section: run failed"
ls "$out/casefile/insitu/" | grep -q "particles_000002.vtm" || fail "insitu: section: no extract at step 2"
! ls "$out/casefile/insitu/" | grep -q "particles_000001.vtm" || fail "insitu: section: every: 2 not honoured"
"$spate" run "$case_2d" --out "$out/badkey" --steps 1 --set insitu.evry=2 "${common[@]}" 2>"$out/badkey.err"
[ $? -eq 2 ] || fail "insitu: unknown key should be exit 2"
grep -q "did you mean 'insitu.every'" "$out/badkey.err" || fail "insitu: unknown key message"
echo "in-situ error behaviour: OK"
