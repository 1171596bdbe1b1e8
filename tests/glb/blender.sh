#!/usr/bin/env bash
# A painted torus baked with --atlas into a GLB, opened by Blender's glTF importer, which must
# find the material with its base colour image and the UVs; then a torus painted with material
# channels, whose GLB must also give Blender roughness and metalness from an image and a normal
# map. Skipped (exit 77) without Blender
# (Debian's `blender`, not in scripts/packages.txt: too large for CI's time).
# Usage: blender.sh LIMN_CLI
set -euo pipefail
limn=$1
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
command -v blender >/dev/null || { echo "blender is not installed: skipped"; exit 77; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$limn" shape torus -o "$work/torus.obj" >/dev/null
echo '{"strokes": [{"type": "fill", "color": [0.2, 0.6, 0.3, 1]}]}' >"$work/fill.json"
"$limn" paint "$work/torus.obj" --strokes "$work/fill.json" -o "$work/torus.lot" >/dev/null
"$limn" bake "$work/torus.lot" "$work/torus.obj" --atlas --size 256 -o "$work/torus.glb" >/dev/null
"$limn" paint "$work/torus.obj" --strokes "$here/material.json" -o "$work/material.lot" >/dev/null
"$limn" bake "$work/material.lot" "$work/torus.obj" --atlas --size 256 --normal-map \
  -o "$work/material.glb" >/dev/null
rc=0
for check in "$work/torus.glb 256" "$work/material.glb 256 material"; do
  # shellcheck disable=SC2086
  out=$(blender -b --factory-startup --python-exit-code 2 --python "$here/blender_check.py" \
    -- $check 2>&1) || rc=$?
  grep -E "^blender:|Error|Traceback|Assertion" <<<"$out" || true
done
exit "$rc"
