#!/usr/bin/env python3
"""Round trip through the store, with the real binary.

- `sylva run --db --export`: the stdout lines equal those of a run without a
  store (elapsed_ms aside); `sylva export` of the last iteration equals the
  --export file byte for byte (to a file and to stdout);
- `sylva export --iteration T` of stored iterations (snapshot ones and ones
  regrown from an earlier snapshot) equals `sylva run --iterations T --export`;
- `sylva runs` lists the run: finished, limit, 10/10;
- CSV: one header line, one row per stem and iteration 1..last, every value as
  on the stats lines of `sylva run` (leaf_area too, and the stats table's
  leaf_area column rounds to the lines'); --iteration T cuts it at T;
- resume after a clean stop (--iterations 5, then resume --iterations 10):
  exactly the uninterrupted lines 6..10 and the done line, the same final
  skeleton and the same CSV; resume of a run at its limit prints only the
  done line;
- a run in years from a start year (tests/scenario/years.json): the same round
  trip, resumed lines and CSV byte for byte; the CSV's age, year, crown_diameter
  and crown_height columns as on the lines; runs.start_year the scenario's;
- a stand with background mortality (six library trees, a fifth dying a year):
  the same round trip; the stats table's alive, died (an iteration) and vigour
  and the iterations table's stand figures as on the lines; the CSV's stand
  columns equal the lines' (died a calendar year, as they give it); the resumed
  CSV is the uninterrupted one; a store of schema 6 stopped at 5 is migrated in
  place (its rows NULL, its CSV without the stand columns until a row has them)
  and resumed to 10: rows 1..5 empty, rows 6..10 those of the uninterrupted CSV;
- bad cases: a taken run name, an unknown run, a missing file, a file that is
  not SQLite, an SQLite file of another program, a store of a newer schema:
  exit 2, a message naming the file and the problem, and the file (and its
  directory) left exactly as it was.
"""
import csv
import io
import json
import math
import os
import sqlite3
import sys
import time

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from store_common import (Checks, Env, crash_text, query, read_bytes,  # noqa: E402
                          stand_scenario, strip_elapsed)

ITERATIONS = 10
SNAPSHOT_EVERY = 3
HEADER = ("iteration,plant,stem,height,dbh,crown_width,crown_base,nodes,shed,light,cap,finished,"
          "pruned,zones,clearance,leaf_area")


def main():
    env = Env(sys.argv)
    c = Checks()
    t0 = time.monotonic()
    try:
        scenario = env.scenario("stand.json")
        with open(scenario) as f:
            stems = sum(len(p["roots"]) for p in json.load(f)["plants"])
        db = env.path("a.db")
        final = env.path("final.json")
        lines = run_with_store(env, c, scenario, db, final)
        export_iterations(env, c, scenario, db)
        runs_listed(env, c, db, lines)
        check_csv(env, c, db, "rt", lines, stems)
        db_b = env.path("b.db")
        stop_at_5(env, c, scenario, db_b, lines)
        resume_to_10(env, c, db, db_b, final, lines)
        bad_cases(env, c, scenario, db)
        site_sky(env, c)
        street_pruned(env, c)
        street_exports(env, c)
        years(env, c)
        stand(env, c)
    finally:
        env.cleanup()
    print("time %.1f s" % (time.monotonic() - t0))
    c.finish()


def run_with_store(env, c, scenario, db, final):
    """`sylva run --db --export`: the lines and skeleton of a run without a store, and
    `sylva export` of the last iteration equal to the --export file; returns the lines."""
    rc, out, err = env.sylva("run", scenario, "--db", db, "--name", "rt",
                             "--snapshot-every", SNAPSHOT_EVERY, "--iterations", ITERATIONS,
                             "--export", final, "--quiet-progress")
    if not c.check(rc == 0, "run --db exits 0", "exit %s: %s" % (rc, err)):
        c.finish()
    lines = out.splitlines()
    c.check(len(lines) == ITERATIONS + 1, "run prints %d lines" % (ITERATIONS + 1), len(lines))
    c.check(lines[-1] == '{"done": true, "iterations": %d, "reason": "limit"}' % ITERATIONS,
            "done line", lines[-1])
    plain = env.clean_lines(scenario, ITERATIONS)
    c.check([strip_elapsed(x) for x in lines] == [strip_elapsed(x) for x in plain],
            "the stats lines with a store equal those without")
    c.check(read_bytes(final) == env.clean_export(scenario, ITERATIONS),
            "--export with a store equals --export without")

    rc, data, err = env.export(db, "rt")
    c.check(rc == 0 and data == read_bytes(final),
            "export of the last iteration equals the --export file byte for byte",
            "exit %s: %s" % (rc, err))
    rc, out2, err = env.sylva("export", "--db", db, "--name", "rt", "--format", "skeleton",
                              "-o", "-")
    c.check(rc == 0 and out2.encode() == read_bytes(final), "export -o - (stdout) too",
            "exit %s: %s" % (rc, err))
    rc, data, err = env.export(db, "rt", iteration=ITERATIONS)
    c.check(rc == 0 and data == read_bytes(final), "export --iteration %d too" % ITERATIONS,
            "exit %s: %s" % (rc, err))
    return lines


def site_sky(env, c):
    """The same under a site's sky (docs/model.md, "Site light"): the snapshots keep
    the sky, so stored, regrown and resumed iterations equal a run without a store."""
    with open(env.scenario("wall.json")) as f:
        doc = json.load(f)
    doc["light"] = {"sky": "site", "latitude": 50, "north": [0, 1], "season": [91, 273],
                    "diffuse": 0.4, "samples": 64}
    scenario = env.path("wall-site.json")
    with open(scenario, "w") as f:
        json.dump(doc, f)
    db, db_b, final = env.path("site.db"), env.path("site-b.db"), env.path("site-final.json")
    lines = run_with_store(env, c, scenario, db, final)
    export_iterations(env, c, scenario, db)
    stop_at_5(env, c, scenario, db_b, lines)
    resume_to_10(env, c, db, db_b, final, lines)


def street_pruned(env, c):
    """Zones, clearances and pruning every 3 iterations (scenarios/street-pruned.json,
    a site sky too): stored, regrown and resumed iterations equal a run without a
    store, and the CSV carries each stem's pruned count, zones and clearances as the
    stats lines do."""
    with open(env.scenario("street-pruned.json")) as f:
        doc = json.load(f)
    stems = sum(len(p["roots"]) for p in doc["plants"])
    # keep-clear strips that reach 5 cm from the trunks, so that 10 iterations prune
    for o in doc["obstacles"]:
        if o["id"] == "keep-clear-north":
            o["min"][1] = 5.05
        if o["id"] == "keep-clear-south":
            o["max"][1] = -5.05
    scenario = env.path("street-pruned.json")
    with open(scenario, "w") as f:
        json.dump(doc, f)
    db, db_b = env.path("street.db"), env.path("street-b.db")
    final = env.path("street-final.json")
    lines = run_with_store(env, c, scenario, db, final)
    c.check(any(s["pruned"] > 0 for x in lines[:-1] for s in json.loads(x)["stems"]) and
            any(s["zones"] for s in json.loads(lines[-2])["stems"]),
            "street-pruned: nodes pruned, zones entered in 10 iterations")
    export_iterations(env, c, scenario, db)
    check_csv(env, c, db, "rt", lines, stems)
    stop_at_5(env, c, scenario, db_b, lines)
    resume_to_10(env, c, db, db_b, final, lines)


def street_exports(env, c):
    """scenarios/street.json stored, then every iteration exported: each stem's zone
    lines (nodes inside, first iteration) and clearances in the stats lines equal a
    count over the exported skeleton's nodes and obstacles. Positions are exported
    with 4 decimals, so a node within 0.1 mm of a zone's face may be counted either
    way, and distances agree within 0.2 mm."""
    scenario = env.scenario("street.json")
    db = env.path("street-x.db")
    rc, out, err = env.sylva("run", scenario, "--db", db, "--name", "sx", "--quiet-progress")
    if not c.check(rc == 0, "street.json stored", "exit %s: %s" % (rc, err)):
        return
    lines = [json.loads(x) for x in out.splitlines()[:-1]]
    eps, first, problems, lines_seen = 1e-4, {}, [], 0
    for line in lines:
        t = line["iteration"]
        rc, data, err = env.export(db, "sx", iteration=t)
        if rc != 0:
            problems.append("export %d: %s" % (t, err))
            continue
        sk = json.loads(data)
        zones = [o for o in sk["obstacles"] if o["kind"] == "zone"]
        solids = [o for o in sk["obstacles"] if o["kind"] == "box"]
        stems = [(p["id"], k, st["nodes"]) for p in sk["plants"] for k, st in enumerate(p["stems"])]
        for (plant, k, nodes), got in zip(stems, line["stems"]):
            for z in zones:
                def inside(n, m):
                    return all(z["min"][a] - m <= n[2 + a] <= z["max"][a] + m for a in range(3))
                sure = sum(1 for n in nodes if inside(n, -eps))
                maybe = sum(1 for n in nodes if inside(n, eps))
                key = (plant, k, z["id"])
                if maybe and key not in first:
                    first[key] = (t if sure else None, t)  # (surely by, at the earliest)
                line_z = got["zones"].get(z["id"])
                if line_z is None:
                    if maybe:
                        problems.append("T=%d %s %s: no line, %d inside" % (t, plant, z["id"], sure))
                    continue
                lines_seen += 1
                if not sure <= line_z["nodes"] <= maybe:
                    problems.append("T=%d %s %s: %d nodes, the skeleton has %d to %d" %
                                    (t, plant, z["id"], line_z["nodes"], sure, maybe))
                earliest = first.get(key, (None, None))[1]
                if earliest is None or line_z["first"] < earliest:
                    problems.append("T=%d %s %s: first %d before any node was inside" %
                                    (t, plant, z["id"], line_z["first"]))
            for o in solids:
                d = min(math.dist([n[2], n[3], n[4]],
                                  [min(max(n[2 + a], o["min"][a]), o["max"][a]) for a in range(3)])
                        for n in nodes)
                got_d = got["clearance"].get(o["id"])
                if got_d is None:
                    if d < 10 - 2e-4:
                        problems.append("T=%d %s %s: no clearance, %.4f m" % (t, plant, o["id"], d))
                elif abs(got_d - d) > 2e-4 or d > 10 + 2e-4:
                    problems.append("T=%d %s %s: clearance %.4f, the skeleton %.4f" %
                                    (t, plant, o["id"], got_d, d))
    c.check(lines_seen > 0 and not problems,
            "street.json: every iteration's zone lines and clearances equal a count over its "
            "exported skeleton (%d zone lines)" % lines_seen, "\n".join(problems[:10]))


YEARS_COLUMNS = ["age", "year", "crown_diameter", "crown_height"]
GIVE_COLUMNS = ["crown_area", "wood_volume", "biomass", "biomass_model", "carbon", "co2",
                "co2_sequestered", "canopy_cover"]
# in a run with stands (a species in years, or deaths), after the rest
STAND_COLUMNS = ["alive", "died", "vigour", "stems_per_ha", "basal_area", "qmd",
                 "dominant_height", "sdi", "cv_height", "cv_dbh", "stand_died"]
STAND_FIGURES = [("stems_per_ha", 1), ("basal_area", 3), ("qmd", 2), ("dominant_height", 3),
                 ("sdi", 1), ("cv_height", 4), ("cv_dbh", 4)]


def years(env, c):
    """A run in years from 2027 (tests/scenario/years.json: two trees of a species
    with years, one planted at 3, an IGM tree, a lane zone): stored, regrown and
    resumed iterations equal a run without a store, the resumed CSV is the
    uninterrupted one; every line has its year, and the CSV's years columns equal
    the lines' ages, years, crown diameters and heights (empty where a line has
    null); the store keeps the start year with the run."""
    scenario = os.path.join(env.scenarios, os.pardir, "tests", "scenario", "years.json")
    db, db_b, final = env.path("years.db"), env.path("years-b.db"), env.path("years-final.json")
    lines = run_with_store(env, c, scenario, db, final)
    export_iterations(env, c, scenario, db)
    stop_at_5(env, c, scenario, db_b, lines)
    resume_to_10(env, c, db, db_b, final, lines)
    objs = [json.loads(x) for x in lines[:-1]]
    c.check(all(o["year"] == 2027 + o["iteration"] for o in objs), "years: every line's year")
    c.check(all([s["age"] for s in o["stems"]] == [o["iteration"], 3 + o["iteration"], None]
                for o in objs), "years: the lines' ages (null for the IGM tree)")
    rc, data, err = env.export(db, "rt", fmt="csv")
    if not c.check(rc == 0 and data is not None, "years: export --format csv", err):
        return
    records = list(csv.reader(io.StringIO(data.decode())))
    c.check(records[0] == HEADER.split(",") + YEARS_COLUMNS + GIVE_COLUMNS + STAND_COLUMNS,
            "years: the CSV header (a species in years: the stand's columns too)", records[0])
    text = lambda v: "" if v is None else str(v)  # noqa: E731
    want = [[text(s["age"]), str(o["year"]), text(s["crown_diameter"]), text(s["crown_height"])]
            for o in objs for s in o["stems"]]
    # the lines print lengths with at most 4 decimals, as the CSV does
    got = [r[16:20] for r in records[1:]]
    c.check(got == want, "years: the CSV's years columns equal the lines'",
            "\n".join("%r != %r" % (g, w) for g, w in zip(got, want) if g != w)[:2000])
    c.check(query(db, "SELECT start_year FROM runs") == [(2027,)], "years: runs.start_year")


def export_iterations(env, c, scenario, db):
    """`sylva export --iteration T` of stored iterations equals `sylva run --iterations T
    --export`; 0 is the planted world; one not stored is exit 2."""
    # snapshots at 0, 3, 6, 9, 10: 4, 5, 8 are regrown, 3 and 6 are restored
    for t in (1, 3, 4, 5, 6, 8):
        rc, data, err = env.export(db, "rt", iteration=t)
        c.check(rc == 0 and data == env.clean_export(scenario, t),
                "export --iteration %d equals run --iterations %d --export" % (t, t),
                "exit %s: %s" % (rc, err))
    rc, data, err = env.export(db, "rt", iteration=0)
    c.check(rc == 0 and data is not None and json.loads(data)["iteration"] == 0,
            "export --iteration 0 (the planted world)", "exit %s: %s" % (rc, err))
    rc, data, err = env.export(db, "rt", iteration=ITERATIONS + 1)
    c.check(rc == 2 and "no iteration %d" % (ITERATIONS + 1) in err and data is None,
            "export of an iteration not stored: exit 2", "exit %s: %s" % (rc, err))


def runs_listed(env, c, db, lines):
    """`sylva runs` lists the run: finished, limit, 10/10, its live nodes."""
    rc, out, err = env.sylva("runs", "--db", db)
    rows = [x.split() for x in out.splitlines()]
    c.check(rc == 0 and len(rows) == 2 and rows[0][:2] == ["NAME", "STATUS"],
            "runs: a header and one run", out + err)
    last_nodes = sum(s["nodes"] for s in json.loads(lines[-2])["stems"])
    c.check(len(rows) == 2 and rows[1][:5] == ["rt", "finished", "limit", "10/10",
                                                 str(last_nodes)],
            "runs: rt finished, limit, 10/10, its live nodes", out)


def stop_at_5(env, c, scenario, db_b, lines):
    """A run stopped cleanly at 5: the first 5 lines and a done line; finished at 5/5."""
    rc, out, err = env.sylva("run", scenario, "--db", db_b, "--name", "rs",
                             "--snapshot-every", SNAPSHOT_EVERY, "--iterations", 5,
                             "--quiet-progress")
    first = out.splitlines()
    c.check(rc == 0 and [strip_elapsed(x) for x in first[:-1]] ==
            [strip_elapsed(x) for x in lines[:5]] and
            first[-1] == '{"done": true, "iterations": 5, "reason": "limit"}',
            "run --iterations 5: lines 1..5 and a done line", "exit %s: %s" % (rc, err))
    rc, out, err = env.sylva("runs", "--db", db_b)
    c.check(rc == 0 and out.splitlines()[1].split()[:4] == ["rs", "finished", "limit", "5/5"],
            "runs: rs finished at 5/5", out + err)


def resume_to_10(env, c, db, db_b, final, lines):
    """Resumed to 10: exactly the uninterrupted lines 6..10 and the done line, the same
    skeleton, CSV and stored iterations; resumed at its limit, only the done line."""
    rc, out, err = env.sylva("resume", "--db", db_b, "--name", "rs", "--iterations",
                             ITERATIONS, "--quiet-progress")
    c.check(rc == 0, "resume --iterations 10 exits 0", "exit %s: %s" % (rc, err))
    c.check(err == "", "resume after a clean stop is silent on stderr", err)
    got = [strip_elapsed(x) for x in out.splitlines()]
    want = [strip_elapsed(x) for x in lines[5:]]
    c.check(got == want, "resume prints exactly the lines 6..10 and the done line",
            "got:\n%s\nwant:\n%s" % ("\n".join(x[:120] for x in got),
                                      "\n".join(x[:120] for x in want)))
    rc, data, err = env.export(db_b, "rs")
    c.check(rc == 0 and data == read_bytes(final),
            "the resumed run's final export equals the uninterrupted one",
            "exit %s: %s" % (rc, err))
    rc_a, csv_a, _ = env.export(db, "rt", fmt="csv")
    rc_b, csv_b, _ = env.export(db_b, "rs", fmt="csv")
    c.check(rc_a == 0 and rc_b == 0 and csv_a == csv_b,
            "the resumed run's CSV equals the uninterrupted one")
    c.check(query(db, "SELECT iteration, hash, nodes FROM iterations ORDER BY iteration") ==
            query(db_b, "SELECT iteration, hash, nodes FROM iterations ORDER BY iteration"),
            "the same world hashes and node counts are stored")
    rc, out, err = env.sylva("runs", "--db", db_b)
    c.check(rc == 0 and out.splitlines()[1].split()[:4] ==
            ["rs", "finished", "limit", "10/10"], "runs: rs finished at 10/10", out + err)
    rc, out, err = env.sylva("resume", "--db", db_b, "--name", "rs", "--quiet-progress")
    c.check(rc == 0 and out == '{"done": true, "iterations": 10, "reason": "limit"}\n',
            "resume of a run at its limit prints only the done line",
            "exit %s: %r %s" % (rc, out, err))


def check_csv(env, c, db, name, lines, stems):
    rc, data, err = env.export(db, name, fmt="csv")
    if not c.check(rc == 0 and data is not None, "export --format csv exits 0",
                   "exit %s: %s" % (rc, err)):
        return
    text = data.decode()
    c.check(text.endswith("\n") and "\r" not in text, "CSV lines end with \\n")
    rows = text.splitlines()
    # a run in years (street.json's planes) carries the years columns after the rest,
    # and one with stands (as its lines have a stand) the stand's columns last
    in_years = rows[0].startswith(",".join([HEADER] + YEARS_COLUMNS))
    stand = "stand" in json.loads(lines[0])
    head = ([HEADER] + (YEARS_COLUMNS if in_years else []) + GIVE_COLUMNS +
            (STAND_COLUMNS if stand else []))
    width = len(",".join(head).split(","))
    give = 16 + (len(YEARS_COLUMNS) if in_years else 0)
    c.check(rows[0] == ",".join(head), "CSV header", rows[0])
    c.check(sum(1 for r in rows if r.startswith("iteration,")) == 1, "exactly one header line")
    records = list(csv.reader(io.StringIO("\n".join(rows[1:]))))
    c.check(len(records) == stems * ITERATIONS,
            "one CSV row per stem (%d) and iteration (1..%d)" % (stems, ITERATIONS), len(records))
    expected = []
    for line in lines[:-1]:
        obj = json.loads(line)
        for s in obj["stems"]:
            expected.append((obj["iteration"], dict(s, canopy_cover=obj["canopy_cover"],
                                                    stand=obj.get("stand"))))
    mismatches = []
    for i, ((it, s), rec) in enumerate(zip(expected, records)):
        if len(rec) != width:
            mismatches.append("row %d: %d fields" % (i + 1, len(rec)))
            continue
        num = lambda v: None if v == "" else float(v)  # noqa: E731
        obj = lambda v: None if v == "" else json.loads(v)  # noqa: E731
        got = (int(rec[0]), rec[1], int(rec[2]), num(rec[3]), num(rec[4]), num(rec[5]),
               num(rec[6]), int(rec[7]), int(rec[8]), num(rec[9]), int(rec[10]), rec[11],
               None if rec[12] == "" else int(rec[12]), obj(rec[13]), obj(rec[14]), num(rec[15]))
        want = (it, s["plant"], s["stem"], s["height"], s["dbh"], s["crown_width"],
                s["crown_base"], s["nodes"], s["shed"], s["light"], s["cap"],
                "true" if s["finished"] else "false", s.get("pruned"), s.get("zones"),
                s.get("clearance"), s["leaf_area"])
        # what the trees give: as the line gives it, empty where it leaves it out
        got += tuple(num(v) for v in rec[give:give + len(GIVE_COLUMNS)])
        want += tuple(s.get(k) for k in GIVE_COLUMNS)
        if stand:  # the stem's alive, died and vigour, then the line's stand
            got += tuple(rec[give + len(GIVE_COLUMNS):])
            want += stand_cells(s, s["stand"])
        if got != want:
            mismatches.append("row %d: %r != %r" % (i + 1, got, want))
    c.check(len(expected) == len(records) and not mismatches,
            "every CSV row equals the stats line of its iteration and stem "
            "(height, dbh, crown, nodes, shed, light, cap, finished, pruned, zones, clearance, "
            "leaf_area, crown_area, wood_volume, the carbon, canopy_cover)",
            "\n".join(mismatches[:10]))
    # the store keeps the measured double; the lines and the CSV print it to 4 decimals
    stored = [round(v, 4) if v is not None else None for (v,) in query(
        db, "SELECT s.leaf_area FROM stats s JOIN runs r ON r.id = s.run WHERE r.name = ?"
        " ORDER BY s.iteration, s.stem", (name,))]
    c.check(stored == [s["leaf_area"] for _, s in expected] and any(stored),
            "the stats table's leaf_area equals the lines' (to their 4 decimals), some above 0",
            "%r != %r" % (stored[:6], [s["leaf_area"] for _, s in expected][:6]))
    rc, data, err = env.export(db, name, fmt="csv", iteration=4)
    c.check(rc == 0 and data is not None and
            data.decode().splitlines() == rows[:1 + 4 * stems],
            "CSV --iteration 4: the header and the rows of iterations 1..4",
            "exit %s: %s" % (rc, err))


def stand_cells(s, stand):
    """The CSV's stand cells of a line's stem s and stand, as text."""
    text = lambda v: "" if v is None else str(v)  # noqa: E731
    return ((text(s["alive"]).lower(), text(s["died"]), text(s["vigour"])) +
            tuple(text(stand[k]) for k, _ in STAND_FIGURES) + (text(stand["died"]),))


def stand(env, c):
    """A stand with background mortality: the round trip, resumed lines and CSV byte
    for byte; the stored alive, died, vigour and stand figures as on the lines; the
    CSV's stand columns as the lines give them; a store of schema 6 migrated."""
    scenario = stand_scenario(env, ITERATIONS)
    db, db_b, final = env.path("stand.db"), env.path("stand-b.db"), env.path("stand-final.json")
    lines = run_with_store(env, c, scenario, db, final)
    objs = [json.loads(x) for x in lines[:-1]]
    died = [s["died"] for s in objs[-1]["stems"]]
    c.check(any(d is not None and d <= 2035 for d in died) and
            any(d is not None and d > 2035 for d in died) and None in died,
            "stand: stems die before and after iteration 5, one lives", died)
    export_iterations(env, c, scenario, db)
    check_csv(env, c, db, "rt", lines, 6)
    stop_at_5(env, c, scenario, db_b, lines)
    resume_to_10(env, c, db, db_b, final, lines)
    # the stats table: died as an iteration, vigour the double the line prints
    stored = [(it, k, alive, d, None if v is None else round(v, 4)) for it, k, alive, d, v in
              query(db, "SELECT iteration, stem, alive, died, vigour FROM stats"
                    " ORDER BY iteration, stem")]
    want = [(o["iteration"], k, int(s["alive"]), None if s["died"] is None else s["died"] - 2030,
             s["vigour"]) for o in objs for k, s in enumerate(o["stems"])]
    c.check(stored == want, "stand: the stats table's alive, died (an iteration) and vigour "
            "equal the lines'", "\n".join("%r != %r" % (g, w) for g, w in zip(stored, want)
                                          if g != w)[:2000])
    stored = [(r[0], round(r[1], 1), r[2], r[3]) +
              tuple(None if v is None else round(v, dec)
                    for v, (_, dec) in zip(r[4:], STAND_FIGURES))
              for r in query(db, "SELECT iteration, stand_area, stand_alive, stand_died,"
                             " stems_per_ha, basal_area, qmd, dominant_height, sdi, cv_height,"
                             " cv_dbh FROM iterations WHERE iteration > 0 ORDER BY iteration")]
    want = [(o["iteration"], o["stand"]["area"], o["stand"]["alive"], o["stand"]["died"]) +
            tuple(o["stand"][k] for k, _ in STAND_FIGURES) for o in objs]
    c.check(stored == want, "stand: the iterations table's stand figures equal the lines'",
            "\n".join("%r != %r" % (g, w) for g, w in zip(stored, want) if g != w)[:2000])
    c.check(query(db, "SELECT count(*) FROM iterations WHERE stand_alive IS NULL") == [(0,)],
            "stand: every iteration (0 too) has its stand")
    schema6_migrates(env, c, scenario, db)


def schema6_migrates(env, c, scenario, db):
    """A store of schema 6 (its stand columns dropped) stopped at 5 is migrated in
    place by the next command: its rows NULL, its CSV the columns it had; resumed to
    10, the rows 1..5 have their stand cells empty and the rest are the uninterrupted
    run's CSV."""
    db6 = env.path("stand-6.db")
    rc, _, err = env.sylva("run", scenario, "--db", db6, "--name", "rt", "--snapshot-every",
                           SNAPSHOT_EVERY, "--iterations", 5, "--quiet-progress")
    c.check(rc == 0, "schema 6: run to 5", err)
    con = sqlite3.connect(db6)
    for table, col in [("stats", "alive"), ("stats", "died"), ("stats", "vigour")] + [
            ("iterations", x) for x in ("stand_area", "stand_alive", "stand_died", "stems_per_ha",
                                        "basal_area", "qmd", "dominant_height", "sdi",
                                        "cv_height", "cv_dbh")]:
        con.execute("ALTER TABLE %s DROP COLUMN %s" % (table, col))
    con.execute("ALTER TABLE runs DROP COLUMN hash_version")
    con.execute("PRAGMA user_version = 6")
    con.commit()
    con.close()
    rc, data, err = env.export(db6, "rt", fmt="csv")
    _, full, _ = env.export(db, "rt", fmt="csv")
    c.check(query(db6, "PRAGMA user_version") == [(8,)] and
            query(db6, "SELECT hash_version FROM runs") == [(1,)] and
            query(db6, "SELECT count(*) FROM stats WHERE alive IS NOT NULL OR died IS NOT NULL OR"
                  " vigour IS NOT NULL") == [(0,)] and
            query(db6, "SELECT count(*) FROM iterations WHERE stand_alive IS NOT NULL") == [(0,)],
            "schema 6: opened, migrated in place to 8, its rows NULL, its run on hash 1", err)
    # This build stored the rows with hash 2; a store of schema 6 holds hash 1's, which
    # unit-store's schema 7 test restores. The run is given the hash its rows hold.
    sqlite_file(db6, "UPDATE runs SET hash_version = 2")
    if not c.check(rc == 0 and data is not None and full is not None,
                   "schema 6: export --format csv", err):
        return
    cut = len(STAND_COLUMNS)
    short = lambda row: ",".join(row.split(",")[:-cut])  # noqa: E731
    old = data.decode().splitlines()
    want = [short(r) for r in full.decode().splitlines()[:1 + 5 * 6]]
    c.check(old == want, "schema 6: before a row has them, the CSV has no stand columns (the "
            "uninterrupted CSV without them)", "%r\n%r" % (old[:2], want[:2]))
    rc, out, err = env.sylva("resume", "--db", db6, "--name", "rt", "--iterations", ITERATIONS,
                             "--quiet-progress")
    c.check(rc == 0, "schema 6: resume to 10", err)
    rc, data, err = env.export(db6, "rt", fmt="csv")
    rows, full_rows = data.decode().splitlines(), full.decode().splitlines()
    blank = lambda row: short(row) + "," * cut  # noqa: E731
    want = full_rows[:1] + [blank(r) for r in full_rows[1:1 + 5 * 6]] + full_rows[1 + 5 * 6:]
    c.check(rc == 0 and rows == want, "schema 6: resumed, the rows 1..5 have their stand cells "
            "empty and the rows 6..10 are the uninterrupted CSV's",
            "\n".join("%r != %r" % (g, w) for g, w in zip(rows, want) if g != w)[:2000])


def snapshot_dir(d):
    """Name, size, mtime and bytes of every file in a directory."""
    out = {}
    for n in sorted(os.listdir(d)):
        p = os.path.join(d, n)
        st = os.stat(p)
        out[n] = (st.st_size, st.st_mtime_ns, read_bytes(p))
    return out


def bad_cases(env, c, scenario, good_db):
    taken_name(env, c, scenario, good_db)
    unknown_run(env, c, good_db)
    missing_store(env, c)
    not_a_store(env, c, scenario, good_db)


def taken_name(env, c, scenario, good_db):
    """A run with a taken name: exit 2, nothing stored."""
    before = (query(good_db, "SELECT count(*) FROM iterations"),
              query(good_db, "SELECT * FROM stats"))
    runs_before = query(good_db, "SELECT * FROM runs")
    rc, out, err = env.sylva("run", scenario, "--db", good_db, "--name", "rt", "--iterations", 3,
                             "--quiet-progress")
    c.check(rc == 2 and "exists already" in err and '"rt"' in err and good_db in err and out == "",
            "run with a taken name: exit 2, says so", "exit %s: %s" % (rc, err))
    c.check((query(good_db, "SELECT count(*) FROM iterations"),
             query(good_db, "SELECT * FROM stats")) == before and
            query(good_db, "SELECT * FROM runs") == runs_before,
            "run with a taken name changes nothing")


def unknown_run(env, c, good_db):
    """resume and export of an unknown run: exit 2, and no output file."""
    for args in (["resume", "--db", good_db, "--name", "nosuch"],
                 ["export", "--db", good_db, "--name", "nosuch", "--format", "skeleton", "-o",
                  env.path("x.json")],
                 ["export", "--db", good_db, "--name", "nosuch", "--format", "csv", "-o",
                  env.path("x.csv")]):
        rc, out, err = env.sylva(*args)
        c.check(rc == 2 and 'no run named "nosuch"' in err and good_db in err,
                "%s of an unknown run: exit 2, says so" % args[0], "exit %s: %s" % (rc, err))
    c.check(not os.path.exists(env.path("x.json")) and not os.path.exists(env.path("x.csv")) and
            not os.path.exists(env.path("x.json.tmp")) and
            not os.path.exists(env.path("x.csv.tmp")),
            "a failed export leaves no output file")


def missing_store(env, c):
    """A missing file is not created by the commands that only read."""
    missing = env.path("missing.db")
    for args in (["resume", "--db", missing, "--name", "rt"],
                 ["export", "--db", missing, "--name", "rt", "--format", "csv", "-o",
                  env.path("x.csv")],
                 ["runs", "--db", missing]):
        rc, out, err = env.sylva(*args)
        c.check(rc == 2 and missing in err and not os.path.exists(missing),
                "%s of a missing store: exit 2, names it, creates nothing" % args[0],
                "exit %s: %s" % (rc, err))


def sqlite_file(path, *statements):
    con = sqlite3.connect(path)
    for sql in statements:
        con.execute(sql)
    con.commit()
    con.close()


def foreign_files(c, bad_dir, good_db):
    """Files that are no sylva store (of this version), with the reason each is refused."""
    text = os.path.join(bad_dir, "text.db")
    with open(text, "w") as f:
        f.write("this is not a database\n" * 200)
    binary = os.path.join(bad_dir, "random.db")
    with open(binary, "wb") as f:
        f.write(bytes((i * 7919 + 13) % 251 for i in range(16384)))
    other = os.path.join(bad_dir, "other.db")
    sqlite_file(other, "CREATE TABLE notes (id INTEGER PRIMARY KEY, text TEXT)",
                "INSERT INTO notes (text) VALUES ('hello')")
    other_app = os.path.join(bad_dir, "other-app.db")
    sqlite_file(other_app, "PRAGMA application_id = 1234", "CREATE TABLE t (x)")
    newer = os.path.join(bad_dir, "newer.db")
    with open(newer, "wb") as f:
        f.write(read_bytes(good_db))
    sqlite_file(newer, "PRAGMA user_version = 99")
    c.check(query(newer, "PRAGMA user_version") == [(99,)] and
            query(newer, "PRAGMA journal_mode") == [("wal",)],
            "the newer-schema store is a WAL sylva store with user_version 99")
    return [(text, "not a sylva store"), (binary, "not a sylva store"),
            (other, "not a sylva store"), (other_app, "not a sylva store"),
            (newer, "newer sylva")]


def not_a_store(env, c, scenario, good_db):
    """Every command on a file that is no sylva store (of this version): exit 2, a
    message naming the file and the problem, the file and its directory unchanged."""
    bad_dir = env.path("bad")
    os.mkdir(bad_dir)
    cases = foreign_files(c, bad_dir, good_db)
    # older timestamps, so that a rewrite within the same clock tick would show
    for path, _ in cases:
        os.utime(path, ns=(1_000_000_000_000_000_000, 1_000_000_000_000_000_000))
    before = snapshot_dir(bad_dir)
    for path, reason in cases:
        for args in (["run", scenario, "--db", path, "--name", "x", "--iterations", 2,
                      "--quiet-progress"],
                     ["resume", "--db", path, "--name", "rt"],
                     ["export", "--db", path, "--name", "rt", "--format", "skeleton", "-o",
                      env.path("x.json")],
                     ["runs", "--db", path]):
            rc, out, err = env.sylva(*args)
            crash = crash_text(rc, err)
            label = "%s on %s" % (args[0], os.path.basename(path))
            c.check(not crash and rc == 2 and out == "" and err.startswith("sylva: ") and
                    path in err and reason in err,
                    "%s: exit 2, names the file and says '%s'" % (label, reason),
                    "exit %s: %s" % (rc, err))
            after = snapshot_dir(bad_dir)
            changed = [n for n in set(before) | set(after) if before.get(n) != after.get(n)]
            c.check(not changed, "%s: the file and its directory are unchanged" % label,
                    "changed: %s" % changed)
            before = after


if __name__ == "__main__":
    main()
