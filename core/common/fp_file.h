/*
 * fp_file.h: every "write a temporary file beside the target, then rename it over" of the
 * project (mesh saves, exports, calibration files, PNGs, bench's --plot and --trace) goes
 * through fp_file_open_output / fp_file_output_commit / fp_file_output_abort: which file a
 * save replaces (fp_file_target), the temporary file beside it (fp_file_temp_beside) with the
 * mode a new file gets (fp_file_new_mode), then fsync and rename. The callers keep their own
 * writes and their error messages and codes (fp_file_output.failed says which step failed).
 * And the one way readers open an input file (fp_file_open_regular: a FIFO or a device never
 * blocks or passes for a file), and read a small one whole (fp_file_read_all). Link: the static library `fp_common` (PIC).
 */
#ifndef FP_FILE_H
#define FP_FILE_H

#include <stddef.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Create the temporary file ".NAME<tag>.PID.XXXXXX" in path's folder (NAME: path's last
 *  component; no folder: the working one; PID: this process's, so that a later save can tell
 *  a temporary of a process that died from one being written), so that a rename over path is
 *  atomic. path: the
 *  target (need not exist); tag: "" or a suffix that tells a caller's several temporaries
 *  apart (NULL as ""); tmp: n bytes for the temporary's name, "" after a failure. Returns the
 *  descriptor (O_CLOEXEC, mode 0600 as mkostemp makes it; the caller owns it and the file),
 *  or a negative errno: -EINVAL (NULL argument), -ENAMETOOLONG (the name does not fit n),
 *  mkostemp's (-ENOENT no folder, -EACCES, ...). Thread-safe. */
int fp_file_temp_beside(const char *path, const char *tag, char *tmp, size_t n);

/** Make the folder `path` and every missing folder above it, as `mkdir -p` (mode 0777 less
 *  the umask). Returns 0 when it is a folder afterwards (made or already there), or a negative
 *  errno: -ENOTDIR (it or a folder above it is a file), mkdir's (-EACCES, -EROFS, -ENOSPC ...),
 *  -ENAMETOOLONG (over 4095 bytes), -EINVAL (NULL or ""). Thread-safe. */
int fp_file_mkdirs(const char *path);

/** Open `path` for reading if it is a regular file (a symbolic link to one included), without
 *  blocking on what is not: opened O_NONBLOCK (a FIFO with no writer, a tty, a device cannot
 *  hold the open), checked by fstat, then made blocking again. Returns the descriptor
 *  (O_CLOEXEC; the caller owns it: close or fdopen it), or a negative errno: open's (-ENOENT,
 *  -EACCES, ...), -EISDIR (a folder), -ENXIO (a FIFO, device or socket: not a file to read);
 *  fp_file_error_text(code) says which in words. Thread-safe. */
int fp_file_open_regular(const char *path);

/** fp_file_open_regular as a stdio stream ("rb"): the FILE, or NULL with *code (the same
 *  negative errno; -ENOMEM from fdopen). Thread-safe. */
FILE *fp_file_fopen_regular(const char *path, int *code);

/** Read the regular file `path` whole (opened by fp_file_open_regular) into *buf, NUL-ended
 *  (*len bytes before the NUL: a file's text may hold NULs, *len says where it ends), at
 *  most `max` bytes. Returns 0 (*buf the caller's: free it), or a negative errno with *buf
 *  NULL: fp_file_open_regular's (-ENOENT, -EISDIR, -ENXIO, ...), -EFBIG (more than max
 *  bytes: nothing parsed of a part; a file whose size is already past max, before reading), -ENOMEM, -EIO (a read error); -EINVAL (NULL). The
 *  rig and calibration readers word each code with the file's name. Thread-safe. */
int fp_file_read_all(const char *path, size_t max, char **buf, size_t *len);

/** The file an atomic save of `path` replaces: `path` itself when it is a regular file or does
 *  not exist, or, for a symbolic link, the file at the end of its chain (the link is written
 *  through, as a shell's > does, not replaced by a file). Into real (n bytes). Returns 0, or a
 *  negative errno: -EISDIR (a folder), -ENXIO (a FIFO, device or socket: never replaced by a
 *  file; as root such a rename would delete /dev/null), -ELOOP (over 16 links), -ENAMETOOLONG
 *  (real too small), -EINVAL (NULL), lstat's others (-EACCES ...). Callers make their
 *  temporary file beside `real` and rename it over `real`. Thread-safe. */
int fp_file_target(const char *path, char *real, size_t n);

/** Words for fp_file_open_regular's and fp_file_target's codes: -EISDIR "is a folder, not a
 *  file", -ENXIO "is not a regular file (a FIFO, device or socket)", -ELOOP "too many
 *  symbolic links", others strerror's. Static text. */
const char *fp_file_error_text(int code);

/** The code an output file's failure is reported with, from the errno of the call that
 *  failed (e > 0): -ENOENT (no such folder: ENOENT, ENOTDIR), -EACCES (EACCES, EPERM, EROFS),
 *  -ENOSPC (ENOSPC, EDQUOT), -ENOMEM, else -EIO. The exports and PNG writers share it, so a
 *  full disk or a read-only folder reads the same from each. Thread-safe. */
int fp_file_output_code(int e);

/** The mode a new file gets: 0666 & ~umask, the umask read from /proc/self/status without
 *  changing it (umask() is process-wide: setting it to read it races other threads); 022 when
 *  it cannot be read. Thread-safe. */
unsigned fp_file_new_mode(void);

/** The step of fp_file_open_output or fp_file_output_commit that failed (fp_file_output.failed),
 *  so that a caller words each as it always has. */
typedef enum fp_file_step {
    FP_FILE_STEP_NONE = 0, /* nothing failed */
    FP_FILE_STEP_TARGET,   /* fp_file_target refused the path (-EISDIR a folder, -ENXIO a FIFO,
                              device or socket, -ELOOP ...: words from fp_file_error_text) */
    FP_FILE_STEP_TEMP,     /* the temporary file could not be made (fp_file_temp_beside's codes:
                              -ENOENT no folder, -EACCES, ...) */
    FP_FILE_STEP_STREAM,   /* fdopen failed (-ENOMEM) */
    FP_FILE_STEP_SYNC,     /* commit: the stream's flush, a write it had failed (-EIO), or fsync */
    FP_FILE_STEP_CLOSE,    /* commit: close (fclose) */
    FP_FILE_STEP_RENAME    /* commit: the rename over the target */
} fp_file_step;

/** fp_file_open_output's flags (0: none). */
enum {
    FP_FILE_OUTPUT_KEEP_MODE = 1u,     /* a file replaced keeps its permission bits (a new one
                                          gets fp_file_new_mode()); without it every save gets
                                          fp_file_new_mode() */
    FP_FILE_OUTPUT_SYNC_FOLDER = 4u    /* commit also fsyncs the folder after the rename (best
                                          effort: the data is already safe) */
};

/** An output being written whole or not at all: the temporary file beside its target, until
 *  fp_file_output_commit renames it over the target or fp_file_output_abort removes it. A
 *  zeroed one holds nothing (abort does nothing). */
typedef struct fp_file_output {
    char path[4096];     /* the file a commit replaces (fp_file_target's: a link's end); kept
                            after commit and abort, for messages */
    char tmp[4200];      /* the temporary file beside it; "" when there is none (not made,
                            committed or aborted) */
    int fd;              /* the temporary's descriptor (O_CLOEXEC), -1 when none; the one
                            under f when there is a stream */
    FILE *f;             /* a stream on fd when opened with a stdio mode, else NULL */
    unsigned flags;      /* fp_file_open_output's */
    fp_file_step failed; /* the step at which the last open or commit failed, else NONE */
    size_t stale;        /* temporaries of dead processes the open removed beside the target */
} fp_file_output;

/** Start writing `path` whole or not at all: resolve the file it replaces (fp_file_target: a
 *  symbolic link written through; a folder, FIFO or device refused), remove the temporaries
 *  an earlier save of that file with the same tag left when its process was killed (SIGKILL,
 *  a power cut: ".NAME<tag>.PID.XXXXXX" whose PID is no process on this machine; o->stale
 *  counts them; a live process's and a name without a PID are left; the folder is read at most
 *  once a second by a thread, so one left there later by another process in that second waits
 *  for the next save), make the temporary file
 *  ".NAME<tag>.PID.XXXXXX" beside that file (tag: as fp_file_temp_beside's; NULL as ""), give it
 *  the mode a new file gets (fp_file_new_mode(); flags FP_FILE_OUTPUT_*; best effort: a file
 *  system without Unix modes, vfat or exFAT, refuses it and the save goes on), and with
 *  stdio_mode ("w", "wb", "w+b", ...; NULL: none) a stream on it. The caller writes through
 *  o->f or o->fd (or has another program write o->tmp), then calls fp_file_output_commit or
 *  fp_file_output_abort exactly once; o owns the descriptor, stream and temporary until then.
 *  Returns 0, or a negative errno with o->failed saying which step failed (FP_FILE_STEP_TARGET:
 *  fp_file_target's codes, o->path unusable; TEMP: fp_file_temp_beside's, o->path the
 *  resolved target; STREAM: fdopen's) and nothing left behind (o->tmp "",
 *  o->fd -1, o->f NULL); -EINVAL for a NULL path or o (o->failed then TARGET when o is
 *  given). Thread-safe for distinct o. */
int fp_file_open_output(const char *path, const char *tag, const char *stdio_mode, unsigned flags,
                        fp_file_output *o);

/** Finish o: flush its stream (a write the stream had failed before: -EIO), fsync, close,
 *  rename the temporary over o->path, and with FP_FILE_OUTPUT_SYNC_FOLDER fsync the folder.
 *  Returns 0 (o->tmp ""), or a negative errno of the first call that failed (o->failed: SYNC,
 *  CLOSE or RENAME), the temporary removed and o->path left as it was; either way o holds
 *  nothing afterwards. -EINVAL (o->failed NONE) when o holds no temporary. Thread-safe for
 *  distinct o. */
int fp_file_output_commit(fp_file_output *o);

/** Give o up: close its stream or descriptor and remove the temporary; o->path is untouched.
 *  Does nothing for NULL, a zeroed o, or one already committed or aborted. errno may change.
 *  Thread-safe for distinct o. */
void fp_file_output_abort(fp_file_output *o);

#ifdef __cplusplus
}
#endif
#endif
