/* fuzz_eventlog.c: libFuzzer target for the event-log reader (core/eventlog). The input is
 * written to a file and read event by event; every event must be valid (fuzz_event_check.h),
 * and must round-trip: written back with fp_eventlog_writer and read again it gives the same
 * bytes (the format's promise that floats round-trip bit for bit). An error must name the
 * file and a line. Seeds: tests/fuzz/corpus/fuzz_eventlog (logs from tests/replay). */
#include "fuzz_file.h"
#include "fuzz_event_check.h"
#include "fp_eventlog.h"

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    fuzz_file_init("log");
    return 0;
}

#define MAX_EVENTS 256

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static fp_event events[MAX_EVENTS];
    const char *path = fuzz_file_write(data, size);
    char err[512];
    fp_eventlog_reader *r = fp_eventlog_reader_open(path, err, sizeof err);
    if (!r) {
        if (!strstr(err, path)) abort();
        return 0;
    }
    size_t n = 0;
    int rc;
    fp_event ev;
    while ((rc = fp_eventlog_reader_next(r, &ev)) == 1) {
        fuzz_check_event(&ev);
        if (n < MAX_EVENTS) events[n++] = ev;
    }
    if (rc < 0) {
        const char *msg = fp_eventlog_reader_error(r);
        if (strncmp(msg, path, strlen(path)) != 0 || msg[strlen(path)] != ':') abort();
        if (fp_eventlog_reader_next(r, &ev) != rc) abort(); /* errors stick */
    }
    fp_eventlog_reader_close(&r);
    if (!n) return 0;
    /* Round trip of what was read. */
    fp_eventlog_writer *w = fp_eventlog_writer_open(fuzz_file_path2, err, sizeof err);
    if (!w) abort();
    for (size_t i = 0; i < n; i++)
        if (fp_eventlog_writer_write(w, &events[i])) abort();
    if (fp_eventlog_writer_close(&w, err, sizeof err)) abort();
    r = fp_eventlog_reader_open(fuzz_file_path2, err, sizeof err);
    if (!r) abort();
    for (size_t i = 0; i < n; i++) {
        if (fp_eventlog_reader_next(r, &ev) != 1) abort();
        if (memcmp(&ev, &events[i], sizeof ev) != 0) abort();
    }
    if (fp_eventlog_reader_next(r, &ev) != 0) abort();
    fp_eventlog_reader_close(&r);
    return 0;
}
