"""`sylva site` through the real binary (Python 3 standard library, GDAL's ogr2ogr
and ogrinfo, PROJ's cs2cs).

meson runs `python3 test_site_cli.py SYLVA_EXE DATA_DIR SOURCE_ROOT` on the fixtures
of tests/gis/data (make_fixtures.py): three buildings in EPSG:32618 (one L-shaped
with a courtyard, one of two parts), a zone and 14 trees in lon/lat near New York.
It checks the summary's counts; every root against cs2cs's own transform of the
tree's lon/lat; every age against the Urban Tree Database's dbh -> age row of
TS6_Growth_coefficients.csv, computed here as docs/cli.md states the rule; every
prism's rings (counter-clockwise outline, clockwise holes, not closed) and area
against GDAL's; that `sylva validate` takes the scenario; the same bytes from the
site given as GeoJSON, GeoPackage, Shapefile, FlatGeobuf and CSV; a species map; a
DBH in inches; a bbox; and bad input: exit 2, a message naming the file, the layer
and the field, and no file written. Then the results back to GIS: the site grown 10
years and exported as GeoJSON and GeoPackage (`sylva export --format geojson|gpkg`),
each trunk within 1 cm of its tree's place, the figures those of the CSV export, the
crowns as large as their crown_area, the buildings with their courtyard.
"""
import csv
import json
import math
import os
import re
import subprocess
import sys
import tempfile

EXE, DATA, ROOT = sys.argv[1], sys.argv[2], sys.argv[3]
failures = []
checks = 0


def check(cond, what):
    global checks
    checks += 1
    if not cond:
        failures.append(what)
        print("FAILED:", what, file=sys.stderr)


def run(*args, timeout=120):
    return subprocess.run(list(args), capture_output=True, text=True, timeout=timeout)


def sylva(*args):
    return run(EXE, *args)


def fixture(name):
    return os.path.join(DATA, name)


BUILDING_OPTS = ["--height-field", "height", "--levels-field", "levels", "--building-id-field", "id"]
TREE_OPTS = ["--species-field", "species", "--dbh-field", "dbh", "--id-field", "id",
             "--keep", "status=alive"]
ZONE_OPTS = ["--zone-field", "clearance"]


def site(out, *extra, buildings="buildings.geojson", trees="trees.geojson",
         zones="zones.geojson", tree_opts=TREE_OPTS):
    """Runs sylva site on the layers given (None: not given), each with its options."""
    args = ["site"]
    for path, opts, option in ((buildings, BUILDING_OPTS, "--buildings"),
                               (trees, tree_opts, "--trees"), (zones, ZONE_OPTS, "--zones")):
        if path:
            args += [option, path if os.path.isabs(path) else fixture(path), *opts]
    p = sylva(*args, "--start-year", "2027", *extra, "-o", out)
    summary = None
    if p.returncode == 0:
        summary = json.loads(p.stdout.strip().splitlines()[-1])
    return p, summary


# ---- the Urban Tree Database's dbh -> age, as docs/cli.md states the rule ----------

def utdb_rows():
    rows = {}
    with open(os.path.join(ROOT, "data", "utdb", "TS6_Growth_coefficients.csv"), newline="") as f:
        for r in csv.DictReader(f):
            r = {k.strip(): (v or "").strip() for k, v in r.items()}
            rows[(r["Region"], r["SpCode"], r["Independent variable"], r["Predicts component"])] = r
    return rows


def number(r, key):
    return float(r[key]) if r[key] else 0.0


def equation(r, x):
    a, b, c, d, e = (number(r, k) for k in "abcde")
    form = r["EqName"]
    if form == "lin":
        return a + b * x
    if form == "quad":
        return a + b * x + c * x * x
    if form == "cub":
        return a + b * x + c * x * x + d * x ** 3
    if form == "quart":
        return a + b * x + c * x * x + d * x ** 3 + e * x ** 4
    if form == "loglogw1":
        return math.exp(a + b * math.log(math.log(x + 1) + c / 2))
    weights = {"loglogw2": math.sqrt(x), "loglogw3": x, "loglogw4": x * x,
               "expow1": 1.0, "expow2": math.sqrt(x), "expow3": x, "expow4": x * x}
    if form.startswith("loglogw"):
        return math.exp(a + b * math.log(math.log(x + 1)) + weights[form] * c / 2)
    return math.exp(a + b * x + weights[form] * c / 2)


def expected_age(rows, library, name, dbh_cm):
    _, region, code = name.split(":")
    age_row = rows[(region, code, "dbh", "age")]
    dbh_row = rows[(region, code, "age", "dbh")]
    lo, hi = float(dbh_row["Apps min"]), float(dbh_row["Apps max"])
    x = min(max(dbh_cm, lo), hi)
    # the running maximum from the start of the range to x, sampled finely
    steps = 20000
    best = max(equation(age_row, lo + (x - lo) * i / steps) for i in range(steps + 1))
    age = math.floor(best + 0.5)
    a_min, a_max = library[name]["ages"]
    return int(min(max(age, a_min, 0), a_max, 500))


def shoelace(ring):
    return sum(ring[i][0] * ring[(i + 1) % len(ring)][1] - ring[(i + 1) % len(ring)][0] * ring[i][1]
               for i in range(len(ring))) / 2


def gdal_areas(path):
    p = run("ogrinfo", "-q", "-sql", "SELECT id, OGR_GEOM_AREA AS area FROM buildings", path)
    check(p.returncode == 0, "ogrinfo: " + p.stderr)
    areas, current = {}, None
    for line in p.stdout.splitlines():
        line = line.strip()
        if line.startswith("id (String) = "):
            current = line.split("= ", 1)[1]
        elif line.startswith("area (Real) = "):
            areas[current] = float(line.split("= ", 1)[1])
    return areas


def cs2cs_utm(lonlats):
    text = "".join("%.7f %.7f\n" % (lat, lon) for lon, lat in lonlats)
    p = run("cs2cs", "-d", "4", "EPSG:4326", "EPSG:32618")
    p = subprocess.run(["cs2cs", "-d", "4", "EPSG:4326", "EPSG:32618"], input=text,
                       capture_output=True, text=True, timeout=60)
    check(p.returncode == 0, "cs2cs: " + p.stderr)
    return [tuple(float(v) for v in line.split()[:2]) for line in p.stdout.splitlines()]


def main():
    rows = utdb_rows()
    with open(os.path.join(ROOT, "data", "species", "library.json")) as f:
        library = {s["name"]: s for s in json.load(f)["species"]}
    with open(fixture("trees.geojson")) as f:
        trees = {t["properties"]["id"]: t for t in json.load(f)["features"]}

    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "site.json")
        p, s = site(out)
        check(p.returncode == 0, "the site: " + p.stderr)
        if p.returncode != 0:
            return
        check(not os.path.exists(out + ".tmp"), "no .tmp left")
        # the summary
        check((s["buildings"], s["prisms"], s["trees"], s["zones"]) == (3, 4, 5, 1),
              "counts: %s" % s)
        check(s["left_out"] == {"filtered": 2, "no_position": 0, "outside_bbox": 0, "unmatched": 4,
                                "no_dbh": 1, "no_height": 1, "too_small": 0, "in_building": 1,
                                "too_close": 1}, "left out: %s" % s["left_out"])
        check(s["unmatched"] == {"Magnolia grandiflora": 1, "Betula papyrifera": 1,
                                 "Zelkova serata": 1, "Quercus palustis": 1},
              "unmatched: %s" % s["unmatched"])
        matched = {"T1": "utdb:NoEast:PLAC", "T2": "utdb:NoEast:ACPL", "T3": "utdb:NoEast:GLTR",
                   "T4": "utdb:NoEast:TICO", "T5": "utdb:NoEast:GIBI"}
        check(s["species"] == {v: 1 for v in matched.values()}, "species: %s" % s["species"])
        check(s["region"] == "NoEast" and s["frame"]["crs"] == "EPSG:32618", "frame: %s" % s)
        with open(out) as f:
            doc = json.load(f)
        check(doc["site"] == s["frame"] and doc["world"]["min"][:2] == s["world"]["min"][:2],
              "the file's site and world")
        check(doc["light"]["sky"] == "site" and abs(doc["light"]["latitude"] - 40.7817) < 0.001,
              "light: %s" % doc["light"])
        check(doc["start_year"] == 2027 and doc["iterations"] == 10, "start_year, iterations")
        plants = {pl["id"]: pl for pl in doc["plants"]}
        check({k: v["species"] for k, v in plants.items()} == matched, "plants: %s" % plants)

        # every root at PROJ's own place for its lon/lat, less the origin
        ids = sorted(plants)
        utm = cs2cs_utm([trees[i]["geometry"]["coordinates"] for i in ids])
        ox, oy = doc["site"]["origin"]
        for i, (e, n) in zip(ids, utm):
            x, y, z = plants[i]["roots"][0]
            check(abs(x - (e - ox)) <= 0.05 and abs(y - (n - oy)) <= 0.05 and z == 0,
                  "%s: root %s, cs2cs %.4f %.4f" % (i, plants[i]["roots"][0], e - ox, n - oy))
        # every age by the dbh -> age equation
        for i in ids:
            want = expected_age(rows, library, plants[i]["species"], trees[i]["properties"]["dbh"])
            check(plants[i]["age"] == want, "%s: age %d, the equation %d" % (i, plants[i]["age"], want))

        # prisms: rings, areas against GDAL's
        areas = gdal_areas(fixture("buildings.geojson"))
        mine = {}
        for ob in doc["obstacles"]:
            rings = [ob["polygon"]] + ob.get("holes", [])
            check(all(r[0] != r[-1] and len(r) >= 3 for r in rings), "%s: rings not closed" % ob["id"])
            check(shoelace(ob["polygon"]) > 0, "%s: outline counter-clockwise" % ob["id"])
            check(all(shoelace(h) < 0 for h in ob.get("holes", [])), "%s: holes clockwise" % ob["id"])
            check("holes" not in ob or ob["holes"], "%s: holes only when there are" % ob["id"])
            if ob["kind"] == "prism":
                base = ob["id"].split("/")[0]
                mine[base] = mine.get(base, 0) + shoelace(ob["polygon"]) + sum(
                    shoelace(h) for h in ob.get("holes", []))
        check(sorted(mine) == ["B1", "B2", "B3"], "prisms: %s" % sorted(mine))
        for k, a in mine.items():
            check(abs(a / areas[k] - 1) <= 0.001, "%s: area %.3f, GDAL %.3f" % (k, a, areas[k]))
        kinds = {ob["id"]: (ob["kind"], ob["z"]) for ob in doc["obstacles"]}
        check(kinds == {"B1": ("prism", [0, 15.5]), "B2": ("prism", [0, 12]),
                        "B3": ("prism", [0, 9]), "B3/2": ("prism", [0, 9]),
                        "zone-1": ("zone", [0, 4.5])}, "obstacles: %s" % kinds)
        check(len(doc["obstacles"][1].get("holes", [])) == 1, "B2's courtyard")

        # sylva validate takes it (prisms and the site are proto's)
        p = sylva("validate", out)
        check(p.returncode == 0, "validate: " + p.stderr)

        results_to_gis(tmp, out, trees)

        # the same site in other formats: the same bytes
        with open(out, "rb") as f:
            reference = f.read()
        conv = os.path.join(tmp, "conv")
        os.mkdir(conv)
        for layer in ("buildings", "trees", "zones"):
            src = fixture(layer + ".geojson")
            for driver, ext, lco in (("GPKG", "gpkg", []), ("ESRI Shapefile", "shp", []),
                                     ("FlatGeobuf", "fgb", ["-lco", "SPATIAL_INDEX=NO"]),
                                     ("CSV", "csv", ["-lco", "GEOMETRY=AS_XY" if layer == "trees"
                                                     else "GEOMETRY=AS_WKT"])):
                q = run("ogr2ogr", "-f", driver, *lco, os.path.join(conv, layer + "." + ext), src,
                        "-nln", layer)
                check(q.returncode == 0, "ogr2ogr %s %s: %s" % (layer, driver, q.stderr))
        for ext in ("gpkg", "shp", "fgb", "csv"):
            other = os.path.join(tmp, "site-%s.json" % ext)
            extra = (["--buildings-crs", "EPSG:32618", "--zones-crs", "EPSG:32618", "--xy-fields",
                      "X,Y"] if ext == "csv" else [])
            p, _ = site(other, *extra, buildings=os.path.join(conv, "buildings." + ext),
                        trees=os.path.join(conv, "trees." + ext),
                        zones=os.path.join(conv, "zones." + ext))
            check(p.returncode == 0, "%s: %s" % (ext, p.stderr))
            if p.returncode == 0:
                with open(other, "rb") as f:
                    check(f.read() == reference, "%s: the same bytes as the GeoJSON's" % ext)

        # a species map for what is left: a code, a scientific name
        mapping = os.path.join(tmp, "map.csv")
        with open(mapping, "w") as f:
            f.write('name,species\nZelkova serata,ZESE\n"quercus  palustis",Quercus palustris\n')
        p, m = site(os.path.join(tmp, "mapped.json"), "--species-map", mapping)
        check(p.returncode == 0, "--species-map: " + p.stderr)
        if m:
            check(m["unmatched"] == {"Magnolia grandiflora": 1, "Betula papyrifera": 1} and
                  m["species"].get("utdb:NoEast:ZESE") == 1 and
                  m["species"].get("utdb:NoEast:QUPA") == 1 and m["trees"] == 7,
                  "mapped: %s" % m)

        # a DBH in inches
        inches = os.path.join(tmp, "inches.json")
        opts = [("dbh_in" if a == "dbh" else a) for a in TREE_OPTS] + ["--dbh-unit", "in"]
        p, _ = site(inches, tree_opts=opts)
        check(p.returncode == 0, "--dbh-unit in: " + p.stderr)
        if p.returncode == 0:
            with open(inches) as f:
                for pl in json.load(f)["plants"]:
                    cm = trees[pl["id"]]["properties"]["dbh_in"] * 2.54
                    want = expected_age(rows, library, pl["species"], cm)
                    check(pl["age"] == want, "inches: %s: age %d, the equation %d" %
                          (pl["id"], pl["age"], want))

        # a bbox around the row of trees: buildings and the zone are cut
        lons = [t["geometry"]["coordinates"][0] for t in trees.values()]
        lats = [t["geometry"]["coordinates"][1] for t in trees.values() if t["properties"]["id"] != "T14"]
        box = "%.7f,%.7f,%.7f,%.7f" % (min(lons) - 1e-5, min(lats) - 1e-5, max(lons) + 1e-5,
                                       max(lats) + 1e-5)
        bboxed = os.path.join(tmp, "bbox.json")
        p, b = site(bboxed, "--bbox", box)
        check(p.returncode == 0, "--bbox: " + p.stderr)
        if b:
            check(b["prisms"] == 0 and b["zones"] == 0 and b["trees"] == 5 and
                  b["left_out"]["outside_bbox"] == 6, "bbox: %s" % b)
            w = b["world"]
            check(w["min"][0] < 0 < w["max"][0] and w["min"][1] < 0 < w["max"][1] and
                  all(isinstance(v, int) for v in w["min"] + w["max"]), "bbox world: %s" % w)

        bad_cases(tmp)


def ogr_csv(path, layer, *sql):
    """A layer (or an SQL query's result) of a GIS file as CSV rows, through ogr2ogr."""
    args = ["ogr2ogr", "-f", "CSV", "/vsistdout/", path]
    args += ["-dialect", "SQLite", "-sql", sql[0]] if sql else [layer, "-lco", "GEOMETRY=AS_XY"]
    p = run(*args)
    check(p.returncode == 0, "ogr2ogr %s %s: %s" % (path, layer, p.stderr))
    return list(csv.DictReader(p.stdout.splitlines()))


def metres_apart(lon1, lat1, lon2, lat2):
    """The distance of two near places on WGS 84, m (its radii of curvature there)."""
    a, f = 6378137.0, 1 / 298.257223563
    e2 = f * (2 - f)
    phi = math.radians((lat1 + lat2) / 2)
    w = math.sqrt(1 - e2 * math.sin(phi) ** 2)
    m, n = a * (1 - e2) / w ** 3, a / w
    return math.hypot(math.radians(lon2 - lon1) * n * math.cos(phi), math.radians(lat2 - lat1) * m)


def results_to_gis(tmp, site_json, trees):
    """The site grown 10 years, then exported as GeoJSON and GeoPackage: every trunk
    within 1 cm of its tree's place, the figures those of the CSV export, each
    crown's polygon as large as its crown_area, the buildings and the zone."""
    db = os.path.join(tmp, "grown.db")
    p = sylva("run", site_json, "--db", db, "--name", "site")
    check(p.returncode == 0, "run the site: " + p.stderr)
    gj, gp = os.path.join(tmp, "site.geojson"), os.path.join(tmp, "site.gpkg")
    for fmt, path in (("geojson", gj), ("gpkg", gp)):
        p = sylva("export", "--db", db, "--name", "site", "--format", fmt, "--years", "5,10",
                  "-o", path)
        check(p.returncode == 0 and os.path.exists(path) and not os.path.exists(path + ".tmp"),
              "export %s: %s" % (fmt, p.stderr))
        q = run("ogrinfo", "-ro", "-so", "-al", path)
        check(q.returncode == 0, "ogrinfo opens the %s: %s" % (fmt, q.stderr))
    if failures:
        return
    with open(gj) as f:
        doc = json.load(f)
    check("crs" not in doc, "GeoJSON: RFC 7946, no crs member")
    feats = doc["features"]
    by = {}
    for ft in feats:
        by.setdefault(ft["properties"]["layer"], []).append(ft)
    check({k: len(v) for k, v in by.items()} == {"trunks": 10, "crowns": 10, "buildings": 4,
                                                  "zones": 1},
          "GeoJSON features: %s" % {k: len(v) for k, v in by.items()})
    # trunks: within 1 cm of the inventory's lon/lat, in both files
    for ft in by.get("trunks", []):
        pr = ft["properties"]
        lon, lat = ft["geometry"]["coordinates"]
        t = trees[pr["plant"]]["geometry"]["coordinates"]
        d = metres_apart(lon, lat, t[0], t[1])
        check(d <= 0.01, "GeoJSON: %s at year %d is %.4f m from its tree" % (pr["plant"], pr["year"], d))
    gtrunks = ogr_csv(gp, "trunks")
    check(len(gtrunks) == 10, "GeoPackage trunks: %d" % len(gtrunks))
    ids = sorted({r["plant"] for r in gtrunks})
    utm = dict(zip(ids, cs2cs_utm([trees[i]["geometry"]["coordinates"] for i in ids])))
    for r in gtrunks:
        e, n = utm[r["plant"]]
        d = math.hypot(float(r["X"]) - e, float(r["Y"]) - n)
        check(d <= 0.01, "GeoPackage: %s at year %s is %.4f m from cs2cs's place" % (r["plant"], r["year"], d))
    # the figures: those of the CSV export at that iteration
    p = sylva("export", "--db", db, "--name", "site", "--format", "csv", "-o", "-")
    stats = {(r["plant"], int(r["iteration"])): r for r in csv.DictReader(p.stdout.splitlines())}
    for ft in by.get("trunks", []) + by.get("crowns", []):
        pr = ft["properties"]
        row = stats[(pr["plant"], pr["iteration"])]
        check(pr["year"] == 2027 + pr["iteration"] and pr["age"] == int(row["age"]) and
              pr["species"] == site_species(site_json)[pr["plant"]],
              "%s %d: year, age, species %s" % (pr["plant"], pr["iteration"], pr))
        for k in ("height", "dbh", "crown_diameter", "crown_height", "leaf_area", "crown_area",
                  "carbon"):
            check(abs(pr[k] - float(row[k])) < 1e-9, "%s %d: %s %s, the CSV's %s" %
                  (pr["plant"], pr["iteration"], k, pr[k], row[k]))
        zones = json.loads(row["zones"] or "{}")
        want = zones["zone-1"]["first"] if "zone-1" in zones else None
        check(pr["conflict_zone-1"] == want, "%s %d: conflict_zone-1 %s, the CSV's %s" %
              (pr["plant"], pr["iteration"], pr["conflict_zone-1"], want))
    check(any(ft["properties"]["conflict_zone-1"] for ft in by.get("trunks", [])),
          "a stem met the zone")
    # crowns: the union of the cells under the leaves, as large as crown_area
    for r in ogr_csv(gp, "crowns", "SELECT plant, iteration, crown_area, ST_Area(geom) AS a "
                                   "FROM crowns"):
        check(abs(float(r["a"]) - float(r["crown_area"])) <= 1e-4,
              "crown %s %s: %s m2, crown_area %s" % (r["plant"], r["iteration"], r["a"], r["crown_area"]))
    # buildings and the zone: B2 keeps its courtyard, the heights their z
    rows = ogr_csv(gp, "buildings", "SELECT id, z_top, AsText(geom) AS wkt, ST_Area(geom) AS a "
                                    "FROM buildings")
    # a MULTIPOLYGON (((outline), (hole), ...)) of one part: its holes are its rings less one
    got = {r["id"]: (float(r["z_top"]), len(re.findall(r"\)\s*,\s*\(", r["wkt"])) -
                     len(re.findall(r"\)\)\s*,\s*\(\(", r["wkt"]))) for r in rows}
    check(got == {"B1": (15.5, 0), "B2": (12.0, 1), "B3": (9.0, 0), "B3/2": (9.0, 0)},
          "GeoPackage buildings: %s" % got)
    areas = gdal_areas(fixture("buildings.geojson"))
    mine = {r["id"]: float(r["a"]) for r in rows}
    check(abs(mine.get("B2", 0) / areas["B2"] - 1) < 1e-6, "B2's area %s, GDAL's %s" %
          (mine.get("B2"), areas["B2"]))
    zones = ogr_csv(gp, "zones", "SELECT id, z_top FROM zones")
    check([(r["id"], float(r["z_top"])) for r in zones] == [("zone-1", 4.5)], "zones: %s" % zones)
    # what it refuses: exit 2, no file
    plain = os.path.join(tmp, "plain.db")
    p = sylva("run", os.path.join(ROOT, "scenarios", "shrub.json"), "--db", plain, "--name", "s",
              "--iterations", "2")
    for args, want in ((["--db", plain, "--name", "s", "--format", "gpkg"], "has no site"),
                       (["--db", db, "--name", "site", "--format", "gpkg", "--years", "11"],
                        "stored years 1 to 10, not 11"),
                       (["--db", db, "--name", "site", "--format", "geojson", "--iteration", "3"],
                        "take --years")):
        bad = os.path.join(tmp, "bad.gpkg")
        q = sylva("export", *args, "-o", bad)
        check(q.returncode == 2 and want in q.stderr and not os.path.exists(bad) and
              not os.path.exists(bad + ".tmp"), "export %s: %d %s" % (args, q.returncode, q.stderr))
    q = sylva("export", "--db", db, "--name", "site", "--format", "gpkg", "-o", "-")
    check(q.returncode == 2 and "stdout" in q.stderr, "gpkg to stdout: " + q.stderr)


def site_species(path):
    with open(path) as f:
        return {pl["id"]: pl["species"] for pl in json.load(f)["plants"]}


def write_trees(path, change):
    with open(fixture("trees.geojson")) as f:
        doc = json.load(f)
    change(doc["features"])
    with open(path, "w") as f:
        json.dump(doc, f)


def bad_cases(tmp):
    not_a_layer = os.path.join(tmp, "notes.geojson")
    with open(not_a_layer, "w") as f:
        f.write("these are notes, not a layer\n")
    bowtie = os.path.join(tmp, "bowtie.geojson")
    with open(bowtie, "w") as f:
        json.dump({"type": "FeatureCollection", "name": "buildings",
                   "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::32618"}},
                   "features": [{"type": "Feature", "properties": {"id": "bow", "height": 6, "levels": 2},
                                 "geometry": {"type": "Polygon", "coordinates": [[
                                     [586000, 4515000], [586010, 4515010], [586010, 4515000],
                                     [586000, 4515010], [586000, 4515000]]]}}]}, f)
    zero = os.path.join(tmp, "zero.geojson")
    write_trees(zero, lambda fs: fs[1]["properties"].update(dbh=0))
    over_csv = os.path.join(tmp, "trees.csv")
    q = run("ogr2ogr", "-f", "CSV", "-lco", "GEOMETRY=AS_XY", over_csv, fixture("trees.geojson"))
    check(q.returncode == 0, "ogr2ogr trees.csv: " + q.stderr)
    with open(over_csv) as f:
        text = f.read().replace("T7,Pyrus calleryana,15,", "T7,Pyrus calleryana,412,")
    with open(over_csv, "w") as f:
        f.write(text)
    no_keep = [a for a in TREE_OPTS if a not in ("--keep", "status=alive")]
    noprj = os.path.join(tmp, "noprj")
    os.mkdir(noprj)
    no_crs = os.path.join(noprj, "buildings.csv")
    q = run("ogr2ogr", "-f", "CSV", "-lco", "GEOMETRY=AS_WKT", no_crs, fixture("buildings.geojson"))
    check(q.returncode == 0 and not os.path.exists(os.path.join(noprj, "buildings.prj")),
          "ogr2ogr buildings.csv: " + q.stderr)
    far = "2.0,48.0,2.1,48.1"
    cases = [
        ("GDAL cannot open", dict(trees=not_a_layer), [],
         ["notes.geojson", "GDAL cannot open it"]),
        ("no such file", dict(trees=os.path.join(tmp, "absent.gpkg")), [], ["absent.gpkg"]),
        ("a missing field", dict(), ["--dbh-field", "diameter"],
         ["trees.geojson: layer trees: no field 'diameter' (fields: ", "species"]),
        ("a missing building field", dict(), ["--height-field", "storeys"],
         ["buildings.geojson: layer buildings: no field 'storeys'"]),
        ("a CRS PROJ cannot read", dict(trees=over_csv, buildings=None, zones=None),
         ["--xy-fields", "X,Y", "--layer-crs", "EPSG:999999"],
         ["trees.csv: layer trees: --layer-crs 'EPSG:999999': PROJ cannot read it"]),
        ("a nonsense WKT", dict(trees=None, zones=None),
         ["--buildings-crs", 'PROJCS["nonsense",UNIT["metre",1]]'],
         ["buildings.geojson: layer buildings: --buildings-crs", "PROJ cannot read it"]),
        ("a CRS PROJ cannot transform", dict(buildings=no_crs, trees=None, zones=None), [],
         ["buildings.csv: layer buildings: row 1 (id B1): the point (", "PROJ cannot transform",
          "names no CRS"]),
        ("a self-intersecting footprint", dict(buildings=bowtie, trees=None, zones=None), [],
         ["bowtie.geojson: layer buildings: row 1 (id bow): the footprint is not a valid polygon",
          "Self-intersection"]),
        ("a DBH of 0", dict(trees=zero), [],
         ["zero.geojson: layer trees: row 2 (id T2): field dbh: 0 cm is not above 0"]),
        ("a DBH over 300 cm", dict(trees=over_csv, buildings=None, zones=None),
         ["--xy-fields", "X,Y"], ["trees.csv: layer trees: row 7 (id T7): field dbh: 412 cm is over 300 cm"]),
        ("a bbox with nothing in it", dict(), ["--bbox", far],
         ["--bbox 2,48,2.1,48.1: no building, tree or zone lies inside it"]),
        ("a bad bbox", dict(), ["--bbox", "3,2,1"], ["--bbox: '3,2,1' is not W,S,E,N"]),
        ("an unknown region", dict(), ["--region", "Atlantis"], ["--region 'Atlantis'", "NoEast"]),
        ("a map naming no species", dict(), ["--species-map", not_a_layer], ["notes.geojson"]),
        ("a CRS in feet", dict(), ["--crs", "EPSG:2263"], ["--crs 'EPSG:2263': not a projected CRS in metres"]),
    ]
    for name, layers, extra, phrases in cases:
        out = os.path.join(tmp, "bad.json")
        opts = no_keep if name == "a DBH over 300 cm" else TREE_OPTS
        p, _ = site(out, *extra, tree_opts=opts, **layers)
        check(p.returncode == 2, "%s: exit %d, expected 2 (%s)" % (name, p.returncode, p.stderr))
        for phrase in phrases:
            check(phrase in p.stderr, "%s: stderr lacks %r: %r" % (name, phrase, p.stderr))
        check(p.stdout == "", "%s: stdout %r" % (name, p.stdout))
        check(not os.path.exists(out) and not os.path.exists(out + ".tmp"), "%s: a file was written" % name)
    usage = [
        (["--trees", fixture("trees.geojson"), "--dbh-field", "dbh"], "--species-field"),
        (["--buildings", fixture("buildings.geojson")], "--height-field"),
        (["--zones", fixture("zones.geojson")], "--zone-field"),
        (["--zones", fixture("zones.geojson"), "--zone-field", "clearance", "--species-field", "s"],
         "--trees FILE"),
        ([], "nothing to read"),
    ]
    for args, phrase in usage:
        p = sylva("site", *args, "-o", os.path.join(tmp, "u.json"))
        check(p.returncode == 2 and phrase in p.stderr, "usage %s: %s" % (args, p.stderr))
    p = sylva("site", "--help")
    check(p.returncode == 0 and "Usage: sylva site" in p.stdout, "site --help")


main()
print("site-cli: %d checks, %d failed" % (checks, len(failures)))
sys.exit(1 if failures else 0)
