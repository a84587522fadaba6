"""`sylva sweep --slurm DIR --submit` on a real Slurm (issue 22): the test starts a
single-node cluster of its own (docs/cli.md, "sweep"; the recipe of
shared/notes/slurm-single-node.md): munged with its own key and socket, slurmctld and
slurmd in the foreground on free ports, every client pointed at its slurm.conf with
SLURM_CONF. Once the node is idle, the sweep's array job is submitted (3 tasks), waited
for with squeue, and its task stores merged; the merged store equals a local sweep's
(run names, places, stored iterations, csv and skeleton exports byte for byte). The
daemons are stopped by the pids in their pid files whatever happens. Without Slurm the
test fails: scripts/bootstrap installs it.
Usage: test_slurm.py SYLVA"""
import os
import signal
import socket
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sweep_common import (check_places, compare_sweeps, finish, must, small_plan,  # noqa: E402
                          sweep_runs, sylva, write_json)

TASKS = 3
DAEMONS = ('munged', 'slurmctld', 'slurmd')
CLIENTS = ('sbatch', 'squeue', 'sinfo')
SEARCH = os.pathsep.join([os.environ.get('PATH', ''), '/usr/sbin', '/sbin', '/usr/bin'])


def which(name):
    for d in SEARCH.split(os.pathsep):
        p = os.path.join(d, name)
        if d and os.access(p, os.X_OK):
            return p
    return None


def free_port():
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        return s.getsockname()[1]


def write_conf(d, host, cpus):
    for sub in ('state', 'spool'):
        os.mkdir(os.path.join(d, sub))
    ctld_port, d_port = free_port(), free_port()
    while d_port == ctld_port:
        d_port = free_port()
    lines = [
        'ClusterName=sylvatest', f'SlurmctldHost={host}(127.0.0.1)',
        'SlurmUser=root', 'SlurmdUser=root',
        'AuthType=auth/munge', f'AuthInfo=socket={d}/munge.sock',
        f'StateSaveLocation={d}/state', f'SlurmdSpoolDir={d}/spool',
        f'SlurmctldPidFile={d}/ctld.pid', f'SlurmdPidFile={d}/d.pid',
        f'SlurmctldLogFile={d}/ctld.log', f'SlurmdLogFile={d}/d.log',
        f'SlurmctldPort={ctld_port}', f'SlurmdPort={d_port}',
        'ProctrackType=proctrack/linuxproc', 'TaskPlugin=task/none',
        'SwitchType=switch/none', 'MpiDefault=none', 'SchedulerType=sched/builtin',
        'SelectType=select/cons_tres', 'SelectTypeParameters=CR_Core',
        'JobCompType=jobcomp/none', 'AccountingStorageType=accounting_storage/none',
        'ReturnToService=2',
        f'NodeName={host} NodeAddr=127.0.0.1 CPUs={cpus} State=UNKNOWN',
        f'PartitionName=debug Nodes={host} Default=YES MaxTime=INFINITE State=UP',
    ]
    conf = os.path.join(d, 'slurm.conf')
    with open(conf, 'w') as f:
        f.write('\n'.join(lines) + '\n')
    return conf


def read_pid(path):
    try:
        with open(path) as f:
            return int(f.read().split()[0])
    except (OSError, ValueError, IndexError):
        return None


def stop(pid_file, proc=None):
    """Stops a daemon by the pid in its pid file (or the process we started, when it
    wrote none): SIGTERM, then SIGKILL after 10 s."""
    pid = read_pid(pid_file) or (proc.pid if proc and proc.poll() is None else None)
    if not pid:
        return
    try:
        os.kill(pid, signal.SIGTERM)
    except ProcessLookupError:
        return
    for _ in range(100):
        if proc is not None and proc.pid == pid:
            if proc.poll() is not None:
                return
        else:
            try:
                os.kill(pid, 0)
            except ProcessLookupError:
                return
        time.sleep(0.1)
    try:
        os.kill(pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    if proc is not None:
        proc.wait()


def wait_for(what, check, timeout):
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        if check():
            return True
        time.sleep(0.5)
    raise SystemExit(f'FAIL: {what} within {timeout} s')


def tail(path, n=15):
    try:
        with open(path, errors='replace') as f:
            return ''.join(f.readlines()[-n:])
    except OSError:
        return '(none)'


def main():
    exe = os.path.abspath(sys.argv[1])
    missing = [n for n in DAEMONS + CLIENTS if not which(n)]
    if missing:
        finish([f'{", ".join(missing)} not installed: Slurm and munge are needed for this test '
                '(scripts/bootstrap installs them: apt-get install slurm-wlm munge)'])
    failures = []
    t_start = time.monotonic()
    host = socket.gethostname().split('.')[0]
    # the sockets' paths must stay short (108 bytes)
    with tempfile.TemporaryDirectory(prefix='sylva-slurm-') as d:
        conf = write_conf(d, host, os.cpu_count() or 1)
        env = dict(os.environ, SLURM_CONF=conf, PATH=SEARCH)
        key = os.path.join(d, 'munge.key')
        with open(key, 'wb') as f:
            f.write(os.urandom(1024))
        os.chmod(key, 0o400)
        procs = {}
        try:
            # munged forks into the background and writes its pid file
            subprocess.run([which('munged'), '--force', f'--key-file={key}',
                            f'--socket={d}/munge.sock', f'--pid-file={d}/munged.pid',
                            f'--log-file={d}/munged.log', f'--seed-file={d}/munge.seed'],
                           check=True, env=env, capture_output=True, timeout=30)
            for name, log in (('slurmctld', 'ctld.out'), ('slurmd', 'd.out')):
                with open(os.path.join(d, log), 'w') as out:
                    procs[name] = subprocess.Popen([which(name), '-D', '-f', conf], env=env,
                                                   stdout=out, stderr=subprocess.STDOUT,
                                                   start_new_session=True)

            def idle():
                for name, p in procs.items():
                    if p.poll() is not None:
                        raise SystemExit(f'FAIL: {name} exited {p.returncode}:\n'
                                         f'{tail(os.path.join(d, "ctld.log" if name == "slurmctld" else "d.log"))}')
                p = subprocess.run([which('sinfo'), '-h', '-o', '%t'], env=env,
                                   capture_output=True, text=True)
                return p.returncode == 0 and p.stdout.strip() == 'idle'
            wait_for('the node idle in sinfo', idle, 90)
            t_up = time.monotonic()
            print(f'cluster up in {t_up - t_start:.1f} s')

            plan = small_plan('slurm', ['utdb:NoEast:PLAC', 'utdb:NoEast:TICO'], [1, 2, 3],
                              iterations=6)  # 12 runs
            plan_path = write_json(os.path.join(d, 'plan.json'), plan)
            folder = os.path.join(d, 'array of tasks')  # a space: sbatch must read it
            p = must(sylva(exe, 'sweep', plan_path, '--slurm', folder, '--submit', '--tasks',
                           str(TASKS), env=env), 'sylva sweep --slurm --submit')
            job = p.stdout.strip()
            print(f'submitted: job {job}')
            if not job.isdigit():
                failures.append(f'--submit printed {p.stdout!r}, not a job id')

            def gone():
                q = subprocess.run([which('squeue'), '-h', '-j', job], env=env,
                                   capture_output=True, text=True)
                return q.returncode == 0 and q.stdout.strip() == ''
            wait_for(f'job {job} done', gone, 300)
            t_job = time.monotonic()
            print(f'array job done in {t_job - t_up:.1f} s')
            for k in range(TASKS):
                if not os.path.exists(os.path.join(folder, f'task-{k}.log')):
                    failures.append(f'task {k} wrote no log in {folder}')
                if not os.path.exists(os.path.join(folder, f'task-{k}.db')):
                    failures.append(f'task {k} wrote no store; its log:\n'
                                    f'{tail(os.path.join(folder, f"task-{k}.log"))}')

            out = os.path.join(d, 'merged.db')
            p = sylva(exe, 'sweep', plan_path, '--merge', folder, '--db', out)
            print(f'merge: exit {p.returncode}: {p.stderr.strip()}')
            if p.returncode != 0:
                failures.append(f'merge: exit {p.returncode}')
            local = os.path.join(d, 'local.db')
            must(sylva(exe, 'sweep', plan_path, '--db', local, '--jobs', '2'), 'the local sweep')
            failures += check_places(plan, sweep_runs(out), 'merged from Slurm')
            failures += compare_sweeps(exe, local, out, d, 'Slurm against local')
        finally:
            stop(os.path.join(d, 'd.pid'), procs.get('slurmd'))
            stop(os.path.join(d, 'ctld.pid'), procs.get('slurmctld'))
            stop(os.path.join(d, 'munged.pid'))
            if failures:
                for log in ('ctld.log', 'd.log'):
                    print(f'--- {log}:\n{tail(os.path.join(d, log))}')
    print(f'Slurm test: {time.monotonic() - t_start:.1f} s')
    finish(failures)


main()
