/* fuzz_replay.c: libFuzzer target for input-replay's loader (plugins/input-replay/
 * replay_load.c): the Leap joints and angles CSVs (core/hand/leapcsv.c) and event logs
 * (core/eventlog), told apart by their first line, as `--input replay:FILE` reads them. The
 * input is written to a file and loaded. A load must give items whose times start at 0 and
 * never decrease, a loop period past the duration, and valid events (fuzz_event_check.h); a
 * refusal a negative code and a message naming the file. Seeds: tests/fuzz/corpus/fuzz_replay
 * and ../shared/data/hands/leap-motion (libFuzzer keeps the first 64 KiB of the large ones). */
#include "fuzz_file.h"
#include "fuzz_event_check.h"
#include "replay_load.h"

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    fuzz_file_init("rec");
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fuzz_file_write(data, size);
    replay_recording rec;
    char err[512];
    int hands = size ? 1 + data[size - 1] % 3 : REPLAY_HAND_BOTH;
    int rc = replay_load(path, hands, &rec, err, sizeof err);
    if (rc) {
        if (rc > 0 || rec.items || !strstr(err, path)) abort();
        return 0;
    }
    if (!rec.count || !rec.items || rec.items[0].t_ns != 0) abort();
    for (size_t i = 0; i < rec.count; i++) {
        if (i && rec.items[i].t_ns < rec.items[i - 1].t_ns) abort();
        fuzz_check_event(&rec.items[i].event);
    }
    if (rec.duration_ns != rec.items[rec.count - 1].t_ns || rec.loop_period_ns <= rec.duration_ns)
        abort();
    replay_recording_free(&rec);
    return 0;
}
