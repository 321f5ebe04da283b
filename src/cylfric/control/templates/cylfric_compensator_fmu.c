/* cylfric friction compensator as an FMI 2.0 co-simulation FMU.
 *
 * Written by cylfric (cylfric.control.export; see docs/control.md). The compensator is
 * cylfric_compensator.c (included below: one translation unit); the kind, the model
 * identifier and the GUID are generated into cylfric_compensator_fmu.h.
 *
 * A sampled controller: every fmi2DoStep is one controller sample with the inputs set at its
 * start (the step must equal the compensator's sample time). The outputs are those of the
 * sample at the current inputs: after fmi2SetReal of an input, fmi2GetReal previews the sample
 * on a copy of the state (direct feedthrough); fmi2DoStep then commits the same sample.
 *
 * Value references: 0 position [m], 1 pressure_a [Pa], 2 pressure_b [Pa],
 * 3 position_reference [m], 4 velocity_reference [m/s], 5 velocity [m/s] (inputs); 6 force
 * [N], 7 command [-] (outputs); 8 z_hat [m] (local). Conventions as cylfric_compensator.h:
 * position absolute from the cap end, gauge pressures, command > 0 opens P->A (extension),
 * the first sample outputs command 0; the command is for the axis baked in at export (listed
 * in modelDescription.xml's description and in cylfric_compensator_params.h).
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "fmi2Functions.h"
#include "cylfric_compensator_fmu.h"
#include "cylfric_compensator.c"

enum { VR_POSITION, VR_PRESSURE_A, VR_PRESSURE_B, VR_POSITION_REFERENCE,
       VR_VELOCITY_REFERENCE, VR_VELOCITY, VR_FORCE, VR_COMMAND, VR_Z_HAT, N_REALS };

typedef struct {
    fmi2Real r[N_REALS];
    cylfric_compensator_state state;
    int pending; /* inputs set since the last committed sample */
    fmi2Real time;
    char name[128];
    const fmi2CallbackFunctions *cb;
    fmi2Boolean logging;
} Instance;

static void log_error(Instance *c, const char *fmt, ...) {
    char buffer[512];
    va_list args;
    if (c == NULL || c->cb == NULL || c->cb->logger == NULL) return;
    va_start(args, fmt);
    vsnprintf(buffer, sizeof buffer, fmt, args);
    va_end(args);
    c->cb->logger(c->cb->componentEnvironment, c->name, fmi2Error, "logStatusError", "%s", buffer);
}

/* one sample at the current inputs on ``state``; the outputs into r */
static void sample(Instance *c, cylfric_compensator_state *state) {
    cylfric_compensator_input in;
    cylfric_compensator_output out;
    in.position = c->r[VR_POSITION];
    in.pressure_a = c->r[VR_PRESSURE_A];
    in.pressure_b = c->r[VR_PRESSURE_B];
    in.position_reference = c->r[VR_POSITION_REFERENCE];
    in.velocity_reference = c->r[VR_VELOCITY_REFERENCE];
    in.velocity = c->r[VR_VELOCITY];
    cylfric_compensator_step(CYLFRIC_FMU_KIND, &in, state, &out);
    c->r[VR_FORCE] = out.force;
    c->r[VR_COMMAND] = out.command;
    c->r[VR_Z_HAT] = state->z_hat;
}

static void preview(Instance *c) {
    cylfric_compensator_state copy = c->state;
    if (c->pending) sample(c, &copy);
}

static void reset(Instance *c) {
    static const fmi2Real starts[N_REALS] = CYLFRIC_FMU_STARTS;
    memcpy(c->r, starts, sizeof c->r);
    cylfric_compensator_init(&c->state);
    c->pending = 1;
    c->time = 0.0;
}

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
    if (fmuType != fmi2CoSimulation || fmuGUID == NULL || strcmp(fmuGUID, MODEL_GUID) != 0) {
        if (functions->logger)
            functions->logger(functions->componentEnvironment, instanceName, fmi2Error,
                              "logStatusError",
                              "co-simulation only, GUID %s expected (got %s)", MODEL_GUID,
                              fmuGUID ? fmuGUID : "(null)");
        return NULL;
    }
    c = (Instance *)functions->allocateMemory(1, sizeof(Instance));
    if (c == NULL) return NULL;
    reset(c);
    snprintf(c->name, sizeof c->name, "%s", instanceName ? instanceName : MODEL_IDENTIFIER_STRING);
    c->cb = functions;
    c->logging = loggingOn;
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
    (void)comp;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component comp) {
    preview((Instance *)comp);
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component comp) {
    (void)comp;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component comp) {
    reset((Instance *)comp);
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[]) {
    Instance *c = (Instance *)comp;
    size_t i;
    preview(c);
    for (i = 0; i < nvr; i++) {
        if (vr[i] >= N_REALS) {
            log_error(c, "unknown value reference %u", vr[i]);
            return fmi2Error;
        }
        value[i] = c->r[vr[i]];
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[]) {
    Instance *c = (Instance *)comp;
    size_t i;
    for (i = 0; i < nvr; i++) {
        if (vr[i] > VR_VELOCITY) {
            log_error(c, "value reference %u is not an input", vr[i]);
            return fmi2Error;
        }
        c->r[vr[i]] = value[i];
        c->pending = 1;
    }
    return fmi2OK;
}

fmi2Status fmi2DoStep(fmi2Component comp, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    Instance *c = (Instance *)comp;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!(fabs(communicationStepSize - CYLFRIC_SAMPLE_TIME) <= 1e-6 * CYLFRIC_SAMPLE_TIME)) {
        log_error(c, "communication step %g s; this compensator samples every %g s", 
                  communicationStepSize, CYLFRIC_SAMPLE_TIME);
        return fmi2Error;
    }
    sample(c, &c->state);
    c->pending = 0;
    c->time = currentCommunicationPoint + communicationStepSize;
    return fmi2OK;
}

#define CYLFRIC_UNSUPPORTED_GET(fn, type)                                                       \
    fmi2Status fn(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, type value[]) {  \
        (void)c; (void)vr; (void)value;                                                        \
        return nvr == 0 ? fmi2OK : fmi2Error;                                                  \
    }
#define CYLFRIC_UNSUPPORTED_SET(fn, type)                                                       \
    fmi2Status fn(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,                  \
                  const type value[]) {                                                        \
        (void)c; (void)vr; (void)value;                                                        \
        return nvr == 0 ? fmi2OK : fmi2Error;                                                  \
    }
CYLFRIC_UNSUPPORTED_GET(fmi2GetInteger, fmi2Integer)
CYLFRIC_UNSUPPORTED_GET(fmi2GetBoolean, fmi2Boolean)
CYLFRIC_UNSUPPORTED_GET(fmi2GetString, fmi2String)
CYLFRIC_UNSUPPORTED_SET(fmi2SetInteger, fmi2Integer)
CYLFRIC_UNSUPPORTED_SET(fmi2SetBoolean, fmi2Boolean)
CYLFRIC_UNSUPPORTED_SET(fmi2SetString, fmi2String)

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s) {
    (void)c; (void)s;
    return fmi2Error;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s) {
    (void)c; (void)s;
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

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                       size_t nvr, const fmi2Integer order[],
                                       const fmi2Real value[]) {
    (void)c; (void)vr; (void)order; (void)value;
    return nvr == 0 ? fmi2OK : fmi2Error;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t nvr, const fmi2Integer order[],
                                        fmi2Real value[]) {
    (void)c; (void)vr; (void)order; (void)value;
    return nvr == 0 ? fmi2OK : fmi2Error;
}

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

/* model-exchange functions: not offered (co-simulation only), present for linkers that bind
 * every fmi2 symbol */
fmi2Status fmi2EnterEventMode(fmi2Component c) { (void)c; return fmi2Error; }
fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *i) { (void)c; (void)i; return fmi2Error; }
fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) { (void)c; return fmi2Error; }
fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean a, fmi2Boolean *b,
                                       fmi2Boolean *d) { (void)c; (void)a; (void)b; (void)d; return fmi2Error; }
fmi2Status fmi2SetTime(fmi2Component c, fmi2Real t) { (void)c; (void)t; return fmi2Error; }
fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t n) { (void)c; (void)x; (void)n; return fmi2Error; }
fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real d[], size_t n) { (void)c; (void)d; (void)n; return fmi2Error; }
fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real e[], size_t n) { (void)c; (void)e; (void)n; return fmi2Error; }
fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t n) { (void)c; (void)x; (void)n; return fmi2Error; }
fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x[], size_t n) { (void)c; (void)x; (void)n; return fmi2Error; }
