/* cli_args.c: checks of a command line shared by the subcommands, made
 * before getopt_long: abbreviations of long options that match more than
 * one option. */
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

/* The option argv[i] = "--NAME[=VALUE]" stands for: the exact name, else
 * the only option NAME begins; NULL when none or several do (*n_match:
 * how many begin with NAME). */
static const struct option *long_match(const char *name, size_t len, const struct option *opts,
                                       int *n_match)
{
    const struct option *found = NULL;
    *n_match = 0;
    for (const struct option *o = opts; o->name; o++) {
        if (strncmp(o->name, name, len) != 0) continue;
        if (strlen(o->name) == len) { /* an exact name wins */
            *n_match = 1;
            return o;
        }
        found = o;
        ++*n_match;
    }
    return *n_match == 1 ? found : NULL;
}

int drape_cli_args_unambiguous(int argc, char *const argv[], const char *shortopts,
                               const struct option *opts, const char *cmd)
{
    /* getopt_long stops at the first non-option with a leading '+' (or
     * POSIXLY_CORRECT); the words after it are not options */
    int stop_at_word = shortopts[0] == '+' || getenv("POSIXLY_CORRECT") != NULL;
    while (shortopts[0] == '+' || shortopts[0] == '-' || shortopts[0] == ':') shortopts++;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "--") == 0) break;
        if (a[0] != '-' || a[1] == 0) {
            if (stop_at_word) break;
            continue;
        }
        if (a[1] == '-') {
            const char *name = a + 2;
            size_t len = strcspn(name, "=");
            int n = 0;
            if (len == 0) continue;
            const struct option *o = long_match(name, len, opts, &n);
            if (n > 1) {
                fprintf(stderr, "%s: option `--%.*s' is ambiguous; possibilities:", cmd, (int)len,
                        name);
                const char *sep = " ";
                for (const struct option *p = opts; p->name; p++)
                    if (strncmp(p->name, name, len) == 0) {
                        fprintf(stderr, "%s--%s", sep, p->name);
                        sep = ", ";
                    }
                fprintf(stderr, "\nTry `%s --help'.\n", cmd);
                return drape_error_exit_status(DRAPE_E_USAGE);
            }
            /* its value is the next word, whatever it looks like */
            if (o && o->has_arg == required_argument && !name[len]) i++;
            continue;
        }
        for (int j = 1; a[j]; j++) { /* a cluster of short options, -qj4 */
            const char *p = a[j] == ':' ? NULL : strchr(shortopts, a[j]);
            if (!p || p[1] != ':') continue;
            if (p[2] != ':' && !a[j + 1]) i++; /* -j 4 */
            break;
        }
    }
    return 0;
}
