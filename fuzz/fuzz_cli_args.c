/* fuzz_cli_args: the command-line tool's number and grid parsers
 * (app/cli_util.c, compiled into this harness): the subcommands parse
 * their options with getopt_long and then run, so the parsers that see the
 * option values are fuzzed directly. The input is one option value (bytes
 * up to the first NUL). Properties: a parsed double is finite, an int lies
 * in [lo, hi], a parsed grid passes sasnav_grid_check. */
#include "fuzz_common.h"
#include "cli.h"

#include <math.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char *text = malloc(size + 1);
    if (!text) return 0;
    memcpy(text, data, size);
    text[size] = '\0';
    double d, v[8];
    if (cli_parse_double(text, &d) == 0 && !isfinite(d)) abort();
    long l;
    static const long ranges[][2] = {{0, 1}, {1, 64}, {-1000, 1000}, {1, 2147483647L}, {0, 9223372036854775807L}};
    for (size_t k = 0; k < sizeof ranges / sizeof ranges[0]; k++)
        if (cli_parse_int(text, ranges[k][0], ranges[k][1], &l) == 0 && (l < ranges[k][0] || l > ranges[k][1]))
            abort();
    for (int n = 1; n <= 8; n++)
        if (cli_parse_doubles(text, n, v) == 0)
            for (int k = 0; k < n; k++)
                if (!isfinite(v[k])) abort();
    sasnav_grid grid;
    if (cli_parse_grid(text, &grid) == 0 && sasnav_grid_check(&grid) != SASNAV_OK) abort();
    free(text);
    return 0;
}
