#!/bin/bash
# A slower tracker (issue 51 on hands the checks were not tuned on): the four Leap recordings
# resampled at 57 Hz (tools/hands-variants: each hand linearly between its own samples), as a
# 56-60 Hz camera or Leap mode delivers them, through
#  1. test_guard's recordings, anchored: no new crossing away from the input's own and no
#     flipped triangle on the three faces;
#  2. test_reach on the three faces: the skin follows the fingertips (median at least 90%,
#     each run's 10th percentile at least 60%; measured 100% and 99.2-100%: the ICT grab's
#     drag under the nose turned skin over and stalled at 55.2% before a flip-held gesture
#     was widened, step_contact.h).
# Usage: test_slow_tracker.sh BUILD_DIR. Exit 77 (skipped) without python3 or the data.
# SPDX-License-Identifier: GPL-3.0-or-later
set -u
. "$(dirname "$0")/hands_variants.sh"
variants_setup "${1:?usage: test_slow_tracker.sh BUILD_DIR}" 57hz
variant_guard_and_reach 57hz "57 Hz hands"
echo "PASS: 57 Hz hands"
