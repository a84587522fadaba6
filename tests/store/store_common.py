"""Shared helpers of the store tests (tests/store/test_*.py).

Every test is started by meson as `python3 test_x.py SYLVA_EXE SCENARIOS_DIR` and
drives the real binary. A check that fails is printed at once; the last line is
"N passed, N failed" and the exit status is 1 when anything failed.
"""
import json
import os
import re
import shutil
import sqlite3
import subprocess
import sys
import tempfile

CRASH_MARKERS = ("runtime error", "AddressSanitizer", "LeakSanitizer",
                 "UndefinedBehaviorSanitizer")
ELAPSED = re.compile(r'"elapsed_ms": [^,]*, ')

# Bounds every single call of the binary (the sanitizer build is ~5x slower).
CALL_TIMEOUT = 300


class Checks:
    def __init__(self):
        self.passed = 0
        self.failed = 0

    def check(self, ok, what, detail=""):
        if ok:
            self.passed += 1
        else:
            self.failed += 1
            msg = "FAIL: " + what
            if detail:
                msg += "\n    " + str(detail).strip().replace("\n", "\n    ")[:3000]
            print(msg, flush=True)
        return bool(ok)

    def finish(self):
        print("%d passed, %d failed" % (self.passed, self.failed), flush=True)
        sys.exit(1 if self.failed else 0)


class Env:
    """The binary, the scenarios and a private temporary directory."""

    def __init__(self, argv):
        if len(argv) < 3:
            sys.exit("usage: %s SYLVA_EXE SCENARIOS_DIR" % argv[0])
        self.exe = os.path.abspath(argv[1])
        self.scenarios = os.path.abspath(argv[2])
        self.tmp = tempfile.mkdtemp(prefix="sylva-store-test-")
        self.libasan = asan_runtime(self.exe)
        self.sanitized = self.libasan is not None
        self._clean = {}

    def scenario(self, name):
        return os.path.join(self.scenarios, name)

    def path(self, name):
        return os.path.join(self.tmp, name)

    def sylva(self, *args, env=None, timeout=CALL_TIMEOUT):
        """Runs sylva; returns (exit status, stdout, stderr) as text."""
        try:
            p = subprocess.run([self.exe] + [str(a) for a in args], capture_output=True,
                               timeout=timeout, env=env)
        except subprocess.TimeoutExpired:
            return None, "", "timed out after %d s" % timeout
        return (p.returncode, p.stdout.decode("utf-8", "replace"),
                p.stderr.decode("utf-8", "replace"))

    def clean_export(self, scenario, iterations, seed=None):
        """The skeleton of `sylva run SCENARIO --iterations T --export` (no store), cached."""
        key = (scenario, iterations, seed)
        if key not in self._clean:
            out = self.path("clean-%s-%d-%s.json" % (os.path.basename(scenario), iterations, seed))
            args = ["run", scenario, "--iterations", iterations, "--export", out,
                    "--quiet-progress"]
            if seed is not None:
                args += ["--seed", seed]
            rc, stdout, err = self.sylva(*args)
            if rc != 0:
                raise RuntimeError("clean run failed (%s): %s" % (rc, err))
            self._clean[key] = (read_bytes(out), stdout.splitlines())
        return self._clean[key][0]

    def clean_lines(self, scenario, iterations, seed=None):
        """The stdout lines of that clean run."""
        self.clean_export(scenario, iterations, seed)
        return self._clean[(scenario, iterations, seed)][1]

    def export(self, db, name, fmt="skeleton", iteration=None, out=None, env=None):
        """`sylva export`; returns (exit status, bytes written or None, stderr)."""
        out = out or self.path("export.out")
        if os.path.exists(out):
            os.remove(out)
        args = ["export", "--db", db, "--name", name, "--format", fmt, "-o", out]
        if iteration is not None:
            args += ["--iteration", iteration]
        rc, _, err = self.sylva(*args, env=env)
        data = read_bytes(out) if rc == 0 and os.path.exists(out) else None
        return rc, data, err

    def cleanup(self):
        shutil.rmtree(self.tmp, ignore_errors=True)


def asan_runtime(exe):
    """Path of the ASan runtime the binary links (None for a build without ASan)."""
    try:
        out = subprocess.run(["ldd", exe], capture_output=True, timeout=60).stdout.decode()
    except (OSError, subprocess.TimeoutExpired):
        out = ""
    for line in out.splitlines():
        if "libasan" in line and "=>" in line:
            path = line.split("=>")[1].split("(")[0].strip()
            if path:
                return path
    with open(exe, "rb") as f:
        if b"__asan_init" in f.read():
            return "libasan.so"
    return None


def read_bytes(path):
    with open(path, "rb") as f:
        return f.read()


def strip_elapsed(line):
    return ELAPSED.sub("", line)


def crash_text(rc, err):
    """Why (rc, stderr) is a crash, or None."""
    if rc is None:
        return err or "timed out"
    if rc < 0 or rc >= 128:
        return "crashed (exit status %d)" % rc
    for marker in CRASH_MARKERS:
        if marker in err:
            return "sanitizer report on stderr"
    return None


def db_files(db):
    return [db + suffix for suffix in ("", "-wal", "-shm", "-journal")]


def copy_db(db, dest):
    """Copies a store with its WAL and shared memory files as they are on disk."""
    for src, dst in zip(db_files(db), db_files(dest)):
        if os.path.exists(dst):
            os.remove(dst)
        if os.path.exists(src):
            shutil.copyfile(src, dst)


def query(db, sql, args=()):
    con = sqlite3.connect(db)
    try:
        return con.execute(sql, args).fetchall()
    finally:
        con.close()


def integrity(db):
    """PRAGMA integrity_check of a copy (so that the original keeps its WAL as the
    crash left it, for sylva to recover)."""
    copy = db + ".check"
    copy_db(db, copy)
    try:
        rows = query(copy, "PRAGMA integrity_check")
        return "ok" if rows == [("ok",)] else repr(rows)
    except sqlite3.Error as e:
        return "sqlite3: %s" % e
    finally:
        for f in db_files(copy):
            if os.path.exists(f):
                os.remove(f)


def run_id(con, name):
    row = con.execute("SELECT id FROM runs WHERE name = ?", (name,)).fetchone()
    return row[0] if row else None


def stored(db, name):
    """(run row exists, sorted stored iterations, iterations with a snapshot), read
    from a copy of the files."""
    copy = db + ".read"
    copy_db(db, copy)
    try:
        if not os.path.exists(copy):
            return False, [], []
        con = sqlite3.connect(copy)
        try:
            if not con.execute("SELECT 1 FROM sqlite_schema WHERE name = 'runs'").fetchall():
                return False, [], []
            run = run_id(con, name)
            if run is None:
                return False, [], []
            its = [r[0] for r in con.execute(
                "SELECT iteration FROM iterations WHERE run = ? ORDER BY iteration", (run,))]
            snaps = [r[0] for r in con.execute(
                "SELECT iteration FROM iterations WHERE run = ? AND snapshot IS NOT NULL"
                " ORDER BY iteration", (run,))]
            return True, its, snaps
        finally:
            con.close()
    finally:
        for f in db_files(copy):
            if os.path.exists(f):
                os.remove(f)


def stats_rows(db, name):
    """Every stats row of a run (without the run id), in order."""
    con = sqlite3.connect(db)
    try:
        run = run_id(con, name)
        return con.execute(
            "SELECT iteration, stem, plant, plant_stem, height, dbh, crown_width, crown_base,"
            " nodes, shed, light, cap, finished FROM stats WHERE run = ?"
            " ORDER BY iteration, stem", (run,)).fetchall()
    finally:
        con.close()


def iteration_rows(db, name):
    """(iteration, hash, nodes, snapshot) of every stored iteration of a run."""
    con = sqlite3.connect(db)
    try:
        run = run_id(con, name)
        return con.execute(
            "SELECT iteration, hash, nodes, snapshot FROM iterations WHERE run = ?"
            " ORDER BY iteration", (run,)).fetchall()
    finally:
        con.close()


def printed_iterations(stdout):
    """Iterations of the complete stats lines on stdout."""
    its = []
    for line in stdout.splitlines():
        m = re.match(r'\{"iteration": (\d+), ', line)
        if m and line.endswith("}"):
            its.append(int(m.group(1)))
    return its


def stand_scenario(env, iterations):
    """Writes a stand with background mortality and returns its path: six lindens of
    the library (utdb:NoEast:TICO) 6 m apart, a fifth of them dying a year, from 2030
    (seed 2: deaths at iterations 2, 3, 5, 7 and 8, one tree left at 10)."""
    doc = {"format": "sylva.scenario/1", "name": "stand with mortality", "seed": 2,
           "iterations": iterations, "start_year": 2030,
           "world": {"min": [0, 0, 0], "max": [30, 30, 20]},
           "species": {"ti": {"preset": "utdb:NoEast:TICO", "mortality": 0.2}},
           "plants": [{"id": p, "species": "ti", "roots": [[6 + 6 * (k % 3), 6 + 6 * (k // 3), 0]]}
                      for k, p in enumerate("abcdef")]}
    path = env.path("stand.json")
    with open(path, "w") as f:
        json.dump(doc, f)
    return path
