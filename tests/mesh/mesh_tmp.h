/* The small mesh tests' scratch folder (test_gltf_topology, test_ply_encoding,
 * test_obj_continuation): one mkdtemp() folder under $TMPDIR (else /tmp) per test program,
 * made by the group's setup and emptied and removed by its teardown. Test code only. */
#ifndef FP_MESH_TMP_H
#define FP_MESH_TMP_H

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char tmpdir[64];

/* tmpdir/name (one of 4 rotating buffers: up to 4 live at once) */
static inline const char *tmp_path(const char *name)
{
    static char buf[4][512];
    static int k;
    k = (k + 1) % 4;
    snprintf(buf[k], sizeof buf[k], "%s/%s", tmpdir, name);
    return buf[k];
}

/* n bytes into tmpdir/name; its path (tmp_path's); NULL when it cannot be written */
static inline const char *tmp_write(const char *name, const void *bytes, size_t n)
{
    const char *p = tmp_path(name);
    FILE *f = fopen(p, "wb");
    if (!f) return NULL;
    const int ok = fwrite(bytes, 1, n, f) == n;
    return fclose(f) == 0 && ok ? p : NULL;
}

/* the folder, named PREFIX-XXXXXX: 0 or -1 */
static inline int tmp_setup(const char *prefix)
{
    snprintf(tmpdir, sizeof tmpdir, "%s/%s-XXXXXX", getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp", prefix);
    return mkdtemp(tmpdir) ? 0 : -1;
}

/* the folder's files removed, then the folder: 0 or -1 */
static inline int tmp_teardown(void)
{
    DIR *d = opendir(tmpdir);
    if (!d) return -1;
    for (struct dirent *e; (e = readdir(d));)
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) unlink(tmp_path(e->d_name));
    closedir(d);
    return rmdir(tmpdir);
}

#endif
