"""`sylva import` through the real binary: the summary line, the skeleton it writes
(sylva.skeleton/1, one plant "imported", one stem per root), an earlier stage, the
skeleton read back, a SimpleForest CSV of two ground stems and a floating piece, and
bad input and options: exit 2, a message naming what is wrong, and no file written.
Usage: test_import_cli.py SYLVA DATA_DIR"""
import json
import os
import subprocess
import sys
import tempfile

SUMMARY_KEYS = ['cylinders', 'nodes', 'height', 'dbh', 'volume', 'length', 'branches',
                'max_order', 'age', 'stems', 'pieces_dropped']

failures = []


def check(cond, what):
    if not cond:
        failures.append(what)
        print('FAIL:', what, file=sys.stderr)


def sylva(exe, args):
    return subprocess.run([exe] + args, capture_output=True, text=True, timeout=120)


def skeleton_ok(path, summary):
    with open(path) as f:
        doc = json.load(f)
    check(doc.get('format') == 'sylva.skeleton/1', f'{path}: format')
    plants = doc.get('plants', [])
    check(len(plants) == 1 and plants[0].get('id') == 'imported', f'{path}: one plant "imported"')
    stems = plants[0]['stems']
    check(len(stems) == summary['stems'], f'{path}: {len(stems)} stems, summary {summary["stems"]}')
    nodes = [n for s in stems for n in s['nodes']]
    check(len(nodes) == summary['nodes'], f'{path}: {len(nodes)} nodes, summary {summary["nodes"]}')
    ids = {n[0] for n in nodes}
    for s in stems:
        check(s['nodes'][0][1] == -1 and s['nodes'][0][2:5] == s['root'], f'{path}: stem root')
    bad = [n for n in nodes if len(n) != 7 or (n[1] != -1 and n[1] not in ids) or n[6] > 0
           or n[5] <= 0]
    check(not bad, f'{path}: nodes [id, parent, x, y, z, radius, birth]: {bad[:3]}')
    return doc, nodes


def main():
    exe, data = sys.argv[1], sys.argv[2]
    trunk = os.path.join(data, 'qsms_qsm_trunk.mat')
    tree = os.path.join(data, 'non_buttressed_trees_single_qsm_tree_2_qsm.mat')
    with tempfile.TemporaryDirectory() as d:
        out = os.path.join(d, 'out.json')
        # a tree with a floating piece: the summary and the file
        r = sylva(exe, ['import', tree, '-o', out])
        check(r.returncode == 0, f'import: exit {r.returncode}: {r.stderr}')
        lines = r.stdout.splitlines()
        check(len(lines) == 1, f'one summary line, got {lines}')
        s = json.loads(lines[0])
        check(all(k in s for k in SUMMARY_KEYS), f'summary keys: {sorted(s)}')
        check(s['pieces_dropped'] == 1 and s['stems'] == 1, f'pieces: {s}')
        td = s.get('treedata', {})
        check(abs(s['height'] / td['height'] - 1) < 0.02, f'height {s["height"]} against {td}')
        check(abs(s['volume'] / td['volume'] - 1) < 0.1, f'volume {s["volume"]} against {td}')
        skeleton_ok(out, s)
        check(not os.path.exists(out + '.tmp'), 'no .tmp left')
        # ten years before: fewer nodes, younger, lower
        r = sylva(exe, ['import', tree, '--years-before', '10', '-o', out])
        check(r.returncode == 0, f'--years-before: exit {r.returncode}: {r.stderr}')
        s10 = json.loads(r.stdout)
        check(s10['nodes'] < s['nodes'] and s10['height'] < s['height'], f'stage: {s10}')
        check(s10['age'] == s['age'] - 10 and s10.get('years_before') == 10, f'stage age: {s10}')
        skeleton_ok(out, s10)
        # an age, another species and rho
        r = sylva(exe, ['import', trunk, '--age', '40', '--species', 'utdb:NoEast:TICO',
                        '--rho', '0.5', '-o', out])
        check(r.returncode == 0, f'--age --species --rho: exit {r.returncode}: {r.stderr}')
        st = json.loads(r.stdout)
        check(st['age'] == 40 and st['stems'] == 1 and st['branches'] == 0, f'trunk: {st}')
        check(49 <= st['nodes'] <= 54, f'trunk of 25.9 m at rho 0.5: {st["nodes"]} nodes')
        # the skeleton read back
        back = os.path.join(d, 'back.json')
        r = sylva(exe, ['import', out, '--rho', '0.5', '-o', back])
        check(r.returncode == 0, f'skeleton read back: exit {r.returncode}: {r.stderr}')
        sb = json.loads(r.stdout)
        check(abs(sb['height'] - st['height']) < 0.01 and sb['nodes'] == st['nodes'],
              f'read back: {sb} against {st}')
        # a SimpleForest CSV: two stems on the ground, a piece floating in the crown
        csv = os.path.join(d, 'two.csv')
        with open(csv, 'w') as f:
            f.write('ID,parentID,startX,startY,startZ,endX,endY,endZ,radius\n'
                    '0,-1,0,0,0,0,0,3,0.1\n'
                    '1,0,0,0,1.5,1.5,1.5,2,0.03\n'
                    '2,-1,0.8,0.6,0.2,0.9,0.6,2.5,0.06\n'
                    '3,-1,0.5,0.5,2.2,0.7,0.6,2.6,0.01\n')
        r = sylva(exe, ['import', csv, '-o', out])
        check(r.returncode == 0, f'CSV: exit {r.returncode}: {r.stderr}')
        sc = json.loads(r.stdout)
        check(sc['stems'] == 2 and sc['pieces_dropped'] == 1 and 'treedata' not in sc,
              f'two stems, one piece dropped: {sc}')
        skeleton_ok(out, sc)

        # bad input and options: exit 2, a message, nothing written
        bad_text = os.path.join(d, 'bad.txt')
        with open(bad_text, 'w') as f:
            f.write('0.1 1 0 0 0 0 0 1 0 0 1 0 1 0 0\n0.1 x 0 0 1 0 0 1 1 0 1 0 2 0 0\n')
        cases = {
            'a bad value': (['import', bad_text, '--format', 'text'], ['bad.txt', 'row 2']),
            'no such file': (['import', os.path.join(d, 'absent.mat')], ['absent.mat']),
            'not a model': (['import', csv + '.nope'], ['two.csv.nope']),
            'unknown format': (['import', trunk, '--format', 'las'],
                               ["--format: 'las' is not mat, text, csv or skeleton"]),
            'unknown species': (['import', trunk, '--species', 'utdb:NoEast:NOPE'],
                                ["unknown library species 'utdb:NoEast:NOPE'", 'utdb:NoEast:PLAC']),
            'age beyond the oldest': (['import', trunk, '--age', '501'], ['--age', '500']),
            'age zero': (['import', trunk, '--age', '0'], ['--age: expected an integer from 1']),
            'rho too short': (['import', trunk, '--rho', '0.001'], ["--rho: '0.001'"]),
            'before the planting': (['import', trunk, '--age', '20', '--years-before', '21'],
                                    ['--years-before 21', '20 years old']),
            'model beyond the file': (['import', trunk, '--model', '2'], ['model 2']),
            'unknown option': (['import', trunk, '--colour', 'red'], ["unknown option '--colour'"]),
            'two files': (['import', trunk, tree], ['unexpected argument']),
        }
        for name, (args, phrases) in cases.items():
            target = os.path.join(d, 'bad.json')
            r = sylva(exe, args + ['-o', target])
            check(r.returncode == 2, f'{name}: exit {r.returncode}, expected 2 ({r.stderr})')
            for p in phrases:
                check(p in r.stderr, f'{name}: stderr lacks {p!r}: {r.stderr!r}')
            check(r.stdout == '', f'{name}: stdout {r.stdout!r}')
            check(not os.path.exists(target) and not os.path.exists(target + '.tmp'),
                  f'{name}: a file was written')
        r = sylva(exe, ['import', trunk])
        check(r.returncode == 2 and '-o FILE is required' in r.stderr, f'no -o: {r.stderr}')
        r = sylva(exe, ['import', '--help'])
        check(r.returncode == 0 and 'Usage: sylva import' in r.stdout, 'import --help')
        r = sylva(exe, ['--help'])
        check('import FILE -o OUT.json' in r.stdout, 'sylva --help lists import')
    print(f'import-cli: {"ok" if not failures else f"{len(failures)} failed"}')
    return 1 if failures else 0


if __name__ == '__main__':
    sys.exit(main())
