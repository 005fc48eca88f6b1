/* The facepuppet command's errors: each bad input gets a clear message and its exit code. */
#define _GNU_SOURCE
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>
#include <cmocka.h>

static char exe[8192], data[4096], build[4096], tmp[256];
static char out[65536];

/* Run facepuppet with args (a shell fragment); capture stderr+stdout; return exit status. */
static int fp(const char *args)
{
    char cmd[40000];
    snprintf(cmd, sizeof cmd, "cd %s && timeout 120 %s %s 2>&1", tmp, exe, args);
    FILE *p = popen(cmd, "r");
    size_t n = fread(out, 1, sizeof out - 1, p);
    out[n] = '\0';
    int st = pclose(p);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

static void write_file(const char *name, const char *text)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s", tmp, name);
    FILE *f = fopen(path, "w");
    fputs(text, f);
    fclose(f);
}

static const char *face(void)
{
    static char p[4200];
    snprintf(p, sizeof p, "%s/faces/mediapipe-canonical/canonical_face_model.obj", data);
    return p;
}

static void test_help_and_usage(void **state)
{
    (void)state;
    assert_int_equal(fp("--help"), 0);
    assert_non_null(strstr(out, "run"));
    assert_int_equal(fp("--version"), 0);
    assert_non_null(strstr(out, "facepuppet "));
    assert_int_equal(fp("frobnicate"), 64);
    assert_non_null(strstr(out, "unknown command 'frobnicate'"));
    assert_int_equal(fp("run --radius -1"), 64);
    assert_int_equal(fp("run --help"), 0);
    assert_non_null(strstr(out, "--frames-out"));
}

static void test_corrupt_obj(void **state)
{
    (void)state;
    write_file("corrupt.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    char args[16384];
    snprintf(args, sizeof args, "run --mesh corrupt.obj --input replay:%s/hands/leap-motion/grab_joints_mm.csv",
             data);
    assert_int_equal(fp(args), 65);
    assert_non_null(strstr(out, "corrupt.obj"));
}

static void test_bad_csv(void **state)
{
    (void)state;
    char header[] = "frame,timestamp_us,hand_id,hand_type,thumb_rotation,thumb_mcp,thumb_ip,"
                    "thumb_abduction,index_mcp,index_pip,index_dip,middle_mcp,middle_pip,middle_dip,"
                    "middle_index_abduction,ring_mcp,ring_pip,ring_dip,ring_middle_abduction,pinky_mcp,"
                    "pinky_pip,pinky_dip,pinky_ring_abduction,palm_arch,wrist_pitch,wrist_yaw\n";
    char text[8192];
    snprintf(text, sizeof text, "%s0,1000,1,right,,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,,,\n"
                                "1,10000,1,right,,1,2,3,4,5,6,7,8,9,1O,11,12,13,14,15,16,17,18,,,\n", header);
    write_file("badnum.csv", text);
    char args[16384];
    snprintf(args, sizeof args, "run --mesh %s --input replay:badnum.csv", face());
    assert_int_equal(fp(args), 65);
    assert_non_null(strstr(out, "badnum.csv:3:"));   /* file and line */

    /* Truncated: the last row is cut off mid-way. The replay ends cleanly at the last full
     * row, the result is written, and the run exits non-zero naming the damage. */
    snprintf(text, sizeof text, "%s0,1000,1,right,,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,,,\n"
                                "1,10000,1,right,,1,2,3,4,5", header);
    write_file("truncated.csv", text);
    snprintf(args, sizeof args, "run --mesh %s --input replay:truncated.csv --out t.obj", face());
    assert_int_equal(fp(args), 65);
    assert_non_null(strstr(out, "truncated.csv"));
    char written[512];
    snprintf(written, sizeof written, "%s/t.obj", tmp);
    assert_int_equal(access(written, F_OK), 0); /* nothing lost: the result was saved */
}

static void test_plugins(void **state)
{
    (void)state;
    char args[16384];
    snprintf(args, sizeof args, "run --mesh %s --input nosuchinput", face());
    assert_int_equal(fp(args), 78);
    assert_non_null(strstr(out, "no input plugin named 'nosuchinput'"));
    snprintf(args, sizeof args, "run --mesh %s --plugin-dir %s/tests/plugins --input fixture-abi2", face(),
             build);
    assert_int_equal(fp(args), 78);
    assert_non_null(strstr(out, "built for plugin ABI 2.0"));
    snprintf(args, sizeof args, "run --mesh %s --input replay:%s/hands/leap-motion/grab_joints_mm.csv "
             "--mapping nosuchmapping", face(), data);
    assert_int_equal(fp(args), 78);
    assert_non_null(strstr(out, "no mapping plugin named 'nosuchmapping'"));
}

static void test_info(void **state)
{
    (void)state;
    char args[16384];
    snprintf(args, sizeof args, "info %s/hands/leap-motion/three-claps_joints_mm.csv", data);
    assert_int_equal(fp(args), 0);
    assert_non_null(strstr(out, "frames    403"));
    assert_non_null(strstr(out, "left, right"));
    assert_non_null(strstr(out, "joints-csv"));
    snprintf(args, sizeof args, "info %s/faces/ict-facekit/generic_neutral_mesh.obj", data);
    assert_int_equal(fp(args), 0);
    assert_non_null(strstr(out, "vertices  26719"));
    assert_non_null(strstr(out, "probably centimetres"));
    assert_int_equal(fp("info /nonexistent/face.obj"), 66);
    assert_non_null(strstr(out, "/nonexistent/face.obj"));
}

/* A mesh that is not there is an input that cannot be opened: exit 66 (EX_NOINPUT), from
 * the code fp_mesh_load gives (-ENOENT) through the session, never from the message. */
static void test_missing_mesh(void **state)
{
    (void)state;
    char args[16384];
    snprintf(args, sizeof args, "run --mesh /nonexistent/face.obj --input replay:%s/hands/leap-motion/"
             "grab_joints_mm.csv", data);
    assert_int_equal(fp(args), 66);
    assert_non_null(strstr(out, "/nonexistent/face.obj"));
}

static void test_frames_out_and_monitor(void **state)
{
    (void)state;
    char args[16384];
    snprintf(args, sizeof args, "run -q --mesh %s --input replay:%s/hands/leap-motion/grab_joints_mm.csv,speed=8 "
             "--fps 20 --frames-out frames --out final.ply", face(), data);
    assert_int_equal(fp(args), 0);
    char cmd[8400];
    snprintf(cmd, sizeof cmd, "ls %s/frames | grep -c '^frame-[0-9]*\\.obj$'", tmp);
    FILE *p = popen(cmd, "r");
    int frames = 0;
    assert_int_equal(fscanf(p, "%d", &frames), 1);
    pclose(p);
    assert_true(frames >= 5); /* 3.3 s / 8 at 20 fps: about 8 frames */
    snprintf(args, sizeof args, "info final.ply");
    assert_int_equal(fp(args), 0);
    assert_non_null(strstr(out, "vertices  468"));

    /* monitor against the CyberGlove emulator on a pseudo-terminal: JSON lines. */
    snprintf(cmd, sizeof cmd, "cd %s && (sleep 30 2>/dev/null | %s/bin/fp-glove-emu --rate 200 > emu.path 2>/dev/null &) && "
             "for i in $(seq 50); do [ -s emu.path ] && break; sleep 0.1; done", tmp, build);
    assert_int_equal(system(cmd), 0);
    char pts[256] = "";
    snprintf(cmd, sizeof cmd, "%s/emu.path", tmp);
    FILE *f = fopen(cmd, "r");
    assert_non_null(f);
    assert_non_null(fgets(pts, sizeof pts, f));
    fclose(f);
    pts[strcspn(pts, "\n")] = '\0';
    snprintf(args, sizeof args, "monitor --count 5 cyberglove:%s", pts);
    assert_int_equal(fp(args), 0);
    assert_non_null(strstr(out, "\"type\":\"joint_angles\",\"hand\":\"right\",\"valid\":"));
    snprintf(cmd, sizeof cmd, "pkill -f '%s/bin/fp-glove-emu --rate 200'; pkill -f '^sleep 30$'", build);
    if (system(cmd)) {}
}

int main(void)
{
    const char *d = getenv("FP_SHARED_DATA"), *b = getenv("FP_BUILD_DIR");
    snprintf(data, sizeof data, "%s", d ? d : "../shared/data");
    if (data[0] != '/') {
        char cwd[2048];
        snprintf(data, sizeof data, "%s/%s", getcwd(cwd, sizeof cwd), d ? d : "../shared/data");
    }
    snprintf(build, sizeof build, "%s", b ? b : "build");
    snprintf(exe, sizeof exe, "%s/bin/facepuppet", build);
    snprintf(tmp, sizeof tmp, "/tmp/fp-cli-XXXXXX");
    if (!mkdtemp(tmp)) return 1;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_help_and_usage), cmocka_unit_test(test_corrupt_obj),
        cmocka_unit_test(test_bad_csv),        cmocka_unit_test(test_plugins),
        cmocka_unit_test(test_info),           cmocka_unit_test(test_missing_mesh),
        cmocka_unit_test(test_frames_out_and_monitor),
    };
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    char cmd[512];
    snprintf(cmd, sizeof cmd, "rm -rf %s", tmp);
    if (system(cmd)) {}
    return rc;
}
