#!/bin/sh
# Benchmark of `sylva site` on a square kilometre (docs/performance.md, "sylva site"),
# run by hand, not a test:
#   tests/bench/site_km2.sh [SYLVA_EXE [DIR]]  (default build/server/sylva; DIR keeps
#                                              the layers, and layers there are reused)
# Writes a synthetic site near New York, 1 x 1 km in WGS 84 / UTM zone 18N
# (EPSG:32618): 2,000 buildings on a 45 x 45 grid of 22 m lots (rotated rectangles and
# L-shapes, every fifth L with a courtyard, 3 to 40 m high) and 5,000 trees in lon/lat
# (the NoEast library's species but Malus, a cultivar or variety name for one in
# ten, DBH 5 to 80 cm), each as a GeoPackage (ogr2ogr), then times sylva site on them.
set -eu
. "$(dirname "$0")/bench_args.sh"
if [ ! -f "$tmp/buildings.gpkg" ] || [ ! -f "$tmp/trees.gpkg" ]; then
  python3 - "$tmp" <<'PY'
import json, math, os, random, subprocess, sys
out = sys.argv[1]
rng = random.Random(2024)
E0, N0, SIDE, LOTS = 586000.0, 4515000.0, 1000.0, 45
lot = SIDE / LOTS

def turned(cx, cy, angle, pts):
    c, s = math.cos(angle), math.sin(angle)
    ring = [[round(cx + x * c - y * s, 2), round(cy + x * s + y * c, 2)] for x, y in pts]
    return ring + [ring[0]]

features = []
for i in range(2000):
    gx, gy = i % LOTS, i // LOTS
    cx, cy = E0 + (gx + 0.5) * lot, N0 + (gy + 0.5) * lot
    angle = rng.uniform(0, math.pi / 2)
    w, d = rng.uniform(8, 15), rng.uniform(6, 12)
    if i % 3 == 0:  # an L of arms w x d/2
        arm = d / 2
        pts = [(-w / 2, -d / 2), (w / 2, -d / 2), (w / 2, -d / 2 + arm), (-w / 2 + arm, -d / 2 + arm),
               (-w / 2 + arm, d / 2), (-w / 2, d / 2)]
        rings = [turned(cx, cy, angle, pts)]
        if i % 15 == 0:
            k = arm / 4
            hole = [(-w / 2 + k, -d / 2 + k), (-w / 2 + k, -d / 2 + 3 * k),
                    (-w / 2 + 3 * k, -d / 2 + 3 * k), (-w / 2 + 3 * k, -d / 2 + k)]
            rings.append(turned(cx, cy, angle, hole))
    else:
        rings = [turned(cx, cy, angle, [(-w / 2, -d / 2), (w / 2, -d / 2), (w / 2, d / 2), (-w / 2, d / 2)])]
    features.append({"type": "Feature",
                     "properties": {"id": "b%d" % i, "height": round(rng.uniform(3, 40), 1)},
                     "geometry": {"type": "Polygon", "coordinates": rings}})
with open(os.path.join(out, "buildings.geojson"), "w") as f:
    json.dump({"type": "FeatureCollection", "name": "buildings",
               "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::32618"}},
               "features": features}, f)

names = ["Acer platanoides", "Acer rubrum", "Acer saccharinum", "Acer saccharum",
         "Aesculus hippocastanum", "Fraxinus pennsylvanica", "Ginkgo biloba",
         "Gleditsia triacanthos", "Liquidambar styraciflua", "Pinus strobus",
         "Platanus x acerifolia", "Prunus serrulata", "Pyrus calleryana", "Quercus palustris",
         "Quercus phellos", "Quercus rubra", "Tilia cordata", "Tilia tomentosa",
         "Ulmus americana", "Zelkova serrata"]
points = "".join("%.3f %.3f\n" % (E0 + rng.uniform(0, SIDE), N0 + rng.uniform(0, SIDE))
                 for _ in range(5000))
lonlat = subprocess.run(["cs2cs", "-f", "%.7f", "EPSG:32618", "EPSG:4326"], input=points,
                        capture_output=True, text=True, check=True).stdout.splitlines()
trees = []
for i, line in enumerate(lonlat):
    lat, lon = (float(v) for v in line.split()[:2])
    name = rng.choice(names)
    if i % 10 == 0:
        name += rng.choice([" 'Autumn Gold'", " var. inermis", " 'Crimson King'"])
    trees.append({"type": "Feature",
                  "properties": {"id": "t%d" % i, "species": name,
                                 "dbh": round(rng.uniform(5, 80), 1)},
                  "geometry": {"type": "Point", "coordinates": [lon, lat]}})
with open(os.path.join(out, "trees.geojson"), "w") as f:
    json.dump({"type": "FeatureCollection", "name": "trees", "features": trees}, f)
PY
  ogr2ogr -f GPKG "$tmp/buildings.gpkg" "$tmp/buildings.geojson" -nln buildings
  ogr2ogr -f GPKG "$tmp/trees.gpkg" "$tmp/trees.geojson" -nln trees
fi
/usr/bin/time -f "sylva site, 1 km2, 2000 buildings, 5000 trees (GeoPackage): %e s wall, %U s user, %M KB peak" \
  "$exe" site --buildings "$tmp/buildings.gpkg" --height-field height --building-id-field id \
  --trees "$tmp/trees.gpkg" --species-field species --dbh-field dbh --id-field id \
  --start-year 2027 -o "$tmp/site.json"
