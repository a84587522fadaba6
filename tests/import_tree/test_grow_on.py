#!/usr/bin/env python3
"""A measured tree grown on beside a wall (issue 21, docs/scenario.md "Plants",
docs/model.md "Measured trees"): a scenario plant `from` an ITSMe TreeQSM file stands
at its root as imported; after 12 seasons the measured part is unchanged except radii
(which never shrink), every new node descends from a bud of the measured tree (a tip
or a node bearing leaves: born within leaf_age seasons), no node is inside the wall,
and a run stopped at 6 and resumed exports the same bytes as the continuous one.
A `from` file that is missing, a tree reaching into an obstacle and a tree reaching
out of the world are refused by validate and run with a named error.

  test_grow_on.py SYLVA DATA_DIR
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile

SYLVA, DATA = sys.argv[1], sys.argv[2]
FILE = "non_buttressed_trees_single_qsm_tree_1_qsm.mat"
WALL = {"id": "wall", "kind": "box", "min": [1.0, -12, 0], "max": [1.5, 12, 14]}
failures = 0
checks = 0


def check(ok, what):
    global failures, checks
    checks += 1
    if not ok:
        failures += 1
        print("FAIL:", what)


def scenario(iterations, plant_extra=None, wall=WALL):
    plant = {"id": "scanned", "species": "plane", "roots": [[0, 0, 0]],
             "from": {"file": "tree.mat", "age": 30}}
    plant.update(plant_extra or {})
    return {"format": "sylva.scenario/1", "name": "measured", "seed": 3,
            "iterations": iterations, "start_year": 2027,
            "world": {"min": [-12, -12, 0], "max": [12, 12, 30]},
            "species": {"plane": {"preset": "utdb:NoEast:PLAC"}},
            "plants": [plant], "obstacles": [wall] if wall else []}


def sylva(*args, ok=True):
    r = subprocess.run([SYLVA, *args], capture_output=True, text=True)
    if ok and r.returncode != 0:
        raise SystemExit("sylva %s: %s" % (" ".join(args), r.stderr))
    return r


def nodes_of(path):
    with open(path) as f:
        sk = json.load(f)
    out = {}
    for pl in sk["plants"]:
        for st in pl["stems"]:
            for n in st["nodes"]:
                out[n[0]] = n
    return out


def main():
    tmp = tempfile.mkdtemp(prefix="sylva-grow-on-")
    try:
        shutil.copy(os.path.join(DATA, FILE), os.path.join(tmp, "tree.mat"))
        scen = os.path.join(tmp, "s.json")
        with open(scen, "w") as f:
            json.dump(scenario(12), f)
        db = os.path.join(tmp, "run.db")
        sylva("run", scen, "--db", db, "--quiet-progress")
        first, last = os.path.join(tmp, "t0.json"), os.path.join(tmp, "t12.json")
        sylva("export", "--db", db, "--name", "measured", "--iteration", "0", "--format", "skeleton", "-o", first)
        sylva("export", "--db", db, "--name", "measured", "--format", "skeleton", "-o", last)
        a, b = nodes_of(first), nodes_of(last)
        imported = subprocess.run([SYLVA, "import", os.path.join(tmp, "tree.mat"), "--age", "30",
                                   "-o", os.path.join(tmp, "imp.json")], capture_output=True, text=True)
        check(imported.returncode == 0, "sylva import: %s" % imported.stderr)
        summary = json.loads(imported.stdout)
        check(len(a) == summary["nodes"], "the plant holds the import's %d nodes at iteration 0 (got %d)"
              % (summary["nodes"], len(a)))
        # dated on the same curve: the run's iteration 0 carries the import's births
        births = sorted(n[6] for n in nodes_of(os.path.join(tmp, "imp.json")).values())
        check(births == sorted(n[6] for n in a.values()),
              "the scenario's plant and `sylva import` give the same births")
        # the measured part: kept (not shed here) with its position, parent and birth; radii >= measured
        kept = [i for i in a if i in b]
        check(len(kept) == len(a), "every measured node is still there (%d of %d)" % (len(kept), len(a)))
        moved = [i for i in kept if a[i][1:5] != b[i][1:5] or a[i][6] != b[i][6]]
        check(not moved, "measured nodes unchanged but radii (%d changed)" % len(moved))
        thinner = [i for i in kept if b[i][5] < a[i][5]]
        check(not thinner, "no measured radius shrinks (%d did)" % len(thinner))
        grown = [i for i in b if i not in a]
        check(len(grown) > 20, "the tree grows on: %d new nodes in 12 seasons" % len(grown))
        # new growth from buds: each new node's first measured ancestor is a tip or bears leaves
        children = {}
        for n in a.values():
            children.setdefault(n[1], []).append(n[0])
        leaf_age = 3
        buds = {i for i, n in a.items() if n[6] >= -leaf_age or i not in children}
        bad = 0
        for i in grown:
            p = b[i][1]
            while p in b and p not in a:
                p = b[p][1]
            bad += p not in buds
        check(bad == 0, "every new shoot starts at a bud of the measured tree (%d do not)" % bad)
        # the wall
        inside = [i for i, n in b.items()
                  if WALL["min"][0] <= n[2] <= WALL["max"][0] and WALL["min"][2] <= n[4] <= WALL["max"][2]]
        check(not inside, "no node inside the wall (%d are)" % len(inside))
        # resume byte for byte
        db2 = os.path.join(tmp, "resumed.db")
        with open(scen, "w") as f:
            json.dump(scenario(6), f)
        sylva("run", scen, "--db", db2, "--quiet-progress")
        sylva("resume", "--db", db2, "--name", "measured", "--iterations", "12", "--quiet-progress")
        again = os.path.join(tmp, "r12.json")
        sylva("export", "--db", db2, "--name", "measured", "--format", "skeleton", "-o", again)
        with open(last, "rb") as f1, open(again, "rb") as f2:
            check(f1.read() == f2.read(), "resumed at 6 and grown to 12: the same skeleton bytes")
        # bad input: a missing file, a tree in a wall, validate names them; nothing stored
        for extra, wall, words in (
                ({"from": {"file": "nowhere.mat"}}, WALL, ["/plants/0/from", "nowhere.mat"]),
                ({}, {"id": "w", "kind": "box", "min": [-0.5, -0.5, 5], "max": [0.5, 0.5, 6]},
                 ["/plants/0/from", "node", "obstacle"]),
                ({"roots": [[0, 0, 10]]}, WALL, ["/plants/0/from", "node", "outside the world"])):
            bad_scen = os.path.join(tmp, "bad.json")
            with open(bad_scen, "w") as f:
                json.dump(scenario(3, extra, wall), f)
            for cmd in (["validate", bad_scen], ["run", bad_scen, "--db", os.path.join(tmp, "bad.db")]):
                r = sylva(*cmd, ok=False)
                check(r.returncode == 2, "%s: exit 2 (got %d)" % (cmd[0], r.returncode))
                check(all(w in r.stderr for w in words), "%s names %s: %s" % (cmd[0], words, r.stderr.strip()))
            check(not os.path.exists(os.path.join(tmp, "bad.db")) or
                  "measured" not in sylva("runs", "--db", os.path.join(tmp, "bad.db"), ok=False).stdout,
                  "nothing stored for a refused scenario")
    finally:
        shutil.rmtree(tmp)
    print("grow-on: %d passed, %d failed" % (checks - failures, failures))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
