/* Packed pairs of a navigation (pair_store.h).
 *
 * Layout of a packed pair: the pair without its two results; the final
 * result without its unused candidate slots; one byte telling how the first
 * result is kept (FIRST_SAME: equal to the final one; FIRST_DISPLACEMENT:
 * equal but for the displacement, which the smoother rewrites in the final
 * one, followed by that pose; FIRST_FULL: packed like the final one). The
 * segments are taken with offsetof, so the layout follows the structs'
 * definitions without listing their fields. */
#include "trajectory/pair_store.h"

#include "sasnav/error.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

enum { FIRST_SAME = 1, FIRST_DISPLACEMENT = 2, FIRST_FULL = 3 };

#define RES_CAND offsetof(sasnav_pair_result, candidates)
#define RES_TAIL (offsetof(sasnav_pair_result, candidates) + sizeof(((sasnav_pair_result *)0)->candidates))
#define PAIR_RES offsetof(sasnav_navigate_pair, result)
#define PAIR_FIRST offsetof(sasnav_navigate_pair, first_result)

static int n_cand(const sasnav_pair_result *r)
{
    int n = r->n_candidates;
    return n < 0 ? 0 : n > SASNAV_PAIR_MAX_CANDIDATES ? SASNAV_PAIR_MAX_CANDIDATES : n;
}

static size_t result_size(const sasnav_pair_result *r)
{
    return RES_CAND + (size_t)n_cand(r) * sizeof r->candidates[0] + (sizeof *r - RES_TAIL);
}

static unsigned char *put_bytes(unsigned char *d, const void *src, size_t off, size_t len)
{
    memcpy(d, (const unsigned char *)src + off, len);
    return d + len;
}

static const unsigned char *get_bytes(const unsigned char *s, void *dst, size_t off, size_t len)
{
    memcpy((unsigned char *)dst + off, s, len);
    return s + len;
}

static unsigned char *put_result(unsigned char *d, const sasnav_pair_result *r)
{
    d = put_bytes(d, r, 0, RES_CAND);
    d = put_bytes(d, r, RES_CAND, (size_t)n_cand(r) * sizeof r->candidates[0]);
    return put_bytes(d, r, RES_TAIL, sizeof *r - RES_TAIL);
}

static const unsigned char *get_result(const unsigned char *s, sasnav_pair_result *r)
{
    memset(r, 0, sizeof *r);
    s = get_bytes(s, r, 0, RES_CAND);
    s = get_bytes(s, r, RES_CAND, (size_t)n_cand(r) * sizeof r->candidates[0]);
    return get_bytes(s, r, RES_TAIL, sizeof *r - RES_TAIL);
}

/* The layout relies on the order of the fields: result before first_result,
 * n_candidates before candidates. */
_Static_assert(offsetof(sasnav_navigate_pair, result) < offsetof(sasnav_navigate_pair, first_result),
               "pair_store: result must precede first_result");
_Static_assert(offsetof(sasnav_pair_result, n_candidates) < offsetof(sasnav_pair_result, candidates),
               "pair_store: n_candidates must precede candidates");

/* The three segments of a pair around its two results. */
static const size_t seg_off[3] = {0, PAIR_RES + sizeof(sasnav_pair_result),
                                  PAIR_FIRST + sizeof(sasnav_pair_result)};
static const size_t seg_len[3] = {PAIR_RES, PAIR_FIRST - (PAIR_RES + sizeof(sasnav_pair_result)),
                                  sizeof(sasnav_navigate_pair) - (PAIR_FIRST + sizeof(sasnav_pair_result))};

/* How the first result differs from the final one. Compared as packed
 * bytes, padding included: results equal but for their padding bytes are
 * stored in full (more space, the same values read back). */
static int first_kind(const sasnav_navigate_pair *np)
{
    sasnav_pair_result a;
    size_t na = result_size(&np->result), nb = result_size(&np->first_result);
    if (na != nb) return FIRST_FULL;
    unsigned char pa[sizeof(sasnav_pair_result)], pb[sizeof(sasnav_pair_result)];
    put_result(pa, &np->result);
    put_result(pb, &np->first_result);
    if (!memcmp(pa, pb, na)) return FIRST_SAME;
    get_result(pa, &a);
    a.displacement = np->first_result.displacement;
    put_result(pa, &a);
    return memcmp(pa, pb, na) ? FIRST_FULL : FIRST_DISPLACEMENT;
}

/* A block of blobs; `used` bytes of `size` handed out. */
struct pair_block {
    pair_block *next;
    size_t size, used;
    _Alignas(8) unsigned char data[];
};

enum { BLOCK_BYTES = 1 << 20 };

int pair_store_init(pair_store *s, int n)
{
    s->n = n;
    s->blocks = NULL;
    s->blob = calloc((size_t)(n > 0 ? n : 1), sizeof *s->blob);
    return s->blob ? SASNAV_OK : sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for the pairs");
}

/* `size` bytes from the current block, or a new one (NULL: out of memory).
 * Serialised: the pairs of a navigation are put by several threads. */
static unsigned char *block_alloc(pair_store *s, size_t size)
{
    unsigned char *p = NULL;
    size = (size + 7) & ~(size_t)7;
#pragma omp critical(sasnav_pair_store)
    {
        pair_block *b = s->blocks;
        if (!b || b->size - b->used < size) {
            size_t bytes = size > BLOCK_BYTES ? size : BLOCK_BYTES;
            pair_block *nb = malloc(sizeof *nb + bytes);
            if (nb) {
                nb->next = b;
                nb->size = bytes;
                nb->used = 0;
                s->blocks = b = nb;
            } else {
                b = NULL;
            }
        }
        if (b) {
            p = b->data + b->used;
            b->used += size;
        }
    }
    return p;
}

int pair_store_put(pair_store *s, int j, const sasnav_navigate_pair *np)
{
    int kind = first_kind(np);
    size_t size = seg_len[0] + seg_len[1] + seg_len[2] + result_size(&np->result) + 1;
    if (kind == FIRST_DISPLACEMENT) size += sizeof(sasnav_pose);
    if (kind == FIRST_FULL) size += result_size(&np->first_result);
    /* In place when it fits; a new blob has room for the first result's
     * displacement, which the smoother nearly always adds. The space of a
     * blob that grows beyond its capacity is not reused (a pair estimated
     * again: rare, except with opts.speed_lags = 2, whose second pass
     * re-estimates every ok pair). */
    unsigned char *b = s->blob[j];
    uint32_t cap = 0;
    if (b) memcpy(&cap, b - sizeof cap, sizeof cap);
    if (!b || cap < size) {
        size_t want = size + (kind == FIRST_SAME ? sizeof(sasnav_pose) : 0);
        unsigned char *nb = block_alloc(s, sizeof cap + want);
        if (!nb) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for the pairs");
        cap = (uint32_t)want;
        memcpy(nb, &cap, sizeof cap);
        b = nb + sizeof cap;
    }
    unsigned char *d = b;
    for (int k = 0; k < 3; k++) d = put_bytes(d, np, seg_off[k], seg_len[k]);
    d = put_result(d, &np->result);
    *d++ = (unsigned char)kind;
    if (kind == FIRST_DISPLACEMENT) d = put_bytes(d, &np->first_result.displacement, 0, sizeof(sasnav_pose));
    if (kind == FIRST_FULL) d = put_result(d, &np->first_result);
    s->blob[j] = b;
    return SASNAV_OK;
}

void pair_store_get(const pair_store *s, int j, sasnav_navigate_pair *np)
{
    memset(np, 0, sizeof *np);
    const unsigned char *p = s->blob[j];
    if (!p) return;
    for (int k = 0; k < 3; k++) p = get_bytes(p, np, seg_off[k], seg_len[k]);
    p = get_result(p, &np->result);
    int kind = *p++;
    if (kind == FIRST_FULL) {
        get_result(p, &np->first_result);
        return;
    }
    np->first_result = np->result;
    if (kind == FIRST_DISPLACEMENT) get_bytes(p, &np->first_result.displacement, 0, sizeof(sasnav_pose));
}

void pair_store_free(pair_store *s)
{
    if (!s) return;
    while (s->blocks) {
        pair_block *b = s->blocks;
        s->blocks = b->next;
        free(b);
    }
    free(s->blob);
    s->blob = NULL;
    s->n = 0;
}
