#!/usr/bin/env bash
# Denoising (issue 20): relMSE of the noisy beauty and of the Open Image Denoise result against
# the shared references, per scene, integrator and time budget, and the denoiser's own time.
# Needs a photon built with the feature: cargo build --release --features denoise.
# RENDER_ARGS adds render flags (e.g. RENDER_ARGS="--aov albedo,normal" for the guides).
# Usage: benches/denoise.sh [BUDGETS...]   (default 1 4 16; prints a Markdown table). The
# masked columns leave out pixels next to reference pixels brighter than 1 (compare --mask-above 1:
# the visible light's edge, where pixel filters disagree; see ../shared/README.md).
set -euo pipefail
cd "$(dirname "$0")/.."
photon=${PHOTON_BIN:-${CARGO_TARGET_DIR:-target}/release/photon}
budgets=("${@:-1 4 16}")
read -r -a budgets <<<"${budgets[*]}"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
relmse() { "$photon" compare "$1" "$2" --downsample "${@:3}" | grep -o '^relMSE [0-9.e-]*' | cut -d' ' -f2; }
echo "| scene (128x128) | integrator | budget | spp | relMSE noisy | relMSE denoised | ratio | without pixels next to the light: noisy | denoised | ratio | OIDN s |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
for pair in cornell-spheres:reference.exr cornell-box:reference-tungsten.exr; do
  scene=${pair%%:*}; ref=../shared/scenes/$scene/${pair#*:}
  file=$(ls ../shared/scenes/$scene/*.pbrt | head -n 1)
  for integrator in photonmap path; do
    for t in "${budgets[@]}"; do
      img=$out/$scene-$integrator-$t.exr
      log=$("$photon" render "$file" --res 128x128 --time "$t" --integrator "$integrator" \
        --denoise --no-png -o "$img" ${RENDER_ARGS:-})
      "$photon" convert "$img" --layer noisy -o "$out/noisy.exr" >/dev/null
      spp=$(grep '^time budget' <<<"$log" | grep -o '[0-9]* spp' | cut -d' ' -f1)
      secs=$(grep -o 'denoised with .* in [0-9.]* s' <<<"$log" | grep -o '[0-9.]* s$' | cut -d' ' -f1)
      a=$(relmse "$out/noisy.exr" "$ref"); b=$(relmse "$img" "$ref")
      c=$(relmse "$out/noisy.exr" "$ref" --mask-above 1); d=$(relmse "$img" "$ref" --mask-above 1)
      ratio=$(python3 -c "print(f'{$a / $b:.1f}x')"); ratio2=$(python3 -c "print(f'{$c / $d:.1f}x')")
      echo "| $scene | $integrator | ${t} s | ${spp:-?} | $a | $b | $ratio | $c | $d | $ratio2 | $secs |"
    done
  done
done
