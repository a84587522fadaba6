#!/usr/bin/env python3
"""Shade tolerance (issue 20, item 5; docs/model.md, "Species in years"): a library
tree 2 m north of a 12 m east-west facade at 48 N under the site's sky, against the
same tree in the open under the same sky, at 25 years, median of seeds 1-3. The
shaded tree grows no taller than the open one, keeps a crown of at least 30% of its
height and between 20% and 100% of the open tree's live internodes, and is no bare
pole (its crown at least a quarter as wide as it is tall).

  shade.py SYLVA [SPECIES ...]
"""
import json
import os
import statistics
import subprocess
import sys
import tempfile

YEARS = 25


def scenario(species, facade, seed):
    s = {"format": "sylva.scenario/1", "name": "shade test", "seed": seed, "iterations": YEARS,
         "world": {"min": [-12, -10, 0], "max": [12, 14, 25]},
         "species": {"s": {"preset": species}},
         "plants": [{"id": "t", "species": "s", "roots": [[0, 2.5, 0]]}],
         "light": {"sky": "site", "latitude": 48, "north": [0, 1], "season": [91, 273],
                   "diffuse": 0.4, "samples": 64}}
    if facade:  # its north face at y = 0.5: the tree stands 2 m north of it
        s["obstacles"] = [{"id": "facade", "kind": "box", "min": [-12, -0.5, 0], "max": [12, 0.5, 12]}]
    return s


def last_stem(sylva, scen):
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as f:
        json.dump(scen, f)
        path = f.name
    try:
        out = subprocess.run([sylva, "run", path, "--quiet-progress"], capture_output=True,
                             text=True, check=True).stdout
    finally:
        os.unlink(path)
    lines = [json.loads(x) for x in out.splitlines() if '"stems"' in x]
    return lines[-1]["stems"][0]


def measures(sylva, species, facade):
    rows = [last_stem(sylva, scenario(species, facade, seed)) for seed in (1, 2, 3)]
    med = lambda f: statistics.median(f(r) for r in rows)
    height = med(lambda r: r["height"])
    base = med(lambda r: r["crown_base"] if r["crown_base"] is not None else r["height"])
    return {"height": height, "crown_height": height - base, "nodes": med(lambda r: r["nodes"]),
            "crown_width": med(lambda r: r["crown_width"])}


def main():
    sylva = sys.argv[1]
    species = sys.argv[2:] or ["utdb:NoEast:TICO", "utdb:NoEast:PLAC"]
    failed = 0
    for sp in species:
        o, s = measures(sylva, sp, False), measures(sylva, sp, True)
        share = s["nodes"] / o["nodes"]
        print("%s at %d years: open H %.2f m, crown %.2f m high, %.2f m wide, %d nodes; "
              "north of the facade H %.2f m, crown %.2f m high (%.0f%%), %.2f m wide, %d nodes (%.0f%%)"
              % (sp, YEARS, o["height"], o["crown_height"], o["crown_width"], o["nodes"],
                 s["height"], s["crown_height"], 100 * s["crown_height"] / s["height"],
                 s["crown_width"], s["nodes"], 100 * share))
        checks = [("no taller than in the open", s["height"] <= o["height"]),
                  ("crown at least 30% of the height", s["crown_height"] >= 0.3 * s["height"]),
                  ("20% to 100% of the open tree's internodes", 0.2 <= share <= 1.0),
                  ("no bare pole (crown at least a quarter as wide as tall)",
                   s["crown_width"] >= 0.25 * s["height"])]
        for what, ok in checks:
            print("  %s %s" % ("ok  " if ok else "FAIL", what))
            failed += not ok
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
