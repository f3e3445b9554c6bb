#!/usr/bin/env bash
# Pictures of a `phymul truthcube` output directory: the error plot and the cube at 18.25 %.
set -euo pipefail
dir=$1
here=$(cd "$(dirname "$0")" && pwd)
/usr/bin/python3 "$here/plot_truthcube.py" "$dir/beads.csv" "$dir/truthcube_errors.png"
for model in lsm fem; do
  vtu="$dir/truthcube_${model}_18.25pct.vtu"
  [ -f "$vtu" ] || continue
  xvfb-run -a /usr/bin/python3 "$here/render.py" "$vtu" "$dir/truthcube_${model}_18.25pct.png" \
    --rest --view front --title "Truth Cube, $model, 18.25 % compression"
done
