"""`sylva sweep` of the ready plan scenarios/street-species.json (issue 22): 5 library
species for the street's trees x 3 seeds x 2 variants, 6 iterations each, in 2
processes. The store holds exactly the plan's 30 runs, each finished, at its position,
with its axes in run_axes, and with its species, seed and variant in its stored
scenario; sweeping again changes nothing.
Usage: test_sweep_local.py SYLVA"""
import json
import os
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sweep_common import (READY_PLAN, check_places, connect, finish, must,  # noqa: E402
                          run_count, species_objects, sylva, sweep_runs, tables)

ITERATIONS = '6'


def main():
    exe = sys.argv[1]
    failures = []
    with open(READY_PLAN) as f:
        plan = json.load(f)
    presets = plan['axes']['species']['street-tree']
    if len(presets) != 5 or plan['axes']['seed'] != [1, 2, 3] or \
            sorted(plan['axes']['variants']) != ['as built', 'no awning']:
        failures.append(f'{READY_PLAN}: not 5 species x seeds 1-3 x "as built", "no awning"')
    with tempfile.TemporaryDirectory() as d:
        db = os.path.join(d, 'street.db')
        t0 = time.monotonic()
        p = must(sylva(exe, 'sweep', READY_PLAN, '--db', db, '--iterations', ITERATIONS,
                       '--jobs', '2'), 'sylva sweep street-species.json')
        print(f'sweep: {time.monotonic() - t0:.1f} s; stderr ends: '
              f'{p.stderr.strip().splitlines()[-1]}')
        if '30 runs to grow in 2 processes' not in p.stderr:
            failures.append('progress: no "30 runs to grow in 2 processes" on stderr')
        if '30/30 runs done' not in p.stderr:
            failures.append('progress: no "30/30 runs done" on stderr')

        runs = sweep_runs(db)
        if run_count(db) != 30:
            failures.append(f'{run_count(db)} runs in the store, expected 30')
        failures += check_places(plan, runs, 'first sweep')
        if any(r['last'] != int(ITERATIONS) or r['iterations'] != int(ITERATIONS)
               for r in runs.values()):
            failures.append(f'a run did not stop at --iterations {ITERATIONS}')

        # the species: each run's stored scenario holds its preset, expanded as sylva
        # stores any preset
        expanded = species_objects(exe, presets, d)
        if len({json.dumps(v, sort_keys=True) for v in expanded.values()}) != len(presets):
            failures.append('two presets expand to the same species object')
        for name, r in runs.items():
            preset = r['axes'].get('species/street-tree')
            if r['scenario']['species'].get('street-tree') != expanded.get(preset):
                failures.append(f'"{name}": its scenario\'s street-tree is not {preset}')
        c = connect(db)
        stored = c.execute('SELECT name, plan FROM sweeps').fetchall()
        c.close()
        kept = json.loads(stored[0][1]) if len(stored) == 1 else {}
        if len(stored) != 1 or stored[0][0] != plan['name'] or kept.get('axes') != plan['axes'] \
                or not isinstance(kept.get('scenario'), dict):
            failures.append('the sweeps table does not hold the plan, its scenario inline')

        # again: the finished runs are kept and the store does not change
        before = tables(db)
        for extra in ([], ['--iterations', ITERATIONS]):
            p = must(sylva(exe, 'sweep', READY_PLAN, '--db', db, '--jobs', '2', *extra),
                     'sylva sweep street-species.json again')
            print(f'again{" " + " ".join(extra) if extra else ""}: '
                  f'{p.stderr.strip().splitlines()[0]}')
            if tables(db) != before:
                failures.append(f'sweeping again ({" ".join(extra) or "no options"}) changed '
                                'the store')
            if run_count(db) != 30:
                failures.append(f'sweeping again: {run_count(db)} runs')
            if ': 0 runs to grow' not in p.stderr:
                failures.append(f'sweeping again ({" ".join(extra) or "no options"}): '
                                f'runs were grown: {p.stderr.strip()}')
    finish(failures)


main()
