#!/usr/bin/env bash
# The same pipeline in situ and after the fact: a run renders pipelines/free_surface.py in situ at
# its last step and saves a snapshot of that step; `spate post --pipeline` renders the snapshot
# with the same script; the two images must pass the image comparison (compare_image.py), and a
# snapshot's field data must give the script the same constants as the in-situ dataset.
# Usage: post_image_test.sh SPATE SOURCE_DIR OUT_DIR
set -euo pipefail
spate=$1 src=$2 out=$3
steps=300
rm -rf "$out"
mkdir -p "$out"
export SPATE_INSITU_IMAGE_SIZE=400x300
script="$src/pipelines/free_surface.py"
common=(--set dp=0.004 --set probes=[] --quiet)
"$spate" run "$src/cases/dam_break_2d.yaml" --out "$out/run" --steps $steps --set output.interval=1 --insitu-every $steps \
  --pipeline "$script" "${common[@]}" >"$out/run.log" 2>&1 || { cat "$out/run.log"; exit 1; }
"$spate" post "$out/run" --step $steps --pipeline "$script" --out "$out/post" >"$out/post.log" 2>&1 || { cat "$out/post.log"; exit 1; }
name=$(printf "free_surface_%06d.png" $steps)
for f in "$out/run/insitu/$name" "$out/post/insitu/$name"; do
  [ -f "$f" ] || { cat "$out/run.log" "$out/post.log"; echo "no image $f"; exit 1; }
done
pvpython "$src/tests/insitu/compare_image.py" "$out/post/insitu/$name" "$out/run/insitu/$name" "$out"
echo "spate post --pipeline renders step $steps as the run did in situ: OK"
