#!/bin/bash
# Issue 8's driver benchmark: rays/s and time-to-error of several photon binaries, runs
# interleaved (A B C, A B C, ...) so that load from other jobs falls on all of them alike.
#
#   benches/driver-compare.sh OUTDIR REPEATS NAME=BINARY...
#
# Per binary and repeat, with `nice -n -10` when allowed:
# - `render --stats` of cornell-spheres and cornell-box at 256x256, 16 spp, 2 threads (the
#   Mrays/s line of the render loop);
# - `bench --quick` on the three shared scenes, 1 thread, no generated mesh (bench.csv);
# - `converge` on cornell-spheres at 1, 2, 4 s, method photonmap (converge.csv).
# Everything goes under OUTDIR/NAME/REPEAT/; `uptime` before each run goes to OUTDIR/load.txt.
set -u
out=$1; reps=$2; shift 2
shared=${SHARED:-../shared}
spheres=$shared/scenes/cornell-spheres/scene.pbrt
box=$shared/scenes/cornell-box/scene-v4.pbrt
nice="nice -n -10"
$nice true 2>/dev/null || nice=""
mkdir -p "$out"
for r in $(seq 1 "$reps"); do
  for pair in "$@"; do
    name=${pair%%=*}; bin=${pair#*=}
    d=$out/$name/$r; mkdir -p "$d"
    for s in spheres box; do
      scene=$spheres; [ $s = box ] && scene=$box
      echo "$name $r render-$s $(uptime)" >> "$out/load.txt"
      $nice "$bin" render "$scene" --res 256x256 --spp 16 --threads 2 --stats \
        -o "$d/$s.exr" --no-png > "$d/render-$s.txt" 2>&1
    done
    echo "$name $r bench $(uptime)" >> "$out/load.txt"
    $nice "$bin" bench --quick --generated 0 --threads 1 --scene "$box" --scene "$spheres" \
      --scene "$shared/scenes/veach-mis/scene-v4.pbrt" --csv "$d/bench.csv" > "$d/bench.txt" 2>&1
    echo "$name $r converge $(uptime)" >> "$out/load.txt"
    $nice "$bin" converge "$spheres" --reference "$shared/scenes/cornell-spheres/reference.exr" \
      --budgets 1,2,4 --methods photonmap --out "$d/converge" > "$d/converge.txt" 2>&1
  done
done
