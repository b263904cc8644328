/*
 * Plain C99 reference of hystcomp's inverse of the linear dynamics, written as an embedded
 * engineer would: fixed sizes (N_FIR taps, N_CREEP creep modes, given at compile time),
 * parameters and state in a struct, a circular delay line (a head index that moves back one
 * place a sample, instead of shifting every sample along), no intrinsics. The same algorithm
 * as the kernel (hystcomp._kernels.dynamics.inverse_block), with the same semantics:
 *
 *   x_ref -> FIR over the delay line (bias + sum_j h_j x[k - j])
 *         -> exact inverse of the creep bank, y = (w SCALE - sum_i c_i a_i lag_i) / DIRECT
 *         -> clamp to [low, high], counted beyond the tolerance -> creep lags follow y
 *
 * A non-finite x_ref gives NaN and leaves the state as it was; a result that overflows gives
 * NaN too. The taps run over the circular line in one of three ways an engineer writes:
 *   ref_run_twice  the line held twice over (each sample written at head and head + N_FIR),
 *                  the taps in one contiguous loop: the kernel's and hystcomp export-c's way;
 *   ref_run_split  in two contiguous runs, from the head to the end and from the start;
 *   ref_run_wrap   in one loop whose index wraps.
 * benchmarks/bench_dynamics_speed.py compiles this file with the licences that numba has and
 * takes the fastest of the three as the reference.
 */
#include <math.h>

#if !defined(N_FIR) || !defined(N_CREEP) || N_FIR < 1 || N_CREEP < 1
#error "compile with -DN_FIR=<taps> -DN_CREEP=<creep modes>, each at least 1"
#endif

typedef struct {
    double h[N_FIR];                 /* FIR taps, newest sample first */
    double a[N_CREEP], c[N_CREEP];   /* creep lag factors and weights */
    double scale, direct, low, high, bias, tol;
    double line[2 * N_FIR];          /* delay line: line[head] is the newest sample */
    double lag[N_CREEP];             /* creep lag states */
    long head;
    double clamped;                  /* count of clamped outputs */
} ref_filter;

/* the creep inverse, the clamp and its count, the lags' update: w is the FIR's output */
static double ref_finish(ref_filter *f, double w)
{
    double acc = w * f->scale;
    double y;
    int i;
    for (i = 0; i < N_CREEP; i++) {
        acc -= f->c[i] * f->a[i] * f->lag[i];
    }
    y = acc / f->direct;
    if (!isfinite(y)) {
        return NAN;
    }
    if (y > f->high + f->tol || y < f->low - f->tol) {
        f->clamped += 1.0;
    }
    if (y > f->high) {
        y = f->high;
    }
    if (y < f->low) {
        y = f->low;
    }
    for (i = 0; i < N_CREEP; i++) {
        f->lag[i] = f->a[i] * f->lag[i] + (1.0 - f->a[i]) * y;
    }
    return y;
}

/* the newest sample in at the head, moved back one place */
static long ref_push(ref_filter *f, double x_ref)
{
    long head = f->head > 0 ? f->head - 1 : N_FIR - 1;
    f->head = head;
    f->line[head] = x_ref;
    return head;
}

static double ref_step_twice(ref_filter *f, double x_ref)
{
    double w = f->bias;
    const double *line;
    long head, j;
    if (!isfinite(x_ref)) {
        return NAN;
    }
    head = ref_push(f, x_ref);
    f->line[head + N_FIR] = x_ref;
    line = f->line + head;
    for (j = 0; j < N_FIR; j++) {
        w += f->h[j] * line[j];
    }
    return ref_finish(f, w);
}

static double ref_step_split(ref_filter *f, double x_ref)
{
    double w = f->bias;
    long head, j;
    if (!isfinite(x_ref)) {
        return NAN;
    }
    head = ref_push(f, x_ref);
    for (j = 0; j < N_FIR - head; j++) {
        w += f->h[j] * f->line[head + j];
    }
    for (; j < N_FIR; j++) {
        w += f->h[j] * f->line[head + j - N_FIR];
    }
    return ref_finish(f, w);
}

static double ref_step_wrap(ref_filter *f, double x_ref)
{
    double w = f->bias;
    long i, j;
    if (!isfinite(x_ref)) {
        return NAN;
    }
    i = ref_push(f, x_ref);
    for (j = 0; j < N_FIR; j++) {
        w += f->h[j] * f->line[i];
        if (++i == N_FIR) {
            i = 0;
        }
    }
    return ref_finish(f, w);
}

void ref_run_twice(ref_filter *f, const double *x_ref, double *y, long n)
{
    long k;
    for (k = 0; k < n; k++) {
        y[k] = ref_step_twice(f, x_ref[k]);
    }
}

void ref_run_split(ref_filter *f, const double *x_ref, double *y, long n)
{
    long k;
    for (k = 0; k < n; k++) {
        y[k] = ref_step_split(f, x_ref[k]);
    }
}

void ref_run_wrap(ref_filter *f, const double *x_ref, double *y, long n)
{
    long k;
    for (k = 0; k < n; k++) {
        y[k] = ref_step_wrap(f, x_ref[k]);
    }
}
