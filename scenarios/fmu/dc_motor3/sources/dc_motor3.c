/* The DC motor of scenarios/fmu/dc_motor as an FMI 3.0 FMU, co-simulation and model exchange (source code;
   netsim builds the library on first use with FMPy's CMake project and the FMI 3 headers FMPy ships).

   Continuous states theta (rad) and omega (rad/s), input u, parameters k and a (1/s):

       theta' = omega,   omega' = -a omega + k u,   outputs theta and omega.

   k = 1000, a = 1 is netsim's dc_servo plant 1000/(s(s+1)). fmi3DoStep holds u constant over the
   communication step h and moves the state by the exact solution over h (the zero-order-hold discretisation):
   with z = -a h,

       omega(h) = exp(z) omega0 + k u h phi1(z)
       theta(h) = theta0 + omega0 h phi1(z) + k u h^2 phi2(z)
       phi1(z) = (exp(z) - 1)/z = sum_n z^n/(n+1)!,   phi2(z) = (exp(z) - 1 - z)/z^2 = sum_n z^n/(n+2)!

   The series are used for |z| < 0.1 (the closed forms lose digits to cancellation there), the closed forms with
   expm1 otherwise. This is the same arithmetic as the FMI 2.0 motor, so both FMUs give the same numbers.

   Model exchange: the importer integrates fmi3GetContinuousStateDerivatives itself. The model has no event
   indicators, no clocks and no time events. Only Float64 variables exist; every other typed getter and setter
   accepts an empty request only. The functions FMI 3.0 lists but this model has no use for (scheduled
   execution, clocks, directional derivatives, serialisation, configuration mode) return fmi3Error. */

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"

#define TOKEN "{netsim-dc-motor-fmi3-1}"

enum { VR_TIME, VR_K, VR_A, VR_U, VR_THETA, VR_OMEGA, VR_DTHETA, VR_DOMEGA, NVR };

#define NX 2

typedef struct {
    double v[NVR];
} Motor;

static const double INITIAL[NVR] = {0.0, 1000.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0};

static void update_derivatives(Motor *m) {
    m->v[VR_DTHETA] = m->v[VR_OMEGA];
    m->v[VR_DOMEGA] = -m->v[VR_A] * m->v[VR_OMEGA] + m->v[VR_K] * m->v[VR_U];
}

static void phi12(double z, double *phi1, double *phi2) {
    if (fabs(z) < 0.1) {
        /* Horner over n = 12..0 with the factorials (n+1)! and (n+2)!; the first term left out is below
           1e-16 relative for |z| < 0.1 */
        double p1 = 0.0, p2 = 0.0;
        int n, j;
        for (n = 12; n >= 0; n--) {
            double f1 = 1.0, f2;
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

static void advance(Motor *m, double h) {
    double k = m->v[VR_K], u = m->v[VR_U], w0 = m->v[VR_OMEGA], th0 = m->v[VR_THETA];
    double z = -m->v[VR_A] * h, phi1, phi2;
    phi12(z, &phi1, &phi2);
    m->v[VR_OMEGA] = exp(z) * w0 + k * u * h * phi1;
    m->v[VR_THETA] = th0 + w0 * h * phi1 + k * u * h * h * phi2;
    update_derivatives(m);
}

static Motor *create(fmi3String token) {
    Motor *m;
    if (token == NULL || strcmp(token, TOKEN) != 0) return NULL;
    m = (Motor *)calloc(1, sizeof(Motor));
    if (m == NULL) return NULL;
    memcpy(m->v, INITIAL, sizeof(INITIAL));
    update_derivatives(m);
    return m;
}

/* ------------------------------------------------------------------ common functions */
const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance c, fmi3Boolean on, size_t n, const fmi3String cat[]) {
    (void)c; (void)on; (void)n; (void)cat;
    return fmi3OK;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String name, fmi3String token, fmi3String resources,
                                          fmi3Boolean visible, fmi3Boolean logging, fmi3InstanceEnvironment env,
                                          fmi3LogMessageCallback log) {
    (void)name; (void)resources; (void)visible; (void)logging; (void)env; (void)log;
    return create(token);
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String name, fmi3String token, fmi3String resources,
                                         fmi3Boolean visible, fmi3Boolean logging, fmi3Boolean eventModeUsed,
                                         fmi3Boolean earlyReturnAllowed, const fmi3ValueReference required[],
                                         size_t nRequired, fmi3InstanceEnvironment env,
                                         fmi3LogMessageCallback log, fmi3IntermediateUpdateCallback update) {
    (void)name; (void)resources; (void)visible; (void)logging; (void)eventModeUsed; (void)earlyReturnAllowed;
    (void)required; (void)nRequired; (void)env; (void)log; (void)update;
    return create(token);
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String name, fmi3String token, fmi3String resources,
                                               fmi3Boolean visible, fmi3Boolean logging,
                                               fmi3InstanceEnvironment env, fmi3LogMessageCallback log,
                                               fmi3ClockUpdateCallback clockUpdate,
                                               fmi3LockPreemptionCallback lock,
                                               fmi3UnlockPreemptionCallback unlock) {
    (void)name; (void)token; (void)resources; (void)visible; (void)logging; (void)env; (void)log;
    (void)clockUpdate; (void)lock; (void)unlock;
    return NULL; /* no scheduled execution interface */
}

void fmi3FreeInstance(fmi3Instance c) { free(c); }

fmi3Status fmi3EnterInitializationMode(fmi3Instance c, fmi3Boolean tolDefined, fmi3Float64 tol,
                                       fmi3Float64 start, fmi3Boolean stopDefined, fmi3Float64 stop) {
    (void)tolDefined; (void)tol; (void)stopDefined; (void)stop;
    ((Motor *)c)->v[VR_TIME] = start;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance c) { update_derivatives((Motor *)c); return fmi3OK; }
fmi3Status fmi3EnterEventMode(fmi3Instance c) { (void)c; return fmi3OK; }
fmi3Status fmi3Terminate(fmi3Instance c) { (void)c; return fmi3OK; }

fmi3Status fmi3Reset(fmi3Instance c) {
    Motor *m = (Motor *)c;
    memcpy(m->v, INITIAL, sizeof(INITIAL));
    update_derivatives(m);
    return fmi3OK;
}

/* ------------------------------------------------------------------ variable values (Float64 only) */
fmi3Status fmi3GetFloat64(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 values[],
                          size_t nValues) {
    Motor *m = (Motor *)c;
    size_t i;
    if (nValues != nvr) return fmi3Error; /* scalar variables: one value each */
    for (i = 0; i < nvr; i++) {
        if (vr[i] >= NVR) return fmi3Error;
        values[i] = m->v[vr[i]];
    }
    return fmi3OK;
}

fmi3Status fmi3SetFloat64(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, const fmi3Float64 values[],
                          size_t nValues) {
    Motor *m = (Motor *)c;
    size_t i;
    if (nValues != nvr) return fmi3Error;
    for (i = 0; i < nvr; i++) {
        /* time is set by fmi3SetTime, derivatives are computed */
        if (vr[i] >= NVR || vr[i] == VR_TIME || vr[i] == VR_DTHETA || vr[i] == VR_DOMEGA) return fmi3Error;
        m->v[vr[i]] = values[i];
    }
    update_derivatives(m);
    return fmi3OK;
}

/* the other types: the model has no such variables, so only an empty request succeeds */
#define NO_GET(NAME, T)                                                                                    \
    fmi3Status fmi3Get##NAME(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, T values[],          \
                             size_t nValues) {                                                             \
        (void)c; (void)vr; (void)values; (void)nValues;                                                    \
        return nvr == 0 ? fmi3OK : fmi3Error;                                                              \
    }
#define NO_SET(NAME, T)                                                                                    \
    fmi3Status fmi3Set##NAME(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, const T values[],    \
                             size_t nValues) {                                                             \
        (void)c; (void)vr; (void)values; (void)nValues;                                                    \
        return nvr == 0 ? fmi3OK : fmi3Error;                                                              \
    }

NO_GET(Float32, fmi3Float32)
NO_GET(Int8, fmi3Int8)
NO_GET(UInt8, fmi3UInt8)
NO_GET(Int16, fmi3Int16)
NO_GET(UInt16, fmi3UInt16)
NO_GET(Int32, fmi3Int32)
NO_GET(UInt32, fmi3UInt32)
NO_GET(Int64, fmi3Int64)
NO_GET(UInt64, fmi3UInt64)
NO_GET(Boolean, fmi3Boolean)
NO_GET(String, fmi3String)
NO_SET(Float32, fmi3Float32)
NO_SET(Int8, fmi3Int8)
NO_SET(UInt8, fmi3UInt8)
NO_SET(Int16, fmi3Int16)
NO_SET(UInt16, fmi3UInt16)
NO_SET(Int32, fmi3Int32)
NO_SET(UInt32, fmi3UInt32)
NO_SET(Int64, fmi3Int64)
NO_SET(UInt64, fmi3UInt64)
NO_SET(Boolean, fmi3Boolean)
NO_SET(String, fmi3String)

fmi3Status fmi3GetBinary(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, size_t sizes[],
                         fmi3Binary values[], size_t nValues) {
    (void)c; (void)vr; (void)sizes; (void)values; (void)nValues;
    return nvr == 0 ? fmi3OK : fmi3Error;
}
fmi3Status fmi3SetBinary(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, const size_t sizes[],
                         const fmi3Binary values[], size_t nValues) {
    (void)c; (void)vr; (void)sizes; (void)values; (void)nValues;
    return nvr == 0 ? fmi3OK : fmi3Error;
}
fmi3Status fmi3GetClock(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, fmi3Clock values[]) {
    (void)c; (void)vr; (void)values;
    return nvr == 0 ? fmi3OK : fmi3Error;
}
fmi3Status fmi3SetClock(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, const fmi3Clock values[]) {
    (void)c; (void)vr; (void)values;
    return nvr == 0 ? fmi3OK : fmi3Error;
}

/* ------------------------------------------------------------------ dependencies and derivatives: not given */
fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance c, fmi3ValueReference vr, size_t *n) {
    (void)c; (void)vr; (void)n; return fmi3Error;
}
fmi3Status fmi3GetVariableDependencies(fmi3Instance c, fmi3ValueReference dependent, size_t elementsOfDependent[],
                                       fmi3ValueReference independents[], size_t elementsOfIndependents[],
                                       fmi3DependencyKind kinds[], size_t n) {
    (void)c; (void)dependent; (void)elementsOfDependent; (void)independents; (void)elementsOfIndependents;
    (void)kinds; (void)n;
    return fmi3Error;
}
fmi3Status fmi3GetDirectionalDerivative(fmi3Instance c, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                        const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                        size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)c; (void)unknowns; (void)nUnknowns; (void)knowns; (void)nKnowns; (void)seed; (void)nSeed;
    (void)sensitivity; (void)nSensitivity;
    return fmi3Error;
}
fmi3Status fmi3GetAdjointDerivative(fmi3Instance c, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                    const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                    size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)c; (void)unknowns; (void)nUnknowns; (void)knowns; (void)nKnowns; (void)seed; (void)nSeed;
    (void)sensitivity; (void)nSensitivity;
    return fmi3Error;
}

/* ------------------------------------------------------------------ FMU state: a copy of the instance */
fmi3Status fmi3GetFMUState(fmi3Instance c, fmi3FMUState *s) {
    Motor *copy = (Motor *)malloc(sizeof(Motor));
    if (copy == NULL) return fmi3Error;
    *copy = *(Motor *)c;
    *s = copy;
    return fmi3OK;
}
fmi3Status fmi3SetFMUState(fmi3Instance c, fmi3FMUState s) { *(Motor *)c = *(Motor *)s; return fmi3OK; }
fmi3Status fmi3FreeFMUState(fmi3Instance c, fmi3FMUState *s) { (void)c; free(*s); *s = NULL; return fmi3OK; }
fmi3Status fmi3SerializedFMUStateSize(fmi3Instance c, fmi3FMUState s, size_t *size) {
    (void)c; (void)s; (void)size; return fmi3Error;
}
fmi3Status fmi3SerializeFMUState(fmi3Instance c, fmi3FMUState s, fmi3Byte bytes[], size_t size) {
    (void)c; (void)s; (void)bytes; (void)size; return fmi3Error;
}
fmi3Status fmi3DeserializeFMUState(fmi3Instance c, const fmi3Byte bytes[], size_t size, fmi3FMUState *s) {
    (void)c; (void)bytes; (void)size; (void)s; return fmi3Error;
}

/* ------------------------------------------------------------------ configuration mode and clocks: none */
fmi3Status fmi3EnterConfigurationMode(fmi3Instance c) { (void)c; return fmi3Error; }
fmi3Status fmi3ExitConfigurationMode(fmi3Instance c) { (void)c; return fmi3Error; }
fmi3Status fmi3GetIntervalDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 intervals[],
                                  fmi3IntervalQualifier qualifiers[]) {
    (void)c; (void)vr; (void)nvr; (void)intervals; (void)qualifiers; return fmi3Error;
}
fmi3Status fmi3GetIntervalFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, fmi3UInt64 counters[],
                                   fmi3UInt64 resolutions[], fmi3IntervalQualifier qualifiers[]) {
    (void)c; (void)vr; (void)nvr; (void)counters; (void)resolutions; (void)qualifiers; return fmi3Error;
}
fmi3Status fmi3GetShiftDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 shifts[]) {
    (void)c; (void)vr; (void)nvr; (void)shifts; return fmi3Error;
}
fmi3Status fmi3GetShiftFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, fmi3UInt64 counters[],
                                fmi3UInt64 resolutions[]) {
    (void)c; (void)vr; (void)nvr; (void)counters; (void)resolutions; return fmi3Error;
}
fmi3Status fmi3SetIntervalDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                  const fmi3Float64 intervals[]) {
    (void)c; (void)vr; (void)nvr; (void)intervals; return fmi3Error;
}
fmi3Status fmi3SetIntervalFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                   const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]) {
    (void)c; (void)vr; (void)nvr; (void)counters; (void)resolutions; return fmi3Error;
}
fmi3Status fmi3SetShiftDecimal(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, const fmi3Float64 shifts[]) {
    (void)c; (void)vr; (void)nvr; (void)shifts; return fmi3Error;
}
fmi3Status fmi3SetShiftFraction(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]) {
    (void)c; (void)vr; (void)nvr; (void)counters; (void)resolutions; return fmi3Error;
}
fmi3Status fmi3ActivateModelPartition(fmi3Instance c, fmi3ValueReference clock, fmi3Float64 t) {
    (void)c; (void)clock; (void)t; return fmi3Error;
}

/* ------------------------------------------------------------------ events: there are none */
fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance c) { (void)c; return fmi3OK; }

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance c, fmi3Boolean *again, fmi3Boolean *terminate,
                                    fmi3Boolean *nominalsChanged, fmi3Boolean *valuesChanged,
                                    fmi3Boolean *nextTimeDefined, fmi3Float64 *nextTime) {
    (void)c;
    *again = false;
    *terminate = false;
    *nominalsChanged = false;
    *valuesChanged = false;
    *nextTimeDefined = false;
    *nextTime = 0.0;
    return fmi3OK;
}

/* ------------------------------------------------------------------ model exchange */
fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance c) { (void)c; return fmi3OK; }

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance c, fmi3Boolean noSetPrior, fmi3Boolean *enterEventMode,
                                       fmi3Boolean *terminate) {
    (void)c; (void)noSetPrior;
    *enterEventMode = false;
    *terminate = false;
    return fmi3OK;
}

fmi3Status fmi3SetTime(fmi3Instance c, fmi3Float64 t) { ((Motor *)c)->v[VR_TIME] = t; return fmi3OK; }

fmi3Status fmi3SetContinuousStates(fmi3Instance c, const fmi3Float64 x[], size_t nx) {
    Motor *m = (Motor *)c;
    if (nx != NX) return fmi3Error;
    m->v[VR_THETA] = x[0];
    m->v[VR_OMEGA] = x[1];
    update_derivatives(m);
    return fmi3OK;
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance c, fmi3Float64 dx[], size_t nx) {
    Motor *m = (Motor *)c;
    if (nx != NX) return fmi3Error;
    update_derivatives(m);
    dx[0] = m->v[VR_DTHETA];
    dx[1] = m->v[VR_DOMEGA];
    return fmi3OK;
}

fmi3Status fmi3GetEventIndicators(fmi3Instance c, fmi3Float64 z[], size_t nz) {
    (void)c; (void)z; return nz == 0 ? fmi3OK : fmi3Error;
}

fmi3Status fmi3GetContinuousStates(fmi3Instance c, fmi3Float64 x[], size_t nx) {
    Motor *m = (Motor *)c;
    if (nx != NX) return fmi3Error;
    x[0] = m->v[VR_THETA];
    x[1] = m->v[VR_OMEGA];
    return fmi3OK;
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance c, fmi3Float64 nominals[], size_t nx) {
    size_t i;
    (void)c;
    for (i = 0; i < nx; i++) nominals[i] = 1.0;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance c, size_t *n) { (void)c; *n = 0; return fmi3OK; }
fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance c, size_t *n) { (void)c; *n = NX; return fmi3OK; }

/* ------------------------------------------------------------------ co-simulation */
fmi3Status fmi3EnterStepMode(fmi3Instance c) { (void)c; return fmi3OK; }

fmi3Status fmi3GetOutputDerivatives(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr,
                                    const fmi3Int32 orders[], fmi3Float64 values[], size_t nValues) {
    (void)c; (void)vr; (void)nvr; (void)orders; (void)values; (void)nValues; return fmi3Error;
}

fmi3Status fmi3DoStep(fmi3Instance c, fmi3Float64 t, fmi3Float64 h, fmi3Boolean noSetPrior,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminate, fmi3Boolean *earlyReturn,
                      fmi3Float64 *lastSuccessfulTime) {
    Motor *m = (Motor *)c;
    (void)noSetPrior;
    *eventHandlingNeeded = false;
    *terminate = false;
    *earlyReturn = false;
    if (h < 0.0) {
        *lastSuccessfulTime = m->v[VR_TIME];
        return fmi3Error;
    }
    advance(m, h);
    m->v[VR_TIME] = t + h;
    *lastSuccessfulTime = t + h;
    return fmi3OK;
}
