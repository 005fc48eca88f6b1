/* fuzz_take.c: libFuzzer target for the take reader (core/take). The input bytes are a take
 * file read from memory: open it, look at the header and summary, read every indexed frame
 * in order and a few at random, and touch every field so that ASan/UBSan see bad reads.
 * Seeds: tests/fuzz/corpus/take/ (small valid takes written by tests/take/test_take with
 * FP_TAKE_WRITE_CORPUS=DIR). Build: fp_add_fuzz(fuzz_take fuzz_take.c LIBS fp_take CORPUS
 * tests/fuzz/corpus/take). */
#include "fp_take.h"

#include <stdint.h>
#include <string.h>

static volatile uint64_t sink;

static void touch(const fp_take_frame *f)
{
    uint64_t h = f->frame ^ (uint64_t)f->time_ns ^ f->requested;
    for (size_t i = 0; i < f->event_count; i++) {
        const fp_event *e = &f->events[i];
        const unsigned char *b = (const unsigned char *)e;
        for (size_t k = 0; k < e->header.size && k < sizeof *e; k++) h += b[k];
    }
    if (f->control) {
        const fp_control_set *c = f->control;
        h += c->active + c->intents + (uint64_t)c->radius;
        for (size_t i = 0; i < c->count; i++) h += (uint64_t)(c->start[i][0] != c->end[i][2]);
        for (size_t i = 0; i < c->channel_count; i++) h += strlen(c->channels[i].name);
    }
    sink += h;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fp_take_reader *r;
    char err[512];
    if (fp_take_reader_open_memory(data, size, "fuzz.fptake", &r, err, sizeof err)) return 0;
    const fp_take_header *h = fp_take_reader_header(r);
    sink += strlen(h->slate) + h->take + h->mapping_key_count + h->input_count;
    if (h->mesh_path) sink += strlen(h->mesh_path);
    if (h->description) sink += strlen(h->description);
    for (size_t i = 0; i < h->mapping_key_count; i++)
        sink += strlen(h->mapping_keys[i].key) + strlen(h->mapping_keys[i].value);
    for (size_t i = 0; i < h->input_count; i++) sink += strlen(h->inputs[i]);
    for (size_t i = 0; i < h->performer_count; i++) /* (1.3) */
        sink += strlen(h->performers[i].name) + (uint64_t)(h->performers[i].scale > 0) +
                (uint64_t)(h->performers[i].hand_offset[1][2] != 0);
    sink += strlen(fp_take_reader_warning(r)) + fp_take_reader_summary(r)->frames;
    fp_take_frame f;
    while (fp_take_reader_next(r, &f, err, sizeof err) == 1) touch(&f);
    size_t n = fp_take_reader_frames(r);
    for (size_t i = 0; n && i < 4; i++)
        if (!fp_take_reader_read(r, (i * 7919u + size) % n, &f, err, sizeof err)) touch(&f);
    fp_take_reader_close(&r);
    return 0;
}
