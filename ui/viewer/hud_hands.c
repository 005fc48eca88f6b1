/* The HUD's hands line (hud_hands.h). */
#include "hud_hands.h"

#include "fp_session.h"

#include <facepuppet/plugin.h>

#include <stdio.h>
#include <string.h>

void fp_hud_hands_log(fp_hud_hands *h, const char *const *inputs, size_t n, int level,
                      const char *source, const char *message)
{
    if (level > FP_LOG_WARNING || !source) return;
    size_t len = strlen(source);
    for (size_t i = 0; i < n; i++)
        if (inputs[i] && strncmp(inputs[i], source, len) == 0 &&
            (inputs[i][len] == '\0' || inputs[i][len] == ':' || inputs[i][len] == ',')) {
            bool named = strncmp(message, source, len) == 0 && message[len] == ':'; /* ("osc: ...") */
            snprintf(h->note, sizeof h->note, "%s%s%s", named ? "" : source, named ? "" : ": ", message);
            return;
        }
}

/* Appends to buf (len bytes, NUL-terminated). */
static void add(char *buf, size_t len, const char *a, const char *b)
{
    size_t used = strlen(buf);
    if (used + 1 < len) snprintf(buf + used, len - used, "%s%s", a, b);
}

void fp_hud_hands_line(fp_hud_hands *h, const fp_session *s, char *buf, size_t len)
{
    static const char *const sides[2] = {"left", "right"};
    size_t np = fp_session_performer_count(s);
    if (np > FP_HUD_HANDS_PERFORMERS) np = FP_HUD_HANDS_PERFORMERS;
    char here[256] = "", gone[256] = "";
    for (size_t p = 0; p < np; p++) {
        const char *name = fp_session_performer_name(s, p);
        const char *who = np < 2 ? "" : name && name[0] ? name : "first";
        char now[64] = "", lost[64] = "";
        for (int side = 0; side < 2; side++) {
            bool present = fp_session_performer_hand(s, p, side) != NULL;
            if (present) h->seen[p][side] = true;
            char *to = present ? now : h->seen[p][side] ? lost : NULL;
            if (to) add(to, 64, to[0] ? " " : "", sides[side]);
        }
        if (np > 1) {
            add(here, sizeof here, p ? ", " : "", who);
            add(here, sizeof here, " ", now[0] ? now : "none");
        } else {
            add(here, sizeof here, "", now[0] ? now : "none");
        }
        if (lost[0]) {
            add(gone, sizeof gone, gone[0] ? ", " : "", who);
            add(gone, sizeof gone, who[0] ? " " : "", lost);
        }
    }
    buf[0] = '\0';
    if (h->was_gone && !gone[0]) h->note[0] = '\0'; /* every hand back: its story is over */
    h->was_gone = gone[0] != '\0';
    if (np < 2 && !gone[0]) return;
    snprintf(buf, len, "\nhands: %s", here);
    if (!gone[0]) return;
    add(buf, len, "; gone: ", gone);
    if (h->note[0]) {
        add(buf, len, " (", h->note);
        add(buf, len, ")", "");
    }
}
