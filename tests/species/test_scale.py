"""The model across scales (issue 20, item 2): NoEast PLAC fitted by `sylva fit
--utdb` (rho 0.25, ref_rho 0.25), grown alone at rho 0.25 and at rho 0.125 (ref_rho
kept, so that its counts scale; the voxel is rho / 2), median of 3 seeds: at ages
20, 30 and 40 height, dbh and crown diameter agree within 15%.
Usage: test_scale.py SYLVA"""
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from species_grow import compare, finish, fit, grow  # noqa: E402

AGES = (20, 30, 40)
TOLERANCES = {'height': 0.15, 'dbh': 0.15, 'crown_diameter': 0.15}


def main():
    exe = sys.argv[1]
    with tempfile.TemporaryDirectory() as d:
        species, secs, summary = fit(exe, ['--utdb', 'NoEast:PLAC'], d)
        print(f'sylva fit --utdb NoEast:PLAC: {secs:.0f} s, {summary}')
        if (species.get('rho'), species.get('ref_rho')) != (0.25, 0.25):
            finish([f'rho {species.get("rho")}, ref_rho {species.get("ref_rho")}: expected 0.25'])
        coarse = grow(exe, species, max(AGES), d)
        fine = grow(exe, dict(species, rho=0.125), max(AGES), d)
    finish(compare('NoEast PLAC: rho 0.25 / rho 0.125', fine, coarse, TOLERANCES, AGES))


main()
