/* sylva gis: a tree inventory's species names matched to the species library
 * (sylva/library.h: species in years calibrated to the Urban Tree Database), and a
 * tree's age from its DBH by the database's dbh -> age equation (server/species/
 * utdb.h). docs/cli.md, "site", states the rules; they are:
 *
 * Names are compared after normalising: surrounding spaces trimmed, runs of spaces
 * made one, ASCII letters lower-cased, the multiplication sign made " x " and
 * curly quotes straight. A name matches, in this order:
 *   1. the species map's entry for it (map.csv: name -> library name or code);
 *   2. a species of the region by its code, scientific or common name, or any
 *      library species by its full name ("utdb:NoEast:PLAC");
 *   3. a cultivar, variety, subspecies or form of a species of the region: a
 *      scientific name cut after its first two words ("Genus species"), or three
 *      for a hybrid ("Genus x species"), when the next word starts with a quote or
 *      is var., ssp., subsp., f. or cv. (with or without the dot), then matched
 *      as in 2 by scientific name;
 *   4. the same species with or without the hybrid's x ("Platanus acerifolia"
 *      matches "Platanus x acerifolia");
 *   5. a genus alone ("Malus", "Malus sp.", "Malus spp.", "Malus 'Prairifire'")
 *      the region's species named "Genus spp." or "Genus sp.".
 * Nothing else matches: misspelt names are left to the species map. */
#ifndef SYLVA_GIS_SPECIES_MATCH_H
#define SYLVA_GIS_SPECIES_MATCH_H

#include <stdbool.h>
#include <stddef.h>

#include "utdb.h"

/** Longest normalised name kept, bytes with the NUL. */
#define SPECIES_NAME_MAX 160

/** One species of the library. */
typedef struct species_entry {
  char name[64];                     /**< "utdb:NoEast:PLAC" */
  char region[16];                   /**< "NoEast" */
  char code[16];                     /**< "PLAC" */
  char scientific[SPECIES_NAME_MAX]; /**< normalised */
  char common[SPECIES_NAME_MAX];     /**< normalised */
  int age_min, age_max;              /**< the library's "ages" */
  double rho;                        /**< its internode length, m */
  const sylva_utdb_species *utdb;    /**< its Urban Tree Database equations */
} species_entry;

/** The library, and the map's entries. */
typedef struct species_library {
  species_entry *species;
  int count;
  sylva_utdb *utdb;
  struct species_map_entry {
    char name[SPECIES_NAME_MAX]; /**< normalised inventory name */
    int species;                 /**< index into species */
  } * map;
  int map_count;
} species_library;

/** Reads the built-in library and the Urban Tree Database: SERVER_OK, SERVER_EFAIL
 *  (a built-in table that does not read, with err), SERVER_ENOMEM. */
int species_library_load(species_library *lib, char *err, size_t errlen);

/** Frees the library; the struct is zeroed. */
void species_library_free(species_library *lib);

/** Normalises a name (above) into out (size at least SPECIES_NAME_MAX). */
void species_normalise(const char *name, char *out, size_t size);

/** Whether the library holds a species of the region. */
bool species_region_has(const species_library *lib, const char *region);

/** The library species `target` names, by step 2 of the rules for the region:
 *  its index, or -1. */
int species_find(const species_library *lib, const char *region, const char *target);

/** Adds a map entry from an inventory name to the species at index `species`:
 *  SERVER_OK or SERVER_ENOMEM. A name given twice keeps its first entry (0). */
int species_map_add(species_library *lib, const char *name, int species);

/** The species an inventory name matches in the region (the rules above): its
 *  index, or -1. */
int species_match(const species_library *lib, const char *region, const char *name);

/** A tree's age from its DBH in cm: the species' dbh -> age equation, the DBH held
 *  to the equation's range and the age to the largest it reaches up to that DBH
 *  (sylva_utdb_eval_clamped), rounded to the nearest year (halves away from zero),
 *  then held to the library's ages [age_min, age_max] and to 0..500. */
int species_age(const species_entry *s, double dbh_cm);

/** The species' height at an age by the Urban Tree Database's chained, clamped
 *  equations, m (NAN without them). */
double species_height(const species_entry *s, int age);

#endif
