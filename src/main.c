/* main.c: drape's command line: global options and subcommand dispatch.
 * Only the command line prints or exits (STYLE.md 6). */
#include <dlfcn.h>
#include <errno.h>
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <gsl/gsl_errno.h>

#include "cli.h"
#include "cli_data.h"
#include "drape/error.h"

static const char usage_text[] =
    "Usage: drape COMMAND [OPTIONS] [FILE...]\n"
    "\n"
    "Simulate the drape of woven fabrics from Kawabata (KES-F) data with the\n"
    "energy method of Chen & Xu (2000), after Breen et al. (1994).\n"
    "\n"
    "Commands:\n"
    "  check FILE.yaml...   validate fabric and scene files and print an SI\n"
    "                       summary (masses, Kawabata curves, bending lengths,\n"
    "                       stiffness bounds)\n"
    "  run [SCENE.yaml]     run a scene (default scenes/cusick.yaml: a drape\n"
    "                       test of 12 specimens); one JSON object on stdout;\n"
    "                       `drape run --help` for options\n"
    "  batch SCENE.yaml FABRIC.yaml...\n"
    "                       run a scene once per fabric, N at a time; one CSV\n"
    "                       row per fabric in DIR/results.csv (docs/batch.md)\n"
    "  import arcsim|kes FILE...\n"
    "                       write fabric files from ARCSim material JSON or a\n"
    "                       CSV table of KES-F summary values\n"
    "  compare REF.json OTHER.json\n"
    "                       are two drape tests (ensembles) distinguishable?\n"
    "                       exact test of the node counts, Welch's test of\n"
    "                       the mean DC (docs/ensemble.md)\n"
    "  bench [SCENE.yaml]   work-precision benchmark of the integrators (CSV:\n"
    "                       time, counters, error against a reference);\n"
    "                       --kernels: cost of one force and Jacobian\n"
    "                       evaluation by lattice size (docs/performance.md)\n"
    "  help                 this help\n"
    "\n"
    "Options:\n"
    "  -h, --help           show this help and exit\n"
    "  -V, --version        show the version and exit\n"
    "\n"
    "Quantities take the unit strings of the input files, with or without a\n"
    "space: --spacing '5 mm', --spacing 5mm; a bare number is SI.\n"
    "\n"
    "Files: a relative path that names no file in the current directory (the\n"
    "default scene, scenes/table.yaml, fabrics/denim-wang.yaml) is read from\n"
    "drape's data directory: $DRAPE_DATA if set, else the checkout the binary\n"
    "was built in, else the installed one; `drape --version' prints them.\n"
    "\n"
    "Threads: drape runs in one thread (ensembles and batches run processes\n"
    "in parallel, -j); it sets OMP_THREAD_LIMIT=1 for CHOLMOD's OpenMP loops\n"
    "unless the environment sets it; with the limit at 1 it runs them in the\n"
    "calling thread, with another it gives them to libgomp's threads.\n"
    "\n"
    "Exit status:\n"
    "  0    success\n"
    "  1    invalid input (malformed YAML, bad key, type, unit or value)\n"
    "  2    bad command line\n"
    "  3    input/output error (missing or unreadable file, unwritable output)\n"
    "  4    numerical failure (the run ended with status `failed`)\n"
    "  5    out of memory, or a lattice too large to allocate\n"
    "  6    drape batch: at least one run failed or could not run\n"
    "  70   internal error (a bug in drape)\n"
    "  130  interrupted by SIGINT (drape run: status `interrupted`, resumable\n"
    "       with --resume; drape batch: finished rows kept)\n"
    "  143  interrupted by SIGTERM (drape run, as above)\n";

/* drape is single-threaded by design: batch runs parallelise over
 * processes.  Debian's CHOLMOD runs its supernodal factorisation in OpenMP
 * threads and OpenBLAS starts its own; on a shared 2-core machine those
 * threads cost more than they gain (the static Cusick solve took 0.8-1.05 s
 * CPU with them against 0.33 s without; docs/equilibrium.md).  The runtimes
 * read OMP_NUM_THREADS / OPENBLAS_NUM_THREADS when they load, before main,
 * so set the thread counts through their API, looked up at run time so
 * that drape does not link libgomp itself. */
static void single_threaded(void)
{
    static const char *const names[] = {"omp_set_num_threads", "openblas_set_num_threads"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        void *sym = dlsym(RTLD_DEFAULT, names[i]);
        if (sym) {
            void (*set)(int);
            memcpy(&set, &sym, sizeof set); /* object -> function pointer, POSIX */
            set(1);
        }
    }
    /* OpenBLAS has already started its thread pool when it loaded, and
     * those threads spin (sched_yield) for about 2^28 cycles before they
     * sleep: 0.1 s of CPU in every drape process, 12 % of a one-specimen
     * fall run (measured with perf).  Its own fork handler,
     * blas_thread_shutdown_ (exported by OpenBLAS 0.3.21), stops them; with
     * one thread OpenBLAS never starts them again. */
    void *sym = dlsym(RTLD_DEFAULT, "blas_thread_shutdown_");
    if (sym) {
        int (*shutdown)(void);
        memcpy(&shutdown, &sym, sizeof shutdown);
        shutdown();
    }
}

/* CHOLMOD's supernodal kernels ask for CHOLMOD_OMP_NUM_THREADS (4, fixed
 * when Debian built it) in the num_threads clauses of their OpenMP loops,
 * which omp_set_num_threads does not lower; only the thread limit does,
 * and libgomp reads OMP_THREAD_LIMIT once, when it loads.  Measured on a
 * 0.5 cm Cusick specimen (5700 unknowns, supernodal): 7.6 s of CPU (3.0 s
 * of it in the kernel, 1.5 million futex calls) and 7.2 s wall with the
 * threads, 2.5 s and 2.5 s with OMP_THREAD_LIMIT=1, the same drape.  So
 * unless the caller set the limit, drape sets it to 1 and executes itself
 * again (once: the limit is then set); without /proc it goes on as it is.
 * docs/performance.md, "Threads". */
static void limit_openmp(char **argv)
{
    if (getenv("OMP_THREAD_LIMIT")) return;
    if (setenv("OMP_THREAD_LIMIT", "1", 1) != 0) return;
    execv("/proc/self/exe", argv);
}

/* OpenMP regions in the calling thread.  Even with the thread limit at 1,
 * libgomp opens a team of one for every OpenMP region and closes it with a
 * futex wake-up: one system call per region, about 220 per supernodal
 * factorisation of the 1 cm fall's matrix (138,000 in a default specimen,
 * `strace -c`), 14-22 % of a specimen's CPU at 1 cm and finer on this
 * virtual machine (the same results bit for bit; docs/performance.md,
 * "OpenMP regions in one thread").  GCC compiles `#pragma omp parallel`
 * (with `for`, static schedule, as in CHOLMOD) into a call of
 * GOMP_parallel, libgomp's entry point since GCC 4.9, with the region's
 * body outlined as fn; drape defines GOMP_parallel, and the dynamic linker
 * binds CHOLMOD's calls to the executable's definition.  With the limit at
 * 1 it runs fn in the calling thread, which is what a team of one does:
 * the outlined body splits its loop by omp_get_num_threads() and
 * omp_get_thread_num(), 1 and 0 outside a region.  With another limit (the
 * caller's OMP_THREAD_LIMIT) it hands the region to libgomp's.  Only
 * drape's executable defines it (the tests link libdrape.a with libgomp's
 * own; test_openmp_inline compares the two). */
void GOMP_parallel(void (*fn)(void *), void *data, unsigned num_threads, unsigned flags);
/* libgomp's GOMP_parallel when the regions go to its threads, else NULL */
static void (*gomp_parallel_next)(void (*)(void *), void *, unsigned, unsigned);

void GOMP_parallel(void (*fn)(void *), void *data, unsigned num_threads, unsigned flags)
{
    if (gomp_parallel_next) gomp_parallel_next(fn, data, num_threads, flags);
    else fn(data);
}

/* After limit_openmp: inline unless the caller set another limit. */
static void openmp_inline(void)
{
    const char *lim = getenv("OMP_THREAD_LIMIT");
    if (lim && strcmp(lim, "1") == 0) return;
    void *sym = dlsym(RTLD_NEXT, "GOMP_parallel");
    if (sym) memcpy(&gomp_parallel_next, &sym, sizeof gomp_parallel_next);
}

static int dispatch(int argc, char **argv);

/* What a command printed on stdout must have reached it: a write that
 * failed (a full disk, a closed pipe with SIGPIPE ignored) and that the
 * command did not see itself (`drape check` and the help texts print and
 * return 0) makes the exit status that of an I/O error, as the commands
 * that check their own result do ("cannot write the result"). */
static int finish_stdout(int rc)
{
    errno = 0;
    if (fflush(stdout) == 0 && !ferror(stdout)) return rc;
    if (rc != 0) return rc; /* the command failed already, and said so */
    int e = errno;
    fprintf(stderr, "drape: <stdout>: cannot write the output%s%s\n", e ? ": " : "",
            e ? strerror(e) : "");
    return drape_error_exit_status(DRAPE_E_IO);
}

int main(int argc, char **argv)
{
    return finish_stdout(dispatch(argc, argv));
}

static int dispatch(int argc, char **argv)
{
    limit_openmp(argv);
    openmp_inline();
    gsl_set_error_handler_off(); /* GSL's default handler aborts */
    single_threaded();

    static const struct option opts[] = {
        {"help", no_argument, NULL, 'h'},
        {"version", no_argument, NULL, 'V'},
        {NULL, 0, NULL, 0}};
    /* global options come before the command: stop at the first non-option */
    int c;
    opterr = 0;
    if ((c = drape_cli_args_unambiguous(argc, argv, "+hV", opts, "drape")) != 0) return c;
    while ((c = getopt_long(argc, argv, "+hV", opts, NULL)) != -1) {
        switch (c) {
        case 'h': fputs(usage_text, stdout); return 0;
        case 'V':
            printf("drape %s\n", DRAPE_VERSION);
            drape_cli_data_describe(stdout);
            return 0;
        default:
            fprintf(stderr, "drape: unknown option `%s'\n%s", argv[optind - 1],
                    "Try `drape --help'.\n");
            return drape_error_exit_status(DRAPE_E_USAGE);
        }
    }
    if (optind >= argc) {
        fputs(usage_text, stderr);
        return drape_error_exit_status(DRAPE_E_USAGE);
    }
    const char *cmd = argv[optind];
    int sub_argc = argc - optind;
    char **sub_argv = argv + optind;
    optind = 0; /* reset getopt for the subcommand (GNU: 0 re-initialises) */
    /* the subcommands' getopt names an unknown option or a missing
     * argument itself ("drape run: unrecognized option '--x'") */
    opterr = 1;
    static char prog[64];
    snprintf(prog, sizeof prog, "drape %.50s", cmd);
    sub_argv[0] = prog;
    if (strcmp(cmd, "check") == 0) return drape_cli_check(sub_argc, sub_argv);
    if (strcmp(cmd, "run") == 0) return drape_cli_run(sub_argc, sub_argv);
    if (strcmp(cmd, "batch") == 0) return drape_cli_batch(sub_argc, sub_argv);
    if (strcmp(cmd, "import") == 0) return drape_cli_import(sub_argc, sub_argv);
    if (strcmp(cmd, "bench") == 0) return drape_cli_bench(sub_argc, sub_argv);
    if (strcmp(cmd, "compare") == 0) return drape_cli_compare(sub_argc, sub_argv);
    if (strcmp(cmd, "help") == 0) { fputs(usage_text, stdout); return 0; }
    fprintf(stderr, "drape: unknown command `%s'\nTry `drape --help'.\n", cmd);
    return drape_error_exit_status(DRAPE_E_USAGE);
}
