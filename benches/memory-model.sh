#!/bin/bash
# The memory model against the measured peak on the Bitterli scenes (BENCHMARKS.md, "Memory
# model"): one line per scene with the `memory:` line's estimate and peak and the photons
# stored. Usage: benches/memory-model.sh SCENES_DIR [render flags...], where SCENES_DIR holds
# <scene>/pbrt/scene-v4.pbrt (as ../shared/tools/repair_bitterli.py writes them), e.g.
#   benches/memory-model.sh /work/bitterli/ph --res 160x90 --spp 1
set -u
DIR=$1; shift
BIN=${PHOTON:-$(cd "$(dirname "$0")/.." && pwd)/target/release/photon}
OUT=$(mktemp -d)
for f in "$DIR"/*/pbrt/scene-v4.pbrt; do
  n=$(basename "$(dirname "$(dirname "$f")")")
  r=$(cd "$(dirname "$f")" && timeout 600 "$BIN" render scene-v4.pbrt -o "$OUT/$n.exr" --no-png --threads 2 "$@" 2>&1)
  m=$(echo "$r" | grep "^memory:" | tail -1 | sed 's/.*(~\([0-9.]* [KMG]B\)), peak.*(~\([0-9.]* [KMG]B\)).*/est \1 peak \2/')
  p=$(echo "$r" | grep "^photons:" | sed 's/photons: global \([0-9]*\) emitted -> \([0-9]*\) stored; caustic \([0-9]*\) emitted -> \([0-9]*\) stored.*/g \1->\2 c \3->\4/')
  [ -n "$m" ] || m="does not render: $(echo "$r" | tail -1 | cut -c1-100)"
  echo -e "$n\t$m\t$p"
done
rm -rf "$OUT"
