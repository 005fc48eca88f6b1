/* Events the pose tests feed: one hand's joint positions (mm, device frame) at time t (ns). */
#ifndef FP_TEST_POSE_EVENTS_H
#define FP_TEST_POSE_EVENTS_H

#include <facepuppet/plugin.h>

#include <string.h>

static inline fp_event joints_event(int hand, const float mm[FP_HAND_JOINTS][3], int64_t t)
{
    fp_event ev;
    memset(&ev, 0, sizeof ev);
    ev.header.size = sizeof ev.positions;
    ev.header.type = FP_EVENT_JOINT_POSITIONS;
    ev.header.hand = hand;
    ev.header.time_ns = t;
    memcpy(ev.positions.mm, mm, sizeof ev.positions.mm);
    return ev;
}

#endif
