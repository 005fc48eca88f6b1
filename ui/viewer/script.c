/* The viewer's script: a few commands that drive a run deterministically. */
#define _GNU_SOURCE
#include "script.h"

#include <GLFW/glfw3.h>
#include <facepuppet/plugin_util.h> /* fp_parse_decimal(_list): numbers as in every option */

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

int fp_script_key(const char *name)
{
    static const struct { const char *name; int key; } named[] = {
        {"space", GLFW_KEY_SPACE}, {"esc", GLFW_KEY_ESCAPE}, {"escape", GLFW_KEY_ESCAPE},
        {"tab", GLFW_KEY_TAB},     {"[", GLFW_KEY_LEFT_BRACKET}, {"]", GLFW_KEY_RIGHT_BRACKET},
        {"?", GLFW_KEY_SLASH},     {"/", GLFW_KEY_SLASH}};
    for (size_t i = 0; i < sizeof named / sizeof named[0]; i++)
        if (!strcasecmp(name, named[i].name)) return named[i].key;
    if (strlen(name) == 1) {
        int c = toupper((unsigned char)name[0]);
        if (strchr("ECXZRWSFHTPJKGVILMO", c)) return GLFW_KEY_A + (c - 'A');
        if (c == ',') return GLFW_KEY_COMMA;
        if (c == '.') return GLFW_KEY_PERIOD;
        if (c == '1' || c == '2') return GLFW_KEY_0 + (c - '0');
    }
    return -1;
}

static int add(fp_script *s, fp_script_cmd c)
{
    fp_script_cmd *grown = realloc(s->cmds, (s->count + 1) * sizeof *grown);
    if (!grown) {
        free(c.text);
        return -ENOMEM;
    }
    s->cmds = grown;
    s->cmds[s->count++] = c;
    return 0;
}

int fp_script_parse(const char *text, fp_script *s, char *err, size_t errlen)
{
    memset(s, 0, sizeof *s);
    char *copy = strdup(text ? text : "");
    if (!copy) return -ENOMEM;
    int rc = 0, index = 0;
    char *save = NULL;
    for (char *cmd = strtok_r(copy, ";\n", &save); cmd && !rc; cmd = strtok_r(NULL, ";\n", &save)) {
        char word[32] = "", arg[4096] = "";
        int n = sscanf(cmd, " %31s %4095[^\n]", word, arg);
        if (n <= 0) continue; /* empty command */
        index++;
        for (char *e = arg + strlen(arg); e > arg && isspace((unsigned char)e[-1]);) *--e = '\0';
        fp_script_cmd c = {0};
        if (!strcmp(word, "wait")) {
            char what[16] = "";
            double k = 0;
            int used = 0, m = sscanf(arg, "%15s%n", what, &used);
            if (m == 1) m += fp_parse_decimal_list(arg + used, ' ', &k, 1) == 1;
            if (m >= 1 && !strcmp(what, "hands")) c.op = FP_SCRIPT_WAIT_HANDS;
            else if (m >= 1 && !strcmp(what, "end")) c.op = FP_SCRIPT_WAIT_END;
            else if (m == 1 && !strcmp(what, "reload")) c.op = FP_SCRIPT_WAIT_RELOAD;
            else if (m == 2 && !strcmp(what, "frames") && k >= 0 && k < 1e9) {
                c.op = FP_SCRIPT_WAIT_FRAMES;
                c.number = floor(k);
            } else if (m == 2 && !strcmp(what, "seconds") && k >= 0 && k < 1e6) {
                c.op = FP_SCRIPT_WAIT_SECONDS; /* for live inputs, which run on the wall clock */
                c.number = k;
            } else {
                rc = -EINVAL;
            }
        } else if (!strcmp(word, "key")) {
            c.op = FP_SCRIPT_KEY;
            c.key = fp_script_key(arg);
            if (c.key < 0) { /* the command is right, the key is not: name the keys */
                snprintf(err, errlen, "--script: command %d 'key %s': no such key; keys: E C X Z R W S F H T P "
                         "J K G V I L M O 1 2 , . [ ] ? space Tab Esc", index, arg);
                rc = -ENOENT;
            }
        } else if (!strcmp(word, "shot") || !strcmp(word, "drop")) {
            c.op = word[0] == 's' ? FP_SCRIPT_SHOT : FP_SCRIPT_DROP;
            if (!arg[0]) rc = -EINVAL;
            else if (!(c.text = strdup(arg))) rc = -ENOMEM;
        } else if (!strcmp(word, "scrub")) {
            /* scrub F: as the mouse on the timeline strip at fraction F of the take */
            c.op = FP_SCRIPT_SCRUB;
            if (!fp_parse_decimal(arg, &c.number) || !(c.number >= 0 && c.number <= 1)) rc = -EINVAL;
        } else if (!strcmp(word, "radius")) {
            c.op = FP_SCRIPT_RADIUS;
            if (!fp_parse_decimal(arg, &c.number) || !(c.number > 0)) rc = -EINVAL;
        } else if (!strcmp(word, "camera")) {
            /* camera YAW PITCH [ZOOM]: as export's --camera (fp_frame_render.h) */
            c.op = FP_SCRIPT_CAMERA;
            double v[3] = {0, 0, 1};
            const size_t m = fp_parse_decimal_list(arg, ' ', v, 3);
            c.number = v[0], c.pitch = v[1], c.zoom = v[2];
            if (m < 2 || !(fabs(c.pitch) <= 89) ||
                !(c.zoom > 0 && c.zoom <= 100))
                rc = -EINVAL;
        } else if (!strcmp(word, "size")) {
            /* size WxH: 16..16384 each, as --size */
            c.op = FP_SCRIPT_SIZE;
            const char *x = strchr(arg, 'x');
            char first[32];
            unsigned long long w = 0, h = 0;
            if (!x || (size_t)(x - arg) >= sizeof first) {
                rc = -EINVAL;
            } else {
                snprintf(first, sizeof first, "%.*s", (int)(x - arg), arg);
                if (!fp_parse_whole(first, 16384, &w) || !fp_parse_whole(x + 1, 16384, &h) || w < 16 || h < 16)
                    rc = -EINVAL;
            }
            c.pitch = (double)w, c.zoom = (double)h;
        } else if (!strcmp(word, "print") && !strcmp(arg, "mapping")) {
            c.op = FP_SCRIPT_PRINT_MAPPING;
        } else if (!strcmp(word, "print") && !strcmp(arg, "hud")) {
            c.op = FP_SCRIPT_PRINT_HUD;
        } else if (!strcmp(word, "print") && !strcmp(arg, "messages")) {
            c.op = FP_SCRIPT_PRINT_MESSAGES;
        } else if (!strcmp(word, "close")) {
            c.op = FP_SCRIPT_CLOSE;
            if (arg[0]) rc = -EINVAL;
        } else {
            rc = -EINVAL;
        }
        if (rc == -EINVAL)
            snprintf(err, errlen, "--script: command %d '%s %s' is not one of: wait hands|end|reload|frames N|seconds S, "
                     "key NAME, shot FILE, radius R, drop FILE, scrub F, camera YAW PITCH [ZOOM], size WxH, print mapping|hud|messages, close", index, word, arg);
        if (rc == -ENOENT) rc = -EINVAL; /* (said above) */
        if (!rc) rc = add(s, c);
        else free(c.text);
    }
    free(copy);
    if (rc) fp_script_free(s);
    return rc;
}

void fp_script_free(fp_script *s)
{
    for (size_t i = 0; i < s->count; i++) free(s->cmds[i].text);
    free(s->cmds);
    memset(s, 0, sizeof *s);
}
