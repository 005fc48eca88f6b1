/*
 * facepuppet/errors.h: facepuppet's own error codes, beside the negative errno values. Part
 * of the plugin ABI (facepuppet/plugin.h includes it); the host's fp_error.h uses the same
 * definitions.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * Every fallible call of the ABI returns 0 (or a count) or a negative code: a negative errno
 * value (docs/plugin-guide.md, installed with the SDK, lists which errno means what and the
 * exit status each leads to) or one of the codes below. A plugin never needs to return one of
 * these; it may meet them in what the host hands back or reports (FP_EPLUGIN_FAULT when a
 * mapping is stopped for writing past its arrays, FP_ENUMERIC from FP_HOST_EXT_SURFACE).
 */
#ifndef FACEPUPPET_ERRORS_H
#define FACEPUPPET_ERRORS_H

/** facepuppet's own error codes, beside the negative errno values; all below -1000. A plugin
 *  never needs to return one; it may meet them in what the host reports (the host's messages
 *  name them). The values are part of the ABI. */
enum fp_error_code {
    FP_EPLUGIN_NOT_FOUND = -1001,  /* no <kind>-<name>.so in any plugin folder */
    FP_EPLUGIN_DLOPEN = -1002,     /* dlopen failed (missing library, bad ELF) */
    FP_EPLUGIN_NO_ENTRY = -1003,   /* no facepuppet_plugin_entry symbol */
    FP_EPLUGIN_ABI = -1004,        /* built against an incompatible ABI */
    FP_EPLUGIN_INIT = -1005,       /* the entry's init returned false */
    FP_EPLUGIN_NO_FACTORY = -1006, /* no factory of the asked kind, or a bad one */
    FP_EPLUGIN_FAULT = -1007,      /* a plugin misbehaved at run time (overrun, NaN, crash, or
                                      create returned 0 without an instance) */
    FP_ENUMERIC = -1101            /* the engine could not solve (singular or indefinite); a
                                      host extension (FP_HOST_EXT_SURFACE) may pass it on */
};

#endif /* FACEPUPPET_ERRORS_H */
