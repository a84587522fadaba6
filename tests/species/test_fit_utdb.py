"""`sylva fit --utdb` on three species-regions outside the library (issue 20): each
is complete in the database and spans at least 40 years; its fitted species, grown
alone (median of 3 seeds), must match the data column of the fit's own report at
ages 10 to 40: height within 15%, dbh and crown diameter within 20%, crown height
within 25%, but for the known misses in KNOWN; and the trees grown here must be the
fit's own, its report's model column to the last printed digit. Prints the tables and the fit times.
Usage: test_fit_utdb.py SYLVA"""
import json
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from species_grow import AGES, compare, finish, fit, grow, report_data, same_as_report, sylva  # noqa: E402

# Chinese pistache (Sacramento Valley), green ash (Temperate Interior West), hackberry
# (Midwest). PacfNW:ACPL (Norway maple) was tried first, before the fit had the
# laterals' reach (docs/model.md, "Calibration", step 6): its young crowns missed (-29%
# at 10 years, -21% at 20).
KEYS = ('SacVal:PICH', 'TpIntW:FRPE', 'MidWst:CEOC')
TOLERANCES = {'height': 0.15, 'dbh': 0.20, 'crown_diameter': 0.20, 'crown_height': 0.25}
# Known misses: none since the crown's control moves the column shade with the shedding threshold
# (docs/model.md, "Calibration"). A miss listed here that meets its tolerance fails
# too, so the list cannot go stale.
KNOWN = set()


def main():
    exe = sys.argv[1]
    failures, times = [], []
    for key in KEYS:
        info = json.loads(sylva(exe, 'species', '--utdb', key, '--json').stdout)
        lo, hi = info['ages']
        if not info['complete'] or hi < max(AGES):
            failures.append(f'{key}: complete {info["complete"]}, ages {lo} to {hi}')
            continue
        with tempfile.TemporaryDirectory() as d:
            species, secs, summary = fit(exe, ['--utdb', key, '--report', 'report'], d)
            data = report_data(os.path.join(d, 'report.md'))
            model = report_data(os.path.join(d, 'report.md'), column=1)
            grown = grow(exe, species, max(AGES), d)
        times.append(f'{key} ({info["scientific"]}): fit {secs:.0f} s, {summary}')
        ages = [a for a in AGES if lo <= a <= hi and a in data]
        missed = compare(f'{key} {info["scientific"]}: data / model', grown, data, TOLERANCES,
                         ages)
        failures += same_as_report(key, grown, model, ages)
        for age in ages:
            for m, tol in TOLERANCES.items():
                bad = abs(grown[age][m] / data[age][m] - 1.0) > tol
                if (key, age, m) in KNOWN and not bad:
                    failures.append(f'{key}: age {age}, {m} is listed as a known miss but meets '
                                    f'its tolerance: take it off KNOWN')
        failures += [f for f in missed
                     if not any(f.startswith(f'{key} ') and f', {m}:' in f and f'age {a},' in f
                                for k, a, m in KNOWN if k == key)]
    print('\n'.join(times))
    finish(failures)


main()
