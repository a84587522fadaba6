#!/usr/bin/env python3
"""Crash test: SIGKILL `sylva run --db` / `sylva resume` of one run at random moments.

A reference run (stand.json, 14 iterations, --snapshot-every 3) is stored
uninterrupted in its own store. Then the same run is grown in another store by a
chain of processes, each killed with SIGKILL after a seeded random delay:
- 0 (the first two processes and now and then: before the first commit, or
  while a resume restores and regrows);
- once the line of one of the next iterations j is out (so j is committed),
  within the time of growing and committing iteration j + 1: for the first,
  fast iterations this is mostly inside a commit;
- around the estimated moment of the commit of one of the next iterations;
- uniform in 0..0.3 s (x5 in the sanitizer build);
until MIN_KILLS kills have happened; the last process is left to finish. (Should
a process finish before its kill, e.g. on a machine that got faster, that run is
checked like the others and another one is started, until MIN_KILLS.)
After every kill:
- PRAGMA integrity_check of the files as the kill left them (a copy, so that
  sylva itself recovers the WAL) is "ok";
- the stored iterations are a consecutive prefix 0..k, with a snapshot at 0 and
  at every multiple of --snapshot-every up to k, and stats rows for 1..k;
- every stats line the killed process printed is stored (k >= its iteration),
  the lines continue where the store was, and they equal the reference lines
  (elapsed_ms aside);
- the next process is `sylva resume`, or `sylva run --db` again when the kill
  came before the run's first commit.
The last process exits 0, silently on stderr, and prints exactly the reference
lines after the iteration it resumed from, and the done line. Then the skeleton
of the last iteration, the stats rows and the stored iterations (hash, nodes,
snapshot bytes) equal the reference store's, and `sylva runs` shows it finished.

SYLVA_CRASH_SEED sets the seed (default 2); SYLVA_CRASH_KILLS the number of kills
(default and minimum 20).
"""
import json
import os
import random
import signal
import subprocess
import sys
import time

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from store_common import (Checks, Env, copy_db, crash_text, db_files, integrity,  # noqa: E402
                          iteration_rows, printed_iterations, stats_rows, stored,
                          strip_elapsed)

SNAPSHOT_EVERY = 3
ITERATIONS = 14  # ~1.5 s uninterrupted in the release build, ~7 s in the sanitizer build
NAME = "crash"


class Reference:
    """The uninterrupted run, and timings to aim the kills."""

    def __init__(self, env, c, scenario):
        self.db = env.path("reference.db")
        t0 = time.monotonic()
        rc, out, err = env.sylva("run", scenario, "--db", self.db, "--name", NAME,
                                 "--snapshot-every", SNAPSHOT_EVERY, "--iterations", ITERATIONS,
                                 "--quiet-progress")
        self.time = time.monotonic() - t0
        if not c.check(rc == 0, "reference run exits 0", "exit %s: %s" % (rc, err)):
            c.finish()
        lines = out.splitlines()
        self.lines = [strip_elapsed(x) for x in lines]
        self.stems = len(self.lines[0].split('"stem": ')) - 1
        # step[i]: seconds to grow iteration i + 1
        self.step = [json.loads(x)["elapsed_ms"] / 1e3 for x in lines[:-1]]
        rc, self.export, err = env.export(self.db, NAME)
        c.check(rc == 0, "reference export", err)
        # the start of a process (store opened, run created, first iteration)
        t0 = time.monotonic()
        env.sylva("run", scenario, "--db", env.path("start.db"), "--iterations", 1,
                  "--quiet-progress")
        self.start = time.monotonic() - t0
        self.commit = max(0.0, (self.time - self.start - sum(self.step[1:])) /
                          (ITERATIONS - 1))
        print("reference run: %d iterations in %.2f s (start %.3f s, commit ~%.4f s)" % (
            ITERATIONS, self.time, self.start, self.commit), flush=True)

    def remaining(self, k, snaps):
        """Estimated seconds a resume needs from stored iteration k to the end."""
        base = max([s for s in snaps if s <= k] or [0])
        return sum(self.step[base:])

    def commit_time(self, k, snaps, j):
        """Estimated seconds from the start of a process at stored iteration k to its
        commit of iteration j."""
        base = max([s for s in snaps if s <= k] or [0])
        return self.start + sum(self.step[base:j]) + self.commit * (j - max(k, 0))


class Chain:
    """Counters over all the killed processes."""

    def __init__(self, seed, min_kills, slow):
        self.rng = random.Random(seed)
        self.min_kills = min_kills
        self.slow = slow
        self.kills = self.processes = self.before_first_commit = self.no_progress = 0
        self.kinds = {"zero": 0, "line": 0, "aimed": 0, "short": 0}


def grow_killed(env, c, ref, ch, scenario, db):
    """Grows one run in db through killed processes; returns True when it finished."""
    exists, its, snaps = False, [], []
    first = ch.processes
    while True:
        ch.processes += 1
        if ch.processes > 400:
            c.check(False, "the runs finish within 400 processes")
            return False
        k = its[-1] if its else -1
        if exists:
            cmd = ["resume", "--db", db, "--name", NAME, "--quiet-progress"]
        else:
            cmd = ["run", scenario, "--db", db, "--name", NAME, "--snapshot-every",
                   SNAPSHOT_EVERY, "--iterations", ITERATIONS, "--quiet-progress"]
        delay = after_line = kind = None
        if ch.kills < ch.min_kills:
            delay, after_line, kind = choose_kill(ref, ch, k, snaps, ch.processes - first <= 2)
        p, out, err = run_process(env, c, ch, cmd, delay, after_line)
        if p is None:
            return False
        if p.returncode != -signal.SIGKILL:
            return check_finished(c, ref, ch, cmd, k, p, out, err)
        ch.kills += 1
        ch.kinds[kind] += 1
        how = "%-6s delay %.3f s%s" % (
            kind, delay, " after line %d" % after_line if after_line is not None else "")
        exists, its, snaps = check_killed(c, ref, ch, cmd, db, k, out, err, how)


def choose_kill(ref, ch, k, snaps, early):
    """(delay, line to wait for or None, kind) of the kill of a process started at stored
    iteration k; early: one of a run's first two processes."""
    rng = ch.rng
    r = rng.random()
    # a target: one of the next iterations (mostly the next, so that the kills spread
    # over the whole run)
    j = max(k, 0) + 1
    while j < ITERATIONS and rng.random() < 0.3:
        j += 1
    after_line = None
    if early or r < 0.1:
        delay, kind = 0.0, "zero"
    elif j < ITERATIONS and r < 0.8:
        after_line = j
        delay, kind = rng.uniform(0, ref.step[j] + ref.commit), "line"
        if j + 1 == ITERATIONS:
            delay = min(delay, 0.8 * ref.step[j])
    elif r < 0.6:
        delay = ref.commit_time(k, snaps, j) * rng.uniform(0.7, 1.3)
        kind = "aimed"
    else:
        delay, kind = rng.uniform(0, 0.3 * ch.slow), "short"
    if after_line is None:
        # not longer than the process is likely to live: the kills must happen
        delay = min(delay, 0.8 * ref.remaining(k, snaps))
    return delay, after_line, kind


def run_process(env, c, ch, cmd, delay, after_line):
    """Runs sylva cmd, killed with SIGKILL after delay seconds (after its line of
    iteration after_line, if given; never if delay is None); returns (process, stdout,
    stderr), or None for the process when it did not end within 600 s."""
    # unbuffered: readline() below must not read ahead, because communicate()
    # reads the pipe itself and would never see what a buffer held (a lost line)
    p = subprocess.Popen([env.exe] + [str(a) for a in cmd], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, bufsize=0)
    head = b""
    if after_line is not None:
        while True:
            line = p.stdout.readline()
            head += line
            if not line or line.startswith(b'{"iteration": %d, ' % after_line):
                break
    if delay is not None:
        if delay > 0:
            time.sleep(delay)
        if p.poll() is None:
            p.send_signal(signal.SIGKILL)
    try:
        out, err = p.communicate(timeout=600)
    except subprocess.TimeoutExpired:
        p.kill()
        p.communicate()
        c.check(False, "process %d (%s) ends within 600 s" % (ch.processes, cmd[0]))
        return None, "", ""
    return p, (head + out).decode("utf-8", "replace"), err.decode("utf-8", "replace")


def check_finished(c, ref, ch, cmd, k, p, out, err):
    """The process that was not killed: exit 0, silent, exactly the reference lines
    after stored iteration k; returns whether it exited 0."""
    crash = crash_text(p.returncode, err)
    c.check(not crash and p.returncode == 0,
            "process %d (%s after %d) exits 0" % (ch.processes, cmd[0], k),
            "exit %s: %s" % (p.returncode, err))
    c.check(err == "", "process %d is silent on stderr" % ch.processes, err)
    want = ref.lines[k:] if k >= 0 else ref.lines
    got = [strip_elapsed(x) for x in out.splitlines()]
    c.check(got == want, "the last %s (from stored iteration %d) prints exactly the "
            "reference lines after it and the done line" % (cmd[0], k),
            "got %d lines, want %d" % (len(got), len(want)))
    if ch.kills < ch.min_kills:
        print("note: process %d finished before its kill" % ch.processes, flush=True)
    return p.returncode == 0


def check_killed(c, ref, ch, cmd, db, prev_k, out, err, how):
    """The store and the output after a kill of a process started at stored iteration
    prev_k (how: the kind of kill, for the log); returns stored(db, NAME)."""
    n = ch.kills
    ok = integrity(db)
    c.check(ok == "ok", "kill %d: integrity_check ok" % n, ok)
    exists, its, snaps = stored(db, NAME)
    if not exists:
        ch.before_first_commit += 1
    k = its[-1] if its else -1
    if k <= prev_k:
        ch.no_progress += 1
    print("kill %2d: %-6s from %2d, %s -> stored 0..%d" % (n, cmd[0], prev_k, how, k),
          flush=True)
    c.check(its == list(range(k + 1)),
            "kill %d: the stored iterations are a consecutive prefix 0..%d" % (n, k), its)
    want_snaps = [i for i in range(k + 1) if i % SNAPSHOT_EVERY == 0]
    c.check(all(s in snaps for s in want_snaps) and set(snaps) <= set(its),
            "kill %d: snapshots at 0 and every %d iterations" % (n, SNAPSHOT_EVERY),
            "snapshots %s of %s" % (snaps, its))
    if exists:
        rows = stats_of_copy(db)
        c.check([r[0] for r in rows] == [i for i in range(1, k + 1) for _ in range(ref.stems)],
                "kill %d: stats rows for iterations 1..%d" % (n, k))
    printed = printed_iterations(out)
    start = prev_k + 1 if cmd[0] == "resume" else 1
    c.check(printed == list(range(start, start + len(printed))),
            "kill %d: the lines printed continue at iteration %d" % (n, start), printed)
    c.check(not printed or printed[-1] <= k, "kill %d: every printed iteration is stored" % n,
            "printed up to %s, stored up to %d" % (printed[-1:], k))
    lines = [x for x in out.splitlines() if x.endswith("}")]
    c.check(all(strip_elapsed(x) == ref.lines[i - 1] for x, i in zip(lines, printed)),
            "kill %d: the printed lines equal the reference" % n)
    c.check(not crash_text(0, err), "kill %d: no sanitizer report" % n, err)
    return exists, its, snaps


def check_result(env, c, ref, db):
    rc, data, err = env.export(db, NAME)
    c.check(rc == 0 and data == ref.export,
            "the final skeleton equals the uninterrupted run's byte for byte",
            "exit %s: %s" % (rc, err))
    c.check(stats_rows(db, NAME) == stats_rows(ref.db, NAME),
            "the stats rows equal the uninterrupted run's")
    a, b = iteration_rows(db, NAME), iteration_rows(ref.db, NAME)
    c.check([r[:3] for r in a] == [r[:3] for r in b],
            "the stored iterations (hash, nodes) equal the uninterrupted run's")
    c.check([r[3] is None for r in a] == [r[3] is None for r in b],
            "snapshots at the same iterations as the uninterrupted run",
            [r[0] for r in a if r[3] is not None])
    c.check(a == b, "the snapshot images equal the uninterrupted run's byte for byte")
    rc, out, err = env.sylva("runs", "--db", db)
    row = out.splitlines()[1].split() if rc == 0 and len(out.splitlines()) > 1 else []
    c.check(row[:4] == [NAME, "finished", "limit", "%d/%d" % (ITERATIONS, ITERATIONS)],
            "runs: the run is finished", out + err)
    c.check(integrity(db) == "ok", "integrity_check ok at the end")


def stats_of_copy(db):
    """The stats rows of the files as they are (read from a copy)."""
    copy = db + ".stats"
    copy_db(db, copy)
    try:
        return stats_rows(copy, NAME)
    finally:
        for f in db_files(copy):
            if os.path.exists(f):
                os.remove(f)


def main():
    env = Env(sys.argv)
    c = Checks()
    t_start = time.monotonic()
    seed = int(os.environ.get("SYLVA_CRASH_SEED", "2"))
    ch = Chain(seed, max(20, int(os.environ.get("SYLVA_CRASH_KILLS", "20"))),
               5.0 if env.sanitized else 1.0)
    scenario = env.scenario("stand.json")
    try:
        ref = Reference(env, c, scenario)
        runs = 0
        while ch.kills < ch.min_kills and runs < 5:
            runs += 1
            db = env.path("crash%d.db" % runs)
            if not grow_killed(env, c, ref, ch, scenario, db):
                break
            check_result(env, c, ref, db)
        print("%d run(s), %d processes, %d kills (%d before the first commit, %d without "
              "progress; delays: %s), %.1f s" % (
                  runs, ch.processes, ch.kills, ch.before_first_commit, ch.no_progress,
                  ", ".join("%s %d" % kv for kv in ch.kinds.items()),
                  time.monotonic() - t_start), flush=True)
        c.check(ch.kills >= ch.min_kills, "at least %d kills" % ch.min_kills, ch.kills)
        c.check(ch.before_first_commit >= 1, "some kills came before the first commit")
        c.check(ch.kills - ch.before_first_commit >= ch.min_kills // 2,
                "most kills came after the run was created", ch.kills - ch.before_first_commit)
    finally:
        env.cleanup()
    print("time %.1f s" % (time.monotonic() - t_start))
    c.finish()


if __name__ == "__main__":
    main()
