/* The session's mapping: its load, its host services, the swap and the hot reload
 * (fp_session.h: fp_session_set_mapping, fp_session_reload_mapping, ...). */
#define _GNU_SOURCE
#include "session_internal.h"

#include "fp_plugin_crash.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

/* FP_HOST_EXT_FAULT_NOTICE: an isolated mapping's fault goes into the frame's record (the
 * take) as a status event of the first input (docs/take-format.md: events carry an input's
 * index), code FP_STATUS_WARNING, hand -1. */
static void fault_notice(void *user, const char *text)
{
    fp_session *s = user;
    if (!s->input_count) return;
    fp_event ev;
    memset(&ev, 0, sizeof ev);
    ev.status.header.size = sizeof ev.status;
    ev.status.header.type = FP_EVENT_STATUS;
    ev.status.header.time_ns = fp_now_ns();
    ev.status.header.source = 0;
    ev.status.header.hand = -1;
    ev.status.code = FP_STATUS_WARNING;
    snprintf(ev.status.text, sizeof ev.status.text, "%s", text);
    fp_record_step_event(&s->record, &ev);
}

/* Load the mapping of SPEC `mapping` (from `file` where not NULL: a copy being hot-reloaded)
 * and create it with the SPEC's keys. */
int fp__session_load_mapping(fp_session *s, const char *mapping, const fp_plugin_path *path,
                             const char *file, char *err, size_t errlen)
{
    fp_spec spec;
    int rc = fp_spec_parse(mapping ? mapping : "anchored", &spec, err, errlen);
    if (rc) return rc;
    if (spec.arg) {
        snprintf(err, errlen, "mapping '%s': a mapping takes no ':ARG', only keys", mapping);
        fp_spec_clear(&spec);
        return -EINVAL;
    }
    /* isolated (fp_isolate.h): found here, loaded and created in a helper process */
    char found[4096];
    bool builtin = false;
    bool isolated = s->isolate != FP_ISOLATE_NONE &&
                    fp_plugin_find(path, FP_PLUGIN_MAPPING, file ? file : spec.name, found, sizeof found,
                                   &builtin, NULL, 0) &&
                    fp_isolate_wanted((fp_isolate_mode)s->isolate, builtin);
    if (isolated) {
        memset(&s->mapping_plugin, 0, sizeof s->mapping_plugin);
        s->mapping_plugin.kind = FP_PLUGIN_MAPPING;
        rc = (s->mapping_plugin.path = strdup(found)) ? 0 : -ENOMEM;
        if (rc) snprintf(err, errlen, "mapping '%s': out of memory", mapping);
    } else {
        rc = fp_plugin_load(path, FP_PLUGIN_MAPPING, file ? file : spec.name, &s->mapping_plugin, err, errlen);
    }
    if (!rc) {
        snprintf(s->mapping_name, sizeof s->mapping_name, "%s", spec.name);
        fp_mapping_host_init(&s->mapping_host, spec.name, s->log.fn, s->log.user);
        s->mapping_host.rig = fp_rig_step_view(&s->rig); /* FP_HOST_EXT_RIG */
        s->mapping_host.services = &s->services; /* FP_HOST_EXT_SURFACE */
        s->mapping_host.relay = &s->mapping_relay;
        s->mapping_host.fault = fault_notice;
        s->mapping_host.fault_user = s;
        const fp_mapping_factory *f = s->mapping_plugin.factory;
        char perr[1024] = "";
        fp_plugin_call_enter(s->mapping_name, "create", s->frame);
        if (isolated)
            rc = fp_isolate_mapping_create(&s->isolate_opt, found, s->mapping_name, &s->mapping_host.host,
                                           spec.params, spec.nparams, &s->mapping, perr, sizeof perr);
        else
            rc = f->create(&s->mapping_host.host, spec.params, spec.nparams, &s->mapping, perr, sizeof perr);
        fp_plugin_call_leave();
        perr[sizeof perr - 1] = '\0'; /* (a plugin that filled it to the end: read no further) */
        fp_mapping_host_drain_log(&s->mapping_host); /* what its create said */
        if (!rc && s->mapping && (!FP_HAS_FIELD(s->mapping, fp_mapping, destroy) || !s->mapping->process)) {
            /* as the helper and `plugins check` refuse it (before: called through NULL) */
            snprintf(err, errlen, "mapping '%s': the fp_mapping has size %u or no process()", mapping,
                     s->mapping->size);
            if (FP_HAS_FIELD(s->mapping, fp_mapping, destroy) && s->mapping->destroy) {
                fp_plugin_call_enter(s->mapping_name, "destroy", s->frame);
                s->mapping->destroy(s->mapping); /* (an instance too short for one: left) */
                fp_plugin_call_leave();
            }
            s->mapping = NULL;
            rc = FP_EPLUGIN_FAULT;
        } else if (rc || !s->mapping) {
            snprintf(err, errlen, "mapping '%s': %s", mapping,
                     perr[0] ? perr : rc ? "create failed" : "create returned 0 without an instance");
            s->mapping = NULL;
            rc = rc ? rc : FP_EPLUGIN_FAULT;
        } else {
            const char *id, *version;
            if (isolated && fp_isolate_mapping_about(s->mapping, &id, &version)) {
                snprintf(s->isolated_id, sizeof s->isolated_id, "%s", id);
                snprintf(s->isolated_version, sizeof s->isolated_version, "%s", version);
                memset(&s->isolated_entry, 0, sizeof s->isolated_entry);
                s->isolated_entry.id = s->isolated_id;
                s->isolated_entry.version = s->isolated_version;
                s->mapping_plugin.entry = &s->isolated_entry;
            }
            snprintf(s->mapping_spec, sizeof s->mapping_spec, "%s", mapping);
            if (!file) snprintf(s->mapping_file, sizeof s->mapping_file, "%s", s->mapping_plugin.path);
        }
    }
    fp_spec_clear(&spec);
    return rc;
}

/* FP_HOST_EXT_SURFACE: nearest vertices of the surface the fingers touch (the posed base),
 * from the engine's index of it. */
static int surface_nearest(const fp_host *host, const float (*points)[3], size_t count,
                           float max_distance, fp_surface_hit *out)
{
    const fp_session *s = ((const fp_mapping_host *)host->host_data)->services->user;
    return fp_engine_step_surface(&s->engine, fp_rig_step_posed(&s->rig, s->base), points, count,
                                  max_distance, out);
}

/* FP_HOST_EXT_BASE_VERSION: the engine counts every change of the base it indexes (the
 * posed base the mapping sees: commits, undo, reset, the rig's poses). */
static uint64_t base_version(void *user)
{
    const fp_session *s = user;
    return s->engine.base_version;
}

void fp__session_mapping_services(fp_session *s)
{
    s->services.surface.nearest = surface_nearest;
    s->services.base_version = base_version;
    s->services.user = s;
}

void fp__session_reset_mapping(fp_session *s)
{
    if (!s->mapping->reset || s->mapping_step.stopped) return;
    fp_plugin_call_enter(s->mapping_name, "reset", s->frame);
    s->mapping->reset(s->mapping);
    fp_plugin_call_leave();
}

void fp__session_destroy_mapping(fp_session *s, fp_mapping *m, const char *name)
{
    if (!m || !m->destroy) return;
    fp_plugin_call_enter(name, "destroy", s->frame);
    m->destroy(m);
    fp_plugin_call_leave();
}

/* Replace the mapping by one made from spec (from file where not NULL); the old one stays on
 * error. */
static int swap_mapping(fp_session *s, const fp_plugin_path *path, const char *spec, const char *file,
                        char *err, size_t errlen)
{
    fp_plugin old_plugin = s->mapping_plugin;
    fp_mapping *old = s->mapping;
    fp_mapping_host old_host = s->mapping_host;
    char old_name[sizeof s->mapping_name], old_spec[sizeof s->mapping_spec];
    memcpy(old_name, s->mapping_name, sizeof old_name);
    memcpy(old_spec, s->mapping_spec, sizeof old_spec);
    memset(&s->mapping_plugin, 0, sizeof s->mapping_plugin);
    s->mapping = NULL;
    char spec_copy[sizeof s->mapping_spec];
    snprintf(spec_copy, sizeof spec_copy, "%s", spec); /* spec may be s->mapping_spec */
    int rc = fp__session_load_mapping(s, spec_copy, path, file, err, errlen);
    if (rc) {
        fp_plugin_unload(&s->mapping_plugin);
        s->mapping_plugin = old_plugin;
        s->mapping = old;
        s->mapping_host = old_host;
        memcpy(s->mapping_name, old_name, sizeof old_name);
        memcpy(s->mapping_spec, old_spec, sizeof old_spec);
        return rc;
    }
    /* The old instance's host must stay valid until it is destroyed. */
    fp_mapping_host new_host = s->mapping_host;
    s->mapping_host = old_host;
    fp__session_destroy_mapping(s, old, old_name);
    fp_mapping_host_drain_log(&s->mapping_host); /* the old one's last lines, under its name */
    s->mapping_host = new_host;
    fp_mapping_step_flush(&s->mapping_step, &s->log);
    fp_plugin_unload(&old_plugin);
    s->shown = fp_rig_step_posed(&s->rig, s->base);
    s->shown_kind = SHOWN_POSED;
    fp_changed_all(&s->shown_changed);
    fp_cg_shown_ref(&s->cg);
    s->engaged = false;
    fp_history_end_gesture(&s->history);
    fp_engine_step_end_gesture(&s->engine, &s->log);
    fp_skin_reach_gesture_end(&s->gesture_reach, &s->gesture_reach_allowed, s->head.mm_per_unit, &s->log);
    fp_cg_end_gesture(&s->cg, &s->log);
    fp_engine_step_invalidate(&s->engine);
    fp_mapping_step_init(&s->mapping_step, &s->cs, s->mapping_budget_ms);
    fp__session_reset_mapping(s);
    return 0;
}

int fp_session_set_mapping(fp_session *s, const fp_plugin_path *path, const char *spec,
                           char *err, size_t errlen)
{
    if (!s || !path || !spec) {
        snprintf(err, errlen, "session: a mapping spec and a plugin path are required");
        return -EINVAL;
    }
    return swap_mapping(s, path, spec, NULL, err, errlen);
}

int fp_session_reload_mapping(fp_session *s, const char *file, char *err, size_t errlen)
{
    if (!s || !file) {
        snprintf(err, errlen, "session: a plugin file is required");
        return -EINVAL;
    }
    fp_plugin_path none;
    memset(&none, 0, sizeof none);
    none.builtin = SIZE_MAX;
    return swap_mapping(s, &none, s->mapping_spec, file, err, errlen);
}

const char *fp_session_mapping_file(const fp_session *s) { return s->mapping_file; }
const fp_plugin *fp_session_mapping_plugin(const fp_session *s) { return &s->mapping_plugin; }
const char *fp_session_mapping_name(const fp_session *s) { return s->mapping_name; }

int fp_session_mapping_fault(const fp_session *s, char *err, size_t errlen)
{
    if (!s->mapping_step.fault) return 0;
    snprintf(err, errlen, "mapping '%s': %s", s->mapping_name, s->mapping_step.fault_message);
    return s->mapping_step.fault;
}
