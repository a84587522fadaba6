"""`sylva fit DATA.csv` on measurements generated from a database curve (issue 20):
40 trees aged 3 to 50 years, each measure scattered by a uniform +-15%; the fit
writes the species, its report and picture; the species grown alone (median of 3
seeds) must match the noise-free curve at ages 10 to 40: height within 20%, dbh
and crown diameter within 25% (crown height is printed).
Usage: test_fit_csv.py SYLVA"""
import os
import random
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from species_grow import MEASURES, compare, finish, fit, grow  # noqa: E402

# NoEast PLAC (London plane, Queens NY), the Urban Tree Database's chained curves
# (sylva_utdb_chain, clamped) at ages 0 to 50: height m, dbh cm, crown diameter m,
# crown height m. Written once from the library; the test only needs a realistic
# curve, the same one for the data and for the check.
CURVE = [
    (4.010, 2.403, 0.784, 2.323), (4.388, 3.690, 1.370, 2.603), (4.758, 4.963, 1.937, 2.878),
    (5.121, 6.222, 2.474, 3.147), (5.476, 7.467, 2.979, 3.412), (5.824, 8.698, 3.454, 3.671),
    (6.164, 9.915, 3.902, 3.925), (6.498, 11.117, 4.325, 4.174), (6.824, 12.306, 4.726, 4.419),
    (7.144, 13.480, 5.106, 4.658), (7.457, 14.640, 5.467, 4.893), (7.763, 15.786, 5.812, 5.124),
    (8.062, 16.918, 6.140, 5.349), (8.355, 18.036, 6.455, 5.570), (8.642, 19.140, 6.756, 5.787),
    (8.922, 20.230, 7.045, 6.000), (9.197, 21.306, 7.322, 6.207), (9.465, 22.367, 7.589, 6.411),
    (9.727, 23.415, 7.845, 6.611), (9.983, 24.448, 8.093, 6.806), (10.234, 25.467, 8.331, 6.997),
    (10.479, 26.472, 8.561, 7.185), (10.718, 27.463, 8.783, 7.368), (10.952, 28.440, 8.998, 7.547),
    (11.180, 29.403, 9.205, 7.723), (11.403, 30.352, 9.406, 7.894), (11.621, 31.287, 9.600, 8.062),
    (11.833, 32.207, 9.788, 8.227), (12.041, 33.114, 9.970, 8.387), (12.244, 34.006, 10.147, 8.544),
    (12.441, 34.884, 10.318, 8.698), (12.634, 35.748, 10.484, 8.848), (12.822, 36.598, 10.644, 8.994),
    (13.006, 37.434, 10.800, 9.138), (13.185, 38.256, 10.952, 9.277), (13.359, 39.064, 11.099, 9.414),
    (13.529, 39.858, 11.241, 9.547), (13.695, 40.637, 11.380, 9.677), (13.856, 41.403, 11.514, 9.804),
    (14.013, 42.154, 11.644, 9.928), (14.166, 42.891, 11.771, 10.049), (14.315, 43.614, 11.894, 10.167),
    (14.460, 44.323, 12.013, 10.281), (14.601, 45.018, 12.129, 10.393), (14.738, 45.699, 12.241, 10.502),
    (14.871, 46.366, 12.350, 10.608), (15.001, 47.019, 12.456, 10.711), (15.127, 47.657, 12.559, 10.812),
    (15.249, 48.282, 12.658, 10.909), (15.367, 48.892, 12.754, 11.004), (15.483, 49.488, 12.848, 11.096),
]
TREES, FIRST, LAST, NOISE = 40, 3, 50, 0.15
TOLERANCES = {'height': 0.20, 'dbh': 0.25, 'crown_diameter': 0.25}


def measurements():
    """The CSV: ages spread evenly over FIRST..LAST, each measure times a uniform
    factor of 1 +- NOISE (a fixed seed), crown height at most the height."""
    rng = random.Random(20)
    lines = ['age,dbh_cm,height_m,crown_diameter_m,crown_height_m']
    for i in range(TREES):
        age = round(FIRST + (LAST - FIRST) * i / (TREES - 1))
        h, dbh, cd, ch = (v * rng.uniform(1 - NOISE, 1 + NOISE) for v in CURVE[age])
        lines.append(f'{age},{dbh:.1f},{h:.2f},{cd:.2f},{min(ch, h):.2f}')
    return '\n'.join(lines) + '\n'


def main():
    exe = sys.argv[1]
    failures = []
    with tempfile.TemporaryDirectory() as d:
        with open(os.path.join(d, 'data.csv'), 'w') as f:
            f.write(measurements())
        species, secs, summary = fit(exe, ['data.csv'], d)
        print(f'sylva fit data.csv: {secs:.0f} s, {summary}')
        with open(os.path.join(d, 'mine.md')) as f:
            report = f.read()
        print(report)
        if '| 40 |' not in report:
            failures.append('mine.md: no row for age 40')
        with open(os.path.join(d, 'mine.png'), 'rb') as f:
            if f.read(8) != b'\x89PNG\r\n\x1a\n':
                failures.append('mine.png: not a PNG')
        if species.get('years') != 1:
            failures.append(f'mine.json: years {species.get("years")}, expected 1')
        grown = grow(exe, species, LAST, d)
    want = {age: dict(zip(MEASURES, CURVE[age])) for age in range(LAST + 1)}
    failures += compare('fit DATA.csv (40 trees of NoEast PLAC +-15%), grown, median of 3 '
                        'seeds: curve / model', grown, want, TOLERANCES)
    finish(failures)


main()
