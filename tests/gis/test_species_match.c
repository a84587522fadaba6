/* The gis suite, species matching (server/gis/species_match.h): an inventory's names
 * to the library's species by the rules of docs/cli.md, "site" (normalising,
 * codes, scientific and common names, cultivars, varieties, hybrids with and
 * without their x, a genus alone, the map first), and ages held to the library's
 * range; the regions of places by their reference cities (region.h). */
#include <string.h>

#include "../check.h"
#include "frame.h"
#include "layer.h"
#include "region.h"
#include "species_match.h"

static species_library lib;

/* The library name an inventory name matches in NoEast, or "" for none. */
static const char *match(const char *name) {
  int i = species_match(&lib, "NoEast", name);
  return i < 0 ? "" : lib.species[i].name;
}

#define CHECK_MATCH(name, want)                                                  \
  do {                                                                           \
    const char *got_ = match(name);                                              \
    if (strcmp(got_, want) == 0) check_passed++;                                 \
    else {                                                                       \
      check_failed++;                                                            \
      fprintf(stderr, "%s:%d: '%s' matched '%s', not '%s'\n", __FILE__, __LINE__, \
              name, got_, want);                                                 \
    }                                                                            \
  } while (0)

static void test_normalise(void) {
  char n[SPECIES_NAME_MAX];
  species_normalise("  Platanus \xc3\x97" "acerifolia\t 'Bloodgood' ", n, sizeof n);
  CHECK(strcmp(n, "platanus x acerifolia 'bloodgood'") == 0);
  species_normalise("Acer  platanoides \xe2\x80\x98" "Crimson King\xe2\x80\x99", n, sizeof n);
  CHECK(strcmp(n, "acer platanoides 'crimson king'") == 0);
  species_normalise("   ", n, sizeof n);
  CHECK(n[0] == '\0');
}

static void test_names(void) {
  CHECK_MATCH("PLAC", "utdb:NoEast:PLAC");
  CHECK_MATCH("plac", "utdb:NoEast:PLAC");
  CHECK_MATCH("Platanus x acerifolia", "utdb:NoEast:PLAC");
  CHECK_MATCH("PLATANUS  X ACERIFOLIA", "utdb:NoEast:PLAC");
  CHECK_MATCH("Platanus \xc3\x97 acerifolia", "utdb:NoEast:PLAC");
  CHECK_MATCH("Platanus acerifolia", "utdb:NoEast:PLAC");
  CHECK_MATCH("Platanus x acerifolia 'Bloodgood'", "utdb:NoEast:PLAC");
  CHECK_MATCH("London planetree", "utdb:NoEast:PLAC");
  CHECK_MATCH("utdb:NoEast:TICO", "utdb:NoEast:TICO");
  CHECK_MATCH("utdb:InlVal:MAGR", "utdb:InlVal:MAGR"); /* a full name, any region */
  CHECK_MATCH("Gleditsia triacanthos var. inermis", "utdb:NoEast:GLTR");
  CHECK_MATCH("Gleditsia triacanthos f. inermis", "utdb:NoEast:GLTR");
  CHECK_MATCH("Acer platanoides 'Crimson King'", "utdb:NoEast:ACPL");
  CHECK_MATCH("Acer platanoides cv. Schwedleri", "utdb:NoEast:ACPL");
  CHECK_MATCH("Acer rubrum ssp. drummondii", "utdb:NoEast:ACRU");
  CHECK_MATCH("Malus", "utdb:NoEast:MA2");
  CHECK_MATCH("Malus spp.", "utdb:NoEast:MA2");
  CHECK_MATCH("Malus sp.", "utdb:NoEast:MA2");
  CHECK_MATCH("Malus 'Prairifire'", "utdb:NoEast:MA2");
  /* not matched: other regions' species, misspellings, a genus of several, words
   * after a species that are no rank */
  CHECK_MATCH("Magnolia grandiflora", "");
  CHECK_MATCH("Zelkova serata", "");
  CHECK_MATCH("Acer", "");
  CHECK_MATCH("Acer platanoides Crimson King", "");
  CHECK_MATCH("", "");
  CHECK_INT(species_match(&lib, "InlVal", "Magnolia grandiflora") >= 0, 1);
  CHECK_INT(species_match(&lib, "InlVal", "Fraxinus velutina 'Modesto'") >= 0, 1);
  CHECK(species_region_has(&lib, "NoEast") && !species_region_has(&lib, "Tropic"));
}

static void test_map(void) {
  int zese = species_find(&lib, "NoEast", "ZESE");
  CHECK(zese >= 0);
  CHECK_INT(species_find(&lib, "NoEast", "Quercus palustris"), species_match(&lib, "NoEast", "QUPA"));
  CHECK_INT(species_find(&lib, "NoEast", "Zelkova serata"), -1);
  CHECK_INT(species_map_add(&lib, "zelkova  SERATA", zese), 0);
  CHECK_MATCH("Zelkova serata", "utdb:NoEast:ZESE");
  /* the map wins over a name that matches by itself */
  CHECK_INT(species_map_add(&lib, "Tilia cordata", species_find(&lib, "NoEast", "TITO")), 0);
  CHECK_MATCH("Tilia cordata", "utdb:NoEast:TITO");
}

static void test_ages(void) {
  const species_entry *plac = &lib.species[species_find(&lib, "NoEast", "PLAC")];
  CHECK_INT(plac->age_min, 0);
  CHECK_INT(plac->age_max, 92);
  /* PLAC's dbh -> age: cub 0.58171 + 0.30204 d + 0.03224 d^2 - 0.00037 d^3 over
   * d in [2.4, 61.76] */
  double d = 30.5, a = 0.58171 + 0.30204 * d + 0.03224 * d * d - 0.00037 * d * d * d;
  CHECK_INT(species_age(plac, d), (int)floor(a + 0.5));
  CHECK_INT(species_age(plac, 1.0), species_age(plac, 2.4)); /* below the range */
  CHECK(species_age(plac, 300) <= 92);                        /* within the library's ages */
  CHECK(species_age(plac, 300) >= species_age(plac, 61.76));
  CHECK(species_height(plac, 20) > 5 && species_height(plac, 20) < 20);
}

static void test_regions(void) {
  gis_init();
  gis_region r[GIS_REGIONS];
  char err[256];
  CHECK_INT(gis_regions_load(r, err, sizeof err), 0);
  double km;
  const gis_region *near = gis_region_nearest(r, -73.98, 40.78, &km); /* Manhattan */
  CHECK(strcmp(near->code, "NoEast") == 0);
  CHECK(km > 5 && km < 20);
  near = gis_region_nearest(r, -121.0, 37.6, &km); /* Modesto */
  CHECK(strcmp(near->code, "InlVal") == 0);
  near = gis_region_nearest(r, 2.35, 48.85, &km); /* Paris: far from all */
  CHECK(km > 400);
  CHECK(gis_region_find(r, "CenFla") != NULL && gis_region_find(r, "Cen Fla") == NULL);
  /* Queens to Modesto along the geodesic, about 4,000 km */
  CHECK_NEAR(gis_geodesic_m(-73.7949, 40.7282, -120.9969, 37.6391) / 1000, 4000, 100);
}

int main(int argc, char **argv) {
  char err[256];
  if (species_library_load(&lib, err, sizeof err)) {
    fprintf(stderr, "the library: %s\n", err);
    return 1;
  }
  static const check_test tests[] = {CHECK_TEST(normalise), CHECK_TEST(names), CHECK_TEST(map),
                                     CHECK_TEST(ages), CHECK_TEST(regions)};
  CHECK_RUN(argc, argv, 1, tests);
  species_library_free(&lib);
  return check_summary("site-match");
}
