/* A mapping written in C++ against the installed headers, as a plugin author may: the entry
 * declared with FP_PLUGIN_DECLARE_ENTRY. In C++ a namespace-scope const object has internal
 * linkage, so the macro must give the entry C linkage for the host to find it (before: the
 * symbol was not exported, g++ warned "'visibility' attribute ignored" and the host said "no
 * symbol 'facepuppet_plugin_entry'"). It shows the base: an inactive, empty set. */
#include <facepuppet/mapping_util.h>
#include <facepuppet/plugin.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace {

int process(fp_mapping *, const fp_frame_input *in, fp_control_set *out)
{
    out->active = false;
    out->intents = 0;
    out->count = 0;
    out->channel_count = 0;
    out->radius = in->radius;
    return 0;
}

void destroy(fp_mapping *m) { delete m; }

const fp_param_info keys[] = {{nullptr, FP_PARAM_BOOL, 0, 0, nullptr, nullptr, nullptr, nullptr}};

int create(const fp_host *, const fp_param *params, size_t nparams, fp_mapping **out, char *err,
           size_t errlen)
{
    fpmu_value v[1];
    int rc = fpmu_params_parse("cxx", keys, params, nparams, v, err, errlen);
    if (rc) return rc;
    fp_mapping *m = new fp_mapping{};
    m->size = sizeof *m;
    m->process = process;
    m->destroy = destroy;
    *out = m;
    return 0;
}

const fp_mapping_factory factory = {sizeof(fp_mapping_factory), "cxx", "a mapping in C++ (tests)",
                                    "cxx", create, keys};

const void *get_factory(const char *id) { return std::strcmp(id, FP_MAPPING_FACTORY_ID) ? nullptr : &factory; }

} // namespace

FP_PLUGIN_DECLARE_ENTRY = {{FP_PLUGIN_ABI_MAJOR, FP_PLUGIN_ABI_MINOR}, "org.facepuppet.test.map-cxx", "1.0",
                           nullptr, nullptr, get_factory};
