/* Hardware reference for benchmarks/bench_stiff.py: the adaptive Rodas3 scheme of
 * cylfric.simulate.kernels.rosenbrock_core, written in plain C (gcc -O3, no fast-math), for a
 * spring pulled at constant speed. Same operations in the same order: inputs on the uniform
 * grid interpolated linearly, exact Jacobian of the LuGre plant solved in closed form, the
 * three breakaway step guards, force-weighted error norm, Hermite/linear output on the grid,
 * instantaneous LuGre force (eq. 2.5) at the grid points.
 *
 * usage: rodas3 DURATION DT MASS K SPEED F_C F_S SIGMA_2 SIGMA_0 SIGMA_1 V_R ALPHA RTOL
 *               ATOL_X ATOL_V ATOL_Z ATOL_F REPS OUT.bin
 * prints: best seconds per run and the accepted steps; writes the friction force (float64)
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static inline double g_function(double speed, double fc, double fs, double vr, double alpha) {
    double u = speed / vr;
    if (alpha == 1.0) return fc + (fs - fc) * exp(-u);
    if (alpha == 2.0) return fc + (fs - fc) * exp(-(u * u));
    return fc + (fs - fc) * exp(-pow(u, alpha));
}

static inline double lugre_instant(double v, double z, double s0, double s1, double s2,
                                   double fc, double fs, double vr, double alpha) {
    double g = g_function(fabs(v), fc, fs, vr, alpha);
    double dz = v - s0 * fabs(v) * z / g;
    return s0 * z + s1 * dz + s2 * v;
}

static inline void lugre_partials(double v, double z, double s0, double fc, double fs,
                                  double vr, double alpha, double *d_v, double *d_z,
                                  double *d_fc, double *d_fs) {
    double speed = fabs(v), u = speed / vr, decay, slope_u;
    if (u == 0.0) {
        decay = 1.0;
        slope_u = alpha == 1.0 ? 1.0 : (alpha > 1.0 ? 0.0 : 1e300);
    } else if (alpha == 1.0) {
        decay = exp(-u);
        slope_u = 1.0;
    } else {
        double ua = pow(u, alpha);
        decay = exp(-ua);
        slope_u = alpha * ua / u;
    }
    double g = fc + (fs - fc) * decay;
    double dg = -(fs - fc) * decay * slope_u / vr;
    double sign = v >= 0.0 ? 1.0 : -1.0;
    *d_v = 1.0 - s0 * z * sign * (g - speed * dg) / (g * g);
    *d_z = -s0 * speed / g;
    double d_g = s0 * speed * z / (g * g);
    *d_fc = d_g * (1.0 - decay);
    *d_fs = d_g * decay;
}

typedef struct {
    int n;
    double dt, mass, k, c, ki, s0, s1, v_r, alpha;
    const double *xr, *vr, *fe, *fc, *fs, *s2;
} Plant;

typedef struct { double xr, vr, fe, fc, fs, s2, sxr, svr, sfe, sfc, sfs, ss2; } Inputs;

static inline Inputs inputs(const Plant *p, double t) {
    Inputs in;
    double pos = t / p->dt, w;
    int i;
    if (pos <= 0.0) { i = 0; w = 0.0; }
    else if (pos >= p->n - 1) { i = p->n - 2; w = 1.0; }
    else { i = (int)pos; w = pos - i; }
    double dxr = p->xr[i + 1] - p->xr[i], dvr = p->vr[i + 1] - p->vr[i];
    double dfe = p->fe[i + 1] - p->fe[i], dfc = p->fc[i + 1] - p->fc[i];
    double dfs = p->fs[i + 1] - p->fs[i], ds2 = p->s2[i + 1] - p->s2[i];
    in.xr = p->xr[i] + w * dxr; in.vr = p->vr[i] + w * dvr; in.fe = p->fe[i] + w * dfe;
    in.fc = p->fc[i] + w * dfc; in.fs = p->fs[i] + w * dfs; in.s2 = p->s2[i] + w * ds2;
    in.sxr = dxr / p->dt; in.svr = dvr / p->dt; in.sfe = dfe / p->dt;
    in.sfc = dfc / p->dt; in.sfs = dfs / p->dt; in.ss2 = ds2 / p->dt;
    return in;
}

static inline void plant(const Plant *p, double t, const double *y, double *out) {
    Inputs in = inputs(p, t);
    double v = y[1], z = y[2];
    double g = g_function(fabs(v), in.fc, in.fs, p->v_r, p->alpha);
    double dz = v - p->s0 * fabs(v) * z / g;
    double friction = p->s0 * z + p->s1 * dz + in.s2 * v;
    out[0] = v;
    out[1] = (p->k * (in.xr - y[0]) + p->c * (in.vr - v) + p->ki * y[3] + in.fe - friction)
             / p->mass;
    out[2] = dz;
    out[3] = in.xr - y[0];
}

/* Rodas3 (Sandu et al. 1997) in the KPP form */
static const double GAMMA0 = 0.5;
static const double A[4][4] = {{0, 0, 0, 0}, {0, 0, 0, 0}, {2, 0, 0, 0}, {2, 0, 1, 0}};
static const double C[4][4] = {{0, 0, 0, 0}, {4, 0, 0, 0}, {1, -1, 0, 0}, {1, -1, -8.0 / 3.0, 0}};
static const double M[4] = {2, 0, 1, 1};
static const double E[4] = {0, 0, 0, 1};
static const double ALPHA[4] = {0, 0, 1, 1};
static const double GAMMA[4] = {0.5, 1.5, 0, 0};
static const int REUSE[4] = {1, 1, 0, 0};

static long run(const Plant *p, double rtol, const double atol_in[4], double atol_f,
                double *out_y /* n x 4 */) {
    int n = p->n;
    double dt = p->dt, t_end = dt * (n - 1);
    double y[4] = {0, 0, 0, 0}, atol[4] = {atol_in[0], atol_in[1], atol_in[2],
                                          atol_in[0] * (t_end > 1.0 ? t_end : 1.0)};
    double K[4][4] = {{0}}, stage[4], f_stage[4], rhs[4], y_new[4], f0[4], f1[4];
    plant(p, 0.0, y, f0);
    for (int q = 0; q < 4; q++) out_y[q] = y[q];
    double t = 0.0, h = dt < 1e-5 ? dt : 1e-5, exponent = -1.0 / 3.0;
    int next_out = 1;
    long accepted = 0, rejected = 0;
    double mass = p->mass, k = p->k, c = p->c, ki = p->ki, s0 = p->s0, s1 = p->s1;
    while (next_out < n && accepted + rejected < 50000000) {
        if (t + h > t_end) h = t_end - t;
        Inputs in = inputs(p, t);
        double v = y[1], z = y[2], d_v, d_z, d_fc, d_fs;
        lugre_partials(v, z, s0, in.fc, in.fs, p->v_r, p->alpha, &d_v, &d_z, &d_fc, &d_fs);
        double f_v = s1 * d_v + in.s2, f_z = s0 + s1 * d_z;
        double load = k * (in.xr - y[0]) + c * (in.vr - v) + ki * y[3] + in.fe;
        double rate = k * (in.sxr - v) + c * in.svr + in.sfe + ki * (in.xr - y[0]);
        if (load * rate > 0.0) {
            double margin = g_function(fabs(v), in.fc, in.fs, p->v_r, p->alpha) - fabs(load);
            if (margin > 0.0) h = fmin(h, fmax(0.5 * margin / fabs(rate), 1e-3 * dt));
        }
        if (v * f0[1] < 0.0 && fabs(v) > 1e-3 * p->v_r)
            h = fmin(h, fmax(0.5 * fabs(v / f0[1]), 1e-3 * dt));
        double trace = -(c + f_v) / mass + d_z;
        double det = -(c + f_v) / mass * d_z + f_z * d_v / mass;
        double disc = 0.25 * trace * trace - det;
        double growth = disc > 0.0 ? 0.5 * trace + sqrt(disc) : 0.5 * trace;
        if (growth > 0.0) h = fmin(h, 1.0 / growth);
        int stiff = h * (fabs(trace) + sqrt(fabs(det))) > 1.0;
        if (t + h > t_end) h = t_end - t;
        double dzdt_t = d_fc * in.sfc + d_fs * in.sfs;
        double ft_v = (k * in.sxr + c * in.svr + in.sfe - s1 * dzdt_t - v * in.ss2) / mass;
        double gi = 1.0 / (h * GAMMA0), a_ = k / mass, b_ = (c + f_v) / mass, cz = f_z / mass;
        double d_ = ki / mass, inv_g = 1.0 / gi, inv_gz = 1.0 / (gi - d_z);
        double inv_den = 1.0 / (a_ * inv_g + gi + b_ + cz * d_v * inv_gz + d_ * inv_g * inv_g);
        for (int s = 0; s < 4; s++) {
            if (REUSE[s]) {
                for (int q = 0; q < 4; q++) f_stage[q] = f0[q];
            } else {
                for (int q = 0; q < 4; q++) {
                    double acc = 0.0;
                    for (int j = 0; j < s; j++) acc += A[s][j] * K[j][q];
                    stage[q] = y[q] + acc;
                }
                plant(p, t + ALPHA[s] * h, stage, f_stage);
            }
            for (int q = 0; q < 4; q++) {
                double acc = 0.0;
                for (int j = 0; j < s; j++) acc += C[s][j] * K[j][q];
                rhs[q] = f_stage[q] + acc / h;
            }
            double hg = h * GAMMA[s];
            double rx = rhs[0], rv = rhs[1] + hg * ft_v, rz = rhs[2] + hg * dzdt_t;
            double re = rhs[3] + hg * in.sxr;
            double kv = (rv - a_ * rx * inv_g - cz * rz * inv_gz + d_ * re * inv_g
                         - d_ * rx * inv_g * inv_g) * inv_den;
            double kx = (rx + kv) * inv_g;
            K[s][0] = kx;
            K[s][1] = kv;
            K[s][2] = (rz + d_v * kv) * inv_gz;
            K[s][3] = (re - kx) * inv_g;
        }
        double err = 0.0, err_f = 0.0;
        for (int q = 0; q < 4; q++) {
            double acc_m = 0.0, acc_e = 0.0;
            for (int j = 0; j < 4; j++) { acc_m += M[j] * K[j][q]; acc_e += E[j] * K[j][q]; }
            y_new[q] = y[q] + acc_m;
            double scale = atol[q] + rtol * fmax(fabs(y[q]), fabs(y_new[q]));
            err += (acc_e / scale) * (acc_e / scale);
            if (q == 1) err_f += f_v * acc_e;
            else if (q == 2) err_f += f_z * acc_e;
        }
        double force_n = s0 * z + s1 * f0[2] + in.s2 * v;
        double ef = err_f / (atol_f + rtol * fabs(force_n));
        err = sqrt((err + ef * ef) / 5);
        double factor;
        if (err <= 1.0 && isfinite(err)) {
            double t_new = t + h;
            plant(p, t_new, y_new, f1);
            while (next_out < n && next_out * dt <= t_new + 1e-12 * dt) {
                double th = (next_out * dt - t) / h, t2 = th * th, t3 = t2 * th;
                double h00 = 2 * t3 - 3 * t2 + 1, h10 = (t3 - 2 * t2 + th) * h;
                double h01 = 3 * t2 - 2 * t3, h11 = (t3 - t2) * h;
                for (int q = 0; q < 4; q++) {
                    if (stiff && (q == 1 || q == 2))
                        out_y[4 * next_out + q] = y[q] + th * (y_new[q] - y[q]);
                    else
                        out_y[4 * next_out + q] = h00 * y[q] + h10 * f0[q] + h01 * y_new[q]
                                                  + h11 * f1[q];
                }
                next_out++;
            }
            t = t_new;
            for (int q = 0; q < 4; q++) { y[q] = y_new[q]; f0[q] = f1[q]; }
            accepted++;
            factor = fmin(6.0, 0.9 * pow(fmax(err, 1e-10), exponent));
        } else {
            rejected++;
            factor = !isfinite(err) ? 0.2 : fmax(0.2, 0.9 * pow(err, exponent));
        }
        h *= factor;
    }
    return accepted;
}

int main(int argc, char **argv) {
    if (argc != 20) { fprintf(stderr, "usage: see the header of rodas3.c\n"); return 2; }
    double a[18];
    for (int i = 1; i < 19; i++) a[i - 1] = atof(argv[i]);
    double duration = a[0], dt = a[1];
    int n = (int)llround(duration / dt) + 1, reps = (int)a[17];
    double *xr = malloc(n * sizeof(double)), *vr = malloc(n * sizeof(double));
    double *fe = calloc(n, sizeof(double)), *fc = malloc(n * sizeof(double));
    double *fs = malloc(n * sizeof(double)), *s2 = malloc(n * sizeof(double));
    double *out_y = malloc(4 * n * sizeof(double)), *force = malloc(n * sizeof(double));
    for (int i = 0; i < n; i++) {
        xr[i] = a[4] * (i * dt); vr[i] = a[4]; fc[i] = a[5]; fs[i] = a[6]; s2[i] = a[7];
    }
    Plant p = {n, dt, a[2], a[3], 0.0, 0.0, a[8], a[9], a[10], a[11], xr, vr, fe, fc, fs, s2};
    double atol[4] = {a[13], a[14], a[15], 0.0};
    double best = 1e30;
    long steps = 0;
    for (int r = 0; r < reps; r++) {
        struct timespec t0, t1;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        steps = run(&p, a[12], atol, a[16], out_y);
        for (int i = 0; i < n; i++)
            force[i] = lugre_instant(out_y[4 * i + 1], out_y[4 * i + 2], p.s0, p.s1, s2[i],
                                     fc[i], fs[i], p.v_r, p.alpha);
        clock_gettime(CLOCK_MONOTONIC, &t1);
        double s = (t1.tv_sec - t0.tv_sec) + 1e-9 * (t1.tv_nsec - t0.tv_nsec);
        if (s < best) best = s;
    }
    FILE *f = fopen(argv[19], "wb");
    if (!f) { perror(argv[19]); return 1; }
    fwrite(force, sizeof(double), n, f);
    fclose(f);
    printf("%.9f %ld\n", best, steps);
    return 0;
}
