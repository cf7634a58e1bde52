/* A DC motor as an FMI 2.0 FMU for co-simulation and model exchange (source code; netsim builds the binary on
   first use).

   States theta (angle, rad) and omega (speed, rad/s), input u (V), parameters k (gain) and a (1/s):

       theta' = omega,   omega' = -a omega + k u,   outputs theta and omega.

   netsim's dc_servo model 1000/(s(s+1)) is k = 1000, a = 1. fmi2DoStep holds u over the step (zero-order
   hold) and advances the state with the exact solution of the linear system over the step length h:

       omega(h) = e omega0 + k u h phi1(z)
       theta(h) = theta0 + omega0 h phi1(z) + k u h^2 phi2(z),   z = -a h, e = exp(z),
       phi1(z) = (e^z - 1)/z,   phi2(z) = (e^z - 1 - z)/z^2

   (the entries of the matrix exponential of [[A, B], [0, 0]] h), so a step equals the zero-order-hold
   discretisation of the same state-space model to rounding. phi1 and phi2 are summed as Taylor series for
   |z| < 0.1, where the closed forms would cancel.

   For model exchange the importer integrates the derivatives (fmi2GetDerivatives) itself; the model has no
   events. */

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

#define VR_K 0
#define VR_A 1
#define VR_U 2
#define VR_THETA 3
#define VR_OMEGA 4
#define VR_DER_THETA 5
#define VR_DER_OMEGA 6
#define N_VR 7

typedef struct {
    double v[N_VR];
    double time;
    fmi2CallbackFunctions cb;
    char *name;
} Motor;

static const double START[N_VR] = {1000.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0};

static void derivatives(Motor *m) {
    m->v[VR_DER_THETA] = m->v[VR_OMEGA];
    m->v[VR_DER_OMEGA] = -m->v[VR_A] * m->v[VR_OMEGA] + m->v[VR_K] * m->v[VR_U];
}

/* phi1(z) = (e^z - 1)/z and phi2(z) = (e^z - 1 - z)/z^2 */
static void phis(double z, double *phi1, double *phi2) {
    if (fabs(z) < 0.1) {
        /* Horner forms of phi1 = sum z^n/(n+1)! and phi2 = sum z^n/(n+2)!, n = 0..12 (the first term
           left out is below 1e-16 relative for |z| < 0.1) */
        double p1 = 0.0, p2 = 0.0, f1 = 1.0, f2 = 1.0;
        int n, j;
        for (n = 12; n >= 0; n--) {
            f1 = 1.0;
            f2 = 1.0;
            for (j = 2; j <= n + 1; j++) f1 *= j;
            f2 = f1 * (n + 2);
            p1 = p1 * z + 1.0 / f1;
            p2 = p2 * z + 1.0 / f2;
        }
        *phi1 = p1;
        *phi2 = p2;
    } else {
        double em1 = expm1(z);
        *phi1 = em1 / z;
        *phi2 = (em1 - z) / (z * z);
    }
}

static void step(Motor *m, double h) {
    double a = m->v[VR_A], k = m->v[VR_K], u = m->v[VR_U];
    double th = m->v[VR_THETA], w = m->v[VR_OMEGA];
    double z = -a * h, phi1, phi2;
    phis(z, &phi1, &phi2);
    m->v[VR_OMEGA] = exp(z) * w + k * u * h * phi1;
    m->v[VR_THETA] = th + w * h * phi1 + k * u * h * h * phi2;
    derivatives(m);
}

/* ------------------------------------------------------------------ FMI 2.0 interface */
const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cat[]) {
    (void)c; (void)on; (void)n; (void)cat;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String resources,
                              const fmi2CallbackFunctions *cb, fmi2Boolean visible, fmi2Boolean logging) {
    Motor *m;
    (void)resources; (void)visible; (void)logging;
    if ((type != fmi2CoSimulation && type != fmi2ModelExchange) || guid == NULL || strcmp(guid, "{netsim-dc-motor-1}") != 0) return NULL;
    m = (Motor *)calloc(1, sizeof(Motor));
    if (m == NULL) return NULL;
    memcpy(m->v, START, sizeof(START));
    m->cb = *cb;
    m->name = NULL;
    (void)name;
    derivatives(m);
    return m;
}

void fmi2FreeInstance(fmi2Component c) { free(c); }

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolDef, fmi2Real tol, fmi2Real start,
                               fmi2Boolean stopDef, fmi2Real stop) {
    (void)tolDef; (void)tol; (void)stopDef; (void)stop;
    ((Motor *)c)->time = start;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2ExitInitializationMode(fmi2Component c) { derivatives((Motor *)c); return fmi2OK; }
fmi2Status fmi2Terminate(fmi2Component c) { (void)c; return fmi2OK; }

fmi2Status fmi2Reset(fmi2Component c) {
    Motor *m = (Motor *)c;
    memcpy(m->v, START, sizeof(START));
    m->time = 0.0;
    derivatives(m);
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real value[]) {
    Motor *m = (Motor *)c;
    size_t i;
    for (i = 0; i < n; i++) {
        if (vr[i] >= N_VR) return fmi2Error;
        value[i] = m->v[vr[i]];
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real value[]) {
    Motor *m = (Motor *)c;
    size_t i;
    for (i = 0; i < n; i++) {
        if (vr[i] >= N_VR || vr[i] == VR_DER_THETA || vr[i] == VR_DER_OMEGA) return fmi2Error;
        m->v[vr[i]] = value[i];
    }
    derivatives(m);
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer v[]) {
    (void)c; (void)vr; (void)v; return n == 0 ? fmi2OK : fmi2Error;
}
fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Boolean v[]) {
    (void)c; (void)vr; (void)v; return n == 0 ? fmi2OK : fmi2Error;
}
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String v[]) {
    (void)c; (void)vr; (void)v; return n == 0 ? fmi2OK : fmi2Error;
}
fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer v[]) {
    (void)c; (void)vr; (void)v; return n == 0 ? fmi2OK : fmi2Error;
}
fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Boolean v[]) {
    (void)c; (void)vr; (void)v; return n == 0 ? fmi2OK : fmi2Error;
}
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2String v[]) {
    (void)c; (void)vr; (void)v; return n == 0 ? fmi2OK : fmi2Error;
}

/* FMU state: a copy of the instance (canGetAndSetFMUstate) */
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s) {
    Motor *copy = (Motor *)malloc(sizeof(Motor));
    if (copy == NULL) return fmi2Error;
    *copy = *(Motor *)c;
    *s = copy;
    return fmi2OK;
}
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s) { *(Motor *)c = *(Motor *)s; return fmi2OK; }
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s) { (void)c; free(*s); *s = NULL; return fmi2OK; }
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *size) {
    (void)c; (void)s; (void)size; return fmi2Error;
}
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t size) {
    (void)c; (void)s; (void)b; (void)size; return fmi2Error;
}
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte b[], size_t size, fmi2FMUstate *s) {
    (void)c; (void)b; (void)size; (void)s; return fmi2Error;
}
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu,
                                        const fmi2ValueReference z[], size_t nz, const fmi2Real du[],
                                        fmi2Real dz[]) {
    (void)c; (void)u; (void)nu; (void)z; (void)nz; (void)du; (void)dz; return fmi2Error;
}

/* ------------------------------------------------------------------ co-simulation */
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    (void)c; (void)vr; (void)n; (void)order; (void)value; return fmi2Error;
}
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                        const fmi2Integer order[], fmi2Real value[]) {
    (void)c; (void)vr; (void)n; (void)order; (void)value; return fmi2Error;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSetPrior) {
    Motor *m = (Motor *)c;
    (void)noSetPrior;
    if (h < 0.0) return fmi2Error;
    step(m, h);
    m->time = t + h;
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component c) { (void)c; return fmi2Error; }
fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *v) {
    (void)c; (void)s; (void)v; return fmi2Discard;
}
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *v) {
    Motor *m = (Motor *)c;
    if (s == fmi2LastSuccessfulTime) { *v = m->time; return fmi2OK; }
    return fmi2Discard;
}
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *v) {
    (void)c; (void)s; (void)v; return fmi2Discard;
}
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *v) {
    (void)c; (void)s; (void)v; return fmi2Discard;
}
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *v) {
    (void)c; (void)s; (void)v; return fmi2Discard;
}

/* ------------------------------------------------------------------ model exchange */
fmi2Status fmi2EnterEventMode(fmi2Component c) { (void)c; return fmi2OK; }

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

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) { (void)c; return fmi2OK; }

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetPrior, fmi2Boolean *enterEventMode,
                                       fmi2Boolean *terminate) {
    (void)c; (void)noSetPrior;
    *enterEventMode = fmi2False;
    *terminate = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real t) { ((Motor *)c)->time = t; return fmi2OK; }

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    Motor *m = (Motor *)c;
    if (nx != 2) return fmi2Error;
    m->v[VR_THETA] = x[0];
    m->v[VR_OMEGA] = x[1];
    derivatives(m);
    return fmi2OK;
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t nx) {
    Motor *m = (Motor *)c;
    if (nx != 2) return fmi2Error;
    derivatives(m);
    dx[0] = m->v[VR_DER_THETA];
    dx[1] = m->v[VR_DER_OMEGA];
    return fmi2OK;
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real z[], size_t nz) {
    (void)c; (void)z; return nz == 0 ? fmi2OK : fmi2Error;
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    Motor *m = (Motor *)c;
    if (nx != 2) return fmi2Error;
    x[0] = m->v[VR_THETA];
    x[1] = m->v[VR_OMEGA];
    return fmi2OK;
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    size_t i;
    (void)c;
    for (i = 0; i < nx; i++) x[i] = 1.0;
    return fmi2OK;
}
