/* The library's version (version.h). */
#include "sasnav/version.h"

const char *sasnav_version(void) { return SASNAV_VERSION_STRING; }

int sasnav_version_number(void) { return SASNAV_VERSION_NUMBER; }
