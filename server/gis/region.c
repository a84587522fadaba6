#include "region.h"

#include <stdbool.h>
#include <stdio.h>
#include <string.h>

#include "frame.h"
#include "layer.h"
#include "server_error.h"

extern const char sylva__reference_cities_csv[];
extern const size_t sylva__reference_cities_csv_len;

int gis_regions_load(gis_region *regions, char *err, size_t errlen) {
  gis_layer *l;
  int rc = gis_layer_open_text("reference_cities", sylva__reference_cities_csv,
                               sylva__reference_cities_csv_len, &l, err, errlen);
  if (rc) return rc == SERVER_ENOMEM ? rc : SERVER_EFAIL;
  int f[4];
  const char *names[4] = {"region", "city", "longitude", "latitude"};
  for (int i = 0; i < 4 && !rc; i++)
    if ((f[i] = gis_layer_field(l, names[i], err, errlen)) < 0) rc = SERVER_EFAIL;
  int n = 0;
  bool failed = false;
  while (!rc && gis_layer_next(l, &failed, err, errlen)) {
    gis_region *r = &regions[n];
    if (n == GIS_REGIONS || !gis_field_text(l, f[0], r->code, sizeof r->code) ||
        !gis_field_text(l, f[1], r->city, sizeof r->city) || gis_field_number(l, f[2], &r->lon) ||
        gis_field_number(l, f[3], &r->lat))
      rc = server_fail(err, errlen, SERVER_EFAIL, "reference_cities.csv: row %ld does not read",
                       gis_layer_row(l));
    n++;
  }
  if (!rc && (failed || n != GIS_REGIONS))
    rc = server_fail(err, errlen, SERVER_EFAIL, "reference_cities.csv: %d regions, not %d", n,
                     GIS_REGIONS);
  gis_layer_close(l);
  return rc;
}

const gis_region *gis_region_nearest(const gis_region *regions, double lon, double lat,
                                     double *km) {
  const gis_region *best = NULL;
  double best_m = 0;
  for (int i = 0; i < GIS_REGIONS; i++) {
    double m = gis_geodesic_m(lon, lat, regions[i].lon, regions[i].lat);
    if (!best || m < best_m) {
      best = &regions[i];
      best_m = m;
    }
  }
  *km = best_m / 1000.0;
  return best;
}

const gis_region *gis_region_find(const gis_region *regions, const char *code) {
  for (int i = 0; i < GIS_REGIONS; i++)
    if (strcmp(regions[i].code, code) == 0) return &regions[i];
  return NULL;
}
