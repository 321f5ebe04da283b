/* Hardware reference for benchmark case A: the fixed-step impulse scheme of
 * cylfric.simulate.kernels.fixed_step, written in plain C (gcc -O3, no fast-math).
 * Same operations: inputs on a uniform grid interpolated linearly per substep, exact LuGre
 * z step with mid-step velocity, quasi-Newton on the end velocity with the stuck-contact
 * Jacobian, instantaneous LuGre force at the grid points.
 *
 * usage: fixed_step DURATION DT SUBSTEPS MASS K SPEED F_C F_S SIGMA_2 SIGMA_0 SIGMA_1 V_R ALPHA
 *                   REPS OUT.bin
 * prints: best seconds per run, and writes the friction force (float64) to OUT.bin
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static inline double g_function(double speed, double fc, double fs, double vr, double alpha) {
    double u = speed / vr;
    if (alpha == 1.0) return fc + (fs - fc) * exp(-u);
    return fc + (fs - fc) * exp(-pow(u, alpha));
}

static inline void z_step(double z0, double v, double h, double s0, double fc, double fs,
                          double vr, double alpha, double *z1, double *zint) {
    if (v == 0.0) { *z1 = z0; *zint = z0 * h; return; }
    double g = g_function(fabs(v), fc, fs, vr, alpha);
    double lam = s0 * fabs(v) / g;
    double x = lam * h;
    double zss = v > 0 ? g / s0 : -g / s0;
    double ome, fac;
    if (x < 1e-5) { ome = x * (1.0 - x * (0.5 - x / 6.0)); fac = h * (1.0 - x * (0.5 - x / 6.0)); }
    else { ome = -expm1(-x); fac = ome / lam; }
    *z1 = zss + (z0 - zss) * (1.0 - ome);
    *zint = zss * h + (z0 - zss) * fac;
}

static inline double lugre_instant(double v, double z, double s0, double s1, double s2,
                                   double fc, double fs, double vr, double alpha) {
    double g = g_function(fabs(v), fc, fs, vr, alpha);
    double dz = v - s0 * fabs(v) * z / g;
    return s0 * z + s1 * dz + s2 * v;
}

static void run(int n, double dt, int sub, double mass, double k, const double *xr_,
                const double *vr_, const double *fe_, const double *fc_, const double *fs_,
                const double *s2_, double s0, double s1, double v_r, double alpha,
                double tol, double *force) {
    double x = 0, v = 0, z = 0, e = 0, c = 0, ki = 0;
    double h = dt / sub;
    force[0] = lugre_instant(0, 0, s0, s1, s2_[0], fc_[0], fs_[0], v_r, alpha);
    for (int i = 0; i < n - 1; i++) {
        for (int j = 0; j < sub; j++) {
            double w = (j + 0.5) / sub;
            double xr = xr_[i] * (1 - w) + xr_[i + 1] * w;
            double vr = vr_[i] * (1 - w) + vr_[i + 1] * w;
            double fe = fe_[i] * (1 - w) + fe_[i + 1] * w;
            double fc = fc_[i] * (1 - w) + fc_[i + 1] * w;
            double fs = fs_[i] * (1 - w) + fs_[i + 1] * w;
            double s2 = s2_[i] * (1 - w) + s2_[i + 1] * w;
            double jac = mass + 0.25 * k * h * h + 0.5 * c * h + 0.5 * (0.5 * s0 * h * h + s1 * h + s2 * h);
            double v1 = v, vm, z1, zint;
            for (int it = 0; it < 60; it++) {
                vm = 0.5 * (v + v1);
                z_step(z, vm, h, s0, fc, fs, v_r, alpha, &z1, &zint);
                double imp = s0 * zint + s1 * (z1 - z) + s2 * vm * h;
                double em = xr - (x + 0.5 * h * vm);
                double drive = (k * em + c * (vr - vm) + ki * (e + 0.5 * h * em) + fe) * h;
                double dv = (mass * (v1 - v) - drive + imp) / jac;
                v1 -= dv;
                if (fabs(dv) <= tol * (fabs(v1) + 1e-9)) break;
            }
            vm = 0.5 * (v + v1);
            z_step(z, vm, h, s0, fc, fs, v_r, alpha, &z1, &zint);
            e += h * (xr - (x + 0.5 * h * vm));
            x += h * vm;
            v = v1;
            z = z1;
        }
        force[i + 1] = lugre_instant(v, z, s0, s1, s2_[i + 1], fc_[i + 1], fs_[i + 1], v_r, alpha);
    }
}

int main(int argc, char **argv) {
    if (argc != 16) { fprintf(stderr, "usage: see the header of fixed_step.c\n"); return 2; }
    double duration = atof(argv[1]), dt = atof(argv[2]);
    int sub = atoi(argv[3]);
    double mass = atof(argv[4]), k = atof(argv[5]), speed = atof(argv[6]);
    double fc = atof(argv[7]), fs = atof(argv[8]), s2 = atof(argv[9]);
    double s0 = atof(argv[10]), s1 = atof(argv[11]), v_r = atof(argv[12]), alpha = atof(argv[13]);
    int reps = atoi(argv[14]);
    int n = (int)llround(duration / dt) + 1;
    double *xr = malloc(n * sizeof(double)), *vr = malloc(n * sizeof(double));
    double *fe = calloc(n, sizeof(double)), *fc_ = malloc(n * sizeof(double));
    double *fs_ = malloc(n * sizeof(double)), *s2_ = malloc(n * sizeof(double));
    double *force = malloc(n * sizeof(double));
    for (int i = 0; i < n; i++) {
        xr[i] = speed * i * dt; vr[i] = speed; fc_[i] = fc; fs_[i] = fs; s2_[i] = s2;
    }
    double best = 1e30;
    for (int r = 0; r < reps; r++) {
        struct timespec t0, t1;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        run(n, dt, sub, mass, k, xr, vr, fe, fc_, fs_, s2_, s0, s1, v_r, alpha, 1e-10, force);
        clock_gettime(CLOCK_MONOTONIC, &t1);
        double s = (t1.tv_sec - t0.tv_sec) + 1e-9 * (t1.tv_nsec - t0.tv_nsec);
        if (s < best) best = s;
    }
    FILE *f = fopen(argv[15], "wb");
    if (!f) { perror(argv[15]); return 1; }
    fwrite(force, sizeof(double), n, f);
    fclose(f);
    printf("%.9f\n", best);
    return 0;
}
