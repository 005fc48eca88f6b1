/* The facepuppet command's errors: each bad input gets a clear message and its exit code. */
#define _GNU_SOURCE
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <math.h>
#include <stdio.h>
#include <sys/stat.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>
#include <cmocka.h>

static char exe[8192], data[4096], build[4096], tmp[256], repo[2048]; /* repo: the source tree */
static char out[65536];

/* Run facepuppet with args (a shell fragment); capture stderr+stdout; return exit status. */
/* a command's time limit: 120 s, times FP_TEST_TIME_SCALE (3 under the sanitizers, where a
 * run of the ICT face with a real recording takes minutes on two cores) */
static int time_limit(int seconds)
{
    const char *e = getenv("FP_TEST_TIME_SCALE");
    int scale = e ? atoi(e) : 1;
    return seconds * (scale > 0 ? scale : 1);
}

static int fp(const char *args)
{
    char cmd[40000];
    snprintf(cmd, sizeof cmd, "cd %s && timeout %d %s %s 2>&1", tmp, time_limit(120), exe, args);
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

/* Numbers in options and in plugin keys are decimals: hexadecimal ("0x10", "0x1p3"), "inf",
 * "infinity" and "nan", which strtod reads, are refused with 64 and a message naming the
 * option or key; every decimal form still works. */
static void test_decimal_options(void **state)
{
    (void)state;
    char args[16384], rec[4200];
    snprintf(rec, sizeof rec, "replay:%s/hands/leap-motion/grab_joints_mm.csv,fast=1", data);
    static const struct { const char *option, *value, *says; } bad[] = {
        {"--radius", "0x10", "--radius must be a number > 0, got '0x10'"},
        {"--radius", "0x1p3", "--radius must be a number > 0, got '0x1p3'"},
        {"--radius", "inf", "--radius must be a number > 0, got 'inf'"},
        {"--radius", "infinity", "--radius must be a number > 0, got 'infinity'"},
        {"--mm-per-unit", "0x10", "--mm-per-unit must be a number > 0, got '0x10'"},
        {"--speed", "0x1", "--speed must be a number from 0.001 to 1e6, got '0x1'"},
        {"--duration", "0x1", "--duration must be > 0 seconds"},
        {"--hand-size", "0x1", "--hand-size must be in 0.3..3, got '0x1'"},
        {"--fps", "0x3c", "--fps must be in 1..10000, got '0x3c'"},
        {"--budget", "0x1p1", "--budget must be in (0, 1000] ms, got '0x1p1'"},
        {"--mapping", "anchored,clamp=0x1p-2", "anchored: key 'clamp': '0x1p-2' is not a number in [0, 100] R"},
        {"--mapping", "onehand,gain=nan", "onehand: key 'gain': 'nan' is not a number in [0, 20] mm/mm"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        snprintf(args, sizeof args, "run -q --mesh %s --input %s --out d.obj --force %s %s", face(), rec,
                 bad[i].option, bad[i].value);
        assert_int_equal(fp(args), 64);
        if (!strstr(out, bad[i].says)) print_message("%s %s: %s", bad[i].option, bad[i].value, out);
        assert_non_null(strstr(out, bad[i].says));
    }
    snprintf(args, sizeof args, "run -q --mesh %s --input %s,speed=0x10 --out d.obj --force", face(), rec);
    assert_int_equal(fp(args), 64);
    assert_non_null(strstr(out, "replay: speed=0x10: expected a number from 0.001 to 1e6"));
    static const char *const others[][2] = {
        {"monitor --duration 0x1 pedal", "--duration must be > 0 seconds"},
        {"monitor --count 5 osc:0,timeout=0x1", "osc: timeout=0x1: expected a number in [0.01, 3600]"},
        {"monitor --count 5 osc:0,box=0x0/0/0/1/1/1", "osc: box=0x0/0/0/1/1/1: expected x0/y0/z0/x1/y1/z1"},
        {"calibrate --mm-per-unit 0x10", "--mm-per-unit must be > 0, got '0x10'"},
        {"calibrate --duration inf", "--duration must be > 0 s and under 1e7, got 'inf'"},
        {"plugins check x.so --budget 0x2", "--budget must be a time in ms > 0, got '0x2'"},
        {"export x.fptake --format pc2 --fps 0x18", "--resample must be in (0, 10000] frames per second, got '0x18'"},
        {"export x.fptake --format pc2 --max-error 0x1p-4", "--max-error must be > 0 mm, got '0x1p-4'"},
        {"export x.fptake --format png-seq --camera 0x10,5", "--camera YAW,PITCH[,ZOOM] in degrees"},
        {"export x.fptake --format png-seq --camera 10,5,inf", "--camera YAW,PITCH[,ZOOM] in degrees"},
    };
    for (size_t i = 0; i < sizeof others / sizeof others[0]; i++) {
        assert_int_equal(fp(others[i][0]), 64);
        if (!strstr(out, others[i][1])) print_message("%s: %s", others[i][0], out);
        assert_non_null(strstr(out, others[i][1]));
    }
    snprintf(args, sizeof args, "pose --mesh %s/faces/ict-facekit/generic_neutral_mesh.obj "
             "--set jaw.open=0x1p-1 --out p.obj --force", data);
    assert_int_equal(fp(args), 64);
    assert_non_null(strstr(out, "--set jaw.open=0x1p-1: expected NAME=NUMBER"));
    /* every decimal form still reads */
    snprintf(args, sizeof args, "run -q --mesh %s --input %s,speed=2. --mapping anchored,clamp=.3 "
             "--radius +5E-1 --fps 3e1 --duration 0.5 --out d.obj --force", face(), rec);
    assert_int_equal(fp(args), 0);
    snprintf(args, sizeof args, "pose --mesh %s/faces/ict-facekit/generic_neutral_mesh.obj "
             "--set jaw.open=.5 --out p.obj --force", data);
    assert_int_equal(fp(args), 0);
}

/* Integer options are digits, with a '+' as fp_parse_decimal takes one: strtol/strtoull
 * skipped a leading blank (and wrapped " -5" round to a huge count), (int) casts turned
 * 4294967297 into 1, sscanf read "640x480x3" as 640x480. Each is 64 naming the option. */
static void test_integer_options(void **state)
{
    (void)state;
    static const char *const bad[][2] = {
        {"live --frames ' 5'", "--frames must be a whole number > 0, got ' 5'"},
        {"live --frames ' -5'", "--frames must be a whole number > 0, got ' -5'"},
        {"live --frames 5e0", "--frames must be a whole number > 0, got '5e0'"},
        {"live --size ' 640x480'", "--size must be WxH (16..16384), got ' 640x480'"},
        {"live --size 640x480x3", "--size must be WxH (16..16384), got '640x480x3'"},
        {"monitor --count ' 5' pedal", "--count must be a whole number > 0, got ' 5'"},
        {"monitor --count 0x5 pedal", "--count must be a whole number > 0, got '0x5'"},
        {"plugins check x.so --cycles ' 5'", "--cycles must be in 1..1000, got ' 5'"},
        {"plugins check x.so --cycles 4294967297", "--cycles must be in 1..1000, got '4294967297'"},
        {"export x.fptake --format pc2 --max-targets ' 5'", "--max-targets must be a whole number from 1 to 2147483647, got ' 5'"},
        {"export x.fptake --format pc2 --max-targets 4294967297", "--max-targets must be a whole number from 1 to 2147483647, got '4294967297'"},
        {"export x.fptake --format png-seq --size '640x 480'", "--size WxH, 16..8192 each, got '640x 480'"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        assert_int_equal(fp(bad[i][0]), 64);
        if (!strstr(out, bad[i][1])) print_message("%s: %s", bad[i][0], out);
        assert_non_null(strstr(out, bad[i][1]));
    }
    char args[8400];
    snprintf(args, sizeof args, "monitor --count +2 replay:%s/hands/leap-motion/grab_joints_mm.csv,fast=1",
             data);
    assert_int_equal(fp(args), 0);
}

/* Run a shell command in tmp (stdin empty); capture stderr+stdout into out; exit status. */
static int sh(const char *command)
{
    char cmd[40000];
    snprintf(cmd, sizeof cmd, "cd %s && timeout %d %s </dev/null 2>&1", tmp, time_limit(60), command);
    FILE *p = popen(cmd, "r");
    size_t n = fread(out, 1, sizeof out - 1, p);
    out[n] = '\0';
    int st = pclose(p);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

/* The tools read their numeric arguments as facepuppet's options do (fp_parse_decimal,
 * fp_parse_whole): atof/atoi/strtof took hexadecimal, inf, nan and blanks, and atof("x") was
 * 0, the default. Each bad one is 64 naming the argument. */
static void test_tool_arguments(void **state)
{
    (void)state;
    char csv[4200], cmd[16384];
    snprintf(csv, sizeof csv, "%s/hands/leap-motion/grab_joints_mm.csv", data);
    static const char *const bad[][3] = {
        {"bin/fp-glove-emu", "--rate 0x10", "fp-glove-emu: --rate '0x10': expected a number of Hz"},
        {"bin/fp-glove-emu", "--rate inf", "fp-glove-emu: --rate 'inf': expected a number of Hz"},
        {"bin/fp-glove-emu", "--rate x", "fp-glove-emu: --rate 'x': expected a number of Hz"},
        {"bin/fp-glove-emu", "--sensors ' 22'", "fp-glove-emu: --sensors ' 22': expected 18 or 22"},
        {"bin/fp-glove-emu", "--sensors x", "fp-glove-emu: --sensors 'x': expected 18 or 22"},
        {"bin/fp-osc-send", "--speed 0x2 CSV", "fp-osc-send: --speed '0x2': expected a number > 0"},
        {"bin/fp-osc-send", "--speed nan CSV", "fp-osc-send: --speed 'nan': expected a number > 0"},
        {"bin/fp-osc-send", "--frames ' 2' CSV", "fp-osc-send: --frames ' 2': expected a whole number"},
        {"bin/fp-handcheck", "--tip-pad 0x1p-1", "fp-handcheck: --tip-pad: expected a number in [0, 1], got '0x1p-1'"},
        {"bin/fp-handcheck", "--tip-pad ' .5'", "fp-handcheck: --tip-pad: expected a number in [0, 1], got ' .5'"},
        {"bin/fp-selfx", "--away ' 1' a.obj b.obj", "fp-selfx: --away takes a ring count 0..8, got ' 1'"},
        {"tests/fp-export-check", "a.fptake b.pc2 --max-error 0x1p-4", "fp-export-check: --max-error '0x1p-4': expected a number of mm > 0"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        char args[4400];
        const char *at = strstr(bad[i][1], "CSV");
        snprintf(args, sizeof args, "%.*s%s", at ? (int)(at - bad[i][1]) : (int)strlen(bad[i][1]),
                 bad[i][1], at ? csv : "");
        snprintf(cmd, sizeof cmd, "%s/%s", build, bad[i][0]);
        if (access(cmd, X_OK)) continue; /* fp-osc-send needs liblo, fp-selfx CGAL */
        snprintf(cmd, sizeof cmd, "%s/%s %s", build, bad[i][0], args);
        int rc = sh(cmd);
        if (rc != 64 || !strstr(out, bad[i][2])) print_message("%s: %d %s", cmd, rc, out);
        assert_int_equal(rc, 64);
        assert_non_null(strstr(out, bad[i][2]));
    }
    /* decimal forms still read */
    snprintf(cmd, sizeof cmd, "%s/bin/fp-osc-send", build);
    if (!access(cmd, X_OK)) {
        snprintf(cmd, sizeof cmd, "%s/bin/fp-osc-send --port 9 --speed +1E1 --frames +1 -q %s", build, csv);
        assert_int_equal(sh(cmd), 0);
    }
    snprintf(cmd, sizeof cmd, "%s/bin/fp-handcheck --tip-pad .25 grab", build);
    assert_int_equal(sh(cmd), 0);
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
    snprintf(args, sizeof args, "run --mesh %s --input replay:truncated.csv --out t.obj --force", face());
    assert_int_equal(fp(args), 65);
    assert_non_null(strstr(out, "truncated.csv"));
    char written[512];
    snprintf(written, sizeof written, "%s/t.obj", tmp);
    assert_int_equal(access(written, F_OK), 0); /* nothing lost: the result was saved */
}

/* Numbers in data files are decimals, as in options: strtod's hexadecimal ("0x1p3" read as
 * 8) is refused with 65 and FILE:LINE:COLUMN and the column or field, in a Leap CSV (info
 * and run), an event log and a CyberGlove calibration; the shared recordings still load. */
static int sh(const char *command);

static void test_decimal_data(void **state)
{
    (void)state;
    char src[4200], line1[4096], line2[4096], text[16384], args[16384];
    snprintf(src, sizeof src, "%s/hands/leap-motion/grab_joints_mm.csv", data);
    FILE *in = fopen(src, "r");
    assert_non_null(in);
    assert_non_null(fgets(line1, sizeof line1, in));
    assert_non_null(fgets(line2, sizeof line2, in));
    fclose(in);
    char *palm_x = line2; /* field 5 */
    for (int k = 0; k < 4; k++) palm_x = strchr(palm_x, ',') + 1;
    snprintf(text, sizeof text, "%s%.*s0x1p3%s", line1, (int)(palm_x - line2), line2,
             strchr(palm_x, ','));
    write_file("hex.csv", text);
    char want[256];
    snprintf(want, sizeof want, "hex.csv:2:%d: bad number \"0x1p3\" in column palm_x",
             (int)(palm_x - line2) + 1);
    assert_int_equal(fp("info hex.csv"), 65);
    if (!strstr(out, want)) print_message("%s", out);
    assert_non_null(strstr(out, want));
    snprintf(args, sizeof args, "run -q --mesh %s --input replay:hex.csv,fast=1 --out d.obj --force", face());
    assert_int_equal(fp(args), 65);
    assert_non_null(strstr(out, want));
    write_file("hex.fplog", "# facepuppet-eventlog 1\n100 wrist left 1 2 0x1p3 1 0 0 0\n");
    assert_int_equal(fp("info hex.fplog"), 65);
    if (!strstr(out, "hex.fplog:2:20: bad number \"0x1p3\" for a wrist coordinate in mm"))
        print_message("%s", out);
    assert_non_null(strstr(out, "hex.fplog:2:20: bad number \"0x1p3\" for a wrist coordinate in mm"));
    write_file("hex.cal", "0 0.01 0\n3 0x1p-7 0\n");
    assert_int_equal(fp("monitor --count 1 cyberglove:/dev/null,cal=hex.cal"), 65);
    assert_non_null(strstr(out, "hex.cal:2: expected finite GAIN and OFFSET after sensor 3"));
    /* fp-glove-emu's own angles CSV reader: the same, 65 */
    static const char angles_header[] =
        "frame,timestamp_us,hand_id,hand_type,thumb_rotation,thumb_mcp,thumb_ip,thumb_abduction,"
        "index_mcp,index_pip,index_dip,middle_mcp,middle_pip,middle_dip,middle_index_abduction,"
        "ring_mcp,ring_pip,ring_dip,ring_middle_abduction,pinky_mcp,pinky_pip,pinky_dip,"
        "pinky_ring_abduction,palm_arch,wrist_pitch,wrist_yaw\n";
    snprintf(text, sizeof text, "%s0,5,1,right,,0x1p3,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,,,\n",
             angles_header);
    write_file("hex_angles.csv", text);
    snprintf(args, sizeof args, "%s/bin/fp-glove-emu --csv hex_angles.csv", build);
    assert_int_equal(sh(args), 65);
    assert_non_null(strstr(out, "hex_angles.csv:2: column 6 is not a number"));
    /* the shared recordings read as before */
    static const char *const recs[] = {"HandSplay-110fps", "Waiting-110fps", "grab", "three-claps"};
    for (int r = 0; r < 4; r++)
        for (int k = 0; k < 2; k++) {
            snprintf(args, sizeof args, "info %s/hands/leap-motion/%s_%s.csv", data, recs[r],
                     k ? "cyberglove_like_angles_deg" : "joints_mm");
            assert_int_equal(fp(args), 0);
        }
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
    /* a bad key's value: 64, as the anchored mapping's engage beyond its release */
    snprintf(args, sizeof args, "run --mesh %s --input replay:%s/hands/leap-motion/grab_joints_mm.csv "
             "--mapping anchored,engage=0.9,release=0.6", face(), data);
    assert_int_equal(fp(args), 64);
    assert_non_null(strstr(out, "anchored: key 'engage' (0.9) is beyond key 'release' (0.6)"));
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
    snprintf(args, sizeof args, "info %s/hands/leap-motion/three-claps.json.lz", data); /* its original */
    assert_int_equal(fp(args), 0);
    assert_non_null(strstr(out, "frames    403"));
    assert_non_null(strstr(out, "left, right"));
    assert_non_null(strstr(out, "leap-playback"));
    /* a plain .json recording in leapjs-playback's packed format 2 (not a rig) */
    write_file("packed.json",
               "{\"metadata\":{\"formatVersion\":2},\"frames\":[[\"id\",\"timestamp\",{\"hands\":[[\"id\","
               "\"type\",\"direction\",\"palmNormal\",\"palmPosition\"]]},{\"pointables\":[[\"id\",\"handId\","
               "\"type\",\"tool\",\"mcpPosition\",\"pipPosition\",\"dipPosition\",\"tipPosition\"]]}],[null,"
               "1000,[[7,\"right\",[0,0,-1],[0,-1,0],[1,200,3]]],[[null,7,1,true,null,null,null,"
               "null],[null,7,0,null,[0,201,0],[0,202,-10],[0,203,-20],[0,204,-30]],[null,7,1,"
               "null,[10,201,0],[10,202,-10],[10,203,-20],[10,204,-30]],[null,7,2,null,[20,201,"
               "0],[20,202,-10],[20,203,-20],[20,204,-30]],[null,7,3,null,[30,201,0],[30,202,"
               "-10],[30,203,-20],[30,204,-30]],[null,7,4,null,[40,201,0],[40,202,-10],[40,203,"
               "-20],[40,204,-30]]]],[null,9000,[[7,\"right\",[0,0,-1],[0,-1,0],[1,200,3]]],[[null,"
               "7,1,true,null,null,null,null],[null,7,0,null,[0,201,0],[0,202,-10],[0,203,-20],"
               "[0,204,-30]],[null,7,1,null,[10,201,0],[10,202,-10],[10,203,-20],[10,204,-30]],"
               "[null,7,2,null,[20,201,0],[20,202,-10],[20,203,-20],[20,204,-30]],[null,7,3,null,"
               "[30,201,0],[30,202,-10],[30,203,-20],[30,204,-30]],[null,7,4,null,[40,201,0],[40,"
               "202,-10],[40,203,-20],[40,204,-30]]]]]}");
    assert_int_equal(fp("info packed.json"), 0);
    assert_non_null(strstr(out, "leap-playback"));
    assert_non_null(strstr(out, "frames    2"));
    snprintf(args, sizeof args, "info %s/faces/ict-facekit/generic_neutral_mesh.obj", data);
    assert_int_equal(fp(args), 0);
    assert_non_null(strstr(out, "vertices  26719"));
    assert_non_null(strstr(out, "probably centimetres"));
    assert_int_equal(fp("info /nonexistent/face.obj"), 66);
    assert_non_null(strstr(out, "/nonexistent/face.obj"));
    /* a glove's calibration file: read as the glove input reads it (before: "unknown
     * format: expected a facepuppet event log, ..." as if a recording; then only what it
     * is). The real asr file: its format, the palm arch it leaves out, and the thumb's
     * rotation at raw 1 and 254 from the file's own two points (asr line 3 calibrates
     * sensor 0, docs/devices.md), computed here */
    snprintf(args, sizeof args, "%s/cyberglove/GloveCalibrationRight.cal", data);
    FILE *cf = fopen(args, "r");
    assert_non_null(cf);
    char cl[256] = "";
    for (int i = 0; i < 4; i++) assert_non_null(fgets(cl, sizeof cl, cf));
    fclose(cf);
    double r1, w1, r2, w2;
    assert_int_equal(sscanf(cl, "%lf:%lf %lf:%lf", &r1, &w1, &r2, &w2), 4);
    const double deg = 180 / 3.14159265358979323846;
    char want[128];
    snprintf(want, sizeof want, " 0 ThumbRotate    %7.1f .. %.1f\n", ((r2 - r1) * (1 - w1) / (w2 - w1) + r1) * deg,
             ((r2 - r1) * (254 - w1) / (w2 - w1) + r1) * deg);
    snprintf(args, sizeof args, "info %s/cyberglove/GloveCalibrationRight.cal", data);
    assert_int_equal(fp(args), 0);
    assert_non_null(strstr(out, "CyberGlove calibration, asr two-point"));
    assert_non_null(strstr(out, "21 of 22 calibrated (unused: 19 PalmArch)"));
    if (!strstr(out, want)) fprintf(stderr, "wanted '%s' in:\n%s", want, out);
    assert_non_null(strstr(out, want));
    assert_non_null(strstr(out, "cyberglove:DEVICE,cal="));
    /* gain/offset lines: sensor 5 at 0.02 rad a step from -0.1 rad; the rest the default map */
    write_file("go.cal", "# sensor gain offset\n5 0.02 -0.1\n");
    assert_int_equal(fp("info go.cal"), 0);
    assert_non_null(strstr(out, "gain/offset"));
    snprintf(want, sizeof want, " 5 IndexPIJ       %7.1f .. %.1f\n", (0.02 - 0.1) * deg, (0.02 * 254 - 0.1) * deg);
    assert_non_null(strstr(out, want));
    assert_non_null(strstr(out, " 4 IndexMPJ           0.0 .. 90.0\n"));
    /* a bad one: 65, the file and line */
    write_file("twice.cal", "5 0.02 -0.1\n5 0.01 0\n");
    assert_int_equal(fp("info twice.cal"), 65);
    assert_non_null(strstr(out, "twice.cal:2: sensor 5 given twice"));
    /* a bad line is quoted as a terminal may show it: an escape sequence (which would
     * recolour the terminal) becomes U+FFFD, the rest as written */
    write_file("esc.cal", "0.3:39 -0.5:111\n\x1b[31mred:1\n");
    assert_int_equal(fp("info esc.cal"), 65);
    assert_non_null(strstr(out, "esc.cal:2: expected `rad1:raw1 rad2:raw2` (asr format), got \"\xef\xbf\xbd[31mred:1\""));
    assert_null(strchr(out, '\x1b'));
}

/* A file's bytes quoted in an error reach the terminal as text, not as commands: an escape
 * sequence in an OBJ token or a Leap CSV field (which would recolour the terminal, or retitle
 * its window) is shown as U+FFFD (fp_error.h); the error itself is unchanged (65, the line). */
static void test_hostile_text_shown_safe(void **state)
{
    (void)state;
    write_file("esc.obj", "v 0 0 \x1b[31mX\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    assert_int_equal(fp("info esc.obj"), 65);
    assert_non_null(strstr(out, "esc.obj: line 1: malformed number '\xef\xbf\xbd[31mX' in 'v' statement"));
    assert_null(strchr(out, '\x1b'));
    char src[4200], row[8192], text[20000];
    snprintf(src, sizeof src, "%s/hands/leap-motion/grab_joints_mm.csv", data);
    FILE *in = fopen(src, "r");
    assert_non_null(in);
    assert_non_null(fgets(text, 10000, in)); /* the header */
    assert_non_null(fgets(row, sizeof row, in));
    fclose(in);
    char *hand = strstr(row, ",right,");
    assert_non_null(hand);
    *hand = 0;
    snprintf(text + strlen(text), sizeof text - strlen(text), "%s,\x1b]0;owned\x07right,%s", row, hand + 7);
    write_file("esc_joints_mm.csv", text);
    assert_int_equal(fp("info esc_joints_mm.csv"), 65);
    assert_non_null(strstr(out, "unknown hand_type \"\xef\xbf\xbd]0;owned\xef\xbf\xbdright\" (left or right)"));
    assert_null(strchr(out, '\x1b'));
    assert_null(strchr(out, '\x07'));
    /* info on a FIFO named as each kind it reads by signature or name: refused (66), never
     * waited on for a writer (fp()'s timeout ends a wait: 124) */
    const char *fifos[] = {"fifo-info.wav", "fifo-info.mdd", "fifo-info.pc2", "fifo-info.cal",
                           "fifo-info.fptake", "fifo-info.obj", "fifo-info.csv"};
    for (size_t i = 0; i < sizeof fifos / sizeof fifos[0]; i++) {
        char path[512], cmd[600];
        snprintf(path, sizeof path, "%s/%s", tmp, fifos[i]);
        assert_int_equal(mkfifo(path, 0600), 0);
        snprintf(cmd, sizeof cmd, "info %s", fifos[i]);
        int rc = fp(cmd);
        if (rc != 66) fail_msg("info %s: exit %d: %s", fifos[i], rc, out);
        assert_non_null(strstr(out, "not a regular file"));
    }
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

/* "vertices moved A of B; ... max M mm" of a run's summary into moved, of, max */
static void moved_of(unsigned *moved, unsigned *of, double *max)
{
    const char *p = strstr(out, "vertices moved ");
    assert_non_null(p);
    assert_int_equal(sscanf(p, "vertices moved %u of %u", moved, of), 2);
    const char *q = strstr(p, " max ");
    assert_non_null(q);
    assert_int_equal(sscanf(q, " max %lf mm", max), 1);
}

/* Run the grab recording on `mesh` (--rig none, written to `out_name`), exit 0, and read its
 * summary's moved vertices, vertex count and max displacement (mm). */
static void grab_on(const char *mesh, const char *out_name, unsigned *moved, unsigned *of, double *max)
{
    char args[16384];
    snprintf(args, sizeof args, "run -q --rig none --mesh %s --input replay:%s/hands/leap-motion/grab_joints_mm.csv,fast=1 "
             "--out %s --force", mesh, data, out_name);
    assert_int_equal(fp(args), 0);
    moved_of(moved, of, max);
}

/* A vertex in no triangle (a stray point an exporter left) is no part of the face's size: one
 * 1e6 units beside the 25-unit MediaPipe mask made a default radius of 6e4 units, placed the
 * hands by it and moved that point alone. Now the run says so and deforms as without it. */
static void test_stray_vertex(void **state)
{
    (void)state;
    char args[16384], path[4400];
    unsigned m0, n0, m1, n1;
    double x0, x1;
    grab_on(face(), "plain.obj", &m0, &n0, &x0);
    assert_null(strstr(out, "in no triangle"));
    snprintf(path, sizeof path, "%s/stray.obj", tmp);
    snprintf(args, sizeof args, "cp %s %s && echo 'v 1000000 0 0' >> %s", face(), path, path);
    assert_int_equal(system(args), 0);
    grab_on("stray.obj", "stray-out.obj", &m1, &n1, &x1);
    assert_non_null(strstr(out, "stray.obj: 1 of 469 vertices are in no triangle"));
    assert_int_equal(n1, n0 + 1);
    assert_int_equal(m1, m0);    /* the face's, not the point's alone */
    assert_true(x1 == x0);
    assert_true(m0 > 400);
    /* info says the same: the surface's bounds, and the point counted */
    assert_int_equal(fp("info stray.obj"), 0);
    assert_non_null(strstr(out, "unused    1 vertices in no triangle"));
    assert_null(strstr(out, "1e+06"));
}

/* One stray long triangle (a spike 30 units out of the 10-unit deep MediaPipe mask, along +z)
 * decided where the face's front is: the hands were placed at its tip and the grab moved the
 * spike's two tips alone. Its tips are left out of the face's size, head and placement (said),
 * and the run deforms the mask as without the spike. */
static void test_spike_triangle(void **state)
{
    (void)state;
    char args[16384], path[4400];
    unsigned m0, n0, m1, n1;
    double x0, x1;
    grab_on(face(), "plain.obj", &m0, &n0, &x0);
    assert_null(strstr(out, "lie far off"));
    snprintf(path, sizeof path, "%s/spike.obj", tmp);
    /* the spike: from vertex 1 (below the nose, z 6) to two points 34 units in front of it */
    snprintf(args, sizeof args, "cp %s %s && printf 'v 0 -3.4 40\\nv 0.05 -3.4 40\\nf 1/1 469/1 470/1\\n' >> %s", face(),
             path, path);
    assert_int_equal(system(args), 0);
    grab_on("spike.obj", "spike-out.obj", &m1, &n1, &x1);
    assert_non_null(strstr(out, "spike.obj: 2 of 470 vertices lie far off the rest"));
    assert_int_equal(n1, n0 + 2);
    print_message("the mask: %u moved, max %.1f mm; with the spike: %u, max %.1f mm\n", m0, x0, m1, x1);
    assert_true(m1 >= m0 - m0 / 20 && m1 <= m0 + 2); /* the face's grab, not the spike's tips */
    assert_true(fabs(x1 - x0) <= 0.1 * x0); /* (the spike triangle on vertex 1 is in the guards too) */
}

/* A --radius under the face's typical edge length moves single vertices or none (spikes):
 * said once at the start, with both figures and a radius to try; the default radius is not. */
static void test_small_radius_warned(void **state)
{
    (void)state;
    unsigned m0, n0;
    double x0;
    grab_on(face(), "plain.obj", &m0, &n0, &x0);
    assert_null(strstr(out, "typical edge length"));
    char args[16384];
    snprintf(args, sizeof args, "run -q --rig none --radius 0.05 --mesh %s --input replay:%s/hands/leap-motion/"
             "grab_joints_mm.csv,fast=1 --out tiny-radius.obj --force", face(), data);
    assert_int_equal(fp(args), 0);
    const char *w = strstr(out, "--radius 0.05 mesh units (");
    if (!w) fail_msg("no warning for --radius 0.05: %.2000s", out);
    assert_non_null(strstr(w, "mm) is under the face's typical edge length, "));
    assert_non_null(strstr(w, "try --radius "));
    const char *once = strstr(out, "typical edge length");
    assert_null(strstr(once + 1, "typical edge length")); /* once */
}

static void test_frames_out_and_monitor(void **state)
{
    (void)state;
    char args[16384];
    snprintf(args, sizeof args, "run -q --mesh %s --input replay:%s/hands/leap-motion/grab_joints_mm.csv,speed=8 "
             "--fps 20 --frames-out frames --out final.ply --force", face(), data);
    assert_int_equal(fp(args), 0);
    char cmd[8400];
    snprintf(cmd, sizeof cmd, "ls %s/frames | grep -c '^frame_[0-9]*_t[0-9]*\\.[0-9]*s\\.obj$'", tmp);
    FILE *p = popen(cmd, "r");
    int frames = 0;
    assert_int_equal(fscanf(p, "%d", &frames), 1);
    pclose(p);
    assert_true(frames >= 64 && frames <= 70); /* every frame of 3.3 s at 20 fps, whatever speed */
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

static int count_lines(const char *cmdfmt, const char *arg)
{
    char cmd[8400];
    snprintf(cmd, sizeof cmd, cmdfmt, arg);
    FILE *p = popen(cmd, "r");
    int n = -1;
    if (fscanf(p, "%d", &n) != 1) n = -1;
    pclose(p);
    return n;
}

/* run on the input's clock: speed=1, speed=10 and fast=1 give bit-identical meshes, also
 * every frame of --frames-out (a frame per 1/60 s of the take, its time in its name), and
 * looped (loop=1) as well. */
static void test_deterministic(void **state)
{
    (void)state;
    static const char *modes[] = {"speed=1", "speed=10", "fast=1"};
    char args[16384], cmd[9000];
    for (int m = 0; m < 3; m++) {
        snprintf(args, sizeof args, "run -q --mesh %s --input replay:%s/hands/leap-motion/"
                 "grab_joints_mm.csv,%s --out det%d.obj --force --frames-out det%d", face(), data, modes[m], m, m);
        assert_int_equal(fp(args), 0);
        assert_non_null(strstr(out, "events dropped 0"));
        assert_null(strstr(out, "vertices moved 0 "));
    }
    for (int m = 1; m < 3; m++) {
        snprintf(cmd, sizeof cmd, "cd %s && cmp det0.obj det%d.obj && diff -r det0 det%d", tmp, m, m);
        assert_int_equal(system(cmd), 0);
    }
    /* looping: fast=1 runs ahead of the frames and fills the input's queue, which the
     * replay waits on (fp_pacer_push): no event is lost, and none is said to be (before:
     * "events dropped 867", every refused try counted), the same mesh as at speed=10 */
    static const char *loops[] = {"speed=10", "fast=1"};
    for (int m = 0; m < 2; m++) {
        snprintf(args, sizeof args, "run -q --mesh %s --input replay:%s/hands/leap-motion/"
                 "three-claps_joints_mm.csv,loop=1,%s --duration 8 --out loop%d.obj --force",
                 face(), data, loops[m], m);
        assert_int_equal(fp(args), 0);
        assert_non_null(strstr(out, "events dropped 0"));
        assert_non_null(strstr(out, "frames 481,"));
    }
    snprintf(cmd, sizeof cmd, "cd %s && cmp loop0.obj loop1.obj", tmp);
    assert_int_equal(system(cmd), 0);
    /* the recording saved by a spreadsheet as "CSV UTF-8" (a byte order mark first, CRLF
     * lines): the same mesh (before: "unknown format") */
    snprintf(cmd, sizeof cmd, "cd %s && printf '\\357\\273\\277' > bom.csv && sed 's/$/\\r/' "
             "%s/hands/leap-motion/grab_joints_mm.csv >> bom.csv", tmp, data);
    assert_int_equal(system(cmd), 0);
    snprintf(args, sizeof args, "run -q --mesh %s --input replay:%s/bom.csv,fast=1 --out bom.obj --force",
             face(), tmp);
    assert_int_equal(fp(args), 0);
    snprintf(cmd, sizeof cmd, "cd %s && cmp det0.obj bom.obj", tmp);
    assert_int_equal(system(cmd), 0);
    /* grab is 3.304 s: frames at 0, 1/60, ..., 3.300 s (199 of them, the last with the end). */
    int n = count_lines("ls %s/det0 | grep -c '^frame_[0-9]*_t[0-9.]*s\\.obj$'", tmp);
    print_message("frames written: %d\n", n);
    assert_true(n >= 198 && n <= 202);
    snprintf(cmd, sizeof cmd, "test -f %s/det0/frame_000123_t2.050s.obj", tmp);
    assert_int_equal(system(cmd), 0);
}

/* Bad requests are refused before any work, with the path named. */
static void test_refused_up_front(void **state)
{
    (void)state;
    char args[16384], rec[4400];
    snprintf(rec, sizeof rec, "--input replay:%s/hands/leap-motion/grab_joints_mm.csv,fast=1", data);
    snprintf(args, sizeof args, "run --mesh %s %s --out result.xyz --force", face(), rec);
    assert_int_equal(fp(args), 64);
    assert_non_null(strstr(out, "result.xyz"));
    assert_null(strstr(out, "vertices")); /* no session made */
    snprintf(args, sizeof args, "run --mesh %s %s --out /nonexistent-dir/out.obj --force", face(), rec);
    assert_int_equal(fp(args), 73);
    assert_non_null(strstr(out, "/nonexistent-dir/out.obj"));
    assert_null(strstr(out, "vertices"));
    snprintf(args, sizeof args, "run --mesh %s %s --frames-out /proc/no-frames-here", face(), rec);
    assert_int_equal(fp(args), 73);
    assert_non_null(strstr(out, "/proc/no-frames-here"));
    write_file("plain-file", "x\n");
    snprintf(args, sizeof args, "run --mesh %s %s --frames-out plain-file", face(), rec);
    assert_int_equal(fp(args), 73);
    assert_non_null(strstr(out, "plain-file"));
    /* A radius beyond 10x the diagonal: a usage error, said once. */
    snprintf(args, sizeof args, "run --mesh %s %s --radius 1e20 --out r.obj --force", face(), rec);
    assert_int_equal(fp(args), 64);
    assert_non_null(strstr(out, "--radius"));
    int lines = 0;
    for (const char *c = out; *c; c++) lines += *c == '\n';
    assert_true(lines <= 2);
    /* A bad calibration file: its name and field, exit 65; a missing one, 66. */
    write_file("bad-cal.json", "{\"mm_per_unit\": \"ten\"}\n");
    snprintf(args, sizeof args, "run --mesh %s %s --calibration bad-cal.json", face(), rec);
    assert_int_equal(fp(args), 65);
    assert_non_null(strstr(out, "bad-cal.json"));
    assert_non_null(strstr(out, "mm_per_unit"));
    snprintf(args, sizeof args, "run --mesh %s %s --calibration missing-cal.json", face(), rec);
    assert_int_equal(fp(args), 66);
    /* Each by its kind, whatever the command: a folder as an input 66; a flat mesh is bad
     * data 65 (as calibrate says); an output mesh without a known extension is usage 64. */
    snprintf(args, sizeof args, "run --mesh %s %s --calibration .", face(), rec);
    assert_int_equal(fp(args), 66);
    assert_non_null(strstr(out, "folder"));
    write_file("flat.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    snprintf(args, sizeof args, "run --mesh flat.obj %s --out f.obj --force", rec);
    assert_int_equal(fp(args), 65);
    assert_non_null(strstr(out, "cannot find a head"));
    /* A mesh outside the engine's range (csrbf.h): coordinates past 1e15 were "cannot index"
     * (70), a diagonal of 1e-20 ran with the engine refusing the radius every frame (0, nothing
     * moved). Bad input data, 65, naming the file and the figure, before any work. */
    write_file("huge.obj", "v 0 0 0\nv 1e20 0 0\nv 0 1e20 0\nv 0 0 1e20\nf 1 2 3\nf 1 3 4\nf 1 4 2\nf 2 4 3\n");
    snprintf(args, sizeof args, "run --mesh huge.obj %s --out h.obj --force", rec);
    assert_int_equal(fp(args), 65);
    assert_non_null(strstr(out, "huge.obj: coordinates reach 1e+20 mesh units, beyond the engine's range"));
    write_file("tiny.obj", "v 0 0 0\nv 1e-20 0 0\nv 0 1e-20 0\nv 0 0 1e-20\nf 1 2 3\nf 1 3 4\nf 1 4 2\nf 2 4 3\n");
    snprintf(args, sizeof args, "run --mesh tiny.obj %s --out t.obj --force", rec);
    assert_int_equal(fp(args), 65);
    assert_non_null(strstr(out, "tiny.obj: the mesh spans 1.73e-20 mesh units"));
    /* Triangles collapsed onto one point away from the origin (a stray vertex beside them):
     * refused, 65, as having no size; it was told to move near the origin, which gives it none
     * ("the surface lies 1 mesh units from the origin ... coarse for a mesh 0 units across") */
    write_file("point.obj", "v 1 1 1\nv 1 1 1\nv 1 1 1\nv 2 2 2\nf 1 2 3\n");
    snprintf(args, sizeof args, "run --mesh point.obj %s --out p.obj --force", rec);
    assert_int_equal(fp(args), 65);
    assert_non_null(strstr(out, "point.obj: its triangles have no size: every corner of every one lies at (1, 1, 1)"));
    assert_null(strstr(out, "near the origin"));
    /* A face 0.3 units across 1e6 units off the origin (a face in metres with a survey
     * offset): its floats keep steps of 0.0625 there, the shape a handful of them; it ran
     * (exit 0, a vertex moved 0.23 units, the unit inf mm on a sphere): refused, 65, naming
     * the file, the step and the size. */
    write_file("far.obj", "v 1000000 1000000.1 1000000\nv 1000000.08 1000000 1000000\n"
               "v 999999.92 1000000 1000000\nv 1000000 1000000 1000000.09\nv 1000000 1000000 999999.91\n"
               "v 1000000 999999.9 1000000\nf 1 4 2\nf 1 3 4\nf 1 5 3\nf 1 2 5\nf 6 2 4\nf 6 4 3\n"
               "f 6 3 5\nf 6 5 2\n");
    snprintf(args, sizeof args, "run --mesh far.obj --rig none %s --out far-out.obj --force", rec);
    assert_int_equal(fp(args), 65);
    assert_non_null(strstr(out, "far.obj: the surface lies 1e+06 mesh units from the origin, where the "
                                "mesh's floats keep steps of 0.0625 units"));
    snprintf(args, sizeof args, "%s/far-out.obj", tmp);
    assert_int_equal(access(args, F_OK), -1);
    assert_int_equal(fp("info far.obj"), 0); /* info shows it, and why run refuses it */
    assert_non_null(strstr(out, "precision the surface lies 1e+06 units from the origin, where its floats "
                                "step by 0.0625 units"));
    snprintf(args, sizeof args, "pose --mesh %s --set jaw.open=0.2 --out noext --force", face());
    assert_int_equal(fp(args), 64);
    assert_non_null(strstr(out, "noext"));
    /* Numbers that would wrap or make nothing move: usage errors naming the option (a
     * --duration of 9.3e9 s wrapped the nanoseconds around and stopped after one frame) */
    static const char *const silly[] = {"--duration 9.3e9", "--radius 1e-300", "--mm-per-unit 1e300",
                                        "--mm-per-unit 1e-300"};
    for (size_t i = 0; i < sizeof silly / sizeof silly[0]; i++) {
        snprintf(args, sizeof args, "run --mesh %s %s %s --out s.obj --force", face(), rec, silly[i]);
        assert_int_equal(fp(args), 64);
        char opt[32];
        snprintf(opt, sizeof opt, "%.*s", (int)strcspn(silly[i], " "), silly[i]);
        if (!strstr(out, opt)) fail_msg("%s: \"%s\"", silly[i], out);
    }
    /* A FIFO where a file is read, here live's --script @FILE (read with fopen, it waited for
     * a writer): refused, 66, before any window (fp()'s timeout ends a wait: 124). 69 where
     * this build has no viewer. */
    snprintf(args, sizeof args, "%s/fifo-script", tmp);
    assert_int_equal(mkfifo(args, 0600), 0);
    int rc = fp("live --script @fifo-script --frames 1");
    if (rc != 69) {
        assert_int_equal(rc, 66);
        assert_non_null(strstr(out, "fifo-script: is not a regular file"));
    }
    /* A good one and --mm-per-unit: the scale line says where the scale came from. */
    write_file("cal.json", "{\"mm_per_unit\": 10, \"offset\": [0, 0, 5]}\n");
    snprintf(args, sizeof args, "run --mesh %s %s --calibration cal.json --out c.obj --force", face(), rec);
    assert_int_equal(fp(args), 0);
    assert_non_null(strstr(out, "scale: 10 mm per mesh unit (from the calibration)"));
    assert_null(strstr(out, "another mesh"));
    snprintf(args, sizeof args, "run --mesh %s %s --mm-per-unit 12.5 --out c.obj --force", face(), rec);
    assert_int_equal(fp(args), 0);
    assert_non_null(strstr(out, "scale: 12.5 mm per mesh unit (from --mm-per-unit)"));
}

/* One tracking glitch (a palm and its joints 3 m away for one sample) moves nothing in the
 * recording's workspace (2nd-98th percentiles): the same box as without it. */
/* facepuppet calibrate: hold mode on a real recording writes a file that run accepts (its
 * placement is checked in tests/pose: the median palm lands on the face); touch mode refuses
 * a recording without three touches, naming why; bad requests fail up front. */
static void test_calibrate(void **state)
{
    (void)state;
    char args[16384], rec[4300], ict[4300];
    snprintf(rec, sizeof rec, "replay:%s/hands/leap-motion/three-claps_joints_mm.csv,fast=1", data);
    snprintf(ict, sizeof ict, "%s/faces/ict-facekit/generic_neutral_mesh.obj", data);
    snprintf(args, sizeof args, "calibrate --mesh %s --input %s --out cal-hold.json --force", ict, rec);
    assert_int_equal(fp(args), 0);
    /* the scale run uses without a calibration (the rig found by the mesh: 10 mm), not the
     * head's estimate (10.24): adding the calibration keeps the scale (issue 53) */
    assert_non_null(strstr(out, "wrote cal-hold.json: 10 mm per mesh unit"));
    assert_non_null(strstr(out, "from the rig"));
    /* three-claps is no hold: each palm travels over 70 mm; said, the file still written */
    assert_non_null(strstr(out, "the left hand's palm travelled"));
    assert_non_null(strstr(out, "not held still"));
    snprintf(args, sizeof args, "run --mesh %s --input %s --calibration cal-hold.json --out h.obj --force", ict, rec);
    assert_int_equal(fp(args), 0);
    assert_non_null(strstr(out, "scale: 10 mm per mesh unit (from the calibration)"));
    assert_null(strstr(out, "another mesh"));
    /* the calibration made for ICT (10 mm per unit) used on Lee Perry-Smith (48.98 by his
     * rig, 48.07 by his head): the hands 4.9 times too large moved the whole head in silence;
     * now warned, naming the file and both units (the run goes on with it) */
    snprintf(args, sizeof args, "run --mesh %s/faces/lee-perry-smith/LeePerrySmith.obj --input %s "
             "--calibration cal-hold.json --duration 0.5 --out l.obj --force", data, rec);
    assert_int_equal(fp(args), 0);
    assert_non_null(strstr(out, "cal-hold.json: 10 mm per mesh unit, but "));
    assert_non_null(strstr(out, "LeePerrySmith.obj is 48.98 mm per unit (the rig "));
    assert_non_null(strstr(out, "a calibration made for another mesh?"));
    /* the same file as the input's calibration= key (SPEC keys) placed the hands as silently:
     * now warned the same, naming the input and the file; on its own face, not */
    snprintf(args, sizeof args, "run --mesh %s/faces/lee-perry-smith/LeePerrySmith.obj --input "
             "%s,calibration=cal-hold.json --duration 0.5 --out l.obj --force", data, rec);
    assert_int_equal(fp(args), 0);
    assert_non_null(strstr(out, "input 'replay': calibration=cal-hold.json: 10 mm per mesh unit, but "));
    assert_non_null(strstr(out, "LeePerrySmith.obj is 48.98 mm per unit (the rig "));
    assert_non_null(strstr(out, "a calibration made for another mesh?"));
    snprintf(args, sizeof args, "run --mesh %s --input %s,calibration=cal-hold.json --duration 0.5 "
             "--out h.obj --force", ict, rec);
    assert_int_equal(fp(args), 0);
    assert_null(strstr(out, "another mesh"));
    snprintf(args, sizeof args, "run --mesh %s/faces/lee-perry-smith/LeePerrySmith.obj --rig none "
             "--input %s --calibration cal-hold.json --duration 0.5 --out l.obj --force", data, rec);
    assert_int_equal(fp(args), 0);
    assert_non_null(strstr(out, "is 48.07 mm per unit (detected from the head"));
    /* info describes the file calibrate wrote (it was read as a rig: "comment: unknown
     * field", 65); a damaged one is named with its field, as run names it */
    assert_int_equal(fp("info cal-hold.json"), 0);
    assert_non_null(strstr(out, "hand calibration"));
    assert_non_null(strstr(out, "10 mm per mesh unit"));
    assert_int_equal(sh("sed 's/\"mm_per_unit\": 10/\"mm_per_unit\": -1/' cal-hold.json > cal-bad.json"), 0);
    assert_int_equal(fp("info cal-bad.json"), 65);
    assert_non_null(strstr(out, "cal-bad.json: field mm_per_unit: must be a finite number > 0"));
    snprintf(args, sizeof args, "run --mesh %s --input %s --out h.obj --force", ict, rec);
    assert_int_equal(fp(args), 0);
    assert_non_null(strstr(out, "scale: 10 mm per mesh unit"));
    /* a palm held still (HandSplay: 28 mm of travel, the fingers splaying) is not warned of */
    snprintf(args, sizeof args, "calibrate --mesh %s --input replay:%s/hands/leap-motion/"
             "HandSplay-110fps_joints_mm.csv,fast=1 --out cal-still.json --force", ict, data);
    assert_int_equal(fp(args), 0);
    assert_null(strstr(out, "travelled"));
    /* touch: three-claps has no three touches */
    snprintf(args, sizeof args, "calibrate --mode touch --mesh %s --input %s --out t.json --force", ict, rec);
    assert_int_equal(fp(args), 65);
    assert_non_null(strstr(out, "chin, nose tip and forehead"));
    snprintf(args, sizeof args, "calibrate --mesh %s --input replay:%s/hands/leap-motion/"
             "grab_cyberglove_like_angles_deg.csv,fast=1 --out g.json --force", ict, data);
    assert_int_equal(fp(args), 65);
    assert_non_null(strstr(out, "no joint positions (only joint angles)"));
    snprintf(args, sizeof args, "calibrate --mesh %s --input %s --out /nonexistent-dir/c.json --force", ict, rec);
    assert_int_equal(fp(args), 73);
    assert_int_equal(fp("calibrate --mode poke --input x --out y.json --force"), 64);
    assert_int_equal(fp("calibrate --input x"), 64);
    /* a --rig that does not fit the mesh: refused before the recording is read (it fell back
     * to estimated landmarks in silence) */
    snprintf(args, sizeof args, "calibrate --mesh %s --rig %s/rigs/ict-facekit.json --mode touch "
             "--input %s --out r.json --force", face(), repo, rec);
    assert_int_equal(fp(args), 65);
    assert_non_null(strstr(out, "--rig"));
    assert_non_null(strstr(out, "26719"));
    /* a Z-up copy with no rig and no --up/--facing: calibrate says the face probably looks
     * along -y, as run does (it wrote its hold for a face looking along +z in silence) */
    snprintf(args, sizeof args, "awk '$1==\"v\"{print \"v\", $2, -$4, $3; next} {print}' %s > mp-zup.obj",
             face());
    assert_int_equal(sh(args), 0);
    snprintf(args, sizeof args, "calibrate --mesh mp-zup.obj --rig none --input %s --out z.json --force", rec);
    assert_int_equal(fp(args), 0);
    assert_non_null(strstr(out, "calibrate: warning: mp-zup.obj: no rig and no --up/--facing"));
    assert_non_null(strstr(out, "toward -y"));
    snprintf(args, sizeof args, "calibrate --mesh mp-zup.obj --rig none --up +z --facing -y --input %s "
             "--out z.json --force", rec);
    assert_int_equal(fp(args), 0);
    assert_null(strstr(out, "no rig and no --up/--facing"));
    snprintf(args, sizeof args, "calibrate --mesh %s --rig none --input %s --out z.json --force", face(), rec);
    assert_int_equal(fp(args), 0);
    assert_null(strstr(out, "no rig and no --up/--facing"));
    snprintf(args, sizeof args, "pose --mesh %s --rig none --set jaw.open=0.3 --out p.obj --force", ict);
    assert_int_equal(fp(args), 64);
    assert_non_null(strstr(out, "needs a rig"));
}

static void test_robust_workspace(void **state)
{
    (void)state;
    char cmd[16384], args[9000], clean[4096], glitch[4096];
    snprintf(cmd, sizeof cmd,
             "awk -F, 'BEGIN{OFS=\",\"} NR==100{for(i=5;i<=NF;i++) if(i<8||i>13) $i=$i+3000} {print}' "
             "%s/hands/leap-motion/grab_joints_mm.csv > %s/glitch_joints_mm.csv", data, tmp);
    assert_int_equal(system(cmd), 0);
    snprintf(args, sizeof args, "info %s/hands/leap-motion/grab_joints_mm.csv", data);
    assert_int_equal(fp(args), 0);
    assert_non_null(strstr(out, "workspace"));
    snprintf(clean, sizeof clean, "%s", strstr(out, "workspace"));
    assert_int_equal(fp("info glitch_joints_mm.csv"), 0);
    snprintf(glitch, sizeof glitch, "%s", strstr(out, "workspace"));
    print_message("clean  %sglitch %s", clean, glitch);
    float a[6], b[6];
    assert_int_equal(sscanf(clean, "workspace x %f..%f y %f..%f z %f..%f", a, a + 1, a + 2, a + 3, a + 4, a + 5), 6);
    assert_int_equal(sscanf(glitch, "workspace x %f..%f y %f..%f z %f..%f", b, b + 1, b + 2, b + 3, b + 4, b + 5), 6);
    for (int k = 0; k < 6; k++) assert_true(fabsf(a[k] - b[k]) < 3.f); /* min/max: 3000 mm */
    /* and the run's hands are the same size: the scale line is the face's. */
    snprintf(args, sizeof args, "run -q --mesh %s --input replay:glitch_joints_mm.csv,fast=1 --out g.obj --force", face());
    assert_int_equal(fp(args), 0);
}

/* The glove alone deforms every face: every *_cyberglove_like_angles_deg.csv through both
 * mappings moves at least 0.5% of each face's vertices (within its first 3 s at 30 fps, to
 * keep the test short on a loaded machine). */
static void test_glove_deforms(void **state)
{
    (void)state;
    static const char *faces[] = {"ict-facekit/generic_neutral_mesh.obj", "lee-perry-smith/LeePerrySmith.obj",
                                  "mediapipe-canonical/canonical_face_model.obj"};
    static const char *recs[] = {"HandSplay-110fps", "Waiting-110fps", "grab", "three-claps"};
    static const char *maps[] = {"anchored", "unanchored"};
    char args[16384];
    for (int f = 0; f < 3; f++)
        for (int r = 0; r < 4; r++)
            for (int m = 0; m < 2; m++) {
                snprintf(args, sizeof args, "run -q --mesh %s/faces/%s --input replay:%s/hands/leap-motion/"
                         "%s_cyberglove_like_angles_deg.csv,fast=1 --mapping %s --fps 30 --duration 3 --out g.obj --force",
                         data, faces[f], data, recs[r], maps[m]);
                assert_int_equal(fp(args), 0);
                const char *v = strstr(out, "vertices moved ");
                assert_non_null(v);
                unsigned long moved = 0, n = 1;
                assert_int_equal(sscanf(v, "vertices moved %lu of %lu", &moved, &n), 2);
                print_message("glove %-45s %-17s %-10s moved %5lu of %5lu = %5.2f%%\n", faces[f], recs[r],
                              maps[m], moved, n, 100.0 * moved / n);
                assert_true(moved * 200 >= n);
            }
}

int main(void)
{
    const char *d = getenv("FP_SHARED_DATA"), *b = getenv("FP_BUILD_DIR");
    snprintf(data, sizeof data, "%s", d ? d : "../shared/data");
    if (data[0] != '/') {
        char cwd[2048];
        snprintf(data, sizeof data, "%s/%s", getcwd(cwd, sizeof cwd), d ? d : "../shared/data");
    }
    if (!getcwd(repo, sizeof repo)) snprintf(repo, sizeof repo, "."); /* ctest: the repository root */
    snprintf(build, sizeof build, "%s", b ? b : "build");
    snprintf(exe, sizeof exe, "%s/bin/facepuppet", build);
    snprintf(tmp, sizeof tmp, "/tmp/fp-cli-XXXXXX");
    if (!mkdtemp(tmp)) return 1;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_help_and_usage), cmocka_unit_test(test_decimal_options),
        cmocka_unit_test(test_integer_options),
        cmocka_unit_test(test_tool_arguments),
        cmocka_unit_test(test_corrupt_obj),
        cmocka_unit_test(test_bad_csv),        cmocka_unit_test(test_decimal_data),
        cmocka_unit_test(test_hostile_text_shown_safe),
        cmocka_unit_test(test_plugins),
        cmocka_unit_test(test_info),           cmocka_unit_test(test_missing_mesh), cmocka_unit_test(test_stray_vertex),
        cmocka_unit_test(test_spike_triangle),
        cmocka_unit_test(test_small_radius_warned),
        cmocka_unit_test(test_frames_out_and_monitor),
        cmocka_unit_test(test_deterministic),  cmocka_unit_test(test_refused_up_front),
        cmocka_unit_test(test_robust_workspace),
        cmocka_unit_test(test_calibrate), cmocka_unit_test(test_glove_deforms),
    };
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    char cmd[512];
    snprintf(cmd, sizeof cmd, "rm -rf %s", tmp);
    if (system(cmd)) {}
    return rc;
}
