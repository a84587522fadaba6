"""`sylva species` (issue 20): one database species with --utdb (names, n and R2 per
curve, age range), the library as a table with the citation, and the library as
one JSON object a line (every entry complete, named utdb:REGION:CODE). The
library may still be empty; its format and the citation are checked all the same.
Usage: test_species_list.py SYLVA"""
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from species_grow import finish, sylva  # noqa: E402

CITATION = ('McPherson, van Doorn and Peper 2016', 'https://doi.org/10.2737/RDS-2016-0005')
CURVES = ('dbh', 'height', 'crown_diameter', 'crown_height')
FIELDS = ('name', 'scientific', 'common', 'region', 'code', 'n', 'r2', 'error')


def main():
    exe = sys.argv[1]
    failures = []

    def check(ok, what):
        if not ok:
            failures.append(what)

    p = sylva(exe, 'species', '--utdb', 'NoEast:PLAC', '--json')
    print(p.stdout, end='')
    check(p.returncode == 0, f'species --utdb --json: exit {p.returncode}: {p.stderr}')
    plac = json.loads(p.stdout)
    check(plac.get('scientific') == 'Platanus x acerifolia', f'scientific: {plac.get("scientific")}')
    check((plac.get('region'), plac.get('code')) == ('NoEast', 'PLAC'), 'region and code')
    check(isinstance(plac.get('n'), (int, float)) and plac['n'] > 0, f'n: {plac.get("n")}')
    r2 = plac.get('r2', {})
    check(all(0 < r2.get(c, -1) <= 1 for c in CURVES), f'r2 per curve: {r2}')
    ages = plac.get('ages')
    check(isinstance(ages, list) and len(ages) == 2 and 0 <= ages[0] < ages[1], f'ages: {ages}')
    check(plac.get('complete') is True, 'complete')

    p = sylva(exe, 'species', '--utdb', 'NoEast:PLAC')
    print(p.stdout, end='')
    check(p.returncode == 0 and 'Platanus x acerifolia' in p.stdout, 'species --utdb: the table')
    check(all(c in p.stdout for c in CITATION), 'species --utdb: the citation')

    p = sylva(exe, 'species')
    print(p.stdout, end='')
    check(p.returncode == 0, f'species: exit {p.returncode}: {p.stderr}')
    check(all(c in p.stdout for c in CITATION), 'species: the citation')
    check(p.stdout.startswith('NAME'), 'species: the table has a header')
    rows = len(p.stdout.splitlines()) - 2

    p = sylva(exe, 'species', '--json')
    check(p.returncode == 0, f'species --json: exit {p.returncode}: {p.stderr}')
    lines = p.stdout.splitlines()
    check(len(lines) == rows, f'species --json: {len(lines)} lines, the table {rows} rows')
    for line in lines:
        e = json.loads(line)
        check(isinstance(e, dict) and all(k in e for k in FIELDS), f'fields of {line}')
        check(e.get('name') == f'utdb:{e.get("region")}:{e.get("code")}', f'name of {line}')
        check(all(isinstance(e.get(k), str) and e[k] for k in FIELDS[:5]), f'names of {line}')
        check(isinstance(e.get('n'), (int, float)) and e['n'] > 0, f'n of {line}')
        check(isinstance(e.get('r2'), dict) and 'height' in e['r2'], f'r2 of {line}')
        check(isinstance(e.get('error'), dict) and all(c in e['error'] for c in CURVES),
              f'error of {line}')
    print(f'library: {len(lines)} species')
    finish(failures)


main()
