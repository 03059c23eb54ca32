/* A minimal FMI 2.0 co-simulation host in C: what a non-Python simulator does with the FMU.

   c_host UNZIPPED_FMU MODEL_IDENTIFIER GUID STOP_TIME STEP VR [VR ...]

   Loads UNZIPPED_FMU/binaries/linux64/MODEL_IDENTIFIER.so, instantiates it with a logger (every
   message to stderr, formatted printf-style as FMI asks), sets up the experiment at t = 0,
   initializes, and steps to STOP_TIME by STEP, reading the Real outputs of the value
   references VR after initialization and after every step. Each row goes to stdout as
   "time value value ..." in C's hexadecimal floating-point format (%a), so that a test can
   compare them bit for bit. Then it terminates and frees the instance, and returns from main.

   The resource location is the file:// URI of UNZIPPED_FMU/resources, or $C_HOST_RESOURCES
   where set (to try others).

   Exit status: 0 done; 1 usage; 2 the binary or a function is missing; 3 fmi2Instantiate
   returned NULL; 4 an FMI call returned worse than fmi2Warning. */
#include <dlfcn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

static const char *status_name(fmi2Status status) {
    static const char *names[] = {"ok", "warning", "discard", "error", "fatal", "pending"};
    return status <= fmi2Pending ? names[status] : "?";
}

static void logger(fmi2ComponentEnvironment environment, fmi2String instance, fmi2Status status,
                   fmi2String category, fmi2String message, ...) {
    char text[8192];
    va_list arguments;
    (void)environment;
    va_start(arguments, message);
    vsnprintf(text, sizeof text, message, arguments);
    va_end(arguments);
    fprintf(stderr, "[%s] %s (%s): %s\n", status_name(status), instance ? instance : "",
            category ? category : "", text);
    fflush(stderr);
}

static void *symbol(void *library, const char *name) {
    void *address = dlsym(library, name);
    if (address == NULL) {
        fprintf(stderr, "c_host: the FMU's binary has no %s\n", name);
        exit(2);
    }
    return address;
}

static void check(fmi2Status status, const char *call) {
    if (status > fmi2Warning) {
        fprintf(stderr, "c_host: %s returned %s\n", call, status_name(status));
        exit(4);
    }
}

static void print_row(fmi2GetRealTYPE *get_real, fmi2Component c, double time,
                      const fmi2ValueReference *vrs, size_t n, double *values) {
    check(get_real(c, vrs, n, values), "fmi2GetReal");
    printf("%a", time);
    for (size_t i = 0; i < n; i++) printf(" %a", values[i]);
    printf("\n");
}

int main(int argc, char **argv) {
    if (argc < 7) {
        fprintf(stderr, "usage: %s UNZIPPED_FMU MODEL_IDENTIFIER GUID STOP_TIME STEP VR...\n",
                argv[0]);
        return 1;
    }
    const char *folder = argv[1], *identifier = argv[2], *guid = argv[3];
    double stop = atof(argv[4]), step = atof(argv[5]);
    size_t n = (size_t)(argc - 6);
    fmi2ValueReference *vrs = calloc(n, sizeof *vrs);
    double *values = calloc(n, sizeof *values);
    for (size_t i = 0; i < n; i++) vrs[i] = (fmi2ValueReference)strtoul(argv[6 + i], NULL, 10);

    char path[4096], resources[4096];
    snprintf(path, sizeof path, "%s/binaries/linux64/%s.so", folder, identifier);
    void *library = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (library == NULL) {
        fprintf(stderr, "c_host: cannot load %s: %s\n", path, dlerror());
        return 2;
    }
    if (getenv("C_HOST_RESOURCES"))
        snprintf(resources, sizeof resources, "%s", getenv("C_HOST_RESOURCES"));
    else
        snprintf(resources, sizeof resources, "file://%s/resources", folder);

    fmi2InstantiateTYPE *instantiate = symbol(library, "fmi2Instantiate");
    fmi2SetupExperimentTYPE *setup = symbol(library, "fmi2SetupExperiment");
    fmi2EnterInitializationModeTYPE *enter = symbol(library, "fmi2EnterInitializationMode");
    fmi2ExitInitializationModeTYPE *exit_init = symbol(library, "fmi2ExitInitializationMode");
    fmi2DoStepTYPE *do_step = symbol(library, "fmi2DoStep");
    fmi2GetRealTYPE *get_real = symbol(library, "fmi2GetReal");
    fmi2TerminateTYPE *terminate = symbol(library, "fmi2Terminate");
    fmi2FreeInstanceTYPE *free_instance = symbol(library, "fmi2FreeInstance");

    fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    fmi2Component c = instantiate("c_host", fmi2CoSimulation, guid, resources, &callbacks,
                                  fmi2False, fmi2True);
    if (c == NULL) {
        fprintf(stderr, "c_host: fmi2Instantiate returned NULL\n");
        return 3;
    }
    check(setup(c, fmi2False, 0.0, 0.0, fmi2True, stop), "fmi2SetupExperiment");
    check(enter(c), "fmi2EnterInitializationMode");
    check(exit_init(c), "fmi2ExitInitializationMode");
    print_row(get_real, c, 0.0, vrs, n, values);
    long steps = (long)(stop / step + 0.5);
    for (long k = 0; k < steps; k++) {
        /* fmpy's arithmetic: points k·step, each step the difference of two of them */
        double time = k * step, next = (k + 1) * step;
        check(do_step(c, time, next - time, fmi2True), "fmi2DoStep");
        print_row(get_real, c, next, vrs, n, values);
    }
    check(terminate(c), "fmi2Terminate");
    free_instance(c);
    free(vrs);
    free(values);
    fflush(stdout);
    return 0;
}
