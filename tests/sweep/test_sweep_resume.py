"""A killed `sylva sweep` continues (issue 22): a plan of 6 street runs of 20 iterations
is swept in 2 processes and the whole process group is killed (SIGKILL) once some runs
have finished and another is half grown; the sweep started again keeps the finished
runs as they are, resumes the unfinished ones from the store and grows the rest. Every
run then equals an uninterrupted sweep's: the same names, places and stored iterations,
and the csv and skeleton exports byte for byte.
Usage: test_sweep_resume.py SYLVA"""
import os
import signal
import sqlite3
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sweep_common import (check_places, compare_sweeps, connect, finish, must,  # noqa: E402
                          small_plan, sweep_runs, sylva, write_json)

ITERATIONS = 20
ATTEMPTS = 3


def progress(db):
    """(finished runs, runs half grown) of the store, or None before it has any."""
    if not os.path.exists(db):
        return None
    try:
        c = connect(db)
        rows = c.execute(
            'SELECT r.status, (SELECT max(iteration) FROM iterations i WHERE i.run = r.id)'
            ' FROM sweep_runs w JOIN runs r ON r.id = w.run').fetchall()
        c.close()
    except sqlite3.Error:  # not yet a store, or its schema is being created
        return None
    finished = sum(1 for status, _ in rows if status == 'finished')
    half = sum(1 for status, last in rows
               if status == 'running' and last is not None and 1 <= last < ITERATIONS)
    return finished, half


def kill_midway(exe, plan_path, db):
    """Starts the sweep and kills its process group once a run has finished and another
    is half grown; returns (finished, half grown) at the kill, or None when the sweep
    ended before such a moment came."""
    p = subprocess.Popen([os.path.abspath(exe), 'sweep', plan_path, '--db', db, '--jobs', '2'],
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                         start_new_session=True)
    try:
        while p.poll() is None:
            state = progress(db)
            if state and state[0] >= 1 and state[1] >= 1:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()
                return state
            time.sleep(0.02)
        return None
    finally:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGKILL)
        p.wait()
        p.stderr.close()


def main():
    exe = sys.argv[1]
    failures = []
    plan = small_plan('resume', ['utdb:NoEast:PLAC', 'utdb:NoEast:TICO'], [1, 2, 3],
                      awning_variant=False, iterations=ITERATIONS)
    with tempfile.TemporaryDirectory() as d:
        plan_path = write_json(os.path.join(d, 'plan.json'), plan)
        db = os.path.join(d, 'killed.db')
        state = None
        for attempt in range(ATTEMPTS):
            for suffix in ('', '-wal', '-shm'):
                if os.path.exists(db + suffix):
                    os.unlink(db + suffix)
            state = kill_midway(exe, plan_path, db)
            if state:
                break
            print(f'attempt {attempt + 1}: the sweep ended before it could be killed mid-way')
        if not state:
            finish([f'could not kill the sweep mid-way in {ATTEMPTS} attempts'])
        before = sweep_runs(db)
        done_before = {n: r for n, r in before.items() if r['status'] == 'finished'}
        half = {n: r['last'] for n, r in before.items() if r['status'] != 'finished'}
        print(f'killed with {len(done_before)} runs finished; unfinished: {half}')
        if len(done_before) >= 6 or not any(1 <= last < ITERATIONS for last in half.values()
                                            if last is not None):
            failures.append(f'the kill came too late: {len(done_before)} finished, {half}')
        c = connect(db)
        updated = dict(c.execute('SELECT name, updated FROM runs'))
        c.close()

        t0 = time.monotonic()
        p = must(sylva(exe, 'sweep', plan_path, '--db', db, '--jobs', '2', '--threads', '1'),
                 'sylva sweep after the kill')
        print(f'started again: {time.monotonic() - t0:.1f} s: {p.stderr.strip().splitlines()[0]}')
        expect = f': {6 - len(done_before)} runs to grow in 2 processes (1 thread each) (the finished ones kept)'
        if expect not in p.stderr:
            failures.append(f'started again: no "{expect}" on stderr: {p.stderr.strip()}')
        after = sweep_runs(db)
        failures += check_places(plan, after, 'after the kill')
        c = connect(db)
        updated_after = dict(c.execute('SELECT name, updated FROM runs'))
        c.close()
        for name, r in done_before.items():
            if after.get(name, {}).get('id') != r['id'] or updated_after.get(name) != updated[name]:
                failures.append(f'"{name}", finished before the kill, was grown again')

        whole = os.path.join(d, 'whole.db')
        must(sylva(exe, 'sweep', plan_path, '--db', whole, '--jobs', '2'),
             'the uninterrupted sweep')
        failures += compare_sweeps(exe, whole, db, d, 'killed and resumed')
        print(f'compared {len(after)} runs with an uninterrupted sweep')
    finish(failures)


main()
