#!/usr/bin/env bash
# Pictures of a `phymul prostate` output directory: deformation against filling, and the
# organs under the pressure probe with the bladder empty and full.
set -euo pipefail
dir=$1
here=$(cd "$(dirname "$0")" && pwd)
/usr/bin/python3 "$here/plot_prostate.py" "$dir/prostate.json" "$dir/prostate_deformation.png"
runs=$(ls "$dir"/*mL_pressure.pvd 2>/dev/null | sort -V)
[ -n "$runs" ] || exit 0
empty=$(echo "$runs" | head -n1)
full=$(echo "$runs" | tail -n1)
for pair in "empty:$empty" "full:$full"; do
  state=${pair%%:*}
  pvd=${pair#*:}
  ml=$(basename "$pvd" _pressure.pvd)
  xvfb-run -a /usr/bin/python3 "$here/render.py" "$pvd" "$dir/prostate_${state}.png" \
    --field probe_displacement --rest --view front \
    --title "bladder $state ($ml): probe pressure, displacement from before the probe"
done
