"""`sylva sweep --slurm` and `--merge` without Slurm (issue 22): the array script is
written (not submitted) and run by hand once per task, as sbatch would with
SLURM_ARRAY_TASK_ID; merging the task stores gives the store of a local sweep (the same
run names, places, stored iterations, and csv and skeleton exports byte for byte), and
merging again changes nothing. A merge with a task store missing and a run unfinished
names both on stderr, merges the rest and exits 1; once the tasks are done, merging
again completes the store. A merge that fails half-way leaves the store as it was (one
transaction), and task stores of another plan are left out.
Usage: test_sweep_merge_manual.py SYLVA"""
import os
import re
import shutil
import sqlite3
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sweep_common import (check_places, compare_sweeps, finish, must, small_plan,  # noqa: E402
                          sweep_runs, sylva, tables, write_json)

TASKS = 3
SPECIES = ['utdb:NoEast:PLAC', 'utdb:NoEast:TICO', 'utdb:NoEast:GIBI']


def run_task(script, k):
    """Runs the array script as task k of the array would run, by hand."""
    env = dict(os.environ, SLURM_ARRAY_TASK_ID=str(k))
    p = subprocess.run(['sh', script], env=env, capture_output=True, text=True)
    if p.returncode != 0:
        raise SystemExit(f'sh {script} as task {k}: exit {p.returncode}\n{p.stderr}')


def merge(exe, plan_path, folder, db):
    p = sylva(exe, 'sweep', plan_path, '--merge', folder, '--db', db)
    print(f'merge {os.path.basename(folder)} -> {os.path.basename(db)}: exit {p.returncode}: '
          + ' | '.join(p.stderr.strip().splitlines()))
    return p


def main():
    exe = sys.argv[1]
    failures = []
    plan = small_plan('merge', SPECIES, [1, 2], iterations=6)  # 12 runs
    with tempfile.TemporaryDirectory() as d:
        plan_path = write_json(os.path.join(d, 'plan.json'), plan)
        folder = os.path.join(d, 'array of tasks')  # a space: the script quotes its paths
        p = must(sylva(exe, 'sweep', plan_path, '--slurm', folder, '--tasks', str(TASKS)),
                 'sylva sweep --slurm')
        script = os.path.join(folder, 'sweep.sbatch')
        if p.stdout != f'sbatch {script}\n':
            failures.append(f'--slurm printed {p.stdout!r}, expected "sbatch {script}"')
        with open(script) as f:
            text = f.read()
        for line in (f'#SBATCH --array=0-{TASKS - 1}', '#SBATCH --cpus-per-task=1',
                     f'#SBATCH --output="{folder}/task-%a.log"'):
            if line not in text.splitlines():
                failures.append(f'the script lacks the line "{line}"')
        if not os.access(script, os.X_OK) or not text.startswith('#!/bin/sh\n'):
            failures.append('the script is not an executable sh script')
        if sylva(exe, 'sweep', plan_path, '--slurm', folder, '--iterations', '3').returncode != 2:
            failures.append('--slurm with --iterations was not refused')
        # more tasks than runs: one task a run
        many = os.path.join(d, 'many')
        p = must(sylva(exe, 'sweep', plan_path, '--slurm', many, '--tasks', '50'), '--tasks 50')
        with open(os.path.join(many, 'sweep.sbatch')) as f:
            if '#SBATCH --array=0-11' not in f.read().splitlines():
                failures.append('--tasks 50 for 12 runs did not give 12 tasks')

        for k in range(TASKS):
            run_task(script, k)
            runs = sweep_runs(os.path.join(folder, f'task-{k}.db'))
            positions = sorted(r['position'] for r in runs.values())
            if positions != list(range(k, 12, TASKS)):
                failures.append(f'task {k} grew the positions {positions}')

        local = os.path.join(d, 'local.db')
        must(sylva(exe, 'sweep', plan_path, '--db', local, '--jobs', '2'), 'the local sweep')
        out = os.path.join(d, 'out.db')
        p = merge(exe, plan_path, folder, out)
        if p.returncode != 0 or '12 runs copied, 0 there already' not in p.stderr:
            failures.append(f'merge: exit {p.returncode}')
        failures += check_places(plan, sweep_runs(out), 'merged')
        failures += compare_sweeps(exe, local, out, d, 'merged against local')
        out_tables = tables(out)
        p = merge(exe, plan_path, folder, out)
        if p.returncode != 0 or '0 runs copied, 12 there already' not in p.stderr:
            failures.append(f'merging again: exit {p.returncode}')
        if tables(out) != out_tables:
            failures.append('merging again changed the store')

        # task 1's store missing, one of task 2's runs unfinished: the rest is merged
        part = os.path.join(d, 'part')
        shutil.copytree(folder, part)
        # its own script: the script names its folder's task stores by absolute paths
        must(sylva(exe, 'sweep', plan_path, '--slurm', part, '--tasks', str(TASKS)),
             'sylva sweep --slurm again')
        os.unlink(os.path.join(part, 'task-1.db'))
        c = sqlite3.connect(os.path.join(part, 'task-2.db'))
        name, position = c.execute(
            'SELECT r.name, w.position FROM runs r JOIN sweep_runs w ON w.run = r.id'
            ' WHERE w.position = 5').fetchone()
        c.execute("UPDATE runs SET status = 'running', reason = NULL WHERE name = ?", (name,))
        c.commit()
        c.close()
        partial = os.path.join(d, 'partial.db')
        p = merge(exe, plan_path, part, partial)
        if p.returncode != 1:
            failures.append(f'merge with a task missing: exit {p.returncode}, expected 1')
        if not re.search(re.escape(os.path.join(part, 'task-1.db')) + r'.*missing', p.stderr):
            failures.append('the merge did not name the missing task-1.db')
        if not re.search(re.escape(os.path.join(part, 'task-2.db')) + '.*' + re.escape(name) +
                         '.*not finished', p.stderr):
            failures.append(f'the merge did not name task-2.db\'s unfinished run "{name}"')
        if '7 runs copied' not in p.stderr or '5 runs are missing' not in p.stderr:
            failures.append('the merge with a task missing did not count 7 runs copied, 5 missing')
        merged = sweep_runs(partial)
        expect = sorted(n for n, r in sweep_runs(local).items()
                        if r['position'] % TASKS != 1 and r['position'] != position)
        if sorted(merged) != expect:
            failures.append(f'the partial merge holds {sorted(merged)}')
        # the tasks done: task 1 grown again, task 2 started again finishes its run
        run_task(os.path.join(part, 'sweep.sbatch'), 1)
        run_task(os.path.join(part, 'sweep.sbatch'), 2)
        p = merge(exe, plan_path, part, partial)
        if p.returncode != 0 or '5 runs copied, 7 there already' not in p.stderr:
            failures.append(f'merging the finished tasks: exit {p.returncode}')
        failures += compare_sweeps(exe, local, partial, d, 'merged in two goes against local')

        # a merge that fails half-way changes nothing: task 0's store is good, task 1's
        # holds runs at task 2's positions that the store has already under other names
        atomic = os.path.join(d, 'atomic.db')
        only2 = os.path.join(d, 'only2')
        os.mkdir(only2)
        shutil.copy(script, only2)
        shutil.copy(os.path.join(folder, 'task-2.db'), only2)
        merge(exe, plan_path, only2, atomic)
        bad = os.path.join(d, 'bad')
        os.mkdir(bad)
        shutil.copy(script, bad)
        shutil.copy(os.path.join(folder, 'task-0.db'), bad)
        shutil.copy(os.path.join(folder, 'task-2.db'), os.path.join(bad, 'task-1.db'))
        c = sqlite3.connect(os.path.join(bad, 'task-1.db'))
        c.execute("UPDATE runs SET name = name || ' (renamed)'")
        c.commit()
        c.close()
        before = tables(atomic)
        p = merge(exe, plan_path, bad, atomic)
        if p.returncode == 0 or 'merging run' not in p.stderr:
            failures.append(f'the merge that fails half-way: exit {p.returncode}, '
                            'no "merging run" on stderr')
        if tables(atomic) != before:
            failures.append('the merge that failed half-way changed the store')

        # task stores of another plan of the same name are left out
        other = dict(plan, axes=dict(plan['axes'], seed=[7, 8]))
        other_path = write_json(os.path.join(d, 'other.json'), other)
        p = merge(exe, other_path, folder, os.path.join(d, 'other.db'))
        if p.returncode != 1 or p.stderr.count('of another plan') != TASKS:
            failures.append(f'task stores of another plan: exit {p.returncode}')
        p = merge(exe, other_path, folder, out)
        if p.returncode != 2 or 'another plan' not in p.stderr:
            failures.append(f'merging another plan into a store of this one: exit {p.returncode}')
        if tables(out) != out_tables:
            failures.append('merging another plan changed the store')
    finish(failures)


main()
