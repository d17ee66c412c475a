/* 64-bit FNV-1a hash (Fowler, Noll, Vo): content keys of ping pairs
 * (navigate.c) and the checksums of checkpoint records (io/checkpoint.c).
 * Not cryptographic: it tells accidental differences apart (another run,
 * a torn or corrupted record), not crafted ones. Private to the library. */
#ifndef SASNAV_HASH_H
#define SASNAV_HASH_H

#include "sasnav/geometry.h"

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#define SASNAV_HASH_INIT UINT64_C(14695981039346656037)

static inline uint64_t sasnav_hash_bytes(uint64_t h, const void *data, size_t n)
{
    const unsigned char *b = data;
    for (size_t i = 0; i < n; i++) {
        h ^= b[i];
        h *= UINT64_C(1099511628211);
    }
    return h;
}

/* The same mixing over 8-byte words (then the tail bytewise): for bulk
 * data such as ping samples, 8 times fewer steps. Not the same value as
 * sasnav_hash_bytes of the same bytes. */
static inline uint64_t sasnav_hash_words(uint64_t h, const void *data, size_t n)
{
    const unsigned char *b = data;
    size_t k = n / 8;
    for (size_t i = 0; i < k; i++) {
        uint64_t w;
        memcpy(&w, b + 8 * i, 8);
        h ^= w;
        h *= UINT64_C(1099511628211);
        h ^= h >> 29;
    }
    return sasnav_hash_bytes(h, b + 8 * k, n - 8 * k);
}

static inline uint64_t sasnav_hash_double(uint64_t h, double v)
{
    if (v == 0) v = 0; /* -0 and +0 alike */
    return sasnav_hash_bytes(h, &v, sizeof v);
}

static inline uint64_t sasnav_hash_doubles(uint64_t h, const double *v, int n)
{
    for (int j = 0; j < n; j++) h = sasnav_hash_double(h, v[j]);
    return h;
}

/* Ping poses, field by field (tx x, y, theta, then array x, y, theta). */
static inline uint64_t sasnav_hash_ping_poses(uint64_t h, const sasnav_ping_pose *p, int n)
{
    for (int i = 0; i < n; i++) {
        const double v[6] = {p[i].tx.x, p[i].tx.y, p[i].tx.theta, p[i].array.x, p[i].array.y, p[i].array.theta};
        h = sasnav_hash_doubles(h, v, 6);
    }
    return h;
}

#endif
