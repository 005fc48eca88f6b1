/* The export side of run, play and export (ui/cli): one exporter fed after each frame, and
 * the summary line all three print (core/export, fp_export.h). */
#ifndef FP_APP_EXPORT_H
#define FP_APP_EXPORT_H

#include "fp_export.h"

#include <stdbool.h>
#include <stdio.h>

struct fp_session; /* fp_session.h */

/** A frame's bytes in `format` for `mesh`, about: a point cache's 12 a vertex (MDD 4 more a
 *  frame), an OBJ sequence's fp_app_obj_frame_bytes; 0 where it is not known ahead (glTF,
 *  whose morph targets are reduced). Pure; any thread. */
double fp_app_export_frame_bytes(fp_export_format format, const struct fp_mesh *mesh);

/** The name an export of a take or stack gives what it writes (the glTF animation and its
 *  root node "NAME_metres", obj-seq's NAME_NNNNNN files): a take's "SLATE_TNNN" (slate and
 *  take from its header), a stack's file name without its folder and .fpstack ("face_S001":
 *  not its base take's, which named a stack's animation as the base take alone). Into buf
 *  (n bytes, cut to fit). */
void fp_app_export_name(const char *path, bool stack, const char *slate, unsigned take, char *buf,
                        size_t n);

/** Bytes this process may still allocate, about: MemAvailable + SwapFree (/proc/meminfo), or
 *  less where RLIMIT_AS (ulimit -v) leaves less above the process's size now (VmSize); 0 where
 *  neither is known. Any thread. */
double fp_app_memory_budget(void);

/** A glTF or GLB export (eo->format; other formats: nothing done, 0) of `frames` frames (known
 *  before any work; 0: not known) of `mesh`: more than FP_EXPORT_GLTF_MAX_FRAMES is refused,
 *  "CMD: WHAT: N frames: a glTF export holds at most 46340 (HINT); nothing written", exit 64;
 *  else eo->frames_expected and eo->memory_budget (fp_app_memory_budget) are set, so that the
 *  exporter stops as soon as the frames played show that its finish cannot fit, and where
 *  moving every vertex would not fit it is said first unless quiet. Returns 0 or 64. [main-thread] */
int fp_app_export_gltf_plan(const char *cmd, const char *what, const char *hint, double frames,
                            const struct fp_mesh *mesh, bool quiet,
                            fp_export_options *eo);

/** `--export FILE` of run and play: the format from FILE's extension (.gltf .glb .pc2 .mdd),
 *  the exporter begun on the session's loaded mesh (a glTF turned by the session's face axes,
 *  fp_session_face_axes, to +y up and +z front). frames: how many the run will
 *  write when known before it (play: the take's; run: --duration's), else 0; a point cache
 *  larger than its file system's free room is then refused before any work
 *  (fp_app_output_fits). Prints "CMD: ..." on error and returns the exit status (64 an
 *  unknown extension, 73 an output not writable or too large); 0 and *x (owned by the
 *  caller: fp_app_export_close or fp_export_abort). The thread that feeds *x. */
int fp_app_export_open(const char *cmd, const char *file, const struct fp_session *s,
                       double mm_per_unit, const char *name, double frames, fp_exporter **x);

/** Finish *x and print the summary to f unless quiet: "CMD: exported N frames to FILE
 *  (FORMAT): " then for glTF "K = K morph targets, SIZE MB, largest error E mm (limit L mm);
 *  in metres: root node scale S (M mm per mesh unit)", for the others "SIZE MB, every frame
 *  exact; mesh units of M mm (scale S for metres)", and always "; R fps" (the rate the
 *  exporter was given, else measured from the frames' times); what the format dropped as a
 *  note. An error prints "CMD: OPTION: MESSAGE" ("facepuppet run: --export: FILE: write
 *  failed: ..."), or "CMD: MESSAGE" with option NULL (the export command, whose output is
 *  the command's own: "facepuppet export: FILE: write failed: ..."); core/export's messages
 *  begin with FILE. Returns the exit status (0, or 73/65/70 by fp_app_exit_code). */
int fp_app_export_close(const char *cmd, const char *option, fp_exporter **x,
                        fp_export_format format, const char *file, double limit_mm, bool quiet,
                        FILE *f);

/** "CMD: note: FILE cannot hold the input's polygons, UV seams, ..." on stderr where a mesh
 *  written to another format lost something (fp_mesh_save_ex's dropped bits); nothing when
 *  dropped is 0 or quiet. */
void fp_app_print_dropped(const char *cmd, const char *file, unsigned dropped, bool quiet);

/** Whether the file at path, whose first n bytes are h (12 suffice), is a point cache: PC2
 *  by its signature ("POINTCACHE2\0"), MDD (which has none) by its .mdd extension. What
 *  `info` reads with fp_app_cache_info. Pure; any thread. */
bool fp_app_is_point_cache(const char *path, const unsigned char *h, size_t n);

/** `facepuppet info` of a point cache (PC2 or MDD, as `export` writes them and Blender's
 *  Mesh Cache modifier reads them): its points, frames, start and sampling (PC2) or the
 *  frames' times and rate (MDD), and whether the file holds all it says: a file of another
 *  size than its header gives (cut short) is described, said on stderr with the frames it
 *  does hold, and exits 65. Prints on stdout; errors on stderr. Returns the exit status (0,
 *  65, or 66 for a file that cannot be opened: a FIFO is refused, never waited on). Reads the
 *  header and MDD's times, never the frames. Main thread (it prints). */
int fp_app_cache_info(const char *path);

#endif
