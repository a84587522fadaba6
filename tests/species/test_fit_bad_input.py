"""`sylva fit` and `sylva species --utdb` on bad input (issue 20): each case exits 2,
names what is wrong (for a CSV row, the line), and writes no file, neither the
species (-o) nor the report (PREFIX.md, PREFIX.png).
Usage: test_fit_bad_input.py SYLVA"""
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from species_grow import finish, sylva  # noqa: E402

HEADER = 'age,dbh_cm,height_m,crown_diameter_m,crown_height_m\n'
# 13 good trees, on lines 2 to 14
ROWS = [f'{a},{2 + 1.5 * a},{3 + 0.4 * a},{1 + 0.3 * a},{2 + 0.3 * a}\n' for a in range(2, 40, 3)]
GOOD = HEADER + ''.join(ROWS)

# name: (the CSV's text or None for no file, sylva fit's arguments, phrases of stderr)
CASES = {
    'too few trees': (HEADER + ''.join(ROWS[:5]), ['data.csv'],
                      ['5 trees with a height', 'at least 8']),
    'non-numeric value': (HEADER + ROWS[0] + '5,abc,5,2.5,3.5\n' + ''.join(ROWS[2:]), ['data.csv'],
                          ['data:3:', 'column 2 (dbh_cm)', "'abc' is not a number"]),
    'negative value': (GOOD + '41,60,-3.5,9,7\n', ['data.csv'],
                       ['data:15:', 'column 3 (height_m)', '-3.5 is negative']),
    'no height at all': (HEADER + ''.join(f'{a},{a},,{a / 3},\n' for a in range(2, 40, 3)),
                         ['data.csv'], ['no tree has a height', 'height_m is empty']),
    'misspelled column': (HEADER.replace('height_m', 'hieght_m') + ''.join(ROWS), ['data.csv'],
                          ['data:1:', "column 3 of the header is 'hieght_m', expected 'height_m'"]),
    'missing column': (HEADER.replace(',crown_height_m', '') +
                       ''.join(r.rsplit(',', 1)[0] + '\n' for r in ROWS),
                       ['data.csv'], ['data:1:', 'the header must be', '(4 columns found)']),
    'empty file': ('', ['data.csv'], ['empty', 'no header']),
    'no such file': (None, ['absent.csv'], ['absent.csv', 'No such file']),
    'unknown code': (None, ['--utdb', 'NoEast:NOPE'],
                     ['no species NOPE in region NoEast', 'its codes:', 'PLAC', 'TICO']),
    'unknown region': (None, ['--utdb', 'Nowhere:PLAC'],
                       ['no region Nowhere', 'regions:', 'NoEast', 'PacfNW', 'InlVal']),
    'not REGION:CODE': (None, ['--utdb', 'PLAC'], ["'PLAC' is not REGION:CODE"]),
    'both data and --utdb': (GOOD, ['data.csv', '--utdb', 'NoEast:PLAC'],
                             ['give either DATA.csv or --utdb']),
    'neither data nor --utdb': (None, [], ['give either DATA.csv or --utdb']),
    'rho not a number': (GOOD, ['data.csv', '--rho', 'abc'],
                         ["--rho: 'abc' is not a length from 0.05 to 2 m"]),
    'rho too large': (GOOD, ['data.csv', '--rho', '5'], ["--rho: '5' is not a length"]),
    'seeds zero': (GOOD, ['data.csv', '--seeds', '0'],
                   ["sylva fit: --seeds: expected an integer from 1 to 16, got '0'"]),
    'seeds not a number': (GOOD, ['data.csv', '--seeds', 'x'],
                           ["sylva fit: --seeds: expected an integer from 1 to 16, got 'x'"]),
}


def main():
    exe = sys.argv[1]
    failures = []
    for name, (text, args, phrases) in CASES.items():
        with tempfile.TemporaryDirectory() as d:
            if text is not None:
                with open(os.path.join(d, 'data.csv'), 'w') as f:
                    f.write(text)
            before = set(os.listdir(d))
            p = sylva(exe, 'fit', *args, '-o', 'out.json', '--report', 'rep', cwd=d)
            written = sorted(set(os.listdir(d)) - before)
        message = p.stderr.strip().splitlines()[0] if p.stderr.strip() else '(nothing on stderr)'
        print(f'{name:24} exit {p.returncode}: {message}')
        if p.returncode != 2:
            failures.append(f'{name}: exit {p.returncode}, expected 2')
        failures += [f'{name}: stderr lacks "{s}"' for s in phrases if s not in p.stderr]
        if written:
            failures.append(f'{name}: wrote {", ".join(written)}')
    p = sylva(exe, 'species', '--utdb', 'NoEast:NOPE')
    print(f'{"species --utdb":24} exit {p.returncode}: {p.stderr.strip().splitlines()[0]}')
    if p.returncode != 2 or "no species 'NoEast:NOPE'" not in p.stderr:
        failures.append(f'sylva species --utdb NoEast:NOPE: exit {p.returncode}, {p.stderr!r}')
    finish(failures)


main()
