#!/bin/sh
# Benchmark of a planner's block grown (docs/performance.md, "sylva site"), run by
# hand, not a test:
#   tests/bench/site_block.sh [SYLVA_EXE [DIR]]  (default build/server/sylva; DIR keeps
#                                               the layers and results)
# Cuts a 200 m x 200 m block (--bbox) out of the synthetic square kilometre of
# site_km2.sh (its layers are made there first), grows it 20 years with `sylva run`
# and writes its trunks and crowns at years 10 and 20 as a GeoPackage, timing each
# step (wall, CPU, peak memory).
set -eu
. "$(dirname "$0")/bench_args.sh"
[ -f "$tmp/buildings.gpkg" ] && [ -f "$tmp/trees.gpkg" ] || sh "$(dirname "$0")/site_km2.sh" "$exe" "$tmp"
# UTM 18N 586400..586600 E, 4515400..4515600 N, as lon/lat (cs2cs)
bbox=$(printf '586400 4515400\n586600 4515600\n' | cs2cs -f %.7f EPSG:32618 EPSG:4326 |
  awk 'NR == 1 {w = $2; s = $1} NR == 2 {printf "%s,%s,%s,%s", w, s, $2, $1}')
"$exe" site --buildings "$tmp/buildings.gpkg" --height-field height --building-id-field id \
  --trees "$tmp/trees.gpkg" --species-field species --dbh-field dbh --id-field id \
  --start-year 2027 --bbox "$bbox" -o "$tmp/block.json" | tail -n 1
rm -f "$tmp/block.db" "$tmp/block.gpkg"
/usr/bin/time -f "sylva run, the 200 m block, 20 years: %e s wall, %U s user, %M KB peak" \
  "$exe" run "$tmp/block.json" --db "$tmp/block.db" --name block --iterations 20 \
  --quiet-progress >/dev/null
/usr/bin/time -f "sylva export --format gpkg, years 10 and 20: %e s wall, %U s user, %M KB peak" \
  "$exe" export --db "$tmp/block.db" --name block --format gpkg --years 10,20 -o "$tmp/block.gpkg"
"$exe" export --db "$tmp/block.db" --name block --format csv -o - | python3 -c '
import csv, sys
rows = [r for r in csv.DictReader(sys.stdin) if r["iteration"] == "20"]
num = lambda k: [float(r[k]) for r in rows if r[k]]
print("year 20: %d stems, mean height %.1f m, mean dbh %.1f cm, carbon %.1f t C, canopy cover %.1f %%"
      % (len(rows), sum(num("height")) / len(rows), 100 * sum(num("dbh")) / len(num("dbh")),
         sum(num("carbon")) / 1000, 100 * float(rows[0]["canopy_cover"])))'
