/* The facepuppet command's subcommands. Each cmd_NAME.c defines one fp_command; main.c holds
 * the one table of them. Exit codes come from error codes through fp_app_exit_code
 * (app_util.h), never from a message's text. */
#ifndef FP_APP_COMMAND_H
#define FP_APP_COMMAND_H

/** Exit codes of the facepuppet command (sysexits.h where one fits). */
enum fp_exit {
    FP_EXIT_OK = 0,
    FP_EXIT_FAILURE = 1,     /* the work ran and failed (a numeric failure, a device gone) */
    FP_EXIT_USAGE = 64,      /* bad command line */
    FP_EXIT_DATAERR = 65,    /* bad input data: a corrupt mesh, a malformed recording */
    FP_EXIT_NOINPUT = 66,    /* an input file or device that cannot be opened */
    FP_EXIT_UNAVAILABLE = 69, /* a command this build left out (live without FP_BUILD_UI) */
    FP_EXIT_SOFTWARE = 70,   /* an internal error, out of memory */
    FP_EXIT_CANTCREAT = 73,  /* an output file that cannot be written */
    FP_EXIT_PLUGIN = 78      /* a plugin missing, of another ABI, or failing its init */
};

typedef struct fp_command {
    const char *name;
    const char *summary;                 /* one line for `facepuppet --help` */
    int (*main)(int argc, char **argv);  /* argv[0] is the subcommand's name */
} fp_command;

/** The directory holding the running executable (from /proc/self/exe), no trailing slash.
 *  Owned by the app; valid for the process's life. */
const char *fp_app_exe_dir(void);

#endif
