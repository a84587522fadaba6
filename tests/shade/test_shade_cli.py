"""`sylva shade` through the real binary (Python 3 standard library only).

meson runs `python3 test_shade_cli.py SYLVA_EXE TESTS_SHADE_DIR`: a small yard
(site.json, 3 iterations at 0.2 m voxels) is grown into a store; the same iteration
shaded twice gives the same bytes (CSV, JSON, PNG); the CSV's rows, the summary's
means and the stdout line agree; bad input exits 2 with the reason on stderr and
writes nothing. A site of prisms (prisms.json): their walls named by edge, e0, e1,
..., one wall alone by --surface, a box's face name refused for a prism.
"""
import csv
import json
import os
import subprocess
import sys
import tempfile

EXE, HERE = sys.argv[1], sys.argv[2]
failures = []


def check(cond, what):
    if not cond:
        failures.append(what)
        print("FAILED:", what, file=sys.stderr)


def sylva(*args):
    return subprocess.run([EXE, *args], capture_output=True, text=True, timeout=300)


with tempfile.TemporaryDirectory() as tmp:
    db = os.path.join(tmp, "yard.db")
    site = os.path.join(HERE, "site.json")
    p = sylva("run", site, "--db", db, "--name", "yard", "--quiet-progress")
    check(p.returncode == 0, "run: " + p.stderr)
    stored = ["--db", db, "--name", "yard"]
    day = ["--date", "06-21", "--from", "06:00", "--to", "20:00", "--step", "20"]

    # the same bytes twice, in every format
    for ext in ("csv", "json", "png"):
        outs = []
        for k in range(2):
            out = os.path.join(tmp, "s%d.%s" % (k, ext))
            p = sylva("shade", *stored, "--year", "2033", *day, "-o", out)
            check(p.returncode == 0, "shade %s: %s" % (ext, p.stderr))
            with open(out, "rb") as f:
                outs.append(f.read())
            summary = json.loads(p.stdout.strip().splitlines()[-1])
        check(outs[0] == outs[1] and len(outs[0]) > 0, "same bytes twice: " + ext)
        check(summary["year"] == 2033 and summary["date"] == "06-21", "summary's day")
        if ext == "json":
            check(json.loads(outs[0]) == summary, "the JSON file is the stdout line")
        if ext == "png":
            check(outs[0][:8] == b"\x89PNG\r\n\x1a\n", "a PNG")
        if ext == "csv":
            rows = list(csv.DictReader(outs[0].decode().splitlines()))
            check(list(rows[0].keys()) == ["x", "y", "z", "surface", "sun_hours_open",
                                           "sun_hours"], "CSV header")
            ground = [r for r in rows if r["surface"] == "ground"]
            check(len(ground) == 30 * 30, "ground cells: %d" % len(ground))
            names = {r["surface"] for r in rows}
            check(names == {"ground", "shed:+x", "shed:-x", "shed:+y", "shed:-y"},
                  "surfaces: %s" % sorted(names))
            by = {s["surface"]: s for s in summary["surfaces"]}
            mean = sum(float(r["sun_hours"]) for r in ground) / len(ground)
            check(abs(mean - by["ground"]["sun_hours"]) < 1e-3, "ground mean")
            check(all(float(r["sun_hours"]) <= float(r["sun_hours_open"]) + 1e-9 for r in rows),
                  "the tree only takes sun")
            check(by["ground"]["tree_shade_hours"] > 0, "the tree shades the ground")
            check(all(float(r["sun_hours_open"]) <= 14.0 for r in rows), "within the hours")

    # one surface
    out = os.path.join(tmp, "face.csv")
    p = sylva("shade", *stored, *day, "--surface", "shed:-y", "-o", out)
    check(p.returncode == 0, "--surface: " + p.stderr)
    with open(out) as f:
        check({r["surface"] for r in csv.DictReader(f)} == {"shed:-y"}, "--surface rows")

    # a scenario as planted, and one without plants
    p = sylva("shade", site, "--date", "03-21", "--step", "60", "-o", os.path.join(tmp, "p.json"))
    check(p.returncode == 0 and json.loads(p.stdout)["year"] == 2030, "scenario: " + p.stderr)

    # bad input: exit 2, the reason, nothing written
    bad = [
        (["--date", "02-30"], "02-30"),
        (["--date", "6-21"], "MM-DD"),
        (["--date", "06-21", "--from", "14:00", "--to", "10:00"], "--from"),
        (["--date", "06-21", "--from", "25:00"], "HH:MM"),
        (["--date", "06-21", "--to", "10:7"], "HH:MM"),
        (["--date", "06-21", "--step", "0"], "step"),
        (["--date", "06-21", "--step", "-5"], "step"),
        (["--date", "06-21", "--step", "ten"], "step"),
        (["--date", "06-21", "--year", "2040"], "2040"),
        (["--date", "06-21", "--year", "2029"], "2029"),
        (["--date", "06-21", "--surface", "awning:+x"], "awning"),
        (["--date", "06-21", "--surface", "shed:+z"], "+z"),
        (["--date", "06-21", "--surface", "path:+x"], "zone"),
        (["--from", "06:00"], "--date"),
    ]
    for args, word in bad:
        for ext in ("csv", "xyz") if word == "02-30" else ("csv",):
            out = os.path.join(tmp, "bad." + ext)
            p = sylva("shade", *stored, *args, "-o", out)
            what = "%s -o %s" % (" ".join(args), out)
            check(p.returncode == 2, "exit 2: %s (got %d)" % (what, p.returncode))
            check(word in p.stderr or ext == "xyz", "names %s: %s: %s" % (word, what, p.stderr))
            check(not os.path.exists(out) and not os.path.exists(out + ".tmp"), "wrote: " + what)
    out = os.path.join(tmp, "bad.txt")
    p = sylva("shade", *stored, "--date", "06-21", "-o", out)
    check(p.returncode == 2 and ".csv" in p.stderr and not os.path.exists(out), "extension")
    p = sylva("shade", os.path.join(HERE, "zenith.json"), "--date", "06-21", "-o", out + ".csv")
    check(p.returncode == 2 and "light.latitude" in p.stderr and not os.path.exists(out + ".csv"),
          "zenith: " + p.stderr)

    # prisms: a wall per edge of the footprint, outline then holes; the zone none
    prisms = os.path.join(HERE, "prisms.json")
    pday = ["--date", "06-21", "--step", "30"]
    out = os.path.join(tmp, "prisms.csv")
    p = sylva("shade", prisms, *pday, "-o", out)
    check(p.returncode == 0, "prisms: " + p.stderr)
    with open(out) as f:
        rows = list(csv.DictReader(f))
    names = [s["surface"] for s in json.loads(p.stdout.strip().splitlines()[-1])["surfaces"]]
    want = ["ground"] + ["block:e%d" % e for e in range(10)] + ["kiosk:e%d" % e for e in range(4)]
    check(names == want, "prism surfaces: %s" % names)
    seen = []
    for r in rows:
        if not seen or seen[-1] != r["surface"]:
            seen.append(r["surface"])
    check(seen == want, "the CSV's surfaces in order: %s" % seen)
    by = {s["surface"]: s for s in json.loads(p.stdout.strip().splitlines()[-1])["surfaces"]}
    check(by["block:e8"]["sun_hours_open"] < by["block:e0"]["sun_hours_open"],
          "the courtyard's south-facing wall gets less sun than the outer one")
    court = [r for r in rows if r["surface"] == "block:e8"]
    check(len(court) == 8 * 12 and all(abs(float(r["y"]) - 6) < 1e-9 for r in court),
          "the courtyard's wall on its edge: %d cells" % len(court))
    out = os.path.join(tmp, "wall.csv")
    p = sylva("shade", prisms, *pday, "--surface", "kiosk:e2", "-o", out)
    check(p.returncode == 0, "--surface kiosk:e2: " + p.stderr)
    with open(out) as f:
        check({r["surface"] for r in csv.DictReader(f)} == {"kiosk:e2"}, "--surface e2 rows")
    p = sylva("shade", prisms, *pday, "-o", os.path.join(tmp, "prisms.png"))
    check(p.returncode == 0, "prisms' plan: " + p.stderr)
    for face, word in (("+x", "e0 to e3"), ("e4", "e0 to e3"), ("e01", "e0 to e3")):
        out = os.path.join(tmp, "bad.csv")
        p = sylva("shade", prisms, *pday, "--surface", "kiosk:" + face, "-o", out)
        check(p.returncode == 2 and word in p.stderr and not os.path.exists(out),
              "kiosk:%s: %d %s" % (face, p.returncode, p.stderr))

if failures:
    print("%d failed" % len(failures))
    sys.exit(1)
print("shade-cli: all passed")
