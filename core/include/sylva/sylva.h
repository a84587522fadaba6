/* sylva: the whole public API of libsylva-core. */
#ifndef SYLVA_SYLVA_H
#define SYLVA_SYLVA_H
#include "equations.h"
#include "params.h"
#include "species_fields.h"
#include "snapshot.h"
#include "status.h"
#include "world.h"
#endif
