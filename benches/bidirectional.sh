#!/bin/bash
# The bidirectional integrators against pbrt-v4 at equal wall time (issue 19): for each scene,
# photon's photonmap, bdpt and vcm (`render --time`), and pbrt-v4's path, bdpt and sppm at the
# samples per pixel that fill the same time, all against REFDIR/<scene>/ref.exr, through
# `scripts/oracle.py table` (0.5-px box filter, the long side RES, 2 threads, SEEDS seeds).
#
#   benches/bidirectional.sh REFDIR SECONDS RES SEEDS SCENE.pbrt...
#
# REFDIR/<scene>/ref.exr: a converged reference of RES pixels on the long side (e.g. the
# Tungsten references of github:gonsolo/bitterli box-filtered down). Needs pbrt-v4 built from
# ../shared/peers/pbrt-v4/ (scripts/oracle.py's default path, or PBRT=...). Prints the tables
# (one per photon integrator; pbrt-v4's columns in the first) and keeps the renders in
# $OUT (default /tmp/bidirectional-bench). PYTHON: a python with numpy and OpenEXR.
set -eu
refs=$1; seconds=$2; res=$3; seeds=$4; shift 4
out=${OUT:-/tmp/bidirectional-bench}
pbrt=${PBRT:-}
extra=(); [ -n "$pbrt" ] && extra=(--pbrt "$pbrt")
here=$(cd "$(dirname "$0")/.." && pwd)
for integ in photonmap bdpt vcm; do
    echo "## photon --integrator $integ, ${seconds} s, ${res} px, ${seeds} seeds"
    pbrt_integrators=""
    [ "$integ" = photonmap ] && pbrt_integrators="path,bdpt,sppm"
    "${PYTHON:-python3}" "$here/scripts/oracle.py" table "$refs" "$@" --res "$res" --seconds "$seconds" \
        --seeds "$seeds" --out "$out/$integ" --integrators "$pbrt_integrators" \
        --flags "--integrator $integ" "${extra[@]}"
done
