/* What makes an input event malformed (fp_event_check.h). */
#include "fp_event_check.h"

#include <math.h>
#include <string.h>

static bool finite_n(const float *v, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (!isfinite(v[i])) return false;
    return true;
}

static bool near_n(const float *v, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (fabsf(v[i]) > FP_EVENT_MAX_MM) return false;
    return true;
}

static fp_event_fault fault(fp_event_fault f, const char *what, const char **why)
{
    if (why) *why = what;
    return f;
}

const char *fp_event_type_name(uint32_t type)
{
    static const char *const names[] = {NULL, "joint angles", "joint positions", "wrist pose",
                                        "button", "status", "channel"};
    return type >= 1 && type <= FP_EVENT_CHANNEL ? names[type] : "an unknown type";
}

fp_event_fault fp_event_check(const fp_event *ev, const char **why)
{
    static const uint32_t sizes[] = {0, sizeof(fp_event_joint_angles), sizeof(fp_event_joint_positions),
                                     sizeof(fp_event_wrist_pose), sizeof(fp_event_button),
                                     sizeof(fp_event_status), sizeof(fp_event_channel)};
    const fp_event_header *h = &ev->header;
    if (why) *why = NULL;
    if (h->type < 1 || h->type > FP_EVENT_CHANNEL) return fault(FP_EVENT_BAD_TYPE, "unknown type", why);
    if (h->size != sizes[h->type]) return fault(FP_EVENT_BAD_SIZE, "size is not that of its type", why);
    if (h->hand < -1 || h->hand > 1) return fault(FP_EVENT_BAD_HAND, "hand is not -1, 0 or 1", why);
    if (h->type <= FP_EVENT_WRIST_POSE && h->hand < 0)
        return fault(FP_EVENT_BAD_HAND, "a pose event without a hand", why);
    switch (h->type) {
    case FP_EVENT_JOINT_ANGLES:
        if (!finite_n(ev->angles.radians, FP_GLOVE_SENSORS))
            return fault(FP_EVENT_NOT_FINITE, "a joint angle is not finite", why);
        break;
    case FP_EVENT_JOINT_POSITIONS:
        if (!finite_n(&ev->positions.mm[0][0], FP_HAND_JOINTS * 3))
            return fault(FP_EVENT_NOT_FINITE, "a joint position is not finite", why);
        if (!near_n(&ev->positions.mm[0][0], FP_HAND_JOINTS * 3))
            return fault(FP_EVENT_TOO_FAR, "a joint position is beyond 10 m", why);
        break;
    case FP_EVENT_WRIST_POSE: {
        const float *q = ev->wrist.rotation;
        if (!finite_n(ev->wrist.position_mm, 3) || !finite_n(q, 4))
            return fault(FP_EVENT_NOT_FINITE, "the wrist pose is not finite", why);
        if (!near_n(ev->wrist.position_mm, 3))
            return fault(FP_EVENT_TOO_FAR, "the wrist position is beyond 10 m", why);
        double n = (double)q[0] * q[0] + (double)q[1] * q[1] + (double)q[2] * q[2] + (double)q[3] * q[3];
        if (fabs(n - 1) > 1e-2)
            return fault(FP_EVENT_BAD_ROTATION, "the wrist rotation is not a unit quaternion", why);
        break;
    }
    case FP_EVENT_BUTTON:
        if (ev->button.button != FP_BUTTON_LEFT && ev->button.button != FP_BUTTON_MIDDLE &&
            ev->button.button != FP_BUTTON_RIGHT)
            return fault(FP_EVENT_BAD_FIELD, "button is not one fp_button bit", why);
        if (ev->button.down > 1 || ev->button.mask > 7)
            return fault(FP_EVENT_BAD_FIELD, "button down or mask out of range", why);
        break;
    case FP_EVENT_STATUS:
        if (ev->status.code < FP_STATUS_CONNECTED || ev->status.code > FP_STATUS_END_OF_STREAM)
            return fault(FP_EVENT_BAD_FIELD, "unknown status code", why);
        if (!memchr(ev->status.text, 0, sizeof ev->status.text))
            return fault(FP_EVENT_BAD_FIELD, "status text not NUL-terminated", why);
        break;
    case FP_EVENT_CHANNEL:
        if (!memchr(ev->channel.name, 0, sizeof ev->channel.name) || !ev->channel.name[0])
            return fault(FP_EVENT_BAD_FIELD, "channel name empty or not NUL-terminated", why);
        if (!isfinite(ev->channel.value)) return fault(FP_EVENT_NOT_FINITE, "channel value not finite", why);
        break;
    }
    return FP_EVENT_OK;
}

fp_event_fault fp_event_check_time(const fp_event *ev, int64_t now_ns, bool own_clock, const char **why)
{
    if (why) *why = NULL;
    if (ev->header.time_ns < 0) return fault(FP_EVENT_BAD_TIME, "time_ns is negative", why);
    if (!own_clock && now_ns <= INT64_MAX - FP_EVENT_MAX_AHEAD_NS &&
        ev->header.time_ns > now_ns + FP_EVENT_MAX_AHEAD_NS)
        return fault(FP_EVENT_BAD_TIME, "time_ns is more than 1 s ahead of the host's clock", why);
    return FP_EVENT_OK;
}

bool fp_input_own_clock(fp_input *in)
{
    return in && FP_HAS_FIELD(in, fp_input, get_extension) && in->get_extension &&
           (in->get_extension(in, FP_EXT_RECORDING_INFO) || in->get_extension(in, FP_EXT_INPUT_CLOCK));
}
