/*
 * The inverse MPI compensator (paper eq. 23) in C99 with the loop structure of hystcomp's
 * compiled chain (hystcomp/_kernels/chain.py, chain_blocks): samples in blocks of 256, the
 * stateless dead-zones as passes over a block (operators outer, samples inner, so that the
 * inner loop vectorises over samples), the plays sample by sample with one fused loop over
 * the operators (their count a multiple of 8), then the hold / slew-limit / clamp. The same
 * parameters and state as inverse_mpi.c. benchmarks/bench_realtime.py compiles it with the
 * licences numba has (-O3 -march=native and the kernels' fast-math subset): the reference
 * that says how far the numba kernel is from what its own loop can do in C.
 */
#include <math.h>

#define N_DEADZONES 16
#define N_PLAYS 16
#define BLOCK 256

typedef struct {
    double dz_r[N_DEADZONES], dz_w[N_DEADZONES]; /* r[0] = 0: s_0(z) = z */
    double play_r[N_PLAYS], play_w[N_PLAYS];
    double in_offset, out_offset, low, high, max_step;
    double y[N_PLAYS]; /* play states */
    double last;       /* last output */
} ref_compensator;

static double max2(double a, double b)
{
    return a > b ? a : b;
}

static double min2(double a, double b)
{
    return a < b ? a : b;
}

void ref_run(ref_compensator *c, const double *x_ref, double *v, long n)
{
    double z[BLOCK];
    double y[N_PLAYS], r[N_PLAYS], w[N_PLAYS]; /* local: no aliasing with x_ref and v */
    double last = c->last;
    long start;
    int i;
    for (i = 0; i < N_PLAYS; i++) {
        y[i] = c->y[i];
        r[i] = c->play_r[i];
        w[i] = c->play_w[i];
    }
    for (start = 0; start < n; start += BLOCK) {
        const double *u = x_ref + start;
        long m = n - start < BLOCK ? n - start : BLOCK;
        long k;
        /* dead-zones: w_0 (z - x0) + sum_j w_j max(z - x0 - r_j, 0), as deadzone_block */
        for (k = 0; k < m; k++) {
            z[k] = c->dz_w[0] * min2(u[k] - c->in_offset, 0.0);
        }
        for (i = 0; i < N_DEADZONES; i++) {
            const double r = c->dz_r[i] + c->in_offset, w = c->dz_w[i];
            for (k = 0; k < m; k++) {
                z[k] += w * max2(u[k] - r, 0.0);
            }
        }
        /* plays, sample by sample (the recurrence), vectorised over the operators */
        for (k = 0; k < m; k++) {
            if (fabs(z[k]) < INFINITY) {
                double acc = 0.0;
#pragma GCC unroll 1 /* let the loop vectoriser, not full unrolling, take it (as LLVM does) */
                for (i = 0; i < N_PLAYS; i++) {
                    y[i] = max2(z[k] - r[i], min2(z[k] + r[i], y[i]));
                    acc += w[i] * y[i];
                }
                z[k] = acc;
            }
        }
        /* hold a non-finite input or result; slew-limit and clamp the others */
        for (k = 0; k < m; k++) {
            double zk = z[k] + c->out_offset;
            if (u[k] - u[k] != 0.0 || !(fabs(zk) < INFINITY)) {
                v[start + k] = last;
                continue;
            }
            if (c->max_step < INFINITY) {
                zk = min2(max2(zk, last - c->max_step), last + c->max_step);
            }
            last = min2(max2(zk, c->low), c->high);
            v[start + k] = last;
        }
    }
    for (i = 0; i < N_PLAYS; i++) {
        c->y[i] = y[i];
    }
    c->last = last;
}
