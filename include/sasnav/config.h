/* sasnav -- scenario configuration files (YAML through libfyaml).
 * A config file starts from a preset (key `preset`, default paper-trajectory)
 * and overrides any field; comments are allowed. Keys are documented in
 * docs/config.md and the examples/ folder.
 *
 * Threads: no state in sasnav (one libfyaml document per call, no OpenMP):
 * distinct calls on distinct files may run concurrently. */
#ifndef SASNAV_CONFIG_H
#define SASNAV_CONFIG_H

#include "sasnav/sim.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Reads `path` and applies it on top of *sc (which the caller fills with a
 * preset first; if the file names a preset, that preset replaces *sc before
 * the overrides). Unknown keys, non-numeric or non-finite values, and values
 * failing sasnav_scenario_check give SASNAV_ERR_CONFIG with the key named. */
int sasnav_config_load(const char *path, sasnav_scenario *sc);

/* Writes the scenario as a YAML config (all keys), for reference. */
int sasnav_config_write(const char *path, const sasnav_scenario *sc);

#ifdef __cplusplus
}
#endif
#endif
