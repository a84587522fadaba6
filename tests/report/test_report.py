"""`sylva report` through the real binary (Python 3 standard library only).

meson runs `python3 test_report.py SYLVA_EXE SCENARIOS_DIR PART`, PART:
  ready   the ready plan scenarios/street-species.json swept (6 iterations): the CSV
          and the HTML summary equal the stored stats;
  sweep   a small sweep (two species, two seeds, two variants of the pruned street,
          12 iterations): every CSV value equals the stats table read here with
          sqlite3 (pruned summed here), the rows are exactly the stored ones at the
          reached years; the HTML summary's numbers equal medians and ranges
          recomputed here from the table, its pictures are inlined PNGs, one per
          species and reached year; the PDF has the pages and the summary's text;
  plain   a store without sweeps (a pruned street and a shrub of ten stems): no axis
          columns, a `stem` column, species by scenario key, the same checks, one
          summary group per species;
  benefits  a sweep with a "shade" day (two species, with and without a latitude, 4
          iterations): co2, co2_sequestered and canopy_cover equal the stats and
          iterations tables, the shade columns `sylva shade`'s tree_shade_hours, empty
          with one warning where the light has no latitude; the HTML's tree shade;
  stand   a store without sweeps of two stands with background mortality and a run
          without stands (12 iterations): the stand columns equal the iterations
          table (died summed here), empty for the run without; the HTML's stand
          table the medians and ranges over the runs recomputed here; the PDF's
          stand page; a report of runs without stands has neither;
  errors  bad input (no --db, no such store, no such sweep, several sweeps, bad
          --years, bad -o): exit 2, a message naming it, no file written and an
          existing one untouched; years no run reached: a warning, header only.
"""
import base64
import html.parser
import json
import os
import re
import sqlite3
import statistics
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "store"))
from store_common import Checks, Env, crash_text, stand_scenario  # noqa: E402

ITERATIONS = 12
YEARS = [5, 10, 12, 20]  # 20 is never reached
# the summary's measures: (CSV column, stored key, per run)
MEASURES = [("height", "height", False), ("dbh", "dbh", False),
            ("crown_diameter", "crown_width", False), ("crown_height", "crown_height", False),
            ("co2", "co2", False), ("canopy_cover", "canopy_cover", True)]
# the CSV's: the summary has no leaf area and no sequestration
CSV_MEASURES = [(col, key) for col, key, _ in MEASURES] + [
    ("leaf_area", "leaf_area"), ("co2_sequestered", "co2_sequestered")]
SUMMARY_HEAD = ["axis", "value", "species", "years", "stems", "height (m)", "dbh (m)",
                "crown diameter (m)", "crown height (m)", "CO2 (kg)", "canopy cover"]
# the stand's figures of a run with stands: (CSV column, stored column, stand table head),
# one value per run; died is the iterations' stand_died summed to the year
STAND = [("stems_per_ha", "stems_per_ha", "stems/ha"),
         ("basal_area", "basal_area", "basal area (m²/ha)"), ("qmd", "qmd", "QMD (cm)"),
         ("dominant_height", "dominant_height", "dominant height (m)"), ("sdi", "sdi", "SDI"),
         ("cv_dbh", "cv_dbh", "CV dbh"), ("died", None, "died")]
STAND_MEASURES = [(col, col, True) for col, _, _ in STAND]


# ---- what the store holds, read here ----------------------------------------------

def store_runs(db, sweep):
    """[(id, name, start_year or 0, {axis: value})] in the report's order."""
    con = sqlite3.connect(db)
    try:
        if sweep:
            runs = con.execute("SELECT r.id, r.name, r.start_year FROM sweep_runs w JOIN runs r"
                               " ON r.id = w.run WHERE w.sweep = ? ORDER BY w.position",
                               (sweep,)).fetchall()
        else:
            runs = con.execute("SELECT id, name, start_year FROM runs ORDER BY id").fetchall()
        out = []
        for rid, name, start in runs:
            axes = dict(con.execute("SELECT axis, value FROM run_axes WHERE run = ?"
                                    " ORDER BY rowid", (rid,)).fetchall())
            out.append((rid, name, start or 0, axes))
        return out
    finally:
        con.close()


def expected_rows(db, sweep, years):
    """The report's rows as the stats table gives them: dicts of the stored values."""
    con = sqlite3.connect(db)
    rows = []
    try:
        for rid, name, start, axes in store_runs(db, sweep):
            scen = json.loads(con.execute("SELECT scenario FROM runs WHERE id = ?",
                                          (rid,)).fetchone()[0])
            keys = {p["id"]: p["species"] for p in scen["plants"]}
            for y in years:
                cover = con.execute("SELECT canopy_cover FROM iterations WHERE run = ? AND"
                                    " iteration = ?", (rid, y)).fetchone()
                stand = con.execute("SELECT %s FROM iterations WHERE run = ? AND iteration = ?"
                                    % ", ".join(k for _, k, _ in STAND if k),
                                    (rid, y)).fetchone() or [None] * (len(STAND) - 1)
                died, known, its = con.execute(
                    "SELECT total(stand_died), count(stand_died), count(*) FROM iterations"
                    " WHERE run = ? AND iteration BETWEEN 1 AND ?", (rid, y)).fetchone()
                stand = dict(zip([col for col, _, _ in STAND],
                                 list(stand) + [died if known == its else None]))
                for (stem, plant, plant_stem, age, height, dbh, cw, ch, la, co2, seq, zones,
                     clearance, pruned) in con.execute(
                        "SELECT stem, plant, plant_stem, age, height, dbh, crown_width,"
                        " crown_height, leaf_area, co2, co2_sequestered, zones, clearance,"
                        " pruned FROM stats"
                        " WHERE run = ? AND iteration = ? ORDER BY stem", (rid, y)):
                    total = con.execute("SELECT SUM(pruned) FROM stats WHERE run = ? AND"
                                        " stem = ? AND iteration <= ?",
                                        (rid, stem, y)).fetchone()[0]
                    key = keys[plant]
                    species = axes.get("species/" + key, key)
                    rows.append({"run": name, "axes": axes, "plant": plant, "stem": plant_stem,
                                 "species": species, "key": key, "age": age,
                                 "year": start + y, "iteration": y, "height": height,
                                 "dbh": dbh, "crown_width": cw, "crown_height": ch,
                                 "leaf_area": la, "co2": co2, "co2_sequestered": seq,
                                 "canopy_cover": cover[0] if cover else None,
                                 "rid": rid, **stand,
                                 "zones": json.loads(zones) if zones else None,
                                 "clearance": json.loads(clearance) if clearance else None,
                                 "pruned": total if pruned is not None else None})
    finally:
        con.close()
    return rows


# ---- the CSV ------------------------------------------------------------------------

def read_csv(path):
    import csv
    with open(path, newline="", encoding="utf-8") as f:
        data = list(csv.reader(f))
    return data[0], data[1:]


def number(field):
    return None if field == "" else float(field)


def check_csv(c, path, expect, axes, multi_stem, shade=False):
    header, rows = read_csv(path)
    c.check(any(h.startswith("shade_") for h in header) == shade,
            "shade_ columns only when the plan names a shade day", header)
    zones = [h[len("first_"):] for h in header if h.startswith("first_")]
    obstacles = [h[len("clearance_"):] for h in header if h.startswith("clearance_")]
    want_head = (["run"] + axes + ["plant"] + (["stem"] if multi_stem else [])
                 + ["species", "age", "year", "height", "dbh", "crown_diameter",
                    "crown_height", "leaf_area"])
    c.check(header[:len(want_head)] == want_head, "CSV header starts " + ",".join(want_head),
            header)
    c.check(len(rows) == len(expect), "CSV has one row per stored stem and reached year",
            "%d rows, %d expected" % (len(rows), len(expect)))
    bad = []
    for i, (row, e) in enumerate(zip(rows, expect)):
        f = dict(zip(header, row))
        got = [f["run"]] + [f[a] for a in axes] + [f["plant"], f["species"]]
        want = [e["run"]] + [e["axes"][a] for a in axes] + [e["plant"], e["species"]]
        if multi_stem and int(f["stem"]) != e["stem"]:
            bad.append((i, "stem", f["stem"], e["stem"]))
        if got != want:
            bad.append((i, "names", got, want))
        if number(f["age"]) != e["age"]:
            bad.append((i, "age", f["age"], e["age"]))
        if int(f["year"]) != e["year"]:
            bad.append((i, "year", f["year"], e["year"]))
        for col, key in CSV_MEASURES:
            if number(f[col]) != e[key]:
                bad.append((i, col, f[col], e[key]))
        for z in zones:
            want = (e["zones"] or {}).get(z, {}).get("first")
            if number(f["first_" + z]) != want:
                bad.append((i, "first_" + z, f["first_" + z], want))
        for o in obstacles:
            want = (e["clearance"] or {}).get(o)
            if number(f["clearance_" + o]) != want:
                bad.append((i, "clearance_" + o, f["clearance_" + o], want))
        if "pruned" in f and number(f["pruned"]) != e["pruned"]:
            bad.append((i, "pruned", f["pruned"], e["pruned"]))
    # the stand's columns: in a report of a run with stands, before the zones' columns
    stand = any(e["stems_per_ha"] is not None for e in expect)
    cols = [col for col, _, _ in STAND]
    at = header.index("first_" + zones[0]) if zones else (
        header.index("pruned") if "pruned" in header else len(header))
    c.check(header[at - len(cols):at] == cols if stand else not set(cols) & set(header),
            "the stand's columns only in a report of runs with stands, before the zones'",
            header)
    for i, (row, e) in enumerate(zip(rows, expect)):
        f = dict(zip(header, row))
        for col in cols if stand else []:
            if number(f[col]) != e[col]:
                bad.append((i, col, f[col], e[col]))
    c.check(not bad, "every CSV value equals the stored stats", bad[:10])
    for key in ("leaf_area", "canopy_cover"):
        c.check(all(e[key] is not None for e in expect) and any(e[key] for e in expect),
                "the %s column holds stored values (some above 0)" % key)
    c.check(any(e["co2"] for e in expect) and any(e["co2_sequestered"] for e in expect),
            "the co2 columns hold stored values (some above 0)")
    return header, rows, zones


# ---- the summary, recomputed ------------------------------------------------------------

def expected_groups(rows, axes, zones, years, measures=MEASURES):
    """[(axis, value, species, year, n, {measure: stat}, {zone: stat})], in the report's
    order: axes but seed, values as they first appear, species as they first appear."""
    group_axes = [a for a in axes if a != "seed"] or [None]
    species = []
    for r in rows:
        if r["species"] not in species:
            species.append(r["species"])
    out = []
    for a in group_axes:
        values = []
        for r in rows:
            v = r["axes"][a] if a else "all runs"
            if v not in values:
                values.append(v)
        for v in values:
            for s in species:
                for y in years:
                    g = [r for r in rows if r["iteration"] == y and r["species"] == s
                         and (a is None or r["axes"][a] == v)
                         and (a is None or not a.startswith("species/")
                              or r["key"] == a[len("species/"):])]
                    if not g:
                        continue
                    meas = {}
                    runs = []
                    for r in g:
                        if r["rid"] not in [x["rid"] for x in runs]:
                            runs.append(r)
                    for _, key, per_run in measures:
                        # a run's value counts once, not once per stem
                        vals = [r[key] for r in (runs if per_run else g) if r[key] is not None]
                        meas[key] = stat(vals) + (len(runs) if per_run else len(g),)
                    firsts = {}
                    for z in zones:
                        vals = [r["zones"][z]["first"] for r in g
                                if r["zones"] and z in r["zones"]]
                        firsts[z] = stat(vals)
                    out.append((a or "all runs", v, s, y, len(g), meas, firsts))
    return out


def stat(vals):
    if not vals:
        return (0, None, None, None)
    return (len(vals), statistics.median(vals), min(vals), max(vals))


class Tables(html.parser.HTMLParser):
    """Every <table>'s class and rows of cell texts."""

    def __init__(self):
        super().__init__()
        self.tables, self.cell, self.row = [], None, None
        self.imgs, self.open = [], []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "table":
            self.tables.append((a.get("class"), []))
            self.open.append(self.tables[-1])
        elif tag == "tr":
            self.row = []
        elif tag in ("td", "th"):
            self.cell = ""
        elif tag == "img":
            self.imgs.append((self.open[-1][0] if self.open else None, a))

    def handle_endtag(self, tag):
        if tag == "table" and self.open:
            self.open.pop()
        elif tag in ("td", "th") and self.row is not None:
            self.row.append(self.cell.strip())
            self.cell = None
        elif tag == "tr" and self.open:
            self.open[-1][1].append(self.row)
            self.row = None

    def handle_data(self, data):
        if self.cell is not None:
            self.cell += data


STAT = re.compile(r"^(-?\d+\.\d{3}) \((-?\d+\.\d{3})–(-?\d+\.\d{3})\)(?:, (\d+) of (\d+))?$")
FIRST = re.compile(r"^(\S+) \((\S+)–(\S+)\), (\d+) of (\d+)$")
NEVER = re.compile(r"^never, 0 of (\d+)$")


def close3(shown, value):
    """A number shown with three decimals against the value it rounds."""
    return abs(float(shown) - value) <= 0.0005 + 1e-9


def stat_cell_ok(cell, cnt, med, lo, hi, n):
    """A summary cell against cnt of n values with that median, minimum and maximum:
    "–" for none, "median (min–max)" and ", cnt of n" where some lack it."""
    if cnt == 0:
        return cell == "–"
    m = STAT.match(cell)
    return bool(m and close3(m.group(1), med) and close3(m.group(2), lo)
                and close3(m.group(3), hi) and (cnt < n) == (m.group(4) is not None)
                and (not m.group(4) or (int(m.group(4)), int(m.group(5))) == (cnt, n)))


def check_summary(c, page, groups, zones, measures=MEASURES, head_fixed=SUMMARY_HEAD):
    p = Tables()
    p.feed(page)
    summary = [rows for cls, rows in p.tables if cls == "summary"]
    if not c.check(len(summary) == 1, "the HTML has one summary table"):
        return p
    head, body = summary[0][0], summary[0][1:]
    fixed = len(head_fixed)
    c.check(head[:fixed] == head_fixed
            and head[fixed:] == ["first conflict: " + z for z in zones],
            "summary header", head)
    c.check(len(body) == len(groups), "one summary line per axis value, species and year",
            "%d lines, %d expected" % (len(body), len(groups)))
    bad = []
    for i, (cells, g) in enumerate(zip(body, groups)):
        axis, value, species, year, n, meas, firsts = g
        if cells[:3] != [axis, value, species] or int(cells[3].split()[0]) != year \
                or int(cells[4]) != n:
            bad.append((i, "keys", cells[:5], g[:5]))
            continue
        for k, (_, key, _) in enumerate(measures):
            cnt, med, lo, hi, n = meas[key]
            if not stat_cell_ok(cells[5 + k], cnt, med, lo, hi, n):
                bad.append((i, key, cells[5 + k], (med, lo, hi, cnt, n)))
        n = g[4]
        for k, z in enumerate(zones):
            cnt, med, lo, hi = firsts[z]
            cell = cells[fixed + k]
            if cnt == 0:
                m = NEVER.match(cell)
                if not m or int(m.group(1)) != n:
                    bad.append((i, z, cell, "never"))
                continue
            m = FIRST.match(cell)
            if not m or [float(m.group(j)) for j in (1, 2, 3)] != [med, lo, hi] \
                    or (int(m.group(4)), int(m.group(5))) != (cnt, n):
                bad.append((i, z, cell, (med, lo, hi, cnt, n)))
    c.check(not bad, "every summary number equals the median, minimum and maximum "
            "recomputed from the stats table", bad[:10])
    return p


def check_stand_table(c, p, groups):
    """The HTML's stand table: a line per summary line, the runs, and each figure's
    median (minimum–maximum) over them; groups from expected_groups(STAND_MEASURES)."""
    stand = [rows for cls, rows in p.tables if cls == "stand"]
    if not c.check(len(stand) == 1, "the HTML has one stand table"):
        return
    head, body = stand[0][0], stand[0][1:]
    c.check(head == ["axis", "value", "species", "years", "runs"] + [h for _, _, h in STAND],
            "stand table header", head)
    c.check(len(body) == len(groups), "one stand line per summary line",
            "%d lines, %d expected" % (len(body), len(groups)))
    bad = []
    for i, (cells, g) in enumerate(zip(body, groups)):
        axis, value, species, year, _, meas, _ = g
        runs = meas[STAND[0][0]][4]
        if cells[:3] != [axis, value, species] or int(cells[3].split()[0]) != year \
                or int(cells[4]) != runs:
            bad.append((i, "keys", cells[:5], g[:4], runs))
            continue
        for k, (col, _, _) in enumerate(STAND):
            cnt, med, lo, hi, n = meas[col]
            if not stat_cell_ok(cells[5 + k], cnt, med, lo, hi, n):
                bad.append((i, col, cells[5 + k], (med, lo, hi, cnt, n)))
    c.check(not bad, "every stand number equals the median, minimum and maximum over the "
            "runs recomputed from the iterations table", bad[:10])


def check_images(c, p, pictures):
    pics = [a for cls, a in p.imgs if cls == "pictures"]
    c.check(len(pics) == pictures, "one picture per species and reached year",
            "%d pictures, %d expected" % (len(pics), pictures))
    c.check(len(p.imgs) == pictures + 3, "pictures, two plots and the conflict chart",
            len(p.imgs))
    bad = []
    for _, a in p.imgs:
        src = a.get("src", "")
        if not src.startswith("data:image/png;base64,"):
            bad.append(src[:60])
            continue
        data = base64.b64decode(src.split(",", 1)[1], validate=True)
        if data[:8] != b"\x89PNG\r\n\x1a\n" or data[-8:-4] != b"IEND":
            bad.append("not a whole PNG")
    c.check(not bad, "every picture is a whole PNG inlined as a data: URI", bad[:5])


def check_pdf(c, env, path, groups, min_pages):
    try:
        info = subprocess.run(["pdfinfo", path], capture_output=True, text=True,
                              timeout=120).stdout
        text = subprocess.run(["pdftotext", "-layout", path, "-"], capture_output=True,
                              text=True, timeout=120).stdout
    except OSError:
        print("pdfinfo/pdftotext missing: PDF contents not checked")
        return
    m = re.search(r"Pages:\s+(\d+)", info)
    c.check(m and int(m.group(1)) >= min_pages, "the PDF has at least %d pages" % min_pages,
            info)
    flat = re.sub(r"\s+", " ", text)
    missing = []
    for g in groups:
        med, lo, hi = g[5]["height"][1:4]
        cell = "%.3f (%.3f–%.3f)" % (med, lo, hi)
        if cell not in flat:
            missing.append(cell)
    c.check(not missing, "the PDF's summary shows every height cell", missing[:5])


def report(env, c, *args):
    rc, out, err = env.sylva("report", *args)
    c.check(crash_text(rc, err) is None, "no crash: report " + " ".join(map(str, args)), err)
    return rc, err


# ---- parts ------------------------------------------------------------------------

def make_sweep(env, name, species, seeds, variants, iterations, db):
    plan = {"format": "sylva.sweep/1", "name": name,
            "scenario": env.scenario("street-pruned.json"),
            "axes": {"species": {"street-tree": species}, "seed": seeds,
                     "variants": variants}}
    path = env.path(name.replace(" ", "-") + ".json")
    with open(path, "w") as f:
        json.dump(plan, f)
    rc, _, err = env.sylva("sweep", path, "--db", db, "--iterations", iterations,
                           "--jobs", "2")
    if rc != 0:
        raise RuntimeError("sweep failed (%s): %s" % (rc, err))


def run_into(env, db, runs):
    """`sylva run SCENARIO [ARGS] --iterations N --db DB` of each (args, N) of runs."""
    for args, n in runs:
        rc, _, err = env.sylva("run", *args, "--iterations", n, "--db", db, "--quiet-progress")
        if rc != 0:
            raise RuntimeError("run failed (%s): %s" % (rc, err))


def part_sweep(env, c):
    db = env.path("sweep.db")
    make_sweep(env, "street species", ["utdb:NoEast:PLAC", "utdb:NoEast:GIBI"], [1, 2],
               {"as built": [], "no awning": [{"op": "remove", "path": "/obstacles/2"}]},
               ITERATIONS, db)
    years = ",".join(map(str, YEARS))
    expect = expected_rows(db, "street species", YEARS)
    axes = ["species/street-tree", "seed", "variant"]
    out = env.path("r.csv")
    rc, err = report(env, c, "--db", db, "--years", years, "-o", out)
    c.check(rc == 0, "report -o .csv exits 0", err)
    header, rows, zones = check_csv(c, out, expect, axes, False)
    c.check(zones == ["road", "keep-clear-south", "keep-clear-north"],
            "a first_ column per zone, in scenario order", zones)
    c.check([h for h in header if h.startswith("clearance_")]
            == ["clearance_facade-south", "clearance_facade-north", "clearance_awning"],
            "a clearance_ column per solid obstacle", header)
    c.check(header[-1] == "pruned", "the pruned column ends the header", header)
    c.check(any(r[-1] not in ("", "0") for r in rows), "some stem was pruned by then")
    c.check(any(r[header.index("clearance_awning")] == "" for r in rows
                if "no awning" in r[0]), "no clearance to the awning where it was removed")
    c.check(not any(int(r[header.index("year")]) == 2027 + 20 for r in rows),
            "no row for a year no run reached")

    groups = expected_groups(expect, axes, zones, [y for y in YEARS if y <= ITERATIONS])
    c.check(len(groups) == 2 * 3 + 2 * 2 * 3, "groups: species x years, variants x species "
            "x years", len(groups))
    page = env.path("r.html")
    rc, err = report(env, c, "--db", db, "--years", years, "-o", page)
    c.check(rc == 0, "report -o .html exits 0", err)
    with open(page, encoding="utf-8") as f:
        text = f.read()
    c.check(not re.search(r"(src|href)=\"(https?:|//|file:)", text),
            "the page links to nothing outside itself")
    p = check_summary(c, text, groups, zones)
    check_images(c, p, pictures=2 * 3)

    pdf = env.path("r.pdf")
    rc, err = report(env, c, "--db", db, "--sweep", "street species", "--years", years,
                     "-o", pdf)
    c.check(rc == 0, "report -o .pdf exits 0", err)
    check_pdf(c, env, pdf, groups, min_pages=1 + 1 + 3)

    # the default years: 10 only (20 and 40 not reached)
    rc, err = report(env, c, "--db", db, "-o", env.path("d.csv"))
    _, drows = read_csv(env.path("d.csv"))
    c.check(rc == 0 and len(drows) == len(expected_rows(db, "street species", [10, 20, 40])),
            "default years 10,20,40: the rows of year 10", len(drows))


def part_ready(env, c):
    """The ready plan scenarios/street-species.json (30 runs, 6 iterations each): the
    CSV and the HTML summary equal the stored stats."""
    db = env.path("ready.db")
    rc, _, err = env.sylva("sweep", env.scenario("street-species.json"), "--db", db,
                           "--iterations", 6, "--jobs", "2")
    c.check(rc == 0, "the ready plan sweeps", err)
    years = [3, 6]
    expect = expected_rows(db, "street species", years)
    c.check(len(expect) == 30 * 5 * len(years), "30 runs x 5 trees x 2 years stored",
            len(expect))
    axes = ["species/street-tree", "seed", "variant"]
    out = env.path("ready.csv")
    rc, err = report(env, c, "--db", db, "--years", "3,6", "-o", out)
    c.check(rc == 0, "report of the ready plan -o .csv exits 0", err)
    _, _, zones = check_csv(c, out, expect, axes, False)
    groups = expected_groups(expect, axes, zones, years)
    c.check(len(groups) == 5 * 2 + 2 * 5 * 2, "groups: species x years, variants x species "
            "x years", len(groups))
    page = env.path("ready.html")
    rc, err = report(env, c, "--db", db, "--years", "3,6", "-o", page)
    c.check(rc == 0, "report of the ready plan -o .html exits 0", err)
    with open(page, encoding="utf-8") as f:
        p = check_summary(c, f.read(), groups, zones)
    check_images(c, p, pictures=5 * 2)


def part_plain(env, c):
    db = env.path("plain.db")
    run_into(env, db, [([env.scenario("street-pruned.json")], 8),
                       ([env.scenario("shrub.json")], 4)])
    years = [2, 4, 8]
    expect = expected_rows(db, None, years)
    out = env.path("p.csv")
    rc, err = report(env, c, "--db", db, "--years", "8,2,4,2", "-o", out)
    c.check(rc == 0, "report of a store without sweeps exits 0", err)
    header, rows, zones = check_csv(c, out, expect, [], True)
    c.check(header[:4] == ["run", "plant", "stem", "species"], "no axis columns, a stem column",
            header)
    species = sorted({r[header.index("species")] for r in rows})
    c.check(species == ["shrub", "street-tree"], "species by scenario key", species)
    c.check(any(r[-1] not in ("", "0") for r in rows), "pruned nodes summed by year 8")
    groups = expected_groups(expect, [], zones, years)
    page = env.path("p.html")
    rc, err = report(env, c, "--db", db, "--years", "2,4,8", "-o", page)
    c.check(rc == 0, "HTML of a store without sweeps exits 0", err)
    with open(page, encoding="utf-8") as f:
        p = check_summary(c, f.read(), groups, zones)
    # the shrub's run reaches 2 and 4, the street's 2, 4 and 8
    check_images(c, p, pictures=3 + 2)
    pdf = env.path("p.pdf")
    rc, err = report(env, c, "--db", db, "--years", "2,4,8", "-o", pdf)
    c.check(rc == 0, "PDF of a store without sweeps exits 0", err)
    check_pdf(c, env, pdf, groups, min_pages=5)


def part_errors(env, c):
    db = env.path("e.db")
    make_sweep(env, "one", ["utdb:NoEast:PLAC"], [1], {"as built": []}, 2, db)
    two = env.path("two.db")
    make_sweep(env, "one", ["utdb:NoEast:PLAC"], [1], {"as built": []}, 2, two)
    make_sweep(env, "other", ["utdb:NoEast:GIBI"], [1], {"as built": []}, 2, two)
    out = env.path("bad.csv")
    kept = env.path("kept.csv")
    with open(kept, "w") as f:
        f.write("before\n")
    cases = [
        ([], "--db FILE is required"),
        (["--db", env.path("none.db")], "none.db"),
        (["--db", db, "--sweep", "nope"], 'no sweep named "nope"'),
        (["--db", two], "choose one with --sweep"),
        (["--db", db, "--years", "ten"], "'ten' is not a whole number"),
        (["--db", db, "--years", "-5"], "'-5' is not a whole number"),
        (["--db", db, "--years", ""], "empty list"),
        (["--db", db, "--years", "10,,20"], "an empty year"),
        (["--db", db, "--years", "1.5"], "'1.5' is not a whole number"),
        (["--db", db, "--years", "0"], "'0' is not from 1"),
    ]
    for args, msg in cases:
        for target in (out, kept):
            rc, err = report(env, c, *(args + ["-o", target]))
            c.check(rc == 2 and msg in err, "exit 2 naming it: %s" % args, (rc, err))
            c.check(not os.path.exists(out) and not os.path.exists(out + ".tmp"),
                    "nothing written: %s" % args)
            with open(kept) as f:
                c.check(f.read() == "before\n", "an existing output untouched: %s" % args)
    for name in ("bad.txt", "bad", "bad.csv.gz"):
        rc, err = report(env, c, "--db", db, "-o", env.path(name))
        c.check(rc == 2 and "does not end in .csv, .html or .pdf" in err,
                "exit 2 for -o %s" % name, (rc, err))
        c.check(not os.path.exists(env.path(name)), "nothing written for -o %s" % name)
    rc, err = report(env, c, "--db", db)
    c.check(rc == 2 and "-o OUT is required" in err, "exit 2 without -o", err)
    # several sweeps: naming one works
    rc, err = report(env, c, "--db", two, "--sweep", "other", "--years", "1,2", "-o", out)
    c.check(rc == 0, "--sweep picks one of several sweeps", err)
    if rc == 0:
        _, rows = read_csv(out)
        c.check(len(rows) == 2 * 5 and all("utdb:NoEast:GIBI" in r for r in rows),
                "only that sweep's runs", rows[:2])
        os.remove(out)
    # years no run reached: a warning and the header only
    rc, err = report(env, c, "--db", db, "--years", "50", "-o", out)
    c.check(rc == 0 and "warning" in err and "no run has reached" in err,
            "unreached years: exit 0 with a warning", (rc, err))
    if rc == 0:
        header, rows = read_csv(out)
        c.check(header[0] == "run" and rows == [], "unreached years: the header only", rows)


SHADE = {"date": "07-21", "from": "10:00", "to": "12:00", "step": 30}
SHADE_MEASURES = MEASURES + [("shade_ground", "shade_ground", True)]
NO_LATITUDE = [{"op": "replace", "path": "/light", "value": {"sky": "zenith"}}]


def shade_day_summary(env, db, run, iteration):
    """`sylva shade`'s summary of a stored iteration on the plan's day: {surface: (cells,
    tree_shade_hours)}."""
    out = env.path("day.json")
    rc, _, err = env.sylva("shade", "--db", db, "--name", run, "--iteration", iteration,
                           "--date", SHADE["date"], "--from", SHADE["from"], "--to", SHADE["to"],
                           "--step", SHADE["step"], "-o", out)
    if rc != 0:
        raise RuntimeError("shade failed (%s): %s" % (rc, err))
    with open(out) as f:
        return {x["surface"]: (x["cells"], x["tree_shade_hours"]) for x in json.load(f)["surfaces"]}


def part_benefits(env, c):
    """A sweep with a shade day: co2, co2_sequestered and canopy_cover as stored, the
    tree shade columns as `sylva shade` gives them, empty with a warning where the
    light has no latitude; the HTML summary's tree shade."""
    db = env.path("benefits.db")
    plan = {"format": "sylva.sweep/1", "name": "benefits",
            "scenario": env.scenario("street.json"), "shade": SHADE,
            "axes": {"species": {"street-tree": ["utdb:NoEast:PLAC", "utdb:NoEast:GIBI"]},
                     "variants": {"as built": [], "no latitude": NO_LATITUDE}}}
    path = env.path("benefits.json")
    with open(path, "w") as f:
        json.dump(plan, f)
    rc, _, err = env.sylva("sweep", path, "--db", db, "--iterations", 4, "--jobs", 2,
                           "--quiet-progress")
    if rc != 0:
        raise RuntimeError("sweep failed (%s): %s" % (rc, err))
    con = sqlite3.connect(db)
    stored = json.loads(con.execute("SELECT plan FROM sweeps").fetchone()[0])
    con.close()
    c.check(stored.get("shade") == SHADE, "the store keeps the plan's shade day", stored.get("shade"))

    years = [2, 4]
    expect = expected_rows(db, "benefits", years)
    axes = ["species/street-tree", "variant"]
    out = env.path("b.csv")
    rc, err = report(env, c, "--db", db, "--years", "2,4", "-o", out)
    c.check(rc == 0, "report of a sweep with a shade day exits 0", err)
    lines = err.strip().splitlines()
    c.check(len(lines) == 1 and "warning" in lines[0] and "2 of 4 runs" in lines[0]
            and "no light.latitude" in lines[0] and "no latitude" in lines[0],
            "one warning line names the runs without a latitude", err)
    header, rows, zones = check_csv(c, out, expect, axes, False, shade=True)
    cols = ["shade_ground", "shade_facade-south", "shade_facade-north", "shade_awning"]
    at = header.index("canopy_cover") + 1
    c.check(header[at:at + len(cols)] == cols and not any(
        h.startswith("shade_") for h in header[at + len(cols):]),
        "shade_ground and a shade_ column per solid obstacle after canopy_cover", header)
    shade = {}  # (run, year) -> the shade fields
    bad = []
    for r in rows:
        f = dict(zip(header, r))
        key = (f["run"], int(f["year"]))
        got = [f[h] for h in cols]
        if shade.setdefault(key, got) != got:
            bad.append(("not the same on every stem", key))
        if (f["variant"] == "no latitude") != (got == [""] * len(cols)):
            bad.append(("empty exactly without a latitude", key, got))
    c.check(not bad, "run-level shade values, empty exactly where the light has no latitude",
            bad[:5])
    c.check(len(shade) == 4 * 2, "every run reached years 2 and 4", sorted(shade))
    # the binary's own `sylva shade` of the same iterations
    start = expect[0]["year"] - expect[0]["iteration"]
    bad = []
    for (run, year), got in sorted(shade.items()):
        if "no latitude" in run:
            continue
        day = shade_day_summary(env, db, run, year - start)
        want = [day["ground"][1]]
        for o in cols[1:]:
            faces = [v for k, v in day.items() if k.rsplit(":", 1)[0] == o[len("shade_"):]]
            cells = sum(n for n, _ in faces)
            want.append(sum(n * h for n, h in faces) / cells)
        # the summary prints 4 decimals: the ground within its rounding, an
        # obstacle's mean of rounded faces within it too
        if any(abs(float(g) - w) > 0.00005 + 1e-9 for g, w in zip(got, want)):
            bad.append((run, year, got, want))
    c.check(not bad, "shade columns equal `sylva shade`'s tree_shade_hours (4 runs x years)",
            bad[:4])
    c.check(any(float(v[0]) > 0 for v in shade.values() if v[0]),
            "the trees shade the ground by year 4")

    rc, err = report(env, c, "--db", db, "--years", "2,4", "-o", env.path("b2.csv"))
    with open(out, "rb") as f1, open(env.path("b2.csv"), "rb") as f2:
        c.check(rc == 0 and f1.read() == f2.read(), "the same store gives the same bytes")

    for e in expect:
        v = shade[(e["run"], e["year"])][0]
        e["shade_ground"] = float(v) if v else None
    groups = expected_groups(expect, axes, zones, years, SHADE_MEASURES)
    page = env.path("b.html")
    rc, err = report(env, c, "--db", db, "--years", "2,4", "-o", page)
    c.check(rc == 0, "HTML with a shade day exits 0", err)
    with open(page, encoding="utf-8") as f:
        text = f.read()
    check_summary(c, text, groups, zones, SHADE_MEASURES,
                  SUMMARY_HEAD + ["tree shade, ground (h)"])
    c.check("on 07-21 from 10:00 to 12:00 (samples every 30 minutes" in text,
            "the page names the shade day")


def part_stand(env, c):
    """Two stands with background mortality (six lindens each, seeds 2 and 4) and a
    shrub of an IGM species without stands, in a store without sweeps."""
    db = env.path("stand.db")
    path = stand_scenario(env, ITERATIONS)
    run_into(env, db, [([path, "--name", "stand-2"], ITERATIONS),
                       ([path, "--name", "stand-4", "--seed", 4], ITERATIONS),
                       ([env.scenario("shrub.json"), "--name", "shrub"], ITERATIONS)])
    years = [3, 8, 10]
    expect = expected_rows(db, None, years)
    out = env.path("s.csv")
    rc, err = report(env, c, "--db", db, "--years", "3,8,10", "-o", out)
    c.check(rc == 0, "report of stands exits 0", err)
    header, rows, zones = check_csv(c, out, expect, [], True)
    f = [dict(zip(header, r)) for r in rows]
    c.check(all(x["died"] == "" for x in f if x["run"] == "shrub") and
            all(x["died"] != "" for x in f if x["run"] != "shrub"),
            "the stand's columns are empty for the run without stands only")
    died = {(x["run"], x["year"]): int(x["died"]) for x in f if x["run"] != "shrub"}
    c.check(all(died[(r, "2038")] > died[(r, "2033")] for r in ("stand-2", "stand-4")) and
            died[("stand-2", "2040")] == 5,
            "died sums the stand's deaths to the year (more by 8 than by 3; five of "
            "stand-2's six by 10)", died)
    groups = expected_groups(expect, [], zones, years, MEASURES + STAND_MEASURES)
    page = env.path("s.html")
    rc, err = report(env, c, "--db", db, "--years", "3,8,10", "-o", page)
    c.check(rc == 0, "HTML of stands exits 0", err)
    with open(page, encoding="utf-8") as fh:
        text = fh.read()
    p = Tables()
    p.feed(text)
    check_stand_table(c, p, groups)
    pdf = env.path("s.pdf")
    rc, err = report(env, c, "--db", db, "--years", "3,8,10", "-o", pdf)
    c.check(rc == 0, "PDF of stands exits 0", err)
    text = subprocess.run(["pdftotext", "-layout", pdf, "-"], capture_output=True, text=True,
                          timeout=120).stdout
    cells = ["%.3f (%.3f–%.3f)" % g[5]["stems_per_ha"][1:4] for g in groups if g[2] == "ti"]
    c.check("the runs of the store — stand" in text and all(x in text for x in cells),
            "the PDF has a stand page with the stems per hectare", cells)
    # runs without stands: neither columns nor table
    plain = env.path("plain.db")
    run_into(env, plain, [([env.scenario("shrub.json")], 3)])
    rc, err = report(env, c, "--db", plain, "--years", "3", "-o", env.path("n.html"))
    with open(env.path("n.html"), encoding="utf-8") as fh:
        text = fh.read()
    rc2, err2 = report(env, c, "--db", plain, "--years", "3", "-o", env.path("n.csv"))
    header, _ = read_csv(env.path("n.csv"))
    c.check(rc == 0 and rc2 == 0 and "<h2>Stand</h2>" not in text and "stems_per_ha" not in header,
            "a report of runs without stands has no stand table or columns", (err, err2, header))


def main():
    env = Env(sys.argv[:3])
    part = sys.argv[3] if len(sys.argv) > 3 else "sweep"
    c = Checks()
    try:
        {"sweep": part_sweep, "ready": part_ready, "plain": part_plain,
         "errors": part_errors, "benefits": part_benefits, "stand": part_stand}[part](env, c)
    finally:
        env.cleanup()
    c.finish()


if __name__ == "__main__":
    main()
