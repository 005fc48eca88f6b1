/* facepuppet: the command-line entry. Dispatches to the subcommands in cmd_*.c. */
#define _GNU_SOURCE
#include "command.h"

#include <limits.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#ifndef FP_VERSION_STRING
#define FP_VERSION_STRING "unknown"
#endif

/* Weak: a subcommand whose source is not part of the build is left out of the table. */
extern const fp_command fp_command_run __attribute__((weak));
extern const fp_command fp_command_live __attribute__((weak));
extern const fp_command fp_command_monitor __attribute__((weak));
extern const fp_command fp_command_info __attribute__((weak));
extern const fp_command fp_command_bench __attribute__((weak));

static const fp_command *commands(size_t i)
{
    const fp_command *all[] = {&fp_command_run, &fp_command_live, &fp_command_monitor,
                               &fp_command_info, &fp_command_bench};
    return i < sizeof all / sizeof all[0] ? all[i] : (const fp_command *)-1;
}

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
    for (size_t i = 0; commands(i) != (const fp_command *)-1; i++)
        if (commands(i))
            fprintf(f, "  %-10s %s\n", commands(i)->name, commands(i)->summary);
    fprintf(f, "\nfacepuppet COMMAND --help shows a command's options.\n"
               "Options: -h, --help   this text;  -V, --version   the version.\n");
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        usage(stderr);
        return FP_EXIT_USAGE;
    }
    const char *name = argv[1];
    if (!strcmp(name, "-h") || !strcmp(name, "--help") || !strcmp(name, "help")) {
        usage(stdout);
        return FP_EXIT_OK;
    }
    if (!strcmp(name, "-V") || !strcmp(name, "--version")) {
        printf("facepuppet %s\n", FP_VERSION_STRING);
        return FP_EXIT_OK;
    }
    for (size_t i = 0; commands(i) != (const fp_command *)-1; i++)
        if (commands(i) && !strcmp(commands(i)->name, name))
            return commands(i)->main(argc - 1, argv + 1);
    fprintf(stderr, "facepuppet: unknown command '%s' (see facepuppet --help)\n", name);
    return FP_EXIT_USAGE;
}
