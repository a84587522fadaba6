/* sylva: the whole public API of libsylva-core. */
#ifndef SYLVA_SYLVA_H
#define SYLVA_SYLVA_H
#include "alloc.h"
#include "equations.h"
#include "params.h"
#include "snapshot.h"
#include "species_fields.h"
#include "status.h"
#include "world.h"
#endif
