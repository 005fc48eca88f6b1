/* fuzz_osc.c: libFuzzer target for the OSC packet decoder of input-osc (plugins/input-osc/
 * input_osc.c: bundles, timetags, liblo's message parser, the facepuppet, leap and mediapipe
 * address formats), the bytes any host on the network may send. The plugin's source is
 * included so that its packet handler is reachable without a socket round trip. Input: byte 0
 * picks the format, hand, clock (0x40: recording) and mirror of an instance made for this input (create() on port 0,
 * a fake host), the rest is split at each 0xFF 0xFE 0xFD 0xFC into datagrams handed to the
 * handler as recvfrom would, 1 ms apart. Every event pushed must be valid
 * (fuzz_event_check.h: finite floats, known type). Seeds: tests/fuzz/corpus/fuzz_osc
 * (packets sent by tools/osc-send, one per format). */
#include "../../plugins/input-osc/input_osc.c"
#include "../../plugins/input-osc/osc_spec.c"

#include "fuzz_event_check.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static int64_t fake_now = 1000000000;

static bool fake_push(const fp_host *host, const fp_event_header *h)
{
    (void)host;
    fuzz_check_event((const fp_event *)h);
    return true;
}

static int64_t fake_now_ns(const fp_host *host)
{
    (void)host;
    return fake_now;
}

static void fake_log(const fp_host *host, fp_log_level level, const char *message)
{
    (void)host;
    (void)level;
    if (!message || !memchr(message, 0, 4096)) abort();
}

static const fp_host host = {.size = sizeof(fp_host), .push_event = fake_push,
                             .now_ns = fake_now_ns, .log = fake_log};

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1) return 0;
    static const char *formats[4] = {"facepuppet", "leap", "mediapipe", "auto"};
    static const char *hands[3] = {"both", "left", "right"};
    fp_param params[4] = {{"format", formats[data[0] % 4]}, {"hand", hands[data[0] / 4 % 3]},
                          {"mirror", data[0] & 0x80 ? "1" : "0"},
                          {"clock", data[0] & 0x40 ? "recording" : "arrival"}};
    fp_input *in = NULL;
    char err[256];
    if (osc_create(&host, "0", params, 4, &in, err, sizeof err)) abort();
    osc_input *o = in->plugin_data;
    data++;
    size--;
    static const uint8_t sep[4] = {0xFF, 0xFE, 0xFD, 0xFC};
    while (size) {
        const uint8_t *cut = memmem(data, size, sep, sizeof sep);
        size_t n = cut ? (size_t)(cut - data) : size;
        if (n > PACKET_MAX) n = PACKET_MAX;
        memcpy(o->buf, data, n);
        fake_now += 1000000;
        handle_packet(o, o->buf, n, fake_now, fake_now, 0);
        timers(o, fake_now);
        size_t skip = cut ? n + sizeof sep : n;
        data += skip;
        size -= skip;
    }
    fake_now += 5000000000LL; /* past the timeout: the disconnect path */
    timers(o, fake_now);
    in->destroy(in);
    return 0;
}
