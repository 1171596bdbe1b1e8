#!/usr/bin/env bash
# Every kind of GLB limn writes, checked by the Khronos glTF validator: shapes, a converted cage
# with UV seams, an unwrapped atlas, bakes into a material (base colour; and with roughness,
# metalness and a normal map), uniform and adaptive subdivision, simplification with UVs, a
# painted scan's material, the demo's painted bake. Zero errors allowed (warnings are printed).
# Usage: validate.sh LIMN_CLI NODE_MODULES_DIR SHARED_MODELS_DIR
set -euo pipefail
limn=$1 modules=$2 models=$3
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
if [[ ! -f "$modules/gltf-validator/package.json" ]]; then
  echo "glb-validate: $modules/gltf-validator is missing: run scripts/setup" >&2
  exit 1
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$limn" shape cube -o "$work/cube.glb" >/dev/null
"$limn" shape torus -o "$work/torus.glb" >/dev/null
"$limn" shape torus -o "$work/torus.obj" >/dev/null
"$limn" unwrap "$work/torus.obj" -o "$work/torus-unwrapped.glb" --size 256 >/dev/null
echo '{"strokes": [{"type": "fill", "color": [0.2, 0.6, 0.3, 1]}]}' >"$work/fill.json"
"$limn" paint "$work/torus.obj" --strokes "$work/fill.json" -o "$work/torus.lot" >/dev/null
"$limn" bake "$work/torus.lot" "$work/torus.obj" --atlas --size 256 -o "$work/torus-baked.glb" >/dev/null
"$limn" paint "$work/torus.obj" --strokes "$here/material.json" -o "$work/material.lot" >/dev/null
"$limn" bake "$work/material.lot" "$work/torus.obj" --atlas --size 256 --normal-map \
  -o "$work/torus-material.glb" >/dev/null
"$limn" demo --quick -o "$work/demo" >/dev/null 2>&1
if [[ -d "$models/osd" ]]; then
  car=$models/osd/catmark_car.obj bigguy=$models/quads/bigguy.obj
  "$limn" convert "$car" "$work/car.glb" >/dev/null 2>&1
  "$limn" subdivide "$car" -o "$work/car-uniform.glb" --uniform 2 >/dev/null 2>&1
  "$limn" subdivide "$car" -o "$work/car-limit.glb" --uniform 2 --limit >/dev/null 2>&1
  "$limn" subdivide "$bigguy" -o "$work/bigguy-adaptive.glb" --adaptive --depth 2 >/dev/null 2>&1
  "$limn" simplify "$bigguy" -o "$work/bigguy-simplified.glb" --proxies 60 >/dev/null 2>&1
  "$limn" convert "$models/tri/spot.obj" "$work/spot.glb" >/dev/null 2>&1
  # A painted scan out to a material GLB: a stroke of red metal along the bunny's flank.
  cat >"$work/bunny.json" <<'JSON'
{"strokes": [{"points": [[-0.0665, 0.101466, 0.041219], [-0.039509, 0.098682, 0.041774],
  [-0.015394, 0.099814, 0.044364], [0.020477, 0.098952, 0.046347]], "radius": 0.006,
  "color": [1, 0, 0, 1], "metallic": 1, "roughness": 0.3, "height": 0.8}]}
JSON
  "$limn" paint "$models/tri/stanford-bunny.obj" --strokes "$work/bunny.json" \
    -o "$work/bunny.lot" >/dev/null 2>&1
  "$limn" bake "$work/bunny.lot" "$models/tri/stanford-bunny.obj" --atlas --size 512 \
    --normal-map -o "$work/bunny-material.glb" >/dev/null 2>&1
fi
mapfile -t files < <(find "$work" -name '*.glb' | sort)
node "$here/validate.cjs" "$modules" "${files[@]}"
