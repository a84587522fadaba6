/* Binary glTF export (gltf.h). Three passes: a plan (the primitives of every stem
 * and obstacle with their counts, the prisms' meshes, the materials, the layout of
 * the buffer), the fill of the buffer (the branches from sylva_mesh_branches, the
 * leaf cards from foliage_place, the boxes and prisms), then the JSON (cJSON), which
 * needs the fill's bounds. */
#include "gltf.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "foliage.h"
#include "leaf_texture.h"
#include "prism_mesh.h"
#include "sylva/status.h"
#include "vec3.h"

/* The GL enums glTF uses. */
enum {
  GL_UNSIGNED_INT = 5125,
  GL_FLOAT = 5126,
  GL_ARRAY_BUFFER = 34962,
  GL_ELEMENT_ARRAY_BUFFER = 34963,
  GL_LINEAR = 9729,
  GL_LINEAR_MIPMAP_LINEAR = 9987,
  GL_CLAMP_TO_EDGE = 33071
};

/* GLB: the header's magic ("glTF") and the chunk types ("JSON", "BIN\0"). */
#define GLB_MAGIC 0x46546C67u
#define GLB_JSON 0x4E4F534Au
#define GLB_BIN 0x004E4942u

/* The colours, sRGB 0xRRGGBB like a species' leaf_colour. */
#define BARK_COLOUR 0x6b4f3a
#define OBSTACLE_COLOUR 0x9a9a9a
#define ZONE_COLOUR 0xffb000
#define ZONE_ALPHA 0.35

/* The buffer's views, in their order in the buffer. */
enum { VIEW_VEC3, VIEW_VEC2, VIEW_INDEX, VIEW_IMAGE, VIEW_COUNT };

typedef enum prim_kind { PRIM_BARK, PRIM_LEAVES, PRIM_BOX, PRIM_PRISM } prim_kind;

/* One primitive: what it is, its material and where its data goes. */
typedef struct prim {
  prim_kind kind;
  int owner;    /* global stem (bark, leaves) or obstacle index (box, prism) */
  int species;  /* leaves: the species, for the material */
  int material;
  size_t vertices, indices;
  size_t vec3, vec2, index; /* byte offsets of its data in those views */
  float min[3], max[3];     /* bounds of its positions, from the fill */
} prim;

typedef enum material_kind { MAT_BARK, MAT_LEAVES, MAT_OBSTACLE, MAT_ZONE } material_kind;

typedef struct material {
  material_kind kind;
  int species; /* leaves: the species it is named for, -1 for the one "leaves" */
  int colour;  /* leaves: 0xRRGGBB */
} material;

/* The whole export. */
typedef struct gltf {
  const sylva_world *w;
  sylva_mesh_branches *b;
  int stems;
  int *stem_plant, *stem_number; /* per global stem: its plant and its index there */
  prism_mesh *obstacles;         /* with obstacles, one per obstacle (a box's all zero) */
  int nobstacles;
  prim *prims;
  size_t nprims;
  material *mats;       /* those in use, in the file's order */
  int nmats;
  size_t view_len[VIEW_COUNT];
  size_t view_start[VIEW_COUNT];
  size_t bin_len;       /* with the padding to 4 bytes */
  unsigned char *bin;
  unsigned char *png;
  size_t png_len;
} gltf;

static void gltf_free(gltf *g) {
  sylva_mesh_branches_destroy(g->b);
  free(g->stem_plant);
  free(g->stem_number);
  prism_meshes_free(g->obstacles, g->nobstacles);
  free(g->prims);
  free(g->mats);
  free(g->bin);
  free(g->png);
}

static size_t pad4(size_t n) { return (n + 3) & ~(size_t)3; }

static bool is_obstacle(prim_kind kind) { return kind == PRIM_BOX || kind == PRIM_PRISM; }

/* ---- the plan ---- */

static bool add_prim(gltf *g, prim_kind kind, int owner, size_t vertices, size_t indices) {
  prim *p = &g->prims[g->nprims++];
  memset(p, 0, sizeof *p);
  p->kind = kind;
  p->owner = owner;
  p->species = -1;
  p->vertices = vertices;
  p->indices = indices;
  /* a primitive's data and its index values must fit the GLB's 32 bits */
  return vertices <= UINT32_MAX / 24 && indices <= UINT32_MAX / 4;
}

/* The leaves of stem s (a sum over its nodes). */
static size_t stem_leaves(const gltf *g, int s) {
  size_t count, leaves = 0;
  const int32_t *nodes = sylva_mesh_branches_stem_nodes(g->b, s, &count);
  sylva_node_info info;
  for (size_t k = 0; k < count; k++) {
    sylva_world_node_at(g->w, (size_t)nodes[k], &info);
    if (info.leaves > 0) leaves += (size_t)info.leaves;
  }
  return leaves;
}

/* The materials in use, in their order: bark, the leaves (one, or one per species
 * in species order when their colours differ), obstacle, zone. */
static int plan_materials(gltf *g) {
  int species = sylva_world_species_count(g->w);
  bool bark = false, solid = false, zone = false;
  bool *leafy = calloc((size_t)species + 1, sizeof *leafy);
  int *species_mat = malloc(((size_t)species + 1) * sizeof *species_mat);
  g->mats = malloc(((size_t)species + 3) * sizeof *g->mats);
  if (!leafy || !species_mat || !g->mats) {
    free(leafy);
    free(species_mat);
    return SYLVA_ENOMEM;
  }
  for (size_t i = 0; i < g->nprims; i++) {
    const prim *p = &g->prims[i];
    if (p->kind == PRIM_BARK) bark = true;
    if (p->kind == PRIM_LEAVES) leafy[p->species] = true;
    if (is_obstacle(p->kind)) {
      sylva_obstacle_def o;
      sylva_world_obstacle_at(g->w, p->owner, NULL, &o);
      if (o.kind == SYLVA_OBSTACLE_ZONE) zone = true;
      else solid = true;
    }
  }
  int first = -1;
  bool differ = false;
  for (int sp = 0; sp < species; sp++) {
    if (!leafy[sp]) continue;
    if (first < 0) first = sp;
    else if (sylva_world_species(g->w, sp)->leaf_colour !=
             sylva_world_species(g->w, first)->leaf_colour)
      differ = true;
  }
  int n = 0, solid_mat = -1, zone_mat = -1;
  if (bark) g->mats[n++] = (material){MAT_BARK, -1, 0};
  int shared = n;
  for (int sp = 0; sp < species; sp++) {
    species_mat[sp] = -1;
    if (!leafy[sp]) continue;
    int colour = sylva_world_species(g->w, sp)->leaf_colour;
    if (differ) {
      species_mat[sp] = n;
      g->mats[n++] = (material){MAT_LEAVES, sp, colour};
    } else {
      species_mat[sp] = shared;
      if (sp == first) g->mats[n++] = (material){MAT_LEAVES, -1, colour};
    }
  }
  if (solid) {
    solid_mat = n;
    g->mats[n++] = (material){MAT_OBSTACLE, -1, 0};
  }
  if (zone) {
    zone_mat = n;
    g->mats[n++] = (material){MAT_ZONE, -1, 0};
  }
  g->nmats = n;
  for (size_t i = 0; i < g->nprims; i++) {
    prim *p = &g->prims[i];
    if (p->kind == PRIM_BARK) p->material = 0;
    else if (p->kind == PRIM_LEAVES) p->material = species_mat[p->species];
    else {
      sylva_obstacle_def o;
      sylva_world_obstacle_at(g->w, p->owner, NULL, &o);
      p->material = o.kind == SYLVA_OBSTACLE_ZONE ? zone_mat : solid_mat;
    }
  }
  free(leafy);
  free(species_mat);
  return 0;
}

static int plan(gltf *g) {
  const sylva_world *w = g->w;
  int plants = sylva_world_plant_count(w);
  size_t m = (size_t)g->stems + 1;
  g->stem_plant = malloc(m * sizeof *g->stem_plant);
  g->stem_number = malloc(m * sizeof *g->stem_number);
  g->prims = malloc((2 * (size_t)g->stems + (size_t)g->nobstacles + 1) * sizeof *g->prims);
  if (!g->stem_plant || !g->stem_number || !g->prims) return SYLVA_ENOMEM;
  for (int pl = 0; pl < plants; pl++)
    for (int k = 0; k < sylva_world_plant_stem_count(w, pl); k++) {
      int s = sylva_world_stem_index(w, pl, k);
      g->stem_plant[s] = pl;
      g->stem_number[s] = k;
    }
  bool fits = true;
  for (int s = 0; s < g->stems; s++) {
    size_t first, vertices, triangles, leaves = stem_leaves(g, s);
    sylva_mesh_branches_stem(g->b, s, &first, &vertices, &triangles);
    if (vertices) fits = add_prim(g, PRIM_BARK, s, vertices, 3 * triangles) && fits;
    if (leaves) {
      fits = leaves <= SIZE_MAX / 6 && add_prim(g, PRIM_LEAVES, s, 4 * leaves, 6 * leaves) && fits;
      g->prims[g->nprims - 1].species = sylva_world_plant_species(w, g->stem_plant[s]);
    }
  }
  for (int i = 0; i < g->nobstacles; i++) {
    const prism_mesh *pm = &g->obstacles[i];
    if (!pm->prism) {
      fits = add_prim(g, PRIM_BOX, i, 24, 36) && fits;
      continue;
    }
    /* four vertices per wall, each cap's points; two triangles per wall, the caps' */
    fits = pm->walls <= SIZE_MAX / 8 && pm->points <= SIZE_MAX / 8 &&
           pm->triangles <= SIZE_MAX / 8 &&
           add_prim(g, PRIM_PRISM, i, 4 * pm->walls + 2 * pm->points,
                    3 * (2 * pm->walls + 2 * pm->triangles)) &&
           fits;
  }
  if (!fits) return SYLVA_ETOOBIG;
  int rc = plan_materials(g);
  if (rc < 0) return rc;
  /* the layout: sums of sizes that each fit 32 bits, so no sum overflows 64 */
  for (size_t i = 0; i < g->nprims; i++) {
    prim *p = &g->prims[i];
    p->vec3 = g->view_len[VIEW_VEC3];
    g->view_len[VIEW_VEC3] += 24 * p->vertices;
    if (p->kind == PRIM_LEAVES) {
      p->vec2 = g->view_len[VIEW_VEC2];
      g->view_len[VIEW_VEC2] += 8 * p->vertices;
    }
    p->index = g->view_len[VIEW_INDEX];
    g->view_len[VIEW_INDEX] += 4 * p->indices;
  }
  if (g->view_len[VIEW_VEC2] > 0) {
    rc = leaf_texture_png(&g->png, &g->png_len);
    if (rc < 0) return rc;
    g->view_len[VIEW_IMAGE] = g->png_len;
  }
  size_t at = 0;
  for (int v = 0; v < VIEW_COUNT; v++) {
    g->view_start[v] = at;
    at += pad4(g->view_len[v]);
  }
  g->bin_len = at;
  /* the header, two chunk headers and a JSON of some size come on top */
  return at > UINT32_MAX - (1u << 24) ? SYLVA_ETOOBIG : 0;
}

/* ---- the fill ---- */

static unsigned char *put_u32(unsigned char *p, uint32_t v) {
  p[0] = (unsigned char)(v & 0xff);
  p[1] = (unsigned char)((v >> 8) & 0xff);
  p[2] = (unsigned char)((v >> 16) & 0xff);
  p[3] = (unsigned char)(v >> 24);
  return p + 4;
}

static unsigned char *put_f32(unsigned char *p, float f) {
  uint32_t u;
  memcpy(&u, &f, sizeof u);
  return put_u32(p, u);
}

/* A world vector (z up) as glTF's (y up), without negative zeros. */
static void y_up(const double v[3], float out[3]) {
  out[0] = (float)v[0];
  out[1] = (float)v[2];
  out[2] = (float)-v[1];
  for (int a = 0; a < 3; a++)
    if (out[a] == 0.0f) out[a] = 0.0f;
}

/* Where the current primitive's data goes. */
typedef struct cursor {
  prim *p;
  unsigned char *pos, *nrm, *uv, *idx;
  uint32_t next; /* vertices written so far */
} cursor;

static void cursor_open(gltf *g, prim *p, cursor *c) {
  c->p = p;
  c->pos = g->bin + g->view_start[VIEW_VEC3] + p->vec3;
  c->nrm = c->pos + 12 * p->vertices;
  c->uv = g->bin + g->view_start[VIEW_VEC2] + p->vec2;
  c->idx = g->bin + g->view_start[VIEW_INDEX] + p->index;
  c->next = 0;
}

static bool put_vertex(void *ctx, const double pos[3], const double normal[3]) {
  cursor *c = ctx;
  float q[3], n[3];
  y_up(pos, q);
  y_up(normal, n);
  for (int a = 0; a < 3; a++) {
    if (c->next == 0 || q[a] < c->p->min[a]) c->p->min[a] = q[a];
    if (c->next == 0 || q[a] > c->p->max[a]) c->p->max[a] = q[a];
    c->pos = put_f32(c->pos, q[a]);
    c->nrm = put_f32(c->nrm, n[a]);
  }
  c->next++;
  return true;
}

static bool put_triangle(void *ctx, size_t a, size_t b, size_t t) {
  cursor *c = ctx;
  c->idx = put_u32(c->idx, (uint32_t)a);
  c->idx = put_u32(c->idx, (uint32_t)b);
  c->idx = put_u32(c->idx, (uint32_t)t);
  return true;
}

static void node_point(const sylva_world *w, size_t i, double out[3]) {
  sylva_node_info info;
  sylva_world_node_at(w, i, &info);
  out[0] = info.x;
  out[1] = info.y;
  out[2] = info.z;
}

/* The leaf cards of stem s: node by node in id order, leaf by leaf. */
static void fill_leaves(gltf *g, cursor *c) {
  int s = c->p->owner;
  double size = sylva_world_species(g->w, c->p->species)->leaf_size;
  size_t count;
  const int32_t *nodes = sylva_mesh_branches_stem_nodes(g->b, s, &count);
  sylva_node_info info;
  for (size_t k = 0; k < count; k++) {
    size_t i = (size_t)nodes[k];
    sylva_world_node_at(g->w, i, &info);
    if (info.leaves <= 0) continue;
    double q[3] = {info.x, info.y, info.z}, p[3];
    int32_t parent = sylva_mesh_branches_parent(g->b, i);
    if (parent >= 0) node_point(g->w, (size_t)parent, p);
    for (int leaf = 0; leaf < info.leaves; leaf++) {
      foliage_leaf f;
      foliage_place(parent >= 0 ? p : NULL, q, leaf, info.leaves, size, &f);
      double h = 0.5 * f.edge, normal[3] = {f.along[1] * f.across[2] - f.along[2] * f.across[1],
                                            f.along[2] * f.across[0] - f.along[0] * f.across[2],
                                            f.along[0] * f.across[1] - f.along[1] * f.across[0]};
      /* base-left, base-right, tip-right, tip-left, with their (u, v) */
      static const double corner[4][2] = {{-1, -1}, {-1, 1}, {1, 1}, {1, -1}};
      static const float uv[4][2] = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};
      uint32_t base = c->next;
      for (int v = 0; v < 4; v++) {
        double pt[3];
        for (int a = 0; a < 3; a++)
          pt[a] = f.centre[a] + h * corner[v][0] * f.along[a] + h * corner[v][1] * f.across[a];
        put_vertex(c, pt, normal);
        c->uv = put_f32(c->uv, uv[v][0]);
        c->uv = put_f32(c->uv, uv[v][1]);
      }
      /* counter-clockwise seen from along x across */
      put_triangle(c, base, base + 2, base + 1);
      put_triangle(c, base, base + 3, base + 2);
    }
  }
}

/* Obstacle i's box: four vertices per side with the side's normal. */
static void fill_box(gltf *g, cursor *c) {
  sylva_obstacle_def o;
  sylva_world_obstacle_at(g->w, c->p->owner, NULL, &o);
  for (int f = 0; f < 6; f++) {
    double normal[3] = {0, 0, 0};
    normal[f / 2] = f % 2 ? 1.0 : -1.0;
    uint32_t base = c->next;
    for (int v = 0; v < 4; v++) {
      double q[3];
      sylva_mesh_box_corner(&o, sylva_mesh_box_quads[f][v], q);
      put_vertex(c, q, normal);
    }
    put_triangle(c, base, base + 1, base + 2);
    put_triangle(c, base, base + 2, base + 3);
  }
}

/* Obstacle i's prism: four vertices per wall with the wall's outward normal (the
 * solid lies left of its edge), then the bottom cap's points facing down and the
 * top cap's facing up, with their triangles. */
static void fill_prism(gltf *g, cursor *c) {
  const prism_mesh *m = &g->obstacles[c->p->owner];
  for (size_t k = 0; k < m->walls; k++) {
    const double *u = m->xy[m->wall[k][0]], *v = m->xy[m->wall[k][1]];
    double normal[3] = {v[1] - u[1], u[0] - v[0], 0.0};
    if (!normalize3(normal)) {
      /* an edge too short to have a direction: any unit normal keeps the file valid */
      normal[0] = 1.0;
      normal[1] = 0.0;
    }
    const double q[4][3] = {{u[0], u[1], m->bottom}, {v[0], v[1], m->bottom},
                            {v[0], v[1], m->top}, {u[0], u[1], m->top}};
    uint32_t base = c->next;
    for (int j = 0; j < 4; j++) put_vertex(c, q[j], normal);
    put_triangle(c, base, base + 1, base + 2);
    put_triangle(c, base, base + 2, base + 3);
  }
  for (int level = 0; level < 2; level++) {
    double normal[3] = {0.0, 0.0, level ? 1.0 : -1.0};
    uint32_t base = c->next;
    for (size_t k = 0; k < m->points; k++) {
      double q[3] = {m->xy[k][0], m->xy[k][1], level ? m->top : m->bottom};
      put_vertex(c, q, normal);
    }
    /* the bottom cap turned over, so it faces down */
    for (size_t k = 0; k < m->triangles; k++)
      put_triangle(c, base + m->tri[k][0], base + m->tri[k][level ? 1 : 2],
                   base + m->tri[k][level ? 2 : 1]);
  }
}

static int fill(gltf *g) {
  g->bin = calloc(g->bin_len ? g->bin_len : 1, 1);
  if (!g->bin) return SYLVA_ENOMEM;
  for (size_t i = 0; i < g->nprims; i++) {
    cursor c;
    cursor_open(g, &g->prims[i], &c);
    switch (c.p->kind) {
    case PRIM_BARK:
      sylva_mesh_branches_vertices(g->b, c.p->owner, put_vertex, &c);
      sylva_mesh_branches_triangles(g->b, c.p->owner, put_triangle, &c);
      break;
    case PRIM_LEAVES: fill_leaves(g, &c); break;
    case PRIM_BOX: fill_box(g, &c); break;
    case PRIM_PRISM: fill_prism(g, &c); break;
    }
  }
  if (g->png_len) memcpy(g->bin + g->view_start[VIEW_IMAGE], g->png, g->png_len);
  return 0;
}

/* ---- the JSON ---- */

/* Adds item to parent (an object under key, or an array for key NULL); a failure
 * anywhere is remembered in *failed and later adds do nothing. Returns item or NULL. */
static cJSON *add(bool *failed, cJSON *parent, const char *key, cJSON *item) {
  if (!item || !parent || *failed) {
    cJSON_Delete(item);
    *failed = true;
    return NULL;
  }
  if (!(key ? cJSON_AddItemToObject(parent, key, item) : cJSON_AddItemToArray(parent, item))) {
    cJSON_Delete(item);
    *failed = true;
    return NULL;
  }
  return item;
}

static cJSON *add_num(bool *failed, cJSON *parent, const char *key, double v) {
  return add(failed, parent, key, cJSON_CreateNumber(v));
}

static cJSON *add_str(bool *failed, cJSON *parent, const char *key, const char *s) {
  return add(failed, parent, key, cJSON_CreateString(s));
}

static cJSON *add_obj(bool *failed, cJSON *parent, const char *key) {
  return add(failed, parent, key, cJSON_CreateObject());
}

static cJSON *add_arr(bool *failed, cJSON *parent, const char *key) {
  return add(failed, parent, key, cJSON_CreateArray());
}

/* An sRGB component (0..1) as the linear value glTF's colour factors hold. */
static double linear(double c) {
  return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

static void add_colour(bool *failed, cJSON *pbr, int colour, double alpha) {
  double rgb[3];
  foliage_rgb(colour, rgb);
  cJSON *f = add_arr(failed, pbr, "baseColorFactor");
  for (int a = 0; a < 3; a++) add_num(failed, f, NULL, linear(rgb[a]));
  add_num(failed, f, NULL, alpha);
}

static void add_material(bool *failed, cJSON *mats, const gltf *g, const material *m) {
  cJSON *o = add_obj(failed, mats, NULL);
  char name[SYLVA_LABEL_MAX + 8];
  switch (m->kind) {
  case MAT_BARK: snprintf(name, sizeof name, "bark"); break;
  case MAT_LEAVES:
    if (m->species < 0) snprintf(name, sizeof name, "leaves");
    else snprintf(name, sizeof name, "leaves-%s", sylva_world_species_label(g->w, m->species));
    break;
  case MAT_OBSTACLE: snprintf(name, sizeof name, "obstacle"); break;
  case MAT_ZONE: snprintf(name, sizeof name, "zone"); break;
  }
  add_str(failed, o, "name", name);
  cJSON *pbr = add_obj(failed, o, "pbrMetallicRoughness");
  switch (m->kind) {
  case MAT_BARK: add_colour(failed, pbr, BARK_COLOUR, 1.0); break;
  case MAT_LEAVES:
    add_colour(failed, pbr, m->colour, 1.0);
    add_num(failed, add_obj(failed, pbr, "baseColorTexture"), "index", 0);
    break;
  case MAT_OBSTACLE: add_colour(failed, pbr, OBSTACLE_COLOUR, 1.0); break;
  case MAT_ZONE: add_colour(failed, pbr, ZONE_COLOUR, ZONE_ALPHA); break;
  }
  add_num(failed, pbr, "metallicFactor", 0);
  add_num(failed, pbr, "roughnessFactor", m->kind == MAT_BARK ? 0.9 : 0.8);
  if (m->kind == MAT_LEAVES) {
    add_str(failed, o, "alphaMode", "MASK");
    add_num(failed, o, "alphaCutoff", 0.5);
  } else if (m->kind == MAT_ZONE) {
    add_str(failed, o, "alphaMode", "BLEND");
  }
  if (m->kind == MAT_LEAVES || m->kind == MAT_ZONE)
    add(failed, o, "doubleSided", cJSON_CreateTrue());
}

/* One accessor, as number *count (then counted); returns it. */
static cJSON *add_accessor(bool *failed, cJSON *accessors, int *count, int view, size_t offset,
                           int component, size_t n, const char *type) {
  cJSON *a = add_obj(failed, accessors, NULL);
  add_num(failed, a, "bufferView", view);
  add_num(failed, a, "byteOffset", (double)offset);
  add_num(failed, a, "componentType", component);
  add_num(failed, a, "count", (double)n);
  add_str(failed, a, "type", type);
  (*count)++;
  return a;
}

static void add_vec3(bool *failed, cJSON *parent, const char *key, const float v[3]) {
  cJSON *arr = add_arr(failed, parent, key);
  for (int a = 0; a < 3; a++) add_num(failed, arr, NULL, (double)v[a]);
}

/* The primitive p in mesh m, with its accessors. */
static void add_primitive(bool *failed, cJSON *prims, cJSON *accessors, int *count,
                          const int views[VIEW_COUNT], const prim *p) {
  cJSON *o = add_obj(failed, prims, NULL), *attr = add_obj(failed, o, "attributes");
  add_num(failed, attr, "POSITION", *count);
  cJSON *pos = add_accessor(failed, accessors, count, views[VIEW_VEC3], p->vec3, GL_FLOAT,
                            p->vertices, "VEC3");
  add_vec3(failed, pos, "min", p->min);
  add_vec3(failed, pos, "max", p->max);
  add_num(failed, attr, "NORMAL", *count);
  add_accessor(failed, accessors, count, views[VIEW_VEC3], p->vec3 + 12 * p->vertices, GL_FLOAT,
               p->vertices, "VEC3");
  if (p->kind == PRIM_LEAVES) {
    add_num(failed, attr, "TEXCOORD_0", *count);
    add_accessor(failed, accessors, count, views[VIEW_VEC2], p->vec2, GL_FLOAT, p->vertices,
                 "VEC2");
  }
  add_num(failed, o, "indices", *count);
  add_accessor(failed, accessors, count, views[VIEW_INDEX], p->index, GL_UNSIGNED_INT,
               p->indices, "SCALAR");
  add_num(failed, o, "material", p->material);
}

/* The name of primitive p's node. */
static void owner_name(const gltf *g, const prim *p, char *buf, size_t size) {
  if (is_obstacle(p->kind)) {
    sylva_obstacle_def o;
    sylva_world_obstacle_at(g->w, p->owner, NULL, &o);
    snprintf(buf, size, "%s/%s", o.kind == SYLVA_OBSTACLE_ZONE ? "zone" : "obstacle", o.label);
  } else {
    snprintf(buf, size, "%s/%d", sylva_world_plant_label(g->w, g->stem_plant[p->owner]),
             g->stem_number[p->owner]);
  }
}

static void add_buffer_parts(bool *failed, cJSON *root, const gltf *g, int views[VIEW_COUNT]) {
  static const int targets[VIEW_COUNT] = {GL_ARRAY_BUFFER, GL_ARRAY_BUFFER,
                                          GL_ELEMENT_ARRAY_BUFFER, 0};
  static const int strides[VIEW_COUNT] = {12, 8, 0, 0};
  cJSON *bv = add_arr(failed, root, "bufferViews");
  int n = 0;
  for (int v = 0; v < VIEW_COUNT; v++) {
    views[v] = -1;
    if (!g->view_len[v]) continue;
    views[v] = n++;
    cJSON *o = add_obj(failed, bv, NULL);
    add_num(failed, o, "buffer", 0);
    add_num(failed, o, "byteOffset", (double)g->view_start[v]);
    add_num(failed, o, "byteLength", (double)g->view_len[v]);
    if (strides[v]) add_num(failed, o, "byteStride", strides[v]);
    if (targets[v]) add_num(failed, o, "target", targets[v]);
  }
  add_num(failed, add_obj(failed, add_arr(failed, root, "buffers"), NULL), "byteLength",
          (double)g->bin_len);
}

static cJSON *build_json(const gltf *g) {
  bool failed = false;
  cJSON *root = cJSON_CreateObject();
  if (!root) return NULL;
  cJSON *asset = add_obj(&failed, root, "asset");
  add_str(&failed, asset, "version", "2.0");
  add_str(&failed, asset, "generator", "sylva");
  add_num(&failed, root, "scene", 0);
  cJSON *scene = add_obj(&failed, add_arr(&failed, root, "scenes"), NULL);
  add_num(&failed, add_arr(&failed, scene, "nodes"), NULL, 0);
  cJSON *nodes = add_arr(&failed, root, "nodes");
  cJSON *top = add_obj(&failed, nodes, NULL);
  add_str(&failed, top, "name", "sylva");
  cJSON *children = g->nprims ? add_arr(&failed, top, "children") : NULL;
  add_num(&failed, add_obj(&failed, top, "extras"), "iteration", sylva_world_iteration(g->w));
  if (g->nprims == 0) {
    if (failed) {
      cJSON_Delete(root);
      return NULL;
    }
    return root;
  }
  int views[VIEW_COUNT];
  cJSON *meshes = add_arr(&failed, root, "meshes");
  cJSON *mats = add_arr(&failed, root, "materials");
  for (int k = 0; k < g->nmats; k++) add_material(&failed, mats, g, &g->mats[k]);
  if (g->png_len) {
    cJSON *tex = add_obj(&failed, add_arr(&failed, root, "textures"), NULL);
    add_num(&failed, tex, "sampler", 0);
    add_num(&failed, tex, "source", 0);
  }
  cJSON *images = g->png_len ? add_arr(&failed, root, "images") : NULL;
  if (g->png_len) {
    cJSON *smp = add_obj(&failed, add_arr(&failed, root, "samplers"), NULL);
    add_num(&failed, smp, "magFilter", GL_LINEAR);
    add_num(&failed, smp, "minFilter", GL_LINEAR_MIPMAP_LINEAR);
    add_num(&failed, smp, "wrapS", GL_CLAMP_TO_EDGE);
    add_num(&failed, smp, "wrapT", GL_CLAMP_TO_EDGE);
  }
  cJSON *accessors = add_arr(&failed, root, "accessors");
  add_buffer_parts(&failed, root, g, views);
  if (images) {
    cJSON *img = add_obj(&failed, images, NULL);
    add_str(&failed, img, "name", "leaf");
    add_num(&failed, img, "bufferView", views[VIEW_IMAGE]);
    add_str(&failed, img, "mimeType", "image/png");
  }
  int naccessors = 0, nmeshes = 0;
  char name[2 * SYLVA_LABEL_MAX + 16];
  cJSON *prims = NULL;
  for (size_t i = 0; i < g->nprims && !failed; i++) {
    const prim *p = &g->prims[i];
    /* a stem's bark and leaves share its node and mesh */
    bool same = i > 0 && p->kind == PRIM_LEAVES && g->prims[i - 1].kind == PRIM_BARK &&
                g->prims[i - 1].owner == p->owner;
    if (!same) {
      owner_name(g, p, name, sizeof name);
      cJSON *node = add_obj(&failed, nodes, NULL);
      add_str(&failed, node, "name", name);
      add_num(&failed, node, "mesh", nmeshes);
      add_num(&failed, children, NULL, 1 + nmeshes);
      cJSON *mesh = add_obj(&failed, meshes, NULL);
      add_str(&failed, mesh, "name", name);
      prims = add_arr(&failed, mesh, "primitives");
      nmeshes++;
    }
    add_primitive(&failed, prims, accessors, &naccessors, views, p);
  }
  if (failed) {
    cJSON_Delete(root);
    return NULL;
  }
  return root;
}

/* ---- the file ---- */

static int write_glb(FILE *out, const char *json, size_t json_len, const gltf *g) {
  size_t json_chunk = pad4(json_len);
  size_t total = 12 + 8 + json_chunk + (g->bin_len ? 8 + g->bin_len : 0);
  if (total > UINT32_MAX) return SYLVA_ETOOBIG;
  unsigned char head[20], *p = head;
  p = put_u32(p, GLB_MAGIC);
  p = put_u32(p, 2);
  p = put_u32(p, (uint32_t)total);
  p = put_u32(p, (uint32_t)json_chunk);
  put_u32(p, GLB_JSON);
  static const char spaces[3] = {' ', ' ', ' '};
  bool ok = fwrite(head, 1, sizeof head, out) == sizeof head &&
            fwrite(json, 1, json_len, out) == json_len &&
            fwrite(spaces, 1, json_chunk - json_len, out) == json_chunk - json_len;
  if (ok && g->bin_len) {
    p = put_u32(head, (uint32_t)g->bin_len);
    put_u32(p, GLB_BIN);
    ok = fwrite(head, 1, 8, out) == 8 && fwrite(g->bin, 1, g->bin_len, out) == g->bin_len;
  }
  ok = fflush(out) == 0 && ok;
  return ok ? 0 : SYLVA_MESH_EWRITE;
}

int gltf_write(FILE *out, const sylva_world *w, const sylva_mesh_options *opt) {
  sylva_mesh_options defaults = sylva_mesh_default_options();
  if (!opt) opt = &defaults;
  if (opt->sides < SYLVA_MESH_MIN_SIDES || opt->sides > SYLVA_MESH_MAX_SIDES)
    return SYLVA_EINVAL;
  gltf g = {.w = w, .stems = sylva_world_stem_count(w)};
  int rc = opt->obstacles ? prism_meshes_build(w, &g.obstacles, &g.nobstacles) : 0;
  if (rc == 0) rc = sylva_mesh_branches_create(w, opt->sides, &g.b);
  if (rc == 0) rc = plan(&g);
  if (rc == 0) rc = fill(&g);
  cJSON *root = rc == 0 ? build_json(&g) : NULL;
  char *json = root ? cJSON_PrintUnformatted(root) : NULL;
  cJSON_Delete(root);
  if (rc == 0 && !json) rc = SYLVA_ENOMEM;
  if (rc == 0) rc = write_glb(out, json, strlen(json), &g);
  int saved = errno;
  cJSON_free(json);
  gltf_free(&g);
  errno = saved;
  return rc;
}
