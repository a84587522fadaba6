"""Shared by the sweep tests (tests/sweep/meson.build): runs the sylva binary, writes
small plans over scenarios/street.json, reads a sweep's store with sqlite3 (its runs,
their place on the axes, whole tables) and compares two stores of one sweep run by
run, exports included. Python 3 standard library only."""
import json
import os
import sqlite3
import subprocess

SOURCE = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
SCENARIOS = os.path.join(SOURCE, 'scenarios')
STREET = os.path.join(SCENARIOS, 'street.json')
READY_PLAN = os.path.join(SCENARIOS, 'street-species.json')
# The obstacle the "no awning" variants remove, and its index in street.json.
AWNING = 'awning'


def sylva(exe, *args, cwd=None, env=None):
    """Runs `sylva ARGS`; returns the completed process (text stdout and stderr)."""
    return subprocess.run([os.path.abspath(exe), *args], cwd=cwd, env=env,
                          capture_output=True, text=True)


def must(p, what):
    """Exits with what and the process's stderr unless it exited 0."""
    if p.returncode != 0:
        raise SystemExit(f'{what}: exit {p.returncode}\n{p.stderr}')
    return p


def street(iterations=None):
    """scenarios/street.json as a dict, with another iteration limit if given."""
    with open(STREET) as f:
        s = json.load(f)
    if iterations is not None:
        s['iterations'] = iterations
    return s


def small_plan(name, species, seeds, awning_variant=True, iterations=None):
    """A plan over the street scenario inline: street-tree over `species`, `seeds`,
    and the variants "as built" and (if awning_variant) "no awning"."""
    variants = {'as built': []}
    if awning_variant:
        variants['no awning'] = [{'op': 'test', 'path': '/obstacles/2/id', 'value': AWNING},
                                 {'op': 'remove', 'path': '/obstacles/2'}]
    return {'format': 'sylva.sweep/1', 'name': name, 'scenario': street(iterations),
            'axes': {'species': {'street-tree': list(species)}, 'seed': list(seeds),
                     'variants': variants}}


def write_json(path, value):
    with open(path, 'w') as f:
        json.dump(value, f, indent=1)
    return path


def connect(db):
    """A read-only connection (the file must exist: opening creates nothing)."""
    return sqlite3.connect(f'file:{db}?mode=ro', uri=True, timeout=10)


def sweep_runs(db, sweep=None):
    """{run name: {'id', 'position', 'sweep', 'status', 'iterations', 'seed', 'scenario',
    'last', 'axes': {axis: value}}} of the store's swept runs."""
    with connect(db) as c:
        rows = c.execute(
            'SELECT r.id, r.name, w.sweep, w.position, r.status, r.iterations, r.seed,'
            ' r.scenario, (SELECT max(iteration) FROM iterations i WHERE i.run = r.id)'
            ' FROM sweep_runs w JOIN runs r ON r.id = w.run'
            ' WHERE ?1 IS NULL OR w.sweep = ?1 ORDER BY w.position', (sweep,)).fetchall()
        axes = {}
        for run, axis, value in c.execute('SELECT run, axis, value FROM run_axes'):
            axes.setdefault(run, {})[axis] = value
    c.close()
    return {name: {'id': rid, 'sweep': sw, 'position': pos, 'status': status,
                   'iterations': its, 'seed': seed, 'scenario': json.loads(scenario),
                   'last': last, 'axes': axes.get(rid, {})}
            for rid, name, sw, pos, status, its, seed, scenario, last in rows}


def run_count(db):
    with connect(db) as c:
        n = c.execute('SELECT count(*) FROM runs').fetchone()[0]
    c.close()
    return n


def tables(db):
    """Every row of every table, sorted: the store's content (rowids aside)."""
    out = {}
    with connect(db) as c:
        names = [r[0] for r in c.execute(
            "SELECT name FROM sqlite_schema WHERE type = 'table' ORDER BY name")]
        for t in names:
            out[t] = sorted(c.execute(f'SELECT * FROM "{t}"').fetchall(), key=repr)
        out['user_version'] = c.execute('PRAGMA user_version').fetchone()[0]
    c.close()
    return out


def expected_names(plan):
    """The run names of a plan in position order (docs/cli.md, "sweep": the plan's
    name, then each axis's value, the last axis varying fastest), with their axes."""
    axes = []
    for key, values in plan['axes'].items():
        if key == 'species':
            for skey, svalues in values.items():
                axes.append((skey, f'species/{skey}',
                             [v if isinstance(v, str) else f'{skey}#{i + 1}'
                              for i, v in enumerate(svalues)],
                             [v if isinstance(v, str) else json.dumps(v, separators=(',', ':'))
                              for v in svalues]))
        elif key == 'seed':
            axes.append(('seed', 'seed', [str(s) for s in values], [str(s) for s in values]))
        else:
            axes.append(('variant', 'variant', list(values), list(values)))
    out = [([], {})]
    for label, axis, shown, stored in axes:
        out = [(parts + [f'{label}={s}'], dict(ax, **{axis: v}))
               for parts, ax in out for s, v in zip(shown, stored)]
    return [(f'{plan["name"]}: ' + ', '.join(parts), ax) for parts, ax in out]


def exports(exe, db, name, workdir):
    """The run's csv and skeleton exports, as bytes."""
    out = {}
    for fmt in ('csv', 'skeleton'):
        path = os.path.join(workdir, f'export.{fmt}')
        must(sylva(exe, 'export', '--db', db, '--name', name, '--format', fmt, '-o', path),
             f'sylva export {name} --format {fmt}')
        with open(path, 'rb') as f:
            out[fmt] = f.read()
        os.unlink(path)
    return out


def hashes(db, run_id):
    with connect(db) as c:
        rows = c.execute('SELECT iteration, hash, nodes FROM iterations WHERE run = ?'
                         ' ORDER BY iteration', (run_id,)).fetchall()
    c.close()
    return rows


def compare_sweeps(exe, a, b, workdir, what):
    """Failures where store b's sweep differs from store a's: the run names, each run's
    position, axes, status, scenario and iteration limit, every stored iteration's hash,
    and its csv and skeleton exports byte for byte."""
    failures = []
    ra, rb = sweep_runs(a), sweep_runs(b)
    if sorted(ra) != sorted(rb):
        failures.append(f'{what}: run names differ: only in {a}: {sorted(set(ra) - set(rb))}; '
                        f'only in {b}: {sorted(set(rb) - set(ra))}')
    for name in sorted(set(ra) & set(rb)):
        x, y = ra[name], rb[name]
        for k in ('sweep', 'position', 'axes', 'status', 'scenario', 'iterations', 'seed', 'last'):
            if x[k] != y[k]:
                failures.append(f'{what}: "{name}": {k} {x[k]!r} != {y[k]!r}')
        if hashes(a, x['id']) != hashes(b, y['id']):
            failures.append(f'{what}: "{name}": the stored iterations differ')
        ea, eb = exports(exe, a, name, workdir), exports(exe, b, name, workdir)
        for fmt in ea:
            if ea[fmt] != eb[fmt]:
                failures.append(f'{what}: "{name}": the {fmt} exports differ '
                                f'({len(ea[fmt])} and {len(eb[fmt])} bytes)')
    return failures


def check_places(plan, runs, what):
    """Failures where the store's runs are not exactly the plan's, each finished at
    its position with its axes, and its scenario with its species, seed and variant."""
    failures = []
    expected = expected_names(plan)
    if sorted(runs) != sorted(n for n, _ in expected):
        failures.append(f'{what}: {len(runs)} runs stored, expected {len(expected)}: '
                        f'{sorted(set(runs) ^ set(n for n, _ in expected))[:4]}...')
    for position, (name, axes) in enumerate(expected):
        r = runs.get(name)
        if r is None:
            continue
        if r['position'] != position:
            failures.append(f'{what}: "{name}" at position {r["position"]}, expected {position}')
        if r['axes'] != axes:
            failures.append(f'{what}: "{name}": axes {r["axes"]}, expected {axes}')
        if r['status'] != 'finished':
            failures.append(f'{what}: "{name}": status {r["status"]}')
        s = r['scenario']
        if 'seed' in axes and (s.get('seed') != int(axes['seed']) or r['seed'] != int(axes['seed'])):
            failures.append(f'{what}: "{name}": seed {s.get("seed")}/{r["seed"]}, '
                            f'expected {axes["seed"]}')
        ids = [o['id'] for o in s.get('obstacles', [])]
        if axes.get('variant') == 'no awning' and AWNING in ids:
            failures.append(f'{what}: "{name}": the awning is still there')
        if axes.get('variant') == 'as built' and AWNING not in ids:
            failures.append(f'{what}: "{name}": the awning is missing')
    return failures


def species_objects(exe, presets, workdir):
    """{preset: the species object a store keeps for it} (sylva stores a scenario with
    its presets expanded): one stored 1-iteration run of the street per preset."""
    out = {}
    db = os.path.join(workdir, 'presets.db')
    for preset in presets:
        s = street(1)
        s['species']['street-tree'] = {'preset': preset}
        path = write_json(os.path.join(workdir, 'preset.json'), s)
        must(sylva(exe, 'run', path, '--db', db, '--name', preset, '--quiet-progress'),
             f'sylva run with {preset}')
        with connect(db) as c:
            scenario = c.execute('SELECT scenario FROM runs WHERE name = ?', (preset,)).fetchone()[0]
        c.close()
        out[preset] = json.loads(scenario)['species']['street-tree']
    return out


def finish(failures):
    """Exits 1 listing the failures, or 0."""
    for f in failures:
        print('FAIL:', f)
    if not failures:
        print('ok')
    raise SystemExit(1 if failures else 0)
