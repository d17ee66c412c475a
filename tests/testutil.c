#include "testutil.h"

#include "sasnav/error.h"

#include <stdlib.h>
#include <string.h>

int test_failures = 0;
int test_checks = 0;

int test_summary(const char *name)
{
    printf("%s: %d checks, %d failures\n", name, test_checks, test_failures);
    if (test_checks == 0) {
        printf("%s: no checks ran\n", name);
        return 1;
    }
    return test_failures ? 1 : 0;
}

const char *test_tmpdir(void)
{
    static char dir[256];
    if (!dir[0]) {
        const char *base = getenv("TMPDIR");
        snprintf(dir, sizeof dir, "%s/sasnav-test-XXXXXX", base ? base : "/tmp");
        if (!mkdtemp(dir)) {
            perror("mkdtemp");
            exit(2);
        }
    }
    return dir;
}

sasnav_run *test_tank_run(const sasnav_tank_params *p)
{
    char dir[1024];
    snprintf(dir, sizeof dir, "%s/rec", test_tmpdir());
    CHECK_OK(sasnav_tank_write_dir(p, dir));
    sasnav_tank_read_opts ro;
    sasnav_tank_default_read_opts(&ro);
    sasnav_run *run = NULL;
    CHECK_OK(sasnav_tank_read_dir(dir, &ro, &run));
    return run;
}
