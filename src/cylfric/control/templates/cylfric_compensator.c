/* cylfric friction compensator: one controller sample (C99, no allocation).
 *
 * Written by cylfric (cylfric.control.export; see docs/control.md). This file is the same for
 * every datasheet; the datasheet's friction laws, the axis and the controller constants are
 * generated into cylfric_compensator_params.h. It is cylfric.control.kernel.compensator_step
 * line by line (SI units):
 *
 *   v      = (x - x_prev) / T  (0 at the first sample), or the input velocity when
 *            CYLFRIC_VELOCITY_INPUT is 1
 *   p      = operating pressure of (p_A, p_B) by the datasheet's rule
 *   none:    F = 0
 *   coulomb: F = F_c0 tanh(v_ref / v_s)
 *   static:  F = g(|v_ref|) tanh(v_ref / v_s) + sigma_2 v_ref             (thesis eq. 2.7)
 *   lugre:   z^ <- exact solution of dz/dt = v - sigma_0 |v| z / g(v) over T, + k_o e T
 *            F = sigma_0 z^ + sigma_1 (v - sigma_0 |v| z^ / g(v)) + sigma_2 v  (eq. 2.5;
 *            Canudas de Wit et al. 1995)
 *   from the second sample on (the first outputs u_c = 0):
 *   F      = F_prev + a (F - F_prev),  a = CYLFRIC_FORCE_FILTER_GAIN = 1 - exp(-T / tau_f)
 *            (first-order filter on the force estimate; a = 1: none)
 *   R      = (F - F_prev) / T + R_L(F),  R_L(F) = beta C_i F / ((A_A + A_B) / 2)
 *            (A_A / V_A + A_B / V_B)     (the force rate that holds F against the
 *                                          cross-piston leakage C_i)
 *   u_c    = R / G_F,  G_F = beta (A_A K_A / V_A + A_B K_B / V_B)  (the force rate per unit
 *            opening; K_A, K_B = K max(r(dp), sqrt(dp_lam)) over the landings that open
 *            for the sign of R: P->A and B->T for R >= 0, A->T and P->B otherwise)
 *   with V_A = V_A0 + A_A x, V_B = V_B0 + A_B (L - x): x absolute from the cap end.
 *
 * Conventions (x > 0 extends, gauge pressures, u_c > 0 opens P->A, one call every T): see
 * cylfric_compensator.h.
 *
 * Compile: cc -O2 -std=c99 -c cylfric_compensator.c   (link with -lm)
 */
#include <math.h>

#include "cylfric_compensator.h"
#include "cylfric_compensator_params.h"

enum { ROW_F_C, ROW_F_S, ROW_SIGMA_2, ROW_V_R, ROW_ALPHA, ROW_SIGMA_0, ROW_SIGMA_1 };

typedef struct {
    double fc, fs, s2, vr, al, s0, s1;
} cylfric_params;

/* pressure law of a table row (codes: 0 constant, 1 linear, 2 quadratic, 3 exponential) */
static double cylfric_law(int row, double p) {
    const double *r = CYLFRIC_FRICTION[row];
    if (r[0] == 0.0) return r[1];
    if (r[0] == 1.0) return r[1] + r[2] * p;
    if (r[0] == 2.0) return r[1] + p * (r[2] + r[3] * p);
    return r[1] + r[2] * expm1(r[3] * p);
}

static double cylfric_max(double a, double b) { return a > b ? a : b; }

static cylfric_params cylfric_params_at(double p) {
    cylfric_params q;
    q.fc = cylfric_max(cylfric_law(ROW_F_C, p), 1e-9);
    q.fs = cylfric_max(cylfric_law(ROW_F_S, p), 1e-9);
    q.s2 = cylfric_max(cylfric_law(ROW_SIGMA_2, p), 0.0);
    q.vr = cylfric_max(cylfric_law(ROW_V_R, p), 1e-12);
    q.al = cylfric_max(cylfric_law(ROW_ALPHA, p), 1e-3);
    q.s0 = cylfric_max(cylfric_law(ROW_SIGMA_0, p), 1e-9);
    q.s1 = cylfric_max(cylfric_law(ROW_SIGMA_1, p), 0.0);
    return q;
}

static double cylfric_operating_pressure(double pa, double pb) {
#if CYLFRIC_REFERENCE == 0
    (void)pb;
    return pa;
#elif CYLFRIC_REFERENCE == 1
    (void)pa;
    return pb;
#elif CYLFRIC_REFERENCE == 2
    return pa + pb;
#elif CYLFRIC_REFERENCE == 3
    return 0.5 * (pa + pb);
#else
    return pa > pb ? pa : pb;
#endif
}

/* exp(-x), x >= 0 (cylfric.simulate.kernels.exp_neg) */
static double cylfric_exp_neg(double x) {
    if (x < 1e-3)
        return 1.0 - x * (1.0 - x * (0.5 - x * (1.0 / 6.0 - x * (1.0 / 24.0 - x * (1.0 / 120.0)))));
    if (x > 746.0) return 0.0;
    return exp(-x);
}

/* g(|v|) of eq. 2.5 [N] */
static double cylfric_g(double speed, const cylfric_params *q) {
    double u = speed * (1.0 / q->vr), decay;
    if (q->al == 2.0)
        decay = cylfric_exp_neg(u * u);
    else if (q->al == 1.0)
        decay = cylfric_exp_neg(u);
    else
        decay = cylfric_exp_neg(pow(u, q->al));
    return q->fc + (q->fs - q->fc) * decay;
}

/* exact z over a step h at constant v (eq. 2.5) */
static double cylfric_z_step(double z0, double v, double h, const cylfric_params *q) {
    double g, lam, x, z_ss, one_minus_e;
    if (v == 0.0) return z0;
    g = cylfric_g(fabs(v), q);
    lam = q->s0 * fabs(v) / g;
    x = lam * h;
    z_ss = v > 0 ? g / q->s0 : -g / q->s0;
    if (x < 1e-5)
        one_minus_e = x * (1.0 - x * (0.5 - x / 6.0));
    else
        one_minus_e = -expm1(-x);
    return z_ss + (z0 - z_ss) * (1.0 - one_minus_e);
}

/* sign(dp) sqrt(|dp|), linear below the laminar drop [sqrt(Pa)] */
static double cylfric_root(double dp) {
    double a = fabs(dp);
    if (a < CYLFRIC_LAMINAR_DROP) return dp / sqrt(CYLFRIC_LAMINAR_DROP);
    return dp > 0 ? sqrt(a) : -sqrt(a);
}

/* d(A_A p_A - A_B p_B)/dt per unit opening [N/s] in the direction of the sign */
static double cylfric_force_rate_gain(double direction, double x, double pa, double pb) {
    double va = CYLFRIC_DEAD_VOLUME_A + CYLFRIC_AREA_A * x;
    double vb = CYLFRIC_DEAD_VOLUME_B + CYLFRIC_AREA_B * (CYLFRIC_STROKE - x);
    double floor_ = sqrt(CYLFRIC_LAMINAR_DROP), ka, kb;
    if (direction >= 0) {
        ka = CYLFRIC_VALVE_K * cylfric_max(cylfric_root(CYLFRIC_SUPPLY - pa), floor_);
        kb = CYLFRIC_VALVE_K * cylfric_max(cylfric_root(pb - CYLFRIC_TANK), floor_);
    } else {
        ka = CYLFRIC_VALVE_K * cylfric_max(cylfric_root(pa - CYLFRIC_TANK), floor_);
        kb = CYLFRIC_VALVE_K * cylfric_max(cylfric_root(CYLFRIC_SUPPLY - pb), floor_);
    }
    return CYLFRIC_BULK_MODULUS * (CYLFRIC_AREA_A * ka / va + CYLFRIC_AREA_B * kb / vb);
}

/* force rate [N/s] that holds a cylinder force against the cross-piston leakage:
 * beta C_i dp (A_A/V_A + A_B/V_B) with dp = force / ((A_A + A_B)/2) */
static double cylfric_leakage_force_rate(double force, double x) {
    double va = CYLFRIC_DEAD_VOLUME_A + CYLFRIC_AREA_A * x;
    double vb = CYLFRIC_DEAD_VOLUME_B + CYLFRIC_AREA_B * (CYLFRIC_STROKE - x);
    return CYLFRIC_BULK_MODULUS * CYLFRIC_LEAKAGE * force /
           (0.5 * (CYLFRIC_AREA_A + CYLFRIC_AREA_B)) *
           (CYLFRIC_AREA_A / va + CYLFRIC_AREA_B / vb);
}

void cylfric_compensator_init(cylfric_compensator_state *state) {
    state->x_prev = 0.0;
    state->z_hat = 0.0;
    state->f_prev = 0.0;
    state->started = 0.0;
}

int cylfric_compensator_step(int kind, const cylfric_compensator_input *in,
                             cylfric_compensator_state *state, cylfric_compensator_output *out) {
    const double T = CYLFRIC_SAMPLE_TIME;
    double v, comp = 0.0, rate, g, dz;
    int started = state->started > 0.0;
    cylfric_params q;
    out->force = 0.0;
    out->command = 0.0;
    if (kind < CYLFRIC_NONE || kind > CYLFRIC_LUGRE) return -1;
    if (CYLFRIC_VELOCITY_INPUT > 0.0)
        v = in->velocity;
    else
        v = started ? (in->position - state->x_prev) / T : 0.0;
    state->x_prev = in->position;
    if (kind == CYLFRIC_COULOMB) {
        comp = CYLFRIC_COULOMB_FORCE * tanh(in->velocity_reference / CYLFRIC_SMOOTHING_VELOCITY);
    } else if (kind == CYLFRIC_STATIC) {
        q = cylfric_params_at(cylfric_operating_pressure(in->pressure_a, in->pressure_b));
        comp = cylfric_g(fabs(in->velocity_reference), &q) *
                   tanh(in->velocity_reference / CYLFRIC_SMOOTHING_VELOCITY) +
               q.s2 * in->velocity_reference;
    } else if (kind == CYLFRIC_LUGRE) {
        q = cylfric_params_at(cylfric_operating_pressure(in->pressure_a, in->pressure_b));
        state->z_hat = cylfric_z_step(state->z_hat, v, T, &q);
        state->z_hat += CYLFRIC_OBSERVER_GAIN * (in->position_reference - in->position) * T;
        g = cylfric_g(fabs(v), &q);
        dz = v - q.s0 * fabs(v) * state->z_hat / g;
        comp = q.s0 * state->z_hat + q.s1 * dz + q.s2 * v;
    }
    if (started && kind != CYLFRIC_NONE) /* first-order filter on the force */
        comp = state->f_prev + CYLFRIC_FORCE_FILTER_GAIN * (comp - state->f_prev);
    out->force = comp;
    if (started && kind != CYLFRIC_NONE) {
        rate = (comp - state->f_prev) / T + cylfric_leakage_force_rate(comp, in->position);
        out->command = rate / cylfric_force_rate_gain(rate >= 0 ? 1.0 : -1.0, in->position,
                                                       in->pressure_a, in->pressure_b);
    }
    state->f_prev = comp;
    state->started = 1.0;
    return 0;
}
