/* facepuppet: the command-line entry. Dispatches to the subcommands in cmd_*.c. */
#define _GNU_SOURCE
#include "command.h"
#include "fp_isolate.h"
#include "fp_plugin_crash.h"

#include <limits.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#ifndef FP_VERSION_STRING
#define FP_VERSION_STRING "unknown"
#endif

/* The subcommands, in --help order. Each is defined in its cmd_NAME.c; `live` exists in
 * every build and says so when the viewer was not built (FP_BUILD_UI off). */
extern const fp_command fp_command_run, fp_command_live, fp_command_monitor, fp_command_info,
    fp_command_bench, fp_command_pose, fp_command_plugins, fp_command_takes, fp_command_play,
    fp_command_export, fp_command_calibrate;
static const fp_command *const commands[] = {&fp_command_run, &fp_command_live,
                                             &fp_command_calibrate,
                                             &fp_command_monitor, &fp_command_info,
                                             &fp_command_pose, &fp_command_takes,
                                             &fp_command_play, &fp_command_export,
                                             &fp_command_plugins,
                                             &fp_command_bench};
enum { NCOMMANDS = sizeof commands / sizeof commands[0] };

const char *fp_app_exe_dir(void)
{
    static char dir[PATH_MAX];
    if (!dir[0]) {
        ssize_t n = readlink("/proc/self/exe", dir, sizeof dir - 1);
        if (n <= 0) {
            strcpy(dir, ".");
        } else {
            dir[n] = '\0';
            char *slash = strrchr(dir, '/');
            if (slash) *slash = '\0';
        }
    }
    return dir;
}

static void usage(FILE *f)
{
    fprintf(f, "usage: facepuppet COMMAND [OPTIONS]\n\n"
               "Live facial puppeteering: data gloves drive compactly supported radial basis\n"
               "functions (Wendland CSRBFs) that deform a 3D face in real time.\n\n"
               "Commands:\n");
    for (size_t i = 0; i < NCOMMANDS; i++)
        fprintf(f, "  %-10s %s\n", commands[i]->name, commands[i]->summary);
    fprintf(f, "\nfacepuppet COMMAND --help (or facepuppet help COMMAND) shows a command's\n"
               "options.\n"
               "Options: -h, --help   this text;  -V, --version   the version.\n\n"
               "Errors name the file and line, the option, the SPEC or the plugin at fault.\n"
               "Exit status (sysexits.h), the same for every command:\n"
               "   0  done\n"
               "   1  the work ran and failed (the engine could not solve, a device went away)\n"
               "  64  usage: a bad option or SPEC key (EINVAL)\n"
               "  65  bad input data: a malformed mesh, recording or calibration (EBADMSG,\n"
               "      ERANGE, EPROTO, ENOTSUP)\n"
               "  66  an input that cannot be opened: file, device or display (ENOENT, EACCES,\n"
               "      ENODEV, EBUSY)\n"
               "  69  a command this build left out (live without the viewer)\n"
               "  70  internal error, out of memory\n"
               "  73  an output that cannot be created or written (ENOENT or EACCES on an\n"
               "      output, EIO, ENOSPC, EROFS), or one that exists: no command overwrites\n"
               "      a file without --force (refused before any work, naming the file)\n"
               "  78  a plugin missing, built for another ABI, failing its init, or stopped\n"
               "      for a fault (it wrote past the host's arrays; create returned no instance)\n"
               "A plugin's create() error goes through the same table by its code (EINVAL 64,\n"
               "EBADMSG 65, ENOENT/ENODEV 66...). A crash inside a plugin in process prints\n"
               "\"fatal signal SIG... in plugin 'NAME' during CALL (frame N)\" and ends with\n"
               "128 + the signal; in an isolated one (run and live's --isolate: a third\n"
               "party's mapping or input by default) it ends only that plugin's helper\n"
               "process, named once in the log, and the run goes on. SIGINT or SIGTERM ends a run after its frame (0); a frame\n"
               "stuck in a plugin call (one that never returns) is abandoned 0.1 s after it,\n"
               "the take closed, and the run ends with 128 + the signal (130, 143). They stop\n"
               "an export at its next frame, its temporary file removed: 130, 143.\n\n"
               "Environment: FACEPUPPET_PLUGIN_PATH  more plugin folders (colon-separated,\n"
               "absolute); FACEPUPPET_DEBUG=1  show plugins' and the session's debug lines.\n");
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        usage(stderr);
        return FP_EXIT_USAGE;
    }
    const char *name = argv[1];
    /* `facepuppet help CMD` is `facepuppet CMD --help`, as git and cmake do it. */
    /* a command's argv[0] is "facepuppet CMD": getopt's messages start with it */
    static char prog[64];
    if (!strcmp(name, "help") && argc >= 3) {
        for (size_t i = 0; i < NCOMMANDS; i++) {
            if (strcmp(commands[i]->name, argv[2])) continue;
            snprintf(prog, sizeof prog, "facepuppet %s", commands[i]->name);
            char *help_argv[] = { prog, "--help", NULL };
            return commands[i]->main(2, help_argv);
        }
        fprintf(stderr, "facepuppet help: unknown command '%s' (see facepuppet --help)\n",
                argv[2]);
        return FP_EXIT_USAGE;
    }
    if (!strcmp(name, "-h") || !strcmp(name, "--help") || !strcmp(name, "help")) {
        usage(stdout);
        return FP_EXIT_OK;
    }
    if (!strcmp(name, "-V") || !strcmp(name, "--version")) {
        printf("facepuppet %s\n", FP_VERSION_STRING);
        return FP_EXIT_OK;
    }
    /* The hidden helper modes of an isolated mapping and an isolated input (fp_isolate.h): no
     * crash handler, so a fault ends the helper by its signal and the host sees it. */
    if (!strcmp(name, FP_ISOLATE_HELPER_ARG)) return fp_isolate_helper_main(argc, argv);
    if (!strcmp(name, FP_ISOLATE_INPUT_HELPER_ARG)) return fp_isolate_input_helper_main(argc, argv);
    /* A fatal signal inside a plugin call names the plugin, the call and the frame. */
    fp_plugin_crash_install();
    for (size_t i = 0; i < NCOMMANDS; i++) {
        if (strcmp(commands[i]->name, name)) continue;
        snprintf(prog, sizeof prog, "facepuppet %s", commands[i]->name);
        argv[1] = prog;
        return commands[i]->main(argc - 1, argv + 1);
    }
    fprintf(stderr, "facepuppet: unknown command '%s' (see facepuppet --help)\n", name);
    return FP_EXIT_USAGE;
}
