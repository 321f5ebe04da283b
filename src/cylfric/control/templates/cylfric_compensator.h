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
 * Units SI: m, m/s, Pa, N; the command is the valve opening fraction [-] (1: the opening
 * that passes the valve's nominal flow at its nominal drop), added to the position
 * controller's command before the valve.
 *
 * The contract (the numbers in cylfric_compensator_params.h):
 * - ONE CALL PER SAMPLE, EVERY CYLFRIC_SAMPLE_TIME. Unless exported with the velocity
 *   input (CYLFRIC_VELOCITY_INPUT 1: the step reads in->velocity), the step
 *   takes v = (x - x_prev) / CYLFRIC_SAMPLE_TIME, and the command the force change over that
 *   period. Calling it at another rate, twice in one sample, or skipping samples gives a
 *   wrong velocity, observer and command. After a pause, call cylfric_compensator_init.
 * - POSITION ABSOLUTE FROM THE CAP END: x = 0 with the piston against chamber A's end
 *   (chamber A then holds its dead volume CYLFRIC_DEAD_VOLUME_A), x = CYLFRIC_STROKE fully
 *   extended; position_reference in the same frame. The chamber volumes V_A = V_A0 + A_A x,
 *   V_B = V_B0 + A_B (L - x) set the command's gain: an offset origin scales the command.
 * - SIGNS: x and v > 0 extend; pressures are gauge [Pa] (as CYLFRIC_SUPPLY, CYLFRIC_TANK);
 *   command > 0 opens the valve P->A and B->T (extension, raises A_A p_A - A_B p_B);
 *   force > 0 is friction in the direction of motion (what the cylinder must add).
 * - THE AXIS IS BAKED IN: the command uses the axis's areas, volumes, valve coefficient,
 *   supply, tank, bulk modulus and leakage, written at export into
 *   cylfric_compensator_params.h (its comment lists them with units; CYLFRIC_DEFAULT_AXIS
 *   is 1 when they are cylfric's default axis, not yours). force does not use them (only
 *   the datasheet and the sample time; kind coulomb: F_c at the axis's rest pressures).
 *   On another axis, export again with its axis.toml, or use force through your own
 *   force-to-valve path.
 * - FIRST SAMPLE: after init, the first step outputs command 0 (no previous sample: v = 0,
 *   no force change) and the LuGre observer's z_hat starts at 0 (no bristle deflection);
 *   force is already the estimate at that sample. Start with the axis at rest.
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
    double velocity;           /* measured rod velocity [m/s]; read only when
                                  CYLFRIC_VELOCITY_INPUT is 1 (else set it to 0) */
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
