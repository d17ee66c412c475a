/* fuzz_checkpoint: the input bytes are a checkpoint file (checkpoint.h),
 * opened as `sasnav navigate`'s pair-record log (header, version, job,
 * checksummed records; a torn tail is cut). Contract: a documented code;
 * on error nothing is returned; an accepted log returns no more records
 * than the file can hold and takes one more append. */
#include "fuzz_common.h"
#include "sasnav/checkpoint.h"


int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fz_path("ckpt.bin");
    fz_write(path, data, size);
    static const int allowed[] = {SASNAV_ERR_FORMAT, SASNAV_ERR_IO, SASNAV_ERR_NOMEM, 0};
    sasnav_checkpoint *ck = NULL;
    sasnav_pair_record *rec = NULL;
    int n = -1;
    int rc = sasnav_checkpoint_open(path, "sasnav navigate", &ck, &rec, &n);
    fz_check_rc("sasnav_checkpoint_open", rc, allowed);
    if (rc == SASNAV_OK) {
        if (!ck || n < 0 || (size_t)n * sizeof(sasnav_pair_record) > size || (n > 0) != (rec != NULL)) abort();
        sasnav_pair_record r;
        memset(&r, 0, sizeof r);
        if (sasnav_checkpoint_append(ck, &r) != SASNAV_OK) abort();
        if (sasnav_checkpoint_count(ck) != n + 1) abort();
        sasnav_checkpoint_close(ck, 0);
    } else if (ck || rec || n != 0) {
        abort();
    }
    free(rec);
    return 0;
}
