/* audio_internal.h: what audio.c shares with audio_in.c (core/audio only). */
#ifndef FP_AUDIO_INTERNAL_H
#define FP_AUDIO_INTERNAL_H

#include <stdbool.h>

/** A PortAudio device by "default", index or a case-insensitive part of its name, with
 *  input (or output) channels. PortAudio must be initialised. Returns the index or
 *  paNoDevice (-1). */
int fp_audio_find_device(const char *spec, bool input);

#endif
