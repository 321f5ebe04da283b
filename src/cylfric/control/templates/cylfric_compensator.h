/* cylfric friction compensator: the interface (C99, no allocation, no globals written).
 *
 * Written by cylfric (cylfric.control.export; see docs/control.md). One call per controller
 * sample, a pure function of the measurements and a fixed-size state:
 *
 *   cylfric_compensator_state st;
 *   cylfric_compensator_init(&st);
 *   every sample T:  cylfric_compensator_step(CYLFRIC_LUGRE, &in, &st, &out);
 *                    valve command += out.command;  (out.force: the friction estimate [N])
 *
 * Units SI: m, m/s, Pa, N; the command is the valve opening fraction [-].
 */
#ifndef CYLFRIC_COMPENSATOR_H
#define CYLFRIC_COMPENSATOR_H

/* compensator kinds (cylfric.control.kernel.COMPENSATOR_CODES; the oracle is not exportable:
 * it needs the plant's own friction) */
enum { CYLFRIC_NONE = 0, CYLFRIC_COULOMB = 1, CYLFRIC_STATIC = 2, CYLFRIC_LUGRE = 3 };

typedef struct {
    double position;           /* measured rod position x [m] */
    double pressure_a;         /* measured pressure in chamber A [Pa] */
    double pressure_b;         /* measured pressure in chamber B [Pa] */
    double position_reference; /* reference position [m] */
    double velocity_reference; /* reference velocity [m/s] */
} cylfric_compensator_input;

typedef struct {
    double x_prev;  /* previous position sample [m] */
    double z_hat;   /* observer's bristle deflection [m] */
    double f_prev;  /* previous force estimate [N] */
    double started; /* 0 before the first sample, then 1 [-] */
} cylfric_compensator_state;

typedef struct {
    double force;   /* friction force estimate F [N], positive in the direction of motion */
    double command; /* valve command u_c [-]: changes the cylinder force by dF, holds F against leakage */
} cylfric_compensator_output;

void cylfric_compensator_init(cylfric_compensator_state *state);

/* One sample; returns 0, or -1 for an unknown kind (outputs 0, state untouched). */
int cylfric_compensator_step(int kind, const cylfric_compensator_input *in,
                             cylfric_compensator_state *state, cylfric_compensator_output *out);

#endif
