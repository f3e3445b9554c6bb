#!/usr/bin/env bash
# Pictures of a `phymul prostate` output directory: deformation against filling, and the
# organs under the pressure probe with the bladder empty and full.
set -euo pipefail
dir=$1
here=$(cd "$(dirname "$0")" && pwd)
/usr/bin/python3 "$here/plot_prostate.py" "$dir/prostate.json" "$dir/prostate_deformation.png"
# The pressure probe's pictures are prostate_{empty,full}.png; the rigid probe's (drawn
# translucent) prostate_{empty,full}_rigid.png.
for probe in pressure rigid; do
  runs=$(ls "$dir"/*mL_$probe.pvd 2>/dev/null | sort -V)
  [ -n "$runs" ] || continue
  suffix=$([ "$probe" = rigid ] && echo _rigid || true)
  empty=$(echo "$runs" | head -n1)
  full=$(echo "$runs" | tail -n1)
  for pair in "empty:$empty" "full:$full"; do
    state=${pair%%:*}
    pvd=${pair#*:}
    ml=$(basename "$pvd" _$probe.pvd)
    xvfb-run -a /usr/bin/python3 "$here/render.py" "$pvd" "$dir/prostate_${state}${suffix}.png" \
      --field probe_displacement --rest --view front \
      --title "bladder $state ($ml): $probe probe, displacement from before the probe"
  done
done
