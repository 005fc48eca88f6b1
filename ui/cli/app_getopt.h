/* getopt_long without its abbreviations: every command parses its options through here. */
#ifndef FP_APP_GETOPT_H
#define FP_APP_GETOPT_H

#include <getopt.h>

/** getopt_long(argc, argv, shortopts, longopts, NULL), but a long option must be spelled out:
 *  the token is exactly --NAME or --NAME=VALUE. glibc takes any unambiguous prefix, so
 *  `run --frames 30` (no such option) was --frames-out 30 and wrote 225 files into ./30.
 *  An abbreviation prints "ARGV0: unknown option '--TOKEN' (did you mean --NAME?)" on stderr
 *  (argv[0] is "facepuppet CMD") and returns '?', as getopt_long does for an unknown option:
 *  the caller's usage path (exit 64, FP_EXIT_USAGE). Same globals (optind, optarg) and
 *  threads as getopt_long (the main thread, one parse at a time); argv is not copied. */
int fp_app_getopt(int argc, char *const *argv, const char *shortopts,
                  const struct option *longopts);

#endif
