/* The pairs of a navigation, packed while it runs (internal to the
 * library; src/trajectory/navigate.c).
 *
 * A sasnav_navigate_pair is 1.6 kB, most of it the two results' candidate
 * slots (8 each) and the first result, which equals the final one for
 * nearly every pair. Packed, a pair keeps only its used candidates and the
 * first result as a difference from the final one: about 0.5 kB for a
 * DPCA pair (no candidates), 0.8-1 kB for a subspace one. A 20,000-ping
 * survey then holds ~10 MB of pairs instead of 32 MB (docs/survey.md). */
#ifndef SASNAV_PAIR_STORE_H
#define SASNAV_PAIR_STORE_H

#include "sasnav/navigate.h"

#include <stddef.h>

typedef struct pair_block pair_block;

typedef struct {
    int n;                /* pairs */
    unsigned char **blob; /* n packed pairs (NULL: not yet stored), each
                             after its capacity (a uint32_t) */
    pair_block *blocks;   /* where the blobs live: large blocks filled in
                             turn (no per-pair malloc, no fragmentation
                             across the threads' malloc arenas) */
} pair_store;

/* Allocates n empty slots. Returns SASNAV_OK or SASNAV_ERR_NOMEM. */
int pair_store_init(pair_store *s, int n);

/* Packs *np into slot j (replacing what was there). Different slots may be
 * written by different threads at once. Returns SASNAV_OK or
 * SASNAV_ERR_NOMEM (the slot keeps its old content). */
int pair_store_put(pair_store *s, int j, const sasnav_navigate_pair *np);

/* Unpacks slot j into *np: the same values as were put (unused candidate
 * slots zero). An empty slot gives a zeroed pair. */
void pair_store_get(const pair_store *s, int j, sasnav_navigate_pair *np);

void pair_store_free(pair_store *s);

#endif
