/* The live viewer's measurements (see measure.h). */
#include "measure.h"

#include "fp_stats.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void fp_vsamples_add(fp_vsamples *s, double x)
{
    if (s->n == s->cap) {
        size_t cap = s->cap ? 2 * s->cap : 1024;
        double *grown = realloc(s->v, cap * sizeof *grown);
        if (!grown) return;
        s->v = grown;
        s->cap = cap;
    }
    s->v[s->n++] = x;
}

void fp_viewer_percentiles(double *v, size_t n, double *median, double *p99)
{
    *median = fp_median(v, n);
    *p99 = fp_percentile(v, n, 0.99);
}

void fp_vmeasure_new_session(fp_vmeasure *m)
{
    for (int h = 0; h < FP_HANDS; h++) m->seen_time[h] = m->pending_time[h] = 0;
}

void fp_vmeasure_hands(fp_vmeasure *m, const fp_session *s)
{
    for (int h = 0; h < FP_HANDS; h++) {
        const fp_hand_pose *p = fp_session_hand(s, h);
        if (p && p->time_ns > m->seen_time[h]) {
            m->seen_time[h] = p->time_ns;
            /* late from its measure, or from its arrival for a replay (its times the
             * recording's, which speed= stretches) */
            m->pending_time[h] = fp_session_hand_since(s, h);
        }
    }
}

void fp_vmeasure_swap(fp_vmeasure *m, int64_t swap)
{
    if (m->swaps > 0) {
        double ms = (double)(swap - m->last_swap) / 1e6;
        fp_vsamples_add(&m->frame_ms, ms);
        m->recent_frame_ms[m->swaps % FP_VMEASURE_RECENT] = ms;
        m->ring_frame[m->ring_frames++ % FP_VMEASURE_RING] = (fp_vtimed){swap, ms};
        if (m->recent_n < FP_VMEASURE_RECENT) m->recent_n++;
    }
    m->last_swap = swap;
    for (int h = 0; h < FP_HANDS; h++)
        if (m->pending_time[h]) {
            double ms = (double)(swap - m->pending_time[h]) / 1e6;
            fp_vsamples_add(&m->latency_ms, ms);
            m->ring_latency[m->ring_latencies++ % FP_VMEASURE_RING] = (fp_vtimed){swap, ms};
            m->pending_time[h] = 0;
        }
    m->swaps++;
}

double fp_vmeasure_recent_ms(const fp_vmeasure *m)
{
    double recent = 0;
    for (int i = 0; i < m->recent_n; i++) recent += m->recent_frame_ms[i];
    return m->recent_n ? recent / m->recent_n : 0;
}

bool fp_vmeasure_lag(double *latency_ms, size_t n, double *frame_ms, size_t nf, double *ms,
                     double *frames)
{
    *ms = fp_median(latency_ms, n);
    double frame = fp_median(frame_ms, nf);
    *frames = frame > 0 ? *ms / frame : 0;
    return n > 0;
}

/* The ring's samples swapped since `since` (ns), newest first, into out (at most
 * FP_VMEASURE_RING); returns their count. */
static size_t ring_since(const fp_vtimed *ring, uint64_t pushed, int64_t since, double *out)
{
    size_t n = 0;
    for (uint64_t k = pushed; k > 0 && n < FP_VMEASURE_RING; k--) {
        const fp_vtimed *t = &ring[(k - 1) % FP_VMEASURE_RING];
        if (t->at < since) break;
        out[n++] = t->ms;
    }
    return n;
}

bool fp_vmeasure_lag_recent(const fp_vmeasure *m, int64_t now, double *ms, double *frames)
{
    double lat[FP_VMEASURE_RING], frame[FP_VMEASURE_RING];
    size_t n = ring_since(m->ring_latency, m->ring_latencies, now - FP_VMEASURE_LAG_NS, lat);
    size_t nf = ring_since(m->ring_frame, m->ring_frames, now - FP_VMEASURE_LAG_NS, frame);
    return fp_vmeasure_lag(lat, n, frame, nf, ms, frames);
}

const char *fp_vmeasure_lag_text(const fp_vmeasure *m, int64_t now, char *buf, size_t len)
{
    double ms, frames;
    if (fp_vmeasure_lag_recent(m, now, &ms, &frames)) snprintf(buf, len, "%.1f frames (%.1f ms)", frames, ms);
    else snprintf(buf, len, "-");
    return buf;
}

void fp_vmeasure_report(fp_vmeasure *m, fp_viewer_report *rep)
{
    fp_viewer_percentiles(m->frame_ms.v, m->frame_ms.n, &rep->frame_ms_median, &rep->frame_ms_p99);
    fp_viewer_percentiles(m->latency_ms.v, m->latency_ms.n, &rep->latency_ms_median, &rep->latency_ms_p99);
    (void)fp_vmeasure_lag(m->latency_ms.v, m->latency_ms.n, m->frame_ms.v, m->frame_ms.n,
                          &rep->latency_ms_median, &rep->latency_frames_median);
    rep->latency_samples = m->latency_ms.n;
    double unused;
    fp_viewer_percentiles(m->engine_ms.v, m->engine_ms.n, &rep->engine_ms_median, &unused);
    fp_viewer_percentiles(m->upload_ms.v, m->upload_ms.n, &rep->upload_ms_median, &rep->upload_ms_p99);
    rep->uploads = m->upload_ms.n;
    fp_viewer_percentiles(m->upload_all_ms.v, m->upload_all_ms.n, &rep->upload_all_ms_median,
                          &rep->upload_all_ms_p99);
}

void fp_vmeasure_free(fp_vmeasure *m)
{
    free(m->frame_ms.v);
    free(m->latency_ms.v);
    free(m->engine_ms.v);
    free(m->upload_ms.v);
    free(m->upload_all_ms.v);
    memset(m, 0, sizeof *m);
}
