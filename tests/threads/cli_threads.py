"""--threads through the real binary (docs/cli.md): the number of threads a world
grows on never changes what sylva writes.

meson runs `python3 cli_threads.py SYLVA_EXE TMPDIR` (SYLVA_SLOW scales the waits in
the sanitizer build). With real files, it checks that:
- `sylva run` writes the same store (every table, row and column but the
  created/updated times, snapshots included), the same lines (elapsed_ms aside),
  the same skeleton (--export) and the same csv and glb exports on 1, 2 and 4
  threads for a street of ten library trees lit by its site's sky
  (scenarios/street-ten.json), and on 1, 4 and the default (the cores) for the IGM
  stand (scenarios/stand.json), both cut to 10 iterations;
- a street grown on 1 thread, broken off after 7 (its last snapshot lost, as after
  a crash) and resumed on 4, regrown from the snapshot of 5, equals the street
  grown on 2 at one go, its resumed lines included;
- `sylva serve` on 1 and on 4 threads grows a run (--run) to the same store and
  serves the same csv, glb and stats.csv over HTTP; and so do daemons on 1 and 4
  threads that load a broken-off run from their store (regrowing it) and grow on;
- `sylva sweep` of a small plan in 2 processes of 1 thread, and as a Slurm array
  script of 1 process of 2 threads run by hand and merged, stores the same runs;
  --slurm --jobs 2 --threads 3 asks for 6 cpus a task;
- the threads are there: a process blocked on a full stdout pipe (run, resume), and
  the daemon holding its run, have N - 1 threads more than on one thread;
- `sylva render` of the stand draws the same PNG on 1 and 4 threads;
- a bad --threads (0, -1, abc, 257, none) exits 2 for run, resume, sweep, serve and
  fit (and render), naming --threads and 1 to 256, and writes nothing.
Each comparison reports where the outputs first differ.
"""
import concurrent.futures
import fcntl
import json
import os
import re
import shutil
import signal
import socket
import sqlite3
import subprocess
import sys
import time
import urllib.request

EXE, TMP = os.path.abspath(sys.argv[1]), sys.argv[2]
SLOW = float(os.environ.get('SYLVA_SLOW', '1'))
SOURCE = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
sys.path[:0] = [os.path.join(SOURCE, 'tests', 'sweep'), os.path.join(SOURCE, 'tests', 'store')]
from store_common import read_bytes as read, strip_elapsed  # noqa: E402
from sweep_common import compare_sweeps, small_plan  # noqa: E402

ITERATIONS = 10  # of each run grown here
CUT = 7          # where a run is broken off: after the snapshot of 5 (every 5), before 10
failures = []
t_start = time.monotonic()


def check(ok, what, detail=''):
    print(('ok   ' if ok else 'FAIL ') + what + (': ' + detail if detail and not ok else ''))
    if not ok:
        failures.append(what)


def sylva(*args, timeout=300):
    return subprocess.run([EXE, *args], capture_output=True, text=True, timeout=timeout * SLOW)


def must(*args):
    p = sylva(*args)
    if p.returncode != 0:
        raise SystemExit(f'FAIL sylva {" ".join(args)}: exit {p.returncode}\n{p.stderr}')
    return p


def scenario(name, iterations, path):
    """scenarios/NAME.json with another iteration limit (and name), written to path."""
    with open(os.path.join(SOURCE, 'scenarios', name + '.json')) as f:
        s = json.load(f)
    s['iterations'] = iterations
    s['name'] = f'threads-{name}'
    with open(path, 'w') as f:
        json.dump(s, f)
    return path


def lines(stdout):
    """The iteration lines without their elapsed_ms, and the done line."""
    return [strip_elapsed(l) for l in stdout.splitlines()]


def dump(db):
    """{table: its rows in order}: every column but the created and updated times
    (a store file holds them, so its bytes differ from run to run)."""
    c = sqlite3.connect(f'file:{db}?mode=ro', uri=True)
    out = {}
    for (t,) in c.execute("SELECT name FROM sqlite_schema WHERE type = 'table' ORDER BY name"):
        cols = [r[1] for r in c.execute(f'PRAGMA table_info("{t}")')
                if r[1] not in ('created', 'updated')]
        order = ', '.join(str(i + 1) for i in range(len(cols)))
        out[t] = (cols, c.execute(f'SELECT {", ".join(chr(34) + x + chr(34) for x in cols)}'
                                  f' FROM "{t}" ORDER BY {order}').fetchall())
    c.close()
    return out


def differ(a, b):
    """'' when the dumps are equal, else where they first differ."""
    if sorted(a) != sorted(b):
        return f'tables {sorted(a)} and {sorted(b)}'
    for t in sorted(a):
        (cols, ra), (_, rb) = a[t], b[t]
        if len(ra) != len(rb):
            return f'{t}: {len(ra)} and {len(rb)} rows'
        for x, y in zip(ra, rb):
            for col, u, v in zip(cols, x, y):
                if u != v:
                    show = (lambda z: f'{len(z)} bytes' if isinstance(z, bytes) else repr(z)[:80])
                    return f'{t}: first at {dict(zip(cols, x[:3]))}: {col} {show(u)} != {show(v)}'
    return ''


def at(x, y):
    """Where x and y first differ (at least 20)."""
    return max(20, next((i for i, (u, v) in enumerate(zip(x, y)) if u != v), min(len(x), len(y))))


def same(what, outputs):
    """Checks that every outputs[k] equals the first: {label: {part: value}}."""
    labels = list(outputs)
    base = outputs[labels[0]]
    for label in labels[1:]:
        for part, value in outputs[label].items():
            if part == 'store':
                why = differ(base[part], value)
            elif part == 'lines':
                why = next((f'line {i + 1}: ...{x[at(x, y) - 20:at(x, y) + 40]}... != '
                             f'...{y[at(x, y) - 20:at(x, y) + 40]}...' for i, (x, y) in
                            enumerate(zip(base[part], value)) if x != y),
                           '' if len(base[part]) == len(value) else
                           f'{len(base[part])} and {len(value)} lines')
            else:
                why = '' if base[part] == value else f'{len(base[part])} and {len(value)} bytes' + \
                    next((f', first at byte {i}' for i, (x, y) in enumerate(zip(base[part], value))
                          if x != y), '')
            check(not why, f'{what}: {part} on {label} as on {labels[0]}', why)


def exports(db, name, d):
    out = {}
    for fmt in ('csv', 'glb'):
        path = os.path.join(d, f'export.{fmt}')
        must('export', '--db', db, '--name', name, '--format', fmt, '-o', path)
        out[fmt] = read(path)
    return out


def threads_of(pid):
    with open(f'/proc/{pid}/status') as f:
        return int(re.search(r'^Threads:\s*(\d+)', f.read(), re.M).group(1))


def probed(args):
    """Runs `sylva ARGS` with stdout into a pipe of one page that is not read until
    the process blocks on it, growing: returns (its threads then, completed stdout)."""
    r, w = os.pipe()
    fcntl.fcntl(w, 1031, 4096)  # F_SETPIPE_SZ: the smallest pipe
    err = open(os.path.join(TMP, 'probe.err'), 'w+')
    p = subprocess.Popen([EXE, *args], stdout=w, stderr=err)
    os.close(w)
    deadline = time.monotonic() + 120 * SLOW
    seen = None
    while time.monotonic() < deadline and p.poll() is None:
        # a first line in the pipe: the world grows on its threads (set before its
        # first iteration), and the lines to come do not fit
        if int.from_bytes(fcntl.ioctl(r, 0x541B, b'\0\0\0\0'), 'little') > 0:  # FIONREAD
            seen = threads_of(p.pid)
            break
        time.sleep(0.01)
    out = b''
    while chunk := os.read(r, 65536):
        out += chunk
    os.close(r)
    p.wait()
    err.seek(0)
    if p.returncode != 0 or seen is None:
        raise SystemExit(f'FAIL sylva {" ".join(args)}: exit {p.returncode}, threads seen '
                         f'{seen}\n{err.read()}')
    err.close()
    return seen, out.decode()


def grown(d, label, scen, threads, probe=False):
    """A stored run of scen for ITERATIONS iterations on `threads` threads (None: the
    default) in folder d/label: its store, lines, skeleton and exports (and threads)."""
    w = os.path.join(d, label)
    os.makedirs(w)
    db = os.path.join(w, 'run.db')
    args = ['run', scen, '--db', db, '--name', 'r', '--iterations', str(ITERATIONS),
            '--export', os.path.join(w, 'skeleton.json'), '--quiet-progress']
    if threads is not None:
        args += ['--threads', str(threads)]
    seen, stdout = probed(args) if probe else (None, must(*args).stdout)
    out = {'store': dump(db), 'lines': lines(stdout),
           'skeleton': read(os.path.join(w, 'skeleton.json'))}
    out.update(exports(db, 'r', w))
    return out, seen, db


def run(d, name, counts):
    """The scenario grown on each number of threads in counts (None: the default);
    returns its path, the outputs and the threads seen."""
    scen = scenario(name, ITERATIONS, os.path.join(d, f'{name}.json'))
    outs, seen = {}, {}
    for n in counts:
        label = f'{name}-{n or "default"}'
        outs[label], seen[n], _ = grown(d, label, scen, n, probe=n != 2)
    same(f'run {name}', outs)
    # the threads there, against one thread (a sanitizer may add threads of its own)
    cores = min(256, os.cpu_count() or 1)
    for n in seen:
        if seen[n] is not None and n != 1:
            check(seen[n] - seen[1] == (n or cores) - 1,
                  f'run {name} --threads {n or "(default: " + str(cores) + ")"}: '
                  f'{(n or cores) - 1} threads more than on 1',
                  f'{seen[n]} threads, {seen[1]} on 1')
    return scen, outs, seen


def render(d, scen):
    """`sylva render SCENARIO` grows it on 1 and on 4 threads to the same picture."""
    pictures = {}
    for n in (1, 4):
        path = os.path.join(d, f'render-{n}.png')
        must('render', scen, '--iterations', str(ITERATIONS), '--view', 'front',
             '--threads', str(n), '-o', path)
        pictures[f'render --threads {n}'] = {'png': read(path)}
    same('render', pictures)


def broken_off(scen, db, name):
    """Run `name` of scen in a new store db, grown to CUT on one thread and broken off
    there, as when its process dies between two snapshots: still running (limit
    ITERATIONS), its last stored iteration without its snapshot."""
    must('run', scen, '--db', db, '--name', name, '--iterations', str(CUT), '--threads', '1',
         '--quiet-progress')
    c = sqlite3.connect(db)
    c.execute('UPDATE iterations SET snapshot = NULL WHERE iteration = ?', (CUT,))
    c.execute("UPDATE runs SET status = 'running', reason = NULL, iterations = ?", (ITERATIONS,))
    c.commit()
    c.close()


def resume(d, name, scen, outs, seen):
    """A run broken off after CUT on one thread, resumed on 4 (regrown from the
    snapshot of 5), against the run grown on 2 at one go."""
    w = os.path.join(d, f'{name}-resumed')
    os.makedirs(w)
    db = os.path.join(w, 'run.db')
    broken_off(scen, db, 'r')
    seen_resume, stdout = probed(['resume', '--db', db, '--name', 'r', '--iterations',
                                  str(ITERATIONS), '--threads', '4', '--quiet-progress'])
    check(seen_resume - seen[1] == 3, f'resume {name} --threads 4: 3 threads more than run on 1',
          f'{seen_resume} threads')
    base = outs[f'{name}-2']
    resumed = {'store': dump(db), 'lines': lines(stdout)}
    resumed.update(exports(db, 'r', w))
    same(f'resume {name}', {f'{name}-2 (continuous)': {k: base[k] if k != 'lines' else
                                                      base[k][CUT:] for k in resumed},
                            'resumed on 4 after 7 on 1': resumed})


def free_port():
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        return s.getsockname()[1]


def get(url):
    with urllib.request.urlopen(url, timeout=60 * SLOW) as r:
        return r.read()


class Daemon:
    def __init__(self, db, threads, run=None):
        self.port = free_port()
        self.http = f'http://127.0.0.1:{self.port}'
        self.log = open(db + f'.{threads}.log', 'w+')
        args = [EXE, 'serve', '--db', db, '--listen', f'127.0.0.1:{self.port}',
                '--threads', str(threads)] + (['--run', run] if run else [])
        self.threads = threads
        self.proc = subprocess.Popen(args, stdout=self.log, stderr=self.log)
        self.wait(lambda: 'listening on' in self.text(), 'listening')

    def text(self):
        self.log.seek(0)
        return self.log.read()

    def wait(self, ok, what):
        deadline = time.monotonic() + 120 * SLOW
        while time.monotonic() < deadline:
            if self.proc.poll() is not None:
                raise SystemExit(f'FAIL the daemon exited {self.proc.returncode}:\n{self.text()}')
            if ok():
                return
            time.sleep(0.05)
        self.proc.kill()
        raise SystemExit(f'FAIL the daemon, waiting for {what}:\n{self.text()}')

    def finished(self, name):
        def done():
            runs = json.loads(get(self.http + '/api/runs'))
            return any(r['name'] == name and r['status'] == 'finished' for r in runs)
        self.wait(done, f'run {name} finished')

    def stop(self):
        self.proc.send_signal(signal.SIGTERM)
        code = self.proc.wait(timeout=60 * SLOW)
        check(code == 0, f'the daemon on {self.threads} threads stopped with 0', str(code))
        self.log.close()


def daemon(d, scen):
    with open(scen) as f:
        name = json.load(f)['name']
    quoted = urllib.request.quote(name)
    outs, seen = {}, {}

    def served(dm, label, db):
        seen[label] = threads_of(dm.proc.pid)  # the run's world is held, finished
        out = {fmt: get(f'{dm.http}/api/runs/{quoted}/export?format={fmt}')
               for fmt in ('csv', 'glb')}
        out['stats.csv'] = get(f'{dm.http}/api/runs/{quoted}/stats.csv')
        dm.stop()
        out['store'] = dump(db)
        outs[label] = out

    for n in (1, 4):
        db = os.path.join(d, f'serve-{n}.db')
        dm = Daemon(db, n, run=scen)
        dm.finished(name)
        served(dm, f'serve --threads {n}', db)
    # a run broken off: the daemon loads it at start, regrowing it from the snapshot
    # of 5, and grows it on
    for n in (1, 4):
        db = os.path.join(d, f'serve-loaded-{n}.db')
        broken_off(scen, db, name)
        dm = Daemon(db, n)
        dm.finished(name)
        served(dm, f'serve --threads {n}, loaded after 7 on 1', db)
    for how in ('', ', loaded after 7 on 1'):
        one, four = seen[f'serve --threads 1{how}'], seen[f'serve --threads 4{how}']
        check(four - one == 3, f'serve --threads 4{how}: 3 threads more than on 1 (its run held)',
              f'{four} and {one}')
    same('serve', outs)


def sweep(d):
    """A plan of 2 runs swept here in 2 processes of 1 thread, and as a Slurm array
    script of one task in 1 process of 2 threads, run by hand and merged."""
    plan = small_plan('threads', ['utdb:NoEast:PLAC'], [1, 2], awning_variant=False, iterations=4)
    path = os.path.join(d, 'plan.json')
    with open(path, 'w') as f:
        json.dump(plan, f)
    one = os.path.join(d, 'one.db')
    p = must('sweep', path, '--db', one, '--jobs', '2', '--threads', '1')
    check('2 runs to grow in 2 processes (1 thread each)' in p.stderr,
          'sweep --jobs 2 --threads 1 says so', p.stderr)
    folder = os.path.join(d, 'slurm')
    must('sweep', path, '--slurm', folder, '--tasks', '1', '--threads', '2')
    script = os.path.join(folder, 'sweep.sbatch')
    text = read(script).decode()
    check('#SBATCH --cpus-per-task=2\n' in text and ' --jobs 1 --threads 2 ' in text,
          'sweep --slurm --threads 2: 2 cpus per task, the task gets --threads 2', text)
    p = subprocess.run(['sh', script], env=dict(os.environ, SLURM_ARRAY_TASK_ID='0'),
                       capture_output=True, text=True, timeout=300 * SLOW)
    check(p.returncode == 0, 'the array script run by hand as task 0', p.stderr)
    merged = os.path.join(d, 'merged.db')
    must('sweep', path, '--merge', folder, '--db', merged)
    for f in compare_sweeps(EXE, one, merged, d, 'sweep --threads 2 (--slurm, merged) against 1'):
        check(False, f)
    # 3 threads of 2 processes: 6 cpus per task
    must('sweep', path, '--slurm', folder, '--tasks', '1', '--jobs', '2', '--threads', '3')
    text = read(script).decode()
    check('#SBATCH --cpus-per-task=6\n' in text and ' --jobs 2 --threads 3 ' in text,
          'sweep --slurm --jobs 2 --threads 3: 6 cpus per task', text)
    return path


def bad_input(d, scen, plan):
    """Each bad --threads exits 2 naming the option and its range, writing nothing."""
    def refused(case):
        cmd, value = case
        empty = os.path.join(d, f'bad-{cmd}-{value}')
        os.makedirs(empty)
        db, out = os.path.join(empty, 'x.db'), os.path.join(empty, 'x')
        args = {
            'run': ['run', scen, '--db', db, '--iterations', '1'],
            'resume': ['resume', '--db', db, '--name', 'r'],
            'render': ['render', scen, '--iterations', '1', '-o', out + '.png'],
            'sweep': ['sweep', plan, '--db', db],
            'serve': ['serve', '--db', db, '--listen', f'127.0.0.1:{free_port()}'],
            'fit': ['fit', '--utdb', 'NoEast:PLAC', '--evals', '1', '--seeds', '1', '-o',
                    out + '.json'],
        }[cmd]
        try:  # the value last, or no value
            p = sylva(*args, '--threads', *([value] if value is not None else []), timeout=20)
            code, err = p.returncode, p.stderr
        except subprocess.TimeoutExpired:  # a daemon or a fit that started
            code, err = 'timeout', ''
        ok = code == 2 and '--threads' in err and '1 to 256' in err and not os.listdir(empty)
        return ok, f'sylva {cmd} --threads {value!r}: exit {code}, {os.listdir(empty)}, {err!r}'

    commands = ('run', 'resume', 'render', 'sweep', 'serve', 'fit')
    values = ('0', '-1', 'abc', '257', None)
    # a process that fails at once is mostly its start: a few at a time
    with concurrent.futures.ThreadPoolExecutor(3) as pool:
        results = list(pool.map(refused, [(c, v) for c in commands for v in values
                                          if c != 'render' or v in ('0', None)]))
    for ok, what in results:
        if not ok:
            check(False, 'a bad --threads refused (exit 2, the option and 1 to 256 named, '
                  'nothing written)', what)
    check(all(ok for ok, _ in results),
          f'bad --threads refused by {", ".join(commands)}')
    empty = os.path.join(d, 'bad-merge')
    os.makedirs(empty)
    p = sylva('sweep', plan, '--merge', d, '--db', os.path.join(empty, 'x.db'), '--threads', '2')
    check(p.returncode == 2 and '--threads' in p.stderr and not os.listdir(empty),
          'sweep --merge refuses --threads', p.stderr)


def timed(what, fn, *args):
    t0 = time.monotonic()
    r = fn(*args)
    print(f'     {what}: {time.monotonic() - t0:.1f} s')
    return r


def main():
    shutil.rmtree(TMP, ignore_errors=True)
    os.makedirs(TMP)
    stand, _, _ = timed('run, stand', run, TMP, 'stand', (1, 4, None))
    timed('render, stand', render, TMP, stand)
    street, outs, seen = timed('run, street of ten', run, TMP, 'street-ten', (1, 2, 4))
    timed('resume, street of ten', resume, TMP, 'street-ten', street, outs, seen)
    timed('serve', daemon, TMP, street)
    plan = timed('sweep', sweep, TMP)
    timed('bad input', bad_input, TMP, stand, plan)
    print(f'{len(failures)} failures in {time.monotonic() - t_start:.1f} s')
    if not failures:
        shutil.rmtree(TMP, ignore_errors=True)
    raise SystemExit(1 if failures else 0)


main()
