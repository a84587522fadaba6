#!/usr/bin/env python3
"""Fault injection: `sylva run --db`, `sylva resume` and `sylva export` under libfiu.

libfiu's POSIX preload library (what `fiu-run -x` loads; package fiu-utils)
makes pwrite, fdatasync/fsync, pread, open... fail at random with a seeded
probability (FIU_PRNG_SEED, so every case is reproducible). SQLite's unix VFS
calls these through the dynamic symbols, so the preload intercepts them: a
first check enables fdatasync failures unconditionally and requires the store
to report a disk I/O error. glibc's stdio writes stdout and stderr through
internal calls that libfiu does not see, so the messages always get out.

For every case:
- the process is not killed by a signal (exit 0, 1 or 2; no sanitizer report);
- on failure, stderr names the store file and says what failed;
- on success, stdout equals the clean run's lines (elapsed_ms aside); on
  failure, what was printed is a prefix of them;
- afterwards (without faults) PRAGMA integrity_check is ok, the stored
  iterations are a consecutive prefix 0..k that includes every iteration whose
  line was printed, and `sylva export --iteration T` of every stored T equals
  `sylva run --iterations T --export` of a clean run;
- the run then completes with `sylva resume` (or `sylva run` when the run was
  never created) and its last skeleton equals the clean one.
At least one failure must have come from inside SQLite (an I/O error or a full
disk reported for the store).

The sanitizer build (ASan first in LD_PRELOAD, libfiu's own leak suppressed)
runs every third case of each kind.
"""
import os
import sys
import time

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from store_common import (Checks, Env, crash_text, integrity, printed_iterations,  # noqa: E402
                          stored, strip_elapsed)

SNAPSHOT_EVERY = 3
ITERATIONS = 10
SQLITE_REASONS = ("disk I/O error", "database or disk is full", "unable to open database file")


def fiu_libs():
    """Directory of libfiu's preload libraries (as fiu-run finds them)."""
    dirs = []
    for d in os.environ.get("PATH", "").split(os.pathsep):
        script = os.path.join(d, "fiu-run")
        if os.path.isfile(script):
            with open(script, errors="replace") as f:
                for line in f:
                    if line.startswith("PLIBPATH="):
                        dirs.append(line.split("=", 1)[1].strip().strip('"'))
            break
    dirs += ["/usr/lib/fiu", "/usr/local/lib/fiu", "/usr/lib/x86_64-linux-gnu/fiu"]
    for d in dirs:
        if os.path.isfile(os.path.join(d, "fiu_posix_preload.so")):
            return d
    return None


class Fiu:
    def __init__(self, env, libdir):
        self.env = env
        preload = [os.path.join(libdir, "fiu_run_preload.so"),
                   os.path.join(libdir, "fiu_posix_preload.so")]
        self.base = dict(os.environ)
        if env.sanitized:
            # ASan must come first; fiu_run_preload keeps its FIU_ENABLE copy for good
            preload.insert(0, env.libasan)
            supp = env.path("lsan.supp")
            with open(supp, "w") as f:
                f.write("leak:fiu_run_preload.so\nleak:libfiu.so\n")
            lsan = self.base.get("LSAN_OPTIONS", "")
            self.base["LSAN_OPTIONS"] = ((lsan + ":" if lsan else "") + "suppressions=" + supp +
                                         ":print_suppressions=0")
        self.base["LD_PRELOAD"] = " ".join(preload)
        self.base["FIU_CTRL_FIFO"] = ""  # no remote control fifos

    def environ(self, enable, seed):
        e = dict(self.base)
        e["FIU_ENABLE"] = "\n".join(enable)
        e["FIU_PRNG_SEED"] = str(seed)
        return e


def main():
    env = Env(sys.argv)
    c = Checks()
    t_start = time.monotonic()
    try:
        libdir = fiu_libs()
        if not c.check(libdir is not None, "libfiu's preload libraries are installed "
                       "(Debian package fiu-utils; scripts/bootstrap installs it)"):
            c.finish()
        fiu = Fiu(env, libdir)
        scenario = env.scenario("stand.json")
        clean = [strip_elapsed(x) for x in env.clean_lines(scenario, ITERATIONS)]
        stats = {"cases": 0, "failed": 0, "in_sqlite": 0}
        probe(env, c, fiu, scenario)
        for n, (command, label, enable, seed) in enumerate(fault_cases(env.sanitized)):
            db = env.path("fault%d.db" % n)
            name = "f%d" % n
            what = "case %d (%s %s, seed %d)" % (n, command, " + ".join(
                e.split("name=")[1] for e in enable), seed)
            stats["cases"] += 1
            if command == "export":
                export_case(env, c, fiu, scenario, db, name, what, enable, seed, stats)
            else:
                grow_case(env, c, fiu, scenario, clean, command, db, name, what, enable, seed,
                          stats)
        print("%d cases, %d failed, %d of them inside SQLite" % (
            stats["cases"], stats["failed"], stats["in_sqlite"]), flush=True)
        c.check(stats["in_sqlite"] >= 1, "some failures came from inside SQLite",
                stats["in_sqlite"])
        c.check(stats["failed"] >= stats["cases"] // 3, "most cases failed somewhere",
                "%d of %d" % (stats["failed"], stats["cases"]))
    finally:
        env.cleanup()
    print("time %.1f s" % (time.monotonic() - t_start))
    c.finish()


def probe(env, c, fiu, scenario):
    """The preload intercepts SQLite's calls: fdatasync failing always is a disk I/O
    error of the store."""
    db = env.path("probe.db")
    rc, out, err = env.sylva("run", scenario, "--db", db, "--iterations", 2,
                             "--quiet-progress",
                             env=fiu.environ(["enable name=posix/io/sync/fdatasync",
                                              "enable name=posix/io/sync/fsync"], 1))
    c.check(rc in (1, 2) and db in err and "disk I/O error" in err and not crash_text(rc, err),
            "fdatasync failing always: the store reports a disk I/O error (libfiu "
            "intercepts SQLite's calls)", "exit %s: %s" % (rc, err))


def fault_cases(sanitized):
    """The cases, (command, label, libfiu's enable lines, seed): every third of each
    kind in the sanitizer build."""
    writes = ["enable_random name=posix/io/rw/pwrite,probability=%s"]
    syncs = ["enable_random name=posix/io/sync/*,probability=%s"]
    both = writes + syncs
    rw = ["enable_random name=posix/io/rw/*,probability=%s"]
    io = ["enable_random name=posix/io/*,probability=%s"]
    reads = ["enable_random name=posix/io/rw/pread,probability=%s"]
    cases = []
    for label, spec, probs in (("writes", writes, ("0.003", "0.01", "0.03")),
                               ("syncs", syncs, ("0.03", "0.1", "0.3")),
                               ("writes+syncs", both, ("0.005", "0.02", "0.05")),
                               ("all read/write", rw, ("0.005", "0.02")),
                               ("all I/O", io, ("0.005", "0.02"))):
        kind = []
        for p in probs:
            for seed in (1, 2, 3):
                kind.append(("run", label, [s % p for s in spec], seed))
        cases += kind[::3] if sanitized else kind
    kind = [("resume", "writes+syncs", [s % p for s in both], seed)
            for p in ("0.01", "0.05") for seed in (1, 2, 3)]
    cases += kind[::3] if sanitized else kind
    kind = [("export", "reads", [s % p for s in reads], seed)
            for p in ("0.005", "0.02", "0.1") for seed in (1, 2)]
    cases += kind[::3] if sanitized else kind
    return cases


def grow_case(env, c, fiu, scenario, clean, command, db, name, what, enable, seed, stats):
    """`sylva run` (or `sylva resume` of a clean first part) with faults: no crash; the
    clean lines, or a prefix of them and a message naming the store; then a sound
    store (check_store)."""
    start_k = -1
    if command == "run":
        args = ["run", scenario, "--db", db, "--name", name, "--snapshot-every",
                SNAPSHOT_EVERY, "--iterations", ITERATIONS, "--quiet-progress"]
    else:
        rc, _, err = env.sylva("run", scenario, "--db", db, "--name", name,
                               "--snapshot-every", SNAPSHOT_EVERY, "--iterations", 4,
                               "--quiet-progress")
        c.check(rc == 0, what + ": the clean first part", err)
        start_k = 4
        args = ["resume", "--db", db, "--name", name, "--iterations", ITERATIONS,
                "--quiet-progress"]
    rc, out, err = env.sylva(*args, env=fiu.environ(enable, seed))
    print("%s: exit %s%s" % (what, rc, (": " + err.strip().splitlines()[0]) if err.strip()
                             else ""), flush=True)
    crash = crash_text(rc, err)
    c.check(not crash and rc in (0, 1, 2), what + ": no crash, exit 0, 1 or 2",
            "exit %s: %s" % (rc, err))
    got = [strip_elapsed(x) for x in out.splitlines()]
    want = clean[start_k:] if start_k >= 0 else clean
    if rc == 0:
        c.check(got == want, what + ": exit 0 and the clean lines")
    else:
        stats["failed"] += 1
        c.check(got == want[:len(got)] and (not got or "done" not in got[-1]),
                what + ": failed; what it printed is a prefix of the clean lines")
        c.check(err.startswith("sylva: ") and (db in err or "store" in err),
                what + ": the message names the store", err)
        if any(r in err for r in SQLITE_REASONS):
            stats["in_sqlite"] += 1
        else:
            print("note: %s: exit %d: %s" % (what, rc, err.strip()), flush=True)
    check_store(env, c, scenario, db, name, what, printed_iterations(out), start_k)


def check_store(env, c, scenario, db, name, what, printed, start_k):
    """After a faulty run: the store is sound, every stored iteration reads back as the
    clean run's, and the run completes."""
    ok = integrity(db) if os.path.exists(db) else "ok"
    c.check(ok == "ok", what + ": integrity_check ok", ok)
    exists, its, _ = stored(db, name)
    k = its[-1] if its else -1
    c.check(its == list(range(k + 1)), what + ": the stored iterations are a prefix 0..%d" % k,
            its)
    c.check(not printed or printed[-1] <= k, what + ": every printed iteration is stored",
            "printed up to %s, stored up to %d" % (printed[-1:], k))
    c.check(k >= start_k, what + ": what was stored before is still there")
    print("%s: printed up to %s, stored up to %d" % (what, printed[-1] if printed else "-", k),
          flush=True)
    bad = []
    for t in its:
        rc, data, err = env.export(db, name, iteration=t)
        if rc != 0:
            bad.append("iteration %d: exit %s: %s" % (t, rc, err.strip()))
        elif t > 0 and data != env.clean_export(scenario, t):
            bad.append("iteration %d: another skeleton than the clean run's" % t)
    c.check(not bad, what + ": every stored iteration (0..%d) exports as the clean run" % k,
            "\n".join(bad))
    # complete the run without faults
    if exists:
        rc, out, err = env.sylva("resume", "--db", db, "--name", name, "--iterations",
                                 ITERATIONS, "--quiet-progress")
        want = env.clean_lines(scenario, ITERATIONS)[k:]
    else:
        rc, out, err = env.sylva("run", scenario, "--db", db, "--name", name,
                                 "--snapshot-every", SNAPSHOT_EVERY, "--iterations", ITERATIONS,
                                 "--quiet-progress")
        want = env.clean_lines(scenario, ITERATIONS)
    c.check(rc == 0 and [strip_elapsed(x) for x in out.splitlines()] ==
            [strip_elapsed(x) for x in want],
            what + ": then %s completes the run with the clean lines" %
            ("resume" if exists else "run"), "exit %s: %s" % (rc, err))
    rc, data, err = env.export(db, name)
    c.check(rc == 0 and data == env.clean_export(scenario, ITERATIONS),
            what + ": and its last skeleton is the clean one", "exit %s: %s" % (rc, err))


def export_case(env, c, fiu, scenario, db, name, what, enable, seed, stats):
    """`sylva export` with failing reads: the right skeleton or a clean failure."""
    rc, _, err = env.sylva("run", scenario, "--db", db, "--name", name, "--snapshot-every",
                           SNAPSHOT_EVERY, "--iterations", ITERATIONS, "--quiet-progress")
    c.check(rc == 0, what + ": the clean run", err)
    bad = []
    for t in (ITERATIONS, ITERATIONS - 2):  # a snapshot, and one regrown from 9
        out = env.path("fault-export.json")
        rc, data, err = env.export(db, name, iteration=t, out=out, env=fiu.environ(enable, seed))
        crash = crash_text(rc, err)
        if crash or rc not in (0, 1, 2):
            bad.append("iteration %d: %s" % (t, crash or "exit %s" % rc))
        elif rc == 0 and data != env.clean_export(scenario, t):
            bad.append("iteration %d: exit 0 with another skeleton" % t)
        elif rc != 0:
            stats["failed"] += 1
            if not (err.startswith("sylva: ") and (db in err or "store" in err)):
                bad.append("iteration %d: exit %d without naming the store: %s" % (t, rc, err))
            if any(r in err for r in SQLITE_REASONS):
                stats["in_sqlite"] += 1
            if os.path.exists(out) or os.path.exists(out + ".tmp"):
                bad.append("iteration %d: a failed export left a file" % t)
    c.check(not bad, what + ": the clean skeleton or a clean failure", "\n".join(bad))
    ok = integrity(db)
    c.check(ok == "ok", what + ": integrity_check ok", ok)


if __name__ == "__main__":
    main()
