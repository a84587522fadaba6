"""Stands that thin themselves (docs/model.md, "Stands"), through the real binary.

meson runs `python3 test_thinning.py SYLVA_EXE SCRIPTS_DIR TMPDIR`. The stand of
scripts/thinning (100 littleleaf lindens, utdb:NoEast:TICO, 2 m apart: 2,500 stems
per hectare) grows 60 years, seed 1:
- stems die, and ln N against ln QMD over the years it thins has a slope within
  -2.2 to -1.2 (Reineke 1933: about -1.6);
- the DBH's coefficient of variation at 40 years is within 0.15 to 0.5, and the
  heights differ (CV of height at least 0.05 at 20 and 40 years);
- the dominant height stays within 15% of the typical tree's grown alone in the open,
  at every decade;
- every stem line's alive and died agree with the stand's counts, a dead stem keeps
  its last measures, and a stem that died stays dead;
- the same seed gives the same lines (elapsed_ms aside), continuous or resumed from
  a store at 30 years (its first 30 years grown again alike).
Then 16 lindens 10 m apart (100 stems per hectare) grow 60 years and none dies.
"""
import importlib.machinery
import json
import math
import os
import re
import subprocess
import sys
import tempfile

sylva, scripts, tmp = sys.argv[1], sys.argv[2], sys.argv[3]
thinning = importlib.machinery.SourceFileLoader("thinning", os.path.join(scripts, "thinning")).load_module()
os.makedirs(tmp, exist_ok=True)
failures = []


def check(ok, what, detail=""):
    print(("ok   " if ok else "FAIL ") + what + (": " + detail if detail else ""))
    if not ok:
        failures.append(what)


def run(*args):
    return subprocess.run([sylva, *args], capture_output=True, text=True, check=True).stdout


def lines_of(text):
    return [json.loads(l) for l in text.splitlines() if l.startswith('{"iteration"')]


def strip(text):
    """The iteration lines without their elapsed_ms."""
    return [re.sub(r'"elapsed_ms": [0-9.]+', "", l) for l in text.splitlines()
            if l.startswith('{"iteration"')]


def write(name, scen):
    path = os.path.join(tmp, name)
    with open(path, "w") as f:
        json.dump(scen, f)
    return path


YEARS = 60
stand = write("stand.json", thinning.scenario("utdb:NoEast:TICO", {}, 10, 2.0, YEARS, 1))
text = run("run", stand, "--quiet-progress")
lines = lines_of(text)
check(len(lines) == YEARS, "the stand grows 60 years", str(len(lines)))
rows = [{"year": l["iteration"], "alive": l["stand"]["alive"], "n": l["stand"]["stems_per_ha"],
         "qmd": l["stand"]["qmd"]} for l in lines]
died = rows[0]["alive"] - rows[-1]["alive"]
check(rows[0]["alive"] == 100 and died > 0, "stems die", "%d of 100" % died)
check(abs(lines[0]["stand"]["stems_per_ha"] - 2506) < 5, "2,500 stems per hectare at planting",
      str(lines[0]["stand"]["stems_per_ha"]))
slope = thinning.slope(rows)
check(slope is not None and -2.2 <= slope <= -1.2, "self-thinning slope within -2.2 to -1.2",
      "%.3f" % slope if slope is not None else "none")
at = {l["iteration"]: l["stand"] for l in lines}
check(0.15 <= at[40]["cv_dbh"] <= 0.5, "DBH CV at 40 years within 0.15 to 0.5", str(at[40]["cv_dbh"]))
check(at[20]["cv_height"] >= 0.05 and at[40]["cv_height"] >= 0.05, "heights differ (CV >= 0.05)",
      "%s, %s" % (at[20]["cv_height"], at[40]["cv_height"]))

# the typical tree alone, as the calibration grows it
lone = write("lone.json", thinning.scenario("utdb:NoEast:TICO", {"vigour_spread": 0, "stock_spread": 0},
                                            1, 2.0, YEARS, 1))
open_h = {l["iteration"]: l["stems"][0]["height"] for l in lines_of(run("run", lone, "--quiet-progress"))}
worst = max(abs(at[y]["dominant_height"] / open_h[y] - 1) for y in range(10, YEARS + 1, 10))
check(worst <= 0.15, "dominant height within 15% of the open-grown tree's at every decade",
      "largest %.3f" % worst)

# the stems' lines against the stand's counts; the dead keep their last measures
consistent, kept, stays = True, True, True
last = {}
for l in lines:
    alive = sum(1 for s in l["stems"] if s["alive"])
    now = sum(1 for s in l["stems"] if s["died"] == l["iteration"])
    consistent &= alive == l["stand"]["alive"] and now == l["stand"]["died"]
    for s in l["stems"]:
        key = s["plant"]
        if key in last and not last[key]["alive"]:
            stays &= not s["alive"] and s["died"] == last[key]["died"]
            kept &= all(s[k] == last[key][k] for k in ("height", "dbh", "crown_width", "leaf_area"))
        last[key] = s
check(consistent, "stems' alive and died agree with the stand's alive and died")
check(stays, "a dead stem stays dead, with the year it died")
check(kept, "a dead stem keeps its last measures")

# same seed, same lines: resumed from a store
db = os.path.join(tmp, "stand.db")
if os.path.exists(db):
    os.unlink(db)
first = run("run", stand, "--db", db, "--name", "s", "--iterations", "30", "--quiet-progress")
rest = run("resume", "--db", db, "--name", "s", "--iterations", str(YEARS), "--quiet-progress")
check(strip(first) + strip(rest) == strip(text),
      "resumed at 30 years, the lines of the continuous run")

# 100 stems per hectare: crowns meet late, no tree is suppressed to death
sparse = write("sparse.json", thinning.scenario("utdb:NoEast:TICO", {}, 4, 10.0, YEARS, 1))
end = lines_of(run("run", sparse, "--quiet-progress"))[-1]
check(end["stand"]["alive"] == 16 and all(s["alive"] for s in end["stems"]),
      "100 stems per hectare: none dies in 60 years", str(end["stand"]["alive"]))

print("%d failed" % len(failures))
sys.exit(1 if failures else 0)
