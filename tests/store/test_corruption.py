#!/usr/bin/env python3
"""Corrupt snapshots: `sylva export` and `sylva resume` fall back to an earlier good
snapshot and regrow, or fail cleanly; never a crash.

A run of stand.json (10 iterations, --snapshot-every 2: snapshots at 0, 2, 4,
6, 8, 10) is stored once; every case works on a fresh copy of that store and
changes it with python's sqlite3:
- the last snapshot damaged in several ways (bits flipped in the middle of the
  payload, in the magic, the version, the size and the checksum of the header;
  truncated; empty; random bytes; the valid image of another iteration; the
  valid image of the same iteration of another run, which only the stored world
  hash can tell):
  `sylva export` of the last iteration (with and without --iteration) exits 0,
  warns on stderr naming the corrupt iteration, and writes exactly the clean
  skeleton;
- every snapshot but iteration 0's damaged: export of iterations 10 and 5
  regrows from 0, warns for each damaged snapshot on the way, same skeletons;
- every snapshot damaged: export exits 1 with a clear message; the CSV (stats
  only) and `sylva runs` still work;
- `sylva resume --iterations 12` with the last snapshot, or all but 0,
  damaged: warns, prints exactly the clean lines 11, 12 and the done line, and
  the final skeleton is the clean one; with every snapshot damaged it exits 1
  and leaves the run as it was;
- a stored world hash that disagrees with the regrown world: exit 1 naming the
  iteration (the regrowth is checked against the store);
- the store file truncated: exit 1 or 2 with a message (or, if SQLite never
  needs the lost pages, the clean output).
Every call: exit 0, 1 or 2, and no sanitizer report.
"""
import os
import random
import shutil
import sqlite3
import sys
import time

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from store_common import (Checks, Env, crash_text, integrity, query,  # noqa: E402
                          strip_elapsed)

NAME = "cor"
ITERATIONS = 10
SNAPSHOTS = [0, 2, 4, 6, 8, 10]


def flip(data, positions):
    b = bytearray(data)
    for p in positions:
        b[p] ^= 0x5A
    return bytes(b)


def warned(err, its):
    return all("snapshot of iteration %d is corrupt" % i in err for i in its)


class Store:
    """The pristine store of the run to corrupt, fresh copies of it to damage, and
    calls of sylva that must not crash."""

    def __init__(self, env, c, rng, pristine):
        self.env, self.c, self.rng, self.pristine = env, c, rng, pristine
        self.n = 0

    def fresh(self):
        self.n += 1
        db = self.env.path("case%d.db" % self.n)
        shutil.copyfile(self.pristine, db)
        return db

    def blob(self, db, it):
        return query(db, "SELECT snapshot FROM iterations WHERE iteration = ?", (it,))[0][0]

    def set_blob(self, db, it, data):
        con = sqlite3.connect(db)
        con.execute("UPDATE iterations SET snapshot = ? WHERE iteration = ?", (data, it))
        con.commit()
        con.close()

    def damage(self, db, it):
        """Bits flipped in the middle of the payload and one in the header."""
        data = self.blob(db, it)
        mid = len(data) // 2
        self.set_blob(db, it, flip(data, [mid, mid + 1, mid + 7,
                                          self.rng.randrange(32, len(data))]))

    def sylva(self, *args):
        rc, out, err = self.env.sylva(*args)
        crash = crash_text(rc, err)
        self.c.check(not crash and rc in (0, 1, 2), "no crash: sylva %s" % " ".join(
            os.path.basename(str(a)) for a in args[:1] + args[3:]), crash or err)
        return rc, out, err

    def export(self, db, iteration=None, fmt="skeleton"):
        rc, data, err = self.env.export(db, NAME, fmt=fmt, iteration=iteration)
        crash = crash_text(rc, err)
        self.c.check(not crash and rc in (0, 1, 2), "no crash: export", crash or err)
        return rc, data, err


def main():
    env = Env(sys.argv)
    c = Checks()
    t_start = time.monotonic()
    rng = random.Random(2017)
    scenario = env.scenario("stand.json")
    try:
        pristine = env.path("pristine.db")
        other10 = store_runs(env, c, scenario, pristine)
        st = Store(env, c, rng, pristine)
        clean10 = env.clean_export(scenario, ITERATIONS)
        last_snapshot_damaged(st, clean10, other10)
        all_but_0 = all_but_0_damaged(st, scenario, clean10)
        all_damaged = every_snapshot_damaged(st)
        resume_falls_back(st, scenario, all_but_0, all_damaged)
        wrong_hash(st, clean10)
        truncated_file(st, clean10)
    finally:
        env.cleanup()
    print("time %.1f s" % (time.monotonic() - t_start))
    c.finish()


def store_runs(env, c, scenario, pristine):
    """Stores the run to corrupt in pristine, and one of another seed; returns that
    one's snapshot of iteration 10."""
    rc, out, err = env.sylva("run", scenario, "--db", pristine, "--name", NAME,
                             "--snapshot-every", 2, "--iterations", ITERATIONS,
                             "--quiet-progress")
    if not c.check(rc == 0, "the run to corrupt", "exit %s: %s" % (rc, err)):
        c.finish()
    snaps = [r[0] for r in query(pristine, "SELECT iteration FROM iterations WHERE"
                                 " snapshot IS NOT NULL ORDER BY iteration")]
    c.check(snaps == SNAPSHOTS, "snapshots at %s" % SNAPSHOTS, snaps)
    other_db = env.path("other.db")
    rc, out, err = env.sylva("run", scenario, "--db", other_db, "--name", NAME, "--seed", 99,
                             "--snapshot-every", 2, "--iterations", ITERATIONS,
                             "--quiet-progress")
    c.check(rc == 0, "a run of another seed", "exit %s: %s" % (rc, err))
    return query(other_db, "SELECT snapshot FROM iterations WHERE iteration = 10")[0][0]


def last_snapshot_damaged(st, clean10, other10):
    """The last snapshot damaged in several ways: export of the last iteration writes
    the clean skeleton and warns about iteration 10 only."""
    c = st.c
    last = st.blob(st.pristine, 10)
    ways = [
        ("bits in the middle", lambda b: flip(b, [len(b) // 2, len(b) // 2 + 3])),
        ("one bit near the end", lambda b: flip(b, [len(b) - 5])),
        ("the magic", lambda b: flip(b, [0])),
        ("the version", lambda b: flip(b, [8])),
        ("the size", lambda b: flip(b, [17])),
        ("the checksum", lambda b: flip(b, [24])),
        ("header and middle", lambda b: flip(b, [3, 12, len(b) // 2])),
        ("truncated", lambda b: b[:len(b) // 2]),
        ("only the header", lambda b: b[:32]),
        ("empty", lambda b: b""),
        ("random bytes", lambda b: bytes(st.rng.randrange(256) for _ in range(len(b)))),
        ("the image of iteration 8", lambda b: st.blob(st.pristine, 8)),
        ("a valid image of another run's iteration 10", lambda b: other10),
    ]
    for label, how in ways:
        db = st.fresh()
        st.set_blob(db, 10, how(last))
        for it in (None, 10):
            rc, data, err = st.export(db, it)
            c.check(rc == 0 and data == clean10,
                    "last snapshot damaged (%s): export%s writes the clean skeleton" %
                    (label, "" if it is None else " --iteration 10"),
                    "exit %s: %s" % (rc, err))
            c.check("warning" in err and warned(err, [10]) and db in err,
                    "last snapshot damaged (%s): a warning names iteration 10" % label, err)
            c.check(not warned(err, [8]),
                    "last snapshot damaged (%s): no warning about iteration 8" % label, err)


def all_but_0_damaged(st, scenario, clean10):
    """Every snapshot but 0 damaged: export regrows from 0 and warns for each damaged
    snapshot on the way; returns the store."""
    c = st.c
    db = st.fresh()
    for it in SNAPSHOTS[1:]:
        st.damage(db, it)
    rc, data, err = st.export(db)
    c.check(rc == 0 and data == clean10,
            "all snapshots but 0 damaged: export regrows from 0, the clean skeleton",
            "exit %s: %s" % (rc, err))
    c.check(warned(err, SNAPSHOTS[1:]), "a warning for each damaged snapshot", err)
    rc, data, err = st.export(db, 5)
    c.check(rc == 0 and data == st.env.clean_export(scenario, 5) and warned(err, [4, 2]) and
            not warned(err, [6, 8, 10]),
            "all but 0 damaged: export --iteration 5 regrows from 0, warns for 4 and 2",
            "exit %s: %s" % (rc, err))
    return db


def every_snapshot_damaged(st):
    """Every snapshot damaged: export exits 1 with a clear message; the CSV and `sylva
    runs` still work; returns the store."""
    c = st.c
    db = st.fresh()
    for it in SNAPSHOTS:
        st.damage(db, it)
    for it in (None, 0, 5):
        rc, data, err = st.export(db, it)
        c.check(rc == 1 and data is None and "no good snapshot" in err and db in err,
                "all snapshots damaged: export%s exits 1, says there is no good snapshot" %
                ("" if it is None else " --iteration %d" % it), "exit %s: %s" % (rc, err))
        c.check(not os.path.exists(st.env.path("export.out.tmp")),
                "all snapshots damaged: no partial output left")
    rc, data, err = st.export(db, fmt="csv")
    rc0, data0, _ = st.export(st.pristine, fmt="csv")
    c.check(rc == 0 and data == data0, "all snapshots damaged: the CSV still exports",
            "exit %s: %s" % (rc, err))
    rc, out, err = st.sylva("runs", "--db", db)
    c.check(rc == 0 and NAME in out, "all snapshots damaged: runs still lists the run",
            err)
    return db


def resume_falls_back(st, scenario, all_but_0, all_damaged):
    """`sylva resume --iterations 12` with the last snapshot, or all but 0, damaged:
    warns, the clean lines and skeleton; with every snapshot damaged: exit 1, the run
    as it was."""
    c, env = st.c, st.env
    clean12 = [strip_elapsed(x) for x in env.clean_lines(scenario, 12)]
    db = st.fresh()
    st.damage(db, 10)
    cases = [("last snapshot damaged", db, [10]), ("all but 0 damaged", all_but_0,
                                                    SNAPSHOTS[1:])]
    for label, db, its in cases:
        rc, out, err = st.sylva("resume", "--db", db, "--name", NAME, "--iterations", 12,
                                "--quiet-progress")
        c.check(rc == 0 and [strip_elapsed(x) for x in out.splitlines()] == clean12[10:],
                "%s: resume --iterations 12 prints the clean lines 11, 12 and done" % label,
                "exit %s: %s\n%s" % (rc, err, out[:500]))
        c.check(warned(err, its), "%s: resume warns for each damaged snapshot" % label,
                err)
        rc, data, err = st.export(db)
        c.check(rc == 0 and data == env.clean_export(scenario, 12),
                "%s: after resume, the last skeleton is the clean one" % label,
                "exit %s: %s" % (rc, err))
        c.check(integrity(db) == "ok", "%s: integrity_check ok after resume" % label)
    db = all_damaged
    before = query(db, "SELECT * FROM runs"), query(db, "SELECT count(*) FROM iterations")
    rc, out, err = st.sylva("resume", "--db", db, "--name", NAME, "--iterations", 12,
                            "--quiet-progress")
    c.check(rc == 1 and out == "" and "no good snapshot" in err,
            "all snapshots damaged: resume exits 1, says there is no good snapshot",
            "exit %s: %s" % (rc, err))
    c.check((query(db, "SELECT * FROM runs"), query(db, "SELECT count(*) FROM iterations")) ==
            before, "all snapshots damaged: the failed resume changed nothing")


def wrong_hash(st, clean10):
    """A stored world hash that disagrees with the regrown world: exit 1 naming the
    iteration (the regrowth is checked against the store)."""
    c = st.c
    db = st.fresh()
    con = sqlite3.connect(db)
    con.execute("UPDATE iterations SET hash = hash + 1 WHERE iteration = 9")
    con.commit()
    con.close()
    rc, data, err = st.export(db, 10)
    c.check(rc == 0 and data == clean10,
            "a wrong hash of iteration 9 does not matter when 10 is restored directly",
            "exit %s: %s" % (rc, err))
    rc, data, err = st.export(db, 9)
    c.check(rc == 1 and data is None and "iteration 9" in err and
            "another world" in err,
            "a wrong hash of iteration 9: export --iteration 9 exits 1 naming it",
            "exit %s: %s" % (rc, err))
    st.damage(db, 10)
    rc, data, err = st.export(db, 10)
    c.check(rc == 1 and data is None and "iteration 9" in err,
            "a wrong hash of 9 and 10 damaged: export of 10 exits 1 (regrowth checked)",
            "exit %s: %s" % (rc, err))


def truncated_file(st, clean10):
    """The store file truncated: exit 1 or 2 with a message (or, if SQLite never needs
    the lost pages, the clean output)."""
    c, env = st.c, st.env
    size = os.path.getsize(st.pristine)
    trunc = env.path("trunc.json")
    for cut in (100, 4096, size // 3, size // 2, size - 4096):
        db = st.fresh()
        with open(db, "r+b") as f:
            f.truncate(cut)
        for args in (["runs", "--db", db],
                     ["export", "--db", db, "--name", NAME, "--format", "skeleton", "-o", trunc],
                     ["resume", "--db", db, "--name", NAME, "--quiet-progress"]):
            if os.path.exists(trunc):
                os.remove(trunc)
            rc, out, err = st.sylva(*args)
            ok = rc in (1, 2) and err.startswith("sylva: ") and db in err
            if rc == 0 and args[0] == "export":
                ok = open(trunc, "rb").read() == clean10
            elif rc == 0 and args[0] == "runs":
                ok = NAME in out
            elif rc == 0:
                ok = out == '{"done": true, "iterations": 10, "reason": "limit"}\n'
            c.check(ok, "file truncated to %d of %d bytes: %s fails cleanly or works" %
                    (cut, size, args[0]), "exit %s: %s" % (rc, err))
            print("truncated to %d of %d bytes: %s: exit %d%s" % (
                cut, size, args[0], rc, (": " + err.strip().splitlines()[-1]) if err.strip()
                else ""), flush=True)


if __name__ == "__main__":
    main()
