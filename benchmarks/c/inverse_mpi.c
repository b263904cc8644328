/*
 * Plain C99 reference of the inverse MPI compensator (paper eq. 23), written as an embedded
 * engineer would: fixed operator counts, parameters in a struct, one scalar loop per stage,
 * the same hold / slew-limit / clamp semantics as hystcomp's chain. No intrinsics.
 * benchmarks/bench_realtime.py compiles it with the licences numba has (-O3 -march=native and
 * the fast-math subset of the package's kernels) as the reference, and with plain `cc -O3`
 * for information, and times ref_run.
 *
 *   x_ref -> (x_ref - x0) -> inverse dead-zones (eq. 14 with eqs. 24-25)
 *         -> inverse plays (eq. 12 with eqs. 24-26) -> (+ v0) -> slew limit -> clamp
 */
#include <math.h>

#define N_DEADZONES 16
#define N_PLAYS 16

typedef struct {
    double dz_r[N_DEADZONES], dz_w[N_DEADZONES]; /* r[0] = 0: s_0(z) = z */
    double play_r[N_PLAYS], play_w[N_PLAYS];
    double in_offset, out_offset, low, high, max_step;
    double y[N_PLAYS]; /* play states */
    double last;       /* last output */
} ref_compensator;

static double ref_step(ref_compensator *c, double x_ref)
{
    double z, u, v;
    int i;

    if (!isfinite(x_ref)) {
        return c->last; /* hold */
    }
    z = x_ref - c->in_offset;
    u = c->dz_w[0] * z;
    for (i = 1; i < N_DEADZONES; i++) {
        double d = z - c->dz_r[i];
        if (d > 0.0) {
            u += c->dz_w[i] * d;
        }
    }
    v = 0.0;
    for (i = 0; i < N_PLAYS; i++) {
        double y = c->y[i];
        double lo = u - c->play_r[i], hi = u + c->play_r[i];
        if (y < lo) {
            y = lo;
        }
        if (y > hi) {
            y = hi;
        }
        c->y[i] = y;
        v += c->play_w[i] * y;
    }
    v += c->out_offset;
    if (v > c->last + c->max_step) {
        v = c->last + c->max_step;
    }
    if (v < c->last - c->max_step) {
        v = c->last - c->max_step;
    }
    if (v > c->high) {
        v = c->high;
    }
    if (v < c->low) {
        v = c->low;
    }
    c->last = v;
    return v;
}

void ref_run(ref_compensator *c, const double *x_ref, double *v, long n)
{
    long k;
    for (k = 0; k < n; k++) {
        v[k] = ref_step(c, x_ref[k]);
    }
}
