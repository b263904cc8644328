/*
 * A bank of play-chain compensators (inverse PI: offset, plays, clamp) in C99 with the loop
 * structure of hystcomp's channel kernel (hystcomp/_kernels/channels.py, bank_run): samples
 * in blocks of 32, channels in blocks of 128, then the samples of the block, then the plays
 * four by four, then the channels of the block in the innermost loop (the vector loop), then
 * the hold / slew-limit / clamp of every channel without branches. Arrays as the kernel has
 * them: parameters and states (operators, channels), inputs and outputs (samples, channels).
 * benchmarks/bench_channels.py compiles it with the licences numba has (-O3 -march=native
 * and the kernels' fast-math subset).
 */
#include <math.h>
#include <stddef.h>

#define CHANNEL_BLOCK 128
#define SAMPLE_BLOCK 32
#define CLAMP_TOLERANCE 1e-9

static double max2(double a, double b)
{
    return a > b ? a : b;
}

static double min2(double a, double b)
{
    return a < b ? a : b;
}

void bank_run(const double *restrict play_r, const double *restrict play_w,
              const double *restrict scalars, double *restrict plays, double *restrict counters,
              const double *restrict u, double *restrict out, long n, long n_ch, long n_play)
{
    double z[CHANNEL_BLOCK], acc[CHANNEL_BLOCK];
    const double *in_off = scalars, *out_off = scalars + n_ch, *low = scalars + 2 * n_ch;
    const double *high = scalars + 3 * n_ch, *max_step = scalars + 4 * n_ch;
    double *last = counters, *held = counters + n_ch, *clamped = counters + 2 * n_ch;
    for (long k0 = 0; k0 < n; k0 += SAMPLE_BLOCK) {
        long k1 = k0 + SAMPLE_BLOCK < n ? k0 + SAMPLE_BLOCK : n;
        for (long c0 = 0; c0 < n_ch; c0 += CHANNEL_BLOCK) {
            long m = n_ch - c0 < CHANNEL_BLOCK ? n_ch - c0 : CHANNEL_BLOCK;
            for (long k = k0; k < k1; k++) {
                const double *uk = u + k * n_ch + c0;
                for (long c = 0; c < m; c++) {
                    z[c] = uk[c] - in_off[c0 + c];
                    acc[c] = 0.0;
                }
                for (long i = 0; i < n_play; i += 4) {
                    const double *r0 = play_r + i * n_ch + c0, *r1 = r0 + n_ch;
                    const double *r2 = r1 + n_ch, *r3 = r2 + n_ch;
                    const double *w0 = play_w + i * n_ch + c0, *w1 = w0 + n_ch;
                    const double *w2 = w1 + n_ch, *w3 = w2 + n_ch;
                    double *y0 = plays + i * n_ch + c0, *y1 = y0 + n_ch;
                    double *y2 = y1 + n_ch, *y3 = y2 + n_ch;
                    for (long c = 0; c < m; c++) {
                        double zc = z[c];
                        double a = max2(zc - r0[c], min2(zc + r0[c], y0[c]));
                        double b = max2(zc - r1[c], min2(zc + r1[c], y1[c]));
                        double d = max2(zc - r2[c], min2(zc + r2[c], y2[c]));
                        double e = max2(zc - r3[c], min2(zc + r3[c], y3[c]));
                        y0[c] = a;
                        y1[c] = b;
                        y2[c] = d;
                        y3[c] = e;
                        acc[c] += (w0[c] * a + w1[c] * b) + (w2[c] * d + w3[c] * e);
                    }
                }
                double *ok = out + k * n_ch + c0;
                for (long c = 0; c < m; c++) {
                    long q = c0 + c;
                    double zk = acc[c] + out_off[q], prev = last[q];
                    int bad = (uk[c] - uk[c] != 0.0) | !(fabs(zk) < INFINITY);
                    double zs = min2(max2(zk, prev - max_step[q]), prev + max_step[q]);
                    double tol = CLAMP_TOLERANCE * (high[q] - low[q]);
                    int cut = (zs < low[q] - tol) | (zs > high[q] + tol);
                    double next = min2(max2(zs, low[q]), high[q]);
                    held[q] += bad ? 1.0 : 0.0;
                    clamped[q] += (cut && !bad) ? 1.0 : 0.0;
                    next = bad ? prev : next;
                    last[q] = next;
                    ok[c] = next;
                }
            }
        }
    }
}
