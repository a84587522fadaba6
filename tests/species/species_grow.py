"""Shared by the species tests (tests/species/meson.build): runs the sylva binary,
fits a species, grows it alone in an open world over several seeds and takes the
medians per age, reads a fit's report, and prints a table of measures against
reference values with tolerances. Python 3 standard library only."""
import json
import os
import statistics
import subprocess
import time

# The measures compared, as `sylva fit`'s report orders them: height (m), dbh (cm),
# crown diameter (m), crown height (m).
MEASURES = ('height', 'dbh', 'crown_diameter', 'crown_height')
AGES = (10, 20, 30, 40)
SEEDS = (1, 2, 3)


def sylva(exe, *args, cwd=None):
    """Runs `sylva ARGS` (in cwd; exe may be relative to this process's directory, as
    meson gives it); returns the completed process (text stdout and stderr)."""
    return subprocess.run([os.path.abspath(exe), *args], cwd=cwd, capture_output=True, text=True)


def fit(exe, args, workdir, out='mine.json'):
    """Runs `sylva fit ARGS -o OUT` in workdir; returns (species object, seconds,
    stdout's JSON line). Exits with the fit's stderr when it fails."""
    t0 = time.monotonic()
    p = sylva(exe, 'fit', *args, '-o', out, cwd=workdir)
    secs = time.monotonic() - t0
    if p.returncode != 0:
        raise SystemExit(f'sylva fit {" ".join(args)}: exit {p.returncode}\n{p.stderr}')
    with open(os.path.join(workdir, out)) as f:
        species = json.load(f)
    if not isinstance(species, dict):
        raise SystemExit(f'{out}: not a JSON object')
    return species, secs, json.loads(p.stdout)


def grow(exe, species, years, workdir, seeds=SEEDS):
    """Grows the species alone (one tree at the origin, world +-15 m x 30 m high) for
    `years` iterations, once per seed; returns {age: {measure: median over seeds}}
    (dbh in cm, crown height = height - crown base, 0 without a crown base)."""
    scenario = {
        'format': 'sylva.scenario/1', 'name': 'one tree alone', 'seed': 1,
        'iterations': years,
        'world': {'min': [-15, -15, 0], 'max': [15, 15, 30]},
        'species': {'mine': species},
        'plants': [{'id': 'tree', 'species': 'mine', 'roots': [[0, 0, 0]]}],
    }
    path = os.path.join(workdir, 'grow.json')
    with open(path, 'w') as f:
        json.dump(scenario, f)
    per_age = {}
    for seed in seeds:
        p = sylva(exe, 'run', path, '--seed', str(seed), '--quiet-progress')
        if p.returncode != 0:
            raise SystemExit(f'sylva run (seed {seed}): exit {p.returncode}\n{p.stderr}')
        for line in p.stdout.splitlines():
            row = json.loads(line)
            if 'iteration' not in row:
                continue
            s = row['stems'][0]
            base = s['crown_base']
            sizes = {'height': s['height'], 'dbh': 100.0 * s['dbh'],
                     'crown_diameter': s['crown_width'],
                     'crown_height': s['height'] - base if base is not None else 0.0}
            per_age.setdefault(row['iteration'], []).append(sizes)
    return {age: {m: statistics.median(r[m] for r in rows) for m in MEASURES}
            for age, rows in per_age.items() if len(rows) == len(seeds)}


def report_data(path, column=0):
    """A column of a fit's report (PREFIX.md), the data (0) or the model (1):
    {age: {measure: value}}."""
    data = {}
    with open(path) as f:
        for line in f:
            cells = [c.strip() for c in line.strip().strip('|').split('|')]
            if len(cells) == 5 and cells[0].isdigit():
                data[int(cells[0])] = {m: float(c.split('/')[column].split('(')[0])
                                       for m, c in zip(MEASURES, cells[1:])}
    return data


def same_as_report(title, grown, report, ages):
    """The failures where a tree grown here differs from the model column of the fit's
    report: the fit grows its trees in an open world bounded in whole metres around
    the root, as grow() does, so they are the same trees (docs/model.md,
    "Calibration"). The report rounds the exact value to 2 decimals (0.005 off at
    most), the run lines give metres to 4 (0.00005 m, 0.005 cm of dbh), so the two
    may differ by 0.01 in the last printed digit and no more."""
    return [f'{title}: age {a}, {m}: grown {grown[a][m]:.4f}, the fit\'s report {report[a][m]:.2f}'
            for a in ages for m in MEASURES if abs(grown[a][m] - report[a][m]) > 0.0101]


def compare(title, got, want, tolerances, ages=AGES):
    """Prints got against want at each age (measure: want / got, error) and returns
    the failures: |got / want - 1| above the measure's tolerance (a measure without
    a tolerance is printed only)."""
    print(f'{title}\n  age  ' + '  '.join(f'{m:>26}' for m in MEASURES))
    failures = []
    for age in ages:
        cells = []
        for m in MEASURES:
            w, g = want[age][m], got[age][m]
            e = g / w - 1.0
            tol = tolerances.get(m)
            bad = tol is not None and abs(e) > tol
            cells.append(f'{w:8.2f} / {g:7.2f} ({100 * e:+4.0f}%){"!" if bad else " "}')
            if bad:
                failures.append(f'{title}: age {age}, {m}: {g:.2f} against {w:.2f} '
                                f'({100 * e:+.1f}%, tolerance {100 * tol:.0f}%)')
        print(f'  {age:3d}  ' + '  '.join(cells))
    return failures


def finish(failures):
    """Exits 1 listing the failures, or 0."""
    for f in failures:
        print('FAIL:', f)
    raise SystemExit(1 if failures else 0)
