#!/usr/bin/env python3
"""Reads the meshes of test_mesh and the scenes of test_gltf back with assimp
(Debian's assimp-utils).

Runs `TEST OUTDIR` (test_mesh writes OBJ and PLY files, test_gltf GLB files, each
with a manifest, expected.tsv, of the vertex and face counts derived from the
world), then `assimp info` on every file, and compares what assimp reports:

- `assimp info -r` (raw import, no post-processing):
  PLY: exactly the file's vertices and faces, in one mesh;
  OBJ: exactly the file's faces, one mesh per object with its name and faces;
       the OBJ importer gives every face corner its own vertex, so the vertices
       are 3 * faces, per mesh and in total.
- `assimp info` (its default post-processing, which joins identical vertices
  within a mesh): faces as in the file; PLY vertices as in the file; OBJ
  vertices per mesh equal to the object's own vertices (sides * rings of a stem,
  8 of a box): no two vertices of an object coincide, so joining undoes exactly
  the per-corner split.
- GLB, raw and default: exactly the file's vertices and faces; one mesh per glTF
  primitive, named for its glTF mesh (with -K for primitive K of a mesh of
  several), with its faces and vertices (no two vertices of a primitive agree in
  position, normal and texture coordinates, so joining changes nothing).
Every primitive must be a triangle. When assimp is missing the check fails: run
scripts/bootstrap. Prints every failure, then "N passed, N failed".
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile

TOTAL = re.compile(r"^(Meshes|Vertices|Faces):\s+(\d+)\s*$")
MESH = re.compile(r"^\s+(\d+) \((.*)\): \[(\d+) / (\d+) / (\d+) \| (.*)\]\s*$")
PRIMITIVES = re.compile(r"^Primitive Types:\s+(.*?)\s*$")


def assimp_info(path, raw):
    """Returns ({'Meshes': n, 'Vertices': n, 'Faces': n}, [(name, vertices, faces, types)],
    primitive types) or raises RuntimeError."""
    cmd = ["assimp", "info", path] + (["-r"] if raw else [])
    proc = subprocess.run(cmd, capture_output=True, timeout=120)
    out = proc.stdout.decode("utf-8", "replace")
    if proc.returncode != 0:
        raise RuntimeError("%s: exit status %d\n%s%s" % (" ".join(cmd), proc.returncode, out,
                                                       proc.stderr.decode("utf-8", "replace")))
    totals, meshes, primitives = {}, [], None
    in_meshes = False
    for line in out.splitlines():
        m = TOTAL.match(line)
        if m and not in_meshes:
            totals[m.group(1)] = int(m.group(2))
            continue
        m = PRIMITIVES.match(line)
        if m:
            primitives = m.group(1)
            continue
        if line.startswith("Meshes:  (name)"):
            in_meshes = True
            continue
        if in_meshes:
            m = MESH.match(line)
            if m:
                meshes.append((m.group(2), int(m.group(3)), int(m.group(5)), m.group(6)))
            elif line.strip() == "" or not line.startswith(" "):
                in_meshes = False
    for key in ("Meshes", "Vertices", "Faces"):
        if key not in totals:
            raise RuntimeError("%s: no '%s:' line in\n%s" % (" ".join(cmd), key, out))
    return totals, meshes, primitives


def read_manifest(path):
    files, objects = [], {}
    with open(path, encoding="utf-8") as f:
        for line in f:
            cols = line.rstrip("\n").split("\t")
            if cols[0] == "file":
                files.append((cols[1], cols[2], int(cols[3]), int(cols[4])))
            elif cols[0] == "object":
                objects.setdefault(cols[1], []).append((cols[2], int(cols[3]), int(cols[4])))
            else:
                raise ValueError("%s: bad line %r" % (path, line))
    return files, objects


class Checker:
    def __init__(self):
        self.passed = 0
        self.failed = 0

    def eq(self, what, got, want):
        if got == want:
            self.passed += 1
        else:
            self.failed += 1
            print("FAIL %s: assimp reports %r, expected %r" % (what, got, want))

    def fail(self, what):
        self.failed += 1
        print("FAIL %s" % what)


def check_file(chk, path, fmt, vertices, faces, objects):
    name = os.path.basename(path)
    for raw in (True, False):
        mode = "raw" if raw else "default"
        try:
            totals, meshes, primitives = assimp_info(path, raw)
        except (RuntimeError, subprocess.TimeoutExpired) as e:
            chk.fail("%s (%s): %s" % (name, mode, e))
            continue
        chk.eq("%s (%s) faces" % (name, mode), totals["Faces"], faces)
        chk.eq("%s (%s) primitive types" % (name, mode), primitives, "triangles")
        if fmt == "glb":
            chk.eq("%s (%s) vertices" % (name, mode), totals["Vertices"], vertices)
            chk.eq("%s (%s) meshes" % (name, mode), totals["Meshes"], len(objects))
            got = [(m[0], m[2], m[1]) for m in meshes]
            want = [(o[0], o[1], o[2]) for o in objects]
            chk.eq("%s (%s) meshes (name, faces, vertices)" % (name, mode), got, want)
            continue
        if fmt == "ply":
            chk.eq("%s (%s) vertices" % (name, mode), totals["Vertices"], vertices)
            chk.eq("%s (%s) meshes" % (name, mode), totals["Meshes"], 1)
            continue
        chk.eq("%s (%s) vertices" % (name, mode), totals["Vertices"],
               3 * faces if raw else vertices)
        chk.eq("%s (%s) meshes" % (name, mode), totals["Meshes"], len(objects))
        got = [(m[0], m[2], m[1]) for m in meshes]
        want = [(o[0], o[1], 3 * o[1] if raw else o[2]) for o in objects]
        chk.eq("%s (%s) meshes (name, faces, vertices)" % (name, mode), got, want)


def main():
    if len(sys.argv) != 2:
        print("usage: assimp_check.py TEST_MESH|TEST_GLTF", file=sys.stderr)
        return 2
    chk = Checker()
    if shutil.which("assimp") is None:
        chk.fail("assimp not found: install Debian's assimp-utils by running scripts/bootstrap")
        print("%d passed, %d failed" % (chk.passed, chk.failed))
        return 1
    with tempfile.TemporaryDirectory(prefix="sylva-mesh-") as out:
        write_meshes(chk, sys.argv[1], out)
        check_manifest(chk, sys.argv[1], out)
    print("%d passed, %d failed" % (chk.passed, chk.failed))
    return 1 if chk.failed else 0


def write_meshes(chk, test_mesh, out):
    """`test_mesh OUTDIR` writes the meshes and expected.tsv into out."""
    proc = subprocess.run([test_mesh, out], capture_output=True, timeout=300)
    if proc.returncode != 0:
        chk.fail("%s %s: exit status %d\n%s%s" % (
            test_mesh, out, proc.returncode, proc.stdout.decode("utf-8", "replace"),
            proc.stderr.decode("utf-8", "replace")))


def check_manifest(chk, test_mesh, out):
    """Every file of expected.tsv as assimp reads it."""
    manifest = os.path.join(out, "expected.tsv")
    if not os.path.exists(manifest):
        chk.fail("%s wrote no expected.tsv" % test_mesh)
        return
    files, objects = read_manifest(manifest)
    chk.eq("files in expected.tsv", len(files) > 0, True)
    for name, fmt, vertices, faces in files:
        check_file(chk, os.path.join(out, name), fmt, vertices, faces, objects.get(name, []))


if __name__ == "__main__":
    sys.exit(main())
