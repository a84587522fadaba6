#!/usr/bin/env python3
"""Replays input corpora through `sylva validate`.

- every tests/fuzz/bad/*.json, through `sylva validate` and `sylva run` alike:
  exit status exactly 2, and stderr contains each substring listed for the file
  in bad/EXPECT.tsv (file<TAB>substring[<TAB>...]);
- every JSONTestSuite file (none is a scenario): exit status 2;
- every scenarios/*.json: exit status 0 and "ok: ..." on stdout; the test
  scenario of years (tests/scenario/years.json) too, naming its start year;
- truncated and byte-flipped copies of the scenarios (a fixed pseudo-random
  sample): exit status 0 or 2.
Nothing may crash: a signal, an exit status >= 128, or sanitizer text on stderr
is a failure. Prints every failure, then "N passed, N failed".
"""
import argparse
import concurrent.futures
import os
import random
import subprocess
import sys
import tempfile

CRASH_MARKERS = ("runtime error", "AddressSanitizer", "LeakSanitizer", "UndefinedBehaviorSanitizer")


def run_validate(sylva, path, command=("validate",)):
    try:
        proc = subprocess.run([sylva, *command, path], capture_output=True, timeout=60)
    except subprocess.TimeoutExpired:
        return None, "", "timed out after 60 s"
    return (proc.returncode, proc.stdout.decode("utf-8", "replace"),
            proc.stderr.decode("utf-8", "replace"))


def crash_text(rc, err):
    if rc is None:
        return err
    if rc < 0 or rc >= 128:
        return "crashed (exit status %d)" % rc
    for marker in CRASH_MARKERS:
        if marker in err:
            return "sanitizer report on stderr"
    return None


# `sylva run` reads a scenario as validate does; one iteration at most, should a
# bad file get through.
BAD_COMMANDS = (("validate",), ("run", "--iterations", "1"))


def check_bad(sylva, path, expected):
    for command in BAD_COMMANDS:
        rc, _out, err = run_validate(sylva, path, command)
        crash = crash_text(rc, err)
        if crash:
            problem = "%s\n    stderr: %s" % (crash, err.strip()[:2000])
        elif rc != 2:
            problem = "exit status %s, expected 2\n    stderr: %s" % (rc, err.strip())
        elif any(s not in err for s in expected):
            problem = "stderr lacks %r\n    stderr: %s" % (
                [s for s in expected if s not in err], err.strip())
        elif not err.startswith("sylva: "):
            problem = "stderr does not start with 'sylva: '\n    stderr: %s" % err.strip()
        else:
            continue
        return "sylva %s: %s" % (command[0], problem)
    return None


def check_not_scenario(sylva, path):
    rc, _out, err = run_validate(sylva, path)
    crash = crash_text(rc, err)
    if crash:
        return "%s\n    stderr: %s" % (crash, err.strip()[:2000])
    if rc != 2:
        return "exit status %s, expected 2\n    stderr: %s" % (rc, err.strip()[:500])
    return None


def check_good(sylva, path, says=""):
    """Exit status 0 and "ok: ..." (holding `says`) on stdout."""
    rc, out, err = run_validate(sylva, path)
    crash = crash_text(rc, err)
    if crash:
        return "%s\n    stderr: %s" % (crash, err.strip()[:2000])
    if rc != 0 or not out.startswith("ok: ") or says not in out:
        return "exit status %s, expected 0 and 'ok: ...'\n    stdout: %s\n    stderr: %s" % (
            rc, out.strip(), err.strip())
    return None


def check_mutant(sylva, path):
    rc, _out, err = run_validate(sylva, path)
    crash = crash_text(rc, err)
    if crash:
        return "%s\n    stderr: %s" % (crash, err.strip()[:2000])
    if rc not in (0, 2):
        return "exit status %s, expected 0 or 2\n    stderr: %s" % (rc, err.strip()[:500])
    return None


def load_expect(bad_dir):
    expect = {}
    with open(os.path.join(bad_dir, "EXPECT.tsv"), encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            line = line.rstrip("\n")
            if not line or line.startswith("#"):
                continue
            fields = line.split("\t")
            if len(fields) < 2 or not all(fields):
                raise SystemExit("EXPECT.tsv:%d: expected file<TAB>substring" % number)
            expect[fields[0]] = fields[1:]
    return expect


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("sylva")
    ap.add_argument("--bad", required=True)
    ap.add_argument("--suite", required=True)
    ap.add_argument("--scenarios", required=True)
    args = ap.parse_args()

    jobs = []  # (label, function, arguments)
    failures = []  # (label, problem)
    bad_jobs(args.bad, jobs, failures)
    suite_jobs(args.suite, jobs, failures)
    tmp = tempfile.TemporaryDirectory(prefix="sylva-fuzz-")
    scenario_jobs(args.scenarios, tmp.name, jobs, failures)
    years = os.path.join(args.scenarios, os.pardir, "tests", "scenario", "years.json")
    jobs.append(("tests/scenario/years.json", check_good, (years, ", start year 2027, ")))
    passed = run_jobs(args.sylva, jobs, failures)
    tmp.cleanup()

    for label, problem in failures:
        print("FAIL %s: %s" % (label, problem))
    print("%d passed, %d failed" % (passed, len(failures)))
    return 1 if failures else 0


def bad_jobs(bad_dir, jobs, failures):
    """Every bad/*.json with its line of EXPECT.tsv, and every line with its file."""
    expect = load_expect(bad_dir)
    bad_files = sorted(f for f in os.listdir(bad_dir) if f.endswith(".json"))
    for name in bad_files:
        if name not in expect:
            failures.append(("bad/" + name, "no line in EXPECT.tsv"))
            continue
        jobs.append(("bad/" + name, check_bad, (os.path.join(bad_dir, name), expect[name])))
    for name in sorted(set(expect) - set(bad_files)):
        failures.append(("bad/" + name, "listed in EXPECT.tsv but missing"))


def suite_jobs(suite_dir, jobs, failures):
    """Every JSONTestSuite file; without a copy (meson option jsontestsuite) none."""
    suite_files = sorted(os.listdir(suite_dir)) if os.path.isdir(suite_dir) else []
    if not suite_files and os.path.isdir(suite_dir):
        failures.append(("JSONTestSuite", "no files in " + suite_dir))
    for name in suite_files:
        jobs.append(("JSONTestSuite/" + name, check_not_scenario,
                     (os.path.join(suite_dir, name),)))


def scenario_jobs(scenario_dir, tmp, jobs, failures):
    """Every scenario, and 12 truncated and 12 byte-flipped copies of each (written
    into tmp) from a fixed pseudo-random sample."""
    scenarios = sorted(f for f in os.listdir(scenario_dir) if f.endswith(".json"))
    if not scenarios:
        failures.append(("scenarios", "no scenarios in " + scenario_dir))
    rng = random.Random(20170601)
    for name in scenarios:
        path = os.path.join(scenario_dir, name)
        jobs.append(("scenarios/" + name, check_good, (path,)))
        with open(path, "rb") as f:
            data = f.read()
        for k in range(12):
            cut = rng.randrange(len(data))
            mutant = os.path.join(tmp, "%s.cut%d" % (name, cut))
            with open(mutant, "wb") as f:
                f.write(data[:cut])
            jobs.append(("truncated scenarios/%s at byte %d" % (name, cut), check_mutant,
                         (mutant,)))
        for k in range(12):
            at = rng.randrange(len(data))
            byte = rng.choice(b'"{}[],:0123456789.eE-+ \\\x00\x0c\xff\xc0ax')
            mutant = os.path.join(tmp, "%s.flip%d" % (name, k))
            with open(mutant, "wb") as f:
                f.write(data[:at] + bytes([byte]) + data[at + 1:])
            jobs.append(("scenarios/%s with byte %d = 0x%02x" % (name, at, byte), check_mutant,
                         (mutant,)))


def run_jobs(sylva, jobs, failures):
    """Runs the jobs in parallel; adds each problem to failures; returns the passes."""
    passed = 0
    with concurrent.futures.ThreadPoolExecutor(max_workers=os.cpu_count() or 4) as pool:
        futures = [(label, pool.submit(fn, sylva, *fn_args)) for label, fn, fn_args in jobs]
        for label, future in futures:
            problem = future.result()
            if problem:
                failures.append((label, problem))
            else:
                passed += 1
    return passed


if __name__ == "__main__":
    sys.exit(main())
