/* The damper FMU's FMI 2.0 boundary (ecdsim): model exchange and co-simulation.
 *
 * No physics here. model.h, written by ecdsim at export (ecdsim.fmu.native), holds the
 * model: the variables (value references, names, start values, causality, bounds), the
 * physics translated to C from ecdsim's own Python functions (ecdsim.fmu.ctranslate),
 * and three glue functions that read and write the variables by value reference:
 *
 *   model_start_states(r)  the states at initialisation (the damper at ambient)
 *   model_outputs(r)       the outputs from the inputs, parameters and states
 *   model_derivatives(r)   the states' time derivatives
 *
 * This file keeps each instance's variables, enforces FMI 2.0's rules on who may set
 * what and when, and, for co-simulation, integrates the states over a communication
 * step with the classical Runge-Kutta method (RK4) in equal substeps no longer than the
 * parameter max_step, the inputs extrapolated linearly over the step (from the input
 * derivatives the importer set, or from the last two communication points when the
 * parameter input_extrapolation is true, or held). Every instance owns its memory: any
 * number may live in one process. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2.h"

/* Causality of a Real variable (REAL_CAUSALITY in model.h) */
enum { ECD_PARAMETER, ECD_INPUT, ECD_OUTPUT, ECD_LOCAL };

#include "model.h"

#define N_STATES_ALLOC (N_STATES > 0 ? N_STATES : 1)

enum { PHASE_INSTANTIATED, PHASE_INITIALIZATION, PHASE_RUNNING, PHASE_TERMINATED };

/* Everything an FMU state (fmi2GetFMUstate) saves: plain numbers, no pointers. */
typedef struct {
    unsigned int magic;
    double r[N_REAL];
    fmi2Boolean b[N_BOOLEAN];
    double time;
    int phase;
    double previous_input[N_INPUTS];
    double previous_step;
    int has_previous;
    double input_slope[N_INPUTS];
    int has_input_slope[N_INPUTS];
} Values;

#define VALUES_MAGIC 0xEC05F002u

typedef struct {
    Values v;
    fmi2Type type;
    fmi2Boolean logging;
    fmi2CallbackLogger logger;
    fmi2CallbackAllocateMemory allocate_memory;
    fmi2CallbackFreeMemory free_memory;
    fmi2ComponentEnvironment environment;
    char *name;
} Instance;

static void *allocate(Instance *m, size_t size) {
    if (m != NULL && m->allocate_memory != NULL) return m->allocate_memory(1, size);
    return calloc(1, size);
}

static void release(Instance *m, void *pointer) {
    if (pointer == NULL) return;
    if (m != NULL && m->free_memory != NULL) {
        m->free_memory(pointer);
    } else {
        free(pointer);
    }
}

/* Log through the importer's logger; errors always, the rest with debug logging on. */
static void log_message(Instance *m, fmi2Status status, const char *category, const char *format,
                        ...) {
    char text[512];
    char escaped[1024];
    size_t i, j = 0;
    va_list args;
    if (m == NULL || m->logger == NULL) return;
    if (status < fmi2Error && !m->logging) return;
    va_start(args, format);
    vsnprintf(text, sizeof text, format, args);
    va_end(args);
    /* The logger reads the message as a printf format: escape its percent signs. */
    for (i = 0; text[i] != '\0' && j + 2 < sizeof escaped; i++) {
        if (text[i] == '%') escaped[j++] = '%';
        escaped[j++] = text[i];
    }
    escaped[j] = '\0';
    m->logger(m->environment, m->name, status, category, escaped);
}

static fmi2Status fail(Instance *m, const char *function, const char *format, ...) {
    char text[400];
    va_list args;
    va_start(args, format);
    vsnprintf(text, sizeof text, format, args);
    va_end(args);
    log_message(m, fmi2Error, "logStatusError", "%s: %s", function, text);
    return fmi2Error;
}

static void start_values(Instance *m) {
    memset(&m->v, 0, sizeof m->v);
    m->v.magic = VALUES_MAGIC;
    memcpy(m->v.r, REAL_START, sizeof m->v.r);
    memcpy(m->v.b, BOOLEAN_START, sizeof m->v.b);
    m->v.phase = PHASE_INSTANTIATED;
}

/* Outputs and derivatives from the current inputs, parameters and states. */
static void evaluate(Instance *m) {
    if (m->v.phase <= PHASE_INITIALIZATION) model_start_states(m->v.r);
    model_outputs(m->v.r);
    model_derivatives(m->v.r);
}

static int check_value(Instance *m, const char *function, fmi2ValueReference vr, double value) {
    if (isnan(value) || value < REAL_MIN[vr] || value > REAL_MAX[vr] ||
        (REAL_MIN_OPEN[vr] && value == REAL_MIN[vr])) {
        fail(m, function, "%s = %.17g is outside its range %s%.17g, %.17g] [%s]", REAL_NAME[vr],
             value, REAL_MIN_OPEN[vr] ? "(" : "[", REAL_MIN[vr], REAL_MAX[vr], REAL_UNIT[vr]);
        return 0;
    }
    return 1;
}

/* ---- Common functions ---------------------------------------------------------------- */

FMI2_Export const char *fmi2GetTypesPlatform(void) { return "default"; }

FMI2_Export const char *fmi2GetVersion(void) { return "2.0"; }

FMI2_Export fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn,
                                           size_t nCategories, const fmi2String categories[]) {
    Instance *m = (Instance *)c;
    (void)nCategories;
    (void)categories;
    if (m == NULL) return fmi2Error;
    m->logging = loggingOn;
    return fmi2OK;
}

FMI2_Export fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType,
                                          fmi2String fmuGUID, fmi2String fmuResourceLocation,
                                          const fmi2CallbackFunctions *functions,
                                          fmi2Boolean visible, fmi2Boolean loggingOn) {
    Instance probe;
    Instance *m;
    const char *name = instanceName != NULL ? instanceName : "";
    (void)fmuResourceLocation;
    (void)visible;
    memset(&probe, 0, sizeof probe);
    if (functions != NULL) {
        probe.logger = functions->logger;
        probe.allocate_memory = functions->allocateMemory;
        probe.free_memory = functions->freeMemory;
        probe.environment = functions->componentEnvironment;
    }
    probe.name = (char *)name;
    if (fmuGUID == NULL || strcmp(fmuGUID, MODEL_GUID) != 0) {
        fail(&probe, "fmi2Instantiate",
             "the GUID %s is not this FMU's %s (a modelDescription.xml of another export?)",
             fmuGUID != NULL ? fmuGUID : "(none)", MODEL_GUID);
        return NULL;
    }
    if (fmuType != fmi2ModelExchange && fmuType != fmi2CoSimulation) {
        fail(&probe, "fmi2Instantiate", "unknown FMU type %d", (int)fmuType);
        return NULL;
    }
    m = (Instance *)allocate(&probe, sizeof(Instance));
    if (m == NULL) {
        fail(&probe, "fmi2Instantiate", "out of memory");
        return NULL;
    }
    *m = probe;
    m->name = (char *)allocate(&probe, strlen(name) + 1);
    if (m->name == NULL) {
        release(&probe, m);
        fail(&probe, "fmi2Instantiate", "out of memory");
        return NULL;
    }
    strcpy(m->name, name);
    m->type = fmuType;
    m->logging = loggingOn;
    start_values(m);
    return m;
}

FMI2_Export void fmi2FreeInstance(fmi2Component c) {
    Instance *m = (Instance *)c;
    if (m == NULL) return;
    release(m, m->name);
    release(m, m);
}

FMI2_Export fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined,
                                           fmi2Real tolerance, fmi2Real startTime,
                                           fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    Instance *m = (Instance *)c;
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    if (m == NULL) return fmi2Error;
    if (m->v.phase != PHASE_INSTANTIATED)
        return fail(m, "fmi2SetupExperiment", "only allowed after fmi2Instantiate");
    m->v.time = startTime;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    Instance *m = (Instance *)c;
    if (m == NULL) return fmi2Error;
    if (m->v.phase != PHASE_INSTANTIATED)
        return fail(m, "fmi2EnterInitializationMode", "only allowed after fmi2Instantiate");
    m->v.phase = PHASE_INITIALIZATION;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    Instance *m = (Instance *)c;
    if (m == NULL) return fmi2Error;
    if (m->v.phase != PHASE_INITIALIZATION)
        return fail(m, "fmi2ExitInitializationMode", "not in initialization mode");
    model_start_states(m->v.r);
    m->v.phase = PHASE_RUNNING;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2Terminate(fmi2Component c) {
    Instance *m = (Instance *)c;
    if (m == NULL) return fmi2Error;
    m->v.phase = PHASE_TERMINATED;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2Reset(fmi2Component c) {
    Instance *m = (Instance *)c;
    if (m == NULL) return fmi2Error;
    start_values(m);
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                   fmi2Real value[]) {
    Instance *m = (Instance *)c;
    size_t i;
    if (m == NULL) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    evaluate(m);
    for (i = 0; i < nvr; i++) {
        if (vr[i] >= N_REAL) return fail(m, "fmi2GetReal", "no Real variable %u", vr[i]);
        value[i] = m->v.r[vr[i]];
    }
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[],
                                      size_t nvr, fmi2Integer value[]) {
    (void)value;
    return nvr == 0 ? fmi2OK : fail((Instance *)c, "fmi2GetInteger", "no Integer variable %u", vr[0]);
}

FMI2_Export fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[],
                                      size_t nvr, fmi2Boolean value[]) {
    Instance *m = (Instance *)c;
    size_t i;
    if (m == NULL) return fmi2Error;
    for (i = 0; i < nvr; i++) {
        if (vr[i] >= N_BOOLEAN) return fail(m, "fmi2GetBoolean", "no Boolean variable %u", vr[i]);
        value[i] = m->v.b[vr[i]];
    }
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[],
                                     size_t nvr, fmi2String value[]) {
    (void)value;
    return nvr == 0 ? fmi2OK : fail((Instance *)c, "fmi2GetString", "no String variable %u", vr[0]);
}

FMI2_Export fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                   const fmi2Real value[]) {
    Instance *m = (Instance *)c;
    size_t i;
    if (m == NULL) return fmi2Error;
    for (i = 0; i < nvr; i++) {
        fmi2ValueReference ref = vr[i];
        if (ref >= N_REAL) return fail(m, "fmi2SetReal", "no Real variable %u", ref);
        if (REAL_CAUSALITY[ref] == ECD_PARAMETER) {
            if (m->v.phase > PHASE_INITIALIZATION)
                return fail(m, "fmi2SetReal",
                            "%s is a fixed parameter: set it before fmi2ExitInitializationMode",
                            REAL_NAME[ref]);
        } else if (REAL_CAUSALITY[ref] != ECD_INPUT) {
            return fail(m, "fmi2SetReal", "%s is not an input or a parameter", REAL_NAME[ref]);
        } else if (m->v.phase == PHASE_TERMINATED) {
            return fail(m, "fmi2SetReal", "the FMU is terminated");
        }
        if (!check_value(m, "fmi2SetReal", ref, value[i])) return fmi2Error;
        m->v.r[ref] = value[i];
    }
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[],
                                      size_t nvr, const fmi2Integer value[]) {
    (void)value;
    return nvr == 0 ? fmi2OK : fail((Instance *)c, "fmi2SetInteger", "no Integer variable %u", vr[0]);
}

FMI2_Export fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[],
                                      size_t nvr, const fmi2Boolean value[]) {
    Instance *m = (Instance *)c;
    size_t i;
    if (m == NULL) return fmi2Error;
    for (i = 0; i < nvr; i++) {
        if (vr[i] >= N_BOOLEAN) return fail(m, "fmi2SetBoolean", "no Boolean variable %u", vr[i]);
        if (m->v.phase > PHASE_INITIALIZATION)
            return fail(m, "fmi2SetBoolean",
                        "Boolean %u is a fixed parameter: set it before fmi2ExitInitializationMode",
                        vr[i]);
        m->v.b[vr[i]] = value[i] ? fmi2True : fmi2False;
    }
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[],
                                     size_t nvr, const fmi2String value[]) {
    (void)value;
    return nvr == 0 ? fmi2OK : fail((Instance *)c, "fmi2SetString", "no String variable %u", vr[0]);
}

FMI2_Export fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    Instance *m = (Instance *)c;
    Values *saved;
    if (m == NULL || FMUstate == NULL) return fmi2Error;
    saved = (Values *)*FMUstate;
    if (saved == NULL) {
        saved = (Values *)allocate(m, sizeof(Values));
        if (saved == NULL) return fail(m, "fmi2GetFMUstate", "out of memory");
    }
    *saved = m->v;
    *FMUstate = saved;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    Instance *m = (Instance *)c;
    const Values *saved = (const Values *)FMUstate;
    if (m == NULL) return fmi2Error;
    if (saved == NULL || saved->magic != VALUES_MAGIC)
        return fail(m, "fmi2SetFMUstate", "not a state of this FMU");
    m->v = *saved;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    Instance *m = (Instance *)c;
    if (m == NULL || FMUstate == NULL) return fmi2Error;
    release(m, *FMUstate);
    *FMUstate = NULL;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate,
                                                  size_t *size) {
    (void)c;
    (void)FMUstate;
    *size = sizeof(Values);
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate,
                                             fmi2Byte serializedState[], size_t size) {
    Instance *m = (Instance *)c;
    if (FMUstate == NULL || size != sizeof(Values))
        return fail(m, "fmi2SerializeFMUstate", "expected %u bytes", (unsigned)sizeof(Values));
    memcpy(serializedState, FMUstate, sizeof(Values));
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2DeSerializeFMUstate(fmi2Component c,
                                               const fmi2Byte serializedState[], size_t size,
                                               fmi2FMUstate *FMUstate) {
    Instance *m = (Instance *)c;
    Values copy;
    if (m == NULL || FMUstate == NULL) return fmi2Error;
    if (size != sizeof(Values))
        return fail(m, "fmi2DeSerializeFMUstate", "expected %u bytes", (unsigned)sizeof(Values));
    memcpy(&copy, serializedState, sizeof copy);
    if (copy.magic != VALUES_MAGIC)
        return fail(m, "fmi2DeSerializeFMUstate", "not a state of this FMU");
    if (*FMUstate == NULL) {
        *FMUstate = allocate(m, sizeof(Values));
        if (*FMUstate == NULL) return fail(m, "fmi2DeSerializeFMUstate", "out of memory");
    }
    memcpy(*FMUstate, &copy, sizeof copy);
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetDirectionalDerivative(fmi2Component c,
                                                    const fmi2ValueReference vUnknown_ref[],
                                                    size_t nUnknown,
                                                    const fmi2ValueReference vKnown_ref[],
                                                    size_t nKnown, const fmi2Real dvKnown[],
                                                    fmi2Real dvUnknown[]) {
    (void)vUnknown_ref;
    (void)nUnknown;
    (void)vKnown_ref;
    (void)nKnown;
    (void)dvKnown;
    (void)dvUnknown;
    return fail((Instance *)c, "fmi2GetDirectionalDerivative",
                "not provided (providesDirectionalDerivative is false)");
}

/* ---- Model exchange ------------------------------------------------------------------ */

FMI2_Export fmi2Status fmi2EnterEventMode(fmi2Component c) { return c ? fmi2OK : fmi2Error; }

FMI2_Export fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *eventInfo) {
    if (c == NULL || eventInfo == NULL) return fmi2Error;
    eventInfo->newDiscreteStatesNeeded = fmi2False;
    eventInfo->terminateSimulation = fmi2False;
    eventInfo->nominalsOfContinuousStatesChanged = fmi2False;
    eventInfo->valuesOfContinuousStatesChanged = fmi2False;
    eventInfo->nextEventTimeDefined = fmi2False;
    eventInfo->nextEventTime = 0.0;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) {
    return c ? fmi2OK : fmi2Error;
}

FMI2_Export fmi2Status fmi2CompletedIntegratorStep(fmi2Component c,
                                                   fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                                   fmi2Boolean *enterEventMode,
                                                   fmi2Boolean *terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint;
    if (c == NULL) return fmi2Error;
    if (enterEventMode) *enterEventMode = fmi2False;
    if (terminateSimulation) *terminateSimulation = fmi2False;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
    Instance *m = (Instance *)c;
    if (m == NULL) return fmi2Error;
    m->v.time = time;
    return fmi2OK;
}

static int count_states(Instance *m, const char *function, size_t n) {
    if (n != (size_t)N_STATES) {
        fail(m, function, "this FMU has %d continuous states, not %u", N_STATES, (unsigned)n);
        return 0;
    }
    return 1;
}

FMI2_Export fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    Instance *m = (Instance *)c;
    size_t i;
    if (m == NULL) return fmi2Error;
    if (!count_states(m, "fmi2SetContinuousStates", nx)) return fmi2Error;
    for (i = 0; i < nx; i++) m->v.r[STATE_VR[i]] = x[i];
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx) {
    Instance *m = (Instance *)c;
    size_t i;
    if (m == NULL) return fmi2Error;
    if (!count_states(m, "fmi2GetDerivatives", nx)) return fmi2Error;
    if (nx == 0) return fmi2OK;
    evaluate(m);
    for (i = 0; i < nx; i++) derivatives[i] = m->v.r[DERIVATIVE_VR[i]];
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[],
                                              size_t ni) {
    (void)eventIndicators;
    if (ni != 0)
        return fail((Instance *)c, "fmi2GetEventIndicators", "this FMU has no event indicators");
    return c ? fmi2OK : fmi2Error;
}

FMI2_Export fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    Instance *m = (Instance *)c;
    size_t i;
    if (m == NULL) return fmi2Error;
    if (!count_states(m, "fmi2GetContinuousStates", nx)) return fmi2Error;
    if (m->v.phase <= PHASE_INITIALIZATION) model_start_states(m->v.r);
    for (i = 0; i < nx; i++) x[i] = m->v.r[STATE_VR[i]];
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[],
                                                         size_t nx) {
    Instance *m = (Instance *)c;
    size_t i;
    if (m == NULL) return fmi2Error;
    if (!count_states(m, "fmi2GetNominalsOfContinuousStates", nx)) return fmi2Error;
    for (i = 0; i < nx; i++) x_nominal[i] = STATE_NOMINAL;
    return fmi2OK;
}

/* ---- Co-simulation ------------------------------------------------------------------- */

FMI2_Export fmi2Status fmi2SetRealInputDerivatives(fmi2Component c,
                                                   const fmi2ValueReference vr[], size_t nvr,
                                                   const fmi2Integer order[],
                                                   const fmi2Real value[]) {
    Instance *m = (Instance *)c;
    size_t i;
    int k;
    if (m == NULL) return fmi2Error;
    for (i = 0; i < nvr; i++) {
        if (order[i] != 1)
            return fail(m, "fmi2SetRealInputDerivatives", "only first derivatives (order 1)");
        for (k = 0; k < N_INPUTS; k++) {
            if (INPUT_VR[k] == vr[i]) break;
        }
        if (k == N_INPUTS)
            return fail(m, "fmi2SetRealInputDerivatives", "variable %u is not an input", vr[i]);
        if (!isfinite(value[i]))
            return fail(m, "fmi2SetRealInputDerivatives", "the derivative of %s is not finite",
                        REAL_NAME[vr[i]]);
        m->v.input_slope[k] = value[i];
        m->v.has_input_slope[k] = 1;
    }
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c,
                                                    const fmi2ValueReference vr[], size_t nvr,
                                                    const fmi2Integer order[],
                                                    fmi2Real value[]) {
    (void)vr;
    (void)order;
    (void)value;
    if (nvr == 0) return fmi2OK;
    return fail((Instance *)c, "fmi2GetRealOutputDerivatives",
                "not provided (maxOutputDerivativeOrder is 0)");
}

/* The states' derivatives with the states x and the inputs at `inputs`. */
static void rates(Instance *m, const double *x, const double *inputs, double *k) {
    int i;
    for (i = 0; i < N_STATES; i++) m->v.r[STATE_VR[i]] = x[i];
    for (i = 0; i < N_INPUTS; i++) m->v.r[INPUT_VR[i]] = inputs[i];
    model_derivatives(m->v.r);
    for (i = 0; i < N_STATES; i++) k[i] = m->v.r[DERIVATIVE_VR[i]];
}

static void inputs_at(const double *start, const double *slope, double tau, double *out) {
    int i;
    for (i = 0; i < N_INPUTS; i++) out[i] = start[i] + slope[i] * tau;
}

/* RK4 over [0, step] in equal substeps no longer than max_step. */
static void integrate(Instance *m, const double *start, const double *slope, double step) {
    double x[N_STATES_ALLOC], y[N_STATES_ALLOC], k1[N_STATES_ALLOC], k2[N_STATES_ALLOC];
    double k3[N_STATES_ALLOC], k4[N_STATES_ALLOC], u[N_INPUTS];
    double h, tau;
    int n, s, i;
    if (N_STATES == 0 || !(step > 0.0)) return;
    n = (int)ceil(step / m->v.r[VR_MAX_STEP] - 1e-9);
    if (n < 1) n = 1;
    h = step / n;
    for (i = 0; i < N_STATES; i++) x[i] = m->v.r[STATE_VR[i]];
    for (s = 0; s < n; s++) {
        tau = s * h;
        inputs_at(start, slope, tau, u);
        rates(m, x, u, k1);
        for (i = 0; i < N_STATES; i++) y[i] = x[i] + 0.5 * h * k1[i];
        inputs_at(start, slope, tau + 0.5 * h, u);
        rates(m, y, u, k2);
        for (i = 0; i < N_STATES; i++) y[i] = x[i] + 0.5 * h * k2[i];
        rates(m, y, u, k3);
        for (i = 0; i < N_STATES; i++) y[i] = x[i] + h * k3[i];
        inputs_at(start, slope, tau + h, u);
        rates(m, y, u, k4);
        for (i = 0; i < N_STATES; i++)
            x[i] = x[i] + h * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]) / 6.0;
    }
    for (i = 0; i < N_STATES; i++) m->v.r[STATE_VR[i]] = x[i];
}

FMI2_Export fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                                  fmi2Real communicationStepSize,
                                  fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    Instance *m = (Instance *)c;
    double start[N_INPUTS], slope[N_INPUTS];
    int i;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (m == NULL) return fmi2Error;
    if (m->type != fmi2CoSimulation)
        return fail(m, "fmi2DoStep", "instantiated for model exchange");
    if (m->v.phase != PHASE_RUNNING)
        return fail(m, "fmi2DoStep", "call fmi2ExitInitializationMode first");
    if (!(communicationStepSize >= 0.0) || !isfinite(currentCommunicationPoint))
        return fail(m, "fmi2DoStep", "the step size %.17g is not >= 0", communicationStepSize);
    for (i = 0; i < N_INPUTS; i++) {
        start[i] = m->v.r[INPUT_VR[i]];
        if (m->v.has_input_slope[i]) {
            slope[i] = m->v.input_slope[i];
        } else if (m->v.b[VB_INPUT_EXTRAPOLATION] && m->v.has_previous &&
                   m->v.previous_step > 0.0) {
            slope[i] = (start[i] - m->v.previous_input[i]) / m->v.previous_step;
        } else {
            slope[i] = 0.0;
        }
        if (!isfinite(start[i]) || !isfinite(slope[i]))
            return fail(m, "fmi2DoStep", "the input %s is not finite", REAL_NAME[INPUT_VR[i]]);
    }
    integrate(m, start, slope, communicationStepSize);
    for (i = 0; i < N_INPUTS; i++) {
        m->v.r[INPUT_VR[i]] = start[i]; /* the inputs as the importer set them */
        m->v.previous_input[i] = start[i];
        m->v.has_input_slope[i] = 0;
    }
    m->v.previous_step = communicationStepSize;
    m->v.has_previous = 1;
    m->v.time = currentCommunicationPoint + communicationStepSize;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2CancelStep(fmi2Component c) {
    return fail((Instance *)c, "fmi2CancelStep", "steps are never pending");
}

FMI2_Export fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    (void)s;
    if (c == NULL) return fmi2Error;
    *value = fmi2OK;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s,
                                         fmi2Real *value) {
    Instance *m = (Instance *)c;
    if (m == NULL) return fmi2Error;
    if (s != fmi2LastSuccessfulTime) return fmi2Discard;
    *value = m->v.time;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s,
                                            fmi2Integer *value) {
    (void)s;
    (void)value;
    return c ? fmi2Discard : fmi2Error;
}

FMI2_Export fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s,
                                            fmi2Boolean *value) {
    if (c == NULL) return fmi2Error;
    if (s != fmi2Terminated) return fmi2Discard;
    *value = fmi2False;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s,
                                           fmi2String *value) {
    (void)s;
    (void)value;
    return c ? fmi2Discard : fmi2Error;
}
