/* The FMI 2.0 library of an FMU built by herringbone, in front of pythonfmu 0.7's.
 *
 * FMI 2.0 passes fmi2Instantiate the resources folder as a file URI (RFC 3986, RFC 8089), which
 * a host percent-encodes: fmpy gives "file:///tmp/%C3%BCber/resources" for /tmp/über/resources.
 * pythonfmu 0.7 decodes %20 alone and cuts "file://" off, so any other escape ("ü", "#", "%")
 * or the form "file:/path" leaves it a folder that is not there, and it crashes the host in
 * fmi2Instantiate before the FMU's Python runs. Here fmi2Instantiate hands pythonfmu the
 * folder as a plain path, which it takes as it is (but for a "%20" in it: `without_escape`);
 * every other function is pythonfmu's, called through. pythonfmu's library lies beside this one, named PYTHONFMU_LIBRARY.
 *
 * Built by herringbone/fmu/builder.py (`with_resource_path`) with the system's C compiler,
 * against the FMI 2.0 headers fmpy ships.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <fcntl.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

#ifndef PYTHONFMU_LIBRARY
#error "define PYTHONFMU_LIBRARY: the file name of pythonfmu's library beside this one"
#endif

/* pythonfmu's functions, each of the type the FMI header gives it */
#define CALLED_THROUGH(X) \
    X(fmi2SetDebugLogging) X(fmi2Instantiate) X(fmi2FreeInstance) X(fmi2SetupExperiment) \
    X(fmi2EnterInitializationMode) X(fmi2ExitInitializationMode) X(fmi2Terminate) \
    X(fmi2Reset) X(fmi2GetReal) X(fmi2GetInteger) X(fmi2GetBoolean) X(fmi2GetString) \
    X(fmi2SetReal) X(fmi2SetInteger) X(fmi2SetBoolean) X(fmi2SetString) X(fmi2GetFMUstate) \
    X(fmi2SetFMUstate) X(fmi2FreeFMUstate) X(fmi2SerializedFMUstateSize) \
    X(fmi2SerializeFMUstate) X(fmi2DeSerializeFMUstate) X(fmi2GetDirectionalDerivative) \
    X(fmi2SetRealInputDerivatives) X(fmi2GetRealOutputDerivatives) X(fmi2DoStep) \
    X(fmi2CancelStep) X(fmi2GetStatus) X(fmi2GetRealStatus) X(fmi2GetIntegerStatus) \
    X(fmi2GetBooleanStatus) X(fmi2GetStringStatus)

#define MEMBER(name) name##TYPE *name;
static struct { CALLED_THROUGH(MEMBER) } pythonfmu;

/* why pythonfmu's library could not be opened, for fmi2Instantiate to tell the host */
static char open_problem[PATH_MAX + 256];

/* Open pythonfmu's library, beside this one, as this one is loaded; it stays open, as a
 * library the host loads with its dependencies would. */
__attribute__((constructor)) static void open_pythonfmu(void)
{
    Dl_info self;
    char path[PATH_MAX];
    if (!dladdr((void *)open_pythonfmu, &self) || self.dli_fname == NULL) {
        snprintf(open_problem, sizeof open_problem, "the FMU's library cannot find its folder");
        return;
    }
    const char *slash = strrchr(self.dli_fname, '/');
    int folder = slash ? (int)(slash - self.dli_fname + 1) : 0;
    snprintf(path, sizeof path, "%.*s%s", folder, self.dli_fname, PYTHONFMU_LIBRARY);
    void *library = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (library == NULL) {
        snprintf(open_problem, sizeof open_problem, "cannot open %s: %s", path, dlerror());
        return;
    }
#define FIND(name) pythonfmu.name = (name##TYPE *)dlsym(library, #name);
    CALLED_THROUGH(FIND)
    if (pythonfmu.fmi2Instantiate == NULL)
        snprintf(open_problem, sizeof open_problem, "%s has no fmi2Instantiate", path);
}

static int hex_digit(char c)
{
    if (c >= '0' && c <= '9')
        return c - '0';
    c = (char)(c | 0x20);
    return c >= 'a' && c <= 'f' ? c - 'a' + 10 : -1;
}

/* The local path that `location` names: a file URI (file:///p, file://localhost/p, file:/p)
 * percent-decoded; anything else (a plain path, another host's URI) as it is. NULL where
 * memory is short. The caller frees it. */
static char *local_path(const char *location)
{
    const char *path = NULL;
    if (strncmp(location, "file:///", 8) == 0)
        path = location + 7;
    else if (strncmp(location, "file://localhost/", 17) == 0)
        path = location + 16;
    else if (strncmp(location, "file:/", 6) == 0 && location[6] != '/')
        path = location + 5;
    if (path == NULL)
        return strdup(location);
    char *decoded = malloc(strlen(path) + 1), *end = decoded;
    if (decoded == NULL)
        return NULL;
    for (; *path; ++path) {
        int high, low;
        if (path[0] == '%' && (high = hex_digit(path[1])) >= 0 && (low = hex_digit(path[2])) >= 0) {
            *end++ = (char)(16 * high + low);
            path += 2;
        } else {
            *end++ = *path;
        }
    }
    *end = '\0';
    return decoded;
}

/* A name of the folder `path` (resources, inside the unpacked FMU) that holds no "%20", which
 * pythonfmu would turn into a space: the unpacked FMU's folder by a descriptor kept open for the
 * process, "/proc/self/fd/N/resources", one descriptor per folder (the descriptor's number must
 * not come to name another folder: pythonfmu leaves the name on Python's sys.path). NULL
 * where the folder cannot be opened. The caller frees it. */
static char *without_escape(const char *path)
{
    static struct { char *folder; int descriptor; } opened[64];
    static int count;
    size_t length = strlen(path);
    while (length > 1 && path[length - 1] == '/')
        --length;
    const char *slash = memrchr(path, '/', length);
    if (slash == NULL || slash == path)
        return NULL;
    char *folder = strndup(path, (size_t)(slash - path));
    if (folder == NULL)
        return NULL;
    int descriptor = -1;
    for (int i = 0; i < count && descriptor < 0; ++i)
        if (strcmp(opened[i].folder, folder) == 0)
            descriptor = opened[i].descriptor;
    if (descriptor < 0) {
        descriptor = open(folder, O_PATH | O_DIRECTORY | O_CLOEXEC);
        if (descriptor >= 0 && count < (int)(sizeof opened / sizeof opened[0])) {
            opened[count].folder = folder;
            opened[count++].descriptor = descriptor;
            folder = NULL;
        }
    }
    free(folder);
    if (descriptor < 0)
        return NULL;
    int name = (int)(path + length - slash);  /* "/resources", without trailing slashes */
    char *alias = malloc((size_t)name + 32);
    if (alias != NULL)
        sprintf(alias, "/proc/self/fd/%d%.*s", descriptor, name, slash);
    return alias;
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }

const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn)
{
    if (pythonfmu.fmi2Instantiate == NULL) {
        if (functions != NULL && functions->logger != NULL)
            functions->logger(functions->componentEnvironment, instanceName, fmi2Fatal,
                              "logStatusFatal", "%s", open_problem);
        return NULL;
    }
    char *path = fmuResourceLocation ? local_path(fmuResourceLocation) : NULL;
    if (path != NULL && strstr(path, "%20") != NULL) {
        char *alias = without_escape(path);
        if (alias != NULL) {
            free(path);
            path = alias;
        }
    }
    fmi2Component instance = pythonfmu.fmi2Instantiate(
        instanceName, fmuType, fmuGUID, path ? path : fmuResourceLocation, functions, visible,
        loggingOn);
    free(path);
    return instance;
}

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{
    return pythonfmu.fmi2SetDebugLogging(c, loggingOn, nCategories, categories);
}

void fmi2FreeInstance(fmi2Component c) { pythonfmu.fmi2FreeInstance(c); }

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    return pythonfmu.fmi2SetupExperiment(c, toleranceDefined, tolerance, startTime,
                                         stopTimeDefined, stopTime);
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    return pythonfmu.fmi2EnterInitializationMode(c);
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    return pythonfmu.fmi2ExitInitializationMode(c);
}

fmi2Status fmi2Terminate(fmi2Component c) { return pythonfmu.fmi2Terminate(c); }

fmi2Status fmi2Reset(fmi2Component c) { return pythonfmu.fmi2Reset(c); }

/* fmi2GetReal, fmi2SetReal and the other kinds' */
#define VALUES_OF(kind, type)                                                                   \
    fmi2Status fmi2Get##kind(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,          \
                             type value[])                                                      \
    {                                                                                           \
        return pythonfmu.fmi2Get##kind(c, vr, nvr, value);                                      \
    }                                                                                           \
    fmi2Status fmi2Set##kind(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,          \
                             const type value[])                                                \
    {                                                                                           \
        return pythonfmu.fmi2Set##kind(c, vr, nvr, value);                                      \
    }
VALUES_OF(Real, fmi2Real)
VALUES_OF(Integer, fmi2Integer)
VALUES_OF(Boolean, fmi2Boolean)
VALUES_OF(String, fmi2String)

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state)
{
    return pythonfmu.fmi2GetFMUstate(c, state);
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state)
{
    return pythonfmu.fmi2SetFMUstate(c, state);
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state)
{
    return pythonfmu.fmi2FreeFMUstate(c, state);
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size)
{
    return pythonfmu.fmi2SerializedFMUstateSize(c, state, size);
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[],
                                 size_t size)
{
    return pythonfmu.fmi2SerializeFMUstate(c, state, bytes, size);
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size,
                                   fmi2FMUstate *state)
{
    return pythonfmu.fmi2DeSerializeFMUstate(c, bytes, size, state);
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference unknowns[],
                                        size_t nUnknown, const fmi2ValueReference knowns[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[])
{
    return pythonfmu.fmi2GetDirectionalDerivative(c, unknowns, nUnknown, knowns, nKnown, dvKnown,
                                                  dvUnknown);
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                       size_t nvr, const fmi2Integer order[],
                                       const fmi2Real value[])
{
    return pythonfmu.fmi2SetRealInputDerivatives(c, vr, nvr, order, value);
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t nvr, const fmi2Integer order[], fmi2Real value[])
{
    return pythonfmu.fmi2GetRealOutputDerivatives(c, vr, nvr, order, value);
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    return pythonfmu.fmi2DoStep(c, currentCommunicationPoint, communicationStepSize,
                                noSetFMUStatePriorToCurrentPoint);
}

fmi2Status fmi2CancelStep(fmi2Component c) { return pythonfmu.fmi2CancelStep(c); }

/* fmi2GetStatus, fmi2GetRealStatus and the other kinds' */
#define STATUS_OF(kind, type)                                                                   \
    fmi2Status fmi2Get##kind##Status(fmi2Component c, const fmi2StatusKind s, type *value)       \
    {                                                                                           \
        return pythonfmu.fmi2Get##kind##Status(c, s, value);                                    \
    }
STATUS_OF(, fmi2Status)
STATUS_OF(Real, fmi2Real)
STATUS_OF(Integer, fmi2Integer)
STATUS_OF(Boolean, fmi2Boolean)
STATUS_OF(String, fmi2String)
