/* The packed pairs of a navigation (src/trajectory/pair_store.c): a pair
 * filled with pseudo-random bytes (every field, padding included) must come
 * back byte for byte, except the candidate slots beyond n_candidates, which
 * come back zero; for every way the first result can relate to the final
 * one (equal, equal but for the displacement, different), with 0..8
 * candidates and out-of-range counts; slots overwritten with larger and
 * smaller pairs; thousands of pairs put from several threads at once
 * (several blocks). And sasnav_navigation_pair's argument checks. */
#include "sasnav/error.h"
#include "testutil.h"
#include "trajectory/pair_store.h"

#include <stddef.h>
#include <stdint.h>
#include <string.h>

static uint64_t rng_state = 0x9e3779b97f4a7c15ull;

static uint8_t next_byte(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (uint8_t)(rng_state >> 24);
}

static void fill(void *p, size_t n)
{
    for (size_t i = 0; i < n; i++) ((uint8_t *)p)[i] = next_byte();
}

/* A random pair with n and m candidates in its final and first result;
 * kind 0: first = final, 1: first = final but for the displacement,
 * 2: first random. */
static void random_pair(sasnav_navigate_pair *np, int n, int m, int kind)
{
    fill(np, sizeof *np);
    np->result.n_candidates = n;
    if (kind == 0) np->first_result = np->result;
    if (kind == 1) {
        sasnav_pose d = np->first_result.displacement;
        np->first_result = np->result;
        np->first_result.displacement = d;
    }
    if (kind == 2) np->first_result.n_candidates = m;
}

static int used(int n) { return n < 0 ? 0 : n > SASNAV_PAIR_MAX_CANDIDATES ? SASNAV_PAIR_MAX_CANDIDATES : n; }

/* Whether result b is a round trip of a: the same bytes but the unused
 * candidate slots, which are zero. */
static int same_result(const sasnav_pair_result *a, const sasnav_pair_result *b)
{
    size_t c0 = offsetof(sasnav_pair_result, candidates), c1 = c0 + sizeof a->candidates;
    int n = used(a->n_candidates);
    if (memcmp(a, b, c0) || memcmp((const char *)a + c1, (const char *)b + c1, sizeof *a - c1)) return 0;
    if (memcmp(a->candidates, b->candidates, sizeof a->candidates[0] * (size_t)n)) return 0;
    static const sasnav_pair_candidate zero;
    for (int k = n; k < SASNAV_PAIR_MAX_CANDIDATES; k++)
        if (memcmp(&b->candidates[k], &zero, sizeof zero)) return 0;
    return 1;
}

static int same_pair(const sasnav_navigate_pair *a, const sasnav_navigate_pair *b)
{
    size_t r0 = offsetof(sasnav_navigate_pair, result), r1 = r0 + sizeof a->result;
    size_t f0 = offsetof(sasnav_navigate_pair, first_result), f1 = f0 + sizeof a->first_result;
    const char *x = (const char *)a, *y = (const char *)b;
    return !memcmp(x, y, r0) && !memcmp(x + r1, y + r1, f0 - r1) && !memcmp(x + f1, y + f1, sizeof *a - f1) &&
           same_result(&a->result, &b->result) && same_result(&a->first_result, &b->first_result);
}

static void test_round_trips(void)
{
    pair_store s;
    CHECK_OK(pair_store_init(&s, 3));
    sasnav_navigate_pair in, out;
    pair_store_get(&s, 1, &out); /* empty slot: zeroed */
    static const sasnav_navigate_pair zero;
    CHECK(!memcmp(&out, &zero, sizeof out), "an empty slot is not a zeroed pair");
    int counts[] = {0, 1, 3, 8, -2, 11};
    for (int kind = 0; kind < 3; kind++)
        for (int a = 0; a < 6; a++)
            for (int b = 0; b < 6; b++) {
                random_pair(&in, counts[a], counts[b], kind);
                int j = (a + b) % 3; /* slots reused: sizes grow and shrink */
                CHECK_OK(pair_store_put(&s, j, &in));
                pair_store_get(&s, j, &out);
                CHECK(same_pair(&in, &out), "kind %d, %d / %d candidates: not a round trip", kind, counts[a],
                      counts[b]);
            }
    pair_store_free(&s);
    pair_store_free(&s); /* freed twice: harmless */
}

/* 20,000 pairs (several 1 MB blocks) put from 2 threads, each slot twice
 * (the second time grown: a first result of its own). */
static void test_many_threads(void)
{
    enum { N = 20000 };
    pair_store s;
    CHECK_OK(pair_store_init(&s, N));
    int bad = 0;
    for (int pass = 0; pass < 2; pass++) {
#pragma omp parallel for num_threads(2) reduction(+ : bad)
        for (int j = 0; j < N; j++) {
            sasnav_navigate_pair np;
            memset(&np, 0, sizeof np);
            np.p = j;
            np.q = j + 1;
            np.result.n_candidates = j % 9;
            for (int k = 0; k < np.result.n_candidates; k++) np.result.candidates[k].eta = j + 0.5 * k;
            np.result.error.x = 1e-3 * j;
            np.first_result = np.result;
            if (pass == 1) {
                np.first_result.n_candidates = 8 - j % 9;
                np.first_result.error.x = -1e-3 * j;
            }
            bad += pair_store_put(&s, j, &np) != SASNAV_OK;
        }
    }
    CHECK(bad == 0, "%d puts failed", bad);
    int wrong = 0;
    for (int j = 0; j < N; j++) {
        sasnav_navigate_pair np;
        pair_store_get(&s, j, &np);
        int n = j % 9;
        wrong += np.p != j || np.q != j + 1 || np.result.n_candidates != n || np.result.error.x != 1e-3 * j ||
                 np.first_result.n_candidates != 8 - n || np.first_result.error.x != -1e-3 * j ||
                 (n > 0 && np.result.candidates[n - 1].eta != j + 0.5 * (n - 1));
    }
    CHECK(wrong == 0, "%d of %d pairs came back wrong", wrong, N);
    pair_store_free(&s);
}

static void test_accessor_errors(void)
{
    sasnav_navigation nav;
    memset(&nav, 0, sizeof nav);
    sasnav_navigate_pair np;
    CHECK(sasnav_navigation_pair(NULL, 0, &np) == SASNAV_ERR_ARG, "NULL navigation accepted");
    CHECK(sasnav_navigation_pair(&nav, 0, NULL) == SASNAV_ERR_ARG, "NULL pair accepted");
    CHECK(sasnav_navigation_pair(&nav, 0, &np) == SASNAV_ERR_ARG, "pair 0 of an empty navigation");
    nav.n_pairs = 2;
    CHECK(sasnav_navigation_pair(&nav, 1, &np) == SASNAV_ERR_ARG, "a navigation without pairs answered");
    sasnav_navigate_pair two[2];
    memset(two, 0, sizeof two);
    two[1].p = 7;
    nav.pairs = two;
    CHECK(sasnav_navigation_pair(&nav, 2, &np) == SASNAV_ERR_ARG, "pair 2 of 2 accepted");
    CHECK(sasnav_navigation_pair(&nav, -1, &np) == SASNAV_ERR_ARG, "pair -1 accepted");
    CHECK(sasnav_navigation_pair(&nav, 1, &np) == SASNAV_OK && np.p == 7, "pair 1 not read from pairs[]");
}

int main(void)
{
    test_round_trips();
    test_many_threads();
    test_accessor_errors();
    return test_summary("test_pair_store");
}
