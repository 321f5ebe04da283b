/* Hardware reference for benchmarks/bench_stiff.py: the adaptive Rodas3 scheme of
 * cylfric.simulate.kernels.rodas3_core, written in plain C, for a spring pulled at constant
 * speed. Same operations in the same order: inputs as a (m x 6) block interpolated linearly
 * (two rows and a ramp for constant inputs), exact Jacobian of the LuGre plant solved in closed
 * form, the exp of f(t_n+1, y_n+1) re-used by the next step's Jacobian (three exps per step),
 * the three breakaway step guards, force-weighted error norm, Horner-form Hermite (linear for
 * v and z on stiff steps) output on the grid with the friction force (eq. 2.5) and the drive
 * force computed there, in one branch-free loop per step that gcc vectorises, the few points
 * whose g(v) needs exp recomputed after (kernels._dense_block and _dense_fixup). Compiled as numba compiles the kernel: gcc -O3 -march=native with FMA
 * contraction, reciprocals and reassociation but no NaN/inf assumptions (fast-math without
 * -ffinite-math-only), see FLAGS in bench_stiff.py.
 *
 * With PLAIN = 1 it is a plain textbook Rodas3 instead (Hairer & Wanner IV.7 step control:
 * no breakaway guards, the error norm the RMS over the states x, v, z with
 * atol_i + rtol max(|y_n|, |y_n+1|), the output loop point by point with one exp_neg each):
 * the baseline of issue 26, run by the benchmark at its loosest passing tolerance.
 *
 * usage: rodas3 DURATION DT MASS K SPEED F_C F_S SIGMA_2 SIGMA_0 SIGMA_1 V_R ALPHA RTOL
 *               ATOL_X ATOL_V ATOL_Z ATOL_F REPS OUT.bin [PLAIN]
 * prints: best seconds per run, the accepted and the rejected steps; writes the friction
 * force (float64)
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#define FORCE_NORM 0.1 /* kernels.FORCE_NORM: weight of the force term of the error norm */

static inline double exp_neg(double x) {
    if (x < 1e-3)
        return 1.0 - x * (1.0 - x * (0.5 - x * (1.0 / 6.0 - x * (1.0 / 24.0 - x * (1.0 / 120.0)))));
    if (x > 746.0) return 0.0;
    return exp(-x);
}

static inline double stribeck_decay(double speed, double inv_vr, double alpha) {
    double u = speed * inv_vr;
    if (alpha == 2.0) return exp_neg(u * u);
    if (alpha == 1.0) return exp_neg(u);
    return exp_neg(pow(u, alpha));
}

typedef struct {
    int m, n_grid, every, mode;
    double dt_s, inv_dt_s, ramp, dt, inv_m, mass, k, c, ki, s0, s1, v_r, inv_vr, alpha, offset;
    const double *sig; /* m x 6: x_ref, v_ref, f_ext, F_c, F_s, sigma_2 */
} Plant;

typedef struct { double xr, vr, fe, fc, fs, s2, sxr, svr, sfe, sfc, sfs, ss2; } Inputs;

static inline Inputs signals(const Plant *p, double t) {
    Inputs in;
    double pos = t * p->inv_dt_s, w;
    int i;
    if (pos <= 0.0) { i = 0; w = 0.0; }
    else if (pos >= p->m - 1) { i = p->m - 2; w = 1.0; }
    else { i = (int)pos; w = pos - i; }
    const double *a = p->sig + 6 * i, *b = a + 6;
    double dxr = b[0] - a[0], dvr = b[1] - a[1], dfe = b[2] - a[2];
    double dfc = b[3] - a[3], dfs = b[4] - a[4], ds2 = b[5] - a[5];
    in.xr = a[0] + w * dxr + p->ramp * t; in.vr = a[1] + w * dvr + p->ramp;
    in.fe = a[2] + w * dfe; in.fc = a[3] + w * dfc; in.fs = a[4] + w * dfs;
    in.s2 = a[5] + w * ds2;
    in.sxr = dxr * p->inv_dt_s + p->ramp; in.svr = dvr * p->inv_dt_s; in.sfe = dfe * p->inv_dt_s;
    in.sfc = dfc * p->inv_dt_s; in.sfs = dfs * p->inv_dt_s; in.ss2 = ds2 * p->inv_dt_s;
    return in;
}

/* dv/dt, dz/dt, de/dt and the decay of g(v) at given inputs */
static inline void rhs_at(const Plant *p, double x, double v, double z, double e,
                          const Inputs *in, double *acc, double *dz, double *de,
                          double *decay) {
    *decay = stribeck_decay(fabs(v), p->inv_vr, p->alpha);
    double g = in->fc + (in->fs - in->fc) * *decay;
    *dz = v - p->s0 * fabs(v) * z / g;
    double friction = p->s0 * z + p->s1 * *dz + in->s2 * v;
    *acc = (p->k * (in->xr - x) + p->c * (in->vr - v) + p->ki * e + in->fe - friction) * p->inv_m;
    *de = in->xr - x;
}

static inline void partials(double v, double z, double s0, double fc, double fs, double inv_vr,
                            double alpha, double decay, double *d_v, double *d_z,
                            double *d_fc, double *d_fs) {
    double speed = fabs(v), u = speed * inv_vr, slope_u;
    if (u == 0.0) slope_u = alpha == 1.0 ? 1.0 : (alpha > 1.0 ? 0.0 : 1e300);
    else if (alpha == 1.0) slope_u = 1.0;
    else if (alpha == 2.0) slope_u = 2.0 * u;
    else slope_u = alpha * pow(u, alpha) / u;
    double g = fc + (fs - fc) * decay;
    double inv_g2 = 1.0 / (g * g);
    double dg = -(fs - fc) * decay * slope_u * inv_vr;
    double sign = v >= 0.0 ? 1.0 : -1.0;
    *d_v = 1.0 - s0 * z * sign * (g - speed * dg) * inv_g2;
    *d_z = -s0 * speed * g * inv_g2;
    double d_g = s0 * speed * z * inv_g2;
    *d_fc = d_g * (1.0 - decay);
    *d_fs = d_g * decay;
}

static inline void solve(double rx, double rv, double rz, double re, double a_, double cz,
                         double d_, double d_v, double inv_gi, double inv_gz, double inv_den,
                         double *kx, double *kv, double *kz, double *ke) {
    *kv = (rv - a_ * rx * inv_gi - cz * rz * inv_gz + d_ * re * inv_gi
           - d_ * rx * inv_gi * inv_gi) * inv_den;
    *kx = (rx + *kv) * inv_gi;
    *kz = (rz + d_v * *kv) * inv_gz;
    *ke = (re - *kx) * inv_gi;
}

/* friction force and drive force at an output point (kernels._outputs) */
static inline void outputs(const Plant *p, double tj, int i_grid, double x, double v, double z,
                           double e, double *friction, double *drive) {
    Inputs in;
    if (p->mode == 0) {
        const double *a = p->sig + 6 * i_grid;
        in.xr = a[0] + p->ramp * tj; in.vr = a[1] + p->ramp;
        in.fe = a[2]; in.fc = a[3]; in.fs = a[4]; in.s2 = a[5];
    } else if (p->mode == 1) {
        in.xr = p->sig[0] + p->ramp * tj; in.vr = p->sig[1] + p->ramp;
        in.fe = p->sig[2]; in.fc = p->sig[3]; in.fs = p->sig[4]; in.s2 = p->sig[5];
    } else {
        in = signals(p, tj);
    }
    double speed = fabs(v);
    double g = in.fc + (in.fs - in.fc) * stribeck_decay(speed, p->inv_vr, p->alpha);
    *friction = p->s0 * z + p->s1 * (v - p->s0 * speed * z / g) + in.s2 * v;
    *drive = p->k * (in.xr - x) + p->c * (in.vr - v) + p->ki * e + in.fe + p->offset;
}

static long run(const Plant *p, double rtol, double atol_x, double atol_v, double atol_z,
                double atol_f, long max_steps, int n_out, double *out /* 5 x n_out */,
                int plain, long *n_rejected) {
    double dt = p->dt, t_end = dt * (p->n_grid - 1);
    double atol_e = atol_x * (t_end > 1.0 ? t_end : 1.0);
    double inv_m = p->inv_m, k = p->k, c = p->c, ki = p->ki, s0 = p->s0, s1 = p->s1;
    double x = 0.0, v = 0.0, z = 0.0, e = 0.0, t = 0.0;
    Inputs in = signals(p, 0.0), in1;
    double a0, dz0, de0, decay0, a1, dz1, de1, decay1, fa, fz_, fe_, dummy;
    rhs_at(p, x, v, z, e, &in, &a0, &dz0, &de0, &decay0);
    double fr, dr;
    outputs(p, 0.0, 0, x, v, z, e, &fr, &dr);
    out[0] = x; out[n_out] = v; out[2 * n_out] = z; out[3 * n_out] = fr; out[4 * n_out] = dr;
    double h = dt < 1e-5 ? dt : 1e-5;
    int fast_out = !plain && p->mode == 1 && (p->alpha == 2.0 || p->alpha == 1.0);
    int next_out = 1;
    long accepted = 0, rejected = 0;
    while (next_out < n_out && accepted + rejected < max_steps) {
        if (t + h > t_end) h = t_end - t;
        double d_v, d_z, d_fc, d_fs;
        partials(v, z, s0, in.fc, in.fs, p->inv_vr, p->alpha, decay0, &d_v, &d_z, &d_fc, &d_fs);
        double f_v = s1 * d_v + in.s2, f_z = s0 + s1 * d_z;
        double load = k * (in.xr - x) + c * (in.vr - v) + ki * e + in.fe;
        double rate = k * (in.sxr - v) + c * in.svr + in.sfe + ki * (in.xr - x);
        if (!plain && load * rate > 0.0) {
            double margin = (in.fc + (in.fs - in.fc) * decay0) - fabs(load);
            if (margin > 0.0) h = fmin(h, fmax(0.5 * margin / fabs(rate), 1e-3 * dt));
        }
        if (!plain && v * a0 < 0.0 && fabs(v) > 1e-3 * p->v_r)
            h = fmin(h, fmax(0.5 * fabs(v / a0), 1e-3 * dt));
        double b_ = (c + f_v) * inv_m, cz = f_z * inv_m;
        double trace = d_z - b_, det = cz * d_v - b_ * d_z;
        double disc = 0.25 * trace * trace - det;
        double growth = disc > 0.0 ? 0.5 * trace + sqrt(disc) : 0.5 * trace;
        if (!plain && growth > 0.0) h = fmin(h, 1.0 / growth);
        int stiff = h * (fabs(trace) + sqrt(fabs(det))) > 1.0;
        if (t + h > t_end) h = t_end - t;
        double dzdt_t = d_fc * in.sfc + d_fs * in.sfs;
        double ft_v = (k * in.sxr + c * in.svr + in.sfe - s1 * dzdt_t - v * in.ss2) * inv_m;
        double inv_h = 1.0 / h, gi = 2.0 * inv_h, inv_gi = 0.5 * h;
        double a_ = k * inv_m, d_ = ki * inv_m;
        double inv_gz = 1.0 / (gi - d_z);
        double inv_den = 1.0 / (a_ * inv_gi + gi + b_ + cz * d_v * inv_gz + d_ * inv_gi * inv_gi);
        double k1x, k1v, k1z, k1e, k2x, k2v, k2z, k2e, k3x, k3v, k3z, k3e, k4x, k4v, k4z, k4e;
        solve(v, a0 + 0.5 * h * ft_v, dz0 + 0.5 * h * dzdt_t, de0 + 0.5 * h * in.sxr, a_, cz, d_,
              d_v, inv_gi, inv_gz, inv_den, &k1x, &k1v, &k1z, &k1e);
        solve(v + 4.0 * inv_h * k1x, a0 + 4.0 * inv_h * k1v + 1.5 * h * ft_v,
              dz0 + 4.0 * inv_h * k1z + 1.5 * h * dzdt_t, de0 + 4.0 * inv_h * k1e + 1.5 * h * in.sxr,
              a_, cz, d_, d_v, inv_gi, inv_gz, inv_den, &k2x, &k2v, &k2z, &k2e);
        double t1 = t + h;
        in1 = signals(p, t1);
        double yv = v + 2.0 * k1v;
        rhs_at(p, x + 2.0 * k1x, yv, z + 2.0 * k1z, e + 2.0 * k1e, &in1, &fa, &fz_, &fe_, &dummy);
        solve(yv + (k1x - k2x) * inv_h, fa + (k1v - k2v) * inv_h, fz_ + (k1z - k2z) * inv_h,
              fe_ + (k1e - k2e) * inv_h, a_, cz, d_, d_v, inv_gi, inv_gz, inv_den,
              &k3x, &k3v, &k3z, &k3e);
        double sx = 2.0 * k1x + k3x, sv = 2.0 * k1v + k3v, sz = 2.0 * k1z + k3z;
        double se = 2.0 * k1e + k3e;
        yv = v + sv;
        rhs_at(p, x + sx, yv, z + sz, e + se, &in1, &fa, &fz_, &fe_, &dummy);
        solve(yv + (k1x - k2x - 8.0 / 3.0 * k3x) * inv_h, fa + (k1v - k2v - 8.0 / 3.0 * k3v) * inv_h,
              fz_ + (k1z - k2z - 8.0 / 3.0 * k3z) * inv_h, fe_ + (k1e - k2e - 8.0 / 3.0 * k3e) * inv_h,
              a_, cz, d_, d_v, inv_gi, inv_gz, inv_den, &k4x, &k4v, &k4z, &k4e);
        double x1 = x + (sx + k4x), v1 = v + (sv + k4v), z1 = z + (sz + k4z), e1 = e + (se + k4e);
        double q = k4x / (atol_x + rtol * fmax(fabs(x), fabs(x1)));
        double err = q * q;
        q = k4v / (atol_v + rtol * fmax(fabs(v), fabs(v1)));
        err += q * q;
        q = k4z / (atol_z + rtol * fmax(fabs(z), fabs(z1)));
        err += q * q;
        if (plain) { /* textbook: RMS over the plant's states x, v, z */
            err = sqrt(err / 3);
        } else {
            q = k4e / (atol_e + rtol * fmax(fabs(e), fabs(e1)));
            err += q * q;
            q = FORCE_NORM * (f_v * k4v + f_z * k4z)
                / (atol_f + rtol * fabs(s0 * z + s1 * dz0 + in.s2 * v));
            err += q * q;
            err = sqrt(err / 5);
        }
        double factor;
        if (err <= 1.0 && isfinite(err)) {
            rhs_at(p, x1, v1, z1, e1, &in1, &a1, &dz1, &de1, &decay1);
            double dx = x1 - x, dv = v1 - v, dzz = z1 - z, dee = e1 - e;
            double cx1 = h * v, cx2 = 3.0 * dx - h * (2.0 * v + v1), cx3 = h * (v + v1) - 2.0 * dx;
            double cv1, cv2, cv3, cz1, cz2, cz3;
            if (stiff) {
                cv1 = dv; cv2 = 0.0; cv3 = 0.0; cz1 = dzz; cz2 = 0.0; cz3 = 0.0;
            } else {
                cv1 = h * a0; cv2 = 3.0 * dv - h * (2.0 * a0 + a1); cv3 = h * (a0 + a1) - 2.0 * dv;
                cz1 = h * dz0; cz2 = 3.0 * dzz - h * (2.0 * dz0 + dz1);
                cz3 = h * (dz0 + dz1) - 2.0 * dzz;
            }
            double ce1 = h * de0, ce2 = 3.0 * dee - h * (2.0 * de0 + de1);
            double ce3 = h * (de0 + de1) - 2.0 * dee;
            if (__builtin_expect(fast_out, 1)) {
                /* cylfric's _dense_block: the step's output points in one branch-free loop
                 * (vectorised by gcc), g(v) without exp where exp_neg takes none, then the
                 * points that need exp recomputed (_dense_fixup) */
                double t_lim = t1 + 1e-12 * dt, step_out = p->every * dt;
                long guess = (long)(t_lim / step_out);
                int j_end = (int)fmin(fmax((double)guess, (double)(next_out - 1)) + 1, n_out);
                while (j_end < n_out && ((long)j_end * p->every) * dt <= t_lim) j_end++;
                while (j_end > next_out && ((long)(j_end - 1) * p->every) * dt > t_lim) j_end--;
                if (j_end - next_out >= 4) {
                    const double *r0 = p->sig;
                    double xr0 = r0[0], vr0 = r0[1] + p->ramp, fe = r0[2], fc = r0[3];
                    double dfs = r0[4] - r0[3], s2 = r0[5], inv_vr = p->inv_vr, ramp = p->ramp;
                    double offset = p->offset;
                    long every = p->every;
                    int alpha2 = p->alpha == 2.0, bad = 0;
                    double *o0 = out, *o1 = out + n_out, *o2 = out + 2 * n_out;
                    double *o3 = out + 3 * n_out, *o4 = out + 4 * n_out;
                    for (int j = next_out; j < j_end; j++) {
                        double tj = ((long)j * every) * dt, th = (tj - t) * inv_h;
                        double xj = x + th * (cx1 + th * (cx2 + th * cx3));
                        double vj = v + th * (cv1 + th * (cv2 + th * cv3));
                        double zj = z + th * (cz1 + th * (cz2 + th * cz3));
                        double ej = e + th * (ce1 + th * (ce2 + th * ce3));
                        double speed = fabs(vj), u = speed * inv_vr, arg = alpha2 ? u * u : u;
                        bad += (arg >= 1e-3) & (arg <= 746.0);
                        double taylor = 1.0 - arg * (1.0 - arg * (0.5 - arg * (1.0 / 6.0
                                        - arg * (1.0 / 24.0 - arg * (1.0 / 120.0)))));
                        double g = fc + dfs * (arg > 746.0 ? 0.0 : taylor);
                        o0[j] = xj; o1[j] = vj; o2[j] = zj;
                        o3[j] = s0 * zj + s1 * (vj - s0 * speed * zj / g) + s2 * vj;
                        o4[j] = k * (xr0 + ramp * tj - xj) + c * (vr0 - vj)
                                + (ki != 0.0 ? ki * ej : 0.0) + fe + offset;
                    }
                    if (bad > 0) {
                        for (int j = next_out; j < j_end; j++) {
                            double vj = o1[j], speed = fabs(vj), u = speed * inv_vr;
                            double arg = alpha2 ? u * u : u;
                            if (arg >= 1e-3 && arg <= 746.0) {
                                double g = fc + dfs * exp_neg(arg), zj = o2[j];
                                o3[j] = s0 * zj + s1 * (vj - s0 * speed * zj / g) + s2 * vj;
                            }
                        }
                    }
                    next_out = j_end;
                }
            }
            while (next_out < n_out) {
                int i_grid = next_out * p->every;
                double tj = i_grid * dt;
                if (tj > t1 + 1e-12 * dt) break;
                double th = (tj - t) * inv_h;
                double xj = x + th * (cx1 + th * (cx2 + th * cx3));
                double vj = v + th * (cv1 + th * (cv2 + th * cv3));
                double zj = z + th * (cz1 + th * (cz2 + th * cz3));
                double ej = ki != 0.0 ? e + th * (ce1 + th * (ce2 + th * ce3)) : 0.0;
                outputs(p, tj, i_grid, xj, vj, zj, ej, &fr, &dr);
                out[next_out] = xj;
                out[n_out + next_out] = vj;
                out[2 * n_out + next_out] = zj;
                out[3 * n_out + next_out] = fr;
                out[4 * n_out + next_out] = dr;
                next_out++;
            }
            t = t1;
            x = x1; v = v1; z = z1; e = e1;
            a0 = a1; dz0 = dz1; de0 = de1; decay0 = decay1;
            in = in1;
            accepted++;
            factor = fmin(6.0, 0.9 / cbrt(fmax(err, 1e-10)));
        } else {
            rejected++;
            factor = !isfinite(err) ? 0.2 : fmax(0.2, 0.9 / cbrt(err));
        }
        h *= factor;
    }
    *n_rejected = rejected;
    return accepted;
}

int main(int argc, char **argv) {
    if (argc != 20 && argc != 21) {
        fprintf(stderr, "usage: see the header of rodas3.c\n");
        return 2;
    }
    int plain = argc == 21 ? atoi(argv[20]) : 0;
    double a[18];
    for (int i = 1; i < 19; i++) a[i - 1] = atof(argv[i]);
    double duration = a[0], dt = a[1];
    int n = (int)llround(duration / dt) + 1, reps = (int)a[17];
    /* a spring pulled at constant speed, constant friction: two rows and a ramp, as simulate() */
    double sig[12] = {0.0, 0.0, 0.0, a[5], a[6], a[7], 0.0, 0.0, 0.0, a[5], a[6], a[7]};
    double *out = malloc(5 * (size_t)n * sizeof(double));
    Plant p = {2, n, 1, n == 2 ? 0 : 1, dt * (n - 1), 1.0 / (dt * (n - 1)), a[4], dt,
               1.0 / a[2], a[2], a[3], 0.0, 0.0, a[8], a[9], a[10], 1.0 / a[10], a[11], 0.0, sig};
    double best = 1e30;
    long steps = 0, rejected = 0;
    for (int r = 0; r < reps; r++) {
        struct timespec t0, t1;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        steps = run(&p, a[12], a[13], a[14], a[15], a[16], 50000000L, n, out, plain, &rejected);
        clock_gettime(CLOCK_MONOTONIC, &t1);
        double s = (t1.tv_sec - t0.tv_sec) + 1e-9 * (t1.tv_nsec - t0.tv_nsec);
        if (s < best) best = s;
    }
    FILE *f = fopen(argv[19], "wb");
    if (!f) { perror(argv[19]); return 1; }
    fwrite(out + 3 * (size_t)n, sizeof(double), n, f);
    fclose(f);
    printf("%.9f %ld %ld\n", best, steps, rejected);
    return 0;
}
