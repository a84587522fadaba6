#!/usr/bin/env python3
"""Benchmark, not a test (run by hand): the speed-up of `sylva sweep --jobs`. Sweeps a
plan of 12 street runs (scenarios/street.json: 2 library species x 3 seeds x the
street with and without its awning, 40 iterations, about 2-4 s a run) into a fresh
store with --jobs 1 and with --jobs N (default 2), and prints both wall times and
their ratio. On a machine busy with other work the ratio says more about the
machine than about sylva: compare with the load average printed beside it, and
with the CPU time both sweeps used (about the same when the workers cost nothing
more than the runs).
Usage: sweep_speedup.py [SYLVA] [--jobs N] [--iterations N]
       (SYLVA defaults to build/server/sylva of the source tree)"""
import argparse
import json
import os
import resource
import subprocess
import tempfile
import time

SOURCE = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))


def plan(iterations):
    with open(os.path.join(SOURCE, 'scenarios', 'street.json')) as f:
        scenario = json.load(f)
    scenario['iterations'] = iterations
    return {'format': 'sylva.sweep/1', 'name': 'speed-up', 'scenario': scenario,
            'axes': {'species': {'street-tree': ['utdb:NoEast:PLAC', 'utdb:NoEast:TICO']},
                     'seed': [1, 2, 3],
                     'variants': {'as built': [],
                                  'no awning': [{'op': 'remove', 'path': '/obstacles/2'}]}}}


def sweep(exe, plan_path, db, jobs):
    """(wall seconds, CPU seconds of sylva and its workers) of one sweep."""
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.monotonic()
    p = subprocess.run([exe, 'sweep', plan_path, '--db', db, '--jobs', str(jobs),
                        '--quiet-progress'], capture_output=True, text=True)
    secs = time.monotonic() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode != 0:
        raise SystemExit(f'sylva sweep --jobs {jobs}: exit {p.returncode}\n{p.stderr}')
    return secs, (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)


def main():
    ap = argparse.ArgumentParser(description='the speed-up of sylva sweep --jobs')
    ap.add_argument('sylva', nargs='?', default=os.path.join(SOURCE, 'build', 'server', 'sylva'))
    ap.add_argument('--jobs', type=int, default=2)
    ap.add_argument('--iterations', type=int, default=40)
    a = ap.parse_args()
    exe = os.path.abspath(a.sylva)
    with tempfile.TemporaryDirectory() as d:
        plan_path = os.path.join(d, 'plan.json')
        with open(plan_path, 'w') as f:
            json.dump(plan(a.iterations), f)
        load = os.getloadavg()[0]
        one, cpu_one = sweep(exe, plan_path, os.path.join(d, 'one.db'), 1)
        many, cpu_many = sweep(exe, plan_path, os.path.join(d, 'many.db'), a.jobs)
        print(f'12 runs of {a.iterations} iterations, {os.cpu_count()} cores, '
              f'load average {load:.2f} before, {os.getloadavg()[0]:.2f} after')
        print(f'--jobs 1: {one:.1f} s wall, {cpu_one:.1f} s CPU ({one / 12:.2f} s a run)')
        print(f'--jobs {a.jobs}: {many:.1f} s wall, {cpu_many:.1f} s CPU')
        # the CPU the processes used is what the other work on the machine does not
        # change much: the same CPU with more processes means no overhead of sylva's
        print(f'speed-up: {one / many:.2f}x (ideal {min(a.jobs, os.cpu_count() or 1)}x); '
              f'CPU with --jobs {a.jobs} / --jobs 1: {cpu_many / cpu_one:.2f}')


main()
