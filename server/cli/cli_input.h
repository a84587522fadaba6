/* sylva server: the scenario files the commands read, with their errors printed
 * ("sylva: PATH: message") and turned into exit statuses (options.h). */
#ifndef SYLVA_SERVER_CLI_INPUT_H
#define SYLVA_SERVER_CLI_INPUT_H

#include "sylva/scenario.h"
#include "sylva/world.h"

/** Reads and parses a scenario file (flags: SYLVA_SCENARIO_*). */
int cli_input_scenario(const char *path, unsigned flags, sylva_scenario **out);

/** Builds the world of the scenario read from path. */
int cli_input_world(const char *path, const sylva_scenario *s, sylva_world **out);

#endif
