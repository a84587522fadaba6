"""`sylva sweep` refuses bad plans before it runs anything (issue 22): each case exits 2,
names the JSON pointer of what is wrong on stderr, and neither creates the --db file
nor changes one that is there (bad "shade" days included). The plans are over scenarios/street.json (species key
street-tree, 6 obstacles, the awning at index 2).
Usage: test_sweep_bad_plans.py SYLVA"""
import hashlib
import json
import os
import shutil
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sweep_common import STREET, finish, must, street, sylva  # noqa: E402

PLAC = 'utdb:NoEast:PLAC'


def plan(axes, **top):
    p = {'format': 'sylva.sweep/1', 'name': 'bad', 'scenario': 'street.json', 'axes': axes}
    p.update(top)
    return json.dumps(p)


RENAME = [{'op': 'move', 'from': '/species/street-tree', 'path': '/species/other'}] + \
    [{'op': 'replace', 'path': f'/plants/{i}/species', 'value': 'other'} for i in range(5)]

# the street without its plants, a site the variants below plant
SITE = street()
PLANT = [{'op': 'add', 'path': '/plants', 'value': SITE.pop('plants')[:2]}]

# name: (the plan's text, extra arguments, phrases of stderr: the pointer first)
CASES = {
    'unknown axis': (plan({'seed': [1], 'colour': ['red']}), [],
                     ['/axes/colour:', 'unknown axis']),
    'unknown species key': (plan({'species': {'tree': [PLAC]}}), [],
                            ['/axes/species/tree:', 'the scenario has no species "tree"']),
    'patch does not apply': (plan({'variants': {'as built': [], 'gone': [
        {'op': 'remove', 'path': '/obstacles/9'}]}}), [],
        ['/axes/variants/gone/0:', 'remove /obstacles/9', 'the array has 6 elements']),
    'patch test fails': (plan({'variants': {'no awning': [
        {'op': 'test', 'path': '/obstacles/3/id', 'value': 'awning'},
        {'op': 'remove', 'path': '/obstacles/3'}]}}), [],
        ['/axes/variants/no awning/0:', 'test /obstacles/3/id']),
    'patch second operation': (plan({'variants': {'v': [
        {'op': 'add', 'path': '/seed', 'value': 5},
        {'op': 'replace', 'path': '/nothing/here', 'value': 1}]}}), [],
        ['/axes/variants/v/1:', 'replace /nothing/here', '/nothing does not exist']),
    'patched scenario invalid': (plan({'variants': {'v': [
        {'op': 'replace', 'path': '/plants/0/roots/0', 'value': [0, -7.5, 0]}]}}), [],
        ['/axes/variants/v:', '/plants/0/roots/0', 'root inside an obstacle']),
    'variant without plants': (plan({'variants': {'v': [{'op': 'remove', 'path': '/plants'}]}}),
                               [], ['/axes/variants/v:', '/plants']),
    'variant renames the varied species': (
        plan({'species': {'street-tree': [PLAC]}, 'variants': {'renamed': RENAME}}), [],
        ['/axes/variants/renamed:', 'no species "street-tree"', '/axes/species/street-tree']),
    'variant not a patch': (plan({'variants': {'v': {'op': 'remove'}}}), [],
                            ['/axes/variants/v:', 'JSON Patch']),
    'empty species axis': (plan({'species': {'street-tree': []}}), [],
                           ['/axes/species/street-tree:', 'empty axis']),
    'species axis without keys': (plan({'species': {}}), [], ['/axes/species:']),
    'empty seed axis': (plan({'seed': []}), [], ['/axes/seed:', 'empty axis']),
    'empty variants axis': (plan({'variants': {}}), [], ['/axes/variants:', 'empty axis']),
    'no axes': (plan({}), [], ['/axes:']),
    'more than 10000 runs': (plan({'seed': list(range(101)),
                                   'variants': {f'v{i}': [] for i in range(100)}}), [],
                             ['/axes:', '10100 runs, more than 10000', '--force']),
    'more than a million runs even with --force': (
        plan({'seed': list(range(1001)), 'variants': {f'v{i}': [] for i in range(1000)}}),
        ['--force'], ['/axes:', '1001000 runs, more than 1000000']),
    'not JSON': ('{"format": "sylva.sweep/1", "name": ', [], ['plan.json', 'line 1']),
    'not an object': ('[1, 2]', [], ['plan.json', 'a plan is a JSON object']),
    'wrong format': (plan({'seed': [1]}, format='sylva.sweep/2'), [],
                     ['/format:', 'sylva.sweep/1']),
    'unknown top-level key': (plan({'seed': [1]}, seeds=[1]), [], ['/seeds:', 'unknown key']),
    'duplicate key': ('{"format": "sylva.sweep/1", "name": "bad", "scenario": "street.json",'
                      ' "axes": {"seed": [1], "seed": [2]}}', [], ['/axes/seed:', 'duplicate key']),
    'unknown preset': (plan({'species': {'street-tree': [PLAC, 'utdb:NoEast:NOPE']}}), [],
                       ['/axes/species/street-tree/1:', 'unknown library species',
                        'utdb:NoEast:NOPE']),
    'bad species object': (plan({'species': {'street-tree': [{'preset': PLAC, 'rho': -1}]}}), [],
                           ['/axes/species/street-tree/0:', '/species/street-tree/rho']),
    'preset listed twice': (plan({'species': {'street-tree': [PLAC, PLAC]}}), [],
                            ['/axes/species/street-tree/1:', 'listed twice']),
    'seed not an integer': (plan({'seed': [1, 2.5]}), [], ['/axes/seed/1:', 'integer']),
    'seed listed twice': (plan({'seed': [3, 3]}), [], ['/axes/seed/1:', 'listed twice']),
    'scenario file missing': (plan({'seed': [1]}, scenario='absent.json'), [],
                              ['/scenario:', 'absent.json']),
    'scenario invalid': (plan({'seed': [1]}, scenario={'format': 'sylva.scenario/1'}), [],
                         ['/scenario:']),
    'site without plants, no variants': (plan({'seed': [1]}, scenario=SITE), [],
                                         ['/scenario:', '/plants: required']),
    'shade date not a date': (plan({'seed': [1]}, shade={'date': '02-30', 'from': '10:00',
                                                          'to': '16:00'}), [],
                              ['/shade/date:', '02-30']),
    'shade time not HH:MM': (plan({'seed': [1]}, shade={'date': '07-21', 'from': '10:61'}), [],
                             ['/shade/from:', '10:61']),
    'shade from after to': (plan({'seed': [1]}, shade={'date': '07-21', 'from': '16:00',
                                                        'to': '10:00'}), [],
                            ['/shade/from:', '16:00 is not before /shade/to 10:00']),
    'shade step 0': (plan({'seed': [1]}, shade={'date': '07-21', 'step': 0}), [],
                     ['/shade/step:', 'an integer from 1 to 1440']),
    'shade step a fraction': (plan({'seed': [1]}, shade={'date': '07-21', 'step': 7.5}), [],
                              ['/shade/step:']),
    'shade without a date': (plan({'seed': [1]}, shade={'from': '10:00'}), [],
                             ['/shade/date:', 'missing']),
    'shade unknown key': (plan({'seed': [1]}, shade={'date': '07-21', 'hour': 3}), [],
                          ['/shade/hour:', 'unknown key']),
    'shade not an object': (plan({'seed': [1]}, shade='07-21'), [], ['/shade:', 'an object']),
    'site without plants, a variant without': (
        plan({'variants': {'bare': [], 'planted': PLANT}}, scenario=SITE), [],
        ['/axes/variants/bare:', '/plants: required']),
}


def digest(path):
    """The bytes of a store and its WAL, hashed; None when there is no file."""
    if not os.path.exists(path):
        return None
    h = hashlib.sha256()
    for p in (path, path + '-wal'):
        if os.path.exists(p):
            with open(p, 'rb') as f:
                h.update(f.read())
    return h.hexdigest()


def main():
    exe = sys.argv[1]
    failures = []
    with tempfile.TemporaryDirectory() as d:
        shutil.copy(STREET, d)
        # a store that is there already: a sweep of one run, one iteration
        good = os.path.join(d, 'good.json')
        with open(good, 'w') as f:
            f.write(plan({'seed': [1]}))
        kept = os.path.join(d, 'kept.db')
        must(sylva(exe, 'sweep', good, '--db', kept, '--iterations', '1', '--quiet-progress'),
             'the good sweep')
        kept_digest = digest(kept)
        for name, (text, args, phrases) in CASES.items():
            path = os.path.join(d, 'plan.json')
            with open(path, 'w') as f:
                f.write(text)
            for db in (os.path.join(d, 'new.db'), kept):
                p = sylva(exe, 'sweep', path, '--db', db, '--iterations', '1', *args, cwd=d)
                err = p.stderr.strip()
                if db == kept:
                    print(f'{name:44} exit {p.returncode}: {err.splitlines()[0] if err else "-"}'[:230])
                if p.returncode != 2:
                    failures.append(f'{name}: exit {p.returncode}, expected 2 ({err[:200]})')
                failures += [f'{name}: stderr lacks "{s}": {err[:300]}' for s in phrases
                             if s not in p.stderr]
                if len(err.splitlines()) != 1:
                    failures.append(f'{name}: {len(err.splitlines())} lines on stderr, expected one')
            if os.path.exists(os.path.join(d, 'new.db')):
                failures.append(f'{name}: created the --db file')
                os.unlink(os.path.join(d, 'new.db'))
            if digest(kept) != kept_digest:
                failures.append(f'{name}: changed the --db store that was there')
                kept_digest = digest(kept)
            # `sylva validate` names the same fault (a plan too big for sweep without
            # --force is still a valid plan; a file without the plan's format is read
            # as a scenario, and refused as one)
            p = sylva(exe, 'validate', path, cwd=d)
            if name in ('not an object', 'wrong format'):
                if p.returncode != 2:
                    failures.append(f'validate, {name}: exit {p.returncode}')
            elif name == 'more than 10000 runs':
                if p.returncode != 0 or 'without --force' not in p.stdout:
                    failures.append(f'validate, {name}: exit {p.returncode}: {p.stdout}{p.stderr}')
            elif p.returncode != 2 or any(s not in p.stderr for s in phrases):
                failures.append(f'validate, {name}: exit {p.returncode}: {p.stderr.strip()[:300]}')
            # the same plan with --slurm writes no script either
            p = sylva(exe, 'sweep', path, '--slurm', os.path.join(d, 'array'), *args, cwd=d)
            if p.returncode != 2 or os.path.exists(os.path.join(d, 'array')):
                failures.append(f'{name}: --slurm: exit {p.returncode} or wrote its folder')
                shutil.rmtree(os.path.join(d, 'array'), ignore_errors=True)
        # a site without plants is fine when every variant plants it
        path = os.path.join(d, 'plan.json')
        with open(path, 'w') as f:
            f.write(plan({'species': {'street-tree': [PLAC, 'utdb:NoEast:TICO']},
                          'variants': {'planted': PLANT}}, scenario=SITE))
        p = sylva(exe, 'sweep', path, '--db', os.path.join(d, 'site.db'), '--iterations', '1',
                  cwd=d)
        if p.returncode != 0:
            failures.append(f'a site planted by its variants: exit {p.returncode}: {p.stderr}')
        p = sylva(exe, 'validate', path, cwd=d)
        if p.returncode != 0 or p.stdout.strip() != \
                'ok: sweep bad: 2 runs (species/street-tree 2 x variant 1)':
            failures.append(f'validate, a site planted by its variants: exit {p.returncode}: '
                            f'{p.stdout.strip()} {p.stderr.strip()}')
        # 10100 runs pass with --force (not run: the --slurm script only, whose tasks
        # need --force too)
        path = os.path.join(d, 'plan.json')
        with open(path, 'w') as f:
            f.write(CASES['more than 10000 runs'][0])
        p = sylva(exe, 'sweep', path, '--force', '--slurm', os.path.join(d, 'array'), '--tasks',
                  '4', cwd=d)
        if p.returncode != 0:
            failures.append(f'10100 runs with --force: exit {p.returncode}: {p.stderr.strip()}')
        else:
            with open(os.path.join(d, 'array', 'sweep.sbatch')) as f:
                if ' --force ' not in f.read():
                    failures.append('the script of 10100 runs does not give its tasks --force')
    finish(failures)


main()
