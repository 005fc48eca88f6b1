/* script.h: the viewer's script (see fp_viewer.h), parsed into commands. Internal to ui/. */
#ifndef FP_UI_SCRIPT_H
#define FP_UI_SCRIPT_H

#include <stddef.h>
#include <stdint.h>

typedef enum fp_script_op {
    FP_SCRIPT_WAIT_HANDS, FP_SCRIPT_WAIT_END, FP_SCRIPT_WAIT_FRAMES, FP_SCRIPT_KEY,
    FP_SCRIPT_SHOT, FP_SCRIPT_RADIUS, FP_SCRIPT_DROP, FP_SCRIPT_CLOSE,
    FP_SCRIPT_WAIT_RELOAD,   /* wait reload: until the mapping's file was reloaded (or failed to) */
    FP_SCRIPT_PRINT_MAPPING, /* print mapping: one stdout line, the mapping's name, id, version */
    FP_SCRIPT_SCRUB,         /* scrub F: the take review's playhead to fraction F (the mouse) */
    FP_SCRIPT_PRINT_HUD,     /* print hud: one stdout line, the HUD's state, commits and scale */
    FP_SCRIPT_CAMERA,        /* camera YAW PITCH [ZOOM]: the framed view turned (degrees), zoomed */
    FP_SCRIPT_PRINT_MESSAGES, /* print messages: the HUD's message stack, a stdout line each */
    FP_SCRIPT_WAIT_SECONDS,  /* wait seconds S: until S s of the wall clock have passed */
    FP_SCRIPT_SIZE           /* size WxH: the window resized (as the performer drags it) */
} fp_script_op;

typedef struct fp_script_cmd {
    fp_script_op op;
    int key;            /* GLFW key code for FP_SCRIPT_KEY */
    double number;      /* frames, seconds, radius; camera: yaw (degrees) */
    double pitch, zoom; /* camera: pitch (degrees), zoom (> 0); size: width, height (pixels) */
    char *text;         /* file for SHOT and DROP (owned) */
} fp_script_cmd;

typedef struct fp_script {
    fp_script_cmd *cmds;
    size_t count, next;
    uint64_t wait_start;  /* frame the current wait began at */
    double wait_start_s;  /* and its wall clock (glfwGetTime, s) */
    int waiting;
    unsigned long reload_mark;  /* reload attempts when the current wait began */
} fp_script;

/** Parse text into s. Returns 0 or -EINVAL with the offending command in err. */
int fp_script_parse(const char *text, fp_script *s, char *err, size_t errlen);
void fp_script_free(fp_script *s);
/** The GLFW key for a script key name (E, space, Esc, Tab, [, ], ?, ...), or -1. */
int fp_script_key(const char *name);

#endif
