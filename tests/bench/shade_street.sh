#!/bin/sh
# Benchmark of `sylva shade` (docs/performance.md, "Shade"), run by hand, not a test:
#   tests/bench/shade_street.sh [SYLVA_EXE]     (default build/server/sylva)
# Grows scenarios/street.json to its end (30 iterations, 2057) into a temporary
# store, then times the whole day of 06-21 at 10-minute steps, every cell of the
# ground and the facades, three times, printing each run's wall and CPU seconds.
set -eu
root=$(cd "$(dirname "$0")/../.." && pwd)
exe=${1:-"$root/build/server/sylva"}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$exe" run "$root/scenarios/street.json" --db "$tmp/street.db" --name street \
  --quiet-progress > /dev/null
for k in 1 2 3; do
  /usr/bin/time -f "shade street 2057 06-21 whole day: %e s wall, %U s user" \
    "$exe" shade --db "$tmp/street.db" --name street --year 2057 --date 06-21 \
    -o "$tmp/street.csv" > /dev/null
done
