/*
 * fp_take_player.h: a take's (or a stack's: a path ending in .fpstack opens an
 * fp_stack_player, fp_stack_player.h, whose base layer gives the session, reader and header,
 * and whose composite is fp_take_player_positions) frames reproduced one by one, the loop `play` and `export`
 * share: open the take (core/take), make a session on its mesh (checked against the take's
 * crc32, its rig, no inputs; the mapping is never called), and apply each stored frame with
 * fp_session_play_frame (engine, guard, history as recorded), so every frame's positions are
 * bit-identical to those the recording session showed.
 *
 * Errors: 0 or a negative errno-style code with a message in err: the reader's (-ENOENT,
 * -EBADMSG a damaged header, -ENOTSUP), -EINVAL (a take that names no mesh and none given),
 * the session's (fp_session_create), -EBADMSG (another mesh: both checksums named).
 * Nothing is printed. Threads: one player belongs to one thread.
 */
#ifndef FP_TAKE_PLAYER_H
#define FP_TAKE_PLAYER_H

#include "fp_session.h"
#include "fp_take.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct fp_take_player fp_take_player;

/** Open `take_path` and make its session. mesh_path: the take's mesh from another path
 *  (its crc32 must match), NULL: the path the take names. plugin_path: where plugins are
 *  found (the session loads its default mapping; it is never called). A damaged tail is
 *  not an error: fp_take_reader_warning(fp_take_player_reader(p)) says where the take was
 *  cut, and the intact frames play. Returns 0 and *out. */
int fp_take_player_open(const char *take_path, const char *mesh_path,
                        const fp_plugin_path *plugin_path, fp_take_player **out, char *err,
                        size_t errlen);

/** fp_take_player_open with the session's log (fp_session_options.log, on the thread that
 *  plays): a frame whose stored control set the engine refuses (a vector not finite, a radius
 *  not > 0) is said there ("engine: ...; the base shown", then counted), not skipped in
 *  silence. log NULL: as fp_take_player_open. */
int fp_take_player_open_logged(const char *take_path, const char *mesh_path,
                               const fp_plugin_path *plugin_path, fp_session_log_fn log,
                               void *log_user, fp_take_player **out, char *err, size_t errlen);

/** Play the next frame: 1 and *frame (the reader's, valid until the next call), *st (may be
 *  NULL); 0 after the last; or the reader's negative code with err. The frame's positions
 *  are fp_session_positions(fp_take_player_session(p)). */
int fp_take_player_next(fp_take_player *p, fp_take_frame *frame, fp_frame_stats *st,
                        char *err, size_t errlen);

/** The player's session, reader and the take's header: the player owns them (never destroy or
 *  close them yourself); valid until fp_take_player_close. [main-thread]. */
fp_session *fp_take_player_session(fp_take_player *p);
fp_take_reader *fp_take_player_reader(fp_take_player *p);
const fp_take_header *fp_take_player_header(const fp_take_player *p);
/** The mesh path the session was made from (the take's or the one given); the player's,
 *  valid until fp_take_player_close. */
const char *fp_take_player_mesh_path(const fp_take_player *p);

/** The frame's positions: the session's (a take), or the stack's composite (a .fpstack):
 *  n x 3 floats, the player's, valid until the next fp_take_player_next. */
const float *fp_take_player_positions(const fp_take_player *p);

/** Save the frame's positions (fp_take_player_positions) on the session's mesh to path, as
 *  fp_session_save_ex (format by extension; *dropped may be NULL). Returns 0 or its code. */
int fp_take_player_save(const fp_take_player *p, const char *path, unsigned *dropped, char *err,
                        size_t errlen);

/** The stack being played (fp_stack_player.h), NULL for a take. The player's. */
struct fp_stack_player *fp_take_player_stack(fp_take_player *p);

/** Millimetres per mesh unit of the take: 1 / the scale of its recorded calibration (the
 *  first hand that has one), else the session's (the rig's, or detected from the head). */
double fp_take_player_mm_per_unit(const fp_take_player *p);

/** Close the session and the reader, free the player, set *p to NULL. NULL-safe. */
void fp_take_player_close(fp_take_player **p);

#ifdef __cplusplus
}
#endif
#endif
