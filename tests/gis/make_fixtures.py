#!/usr/bin/env python3
"""Writes the fixtures of the gis suite (tests/gis/data/), run by hand when they
change; the files are committed:

    python3 tests/gis/make_fixtures.py   (needs cs2cs from proj-bin)

A small site in Manhattan, in WGS 84 / UTM zone 18N (EPSG:32618), metres, two
decimals: the NoEast region is the nearest (Queens, 12 km).
- buildings.geojson: B1 a 20 x 12 m rectangle turned 30 degrees, height 15.5 m
  (its ring given clockwise); B2 an L of 30 m arms 12 m wide turned 30 degrees with
  a 6 x 6 m courtyard (a hole), 4 levels and no height; B3 a multipolygon of two
  10 x 8 m blocks, height 9 m and 3 levels (the height wins); B4 8 x 8 m with
  neither (no height: left out).
- zones.geojson: a road's clearance, 130 x 7 m, 4.5 m high.
- trees.geojson: 14 trees in lon/lat (EPSG:4326, 7 decimals): five that match the
  library (a hybrid, a cultivar, a variety, a common name and a code), two dead, two
  of species outside the library, two misspelt, one without a DBH, one 3.6 cm from
  the first (the same voxel column: too close) and one inside B1. dbh in cm,
  dbh_in the same in inches (one decimal).
"""
import json
import math
import os
import subprocess

HERE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data")
E0, N0 = 586000.0, 4515000.0
COS, SIN = math.cos(math.radians(30)), math.sin(math.radians(30))


def turned(anchor, pts):
    ax, ay = anchor
    return [[round(ax + x * COS - y * SIN, 2), round(ay + x * SIN + y * COS, 2)] for x, y in pts]


def ring(anchor, pts, clockwise=False):
    r = turned(anchor, pts)
    if clockwise:
        r = r[::-1]
    return r + [r[0]]


def building(id_, geometry, height, levels):
    return {"type": "Feature", "properties": {"id": id_, "height": height, "levels": levels},
            "geometry": geometry}


def lonlat(points):
    """UTM 18N metres -> (lon, lat), 7 decimals, by cs2cs."""
    text = "".join("%.4f %.4f\n" % tuple(p) for p in points)
    out = subprocess.run(["cs2cs", "-f", "%.7f", "EPSG:32618", "EPSG:4326"], input=text,
                         capture_output=True, text=True, check=True).stdout
    result = []
    for line in out.splitlines():
        lat, lon = line.split()[:2]
        result.append((float(lon), float(lat)))
    return result


def collection(name, crs, features):
    return {"type": "FeatureCollection", "name": name,
            "crs": {"type": "name", "properties": {"name": crs}}, "features": features}


def write(name, doc):
    with open(os.path.join(HERE, name), "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")


def main():
    os.makedirs(HERE, exist_ok=True)
    rect = lambda w, h, x=0, y=0: [(x, y), (x + w, y), (x + w, y + h), (x, y + h)]
    b1 = (E0, N0)
    b2 = (E0 + 40, N0 + 10)
    b3 = (E0 - 10, N0 + 50)
    b4 = (E0 + 70, N0 + 50)
    ell = [(0, 0), (30, 0), (30, 12), (12, 12), (12, 30), (0, 30)]
    buildings = [
        building("B1", {"type": "Polygon", "coordinates": [ring(b1, rect(20, 12), clockwise=True)]},
                 15.5, None),
        building("B2", {"type": "Polygon", "coordinates": [
            ring(b2, ell), ring(b2, rect(6, 6, 3, 3), clockwise=True)]}, None, 4),
        building("B3", {"type": "MultiPolygon", "coordinates": [
            [ring(b3, rect(10, 8))], [ring(b3, rect(10, 8, 14, 0))]]}, 9.0, 3),
        building("B4", {"type": "Polygon", "coordinates": [ring(b4, rect(8, 8))]}, None, None),
    ]
    write("buildings.geojson", collection("buildings", "urn:ogc:def:crs:EPSG::32618", buildings))

    road = [[[E0 - 30, N0 - 15], [E0 + 100, N0 - 15], [E0 + 100, N0 - 8], [E0 - 30, N0 - 8],
             [E0 - 30, N0 - 15]]]
    write("zones.geojson", collection("zones", "urn:ogc:def:crs:EPSG::32618", [
        {"type": "Feature", "properties": {"name": "road", "clearance": 4.5},
         "geometry": {"type": "Polygon", "coordinates": road}}]))

    # column centres of a 0.125 m voxel grid on whole metres: x.0625
    spots = [(E0 - 25 + 6 * i + 0.0625, N0 - 4.9375) for i in range(12)]
    spots.append((spots[0][0] + 0.03, spots[0][1] + 0.02))  # too close to T1
    spots.append(turned(b1, [(10, 6)])[0])  # inside B1
    rows = [
        ("T1", "Platanus x acerifolia", 30.5, "Alive"),
        ("T2", "Acer platanoides 'Crimson King'", 25, "Alive"),
        ("T3", "Gleditsia triacanthos var. inermis", 40.2, "Alive"),
        ("T4", "littleleaf linden", 18, "Alive"),
        ("T5", "GIBI", 22.7, "ALIVE"),
        ("T6", "Quercus rubra", 55, "Dead"),
        ("T7", "Pyrus calleryana", 15, "Dead"),
        ("T8", "Magnolia grandiflora", 20, "Alive"),
        ("T9", "Betula papyrifera", 12, "Alive"),
        ("T10", "Zelkova serata", 28, "Alive"),
        ("T11", "Quercus palustis", 33, "Alive"),
        ("T12", "Acer rubrum", None, "Alive"),
        ("T13", "Ulmus americana", 35, "Alive"),
        ("T14", "Tilia cordata", 26, "Alive"),
    ]
    trees = []
    for (id_, name, dbh, status), (lon, lat) in zip(rows, lonlat(spots)):
        trees.append({"type": "Feature",
                      "properties": {"id": id_, "species": name, "dbh": dbh,
                                     "dbh_in": None if dbh is None else round(dbh / 2.54, 1),
                                     "status": status},
                      "geometry": {"type": "Point", "coordinates": [lon, lat]}})
    write("trees.geojson", collection("trees", "urn:ogc:def:crs:OGC:1.3:CRS84", trees))


if __name__ == "__main__":
    main()
