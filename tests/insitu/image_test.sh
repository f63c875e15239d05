#!/usr/bin/env bash
# One image-regression test: runs spate with pipelines/free_surface.py (or the pipeline that
# SPATE_IMAGE_PIPELINE names, e.g. temperature) for a fixed number of steps, renders 400x300 off screen (spate starts a private Xvfb when there is no DISPLAY) and compares the last
# image with tests/baselines/NAME.png. With SPATE_UPDATE_BASELINES=1 it refreshes the baseline.
# Usage: image_test.sh SPATE SOURCE_DIR OUT_DIR NAME CASE STEPS [spate run options...]
set -euo pipefail
spate=$1 src=$2 out=$3 name=$4 case_file=$5 steps=$6
shift 6
pipeline=${SPATE_IMAGE_PIPELINE:-free_surface}
rm -rf "$out"
mkdir -p "$out"
SPATE_INSITU_IMAGE_SIZE=400x300 "$spate" run "$src/cases/$case_file" --out "$out/run" --steps "$steps" \
  --insitu-every "$steps" --pipeline "$src/pipelines/$pipeline.py" --quiet "$@" >"$out/run.log" 2>&1 ||
  { cat "$out/run.log"; exit 1; }
image="$out/run/insitu/${pipeline}_$(printf %06d "$steps").png"
[ -f "$image" ] || { cat "$out/run.log"; echo "no image $image"; exit 1; }
cp "$image" "$out/$name.new.png"
if [ "${SPATE_UPDATE_BASELINES:-0}" = 1 ]; then
  mkdir -p "$src/tests/baselines"
  cp "$image" "$src/tests/baselines/$name.png"
  echo "baseline refreshed: tests/baselines/$name.png"
  exit 0
fi
pvpython "$src/tests/insitu/compare_image.py" "$out/$name.new.png" "$src/tests/baselines/$name.png" "$out"
