"""Wood and carbon through the real binary and its SQLite store (docs/model.md, "Wood
and carbon"; Python 3 standard library only).

meson runs `python3 test_carbon.py SYLVA_EXE SCENARIOS_DIR DATA_DIR`. One run plants a
tree of every library species whose UTDB match (TS9) is a species-specific urban
volume equation (TS7), beside an IGM preset given a wood density and one without,
and grows them ITERATIONS years into a store. Checked against the tables read here:
- every stored row's `biomass` equals the TS7 equation of DBH and height times TS9's
  density, at the stem's stored DBH and height, to 0.1%; `carbon` is half of it and
  `co2` 44/12 of that; `biomass_model` is `wood_volume` times TS9's density;
- the run lines carry the same values (3 decimals) and leave out what does not
  apply: the preset with a density has `biomass_model` only, the other none;
- `co2_sequestered` is each year's co2 less the last's; the first year's is counted
  from the planted tree's co2, found here from the exported skeleton of iteration 0
  (its dbh and height), so that the planted co2 and the years' sequestration sum to
  the final co2;
- `wood_volume` equals the frustums of the exported skeleton's internodes.
"""
import csv
import json
import math
import os
import re
import sqlite3
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "store"))
from store_common import Checks, Env, crash_text  # noqa: E402

ITERATIONS = 8
SPACING = 9.0
NUM = r"([-+]?\d*\.?\d+(?:[eE][-+]?\d+)?)"
DH = re.compile(r"^=" + NUM + r"\*dbhcm\^" + NUM + r"\*(?:htm|htmet)\^" + NUM + r"$")


def read_csv(path):
    with open(path, newline="", encoding="utf-8-sig") as f:
        return list(csv.DictReader(f))


def urban_equations(data):
    """{TS7 species: (a, b, c)} of the equations of DBH and height."""
    out = {}
    for r in read_csv(os.path.join(data, "utdb", "TS7_Volume_eqns_from_urban.csv")):
        m = DH.match(r["Equation"].replace(" ", ""))
        if m and r["Predicts"] == "Volume":
            out[r["Equation Species"]] = tuple(map(float, m.groups()))
    return out


def library_codes(data):
    with open(os.path.join(data, "species", "library.json"), encoding="utf-8") as f:
        return [(s["name"], s["code"]) for s in json.load(f)["species"]]


def frustums(stem):
    """The wood of a skeleton stem: each internode's tapered cylinder."""
    nodes = {n[0]: n for n in stem["nodes"]}
    v = 0.0
    for n in stem["nodes"]:
        p = nodes.get(n[1])
        if p is None:
            continue
        length = math.dist(p[2:5], n[2:5])
        v += math.pi / 3 * length * (p[5] ** 2 + p[5] * n[5] + n[5] ** 2)
    return v


def dbh_height(stem):
    """(dbh m, height m) of a skeleton stem: the thickest internode crossing 1.3 m."""
    nodes = {n[0]: n for n in stem["nodes"]}
    rz = stem["root"][2]
    dbh = None
    for n in stem["nodes"]:
        p = nodes.get(n[1])
        if p is not None and p[4] - rz < 1.3 <= n[4] - rz:
            dbh = max(dbh or 0.0, 2 * n[5])
    return dbh, max(n[4] for n in stem["nodes"]) - rz


def close(a, b, rel):
    return a is not None and b is not None and abs(a - b) <= rel * max(abs(b), 1e-9)


def main():
    env = Env(sys.argv)
    data = os.path.abspath(sys.argv[3])
    c = Checks()
    ts9 = {r["SpCode"]: r for r in read_csv(os.path.join(data, "utdb", "TS9_Biomass_density_factors.csv"))}
    eqs = urban_equations(data)
    aliases = {"Platanus x acerifolia": "Platanus hybrida"}  # TS9's and TS7's names of one species
    chosen = []
    for name, code in library_codes(data):
        match = aliases.get(ts9[code]["Matched Equation Species"], ts9[code]["Matched Equation Species"])
        if match in eqs and not match.startswith("Urb Gen") and code not in [k for _, k, _ in chosen]:
            chosen.append((name, code, match))
    c.check(len(chosen) >= 12, "library species with a species-specific urban equation", chosen)
    species = {code: {"preset": name} for name, code, _ in chosen}
    species["igm-dense"] = {"preset": "igm-fig13", "wood_density": 450}
    species["igm-plain"] = {"preset": "igm-fig13"}
    plants = [{"id": code, "species": code, "roots": [[i * SPACING, 0, 0]]}
              for i, (_, code, _) in enumerate(chosen)]
    n = len(chosen)
    plants.append({"id": "igm-dense", "species": "igm-dense", "roots": [[n * SPACING, 0, 0]]})
    plants.append({"id": "igm-plain", "species": "igm-plain", "roots": [[(n + 1) * SPACING, 0, 0]]})
    scenario = {"format": "sylva.scenario/1", "name": "carbon", "seed": 5, "iterations": ITERATIONS,
                "start_year": 2030,
                "world": {"min": [-5, -5, 0], "max": [(n + 2) * SPACING, 5, 16], "voxel": 0.125},
                "species": species, "plants": plants}
    path = env.path("carbon.json")
    with open(path, "w", encoding="utf-8") as f:
        json.dump(scenario, f)
    db = env.path("carbon.db")
    rc, out, err = env.sylva("run", path, "--db", db, "--name", "c", "--quiet-progress")
    if not c.check(rc == 0, "sylva run", crash_text(rc, err) or err):
        c.finish()
    lines = [json.loads(l) for l in out.splitlines() if l.startswith('{"iteration"')]
    c.check(len(lines) == ITERATIONS, "a line per iteration", len(lines))

    con = sqlite3.connect(db)
    rows = con.execute("SELECT iteration, plant, height, dbh, wood_volume, biomass, biomass_model,"
                       " carbon, co2, co2_sequestered FROM stats ORDER BY iteration, stem").fetchall()
    con.close()
    by_plant = {}
    for r in rows:
        by_plant.setdefault(r[1], []).append(r)
    density = {code: float(ts9[code]["DW Density"]) for _, code, _ in chosen}
    checked = 0
    for _, code, match in chosen:
        a, b, cc = eqs[match]
        for (it, _, height, dbh, wood, biomass, model, carbon, co2, seq) in by_plant.get(code, []):
            if dbh is None:
                c.check(biomass is None and co2 is None, "%s %d: no dbh, no biomass" % (code, it))
                continue
            want = a * (100 * dbh) ** b * height ** cc * density[code]
            c.check(close(biomass, want, 1e-3), "%s %d: biomass = TS7 x TS9 density" % (code, it),
                    "%r vs %r (dbh %r, height %r)" % (biomass, want, dbh, height))
            c.check(close(carbon, 0.5 * biomass, 1e-12), "%s %d: carbon = biomass / 2" % (code, it))
            c.check(close(co2, carbon * 44 / 12, 1e-12), "%s %d: co2 = carbon 44/12" % (code, it))
            c.check(close(model, wood * density[code], 1e-12), "%s %d: biomass_model" % (code, it))
            checked += 1
    c.check(checked >= ITERATIONS * 10, "rows checked", checked)

    # the lines: the same values, and nothing where it does not apply
    last = lines[-1]["stems"] if lines else []
    final = {s["plant"]: s for s in last}
    for _, code, _ in chosen:
        s = final.get(code, {})
        r = by_plant[code][-1]
        for key, col in (("biomass", 5), ("biomass_model", 6), ("carbon", 7), ("co2", 8),
                         ("co2_sequestered", 9)):
            c.check(key in s and abs(s[key] - r[col]) <= 0.0005 + 1e-12, "%s: line %s" % (code, key),
                    (s.get(key), r[col]))
    dense, plain = final.get("igm-dense", {}), final.get("igm-plain", {})
    c.check("biomass_model" in dense and dense["biomass_model"] > 0, "a density gives biomass_model", dense)
    for key in ("biomass", "carbon", "co2", "co2_sequestered"):
        c.check(key not in dense and key not in plain, "no %s without an allometry" % key)
    c.check("biomass_model" not in plain and plain.get("wood_volume", 0) > 0,
            "no biomass_model without a density; wood_volume always", plain)

    # co2_sequestered: year on year, from the planted tree's co2
    sk0, sk_last = env.path("sk0.json"), env.path("sklast.json")
    rc0 = env.sylva("export", "--db", db, "--name", "c", "--iteration", 0, "--format", "skeleton", "-o", sk0)[0]
    rc1 = env.sylva("export", "--db", db, "--name", "c", "--format", "skeleton", "-o", sk_last)[0]
    c.check(rc0 == 0 and rc1 == 0, "skeletons exported")
    with open(sk0, encoding="utf-8") as f:
        start = {p["id"]: p["stems"][0] for p in json.load(f)["plants"]}
    with open(sk_last, encoding="utf-8") as f:
        end = {p["id"]: p["stems"][0] for p in json.load(f)["plants"]}
    for _, code, match in chosen:
        a, b, cc = eqs[match]
        rs = by_plant[code]
        for prev, cur in zip(rs, rs[1:]):
            if prev[8] is not None and cur[8] is not None:
                c.check(abs(cur[9] - (cur[8] - prev[8])) <= 1e-9 * max(1.0, cur[8]),
                        "%s %d: co2_sequestered = co2 - last co2" % (code, cur[0]))
        dbh0, h0 = dbh_height(start[code])
        planted = 0.0 if dbh0 is None else a * (100 * dbh0) ** b * h0 ** cc * density[code] * 0.5 * 44 / 12
        total = planted + sum(r[9] or 0.0 for r in rs)
        c.check(close(total, rs[-1][8], 3e-3), "%s: planted co2 + sequestered = final co2" % code,
                (planted, total, rs[-1][8]))
        c.check(close(rs[-1][4], frustums(end[code]), 2e-3), "%s: wood_volume = the skeleton's frustums" % code,
                (rs[-1][4], frustums(end[code])))
    env.cleanup()
    c.finish()


if __name__ == "__main__":
    main()
