#!/bin/bash
# What `render --display-server` costs: the same render without it, with it and no viewer
# listening (a closed port), and with a viewer that reads and discards everything (a stand-in
# for tev), interleaved.
#
#   benches/display-overhead.sh SCENE REPEATS "RENDER ARGS"
#
# Prints one line per run: mode, repeat, the render's own seconds ("rendered in") and the
# process's wall seconds; then the median of each mode.
set -u
scene=$1; reps=$2; args=$3
bin=${PHOTON:-target/release/photon}
tmp=$(mktemp -d)
# The stand-in viewer: accepts connections one after another and discards what they send.
python3 -c '
import socket, sys
s = socket.socket(); s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
s.bind(("127.0.0.1", 0)); s.listen(4)
print(s.getsockname()[1], flush=True)
while True:
    c, _ = s.accept()
    while c.recv(1 << 20):
        pass
    c.close()
' > "$tmp/port" &
viewer=$!
trap 'kill $viewer 2>/dev/null; rm -rf "$tmp"' EXIT
while [ ! -s "$tmp/port" ]; do sleep 0.1; done
port=$(cat "$tmp/port")
# A port nobody listens on: bind one, note it, close it.
closed=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
for r in $(seq 1 "$reps"); do
  for mode in none closed viewer; do
    case $mode in
      none) extra="" ;;
      closed) extra="--display-server 127.0.0.1:$closed" ;;
      viewer) extra="--display-server 127.0.0.1:$port" ;;
    esac
    start=$(date +%s.%N)
    # shellcheck disable=SC2086
    "$bin" render "$scene" $args $extra -o "$tmp/out.exr" --no-png > "$tmp/log" 2>&1
    wall=$(echo "$(date +%s.%N) - $start" | bc)
    render=$(sed -n 's/^rendered in \([0-9.]*\) s.*/\1/p' "$tmp/log")
    echo "$mode $r render $render wall $wall"
  done
done | tee "$tmp/runs"
for mode in none closed viewer; do
  median=$(awk -v m="$mode" '$1 == m { print $4 }' "$tmp/runs" | sort -n | awk '{ a[NR] = $1 } END { print a[int((NR + 1) / 2)] }')
  echo "median $mode render $median s"
done
