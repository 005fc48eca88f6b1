/* Helpers shared by the subcommands: plugin search path, data paths, error -> exit code. */
#ifndef FP_APP_UTIL_H
#define FP_APP_UTIL_H

#include "fp_plugin_host.h"
#include "fp_session.h"
#include "fp_session_take.h"
/* fp_parse_decimal, fp_decimal_span: the one syntax of a number in an option (decimal,
 * finite: no hex, inf or nan), as in a plugin's keys */
#include <facepuppet/plugin_util.h>

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

/** A session's opening shown on a terminal (fp_session_options.progress): while
 *  fp_session_create works, one status line on stderr, "CMD: opening: STAGE ...", rewritten
 *  as each step begins; when it returns the line is cleared, or replaced by "CMD: opened in
 *  N.N s" when that took a second or more (a large face: loading it and building the contact
 *  guard take long; docs/performance.md). Where stderr is not a terminal (a pipe, a log), or
 *  quiet: nothing. A line fp_app_log_line prints meanwhile erases the status line first and
 *  draws it again after (one status line on the screen at a time, process-wide). */
typedef struct fp_app_open_progress {
    const char *cmd;  /* "facepuppet run" */
    bool on;          /* stderr is a terminal and not quiet */
    bool shown;       /* a status line is on the screen */
    int64_t t0;       /* the first step's start, ns (fp_now_ns) */
    const char *phase; /* the status line's word: "opening" (init), e.g. "writing" */
    char done[512];   /* the closing line's words: "opened" (init), e.g. "wrote out.obj" */
} fp_app_open_progress;

/** Set up *p for `cmd`; then so->progress = fp_app_open_progress_fn, so->progress_user = p.
 *  p must outlive fp_session_create (and, for live, every reopening of the session). */
void fp_app_open_progress_init(fp_app_open_progress *p, const char *cmd, bool quiet);

/** fp_session_progress_fn for fp_app_open_progress (user: the struct). [the thread that
 *  calls fp_session_create]. */
void fp_app_open_progress_fn(void *user, const char *stage);

struct fp_mesh;
/** fp_mesh_load (same results) shown on a terminal as fp_app_open_progress shows a session's
 *  opening: "CMD: opening: loading NAME (N MiB) ...", erased when it returns ("opened in
 *  N.N s" after a second or more); nothing on a pipe or when quiet. For the commands that
 *  load a face without a session (info, pose, calibrate). */
int fp_app_load_mesh(const char *cmd, bool quiet, const char *path, struct fp_mesh **out,
                     char *err, size_t errlen);

/** The plugin path: --plugin-dir folders, FACEPUPPET_PLUGIN_PATH, the built-in folder. */
void fp_app_plugin_path(fp_plugin_path *path, const char *const *dirs, size_t ndirs);

/** The built-in plugin folder, <directory of the executable>/FP_PLUGIN_RELDIR, into buf. */
const char *fp_app_builtin_plugin_dir(char *buf, size_t len);

/** The shared data folder (faces/, hands/: the demo's face and recording, a rig's mesh) into
 *  buf, looked up in order: FP_SHARED_DATA in the environment; PREFIX/share/facepuppet/data
 *  beside the executable (PREFIX/bin) where that folder exists; for the build tree's binary
 *  only (its folder is the build's bin/), the FP_SHARED_DATA the build was configured with
 *  (../shared/data beside the source tree). NULL when none applies: an installed binary never
 *  reads the build tree. Main thread (fp_app_exe_dir); no message. */
const char *fp_app_data_root(char *buf, size_t len);

/** "<data>/<rel>" into buf (fp_app_data_root), or NULL after "CMD: no shared data folder for
 *  REL: set FP_SHARED_DATA ..." on stderr (the caller exits FP_EXIT_NOINPUT). */
const char *fp_app_data_path(const char *cmd, const char *rel, char *buf, size_t len);

/** What a failing call was doing, for the codes whose exit status depends on it. */
typedef enum fp_app_io {
    FP_APP_INPUT,   /* reading an input: a mesh, a recording, a device, plugins, options */
    FP_APP_OUTPUT   /* creating or writing an output file */
} fp_app_io;

/** A log callback (fp_session_log_fn, fp_host_log_fn) for the commands: "facepuppet: SOURCE:
 *  MESSAGE" on stderr; FP_LOG_DEBUG lines only with FACEPUPPET_DEBUG set. user unused. */
void fp_app_log_line(void *user, int level, const char *source, const char *message);

/** fp_app_log_line for a command given -q: the engine's and the contact guard's notes on
 *  each gesture (fp_slog_is_note) are left out; the inputs', recordings', the mapping's and
 *  the rig's lines and every error print as with fp_app_log_line. user unused. Any thread, as
 *  fp_app_log_line (one fprintf a line: lines from two threads never interleave). */
void fp_app_log_line_quiet(void *user, int level, const char *source, const char *message);

/** fp_app_log_line for play -q and export -q, which play a take (no inputs, mapping or hands
 *  placed): errors and warnings alone (level FP_LOG_WARNING or below, the engine's and
 *  contact guard's notes left out as by fp_app_log_line_quiet); an information line such as
 *  the session's "the face looks along ... the hands are placed in front of it" printed under
 *  -q, which their help says prints errors and a damaged take's warning only. Any thread. */
void fp_app_log_line_warnings(void *user, int level, const char *source, const char *message);

/** The longest --duration a command takes, seconds (116 days: its nanoseconds fit an
 *  int64 with room; 9.3e9 s wrapped around and stopped after one frame). */
#define FP_APP_MAX_DURATION_S 1e7

/** Before play or export (verb) of the take at path: with no intact frame, "CMD: PATH: no
 *  intact frame to VERB (the cut)" and 65, before any output; a damaged tail is warned about
 *  ("CMD: warning: CUT; VERBing the N intact frames") and 0 returned; so is a take with no
 *  end chunk, still being recorded or left open by a recorder that died ("CMD: warning:
 *  PATH: no end chunk: ...; VERBing the N frames it holds now"). */
struct fp_take_reader;
int fp_app_take_intact(const char *cmd, const char *verb, const char *path,
                       const struct fp_take_reader *r);

/** --size's WxH: two whole numbers (fp_parse_whole: an optional '+', digits; no blanks, no
 *  '-') joined by 'x', each in lo..hi (pixels), nothing before or after. true with *w, *h set;
 *  false where v (NULL too) is not one, *w and *h then untouched (the caller names the
 *  option). [any-thread], no allocation. */
bool fp_app_parse_size(const char *v, int lo, int hi, int *w, int *h);

/** An output mesh's name: an extension the mesh writer knows (.obj .ply .off .stl .gltf .glb,
 *  any case). Returns 0, or 64 (usage) with "CMD: OPTION PATH: unknown mesh format ..."
 *  printed. */
int fp_app_check_mesh_name(const char *cmd, const char *option, const char *path);

/** An output file, checked before any work: what a save would replace (fp_file_target: a
 *  folder, FIFO or device never is) and that its folder takes files. Returns 0, or an exit
 *  status (73) with "CMD: OPTION PATH: REASON" printed. */
int fp_app_check_output(const char *cmd, const char *option, const char *path);

/** No silent overwrite (issue 53): fp_app_check_output, then, unless force, an output that
 *  exists (a symbolic link's end included) is refused before any work: "CMD: OPTION PATH:
 *  exists (--force to overwrite)". Returns 0, or 73 (FP_EXIT_CANTCREAT, the code of every
 *  output refused) with the line printed. */
int fp_app_check_new_output(const char *cmd, const char *option, const char *path, bool force);

/** An output that is one of the command's inputs (the same file by device and inode: another
 *  spelling, a hard or symbolic link) would be written over the data it comes from, --force
 *  or not (`export T.fptake --format pc2 --out T.fptake --force` replaced the take by its
 *  point cache): refused before any work. input may be NULL or "" (nothing to compare); what
 *  names it ("the take"). Returns 0 (different files, or either missing), or 73 with
 *  "CMD: OPTION OUT: is WHAT being read (INPUT): refused (it would be written over)" printed. */
int fp_app_check_not_input(const char *cmd, const char *option, const char *out, const char *input,
                           const char *what);

/** A default output name (one the user did not give) that exists: the next free name, as
 *  record= takes one: PATH itself when free, else STEM-1.EXT, STEM-2.EXT ... (up to 999).
 *  Into buf (len bytes). Returns true with buf set, false when none is free or it does not
 *  fit (buf then PATH). Looks only (lstat): a name may be taken between this and the write. */
bool fp_app_free_name(const char *path, char *buf, size_t len);

/** A folder of numbered outputs (--frames-out, export's obj-seq and png-seq), before any work:
 *  made when missing (mkdir 0777, when make; *made, when not NULL, says whether this call made
 *  it, so that a command refused before its first frame can take it away again with rmdir), a
 *  folder we can write in, and, unless force, one that already holds a file the command
 *  writes (a name starting with prefix and ending with suffix, either "" for any) is refused:
 *  "CMD: OPTION DIR: holds N files of an earlier run (FILE ...) (--force to overwrite)". A
 *  missing folder with make false passes. Returns 0, or 73 with the line printed. */
int fp_app_check_output_dir(const char *cmd, const char *option, const char *dir, const char *prefix,
                            const char *suffix, bool make, bool force, bool *made);

/** After an obj-seq or png-seq export written whole over an earlier one (--force): the files
 *  of dir named prefix, a frame number (six digits or more), then suffix (".png"), or with
 *  suffix NULL a dot and one extension with no further dot (".obj"), or with suffix "_t*REST"
 *  "_t", a time (digits, '.', '-') and REST (--frames-out's "_t*s.obj"), numbered `from` or more,
 *  are removed, so that the folder holds the new sequence alone (10 frames exported over 113
 *  left frames 10-112 of the old take after the new ones). Hidden files and other names are
 *  left. Returns how many were removed (the first by name into first, len bytes), or -errno
 *  of the first that could not be (its name in first). [main-thread]. */
long fp_app_remove_stale_frames(const char *dir, const char *prefix, const char *suffix,
                                unsigned long long from, char *first, size_t len);

/** --frames-out DIR with --force, once the command's checks have passed and before its first
 *  frame: the frames of an earlier run there (frame_NNNNNN_tS.SSSs.obj) are removed, said on
 *  stderr unless quiet, so that the folder holds this run's frames alone (a run at 24 fps over
 *  one at 60 left frame_000001_t0.017s.obj beside frame_000001_t0.042s.obj, 85 files for 25
 *  frames). Returns 0, or 73 with the line printed. [main-thread]. */
int fp_app_frames_out_clear(const char *cmd, const char *dir, bool quiet);

/** The files a session will read, before a command's slow or fallible start (live's window):
 *  so->mesh_path, so->rig_path (not "none"), and the FILE of each replay: or take: input SPEC,
 *  each a regular file that opens for reading (fp_file_open_regular), so that a wrong path is
 *  said first, as `run` says it, and not after "no display". Their content is read later, by
 *  the session. Returns 0, or the exit code (66 for a missing or unreadable file) with
 *  "CMD: [input 'SPEC': ]FILE: cannot open: reason" printed. [main-thread] */
int fp_app_check_input_files(const char *cmd, const fp_session_options *so);

/** --take-dir DIR of run and live, before any work, making nothing: DIR a folder we can write
 *  in, or, where it is missing, the nearest folder above it that is there (the take writer
 *  makes DIR with its parents at the first take, as `mkdir -p`: fp_take_writer_create), with
 *  no file in the way. Takes are numbered on, never overwritten: what DIR holds is kept.
 *  Returns 0, or 73 with "CMD: --take-dir DIR: reason[: the folder or file at fault]" printed. */
int fp_app_check_take_dir(const char *cmd, const char *dir);

/** Bytes a frame of --frames-out takes a vertex, about (an OBJ written back as the input came
 *  in: its v, vn, vt and face lines; 1.34 MB a frame for the ICT face's 26719 vertices). */
/** An OBJ frame's bytes, about, as the mesh writer writes it (core/mesh): a "v" line of about
 *  36 bytes a vertex, a "vt" line of 23 where the mesh has texture coordinates, and "f" lines
 *  of about 17 bytes a triangle (24 with "vt" indices; a quad's line holds two). On the ICT
 *  face 2.84 MB against the 2.79 MB written (26,719 vertices, 52,768 triangles as 26,384 quads;
 *  50 bytes a vertex, the estimate before, said 1.3 MB). Pure; any thread. */
double fp_app_obj_frame_bytes(const struct fp_mesh *mesh);
/** bytes as "123 MB", "1.3 GB" or "12 kB" (decimal, as the exports' summaries) into buf (len
 *  bytes, NUL-ended, cut if short). Pure; any thread. */
void fp_app_size_text(double bytes, char *buf, size_t len);
/** Above this an output's size said before the work is a warning (1 GiB): fp_app_output_fits. */
#define FP_APP_FRAMES_WARN_BYTES (1024.0 * 1024.0 * 1024.0)

/** The room free, in bytes, for an unprivileged user (statvfs's f_bavail) on the file system
 *  that `path` lands on: path itself when it exists, else the nearest folder above it that
 *  does ("." for a bare name). Returns 0 and *bytes, or -1 when none answered. Any thread. */
int fp_app_free_room(const char *path, double *bytes);

/** An output of about `bytes` (frames x vertices, for the message) that `path` will hold,
 *  checked before any work: when its file system has less room free (fp_app_free_room),
 *  "CMD: WHAT: about SIZE (N frames x V vertices), more than the FREE free there; nothing
 *  written (HINT)" on stderr and FP_EXIT_CANTCREAT (73); else 0 (also when bytes is 0, or the
 *  room cannot be asked), after "CMD: warning: WHAT: about SIZE (N frames x V vertices, ~B a
 *  frame), over 1 GiB" on stderr where bytes is above FP_APP_FRAMES_WARN_BYTES. hint may be
 *  NULL. Any thread. */
int fp_app_output_fits(const char *cmd, const char *what, const char *path, double bytes,
                       double frames, size_t vertices, const char *hint);

/** Say a --frames-out folder's size before any work, on stderr: "CMD: OPTION DIR: about SIZE
 *  (N frames x V vertices, ~B a frame)" unless quiet, and "CMD: warning: ..." above
 *  FP_APP_FRAMES_WARN_BYTES whatever quiet; refused as fp_app_output_fits (73, its hint)
 *  where the folder's file system has less room free. frames 0: not known before the run
 *  (live inputs, a recording read to its end): the rate at fps frames a second and when it
 *  passes 1 GiB are said instead, and nothing is refused. mesh: the session's loaded mesh
 *  (its vertex and triangle counts, uvs). Returns 0 or FP_EXIT_CANTCREAT. Any thread. */
int fp_app_frames_estimate(const char *cmd, const char *option, const char *dir, double frames,
                           double fps, const struct fp_mesh *mesh, bool quiet, const char *hint);

/** A --input SPEC that looks like a file (its NAME, before ':' and ',', holds '/' or '.',
 *  which no plugin name does: "foo.csv", "../rec/clap.fplog"): "CMD: OPTION SPEC: not a SPEC
 *  (NAME[:ARG][,key=value...]); it looks like a file: did you mean OPTION take:SPEC?" (a
 *  .fptake) or "replay:SPEC" (any other) on stderr and true; false (nothing said) for a SPEC
 *  whose name a plugin could have, or that names a plugin's file (a path holding '/' and
 *  ending in ".so": docs/plugin-guide.md). Before any work, in every command taking --input. */
bool fp_app_spec_looks_like_file(const char *cmd, const char *option, const char *spec);

/** The one map from an error code (fp_error.h: 0, a negative errno or an FP_E* code) to the
 *  command's exit status (enum fp_exit, sysexits.h); every subcommand uses it, never the
 *  message text. The table (docs/architecture.md, "Errors"; `facepuppet --help`):
 *    0                                          0
 *    -EINVAL (a bad option or SPEC key)         64 usage
 *    -EBADMSG -ERANGE -EDOM -EPROTO -ENOTSUP    65 bad input data (and -EILSEQ)
 *    -ENOENT -EACCES -EPERM -ENODEV -ENXIO      66 an input (file, device, display) that cannot
 *    -EBUSY -ENOTDIR -EISDIR -ENAMETOOLONG      be opened; 73 when io is FP_APP_OUTPUT
 *    -ELOOP
 *    -EIO -ENOSPC -EROFS -EDQUOT -EFBIG -EEXIST 73 an output that cannot be created or written
 *    -ENOMEM                                    70 internal
 *    FP_EPLUGIN_*                               78 a plugin missing, of another ABI, failing
 *    anything else (FP_ENUMERIC, -ETIMEDOUT...) 1
 *  A plugin's create() and start() codes go through the same table, so a plugin says "bad
 *  SPEC" with -EINVAL, "malformed file" with -EBADMSG, "no such file or device" with -ENOENT
 *  or -ENODEV (plugin.h). */
int fp_app_exit_code(int code, fp_app_io io);

/** Storage for the strings fp_app_session_defaults puts into a fp_session_options; it must
 *  outlive the options' use. */
typedef struct fp_app_inputs {
    char demo_mesh[4096];
    char demo_input[4200];
    char data_root[4096];   /* the shared data folder: the rigs' meshes (rig_mesh_root) */
    char specs[FP_SESSION_MAX_INPUTS][4300];
    char takes[FP_SESSION_MAX_INPUTS][5600]; /* a take's inputs, one take input each (source=N) */
    fp_calibration take_calibration;   /* a take input's recorded calibration */
    fp_session_performer_placement performers[FP_PERFORMER_CAPACITY]; /* a take's further
                                          performers' (take format 1.3) */
    char performer_names[FP_PERFORMER_CAPACITY][FP_PERFORMER_NAME_MAX + 1];
} fp_app_inputs;

/** Defaults shared by `run` and `live` (cmd: "facepuppet run", for the messages). With
 *  neither a mesh nor an input the session is the demo: the ICT face and the three-claps
 *  recording (*demo true; demo may be NULL). Without a mesh: the ICT face. Without a mapping:
 *  "anchored". A speed other than 1 is appended as `,speed=X` to every replay or take input
 *  that sets none. With no calibration and a `take:FILE` input, the calibration the take
 *  recorded (so that a take performed again sees its hands where they were): from format 1.3
 *  each performer's placement (the first's as `calibration`, the others' by name as
 *  `performer_calibrations`), before it the first performer's scale and offset. A
 *  `take:FILE` input without source= or performer= whose take has two or more inputs
 *  becomes one take input for each of them: SPEC,source=N and the recorded performer= and
 *  calibration= (where that file can be read), so that each performer's hands and each
 *  input's filter and clock are their own again; a take that cannot be read is left as
 *  given (its plugin says why). Strings
 *  point into *buf. Returns 0, or 64 with "CMD: --input SPEC: ..." printed where the take's
 *  inputs and the others make more than FP_SESSION_MAX_INPUTS. */
int fp_app_session_defaults(const char *cmd, fp_session_options *so, double speed, fp_app_inputs *buf,
                            bool *demo);

/** `facepuppet info RIG.json` (cmd_pose.c): describe the rig and check it against its mesh
 *  (the mesh the rig names under the shared data folder, when it is there). Returns an exit
 *  code. */
int fp_app_rig_info(const char *path);

/** `facepuppet info TAKE.fptake` (cmd_takes.c): header, summary, the cut warning. Returns an
 *  exit code. */
int fp_app_take_info(const char *path);

/** The take frame rate of a session loop at fps frames per second: N/1 for a whole number,
 *  N*1000/1001 within 0.005 of it (23.976 -> 24000/1001, 29.97 -> 30000/1001, 59.94 ->
 *  60000/1001), else round(fps*1000)/1000. */
fp_take_rate fp_app_take_rate(double fps);

/** One line about a finished take to f: "PREFIX: take PATH: N frames, D dropped, timecode
 *  IN - OUT" (and its error, if it stopped on one). */
void fp_app_print_take(FILE *f, const char *prefix, const fp_session_take_result *r);

/** How far the skin followed the fingertips over a run (skin_reach.h): every frame's
 *  touching vectors' reaches (fp_frame_stats.reach), gathered by fp_app_reach_add. Zero-
 *  initialise; fp_app_reach_free frees it. */
typedef struct fp_app_reach {
    double *v;
    size_t n, cap;
    double asked_max;     /* the longest drag, mesh units */
    double *va;           /* with a rig: against what it allowed (reach_allowed) */
    size_t na, capa;
    size_t held;          /* with a rig: vectors on the skull or the jaw (reach_held) */
} fp_app_reach;
/** Gather st's reaches (a failed allocation drops them: the figure is a report). */
void fp_app_reach_add(fp_app_reach *r, const fp_frame_stats *st);
/** "; the skin followed the fingertips 91% (median over 574 touching vectors, 10th percentile
 *  35%, longest drag 79.4 mm)" into text (empty when no vector was gathered); mm from
 *  mm_per_unit; with a rig whose clamp held a push back (the reach against what it allowed
 *  differs by half a point or more), "...; 100% of what the rig allowed, 10th percentile
 *  100%: it holds back a push toward the skull or the jaw)", and where fingertips grabbed
 *  the skull or the jaw, "...; 26 of them on the skull or the jaw, which the rig keeps
 *  still)". Reorders r->v and r->va. played_rig: the reaches were measured on takes played
 *  with a rig (play of a stack or of a take cut before its end chunk), whose stored vectors
 *  are already the rig's cut of the fingertips' ask: then only "; the skin followed 100% of
 *  what the rig allowed (median over N touching vectors, ...; a take holds the rig's
 *  vectors, not how far the fingertips asked)" (empty when none was gathered). */
void fp_app_reach_text(fp_app_reach *r, double mm_per_unit, bool played_rig, char *text, size_t len);
/** The clause run's summary adds with a rig: "; 100% of what the rig allowed, 10th percentile
 *  100%: it holds back a push toward the skull or the jaw" where r's reach against what the
 *  rig allowed (r->va: median, 10th percentile) differs from median or p10 (fractions) by half
 *  a point or more; else "" (also without r->va). Into rig (len bytes). Reorders r->va. */
void fp_app_reach_rig_clause(fp_app_reach *r, double median, double p10, char *rig, size_t len);
void fp_app_reach_free(fp_app_reach *r);
/** The sentence both `run`'s summary (fp_app_reach_text) and `info` (a take's TAIL) print:
 *  "the skin followed the fingertips M% (median over N touching vectors, 10th percentile P%,
 *  longest drag D mm[rig][; H of them on the skull or the jaw, which the rig keeps still])"
 *  into text (len bytes, truncated), median and p10 as fractions, rig "" or a clause that
 *  starts "; ", held 0 for none. No errors; any thread. */
void fp_app_reach_sentence(char *text, size_t len, double median, size_t vectors, double p10,
                           double longest_mm, const char *rig, size_t held);

#endif
