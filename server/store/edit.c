#include "edit.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sylva/snapshot.h"
#include "sylva/status.h"

int edit_reserve(edit *e, int removals, int obstacles, int plants) {
  if ((removals && !(e->removals = calloc((size_t)removals, sizeof *e->removals))) ||
      (obstacles && !(e->obstacles = calloc((size_t)obstacles, sizeof *e->obstacles))) ||
      (plants && !(e->plants = calloc((size_t)plants, sizeof *e->plants))))
    return SYLVA_ENOMEM;
  e->removal_count = removals;
  e->obstacle_count = obstacles;
  e->plant_count = plants;
  return SYLVA_OK;
}

int edit_obstacle_footprint(edit_obstacle *o, const sylva_footprint *f) {
  if (!f->ring_count) return SYLVA_OK;
  if (!(o->points = malloc((size_t)f->point_count * sizeof *o->points)) ||
      !(o->ring_sizes = malloc((size_t)f->ring_count * sizeof *o->ring_sizes)))
    return SYLVA_ENOMEM;
  memcpy(o->points, f->points, (size_t)f->point_count * sizeof *o->points);
  memcpy(o->ring_sizes, f->ring_sizes, (size_t)f->ring_count * sizeof *o->ring_sizes);
  o->point_count = f->point_count;
  o->ring_count = f->ring_count;
  return SYLVA_OK;
}

void edit_free(edit *e) {
  for (int i = 0; e->removals && i < e->removal_count; i++) free(e->removals[i]);
  for (int i = 0; e->obstacles && i < e->obstacle_count; i++) {
    free(e->obstacles[i].id);
    free(e->obstacles[i].points);
    free(e->obstacles[i].ring_sizes);
  }
  for (int i = 0; e->plants && i < e->plant_count; i++) {
    free(e->plants[i].id);
    free(e->plants[i].species);
    free(e->plants[i].roots);
  }
  free(e->prune.zone);
  free(e->removals);
  free(e->obstacles);
  free(e->plants);
  *e = (edit){0};
}

static int species_by_label(const sylva_world *w, const char *label) {
  for (int i = 0; i < sylva_world_species_count(w); i++)
    if (strcmp(sylva_world_species_label(w, i), label) == 0) return i;
  return -1;
}

int edit_apply(const sylva_world *w, const edit *e, sylva_world **out, char *err,
               size_t errlen) {
  /* edit a copy, so that a failure part way changes nothing */
  *out = NULL;
  uint8_t *img;
  size_t size;
  int rc = sylva_snapshot_save(w, &img, &size);
  if (rc) {
    snprintf(err, errlen, "%s", sylva_strerror(rc));
    return rc;
  }
  sylva_world *copy;
  rc = sylva_snapshot_load(img, size, &copy);
  free(img);
  if (rc) {
    snprintf(err, errlen, "%s", sylva_strerror(rc));
    return rc;
  }
  /* the copy grows on the threads of w, shared or its own (or on one if the system
   * gives no more: the same world) */
  if (sylva_world_shared_threads(w))
    sylva_world_share_threads(copy, sylva_world_shared_threads(w));
  else if (sylva_world_threads(w) > 1)
    sylva_world_set_threads(copy, sylva_world_threads(w));
  for (int i = 0; i < e->removal_count; i++) {
    int id = sylva_world_find_obstacle(copy, e->removals[i]);
    if (id < 0 || (rc = sylva_world_remove_obstacle(copy, id)) != 0) {
      snprintf(err, errlen, "/remove_obstacles/%d: no obstacle \"%s\"", i, e->removals[i]);
      sylva_world_destroy(copy);
      return SYLVA_EINVAL;
    }
  }
  for (int i = 0; i < e->obstacle_count; i++) {
    const edit_obstacle *o = &e->obstacles[i];
    sylva_obstacle_def def = {o->id, {o->min[0], o->min[1], o->min[2]},
                              {o->max[0], o->max[1], o->max[2]}, o->kind,
                              {(const double(*)[2])o->points, o->point_count, o->ring_sizes, o->ring_count}};
    rc = sylva_world_add_obstacle(copy, &def);
    if (rc < 0) {
      snprintf(err, errlen, "/add_obstacles/%d/id: %s", i,
               rc == SYLVA_EINVAL ? "an obstacle with this id exists" : sylva_strerror(rc));
      sylva_world_destroy(copy);
      return rc == SYLVA_ENOMEM ? rc : SYLVA_EINVAL;
    }
  }
  for (int i = 0; i < e->plant_count; i++) {
    const edit_plant *p = &e->plants[i];
    int species = species_by_label(copy, p->species);
    if (species < 0) {
      snprintf(err, errlen, "/add_plants/%d/species: the run has no species \"%s\"", i,
               p->species);
      sylva_world_destroy(copy);
      return SYLVA_EINVAL;
    }
    if (p->age > 0 && !sylva_world_species(copy, species)->years) {
      snprintf(err, errlen, "/add_plants/%d/age: species \"%s\" has no time scale (years)", i,
               p->species);
      sylva_world_destroy(copy);
      return SYLVA_EINVAL;
    }
    sylva_plant_def def = {.species = species, .label = p->id, .roots = (const double(*)[3])p->roots,
                           .root_count = p->root_count, .age = p->age};
    int bad = -1;
    rc = sylva_world_add_plant(copy, &def, &bad);
    if (rc < 0) {
      if (bad >= 0)
        snprintf(err, errlen, "/add_plants/%d/roots/%d: %s", i, bad, sylva_strerror(rc));
      else
        snprintf(err, errlen, "/add_plants/%d/id: %s", i,
                 rc == SYLVA_EINVAL ? "a plant with this id exists" : sylva_strerror(rc));
      sylva_world_destroy(copy);
      return rc == SYLVA_ENOMEM ? rc : SYLVA_EINVAL;
    }
  }
  if (e->prune.set) {
    double mn[3], mx[3];
    memcpy(mn, e->prune.min, sizeof mn);
    memcpy(mx, e->prune.max, sizeof mx);
    if (e->prune.zone) {
      sylva_obstacle_def z;
      if (sylva_world_obstacle(copy, sylva_world_find_obstacle(copy, e->prune.zone), &z) != 0 ||
          z.kind != SYLVA_OBSTACLE_ZONE) {
        snprintf(err, errlen, "/prune/zone: no zone \"%s\"", e->prune.zone);
        sylva_world_destroy(copy);
        return SYLVA_EINVAL;
      }
      memcpy(mn, z.min, sizeof mn);
      memcpy(mx, z.max, sizeof mx);
    }
    int64_t n = sylva_world_prune(copy, mn, mx, NULL, NULL);
    if (n < 0) {
      snprintf(err, errlen, "/prune: %s", sylva_strerror((int)n));
      sylva_world_destroy(copy);
      return n == SYLVA_ENOMEM ? SYLVA_ENOMEM : SYLVA_EINVAL;
    }
  }
  *out = copy;
  return SYLVA_OK;
}
