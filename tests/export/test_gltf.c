/* glTF export (server/export/gltf.c): a tree and a two-root shrub of two species with
 * different leaf colours, a wall and a clearance zone, grown a few iterations and
 * written as GLB. The file is read back (GLB header and chunks, the JSON with cJSON,
 * the buffer) and checked against the world: the nodes, meshes and materials of
 * gltf.h, every bark vertex, normal and index against sylva_mesh_branches (turned
 * y up), every leaf card against foliage_place, the bounds of every POSITION, the
 * same bytes on a second write, one "leaves" material when the colours agree, an
 * empty world, bad options and a failed write. The prisms of prism_world.h (an
 * L-shaped building with a courtyard at 30 degrees, a prism equal to a box, a zone):
 * closed meshes (welded by position) of their footprints' volume and cap areas,
 * flat normals facing out. The Khronos validator reads the files of OUTDIR
 * (gltf_validate.mjs).
 *
 * Usage: test_gltf [OUTDIR|- [TEST]]; with OUTDIR (not -), the files are also
 * written there and listed in OUTDIR/expected.tsv for assimp_check.py:
 *   file <TAB> NAME <TAB> glb <TAB> VERTICES <TAB> FACES
 *   object <TAB> NAME <TAB> MESH <TAB> FACES <TAB> VERTICES   (one per primitive, as
 *   assimp names them: the mesh's name, with -K for primitive K of several) */
#include <cjson/cJSON.h>
#include <errno.h>
#include <stdint.h>
#include <string.h>

#include "../check.h"
#include "export_world.h"
#include "foliage.h"
#include "gltf.h"
#include "prism_world.h"
#include "sylva/sylva.h"

#define LEAF_GREEN 0x2f8f2f
#define LEAF_PURPLE 0x8f2f8f

/* The world: the tree and the shrub, a wall between them and a clearance zone. */
static sylva_world *make_world(int colour_x, int colour_y, int iterations) {
  static const sylva_obstacle_def obstacles[2] = {
      {"wall", {-0.2, -3.0, 0.0}, {0.2, 3.0, 2.5}, SYLVA_OBSTACLE_SOLID, {0}},
      {"lane", {3.0, -3.0, 0.5}, {4.0, 3.0, 4.0}, SYLVA_OBSTACLE_ZONE, {0}}};
  return export_world(colour_x, colour_y, obstacles, 2, iterations);
}

/* ---- writing and reading back ---- */

static blob write_blob(const sylva_world *w, const sylva_mesh_options *opt) {
  blob b;
  FILE *f = blob_open(&b);
  b.rc = gltf_write(f, w, opt);
  fclose(f);
  return b;
}

static uint32_t u32_at(const unsigned char *p) {
  return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static float f32_at(const unsigned char *p) {
  uint32_t u = u32_at(p);
  float f;
  memcpy(&f, &u, sizeof f);
  return f;
}

/* A GLB read back: its JSON and its buffer. */
typedef struct glb {
  bool ok;
  cJSON *json;
  const unsigned char *bin;
  size_t bin_len;
} glb;

static glb read_glb(const blob *b) {
  glb g = {false, NULL, NULL, 0};
  int failed_before = check_failed;
  const unsigned char *d = (const unsigned char *)b->data;
  CHECK(b->rc == 0 && b->size >= 20);
  if (b->rc != 0 || b->size < 20) return g;
  CHECK_INT(u32_at(d), 0x46546C67u); /* "glTF" */
  CHECK_INT(u32_at(d + 4), 2);
  CHECK_INT(u32_at(d + 8), b->size);
  size_t json_len = u32_at(d + 12);
  CHECK_INT(u32_at(d + 16), 0x4E4F534Au); /* "JSON" */
  CHECK_INT(json_len % 4, 0);
  CHECK(20 + json_len <= b->size);
  if (20 + json_len > b->size) return g;
  g.json = cJSON_ParseWithLength((const char *)d + 20, json_len);
  CHECK(g.json != NULL);
  size_t at = 20 + json_len;
  if (at < b->size) {
    CHECK(at + 8 <= b->size);
    if (at + 8 > b->size) return g;
    g.bin_len = u32_at(d + at);
    CHECK_INT(u32_at(d + at + 4), 0x004E4942u); /* "BIN\0" */
    CHECK_INT(g.bin_len % 4, 0);
    CHECK_INT(at + 8 + g.bin_len, b->size);
    g.bin = d + at + 8;
  }
  g.ok = g.json != NULL && check_failed == failed_before;
  return g;
}

static double num(const cJSON *o, const char *key) {
  const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
  return cJSON_IsNumber(v) ? v->valuedouble : -1.0;
}

static const char *str(const cJSON *o, const char *key) {
  const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
  return cJSON_IsString(v) ? v->valuestring : "";
}

static const cJSON *item(const cJSON *o, const char *key, int i) {
  return cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(o, key), i);
}

static int count(const cJSON *o, const char *key) {
  return cJSON_GetArraySize(cJSON_GetObjectItemCaseSensitive(o, key));
}

/* The data of accessor a: its first byte in the buffer, element count and stride. */
static const unsigned char *accessor_data(const glb *g, int a, size_t *n, size_t *stride) {
  const cJSON *acc = item(g->json, "accessors", a);
  const cJSON *view = item(g->json, "bufferViews", (int)num(acc, "bufferView"));
  *n = (size_t)num(acc, "count");
  double s = num(view, "byteStride");
  *stride = s > 0 ? (size_t)s : 4;
  size_t off = (size_t)num(view, "byteOffset") + (size_t)num(acc, "byteOffset");
  CHECK(acc && view && off + *n * *stride <= g->bin_len);
  return g->bin + off;
}

static void y_up(const double v[3], double out[3]) {
  out[0] = v[0];
  out[1] = v[2];
  out[2] = -v[1];
}

/* ---- the world of most tests ---- */

static sylva_world *world;
static blob world_glb;
static glb world_read;

static const sylva_world *the_world(void) {
  if (!world) {
    world = make_world(LEAF_GREEN, LEAF_PURPLE, 7);
    if (!world) {
      fprintf(stderr, "could not make the world\n");
      exit(1);
    }
    sylva_mesh_options opt = sylva_mesh_default_options();
    opt.obstacles = true;
    world_glb = write_blob(world, &opt);
    world_read = read_glb(&world_glb);
  }
  return world;
}

/* The leaves a stem bears: the sum over its nodes. */
static size_t stem_leaves(const sylva_world *w, int s) {
  size_t n = sylva_world_node_count(w), leaves = 0;
  sylva_node_info info;
  for (size_t i = 0; i < n; i++) {
    sylva_world_node_at(w, i, &info);
    if (sylva_world_stem_index(w, info.plant, info.stem) == s && info.leaves > 0)
      leaves += (size_t)info.leaves;
  }
  return leaves;
}

/* The world has leaves on both plants, and the file reads back. */
static void test_world(void) {
  const sylva_world *w = the_world();
  CHECK_INT(sylva_world_stem_count(w), 3);
  CHECK(stem_leaves(w, 0) > 0 && stem_leaves(w, 1) > 0);
  CHECK(world_read.ok);
  CHECK_INT(world_glb.rc, 0);
  CHECK_INT(num(item(world_read.json, "buffers", 0), "byteLength"), world_read.bin_len);
  /* the JSON chunk is padded with spaces */
  size_t json_len = u32_at((const unsigned char *)world_glb.data + 12);
  const char *json = world_glb.data + 20;
  size_t end = json_len;
  while (end > 0 && json[end - 1] == ' ') end--;
  CHECK(json_len - end < 4 && json[end - 1] == '}');
}

/* The nodes: the root, one per stem with geometry, one per obstacle, each with its
 * mesh of the same name. */
static void test_nodes(void) {
  the_world();
  const cJSON *j = world_read.json;
  CHECK(strcmp(str(cJSON_GetObjectItemCaseSensitive(j, "asset"), "version"), "2.0") == 0);
  CHECK_INT(num(j, "scene"), 0);
  static const char *const names[] = {"sylva", "oak/0", "hazel bush/0", "hazel bush/1",
                                      "obstacle/wall", "zone/lane"};
  CHECK_INT(count(j, "nodes"), 6);
  CHECK_INT(count(j, "meshes"), 5);
  for (int i = 0; i < 6; i++) {
    const cJSON *n = item(j, "nodes", i);
    CHECK(strcmp(str(n, "name"), names[i]) == 0);
    CHECK(!cJSON_GetObjectItemCaseSensitive(n, "matrix") &&
          !cJSON_GetObjectItemCaseSensitive(n, "translation"));
    if (i == 0) continue;
    CHECK_INT(num(n, "mesh"), i - 1);
    CHECK_INT(cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(item(j, "nodes", 0), "children"),
                                 i - 1)->valueint, i);
    CHECK(strcmp(str(item(j, "meshes", i - 1), "name"), names[i]) == 0);
  }
  const cJSON *extras = cJSON_GetObjectItemCaseSensitive(item(j, "nodes", 0), "extras");
  CHECK_INT(num(extras, "iteration"), 7);
}

static double linear(double c) { return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4); }

/* Materials in their order; the leaves' textured and cut out with their colour. */
static void test_materials(void) {
  the_world();
  const cJSON *j = world_read.json;
  static const char *const names[] = {"bark", "leaves-x", "leaves-y", "obstacle", "zone"};
  static const char *const modes[] = {"", "MASK", "MASK", "", "BLEND"};
  static const int colours[] = {0, LEAF_GREEN, LEAF_PURPLE};
  CHECK_INT(count(j, "materials"), 5);
  for (int i = 0; i < 5; i++) {
    const cJSON *m = item(j, "materials", i);
    const cJSON *pbr = cJSON_GetObjectItemCaseSensitive(m, "pbrMetallicRoughness");
    CHECK(strcmp(str(m, "name"), names[i]) == 0);
    CHECK(strcmp(str(m, "alphaMode"), modes[i]) == 0);
    CHECK_INT(num(pbr, "metallicFactor"), 0);
    bool leaves = i == 1 || i == 2;
    CHECK(cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(m, "doubleSided")) == (leaves || i == 4));
    CHECK((cJSON_GetObjectItemCaseSensitive(pbr, "baseColorTexture") != NULL) == leaves);
    if (!leaves) continue;
    CHECK_NEAR(num(m, "alphaCutoff"), 0.5, 0);
    double rgb[3];
    foliage_rgb(colours[i], rgb);
    for (int a = 0; a < 3; a++)
      CHECK_NEAR(cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(pbr, "baseColorFactor"), a)
                     ->valuedouble,
                 linear(rgb[a]), 1e-12);
  }
  CHECK_NEAR(num(cJSON_GetObjectItemCaseSensitive(item(j, "materials", 0), "pbrMetallicRoughness"),
                 "roughnessFactor"),
             0.9, 0);
  /* the texture: a PNG in a bufferView */
  CHECK_INT(count(j, "textures"), 1);
  CHECK_INT(count(j, "images"), 1);
  const cJSON *img = item(j, "images", 0);
  CHECK(strcmp(str(img, "mimeType"), "image/png") == 0);
  const cJSON *view = item(j, "bufferViews", (int)num(img, "bufferView"));
  size_t off = (size_t)num(view, "byteOffset");
  CHECK(off + 8 <= world_read.bin_len &&
        memcmp(world_read.bin + off, "\x89PNG\r\n\x1a\n", 8) == 0);
}

/* Each primitive's material and attributes, as gltf.h lays them out. */
static const cJSON *primitive(int mesh, int k) {
  return cJSON_GetArrayItem(
      cJSON_GetObjectItemCaseSensitive(item(world_read.json, "meshes", mesh), "primitives"), k);
}

static int attribute(const cJSON *prim, const char *name) {
  return (int)num(cJSON_GetObjectItemCaseSensitive(prim, "attributes"), name);
}

/* Collects what sylva_mesh_branches gives for a stem. */
typedef struct expect {
  double (*pos)[3], (*nrm)[3];
  size_t nv, nt, cap_v, cap_t;
  size_t (*tri)[3];
} expect;

static bool collect_vertex(void *ctx, const double pos[3], const double normal[3]) {
  expect *e = ctx;
  if (e->nv < e->cap_v) {
    y_up(pos, e->pos[e->nv]);
    y_up(normal, e->nrm[e->nv]);
  }
  e->nv++;
  return true;
}

static bool collect_triangle(void *ctx, size_t a, size_t b, size_t c) {
  expect *e = ctx;
  if (e->nt < e->cap_t) {
    e->tri[e->nt][0] = a;
    e->tri[e->nt][1] = b;
    e->tri[e->nt][2] = c;
  }
  e->nt++;
  return true;
}

/* POSITION's min and max are those of its data, in single precision. */
static void check_bounds(const glb *g, int a) {
  size_t n, stride;
  const unsigned char *d = accessor_data(g, a, &n, &stride);
  const cJSON *acc = item(g->json, "accessors", a);
  for (int c = 0; c < 3; c++) {
    float lo = 0, hi = 0;
    for (size_t i = 0; i < n; i++) {
      float v = f32_at(d + i * stride + 4 * (size_t)c);
      if (i == 0 || v < lo) lo = v;
      if (i == 0 || v > hi) hi = v;
    }
    /* glTF 2.0, 3.6.2.5: the JSON bounds of floats stand for single precision values */
    CHECK((float)cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(acc, "min"), c)->valuedouble ==
          lo);
    CHECK((float)cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(acc, "max"), c)->valuedouble ==
          hi);
  }
}

/* The bark of every stem: vertices, normals and triangles of sylva_mesh_branches. */
static void test_bark(void) {
  const sylva_world *w = the_world();
  sylva_mesh_branches *b;
  CHECK_INT(sylva_mesh_branches_create(w, 8, &b), 0);
  for (int s = 0; s < 3; s++) {
    size_t first, nv, nt;
    sylva_mesh_branches_stem(b, s, &first, &nv, &nt);
    CHECK(nv > 0);
    expect e = {malloc(nv * sizeof *e.pos), malloc(nv * sizeof *e.nrm), 0, 0, nv, nt,
                malloc(nt * sizeof *e.tri)};
    sylva_mesh_branches_vertices(b, s, collect_vertex, &e);
    sylva_mesh_branches_triangles(b, s, collect_triangle, &e);
    const cJSON *prim = primitive(s, 0);
    CHECK_INT(num(prim, "material"), 0);
    size_t n, stride, nn, nstride, ni, istride;
    const unsigned char *pos = accessor_data(&world_read, attribute(prim, "POSITION"), &n, &stride);
    const unsigned char *nrm =
        accessor_data(&world_read, attribute(prim, "NORMAL"), &nn, &nstride);
    const unsigned char *idx = accessor_data(&world_read, (int)num(prim, "indices"), &ni, &istride);
    CHECK_INT(n, nv);
    CHECK_INT(nn, nv);
    CHECK_INT(ni, 3 * nt);
    size_t bad = 0;
    for (size_t i = 0; i < nv && n == nv && nn == nv; i++) {
      double len = 0;
      for (int a = 0; a < 3; a++) {
        float p = f32_at(pos + i * stride + 4 * (size_t)a);
        float q = f32_at(nrm + i * nstride + 4 * (size_t)a);
        if (p != (float)e.pos[i][a] && !(p == 0 && (float)e.pos[i][a] == 0)) bad++;
        if (fabs((double)q - e.nrm[i][a]) > 1e-6) bad++;
        len += (double)q * q;
      }
      if (fabs(len - 1.0) > 1e-5) bad++;
    }
    for (size_t t = 0; t < nt && ni == 3 * nt; t++)
      for (int c = 0; c < 3; c++)
        if (u32_at(idx + (3 * t + (size_t)c) * 4) != e.tri[t][c]) bad++;
    CHECK_INT(bad, 0);
    check_bounds(&world_read, attribute(prim, "POSITION"));
    free(e.pos);
    free(e.nrm);
    free(e.tri);
  }
  sylva_mesh_branches_destroy(b);
}

/* The leaves of every stem: four corners per card around foliage_place's centre,
 * the card's UVs, a normal along x across, two triangles facing it. */
static void test_leaves(void) {
  const sylva_world *w = the_world();
  size_t nodes = sylva_world_node_count(w);
  sylva_node_info info, par;
  for (int s = 0; s < 3; s++) {
    const cJSON *prim = primitive(s, 1);
    int plant = s == 0 ? 0 : 1;
    int species = sylva_world_plant_species(w, plant);
    const sylva_species_def *def = sylva_world_species(w, species);
    CHECK_INT(num(prim, "material"), 1 + species);
    size_t n, stride, nn, nstride, nu, ustride, ni, istride;
    const unsigned char *pos = accessor_data(&world_read, attribute(prim, "POSITION"), &n, &stride);
    const unsigned char *nrm =
        accessor_data(&world_read, attribute(prim, "NORMAL"), &nn, &nstride);
    const unsigned char *uv =
        accessor_data(&world_read, attribute(prim, "TEXCOORD_0"), &nu, &ustride);
    const unsigned char *idx = accessor_data(&world_read, (int)num(prim, "indices"), &ni, &istride);
    size_t leaves = stem_leaves(w, s);
    CHECK_INT(n, 4 * leaves);
    CHECK_INT(nu, 4 * leaves);
    CHECK_INT(ni, 6 * leaves);
    if (n != 4 * leaves || nu != n || nn != n || ni != 6 * leaves) continue;
    static const float uvs[4][2] = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};
    static const uint32_t tris[6] = {0, 2, 1, 0, 3, 2};
    size_t card = 0, bad = 0;
    for (size_t i = 0; i < nodes; i++) {
      sylva_world_node_at(w, i, &info);
      if (sylva_world_stem_index(w, info.plant, info.stem) != s || info.leaves <= 0) continue;
      double q[3] = {info.x, info.y, info.z}, p[3] = {0, 0, 0};
      bool root = info.parent < 0;
      for (size_t k = 0; !root && k < i; k++) {
        sylva_world_node_at(w, k, &par);
        if (par.id == info.parent) {
          p[0] = par.x;
          p[1] = par.y;
          p[2] = par.z;
        }
      }
      for (int k = 0; k < info.leaves; k++, card++) {
        foliage_leaf f;
        foliage_place(root ? NULL : p, q, k, info.leaves, def->leaf_size, &f);
        double centre[3], normal[3], want_n[3] = {
            f.along[1] * f.across[2] - f.along[2] * f.across[1],
            f.along[2] * f.across[0] - f.along[0] * f.across[2],
            f.along[0] * f.across[1] - f.along[1] * f.across[0]};
        y_up(f.centre, centre);
        y_up(want_n, normal);
        double sum[3] = {0, 0, 0}, tip[3], base[3];
        for (int v = 0; v < 4; v++) {
          size_t at = 4 * card + (size_t)v;
          for (int a = 0; a < 3; a++) {
            double c = f32_at(pos + at * stride + 4 * (size_t)a);
            sum[a] += c;
            if (v == 2) tip[a] = c;
            if (v == 0) base[a] = c;
            if (fabs(f32_at(nrm + at * nstride + 4 * (size_t)a) - normal[a]) > 1e-6) bad++;
          }
          if (f32_at(uv + at * ustride) != uvs[v][0] || f32_at(uv + at * ustride + 4) != uvs[v][1])
            bad++;
        }
        for (int a = 0; a < 3; a++)
          if (fabs(sum[a] / 4 - centre[a]) > 1e-5) bad++;
        /* the diagonal base-left to tip-right: the edge times sqrt 2 */
        double d = 0;
        for (int a = 0; a < 3; a++) d += (tip[a] - base[a]) * (tip[a] - base[a]);
        if (fabs(sqrt(d) - def->leaf_size * sqrt(2.0)) > 1e-5) bad++;
        for (int t = 0; t < 6; t++)
          if (u32_at(idx + (6 * card + (size_t)t) * 4) != 4 * card + tris[t]) bad++;
      }
    }
    CHECK_INT(card, leaves);
    CHECK_INT(bad, 0);
    check_bounds(&world_read, attribute(prim, "POSITION"));
  }
}

/* The boxes: 24 vertices of the obstacle's corners, turned y up, 12 triangles. */
static void test_boxes(void) {
  const sylva_world *w = the_world();
  for (int i = 0; i < 2; i++) {
    sylva_obstacle_def o;
    sylva_world_obstacle_at(w, i, NULL, &o);
    const cJSON *prim = primitive(3 + i, 0);
    CHECK_INT(num(prim, "material"), 3 + i);
    const cJSON *acc = item(world_read.json, "accessors", attribute(prim, "POSITION"));
    CHECK_INT(num(acc, "count"), 24);
    CHECK_INT(num(item(world_read.json, "accessors", (int)num(prim, "indices")), "count"), 36);
    double lo[3], hi[3];
    y_up(o.min, lo);
    y_up(o.max, hi);
    for (int a = 0; a < 3; a++) {
      double want_lo = a == 2 ? -o.max[1] : lo[a], want_hi = a == 2 ? -o.min[1] : hi[a];
      CHECK_NEAR(cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(acc, "min"), a)->valuedouble,
                 want_lo, 1e-6);
      CHECK_NEAR(cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(acc, "max"), a)->valuedouble,
                 want_hi, 1e-6);
    }
    check_bounds(&world_read, attribute(prim, "POSITION"));
  }
}

/* ---- prisms ---- */

/* Per obstacle of prism_world: its node, and its primitive's vertices and indices
 * (four vertices per wall, each cap's points; two triangles per wall, the caps'):
 * the house and the yard have 10 points, 10 walls and 10 cap triangles. */
static const char *const prism_nodes[PRISMS] = {"obstacle/house", "obstacle/slab", "zone/yard"};
static const size_t prism_vertices[PRISMS] = {60, 24, 60};
static const size_t prism_indices[PRISMS] = {120, 36, 120};
static const size_t prism_walls[PRISMS] = {20, 8, 20};

/* A primitive read back: its positions turned z up again, its triangles with each
 * corner on the first vertex of its position (welded: a flat-shaded mesh repeats
 * its vertices), and the corners whose NORMAL is not their triangle's unit normal. */
typedef struct soup {
  size_t nv, nt;
  double (*v)[3];
  size_t (*welded)[3];
  size_t bad_normals;
} soup;

/* A position and its vertex, to weld by sorting. */
typedef struct placed {
  double p[3];
  size_t i;
} placed;

static int compare_placed(const void *a, const void *b) {
  const placed *s = a, *t = b;
  for (int d = 0; d < 3; d++)
    if (s->p[d] != t->p[d]) return s->p[d] < t->p[d] ? -1 : 1;
  return (s->i > t->i) - (s->i < t->i);
}

static bool same_position(const placed *a, const placed *b) {
  return a->p[0] == b->p[0] && a->p[1] == b->p[1] && a->p[2] == b->p[2];
}

/* A glTF vector (y up) as the world's (z up). */
static void z_up(const float v[3], double out[3]) {
  out[0] = v[0];
  out[1] = -(double)v[2];
  out[2] = v[1];
}

static soup read_soup(const glb *g, const cJSON *prim) {
  soup s = {0, 0, NULL, NULL, 0};
  size_t n, stride, nn, nstride, ni, istride;
  const unsigned char *pos = accessor_data(g, attribute(prim, "POSITION"), &n, &stride);
  const unsigned char *nrm = accessor_data(g, attribute(prim, "NORMAL"), &nn, &nstride);
  const unsigned char *idx = accessor_data(g, (int)num(prim, "indices"), &ni, &istride);
  CHECK_INT(nn, n);
  s.nv = n;
  s.nt = ni / 3;
  s.v = malloc((n + 1) * sizeof *s.v);
  double(*normal)[3] = malloc((n + 1) * sizeof *normal);
  placed *order = malloc((n + 1) * sizeof *order);
  size_t *first = malloc((n + 1) * sizeof *first);
  s.welded = malloc((s.nt + 1) * sizeof *s.welded);
  if (!s.v || !normal || !order || !first || !s.welded) exit(1);
  for (size_t i = 0; i < n; i++) {
    float q[3], m[3];
    for (int a = 0; a < 3; a++) {
      q[a] = f32_at(pos + i * stride + 4 * (size_t)a);
      m[a] = f32_at(nrm + i * nstride + 4 * (size_t)a);
    }
    z_up(q, s.v[i]);
    z_up(m, normal[i]);
    memcpy(order[i].p, s.v[i], sizeof order[i].p);
    order[i].i = i;
  }
  qsort(order, n, sizeof *order, compare_placed);
  for (size_t k = 0; k < n; k++)
    first[order[k].i] = k > 0 && same_position(&order[k - 1], &order[k]) ? first[order[k - 1].i]
                                                                         : order[k].i;
  for (size_t t = 0; t < s.nt; t++) {
    size_t c[3];
    for (int k = 0; k < 3; k++) {
      c[k] = u32_at(idx + (3 * t + (size_t)k) * 4);
      if (c[k] >= n) exit(1);
      s.welded[t][k] = first[c[k]];
    }
    const double *a = s.v[c[0]], *b = s.v[c[1]], *d = s.v[c[2]];
    double e1[3], e2[3], u[3];
    for (int q = 0; q < 3; q++) e1[q] = b[q] - a[q], e2[q] = d[q] - a[q];
    u[0] = e1[1] * e2[2] - e1[2] * e2[1];
    u[1] = e1[2] * e2[0] - e1[0] * e2[2];
    u[2] = e1[0] * e2[1] - e1[1] * e2[0];
    double len = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (int k = 0; k < 3; k++)
      for (int q = 0; q < 3; q++)
        if (!(fabs(normal[c[k]][q] - u[q] / len) <= 1e-6)) s.bad_normals++;
  }
  free(normal);
  free(order);
  free(first);
  return s;
}

static void soup_free(soup *s) {
  free(s->v);
  free(s->welded);
}

/* The prisms' meshes: a node and a primitive each, material "obstacle" or "zone",
 * the counts above; welded, each a closed mesh of its footprint's volume and cap
 * areas with walls facing out (into the courtyard for its hole), flat unit normals
 * facing out, its bounds; the slab's the volume and bounds of the box of its
 * corners (block_world). */
static void test_prisms(void) {
  sylva_world *w = prism_world(), *bw = block_world();
  CHECK(w != NULL && bw != NULL);
  if (!w || !bw) exit(1);
  sylva_mesh_options opt = {.sides = 8, .obstacles = true};
  blob b = write_blob(w, &opt), bb = write_blob(bw, &opt);
  glb g = read_glb(&b), bg = read_glb(&bb);
  CHECK(g.ok && bg.ok);
  if (g.ok && bg.ok) {
    CHECK_INT(count(g.json, "nodes"), 1 + PRISMS);
    CHECK_INT(count(g.json, "materials"), 2);
    CHECK(strcmp(str(item(g.json, "materials", 0), "name"), "obstacle") == 0);
    CHECK(strcmp(str(item(g.json, "materials", 1), "name"), "zone") == 0);
    mesh_measure slab = {0};
    for (int i = 0; i < PRISMS; i++) {
      CHECK(strcmp(str(item(g.json, "nodes", 1 + i), "name"), prism_nodes[i]) == 0);
      const cJSON *prim = cJSON_GetArrayItem(
          cJSON_GetObjectItemCaseSensitive(item(g.json, "meshes", i), "primitives"), 0);
      CHECK_INT(num(prim, "material"), i == 2 ? 1 : 0);
      soup s = read_soup(&g, prim);
      CHECK_INT(s.nv, prism_vertices[i]);
      CHECK_INT(3 * s.nt, prism_indices[i]);
      CHECK_INT(s.bad_normals, 0);
      sylva_obstacle_def o;
      sylva_world_obstacle_at(w, i, NULL, &o);
      mesh_measure m =
          measure_mesh((const double(*)[3])s.v, (const size_t(*)[3])s.welded, s.nt, &o);
      check_measures(&m, &o, prism_walls[i]);
      check_bounds(&g, attribute(prim, "POSITION"));
      if (i == 1) slab = m;
      soup_free(&s);
    }
    /* the box of the slab's corners: 24 vertices and 12 triangles as well */
    const cJSON *prim = cJSON_GetArrayItem(
        cJSON_GetObjectItemCaseSensitive(item(bg.json, "meshes", 0), "primitives"), 0);
    soup s = read_soup(&bg, prim);
    CHECK_INT(s.nv, 24);
    CHECK_INT(s.nt, 12);
    sylva_obstacle_def o;
    sylva_world_obstacle_at(bw, 0, NULL, &o);
    mesh_measure box =
        measure_mesh((const double(*)[3])s.v, (const size_t(*)[3])s.welded, s.nt, &o);
    CHECK(box.closed);
    CHECK_NEAR(box.volume, 6.0, 1e-12);
    CHECK_NEAR(slab.volume, box.volume, 1e-12);
    for (int d = 0; d < 3; d++) CHECK(slab.lo[d] == box.lo[d] && slab.hi[d] == box.hi[d]);
    soup_free(&s);
  }
  cJSON_Delete(g.json);
  cJSON_Delete(bg.json);
  free(b.data);
  free(bb.data);
  sylva_world_destroy(w);
  sylva_world_destroy(bw);
}

/* The same world and options: the same bytes; other sides: other bytes. */
static void test_deterministic(void) {
  const sylva_world *w = the_world();
  sylva_mesh_options opt = sylva_mesh_default_options();
  opt.obstacles = true;
  blob again = write_blob(w, &opt);
  CHECK(again.size == world_glb.size && memcmp(again.data, world_glb.data, again.size) == 0);
  free(again.data);
  opt.sides = 5;
  blob five = write_blob(w, &opt);
  CHECK_INT(five.rc, 0);
  CHECK(five.size < world_glb.size);
  free(five.data);
}

/* Species whose leaves agree in colour share one material "leaves". */
static void test_one_colour(void) {
  sylva_world *w = make_world(LEAF_GREEN, LEAF_GREEN, 5);
  CHECK(w != NULL);
  if (!w) return;
  blob b = write_blob(w, NULL);
  glb g = read_glb(&b);
  if (g.ok) {
    CHECK_INT(count(g.json, "materials"), 2);
    CHECK(strcmp(str(item(g.json, "materials", 0), "name"), "bark") == 0);
    CHECK(strcmp(str(item(g.json, "materials", 1), "name"), "leaves") == 0);
    /* no obstacles asked for: the plants' nodes only */
    CHECK_INT(count(g.json, "nodes"), 4);
  }
  cJSON_Delete(g.json);
  free(b.data);
  sylva_world_destroy(w);
}

/* A world with nothing to draw: a root node, no buffer, no BIN chunk. */
static void test_empty(void) {
  sylva_world_def wd = sylva_default_world_def();
  sylva_world *w;
  CHECK_INT(sylva_world_create(&wd, &w), 0);
  blob b = write_blob(w, NULL);
  glb g = read_glb(&b);
  CHECK(g.ok && g.bin == NULL);
  if (g.ok) {
    CHECK_INT(count(g.json, "nodes"), 1);
    CHECK(!cJSON_GetObjectItemCaseSensitive(g.json, "buffers"));
    CHECK(!cJSON_GetObjectItemCaseSensitive(item(g.json, "nodes", 0), "children"));
  }
  cJSON_Delete(g.json);
  free(b.data);
  /* a box alone */
  sylva_obstacle_def box = {"a box", {1, 1, 1}, {2, 3, 4}, SYLVA_OBSTACLE_SOLID, {0}};
  CHECK(sylva_world_add_obstacle(w, &box) >= 0);
  sylva_mesh_options opt = {.sides = 8, .obstacles = true};
  b = write_blob(w, &opt);
  g = read_glb(&b);
  if (g.ok) {
    CHECK_INT(count(g.json, "nodes"), 2);
    CHECK(strcmp(str(item(g.json, "nodes", 1), "name"), "obstacle/a box") == 0);
    CHECK_INT(count(g.json, "materials"), 1);
    CHECK(!cJSON_GetObjectItemCaseSensitive(g.json, "images"));
  }
  cJSON_Delete(g.json);
  free(b.data);
  sylva_world_destroy(w);
}

/* 3 to 64 sides; anything else writes nothing. */
static void test_options(void) {
  const sylva_world *w = the_world();
  static const int sides[] = {-1, 0, 2, 3, 64, 65};
  for (size_t i = 0; i < sizeof sides / sizeof *sides; i++) {
    sylva_mesh_options opt = {.sides = sides[i], .obstacles = false};
    blob b = write_blob(w, &opt);
    bool good = sides[i] >= 3 && sides[i] <= 64;
    CHECK_INT(b.rc, good ? 0 : SYLVA_EINVAL);
    CHECK(good ? b.size > 0 : b.size == 0);
    free(b.data);
  }
  /* NULL: the defaults, 8 sides without obstacles */
  sylva_mesh_options eight = {.sides = 8, .obstacles = false};
  blob defaults = write_blob(w, NULL), explicit = write_blob(w, &eight);
  CHECK(defaults.size == explicit.size &&
        memcmp(defaults.data, explicit.data, defaults.size) == 0);
  free(defaults.data);
  free(explicit.data);
}

static int write_glb(FILE *f, const void *w) { return gltf_write(f, w, NULL); }

/* A failed write is SYLVA_MESH_EWRITE with errno kept. */
static void test_write_error(void) {
  int err;
  CHECK_INT(write_to_full(write_glb, the_world(), &err), SYLVA_MESH_EWRITE);
  CHECK_INT(err, ENOSPC);
}

/* With OUTDIR: the files written there and listed for assimp_check.py and
 * gltf_validate.mjs: the world's with obstacles and 8 sides, without and with 3,
 * and the prisms'. */
static const char *outdir;

/* Writes b to OUTDIR/name and lists it and its primitives in the manifest. */
static void save_glb(FILE *manifest, const char *name, const blob *b) {
  char path[4096];
  glb g = read_glb(b);
  snprintf(path, sizeof path, "%s/%s", outdir, name);
  FILE *f = fopen(path, "wb");
  CHECK(f != NULL);
  if (f) {
    CHECK_INT(fwrite(b->data, 1, b->size, f), b->size);
    CHECK_INT(fclose(f), 0);
  }
  size_t vertices = 0, faces = 0;
  int meshes = count(g.json, "meshes");
  for (int m = 0; m < meshes; m++) {
    const cJSON *mesh = item(g.json, "meshes", m);
    int prims = count(mesh, "primitives");
    for (int k = 0; k < prims; k++) {
      const cJSON *prim =
          cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(mesh, "primitives"), k);
      size_t v = (size_t)num(item(g.json, "accessors", attribute(prim, "POSITION")), "count");
      size_t t = (size_t)num(item(g.json, "accessors", (int)num(prim, "indices")), "count") / 3;
      vertices += v;
      faces += t;
      char mesh_name[160];
      if (prims > 1) snprintf(mesh_name, sizeof mesh_name, "%s-%d", str(mesh, "name"), k);
      else snprintf(mesh_name, sizeof mesh_name, "%s", str(mesh, "name"));
      fprintf(manifest, "object\t%s\t%s\t%zu\t%zu\n", name, mesh_name, t, v);
    }
  }
  fprintf(manifest, "file\t%s\tglb\t%zu\t%zu\n", name, vertices, faces);
  cJSON_Delete(g.json);
}

static void test_files(void) {
  if (!outdir) return;
  const sylva_world *w = the_world();
  char path[4096];
  snprintf(path, sizeof path, "%s/expected.tsv", outdir);
  FILE *manifest = fopen(path, "w");
  CHECK(manifest != NULL);
  if (!manifest) return;
  static const int sides[] = {8, 3};
  for (int c = 0; c < 2; c++) {
    sylva_mesh_options opt = {.sides = sides[c], .obstacles = c == 0};
    blob b = write_blob(w, &opt);
    char name[64];
    snprintf(name, sizeof name, "scene_s%d%s.glb", sides[c], c == 0 ? "_obstacles" : "");
    save_glb(manifest, name, &b);
    free(b.data);
  }
  sylva_world *pw = prism_world();
  CHECK(pw != NULL);
  if (pw) {
    sylva_mesh_options opt = {.sides = 8, .obstacles = true};
    blob b = write_blob(pw, &opt);
    save_glb(manifest, "prisms.glb", &b);
    free(b.data);
    sylva_world_destroy(pw);
  }
  CHECK_INT(fclose(manifest), 0);
}

int main(int argc, char **argv) {
  if (argc > 3) {
    fprintf(stderr, "usage: %s [OUTDIR|- [TEST]]\n", argv[0]);
    return 2;
  }
  if (argc >= 2 && strcmp(argv[1], "-") != 0) outdir = argv[1];
  static const check_test tests[] = {
      CHECK_TEST(world),      CHECK_TEST(nodes),         CHECK_TEST(materials),
      CHECK_TEST(bark),       CHECK_TEST(leaves),        CHECK_TEST(boxes),
      CHECK_TEST(prisms),
      CHECK_TEST(deterministic), CHECK_TEST(one_colour), CHECK_TEST(empty),
      CHECK_TEST(options),    CHECK_TEST(write_error),   CHECK_TEST(files)};
  CHECK_RUN(argc, argv, 2, tests);
  cJSON_Delete(world_read.json);
  free(world_glb.data);
  sylva_world_destroy(world);
  return check_summary("export-gltf");
}
