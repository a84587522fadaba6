#!/bin/sh
# Benchmark of `sylva shade` on a hectare (docs/performance.md, "Shade"), run by
# hand, not a test:
#   tests/bench/shade_hectare.sh [SYLVA_EXE [DIR]]  (default build/server/sylva; DIR keeps
#                                                 the store, and a store there is reused)
# Grows the hectare of `bench years` (400 littleleaf lindens, utdb:NoEast:TICO, 5 m
# apart, 106 x 106 m, 30 m high, the voxel of the species' rho / 2) 40 years into a
# temporary store, under a site sky at 48° N of 16 directions (shade needs the
# site's latitude), then times the whole day of 07-21 at 10-minute steps on every
# cell of the ground (the hectare has no obstacles).
set -eu
. "$(dirname "$0")/bench_args.sh"
python3 - "$tmp/hectare.json" <<'PY'
import json, sys
rows, spacing = 20, 5.0
half = rows * spacing / 2 + 3
plants = [{"id": "t%d" % i, "species": "linden",
           "roots": [[(i % rows - (rows - 1) / 2) * spacing, (i // rows - (rows - 1) / 2) * spacing, 0]]}
          for i in range(rows * rows)]
json.dump({"format": "sylva.scenario/1", "name": "a hectare of 400 lindens", "seed": 2024,
           "iterations": 40, "start_year": 2030,
           "world": {"min": [-half, -half, 0], "max": [half, half, 30]},
           "species": {"linden": {"preset": "utdb:NoEast:TICO"}}, "plants": plants,
           "light": {"sky": "site", "latitude": 48, "samples": 16}}, open(sys.argv[1], "w"))
PY
[ -f "$tmp/hectare.db" ] ||
  /usr/bin/time -f "grow the hectare 40 years: %e s wall, %U s user, %M KB peak" \
    "$exe" run "$tmp/hectare.json" --db "$tmp/hectare.db" --name h --quiet-progress > /dev/null
/usr/bin/time -f "shade hectare 2070 07-21 whole day (all cores): %e s wall, %U s user, %M KB peak" \
  "$exe" shade --db "$tmp/hectare.db" --name h --year 2070 --date 07-21 --surface ground \
  -o "$tmp/hectare.json.out.json"
