"""`sylva render` through the real binary (Python 3 standard library only).

meson runs `python3 test_render.py SYLVA_EXE TESTS_RENDER_DIR SERVER_DIR PART`, PART:
  formats   a small stored run drawn as PNG, SVG and PDF, checked with `file`,
            `rsvg-convert` and `pdfinfo`;
  pixels    the tree beside a wall drawn from the front into a PNG, decoded here:
            tree-coloured pixels on the open side of the wall, none inside it;
  errors    bad views, extensions, runs, iterations and paths: exit 2 (1 for a
            failed write), a message naming the problem, no output file;
  scenario  the scenario form, grown to its end, equals the stored run's picture;
  years     the title line (read back with `pdftotext`): a run in years from a
            start year names the calendar year and its plants' ages, others not;
  leaves    one tree with magenta leaves (leafy.json) drawn from the front with and
            without --no-leaves: leaf-coloured pixels, shaded as render.h says, in
            the crown's box and none in the sky above it or without leaves; the
            same world gives the same bytes; a world whose nodes bear no leaves
            gives the skeleton's picture;
  prisms    an L-shaped building at 30 degrees with a courtyard (prism_top.json)
            from above: grey in its leg, white in its courtyard and in the notch of
            the L; in the SVG one path of its two rings filled even-odd; from the
            front, its bounds' rectangle grey.
The layout constants and the palette are read from server/export/render.h and
server/export/render.c, so the pixel test maps metres to pixels as the renderer does.
"""
import json
import math
import os
import re
import shutil
import struct
import subprocess
import sys
import zlib

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "store"))
from store_common import CRASH_MARKERS, Checks, Env  # noqa: E402

SCENARIO = "wall_small.json"
RUN = "small wall"


class Png:
    """An 8-bit RGB or RGBA, non-interlaced PNG (what cairo writes), decoded."""

    def __init__(self, path):
        with open(path, "rb") as f:
            data = f.read()
        if data[:8] != b"\x89PNG\r\n\x1a\n":
            raise ValueError("%s: not a PNG" % path)
        pos, idat, header = 8, b"", None
        while pos < len(data):
            length, kind = struct.unpack(">I4s", data[pos:pos + 8])
            body = data[pos + 8:pos + 8 + length]
            if kind == b"IHDR":
                header = struct.unpack(">IIBBBBB", body)
            elif kind == b"IDAT":
                idat += body
            elif kind == b"IEND":
                break
            pos += 12 + length
        self.width, self.height, depth, color, _, _, interlace = header
        if depth != 8 or color not in (2, 6) or interlace != 0:
            raise ValueError("unexpected PNG type: depth %d, colour %d, interlace %d"
                             % (depth, color, interlace))
        bpp = self.bpp = 3 if color == 2 else 4
        raw = zlib.decompress(idat)
        stride = self.width * bpp
        self.rows, prev = [], bytearray(stride)
        for y in range(self.height):
            start = y * (stride + 1)
            kind, line = raw[start], bytearray(raw[start + 1:start + 1 + stride])
            if kind == 2:  # Up, most rows: one pass without the neighbours
                line = bytearray((a + b) & 255 for a, b in zip(line, prev))
            elif kind in (1, 3, 4):
                for i in range(stride):
                    a = line[i - bpp] if i >= bpp else 0
                    b = prev[i]
                    c = prev[i - bpp] if i >= bpp else 0
                    if kind == 1:
                        line[i] = (line[i] + a) & 255
                    elif kind == 3:
                        line[i] = (line[i] + (a + b) // 2) & 255
                    else:
                        p = a + b - c
                        pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                        pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                        line[i] = (line[i] + pred) & 255
            self.rows.append(bytes(line))
            prev = line

    def pixel(self, x, y):
        """(r, g, b) at column x, row y."""
        return tuple(self.rows[y][x * self.bpp:x * self.bpp + 3])


def png_size(path):
    """(width, height) from a PNG's header."""
    with open(path, "rb") as f:
        head = f.read(24)
    return struct.unpack(">II", head[16:24])


def render_constants(server_dir):
    """The layout defines of render.h and the first palette colour of render.c."""
    with open(os.path.join(server_dir, "render.h")) as f:
        defines = {m.group(1): float(m.group(2)) for m in
                   re.finditer(r"#define (RENDER_\w+) ([0-9.]+)", f.read())}
    with open(os.path.join(server_dir, "render.c")) as f:
        m = re.search(r"render_palette\[RENDER_PALETTE_SIZE\] = \{\s*0x([0-9a-fA-F]{6})", f.read())
    first = int(m.group(1), 16)
    defines["palette0"] = ((first >> 16) & 255, (first >> 8) & 255, first & 255)
    return defines


def tree_coloured(pixel, colour, backgrounds, tol=6):
    """Whether pixel is the plant colour over one of the backgrounds with a coverage
    of at least one half (antialiased twig edges count when mostly covered)."""
    for bg in backgrounds:
        k = max(range(3), key=lambda i: abs(colour[i] - bg[i]))
        alpha = (pixel[k] - bg[k]) / (colour[k] - bg[k])
        if alpha >= 0.5 and all(abs(pixel[i] - (bg[i] + alpha * (colour[i] - bg[i]))) <= tol
                                for i in range(3)):
            return True
    return False


def no_output(path):
    return not os.path.exists(path) and not os.path.exists(path + ".tmp")


def clean_stderr(err):
    return not any(m in err for m in CRASH_MARKERS)


class RenderEnv(Env):
    def __init__(self, argv):
        super().__init__(argv)
        self.server = os.path.abspath(argv[3])
        self.db = self.path("render.db")

    def stored_run(self, c):
        rc, _, err = self.sylva("run", self.scenario(SCENARIO), "--db", self.db,
                                "--iterations", 4, "--quiet-progress")
        return c.check(rc == 0, "sylva run --db stores the small run", err)

    def render(self, *args):
        return self.sylva("render", *args)


def part_formats(env, c):
    if not env.stored_run(c):
        return
    formats_written(env, c)
    svg_and_pdf_read(env, c)
    views_and_width(env, c)


def formats_written(env, c):
    """render -o run.png, .svg and .pdf: exit 0 silently, no .tmp left, the type `file`
    names."""
    for ext, magic in (("png", "PNG image data"), ("svg", "SVG Scalable Vector Graphics image"),
                       ("pdf", "PDF document")):
        out = env.path("run." + ext)
        rc, stdout, err = env.render("--db", env.db, "--name", RUN, "-o", out)
        c.check(rc == 0 and stdout == "" and clean_stderr(err) and err == "",
                "render -o run.%s exits 0 silently" % ext, "%s %r %s" % (rc, stdout, err))
        c.check(os.path.exists(out) and not os.path.exists(out + ".tmp"),
                "run.%s written, no run.%s.tmp left" % (ext, ext))
        if not os.path.exists(out):
            continue
        kind = subprocess.run(["file", "-b", out], capture_output=True).stdout.decode()
        c.check(kind.startswith(magic), "file says %s is %s" % (out, magic), kind)


def svg_and_pdf_read(env, c):
    """rsvg-convert converts the SVG; pdfinfo reads the PDF, one page."""
    svg, pdf = env.path("run.svg"), env.path("run.pdf")
    if os.path.exists(svg):
        p = subprocess.run(["rsvg-convert", "-o", env.path("svg.png"), svg], capture_output=True)
        c.check(p.returncode == 0 and os.path.getsize(env.path("svg.png")) > 0,
                "rsvg-convert converts the SVG", p.stderr.decode())
    if os.path.exists(pdf):
        p = subprocess.run(["pdfinfo", pdf], capture_output=True)
        info = p.stdout.decode()
        c.check(p.returncode == 0 and re.search(r"^Pages:\s+1$", info, re.M),
                "pdfinfo reads the PDF: one page", info + p.stderr.decode())


def views_and_width(env, c):
    """The default picture is 500 per view; --width, --view and --iteration are
    honoured."""
    w, _ = png_size(env.path("run.png"))
    c.check(w == 1500, "all three views: 1500 pixels wide by default", w)
    for view in ("front", "side", "top"):
        out = env.path("%s.png" % view)
        rc, _, err = env.render("--db", env.db, "--name", RUN, "--view", view, "--width", 640,
                                "--iteration", 2, "-o", out)
        c.check(rc == 0 and os.path.exists(out), "render --view %s --iteration 2" % view, err)
        if rc == 0:
            c.check(png_size(out)[0] == 640, "--width 640 gives 640 pixels (%s)" % view)


class FrontView:
    """A front view decoded, with render.h's mapping of metres to pixels (one panel,
    x to the right, z up) and the colours the renderer uses."""

    def __init__(self, path, k, world, width):
        self.png = png = Png(path)
        self.w, self.h = png.width, png.height
        self.lo, self.hi = world["min"], world["max"]
        self.left = k["RENDER_MARGIN_LEFT"]
        self.scale = (width - k["RENDER_MARGIN_LEFT"] - k["RENDER_MARGIN_RIGHT"]) / (
            self.hi[0] - self.lo[0])
        self.top = k["RENDER_TITLE_HEIGHT"] + k["RENDER_PANEL_TITLE_HEIGHT"]
        self.grey = round(255 * (1 - k["RENDER_OBSTACLE_ALPHA"] * (1 - k["RENDER_OBSTACLE_GREY"])))
        self.tree = k["palette0"]
        self.backgrounds = ((255, 255, 255), (self.grey, self.grey, self.grey))
        self.seen = {}  # a picture has few distinct colours

    def px(self, x):
        return self.left + (x - self.lo[0]) * self.scale

    def py(self, z):
        return self.top + (self.hi[2] - z) * self.scale

    def is_grey(self, p):
        g = self.grey
        return abs(p[0] - g) <= 3 and abs(p[1] - g) <= 3 and abs(p[2] - g) <= 3

    def box(self, x0, x1, z0, z1, inset):
        """Pixel columns and rows whose centres lie inside the box of metres,
        shrunk by inset pixels, clipped to the picture."""
        cols = range(max(0, int(self.px(x0) + inset)), min(self.w, int(self.px(x1) - inset)))
        lines = range(max(0, int(self.py(z1) + inset)), min(self.h, int(self.py(z0) - inset)))
        return [(x, y) for y in lines for x in cols]

    def count_tree(self, pixels):
        n = 0
        for x, y in pixels:
            p = self.png.pixel(x, y)
            if p not in self.seen:
                self.seen[p] = tree_coloured(p, self.tree, self.backgrounds)
            n += self.seen[p]
        return n


def part_pixels(env, c):
    if not env.stored_run(c):
        return
    k = render_constants(env.server)
    with open(env.scenario(SCENARIO)) as f:
        scenario = json.load(f)
    width = 800
    out = env.path("front.png")
    rc, _, err = env.render("--db", env.db, "--name", RUN, "--view", "front", "--width", width,
                            "-o", out)
    if not c.check(rc == 0, "render --view front", err):
        return
    view = FrontView(out, k, scenario["world"], width)
    c.check(view.w == width and view.h == math.ceil(view.top + (view.hi[2] - view.lo[2]) *
                                                    view.scale + k["RENDER_MARGIN_BOTTOM"]),
            "the picture's size follows render.h", (view.w, view.h))
    wall = scenario["obstacles"][0]
    wall_is_grey(c, view, wall)
    tree_beside_wall(c, view, wall)


def wall_is_grey(c, view, wall):
    """The wall's rectangle, where the mapping puts it, is the obstacle grey, and the
    grey pixels of the panel lie in that rectangle (the mapping agrees)."""
    wall_px = view.box(wall["min"][0], wall["max"][0], wall["min"][2], wall["max"][2], 3)
    greys = sum(1 for x, y in wall_px if view.is_grey(view.png.pixel(x, y)))
    c.check(wall_px and greys >= 0.95 * len(wall_px),
            "the wall's projected rectangle is obstacle grey (%d)" % view.grey,
            "%d of %d pixels" % (greys, len(wall_px)))
    lo, hi = view.lo, view.hi
    panel = view.box(lo[0], hi[0], lo[2], hi[2], 2)
    found = [(x, y) for x, y in panel if view.is_grey(view.png.pixel(x, y))]
    if c.check(found, "grey pixels in the panel"):
        xs = [x for x, _ in found]
        ys = [y for _, y in found]
        expect = (view.px(wall["min"][0]), view.px(wall["max"][0]), view.py(wall["max"][2]),
                  view.py(wall["min"][2]))
        got = (min(xs), max(xs) + 1, min(ys), max(ys) + 1)
        c.check(all(abs(a - b) <= 3 for a, b in zip(got, expect)),
                "the grey rectangle is where render.h maps the wall", "%s vs %s" % (got, expect))


def tree_beside_wall(c, view, wall):
    """Tree-coloured pixels on the open side of the wall, none inside it; the same count
    finds the trunk (a rectangle of the wall's width at the root)."""
    lo, hi = view.lo, view.hi
    open_side = view.box(lo[0], wall["min"][0], lo[2], hi[2], 2)
    inside = view.box(wall["min"][0], wall["max"][0], wall["min"][2], wall["max"][2], 2)
    n_open, n_inside = view.count_tree(open_side), view.count_tree(inside)
    c.check(n_open >= 10, "tree-coloured pixels on the open side of the wall (x < %g)"
            % wall["min"][0], n_open)
    c.check(n_inside == 0, "no tree-coloured pixel inside the wall", n_inside)
    trunk = view.box(-0.1, 0.1, lo[2], lo[2] + 0.2, 2)
    c.check(view.count_tree(trunk) > 0, "control: the count finds the trunk at x = 0",
            view.count_tree(trunk))


def part_errors(env, c):
    if not env.stored_run(c):
        return
    out = env.path("bad.png")
    base = ["--db", env.db, "--name", RUN]
    cases = [
        (base + ["--view", "back", "-o", out], 2, "--view: expected front, side, top or all"),
        (base + ["-o", env.path("bad.gif")], 2, ".png, .svg or .pdf"),
        (base + ["-o", env.path("bad")], 2, ".png, .svg or .pdf"),
        (["--db", env.db, "--name", "nosuch", "-o", out], 2, 'no run named "nosuch"'),
        (base + ["--iteration", 99, "-o", out], 2, "has no iteration 99 (it has 0 to 4)"),
        (base + ["--width", 10, "-o", out], 2, "--width"),
        (base + ["-o", env.path("no/such/dir/bad.png")], 2, "cannot create"),
        (base, 2, "-o OUT is required"),
        (["--db", env.db, "-o", out], 2, "--name NAME is required"),
        (["-o", out], 2, "expected --db FILE --name NAME, or SCENARIO.json"),
        ([env.scenario(SCENARIO), "--db", env.db, "-o", out], 2, "are for a stored run"),
        (base + ["--seed", 3, "-o", out], 2, "--seed and --iterations need SCENARIO.json"),
        ([env.path("missing.json"), "-o", out], 2, "missing.json"),
        (["--db", env.path("nodb.db"), "--name", RUN, "-o", out], 2, "nodb.db"),
        (base + ["--leaves", "-o", out], 2, "unknown option '--leaves'"),
        (base + ["--no-leaves=1", "-o", out], 2, "--no-leaves takes no argument"),
    ]
    for args, status, words in cases:
        for path in (out, env.path("bad.gif"), env.path("bad")):
            if os.path.exists(path):
                os.remove(path)
        rc, stdout, err = env.render(*args)
        what = "render %s" % " ".join(str(a) for a in args)
        c.check(rc == status and words in err and clean_stderr(err),
                "%s: exit %d, says '%s'" % (what, status, words), "%s: %s" % (rc, err))
        c.check(no_output(out) and no_output(env.path("bad.gif")) and no_output(env.path("bad")),
                "%s: no output file left" % what)
    # A failed write (OUT is a directory, so the rename fails): exit 1, no OUT.tmp left.
    target = env.path("dir.png")
    os.mkdir(target)
    rc, _, err = env.render(*base, "-o", target)
    c.check(rc == 1 and "dir.png" in err and clean_stderr(err)
            and not os.path.exists(target + ".tmp"),
            "render -o DIRECTORY.png: exit 1 naming it, no .tmp left", "%s: %s" % (rc, err))
    rc, stdout, _ = env.render("--help")
    c.check(rc == 0 and stdout.startswith("Usage: sylva render"), "render --help")


def part_scenario(env, c):
    scenario = env.scenario(SCENARIO)
    # grown to its end (the file's own limit, 4) it equals the stored run's last iteration
    if not env.stored_run(c):
        return
    direct, stored = env.path("direct.png"), env.path("stored.png")
    rc, stdout, err = env.render(scenario, "-o", direct)
    c.check(rc == 0 and stdout == "" and clean_stderr(err), "render SCENARIO -o direct.png",
            "%s %r %s" % (rc, stdout, err))
    rc, _, err = env.render("--db", env.db, "--name", RUN, "-o", stored)
    c.check(rc == 0, "render the stored run", err)
    if os.path.exists(direct) and os.path.exists(stored):
        with open(direct, "rb") as a, open(stored, "rb") as b:
            c.check(a.read() == b.read(),
                    "the scenario grown to its end draws the stored run's last iteration")
    out = env.path("seeded.svg")
    rc, _, err = env.render(scenario, "--seed", 5, "--iterations", 2, "--view", "side", "-o", out)
    c.check(rc == 0 and os.path.exists(out) and clean_stderr(err),
            "render SCENARIO --seed 5 --iterations 2 --view side -o seeded.svg", err)
    if os.path.exists(out):
        kind = subprocess.run(["file", "-b", out], capture_output=True).stdout.decode()
        c.check(kind.startswith("SVG"), "seeded.svg is an SVG", kind)


def title_of(env, c, *args):
    """The first line of the text of a rendered PDF (its title line)."""
    out = env.path("title.pdf")
    rc, _, err = env.render(*args, "-o", out)
    if not c.check(rc == 0 and clean_stderr(err), "render %s" % " ".join(map(str, args)), err):
        return ""
    p = subprocess.run(["pdftotext", "-layout", out, "-"], capture_output=True)
    return p.stdout.decode().strip().splitlines()[0].strip() if p.returncode == 0 else ""


def part_years(env, c):
    """A run of tests/scenario/years.json (from 2027; two trees of a species with
    years, planted at 0 and 3, and an IGM tree) drawn at iteration 3 names 2030 and
    the ages of the two trees; the scenario form grown to its end (8) names 2035;
    a run without years or a start year keeps its title."""
    years = os.path.join(env.scenarios, os.pardir, "scenario", "years.json")
    db = env.path("years.db")
    rc, _, err = env.sylva("run", years, "--db", db, "--name", "y", "--quiet-progress")
    if not c.check(rc == 0, "sylva run --db stores the run in years", err):
        return
    title = title_of(env, c, "--db", db, "--name", "y", "--iteration", 3)
    c.check(re.fullmatch(r"y \u2014 2030 \(iteration 3\) \u2014 \d+ nodes "
                         r"\u2014 ages young 3, old 6", title), "the stored run's title", title)
    title = title_of(env, c, years)
    c.check(re.fullmatch(r"Trees in years \u2014 2035 \(iteration 8\) \u2014 \d+ nodes "
                         r"\u2014 ages young 8, old 11", title), "the scenario's title", title)
    title = title_of(env, c, env.scenario(SCENARIO))
    c.check(re.fullmatch(r"\S.* \u2014 iteration 4 \u2014 \d+ nodes", title),
            "a title without years", title)


LEAFY = "leafy.json"


def leaf_coloured(p):
    """Whether pixel p is the test's magenta leaf colour (shaded: s * (255, 0, 255),
    s >= RENDER_LEAF_SHADE) over white or over branches, at least half covering: red
    equals blue and both stand well above green. No branch colour, grey, text or
    ground pixel is like that."""
    return abs(p[0] - p[2]) <= 4 and p[0] - p[1] >= 60


def same_bytes(a, b):
    with open(a, "rb") as f, open(b, "rb") as g:
        return f.read() == g.read()


def part_leaves(env, c):
    k = render_constants(env.server)
    scenario = env.scenario(LEAFY)
    with open(scenario) as f:
        spec = json.load(f)
    leaf_size = spec["species"]["plane"]["leaf_size"]
    width = 800
    leafy, bare = env.path("leafy.png"), env.path("bare.png")
    for out, extra in ((leafy, []), (bare, ["--no-leaves"])):
        rc, stdout, err = env.render(scenario, "--view", "front", "--width", width, *extra,
                                     "-o", out)
        if not c.check(rc == 0 and stdout == "" and clean_stderr(err),
                       "render leafy.json --view front %s" % " ".join(extra), err):
            return
    with_leaves = FrontView(leafy, k, spec["world"], width)
    skeleton = FrontView(bare, k, spec["world"], width)
    c.check((with_leaves.w, with_leaves.h) == (skeleton.w, skeleton.h),
            "leaves change no part of the layout: the same size",
            ((with_leaves.w, with_leaves.h), (skeleton.w, skeleton.h)))
    lo, hi = skeleton.lo, skeleton.hi
    panel = skeleton.box(lo[0], hi[0], lo[2], hi[2], 1)
    # the crown's box: the skeleton's pixels, widened by a leaf's edge on every side
    wood = [(x, y) for x, y in panel if skeleton.count_tree([(x, y)])]
    if not c.check(wood, "the skeleton is drawn"):
        return
    margin = leaf_size * skeleton.scale + 2
    x0, x1 = min(x for x, _ in wood) - margin, max(x for x, _ in wood) + 1 + margin
    y0, y1 = min(y for _, y in wood) - margin, max(y for _, y in wood) + 1 + margin
    leaf = {}
    for x, y in panel:
        p = with_leaves.png.pixel(x, y)
        if leaf_coloured(p):
            leaf[(x, y)] = p
    inside = [xy for xy in leaf if x0 <= xy[0] < x1 and y0 <= xy[1] < y1]
    c.check(len(inside) >= 2000, "leaf-coloured pixels in the crown's box", len(inside))
    sky = [(x, y) for x, y in panel if y < y0]
    c.check(y0 - skeleton.top >= 100, "control: 100 rows of sky above the crown",
            y0 - skeleton.top)
    c.check(not any(xy in leaf for xy in sky), "no leaf-coloured pixel in the sky above the crown",
            sum(1 for xy in sky if xy in leaf))
    c.check(len(inside) == len(leaf), "no leaf-coloured pixel outside the crown's box",
            len(leaf) - len(inside))
    none = sum(1 for x, y in panel if leaf_coloured(skeleton.png.pixel(x, y)))
    c.check(none == 0, "--no-leaves: no leaf-coloured pixel", none)
    # a leaf covering its pixel whole is s * (255, 0, 255), s from RENDER_LEAF_SHADE
    # (seen edge-on) to 1 (facing the viewer), and the crown shows several shades;
    # red and blue within 1 of each other (the library London plane's crown has
    # a pixel of two overlapping cards' edges at (228, 0, 229): 8-bit rounding)
    solid = {p for p in leaf.values() if p[1] == 0}
    least = math.floor(255 * k["RENDER_LEAF_SHADE"]) - 1
    c.check(solid and all(least <= p[0] <= 255 and abs(p[0] - p[2]) <= 1 for p in solid),
            "whole leaf pixels are the leaf colour shaded by %g to 1" % k["RENDER_LEAF_SHADE"],
            sorted(solid)[:5])
    c.check(len(solid) >= 5, "the crown shows several shades of the leaf colour", len(solid))
    leaves_deterministic(env, c, scenario)
    no_leaves_borne(env, c, spec)


def leaves_deterministic(env, c, scenario):
    """Two renders of the same world with leaves give the same bytes (PNG and SVG);
    the SVG is read by rsvg-convert; leaves show from above too."""
    for ext in ("png", "svg"):
        a, b = env.path("again1." + ext), env.path("again2." + ext)
        for out in (a, b):
            rc, _, err = env.render(scenario, "-o", out)
            c.check(rc == 0, "render leafy.json -o %s" % os.path.basename(out), err)
        if os.path.exists(a) and os.path.exists(b):
            c.check(same_bytes(a, b), "the same world with leaves: the same %s bytes" % ext)
    p = subprocess.run(["rsvg-convert", "-o", env.path("svg.png"), env.path("again1.svg")],
                       capture_output=True)
    c.check(p.returncode == 0, "rsvg-convert converts the SVG with leaves", p.stderr.decode())
    top = env.path("top.png")
    rc, _, err = env.render(scenario, "--view", "top", "-o", top)
    if c.check(rc == 0, "render leafy.json --view top", err):
        png = Png(top)
        seen = sum(1 for row in range(png.height) for x in range(png.width)
                   if leaf_coloured(png.pixel(x, row)))
        c.check(seen >= 1000, "leaves show from above", seen)


def no_leaves_borne(env, c, spec):
    """A world whose nodes bear no leaves (leaf_density 0) draws the same bytes with
    leaves as with --no-leaves: leaves add nothing else to the picture."""
    spec = json.loads(json.dumps(spec))
    spec["species"]["plane"]["leaf_density"] = 0
    bare_scenario = env.path("leafless.json")
    with open(bare_scenario, "w") as f:
        json.dump(spec, f)
    a, b = env.path("leafless-default.png"), env.path("leafless-bare.png")
    rc1, _, err1 = env.render(bare_scenario, "-o", a)
    rc2, _, err2 = env.render(bare_scenario, "--no-leaves", "-o", b)
    if c.check(rc1 == 0 and rc2 == 0, "render a world without leaves, with and without "
               "--no-leaves", err1 + err2):
        c.check(same_bytes(a, b), "no leaves borne: the same bytes as --no-leaves")


PRISM = "prism_top.json"


class TopView(FrontView):
    """A top view decoded: x to the right, y up, on FrontView's scale."""

    def py(self, y):
        return self.top + (self.hi[1] - y) * self.scale


def mean_point(points):
    return [sum(p[a] for p in points) / len(points) for a in (0, 1)]


def part_prisms(env, c):
    k = render_constants(env.server)
    scenario = env.scenario(PRISM)
    with open(scenario) as f:
        spec = json.load(f)
    house = spec["obstacles"][0]
    outline, hole = house["polygon"], house["holes"][0]
    width = 800
    top = env.path("top.png")
    rc, _, err = env.render(scenario, "--view", "top", "--width", width, "-o", top)
    if c.check(rc == 0 and clean_stderr(err), "render prism_top.json --view top", err):
        view = TopView(top, k, spec["world"], width)
        # outline[2:5], the inner corner and the legs' inner ends: their mean is in the notch
        for what, (x, y), white in (("the courtyard's centre", mean_point(hole), True),
                                    ("the notch of the L", mean_point(outline[2:5]), True),
                                    ("the long leg", mean_point(outline[0:4]), False)):
            p = view.png.pixel(int(view.px(x)), int(view.py(y)))
            c.check(p == (255, 255, 255) if white else view.is_grey(p),
                    "from above, %s (%.2f, %.2f) is %s" % (what, x, y,
                                                          "white" if white else "grey"), p)
    svg = env.path("top.svg")
    rc, _, err = env.render(scenario, "--view", "top", "-o", svg)
    if c.check(rc == 0 and clean_stderr(err), "render prism_top.json --view top -o top.svg", err):
        with open(svg, encoding="utf-8") as f:
            paths = re.findall(r'<path style="[^"]*fill-rule:evenodd;[^"]*" d="([^"]*)"', f.read())
        c.check(len(paths) == 1 and paths[0].count("Z") == 2,
                "the SVG fills the footprint even-odd, one path of two rings", paths)
    front = env.path("front.png")
    rc, _, err = env.render(scenario, "--view", "front", "--width", width, "-o", front)
    if c.check(rc == 0 and clean_stderr(err), "render prism_top.json --view front", err):
        view = FrontView(front, k, spec["world"], width)
        xs = [p[0] for p in outline]
        # the bounds' corners, 0.1 m inside, and the middle
        for x, z in ((min(xs) + 0.1, 0.1), (max(xs) - 0.1, house["z"][1] - 0.1),
                     ((min(xs) + max(xs)) / 2, house["z"][1] / 2)):
            p = view.png.pixel(int(view.px(x)), int(view.py(z)))
            c.check(view.is_grey(p), "from the front, (%.2f, %.2f) in the bounds is grey"
                    % (x, z), p)


PARTS = {"formats": part_formats, "pixels": part_pixels, "errors": part_errors,
         "scenario": part_scenario, "years": part_years, "leaves": part_leaves,
         "prisms": part_prisms}


def main():
    if len(sys.argv) != 5 or sys.argv[4] not in PARTS:
        sys.exit("usage: test_render.py SYLVA_EXE TESTS_RENDER_DIR SERVER_DIR "
                 + "|".join(PARTS))
    for tool in ("file", "rsvg-convert", "pdfinfo", "pdftotext"):
        if not shutil.which(tool):
            sys.exit("test_render.py: %s is missing (scripts/bootstrap installs it)" % tool)
    env = RenderEnv(sys.argv)
    c = Checks()
    try:
        PARTS[sys.argv[4]](env, c)
    finally:
        env.cleanup()
    c.finish()


if __name__ == "__main__":
    main()
