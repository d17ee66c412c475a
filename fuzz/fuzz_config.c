/* fuzz_config: sasnav_config_load on the input as a YAML scenario file,
 * starting from the "point" preset. Contract: SASNAV_OK with a scenario
 * that passes sasnav_scenario_check, or SASNAV_ERR_CONFIG / IO / NOMEM with
 * a message. An accepted scenario must also survive a round trip:
 * sasnav_config_write, then sasnav_config_load of what was written. */
#include "fuzz_common.h"
#include "sasnav/config.h"
#include "sasnav/sim.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *p = fz_path("config.yaml");
    char path[256], back[256];
    snprintf(path, sizeof path, "%s", p);
    snprintf(back, sizeof back, "%s", fz_path("written.yaml"));
    fz_write(path, data, size);
    sasnav_scenario sc;
    if (sasnav_scenario_preset("point", &sc)) abort();
    int rc = sasnav_config_load(path, &sc);
    static const int allowed[] = {SASNAV_ERR_CONFIG, SASNAV_ERR_IO, SASNAV_ERR_NOMEM, 0};
    fz_check_rc("sasnav_config_load", rc, allowed);
    if (rc == SASNAV_OK) {
        if (sasnav_scenario_check(&sc)) {
            fprintf(stderr, "config accepted but the scenario is invalid: %s\n", sasnav_last_error());
            abort();
        }
        rc = sasnav_config_write(back, &sc);
        if (rc) {
            fprintf(stderr, "config accepted but not writable: %s\n", sasnav_last_error());
            abort();
        }
        sasnav_scenario again;
        if (sasnav_scenario_preset("point", &again)) abort();
        rc = sasnav_config_load(back, &again);
        if (rc) {
            fprintf(stderr, "written config does not load back: %s\n", sasnav_last_error());
            abort();
        }
    }
    return 0;
}
