/* cylfric FMU: pressure-dependent LuGre friction of a hydraulic cylinder (FMI 2.0,
 * model exchange and co-simulation in one binary).
 *
 * Written by cylfric (cylfric.export.fmu; see docs/export_fmu_matlab.md). The model-specific part (value references, default
 * parameter values, the pressure law of each friction parameter, the operating-pressure
 * rule) is generated into cylfric_model.h; this file is the same for every model.
 *
 * Equations (SI: N, m, s, Pa), thesis Perez Dorado (Linkoping 2016):
 *   p      = operating pressure of (pressure_a, pressure_b) by the datasheet's rule
 *   theta  = pressure law of each parameter at p (constant, linear, quadratic, exponential)
 *   g(v)   = F_c + (F_s - F_c) exp(-(|v|/v_r)^alpha)                       eq. 2.5
 *   dz/dt  = v - sigma_0 |v| z / g(v)                                      eq. 2.5
 *   F      = sigma_0 z + sigma_1 dz/dt + sigma_2 v                         eq. 2.5
 * Steady state (dz/dt = 0): F = sign(v) (g(v) + sigma_2 |v|)                eq. 2.7
 *
 * Co-simulation: fmi2DoStep integrates z with the exact solution of eq. 2.5 for a velocity
 * held over a substep (exponential decay towards z_ss = sign(v) g(v) / sigma_0), with the
 * inputs taken at the middle of each substep (linear in time when the master sets input
 * derivatives, held otherwise). The update is unconditionally stable for any sigma_0 and
 * step, and exact for held inputs.
 *
 * Element "cylinder" (CYLFRIC_CYLINDER = 1) adds the moving mass m driven by the input force
 * and/or a position servo (gains kp, kd on the reference inputs):
 *   m dv/dt = force + kp (x_ref - x) + kd (v_ref - v) + area_a p_a - area_b p_b - F    eq. 3.1
 *   dx/dt = v
 * with states position, velocity, z; its co-simulation step is cylfric's fixed-step impulse
 * scheme (cylfric.simulate, method "fixed"): midpoint velocity, exact z for it, friction as
 * its impulse over the substep, the new velocity by a quasi-Newton iteration that converges
 * for any sigma_0 and step.
 *
 * Compile (Linux):  cc -shared -fPIC -O2 -ffp-contract=off -I. cylfric_fmu.c -o <id>.so -lm
 */

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "fmi2Functions.h"
#include "cylfric_model.h"

/* friction parameters at an operating pressure, the order of cylfric_params_at() */
enum { P_F_C, P_F_S, P_SIGMA_2, P_V_R, P_ALPHA, P_SIGMA_0, P_SIGMA_1, N_PRM };

#if defined(_MSC_VER)
#define CYLFRIC_INLINE __inline
#else
#define CYLFRIC_INLINE inline
#endif

/* pressure laws (cylfric.friction.pressure), p in Pa; inline: a model uses some of them */
static CYLFRIC_INLINE fmi2Real law_constant(fmi2Real p, fmi2Real intercept) {
    (void)p;
    return intercept;
}

static CYLFRIC_INLINE fmi2Real law_linear(fmi2Real p, fmi2Real intercept, fmi2Real slope) {
    return intercept + slope * p;
}

static CYLFRIC_INLINE fmi2Real law_quadratic(fmi2Real p, fmi2Real intercept, fmi2Real slope,
                                             fmi2Real curvature) {
    return intercept + slope * p + curvature * p * p;
}

/* a + b (exp(c p) - 1), written by its initial slope b c as cylfric does, so that it stays
 * well posed as c -> 0 (|c| below 1e-14 1/Pa is taken as 1e-14) */
static CYLFRIC_INLINE fmi2Real law_exponential(fmi2Real p, fmi2Real intercept,
                                               fmi2Real amplitude, fmi2Real rate) {
    fmi2Real c = fabs(rate) < 1e-14 ? 1e-14 : rate;
    return intercept + amplitude * rate * expm1(c * p) / c;
}

#include "cylfric_params.h"

typedef enum { ST_INSTANTIATED, ST_INIT, ST_RUNNING, ST_TERMINATED } ModelState;

typedef struct {
    fmi2Real r[N_REALS];
    fmi2Real du[N_REALS]; /* first derivatives of the inputs (co-simulation) */
    fmi2Real time;
    fmi2Type type;
    char name[128];
    const fmi2CallbackFunctions *cb;
    fmi2Boolean logging;
    ModelState state;
} Instance;

static void logf_(Instance *c, fmi2Status status, const char *category, const char *fmt, ...) {
    char buffer[512];
    va_list args;
    if (c == NULL || c->cb == NULL || c->cb->logger == NULL) return;
    if (!c->logging && status == fmi2OK) return;
    va_start(args, fmt);
    vsnprintf(buffer, sizeof buffer, fmt, args);
    va_end(args);
    c->cb->logger(c->cb->componentEnvironment, c->name, status, category, "%s", buffer);
}

static fmi2Real operating_pressure(fmi2Real pa, fmi2Real pb) {
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

/* g(v) of eq. 2.5 [N]; returns 0 when the parameters make it non-positive */
static int g_function(Instance *c, fmi2Real v, const fmi2Real *prm, fmi2Real p, fmi2Real *g) {
    fmi2Real speed = fabs(v);
    *g = prm[P_F_C] + (prm[P_F_S] - prm[P_F_C]) * exp(-pow(speed / prm[P_V_R], prm[P_ALPHA]));
    if (!(*g > 0) || !isfinite(*g) || !(prm[P_SIGMA_0] >= 0)) {
        logf_(c, fmi2Error, "logStatusError",
              "g(v) = %g N at v = %g m/s and operating pressure %g Pa (sigma_0 = %g N/m): "
              "F_c and F_s must be > 0 N and sigma_0 >= 0 N/m; check the parameters and the "
              "pressures (in Pa)", *g, v, p, prm[P_SIGMA_0]);
        return 0;
    }
    return 1;
}

/* the outputs and the derivative at the current inputs and state */
static fmi2Status compute(Instance *c) {
    fmi2Real prm[N_PRM], g, v, z, dz;
    fmi2Real p = operating_pressure(c->r[VR_PRESSURE_A], c->r[VR_PRESSURE_B]);
    cylfric_params_at(c->r, p, prm);
    v = c->r[VR_VELOCITY];
    z = c->r[VR_Z];
    if (!g_function(c, v, prm, p, &g)) return fmi2Error;
    dz = v - prm[P_SIGMA_0] * fabs(v) * z / g;                                /* eq. 2.5 */
    c->r[VR_DER_Z] = dz;
    c->r[VR_FRICTION_FORCE] = prm[P_SIGMA_0] * z + prm[P_SIGMA_1] * dz + prm[P_SIGMA_2] * v;
    c->r[VR_OPERATING_PRESSURE] = p;
#if CYLFRIC_CYLINDER
    if (!(c->r[VR_MASS] > 0)) {
        logf_(c, fmi2Error, "logStatusError", "mass = %g kg; expected > 0 kg", c->r[VR_MASS]);
        return fmi2Error;
    }
    c->r[VR_DER_VELOCITY] =
        (c->r[VR_FORCE] + c->r[VR_KP] * (c->r[VR_POSITION_REFERENCE] - c->r[VR_POSITION]) +
         c->r[VR_KD] * (c->r[VR_VELOCITY_REFERENCE] - v) + c->r[VR_AREA_A] * c->r[VR_PRESSURE_A] -
         c->r[VR_AREA_B] * c->r[VR_PRESSURE_B] - c->r[VR_FRICTION_FORCE]) /
        c->r[VR_MASS]; /* eq. 3.1 */
#endif
    return fmi2OK;
}

static int is_input(fmi2ValueReference vr) { return vr < N_REALS && IS_INPUT[vr]; }

static int is_settable(fmi2ValueReference vr) { return vr < N_REALS && IS_SETTABLE[vr]; }

/* ------------------------------------------------------------------ common functions */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }

const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component comp, fmi2Boolean loggingOn, size_t n,
                               const fmi2String categories[]) {
    (void)n;
    (void)categories;
    ((Instance *)comp)->logging = loggingOn;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn) {
    Instance *c;
    (void)fmuResourceLocation;
    (void)visible;
    if (functions == NULL || functions->allocateMemory == NULL) return NULL;
    if (fmuGUID == NULL || strcmp(fmuGUID, MODEL_GUID) != 0) {
        if (functions->logger)
            functions->logger(functions->componentEnvironment, instanceName, fmi2Error,
                              "logStatusError", "GUID %s does not match this binary (%s)",
                              fmuGUID ? fmuGUID : "(null)", MODEL_GUID);
        return NULL;
    }
    c = (Instance *)functions->allocateMemory(1, sizeof(Instance));
    if (c == NULL) return NULL;
    memcpy(c->r, DEFAULT_REALS, sizeof c->r);
    memset(c->du, 0, sizeof c->du);
    c->time = 0.0;
    c->type = fmuType;
    snprintf(c->name, sizeof c->name, "%s", instanceName ? instanceName : MODEL_IDENTIFIER_STRING);
    c->cb = functions;
    c->logging = loggingOn;
    c->state = ST_INSTANTIATED;
    return c;
}

void fmi2FreeInstance(fmi2Component comp) {
    Instance *c = (Instance *)comp;
    if (c != NULL && c->cb != NULL && c->cb->freeMemory != NULL) c->cb->freeMemory(c);
}

fmi2Status fmi2SetupExperiment(fmi2Component comp, fmi2Boolean toleranceDefined,
                               fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    ((Instance *)comp)->time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component comp) {
    ((Instance *)comp)->state = ST_INIT;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component comp) {
    Instance *c = (Instance *)comp;
    if (!(c->r[VR_MAX_SUBSTEP] > 0)) {
        logf_(c, fmi2Error, "logStatusError", "max_substep = %g s; expected > 0 s",
              c->r[VR_MAX_SUBSTEP]);
        return fmi2Error;
    }
    c->state = ST_RUNNING;
    return compute(c);
}

fmi2Status fmi2Terminate(fmi2Component comp) {
    ((Instance *)comp)->state = ST_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component comp) {
    Instance *c = (Instance *)comp;
    memcpy(c->r, DEFAULT_REALS, sizeof c->r);
    memset(c->du, 0, sizeof c->du);
    c->time = 0.0;
    c->state = ST_INSTANTIATED;
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[]) {
    Instance *c = (Instance *)comp;
    size_t i;
    if (nvr > 0 && c->state != ST_INSTANTIATED && compute(c) != fmi2OK) return fmi2Error;
    for (i = 0; i < nvr; i++) {
        if (vr[i] >= N_REALS) {
            logf_(c, fmi2Error, "logStatusError", "unknown value reference %u", vr[i]);
            return fmi2Error;
        }
        value[i] = c->r[vr[i]];
    }
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[]) {
    (void)c; (void)vr; (void)value;
    return nvr == 0 ? fmi2OK : fmi2Error;
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[]) {
    (void)c; (void)vr; (void)value;
    return nvr == 0 ? fmi2OK : fmi2Error;
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[]) {
    (void)c; (void)vr; (void)value;
    return nvr == 0 ? fmi2OK : fmi2Error;
}

fmi2Status fmi2SetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[]) {
    Instance *c = (Instance *)comp;
    size_t i;
    for (i = 0; i < nvr; i++) {
        if (vr[i] >= N_REALS || !is_settable(vr[i])) {
            logf_(c, fmi2Error, "logStatusError", "value reference %u cannot be set", vr[i]);
            return fmi2Error;
        }
        c->r[vr[i]] = value[i];
        if (is_input(vr[i])) c->du[vr[i]] = 0.0; /* held unless derivatives follow */
    }
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[]) {
    (void)c; (void)vr; (void)value;
    return nvr == 0 ? fmi2OK : fmi2Error;
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[]) {
    (void)c; (void)vr; (void)value;
    return nvr == 0 ? fmi2OK : fmi2Error;
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[]) {
    (void)c; (void)vr; (void)value;
    return nvr == 0 ? fmi2OK : fmi2Error;
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s) {
    (void)s;
    logf_((Instance *)c, fmi2Error, "logStatusError", "fmi2GetFMUstate is not supported");
    return fmi2Error;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s) {
    (void)s;
    logf_((Instance *)c, fmi2Error, "logStatusError", "fmi2SetFMUstate is not supported");
    return fmi2Error;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s) {
    (void)c; (void)s;
    return fmi2Error;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *size) {
    (void)c; (void)s; (void)size;
    return fmi2Error;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t n) {
    (void)c; (void)s; (void)b; (void)n;
    return fmi2Error;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte b[], size_t n,
                                   fmi2FMUstate *s) {
    (void)c; (void)b; (void)n; (void)s;
    return fmi2Error;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[],
                                        size_t nu, const fmi2ValueReference z[], size_t nz,
                                        const fmi2Real dv[], fmi2Real dz[]) {
    (void)c; (void)u; (void)nu; (void)z; (void)nz; (void)dv; (void)dz;
    return fmi2Error;
}

/* ------------------------------------------------------------------ model exchange */

fmi2Status fmi2EnterEventMode(fmi2Component c) {
    (void)c;
    return fmi2OK;
}

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *info) {
    (void)c;
    info->newDiscreteStatesNeeded = fmi2False;
    info->terminateSimulation = fmi2False;
    info->nominalsOfContinuousStatesChanged = fmi2False;
    info->valuesOfContinuousStatesChanged = fmi2False;
    info->nextEventTimeDefined = fmi2False;
    info->nextEventTime = 0.0;
    return fmi2OK;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) {
    (void)c;
    return fmi2OK;
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation) {
    (void)c;
    (void)noSetFMUStatePriorToCurrentPoint;
    *enterEventMode = fmi2False;
    *terminateSimulation = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
    ((Instance *)c)->time = time;
    return fmi2OK;
}

fmi2Status fmi2SetContinuousStates(fmi2Component comp, const fmi2Real x[], size_t nx) {
    Instance *c = (Instance *)comp;
    size_t i;
    if (nx != N_STATES) return fmi2Error;
    for (i = 0; i < nx; i++) c->r[STATE_VRS[i]] = x[i];
    return fmi2OK;
}

fmi2Status fmi2GetDerivatives(fmi2Component comp, fmi2Real derivatives[], size_t nx) {
    Instance *c = (Instance *)comp;
    size_t i;
    if (nx != N_STATES) return fmi2Error;
    if (compute(c) != fmi2OK) return fmi2Error;
    for (i = 0; i < nx; i++) derivatives[i] = c->r[DERIVATIVE_VRS[i]];
    return fmi2OK;
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real indicators[], size_t ni) {
    (void)c;
    (void)indicators;
    return ni == 0 ? fmi2OK : fmi2Error;
}

fmi2Status fmi2GetContinuousStates(fmi2Component comp, fmi2Real x[], size_t nx) {
    Instance *c = (Instance *)comp;
    size_t i;
    if (nx != N_STATES) return fmi2Error;
    for (i = 0; i < nx; i++) x[i] = c->r[STATE_VRS[i]];
    return fmi2OK;
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx) {
    size_t i;
    (void)c;
    if (nx != N_STATES) return fmi2Error;
    for (i = 0; i < nx; i++) x_nominal[i] = STATE_NOMINALS[i];
    return fmi2OK;
}

/* ------------------------------------------------------------------ co-simulation */

fmi2Status fmi2SetRealInputDerivatives(fmi2Component comp, const fmi2ValueReference vr[],
                                       size_t nvr, const fmi2Integer order[],
                                       const fmi2Real value[]) {
    Instance *c = (Instance *)comp;
    size_t i;
    for (i = 0; i < nvr; i++) {
        if (!is_input(vr[i]) || order[i] != 1) {
            logf_(c, fmi2Error, "logStatusError",
                  "input derivative of order %d for value reference %u: only first "
                  "derivatives of the inputs are supported", (int)order[i], vr[i]);
            return fmi2Error;
        }
        c->du[vr[i]] = value[i];
    }
    return fmi2OK;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t nvr, const fmi2Integer order[],
                                        fmi2Real value[]) {
    (void)c; (void)vr; (void)order; (void)value;
    return nvr == 0 ? fmi2OK : fmi2Error;
}

#if CYLFRIC_CYLINDER
/* exact z over a substep at constant v: z(h) and the integral of z over the substep
 * (cylfric.simulate.kernels.z_step) */
static void z_step(fmi2Real z0, fmi2Real v, fmi2Real h, fmi2Real s0, fmi2Real g, fmi2Real *z1,
                   fmi2Real *zint) {
    fmi2Real lam, x, z_ss, one_minus_e, integral_factor;
    if (v == 0.0 || !(s0 > 0)) {
        *z1 = z0 + v * h;
        *zint = z0 * h + 0.5 * v * h * h;
        return;
    }
    lam = s0 * fabs(v) / g;
    x = lam * h;
    z_ss = v > 0 ? g / s0 : -g / s0;
    if (x < 1e-5) {
        one_minus_e = x * (1.0 - x * (0.5 - x / 6.0));
        integral_factor = h * (1.0 - x * (0.5 - x / 6.0));
    } else {
        one_minus_e = -expm1(-x);
        integral_factor = one_minus_e / lam;
    }
    *z1 = z_ss + (z0 - z_ss) * (1.0 - one_minus_e);
    *zint = z_ss * h + (z0 - z_ss) * integral_factor;
}

fmi2Status fmi2DoStep(fmi2Component comp, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    Instance *c = (Instance *)comp;
    fmi2Real prm[N_PRM], g, p, w, hs, pa, pb, fext, jac, v1, vm, z1, zint, impulse, dv;
    fmi2Real xr, vr, em, drive;
    fmi2Real x = c->r[VR_POSITION], v = c->r[VR_VELOCITY], z = c->r[VR_Z];
    fmi2Real m = c->r[VR_MASS], k = c->r[VR_KP], cd = c->r[VR_KD];
    int n, j, it;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!(communicationStepSize >= 0) || !(m > 0)) {
        logf_(c, fmi2Error, "logStatusError",
              "communication step %g s, mass %g kg; expected a step >= 0 s and a mass > 0 kg",
              communicationStepSize, m);
        return fmi2Error;
    }
    n = (int)ceil(communicationStepSize / c->r[VR_MAX_SUBSTEP] - 1e-9);
    if (n < 1) n = 1;
    hs = communicationStepSize / n;
    for (j = 0; j < n; j++) {
        w = (j + 0.5) * hs; /* inputs at the middle of the substep */
        pa = c->r[VR_PRESSURE_A] + c->du[VR_PRESSURE_A] * w;
        pb = c->r[VR_PRESSURE_B] + c->du[VR_PRESSURE_B] * w;
        fext = c->r[VR_FORCE] + c->du[VR_FORCE] * w + c->r[VR_AREA_A] * pa - c->r[VR_AREA_B] * pb;
        xr = c->r[VR_POSITION_REFERENCE] + c->du[VR_POSITION_REFERENCE] * w;
        vr = c->r[VR_VELOCITY_REFERENCE] + c->du[VR_VELOCITY_REFERENCE] * w;
        p = operating_pressure(pa, pb);
        cylfric_params_at(c->r, p, prm);
        /* stuck-contact Jacobian: bounds the true one, so the iteration converges */
        jac = m + 0.25 * k * hs * hs + 0.5 * cd * hs +
              0.5 * (0.5 * prm[P_SIGMA_0] * hs * hs + prm[P_SIGMA_1] * hs + prm[P_SIGMA_2] * hs);
        v1 = v;
        for (it = 0; it < 60; it++) {
            vm = 0.5 * (v + v1);
            if (!g_function(c, vm, prm, p, &g)) return fmi2Error;
            z_step(z, vm, hs, prm[P_SIGMA_0], g, &z1, &zint);
            impulse = prm[P_SIGMA_0] * zint + prm[P_SIGMA_1] * (z1 - z) + prm[P_SIGMA_2] * vm * hs;
            em = xr - (x + 0.5 * hs * vm);
            drive = (k * em + cd * (vr - vm) + fext) * hs;
            dv = (m * (v1 - v) - drive + impulse) / jac;
            v1 -= dv;
            if (fabs(dv) <= 1e-10 * (fabs(v1) + 1e-9)) break;
        }
        vm = 0.5 * (v + v1);
        if (!g_function(c, vm, prm, p, &g)) return fmi2Error;
        z_step(z, vm, hs, prm[P_SIGMA_0], g, &z1, &zint);
        x += hs * vm;
        v = v1;
        z = z1;
    }
    c->r[VR_POSITION] = x;
    c->r[VR_VELOCITY] = v;
    c->r[VR_Z] = z;
    c->r[VR_FORCE] += c->du[VR_FORCE] * communicationStepSize;
    c->r[VR_POSITION_REFERENCE] += c->du[VR_POSITION_REFERENCE] * communicationStepSize;
    c->r[VR_VELOCITY_REFERENCE] += c->du[VR_VELOCITY_REFERENCE] * communicationStepSize;
    c->r[VR_PRESSURE_A] += c->du[VR_PRESSURE_A] * communicationStepSize;
    c->r[VR_PRESSURE_B] += c->du[VR_PRESSURE_B] * communicationStepSize;
    c->time = currentCommunicationPoint + communicationStepSize;
    return compute(c);
}
#else
fmi2Status fmi2DoStep(fmi2Component comp, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    Instance *c = (Instance *)comp;
    fmi2Real prm[N_PRM], g, v, p, w, hs, z_ss, pa, pb;
    fmi2Real z = c->r[VR_Z];
    int n, j;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!(communicationStepSize >= 0)) {
        logf_(c, fmi2Error, "logStatusError", "communication step %g s; expected >= 0 s",
              communicationStepSize);
        return fmi2Error;
    }
    n = (int)ceil(communicationStepSize / c->r[VR_MAX_SUBSTEP] - 1e-9);
    if (n < 1) n = 1;
    hs = communicationStepSize / n;
    for (j = 0; j < n; j++) {
        w = (j + 0.5) * hs; /* inputs at the middle of the substep */
        v = c->r[VR_VELOCITY] + c->du[VR_VELOCITY] * w;
        pa = c->r[VR_PRESSURE_A] + c->du[VR_PRESSURE_A] * w;
        pb = c->r[VR_PRESSURE_B] + c->du[VR_PRESSURE_B] * w;
        if (v == 0.0) continue; /* dz/dt = 0 */
        p = operating_pressure(pa, pb);
        cylfric_params_at(c->r, p, prm);
        if (!g_function(c, v, prm, p, &g)) return fmi2Error;
        if (prm[P_SIGMA_0] > 0) {
            /* exact solution of eq. 2.5 at constant v (cylfric.friction.lugre_z_update) */
            z_ss = (v > 0 ? g : -g) / prm[P_SIGMA_0];
            z = z_ss + (z - z_ss) * exp(-prm[P_SIGMA_0] * fabs(v) * hs / g);
        } else {
            z += v * hs;
        }
    }
    c->r[VR_Z] = z;
    c->r[VR_VELOCITY] += c->du[VR_VELOCITY] * communicationStepSize;
    c->r[VR_PRESSURE_A] += c->du[VR_PRESSURE_A] * communicationStepSize;
    c->r[VR_PRESSURE_B] += c->du[VR_PRESSURE_B] * communicationStepSize;
    c->time = currentCommunicationPoint + communicationStepSize;
    return compute(c);
}

#endif

fmi2Status fmi2CancelStep(fmi2Component c) {
    (void)c;
    return fmi2Error;
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    (void)c; (void)s; (void)value;
    return fmi2Discard;
}

fmi2Status fmi2GetRealStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Real *value) {
    Instance *c = (Instance *)comp;
    if (s == fmi2LastSuccessfulTime) {
        *value = c->time;
        return fmi2OK;
    }
    return fmi2Discard;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    (void)c; (void)s; (void)value;
    return fmi2Discard;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    (void)c; (void)s; (void)value;
    return fmi2Discard;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    (void)c; (void)s; (void)value;
    return fmi2Discard;
}
