#include "edit.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sylva/snapshot.h"
#include "sylva/status.h"

static int species_by_label(const sylva_world *w, const char *label) {
  for (int i = 0; i < sylva_world_species_count(w); i++)
    if (strcmp(sylva_world_species_label(w, i), label) == 0) return i;
  return -1;
}

int edit_apply(const sylva_world *w, const sylva_msg *m, sylva_world **out, char *err,
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
  for (int i = 0; i < m->remove_obstacle_count; i++) {
    int id = sylva_world_find_obstacle(copy, m->remove_obstacles[i]);
    if (id < 0 || (rc = sylva_world_remove_obstacle(copy, id)) != 0) {
      snprintf(err, errlen, "/remove_obstacles/%d: no obstacle \"%s\"", i, m->remove_obstacles[i]);
      sylva_world_destroy(copy);
      return SYLVA_EINVAL;
    }
  }
  for (int i = 0; i < m->add_obstacle_count; i++) {
    const sylva_scenario_obstacle *o = &m->add_obstacles[i];
    sylva_obstacle_def def = {o->id, {o->min[0], o->min[1], o->min[2]},
                              {o->max[0], o->max[1], o->max[2]}};
    rc = sylva_world_add_obstacle(copy, &def);
    if (rc < 0) {
      snprintf(err, errlen, "/add_obstacles/%d/id: %s", i,
               rc == SYLVA_EINVAL ? "an obstacle with this id exists" : sylva_strerror(rc));
      sylva_world_destroy(copy);
      return rc == SYLVA_ENOMEM ? rc : SYLVA_EINVAL;
    }
  }
  for (int i = 0; i < m->add_plant_count; i++) {
    const sylva_scenario_plant *p = &m->add_plants[i];
    int species = species_by_label(copy, m->add_plant_species[i]);
    if (species < 0) {
      snprintf(err, errlen, "/add_plants/%d/species: the run has no species \"%s\"", i,
               m->add_plant_species[i]);
      sylva_world_destroy(copy);
      return SYLVA_EINVAL;
    }
    sylva_plant_def def = {species, p->id, (const double(*)[3])p->roots, p->root_count};
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
  *out = copy;
  return SYLVA_OK;
}

int edit_replay(sylva_world **w, const char *json, char *err, size_t errlen) {
  sylva_msg m;
  int rc = sylva_msg_parse(json, strlen(json), &m, err, errlen);
  if (rc == SYLVA_OK) {
    sylva_world *edited = NULL;
    rc = m.type == SYLVA_MSG_EDIT ? edit_apply(*w, &m, &edited, err, errlen) : SYLVA_EINVAL;
    if (m.type != SYLVA_MSG_EDIT) snprintf(err, errlen, "logged command is not an edit");
    if (rc == SYLVA_OK) {
      sylva_world_destroy(*w);
      *w = edited;
    }
  }
  sylva_msg_free(&m);
  return rc;
}
