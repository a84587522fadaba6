/* sylva: the species library, species in years calibrated to the USDA Urban Tree
 * Database (McPherson, van Doorn and Peper 2016, https://doi.org/10.2737/RDS-2016-0005)
 * by scripts/species-library. Its file, data/species/library.json, is built into
 * the binary, and so is the foliage of its species, data/species/foliage.csv. A
 * library species is a preset: "preset": "utdb:NoEast:PLAC". */
#ifndef SYLVA_LIBRARY_H
#define SYLVA_LIBRARY_H

#include <stddef.h>

#include "sylva/params.h"

/** Prefix of every library name. */
#define SYLVA_LIBRARY_PREFIX "utdb:"

/** The library's JSON text (`sylva.species-library/1`), NUL-terminated; *len (if
 *  given) receives its length. */
const char *sylva_library_text(size_t *len);

/** The foliage table (data/species/foliage.csv: `code,kind,leaf_size,leaf_density,
 *  leaf_colour,source`, one row per species code), NUL-terminated; *len (if given)
 *  receives its length. */
const char *sylva_library_foliage_text(size_t *len);

/** The carbon table (data/species/carbon.csv: `code,wood_density,biomass_form,
 *  biomass_a,biomass_b,biomass_c,biomass_p,biomass_q,biomass_factor,dbh_min,dbh_max,
 *  equation_species,source`, one row per UTDB species code), NUL-terminated; *len (if
 *  given) receives its length. */
const char *sylva_library_carbon_text(size_t *len);
/** The stand table built in (data/species/stand.csv: how each library species' plants
 *  differ and die, docs/model.md "Stands"), its length in *len. */
const char *sylva_library_stand_text(size_t *len);

/** The species named `name` ("utdb:REGION:CODE"), with the leaf_size, leaf_density
 *  and leaf_colour of its code's row of the foliage table and the wood density and
 *  biomass allometry of its row of the carbon table: 0 and *out,
 *  SYLVA_ENOTFOUND, SYLVA_EINVAL (a value out of its range), or SYLVA_ENOMEM. */
int sylva_library_find(const char *name, sylva_species_def *out);

/** The library's names, ", "-separated, into buf (truncated to size). */
void sylva_library_names(char *buf, size_t size);

#endif
