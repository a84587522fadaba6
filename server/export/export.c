#include "export.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "csv.h"
#include "gltf.h"
#include "mesh.h"
#include "sylva/encode.h"
#include "sylva/status.h"

static const char *const format_names[] = {
    [EXPORT_SKELETON] = "skeleton", [EXPORT_OBJ] = "obj", [EXPORT_PLY] = "ply",
    [EXPORT_CSV] = "csv", [EXPORT_GLB] = "glb"};
static const char *const format_extensions[] = {
    [EXPORT_SKELETON] = "json", [EXPORT_OBJ] = "obj", [EXPORT_PLY] = "ply",
    [EXPORT_CSV] = "csv", [EXPORT_GLB] = "glb"};

bool export_format_parse(const char *name, export_format *out) {
  for (size_t k = 0; k < sizeof format_names / sizeof format_names[0]; k++)
    if (strcmp(name, format_names[k]) == 0) {
      *out = (export_format)k;
      return true;
    }
  return false;
}

const char *export_format_extension(export_format format) { return format_extensions[format]; }

static int write_failed(char *err, size_t errlen) {
  snprintf(err, errlen, "%s", strerror(errno ? errno : EIO));
  return SERVER_EWRITE;
}

int export_write(FILE *f, store *st, const export_spec *spec, void (*warn)(const char *msg),
                 char *err, size_t errlen) {
  errno = 0;
  if (spec->format == EXPORT_CSV) {
    int failed = csv_write_stats(f, st, spec->run, spec->iteration);
    if (failed && !ferror(f)) snprintf(err, errlen, "%s", store_error(st));
    if (failed) return ferror(f) ? write_failed(err, errlen) : SERVER_EFAIL;
    return fflush(f) != 0 ? write_failed(err, errlen) : SERVER_OK;
  }
  sylva_world *w = NULL;
  if (store_world_at(st, spec->run, spec->iteration, warn, &w)) {
    snprintf(err, errlen, "run \"%s\": %s", spec->name, store_error(st));
    return SERVER_EFAIL;
  }
  int rc = SERVER_OK;
  if (spec->format == EXPORT_SKELETON) {
    char *text = sylva_encode_skeleton(w);
    if (!text) {
      snprintf(err, errlen, "out of memory");
      rc = SERVER_ENOMEM;
    } else if (fputs(text, f) == EOF || fflush(f) != 0) {
      rc = write_failed(err, errlen);
    }
    free(text);
  } else {
    sylva_mesh_options mo = sylva_mesh_default_options();
    mo.sides = spec->sides;
    mo.obstacles = spec->obstacles;
    int m = spec->format == EXPORT_GLB
                ? gltf_write(f, w, &mo)
                : sylva_mesh_write(f, w,
                                   spec->format == EXPORT_OBJ ? SYLVA_MESH_OBJ : SYLVA_MESH_PLY,
                                   &mo);
    if (m == SYLVA_MESH_EWRITE) {
      rc = write_failed(err, errlen);
    } else if (m == SYLVA_ETOOBIG && spec->format == EXPORT_GLB) {
      snprintf(err, errlen, "run \"%s\": the scene is larger than the 4 GiB a GLB file holds",
               spec->name);
      rc = SERVER_EFAIL;
    } else if (m) {
      snprintf(err, errlen, "%s", sylva_strerror(m));
      rc = m == SYLVA_ENOMEM ? SERVER_ENOMEM : SERVER_EFAIL;
    }
  }
  sylva_world_destroy(w);
  return rc;
}
