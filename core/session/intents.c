/* Step 1 of the frame: drain the inputs, bind pedals and keys to intents, count statuses. */
#include "intents.h"

#include "fp_clock.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void fp_intents_init(fp_intents *it) { memset(it, 0, sizeof *it); }


void fp_intents_request(fp_intents *it, uint32_t intents) { it->requested |= intents; }

void fp_intents_bind_button(fp_intents *it, const fp_event_button *b, bool engaged)
{
    if (!b->down) return;
    if (b->button == FP_BUTTON_LEFT) it->requested |= engaged ? FP_INTENT_COMMIT : FP_INTENT_ENGAGE;
    else if (b->button == FP_BUTTON_RIGHT) it->requested |= FP_INTENT_CANCEL;
    else if (b->button == FP_BUTTON_MIDDLE) it->record_toggles++;   /* start/stop a take */
    else if (b->button == FP_BUTTON_REQUEST)
        it->requested |= b->mask & (FP_INTENT_ENGAGE | FP_INTENT_COMMIT | FP_INTENT_CANCEL);
}

static void keep(fp_intents *it, const fp_event *ev)
{
    if (it->frame_event_count < FP_INTENTS_MAX_FRAME_EVENTS) it->frame_events[it->frame_event_count++] = *ev;
}

void fp_intents_take(fp_intents *it, size_t input, const char *name, const fp_event *ev,
                     bool engaged, const fp_slog *log)
{
    switch (ev->header.type) {
    case FP_EVENT_BUTTON:
        fp_intents_bind_button(it, &ev->button, engaged);
        keep(it, ev);
        break;
    case FP_EVENT_STATUS: {
        const fp_event_status *st = &ev->status;
        if (st->code == FP_STATUS_END_OF_STREAM && input < FP_INTENTS_MAX_INPUTS) it->ended[input] = true;
        if (st->code == FP_STATUS_ERROR) {
            it->input_errors++;
            snprintf(it->last_error, sizeof it->last_error, "%.*s", 100, st->text);
        }
        /* (a DISCONNECTED without text says nothing: an isolated input's hands released after
         * its fault, which its WARNING said) */
        if (st->code == FP_STATUS_ERROR || st->code == FP_STATUS_WARNING ||
            (st->code == FP_STATUS_DISCONNECTED && st->text[0])) {
            /* the line's source is the input's name: a text that names it itself ("osc: left
             * hand: no data ...") is said once, not "osc: osc: ..." */
            const char *who = name ? name : "input", *text = st->text;
            size_t k = strlen(who);
            if (strncmp(text, who, k) == 0 && text[k] == ':' && text[k + 1] == ' ') text += k + 2;
            fp_slog_printf(log, st->code == FP_STATUS_ERROR ? FP_LOG_ERROR : FP_LOG_WARNING, who,
                           "%.*s", (int)(sizeof st->text - (size_t)(text - st->text)), text);
        }
        keep(it, ev);
        break;
    }
    default:
        break;
    }
}

size_t fp_intents_drain(fp_intents *it, fp_input_instance *inputs, size_t n, bool engaged,
                        const fp_slog *log, fp_intents_event_fn each, void *user)
{
    size_t count = 0;
    it->frame_event_count = 0;
    for (size_t i = 0; i < n; i++) {
        fp_event ev;
        while (fp_input_instance_poll(&inputs[i], &ev)) {
            fp_intents_take(it, i, inputs[i].name, &ev, engaged, log);
            if (each) each(user, i, &ev);
            count++;
        }
    }
    return count;
}

uint32_t fp_intents_take_requested(fp_intents *it)
{
    uint32_t r = it->requested;
    it->requested = 0;
    return r;
}

bool fp_intents_all_ended(const fp_intents *it, size_t n)
{
    if (!n) return false;
    for (size_t i = 0; i < n && i < FP_INTENTS_MAX_INPUTS; i++)
        if (!it->ended[i]) return false;
    return true;
}

/* ---- the input clock ------------------------------------------------------------------- */

static const fp_event *ahead_at(const fp_intents_ahead *a, size_t k) { return &a->ev[(a->head + k) % a->cap]; }

/* Move queued events of input i into its lookahead while it holds nothing later than t. */
static void fetch(fp_intents *it, fp_input_instance *in, size_t i, int64_t t)
{
    fp_intents_ahead *a = &it->ahead[i];
    while (!a->len || ahead_at(a, a->len - 1)->header.time_ns <= t) {
        if (a->len == a->cap) {
            size_t cap = a->cap ? 2 * a->cap : 256;
            fp_event *ev = malloc(cap * sizeof *ev);
            if (!ev) return;
            for (size_t k = 0; k < a->len; k++) ev[k] = *ahead_at(a, k);
            free(a->ev);
            a->ev = ev;
            a->cap = cap;
            a->head = 0;
        }
        fp_event *slot = &a->ev[(a->head + a->len) % a->cap];
        if (!fp_input_instance_poll(in, slot)) return;
        if (it->started) slot->header.time_ns += it->shift[i];
        a->len++;
        if (slot->header.type == FP_EVENT_STATUS && slot->status.code == FP_STATUS_END_OF_STREAM)
            a->eos = true;
    }
}

size_t fp_intents_drain_until(fp_intents *it, fp_input_instance *inputs, size_t n, int64_t t,
                              bool engaged, const fp_slog *log, fp_intents_event_fn each, void *user)
{
    size_t count = 0;
    it->frame_event_count = 0;
    for (size_t i = 0; i < n; i++) {
        fp_event ev;
        if (i >= FP_INTENTS_MAX_INPUTS) {
            while (fp_input_instance_poll(&inputs[i], &ev)) {
                fp_intents_take(it, i, inputs[i].name, &ev, engaged, log);
                if (each) each(user, i, &ev);
                count++;
            }
            continue;
        }
        /* a live input's event stamped after t waits for the frame of its time (a frame that
         * runs late sees each hand as at its own time), unless it is stamped beyond the wall
         * clock (another clock than the host's: taken at once) */
        const int64_t beyond = it->waited[i] ? INT64_MAX : fp_now_ns() + FP_INTENTS_HOLD_MAX_NS;
        fp_intents_ahead *a = &it->ahead[i];
        for (;;) {
            if (!a->len) fetch(it, &inputs[i], i, t);
            if (!a->len) break;
            const int64_t et = ahead_at(a, 0)->header.time_ns;
            if (et > t && et <= beyond) break;
            ev = *ahead_at(a, 0);
            a->head = (a->head + 1) % a->cap;
            a->len--;
            fp_intents_take(it, i, inputs[i].name, &ev, engaged, log);
            if (each) each(user, i, &ev);
            count++;
        }
    }
    return count;
}

bool fp_intents_input_ready(const fp_intents *it, size_t i, int64_t t)
{
    if (i >= FP_INTENTS_MAX_INPUTS || !it->waited[i] || it->ended[i]) return true;
    const fp_intents_ahead *a = &it->ahead[i];
    return a->eos || (a->len && ahead_at(a, a->len - 1)->header.time_ns > t);
}

bool fp_intents_ready(fp_intents *it, fp_input_instance *inputs, size_t n, int64_t t)
{
    for (size_t i = 0; i < n && i < FP_INTENTS_MAX_INPUTS; i++) {
        if (!it->waited[i] || it->ended[i]) continue;
        fetch(it, &inputs[i], i, t);
        if (!fp_intents_input_ready(it, i, t)) return false;
    }
    return true;
}

int fp_intents_first_time(fp_intents *it, fp_input_instance *inputs, size_t n, int64_t *t0)
{
    if (it->started) {
        *t0 = it->t0;
        return 1;
    }
    bool any = false;
    int64_t first = 0;
    for (size_t i = 0; i < n && i < FP_INTENTS_MAX_INPUTS; i++) {
        if (!it->waited[i]) continue;
        fp_intents_ahead *a = &it->ahead[i];
        if (!a->len) fetch(it, &inputs[i], i, INT64_MIN);
        if (!a->len) {
            if (a->eos || it->ended[i]) continue;
            return 0;
        }
        int64_t t = ahead_at(a, 0)->header.time_ns;
        if (!any || t < first) first = t;
        any = true;
    }
    if (!any) return -1;
    for (size_t i = 0; i < n && i < FP_INTENTS_MAX_INPUTS; i++) { /* each time zero to the earliest */
        fp_intents_ahead *a = &it->ahead[i];
        if (!it->waited[i] || !a->len) continue;
        it->shift[i] = first - ahead_at(a, 0)->header.time_ns;
        for (size_t k = 0; k < a->len; k++) a->ev[(a->head + k) % a->cap].header.time_ns += it->shift[i];
    }
    it->started = true;
    *t0 = it->t0 = first;
    return 1;
}

void fp_intents_free(fp_intents *it)
{
    for (size_t i = 0; i < FP_INTENTS_MAX_INPUTS; i++) {
        free(it->ahead[i].ev);
        it->ahead[i] = (fp_intents_ahead){0};
    }
}
