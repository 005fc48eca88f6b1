/* take_internal.h: what the parts of core/take share (not installed, not public). */
#ifndef FP_TAKE_INTERNAL_H
#define FP_TAKE_INTERNAL_H

#include "fp_take.h"

#include <stdint.h>
#include <string.h>

/* File signature (16 bytes): 8 magic bytes, u16 major, u16 minor, u32 crc32 of bytes 0..11. */
#define TAKE_SIG_MAGIC "\x89" "FPTAKE\n"
#define TAKE_SIG_SIZE 16u
/* Chunk: "FPCK", 4-byte type, u32 payload length, u32 count, payload, u32 crc32. */
#define TAKE_CHUNK_MAGIC "FPCK"
#define TAKE_CHUNK_HEAD_SIZE 16u
#define TAKE_CHUNK_OVERHEAD 20u
#define TAKE_CHUNK_MAX_PAYLOAD (64u << 20)
#define TAKE_TYPE_HEAD "HEAD"
#define TAKE_TYPE_FRAMES "FRMS"
#define TAKE_TYPE_META "META"
#define TAKE_TYPE_TAIL "TAIL"
/* Frame record: fixed part, then vectors, channels, events. */
#define TAKE_FRAME_FIXED 56u
#define TAKE_VECTOR_SIZE 24u
#define TAKE_CHANNEL_SIZE 36u
#define TAKE_EVENT_HEAD 24u
#define TAKE_FRAME_FLAG_ACTIVE 1u
#define TAKE_FRAME_FLAG_CONTROL 2u
#define TAKE_COUNT_MAX (1u << 24)
/* A stored control set's radius, mesh units: the solver's range (csrbf.h: 1e-15 <= R <= 1e15). */
#define TAKE_RADIUS_MIN 1e-15
#define TAKE_RADIUS_MAX 1e15

static inline void le_put16(uint8_t *p, uint16_t v) { p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8); }
static inline void le_put32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8); p[2] = (uint8_t)(v >> 16); p[3] = (uint8_t)(v >> 24);
}
static inline void le_put64(uint8_t *p, uint64_t v) { le_put32(p, (uint32_t)v); le_put32(p + 4, (uint32_t)(v >> 32)); }
static inline void le_putf(uint8_t *p, float f) { uint32_t u; memcpy(&u, &f, 4); le_put32(p, u); }
static inline void le_putd(uint8_t *p, double d) { uint64_t u; memcpy(&u, &d, 8); le_put64(p, u); }
static inline uint16_t le_get16(const uint8_t *p) { return (uint16_t)(p[0] | p[1] << 8); }
static inline uint32_t le_get32(const uint8_t *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}
static inline uint64_t le_get64(const uint8_t *p) { return le_get32(p) | (uint64_t)le_get32(p + 4) << 32; }
static inline float le_getf(const uint8_t *p) { uint32_t u = le_get32(p); float f; memcpy(&f, &u, 4); return f; }
static inline double le_getd(const uint8_t *p) { uint64_t u = le_get64(p); double d; memcpy(&d, &u, 8); return d; }

/** Encoded size of one event (0 for a type this version cannot record). */
size_t take_event_size(const fp_event *e);

/** Reader-side buffers one decoded frame points into. */
typedef struct take_frame_buf {
    fp_event *events;
    size_t events_cap;
    float (*start)[3];
    float (*end)[3];
    size_t vec_cap;
    fp_channel *channels;
    size_t chan_cap;
    fp_control_set control;
} take_frame_buf;

/** Check a frame record's structure (rec, n bytes: exactly one record), its events' sources
 *  below `inputs` (the header's input count), and that every float the engine, the rig or an
 *  input would take is finite (control vectors, channel values, known events' fields).
 *  Returns 0, or -EBADMSG with *bad_at the offset within the record and the reason in why
 *  (whylen bytes, e.g. `channel "jaw.open" value not finite`). */
int take_frame_check(const uint8_t *rec, size_t n, size_t inputs, size_t *bad_at, char *why, size_t whylen);
/** Decode a checked record into *frame, growing buf. Returns 0 or -ENOMEM. */
int take_frame_decode(const uint8_t *rec, size_t n, take_frame_buf *buf, fp_take_frame *frame);
void take_frame_buf_free(take_frame_buf *buf);

/** Header <-> JSON text (malloc()ed). */
char *take_header_to_json(const fp_take_header *h);
/** Parse the HEAD chunk's JSON into *h; strings go into *store (one malloc()ed block, freed
 *  by the caller). Returns 0 or -EBADMSG with *bad_at (offset in the text) and a message. */
int take_header_from_json(const char *text, size_t n, fp_take_header *h, char **store,
                          size_t *bad_at, char *msg, size_t msglen);
/** Validate a header for writing. Returns 0 or -EINVAL with err. */
int take_header_check(const fp_take_header *h, char *err, size_t errlen);

/** Chunk framing: write the 16-byte chunk header into hdr. */
void take_chunk_head(uint8_t hdr[TAKE_CHUNK_HEAD_SIZE], const char type[4], uint32_t length,
                     uint32_t count);
/** Frames and bytes on disk so far (the recorder's status). */
uint64_t take_writer_frames(const fp_take_writer *w);
uint64_t take_writer_bytes(const fp_take_writer *w);

/** File signature bytes. */
void take_signature(uint8_t sig[TAKE_SIG_SIZE]);

#endif
