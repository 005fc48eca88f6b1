/* getopt_long without its abbreviations (app_getopt.h). */
#include "app_getopt.h"

#include <stdio.h>
#include <string.h>

int fp_app_getopt(int argc, char *const *argv, const char *shortopts,
                  const struct option *longopts)
{
    int idx = -1;
    int c = getopt_long(argc, argv, shortopts, longopts, &idx);
    if (c == -1 || c == '?' || c == ':' || idx < 0) return c; /* a short option or the end */
    /* the token getopt took: the one before optind, or the one before its separate value
     * (GNU getopt permutes non-options lazily: the option is always just before optind) */
    int at = optind - 1;
    if (optarg && at >= 1 && optarg == argv[at] && at - 1 >= 1) at--;
    if (at < 1 || at >= argc) return c;
    const char *tok = argv[at];
    const char *name = longopts[idx].name;
    size_t n = strlen(name);
    if (!strncmp(tok, "--", 2) && !strncmp(tok + 2, name, n) &&
        (tok[2 + n] == '\0' || tok[2 + n] == '='))
        return c;
    const char *eq = strchr(tok, '=');
    int len = eq ? (int)(eq - tok) : (int)strlen(tok);
    fprintf(stderr, "%s: unknown option '%.*s' (did you mean --%s?)\n", argv[0], len, tok, name);
    return '?';
}
