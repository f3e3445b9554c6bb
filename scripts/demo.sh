#!/usr/bin/env bash
# make demo: runs every example, renders pictures and plots, says where they are.
set -euo pipefail
build=${1:-build}
root=$(cd "$(dirname "$0")/.." && pwd)
results="$root/results"
mkdir -p "$results"
py=/usr/bin/python3
for scene in "$root"/examples/*.yaml; do
  name=$(basename "$scene" .yaml)
  out="$results/$name"
  rm -rf "$out"
  echo "== $name"
  "$root/$build/phymul" run "$scene" -o "$out"
  # A scene may ask for its picture's options in a comment, e.g. "# picture: --view below".
  read -r -a picture < <(sed -n 's/^# picture: *//p' "$scene" | head -n 1) || true
  xvfb-run -a "$py" "$root/scripts/render.py" "$out/$name.pvd" "$out/$name.png" \
    --rest --title "$name: last frame, |displacement|" "${picture[@]}"
  "$py" "$root/scripts/plot_monitors.py" "$out/monitors.csv" "$out/${name}_monitors.png" \
    --title "$name"
done
# The biopsy (docs/needles.md): a needle through the probe's guide into the prostate.
echo "== biopsy (a needle inserted into the prostate toward a target)"
out="$results/biopsy"
rm -rf "$out"
"$root/$build/phymul" run "$root/examples/prostate/biopsy.yaml" -o "$out"
xvfb-run -a "$py" "$root/scripts/render.py" "$out/biopsy.pvd" "$out/biopsy.png" \
  --rest --title "biopsy: last frame, |displacement|" --view side
"$py" "$root/scripts/plot_needle.py" "$out/monitors.csv" "$out/biopsy_needle.png" \
  --title "biopsy: needle force against depth, target displacement"
# Patient anatomy (docs/anatomy.md): a prostate meshed from its MRI segmentation, beside the
# study's ellipsoid prostate under the same kind of probe; a bladder read from an STL surface.
for name in prostate_mri bladder_from_stl; do
  echo "== anatomy/$name"
  out="$results/anatomy/$name"
  rm -rf "$out"
  "$root/$build/phymul" run "$root/examples/anatomy/$name.yaml" -o "$out"
  xvfb-run -a "$py" "$root/scripts/render.py" "$out/$name.pvd" "$out/$name.png" \
    --rest --title "$name: last frame, |displacement|" --view side
done
out="$results/anatomy/ellipsoid_50mL_rigid"
rm -rf "$out"
"$root/$build/phymul" run "$root/examples/prostate/50mL_rigid.yaml" -o "$out"
xvfb-run -a "$py" "$root/scripts/render.py" "$out/50mL_rigid.pvd" "$out/50mL_rigid.png" \
  --rest --title "ellipsoid prostate (the study's), 50 mL, rigid probe" --view side
"$py" "$root/scripts/side_by_side.py" "$results/anatomy/prostate_mri_beside_ellipsoid.png" \
  "A prostate from MRI (Medical Segmentation Decathlon, CC-BY-SA 4.0) beside the study's ellipsoid" \
  "$results/anatomy/prostate_mri/prostate_mri.png" "$out/50mL_rigid.png"
echo "== truthcube (the paper's section 3: beads measured in a compressed silicone cube)"
"$root/$build/phymul" truthcube -o "$results/truthcube"
echo "== prostate (the paper's section 4: an endorectal probe, bladder empty to full)"
"$root/$build/phymul" prostate -o "$results/prostate"
# Parameter sweeps on a local Dask cluster (docs/scale-out.md), each in a fresh directory.
for sweep in "$root"/examples/sweeps/*.yaml; do
  name=$(basename "$sweep" .yaml)
  echo "== sweep $name"
  rm -rf "$results/sweeps/$name"
  # Exit 2: it ran, and some samples failed (each one's error is in results.csv).
  rc=0
  "$root/$build/phymul" sweep "$sweep" -o "$results/sweeps/$name" || rc=$?
  [ $rc -eq 0 ] || [ $rc -eq 2 ] || exit $rc
done
# The paper configuration's sensitivity table and plot (docs/validation.md).
/usr/bin/python3 "$root/scripts/plot_sensitivity.py" \
  "$results/sweeps/prostate_paper_sensitivity/results.csv" \
  "$results/sweeps/prostate_paper_sensitivity/sensitivity.png"
# The live view (docs/live-view.md): phymul serve on the 50 mL rigid-probe prostate scene, its
# page in headless chromium, a screenshot once the probe has pushed (about 1.5 s in).
echo "== live view (phymul serve) of the prostate scene, in headless chromium"
mkdir -p "$results/live_view"
live=0
NODE_PATH="$root/$build/web/node_modules" node "$root/tests/serve/browser_test.cjs" \
  "$root/$build/phymul" "$root/examples/prostate/50mL_rigid.yaml" \
  --screenshot "$results/live_view/prostate_50mL_rigid.png" --seconds 1.5 || live=$?
[ $live -eq 0 ] || echo "warning: no live view screenshot (exit $live: see above)" >&2
echo
echo "Results are in $results/<example>/:"
echo "  <example>.png            the last frame, coloured by displacement (rest shape in grey)"
echo "  <example>_monitors.png   kinetic energy, residual force and volumes over time"
echo "  <example>.pvd            open in ParaView for the whole series (frames: *.vtu)"
echo "  monitors.csv, report.json"
echo "and the Truth Cube study in $results/truthcube/: truthcube_errors.png (error per bead"
echo "layer), truthcube_lsm_18.25pct.png, truthcube.json, beads.csv, *.vtu"
echo "and the biopsy in $results/biopsy/: biopsy_needle.png (needle force against depth, the"
echo "target's displacement and the tip-to-target distance), biopsy.png, biopsy_needles.pvd (needle)"
echo "and the prostate study in $results/prostate/: prostate_deformation.png (deformation,"
echo "centre displacement and probe force against filling), prostate_empty.png, prostate_full.png"
echo "(pressure probe), prostate_empty_rigid.png, prostate_full_rigid.png (rigid probe, drawn),"
echo "prostate.json, one scene (.yaml) and .pvd series per filling and probe, real_time/<run>/report.json"
echo "and the sweeps in $results/sweeps/<sweep>/: results.csv (a row per sample), summary.png"
echo "(prostate_sensitivity: the prostate's deformation against its stiffness, a curve per"
echo "bladder filling, a panel per probe force), samples/<id>/ (each sample's scene and results)"
echo "and patient anatomy in $results/anatomy/: prostate_mri_beside_ellipsoid.png (a prostate"
echo "meshed from an MRI segmentation beside the study's ellipsoid), <example>/<example>.png"
echo "and the live view's page on the prostate scene: $results/live_view/prostate_50mL_rigid.png"
